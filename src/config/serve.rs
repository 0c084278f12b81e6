//! `mavping serve [OPTIONS]` and its TOML file into a [`ServeConfig`], and
//! each `/probe?target=...` request into a [`ProbePlan`]: the same rules as
//! the command line, one function a rule, errors on one line.
//!
//! Default deny: `/probe` opens only targets an allow pattern admits. In a
//! pattern, `*` stands for one part of an address (no `.`, `:` or `/`: a
//! port, an octet, a device or host name) and `**` for anything, so
//! `udpout:10.0.0.*:14550` cannot be stretched to `udpout:10.0.0.5.evil.example:14550`.

use std::collections::BTreeMap;
use std::net::SocketAddr;
use std::path::{Path, PathBuf};
use std::time::Duration;

use clap::ValueEnum;
use serde::Deserialize;

use super::ping::{pending_capacity, probe_of, ProbeChoice};
use super::{
    invalid, signing, validate_baud, validate_ids, validate_listen, ConfigError, Keys, LinkConfig,
    Probe, MAX_TIMEOUT,
};
use crate::cli::{parse_expected, parse_rtt_limit, ProbeKind, ServeArgs, SigningArgs};
use crate::engine::SessionConfig;
use crate::frame::signing::SigningConfig;
use crate::frame::{SysComp, Version};
use crate::transport::address::LinkSpec;
use crate::transport::{serial, LinkOptions};
use crate::units::{parse_duration, parse_percent};
use crate::verdict::Thresholds;

/// `mavping serve` listens here unless told otherwise: this machine only.
pub const DEFAULT_LISTEN: &str = "127.0.0.1:9465";
/// Probes at once unless told otherwise.
pub const DEFAULT_MAX_CONCURRENT: usize = 16;
const MAX_CONCURRENT: usize = 1024;
/// The module `/probe` uses when none is named, unless the file defines one.
pub const DEFAULT_MODULE: &str = "default";
/// Bounds on what a `/probe` request may ask: a remote caller must not
/// turn the exporter into a flood or tie it up for long.
const MAX_PROBE_COUNT: u64 = 10_000;
const MIN_PROBE_INTERVAL: Duration = Duration::from_millis(1);
const MAX_PROBE_INTERVAL: Duration = Duration::from_secs(60);
const MAX_PROBE_TIMEOUT: Duration = Duration::from_secs(60);
/// Most continuous links one server runs.
const MAX_LINKS: usize = 10_000;

/// `mavping serve`, validated.
#[derive(Debug)]
pub struct ServeConfig {
    pub listen: SocketAddr,
    /// Reread on SIGHUP.
    pub file: Option<PathBuf>,
    pub settings: ServeSettings,
    pub verbose: u8,
    /// The command line, whose `--allow` and `--link` a reload keeps.
    args: ServeArgs,
}

impl ServeConfig {
    /// The settings as they are now: the file read again, beside the
    /// command line's. The address stays what it was at the start.
    pub fn reload(&self) -> Result<ServeSettings, ConfigError> {
        ServeSettings::load(&self.args, self.file.as_deref()).map(|(settings, _)| settings)
    }
}

/// What a reload may change (everything but the address).
#[derive(Debug, Clone, PartialEq)]
pub struct ServeSettings {
    pub allow: Vec<Pattern>,
    pub modules: BTreeMap<String, Module>,
    pub links: Vec<ContinuousLink>,
    pub max_concurrent: usize,
}

/// How a `/probe` measures, unless its request says otherwise.
#[derive(Debug, Clone, PartialEq)]
pub struct Module {
    pub kind: ProbeKind,
    pub target: Option<String>,
    pub command: String,
    pub retry_interval: Duration,
    pub retries: u8,
    pub count: u64,
    pub interval: Duration,
    pub timeout: Duration,
    pub thresholds: Thresholds,
    pub ours: SysComp,
    pub version: Version,
    pub heartbeat: bool,
    pub signing: Option<SigningConfig>,
    pub baud: u32,
}

/// A link probed all the time, shown at `/metrics` as `link="NAME"`.
#[derive(Debug, Clone, PartialEq)]
pub struct ContinuousLink {
    pub link: LinkConfig,
    pub probe: Probe,
    pub options: LinkOptions,
}

/// One `/probe` request, validated: what to open and how to measure it.
#[derive(Debug, Clone, PartialEq)]
pub struct ProbePlan {
    pub module: String,
    pub link: LinkConfig,
    pub probe: Probe,
    pub options: LinkOptions,
}

/// An allow pattern, in the canonical form targets are compared in.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Pattern(String);

/// Link kinds as patterns may spell them, and their canonical form.
const KINDS: [(&str, &str); 10] = [
    ("udpin:", "udpin:"),
    ("udp:", "udpin:"),
    ("udpout:", "udpout:"),
    ("udpbcast:", "udpbcast:"),
    ("tcpout:", "tcp:"),
    ("tcp:", "tcp:"),
    ("tcpin:", "tcpin:"),
    ("serial:", "serial:"),
    ("/", "serial:/"),
    ("sim:", "sim:"),
];

