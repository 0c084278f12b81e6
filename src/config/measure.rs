//! `mavping [OPTIONS] LINK...` into a [`Config`]: one rule a function, each
//! with an error that names the option and says what would be accepted.

use std::net::SocketAddr;
use std::path::{Path, PathBuf};
use std::time::Duration;

use super::error::ConfigError;
use super::keys::Keys;
use super::link::LinkConfig;
use super::probe::{probe_of, wire_budget, Probe, ProbeChoice, ECHO_PROBES};
use super::signing::signing;
use super::values::{validate_baud, validate_ids, validate_listen, MAX_RATE, MAX_TIMEOUT};
use crate::cli::{Format, PingArgs, ProbeKind, ReportKind};
use crate::engine::matcher::Window;
use crate::engine::SessionConfig;
use crate::frame::signing::SigningConfig;
use crate::frame::Version;
use crate::transport::address::LinkSpec;
use crate::transport::route::Route;
use crate::transport::tlog::writer;
use crate::transport::{Family, LinkOptions};
use crate::verdict::{Expected, Thresholds};

/// More requests than this in flight at once would need an unreasonably
/// large pending table: lower the rate or the timeout.
pub(super) const MAX_IN_FLIGHT: u64 = 1 << 21;
/// The longest interval between requests (the lowest rate).
const MAX_INTERVAL: Duration = Duration::from_secs(86_400);

/// A measurement run over one or more links.
#[derive(Debug, Clone)]
pub(crate) struct Config {
    /// In command-line order; each gets its own session.
    pub(crate) links: Vec<LinkConfig>,
    pub(crate) link_options: LinkOptions,
    pub(crate) probe: Probe,
    pub(crate) output: OutputConfig,
    pub(crate) verbose: u8,
}

/// Where results go.
#[derive(Debug, Clone)]
pub(crate) struct OutputConfig {
    pub(crate) format: Format,
    pub(crate) quiet: bool,
    /// `-D`: event lines start with their Unix time.
    pub(crate) timestamps: bool,
    pub(crate) every_reply: bool,
    /// `--live`; the run falls back to text when stdout is not a terminal.
    pub(crate) live: bool,
    pub(crate) hgrm: Option<PathBuf>,
    pub(crate) samples: Option<PathBuf>,
    pub(crate) plot: Option<PathBuf>,
    pub(crate) prometheus: Option<SocketAddr>,
    /// `--prometheus-textfile`: the run's metrics, written at its end.
    pub(crate) prometheus_textfile: Option<PathBuf>,
    /// `--tlog`: record what every link received and sent.
    pub(crate) tlog: Option<PathBuf>,
}

impl Config {
    /// True when the run should use tokio's paused, virtual clock (only
    /// simulated links with `clock=virtual`; validation rejects a mix).
    pub(crate) fn virtual_clock(&self) -> bool {
        self.links.iter().all(|l| l.spec.is_virtual())
    }
}

/// `--expect LINK=ID`: LINK must be one of the links (as given, or in the
/// form mavping prints it). Returns (index of the link, responder).
fn validate_scoped_expect(
    cli: &PingArgs,
    given: &[String],
    links: &[LinkSpec],
) -> Result<Vec<(usize, Expected)>, ConfigError> {
    let mut scoped = Vec::new();
    for e in &cli.expect {
        let Some(link) = &e.link else { continue };
        let index = given
            .iter()
            .zip(links)
            .position(|(given, spec)| given.trim() == link || spec.to_string() == *link)
            .ok_or_else(|| {
                ConfigError::value(
                    "--expect",
                    format!("{link}={}", e.id),
                    format!("{link} is not one of the links given"),
                )
            })?;
        scoped.push((index, e.id));
    }
    Ok(scoped)
}

/// `-4`/`-6`, `--bind ADDR[:PORT]` (a numeric address: nothing resolved
/// behind the user's back) for links that send first, `-I IFACE`.
fn validate_route(cli: &PingArgs, links: &[LinkConfig]) -> Result<Route, ConfigError> {
    let family = match (cli.ipv4, cli.ipv6) {
        (true, _) => Some(Family::V4),
        (_, true) => Some(Family::V6),
        _ => None,
    };
    let bind = match cli.bind.as_deref() {
        None => None,
        Some(text) => {
            let addr = text
                .parse::<SocketAddr>()
                .or_else(|_| {
                    text.parse::<std::net::IpAddr>()
                        .map(|ip| SocketAddr::new(ip, 0))
                })
                .map_err(|_| {
                    ConfigError::value(
                        "--bind",
                        text,
                        "expected ADDR or ADDR:PORT, e.g. 192.168.1.5 or 0.0.0.0:14551",
                    )
                })?;
            let outgoing = links.iter().any(|l| {
                matches!(
                    l.spec,
                    LinkSpec::UdpOut(_) | LinkSpec::TcpOut(_) | LinkSpec::UdpBcast(_)
                )
            });
            if !outgoing {
                return Err(ConfigError::value(
                    "--bind",
                    text,
                    "only links that send first (udpout:, tcp:, udpbcast:) take a local \
                     address; a listening link names its own",
                ));
            }
            Some(addr)
        }
    };
    let interface = match cli.interface.as_deref() {
        None => None,
        Some(name) if name.is_empty() || name.len() > 15 || name.contains(['/', ' ']) => {
            return Err(ConfigError::value(
                "-I",
                name,
                "expected a network interface name (up to 15 characters), e.g. wlan0",
            ))
        }
        Some(name) if cfg!(mavping_portable) => {
            return Err(ConfigError::InterfaceNeedsLinux {
                interface: name.to_string(),
            })
        }
        Some(name) => Some(name.to_string()),
    };
    Ok(Route {
        family,
        bind,
        interface,
    })
}

