//! What the command probe tells as it goes.

use crate::engine::Nanos;
use crate::frame::SysComp;

/// What the command probe decided (its tracker is pure; the driver turns
/// `Send` into a frame on the wire).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum CommandEvent {
    /// Put attempt `attempt` (1-based) of command `n` on the wire.
    Send {
        n: u64,
        target: SysComp,
        command: u16,
        attempt: u32,
    },
    Skipped {
        target: SysComp,
        command: u16,
        at: Nanos,
    },
    Acked {
        n: u64,
        target: SysComp,
        from: SysComp,
        command: u16,
        result: u8,
        attempts: u32,
        time_to_ack: Nanos,
    },
    Failed {
        n: u64,
        target: SysComp,
        command: u16,
        attempts: u32,
    },
    LateAck {
        from: SysComp,
        command: u16,
        result: u8,
    },
    DuplicateAck {
        from: SysComp,
        command: u16,
        result: u8,
    },
}
