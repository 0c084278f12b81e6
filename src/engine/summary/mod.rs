//! The end-of-run figures, built from the matcher and the roster. Every
//! report format renders this one structure.

pub(crate) mod passive;

use std::fmt;

use serde::Serialize;

use super::capacity::WireBudget;
use super::clock_offset::ClockSummary;
use super::hint::{Hint, HintCode};
use super::link_node::LinkNodeSummary;
use super::matcher::{Counts, Matcher};
use super::radio::RadioSummary;
use super::roster::{Identity, Roster};
use super::stats::{Bucket, RttSummary};
use super::sweep_report::SweepSummary;
use crate::frame::signing::SigningSummary;
use crate::frame::{ScanStats, SysComp};
use crate::transport::RxClock;

/// Which probe a session runs, by the name reports give it (`PING` in
/// text, `"probe": "ping"` in JSON, `probe="ping"` in Prometheus labels).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum ProbeName {
    Ping,
    Timesync,
    /// PING, and TIMESYNC for responders that do not answer PING.
    Auto,
    Command,
    /// No probes: the sequence numbers of what the link carries.
    Passive,
}

impl ProbeName {
    pub(crate) fn as_str(self) -> &'static str {
        match self {
            ProbeName::Ping => "ping",
            ProbeName::Timesync => "timesync",
            ProbeName::Auto => "auto",
            ProbeName::Command => "command",
            ProbeName::Passive => "passive",
        }
    }
}

impl fmt::Display for ProbeName {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

/// Rows in the ASCII/JSON RTT distribution.
pub(crate) const HISTOGRAM_ROWS: usize = 8;

#[derive(Debug, Clone, Serialize)]
pub struct ResponderSummary {
    pub id: SysComp,
    pub counts: Counts,
    pub(crate) loss_ratio: f64,
    pub(crate) rtt: Option<RttSummary>,
    pub(crate) histogram: Vec<Bucket>,
    pub(crate) identity: Option<Identity>,
    /// The probe it was measured by (`--probe auto` only: PING or
    /// TIMESYNC, chosen per responder).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(crate) probe: Option<ProbeName>,
    /// Clock offset and drift (TIMESYNC probe only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(crate) clock: Option<ClockSummary>,
    /// Which way the losses were, when there were any: the responder's
    /// own sequence numbers give the downlink.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(crate) direction: Option<Direction>,
}

/// Round-trip loss split by direction. The downlink loss is the sequence
/// loss of every frame the responder sent us (replies, telemetry,
/// HEARTBEATs); a request survives both ways with (1 − up)(1 − down), so
/// up = 1 − (1 − round trip) / (1 − down). Its standard error is the
/// binomial errors of both ratios carried through that formula.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub(crate) struct Direction {
    pub(crate) round_trip_loss: f64,
    /// Frames of the responder's the sequence counted, and of them lost.
    pub(crate) downlink_frames: u64,
    pub(crate) downlink_lost: u64,
    pub(crate) downlink_loss: f64,
    /// `None` when every downlink frame was lost.
    pub(crate) uplink_loss: Option<f64>,
    pub(crate) uplink_stderr: Option<f64>,
    /// False when the downlink alone loses more than the round trip, by
    /// more than two standard errors: the responder's sequence does not
    /// number just what it sends us on this link (a router re-sequencing,
    /// or merging links), so the split would be wrong.
    pub(crate) consistent: bool,
}

impl Direction {
    /// The split for a responder with `round_trip` loss over `requests`,
    /// whose own frames' sequence counted `seq`: every front end's one
    /// way in (the summary at the end, Prometheus while a run goes on).
    pub(crate) fn of_sequence(
        round_trip: f64,
        requests: u64,
        seq: &passive::SeqCounts,
    ) -> Option<Self> {
        Direction::split(round_trip, requests, seq.numbered(), seq.lost)
    }

