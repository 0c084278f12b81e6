//! The session a `/probe` or a continuous link runs: what both a module
//! and a link set, and what the server cannot run (its own clock).

use std::time::Duration;

use crate::cli::ProbeKind;
use crate::config::error::ConfigError;
use crate::config::measure::{count_wait, listens, pending_capacity};
use crate::config::probe::{wire_budget, Probe};
use crate::engine::c2::C2Config;
use crate::engine::matcher::Window;
use crate::engine::radio::RadioType;
use crate::engine::SessionConfig;
use crate::frame::signing::SigningConfig;
use crate::frame::{SysComp, Version};
use crate::transport::address::LinkSpec;

/// What both a module and a link set: how requests are made.
pub(super) struct Common {
    pub(super) probe: Probe,
    pub(super) kind: ProbeKind,
    pub(super) ours: SysComp,
    pub(super) version: Version,
    pub(super) heartbeat: bool,
    pub(super) signing: Option<SigningConfig>,
    pub(super) baud: u32,
    pub(super) radio_type: RadioType,
    /// The C2 link report, when asked for.
    pub(super) c2: Option<C2Config>,
    pub(super) timeout: Duration,
    pub(super) retry_interval: Duration,
}

/// `sim:?clock=virtual` and a telemetry log need a runtime of their own,
/// paused.
pub(super) fn refuse_virtual(spec: &LinkSpec) -> Result<(), ConfigError> {
    if spec.is_log() {
        return Err(ConfigError::LogServed { log: spec.clone() });
    }
    if spec.is_virtual() {
        return Err(ConfigError::VirtualServed);
    }
    Ok(())
}

/// A probe (`count` given) names its target: every request counts, the
/// ring holds them all, and a listening link gives up when no peer is
/// heard within what the count takes plus one timeout, as `-c` does. A
/// continuous link streams: a responder heard late is not charged for
/// before, and a listening one waits for ever.
pub(super) fn session(
    spec: &LinkSpec,
    name: &str,
    count: Option<u64>,
    interval: Duration,
    timeout: Duration,
    c: &Common,
) -> Result<SessionConfig, ConfigError> {
    let pending = pending_capacity(interval, timeout)?;
    let mut session = SessionConfig {
        link_name: name.to_string(),
        ours: c.ours,
        interval,
        count,
        deadline: None,
        wait: count
            .filter(|_| listens(spec))
            .and_then(|count| count_wait(count, interval, timeout)),
        interim: None,
        timeout,
        version: c.version,
        heartbeat: c.heartbeat,
        // A system that says it is a ground station answers as one.
        answer: c.heartbeat,
        capacity: count.map_or(pending, |count| {
            pending.max((count as usize).next_power_of_two())
        }),
        window: if count.is_some() {
            Window::FromStart
        } else {
            Window::FirstAnswer
        },
        first_seq: 0,
        // Many sessions share the server's thread: none may spin.
        precise_pacing: false,
        signing: c.signing,
        sweep: None,
        wire: None,
        radio_type: c.radio_type,
        c2: c.c2.clone(),
    };
    session.wire = wire_budget(spec, c.baud, &c.probe, &session);
    Ok(session)
}
