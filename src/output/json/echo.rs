//! JSON objects of the echo probes (PING, TIMESYNC).

use std::io::Write;

use serde_json::{json, Value};

use super::{us, JsonReporter, SCHEMA_VERSION};
use crate::engine::matcher::MatchEvent;
use crate::engine::summary::{Interim, ResponderSummary, Summary};
use crate::output::Event;
use crate::verdict::Verdict;

impl<W: Write> JsonReporter<W> {
    /// The `interim` object: each responder's figures so far.
    pub(super) fn interim_object(&self, figures: &Interim) -> Value {
        json!({
            "type": "interim",
            "t_s": figures.at as f64 / 1e9,
            "time": self.wall.rfc3339(figures.at),
            "requests": figures.requests,
            "responders": figures
                .responders
                .iter()
                .map(|r| json!({
                    "responder": r.id,
                    "sent": r.counts.sent,
                    "received": r.counts.received,
                    "lost": r.counts.lost,
                    "loss_ratio": r.loss_ratio,
                    "late": r.counts.late,
                    "duplicate": r.counts.duplicate,
                    "not_charged": r.counts.not_charged,
                    "in_flight": r.counts.in_flight,
                    "rtt_us": r.rtt.map(|s| json!({
                        "min": s.min_us, "mean": s.mean_us, "max": s.max_us,
                        "p50": s.p50_us, "p90": s.p90_us, "p99": s.p99_us, "jitter": s.jitter_us,
                    })),
                }))
                .collect::<Vec<_>>(),
        })
    }

    /// The object of an echo run's event, if it has one.
    pub(super) fn echo_event(&self, event: &Event<'_>) -> Option<Value> {
        let value = match *event {
            Event::Match(MatchEvent::Reply {
                responder,
                seq,
                rtt,
                at,
                out_of_order,
                ..
            }) => {
                let mut m = self.stamped("reply", at, responder);
                m.insert("seq".into(), seq.into());
                m.insert("rtt_us".into(), us(rtt).into());
                m.insert("out_of_order".into(), out_of_order.into());
                Value::Object(m)
            }
            Event::Match(MatchEvent::Lost {
                responder,
                seq,
                sent_at,
                at,
            }) => {
                let mut m = self.stamped("lost", at, responder);
                m.insert("seq".into(), seq.into());
                m.insert("sent_t_s".into(), json!(sent_at as f64 / 1e9));
                Value::Object(m)
            }
            Event::Match(MatchEvent::Late {
                responder,
                seq,
                rtt,
                at,
                ..
            }) => {
                let mut m = self.stamped("late", at, responder);
                m.insert("seq".into(), seq.into());
                m.insert("rtt_us".into(), us(rtt).into());
                Value::Object(m)
            }
            Event::Match(MatchEvent::Duplicate {
                responder,
                seq,
                rtt,
                at,
                ..
            }) => {
                let mut m = self.stamped("duplicate", at, responder);
                m.insert("seq".into(), seq.into());
                m.insert("rtt_us".into(), us(rtt).into());
                Value::Object(m)
            }
            Event::Match(MatchEvent::Stale { responder, at }) => {
                Value::Object(self.stamped("stale", at, responder))
            }
            Event::Heard { id, identity } => {
                let mut m = self.stamped("responder", identity.first_heard, id);
                m.insert("mav_type".into(), identity.mav_type.into());
                m.insert("autopilot".into(), identity.autopilot.into());
                m.insert("vehicle".into(), identity.vehicle.clone().into());
                m.insert(
                    "autopilot_name".into(),
                    identity.autopilot_name.clone().into(),
                );
                Value::Object(m)
            }
            Event::WaitingForPeer => json!({"type": "waiting", "reason": "no peer heard yet"}),
            Event::Step(step) => self.step_object(step),
            // The summary has each clock and the link's error; a stream
            // of estimates is for the exporters.
            Event::Command(_) | Event::Clock { .. } | Event::LinkFailed { .. } => return None,
            // The first report of each radio; the summary has the rest.
            Event::Radio {
                id,
                at,
                report,
                first,
            } => {
                if !first {
                    return None;
                }
                let mut m = self.stamped("radio", at, id);
                m.insert("status".into(), json!(report));
                Value::Object(m)
            }
        };
        Some(value)
    }
}