    /// The split for a responder `round_trip` of whose `requests` were
    /// lost, whose sequence counted `frames` and `lost` of them.
    pub(crate) fn split(round_trip: f64, requests: u64, frames: u64, lost: u64) -> Option<Self> {
        if requests == 0 || frames == 0 || (round_trip == 0.0 && lost == 0) {
            return None;
        }
        let down = lost as f64 / frames as f64;
        let se = |p: f64, n: u64| (p * (1.0 - p) / n as f64).sqrt();
        let (se_rt, se_down) = (se(round_trip, requests), se(down, frames));
        let kept = 1.0 - down;
        let (uplink, stderr) = if kept > 0.0 {
            let up = 1.0 - (1.0 - round_trip) / kept;
            let stderr = ((se_rt / kept).powi(2)
                + ((1.0 - round_trip) * se_down / kept.powi(2)).powi(2))
            .sqrt();
            (Some(up), Some(stderr))
        } else {
            (None, None)
        };
        let consistent = match (uplink, stderr) {
            (Some(up), Some(e)) => up >= -2.0 * e.max(1e-9),
            _ => true,
        };
        Some(Direction {
            round_trip_loss: round_trip,
            downlink_frames: frames,
            downlink_lost: lost,
            downlink_loss: down,
            uplink_loss: uplink.map(|u| u.clamp(0.0, 1.0)),
            uplink_stderr: stderr,
            consistent,
        })
    }
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

#[derive(Debug, Clone, Serialize)]
pub struct Summary {
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
    pub responders: Vec<ResponderSummary>,
    /// Replies addressed to another system.
    pub(crate) foreign_replies: u64,
    /// Replies naming a responder that answered from another link peer
    /// (spoofed ids): counted, never measured.
    pub(crate) wrong_path_replies: u64,
    /// Replies from responders beyond the tracking limit.
    pub(crate) untracked_replies: u64,
    pub(crate) frames: ScanStats,
    pub(crate) hints: Vec<Hint>,
    pub(crate) interrupted: bool,
    pub(crate) link_error: Option<String>,
    /// Seconds the link was down while reconnecting (`--reconnect`).
    pub(crate) downtime_s: f64,
    /// Send pacing figures, once a request was sent.
    pub(crate) schedule: Option<ScheduleSummary>,
    /// How receive times were taken (kernel timestamps or user space).
    pub(crate) rx_clock: RxClock,
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
    /// `--sweep` or `--load`: the steps and what they say.
    pub(crate) sweep: Option<Box<SweepSummary>>,
}

impl Summary {
    /// True when at least one responder answered in time.
    pub(crate) fn any_reply(&self) -> bool {
        self.responders.iter().any(|r| r.counts.received > 0)
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
        })
        .collect();
    out.sort_by_key(|r| r.id);
    out
}

/// The figures of a run so far (`-Q`, SIGQUIT), by the kind of run that
/// has them.
#[derive(Debug, Clone)]
pub enum Interim {
    /// An echo probe's (PING, TIMESYNC, and a sweep's steps).
    Echo(EchoInterim),
    /// A `--passive` run's.
    Passive(PassiveInterim),
}

impl Interim {}

/// An echo run so far: each responder's counts of decided requests and
/// its RTT figures.
#[derive(Debug, Clone)]
pub struct EchoInterim {
    /// Session time, ns.
    pub(crate) at: super::Nanos,
    pub(crate) requests: u64,
    pub(crate) responders: Vec<ResponderSummary>,
}

/// A passive run so far: every source's sequence figures (cumulative), as
/// the summary will give them.
#[derive(Debug, Clone)]
pub struct PassiveInterim {
    /// Session time, ns.
    pub(crate) at: super::Nanos,
    pub(crate) table: passive::TableSummary,
    /// What each source said it is, from its HEARTBEAT.
    pub(crate) identities: Vec<(SysComp, Identity)>,
}

/// `--probe command`: one target's figures.
#[derive(Debug, Clone, Serialize)]
pub(crate) struct CommandTargetSummary {
    pub(crate) id: SysComp,
    pub(crate) commands: u64,
    pub(crate) acknowledged: u64,
    pub(crate) failed: u64,
    pub(crate) skipped: u64,
    pub(crate) late_acks: u64,
    pub(crate) duplicate_acks: u64,
    /// `attempts[k - 1]`: commands acknowledged after k transmissions.
    pub(crate) attempts: Vec<u64>,
    pub(crate) time_to_ack: Option<RttSummary>,
    pub(crate) histogram: Vec<Bucket>,
    pub(crate) results: Vec<AckResult>,
    pub(crate) identity: Option<Identity>,
}

/// How many acknowledged commands got one MAV_RESULT.
#[derive(Debug, Clone, Serialize)]
pub(crate) struct AckResult {
    pub(crate) result: u8,
    pub(crate) name: String,
    pub(crate) count: u64,
}

