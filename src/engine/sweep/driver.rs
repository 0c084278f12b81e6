//! A sweep in the session: the echo probe's own driver does the sending
//! and matching; this one wraps it, gives the session a new [`Schedule`]
//! at each step (the step's rate, the step's count), waits between steps
//! until the last one's requests are decided, runs the `--load` streams,
//! and tells the observer each step as it ends (its `StepFigures`, a
//! kind's own event).
//!
//! Steps never overlap: the next starts once every request of the last is
//! answered or timed out, so every loss is its own step's. A request that
//! timed out may still be queued on the link (a radio with a deep buffer),
//! so after a step that lost any, the next waits until no late reply has
//! come for one timeout: each rate is measured on a drained link.

use std::io;

use crate::engine::stats::RttStats;

use super::plan::Planner;
use super::step::{StepFigures, StepTally};
use super::verdict::{self, SweepEnd, SweepSummary};
use super::{PlanKind, SweepConfig};
use crate::engine::hint::HintCode;
use crate::engine::link_io::{Clock, Sender, WallAtZero};
use crate::engine::load::Load;
use crate::engine::matcher::MatchEvent;
use crate::engine::observe::{Event, Observer, StartInfo};
use crate::engine::probe::echo::EchoDriver;
use crate::engine::probe::EchoProbe;
use crate::engine::radio::{RadioReport, Radios};
use crate::engine::roster::Roster;
use crate::engine::schedule::Schedule;
use crate::engine::session::{self, Controls, Driver, Measurement, SessionEnd};
use crate::engine::summary::{EchoSummary, Interim, LinkSummary};
use crate::engine::{Nanos, SessionConfig};
use crate::frame::{Frame, ScanStats, SysComp};
use crate::transport::{LinkError, PathId, Transport};

pub(crate) struct SweepDriver<P> {
    inner: EchoDriver<P>,
    config: SweepConfig,
    planner: Planner,
    load: Load,
    /// The step sending or waiting for its replies.
    active: Option<StepTally>,
    /// Every step ended so far, in order (bounded by the planner).
    steps: Vec<StepFigures>,
    /// Steps told to the observer.
    told: usize,
    /// The first sweep step's p99: the knee test's reference.
    reference_p99: Option<f64>,
    /// No step left to run.
    finished: bool,
    /// The radio the steps follow (the first heard) and its latest
    /// rxerrors, so a step's delta starts where the last one ended.
    radio: Option<(SysComp, u16)>,
    /// Bytes sent, as of the last send (the summary needs them after the
    /// sender is gone).
    tx_bytes: u64,
    timeout: Nanos,
    /// When the active step had sent everything and nothing of it was
    /// pending any more.
    settled_at: Option<Nanos>,
    /// When the last late reply came: the link is still draining a queue.
    last_late: Option<Nanos>,
}

impl<P: EchoProbe> SweepDriver<P> {
    pub(crate) fn new(cfg: &SessionConfig, sweep: &SweepConfig, inner: EchoDriver<P>) -> Self {
        SweepDriver {
            inner,
            config: sweep.clone(),
            planner: Planner::new(sweep),
            load: Load::new(&sweep.load, cfg.version, cfg.signing.is_some()),
            active: None,
            steps: Vec::new(),
            told: 0,
            reference_p99: None,
            finished: false,
            radio: None,
            tx_bytes: 0,
            timeout: cfg.timeout.as_nanos() as Nanos,
            settled_at: None,
            last_late: None,
        }
    }

    /// Ends the active step; `complete` when it ran its course.
    fn close(&mut self, complete: bool, now: Nanos, rx_bytes: u64) {
        let Some(tally) = self.active.take() else {
            return;
        };
        let index = self.steps.len() as u32 + 1;
        let mut f = tally.figures(index, complete, now, (self.tx_bytes, rx_bytes));
        if !complete && f.requests == 0 {
            return;
        }
        if f.phase.sweeps() && complete {
            if self.reference_p99.is_none() {
                self.reference_p99 = f.rtt.map(|r| r.p99_us);
            }
            f.passed = Some(self.reference_p99.is_some_and(|r| f.passes(r)));
        }
        self.steps.push(f);
    }