impl Pattern {
    pub fn parse(text: &str) -> Result<Self, ConfigError> {
        let text = text.trim();
        let Some((given, canonical)) = KINDS.iter().find(|(k, _)| text.starts_with(k)) else {
            return Err(invalid(format!(
                "allow pattern '{text}': start it with a link kind (udpout:, udpin:, udpbcast:, \
                 tcp:, tcpin:, serial:, /dev/..., sim:), e.g. 'udpout:127.0.0.1:*'"
            )));
        };
        let mut pattern = format!("{canonical}{}", &text[given.len()..]);
        if pattern.starts_with("serial:") {
            pattern = without_baud(&pattern).to_string();
        }
        if pattern.len() <= canonical.len() {
            return Err(invalid(format!(
                "allow pattern '{text}': it names no address; '{canonical}**' allows every one"
            )));
        }
        Ok(Pattern(pattern))
    }

    /// Whether the target (in its canonical form) is admitted.
    pub fn admits(&self, target: &LinkSpec) -> bool {
        glob(self.0.as_bytes(), canonical(target).as_bytes())
    }
}

impl std::fmt::Display for Pattern {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

/// A serial device is allowed whatever its baud: the device is what matters.
fn without_baud(serial: &str) -> &str {
    match serial.rsplit_once(':') {
        Some((device, baud))
            if device.len() > "serial".len()
                && !baud.is_empty()
                && baud.bytes().all(|b| b.is_ascii_digit() || b == b'*') =>
        {
            device
        }
        _ => serial,
    }
}

/// The form a target is matched in: how mavping prints it, serial
/// devices without their baud.
fn canonical(target: &LinkSpec) -> String {
    match target {
        LinkSpec::Serial { path, .. } => format!("serial:{path}"),
        other => other.to_string(),
    }
}

/// `*` matches a run of characters other than `.`, `:` and `/`; `**`
/// any run at all; everything else itself.
fn glob(pattern: &[u8], text: &[u8]) -> bool {
    match pattern {
        [] => text.is_empty(),
        [b'*', b'*', rest @ ..] => (0..=text.len()).any(|i| glob(rest, &text[i..])),
        [b'*', rest @ ..] => {
            let part = text
                .iter()
                .position(|b| matches!(b, b'.' | b':' | b'/'))
                .unwrap_or(text.len());
            (0..=part).any(|i| glob(rest, &text[i..]))
        }
        [c, rest @ ..] => text.first() == Some(c) && glob(rest, &text[1..]),
    }
}

/// A duration in the file: `"250ms"`, `"2s"`, or a number of seconds.
#[derive(Debug, Clone, Deserialize)]
#[serde(untagged)]
enum FileDuration {
    Text(String),
    Seconds(f64),
}

impl FileDuration {
    fn get(&self, key: &str) -> Result<Duration, ConfigError> {
        match self {
            FileDuration::Text(t) => parse_duration(t),
            FileDuration::Seconds(s) => parse_duration(&s.to_string()),
        }
        .map_err(|e| invalid(format!("{key}: {e}")))
    }
}

/// The file as written. One table type for modules and links, so each key
/// is parsed once; keys that belong to the other kind are refused by name.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct File {
    listen: Option<String>,
    max_concurrent: Option<usize>,
    #[serde(default)]
    allow: Vec<String>,
    #[serde(default)]
    module: BTreeMap<String, Table>,
    #[serde(default)]
    link: Vec<Table>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct Table {
    // [[link]] only
    link: Option<String>,
    name: Option<String>,
    rate: Option<f64>,
    // [module.NAME] only
    count: Option<u64>,
    max_loss: Option<String>,
    #[serde(default)]
    max_rtt: Vec<String>,
    max_jitter: Option<FileDuration>,
    #[serde(default)]
    expect: Vec<String>,
    min_responders: Option<usize>,
    // both
    probe: Option<String>,
    interval: Option<FileDuration>,
    timeout: Option<FileDuration>,
    target: Option<String>,
    command: Option<String>,
    retry_interval: Option<FileDuration>,
    retries: Option<u8>,
    sysid: Option<u8>,
    compid: Option<u8>,
    mavlink: Option<u8>,
    heartbeat: Option<bool>,
    signing_key_file: Option<PathBuf>,
    signing_link_id: Option<u8>,
    require_signed: Option<bool>,
    baud: Option<u32>,
}

/// What both a module and a link set: how requests are made.
struct Common {
    probe: Probe,
    kind: ProbeKind,
    ours: SysComp,
    version: Version,
    heartbeat: bool,
    signing: Option<SigningConfig>,
    baud: u32,
    timeout: Duration,
    retry_interval: Duration,
}

impl Table {
    /// Keys set here that only the other kind of table takes.
    fn misplaced(&self, module: bool) -> Option<&'static str> {
        let link_only = [
            ("link", self.link.is_some()),
            ("name", self.name.is_some()),
            ("rate", self.rate.is_some()),
        ];
        let module_only = [
            ("count", self.count.is_some()),
            ("max_loss", self.max_loss.is_some()),
            ("max_rtt", !self.max_rtt.is_empty()),
            ("max_jitter", self.max_jitter.is_some()),
            ("expect", !self.expect.is_empty()),
            ("min_responders", self.min_responders.is_some()),
        ];
        let wrong: &[(&str, bool)] = if module { &link_only } else { &module_only };
        wrong.iter().find(|(_, set)| *set).map(|(k, _)| *k)
    }