/// `-f FILE` (`-` is standard input): a link a line, `#` starts a
/// comment, blank lines are skipped. Errors name the line.
fn links_from_file(path: &Path) -> Result<Vec<(String, LinkSpec)>, ConfigError> {
    let shown = path.display();
    let text = if path == Path::new("-") {
        std::io::read_to_string(std::io::stdin())
    } else {
        std::fs::read_to_string(path)
    }
    .map_err(|source| ConfigError::Unreadable {
        what: format!("-f {shown}"),
        source,
    })?;
    let mut links = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let link = line.split('#').next().unwrap_or_default().trim();
        if link.is_empty() {
            continue;
        }
        let spec = link
            .parse::<LinkSpec>()
            .map_err(|e| ConfigError::from(e).within(format!("-f {shown}, line {}", n + 1)))?;
        links.push((link.to_string(), spec));
    }
    if links.is_empty() {
        return Err(ConfigError::value("-f", shown, "no link in it"));
    }
    Ok(links)
}

/// Several links: each must be named once (reports are keyed by the
/// connection string), and a virtual clock cannot drive real links.
pub(super) fn validate_links(given: &[String], links: &[LinkSpec]) -> Result<(), ConfigError> {
    for (i, link) in links.iter().enumerate() {
        if links[..i].iter().any(|l| l.to_string() == link.to_string()) {
            return Err(ConfigError::SameLink {
                given: given[i].clone(),
                link: link.clone(),
            });
        }
    }
    if links.iter().any(LinkSpec::is_virtual) && !links.iter().all(LinkSpec::is_virtual) {
        if let Some(log) = links.iter().find(|l| l.is_log()) {
            return Err(ConfigError::LogBesideLive { log: log.clone() });
        }
        return Err(ConfigError::VirtualBesideReal);
    }
    Ok(())
}

/// A telemetry log is read, never probed: `--passive` is implied, and an
/// option that only a probe uses is refused, naming the log.
fn refuse_probes_on_logs(cli: &PingArgs, links: &[LinkSpec]) -> Result<(), ConfigError> {
    let Some(log) = links.iter().find(|l| l.is_log()) else {
        return Ok(());
    };
    let probe = match cli.probe {
        ProbeKind::Auto | ProbeKind::Ping => None,
        ProbeKind::Timesync => Some("--probe timesync"),
        ProbeKind::Command => Some("--probe command"),
        ProbeKind::Params => Some("--probe params"),
        ProbeKind::Mission => Some("--probe mission"),
        ProbeKind::Ftp => Some("--probe ftp"),
    };
    let given = probe.or_else(|| {
        [
            (cli.count.is_some(), "-c"),
            (cli.interval.is_some(), "-i"),
            (cli.rate.is_some(), "--rate"),
            (cli.target.is_some(), "--target"),
            (cli.sweep, "--sweep"),
            (!cli.load.is_empty(), "--load"),
        ]
        .into_iter()
        .find_map(|(set, flag)| set.then_some(flag))
    });
    match given {
        Some(flag) => Err(ConfigError::LogProbed {
            flag,
            log: log.clone(),
        }),
        None => Ok(()),
    }
}

/// `--tlog`: the links of a run are told apart in the log by the stamps'
/// two lowest bits, which hold three (the fourth marks what we sent); a
/// telemetry log read is not recorded again.
fn validate_tlog(cli: &PingArgs, given: &[String], links: &[LinkSpec]) -> Result<(), ConfigError> {
    let Some(path) = &cli.tlog else {
        return Ok(());
    };
    let shown = path.display();
    if let Some(log) = links.iter().find(|l| l.is_log()) {
        return Err(ConfigError::value(
            "--tlog",
            shown,
            format!("{log} is a telemetry log already; --tlog records live links"),
        ));
    }
    if links.len() > writer::MAX_LINKS {
        return Err(ConfigError::value(
            "--tlog",
            shown,
            format!(
                "records at most {} links in one log (the stamps' link bits), not {}: run {} \
                 separately",
                writer::MAX_LINKS,
                links.len(),
                given[writer::MAX_LINKS..].join(" ")
            ),
        ));
    }
    Ok(())
}

/// `--plot`: only SVG; the PNG backend needs system font libraries.
fn validate_plot(path: &Path) -> Result<PathBuf, ConfigError> {
    let svg = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("svg"));
    if !svg {
        return Err(ConfigError::value(
            "--plot",
            path.display(),
            "only .svg files can be drawn",
        ));
    }
    Ok(path.to_path_buf())
}

/// node_exporter's textfile collector reads `*.prom` files only.
fn validate_textfile(path: &Path) -> Result<PathBuf, ConfigError> {
    if path.extension().is_none_or(|e| e != "prom") {
        return Err(ConfigError::value(
            "--prometheus-textfile",
            path.display(),
            "node_exporter's textfile collector reads only files named *.prom",
        ));
    }
    Ok(path.to_path_buf())
}

