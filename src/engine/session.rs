//! One measurement run on one link, whatever the probe: sends on schedule,
//! takes in what the link delivers, tells an [`Observer`] what happened,
//! and ends on count, deadline, Ctrl-C or a link failure.
//!
//! The only place that reads a clock. What a probe's requests and replies
//! mean is its [`Driver`]'s business (echo probes: [`super::echo`];
//! commands: [`super::command`]); this loop owns the timing, our
//! HEARTBEAT, the signing gate and the systems, radios and link nodes
//! heard.

use std::io;
use std::time::Duration;

use std::sync::Arc;

use tokio::sync::Notify;

use super::answers::{AnswerSummary, Answers};
use super::c2::{C2Tracker, Watching};
use super::link_io::{admitted, Clock, Heartbeat, Sender, WallAtZero};
use super::link_node::LinkNodes;
use super::observe::{Event, Observer, OutputFate, RadioHeard, StartInfo};
use super::radio::{RadioReport, Radios};
use super::roster::Roster;
use super::schedule::Schedule;
use super::stats::RttStats;
use super::summary::{Interim, LinkSummary};
use super::wait::{self, Waiter};
use super::{Nanos, SessionConfig};
use crate::frame::signing::{self, Gate, SigningConfig};
use crate::frame::{Frame, Msg, ScanStats, SysComp};
use crate::transport::{Inbound, LinkError, LinkKind, PathId, RxClock, Transport};

/// What may reach into a running session from outside: a stop (Ctrl-C,
/// SIGTERM, `q` in the live view) and a request for an interim summary
/// (SIGQUIT, as Linux `ping`).
#[derive(Clone, Default)]
pub struct Controls {
    pub(crate) stop: Arc<Notify>,
    pub(crate) interim: Arc<Notify>,
}

/// How the run ended. The caller judges it and reports the summary.
pub struct Measurement {
    pub summary: LinkSummary,
    /// Each responder's RTT (or time-to-ACK) statistics, whose histograms
    /// (µs) the exports write.
    pub(crate) histograms: Vec<(SysComp, RttStats)>,
    /// What became of the observer's output.
    pub(crate) output: OutputFate,
}

/// What the loop knows at the end, for a driver's summary.
pub(crate) struct SessionEnd<'a> {
    pub(crate) cfg: &'a SessionConfig,
    pub(crate) duration_s: f64,
    pub(crate) interrupted: bool,
    pub(crate) link_error: Option<String>,
    pub(crate) frames: ScanStats,
    /// ICMP "port unreachable" reports the link shrugged off.
    pub(crate) unreachable: u64,
    pub(crate) downtime_s: f64,
    pub(crate) rx_clock: RxClock,
    pub(crate) kind: LinkKind,
    /// A listening link heard no peer within `SessionConfig::wait`.
    pub(crate) no_peer_within: Option<Duration>,
    pub(crate) roster: Roster,
    pub(crate) radios: Radios,
    /// Nodes heard by their LINK_NODE_STATUS (the vehicle's own view).
    pub(crate) link_nodes: LinkNodes,
    pub(crate) gate: Gate,
    /// The vehicle's requests we answered.
    pub(crate) answered: AnswerSummary,
}

