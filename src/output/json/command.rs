//! Lines of the command probe.

use serde::Serialize;

use super::lines::SCHEMA_VERSION;
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