/// The live view, exporter, plot and sample log follow echo probes'
/// replies; a command probe has none.
fn validate_views(cli: &PingArgs) -> Result<(), ConfigError> {
    if cli.probe == ProbeKind::Command {
        for (set, flag) in [
            (cli.live, "--live"),
            (cli.prometheus.is_some(), "--prometheus"),
            (cli.prometheus_textfile.is_some(), "--prometheus-textfile"),
            (cli.plot.is_some(), "--plot"),
            (cli.samples.is_some(), "--samples"),
        ] {
            if set {
                return Err(ConfigError::WorksWith {
                    setting: flag,
                    with: ECHO_PROBES,
                });
            }
        }
    }
    if cli.live && (cli.json || cli.format == Format::Json) {
        return Err(ConfigError::Other(
            "--live cannot be used with --json".into(),
        ));
    }
    Ok(())
}

fn validate_interval(cli: &PingArgs) -> Result<Duration, ConfigError> {
    let interval = match (cli.rate, cli.interval) {
        (Some(rate), _) => {
            if !rate.is_finite() || rate <= 0.0 || rate > MAX_RATE {
                return Err(ConfigError::value(
                    "--rate",
                    rate,
                    format!("expected more than 0 and at most {MAX_RATE} requests per second"),
                ));
            }
            // A tiny rate would mean an interval past what a Duration holds.
            if rate < 1.0 / MAX_INTERVAL.as_secs_f64() {
                return Err(ConfigError::value(
                    "--rate",
                    rate,
                    "at least one request a day (1.2e-5 per second)",
                ));
            }
            Duration::from_secs_f64(1.0 / rate)
        }
        (None, Some(interval)) => interval,
        (None, None) => match super::sweep::default_rate(cli) {
            Some(rate) => Duration::from_secs_f64(1.0 / rate),
            None => Duration::from_secs(1),
        },
    };
    if interval < Duration::from_micros(1) {
        return Err(ConfigError::value(
            "--interval",
            humantime::format_duration(interval),
            "at least 1us (1,000,000 requests per second)",
        ));
    }
    if interval > MAX_INTERVAL {
        return Err(ConfigError::value(
            "--interval",
            humantime::format_duration(interval),
            "at most 1 day",
        ));
    }
    Ok(interval)
}

fn validate_signing(cli: &PingArgs) -> Result<Option<SigningConfig>, ConfigError> {
    let policy = signing(&cli.signing, cli.require_signed)?;
    if policy.is_none() && cli.require_signed {
        return Err(ConfigError::Needs {
            setting: "--require-signed",
            needs: "a signing key (--signing-key, MAVPING_SIGNING_KEY or --signing-key-file)",
        });
    }
    if policy.is_some() && cli.mavlink_version == 1 {
        return Err(ConfigError::SignedMavlink1 {
            mavlink: "--mavlink",
            hint: " (drop --mavlink 1)",
        });
    }
    Ok(policy)
}

/// Ring size: twice the requests that can be in flight within one
/// timeout, so a late reply is still recognised for about one more timeout.
pub(super) fn pending_capacity(
    interval: Duration,
    timeout: Duration,
) -> Result<usize, ConfigError> {
    let in_flight = (timeout.as_nanos() / interval.as_nanos()) as u64 + 1;
    if in_flight > MAX_IN_FLIGHT {
        return Err(ConfigError::InFlight {
            timeout,
            interval,
            in_flight,
            max: MAX_IN_FLIGHT,
        });
    }
    Ok(((in_flight * 2 + 16) as usize).next_power_of_two().max(64))
}

/// How long a listening link waits for its first peer before the run ends:
/// `--wait`, else what `-c` takes plus one timeout; other links do not
/// wait for a peer (they send from the start).
fn peer_wait(cli: &PingArgs, spec: &LinkSpec, session: &SessionConfig) -> Option<Duration> {
    if !listens(spec) {
        return None;
    }
    cli.wait
        .or_else(|| count_wait(cli.count?, session.interval, session.timeout))
}

/// A link that waits for its peers to send first.
pub(super) fn listens(spec: &LinkSpec) -> bool {
    matches!(spec, LinkSpec::UdpIn(_) | LinkSpec::TcpIn(_))
}

/// What `count` requests take at `interval`, plus one timeout: how long a
/// listening link with a count waits for a peer (`-c`, a `/probe`).
pub(super) fn count_wait(count: u64, interval: Duration, timeout: Duration) -> Option<Duration> {
    let count = u32::try_from(count).unwrap_or(u32::MAX);
    interval
        .checked_mul(count)
        .and_then(|d| d.checked_add(timeout))
        .map(|d| d.min(crate::units::MAX_DURATION))
}

fn validate_probe(cli: &PingArgs, links: &[LinkSpec]) -> Result<Probe, ConfigError> {
    let logs = links.iter().any(LinkSpec::is_log);
    if cli.gap.is_some() && !cli.passive && !logs {
        return Err(ConfigError::WorksWith {
            setting: "--gap",
            with: "--passive (or a tlog: link, which is passive)",
        });
    }
    if cli.passive || logs {
        if cli.gap.is_some_and(|g| g < Duration::from_millis(10)) {
            return Err(ConfigError::Expected {
                setting: "--gap",
                expected: "at least 10ms",
            });
        }
        return Ok(Probe::Passive { gap: cli.gap });
    }
    // A sweep or a load run measures one exchange whose frame sizes its
    // wire figures and knee are in: under `auto` that is PING (an
    // ArduPilot is swept with --probe timesync).
    let in_steps = cli.sweep || !cli.load.is_empty();
    let kind = match cli.probe {
        ProbeKind::Auto if in_steps => ProbeKind::Ping,
        kind => kind,
    };
    probe_of(
        Keys::Flags,
        &ProbeChoice {
            kind,
            target: cli.target.as_deref(),
            command: &cli.command,
            retry_interval: cli.retry_interval,
            retries: cli.retries,
            timeout: cli.timeout,
            path: &cli.path,
        },
    )
}

