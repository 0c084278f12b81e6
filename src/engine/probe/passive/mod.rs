//! Passive measurement: what a link's own traffic says about its losses,
//! without sending anything on it.

pub mod driver;
pub mod flight;
pub mod links;
mod rate;
pub mod round_trips;
pub mod ticks;
pub mod tracker;
