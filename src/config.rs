//! The validated run configuration: nothing downstream sees raw flags.

use std::net::SocketAddr;
use std::path::{Path, PathBuf};
use std::time::Duration;

use thiserror::Error;

use crate::cli::{Format, PingArgs, ProbeKind, RespondArgs, SigningArgs};
use crate::engine::session::SessionConfig;
use crate::frame::codec;
use crate::frame::signing::{SecretKey, SigningConfig};
use crate::frame::{SysComp, Version};
use crate::transport::address::{AddressError, LinkSpec};
use crate::transport::LinkOptions;
use crate::verdict::{Expected, Thresholds};

#[derive(Debug, Error)]
pub enum ConfigError {
    #[error(transparent)]
    Address(#[from] AddressError),
    #[error("{0}")]
    Invalid(String),
}

fn invalid(msg: impl Into<String>) -> ConfigError {
    ConfigError::Invalid(msg.into())
}

/// More requests than this in flight at once would need an unreasonably
/// large pending table: lower the rate or the timeout.
pub const MAX_IN_FLIGHT: u64 = 1 << 21;
const MAX_RATE: f64 = 1_000_000.0;
/// The longest interval between requests (the lowest rate).
const MAX_INTERVAL: Duration = Duration::from_secs(86_400);
const MAX_TIMEOUT: Duration = Duration::from_secs(3600);

#[derive(Debug, Clone)]
pub struct Config {
    /// One or more links, in command-line order; each gets its own session.
    pub links: Vec<LinkSpec>,
    /// Each link's connection string as typed: with several links, the
    /// name reports and error lines give it.
    pub link_names: Vec<String>,
    pub link_options: LinkOptions,
    pub session: SessionConfig,
    pub quiet: bool,
    pub every_reply: bool,
    pub verbose: u8,
    pub format: Format,
    /// Thresholds of every link (with one link, all of them).
    pub thresholds: Thresholds,
    /// `--expect LINK=ID`: (index of the link, responder), several links.
    pub expect_on: Vec<(usize, Expected)>,
    pub hgrm: Option<PathBuf>,
    pub samples: Option<PathBuf>,
    pub probe: Probe,
    /// `--live`; app.rs falls back to text when stdout is not a terminal.
    pub live: bool,
    pub prometheus: Option<SocketAddr>,
    pub plot: Option<PathBuf>,
}

/// Which probe, with what it needs.
#[derive(Debug, Clone, PartialEq)]
pub enum Probe {
    Ping,
    Timesync { target: SysComp },
    Command(CommandSpec),
}

/// The command probe's request and retry policy.
#[derive(Debug, Clone, PartialEq)]
pub struct CommandSpec {
    pub target: SysComp,
    pub command: u16,
    pub params: [f32; 7],
    pub retry_interval: Duration,
    /// Re-sends after the first transmission.
    pub retries: u8,
}

/// `mavping respond`, validated.
#[derive(Debug, Clone)]
pub struct RespondConfig {
    pub link: LinkSpec,
    pub id: SysComp,
    pub delay: Duration,
    pub jitter: Duration,
    /// Shares of replies dropped and duplicated, 0..=1.
    pub drop: f64,
    pub dup: f64,
    pub seed: u64,
    pub answer_ping: bool,
    pub verbose: u8,
    pub link_options: LinkOptions,
    /// With a key: replies signed, requests checked (all must be signed).
    pub signing: Option<SigningConfig>,
}

impl Config {
    /// True when the run should use tokio's paused, virtual clock (only
    /// simulated links with `clock=virtual`; validation rejects a mix).
    pub fn virtual_clock(&self) -> bool {
        self.links
            .iter()
            .all(|l| matches!(l, LinkSpec::Sim(p) if p.virtual_clock))
    }