/// The session settings every link shares; each link then names its own.
fn session(
    cli: &PingArgs,
    links: &[LinkSpec],
    probe: &Probe,
) -> Result<SessionConfig, ConfigError> {
    super::sweep::validate_flags(cli)?;
    let interval = validate_interval(cli)?;
    if cli.count == Some(0) {
        return Err(ConfigError::value("--count", 0, "expected at least 1"));
    }
    if cli.timeout.is_zero() || cli.timeout > MAX_TIMEOUT {
        return Err(ConfigError::value(
            "--timeout",
            humantime::format_duration(cli.timeout),
            "expected more than 0 and at most 1h",
        ));
    }
    if cli.deadline.is_some_and(|d| d.is_zero()) {
        return Err(ConfigError::value("--deadline", 0, "expected more than 0"));
    }
    if cli.wait.is_some_and(|d| d.is_zero()) {
        return Err(ConfigError::value("--wait", 0, "expected more than 0"));
    }
    if cli.interim.is_some_and(|d| d < Duration::from_millis(10)) {
        return Err(ConfigError::Expected {
            setting: "-Q",
            expected: "an interval of at least 10ms",
        });
    }
    let ours = validate_ids(cli.sysid, cli.compid)?;
    let signing = validate_signing(cli)?;
    let echo = !matches!(probe, Probe::Command(_) | Probe::Transfer(_));
    // A download is made once unless -c asks for more.
    let count = match probe {
        Probe::Transfer(_) => cli.count.or(Some(1)),
        _ => cli.count,
    };
    Ok(SessionConfig {
        link_name: String::new(),
        ours,
        interval,
        count,
        deadline: cli.deadline,
        // Each link sets its own: only listening links wait for a peer.
        wait: None,
        interim: cli.interim,
        timeout: cli.timeout,
        version: if cli.mavlink_version == 1 {
            Version::V1
        } else {
            Version::V2
        },
        // A log is read: nothing is sent on it.
        heartbeat: !cli.no_heartbeat && !links.iter().any(LinkSpec::is_log),
        answer: !cli.no_answer && !links.iter().any(LinkSpec::is_log),
        capacity: pending_capacity(interval, cli.timeout)?,
        // A run streams: a responder that joins it late is not blamed
        // for the time before.
        window: Window::FirstAnswer,
        first_seq: cli.first_seq,
        // Several links share one thread: a session must not spin there
        // while another's replies wait. Commands go out at most every few
        // ms: tokio's timer is precise enough.
        precise_pacing: echo && links.len() == 1 && !matches!(links[0], LinkSpec::Sim(_)),
        signing,
        sweep: None,
        // Each link has its own.
        wire: None,
        radio_type: cli.radio_type.into(),
        c2: super::c2::validate(&super::c2::C2Flags {
            keys: super::keys::Keys::Flags,
            asked: cli.report == Some(ReportKind::C2),
            up_within: cli.up_within,
            continuity_within: cli.continuity_within,
            distance_band_m: cli.distance_band,
            failsafes: &cli.failsafe,
            min_availability: cli.min_availability.map(|r| r * 100.0),
            min_continuity: cli.min_continuity.map(|r| r * 100.0),
            timeout: cli.timeout,
        })?,
    })
}

/// Where and how the run reports.
fn output(cli: &PingArgs) -> Result<OutputConfig, ConfigError> {
    Ok(OutputConfig {
        format: if cli.json { Format::Json } else { cli.format },
        // -Q is quiet with interim summaries, as fping's.
        quiet: cli.quiet || cli.interim.is_some(),
        timestamps: cli.timestamps,
        every_reply: cli.every_reply,
        live: cli.live,
        hgrm: cli.hgrm.clone(),
        samples: cli.samples.clone(),
        plot: cli.plot.as_deref().map(validate_plot).transpose()?,
        tlog: cli.tlog.clone(),
        prometheus: cli
            .prometheus
            .as_deref()
            .map(|a| validate_listen("--prometheus", a))
            .transpose()?,
        prometheus_textfile: cli
            .prometheus_textfile
            .as_deref()
            .map(validate_textfile)
            .transpose()?,
    })
}

/// The run's links, as given and parsed: the command line's, then those
/// of `-f`.
fn links_given(cli: &PingArgs) -> Result<(Vec<String>, Vec<LinkSpec>), ConfigError> {
    let mut given: Vec<String> = cli.links.iter().map(|l| l.trim().to_string()).collect();
    let mut specs = given
        .iter()
        .map(|l| l.parse::<LinkSpec>())
        .collect::<Result<Vec<_>, _>>()?;
    if let Some(path) = &cli.file {
        for (link, spec) in links_from_file(path)? {
            given.push(link);
            specs.push(spec);
        }
    }
    if given.is_empty() {
        return Err(ConfigError::Other(
            "missing CONNECTION (e.g. udp:127.0.0.1:14550 or sim:)".into(),
        ));
    }
    validate_links(&given, &specs)?;
    Ok((given, specs))
}

impl TryFrom<&PingArgs> for Config {
    type Error = ConfigError;

