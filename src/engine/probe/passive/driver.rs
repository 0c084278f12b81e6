//! `--passive` in the session: no probes, every admitted frame handed to
//! the pure [`SourceTable`], and at the end one summary per source.
//!
//! The session still sends our HEARTBEAT (where a router or vehicle only
//! sends to what it has heard) unless `--no-heartbeat`, hears systems and
//! radios, and ends on the deadline, Ctrl-C or a link failure. Reading a
//! telemetry log, it sends nothing, keeps a table per path (the stamps'
//! MAVProxy link bits) beside the table of all frames, and ends with the
//! log.

use std::io;
use std::sync::Arc;
use std::time::Duration;

use super::flight::{self, Flight, Totals};
use super::ground::GroundIds;
use super::links;
use super::round_trips::RoundTrips;
use super::ticks::Ticks;
use super::tracker::{SourceTable, DEFAULT_MAX_SOURCES};
use super::{PassivePlan, SourcesNow};
use crate::engine::age::{self, AgeTracker, SourceAge};
use crate::engine::link_io::{Clock, Sender};
use crate::engine::observe::{Event, Observer, StartInfo};
use crate::engine::radio::Radios;
use crate::engine::roster::{Identity, Roster};
use crate::engine::schedule::Schedule;
use crate::engine::session::{self, Controls, Driver, Measurement, SessionEnd};
use crate::engine::stats::RttStats;
use crate::engine::summary::passive::{PassiveSummary, PerLink, SeqCounts, TableSummary};
use crate::engine::summary::{Interim, LinkSummary, PassiveInterim, ProbeName};
use crate::engine::{Nanos, SessionConfig};
use crate::frame::{Frame, Msg, SysComp};
use crate::transport::{LinkError, PathId, Transport};

/// Listens on `link` until the run ends.
pub(crate) async fn run<T: Transport>(
    cfg: &SessionConfig,
    gap: Option<Duration>,
    link: &mut T,
    observer: &mut dyn Observer,
    controls: &Controls,
) -> Measurement {
    session::run(cfg, link, PassiveDriver::new(cfg, gap), observer, controls).await
}

pub(crate) struct PassiveDriver {
    ours: SysComp,
    table: SourceTable,
    /// Frames with our own ids (a router echoing ours back): not a source.
    own_frames: u64,
    ticks: Ticks,
    /// Reading a telemetry log: a table per path (the stamps' two low
    /// bits, MAVProxy's link number), for [`links::per_link`].
    paths: Option<Paths>,
    /// Reading a telemetry log: requests matched to replies by their
    /// stamps, our own ids' requests included (a log mavping recorded).
    round_trips: Option<RoundTrips>,
    /// Reading a telemetry log: the flight's timeline.
    flight: Option<Flight>,
    /// Reading a telemetry log: which sources are the recording ground
    /// station's own frames.
    ground: Option<GroundIds>,
    /// How old each source's frames are, from their own clock stamps.
    age: AgeTracker,
}

/// The tables per path of a log.
enum Paths {
    /// Every frame so far came by path 0: its table is the table of all
    /// frames, so none is kept (most logs: QGroundControl's, pymavlink's).
    AllZero,
    /// Since the first frame by another path: one table each.
    Split(Box<[SourceTable; 4]>),
}

impl PassiveDriver {
    pub(crate) fn new(cfg: &SessionConfig, gap: Option<Duration>) -> Self {
        let gap = gap.map(|g| Nanos::try_from(g.as_nanos()).unwrap_or(Nanos::MAX));
        PassiveDriver {
            ours: cfg.ours,
            table: SourceTable::new(gap, DEFAULT_MAX_SOURCES),
            own_frames: 0,
            ticks: Ticks::default(),
            paths: None,
            round_trips: None,
            flight: None,
            ground: None,
            age: AgeTracker::default(),
        }
    }

    /// The ages of the sources that are not the ground station's own.
    fn source_ages(&self, table: &TableSummary) -> Vec<SourceAge> {
        let ground = |id: SysComp| table.sources.iter().any(|r| r.source == id && r.ground);
        let mut ages = self.age.summary();
        ages.retain(|a| !ground(a.source));
        ages
    }

    /// A log's figures per MAVProxy link, when its stamps carry them.
    fn per_link(&self, table: &TableSummary, at: Nanos) -> Option<PerLink> {
        match &self.paths {
            Some(Paths::Split(paths)) => {
                let by_path: Vec<_> = paths.iter().map(|t| t.summary(at)).collect();
                links::per_link(table, &by_path)
            }
            // All by path 0, or not a log: no links to tell apart.
            Some(Paths::AllZero) | None => None,
        }
    }

