//! The transfer probes: what a ground station downloads at connect, made
//! a measurement. `--probe params` (every parameter), `mission` (the
//! mission's items), `ftp` (a file over MAVLink FTP), each read-only.
//! Each protocol is a pure [`attempt::Protocol`] (`params.rs`,
//! `mission.rs`, `ftp.rs`) on the shared request bookkeeping (`asks.rs`)
//! and progress (`progress.rs`); `driver.rs` runs them in the session
//! with TIMESYNC probes beside; `summary.rs` is the run's end.

mod asks;
pub(crate) mod attempt;
pub(crate) mod driver;
mod ftp;
mod mission;
mod params;
pub(crate) mod progress;
mod spec;
pub(crate) mod summary;

pub(crate) use attempt::{AttemptFigures, Ending};
pub(crate) use driver::TransferProgress;
pub(crate) use spec::{TransferKind, TransferSpec};
pub(crate) use summary::TransferSummary;