fn responder_json(r: &ResponderSummary, verdict: &Verdict) -> Value {
    let failures: Vec<&str> = verdict
        .failures
        .iter()
        .filter(|f| f.responder == Some(r.id))
        .map(|f| f.message.as_str())
        .collect();
    json!({
        "responder": r.id,
        "identity": r.identity.as_ref().map(|i| json!({
            "mav_type": i.mav_type,
            "autopilot": i.autopilot,
            "vehicle": i.vehicle,
            "autopilot_name": i.autopilot_name,
        })),
        "sent": r.counts.sent,
        "received": r.counts.received,
        "lost": r.counts.lost,
        "loss_ratio": r.loss_ratio,
        "late": r.counts.late,
        "duplicate": r.counts.duplicate,
        "out_of_order": r.counts.out_of_order,
        "stale": r.counts.stale,
        "not_charged": r.counts.not_charged,
        "in_flight": r.counts.in_flight,
        "rtt_us": r.rtt.map(|s| json!({
            "min": s.min_us,
            "mean": s.mean_us,
            "max": s.max_us,
            "stddev": s.stddev_us,
            "p50": s.p50_us,
            "p90": s.p90_us,
            "p99": s.p99_us,
            "p99_9": s.p999_us,
            "jitter": s.jitter_us,
        })),
        "histogram": r.histogram,
        "clock": r.clock.map(|c| json!({
            "offset_ns": ns(c.offset_ns),
            "uncertainty_ns": c.uncertainty_ns,
            "lower_ns": c.bounds_ns.map(|(lower, _)| ns(lower)),
            "upper_ns": c.bounds_ns.map(|(_, upper)| ns(upper)),
            "bounds_drift_limit_ppm": c.bounds_drift_limit_ppm,
            "spread_ns": c.spread_ns,
            "drift_ppm": c.drift_ppm,
            "drift_stderr_ppm": c.drift_stderr_ppm,
            "samples": c.samples,
        })),
        "failures": failures,
    })
}

/// i64 holds ±292 years of ns: enough for any two clocks.
fn ns(v: i128) -> i64 {
    i64::try_from(v).unwrap_or(if v < 0 { i64::MIN } else { i64::MAX })
}

/// The `summary` object.
pub(super) fn summary(s: &Summary, verdict: &Verdict) -> Value {
    let mut v = json!({
        "type": "summary",
        "schema_version": SCHEMA_VERSION,
        "link": s.link,
        "probe": s.probe,
        "ours": s.ours,
        "duration_s": s.duration_s,
        "requests": s.requests,
        "in_flight": s.in_flight,
        "no_peer_heard_s": s.no_peer_heard_s,
        "interrupted": s.interrupted,
        "link_error": s.link_error,
        "downtime_s": s.downtime_s,
        "schedule": s.schedule,
        "rx_clock": s.rx_clock,
        "frames": s.frames,
        "foreign_replies": s.foreign_replies,
        "wrong_path_replies": s.wrong_path_replies,
        "untracked_replies": s.untracked_replies,
        "hints": s.hints,
        "radios": s.radios,
        "wire": s.wire,
        "signing": s.signing,
        "responders": s.responders.iter().map(|r| responder_json(r, verdict)).collect::<Vec<_>>(),
        "verdict": verdict,
        "exit_code": verdict.exit_code,
    });
    if let Some(sweep) = &s.sweep {
        v["sweep"] = super::sweep::summary(sweep, s.wire.as_ref());
    }
    v
}
