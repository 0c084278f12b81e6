//! A transfer probe in the session: downloads one after another (`-c`),
//! each a [`Protocol`] fed the target's transfer frames, with echo probes
//! beside them at the run's interval (`--probe auto`'s: PING, and
//! TIMESYNC to a target that does not answer PING, as ArduPilot; MAVSDK
//! answers PING and not TIMESYNC), the echo probe's own driver wrapped as
//! the sweep wraps it, so the round trip is measured under the downlink a
//! download makes. A download begins
//! one timeout after the last ended, so its stragglers are not the next
//! one's first pass.

use std::io;
use std::sync::Arc;

use serde::Serialize;

use super::attempt::{figures_of, AttemptFigures, Ending, Protocol};
use super::ftp::FtpDownload;
use super::mission::MissionDownload;
use super::params::ParamsDownload;
use super::spec::{TransferKind, TransferSpec};
use super::summary::{LatencyBeside, Tally, TransferSummary};
use crate::engine::capacity;
use crate::engine::hint::{Hint, HintCode};
use crate::engine::ignored::{ignored_by, Asked};
use crate::engine::link_io::{Clock, Sender, WallAtZero};
use crate::engine::observe::{tell_kind, Observer, StartInfo};
use crate::engine::probe::auto::AutoProbe;
use crate::engine::probe::echo::EchoDriver;
use crate::engine::radio::Radios;
use crate::engine::schedule::Schedule;
use crate::engine::session::{self, Controls, Driver, Measurement, SessionEnd};
use crate::engine::stats::RttStats;
use crate::engine::summary::{EchoSummary, LinkSummary};
use crate::engine::{Nanos, SessionConfig};
use crate::frame::{Frame, Msg, ScanStats, SysComp, Transfer};
use crate::transport::{LinkError, PathId, Transport};

/// A download's progress is told at most this often (the plot's curve).
const PROGRESS_EVERY_NS: Nanos = 250_000_000;

/// How far a download has got: the `transfer_progress` JSON line.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(tag = "type", rename = "transfer_progress")]
pub(crate) struct TransferProgress {
    pub(crate) attempt: u32,
    /// Since the download began.
    pub(crate) elapsed_ms: f64,
    pub(crate) received: u64,
    pub(crate) total: Option<u64>,
}

impl crate::engine::kind::KindValue for TransferProgress {
    fn serialized(&self) -> Option<&dyn erased_serde::Serialize> {
        Some(self)
    }
}

/// Runs the transfer probe on `link` until the run ends.
pub(crate) async fn run<T: Transport>(
    cfg: &SessionConfig,
    spec: &TransferSpec,
    link: &mut T,
    beside: AutoProbe,
    observer: &mut dyn Observer,
    controls: &Controls,
) -> Measurement {
    let beside = EchoDriver::new(cfg, beside);
    let driver = TransferDriver::new(cfg, spec, beside);
    session::run(cfg, link, driver, observer, controls).await
}

/// The download under way.
#[derive(Debug)]
struct Running {
    protocol: Box<dyn Protocol>,
    attempt: u32,
    started: Nanos,
    told_at: Nanos,
}

pub(crate) struct TransferDriver {
    spec: TransferSpec,
    beside: EchoDriver<AutoProbe>,
    interval: Nanos,
    timeout: Nanos,
    /// The link's baud rate, where it has one.
    baud: Option<u32>,
    /// Downloads to make (`-c`); none: until the run ends.
    wanted: Option<u64>,
    running: Option<Running>,
    next_start: Option<Nanos>,
    began: bool,
    finished: bool,
    /// Transfer requests to put on the wire.
    out: Vec<Transfer>,
    ended: Vec<AttemptFigures>,
    progress: Vec<TransferProgress>,
    tally: Tally,
}

