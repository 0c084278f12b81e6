//! `--probe command` in the session: a COMMAND_LONG due every interval,
//! re-sent until acknowledged, through the pure [`CommandTracker`].
//!
//! The mechanics differ from the echo probes (one command in flight per
//! target, retries on a fixed plan, no per-reply matching ring); the
//! clock, framing, schedule and loop are the session's.

use std::io;
use std::sync::Arc;

use crate::engine::stats::RttStats;

use super::tracker::CommandTracker;
use super::CommandEvent;
use crate::engine::diagnosis::{command_hints, Observed};
use crate::engine::hint::Hint;
use crate::engine::ignored::{ignored_by, Asked};
use crate::engine::link_io::{Clock, Sender};
use crate::engine::observe::{tell_kind, Observer, StartInfo};
use crate::engine::radio::Radios;
use crate::engine::schedule::Schedule;
use crate::engine::session::{self, Controls, Driver, Measurement, SessionEnd};
use crate::engine::summary::ProbeName;
use crate::engine::summary::{CommandSummary, CommandTargetSummary, LinkSummary};
use crate::engine::CommandSpec;
use crate::engine::Nanos;
use crate::engine::SessionConfig;
use crate::frame::{codec, Frame, Msg, SysComp};
use crate::transport::{LinkError, PathId, Transport};

/// Runs the command probe on `link` until the run ends.
pub(crate) async fn run<T: Transport>(
    cfg: &SessionConfig,
    spec: &CommandSpec,
    link: &mut T,
    observer: &mut dyn Observer,
    controls: &Controls,
) -> Measurement {
    session::run(cfg, link, CommandDriver::new(cfg, spec), observer, controls).await
}

pub(crate) struct CommandDriver {
    spec: CommandSpec,
    ours: SysComp,
    tracker: CommandTracker,
    /// Decided, not yet reported...
    events: Vec<CommandEvent>,
    /// ...of which the first `transmitted` were looked at for sending.
    transmitted: usize,
}

impl CommandDriver {
    pub(crate) fn new(cfg: &SessionConfig, spec: &CommandSpec) -> Self {
        CommandDriver {
            spec: spec.clone(),
            ours: cfg.ours,
            tracker: CommandTracker::new(spec.retry_interval.as_nanos() as Nanos, spec.retries),
            events: Vec::new(),
            transmitted: 0,
        }
    }
}

impl CommandDriver {
    /// Why targets never acknowledged, from what the link heard.
    fn hints(&self, ended: &SessionEnd<'_>, targets: &[CommandTargetSummary]) -> Vec<Hint> {
        let unacknowledged: Vec<SysComp> = targets
            .iter()
            .filter(|t| t.acknowledged == 0 && t.failed > 0)
            .map(|t| t.id)
            .collect();
        let signing = ended.gate.summary();
        let observed = Observed {
            link: &ended.cfg.link_name,
            kind: ended.kind,
            probe: ProbeName::Command,
            ours: self.ours,
            version: ended.cfg.version,
            key: signing.key,
            signing: signing.counts,
            frames: ended.frames,
            unreachable: ended.unreachable,
            roster: &ended.roster,
            responders: &[],
            radios: &[],
            requests: targets.iter().map(|t| t.commands).sum(),
            undecided: self.tracker.in_flight(),
            timeout: self.spec.retry_interval,
            no_peer_within: ended.no_peer_within,
            link_failed: ended.link_error.is_some(),
        };
        let mut hints = command_hints(&observed, &unacknowledged);
        if observed.no_peer_within.is_some() || observed.link_failed {
            return hints;
        }
        let name = codec::command_name(self.spec.command).to_uppercase();
        for t in targets.iter().filter(|t| unacknowledged.contains(&t.id)) {
            let asked = Asked {
                ours: self.ours,
                version: ended.cfg.version,
                key: signing.key,
                what: match t.commands {
                    1 => format!("the {name} command"),
                    n => format!("any of the {n} {name} commands"),
                },
                echoes: None,
            };
            hints.extend(ignored_by(&ended.roster, t.id, &asked));
        }
        hints
    }
}

impl Driver for CommandDriver {
    fn start_info(&self, cfg: &SessionConfig) -> StartInfo {
        StartInfo {
            link: cfg.link_name.clone(),
            probe: ProbeName::Command,
            ours: cfg.ours,
            interval: cfg.interval,
            timeout: self.spec.retry_interval,
            count: cfg.count,
            plan: Some(Arc::new(self.spec.clone())),
        }
    }

    async fn send_due<T: Transport>(
        &mut self,
        schedule: &mut Schedule,
        link: &mut T,
        sender: &mut Sender,
        clock: &Clock,
    ) -> Result<(), LinkError> {
        let events = &mut self.events;
        while schedule.take_due(clock.now()).is_some() {
            let (target, command) = (self.spec.target, self.spec.command);
            self.tracker
                .start(target, command, clock.now(), &mut |e| events.push(e));
        }
        self.tracker.poll(clock.now(), &mut |e| events.push(e));
        while let Some(&e) = self.events.get(self.transmitted) {
            self.transmitted += 1;
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
                    params: self.spec.params,
                };
                link.send(sender.frame(&request)).await?;
            }
        }
        Ok(())
    }

    fn expire(&mut self, _now: Nanos) {
        // Failures are decided with the re-sends, in `send_due`.
    }

    fn on_frame(&mut self, frame: &Frame, _path: PathId, at: Nanos) {
        let Msg::CommandAck {
            command,
            result,
            target_system,
            target_component,
        } = frame.msg
        else {
            return;
        };
        // Old stacks leave the targets 0: only set targets can make an
        // ACK someone else's.
        let ours = self.ours;
        if (target_system != 0 && target_system != ours.sysid)
            || (target_component != 0 && target_component != ours.compid)
        {
            return;
        }
        let events = &mut self.events;
        self.tracker
            .on_ack(frame.source, command, result, at, &mut |e| events.push(e));
    }

    fn report(&mut self, _radios: &mut Radios, observer: &mut dyn Observer) -> io::Result<()> {
        self.transmitted = 0;
        tell_kind(observer, self.events.drain(..))
    }

    fn next_deadline(&self) -> Option<Nanos> {
        self.tracker.next_deadline()
    }

    fn settled(&self) -> bool {
        self.tracker.idle()
    }

    fn requests(&self) -> Option<u64> {
        Some(self.tracker.targets().iter().map(|t| t.commands).sum())
    }

    fn finish(self, ended: SessionEnd<'_>) -> (LinkSummary, Vec<(SysComp, RttStats)>) {
        let cfg = ended.cfg;
        let targets = self.tracker.summaries(&ended.roster);
        let hints = self.hints(&ended, &targets);
        let summary = CommandSummary {
            link: cfg.link_name.clone(),
            ours: cfg.ours,
            command: self.spec.command,
            command_name: codec::command_name(self.spec.command),
            duration_s: ended.duration_s,
            in_flight: self.tracker.in_flight(),
            targets,
            hints,
            unmatched_acks: self.tracker.unmatched_acks(),
            frames: ended.frames,
            interrupted: ended.interrupted,
            link_error: ended.link_error,
            signing: ended.gate.summary(),
            answered: ended.answered,
            link_node: ended.link_nodes.summaries(),
        };
        let histograms = self
            .tracker
            .targets()
            .iter()
            .map(|t| (t.id, t.time_to_ack.clone()))
            .collect();
        (LinkSummary::new(summary), histograms)
    }
}