/// What one probe kind does inside the session loop.
#[allow(async_fn_in_trait)] // used with concrete types only, never boxed
pub(crate) trait Driver {
    /// What the run announces first.
    fn start_info(&self, cfg: &SessionConfig) -> StartInfo;
    /// Whether it sends requests on a schedule (the passive probe does not:
    /// the session then keeps no schedule and wakes for nothing but the
    /// link, our HEARTBEAT and its deadlines).
    fn sends(&self) -> bool {
        true
    }
    /// The session's time 0 is `wall_at_zero` on the wall clock.
    fn begin(&mut self, _wall_at_zero: WallAtZero) {}
    /// Puts what is due now on the wire: requests the schedule has due,
    /// re-sends.
    async fn send_due<T: Transport>(
        &mut self,
        schedule: &mut Schedule,
        link: &mut T,
        sender: &mut Sender,
        clock: &Clock,
    ) -> Result<(), LinkError>;
    /// Decides what is overdue at `now`.
    fn expire(&mut self, now: Nanos);
    /// Every frame the signing gate admitted, before the session reads it
    /// (the passive probe counts them all), with the path it came by; and
    /// every damaged frame ([`Msg::Damaged`]), which goes nowhere else.
    fn on_received(&mut self, _frame: &Frame, _path: PathId, _at: Nanos) {}
    /// A received frame that is neither a HEARTBEAT, a RADIO_STATUS nor a
    /// LINK_NODE_STATUS.
    fn on_frame(&mut self, frame: &Frame, path: PathId, at: Nanos);
    /// A radio's RADIO_STATUS (the session keeps the run's figures; a
    /// driver may follow them too).
    fn on_radio(&mut self, _id: SysComp, _report: &RadioReport, _at: Nanos) {}
    /// Hands what was decided since the last call to the observer.
    fn report(&mut self, radios: &mut Radios, observer: &mut dyn Observer) -> io::Result<()>;
    /// The next time something may become overdue.
    fn next_deadline(&self) -> Option<Nanos>;
    /// Once every request is sent: nothing left worth waiting for.
    fn settled(&self) -> bool;
    /// The run is ending at `now` (its count, deadline, Ctrl-C or a link
    /// failure): close what is open, so the last report tells it (a
    /// sweep's step cut short).
    fn stopping(&mut self, _now: Nanos, _frames: &ScanStats) {}
    /// Requests put on the wire so far (`None`: the probe sends none).
    fn requests(&self) -> Option<u64> {
        None
    }
    /// The summary and histograms of the run.
    fn finish(self, end: SessionEnd<'_>) -> (LinkSummary, Vec<(SysComp, RttStats)>);
    /// The figures so far, for an interim summary; `None` where the probe
    /// has none.
    fn interim(&self, _roster: &Roster, _at: Nanos) -> Option<Interim> {
        None
    }
}

/// On a link whose datagrams the kernel dates (UDP), a send due within this
/// is waited for by sleeping straight to it ([`wait::block_until`]),
/// reading what arrived on waking: at 50 requests a second and more the
/// session then wakes once per send instead of once more per reply, and a
/// reply is reported at most this much later than it came (its RTT is the
/// kernel's). Slower schedules report each reply as it comes.
const SLEEP_THROUGH_NS: Nanos = 20_000_000;
/// Sleeping that way, the session wakes at most this often: requests that
/// fall due in between leave together, in one system call.
const MIN_WAKE_GAP_NS: Nanos = 100_000;
/// ...and gives the runtime a turn this often (signals, other tasks).
const YIELD_EVERY_NS: Nanos = 50_000_000;
/// Output is buffered; while busy, it reaches the reader this often.
const FLUSH_EVERY_NS: Nanos = 50_000_000;

/// While a run sends, its requests so far are told at most this often.
const PROGRESS_EVERY_NS: Nanos = 1_000_000_000;

/// The systems, radios and link nodes heard, and the signing gate: what
/// every session learns from the link whatever its probe.
struct Heard {
    roster: Roster,
    radios: Radios,
    link_nodes: LinkNodes,
    gate: Gate,
    answers: Answers,
    /// `--report c2`: the C2 link report's figures.
    c2: Option<C2Tracker>,
}

impl Heard {
    /// Takes in received frames: HEARTBEAT, RADIO_STATUS and
    /// LINK_NODE_STATUS here, the rest to the driver, then reports what was
    /// decided.
    fn take<D: Driver>(
        &mut self,
        clock: &Clock,
        inbound: &mut Vec<Inbound>,
        driver: &mut D,
        observer: &mut dyn Observer,
    ) -> io::Result<()> {
        let mut output = Ok(());
        for Inbound {
            frame,
            at,
            signature,
            path,
            ..
        } in inbound.drain(..)
        {
            let at = clock.ns(at);
            // A damaged frame's header is all it has: it fills its source's
            // sequence, and is no evidence of anything else (its signature
            // cannot be checked against bytes that changed, and no system is
            // heard by it).
            if matches!(frame.msg, Msg::Damaged) {
                driver.on_received(&frame, path, at);
                continue;
            }
            if !admitted(&mut self.gate, &frame, signature.as_ref()) {
                continue;
            }
            self.roster.frame(frame.source, frame.version, frame.signed);
            if let Some(stamp) = frame.stamps.signature {
                // Ours as the signer would stamp now: the wall clock.
                let ours = signing::timestamp_now();
                self.roster.signature(frame.source, stamp.value, ours);
            }
            if let Some(to) = frame.msg.addressed_to() {
                self.roster.addressed(frame.source, to, frame.msgid);
            }
            self.answers.take(&frame, path, at);
            if let Some(c2) = &mut self.c2 {
                c2.frame(&frame, at);
            }
            driver.on_received(&frame, path, at);
            match frame.msg {
                Msg::Heartbeat {
                    mav_type,
                    autopilot,
                } => {
                    // mLRS says what it is by its HEARTBEAT.
                    if self.radios.heartbeat(frame.source, mav_type, autopilot) {
                        output = output.and(self.tell_radio(frame.source, at, false, observer));
                    }
                    if self.roster.heard(frame.source, mav_type, autopilot, at) {
                        let identity = self.roster.get(frame.source).expect("just added");
                        output = output.and(observer.event(&Event::Heard {
                            id: frame.source,
                            identity,
                        }));
                    }
                }
                // Radios inject this (or RADIO) from their own ids on any
                // link; a report sent as both counts once.
                Msg::RadioStatus(report) => {
                    let id = frame.source;
                    let Some(taken) =
                        self.radios
                            .take(id, frame.msgid, frame.packet_seq, report, at)
                    else {
                        continue;
                    };
                    driver.on_radio(id, &report, at);
                    if taken.first || taken.kind_changed {
                        output = output.and(self.tell_radio(id, at, taken.first, observer));
                    } else {
                        output = output.and(self.tell_report(id, at, report, observer));
                    }
                }
                // A node's own count of the link it sends this on (PX4's,
                // at 1 Hz): every kind of run keeps it.
                Msg::LinkNodeStatus(report) => {
                    let first = self.link_nodes.record(frame.source, report, at);
                    output = output.and(observer.event(&Event::LinkNode {
                        id: frame.source,
                        at,
                        report,
                        first,
                    }));
                }
                _ => driver.on_frame(&frame, path, at),
            }
        }
        let mut watching = Watching {
            c2: self.c2.as_mut(),
            observer,
        };
        output.and(driver.report(&mut self.radios, &mut watching))
    }

