//! Lines of the echo probes (PING, TIMESYNC).

use serde::Serialize;

use super::lines::{Lines, Stamp, SCHEMA_VERSION};
use super::sweep;
use super::units::{seconds, us};
use crate::engine::matcher::MatchEvent;
use crate::engine::summary::{self, Direction, ResponderSummary};
use crate::frame::SysComp;
use crate::verdict::Verdict;

/// `reply`: an answer within the timeout.
#[derive(Serialize)]
pub(super) struct Reply {
    #[serde(flatten)]
    stamp: Stamp,
    seq: u32,
    rtt_us: f64,
    out_of_order: bool,
}

/// `lost`: no answer within the timeout.
#[derive(Serialize)]
pub(super) struct Lost {
    #[serde(flatten)]
    stamp: Stamp,
    seq: u32,
    sent_t_s: f64,
}

/// The line of a reply, loss, late, duplicate or stale reply.
#[derive(Serialize)]
#[serde(untagged)]
pub(super) enum MatchLine {
    Reply(Reply),
    Lost(Lost),
    Again(Again),
    Stale(Stamp),
}

/// `late` or `duplicate`: an answer after the timeout, or another one.
#[derive(Serialize)]
pub(super) struct Again {
    #[serde(flatten)]
    stamp: Stamp,
    seq: u32,
    rtt_us: f64,
}

/// `interim`: each responder's figures so far.
#[derive(Serialize)]
pub(super) struct Interim {
    r#type: &'static str,
    t_s: f64,
    time: String,
    requests: u64,
    responders: Vec<InterimResponder>,
}

#[derive(Serialize)]
struct InterimResponder {
    responder: SysComp,
    sent: u64,
    received: u64,
    lost: u64,
    loss_ratio: f64,
    late: u64,
    duplicate: u64,
    not_charged: u64,
    in_flight: u64,
    rtt_us: Option<InterimRtt>,
}

/// The RTT figures so far, in µs.
#[derive(Serialize)]
struct InterimRtt {
    min: f64,
    mean: f64,
    max: f64,
    p50: f64,
    p90: f64,
    p99: f64,
    jitter: f64,
}

impl InterimResponder {
    fn of(r: &ResponderSummary) -> Self {
        InterimResponder {
            responder: r.id,
            sent: r.counts.sent,
            received: r.counts.received,
            lost: r.counts.lost,
            loss_ratio: r.loss_ratio,
            late: r.counts.late,
            duplicate: r.counts.duplicate,
            not_charged: r.counts.not_charged,
            in_flight: r.counts.in_flight,
            rtt_us: r.rtt.map(|s| InterimRtt {
                min: s.min_us,
                mean: s.mean_us,
                max: s.max_us,
                p50: s.p50_us,
                p90: s.p90_us,
                p99: s.p99_us,
                jitter: s.jitter_us,
            }),
        }
    }
}

impl Lines {
    /// The `interim` line.
    pub(super) fn echo_interim(&self, figures: &summary::EchoInterim) -> Interim {
        Interim {
            r#type: "interim",
            t_s: seconds(figures.at),
            time: self.wall.rfc3339(figures.at),
            requests: figures.requests,
            responders: figures
                .responders
                .iter()
                .map(InterimResponder::of)
                .collect(),
        }
    }

    /// A reply, loss, late, duplicate or stale reply.
    pub(super) fn match_line(&self, e: &MatchEvent) -> MatchLine {
        let stamp = |r#type| self.stamp(r#type, e.at(), e.responder());
        match *e {
            MatchEvent::Reply {
                seq,
                rtt,
                out_of_order,
                ..
            } => MatchLine::Reply(Reply {
                stamp: stamp("reply"),
                seq,
                rtt_us: us(rtt),
                out_of_order,
            }),
            MatchEvent::Lost { seq, sent_at, .. } => MatchLine::Lost(Lost {
                stamp: stamp("lost"),
                seq,
                sent_t_s: seconds(sent_at),
            }),
            MatchEvent::Late { seq, rtt, .. } => MatchLine::Again(Again {
                stamp: stamp("late"),
                seq,
                rtt_us: us(rtt),
            }),
            MatchEvent::Duplicate { seq, rtt, .. } => MatchLine::Again(Again {
                stamp: stamp("duplicate"),
                seq,
                rtt_us: us(rtt),
            }),
            MatchEvent::Stale { .. } => MatchLine::Stale(stamp("stale")),
        }
    }
}

/// The `summary` line: the echo run's figures as the engine serialises
/// them, between what the line adds.
#[derive(Serialize)]
pub(super) struct Summary<'a> {
    r#type: &'static str,
    schema_version: u32,
    link: &'a str,
    #[serde(flatten)]
    figures: &'a summary::EchoSummary,
    responders: Vec<Responder<'a>>,
    verdict: &'a Verdict,
    exit_code: u8,
    #[serde(skip_serializing_if = "Option::is_none")]
    sweep: Option<sweep::Summary<'a>>,
}

impl<'a> Summary<'a> {
    pub(super) fn of(s: &'a summary::EchoSummary, verdict: &'a Verdict, link: &'a str) -> Self {
        Summary {
            r#type: "summary",
            schema_version: SCHEMA_VERSION,
            link,
            figures: s,
            responders: s
                .responders
                .iter()
                .map(|r| Responder::of(r, verdict))
                .collect(),
            verdict,
            exit_code: verdict.exit_code(),
            sweep: s
                .sweep
                .as_deref()
                .map(|sweep| sweep::Summary::of(sweep, s.wire.as_ref())),
        }
    }
}

/// One responder in the summary: its figures as the engine serialises
/// them, then the verdict's messages about it and the way it lost.
#[derive(Serialize)]
struct Responder<'a> {
    #[serde(flatten)]
    figures: &'a ResponderSummary,
    failures: Vec<&'a str>,
    #[serde(skip_serializing_if = "Option::is_none")]
    direction: Option<Direction>,
}

impl<'a> Responder<'a> {
    fn of(r: &'a ResponderSummary, verdict: &'a Verdict) -> Self {
        Responder {
            figures: r,
            failures: verdict
                .failures
                .iter()
                .filter(|f| f.responder == Some(r.id))
                .map(|f| f.message.as_str())
                .collect(),
            direction: r.direction,
        }
    }
}
