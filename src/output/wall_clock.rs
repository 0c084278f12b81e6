//! Session time as wall-clock time, for the formats that write it.

use std::time::{Duration, SystemTime};

use crate::engine::Nanos;

/// Session time to wall-clock time. The wall clock is read once at the
/// start (the UNIX epoch under the virtual clock, so output is reproducible)
/// and advanced by the monotonic session clock.
#[derive(Debug, Clone, Copy)]
pub(crate) struct WallClock {
    pub(crate) start: SystemTime,
}

impl WallClock {
    /// Now, or the UNIX epoch when the run is on a virtual clock.
    pub(crate) fn starting(virtual_clock: bool) -> Self {
        WallClock {
            start: if virtual_clock {
                SystemTime::UNIX_EPOCH
            } else {
                SystemTime::now()
            },
        }
    }

    pub(crate) fn at(&self, t: Nanos) -> SystemTime {
        self.start + Duration::from_nanos(t)
    }

    pub(crate) fn rfc3339(&self, t: Nanos) -> String {
        humantime::format_rfc3339_micros(self.at(t)).to_string()
    }

    pub(crate) fn micros_since_epoch(&self) -> u64 {
        self.start
            .duration_since(SystemTime::UNIX_EPOCH)
            .map_or(0, |d| d.as_micros() as u64)
    }
}
