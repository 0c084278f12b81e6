//! The end of an echo run (PING, TIMESYNC, auto, a sweep's steps): the
//! [`EchoSummary`] with each responder's figures, its send pacing, and the
//! wire budget a serial link's baud rate sets; built from the matcher and
//! the roster.

use serde::ser::SerializeMap;
use serde::{Serialize, Serializer};

use super::direction::Direction;
use super::probe_name::ProbeName;
use crate::engine::age::{SourceAge, SplitSummary};
use crate::engine::answers::AnswerSummary;
use crate::engine::capacity::WireBudget;
use crate::engine::clock_offset::ClockSummary;
use crate::engine::hint::{Hint, HintCode};
use crate::engine::link_node::LinkNodeSummary;
use crate::engine::matcher::{Counts, Matcher};
use crate::engine::radio::RadioSummary;
use crate::engine::roster::{Identity, Roster};
use crate::engine::stats::{Bucket, RttSummary};
use crate::engine::sweep_report::SweepSummary;
use crate::frame::signing::SigningSummary;
use crate::frame::{ScanStats, SysComp};
use crate::transport::RxClock;

/// Rows in the ASCII/JSON RTT distribution.
pub(crate) const HISTOGRAM_ROWS: usize = 8;

/// One responder's figures. Serialised as a responder of the JSON
/// `summary` line, in this order; the line adds the verdict's messages
/// about it, and then the direction, so that is skipped here.
#[derive(Debug, Clone, Serialize)]
pub struct ResponderSummary {
    #[serde(rename = "responder")]
    pub id: SysComp,
    pub(crate) identity: Option<Identity>,
    #[serde(flatten, serialize_with = "counts")]
    pub counts: Counts,
    /// Written among the counts it is computed from.
    #[serde(skip)]
    pub(crate) loss_ratio: f64,
    #[serde(rename = "rtt_us")]
    pub(crate) rtt: Option<RttSummary>,
    pub(crate) histogram: Vec<Bucket>,
    /// The probe it was measured by (`--probe auto` only: PING or
    /// TIMESYNC, chosen per responder).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(crate) probe: Option<ProbeName>,
    /// Clock offset and drift (TIMESYNC probe only).
    pub(crate) clock: Option<ClockSummary>,
    /// Which way the losses were, when there were any: the responder's
    /// own sequence numbers give the downlink.
    #[serde(skip)]
    pub(crate) direction: Option<Direction>,
    /// The round trip split into uplink and downlink queues, from the
    /// responder's clock in its replies (TIMESYNC).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(crate) split: Option<SplitSummary>,
}

/// A responder's counts with its loss ratio, in the order the JSON has
/// always given them.
fn counts<S: Serializer>(c: &Counts, s: S) -> Result<S::Ok, S::Error> {
    let mut map = s.serialize_map(Some(10))?;
    map.serialize_entry("sent", &c.sent)?;
    map.serialize_entry("received", &c.received)?;
    map.serialize_entry("lost", &c.lost)?;
    map.serialize_entry("loss_ratio", &c.loss_ratio())?;
    map.serialize_entry("late", &c.late)?;
    map.serialize_entry("duplicate", &c.duplicate)?;
    map.serialize_entry("out_of_order", &c.out_of_order)?;
    map.serialize_entry("stale", &c.stale)?;
    map.serialize_entry("not_charged", &c.not_charged)?;
    map.serialize_entry("in_flight", &c.in_flight)?;
    map.end()
}

/// How well requests kept to their schedule (see the session's pacing).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub(crate) struct ScheduleSummary {
    pub(crate) requested_rate_hz: f64,
    pub(crate) achieved_rate_hz: f64,
    /// Actual send minus planned send, over all requests.
    pub(crate) lateness_p50_us: f64,
    pub(crate) lateness_p99_us: f64,
    pub(crate) lateness_max_us: f64,
    /// Requests the link refused because its peer is not reading (a
    /// byte stream whose queue was full): never sent, so never lost.
    pub(crate) not_sent: u64,
}

