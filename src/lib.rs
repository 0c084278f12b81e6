//! mavping: MAVLink link latency measurement.
//!
//! Data flows link -> frames -> probe -> matcher -> statistics -> report:
//! [`transport`] reads bytes and yields CRC-checked [`frame`]s, a probe ([`engine::probe`])
//! recognises replies, the pure [`engine::matcher`] counts them, and an
//! [`output`] reporter prints events and the summary. [`run`] joins them
//! for one or many links from a validated [`config`]; [`exit`] decides the
//! exit code.
//!
//! The public paths are the façade: what the binary, the integration
//! tests, the benches, the examples and the fuzz targets use. Everything
//! else is `pub(crate)`, which `unreachable_pub` keeps so: an item nothing
//! outside uses is not public, and one nothing uses at all is dead code
//! the compiler reports.
#![warn(unreachable_pub)]

pub(crate) mod answering;
pub mod cli;
pub(crate) mod compare;
pub mod config;
pub mod engine;
pub mod exit;
pub mod frame;
pub mod http;
pub mod output;
pub(crate) mod responder;
pub mod run;
pub(crate) mod stderr;
pub(crate) mod telemetry;
pub mod transport;
pub mod units;
pub(crate) mod verdict;
