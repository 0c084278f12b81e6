//! Which probe a run or a server's probe sends, from its kind and the
//! options that go with it (`--target`, `--command`, ... or their keys in
//! the serve file), and the wire budget it has on a serial link.

use std::time::Duration;

use super::error::ConfigError;
use super::keys::Keys;
use super::values::MAX_TIMEOUT;
use crate::cli::ProbeKind;
use crate::engine::capacity::{self, WireBudget};
use crate::engine::probe::transfer::{TransferKind, TransferSpec};
use crate::engine::summary::ProbeName;
use crate::engine::CommandSpec;
use crate::engine::SessionConfig;
use crate::frame::transfer::FTP_DATA_MAX;
use crate::frame::{codec, SysComp};
use crate::transport::address::LinkSpec;

/// Where the options that follow an echo's replies work (what `--live`,
/// `--sweep`... are told).
pub(super) const ECHO_PROBES: &str = "--probe ping and timesync, not command or a download";

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
    /// A download (`--probe params`, `mission`, `ftp`).
    Transfer(TransferSpec),
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
            Probe::Transfer(spec) => spec.kind.probe_name(),
            Probe::Passive { .. } => ProbeName::Passive,
        }
    }
}

/// What the baud rate allows `spec` for `session`'s requests: set once
/// here, so every front end reports the same. The command probe has none
/// (its frames and retries vary), nor a link without a baud rate; a
/// download's is its PINGs', and its baud times the download's frames.
pub(super) fn wire_budget(
    spec: &LinkSpec,
    default_baud: u32,
    probe: &Probe,
    session: &SessionConfig,
) -> Option<WireBudget> {
    let exchange = match probe {
        Probe::Command(_) | Probe::Passive { .. } => return None,
        // Auto sends a PING each slot (and a TIMESYNC only to those that
        // need it): the PING's sizes are the floor. A download's probes
        // beside it are auto's; its own frames are timed against the baud.
        Probe::Auto | Probe::Ping | Probe::Transfer(_) => capacity::Exchange::Ping,
        Probe::Timesync { target } => capacity::Exchange::Timesync { target: *target },
    };
    // One responder on a real link unless the run shows more: the
    // warning is a floor.
    let (baud, replies) = match spec {
        LinkSpec::Serial { baud, .. } => (baud.unwrap_or(default_baud), 1),
        LinkSpec::Sim(p) => (p.baud?, u64::from(p.responders)),
        _ => return None,
    };
    Some(WireBudget {
        ignorer: spec.baud_ignorer(),
        may_ignore_baud: spec.may_ignore_baud(),
        ..capacity::for_baud(baud, replies, session, exchange)
    })
}

/// "SYS/COMP", or "SYS" for every component of a system; `key` names the
/// option or configuration key in errors.
fn parse_target(key: Keys, text: &str) -> Result<SysComp, ConfigError> {
    let bad = || {
        ConfigError::value(
            key.name("target"),
            text,
            "expected SYS/COMP or SYS, ids 0-255 (e.g. 1/1)",
        )
    };
    let (sys, comp) = text.split_once('/').unwrap_or((text, "0"));
    let sysid = sys.trim().parse::<u8>().map_err(|_| bad())?;
    let compid = comp.trim().parse::<u8>().map_err(|_| bad())?;
    Ok(SysComp::new(sysid, compid))
}

/// "REQUEST_MESSAGE,0" or "512,0": a MAV_CMD by name or id, then params.
fn parse_command(key: Keys, text: &str) -> Result<(u16, [f32; 7]), ConfigError> {
    let key = key.name("command");
    let mut parts = text.split(',').map(str::trim);
    let name = parts.next().unwrap_or_default();
    let command = match name.parse::<u16>() {
        Ok(id) => id,
        Err(_) => codec::command_id_from_name(name).ok_or_else(|| {
            ConfigError::value(
                &key,
                text,
                format!("'{name}' is not a MAV_CMD name or id (e.g. REQUEST_MESSAGE,0 or 512,0)"),
            )
        })?,
    };
    let mut params = [0.0f32; 7];
    for (i, p) in parts.enumerate() {
        if i >= params.len() {
            return Err(ConfigError::value(
                &key,
                text,
                "at most 7 params after the command",
            ));
        }
        params[i] = p
            .parse::<f32>()
            .ok()
            .filter(|v| v.is_finite())
            .ok_or_else(|| {
                ConfigError::value(&key, text, format!("param {} '{p}' is not a number", i + 1))
            })?;
    }
    Ok((command, params))
}