    fn try_from(cli: &PingArgs) -> Result<Self, ConfigError> {
        let (given, specs) = links_given(cli)?;
        if cli.min_responders == Some(0) {
            return Err(ConfigError::value(
                "--min-responders",
                0,
                "expected at least 1",
            ));
        }
        validate_baud(cli.baud)?;
        validate_views(cli)?;
        refuse_probes_on_logs(cli, &specs)?;
        validate_tlog(cli, &given, &specs)?;
        let probe = validate_probe(cli, &specs)?;
        let session = session(cli, &specs, &probe)?;
        let everywhere = Thresholds {
            max_loss: cli.max_loss,
            max_rtt: cli.max_rtt.clone(),
            max_jitter: cli.max_jitter,
            max_age: cli.max_age,
            max_transfer_time: cli.max_transfer_time,
            min_availability: cli.min_availability.map(|r| r * 100.0),
            min_continuity: cli.min_continuity.map(|r| r * 100.0),
            expect: cli
                .expect
                .iter()
                .filter(|e| e.link.is_none())
                .map(|e| e.id)
                .collect(),
            min_responders: cli.min_responders,
        };
        let scoped = validate_scoped_expect(cli, &given, &specs)?;
        let several = specs.len() > 1;
        let mut links: Vec<LinkConfig> = Vec::new();
        for (index, (spec, name)) in specs.into_iter().zip(given).enumerate() {
            let mut thresholds = everywhere.clone();
            thresholds.expect.extend(
                scoped
                    .iter()
                    .filter(|(i, _)| *i == index)
                    .map(|(_, id)| *id),
            );
            let session = SessionConfig {
                wire: wire_budget(&spec, cli.baud, &probe, &session),
                ..session.clone()
            };
            let sweep = super::sweep::for_link(cli, &session)?;
            // The pending table holds what the fastest step keeps in flight.
            let capacity = match &sweep {
                Some(s) => pending_capacity(
                    Duration::from_secs_f64(1.0 / super::sweep::fastest_hz(s)),
                    session.timeout,
                )?,
                None => session.capacity,
            };
            links.push(LinkConfig {
                session: SessionConfig {
                    wait: peer_wait(cli, &spec, &session),
                    // Alone, a link is headed by its full form (the
                    // defaults of `sim:` spelled out); beside others, by
                    // the name it was given.
                    link_name: if several {
                        name.clone()
                    } else {
                        spec.to_string()
                    },
                    capacity,
                    sweep,
                    ..session.clone()
                },
                spec,
                name,
                thresholds,
            });
        }
        let route = validate_route(cli, &links)?;
        Ok(Config {
            links,
            link_options: LinkOptions {
                baud: cli.baud,
                reconnect: cli.reconnect,
                wait_for_peer: false,
                route,
                trust: super::link::trust(cli.cacert.as_deref())?,
            },
            probe,
            output: output(cli)?,
            verbose: cli.verbose,
        })
    }
}

#[cfg(test)]
mod tests {
    use clap::Parser;

    use super::*;
    use crate::cli::Cli;
    use crate::engine::CommandSpec;
    use crate::frame::signing::SecretKey;
    use crate::frame::SysComp;

    fn config(args: &str) -> Result<Config, String> {
        let cli = Cli::try_parse_from(std::iter::once("mavping").chain(args.split_whitespace()))
            .map_err(|e| e.to_string())?;
        Config::try_from(&cli.ping).map_err(|e| e.to_string())
    }

