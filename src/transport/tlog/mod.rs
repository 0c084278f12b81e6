//! `tlog:FILE` and `tlog:-` (standard input): a telemetry log read as a
//! link, on the log's own clock. Every ground station records one
//! (QGroundControl, Mission Planner, MAVProxy, mavlink-router); the
//! passive figures of a live link come out of it the same way.
//!
//! - **Streaming, in constant memory.** The file is read in chunks of
//!   [`READ_CHUNK`](input::READ_CHUNK) on tokio's blocking pool
//!   ([`input`]; while a read is under way a paused clock does not move,
//!   so the log's time never runs ahead of its bytes), split into records
//!   ([`records`]) in a buffer of at most a chunk and two records, each
//!   frame checked by the frame scanner.
//! - **The log's clock.** The run is on tokio's paused clock, as
//!   `sim:?clock=virtual`: session time 0 is the first record and each
//!   record arrives at its stamp ([`stamps`]). Before each wait the
//!   session says when it wakes next
//!   ([`Transport::next_wake`](crate::transport::Transport::next_wake));
//!   one `recv` then hands over every record due by then (up to
//!   [`MAX_BATCH`](link::MAX_BATCH)), after sleeping to the last one's
//!   time, so a frame is never seen before its time and a second's tick
//!   or a `-w` deadline falls exactly between records ([`link`]). A
//!   two-hour log is read in seconds.
//! - **The end of the log ends the run**, cleanly
//!   ([`LinkError::End`](crate::transport::LinkError::End)), once the
//!   clock has reached the last record.
//! - **Nothing is sent**: `send` is refused; a passive session without
//!   our HEARTBEAT never calls it.
//! - The stamps' two lowest bits (MAVProxy's link number) are each
//!   frame's path, for per-link figures.

mod facts;
mod input;
mod link;
mod path;
pub(crate) mod records;
mod sniff;
pub(crate) mod stamps;
pub(crate) mod writer;

pub(crate) use facts::LogFacts;
pub(crate) use link::TlogLink;
pub(crate) use path::TlogPath;
