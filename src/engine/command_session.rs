//! A `--probe command` run: a COMMAND_LONG due every interval, re-sent
//! until acknowledged, through the pure [`CommandTracker`].
//!
//! Its own loop because the mechanics differ from the echo probes: one
//! command in flight per target, retries on a fixed plan, no per-reply
//! matching ring. The clock, framing and schedule are the echo session's.

use std::io;
use std::sync::Arc;

use tokio::sync::Notify;
use tokio::time::Instant;

use super::commands::{CommandEvent, CommandTracker};
use super::roster::Roster;
use super::schedule::Schedule;
use super::session::{admitted, heartbeat_if_due, Clock, Sender, SessionConfig};
use super::summary::{command_target_summaries, CommandSummary};
use super::Nanos;
use crate::config::CommandSpec;
use crate::frame::signing::Gate;
use crate::frame::{codec, Msg};
use crate::output::{CommandReporter, StartInfo};
use crate::transport::{Inbound, LinkError, Transport};
use crate::verdict::exit;

pub struct CommandOutcome {
    pub summary: CommandSummary,
    pub output_closed: bool,
}

impl CommandOutcome {
    /// As for PING: 0 when something was acknowledged, 1 when nothing was.
    pub fn exit_code(&self) -> u8 {
        if self.summary.link_error.is_some() {
            exit::ERROR
        } else if self.output_closed || self.summary.any_ack() {
            exit::OK
        } else {
            exit::FAILED
        }
    }
}

/// Runs the command probe until it ends, then reports the summary.
pub async fn run<T: Transport>(
    cfg: &SessionConfig,
    spec: &CommandSpec,
    link: &mut T,
    report: &mut dyn CommandReporter,
    stop: Arc<Notify>,
) -> CommandOutcome {
    let clock = Clock {
        epoch: Instant::now(),
    };
    let mut tracker = CommandTracker::new(spec.retry_interval.as_nanos() as Nanos, spec.retries);
    let mut roster = Roster::default();
    let mut sender = Sender::new(cfg);
    let mut gate = cfg.signing.map(Gate::new);
    let mut schedule: Option<Schedule> = None;
    let mut next_heartbeat: Option<Nanos> = cfg.heartbeat.then_some(0);
    let deadline_ns = cfg.deadline.map(|d| d.as_nanos() as Nanos);
    let mut events: Vec<CommandEvent> = Vec::new();
    let mut inbound: Vec<Inbound> = Vec::new();
    let mut interrupted = false;
    let mut link_error: Option<LinkError> = None;
    let mut output: io::Result<()> = report.command_start(
        &StartInfo {
            link: cfg.link_name.clone(),
            probe: "command",
            ours: cfg.ours,
            interval: cfg.interval,
            timeout: spec.retry_interval,
            count: cfg.count,
        },
        spec,
    );

    'run: while output.is_ok() {
        let now = clock.now();
        if deadline_ns.is_some_and(|d| now >= d) {
            break;
        }
        if let Err(e) = heartbeat_if_due(link, &mut sender, &mut next_heartbeat, now).await {
            link_error = Some(e);
            break;
        }
        if schedule.is_none() && link.has_peers() {
            let interval = cfg.interval.as_nanos() as Nanos;
            schedule = Some(Schedule::new(now, interval, cfg.count));
        }
        if let Some(s) = schedule.as_mut() {
            while s.take_due(clock.now()).is_some() {
                tracker.start(spec.target, spec.command, clock.now(), &mut |e| {
                    events.push(e)
                });
            }
        }
        tracker.poll(clock.now(), &mut |e| events.push(e));
        for e in events.drain(..) {
            if let CommandEvent::Send {
                target,
                command,
                attempt,
                ..
            } = e
            {
                let request = Msg::CommandLong {
                    command,
                    // Tells the target this is a re-send (MAVLink's rule).
                    confirmation: (attempt - 1).min(255) as u8,
                    target_system: target.sysid,
                    target_component: target.compid,
                    params: spec.params,
                };
                if let Err(e) = link.send(sender.frame(&request)).await {
                    link_error = Some(e);
                    break 'run;
                }
            }
            output = output.and(report.command_event(&e));
        }
        if output.is_err() {
            break;
        }
        if schedule.as_ref().is_some_and(|s| s.finished()) && tracker.idle() {
            break;
        }

        let wake = [
            schedule.as_ref().and_then(|s| s.next_due()),
            tracker.next_deadline(),
            next_heartbeat,
            deadline_ns,
        ]
        .into_iter()
        .flatten()
        .min();
        let sleep = clock.sleep_until(wake);
        tokio::select! {
            biased;
            _ = stop.notified() => {
                interrupted = true;
                break;
            }
            received = link.recv(&mut inbound) => {
                if let Err(e) = received {
                    link_error = Some(e);
                    break;
                }
                for Inbound { frame, at, signature, .. } in inbound.drain(..) {
                    if !admitted(&mut gate, &frame, signature.as_ref()) {
                        continue;
                    }
                    let at = clock.ns(at);
                    match frame.msg {
                        Msg::Heartbeat { mav_type, autopilot } => {
                            roster.heard(frame.source, mav_type, autopilot, at);
                        }
                        Msg::CommandAck { command, result, target_system, target_component } => {
                            // Old stacks leave the targets 0: only set
                            // targets can make an ACK someone else's.
                            let ours = cfg.ours;
                            if (target_system != 0 && target_system != ours.sysid)
                                || (target_component != 0 && target_component != ours.compid)
                            {
                                continue;
                            }
                            tracker.on_ack(frame.source, command, result, at, &mut |e| events.push(e));
                        }
                        _ => {}
                    }
                }
                // Reported (and any re-send due before the ACK put on the
                // wire) at the top of the loop.
            }
            _ = sleep => {}
        }
    }

    let summary = CommandSummary {
        link: cfg.link_name.clone(),
        ours: cfg.ours,
        command: spec.command,
        command_name: codec::command_name(spec.command),
        duration_s: clock.now() as f64 / 1e9,
        in_flight: tracker.in_flight(),
        targets: command_target_summaries(&tracker, &roster),
        unmatched_acks: tracker.unmatched_acks(),
        frames: link.scan_stats(),
        interrupted,
        link_error: link_error.map(|e| e.to_string()),
        signing: gate.as_ref().map(Gate::summary),
    };
    if output.is_ok() {
        output = report.command_summary(&summary);
    }
    CommandOutcome {
        summary,
        output_closed: output.is_err(),
    }
}