    fn common(&self, default_timeout: Duration) -> Result<Common, ConfigError> {
        let kind = match &self.probe {
            None => ProbeKind::Ping,
            Some(p) => ProbeKind::from_str(p, true)
                .map_err(|_| invalid(format!("probe '{p}': expected ping, timesync or command")))?,
        };
        let retry_interval = match &self.retry_interval {
            Some(d) => d.get("retry_interval")?,
            None => Duration::from_millis(100),
        };
        let probe = probe_of(
            Keys::File,
            &ProbeChoice {
                kind,
                target: self.target.as_deref(),
                command: self.command.as_deref().unwrap_or("REQUEST_MESSAGE,0"),
                retry_interval,
                retries: self.retries.unwrap_or(3),
            },
        )?;
        let version = match self.mavlink.unwrap_or(2) {
            1 => Version::V1,
            2 => Version::V2,
            v => return Err(invalid(format!("mavlink {v}: expected 1 or 2"))),
        };
        let signing = match &self.signing_key_file {
            None if self.require_signed.is_some() => {
                return Err(invalid("require_signed needs signing_key_file"))
            }
            None => None,
            Some(path) => signing(
                &SigningArgs {
                    signing_key: None,
                    signing_key_file: Some(path.clone()),
                    signing_link_id: self.signing_link_id.unwrap_or(0),
                },
                self.require_signed.unwrap_or(false),
            )?,
        };
        if signing.is_some() && version == Version::V1 {
            return Err(invalid(
                "mavlink 1 with a signing key: signing needs MAVLink 2",
            ));
        }
        let timeout = match &self.timeout {
            Some(d) => validate_timeout("timeout", d.get("timeout")?, MAX_TIMEOUT)?,
            None => default_timeout,
        };
        Ok(Common {
            probe,
            kind,
            ours: validate_ids(self.sysid.unwrap_or(255), self.compid.unwrap_or(190))?,
            version,
            heartbeat: self.heartbeat.unwrap_or(true),
            signing,
            baud: validate_baud(self.baud.unwrap_or(serial::DEFAULT_BAUD))?,
            timeout,
            retry_interval,
        })
    }

    fn module(&self) -> Result<Module, ConfigError> {
        let c = self.common(Duration::from_secs(1))?;
        let count = self.count.unwrap_or(10);
        validate_count(count)?;
        let interval = match &self.interval {
            Some(d) => validate_probe_interval("interval", d.get("interval")?)?,
            None => Duration::from_millis(100),
        };
        if c.timeout > MAX_PROBE_TIMEOUT {
            return Err(invalid(format!(
                "timeout {}: a probe's timeout is at most 1m",
                humantime::format_duration(c.timeout)
            )));
        }
        let thresholds = Thresholds {
            max_loss: self
                .max_loss
                .as_deref()
                .map(|p| parse_percent(p).map_err(|e| invalid(format!("max_loss: {e}"))))
                .transpose()?,
            max_rtt: self
                .max_rtt
                .iter()
                .map(|r| parse_rtt_limit(r).map_err(|e| invalid(format!("max_rtt {r}: {e}"))))
                .collect::<Result<_, _>>()?,
            max_jitter: self
                .max_jitter
                .as_ref()
                .map(|d| d.get("max_jitter"))
                .transpose()?,
            expect: self
                .expect
                .iter()
                .map(|e| parse_expected(e).map_err(|m| invalid(format!("expect: {m}"))))
                .collect::<Result<_, _>>()?,
            min_responders: match self.min_responders {
                Some(0) => return Err(invalid("min_responders 0: expected at least 1")),
                n => n,
            },
        };
        Ok(Module {
            kind: c.kind,
            target: self.target.clone(),
            command: self
                .command
                .clone()
                .unwrap_or_else(|| "REQUEST_MESSAGE,0".into()),
            retry_interval: c.retry_interval,
            retries: self.retries.unwrap_or(3),
            count,
            interval,
            timeout: c.timeout,
            thresholds,
            ours: c.ours,
            version: c.version,
            heartbeat: c.heartbeat,
            signing: c.signing,
            baud: c.baud,
        })
    }

