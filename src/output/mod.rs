//! Reports: each output format is a [`Reporter`], which the engine tells
//! as an `Observer`; it takes the kinds of event it shows and renders the
//! judged summary at the end. This file only declares and re-exports.

#[cfg(test)]
mod every_format;
mod fanout;
pub(crate) mod hgrm;
pub(crate) mod json;
pub(crate) mod live;
pub(crate) mod pair;
pub(crate) mod plot;
pub mod prometheus;
mod reporter;
#[cfg(test)]
mod runs;
pub(crate) mod samples;
pub(crate) mod text;
pub(crate) mod textfile;
mod wall_clock;
pub(crate) mod windows;
mod writers;

pub(crate) use crate::engine::observe::{Event, StartInfo};
pub(crate) use fanout::Fanout;
pub(crate) use reporter::Reporter;
pub(crate) use wall_clock::WallClock;
pub(crate) use writers::{Prefixed, Shared};