    /// A radio's latest report, with what it is and why: at its first
    /// report and when its kind changes.
    fn tell_radio(
        &self,
        id: SysComp,
        at: Nanos,
        first: bool,
        observer: &mut dyn Observer,
    ) -> io::Result<()> {
        let (Some(report), Some(judgement)) = (self.radios.latest(id), self.radios.judgement(id))
        else {
            return Ok(());
        };
        observer.event(&Event::Radio(RadioHeard {
            id,
            at,
            report,
            judgement,
            first,
            kind_changed: !first,
        }))
    }

    /// Any other report.
    fn tell_report(
        &self,
        id: SysComp,
        at: Nanos,
        report: RadioReport,
        observer: &mut dyn Observer,
    ) -> io::Result<()> {
        let Some(judgement) = self.radios.judgement(id) else {
            return Ok(());
        };
        observer.event(&Event::Radio(RadioHeard {
            id,
            at,
            report,
            judgement,
            first: false,
            kind_changed: false,
        }))
    }
}

/// Polls a future once: its result if it is ready now. Used on cancel-safe
/// futures only (the stop and interim signals), between precise sleeps.
fn ready_now<F: std::future::Future>(f: F) -> Option<F::Output> {
    let mut f = std::pin::pin!(f);
    let mut cx = std::task::Context::from_waker(std::task::Waker::noop());
    match f.as_mut().poll(&mut cx) {
        std::task::Poll::Ready(v) => Some(v),
        std::task::Poll::Pending => None,
    }
}

/// Why the loop stopped.
enum Stop {
    /// The count was sent and settled, or the deadline came.
    Done,
    Interrupted,
    LinkFailed(LinkError),
    /// A listening link heard nobody in time.
    NoPeer,
}

impl Stop {
    /// A link error ends the session as a failure, but a recorded link
    /// that reached its end (a telemetry log) is done.
    fn from_link(error: LinkError) -> Stop {
        match error {
            LinkError::End => Stop::Done,
            e => Stop::LinkFailed(e),
        }
    }
}

/// One turn of the loop: `Err` ends the session, for the reason it gives.
type Turn = Result<(), Stop>;

/// The session's own times, in session nanoseconds.
struct Timers {
    deadline: Option<Nanos>,
    /// Until a peer is heard (listening links).
    wait: Option<Nanos>,
    interim_every: Option<Nanos>,
    next_interim: Option<Nanos>,
    last_flush: Nanos,
    /// The last planned wake-up of a sleep-through.
    last_wake: Nanos,
    last_yield: Nanos,
    /// The requests last told ([`Event::Progress`]), and when the next
    /// telling may come.
    progress_told: u64,
    next_progress: Nanos,
}

impl Timers {
    fn new(cfg: &SessionConfig) -> Self {
        let ns = |d: Duration| d.as_nanos() as Nanos;
        let interim_every = cfg.interim.map(ns);
        Timers {
            deadline: cfg.deadline.map(ns),
            wait: cfg.wait.map(ns),
            interim_every,
            next_interim: interim_every,
            last_flush: 0,
            last_wake: 0,
            last_yield: 0,
            progress_told: 0,
            next_progress: 0,
        }
    }

