//! What the responders send, in the order they send it: the timetable of
//! HEARTBEATs, telemetry and replies ([`Outgoing`]), each numbered when it
//! goes, and the frames themselves.

use std::cmp::{Ordering, Reverse};
use std::time::Duration;

use tokio::time::Instant;

use super::deliveries::Copies;
use super::link::SimLink;
use crate::frame::{self, Frame, Msg, Version};

/// A frame a responder sends at `at`, numbered then.
pub(super) struct Outgoing {
    pub(super) at: Instant,
    pub(super) order: u64,
    pub(super) responder: usize,
    pub(super) what: Sends,
}

pub(super) enum Sends {
    Heartbeat,
    /// Telemetry: the responder's stream of this index.
    Stream(usize),
    /// A reply, its fate drawn when its request was sent.
    Reply(Box<Reply>),
    /// A transfer request reaches the responder ([`super::transfers`]).
    TransferRequest(Box<Frame>),
    /// The responder's next transfer frame.
    Transfer,
}

pub(super) struct Reply {
    pub(super) msg: Msg,
    pub(super) version: Version,
    /// When (and by which paths) its copies arrive, or `None`: lost on
    /// the way.
    pub(super) copies: Option<Copies>,
}

impl PartialEq for Outgoing {
    fn eq(&self, other: &Self) -> bool {
        self.cmp(other) == Ordering::Equal
    }
}

impl Eq for Outgoing {}

impl PartialOrd for Outgoing {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for Outgoing {
    fn cmp(&self, other: &Self) -> Ordering {
        (self.at, self.order).cmp(&(other.at, other.order))
    }
}

/// The simulated responders' HEARTBEAT: a PX4 quadrotor, or with
/// `ping=off` an ArduPilot one (which answers TIMESYNC, never PING).
const fn heartbeat(answers_ping: bool) -> Msg {
    Msg::Heartbeat {
        mav_type: 2, // quadrotor
        autopilot: if answers_ping {
            12 // PX4
        } else {
            crate::frame::AUTOPILOT_ARDUPILOT
        },
    }
}

impl SimLink {
    /// Responder `i` sends `what` at `ns` after the link opened.
    pub(super) fn schedule(&mut self, ns: u64, i: usize, what: Sends) {
        self.outgoing_order += 1;
        self.outgoing.push(Reverse(Outgoing {
            at: self.instant(ns),
            order: self.outgoing_order,
            responder: i,
            what,
        }));
    }

    /// Numbers and sends, in order, every frame the responders send until
    /// `now`.
    pub(super) fn send_due_frames(&mut self, now: Instant) {
        while self.outgoing.peek().is_some_and(|o| o.0.at <= now) {
            let Reverse(o) = self.outgoing.pop().expect("peeked");
            let i = o.responder;
            match o.what {
                Sends::Heartbeat => {
                    self.send_heartbeat(i, o.at);
                    let schedule = self.responders[i].heartbeat.as_mut().expect("on");
                    schedule.advance();
                    let next = schedule.due_ns();
                    self.schedule(next, i, Sends::Heartbeat);
                }
                Sends::Stream(k) => {
                    self.send_telemetry(i, k, o.at);
                    let schedule = &mut self.responders[i].streams[k].1;
                    schedule.advance();
                    let next = schedule.due_ns();
                    self.schedule(next, i, Sends::Stream(k));
                }
                Sends::Reply(reply) => {
                    let (header, index) = self.responders[i].header();
                    match reply.copies {
                        Some(copies) => {
                            let mut bytes = Vec::new();
                            frame::encode(&mut bytes, reply.version, header, &reply.msg);
                            self.put_on_way(i, index, bytes, &copies);
                        }
                        None => self.responders[i].truth.down.dropped += 1,
                    }
                }
                Sends::TransferRequest(request) => self.take_transfer_request(i, &request, o.at),
                Sends::Transfer => self.send_transfer(i, o.at),
            }
        }
    }

    /// A HEARTBEAT sent at `sent`: one leg later at mavping (no jitter, no
    /// wire time), but for the per-direction faults and the outage (which
    /// silences the whole link: what a C2 report's availability sees).
    fn send_heartbeat(&mut self, i: usize, sent: Instant) {
        let (header, index) = self.responders[i].header();
        if self.in_outage(sent) {
            self.responders[i].truth.down.dropped += 1;
            return;
        }
        let mut bytes = Vec::new();
        frame::encode(
            &mut bytes,
            Version::V2,
            header,
            &heartbeat(self.params.answer_ping),
        );
        let at = sent + self.queued_down(sent) + self.params.delay;
        self.send_down(i, index, bytes, sent, at);
    }

    /// A telemetry frame sent at `sent`: through the outage, the wire or
    /// the radios, and the per-direction faults.
    fn send_telemetry(&mut self, i: usize, k: usize, sent: Instant) {
        let kind = self.responders[i].streams[k].0;
        let (header, index) = self.responders[i].header();
        // Stamped by the vehicle's clock (`offset=`, `drift=`), which
        // counts since it booted, as a u32 of milliseconds does: wrapping.
        let time_boot_ms = self
            .clock_ns(sent)
            .div_euclid(1_000_000)
            .rem_euclid(1 << 32) as u32;
        let mut bytes = Vec::new();
        frame::encode(
            &mut bytes,
            Version::V2,
            header,
            &kind.msg(time_boot_ms, &heartbeat(self.params.answer_ping)),
        );
        if self.in_outage(sent) {
            self.responders[i].truth.down.dropped += 1;
            return;
        }
        let Some(done) = self.downlink(sent, Duration::ZERO, bytes.len()) else {
            self.responders[i].truth.down.dropped += 1;
            return;
        };
        let at = done + self.queued_down(done) + self.vehicle_one_way();
        self.send_down(i, index, bytes, sent, at);
    }
}
