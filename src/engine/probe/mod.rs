//! Kinds of measurement, one home each: what a request looks like, how its
//! reply is recognised, and the [`Driver`](crate::engine::session::Driver)
//! that runs it in the session loop. Echo probes (PING, TIMESYNC) share
//! [`echo`]'s driver; the command probe has its own ([`command`]). The
//! matcher never sees MAVLink; a probe turns frames into
//! [`Lookup`](crate::engine::matcher::Lookup)s; [`EchoProbe`] is what an
//! echo probe implements.
//!
//! Probes build on the engine's pure parts and its session; nothing else
//! in the engine names a probe.

pub(crate) mod auto;
pub(crate) mod command;
pub mod echo;
mod echo_probe;
pub mod passive;
pub mod ping;
pub(crate) mod timesync;
pub(crate) mod transfer;
pub(crate) mod uplink_check;

pub use echo_probe::{Classified, EchoProbe};

// The probes name it as `super::ProbeName`.
use crate::engine::summary::ProbeName;
