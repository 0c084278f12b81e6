//! The measurement: scheduling, matching and statistics (pure, time passed
//! in), and the async session that joins them to a transport. It defines
//! what it tells the world ([`observe`]) and depends on nothing above it:
//! not on the command line, the configuration, the reports or the verdict.

pub(crate) mod age;
pub(crate) mod answers;
pub(crate) mod c2;
pub(crate) mod capacity;
pub(crate) mod clock_offset;
pub(crate) mod diagnosis;
pub(crate) mod hint;
pub(crate) mod ignored;
pub mod kind;
pub(crate) mod link_io;
pub(crate) mod link_node;
pub(crate) mod load;
pub mod matcher;
pub mod observe;
pub(crate) mod pair;
pub mod probe;
pub mod radio;
pub(crate) mod radio_kind;
pub(crate) mod roster;
pub(crate) mod schedule;
pub mod session;
mod session_config;
pub mod stats;
pub mod summary;
pub(crate) mod sweep;
pub(crate) mod sweep_report;
#[cfg(not(mavping_portable))]
pub(crate) mod wait;
// The portable path's waits (build.rs): same interface, no Linux timers.
#[cfg(mavping_portable)]
#[path = "wait_portable.rs"]
pub(crate) mod wait;

pub use session_config::{CommandSpec, SessionConfig};

/// Time in nanoseconds since the session started, from a monotonic clock.
/// The pure parts take time as a value; only the session reads a clock.
pub(crate) type Nanos = u64;