/// The end of an echo run. Serialised as the JSON `summary` line's
/// figures, in this order (the line adds the link as named, the
/// responders with the verdict's messages about each, and the sweep); the
/// fields it adds itself are skipped here.
#[derive(Debug, Clone, Serialize)]
pub struct EchoSummary {
    #[serde(skip)]
    pub(crate) link: String,
    pub(crate) probe: ProbeName,
    pub(crate) ours: SysComp,
    pub(crate) duration_s: f64,
    /// Requests put on the wire.
    pub requests: u64,
    /// Requests still within their timeout when the run ended, unanswered
    /// by at least one responder: counted neither received nor lost.
    pub(crate) in_flight: u64,
    /// A listening link heard no MAVLink system in this many seconds, and
    /// the run ended.
    pub(crate) no_peer_heard_s: Option<f64>,
    pub(crate) interrupted: bool,
    pub(crate) link_error: Option<String>,
    /// Seconds the link was down while reconnecting (`--reconnect`).
    pub(crate) downtime_s: f64,
    /// Send pacing figures, once a request was sent.
    pub(crate) schedule: Option<ScheduleSummary>,
    /// How receive times were taken (kernel timestamps or user space).
    pub(crate) rx_clock: RxClock,
    pub(crate) frames: ScanStats,
    /// Replies addressed to another system.
    pub(crate) foreign_replies: u64,
    /// Replies naming a responder that answered from another link peer
    /// (spoofed ids): counted, never measured.
    pub(crate) wrong_path_replies: u64,
    /// Replies from responders beyond the tracking limit.
    pub(crate) untracked_replies: u64,
    pub(crate) hints: Vec<Hint>,
    /// Radios heard by their RADIO_STATUS.
    pub(crate) radios: Vec<RadioSummary>,
    /// Nodes heard by their LINK_NODE_STATUS (the vehicle's own view of
    /// the link), each beside mavping's uplink estimate for its system.
    pub(crate) link_node: Vec<LinkNodeSummary>,
    /// What a serial link's baud rate carries (serial links only).
    pub(crate) wire: Option<WireBudget>,
    /// What the signing gate accepted and refused, or, without a key, what
    /// came signed unchecked.
    pub(crate) signing: SigningSummary,
    /// The vehicle's TIMESYNC and PING requests answered.
    #[serde(skip_serializing_if = "AnswerSummary::is_none")]
    pub(crate) answered: AnswerSummary,
    /// How old each source's frames were when they arrived, above its
    /// baseline, from their own clock stamps.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub(crate) age: Vec<SourceAge>,
    #[serde(skip)]
    pub responders: Vec<ResponderSummary>,
    /// `--sweep` or `--load`: the steps and what they say.
    #[serde(skip)]
    pub(crate) sweep: Option<Box<SweepSummary>>,
}

impl EchoSummary {
    /// True when at least one responder answered in time.
    pub(crate) fn any_reply(&self) -> bool {
        self.responders.iter().any(|r| r.counts.received > 0)
    }

    /// The smallest RTT median across the responders, in µs: what the
    /// wire's floor is set beside.
    pub(crate) fn smallest_p50_us(&self) -> Option<f64> {
        let p50s = self.responders.iter().filter_map(|r| r.rtt);
        p50s.map(|t| t.p50_us).reduce(f64::min)
    }

