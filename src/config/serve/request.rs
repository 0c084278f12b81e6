//! One `/probe?target=...` query into a [`ProbePlan`], or the one line
//! that says why not (the HTTP 400 body).

use std::collections::BTreeMap;
use std::time::Duration;

use clap::ValueEnum;
use thiserror::Error;

use super::allow::Pattern;
use super::file::PROBES;
use super::limits::{
    validate_count, validate_probe_interval, validate_timeout, DEFAULT_MODULE, MAX_PROBE_TIMEOUT,
};
use super::session::{refuse_virtual, session, Common};
use super::settings::{Module, ServeSettings};
use crate::cli::ProbeKind;
use crate::config::c2::C2Flags;
use crate::config::error::ConfigError;
use crate::config::keys::Keys;
use crate::config::link::LinkConfig;
use crate::config::probe::{probe_of, Probe, ProbeChoice};
use crate::engine::c2::C2Config;
use crate::transport::address::{AddressError, LinkSpec};
use crate::transport::route::Route;
use crate::transport::LinkOptions;
use crate::units::parse_duration;

/// One `/probe` request, validated: what to open and how to measure it.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct ProbePlan {
    pub(crate) module: String,
    pub(crate) link: LinkConfig,
    pub(crate) probe: Probe,
    pub(crate) options: LinkOptions,
}

/// Why a `/probe` request is refused: one line, the HTTP 400 body.
#[derive(Debug, Error)]
pub(crate) enum BadProbeRequest {
    #[error(
        "unknown parameter '{0}'; /probe takes target, module, count, interval, timeout and probe"
    )]
    UnknownParameter(String),
    #[error("parameter '{0}' is given twice")]
    Twice(String),
    #[error("missing target: /probe?target=LINK, e.g. /probe?target=udpout:127.0.0.1:14550")]
    MissingTarget,
    #[error("unknown module '{name}'; known: {}", .known.join(", "))]
    UnknownModule { name: String, known: Vec<String> },
    #[error("target: {0}")]
    Target(#[source] AddressError),
    /// Default deny, and nothing allowed.
    #[error(
        "target {0} is not allowed: no target is; start mavping serve with \
         --allow PATTERN (e.g. --allow 'udpout:127.0.0.1:*') or list patterns in \
         allow = [...] of --config"
    )]
    NoneAllowed(String),
    #[error(
        "target {target} is not allowed: it matches no allow pattern ({})",
        .allow.iter().map(Pattern::to_string).collect::<Vec<_>>().join(", ")
    )]
    NotAllowed { target: String, allow: Vec<Pattern> },
    /// What the module or the command line would refuse alike.
    #[error(transparent)]
    Config(#[from] ConfigError),
}

impl ServeSettings {
    /// A `/probe` request's query string into what to run, or the one line
    /// that says why not (the HTTP 400 body).
    pub(crate) fn plan(&self, query: &str) -> Result<ProbePlan, BadProbeRequest> {
        let mut params: BTreeMap<String, String> = BTreeMap::new();
        for (key, value) in form_urlencoded::parse(query.as_bytes()) {
            let known = [
                "target", "module", "count", "interval", "timeout", "probe", "report",
            ];
            if !known.contains(&&*key) {
                return Err(BadProbeRequest::UnknownParameter(key.to_string()));
            }
            if params.insert(key.to_string(), value.to_string()).is_some() {
                return Err(BadProbeRequest::Twice(key.to_string()));
            }
        }
        let Some(target) = params.get("target").map(|t| t.trim()) else {
            return Err(BadProbeRequest::MissingTarget);
        };
        let module_name = params.get("module").map_or(DEFAULT_MODULE, String::as_str);
        let Some(module) = self.modules.get(module_name) else {
            return Err(BadProbeRequest::UnknownModule {
                name: module_name.to_string(),
                known: self.modules.keys().cloned().collect(),
            });
        };
        let spec: LinkSpec = target.parse().map_err(BadProbeRequest::Target)?;
        self.admit(target, &spec)?;
        let count = match params.get("count") {
            Some(c) => validate_count(c.parse().map_err(|_| ConfigError::Unknown {
                setting: "count",
                value: c.clone(),
                expected: "a whole number",
            })?)?,
            None => module.count,
        };
        let duration = |key: &'static str| -> Result<Option<Duration>, ConfigError> {
            params
                .get(key)
                .map(|d| parse_duration(d).map_err(|e| ConfigError::rejected(key, e)))
                .transpose()
        };
        let interval = match duration("interval")? {
            Some(d) => validate_probe_interval("interval", d)?,
            None => module.interval,
        };
        let timeout = match duration("timeout")? {
            Some(d) => validate_timeout("timeout", d, MAX_PROBE_TIMEOUT)?,
            None => module.timeout,
        };
        let kind = match params.get("probe") {
            Some(p) => ProbeKind::from_str(p, true).map_err(|_| ConfigError::Unknown {
                setting: "probe",
                value: p.clone(),
                expected: PROBES,
            })?,
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
                timeout,
                path: &module.path,
            },
        )?;
        let common = Common {
            probe: probe.clone(),
            kind,
            ours: module.ours,
            version: module.version,
            heartbeat: module.heartbeat,
            signing: module.signing,
            baud: module.baud,
            radio_type: module.radio_type,
            c2: report(params.get("report").map(String::as_str), module, timeout)?,
            timeout,
            retry_interval: module.retry_interval,
        };
        Ok(ProbePlan {
            module: module_name.to_string(),
            link: LinkConfig {
                session: session(&spec, target, Some(count), interval, timeout, &common)?,
                spec,
                name: target.to_string(),
                thresholds: module.thresholds.clone(),
            },
            probe,
            options: LinkOptions {
                baud: module.baud,
                reconnect: false,
                wait_for_peer: false,
                route: Route::default(),
                trust: crate::transport::ws::Trust::default(),
            },
        })
    }

    /// Default deny: the target must match an allow pattern.
    fn admit(&self, given: &str, spec: &LinkSpec) -> Result<(), BadProbeRequest> {
        refuse_virtual(spec)?;
        if self.allow.is_empty() {
            return Err(BadProbeRequest::NoneAllowed(given.to_string()));
        }
        if !self.allow.iter().any(|p| p.admits(spec)) {
            return Err(BadProbeRequest::NotAllowed {
                target: given.to_string(),
                allow: self.allow.clone(),
            });
        }
        Ok(())
    }
}

/// `report=c2` in the query: the module's C2 report settings, else the
/// defaults (as `--report c2` alone).
fn report(
    asked: Option<&str>,
    module: &Module,
    timeout: Duration,
) -> Result<Option<C2Config>, ConfigError> {
    match asked {
        None => Ok(module.c2.clone()),
        Some("c2") if module.c2.is_some() => Ok(module.c2.clone()),
        Some("c2") => crate::config::c2::validate(&C2Flags::defaults(Keys::File, timeout)),
        Some(other) => Err(ConfigError::Unknown {
            setting: "report",
            value: other.to_string(),
            expected: "c2",
        }),
    }
}

#[cfg(test)]
mod tests {
    use super::super::settings::{test_args, ServeConfig};
    use super::*;

    fn settings(line: &str) -> ServeSettings {
        ServeConfig::try_from(&test_args(line)).unwrap().settings
    }

    #[test]
    fn bad_probe_requests_say_why_on_one_line() {
        let s = settings("--allow udpout:127.0.0.1:* --allow sim:**");
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
            let e = s.plan(query).unwrap_err().to_string();
            assert!(e.contains(needle), "{query}: {e}");
            assert!(!e.contains('\n'), "{e}");
        }
    }
}