/// What a probe is given: its kind and, for TIMESYNC and commands, whom
/// it addresses and how a command is re-sent.
pub(super) struct ProbeChoice<'a> {
    pub(crate) kind: ProbeKind,
    pub(crate) target: Option<&'a str>,
    pub(crate) command: &'a str,
    pub(crate) retry_interval: Duration,
    pub(crate) retries: u8,
    /// How long a download's request waits for its answer (the run's
    /// reply timeout).
    pub(crate) timeout: Duration,
    /// The file `--probe ftp` reads.
    pub(crate) path: &'a str,
}

/// Requests for missing pieces a download keeps in flight at once.
const TRANSFER_WINDOW: u8 = 4;

/// The probe a choice names; `key` names options or configuration keys in errors.
pub(super) fn probe_of(key: Keys, choice: &ProbeChoice<'_>) -> Result<Probe, ConfigError> {
    let target = choice.target.map(|t| parse_target(key, t)).transpose()?;
    let flag = |name| key.name(name);
    match choice.kind {
        ProbeKind::Ping | ProbeKind::Auto => {
            if target.is_some() {
                return Err(ConfigError::Other(format!(
                    "{}: PING requests are always broadcast; use it with {} timesync or command",
                    flag("target"),
                    flag("probe")
                )));
            }
            Ok(if choice.kind == ProbeKind::Auto {
                Probe::Auto
            } else {
                Probe::Ping
            })
        }
        ProbeKind::Timesync => Ok(Probe::Timesync {
            target: target.unwrap_or(SysComp::new(0, 0)),
        }),
        ProbeKind::Params | ProbeKind::Mission | ProbeKind::Ftp => transfer_of(key, choice, target),
        ProbeKind::Command => {
            let target = target.unwrap_or(SysComp::new(1, 1));
            if target.sysid == 0 {
                return Err(ConfigError::value(
                    flag("target"),
                    0,
                    format!(
                        "a command needs one target system (e.g. {} 1/1)",
                        flag("target")
                    ),
                ));
            }
            let retry = choice.retry_interval;
            if retry.is_zero() || retry > MAX_TIMEOUT {
                return Err(ConfigError::value(
                    flag("retry-interval"),
                    humantime::format_duration(retry),
                    "expected more than 0 and at most 1h",
                ));
            }
            let (command, params) = parse_command(key, choice.command)?;
            Ok(Probe::Command(CommandSpec {
                target,
                command,
                params,
                retry_interval: retry,
                retries: choice.retries,
            }))
        }
    }
}

/// A download's plan: its target (1/1 unless named), its timeout and
/// retries, and for FTP its path.
fn transfer_of(
    key: Keys,
    choice: &ProbeChoice<'_>,
    target: Option<SysComp>,
) -> Result<Probe, ConfigError> {
    let target = target.unwrap_or(SysComp::new(1, 1));
    if target.sysid == 0 {
        return Err(ConfigError::value(
            key.name("target"),
            0,
            "a download needs one target system (e.g. 1/1)",
        ));
    }
    let kind = match choice.kind {
        ProbeKind::Params => TransferKind::Params,
        ProbeKind::Mission => TransferKind::Mission,
        _ => {
            let path = choice.path.trim();
            if path.is_empty() || path.len() > FTP_DATA_MAX {
                return Err(ConfigError::value(
                    key.name("path"),
                    choice.path,
                    format!("expected a path of 1 to {FTP_DATA_MAX} bytes"),
                ));
            }
            TransferKind::Ftp {
                path: path.to_string(),
            }
        }
    };
    Ok(Probe::Transfer(TransferSpec {
        kind,
        target,
        timeout: choice.timeout,
        retries: choice.retries,
        window: TRANSFER_WINDOW,
    }))
}