    /// Puts a serial link's budget in the summary and, when the run shows
    /// the link was overrun (losses, or an RTT spread far beyond the wire
    /// time, which is a queue growing), says so. Replies faster than the
    /// baud rate allows show the device ignores it (USB CDC, a pty): then
    /// there is no budget to report.
    pub(crate) fn apply_wire(&mut self, budget: WireBudget) {
        let fastest = self
            .responders
            .iter()
            .filter_map(|r| r.rtt)
            .map(|t| t.min_us)
            .reduce(f64::min);
        // Well under the floor: the clocks' and the arithmetic's rounding
        // cannot explain it.
        if let Some(fastest) = fastest.filter(|&f| f < 0.9 * budget.floor_us) {
            self.hints.push(Hint::new(
                HintCode::BaudNotInEffect,
                format!(
                    "replies came back in {:.3} ms, faster than {} baud allows ({:.3} ms per \
                     round trip): the device ignores the baud rate (USB CDC or a pty), so no \
                     wire floor or capacity applies",
                    fastest / 1e3,
                    budget.baud,
                    budget.floor_us / 1e3
                ),
            ));
            return;
        }
        if let (Some(device), Some(fastest)) = (budget.ignorer, fastest) {
            self.hints.push(Hint::new(
                HintCode::BaudUnverified,
                format!(
                    "the wire figures assume {} baud paces this link, but the device is {}, \
                     which passes data as fast as it is read unless something behind it \
                     paces it; the fastest reply ({:.3} ms) fits a {:.3} ms wire floor either \
                     way, so they are unproven",
                    budget.baud,
                    device,
                    fastest / 1e3,
                    budget.floor_us / 1e3
                ),
            ));
        }
        self.wire = Some(budget);
        let Some(rate) = self.schedule.map(|s| s.requested_rate_hz) else {
            return;
        };
        // After the run the responders are known, not guessed.
        let b = budget.with_replies(self.responders.len() as u64);
        let overrun = self.responders.iter().any(|r| {
            r.counts.lost > 0
                || r.rtt
                    .is_some_and(|t| t.max_us - t.min_us > 10.0 * budget.floor_us)
        });
        if overrun {
            if let Some(w) = b.warning(rate) {
                self.hints.push(Hint::new(
                    HintCode::WireOverrun,
                    format!("{w}: this run did"),
                ));
            }
        }
    }
}

pub(crate) fn responder_summaries(matcher: &Matcher, roster: &Roster) -> Vec<ResponderSummary> {
    let mut out: Vec<ResponderSummary> = matcher
        .responders()
        .iter()
        .map(|r| (r, matcher.counts_now(r)))
        .map(|(r, counts)| ResponderSummary {
            id: r.id,
            counts,
            loss_ratio: counts.loss_ratio(),
            rtt: r.rtt.summary(),
            histogram: r.rtt.distribution(HISTOGRAM_ROWS),
            identity: roster.get(r.id).cloned(),
            probe: None,
            clock: None,
            direction: None,
            split: None,
        })
        .collect();
    out.sort_by_key(|r| r.id);
    out
}

impl super::KindSummary for EchoSummary {
    fn link(&self) -> &str {
        &self.link
    }
    fn link_error(&self) -> Option<&str> {
        self.link_error.as_deref()
    }
    fn requests(&self) -> (u64, u64) {
        (self.requests, self.in_flight)
    }
    fn apply_wire(&mut self, budget: WireBudget) {
        EchoSummary::apply_wire(self, budget);
    }
}

/// An echo run so far: each responder's counts of decided requests and
/// its RTT figures.
#[derive(Debug, Clone)]
pub struct EchoInterim {
    /// Session time, ns.
    pub(crate) at: crate::engine::Nanos,
    pub(crate) requests: u64,
    pub(crate) responders: Vec<ResponderSummary>,
}

impl crate::engine::kind::KindValue for EchoInterim {}