    fn continuous(&self) -> Result<ContinuousLink, ConfigError> {
        let Some(given) = &self.link else {
            return Err(invalid(
                "a [[link]] needs link = \"CONNECTION\", e.g. link = \"udpout:10.0.0.2:14550\"",
            ));
        };
        let c = self.common(Duration::from_secs(2))?;
        let interval = match (self.rate, &self.interval) {
            (Some(_), Some(_)) => return Err(invalid("rate and interval: give one, not both")),
            (Some(rate), None) => {
                if !rate.is_finite() || !(1.0 / 86_400.0..=1000.0).contains(&rate) {
                    return Err(invalid(format!(
                        "rate {rate}: expected at least one request a day and at most 1000 a second"
                    )));
                }
                Duration::from_secs_f64(1.0 / rate)
            }
            (None, Some(d)) => {
                let d = d.get("interval")?;
                if d < MIN_PROBE_INTERVAL || d > Duration::from_secs(86_400) {
                    return Err(invalid(format!(
                        "interval {}: expected 1ms to 1 day",
                        humantime::format_duration(d)
                    )));
                }
                d
            }
            (None, None) => Duration::from_secs(1),
        };
        continuous_link(given, self.name.as_deref(), interval, c)
    }
}

fn continuous_link(
    given: &str,
    name: Option<&str>,
    interval: Duration,
    c: Common,
) -> Result<ContinuousLink, ConfigError> {
    let spec: LinkSpec = given.parse()?;
    refuse_virtual(&spec)?;
    let name = name.unwrap_or(given).trim().to_string();
    if name.is_empty() {
        return Err(invalid(format!("link {given}: its name is empty")));
    }
    Ok(ContinuousLink {
        link: LinkConfig {
            session: session(&name, None, interval, c.timeout, &c)?,
            spec,
            name,
            thresholds: Thresholds::default(),
        },
        probe: c.probe,
        options: LinkOptions {
            baud: c.baud,
            // A broken link is reopened by the server, with backoff, so
            // it shows as down meanwhile.
            reconnect: false,
        },
    })
}

/// `sim:?clock=virtual` needs a runtime of its own, paused.
fn refuse_virtual(spec: &LinkSpec) -> Result<(), ConfigError> {
    if spec.is_virtual() {
        return Err(invalid(
            "sim:?clock=virtual cannot be served: drop clock=virtual (the server runs on real time)",
        ));
    }
    Ok(())
}

fn session(
    name: &str,
    count: Option<u64>,
    interval: Duration,
    timeout: Duration,
    c: &Common,
) -> Result<SessionConfig, ConfigError> {
    Ok(SessionConfig {
        link_name: name.to_string(),
        ours: c.ours,
        interval,
        count,
        deadline: None,
        timeout,
        version: c.version,
        heartbeat: c.heartbeat,
        capacity: pending_capacity(interval, timeout)?,
        first_seq: 0,
        // Many sessions share the server's thread: none may spin.
        precise_pacing: false,
        signing: c.signing,
    })
}

fn validate_count(count: u64) -> Result<u64, ConfigError> {
    if count == 0 || count > MAX_PROBE_COUNT {
        return Err(invalid(format!(
            "count {count}: expected 1 to {MAX_PROBE_COUNT}"
        )));
    }
    Ok(count)
}

fn validate_probe_interval(key: &str, d: Duration) -> Result<Duration, ConfigError> {
    if d < MIN_PROBE_INTERVAL || d > MAX_PROBE_INTERVAL {
        return Err(invalid(format!(
            "{key} {}: a probe's interval is 1ms to 1m",
            humantime::format_duration(d)
        )));
    }
    Ok(d)
}

fn validate_timeout(key: &str, d: Duration, max: Duration) -> Result<Duration, ConfigError> {
    if d.is_zero() || d > max {
        return Err(invalid(format!(
            "{key} {}: expected more than 0 and at most {}",
            humantime::format_duration(d),
            humantime::format_duration(max)
        )));
    }
    Ok(d)
}

/// The built-in module: ten PINGs, 100 ms apart, 1 s timeout.
fn default_module() -> Module {
    Table::default()
        .module()
        .expect("the default module is valid")
}

/// "FILE:LINE: message" from a TOML error, on one line.
fn file_error(path: &Path, text: &str, e: &toml::de::Error) -> ConfigError {
    let line = e
        .span()
        .map(|s| text[..s.start.min(text.len())].matches('\n').count() + 1);
    let message = e.message().lines().next().unwrap_or("invalid TOML");
    match line {
        Some(line) => invalid(format!("{}:{line}: {message}", path.display())),
        None => invalid(format!("{}: {message}", path.display())),
    }
}

/// Names the file and the table an error is about.
fn within(path: &Path, table: &str, e: ConfigError) -> ConfigError {
    invalid(format!("{}: {table}: {e}", path.display()))
}

