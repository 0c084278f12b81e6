//! mavping: MAVLink link latency measurement.
//!
//! Data flows link -> frames -> probe -> matcher -> statistics -> report:
//! [`transport`] reads bytes and yields CRC-checked [`frame`]s, a [`probe`]
//! recognises replies, the pure [`engine::matcher`] counts them, and an
//! [`output`] reporter prints events and the summary.

pub mod app;
pub mod cli;
pub mod config;
pub mod engine;
pub mod frame;
pub mod multilink;
pub mod output;
pub mod probe;
pub mod respond;
pub mod responder;
pub mod transport;
pub mod verdict;