    #[test]
    fn good_argument_lines() {
        let c = config("sim:").unwrap();
        assert_eq!(c.links[0].session.interval, Duration::from_secs(1));
        assert_eq!(c.links[0].session.timeout, Duration::from_secs(2));
        assert_eq!(c.links[0].session.ours, SysComp::new(250, 190));
        assert_eq!(c.links[0].session.capacity, 64);
        let c =
            config("-c 5 -i 0.2 -W 500ms --sysid 200 --compid 1 udpout:127.0.0.1:14550").unwrap();
        assert_eq!(c.links[0].session.count, Some(5));
        assert_eq!(c.links[0].session.interval, Duration::from_millis(200));
        assert_eq!(c.links[0].session.timeout, Duration::from_millis(500));
        let c = config("--rate 1000 -W 1s sim:").unwrap();
        assert_eq!(c.links[0].session.interval, Duration::from_millis(1));
        assert_eq!(c.links[0].session.capacity, 2048);
        assert!(config("sim:?clock=virtual").unwrap().virtual_clock());
        let c = config(
            "--json --max-loss 5% --max-rtt p99=50ms --max-rtt 1s --expect 1 --expect 2/1 sim:",
        )
        .unwrap();
        assert_eq!(c.output.format, Format::Json);
        let t = &c.links[0].thresholds;
        assert_eq!(t.max_loss, Some(0.05));
        assert_eq!(t.max_rtt.len(), 2);
        assert_eq!(t.max_rtt[1].figure, crate::verdict::RttFigure::Max);
        assert_eq!(
            t.expect[1],
            crate::verdict::Expected {
                sysid: 2,
                compid: Some(1)
            }
        );
        let c = config("/dev/ttyUSB0").unwrap();
        assert_eq!(c.link_options, LinkOptions::default());
        assert_eq!(c.link_options.baud, 115_200);
        let c = config("--baud 57600 --reconnect tcp:127.0.0.1:5760").unwrap();
        assert_eq!(
            c.link_options,
            LinkOptions {
                baud: 57600,
                reconnect: true,
                wait_for_peer: false,
                route: Route::default(),
                trust: crate::transport::ws::Trust::default(),
            }
        );
        assert_eq!(config("sim:").unwrap().probe, Probe::Auto);
        assert_eq!(config("--sweep sim:").unwrap().probe, Probe::Ping);
        assert_eq!(
            config("--load ATTITUDE@10 sim:").unwrap().probe,
            Probe::Ping
        );
        assert_eq!(config("--probe ping sim:").unwrap().probe, Probe::Ping);
        assert_eq!(
            config("--probe timesync sim:").unwrap().probe,
            Probe::Timesync {
                target: SysComp::new(0, 0)
            }
        );
        assert_eq!(
            config("--probe timesync --target 1 sim:").unwrap().probe,
            Probe::Timesync {
                target: SysComp::new(1, 0)
            }
        );
        assert_eq!(
            config("--probe command sim:").unwrap().probe,
            Probe::Command(CommandSpec {
                target: SysComp::new(1, 1),
                command: 512,
                params: [0.0; 7],
                retry_interval: Duration::from_millis(100),
                retries: 3,
            })
        );
        let Probe::Command(c) = config(
            "--probe command --target 3/4 --command 400,1,21196 --retry-interval 50ms --retries 9 sim:",
        )
        .unwrap()
        .probe
        else {
            panic!("not a command probe")
        };
        assert_eq!((c.target, c.command), (SysComp::new(3, 4), 400));
        assert_eq!(c.params, [1.0, 21196.0, 0.0, 0.0, 0.0, 0.0, 0.0]);
        assert_eq!(
            (c.retry_interval, c.retries),
            (Duration::from_millis(50), 9)
        );
        let Probe::Command(c) =
            config("--probe command --command mav_cmd_request_message,245 sim:")
                .unwrap()
                .probe
        else {
            panic!("not a command probe")
        };
        assert_eq!((c.command, c.params[0]), (512, 245.0));
        let c = config("--live --prometheus [::1]:9100 --plot out/RTT.SVG sim:").unwrap();
        assert!(c.output.live);
        assert_eq!(c.output.prometheus, Some("[::1]:9100".parse().unwrap()));
        assert_eq!(c.output.plot, Some(PathBuf::from("out/RTT.SVG")));
        let c = config("-c 3 --json --samples s.csv --hgrm h.hgrm sim: sim:?delay=50ms").unwrap();
        assert_eq!(c.links.len(), 2);
        let names: Vec<&str> = c.links.iter().map(|l| l.name.as_str()).collect();
        assert_eq!(names, ["sim:", "sim:?delay=50ms"]);
        assert_eq!(c.links[1].session.link_name, "sim:?delay=50ms");
        assert!(!c.links[0].session.precise_pacing, "links share one thread");
        assert!(!c.virtual_clock());
        assert!(config("sim:?clock=virtual sim:?delay=5ms&clock=virtual")
            .unwrap()
            .virtual_clock());
        let c = config("--expect 1 --expect sim:?delay=50ms=2/1 sim: sim:?delay=50ms").unwrap();
        let two_one = Expected {
            sysid: 2,
            compid: Some(1),
        };
        assert_eq!(c.links[0].thresholds.expect.len(), 1);
        assert_eq!(c.links[1].thresholds.expect.len(), 2);
        assert_eq!(c.links[1].thresholds.expect[1], two_one);
        // By the form mavping prints, too; with one link it is a plain --expect.
        let c = config(
            "--expect sim:?responders=1&delay=10ms&jitter=2ms&loss=0%&dup=0%&reorder=0%&seed=1=2/1 sim:",
        )
        .unwrap();
        assert_eq!(c.links[0].thresholds.expect, vec![two_one]);
        let c = config("--probe timesync --prometheus 0.0.0.0:0 sim:").unwrap();
        assert_eq!(c.output.prometheus, Some("0.0.0.0:0".parse().unwrap()));
    }