    /// Marks `source` as the ground station's in every table.
    fn mark_ground(&mut self, source: SysComp) {
        self.table.set_ground(source);
        if let Some(Paths::Split(tables)) = &mut self.paths {
            for t in tables.iter_mut() {
                t.set_ground(source);
            }
        }
    }

    /// The driver of a telemetry log: also a table per MAVProxy link.
    pub(crate) fn for_log(cfg: &SessionConfig, gap: Option<Duration>) -> Self {
        let silence = gap.map_or(flight::DEFAULT_SILENCE_NS, |g| {
            Nanos::try_from(g.as_nanos()).unwrap_or(Nanos::MAX)
        });
        PassiveDriver {
            paths: Some(Paths::AllZero),
            round_trips: Some(RoundTrips::new(
                Nanos::try_from(cfg.timeout.as_nanos()).unwrap_or(Nanos::MAX),
            )),
            flight: Some(Flight::new(
                flight::DEFAULT_WINDOW_NS,
                silence,
                cfg.radio_type,
            )),
            ground: Some(GroundIds::default()),
            ..Self::new(cfg, gap)
        }
    }

    /// Closes the flight's windows that end by `at`, with the table as it
    /// stands before anything at `at` is taken.
    fn close_windows(&mut self, at: Nanos) {
        let Some(f) = &mut self.flight else { return };
        while f.due(at) {
            f.close(totals(&self.table, at));
        }
    }

    /// Takes a frame into the table of its path.
    fn by_path(&mut self, frame: &Frame, path: PathId, at: Nanos) {
        let Some(paths) = &mut self.paths else { return };
        if path == 0 && matches!(paths, Paths::AllZero) {
            return;
        }
        if matches!(paths, Paths::AllZero) {
            // Every frame before this one came by path 0.
            let gap = self.table.gap();
            let mut split: [SourceTable; 4] =
                std::array::from_fn(|_| SourceTable::new(gap, DEFAULT_MAX_SOURCES));
            split[0] = self.table.clone();
            *paths = Paths::Split(Box::new(split));
        }
        let Paths::Split(tables) = paths else { return };
        if let Some(t) = tables.get_mut(path as usize) {
            take(t, frame, at);
        }
    }
}

/// Takes a frame into `table`: a damaged one fills its number only.
#[inline]
pub(crate) fn take(table: &mut SourceTable, frame: &Frame, at: Nanos) {
    let (seq, id, len) = (frame.packet_seq, frame.msgid, usize::from(frame.len));
    if matches!(frame.msg, Msg::Damaged) {
        table.on_damaged(frame.source, seq, id, len, at);
    } else {
        table.on_frame(frame.source, seq, id, len, at);
    }
}

/// The link's totals, for the flight's windows.
fn totals(table: &SourceTable, at: Nanos) -> Totals {
    totals_of(&table.summary(at).totals.counts)
}

/// The figures of `c` the flight's windows count. (The flight module
/// names no summary type: the summary names the flight's.)
fn totals_of(c: &SeqCounts) -> Totals {
    Totals {
        received: c.received,
        duplicate: c.duplicate,
        lost: c.lost,
    }
}

/// Tells `observer` the flight's events closed since the last telling.
fn tell_flight(flight: Option<&mut Flight>, observer: &mut dyn Observer) -> io::Result<()> {
    let Some(f) = flight else { return Ok(()) };
    let mut result = Ok(());
    for e in f.drain() {
        if result.is_ok() {
            result = observer.event(&Event::Kind(&e));
        }
    }
    result
}

/// Tells `observer` the table, if a telling is due.
pub(crate) fn tell_sources(
    table: &SourceTable,
    age: &mut AgeTracker,
    ticks: &mut Ticks,
    observer: &mut dyn Observer,
) -> io::Result<()> {
    let Some(at) = ticks.take() else {
        return Ok(());
    };
    let table = table.summary(at);
    let ages = table
        .sources
        .iter()
        .filter_map(|s| Some((s.source, age.now(s.source)?)))
        .collect();
    let age_counts = table
        .sources
        .iter()
        .filter_map(|s| Some((s.source, age.counts(s.source)?)))
        .collect();
    observer.event(&Event::Kind(&SourcesNow {
        at,
        table,
        ages,
        age_counts,
        age_max: age.take_window_max(),
    }))
}

/// What each source of `table` said it is, from its HEARTBEAT.
fn identities(table: &TableSummary, roster: &Roster) -> Vec<(SysComp, Identity)> {
    table
        .sources
        .iter()
        .filter_map(|s| roster.get(s.source).map(|i| (s.source, i.clone())))
        .collect()
}

impl Driver for PassiveDriver {
    fn start_info(&self, cfg: &SessionConfig) -> StartInfo {
        StartInfo {
            link: cfg.link_name.clone(),
            probe: ProbeName::Passive,
            ours: cfg.ours,
            interval: cfg.interval,
            timeout: cfg.timeout,
            count: None,
            plan: Some(Arc::new(PassivePlan {
                heartbeat: cfg.heartbeat,
                log: self.paths.is_some(),
            })),
        }
    }

