//! Why a configuration is refused. Each variant is one shape of message,
//! written once here; the settings, values and causes are its fields, so
//! the words a front end uses (`--target`, or `target` in the serve file)
//! are filled in where the rule is checked.

use std::error::Error;
use std::io;
use std::time::Duration;

use thiserror::Error;

use crate::transport::address::{AddressError, LinkSpec};

/// The error of a setting's own parser or check, kept as the cause; boxed
/// because several of those types are the crate's own, which this public
/// enum cannot name.
type Cause = Box<dyn Error + Send + Sync>;

/// Why the command line, `respond`'s options or the serve files are
/// refused: one line, said as `mavping: ...` (or as the HTTP 400 body).
#[derive(Debug, Error)]
pub enum ConfigError {
    #[error(transparent)]
    Address(#[from] AddressError),
    /// A setting given a value it does not take: out of range, malformed,
    /// or not for this run (`--rate 0: expected more than 0 ...`).
    #[error("{setting} {value}: {problem}")]
    Value {
        setting: String,
        value: String,
        problem: String,
    },
    /// A word that is none of those the setting knows (`probe 'echo':
    /// expected auto, ping, timesync or command`).
    #[error("{setting} '{value}': expected {expected}")]
    Unknown {
        setting: &'static str,
        value: String,
        expected: &'static str,
    },
    /// A setting whose value falls short, the value not shown (`--gap:
    /// expected at least 10ms`).
    #[error("{setting}: expected {expected}")]
    Expected {
        setting: &'static str,
        expected: &'static str,
    },
    /// A setting that means nothing without another (`--step needs --sweep
    /// or --load`).
    #[error("{setting} needs {needs}")]
    Needs {
        setting: &'static str,
        needs: &'static str,
    },
    /// A setting only some runs take (`--live works with --probe ping and
    /// timesync, not command`).
    #[error("{setting} works with {with}")]
    WorksWith {
        setting: &'static str,
        with: &'static str,
    },
    /// Two ways of saying one thing, both used.
    #[error("{first} and {second}: give one, not both")]
    GiveOne {
        first: &'static str,
        second: &'static str,
    },
    /// A key of the serve file in the other kind of table.
    #[error("{key} belongs in {table}")]
    Misplaced {
        key: &'static str,
        table: &'static str,
    },
    /// A file a setting names that cannot be read.
    #[error("{what}: cannot read it: {source}")]
    Unreadable { what: String, source: io::Error },
    /// A file its parser refused: where, and the parser's first line.
    #[error("{place}: {message}")]
    Syntax { place: String, message: String },
    /// A setting its own parser or check refused (`max_loss: ...`).
    #[error("{setting}: {source}")]
    Rejected { setting: String, source: Cause },
    /// An error inside a part of the configuration, named (`--link: ...`,
    /// `serve.toml: [module.a]: ...`).
    #[error("{place}: {source}")]
    Within {
        place: String,
        source: Box<ConfigError>,
    },
    /// A signing key that is not one.
    #[error("{from}: {source}; expected 64 hex characters or a passphrase")]
    SigningKey { from: String, source: Cause },
    /// Signing asked of MAVLink 1, which has no room for a signature.
    #[error("{mavlink} 1 with a signing key: signing needs MAVLink 2{hint}")]
    SignedMavlink1 {
        mavlink: &'static str,
        hint: &'static str,
    },
    /// `-I` where the build cannot tie a socket to an interface.
    #[error("{}", crate::transport::route::interface_needs_linux(.interface))]
    InterfaceNeedsLinux { interface: String },
    /// Two links of a run that are one.
    #[error("{given} names the same link as an earlier one ({link}): name each link once")]
    SameLink { given: String, link: LinkSpec },
    /// Two continuous links of a server under one name.
    #[error(
        "two continuous links are named '{name}': give each a name of its own (name = \"...\")"
    )]
    SameName { name: String },
    /// A telemetry log beside a probe option.
    #[error(
        "{flag}: {log} is a telemetry log, read without probes (--passive is implied); \
         drop {flag}"
    )]
    LogProbed { flag: &'static str, log: LinkSpec },
    /// A telemetry log beside live links.
    #[error(
        "{log} runs on the log's own clock and cannot run beside live links: read logs \
         on their own (or beside sim:?clock=virtual links)"
    )]
    LogBesideLive { log: LinkSpec },
    #[error(
        "sim:?clock=virtual cannot run beside other links: use clock=virtual on every sim: link or on none"
    )]
    VirtualBesideReal,
    /// The server runs on real time; a log or a virtual clock cannot.
    #[error(
        "{log} cannot be served: a telemetry log runs on its own clock (read it with \
         mavping {log})"
    )]
    LogServed { log: LinkSpec },
    #[error(
        "sim:?clock=virtual cannot be served: drop clock=virtual (the server runs on real time)"
    )]
    VirtualServed,
    /// More requests in flight than the pending table may hold.
    #[error(
        "--timeout {} at one request every {} keeps {in_flight} requests in flight \
         (at most {max}): lower the rate or the timeout",
        humantime::format_duration(*.timeout),
        humantime::format_duration(*.interval)
    )]
    InFlight {
        timeout: Duration,
        interval: Duration,
        in_flight: u64,
        max: u64,
    },
    #[error("{links} continuous links: at most {max}")]
    TooManyLinks { links: usize, max: usize },
    /// A rule of its own, said in one place only.
    #[error("{0}")]
    Other(String),
}

impl ConfigError {
    /// [`ConfigError::Value`], for a setting, the value as given or shown,
    /// and what is wrong with it.
    pub(crate) fn value(
        setting: impl Into<String>,
        value: impl ToString,
        problem: impl Into<String>,
    ) -> Self {
        ConfigError::Value {
            setting: setting.into(),
            value: value.to_string(),
            problem: problem.into(),
        }
    }

    /// [`ConfigError::Rejected`].
    pub(crate) fn rejected(
        setting: impl Into<String>,
        source: impl Error + Send + Sync + 'static,
    ) -> Self {
        ConfigError::Rejected {
            setting: setting.into(),
            source: Box::new(source),
        }
    }

    /// [`ConfigError::Within`]: `self` inside `place`.
    pub(crate) fn within(self, place: impl Into<String>) -> Self {
        ConfigError::Within {
            place: place.into(),
            source: Box::new(self),
        }
    }
}
