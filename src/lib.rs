//! mavping: MAVLink link latency measurement.
//!
//! Data flows link -> frames -> probe -> matcher -> statistics -> report:
//! [`transport`] reads bytes and yields CRC-checked [`frame`]s, a probe ([`engine::probe`])
//! recognises replies, the pure [`engine::matcher`] counts them, and an
//! [`output`] reporter prints events and the summary. [`run`] joins them
//! for one or many links from a validated [`config`]; [`exit`] decides the
//! exit code.

pub mod answering;
pub mod cli;
pub mod config;
pub mod engine;
pub mod exit;
pub mod frame;
pub mod output;
pub mod responder;
pub mod run;
pub mod stderr;
pub mod telemetry;
pub mod transport;
pub mod units;
pub mod verdict;
