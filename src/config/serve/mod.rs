//! `mavping serve [OPTIONS]` and its TOML file into a [`ServeConfig`], and
//! each `/probe?target=...` request into a [`ProbePlan`]: the same rules as
//! the command line, one function a rule, errors on one line.
//!
//! - `settings.rs`: the command line and the file into the settings a
//!   reload may change;
//! - `allow.rs`: default deny, the patterns `/probe` targets must match;
//! - `file.rs`: the TOML file's tables into modules and continuous links;
//! - `request.rs`: a `/probe` query into a plan;
//! - `session.rs`: the session each probe and link runs;
//! - `limits.rs`: what a server takes at most, and its defaults;
//! - `web.rs`: `--web.config.file` (TLS, basic auth, headers).

mod allow;
mod file;
mod limits;
mod request;
mod session;
mod settings;
mod web;

pub use allow::Pattern;
pub(crate) use request::ProbePlan;
pub(crate) use settings::ContinuousLink;
pub use settings::{ServeConfig, ServeSettings};
pub(crate) use web::WebConfig;