    /// Whether an interim summary is due at `now`; if so, plans the next.
    fn interim_due(&mut self, now: Nanos) -> bool {
        if self.next_interim.is_none_or(|due| now < due) {
            return false;
        }
        self.next_interim = self
            .next_interim
            .zip(self.interim_every)
            .map(|(due, every)| due + every);
        true
    }
}

/// A running session: the loop's state, stepped by [`Session::turn`].
struct Session<'a, T, D> {
    cfg: &'a SessionConfig,
    link: &'a mut T,
    driver: D,
    observer: &'a mut dyn Observer,
    controls: &'a Controls,
    clock: Clock,
    waiter: Waiter,
    sender: Sender,
    heartbeat: Heartbeat,
    heard: Heard,
    /// Made once a peer is known.
    schedule: Option<Schedule>,
    timers: Timers,
    told_waiting: bool,
    /// The link dates what it receives in the kernel (UDP).
    kernel_stamped: bool,
    inbound: Vec<Inbound>,
    /// What became of the observer's output (the run goes on regardless).
    output: OutputFate,
}

impl<'a, T: Transport, D: Driver> Session<'a, T, D> {
    fn start(
        cfg: &'a SessionConfig,
        link: &'a mut T,
        mut driver: D,
        observer: &'a mut dyn Observer,
        controls: &'a Controls,
    ) -> Self {
        wait::tighten_timer_slack();
        let clock = Clock::start();
        driver.begin(clock.wall_at_zero());
        let mut output = OutputFate::default();
        output.note(&observer.start(&driver.start_info(cfg)));
        let kernel_stamped = link.rx_clock() == RxClock::Kernel;
        let log = link.kind() == LinkKind::Log;
        Session {
            cfg,
            link,
            observer,
            controls,
            waiter: Waiter::new(cfg.precise_pacing),
            sender: Sender::new(
                cfg.ours,
                cfg.version,
                cfg.signing.as_ref().map(SigningConfig::signer),
            ),
            heartbeat: Heartbeat::ground_station(cfg.heartbeat),
            heard: Heard {
                roster: Roster::default(),
                radios: Radios::new(cfg.radio_type),
                link_nodes: LinkNodes::default(),
                gate: Gate::new(cfg.signing),
                answers: Answers::new(cfg.ours, cfg.answer),
                c2: cfg.c2.as_ref().map(|c2| {
                    let timeout = Nanos::try_from(cfg.timeout.as_nanos()).unwrap_or(Nanos::MAX);
                    C2Tracker::new(c2, cfg.ours, timeout, cfg.first_seq, log)
                }),
            },
            schedule: None,
            timers: Timers::new(cfg),
            told_waiting: false,
            kernel_stamped,
            inbound: Vec::new(),
            output,
            clock,
            driver,
        }
    }

