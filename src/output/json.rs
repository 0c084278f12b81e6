//! `--json`: newline-delimited JSON, one object per event. The schema is
//! `schema/mavping-events.schema.json`; bump [`SCHEMA_VERSION`] on any
//! change that could break a consumer.

use std::io::{self, Write};

use serde_json::{json, Value};

use super::{Event, Reporter, StartInfo, WallClock};
use crate::engine::matcher::MatchEvent;
use crate::engine::summary::{ResponderSummary, Summary};
use crate::engine::Nanos;
use crate::frame::SysComp;
use crate::verdict::Verdict;

pub const SCHEMA_VERSION: u32 = 1;

pub struct JsonReporter<W: Write> {
    out: W,
    /// Only the summary object (`--json -q`).
    quiet: bool,
    wall: WallClock,
    /// With several links, every object names its link.
    link: Option<String>,
}

impl<W: Write> JsonReporter<W> {
    pub fn new(out: W, quiet: bool, wall: WallClock) -> Self {
        JsonReporter {
            out,
            quiet,
            wall,
            link: None,
        }
    }

    /// Adds `"link": LINK` to every event (the start and summary objects
    /// always carry it), for runs over several links.
    pub fn with_link(mut self, link: String) -> Self {
        self.link = Some(link);
        self
    }

    fn emit(&mut self, mut value: Value) -> io::Result<()> {
        if let (Some(link), Value::Object(m)) = (&self.link, &mut value) {
            m.insert("link".into(), link.clone().into());
        }
        serde_json::to_writer(&mut self.out, &value)?;
        self.out.write_all(b"\n")
    }

    /// The `start` event: what the run is about to do.
    fn start_object(&self, info: &StartInfo) -> serde_json::Map<String, Value> {
        let Value::Object(m) = json!({
            "type": "start",
            "schema_version": SCHEMA_VERSION,
            "mavping_version": env!("CARGO_PKG_VERSION"),
            "time": self.wall.rfc3339(0),
            "link": info.link,
            "probe": info.probe,
            "ours": info.ours,
            "interval_s": info.interval.as_secs_f64(),
            "rate_hz": 1.0 / info.interval.as_secs_f64(),
            "timeout_s": info.timeout.as_secs_f64(),
            "count": info.count,
        }) else {
            unreachable!("json! of an object literal is an object")
        };
        m
    }

    /// Fields every timed event carries: session seconds and wall time.
    fn stamped(&self, kind: &str, t: Nanos, responder: SysComp) -> serde_json::Map<String, Value> {
        let mut m = serde_json::Map::new();
        m.insert("type".into(), kind.into());
        m.insert("t_s".into(), json!(t as f64 / 1e9));
        m.insert("time".into(), self.wall.rfc3339(t).into());
        m.insert("responder".into(), json!(responder));
        m
    }
}

fn us(ns: Nanos) -> f64 {
    ns as f64 / 1e3
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
            // i64 holds ±292 years of ns: enough for any two clocks.
            "offset_ns": i64::try_from(c.offset_ns).unwrap_or(if c.offset_ns < 0 { i64::MIN } else { i64::MAX }),
            "uncertainty_ns": c.uncertainty_ns,
            "spread_ns": c.spread_ns,
            "drift_ppm": c.drift_ppm,
            "drift_stderr_ppm": c.drift_stderr_ppm,
            "samples": c.samples,
        })),
        "failures": failures,
    })
}

impl<W: Write> Reporter for JsonReporter<W> {
    fn flush(&mut self) -> io::Result<()> {
        self.out.flush()
    }

    fn start(&mut self, info: &StartInfo) -> io::Result<()> {
        if self.quiet {
            return Ok(());
        }
        let value = Value::Object(self.start_object(info));
        self.emit(value)
    }

    fn event(&mut self, event: &Event<'_>) -> io::Result<()> {
        if self.quiet {
            return Ok(());
        }
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
            // The first report of each radio; the summary has the rest.
            Event::Radio {
                id,
                at,
                report,
                first,
            } => {
                if !first {
                    return Ok(());
                }
                let mut m = self.stamped("radio", at, id);
                m.insert("status".into(), json!(report));
                Value::Object(m)
            }
        };
        self.emit(value)
    }

    fn summary(&mut self, s: &Summary, verdict: &Verdict) -> io::Result<()> {
        let value = json!({
            "type": "summary",
            "schema_version": SCHEMA_VERSION,
            "link": s.link,
            "probe": s.probe,
            "ours": s.ours,
            "duration_s": s.duration_s,
            "requests": s.requests,
            "in_flight": s.in_flight,
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
        self.emit(value)?;
        self.out.flush()
    }
}

impl<W: Write> super::CommandReporter for JsonReporter<W> {
    fn command_start(
        &mut self,
        info: &StartInfo,
        spec: &crate::config::CommandSpec,
    ) -> io::Result<()> {
        if self.quiet {
            return Ok(());
        }
        let mut value = self.start_object(info);
        value.insert(
            "command".into(),
            json!({
                "id": spec.command,
                "name": crate::frame::codec::command_name(spec.command),
                "target": spec.target,
                "params": spec.params,
                "retry_interval_s": spec.retry_interval.as_secs_f64(),
                "retries": spec.retries,
            }),
        );
        self.emit(Value::Object(value))
    }

    fn command_event(&mut self, event: &crate::engine::commands::CommandEvent) -> io::Result<()> {
        use crate::engine::commands::CommandEvent as E;
        if self.quiet {
            return Ok(());
        }
        let value = match *event {
            // Each transmission is in the summary's attempt counts.
            E::Send { .. } => return Ok(()),
            E::Acked {
                n,
                target,
                from,
                command,
                result,
                attempts,
                time_to_ack,
            } => json!({
                "type": "ack", "n": n, "target": target, "from": from, "command": command,
                "result": result, "result_name": crate::frame::codec::result_name(result),
                "attempts": attempts, "time_to_ack_us": us(time_to_ack),
            }),
            E::Failed {
                n,
                target,
                command,
                attempts,
            } => json!({
                "type": "command_failed", "n": n, "target": target, "command": command,
                "attempts": attempts,
            }),
            E::Skipped {
                target,
                command,
                at,
                ..
            } => json!({
                "type": "skipped", "t_s": at as f64 / 1e9, "target": target, "command": command,
            }),
            E::LateAck {
                from,
                command,
                result,
            } => json!({"type": "late_ack", "from": from, "command": command, "result": result}),
            E::DuplicateAck {
                from,
                command,
                result,
            } => {
                json!({"type": "duplicate_ack", "from": from, "command": command, "result": result})
            }
        };
        self.emit(value)
    }

    fn command_summary(
        &mut self,
        summary: &crate::engine::summary::CommandSummary,
    ) -> io::Result<()> {
        let mut value = serde_json::to_value(summary)?;
        if let Value::Object(m) = &mut value {
            m.insert("type".into(), "command_summary".into());
            m.insert("schema_version".into(), SCHEMA_VERSION.into());
            let exit_code = if summary.link_error.is_some() {
                crate::verdict::exit::ERROR
            } else if summary.any_ack() {
                crate::verdict::exit::OK
            } else {
                crate::verdict::exit::FAILED
            };
            m.insert("exit_code".into(), exit_code.into());
        }
        self.emit(value)?;
        self.out.flush()
    }
}
