//! `mavping serve`: Prometheus's multi-target exporter pattern for MAVLink.
//! `/probe?target=...` runs one bounded probe ([`probe`]); continuous links
//! are measured all the time ([`links`]) and shown at `/metrics` with the
//! exporter's own health. SIGHUP, or `POST /-/reload` with
//! `--web.enable-lifecycle`, rereads the configuration and the web config
//! (TLS, basic auth): an invalid one is refused and the old ones kept.
//!
//! Everything runs on one thread: the HTTP server's handlers, every probe
//! and every link's session share it, none of them spinning.

mod descriptors;
mod links;
mod listen;
mod probe;
mod server;

pub(super) use listen::{check, run};
pub use server::handler_for;
