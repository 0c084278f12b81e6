//! The measurement: scheduling, matching, statistics (pure), and the async
//! session that joins them to a transport and a report.

pub mod capacity;
pub mod clock_offset;
pub mod command_session;
pub mod commands;
pub mod matcher;
pub mod radio;
pub mod roster;
pub mod schedule;
pub mod session;
pub mod stats;

/// Time in nanoseconds since the session started, from a monotonic clock.
/// The pure parts take time as a value; only the session reads a clock.
pub type Nanos = u64;
pub mod summary;
