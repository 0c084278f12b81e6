//! `--passive` in the session: no probes, every admitted frame handed to
//! the pure [`SourceTable`], and at the end one summary per source.
//!
//! The session still sends our HEARTBEAT (where a router or vehicle only
//! sends to what it has heard) unless `--no-heartbeat`, hears systems and
//! radios, and ends on the deadline, Ctrl-C or a link failure.

use std::io;
use std::time::Duration;

use super::ticks::Ticks;
use super::tracker::{SourceTable, DEFAULT_MAX_SOURCES};
use crate::engine::link_io::{Clock, Sender};
use crate::engine::observe::{Event, Observer, RunKind, StartInfo};
use crate::engine::radio::Radios;
use crate::engine::roster::{Identity, Roster};
use crate::engine::schedule::Schedule;
use crate::engine::session::{self, Controls, Driver, Measurement, SessionEnd};
use crate::engine::stats::RttStats;
use crate::engine::summary::passive::{PassiveSummary, TableSummary};
use crate::engine::summary::{Interim, LinkSummary, PassiveInterim, ProbeName};
use crate::engine::{Nanos, SessionConfig};
use crate::frame::{Frame, SysComp};
use crate::transport::{LinkError, PathId, Transport};

/// Listens on `link` until the run ends.
pub async fn run<T: Transport>(
    cfg: &SessionConfig,
    gap: Option<Duration>,
    link: &mut T,
    observer: &mut dyn Observer,
    controls: &Controls,
) -> Measurement {
    session::run(cfg, link, PassiveDriver::new(cfg, gap), observer, controls).await
}

pub struct PassiveDriver {
    ours: SysComp,
    table: SourceTable,
    /// Frames with our own ids (a router echoing ours back): not a source.
    own_frames: u64,
    ticks: Ticks,
}

impl PassiveDriver {
    pub fn new(cfg: &SessionConfig, gap: Option<Duration>) -> Self {
        let gap = gap.map(|g| Nanos::try_from(g.as_nanos()).unwrap_or(Nanos::MAX));
        PassiveDriver {
            ours: cfg.ours,
            table: SourceTable::new(gap, DEFAULT_MAX_SOURCES),
            own_frames: 0,
            ticks: Ticks::default(),
        }
    }
}

/// Tells `observer` the table, if a telling is due.
pub(crate) fn tell_sources(
    table: &SourceTable,
    ticks: &mut Ticks,
    observer: &mut dyn Observer,
) -> io::Result<()> {
    match ticks.take() {
        Some(at) => observer.event(&Event::Sources {
            at,
            table: &table.summary(at),
        }),
        None => Ok(()),
    }
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
            run: RunKind::Passive {
                heartbeat: cfg.heartbeat,
            },
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
    }

    fn on_received(&mut self, frame: &Frame, at: Nanos) {
        if frame.source == self.ours {
            self.own_frames += 1;
            return;
        }
        let len = usize::from(frame.len);
        self.table
            .on_frame(frame.source, frame.packet_seq, frame.msgid, len, at);
    }

    fn on_frame(&mut self, _frame: &Frame, _path: PathId, _at: Nanos) {}

    fn report(&mut self, _radios: &mut Radios, observer: &mut dyn Observer) -> io::Result<()> {
        tell_sources(&self.table, &mut self.ticks, observer)
    }

    fn next_deadline(&self) -> Option<Nanos> {
        Some(self.ticks.next_deadline())
    }

    /// Listening ends on the deadline, Ctrl-C or a failure, never by itself.
    fn settled(&self) -> bool {
        false
    }

    fn finish(self, end: SessionEnd<'_>) -> (LinkSummary, Vec<(SysComp, RttStats)>) {
        let at = (end.duration_s * 1e9) as Nanos;
        let table = self.table.summary(at);
        let identities = identities(&table, &end.roster);
        let summary = PassiveSummary {
            link: end.cfg.link_name.clone(),
            ours: end.cfg.ours,
            heartbeat: end.cfg.heartbeat,
            duration_s: end.duration_s,
            table,
            identities,
            own_frames: self.own_frames,
            radios: end.radios.summaries(),
            frames: end.frames,
            rx_clock: end.rx_clock,
            interrupted: end.interrupted,
            link_error: end.link_error,
            signing: end.gate.summary(),
        };
        (LinkSummary::Passive(Box::new(summary)), Vec::new())
    }

    /// Every source's figures as of `at`, as the summary would give them.
    fn interim(&self, roster: &Roster, at: Nanos) -> Option<Interim> {
        let table = self.table.summary(at);
        Some(Interim::Passive(PassiveInterim {
            at,
            identities: identities(&table, roster),
            table,
        }))
    }
}
