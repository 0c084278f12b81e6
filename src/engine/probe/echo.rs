//! Echo probes (PING, TIMESYNC) in the session: requests on schedule, each
//! reply matched to its request by the pure [`Matcher`], per responder.

use std::collections::HashMap;
use std::io;
use std::sync::Arc;
use std::time::Duration;

use super::passive::driver::{self as passive_driver, tell_sources};
use super::passive::ticks::Ticks;
use super::passive::tracker::{SourceTable, DEFAULT_MAX_SOURCES};
use super::{Classified, EchoProbe};
use crate::engine::age::{self, AgeTracker, AgedSplit, RoundTripSplit, SourceAge};
use crate::engine::diagnosis::{diagnose, Observed};
use crate::engine::hint::{Hint, HintCode};
use crate::engine::kind::KindValue;
use crate::engine::link_io::{Clock, Sender, WallAtZero};
use crate::engine::matcher::{MatchEvent, Matcher, MAX_RESPONDERS};
use crate::engine::observe::{tell_each, tell_kind, Event, Observer, StartInfo};
use crate::engine::probe::uplink_check::compare_uplink;
use crate::engine::radio::{radio_hints, Radios};
use crate::engine::roster::Roster;
use crate::engine::schedule::Schedule;
use crate::engine::session::{self, Controls, Driver, Measurement, SessionEnd};
use crate::engine::stats::RttStats;
use crate::engine::summary::{
    responder_summaries, Direction, EchoInterim, EchoSummary, Interim, LinkSummary,
    ResponderSummary, ScheduleSummary,
};
use crate::engine::Nanos;
use crate::engine::SessionConfig;
use crate::frame::{Frame, StampClock, StampMeaning, SysComp};
use crate::transport::{LinkError, Outbox, PathId, To, Transport};

/// Most requests sent back to back before the session reads the link.
const MAX_BURST: usize = 256;

/// Runs an echo probe on `link` until the run ends.
pub async fn run<T: Transport, P: EchoProbe>(
    cfg: &SessionConfig,
    link: &mut T,
    probe: P,
    observer: &mut dyn Observer,
    controls: &Controls,
) -> Measurement {
    let driver = EchoDriver::new(cfg, probe);
    session::run(cfg, link, driver, observer, controls).await
}

/// An echo probe's state in a session.
pub(crate) struct EchoDriver<P> {
    probe: P,
    ours: SysComp,
    first_seq: u32,
    timeout: Nanos,
    matcher: Matcher,
    /// Decided, not yet reported.
    events: Vec<MatchEvent>,
    foreign_replies: u64,
    /// The link path each responder answers from (links with several
    /// peers) and when it last did: its ids are believed from that path
    /// only, until it has been silent for a whole timeout (a responder that
    /// restarts or reconnects comes back on a new path).
    paths: HashMap<SysComp, (PathId, Nanos)>,
    wrong_path_replies: u64,
    pacing: Pacing,
    /// The burst being sent: its frames, and each request's planned time,
    /// token and number of frames (kept between bursts so sending does not allocate).
    outbox: Outbox,
    burst: Vec<(Nanos, u64, u8)>,
    /// When each responder's clock offset was last told (TIMESYNC), and
    /// the ones due now.
    clocks_told: HashMap<SysComp, Nanos>,
    clocks_due: Vec<(SysComp, Nanos)>,
    /// Every source's packet sequence: a responder's is its downlink loss.
    sequences: SourceTable,
    sequence_ticks: Ticks,
    /// How old every source's frames are, from their own clock stamps.
    age: AgeTracker,
    /// Each responder's round trips split into up and down, where its
    /// replies carry its clock (TIMESYNC's `tc1`, a signature).
    splits: HashMap<SysComp, RoundTripSplit>,
    /// Where the replies carry no clock, each responder's round trips
    /// split by its telemetry's age.
    aged_splits: HashMap<SysComp, AgedSplit>,
}

/// A responder's telemetry age speaks for its reply only if its newest
/// stamped frame came this close before it (ns): 5 frames a second.
const AGE_FRESH_NS: Nanos = 200_000_000;

/// A responder's clock offset is told at most this often.
const CLOCK_TOLD_EVERY: Nanos = 1_000_000_000;