    #[test]
    fn sweep_and_load_lines() {
        use crate::engine::sweep::{MaxFrom, PlanKind};
        let c = config("--sweep sim:?baud=57600").unwrap();
        let session = &c.links[0].session;
        let sweep = session.sweep.as_ref().unwrap();
        // From 2/s up to twice what 57600 baud carries (5760 B/s over a
        // 24-byte request and a 26-byte reply: 115.2/s).
        let PlanKind::Sweep {
            first_hz,
            max_hz,
            max_from,
            loss_limit,
        } = sweep.plan
        else {
            panic!("not a sweep")
        };
        assert_eq!((first_hz, max_hz, loss_limit), (2.0, 230.0, 0.2));
        assert!(matches!(max_from, MaxFrom::Baud { baud: 57_600, .. }));
        assert_eq!(sweep.step, Duration::from_secs(5));
        assert_eq!(session.interval, Duration::from_millis(500));
        // The pending table holds what 230/s keeps in flight for 2 s.
        assert_eq!(session.capacity, 1024);
        assert_eq!(session.count, None);
        let c = config(
            "--sweep --rate 10 --sweep-max 500 --step 2s --sweep-loss 5% udpout:127.0.0.1:14550",
        )
        .unwrap();
        let sweep = c.links[0].session.sweep.clone().unwrap();
        assert_eq!(
            sweep.plan,
            PlanKind::Sweep {
                first_hz: 10.0,
                max_hz: 500.0,
                max_from: MaxFrom::Given,
                loss_limit: 0.05
            }
        );
        assert_eq!(sweep.step, Duration::from_secs(2));
        let c = config("--sweep udpout:127.0.0.1:14550").unwrap();
        let PlanKind::Sweep {
            max_hz, max_from, ..
        } = c.links[0].session.sweep.as_ref().unwrap().plan
        else {
            panic!("not a sweep")
        };
        assert_eq!((max_hz, max_from), (1000.0, MaxFrom::Default));
        // --load alone: 10/s unless told, one step without, one with.
        let c = config("--load ATTITUDE@50 --load BYTES@1170 sim:").unwrap();
        let sweep = c.links[0].session.sweep.as_ref().unwrap();
        assert_eq!(sweep.plan, PlanKind::Load { rate_hz: 10.0 });
        assert_eq!(sweep.load.len(), 2);
        assert_eq!(sweep.load_bytes_per_s, 50.0 * 40.0 + 1170.0);
        let c = config("--load ATTITUDE@50 -i 0.05 sim:").unwrap();
        let sweep = c.links[0].session.sweep.as_ref().unwrap();
        assert_eq!(sweep.plan, PlanKind::Load { rate_hz: 20.0 });
        assert!(config("sim:").unwrap().links[0].session.sweep.is_none());
        // Signed, every load frame is 13 bytes longer.
        let c = config("--load ATTITUDE@50 --signing-key k sim:").unwrap();
        assert_eq!(
            c.links[0].session.sweep.as_ref().unwrap().load_bytes_per_s,
            50.0 * 53.0
        );

        for (line, error) in [
            ("--sweep -c 5 sim:", "-c does not apply"),
            ("--load ATTITUDE@5 -c 5 sim:", "--load runs in steps"),
            ("--sweep-max 100 sim:", "--sweep-max needs --sweep"),
            ("--sweep-loss 5% sim:", "--sweep-loss needs --sweep"),
            ("--step 2s sim:", "--step needs --sweep or --load"),
            (
                "--sweep --probe command sim:",
                "with --probe ping and timesync",
            ),
            (
                "--load ATTITUDE@5 --probe command sim:",
                "--load works with",
            ),
            ("--sweep --max-loss 5% sim:", "loses on purpose"),
            ("--sweep --max-rtt 1s sim:", "loses on purpose"),
            (
                "--sweep --rate 100 --sweep-max 50 sim:",
                "--sweep-max 50: expected more than the first step's 100/s",
            ),
            ("--sweep --sweep-max 1e9 sim:", "at most 1000000"),
            (
                "--sweep --step 10ms sim:",
                "--step 10ms: expected 100ms to 1h",
            ),
            (
                "--sweep --sweep-loss 0 sim:",
                "--sweep-loss 0: expected more than 0%",
            ),
            ("--load FOO@5 sim:", "unknown message FOO"),
            ("--load ATTITUDE@0 sim:", "above 0"),
        ] {
            let e = config(line).unwrap_err();
            assert!(e.contains(error), "{line}: {e}");
        }
    }

    #[test]
    fn signing_lines() {
        let hex = "000102030405060708090a0b0c0d0e0f101112131415161718191a1b1c1d1e1f";
        let c = config(&format!("--signing-key {hex} sim:")).unwrap();
        let s = c.links[0].session.signing.expect("signing on");
        let mut bytes = [0u8; 32];
        for (i, b) in bytes.iter_mut().enumerate() {
            *b = i as u8;
        }
        assert_eq!(s.key, SecretKey::from_bytes(bytes));
        assert_eq!((s.link_id, s.require_signed), (0, false));
        let s = config("--signing-key pass --signing-link-id 9 --require-signed sim:")
            .unwrap()
            .links[0]
            .session
            .signing
            .unwrap();
        assert_eq!(s.key, SecretKey::parse("pass").unwrap());
        assert_eq!((s.link_id, s.require_signed), (9, true));
        assert!(config("sim:").unwrap().links[0].session.signing.is_none());

        let file = std::env::temp_dir().join(format!("mavping-key-{}", std::process::id()));
        std::fs::write(&file, "  pass\n").unwrap();
        let from_file = config(&format!("--signing-key-file {} sim:", file.display()));
        std::fs::remove_file(&file).unwrap();
        assert_eq!(
            from_file.unwrap().links[0].session.signing.unwrap().key,
            SecretKey::parse("pass").unwrap()
        );

        for (line, error) in [
            (
                "--require-signed sim:",
                "--require-signed needs a signing key",
            ),
            (
                "--signing-key k --mavlink 1 sim:",
                "signing needs MAVLink 2",
            ),
            (
                "--signing-key-file /nonexistent/key sim:",
                "--signing-key-file /nonexistent/key: cannot read it",
            ),
            (
                "--signing-key k --signing-key-file /x sim:",
                "give one, not both",
            ),
            ("--signing-link-id 256 --signing-key k sim:", "256"),
        ] {
            let e = config(line).unwrap_err();
            assert!(e.contains(error), "{line}: {e}");
        }
    }

    #[test]
    fn several_links_take_every_probe_and_the_plot() {
        let c = config("--probe command --target 1/1 sim: sim:?delay=5ms").unwrap();
        assert!(matches!(c.probe, Probe::Command(_)));
        assert_eq!(c.links.len(), 2);
        let c = config("--plot a.svg sim: sim:?delay=5ms").unwrap();
        assert_eq!(c.output.plot, Some(PathBuf::from("a.svg")));
        // One link alone is headed by its full form.
        let c = config("udpout:127.0.0.1:14550").unwrap();
        assert_eq!(c.links[0].name, "udpout:127.0.0.1:14550");
        assert!(c.links[0].session.precise_pacing);
        assert!(
            !config("--probe command udpout:127.0.0.1:14550")
                .unwrap()
                .links[0]
                .session
                .precise_pacing
        );
    }