impl ServeSettings {
    /// The settings from the command line and, when given, the file (read
    /// again at each reload); also the file's `listen`.
    pub fn load(
        args: &ServeArgs,
        path: Option<&Path>,
    ) -> Result<(Self, Option<String>), ConfigError> {
        let file = match path {
            None => File::default(),
            Some(path) => {
                let text = std::fs::read_to_string(path).map_err(|e| {
                    invalid(format!("--config {}: cannot read it: {e}", path.display()))
                })?;
                toml::from_str(&text).map_err(|e| file_error(path, &text, &e))?
            }
        };
        let path = path.unwrap_or(Path::new("--config"));
        let mut allow = Vec::new();
        for p in &args.allow {
            allow.push(Pattern::parse(p).map_err(|e| invalid(format!("--allow: {e}")))?);
        }
        for p in &file.allow {
            allow.push(Pattern::parse(p).map_err(|e| within(path, "allow", e))?);
        }
        let mut modules = BTreeMap::new();
        modules.insert(DEFAULT_MODULE.to_string(), default_module());
        for (name, table) in &file.module {
            let section = format!("[module.{name}]");
            if let Some(key) = table.misplaced(true) {
                return Err(within(
                    path,
                    &section,
                    invalid(format!("{key} belongs in a [[link]], not a module")),
                ));
            }
            let module = table.module().map_err(|e| within(path, &section, e))?;
            modules.insert(name.clone(), module);
        }
        let mut links = Vec::new();
        for given in &args.links {
            let c = Table::default().common(Duration::from_secs(2))?;
            links.push(
                continuous_link(given, None, Duration::from_secs(1), c)
                    .map_err(|e| invalid(format!("--link: {e}")))?,
            );
        }
        for (i, table) in file.link.iter().enumerate() {
            let section = format!("[[link]] #{}", i + 1);
            if let Some(key) = table.misplaced(false) {
                return Err(within(
                    path,
                    &section,
                    invalid(format!(
                        "{key} belongs in a [module.NAME]: a continuous link has no end to judge (alert in Prometheus instead)"
                    )),
                ));
            }
            links.push(table.continuous().map_err(|e| within(path, &section, e))?);
        }
        if links.len() > MAX_LINKS {
            return Err(invalid(format!(
                "{} continuous links: at most {MAX_LINKS}",
                links.len()
            )));
        }
        for (i, l) in links.iter().enumerate() {
            if links[..i].iter().any(|o| o.link.name == l.link.name) {
                return Err(invalid(format!(
                    "two continuous links are named '{}': give each a name of its own (name = \"...\")",
                    l.link.name
                )));
            }
        }
        let max_concurrent = args
            .max_concurrent
            .or(file.max_concurrent)
            .unwrap_or(DEFAULT_MAX_CONCURRENT);
        if max_concurrent == 0 || max_concurrent > MAX_CONCURRENT {
            return Err(invalid(format!(
                "max_concurrent {max_concurrent}: expected 1 to {MAX_CONCURRENT}"
            )));
        }
        Ok((
            ServeSettings {
                allow,
                modules,
                links,
                max_concurrent,
            },
            file.listen,
        ))
    }

    /// A `/probe` request's query string into what to run, or the one line
    /// that says why not (the HTTP 400 body).
    pub fn plan(&self, query: &str) -> Result<ProbePlan, String> {
        let mut params: BTreeMap<String, String> = BTreeMap::new();
        for (key, value) in form_urlencoded::parse(query.as_bytes()) {
            if !["target", "module", "count", "interval", "timeout", "probe"].contains(&&*key) {
                return Err(format!(
                    "unknown parameter '{key}'; /probe takes target, module, count, interval, timeout and probe"
                ));
            }
            if params.insert(key.to_string(), value.to_string()).is_some() {
                return Err(format!("parameter '{key}' is given twice"));
            }
        }
        let Some(target) = params.get("target").map(|t| t.trim()) else {
            return Err(
                "missing target: /probe?target=LINK, e.g. /probe?target=udpout:127.0.0.1:14550"
                    .into(),
            );
        };
        let module_name = params.get("module").map_or(DEFAULT_MODULE, String::as_str);
        let Some(module) = self.modules.get(module_name) else {
            let known: Vec<&str> = self.modules.keys().map(String::as_str).collect();
            return Err(format!(
                "unknown module '{module_name}'; known: {}",
                known.join(", ")
            ));
        };
        let spec: LinkSpec = target
            .parse()
            .map_err(|e: crate::transport::address::AddressError| format!("target: {e}"))?;
        self.admit(target, &spec)?;
        let plan = |e: ConfigError| e.to_string();
        let count = match params.get("count") {
            Some(c) => validate_count(
                c.parse()
                    .map_err(|_| format!("count '{c}': expected a whole number"))?,
            )
            .map_err(plan)?,
            None => module.count,
        };
        let duration = |key: &str| -> Result<Option<Duration>, String> {
            params
                .get(key)
                .map(|d| parse_duration(d).map_err(|e| format!("{key}: {e}")))
                .transpose()
        };
        let interval = match duration("interval")? {
            Some(d) => validate_probe_interval("interval", d).map_err(plan)?,
            None => module.interval,
        };
        let timeout = match duration("timeout")? {
            Some(d) => validate_timeout("timeout", d, MAX_PROBE_TIMEOUT).map_err(plan)?,
            None => module.timeout,
        };
        let kind = match params.get("probe") {
            Some(p) => ProbeKind::from_str(p, true)
                .map_err(|_| format!("probe '{p}': expected ping, timesync or command"))?,
            None => module.kind,
        };
        let probe = probe_of(
            Keys::File,
            &ProbeChoice {
                kind,
                // A module's target is for its own kind of probe; PING has none.
                target: module.target.as_deref().filter(|_| kind != ProbeKind::Ping),
                command: &module.command,
                retry_interval: module.retry_interval,
                retries: module.retries,
            },
        )
        .map_err(plan)?;
        let common = Common {
            probe: probe.clone(),
            kind,
            ours: module.ours,
            version: module.version,
            heartbeat: module.heartbeat,
            signing: module.signing,
            baud: module.baud,
            timeout,
            retry_interval: module.retry_interval,
        };
        Ok(ProbePlan {
            module: module_name.to_string(),
            link: LinkConfig {
                session: session(target, Some(count), interval, timeout, &common).map_err(plan)?,
                spec,
                name: target.to_string(),
                thresholds: module.thresholds.clone(),
            },
            probe,
            options: LinkOptions {
                baud: module.baud,
                reconnect: false,
            },
        })
    }