impl<P: EchoProbe> EchoDriver<P> {
    /// Records a reply's round trip split, when it carries the
    /// responder's clock: TIMESYNC's `tc1`, else a signature's time.
    fn split(&mut self, frame: &Frame, sent_at: Nanos, at: Nanos) {
        let theirs = frame.stamps.iter().find(|s| {
            s.meaning == StampMeaning::Sent
                && matches!(s.clock, StampClock::TimesyncNs | StampClock::Signature)
        });
        let Some(stamp) = theirs else {
            self.aged_split(frame.source, sent_at, at);
            return;
        };
        if !self.splits.contains_key(&frame.source) && self.splits.len() >= MAX_RESPONDERS {
            return;
        }
        let theirs_ns = i128::from(stamp.value) * i128::from(stamp.clock.unit_ns());
        let split = self.splits.entry(frame.source).or_default();
        split.record(sent_at, theirs_ns, at);
    }

    /// Records a reply without the responder's clock split by its
    /// telemetry's age, when a send-stamped frame of its came just before.
    fn aged_split(&mut self, source: SysComp, sent_at: Nanos, at: Nanos) {
        let Some(now) = self.age.now(source) else {
            return;
        };
        let fresh = now.meaning == StampMeaning::Sent
            && now.clock.keeps_time()
            && at.saturating_sub(now.at) <= AGE_FRESH_NS;
        let room =
            self.aged_splits.len() < MAX_RESPONDERS || self.aged_splits.contains_key(&source);
        if fresh && room {
            let split = self.aged_splits.entry(source).or_default();
            split.record(at.saturating_sub(sent_at), now.age_ms);
        }
    }

    /// Every source's age, each responder's split, and the queue hint for
    /// each source whose frames came ever later while it lost next to none.
    fn ages(&self, responders: &mut [ResponderSummary]) -> (Vec<SourceAge>, Vec<Hint>) {
        for r in responders.iter_mut() {
            r.split = (self.splits.get(&r.id).and_then(RoundTripSplit::summary))
                .or_else(|| self.aged_splits.get(&r.id).and_then(AgedSplit::summary));
        }
        let mut ages = self.age.summary();
        let base_ns = self.probe.clock_base_ns();
        for a in &mut ages {
            let clock = self.probe.clock(a.source);
            a.absolute = clock.and_then(|c| self.age.absolute(a, &c, base_ns));
        }
        let hints = age::queue_hints(&ages, |id| {
            let c = self.sequences.source(id)?.counts();
            Some((c.received, c.lost))
        });
        (ages, hints)
    }

    pub(crate) fn new(cfg: &SessionConfig, probe: P) -> Self {
        let timeout = cfg.timeout.as_nanos() as Nanos;
        EchoDriver {
            sequences: SourceTable::new(None, DEFAULT_MAX_SOURCES),
            sequence_ticks: Ticks::default(),
            probe,
            ours: cfg.ours,
            first_seq: cfg.first_seq,
            timeout,
            matcher: Matcher::new(timeout, cfg.capacity, cfg.first_seq).with_window(cfg.window),
            events: Vec::new(),
            foreign_replies: 0,
            paths: HashMap::new(),
            wrong_path_replies: 0,
            pacing: Pacing::default(),
            outbox: Outbox::default(),
            burst: Vec::with_capacity(MAX_BURST),
            clocks_told: HashMap::new(),
            clocks_due: Vec::new(),
            age: AgeTracker::default(),
            splits: HashMap::new(),
            aged_splits: HashMap::new(),
        }
    }

    fn on_reply(
        &mut self,
        frame: &Frame,
        lookup: crate::engine::matcher::Lookup,
        path: PathId,
        at: Nanos,
    ) {
        // A reply naming a responder that answered from another peer of
        // this link (a spoofed id, or one system heard through two routers)
        // is counted, never measured.
        let timeout = self.timeout;
        if self
            .paths
            .get(&frame.source)
            .is_some_and(|&(p, last)| p != path && at < last.saturating_add(timeout))
        {
            self.wrong_path_replies += 1;
            return;
        }
        let before = self.events.len();
        let events = &mut self.events;
        self.matcher
            .on_reply(frame.source, lookup, at, &mut |e| events.push(e));
        // Only an accepted in-time reply feeds the probe.
        for i in before..self.events.len() {
            if let MatchEvent::Reply {
                responder,
                sent_at,
                at,
                ..
            } = self.events[i]
            {
                if responder == frame.source {
                    self.probe.on_reply(frame, sent_at, at);
                    self.split(frame, sent_at, at);
                    if self.probe.measures_clocks() {
                        self.clock_may_be_due(responder, at);
                    }
                    // Bound by accepted replies only, so stale forgeries
                    // cannot claim an id.
                    if self.paths.len() < MAX_RESPONDERS || self.paths.contains_key(&responder) {
                        self.paths.insert(responder, (path, at));
                    }
                }
            }
        }
    }
}