/// The end of a `--probe command` run.
#[derive(Debug, Clone, Serialize)]
pub struct CommandSummary {
    pub(crate) link: String,
    pub(crate) ours: SysComp,
    pub(crate) command: u16,
    pub(crate) command_name: String,
    pub(crate) duration_s: f64,
    /// Commands still pending when the run ended: neither acknowledged
    /// nor failed.
    pub(crate) in_flight: u64,
    pub(crate) targets: Vec<CommandTargetSummary>,
    /// Why targets never acknowledged, from what the link heard.
    pub(crate) hints: Vec<Hint>,
    /// ACKs addressed to us for commands we never sent that system.
    pub(crate) unmatched_acks: u64,
    pub(crate) frames: ScanStats,
    pub(crate) interrupted: bool,
    pub(crate) link_error: Option<String>,
    /// What the signing gate accepted and refused, or, without a key, what
    /// came signed unchecked.
    pub(crate) signing: SigningSummary,
    /// Nodes heard by their LINK_NODE_STATUS (the vehicle's own view of
    /// the link).
    pub(crate) link_node: Vec<LinkNodeSummary>,
}

impl CommandSummary {
    pub(crate) fn any_ack(&self) -> bool {
        self.targets.iter().any(|t| t.acknowledged > 0)
    }
}

/// The end of one link's run, by probe kind.
#[derive(Debug, Clone)]
pub enum LinkSummary {
    /// PING or TIMESYNC.
    Echo(Box<Summary>),
    /// COMMAND_LONG until acknowledged.
    Command(Box<CommandSummary>),
    /// `--passive`: no probes, the sources' own sequence numbers.
    Passive(Box<passive::PassiveSummary>),
}

impl LinkSummary {
    pub(crate) fn link(&self) -> &str {
        match self {
            LinkSummary::Echo(s) => &s.link,
            LinkSummary::Command(s) => &s.link,
            LinkSummary::Passive(s) => &s.link,
        }
    }

    pub(crate) fn link_error(&self) -> Option<&str> {
        match self {
            LinkSummary::Echo(s) => s.link_error.as_deref(),
            LinkSummary::Command(s) => s.link_error.as_deref(),
            LinkSummary::Passive(s) => s.link_error.as_deref(),
        }
    }
}

#[cfg(test)]
impl Summary {
    /// A run of `requests` PINGs on `link` with nothing in it, for tests
    /// to fill in.
    pub(crate) fn empty(link: &str, requests: u64) -> Summary {
        Summary {
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
            sweep: None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::engine::matcher::Counts;
    use crate::engine::stats::RttStats;

    fn run(lost: u64, requested_rate_hz: f64, min_rtt_ms: u64) -> Summary {
        let mut rtt = RttStats::new();
        rtt.record(min_rtt_ms * 1_000_000);
        Summary {
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
            }],
            schedule: Some(ScheduleSummary {
                requested_rate_hz,
                achieved_rate_hz: requested_rate_hz,
                lateness_p50_us: 0.0,
                lateness_p99_us: 0.0,
                lateness_max_us: 0.0,
                not_sent: 0,
            }),
            ..Summary::empty("serial:/dev/x:57600", 10)
        }
    }

    #[test]
    fn the_summary_says_so_only_when_the_run_shows_it() {
        let b = super::super::capacity::budget(57_600, crate::frame::Version::V2, 99, 1);
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
    fn replies_faster_than_the_baud_allows_drop_the_budget() {
        let b = super::super::capacity::budget(57_600, crate::frame::Version::V2, 99, 1);
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

    #[test]
    fn direction_splits_the_round_trip_and_says_when_it_cannot() {
        // 10% up and 5% down: 1 - 0.9 * 0.95 = 14.5% round trip.
        let d = Direction::split(0.145, 10_000, 20_000, 1_000).unwrap();
        assert!((d.downlink_loss - 0.05).abs() < 1e-12);
        assert!((d.uplink_loss.unwrap() - 0.10).abs() < 1e-9, "{d:?}");
        let e = d.uplink_stderr.unwrap();
        assert!(e > 0.002 && e < 0.006, "{e}");
        assert!(d.consistent);
        // Nothing lost either way: nothing to split.
        assert_eq!(Direction::split(0.0, 100, 300, 0), None);
        assert_eq!(Direction::split(0.1, 0, 300, 0), None);
        // The downlink loses far more than the round trip: no split.
        let d = Direction::split(0.01, 1_000, 2_000, 400).unwrap();
        assert!(!d.consistent, "{d:?}");
        // Every frame of its lost: no uplink figure.
        let d = Direction::split(1.0, 10, 5, 5).unwrap();
        assert_eq!((d.uplink_loss, d.consistent), (None, true));
    }
}