    /// Notes a write error; the measurement goes on.
    fn told(&mut self, written: io::Result<()>) {
        self.output.note(&written);
    }

    /// A run with no count, deadline or sweep whose reader went away ends
    /// as `ping | head` does, judged as if interrupted; any other run goes
    /// on to its end, so a closed pipe cannot cut a check short.
    fn reader_gone(&self) -> Turn {
        let cfg = self.cfg;
        let endless = cfg.count.is_none() && cfg.deadline.is_none() && cfg.sweep.is_none();
        match self.output {
            OutputFate::Closed if endless => Err(Stop::Interrupted),
            _ => Ok(()),
        }
    }

    /// Sends what is due, decides what is overdue, then waits for the
    /// next thing to do.
    async fn turn(&mut self) -> Turn {
        self.reader_gone()?;
        let now = self.clock.now();
        if self.timers.deadline.is_some_and(|d| now >= d) {
            return Err(Stop::Done);
        }
        // Our HEARTBEAT goes first, so a stack that discovers systems by
        // their messages (MAVSDK) knows us before our first request.
        let beat = self.heartbeat.send_if_due(self.link, &mut self.sender, now);
        beat.await.map_err(Stop::LinkFailed)?;
        let answers = self.heard.answers.send(self.link, &mut self.sender);
        answers.await.map_err(Stop::LinkFailed)?;
        self.schedule_once_a_peer_is_known(now)?;
        self.send_due().await?;
        self.decide();
        if self.schedule.as_ref().is_some_and(Schedule::finished) && self.driver.settled() {
            return Err(Stop::Done);
        }
        let next_send = self.schedule.as_ref().and_then(Schedule::next_due);
        match next_send.filter(|&due| self.sleeps_through_to(due)) {
            Some(due) => self.sleep_through(due).await,
            None => self.wait(next_send).await,
        }
    }

    /// A listening link has no schedule until it hears a peer.
    fn schedule_once_a_peer_is_known(&mut self, now: Nanos) -> Turn {
        if self.schedule.is_some() {
            return Ok(());
        }
        if self.link.has_peers() {
            if !self.driver.sends() {
                return Ok(());
            }
            let interval = self.cfg.interval.as_nanos() as Nanos;
            self.schedule = Some(Schedule::new(now, interval, self.cfg.count));
        } else if self.timers.wait.is_some_and(|w| now >= w) {
            return Err(Stop::NoPeer);
        } else if !self.told_waiting {
            self.told_waiting = true;
            let told = self.observer.event(&Event::WaitingForPeer);
            self.told(told);
        }
        Ok(())
    }

    async fn send_due(&mut self) -> Turn {
        let Some(schedule) = self.schedule.as_mut() else {
            return Ok(());
        };
        let sent = self
            .driver
            .send_due(schedule, self.link, &mut self.sender, &self.clock);
        sent.await.map_err(Stop::LinkFailed)?;
        self.tell_progress(false);
        Ok(())
    }