impl<P: EchoProbe> EchoDriver<P> {
    /// The responders' figures so far, each named by its probe where
    /// responders may differ in it.
    fn summaries(&self, roster: &Roster) -> Vec<crate::engine::summary::ResponderSummary> {
        let mut responders = responder_summaries(&self.matcher, roster);
        for r in &mut responders {
            r.probe = self.probe.used_by(r.id);
        }
        responders
    }

    /// Requests sent so far, and the replies `target`'s system gave
    /// (late ones too: they came).
    pub(crate) fn answered_by(&self, roster: &Roster, target: SysComp) -> (u64, u64) {
        let answered = self
            .summaries(roster)
            .iter()
            .filter(|r| r.id.sysid == target.sysid)
            .map(|r| r.counts.received + r.counts.late)
            .sum();
        (self.matcher.issued(), answered)
    }

    fn clock_may_be_due(&mut self, responder: SysComp, at: Nanos) {
        let due = match self.clocks_told.get(&responder) {
            Some(&told) => at >= told.saturating_add(CLOCK_TOLD_EVERY),
            None => self.clocks_told.len() < MAX_RESPONDERS,
        };
        if due {
            self.clocks_told.insert(responder, at);
            self.clocks_due.push((responder, at));
        }
    }
}

impl<P: EchoProbe> Driver for EchoDriver<P> {
    fn start_info(&self, cfg: &SessionConfig) -> StartInfo {
        StartInfo {
            link: cfg.link_name.clone(),
            probe: self.probe.name(),
            ours: cfg.ours,
            interval: cfg.interval,
            timeout: cfg.timeout,
            count: cfg.count,
            plan: cfg
                .sweep
                .clone()
                .map(|plan| Arc::new(plan) as Arc<dyn KindValue + Send + Sync>),
        }
    }

    fn begin(&mut self, wall_at_zero: WallAtZero) {
        self.probe.begin(wall_at_zero);
    }

    async fn send_due<T: Transport>(
        &mut self,
        schedule: &mut Schedule,
        link: &mut T,
        sender: &mut Sender,
        clock: &Clock,
    ) -> Result<(), LinkError> {
        // At most a burst per turn: a machine too slow for the rate falls
        // behind (and the lateness figures say so) but still reads replies
        // and honours the deadline between bursts.
        let now = clock.now();
        let issued = self.matcher.issued();
        self.outbox.clear();
        self.burst.clear();
        while self.burst.len() < MAX_BURST {
            let Some((_, planned)) = schedule.take_due(now) else {
                break;
            };
            let token = self.probe.token(now);
            let seq = self
                .first_seq
                .wrapping_add((issued + self.burst.len() as u64) as u32);
            let request = self.probe.request(seq, token);
            self.outbox.push(sender.frame(&request), To::Every);
            let second = self.probe.second_request(seq, token);
            if let Some(second) = &second {
                self.outbox.push(sender.frame(second), To::Every);
            }
            self.burst
                .push((planned, token, 1 + u8::from(second.is_some())));
        }
        if self.burst.is_empty() {
            return Ok(());
        }
        // Requests due together leave together, with one system call where
        // the link allows, and share the stamp taken before the first write.
        let refused_before = link.refused();
        let sent = clock.ns(link.send_all(&self.outbox).await?);
        // A link whose peer stopped reading refuses the tail of a burst:
        // those requests never left, so they are neither sent nor lost (a
        // request of two frames left only if both did).
        let refused_frames = link.refused() - refused_before;
        let accepted = accepted_requests(&self.burst, refused_frames);
        let events = &mut self.events;
        for &(planned, token, _) in &self.burst[..accepted] {
            self.pacing.sent(planned, sent);
            self.matcher.on_send(token, sent, &mut |e| events.push(e));
        }
        for &(planned, _, _) in &self.burst[accepted..] {
            self.pacing.refused(planned, sent);
        }
        Ok(())
    }

