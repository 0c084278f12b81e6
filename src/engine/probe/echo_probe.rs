//! What an echo probe is ([`EchoProbe`]: its requests, how it recognises
//! a reply, what it learns from one) and what a frame means to it
//! ([`Classified`]): the interface PING, TIMESYNC and auto implement and
//! the echo driver runs, apart from any one of them.

use crate::engine::clock_offset::ClockSummary;
use crate::engine::link_io::WallAtZero;
use crate::engine::matcher::Lookup;
use crate::engine::summary::ProbeName;
use crate::engine::Nanos;
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
    /// The session starts: its time 0 is `wall_at_zero` on the wall clock
    /// (both read together, so our clock is the wall clock, not late by
    /// however long the run took to start).
    fn begin(&mut self, _wall_at_zero: WallAtZero) {}
    /// Which probe it is, as reports name it.
    fn name(&self) -> ProbeName;
    /// The token for a request sent at `now_ns` (session clock); tokens
    /// must rise strictly if replies are looked up by token.
    fn token(&mut self, now_ns: u64) -> u64;
    /// The request to send.
    fn request(&self, seq: u32, token: u64) -> Msg;
    /// A second request carrying the same token, sent beside the first
    /// (auto: TIMESYNC beside PING once a responder needs it).
    fn second_request(&self, _seq: u32, _token: u64) -> Option<Msg> {
        None
    }
    /// Sees every frame before it is classified (auto: who sent
    /// HEARTBEAT, who answered PING).
    fn heard(&mut self, _frame: &Frame, _ours: SysComp) {}
    /// Classifies a received frame; `ours` is our own address.
    fn classify(&self, frame: &Frame, ours: SysComp) -> Classified;
    /// Called with each in-time reply the matcher accepted (TIMESYNC reads
    /// the responder's clock from it).
    fn on_reply(&mut self, _frame: &Frame, _sent_at: Nanos, _at: Nanos) {}
    /// Whether this probe measures the responders' clocks.
    fn measures_clocks(&self) -> bool {
        false
    }
    /// The probe a responder is measured by, where it may differ between
    /// responders (auto); `None`: the probe's own name says it.
    fn used_by(&self, _responder: SysComp) -> Option<ProbeName> {
        None
    }
    /// The responder's clock offset, for probes that measure one.
    fn clock(&self, _responder: SysComp) -> Option<ClockSummary> {
        None
    }

    /// What our clock read at session time 0 in the clock offsets'
    /// terms (ns): their clock minus this plus session time is the offset.
    fn clock_base_ns(&self) -> i128 {
        0
    }
}