impl TransferDriver {
    pub(crate) fn new(
        cfg: &SessionConfig,
        spec: &TransferSpec,
        beside: EchoDriver<AutoProbe>,
    ) -> Self {
        TransferDriver {
            spec: spec.clone(),
            beside,
            interval: cfg.interval.as_nanos() as Nanos,
            timeout: spec.timeout.as_nanos() as Nanos,
            baud: cfg.wire.map(|w| w.baud),
            wanted: cfg.count,
            running: None,
            next_start: None,
            began: false,
            finished: false,
            out: Vec::new(),
            ended: Vec::new(),
            progress: Vec::new(),
            tally: Tally::default(),
        }
    }

    fn protocol(&self, now: Nanos) -> Box<dyn Protocol> {
        let s = &self.spec;
        let timeout = self.timeout;
        match &s.kind {
            TransferKind::Params => Box::new(ParamsDownload::new(
                s.target, timeout, s.retries, s.window, now,
            )),
            TransferKind::Mission => {
                Box::new(MissionDownload::new(s.target, timeout, s.retries, now))
            }
            TransferKind::Ftp { path } => Box::new(FtpDownload::new(
                s.target, path, timeout, s.retries, s.window, now,
            )),
        }
    }

    /// Starts the next download when one is due, moves the running one
    /// on, and ends it when it has ended.
    fn step(&mut self, now: Nanos) {
        if self.running.is_none() && !self.finished && self.next_start.is_some_and(|t| now >= t) {
            let attempt = self.tally.attempts + 1;
            // Its line starts at 0.
            self.progress.push(TransferProgress {
                attempt,
                elapsed_ms: 0.0,
                received: 0,
                total: None,
            });
            self.running = Some(Running {
                protocol: self.protocol(now),
                attempt,
                started: now,
                told_at: now,
            });
            self.next_start = None;
        }
        if let Some(run) = self.running.as_mut() {
            run.protocol.poll(now, &mut self.out);
        }
        self.after(now);
    }

    /// Tells progress when due, and ends a download that has ended.
    fn after(&mut self, now: Nanos) {
        let Some(run) = self.running.as_mut() else {
            return;
        };
        let ended = run.protocol.ending().is_some();
        if ended || now >= run.told_at + PROGRESS_EVERY_NS {
            run.told_at = now;
            let p = run.protocol.progress();
            self.progress.push(TransferProgress {
                attempt: run.attempt,
                elapsed_ms: now.saturating_sub(run.started) as f64 / 1e6,
                received: p.done(),
                total: p.total_known(),
            });
        }
        if ended {
            self.end_download(now);
        }
    }

    fn end_download(&mut self, now: Nanos) {
        let Some(mut run) = self.running.take() else {
            return;
        };
        if run.protocol.ending().is_none() {
            run.protocol.close(&mut self.out);
        }
        let mut figures = figures_of(run.protocol.as_ref(), run.attempt, run.started, now);
        figures.unit = self.spec.kind.unit();
        figures.wire_floor_ms = self.baud.map(|baud| {
            let bits = figures.progress.wire_bytes * capacity::BITS_PER_BYTE;
            bits as f64 * 1e3 / f64::from(baud)
        });
        self.tally.add(&figures);
        self.ended.push(figures);
        if self
            .wanted
            .is_some_and(|n| u64::from(self.tally.attempts) >= n)
        {
            self.finished = true;
        } else {
            self.next_start = Some(now + self.timeout);
        }
    }
}

/// The round trips to the target beside the downloads (or to the first
/// system to answer).
fn latency(tally: &Tally, echo: &EchoSummary) -> Option<LatencyBeside> {
    let wanted = tally.last.as_ref().and_then(|a| a.responder);
    let r = echo
        .responders
        .iter()
        .find(|r| Some(r.id) == wanted)
        .or_else(|| echo.responders.first())?;
    Some(LatencyBeside {
        responder: r.id,
        counts: r.counts,
        rtt: r.rtt,
    })
}

