//! The validated configuration: clap's types stop here. What the engine
//! and transports get from it are their own plain types ([`SessionConfig`],
//! [`CommandSpec`], [`LinkSpec`], [`ResponderSettings`]).

mod error;
mod measure;
mod respond;
mod serve;
mod sweep;

use std::net::SocketAddr;
use std::path::PathBuf;
use std::time::Duration;

pub use error::ConfigError;
pub(crate) use serve::{ContinuousLink, ProbePlan, WebConfig};
pub use serve::{Pattern, ServeConfig, ServeSettings};

use crate::cli::{Format, SigningArgs};
use crate::engine::capacity::{self, WireBudget};
use crate::engine::summary::ProbeName;
use crate::engine::CommandSpec;
use crate::engine::SessionConfig;
use crate::frame::signing::{SecretKey, SigningConfig};
use crate::frame::SysComp;
use crate::responder::ResponderSettings;
use crate::transport::address::LinkSpec;
use crate::transport::LinkOptions;
use crate::verdict::Thresholds;

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

/// One link of a run.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct LinkConfig {
    pub(crate) spec: LinkSpec,
    /// The connection string as typed: with several links, reply lines,
    /// error lines and exports are labelled with it.
    pub(crate) name: String,
    /// Its session; `link_name` is the form reports head the run with
    /// (the link's full form alone, or the name beside others).
    pub(crate) session: SessionConfig,
    /// Every link's thresholds, and the responders `--expect` wants here.
    pub(crate) thresholds: Thresholds,
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

/// Which probe, with what it needs.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Probe {
    /// PING, and TIMESYNC for responders that do not answer it.
    Auto,
    Ping,
    Timesync {
        target: SysComp,
    },
    Command(CommandSpec),
    /// No probes: sequence accounting of what every source sends
    /// (`--passive`), with its silence threshold if given.
    Passive {
        gap: Option<Duration>,
    },
}

impl Probe {
    /// The name reports give the probe (`probe="ping"`).
    pub(crate) fn name(&self) -> ProbeName {
        match self {
            Probe::Auto => ProbeName::Auto,
            Probe::Ping => ProbeName::Ping,
            Probe::Timesync { .. } => ProbeName::Timesync,
            Probe::Command(_) => ProbeName::Command,
            Probe::Passive { .. } => ProbeName::Passive,
        }
    }
}

/// What the baud rate allows `spec` for `session`'s requests: set once
/// here, so every front end reports the same. The command probe has none
/// (its frames and retries vary).
fn wire_budget(
    spec: &LinkSpec,
    default_baud: u32,
    probe: &Probe,
    session: &SessionConfig,
) -> Option<WireBudget> {
    match probe {
        Probe::Command(_) | Probe::Passive { .. } => None,
        // Auto sends a PING each slot (and a TIMESYNC only to those that
        // need it): the PING's sizes are the floor.
        Probe::Auto | Probe::Ping => {
            capacity::for_link(spec, default_baud, session, capacity::Exchange::Ping)
        }
        Probe::Timesync { target } => capacity::for_link(
            spec,
            default_baud,
            session,
            capacity::Exchange::Timesync { target: *target },
        ),
    }
}

/// `mavping respond`, validated.
#[derive(Debug, Clone)]
pub(crate) struct RespondConfig {
    pub(crate) link: LinkSpec,
    pub(crate) link_options: LinkOptions,
    pub(crate) settings: ResponderSettings,
    pub(crate) verbose: u8,
}

impl Config {
    /// True when the run should use tokio's paused, virtual clock (only
    /// simulated links with `clock=virtual`; validation rejects a mix).
    pub(crate) fn virtual_clock(&self) -> bool {
        self.links.iter().all(|l| l.spec.is_virtual())
    }
}

/// How errors name a setting: as a command-line option (`--target`) or as
/// a key of the `mavping serve` configuration file (`target`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Keys {
    Flags,
    File,
}

impl Keys {
    /// `name` is the key's form in the file (`retry_interval` or
    /// `retry-interval`, either); the option's form is derived from it.
    pub(crate) fn name(self, name: &str) -> String {
        match self {
            Keys::Flags => format!("--{}", name.replace('_', "-")),
            Keys::File => name.replace('-', "_"),
        }
    }
}

/// `--prometheus`, `--listen`: a numeric address, so nothing is resolved
/// behind the user's back (and `localhost` cannot silently mean IPv6 only).
fn validate_listen(flag: &str, arg: &str) -> Result<SocketAddr, ConfigError> {
    arg.parse().map_err(|_| {
        ConfigError::value(
            flag,
            arg,
            "expected ADDR:PORT, e.g. 127.0.0.1:9090, 0.0.0.0:9090 or [::1]:9090",
        )
    })
}

/// The highest request rate (requests per second).
const MAX_RATE: f64 = 1_000_000.0;

/// Longest reply timeout, retry interval or emulated delay.
const MAX_TIMEOUT: Duration = Duration::from_secs(3600);

fn validate_baud(baud: u32) -> Result<u32, ConfigError> {
    if baud == 0 {
        return Err(ConfigError::value(
            "--baud",
            0,
            "expected a baud rate such as 57600 or 115200",
        ));
    }
    Ok(baud)
}

fn validate_ids(sysid: u8, compid: u8) -> Result<SysComp, ConfigError> {
    if sysid == 0 {
        return Err(ConfigError::value(
            "--sysid",
            0,
            "0 means 'broadcast'; use 1-255 (ground stations use 250-255)",
        ));
    }
    if compid == 0 {
        return Err(ConfigError::value(
            "--compid",
            0,
            "0 means 'all components'; use 1-255 (190 is a GCS)",
        ));
    }
    Ok(SysComp::new(sysid, compid))
}

/// The signing key from `--signing-key` (or its env var) or the file
/// `--signing-key-file` names; `None` when neither is given.
fn signing_key(args: &SigningArgs) -> Result<Option<SecretKey>, ConfigError> {
    let text = match (&args.signing_key, &args.signing_key_file) {
        (Some(_), Some(_)) => {
            return Err(ConfigError::GiveOne {
                first: "--signing-key (or MAVPING_SIGNING_KEY)",
                second: "--signing-key-file",
            })
        }
        (Some(key), None) => key.trim().to_string(),
        (None, Some(path)) => std::fs::read_to_string(path)
            .map_err(|source| ConfigError::Unreadable {
                what: format!("--signing-key-file {}", path.display()),
                source,
            })?
            .trim()
            .to_string(),
        (None, None) => return Ok(None),
    };
    let from = match &args.signing_key_file {
        Some(path) if args.signing_key.is_none() => {
            format!("--signing-key-file {}", path.display())
        }
        _ => "--signing-key".to_string(),
    };
    SecretKey::parse(&text)
        .map(Some)
        .map_err(|e| ConfigError::SigningKey {
            from,
            source: Box::new(e),
        })
}

/// The signing policy: a key signs what we send and checks what comes.
fn signing(args: &SigningArgs, require_signed: bool) -> Result<Option<SigningConfig>, ConfigError> {
    Ok(signing_key(args)?.map(|key| SigningConfig {
        key,
        link_id: args.signing_link_id,
        require_signed,
    }))
}
