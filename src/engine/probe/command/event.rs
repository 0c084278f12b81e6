//! What the command probe tells as it goes. Each event but `Send` is a
//! JSON line as it serialises (`ack`, `command_failed`, `skipped`,
//! `late_ack`, `duplicate_ack`): its serde names and field order are the
//! line's.

use serde::ser::SerializeMap;
use serde::{Serialize, Serializer};

use crate::engine::kind::KindValue;
use crate::engine::Nanos;
use crate::frame::{codec, SysComp};

/// What the command probe decided (its tracker is pure; the driver turns
/// `Send` into a frame on the wire).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(tag = "type", rename_all = "snake_case")]
pub(crate) enum CommandEvent {
    /// Put attempt `attempt` (1-based) of command `n` on the wire. Not a
    /// line: each transmission is in the summary's attempt counts.
    #[serde(skip)]
    Send {
        n: u64,
        target: SysComp,
        command: u16,
        attempt: u32,
    },
    Skipped {
        #[serde(rename = "t_s", serialize_with = "seconds")]
        at: Nanos,
        target: SysComp,
        command: u16,
    },
    #[serde(rename = "ack")]
    Acked {
        n: u64,
        target: SysComp,
        from: SysComp,
        command: u16,
        #[serde(flatten, serialize_with = "result_and_name")]
        result: u8,
        attempts: u32,
        #[serde(rename = "time_to_ack_us", serialize_with = "us")]
        time_to_ack: Nanos,
    },
    #[serde(rename = "command_failed")]
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

impl CommandEvent {
    /// Whether it is a line of its own (every event but a transmission).
    pub(crate) fn is_line(&self) -> bool {
        !matches!(self, CommandEvent::Send { .. })
    }
}

/// Every event but `Send` is written whole, as its JSON line.
impl KindValue for CommandEvent {
    fn serialized(&self) -> Option<&dyn erased_serde::Serialize> {
        self.is_line().then_some(self)
    }
}

fn seconds<S: Serializer>(t: &Nanos, s: S) -> Result<S::Ok, S::Error> {
    s.serialize_f64(*t as f64 / 1e9)
}

fn us<S: Serializer>(t: &Nanos, s: S) -> Result<S::Ok, S::Error> {
    s.serialize_f64(*t as f64 / 1e3)
}

/// MAV_RESULT and its name.
fn result_and_name<S: Serializer>(result: &u8, s: S) -> Result<S::Ok, S::Error> {
    let mut map = s.serialize_map(Some(2))?;
    map.serialize_entry("result", result)?;
    map.serialize_entry("result_name", &codec::result_name(*result))?;
    map.end()
}