    /// The first (with one link, the only) link.
    pub fn link(&self) -> &LinkSpec {
        &self.links[0]
    }
}

/// `--expect LINK=ID`: LINK must be one of the links (as given, or in the
/// form mavping prints it). With one link it is the plain `--expect ID`.
fn validate_scoped_expect(
    cli: &PingArgs,
    links: &[LinkSpec],
) -> Result<Vec<(usize, Expected)>, ConfigError> {
    let mut scoped = Vec::new();
    for e in &cli.expect {
        let Some(link) = &e.link else { continue };
        let index = cli
            .links
            .iter()
            .zip(links)
            .position(|(given, spec)| given.trim() == link || spec.to_string() == *link)
            .ok_or_else(|| {
                invalid(format!(
                    "--expect {link}={}: {link} is not one of the links given",
                    e.id
                ))
            })?;
        if links.len() > 1 {
            scoped.push((index, e.id));
        }
    }
    Ok(scoped)
}

/// Several links: each must be named once (reports are keyed by the
/// connection string), a virtual clock cannot drive real links, and the
/// plot (it draws one link) and the command probe are for one link only.
fn validate_links(cli: &PingArgs, links: &[LinkSpec]) -> Result<(), ConfigError> {
    if links.len() < 2 {
        return Ok(());
    }
    for (i, link) in links.iter().enumerate() {
        if links[..i].iter().any(|l| l.to_string() == link.to_string()) {
            return Err(invalid(format!(
                "{} names the same link as an earlier one ({link}): name each link once",
                cli.links[i]
            )));
        }
    }
    let is_virtual = |l: &LinkSpec| matches!(l, LinkSpec::Sim(p) if p.virtual_clock);
    if links.iter().any(is_virtual) && !links.iter().all(is_virtual) {
        return Err(invalid(
            "sim:?clock=virtual cannot run beside other links: use clock=virtual on every sim: link or on none",
        ));
    }
    for (set, flag) in [
        (cli.probe == ProbeKind::Command, "--probe command"),
        (cli.plot.is_some(), "--plot"),
    ] {
        if set {
            return Err(invalid(format!(
                "{flag} works with one link, not {}",
                links.len()
            )));
        }
    }
    Ok(())
}

/// `--prometheus`: a numeric address, so nothing is resolved behind the
/// user's back (and `localhost` cannot silently mean IPv6 only).
fn validate_listen(arg: &str) -> Result<SocketAddr, ConfigError> {
    arg.parse().map_err(|_| {
        invalid(format!(
            "--prometheus {arg}: expected ADDR:PORT, e.g. 127.0.0.1:9090, 0.0.0.0:9090 or [::1]:9090"
        ))
    })
}

/// `--plot`: only SVG; the PNG backend needs system font libraries.
fn validate_plot(path: &Path) -> Result<PathBuf, ConfigError> {
    let svg = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("svg"));
    if !svg {
        return Err(invalid(format!(
            "--plot {}: only .svg files can be drawn",
            path.display()
        )));
    }
    Ok(path.to_path_buf())
}

/// The live view, exporter and plot follow echo probes' events.
fn validate_views(cli: &PingArgs) -> Result<(), ConfigError> {
    if cli.probe == ProbeKind::Command {
        for (set, flag) in [
            (cli.live, "--live"),
            (cli.prometheus.is_some(), "--prometheus"),
            (cli.plot.is_some(), "--plot"),
        ] {
            if set {
                return Err(invalid(format!(
                    "{flag} works with --probe ping and timesync, not command"
                )));
            }
        }
    }
    if cli.live && (cli.json || cli.format == Format::Json) {
        return Err(invalid("--live cannot be used with --json"));
    }
    Ok(())
}