    fn expire(&mut self, now: Nanos) {
        let events = &mut self.events;
        self.matcher.expire(now, &mut |e| events.push(e));
        self.sequence_ticks.expire(now);
    }

    fn on_received(&mut self, frame: &Frame, _path: PathId, at: Nanos) {
        // HEARTBEATs included: the auto probe chooses by them.
        self.probe.heard(frame, self.ours);
        passive_driver::take(&mut self.sequences, frame, at);
        if frame.source != self.ours {
            self.age.on_frame(frame, at);
        }
    }

    fn on_frame(&mut self, frame: &Frame, path: PathId, at: Nanos) {
        match self.probe.classify(frame, self.ours) {
            Classified::Reply(lookup) => self.on_reply(frame, lookup, path, at),
            Classified::ForeignReply => self.foreign_replies += 1,
            Classified::NotAReply => {}
        }
    }

    fn report(&mut self, radios: &mut Radios, observer: &mut dyn Observer) -> io::Result<()> {
        // Outcomes against the radio's buffer, for the "overloaded" hint.
        let events = self.events.drain(..).inspect(|e| match *e {
            MatchEvent::Reply { sent_at, .. } => radios.outcome(false, sent_at),
            MatchEvent::Lost { sent_at, .. } => radios.outcome(true, sent_at),
            _ => {}
        });
        let matched = tell_kind(observer, events);
        let probe = &self.probe;
        let clocks = self.clocks_due.drain(..).filter_map(|(id, at)| {
            Some(Event::Clock {
                id,
                at,
                clock: probe.clock(id)?,
            })
        });
        let told = tell_each(observer, clocks);
        let sources = tell_sources(
            &self.sequences,
            &mut self.age,
            &mut self.sequence_ticks,
            observer,
        );
        matched.and(told).and(sources)
    }

    fn next_deadline(&self) -> Option<Nanos> {
        let tick = self.sequence_ticks.next_deadline();
        Some(self.matcher.next_deadline().map_or(tick, |d| d.min(tick)))
    }

    fn interim(&self, roster: &Roster, at: Nanos) -> Option<Interim> {
        Some(Interim::new(EchoInterim {
            at,
            requests: self.matcher.issued(),
            responders: self.summaries(roster),
        }))
    }

    fn settled(&self) -> bool {
        self.matcher.next_deadline().is_none() || self.matcher.all_answered()
    }

    fn requests(&self) -> Option<u64> {
        Some(self.matcher.issued())
    }

    fn finish(mut self, ended: SessionEnd<'_>) -> (LinkSummary, Vec<(SysComp, RttStats)>) {
        let cfg = ended.cfg;
        let undecided = self.matcher.undecided();
        let in_flight = self.matcher.finish();
        let mut responders = self.summaries(&ended.roster);
        let (age, queue_hints) = self.ages(&mut responders);
        for r in &mut responders {
            r.clock = self.probe.clock(r.id);
            r.direction = self.sequences.source(r.id).and_then(|s| {
                Direction::of_sequence(r.loss_ratio, r.counts.sent, r.counts.late, &s.counts())
            });
        }
        let loss_by_txbuf = ended.radios.loss_by_txbuf();
        let radios = ended.radios.summaries();
        let radio_ids: Vec<SysComp> = radios.iter().map(|r| r.id).collect();
        let name = self.probe.name();
        let signing = ended.gate.summary();
        let mut hints = diagnose(&Observed {
            link: &cfg.link_name,
            kind: ended.kind,
            probe: name,
            ours: self.ours,
            version: cfg.version,
            key: signing.key,
            signing: signing.counts,
            frames: ended.frames,
            unreachable: ended.unreachable,
            roster: &ended.roster,
            responders: &responders,
            radios: &radio_ids,
            requests: self.matcher.issued(),
            undecided,
            timeout: cfg.timeout,
            no_peer_within: ended.no_peer_within,
            link_failed: ended.link_error.is_some(),
        });
        if let Some(p) = self.pacing.summary(cfg.interval).filter(|p| p.not_sent > 0) {
            hints.insert(0, not_reading(&cfg.link_name, &p, self.matcher.issued()));
        }
        hints.extend(radio_hints(&radios, loss_by_txbuf));
        hints.extend(queue_hints);
        let mut link_node = ended.link_nodes.summaries();
        hints.extend(compare_uplink(&mut link_node, &responders));
        hints.extend(responders.iter().filter_map(|r| {
            let clock = r.clock.filter(|c| c.bounds_ns.is_none())?;
            Some(Hint::new(
                HintCode::ClockInconsistent,
                format!(
                    "{}: the causal bounds of its clock offset do not intersect: a clock stepped \
                     during the run, it stamps TIMESYNC outside its receive-reply window, or the \
                     clocks' rates differ by more than {} ppm",
                    r.id, clock.bounds_drift_limit_ppm
                ),
            ))
        }));
        let summary = EchoSummary {
            link: cfg.link_name.clone(),
            probe: name,
            ours: self.ours,
            duration_s: ended.duration_s,
            requests: self.matcher.issued(),
            in_flight,
            no_peer_heard_s: ended.no_peer_within.map(|d| d.as_secs_f64()),
            responders,
            foreign_replies: self.foreign_replies,
            wrong_path_replies: self.wrong_path_replies,
            untracked_replies: self.matcher.untracked(),
            frames: ended.frames,
            hints,
            interrupted: ended.interrupted,
            link_error: ended.link_error,
            downtime_s: ended.downtime_s,
            schedule: self.pacing.summary(cfg.interval),
            rx_clock: ended.rx_clock,
            radios,
            link_node,
            wire: None,
            signing,
            answered: ended.answered,
            age,
            sweep: None,
        };
        // Moved, not copied: a thousand responders' histograms are tens
        // of MiB.
        let histograms = self
            .matcher
            .into_responders()
            .into_iter()
            .map(|r| (r.id, r.rtt))
            .collect();
        (LinkSummary::new(summary), histograms)
    }
}