    /// Default deny: the target must match an allow pattern.
    fn admit(&self, given: &str, spec: &LinkSpec) -> Result<(), String> {
        refuse_virtual(spec).map_err(|e| e.to_string())?;
        if self.allow.is_empty() {
            return Err(format!(
                "target {given} is not allowed: no target is; start mavping serve with \
                 --allow PATTERN (e.g. --allow 'udpout:127.0.0.1:*') or list patterns in \
                 allow = [...] of --config"
            ));
        }
        if !self.allow.iter().any(|p| p.admits(spec)) {
            return Err(format!(
                "target {given} is not allowed: it matches no allow pattern ({})",
                self.allow
                    .iter()
                    .map(Pattern::to_string)
                    .collect::<Vec<_>>()
                    .join(", ")
            ));
        }
        Ok(())
    }
}

impl TryFrom<&ServeArgs> for ServeConfig {
    type Error = ConfigError;

    fn try_from(args: &ServeArgs) -> Result<Self, ConfigError> {
        let (settings, file_listen) = ServeSettings::load(args, args.config.as_deref())?;
        let listen = match (&args.listen, file_listen) {
            (Some(l), _) => validate_listen("--listen", l)?,
            (None, Some(l)) => validate_listen("listen", &l).map_err(|e| {
                within(
                    args.config.as_deref().unwrap_or(Path::new("--config")),
                    "listen",
                    e,
                )
            })?,
            (None, None) => DEFAULT_LISTEN.parse().expect("a valid address"),
        };
        Ok(ServeConfig {
            listen,
            file: args.config.clone(),
            settings,
            verbose: args.verbose,
            args: args.clone(),
        })
    }
}

#[cfg(test)]
mod tests {
    use clap::Parser;

    use super::*;
    use crate::cli::{Cli, Mode};

    fn args(line: &str) -> ServeArgs {
        let cli = Cli::try_parse_from(
            ["mavping", "serve"]
                .into_iter()
                .chain(line.split_whitespace()),
        )
        .unwrap();
        match cli.mode {
            Some(Mode::Serve(a)) => a,
            _ => panic!("not serve"),
        }
    }

    fn with_file(toml: &str) -> Result<ServeConfig, String> {
        let path = std::env::temp_dir().join(format!(
            "mavping-serve-{}-{}.toml",
            std::process::id(),
            toml.len()
        ));
        std::fs::write(&path, toml).unwrap();
        let mut a = args("");
        a.config = Some(path.clone());
        let c = ServeConfig::try_from(&a).map_err(|e| e.to_string());
        std::fs::remove_file(&path).unwrap();
        c
    }

    fn spec(s: &str) -> LinkSpec {
        s.parse().unwrap()
    }