impl TransferDriver {
    /// What the downloads showed, in words: why one failed, a list that
    /// stopped by itself, loss that the transfer's own load makes.
    fn hints(&self, ended: &SessionEnd<'_>) -> Vec<Hint> {
        let roster = &ended.roster;
        let what = match self.spec.kind {
            TransferKind::Params => "the parameter list",
            TransferKind::Mission => "the mission",
            TransferKind::Ftp { .. } => "the file",
        };
        let tally = &self.tally;
        let mut hints = Vec::new();
        if let Some(failed) = tally.first_failed.as_ref() {
            let target = self.spec.target;
            // Any frame of the system: a HEARTBEAT, a TIMESYNC answer.
            let heard = roster.sources().any(|(id, _)| id.sysid == target.sysid);
            hints.extend(failure_hint(failed, what, target, heard));
            if failed.ending == Ending::NoAnswer {
                let asked = Asked {
                    ours: ended.cfg.ours,
                    version: ended.cfg.version,
                    key: ended.gate.summary().key,
                    what: format!("the request for {what}"),
                    echoes: Some(self.beside.answered_by(roster, target)),
                };
                hints.extend(ignored_by(roster, target, &asked));
            }
        }
        if let Some(a) = &tally.first_stopped {
            hints.push(stopped_hint(a));
        } else if let Some(h) = load_loss_hint(tally) {
            hints.push(h);
        }
        hints
    }
}

/// Why download `failed` did not complete.
fn failure_hint(failed: &AttemptFigures, what: &str, target: SysComp, heard: bool) -> Option<Hint> {
    let reason = failed.reason.as_deref().unwrap_or("no reason known");
    let (code, text) = match failed.ending {
        Ending::NoAnswer if heard => (
            HintCode::TransferNoAnswer,
            format!(
                "system {} is heard on the link but never answered the request for {what} \
                 ({} requests): it may not serve it on this component, or drops our frames",
                target.sysid, failed.counts.requests
            ),
        ),
        Ending::NoAnswer => (
            HintCode::TransferNoAnswer,
            format!(
                "nothing of system {} was heard, and the request for {what} went unanswered",
                target.sysid
            ),
        ),
        Ending::Stalled => (
            HintCode::TransferStalled,
            format!("{what} stopped coming and asking again did not finish it: {reason}"),
        ),
        Ending::Refused => (
            HintCode::TransferRefused,
            format!("the vehicle refused {what}: {reason}"),
        ),
        Ending::Complete | Ending::Cut => return None,
    };
    Some(Hint::new(code, text))
}

/// A list that stopped by itself: what followed its last never came
/// with it, and what asking one by one then brought.
fn stopped_hint(a: &AttemptFigures) -> Hint {
    let total = a.progress.total.unwrap_or(0);
    let after = a.stopped_after.unwrap_or(0);
    let tail = total.saturating_sub(after + 1);
    Hint::new(
        HintCode::TransferListStopped,
        format!(
            "in download {}, the list stopped after index {after}: the {tail} after it never \
             came with it; asked for one by one, {} re-requests were answered",
            a.attempt, a.counts.re_requests_answered
        ),
    )
}

/// The first passes lost far more than the re-requests did: loss that
/// comes with the transfer's own downlink load, not evenly.
fn load_loss_hint(tally: &Tally) -> Option<Hint> {
    if tally.units == 0 || tally.re_requests < 10 {
        return None;
    }
    let first = tally.missing_first_pass as f64 / tally.units as f64;
    let asked = 1.0 - tally.re_requests_answered as f64 / tally.re_requests as f64;
    (first >= 0.05 && asked <= first / 2.0).then(|| {
        Hint::new(
            HintCode::TransferLoadLoss,
            format!(
                "the first passes missed {:.1} % of what they carried, while {:.1} % of the \
                 re-requests went unanswered: frames are lost under the transfer's own \
                 downlink load, not evenly",
                first * 100.0,
                asked * 100.0
            ),
        )
    })
}

impl Driver for TransferDriver {
    fn start_info(&self, cfg: &SessionConfig) -> StartInfo {
        StartInfo {
            link: cfg.link_name.clone(),
            probe: self.spec.kind.probe_name(),
            ours: cfg.ours,
            interval: cfg.interval,
            timeout: self.spec.timeout,
            count: cfg.count,
            plan: Some(Arc::new(self.spec.clone())),
        }
    }

