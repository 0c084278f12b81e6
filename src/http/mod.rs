//! The one HTTP server of mavping, behind `--prometheus` and `mavping
//! serve` ([`server`]), and the basic auth its web config asks for
//! ([`basic_auth`]). A transport for the reports, not a report: the
//! exporter and `serve` hand it the text they render.

pub(crate) mod basic_auth;
mod server;

pub(crate) use server::{listener, serve, serve_with, Head, Replying, SharedWeb};
pub use server::{serve_one, Limits, Reply};