    /// Starts the next step at `now` on a fresh schedule, or finishes.
    fn begin_next(&mut self, schedule: &mut Schedule, now: Nanos, rx_bytes: u64) {
        match self.planner.next(&self.steps) {
            Some(plan) => {
                *schedule = Schedule::new(now, plan.interval_ns(), Some(plan.count));
                if plan.load {
                    self.load.start(now);
                } else {
                    self.load.stop();
                }
                self.active = Some(StepTally::new(
                    plan,
                    now,
                    (self.tx_bytes, rx_bytes),
                    self.radio,
                ));
                self.settled_at = None;
            }
            None => {
                self.finished = true;
                self.load.stop();
                schedule.stop();
            }
        }
    }

    /// When the next step may begin: once the active one's time is up,
    /// it has sent everything, nothing of it is pending, and (after a
    /// loss) the link has been quiet of late replies for a timeout.
    fn next_step_at(&self) -> Option<Nanos> {
        let step = self.active.as_ref()?;
        let settled = self.settled_at?.max(step.nominal_end());
        if !step.lost_any() {
            return Some(settled);
        }
        Some(settled.max(self.last_late.unwrap_or(0) + self.timeout))
    }

    fn summary(&self, ending: SweepEnd) -> SweepSummary {
        SweepSummary {
            kind: match self.config.plan {
                PlanKind::Sweep { .. } => "sweep",
                PlanKind::Load { .. } => "load",
            },
            steps: self.steps.clone(),
            reference_p99_us: verdict::reference_p99(&self.steps),
            knee: verdict::knee(&self.steps),
            queueing: verdict::queueing(&self.steps),
            load: self.load.summary(),
            load_effect: verdict::load_effect(&self.steps),
            ending,
        }
    }
}

/// Forwards the echo driver's events to the observer, counting each into
/// the step its request was sent in.
struct Tap<'a> {
    observer: &'a mut dyn Observer,
    step: Option<&'a mut StepTally>,
    last_late: &'a mut Option<Nanos>,
}

impl Observer for Tap<'_> {
    fn start(&mut self, info: &StartInfo) -> io::Result<()> {
        self.observer.start(info)
    }

    fn event(&mut self, event: &Event<'_>) -> io::Result<()> {
        if let Some(MatchEvent::Late { at, .. }) = event.kind::<MatchEvent>() {
            *self.last_late = Some(*at);
        }
        if let (Some(e), Some(step)) = (event.kind::<MatchEvent>(), self.step.as_deref_mut()) {
            let sent_at = match *e {
                MatchEvent::Reply { sent_at, .. }
                | MatchEvent::Lost { sent_at, .. }
                | MatchEvent::Late { sent_at, .. }
                | MatchEvent::Duplicate { sent_at, .. } => Some(sent_at),
                MatchEvent::Stale { .. } => None,
            };
            // A late reply to an earlier step's request is in the run's
            // totals; that step's row is already out.
            if sent_at.is_some_and(|t| step.owns(t)) {
                step.on_event(e);
            }
        }
        self.observer.event(event)
    }

    fn flush(&mut self) -> io::Result<()> {
        self.observer.flush()
    }

    fn interim(&mut self, figures: &Interim) -> io::Result<()> {
        self.observer.interim(figures)
    }
}

impl<P: EchoProbe> Driver for SweepDriver<P> {
    fn start_info(&self, cfg: &SessionConfig) -> StartInfo {
        self.inner.start_info(cfg)
    }

    fn begin(&mut self, wall_at_zero: WallAtZero) {
        self.inner.begin(wall_at_zero);
    }

    async fn send_due<T: Transport>(
        &mut self,
        schedule: &mut Schedule,
        link: &mut T,
        sender: &mut Sender,
        clock: &Clock,
    ) -> Result<(), LinkError> {
        let now = clock.now();
        let next_due = self.active.is_none() || self.next_step_at().is_some_and(|at| at <= now);
        if !self.finished && next_due {
            let rx = link.scan_stats().frame_bytes;
            self.tx_bytes = sender.bytes();
            self.close(true, now, rx);
            self.begin_next(schedule, now, rx);
        }
        if let Some(step) = self.active.as_mut() {
            let before = schedule.issued();
            self.inner.send_due(schedule, link, sender, clock).await?;
            let now = clock.now();
            step.sent(schedule.issued() - before, now);
            self.tx_bytes = sender.bytes();
            if schedule.finished() && !step.sending_finished() {
                step.sending_done(now, self.tx_bytes);
            }
        }
        if !self.load.is_empty() {
            self.load.send_due(link, sender, clock).await?;
            self.tx_bytes = sender.bytes();
        }
        Ok(())
    }

