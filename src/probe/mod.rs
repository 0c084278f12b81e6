//! Probes: what a request looks like and how to recognise its reply.
//! The matcher never sees MAVLink; a probe turns frames into [`Lookup`]s.

pub mod ping;

use crate::engine::matcher::Lookup;
use crate::frame::{Frame, Msg, SysComp};

/// What a received frame means to the probe.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Classified {
    /// A reply addressed to us.
    Reply(Lookup),
    /// A reply addressed to another system (counted, never measured).
    ForeignReply,
    /// Not a reply of this probe's kind (requests, telemetry...).
    NotAReply,
}

/// A request/reply probe whose replies echo a token (PING, TIMESYNC).
pub trait EchoProbe {
    /// Name shown in reports ("ping").
    fn name(&self) -> &'static str;
    /// The token for a request sent at `now_ns` (session clock); tokens
    /// must rise strictly if replies are looked up by token.
    fn token(&mut self, now_ns: u64) -> u64;
    /// The request to send.
    fn request(&self, seq: u32, token: u64) -> Msg;
    /// Classifies a received frame; `ours` is our own address.
    fn classify(&self, frame: &Frame, ours: SysComp) -> Classified;
}