    /// Tells the requests put on the wire so far if the figure changed: at
    /// once when the last telling is [`PROGRESS_EVERY_NS`] old (a slow
    /// schedule wakes for nothing more), else when it is
    /// ([`Session::progress_due`]); and at the end (`last`).
    fn tell_progress(&mut self, last: bool) {
        let Some(requests) = self.driver.requests() else {
            return;
        };
        let now = self.clock.now();
        let t = &mut self.timers;
        if t.progress_told == requests || !(last || now >= t.next_progress) {
            return;
        }
        t.progress_told = requests;
        t.next_progress = now.saturating_add(PROGRESS_EVERY_NS);
        let told = self.observer.event(&Event::Progress { at: now, requests });
        self.told(told);
    }

    /// When the requests sent since the last telling are to be told.
    fn progress_due(&self) -> Option<Nanos> {
        let requests = self.driver.requests()?;
        (self.timers.progress_told != requests).then_some(self.timers.next_progress)
    }

    /// Decides what is overdue and reports it, and an interim summary when
    /// one is due.
    fn decide(&mut self) {
        self.driver.expire(self.clock.now());
        let mut watching = Watching {
            c2: self.heard.c2.as_mut(),
            observer: self.observer,
        };
        let reported = self.driver.report(&mut self.heard.radios, &mut watching);
        self.told(reported);
        if self.timers.interim_due(self.clock.now()) {
            self.interim();
        }
    }

    /// Tells the observer the figures so far, if the probe has an interim.
    fn interim(&mut self) {
        let told = match self.driver.interim(&self.heard.roster, self.clock.now()) {
            Some(figures) => self.observer.interim(&figures),
            None => Ok(()),
        };
        self.told(told);
    }

    /// Takes in what was received and reports what it decided.
    fn take_inbound(&mut self) {
        let taken = self.heard.take(
            &self.clock,
            &mut self.inbound,
            &mut self.driver,
            self.observer,
        );
        self.told(taken);
    }

    /// Whether to sleep straight to the send due at `due` (see
    /// [`SLEEP_THROUGH_NS`]).
    fn sleeps_through_to(&self, due: Nanos) -> bool {
        self.cfg.precise_pacing
            && self.kernel_stamped
            && due.saturating_sub(self.clock.now()) <= SLEEP_THROUGH_NS
    }

    /// Sleeps to the send due at `due` on the session's own clock, taking
    /// in what arrived at each wake-up, with the runtime idle meanwhile.
    async fn sleep_through(&mut self, due: Nanos) -> Turn {
        // Spaced from the last planned wake-up, not the actual one, so a
        // late wake-up does not push the next one later.
        let wake_at = due.max(self.timers.last_wake.saturating_add(MIN_WAKE_GAP_NS));
        loop {
            if ready_now(self.controls.stop.notified()).is_some() {
                return Err(Stop::Interrupted);
            }
            if ready_now(self.controls.interim.notified()).is_some() {
                self.interim();
            }
            if self.clock.now() < wake_at {
                wait::block_until(&self.clock, wake_at);
            }
            if self
                .link
                .read_waiting(&mut self.inbound)
                .map_err(Stop::from_link)?
            {
                self.take_inbound();
            }
            let now = self.clock.now();
            if now.saturating_sub(self.timers.last_flush) > FLUSH_EVERY_NS {
                self.timers.last_flush = now;
                let flushed = self.observer.flush();
                self.told(flushed);
            }
            // The runtime runs nothing while the thread sleeps here: let it
            // handle signals now and then.
            if now.saturating_sub(self.timers.last_yield) > YIELD_EVERY_NS {
                self.timers.last_yield = now;
                tokio::task::yield_now().await;
            }
            if now >= wake_at {
                break;
            }
        }
        self.timers.last_wake = wake_at;
        Ok(())
    }