    #[test]
    fn patterns_stand_for_parts_of_an_address() {
        let p = |s| Pattern::parse(s).unwrap();
        assert!(p("udpout:127.0.0.1:*").admits(&spec("udpout:127.0.0.1:14550")));
        assert!(!p("udpout:127.0.0.1:*").admits(&spec("udpout:127.0.0.2:14550")));
        assert!(!p("udpout:127.0.0.1:*").admits(&spec("udpin:127.0.0.1:14550")));
        assert!(p("udpout:10.0.0.*:14550").admits(&spec("udpout:10.0.0.7:14550")));
        // A host name cannot stand in for the last octet.
        assert!(!p("udpout:10.0.0.*:14550").admits(&spec("udpout:10.0.0.5.evil.example:14550")));
        assert!(p("udpout:**").admits(&spec("udpout:gcs.example:14550")));
        // Kinds are compared in their canonical form.
        assert!(p("udp:0.0.0.0:*").admits(&spec("udpin:0.0.0.0:14550")));
        assert!(p("tcpout:127.0.0.1:5760").admits(&spec("tcp:127.0.0.1:5760")));
        // Serial devices, whatever the baud.
        assert!(p("/dev/ttyUSB*").admits(&spec("serial:/dev/ttyUSB0:57600")));
        assert!(p("serial:/dev/ttyUSB*:57600").admits(&spec("/dev/ttyUSB1")));
        assert!(!p("/dev/ttyUSB*").admits(&spec("/dev/ttyS0")));
        assert!(!p("/dev/tty*").admits(&spec("/dev/pts/3")));
        assert!(p("sim:**").admits(&spec("sim:?loss=0.5%")));
        assert!(p("udpout:[::1]:*").admits(&spec("udpout:[::1]:14550")));
        for bad in ["127.0.0.1:*", "*", "udpout:", "sim:"] {
            assert!(Pattern::parse(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn the_command_line_alone_needs_no_file() {
        let c = ServeConfig::try_from(&args("")).unwrap();
        assert_eq!(c.listen, "127.0.0.1:9465".parse().unwrap());
        assert!(c.settings.allow.is_empty() && c.settings.links.is_empty());
        assert_eq!(c.settings.max_concurrent, DEFAULT_MAX_CONCURRENT);
        let e = c
            .settings
            .plan("target=udpout:127.0.0.1:14550")
            .unwrap_err();
        assert!(
            e.contains("no target is; start mavping serve with --allow"),
            "{e}"
        );

        let c = ServeConfig::try_from(&args(
            "--listen [::1]:0 --allow udpout:127.0.0.1:* --link sim: --link udpout:10.0.0.2:14550 --max-concurrent 3",
        ))
        .unwrap();
        assert_eq!(c.listen, "[::1]:0".parse().unwrap());
        assert_eq!(c.settings.max_concurrent, 3);
        let names: Vec<&str> = c
            .settings
            .links
            .iter()
            .map(|l| l.link.name.as_str())
            .collect();
        assert_eq!(names, ["sim:", "udpout:10.0.0.2:14550"]);
        let l = &c.settings.links[1];
        assert_eq!(l.link.session.interval, Duration::from_secs(1));
        assert_eq!(l.link.session.timeout, Duration::from_secs(2));
        assert_eq!(l.link.session.count, None);
        assert_eq!(l.probe, Probe::Ping);

        let p = c
            .settings
            .plan("target=udpout%3A127.0.0.1%3A14550")
            .unwrap();
        assert_eq!(p.module, "default");
        assert_eq!(p.link.name, "udpout:127.0.0.1:14550");
        assert_eq!(p.link.session.count, Some(10));
        assert_eq!(p.link.session.interval, Duration::from_millis(100));
        assert_eq!(p.link.session.timeout, Duration::from_secs(1));
        assert!(!p.link.session.precise_pacing);
        let p = c
            .settings
            .plan("target=udpout:127.0.0.1:9&count=3&interval=20ms&timeout=0.5&probe=timesync")
            .unwrap();
        assert_eq!(p.link.session.count, Some(3));
        assert_eq!(p.link.session.interval, Duration::from_millis(20));
        assert_eq!(p.link.session.timeout, Duration::from_millis(500));
        assert_eq!(
            p.probe,
            Probe::Timesync {
                target: SysComp::new(0, 0)
            }
        );
    }

    #[test]
    fn bad_probe_requests_say_why_on_one_line() {
        let c = ServeConfig::try_from(&args("--allow udpout:127.0.0.1:* --allow sim:**")).unwrap();
        for (query, needle) in [
            ("", "missing target"),
            (
                "target=udpout:10.0.0.1:14550",
                "matches no allow pattern (udpout:127.0.0.1:*, sim:**)",
            ),
            ("target=nowhere", "accepted forms"),
            (
                "target=udpout:127.0.0.1:1&module=fast",
                "unknown module 'fast'; known: default",
            ),
            ("target=udpout:127.0.0.1:1&count=0", "count 0"),
            ("target=udpout:127.0.0.1:1&count=many", "count 'many'"),
            (
                "target=udpout:127.0.0.1:1&count=99999",
                "expected 1 to 10000",
            ),
            ("target=udpout:127.0.0.1:1&interval=0", "1ms to 1m"),
            ("target=udpout:127.0.0.1:1&timeout=2h", "at most 1m"),
            ("target=udpout:127.0.0.1:1&probe=echo", "probe 'echo'"),
            ("target=udpout:127.0.0.1:1&target=sim:", "given twice"),
            (
                "target=udpout:127.0.0.1:1&debug=1",
                "unknown parameter 'debug'",
            ),
            (
                "target=sim:?clock=virtual",
                "clock=virtual cannot be served",
            ),
        ] {
            let e = c.settings.plan(query).unwrap_err();
            assert!(e.contains(needle), "{query}: {e}");
            assert!(!e.contains('\n'), "{e}");
        }
    }

    #[test]
    fn the_file_sets_modules_links_and_limits() {
        let key = std::env::temp_dir().join(format!("mavping-serve-key-{}", std::process::id()));
        std::fs::write(&key, "secret\n").unwrap();
        let c = with_file(&format!(
            r#"
listen = "127.0.0.1:0"
max_concurrent = 4
allow = ["udpout:127.0.0.1:*", "/dev/ttyUSB*"]

[module.strict]
probe = "timesync"
target = "1/1"
count = 20
interval = "50ms"
timeout = 0.5
max_loss = "5%"
max_rtt = ["p99=50ms", "200ms"]
expect = ["1/1"]
signing_key_file = "{}"

[module.default]
count = 3

[[link]]
link = "udpout:10.0.0.2:14550"
name = "gcs-1"
rate = 5
probe = "timesync"

[[link]]
link = "sim:?loss=5%"
interval = "200ms"
timeout = "1s"
"#,
            key.display()
        ));
        std::fs::remove_file(&key).unwrap();
        let c = c.unwrap();
        assert_eq!(c.listen, "127.0.0.1:0".parse().unwrap());
        let s = &c.settings;
        assert_eq!(s.max_concurrent, 4);
        assert_eq!(s.allow.len(), 2);
        let strict = &s.modules["strict"];
        assert_eq!((strict.count, strict.kind), (20, ProbeKind::Timesync));
        assert_eq!(strict.timeout, Duration::from_millis(500));
        assert_eq!(strict.thresholds.max_loss, Some(0.05));
        assert_eq!(strict.thresholds.max_rtt.len(), 2);
        assert!(strict.signing.is_some());
        assert_eq!(s.modules["default"].count, 3);
        let p = s.plan("target=udpout:127.0.0.1:5&module=strict").unwrap();
        assert_eq!(
            p.probe,
            Probe::Timesync {
                target: SysComp::new(1, 1)
            }
        );
        assert_eq!(p.link.thresholds.expect.len(), 1);
        assert!(p.link.session.signing.is_some());
        // PING addresses no one, whatever the module's target.
        let p = s
            .plan("target=/dev/ttyUSB0&module=strict&probe=ping")
            .unwrap();
        assert_eq!(p.probe, Probe::Ping);
        assert_eq!(s.links[0].link.name, "gcs-1");
        assert_eq!(s.links[0].link.session.interval, Duration::from_millis(200));
        assert!(matches!(s.links[0].probe, Probe::Timesync { .. }));
        assert_eq!(s.links[1].link.name, "sim:?loss=5%");
        assert_eq!(s.links[1].link.session.timeout, Duration::from_secs(1));
    }

    #[test]
    fn the_example_in_contrib_is_valid() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("contrib/mavping-serve.toml");
        let (s, listen) = ServeSettings::load(&args(""), Some(&path)).unwrap();
        assert_eq!(listen.as_deref(), Some("0.0.0.0:9465"));
        assert_eq!(s.allow.len(), 3);
        assert!(s.modules.contains_key("ardupilot") && s.modules.contains_key("radio"));
        let names: Vec<&str> = s.links.iter().map(|l| l.link.name.as_str()).collect();
        assert_eq!(names, ["sik-radio", "companion"]);
        assert!(s.plan("target=serial:/dev/ttyUSB3&module=radio").is_ok());
        assert!(s
            .plan("target=udpout:10.0.0.9:14550&module=ardupilot")
            .is_ok());
        assert!(s.plan("target=udpout:10.0.1.9:14550").is_err());
    }

    #[test]
    fn bad_files_name_the_place() {
        for (toml, needle) in [
            ("allow = [\n\"udpout:1.2.3.4:*\",\n 7]", ":3: "),
            ("colour = 1", "unknown field `colour`"),
            ("[module.a]\ncount = 0", "[module.a]: count 0"),
            ("[module.a]\nlink = \"sim:\"", "link belongs in a [[link]]"),
            (
                "[[link]]\nlink = \"sim:\"\nmax_loss = \"5%\"",
                "[[link]] #1: max_loss belongs in a [module.NAME]",
            ),
            ("[[link]]\nname = \"x\"", "needs link ="),
            (
                "[[link]]\nlink = \"sim:\"\nrate = 1\ninterval = 1",
                "give one, not both",
            ),
            (
                "[[link]]\nlink = \"sim:\"\n[[link]]\nlink = \"sim:\"",
                "two continuous links are named 'sim:'",
            ),
            ("[module.a]\nprobe = \"echo\"", "probe 'echo'"),
            (
                "[module.a]\ntarget = \"1/1\"",
                "[module.a]: target: PING requests are always broadcast",
            ),
            ("[module.a]\nsysid = 0", "sysid 0"),
            ("[module.a]\ninterval = \"soon\"", "interval: 'soon'"),
            (
                "[module.a]\nsigning_key_file = \"/nonexistent/k\"",
                "cannot read it",
            ),
            ("max_concurrent = 0", "max_concurrent 0"),
            (
                "listen = \"localhost:1\"",
                "listen: listen localhost:1: expected ADDR:PORT",
            ),
            ("allow = [\"*\"]", "start it with a link kind"),
        ] {
            let e = with_file(toml).unwrap_err();
            assert!(e.contains(needle), "{toml}: {e}");
            assert!(!e.contains('\n'), "{e}");
        }
        let mut a = args("");
        a.config = Some(PathBuf::from("/nonexistent/serve.toml"));
        let e = ServeConfig::try_from(&a).unwrap_err().to_string();
        assert!(
            e.contains("--config /nonexistent/serve.toml: cannot read it"),
            "{e}"
        );
    }
}