fn validate_interval(cli: &PingArgs) -> Result<Duration, ConfigError> {
    let interval = match (cli.rate, cli.interval) {
        (Some(rate), _) => {
            if !rate.is_finite() || rate <= 0.0 || rate > MAX_RATE {
                return Err(invalid(format!(
                    "--rate {rate}: expected more than 0 and at most {MAX_RATE} requests per second"
                )));
            }
            // A tiny rate would mean an interval past what a Duration holds.
            if rate < 1.0 / MAX_INTERVAL.as_secs_f64() {
                return Err(invalid(format!(
                    "--rate {rate}: at least one request a day (1.2e-5 per second)"
                )));
            }
            Duration::from_secs_f64(1.0 / rate)
        }
        (None, Some(interval)) => interval,
        (None, None) => Duration::from_secs(1),
    };
    if interval < Duration::from_micros(1) {
        return Err(invalid(format!(
            "--interval {}: at least 1us (1,000,000 requests per second)",
            humantime::format_duration(interval)
        )));
    }
    if interval > MAX_INTERVAL {
        return Err(invalid(format!(
            "--interval {}: at most 1 day",
            humantime::format_duration(interval)
        )));
    }
    Ok(interval)
}

/// The signing key from `--signing-key` (or its env var) or the file
/// `--signing-key-file` names; `None` when neither is given.
fn signing_key(args: &SigningArgs) -> Result<Option<SecretKey>, ConfigError> {
    let text =
        match (&args.signing_key, &args.signing_key_file) {
            (Some(_), Some(_)) => return Err(invalid(
                "--signing-key (or MAVPING_SIGNING_KEY) and --signing-key-file: give one, not both",
            )),
            (Some(key), None) => key.trim().to_string(),
            (None, Some(path)) => std::fs::read_to_string(path)
                .map_err(|e| {
                    invalid(format!(
                        "--signing-key-file {}: cannot read it: {e}",
                        path.display()
                    ))
                })?
                .trim()
                .to_string(),
            (None, None) => return Ok(None),
        };
    let from = if args.signing_key.is_some() {
        "--signing-key".to_string()
    } else {
        format!(
            "--signing-key-file {}",
            args.signing_key_file.as_ref().expect("matched").display()
        )
    };
    SecretKey::parse(&text).map(Some).map_err(|e| {
        invalid(format!(
            "{from}: {e}; expected 64 hex characters or a passphrase"
        ))
    })
}

fn validate_signing(
    args: &SigningArgs,
    require_signed: bool,
) -> Result<Option<SigningConfig>, ConfigError> {
    let key = signing_key(args)?;
    match key {
        None if require_signed => Err(invalid(
            "--require-signed needs a signing key (--signing-key, MAVPING_SIGNING_KEY or --signing-key-file)",
        )),
        None => Ok(None),
        Some(key) => Ok(Some(SigningConfig {
            key,
            link_id: args.signing_link_id,
            require_signed,
        })),
    }
}

fn validate_baud(baud: u32) -> Result<u32, ConfigError> {
    if baud == 0 {
        return Err(invalid(
            "--baud 0: expected a baud rate such as 57600 or 115200",
        ));
    }
    Ok(baud)
}

fn validate_ids(sysid: u8, compid: u8) -> Result<SysComp, ConfigError> {
    if sysid == 0 {
        return Err(invalid(
            "--sysid 0: 0 means 'broadcast'; use 1-255 (255 is a GCS)",
        ));
    }
    if compid == 0 {
        return Err(invalid(
            "--compid 0: 0 means 'all components'; use 1-255 (190 is a GCS)",
        ));
    }
    Ok(SysComp::new(sysid, compid))
}

/// Ring size: twice the requests that can be in flight within one
/// timeout, so a late reply is still recognised for about one more timeout.
fn pending_capacity(interval: Duration, timeout: Duration) -> Result<usize, ConfigError> {
    let in_flight = (timeout.as_nanos() / interval.as_nanos()) as u64 + 1;
    if in_flight > MAX_IN_FLIGHT {
        return Err(invalid(format!(
            "--timeout {} at one request every {} keeps {in_flight} requests in flight \
             (at most {MAX_IN_FLIGHT}): lower the rate or the timeout",
            humantime::format_duration(timeout),
            humantime::format_duration(interval)
        )));
    }
    Ok(((in_flight * 2 + 16) as usize).next_power_of_two().max(64))
}