    fn expire(&mut self, now: Nanos) {
        self.inner.expire(now);
        let sent_all = self
            .active
            .as_ref()
            .is_some_and(StepTally::sending_finished);
        if sent_all && self.settled_at.is_none() && self.inner.settled() {
            self.settled_at = Some(now);
        }
    }

    fn on_frame(&mut self, frame: &Frame, path: PathId, at: Nanos) {
        self.inner.on_frame(frame, path, at);
    }

    fn on_radio(&mut self, id: SysComp, report: &RadioReport, _at: Nanos) {
        if self.radio.is_none_or(|(followed, _)| followed == id) {
            self.radio = Some((id, report.rxerrors));
        }
        if let Some(step) = self.active.as_mut() {
            step.on_radio(id, report);
        }
    }

    fn report(&mut self, radios: &mut Radios, observer: &mut dyn Observer) -> io::Result<()> {
        let mut tap = Tap {
            observer: &mut *observer,
            step: self.active.as_mut(),
            last_late: &mut self.last_late,
        };
        let matched = self.inner.report(radios, &mut tap);
        let mut told = Ok(());
        for step in &self.steps[self.told..] {
            if told.is_ok() {
                told = observer.event(&Event::Kind(step));
            }
        }
        self.told = self.steps.len();
        matched.and(told)
    }

    fn next_deadline(&self) -> Option<Nanos> {
        let next_step = self.next_step_at().filter(|_| !self.finished);
        [self.inner.next_deadline(), self.load.next_due(), next_step]
            .into_iter()
            .flatten()
            .min()
    }

    fn settled(&self) -> bool {
        self.finished && self.inner.settled()
    }

    /// A step cut short by the run's end is closed here, before the
    /// session's last report, so it is told as a `step` like the others.
    fn stopping(&mut self, now: Nanos, frames: &ScanStats) {
        self.close(false, now, frames.frame_bytes);
    }

    fn requests(&self) -> Option<u64> {
        self.inner.requests()
    }

    fn finish(mut self, ended: SessionEnd<'_>) -> (LinkSummary, Vec<(SysComp, RttStats)>) {
        let now = (ended.duration_s * 1e9) as Nanos;
        self.close(false, now, ended.frames.frame_bytes);
        let loss_limit = match self.config.plan {
            PlanKind::Sweep { loss_limit, .. } => loss_limit,
            PlanKind::Load { .. } => f64::INFINITY,
        };
        let ending = if ended.interrupted {
            SweepEnd::Interrupted
        } else if ended.link_error.is_some() {
            SweepEnd::LinkFailed
        } else if !self.finished {
            SweepEnd::Deadline
        } else if self
            .steps
            .iter()
            .any(|s| s.phase.sweeps() && s.received == 0)
        {
            SweepEnd::NoReplies
        } else if self
            .steps
            .iter()
            .any(|s| s.phase.sweeps() && s.loss_ratio > loss_limit)
        {
            SweepEnd::LossLimit
        } else {
            SweepEnd::Planned
        };
        let sweep = self.summary(ending);
        let self_plan = self.config.plan;
        let (mut summary, histograms) = self.inner.finish(ended);
        if let Some(s) = summary.get_mut::<EchoSummary>() {
            // The rate changed at every step: the steps' own achieved
            // rates say how well they kept to it.
            s.schedule = None;
            // A sweep overloads the radio on purpose; the knee says where.
            if matches!(self_plan, PlanKind::Sweep { .. }) {
                s.hints.retain(|h| h.code != HintCode::RadioOverloaded);
            }
            s.sweep = Some(Box::new(sweep));
        }
        (summary, histograms)
    }

    fn interim(&self, roster: &Roster, at: Nanos) -> Option<Interim> {
        self.inner.interim(roster, at)
    }
}

/// Runs an echo probe in steps on `link` until the steps or the run end.
pub(crate) async fn run<T: Transport, P: EchoProbe>(
    cfg: &SessionConfig,
    sweep: &SweepConfig,
    link: &mut T,
    probe: P,
    observer: &mut dyn Observer,
    controls: &Controls,
) -> Measurement {
    let driver = SweepDriver::new(cfg, sweep, EchoDriver::new(cfg, probe));
    session::run(cfg, link, driver, observer, controls).await
}
