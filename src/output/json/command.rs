//! Lines of the command probe.

use serde::Serialize;

use crate::engine::CommandSpec;
use crate::frame::codec;
use crate::frame::SysComp;

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
