//! One measurement run on one link, whatever the probe: sends on schedule,
//! takes in what the link delivers, tells an [`Observer`] what happened,
//! and ends on count, deadline, Ctrl-C or a link failure.
//!
//! The only place that reads a clock. What a probe's requests and replies
//! mean is its [`Driver`]'s business (echo probes: [`super::echo`];
//! commands: [`super::command`]); this loop owns the timing, our
//! HEARTBEAT, the signing gate and the systems and radios heard.

use std::io;
use std::time::Duration;

use std::sync::Arc;

use tokio::sync::Notify;

use super::link_io::{admitted, Clock, Heartbeat, Sender};
use super::observe::{Event, Observer, StartInfo};
use super::radio::{RadioReport, Radios};
use super::roster::Roster;
use super::schedule::Schedule;
use super::stats::RttStats;
use super::summary::{Interim, LinkSummary};
use super::wait::{self, Waiter};
use super::{Nanos, SessionConfig};
use crate::frame::signing::{Gate, SigningConfig};
use crate::frame::{Frame, Msg, ScanStats, SysComp};
use crate::transport::{Inbound, LinkError, LinkKind, PathId, RxClock, Transport};

/// What may reach into a running session from outside: a stop (Ctrl-C,
/// SIGTERM, `q` in the live view) and a request for an interim summary
/// (SIGQUIT, as Linux `ping`).
#[derive(Clone, Default)]
pub struct Controls {
    pub stop: Arc<Notify>,
    pub interim: Arc<Notify>,
}

/// How the run ended. The caller judges it and reports the summary.
pub struct Outcome {
    pub summary: LinkSummary,
    /// Each responder's RTT (or time-to-ACK) statistics, whose histograms
    /// (µs) the exports write.
    pub histograms: Vec<(SysComp, RttStats)>,
    /// The observer's output went away (closed pipe): stop quietly.
    pub output_closed: bool,
}

/// What the loop knows at the end, for a driver's summary.
pub struct Ended<'a> {
    pub cfg: &'a SessionConfig,
    pub duration_s: f64,
    pub interrupted: bool,
    pub link_error: Option<String>,
    pub frames: ScanStats,
    pub downtime_s: f64,
    pub rx_clock: RxClock,
    pub kind: LinkKind,
    /// A listening link heard no peer within `SessionConfig::wait`.
    pub no_peer_within: Option<Duration>,
    pub roster: Roster,
    pub radios: Radios,
    pub gate: Gate,
}

/// What one probe kind does inside the session loop.
#[allow(async_fn_in_trait)] // used with concrete types only, never boxed
pub trait Driver {
    /// What the run announces first.
    fn start_info(&self, cfg: &SessionConfig) -> StartInfo;
    /// The session's time 0 is `wall_at_zero` on the wall clock.
    fn begin(&mut self, _wall_at_zero: std::time::SystemTime) {}
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
    /// A received frame that is neither a HEARTBEAT nor a RADIO_STATUS.
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
    /// The summary and histograms of the run.
    fn finish(self, ended: Ended<'_>) -> (LinkSummary, Vec<(SysComp, RttStats)>);
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

/// The systems and radios heard, and the signing gate: what every session
/// learns from the link whatever its probe.
struct Heard {
    roster: Roster,
    radios: Radios,
    gate: Gate,
}

impl Heard {
    /// Takes in received frames: HEARTBEAT and RADIO_STATUS here, the rest
    /// to the driver, then reports what was decided.
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
        } in inbound.drain(..)
        {
            if !admitted(&mut self.gate, &frame, signature.as_ref()) {
                continue;
            }
            self.roster.frame(frame.source, frame.version, frame.signed);
            let at = clock.ns(at);
            match frame.msg {
                Msg::Heartbeat {
                    mav_type,
                    autopilot,
                } => {
                    if self.roster.heard(frame.source, mav_type, autopilot, at) {
                        let identity = self.roster.get(frame.source).expect("just added");
                        output = output.and(observer.event(&Event::Heard {
                            id: frame.source,
                            identity,
                        }));
                    }
                }
                // Radios inject this from their own ids on any link.
                Msg::RadioStatus(report) => {
                    let first = self.radios.record(frame.source, report, at);
                    driver.on_radio(frame.source, &report, at);
                    output = output.and(observer.event(&Event::Radio {
                        id: frame.source,
                        at,
                        report,
                        first,
                    }));
                }
                _ => driver.on_frame(&frame, path, at),
            }
        }
        output.and(driver.report(&mut self.radios, observer))
    }
}

