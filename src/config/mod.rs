//! The validated configuration: clap's types stop here. What the engine
//! and transports get from it are their own plain types ([`SessionConfig`],
//! [`CommandSpec`], [`LinkSpec`], [`ResponderSettings`]).
//!
//! - `measure.rs`: `mavping [OPTIONS] LINK...` into a `Config`, with
//!   `sweep.rs` for a run in steps;
//! - `respond.rs`: `mavping respond` into a `RespondConfig`;
//! - `compare.rs`: `mavping compare` into a `CompareConfig`;
//! - `serve/`: `mavping serve`, its file and each `/probe` request;
//! - what they share: `link.rs`, `probe.rs`, `signing.rs`, `values.rs`
//!   (checks every front end makes alike), `keys.rs` (how errors name a
//!   setting) and `error.rs`.
//!
//! [`SessionConfig`]: crate::engine::SessionConfig
//! [`CommandSpec`]: crate::engine::CommandSpec
//! [`LinkSpec`]: crate::transport::address::LinkSpec
//! [`ResponderSettings`]: crate::responder::ResponderSettings

pub(crate) mod c2;
mod compare;
mod error;
mod keys;
mod link;
mod measure;
mod probe;
mod respond;
mod serve;
mod signing;
mod sweep;
mod values;

pub(crate) use compare::CompareConfig;
pub use error::ConfigError;
pub(crate) use link::LinkConfig;
pub(crate) use measure::{Config, OutputConfig};
pub(crate) use probe::Probe;
pub(crate) use respond::RespondConfig;
pub(crate) use serve::{ContinuousLink, ProbePlan, WebConfig};
pub use serve::{Pattern, ServeConfig, ServeSettings};
