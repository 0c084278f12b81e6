//! Passive measurement: what a link's own traffic says about its losses,
//! without sending anything on it.

pub(crate) mod driver;
pub(crate) mod flight;
pub(crate) mod ground;
pub(crate) mod links;
mod rate;
pub(crate) mod round_trips;
pub(crate) mod ticks;
mod told;
pub mod tracker;

pub use told::{PassivePlan, SourcesNow};