/// "SYS/COMP", or "SYS" for every component of a system.
fn parse_target(text: &str) -> Result<SysComp, ConfigError> {
    let bad = || {
        invalid(format!(
            "--target {text}: expected SYS/COMP or SYS, ids 0-255 (e.g. 1/1)"
        ))
    };
    let (sys, comp) = text.split_once('/').unwrap_or((text, "0"));
    let sysid = sys.trim().parse::<u8>().map_err(|_| bad())?;
    let compid = comp.trim().parse::<u8>().map_err(|_| bad())?;
    Ok(SysComp::new(sysid, compid))
}

/// "REQUEST_MESSAGE,0" or "512,0": a MAV_CMD by name or id, then params.
fn parse_command(text: &str) -> Result<(u16, [f32; 7]), ConfigError> {
    let mut parts = text.split(',').map(str::trim);
    let name = parts.next().unwrap_or_default();
    let command = match name.parse::<u16>() {
        Ok(id) => id,
        Err(_) => codec::command_id_from_name(name).ok_or_else(|| {
            invalid(format!(
                "--command {text}: '{name}' is not a MAV_CMD name or id (e.g. REQUEST_MESSAGE,0 or 512,0)"
            ))
        })?,
    };
    let mut params = [0.0f32; 7];
    for (i, p) in parts.enumerate() {
        if i >= params.len() {
            return Err(invalid(format!(
                "--command {text}: at most 7 params after the command"
            )));
        }
        params[i] = p
            .parse::<f32>()
            .ok()
            .filter(|v| v.is_finite())
            .ok_or_else(|| {
                invalid(format!(
                    "--command {text}: param {} '{p}' is not a number",
                    i + 1
                ))
            })?;
    }
    Ok((command, params))
}

fn validate_probe(cli: &PingArgs) -> Result<Probe, ConfigError> {
    let target = cli.target.as_deref().map(parse_target).transpose()?;
    match cli.probe {
        ProbeKind::Ping => {
            if target.is_some() {
                return Err(invalid(
                    "--target: PING requests are always broadcast; use it with --probe timesync or command",
                ));
            }
            Ok(Probe::Ping)
        }
        ProbeKind::Timesync => Ok(Probe::Timesync {
            target: target.unwrap_or(SysComp::new(0, 0)),
        }),
        ProbeKind::Command => {
            let target = target.unwrap_or(SysComp::new(1, 1));
            if target.sysid == 0 {
                return Err(invalid(
                    "--target 0: a command needs one target system (e.g. --target 1/1)",
                ));
            }
            if cli.retry_interval.is_zero() || cli.retry_interval > MAX_TIMEOUT {
                return Err(invalid(format!(
                    "--retry-interval {}: expected more than 0 and at most 1h",
                    humantime::format_duration(cli.retry_interval)
                )));
            }
            let (command, params) = parse_command(&cli.command)?;
            Ok(Probe::Command(CommandSpec {
                target,
                command,
                params,
                retry_interval: cli.retry_interval,
                retries: cli.retries,
            }))
        }
    }
}

fn percent(flag: &str, text: &str) -> Result<f64, ConfigError> {
    let number = text.strip_suffix('%').unwrap_or(text);
    match number.parse::<f64>() {
        Ok(p) if (0.0..=100.0).contains(&p) => Ok(p / 100.0),
        _ => Err(invalid(format!(
            "{flag} {text}: expected a percentage from 0 to 100"
        ))),
    }
}

impl TryFrom<&RespondArgs> for RespondConfig {
    type Error = ConfigError;