#[cfg(test)]
impl EchoSummary {
    /// A run of `requests` PINGs on `link` with nothing in it, for tests
    /// to fill in.
    pub(crate) fn empty(link: &str, requests: u64) -> EchoSummary {
        EchoSummary {
            link: link.into(),
            probe: ProbeName::Ping,
            ours: SysComp::new(250, 190),
            duration_s: 1.0,
            requests,
            in_flight: 0,
            no_peer_heard_s: None,
            responders: vec![],
            foreign_replies: 0,
            wrong_path_replies: 0,
            untracked_replies: 0,
            frames: ScanStats::default(),
            hints: vec![],
            interrupted: false,
            link_error: None,
            downtime_s: 0.0,
            schedule: None,
            rx_clock: RxClock::Simulated,
            radios: vec![],
            link_node: vec![],
            wire: None,
            signing: crate::frame::signing::Gate::new(None).summary(),
            answered: AnswerSummary::default(),
            age: Vec::new(),
            sweep: None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::engine::matcher::Counts;
    use crate::engine::stats::RttStats;

    fn run(lost: u64, requested_rate_hz: f64, min_rtt_ms: u64) -> EchoSummary {
        let mut rtt = RttStats::new();
        rtt.record(min_rtt_ms * 1_000_000);
        EchoSummary {
            responders: vec![ResponderSummary {
                id: SysComp::new(1, 1),
                counts: Counts {
                    sent: 10,
                    received: 10 - lost,
                    lost,
                    ..Counts::default()
                },
                loss_ratio: lost as f64 / 10.0,
                rtt: rtt.summary(),
                histogram: vec![],
                identity: None,
                probe: None,
                clock: None,
                direction: None,
                split: None,
            }],
            schedule: Some(ScheduleSummary {
                requested_rate_hz,
                achieved_rate_hz: requested_rate_hz,
                lateness_p50_us: 0.0,
                lateness_p99_us: 0.0,
                lateness_max_us: 0.0,
                not_sent: 0,
            }),
            ..EchoSummary::empty("serial:/dev/x:57600", 10)
        }
    }

    #[test]
    fn the_summary_says_so_only_when_the_run_shows_it() {
        let b = crate::engine::capacity::budget(57_600, crate::frame::Version::V2, 99, 1);
        // Over capacity and losing: said.
        let mut s = run(3, 500.0, 20);
        s.apply_wire(b);
        assert_eq!(s.wire, Some(b));
        assert_eq!(s.hints.len(), 1, "{:?}", s.hints);
        assert_eq!(s.hints[0].code, HintCode::WireOverrun);
        assert!(s.hints[0]
            .text
            .ends_with("will queue and then lose: this run did"));
        // Over capacity but nothing lost: silent.
        let mut s = run(0, 500.0, 20);
        s.apply_wire(b);
        assert!(s.hints.is_empty());
        // Losing below capacity: the wire is not the reason.
        let mut s = run(3, 50.0, 20);
        s.apply_wire(b);
        assert!(s.hints.is_empty());
    }

    #[test]
    fn the_smallest_median_is_over_the_responders_that_answered() {
        let mut s = run(0, 50.0, 20);
        assert_eq!(s.smallest_p50_us().map(f64::round), Some(20_000.0));
        let mut faster = s.responders[0].clone();
        (faster.rtt.as_mut().unwrap().p50_us, faster.id) = (7_000.0, SysComp::new(2, 1));
        let mut silent = faster.clone();
        silent.rtt = None;
        s.responders.extend([faster, silent]);
        assert_eq!(s.smallest_p50_us(), Some(7_000.0));
        s.responders.clear();
        assert_eq!(s.smallest_p50_us(), None);
    }

    #[test]
    fn replies_faster_than_the_baud_allows_drop_the_budget() {
        let b = crate::engine::capacity::budget(57_600, crate::frame::Version::V2, 99, 1);
        // 8.16 ms is the floor at 57600 baud; a pty answers in 1 ms.
        let mut s = run(3, 500.0, 1);
        s.apply_wire(b);
        assert_eq!(s.wire, None);
        let codes: Vec<HintCode> = s.hints.iter().map(|h| h.code).collect();
        assert_eq!(codes, [HintCode::BaudNotInEffect]);
        assert!(
            s.hints[0].text.contains("faster than 57600 baud allows"),
            "{:?}",
            s.hints
        );
    }
}