    /// Waits in the runtime for the first of: the next send, a driver's
    /// deadline, our HEARTBEAT, the run's deadline or wait, an interim, a
    /// frame, a stop.
    async fn wait(&mut self, next_send: Option<Nanos>) -> Turn {
        let t = &self.timers;
        let wake = [
            next_send,
            self.driver.next_deadline(),
            self.heartbeat.next(),
            t.deadline,
            t.wait.filter(|_| self.schedule.is_none()),
            t.next_interim,
            self.progress_due(),
        ]
        .into_iter()
        .flatten()
        .min();
        // About to block: let buffered output reach the reader.
        self.timers.last_flush = self.clock.now();
        let flushed = self.observer.flush();
        self.told(flushed);
        let controls = self.controls;
        self.link.next_wake(wake.map(|ns| self.clock.at(ns)));
        let sleep = self.waiter.until(&self.clock, wake);
        tokio::select! {
            biased;
            _ = controls.stop.notified() => return Err(Stop::Interrupted),
            _ = controls.interim.notified() => self.interim(),
            received = self.link.recv(&mut self.inbound) => {
                received.map_err(Stop::from_link)?;
                self.take_inbound();
            }
            _ = sleep => {}
        }
        Ok(())
    }

    /// Decides what is left, tells how the link ended, and hands the
    /// driver's summary back.
    fn finish(mut self, stop: Stop) -> Measurement {
        // Decide what is due before counting what is still in flight.
        self.driver.expire(self.clock.now());
        self.driver
            .stopping(self.clock.now(), &self.link.scan_stats());
        let reported = self.driver.report(&mut self.heard.radios, self.observer);
        self.told(reported);
        self.tell_progress(true);
        let (interrupted, link_error, no_peer_within) = match stop {
            Stop::Interrupted => (true, None, None),
            Stop::LinkFailed(e) => (false, Some(e.to_string()), None),
            Stop::NoPeer => (false, None, self.cfg.wait),
            Stop::Done => (false, None, None),
        };
        if let Some(error) = &link_error {
            let failed = Event::LinkFailed {
                at: self.clock.now(),
                error,
            };
            let told = self.observer.event(&failed);
            self.told(told);
        }
        let end = self.clock.now();
        let c2 = self.heard.c2.take();
        let (mut summary, histograms) = self.driver.finish(SessionEnd {
            cfg: self.cfg,
            duration_s: self.clock.now() as f64 / 1e9,
            interrupted,
            link_error,
            frames: self.link.scan_stats(),
            unreachable: self.link.unreachable(),
            downtime_s: self.link.downtime().as_secs_f64(),
            rx_clock: self.link.rx_clock(),
            kind: self.link.kind(),
            no_peer_within,
            roster: self.heard.roster,
            radios: self.heard.radios,
            link_nodes: self.heard.link_nodes,
            gate: self.heard.gate,
            answered: self.heard.answers.summary(),
        });
        // Last, as it judges the finished figures (a sweep's included).
        if let Some(wire) = self.cfg.wire {
            summary.apply_wire(wire);
        }
        if let Some(c2) = c2 {
            let mut report = c2.finish(end, &summary);
            // A log is dated by its own clock once read; the simulated
            // link has none (its output is reproducible).
            if !matches!(self.link.kind(), LinkKind::Log | LinkKind::Simulated) {
                report.date(self.clock.wall_at_zero().wall);
            }
            summary.set_c2(report);
        }
        Measurement {
            summary,
            histograms,
            output: self.output,
        }
    }
}

/// Runs one session until it ends and returns what it measured.
pub(crate) async fn run<T: Transport, D: Driver>(
    cfg: &SessionConfig,
    link: &mut T,
    driver: D,
    observer: &mut dyn Observer,
    controls: &Controls,
) -> Measurement {
    let mut session = Session::start(cfg, link, driver, observer, controls);
    let stop = loop {
        if let Err(stop) = session.turn().await {
            break stop;
        }
    };
    session.finish(stop)
}