    #[test]
    fn bad_argument_lines_say_why() {
        for (args, needle) in [
            ("--sysid 0 sim:", "--sysid 0"),
            ("--compid 0 sim:", "--compid 0"),
            ("--sysid 256 sim:", "256"),
            ("-c 0 sim:", "--count 0"),
            ("--rate 0 sim:", "--rate 0"),
            ("--rate -5 sim:", "-5"),
            ("--rate 1e9 sim:", "at most"),
            ("-i 0 sim:", "at least 1us"),
            ("-W 0 sim:", "--timeout"),
            ("-W 2h sim:", "at most 1h"),
            ("-w 0 sim:", "--deadline 0"),
            ("-i soon sim:", "soon"),
            ("--rate 1e-30 sim:", "at least one request a day"),
            ("-i 2d sim:", "at most 1 day"),
            ("--rate 100000 -W 1h sim:", "in flight"),
            ("-i 1s --rate 5 sim:", "cannot be used with"),
            ("udpout:nowhere", "accepted forms"),
            ("--mavlink 3 sim:", "3"),
            ("--max-loss 101% sim:", "percentage"),
            ("--max-rtt p42=1ms sim:", "p42"),
            ("--max-rtt p99=fast sim:", "fast"),
            ("--expect 0 sim:", "SYSID"),
            ("--expect 1/300 sim:", "SYSID"),
            ("--min-responders 0 sim:", "--min-responders 0"),
            ("--format xml sim:", "xml"),
            ("--baud 0 /dev/ttyUSB0", "--baud 0"),
            ("--baud fast /dev/ttyUSB0", "fast"),
            ("--probe echo sim:", "echo"),
            ("--target 1/1 sim:", "--target"),
            ("--probe timesync --target 1/x sim:", "SYS/COMP"),
            ("--probe timesync --target 300 sim:", "SYS/COMP"),
            ("--probe command --target 0/1 sim:", "one target system"),
            (
                "--prometheus 9090 sim:",
                "--prometheus 9090: expected ADDR:PORT",
            ),
            ("--prometheus localhost:9090 sim:", "expected ADDR:PORT"),
            ("--prometheus 127.0.0.1:99999 sim:", "99999"),
            ("--plot rtt.png sim:", "--plot rtt.png: only .svg"),
            ("--plot rtt sim:", "only .svg"),
            ("--live --json sim:", "--live cannot be used with --json"),
            ("--live --probe command sim:", "--live works with"),
            (
                "--prometheus 127.0.0.1:9090 --probe command sim:",
                "--prometheus works with",
            ),
            ("--plot a.svg --probe command sim:", "--plot works with"),
            ("--probe command --command FLY_TO_MOON sim:", "FLY_TO_MOON"),
            ("--probe command --command 512,a sim:", "param 1"),
            (
                "--probe command --command 512,1,2,3,4,5,6,7,8 sim:",
                "at most 7",
            ),
            (
                "--probe command --retry-interval 0 sim:",
                "--retry-interval",
            ),
            ("--probe command --retries 300 sim:", "300"),
            (
                "sim: sim:?delay=10ms",
                "sim:?delay=10ms names the same link",
            ),
            (
                "sim: sim:?clock=virtual&delay=5ms",
                "clock=virtual cannot run beside",
            ),
            (
                "--samples s.csv --probe command sim:",
                "--samples works with",
            ),
            ("sim: udpout:nowhere", "accepted forms"),
            (
                "--expect udp:1.2.3.4:5=1 sim: sim:?delay=5ms",
                "--expect udp:1.2.3.4:5=1: udp:1.2.3.4:5 is not one of the links given",
            ),
            ("--expect sim:=1/0 sim:", "LINK=SYSID"),
            ("-c 5 tlog:a.tlog", "-c: tlog:a.tlog is a telemetry log"),
            ("--probe timesync a.tlog", "--probe timesync: tlog:a.tlog"),
            ("--rate 5 tlog:-", "--rate: tlog:- is a telemetry log"),
            ("--load ATTITUDE@10 tlog:-", "--load: tlog:-"),
            (
                "tlog:a.tlog sim:",
                "tlog:a.tlog runs on the log's own clock",
            ),
            ("tlog:", "missing file"),
            ("--gap 2s sim:", "--gap works with --passive"),
        ] {
            let err = config(args).unwrap_err();
            assert!(err.contains(needle), "{args}: {err}");
        }
    }

    #[test]
    fn a_log_is_passive_sends_nothing_and_runs_on_its_own_clock() {
        let c = config("--gap 3s flight.tlog tlog:-").unwrap();
        assert_eq!(
            c.probe,
            Probe::Passive {
                gap: Some(Duration::from_secs(3))
            }
        );
        assert!(c.virtual_clock());
        assert!(c.links.iter().all(|l| !l.session.heartbeat));
        // Beside a simulated link on the virtual clock: both passive.
        let c = config("tlog:a.tlog sim:?clock=virtual").unwrap();
        assert!(matches!(c.probe, Probe::Passive { .. }));
    }
}