    fn sends(&self) -> bool {
        false
    }

    async fn send_due<T: Transport>(
        &mut self,
        _schedule: &mut Schedule,
        _link: &mut T,
        _sender: &mut Sender,
        _clock: &Clock,
    ) -> Result<(), LinkError> {
        Ok(())
    }

    fn expire(&mut self, now: Nanos) {
        self.ticks.expire(now);
        self.close_windows(now);
    }

    fn on_received(&mut self, frame: &Frame, path: PathId, at: Nanos) {
        if let Some(rt) = &mut self.round_trips {
            rt.on_frame(frame, at);
        }
        // A log read sends nothing, so nothing in it is an echo of ours:
        // frames with our ids there are a source (`--tlog` records
        // mavping's own frames as 250/190).
        if frame.source == self.ours && self.paths.is_none() {
            self.own_frames += 1;
            return;
        }
        let ground = self.ground.as_mut().is_some_and(|g| g.sees(frame));
        if ground {
            self.mark_ground(frame.source);
        }
        // Before the table of all frames takes it: a first frame by another
        // path copies that table as path 0's.
        self.by_path(frame, path, at);
        self.close_windows(at);
        // What the ground station sent is not what it heard: never
        // "heard" for the flight's silences.
        if let Some(f) = self.flight.as_mut().filter(|_| !ground) {
            f.on_received(frame, at);
        }
        take(&mut self.table, frame, at);
        let age = self.age.on_frame(frame, at);
        if let (Some(f), Some(age)) = (self.flight.as_mut().filter(|_| !ground), age) {
            f.age(frame.source, age);
        }
    }

    fn on_frame(&mut self, _frame: &Frame, _path: PathId, _at: Nanos) {}

    fn report(&mut self, _radios: &mut Radios, observer: &mut dyn Observer) -> io::Result<()> {
        let flight = tell_flight(self.flight.as_mut(), observer);
        flight.and(tell_sources(
            &self.table,
            &mut self.age,
            &mut self.ticks,
            observer,
        ))
    }

    fn next_deadline(&self) -> Option<Nanos> {
        Some(self.ticks.next_deadline())
    }

    /// Listening ends on the deadline, Ctrl-C or a failure, never by itself.
    fn settled(&self) -> bool {
        false
    }

    fn finish(mut self, end: SessionEnd<'_>) -> (LinkSummary, Vec<(SysComp, RttStats)>) {
        let at = (end.duration_s * 1e9) as Nanos;
        let mut table = self.table.summary(at);
        let mut per_link = self.per_link(&table, at);
        // With links shown, what only MAVProxy's link 3 carried is what it
        // sent itself: marked, and the tables told again with it.
        if let Some(own) = per_link.as_ref().map(links::sent_by_mavproxy) {
            for source in own {
                self.mark_ground(source);
            }
            table = self.table.summary(at);
            per_link = self.per_link(&table, at);
        }
        let identities = identities(&table, &end.roster);
        let age = self.source_ages(&table);
        // A log's stamps are when the logger wrote, in batches (FIELD-NOTES):
        // a late frame there may be the logger's, so no hint says queue.
        let hints = match self.paths {
            None => age::queue_hints(&age, |id| {
                let row = table.sources.iter().find(|r| r.source == id)?;
                Some((row.counts.received, row.counts.lost))
            }),
            Some(_) => Vec::new(),
        };
        let flight = self
            .flight
            .as_ref()
            .map(|f| f.summary(at, totals_of(&table.totals.counts)));
        let summary = PassiveSummary {
            link: end.cfg.link_name.clone(),
            ours: end.cfg.ours,
            heartbeat: end.cfg.heartbeat,
            duration_s: end.duration_s,
            table,
            identities,
            own_frames: self.own_frames,
            radios: end.radios.summaries(),
            link_node: end.link_nodes.summaries(),
            frames: end.frames,
            rx_clock: end.rx_clock,
            interrupted: end.interrupted,
            link_error: end.link_error,
            signing: end.gate.summary(),
            answered: end.answered,
            age,
            hints,
            log: None,
            per_link,
            round_trips: self.round_trips.as_mut().map(|rt| rt.summary(at)),
            flight,
        };
        (LinkSummary::new(summary), Vec::new())
    }

    /// Every source's figures as of `at`, as the summary would give them.
    fn interim(&self, roster: &Roster, at: Nanos) -> Option<Interim> {
        let table = self.table.summary(at);
        Some(Interim::new(PassiveInterim {
            at,
            identities: identities(&table, roster),
            ages: self.source_ages(&table),
            table,
        }))
    }
}