    fn try_from(cli: &RespondArgs) -> Result<Self, ConfigError> {
        let link: LinkSpec = cli.link.parse()?;
        for (flag, d) in [("--delay", cli.delay), ("--jitter", cli.jitter)] {
            if d > MAX_TIMEOUT {
                return Err(invalid(format!(
                    "{flag} {}: at most 1h",
                    humantime::format_duration(d)
                )));
            }
        }
        Ok(RespondConfig {
            link,
            id: validate_ids(cli.sysid, cli.compid)?,
            delay: cli.delay,
            jitter: cli.jitter,
            drop: percent("--drop", &cli.drop)?,
            dup: percent("--dup", &cli.dup)?,
            seed: cli.seed,
            answer_ping: !cli.no_ping,
            verbose: cli.verbose,
            link_options: LinkOptions {
                baud: validate_baud(cli.baud)?,
                // A responder outlives its pingers: one that is not up yet
                // or restarts must not end it.
                reconnect: true,
            },
            // A responder with a key answers only signed requests.
            signing: signing_key(&cli.signing)?.map(|key| SigningConfig {
                key,
                link_id: cli.signing.signing_link_id,
                require_signed: true,
            }),
        })
    }
}

impl TryFrom<&PingArgs> for Config {
    type Error = ConfigError;

    fn try_from(cli: &PingArgs) -> Result<Self, ConfigError> {
        if cli.links.is_empty() {
            return Err(invalid(
                "missing CONNECTION (e.g. udpout:127.0.0.1:14550 or sim:)",
            ));
        }
        let links = cli
            .links
            .iter()
            .map(|l| l.parse::<LinkSpec>())
            .collect::<Result<Vec<_>, _>>()?;
        validate_links(cli, &links)?;
        let link = &links[0];
        if cli.min_responders == Some(0) {
            return Err(invalid("--min-responders 0: expected at least 1"));
        }
        let interval = validate_interval(cli)?;
        if cli.count == Some(0) {
            return Err(invalid("--count 0: expected at least 1"));
        }
        if cli.timeout.is_zero() || cli.timeout > MAX_TIMEOUT {
            return Err(invalid(format!(
                "--timeout {}: expected more than 0 and at most 1h",
                humantime::format_duration(cli.timeout)
            )));
        }
        if cli.deadline.is_some_and(|d| d.is_zero()) {
            return Err(invalid("--deadline 0: expected more than 0"));
        }
        let ours = validate_ids(cli.sysid, cli.compid)?;
        validate_baud(cli.baud)?;
        validate_views(cli)?;
        let signing = validate_signing(&cli.signing, cli.require_signed)?;
        if signing.is_some() && cli.mavlink_version == 1 {
            return Err(invalid(
                "--mavlink 1 with a signing key: signing needs MAVLink 2 (drop --mavlink 1)",
            ));
        }
        Ok(Config {
            session: SessionConfig {
                link_name: link.to_string(),
                ours,
                interval,
                count: cli.count,
                deadline: cli.deadline,
                timeout: cli.timeout,
                version: if cli.mavlink_version == 1 {
                    Version::V1
                } else {
                    Version::V2
                },
                heartbeat: !cli.no_heartbeat,
                capacity: pending_capacity(interval, cli.timeout)?,
                first_seq: cli.first_seq,
                // Several links share one thread: a session must not spin
                // there while another's replies wait (see app.rs).
                precise_pacing: links.len() == 1 && !matches!(link, LinkSpec::Sim(_)),
                signing,
            },
            expect_on: validate_scoped_expect(cli, &links)?,
            link_names: cli.links.iter().map(|l| l.trim().to_string()).collect(),
            links,
            link_options: LinkOptions {
                baud: cli.baud,
                reconnect: cli.reconnect,
            },
            quiet: cli.quiet,
            every_reply: cli.every_reply,
            verbose: cli.verbose,
            format: if cli.json { Format::Json } else { cli.format },
            thresholds: Thresholds {
                max_loss: cli.max_loss,
                max_rtt: cli.max_rtt.clone(),
                max_jitter: cli.max_jitter,
                expect: cli
                    .expect
                    .iter()
                    .filter(|e| e.link.is_none() || cli.links.len() == 1)
                    .map(|e| e.id)
                    .collect(),
                min_responders: cli.min_responders,
            },
            hgrm: cli.hgrm.clone(),
            samples: cli.samples.clone(),
            probe: validate_probe(cli)?,
            live: cli.live,
            prometheus: cli.prometheus.as_deref().map(validate_listen).transpose()?,
            plot: cli.plot.as_deref().map(validate_plot).transpose()?,
        })
    }
}