/// How many of a burst's requests left whole when the link refused the
/// last `refused_frames` of its frames.
fn accepted_requests(burst: &[(Nanos, u64, u8)], refused_frames: u64) -> usize {
    let frames: u64 = burst.iter().map(|&(_, _, n)| u64::from(n)).sum();
    let mut left = frames.saturating_sub(refused_frames);
    burst
        .iter()
        .take_while(|&&(_, _, n)| {
            let whole = left >= u64::from(n);
            left = left.saturating_sub(u64::from(n));
            whole
        })
        .count()
}

/// The link refused requests: what it took, of what was asked.
fn not_reading(link: &str, p: &ScheduleSummary, sent: u64) -> Hint {
    Hint::new(
        HintCode::LinkNotReading,
        format!(
            "{link} took only {sent} of {} requests ({:.1}/s of {:.1}/s): its peer is not \
             reading what we send (a pty or serial port nobody reads, flow control held off, \
             a TCP peer that stopped reading)",
            sent + p.not_sent,
            p.achieved_rate_hz,
            p.requested_rate_hz
        ),
    )
}

/// How well requests kept to their schedule: achieved rate and how late
/// each went out against its planned time. Late sends mean the machine,
/// not the link, was the bottleneck.
#[derive(Default)]
struct Pacing {
    /// The first and last attempt to send, taken or refused.
    first: Option<Nanos>,
    last: Nanos,
    count: u64,
    /// Requests the link refused (its peer is not reading).
    refused: u64,
    lateness: RttStats,
}

impl Pacing {
    fn sent(&mut self, planned: Nanos, actual: Nanos) {
        self.attempted(actual);
        self.count += 1;
        self.lateness.record(actual.saturating_sub(planned));
    }

    fn refused(&mut self, _planned: Nanos, at: Nanos) {
        self.attempted(at);
        self.refused += 1;
    }

    fn attempted(&mut self, at: Nanos) {
        self.first.get_or_insert(at);
        self.last = at;
    }

    fn summary(&self, interval: Duration) -> Option<ScheduleSummary> {
        let first = self.first?;
        let late = self.lateness.summary()?;
        let span = self.last.saturating_sub(first) as f64 / 1e9;
        // Over the span of every attempt, so a link that took a burst and
        // then nothing shows the rate it really took.
        let attempts = self.count + self.refused;
        Some(ScheduleSummary {
            requested_rate_hz: 1.0 / interval.as_secs_f64(),
            achieved_rate_hz: if attempts > 1 && span > 0.0 {
                (attempts - 1) as f64 * (self.count as f64 / attempts as f64) / span
            } else {
                0.0
            },
            not_sent: self.refused,
            lateness_p50_us: late.p50_us,
            lateness_p99_us: late.p99_us,
            lateness_max_us: late.max_us,
        })
    }
}
