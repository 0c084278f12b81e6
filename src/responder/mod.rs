//! `mavping respond`: a well-behaved MAVLink system on any link, answering
//! PING, TIMESYNC and COMMAND_LONG through [`core::ResponderCore`], serving
//! a parameter list, a mission and a file read-only, with
//! optional link emulation (delay, jitter, drop, duplicate) for tests,
//! and telemetry streamed as a vehicle does (`--stream`), numbered with
//! the same packet sequence as every other frame it sends.
//!
//! Every answer goes back only on the path its request came from
//! (`send_to`): one reply per request, never amplified to other peers.
//!
//! One file per concern: the [`settings`], the loop that answers
//! ([`respond_loop`]), the link emulation of the replies ([`replies`]),
//! the transfers [`serving`] (parameters, mission, a file), the telemetry
//! [`streams`] and the [`counts`] printed on exit.

mod counts;
mod replies;
mod respond_loop;
mod serving;
mod settings;
mod streams;

pub(crate) use counts::RespondCounts;
pub(crate) use respond_loop::run;
pub(crate) use settings::{describe, ResponderSettings};