/// Tells the observer the figures so far, if the probe has an interim.
fn interim<D: Driver>(
    driver: &D,
    roster: &Roster,
    at: Nanos,
    observer: &mut dyn Observer,
) -> io::Result<()> {
    match driver.interim(roster, at) {
        Some(figures) => observer.interim(&figures),
        None => Ok(()),
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

/// Why the loop stopped early.
enum Stopped {
    Interrupted,
    LinkFailed(LinkError),
    OutputClosed,
    /// A listening link heard nobody in time.
    NoPeer,
}

/// Runs one session until it ends and returns what it measured.
pub async fn run<T: Transport, D: Driver>(
    cfg: &SessionConfig,
    link: &mut T,
    mut driver: D,
    observer: &mut dyn Observer,
    controls: &Controls,
) -> Outcome {
    let stop = &*controls.stop;
    wait::tighten_timer_slack();
    let mut waiter = Waiter::new(cfg.precise_pacing);
    let clock = Clock::start();
    driver.begin(clock.wall_at_zero());
    let mut sender = Sender::new(
        cfg.ours,
        cfg.version,
        cfg.signing.as_ref().map(SigningConfig::signer),
    );
    let mut heartbeat = Heartbeat::ground_station(cfg.heartbeat);
    let mut heard = Heard {
        roster: Roster::default(),
        radios: Radios::default(),
        gate: Gate::new(cfg.signing),
    };
    let mut schedule: Option<Schedule> = None;
    let deadline_ns = cfg.deadline.map(|d| d.as_nanos() as Nanos);
    let wait_ns = cfg.wait.map(|d| d.as_nanos() as Nanos);
    let interim_ns = cfg.interim.map(|d| d.as_nanos() as Nanos);
    let mut next_interim = interim_ns;
    let mut inbound: Vec<Inbound> = Vec::new();
    let mut told_waiting = false;
    let mut last_flush: Nanos = 0;
    let mut last_wake: Nanos = 0;
    let mut last_yield: Nanos = 0;
    let kernel_stamped = link.rx_clock() == RxClock::Kernel;
    let mut output = observer.start(&driver.start_info(cfg));

    let stopped: Option<Stopped> = 'run: loop {
        if output.is_err() {
            break Some(Stopped::OutputClosed);
        }
        let now = clock.now();
        if deadline_ns.is_some_and(|d| now >= d) {
            break None;
        }
        // Our HEARTBEAT goes first, so a stack that discovers systems by
        // their messages (MAVSDK) knows us before our first request.
        if let Err(e) = heartbeat.send_if_due(link, &mut sender, now).await {
            break Some(Stopped::LinkFailed(e));
        }
        if schedule.is_none() {
            if link.has_peers() {
                let interval = cfg.interval.as_nanos() as Nanos;
                schedule = Some(Schedule::new(now, interval, cfg.count));
            } else if wait_ns.is_some_and(|w| now >= w) {
                break Some(Stopped::NoPeer);
            } else if !told_waiting {
                told_waiting = true;
                output = observer.event(&Event::WaitingForPeer);
            }
        }
        if let Some(s) = schedule.as_mut() {
            if let Err(e) = driver.send_due(s, link, &mut sender, &clock).await {
                break Some(Stopped::LinkFailed(e));
            }
        }
        driver.expire(clock.now());
        output = output.and(driver.report(&mut heard.radios, observer));
        let now = clock.now();
        if next_interim.is_some_and(|due| now >= due) {
            next_interim = next_interim.zip(interim_ns).map(|(due, every)| due + every);
            output = output.and(interim(&driver, &heard.roster, now, observer));
        }
        if output.is_err() {
            continue;
        }
        if schedule.as_ref().is_some_and(|s| s.finished()) && driver.settled() {
            break None;
        }

        let next_send = schedule.as_ref().and_then(|s| s.next_due());
        let now = clock.now();
        let close = next_send.filter(|&due| {
            cfg.precise_pacing && kernel_stamped && due.saturating_sub(now) <= SLEEP_THROUGH_NS
        });
        if let Some(due) = close {
            // Spaced from the last planned wake-up, not the actual one, so
            // a late wake-up does not push the next one later.
            let wake_at = due.max(last_wake.saturating_add(MIN_WAKE_GAP_NS));
            loop {
                if ready_now(stop.notified()).is_some() {
                    break 'run Some(Stopped::Interrupted);
                }
                if ready_now(controls.interim.notified()).is_some() {
                    output = output.and(interim(&driver, &heard.roster, clock.now(), observer));
                }
                if clock.now() < wake_at {
                    wait::block_until(&clock, wake_at);
                }
                match link.read_waiting(&mut inbound) {
                    Err(e) => break 'run Some(Stopped::LinkFailed(e)),
                    Ok(true) => {
                        let taken = heard.take(&clock, &mut inbound, &mut driver, observer);
                        output = output.and(taken);
                    }
                    Ok(false) => {}
                }
                let now = clock.now();
                if now.saturating_sub(last_flush) > FLUSH_EVERY_NS {
                    last_flush = now;
                    output = output.and(observer.flush());
                }
                if output.is_err() {
                    continue 'run;
                }
                // The runtime runs nothing while the thread sleeps here:
                // let it handle signals now and then.
                if now.saturating_sub(last_yield) > YIELD_EVERY_NS {
                    last_yield = now;
                    tokio::task::yield_now().await;
                }
                if now >= wake_at {
                    break;
                }
            }
            last_wake = wake_at;
            continue;
        }

        let wake = [
            next_send,
            driver.next_deadline(),
            heartbeat.next(),
            deadline_ns,
            wait_ns.filter(|_| schedule.is_none()),
            next_interim,
        ]
        .into_iter()
        .flatten()
        .min();
        // About to block: let buffered output reach the reader.
        last_flush = now;
        output = observer.flush();
        if output.is_err() {
            continue;
        }
        let sleep = waiter.until(&clock, wake);
        tokio::select! {
            biased;
            _ = stop.notified() => break Some(Stopped::Interrupted),
            _ = controls.interim.notified() => {
                output = interim(&driver, &heard.roster, clock.now(), observer);
            }
            received = link.recv(&mut inbound) => {
                if let Err(e) = received {
                    break Some(Stopped::LinkFailed(e));
                }
                output = heard.take(&clock, &mut inbound, &mut driver, observer);
            }
            _ = sleep => {}
        }
    };

    // Decide what is due before counting what is still in flight.
    driver.expire(clock.now());
    let mut output_closed = match stopped {
        Some(Stopped::OutputClosed) => true,
        _ => driver.report(&mut heard.radios, observer).is_err(),
    };
    if let Some(Stopped::LinkFailed(e)) = &stopped {
        let error = e.to_string();
        let failed = Event::LinkFailed {
            at: clock.now(),
            error: &error,
        };
        output_closed |= observer.event(&failed).is_err();
    }
    let no_peer_within = match stopped {
        Some(Stopped::NoPeer) => cfg.wait,
        _ => None,
    };
    let (interrupted, link_error) = match stopped {
        Some(Stopped::Interrupted) => (true, None),
        Some(Stopped::LinkFailed(e)) => (false, Some(e.to_string())),
        _ => (false, None),
    };
    let (summary, histograms) = driver.finish(Ended {
        cfg,
        duration_s: clock.now() as f64 / 1e9,
        interrupted,
        link_error,
        frames: link.scan_stats(),
        downtime_s: link.downtime().as_secs_f64(),
        rx_clock: link.rx_clock(),
        kind: link.kind(),
        no_peer_within,
        roster: heard.roster,
        radios: heard.radios,
        gate: heard.gate,
    });
    Outcome {
        summary,
        histograms,
        output_closed,
    }
}