#[cfg(test)]
mod tests {
    use clap::Parser;

    use super::*;
    use crate::cli::Cli;

    fn config(args: &str) -> Result<Config, String> {
        let cli = Cli::try_parse_from(std::iter::once("mavping").chain(args.split_whitespace()))
            .map_err(|e| e.to_string())?;
        Config::try_from(&cli.ping).map_err(|e| e.to_string())
    }

    #[test]
    fn good_argument_lines() {
        let c = config("sim:").unwrap();
        assert_eq!(c.session.interval, Duration::from_secs(1));
        assert_eq!(c.session.timeout, Duration::from_secs(2));
        assert_eq!(c.session.ours, SysComp::new(255, 190));
        assert_eq!(c.session.capacity, 64);
        let c =
            config("-c 5 -i 0.2 -W 500ms --sysid 200 --compid 1 udpout:127.0.0.1:14550").unwrap();
        assert_eq!(c.session.count, Some(5));
        assert_eq!(c.session.interval, Duration::from_millis(200));
        assert_eq!(c.session.timeout, Duration::from_millis(500));
        let c = config("--rate 1000 -W 1s sim:").unwrap();
        assert_eq!(c.session.interval, Duration::from_millis(1));
        assert_eq!(c.session.capacity, 2048);
        assert!(config("sim:?clock=virtual").unwrap().virtual_clock());
        let c = config(
            "--json --max-loss 5% --max-rtt p99=50ms --max-rtt 1s --expect 1 --expect 2/1 sim:",
        )
        .unwrap();
        assert_eq!(c.format, Format::Json);
        let t = &c.thresholds;
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
                reconnect: true
            }
        );
        assert_eq!(config("sim:").unwrap().probe, Probe::Ping);
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
        assert!(c.live);
        assert_eq!(c.prometheus, Some("[::1]:9100".parse().unwrap()));
        assert_eq!(c.plot, Some(PathBuf::from("out/RTT.SVG")));
        let c = config("-c 3 --json --samples s.csv --hgrm h.hgrm sim: sim:?delay=50ms").unwrap();
        assert_eq!(c.links.len(), 2);
        assert_eq!(c.link_names, ["sim:", "sim:?delay=50ms"]);
        assert!(!c.session.precise_pacing, "links share one thread");
        assert!(!c.virtual_clock());
        assert!(config("sim:?clock=virtual sim:?delay=5ms&clock=virtual")
            .unwrap()
            .virtual_clock());
        let c = config("--expect 1 --expect sim:?delay=50ms=2/1 sim: sim:?delay=50ms").unwrap();
        let two_one = Expected {
            sysid: 2,
            compid: Some(1),
        };
        assert_eq!(c.thresholds.expect.len(), 1);
        assert_eq!(c.expect_on, [(1, two_one)]);
        // By the form mavping prints, too; with one link it is a plain --expect.
        let c = config(
            "--expect sim:?responders=1&delay=10ms&jitter=2ms&loss=0%&dup=0%&reorder=0%&seed=1=2/1 sim:",
        )
        .unwrap();
        assert_eq!(
            (c.thresholds.expect.clone(), c.expect_on),
            (vec![two_one], vec![])
        );
        let c = config("--probe timesync --prometheus 0.0.0.0:0 sim:").unwrap();
        assert_eq!(c.prometheus, Some("0.0.0.0:0".parse().unwrap()));
    }

    fn respond(args: &str) -> Result<RespondConfig, String> {
        let cli = Cli::try_parse_from(
            ["mavping", "respond"]
                .into_iter()
                .chain(args.split_whitespace()),
        )
        .map_err(|e| e.to_string())?;
        let Some(crate::cli::Mode::Respond(r)) = &cli.mode else {
            return Err("not respond".into());
        };
        RespondConfig::try_from(r).map_err(|e| e.to_string())
    }

    #[test]
    fn signing_lines() {
        let hex = "000102030405060708090a0b0c0d0e0f101112131415161718191a1b1c1d1e1f";
        let c = config(&format!("--signing-key {hex} sim:")).unwrap();
        let s = c.session.signing.expect("signing on");
        let mut bytes = [0u8; 32];
        for (i, b) in bytes.iter_mut().enumerate() {
            *b = i as u8;
        }
        assert_eq!(s.key, SecretKey::from_bytes(bytes));
        assert_eq!((s.link_id, s.require_signed), (0, false));
        let s = config("--signing-key pass --signing-link-id 9 --require-signed sim:")
            .unwrap()
            .session
            .signing
            .unwrap();
        assert_eq!(s.key, SecretKey::parse("pass").unwrap());
        assert_eq!((s.link_id, s.require_signed), (9, true));
        assert!(config("sim:").unwrap().session.signing.is_none());

        let file = std::env::temp_dir().join(format!("mavping-key-{}", std::process::id()));
        std::fs::write(&file, "  pass\n").unwrap();
        let from_file = config(&format!("--signing-key-file {} sim:", file.display()));
        std::fs::remove_file(&file).unwrap();
        assert_eq!(
            from_file.unwrap().session.signing.unwrap().key,
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
        let r = respond("--signing-key pass --signing-link-id 3 udpin:0.0.0.0:14550").unwrap();
        let s = r.signing.unwrap();
        assert_eq!((s.link_id, s.require_signed), (3, true));
        assert!(respond("udpin:0.0.0.0:14550").unwrap().signing.is_none());
    }

    #[test]
    fn respond_lines() {
        let r = respond("udpin:0.0.0.0:14550").unwrap();
        assert_eq!(r.id, SysComp::new(1, 1));
        assert!(r.answer_ping);
        assert_eq!((r.drop, r.dup), (0.0, 0.0));
        let r = respond(
            "--sysid 7 --compid 2 --delay 5ms --jitter 1ms --drop 10% --dup 2.5 --seed 9 --no-ping sim:",
        )
        .unwrap();
        assert_eq!(r.id, SysComp::new(7, 2));
        assert_eq!(
            (r.delay, r.jitter),
            (Duration::from_millis(5), Duration::from_millis(1))
        );
        assert!((r.drop - 0.1).abs() < 1e-12 && (r.dup - 0.025).abs() < 1e-12);
        assert!(!r.answer_ping);
        for (args, needle) in [
            ("--drop 150 sim:", "--drop 150"),
            ("--dup x sim:", "--dup x"),
            ("--sysid 0 sim:", "--sysid 0"),
            ("--delay 2h sim:", "at most 1h"),
            ("bogus:1:2", "accepted forms"),
            ("", "CONNECTION"),
        ] {
            let err = respond(args).unwrap_err();
            assert!(err.contains(needle), "{args}: {err}");
        }
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
            ("respond sim: sim:", "unexpected"),
            (
                "sim: sim:?delay=10ms",
                "sim:?delay=10ms names the same link",
            ),
            (
                "sim: sim:?clock=virtual&delay=5ms",
                "clock=virtual cannot run beside",
            ),
            (
                "--plot a.svg sim: sim:?delay=5ms",
                "--plot works with one link",
            ),
            (
                "--probe command sim: sim:?delay=5ms",
                "--probe command works with one link",
            ),
            ("sim: udpout:nowhere", "accepted forms"),
            (
                "--expect udp:1.2.3.4:5=1 sim: sim:?delay=5ms",
                "--expect udp:1.2.3.4:5=1: udp:1.2.3.4:5 is not one of the links given",
            ),
            ("--expect sim:=1/0 sim:", "LINK=SYSID"),
        ] {
            let err = config(args).unwrap_err();
            assert!(err.contains(needle), "{args}: {err}");
        }
    }
}
