//! Lines of the command probe.

use serde::Serialize;

use super::lines::SCHEMA_VERSION;
use super::units::{seconds, us};
use crate::engine::probe::command::CommandEvent;
use crate::engine::summary::CommandSummary;
use crate::engine::CommandSpec;
use crate::frame::codec;
use crate::frame::SysComp;
use crate::verdict::Verdict;

/// The start line's `command`: what is sent, and how.
#[derive(Serialize)]
pub(super) struct Spec {
    id: u16,
    name: String,
    target: SysComp,
    /// The f32 params as the f64 they widen to.
    params: [f64; 7],
    retry_interval_s: f64,
    retries: u8,
}

impl Spec {
    pub(super) fn of(spec: &CommandSpec) -> Self {
        Spec {
            id: spec.command,
            name: codec::command_name(spec.command),
            target: spec.target,
            params: spec.params.map(f64::from),
            retry_interval_s: spec.retry_interval.as_secs_f64(),
            retries: spec.retries,
        }
    }
}

/// `ack`: a command acknowledged.
#[derive(Serialize)]
pub(super) struct Ack {
    r#type: &'static str,
    n: u64,
    target: SysComp,
    from: SysComp,
    command: u16,
    result: u8,
    result_name: String,
    attempts: u32,
    time_to_ack_us: f64,
}

/// `command_failed`: every attempt went unacknowledged.
#[derive(Serialize)]
pub(super) struct Failed {
    r#type: &'static str,
    n: u64,
    target: SysComp,
    command: u16,
    attempts: u32,
}

/// `skipped`: a command not sent.
#[derive(Serialize)]
pub(super) struct Skipped {
    r#type: &'static str,
    t_s: f64,
    target: SysComp,
    command: u16,
}

/// `late_ack` or `duplicate_ack`: an ACK after the command was decided.
#[derive(Serialize)]
pub(super) struct AckAgain {
    r#type: &'static str,
    from: SysComp,
    command: u16,
    result: u8,
}

/// The line of a command's acknowledgement, failure or skip, or of an ACK
/// after it was decided.
#[derive(Serialize)]
#[serde(untagged)]
pub(super) enum CommandLine {
    Ack(Ack),
    Failed(Failed),
    Skipped(Skipped),
    Again(AckAgain),
}

/// The line of a command event, if it has one.
pub(super) fn line(event: &CommandEvent) -> Option<CommandLine> {
    use CommandEvent as E;
    let line = match *event {
        // Each transmission is in the summary's attempt counts.
        E::Send { .. } => return None,
        E::Acked {
            n,
            target,
            from,
            command,
            result,
            attempts,
            time_to_ack,
        } => CommandLine::Ack(Ack {
            r#type: "ack",
            n,
            target,
            from,
            command,
            result,
            result_name: codec::result_name(result),
            attempts,
            time_to_ack_us: us(time_to_ack),
        }),
        E::Failed {
            n,
            target,
            command,
            attempts,
        } => CommandLine::Failed(Failed {
            r#type: "command_failed",
            n,
            target,
            command,
            attempts,
        }),
        E::Skipped {
            target,
            command,
            at,
            ..
        } => CommandLine::Skipped(Skipped {
            r#type: "skipped",
            t_s: seconds(at),
            target,
            command,
        }),
        E::LateAck {
            from,
            command,
            result,
        } => CommandLine::Again(AckAgain {
            r#type: "late_ack",
            from,
            command,
            result,
        }),
        E::DuplicateAck {
            from,
            command,
            result,
        } => CommandLine::Again(AckAgain {
            r#type: "duplicate_ack",
            from,
            command,
            result,
        }),
    };
    Some(line)
}

/// The `command_summary` line: the run's figures as the engine
/// serialises them, after the link as named.
#[derive(Serialize)]
pub(super) struct Summary<'a> {
    link: &'a str,
    #[serde(flatten)]
    figures: &'a CommandSummary,
    r#type: &'static str,
    schema_version: u32,
    exit_code: u8,
}

impl<'a> Summary<'a> {
    pub(super) fn of(s: &'a CommandSummary, verdict: &Verdict, link: &'a str) -> Self {
        Summary {
            link,
            figures: s,
            r#type: "command_summary",
            schema_version: SCHEMA_VERSION,
            exit_code: verdict.exit_code(),
        }
    }
}