    fn begin(&mut self, wall_at_zero: WallAtZero) {
        self.beside.begin(wall_at_zero);
    }

    async fn send_due<T: Transport>(
        &mut self,
        schedule: &mut Schedule,
        link: &mut T,
        sender: &mut Sender,
        clock: &Clock,
    ) -> Result<(), LinkError> {
        let now = clock.now();
        if !self.began {
            // The schedule is the TIMESYNC probes', for as long as the
            // downloads run (`-c` counts downloads, not probes).
            self.began = true;
            *schedule = Schedule::new(now, self.interval, None);
            self.next_start = Some(now);
        }
        self.step(now);
        let out = std::mem::take(&mut self.out);
        for t in &out {
            link.send(sender.frame(&Msg::Transfer(*t))).await?;
        }
        self.out = out;
        self.out.clear();
        if self.finished {
            schedule.stop();
        } else {
            self.beside.send_due(schedule, link, sender, clock).await?;
        }
        Ok(())
    }

    fn expire(&mut self, now: Nanos) {
        self.beside.expire(now);
    }

    fn on_frame(&mut self, frame: &Frame, path: PathId, at: Nanos) {
        let Msg::Transfer(t) = frame.msg else {
            self.beside.on_frame(frame, path, at);
            return;
        };
        if let Some(run) = self.running.as_mut() {
            run.protocol
                .on_message(frame.source, &t, frame.len, at, &mut self.out);
            self.after(at);
        }
    }

    fn report(&mut self, radios: &mut Radios, observer: &mut dyn Observer) -> io::Result<()> {
        let beside = self.beside.report(radios, observer);
        let progress = tell_kind(observer, self.progress.drain(..));
        let ended = tell_kind(observer, self.ended.drain(..));
        beside.and(progress).and(ended)
    }

    fn next_deadline(&self) -> Option<Nanos> {
        // Requests a frame called for go at once.
        let now = (!self.out.is_empty()).then_some(0);
        let running = self.running.as_ref().map(|r| {
            let progress = r.told_at + PROGRESS_EVERY_NS;
            r.protocol
                .next_deadline()
                .map_or(progress, |d| d.min(progress))
        });
        [now, running, self.next_start, self.beside.next_deadline()]
            .into_iter()
            .flatten()
            .min()
    }

    fn settled(&self) -> bool {
        self.finished && self.beside.settled()
    }

    fn stopping(&mut self, now: Nanos, frames: &ScanStats) {
        self.beside.stopping(now, frames);
        self.end_download(now);
    }

    fn requests(&self) -> Option<u64> {
        let running = self
            .running
            .as_ref()
            .map_or(0, |r| r.protocol.counts().requests);
        Some(self.tally.requests + running)
    }

    fn finish(mut self, ended: SessionEnd<'_>) -> (LinkSummary, Vec<(SysComp, RttStats)>) {
        let now = (ended.duration_s * 1e9) as Nanos;
        self.end_download(now);
        let hints = self.hints(&ended);
        let ours = ended.cfg.ours;
        let (echo, histograms) = self.beside.finish(ended);
        let Some(echo) = echo.get::<EchoSummary>() else {
            unreachable!("the echo probe ends with an echo summary");
        };
        let tally = &self.tally;
        let summary = TransferSummary {
            link: echo.link.clone(),
            ours,
            plan: self.spec.clone(),
            duration_s: echo.duration_s,
            attempts: tally.attempts,
            complete: tally.complete,
            time_to_complete: tally.times(),
            missing_first_pass: tally.missing_first_pass,
            requests: tally.requests,
            re_requests: tally.re_requests,
            given_up: tally.given_up,
            first_failed: tally
                .first_failed
                .clone()
                .filter(|f| Some(f) != tally.last.as_ref()),
            last: tally.last.clone(),
            latency: latency(tally, echo),
            hints,
            frames: echo.frames,
            interrupted: echo.interrupted,
            link_error: echo.link_error.clone(),
            signing: echo.signing,
            answered: echo.answered,
            link_node: echo.link_node.clone(),
        };
        (LinkSummary::new(summary), histograms)
    }
}
