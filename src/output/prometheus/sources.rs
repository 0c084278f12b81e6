//! Each source's packet-sequence figures as Prometheus shows them: the
//! table the engine tells once a second is cumulative, so counters are
//! set from it, never added to; they never go down (a loss a late frame
//! may still fill waits outside `mavping_source_lost_total` until it
//! cannot); and a continuous link's earlier sessions are carried, so its
//! counters go on across reopenings. At most [`MAX_SOURCES`] sources a
//! link, whatever the run length.

use std::collections::BTreeMap;

use crate::engine::age::AgeCounts;
use crate::engine::probe::passive::tracker::DEFAULT_MAX_SOURCES;
use crate::engine::probe::passive::SourcesNow;
use crate::engine::summary::passive::{SeqCounts, SourceSummary, TableSummary};
use crate::engine::Nanos;
use crate::frame::SysComp;

/// Sources kept per link: the engine's table cap, and the radio.
pub(super) const MAX_SOURCES: usize = DEFAULT_MAX_SOURCES + 1;

/// What only grows for one source.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub(super) struct Figures {
    /// The sequence's counts as the table said them (`lost` may still
    /// move to `reordered`).
    pub(crate) seq: SeqCounts,
    /// What a counter of losses shows: `lost` less what may still be
    /// filled (all of it once the session has ended).
    pub(crate) lost_settled: u64,
    pub(crate) bytes: u64,
    pub(crate) silences: u64,
    pub(crate) silence_ns: Nanos,
    pub(crate) pymav_count: u64,
    pub(crate) pymav_loss: u64,
}

impl Figures {
    /// `pending`: the losses a late frame may still fill.
    fn of(s: &SourceSummary, pending: u64) -> Self {
        Figures {
            seq: s.counts,
            lost_settled: s.counts.lost.saturating_sub(pending),
            bytes: s.bytes,
            silences: s.silence_count,
            silence_ns: s.silence_ns,
            pymav_count: s.pymav.count,
            pymav_loss: s.pymav.loss,
        }
    }

    /// Field by field, the larger: a counter's value never goes back
    /// (an ongoing silence measured to a tick can end a little before it,
    /// by a frame read after the tick but stamped before).
    fn max(self, o: Figures) -> Figures {
        self.zip(o, u64::max)
    }

    fn plus(self, o: Figures) -> Figures {
        self.zip(o, u64::saturating_add)
    }

    /// `f` of the two, field by field.
    fn zip(self, o: Figures, f: fn(u64, u64) -> u64) -> Figures {
        let seq = |g: fn(&SeqCounts) -> u64| f(g(&self.seq), g(&o.seq));
        Figures {
            seq: SeqCounts {
                received: seq(|c| c.received),
                damaged: seq(|c| c.damaged),
                lost: seq(|c| c.lost),
                duplicate: seq(|c| c.duplicate),
                reordered: seq(|c| c.reordered),
                resyncs: seq(|c| c.resyncs),
            },
            lost_settled: f(self.lost_settled, o.lost_settled),
            bytes: f(self.bytes, o.bytes),
            silences: f(self.silences, o.silences),
            silence_ns: f(self.silence_ns, o.silence_ns),
            pymav_count: f(self.pymav_count, o.pymav_count),
            pymav_loss: f(self.pymav_loss, o.pymav_loss),
        }
    }
}

/// The latest table's figures that are not counters.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Latest {
    figures: Figures,
    pending: u64,
    frames_per_s: Option<f64>,
    silent: bool,
}

/// One source on one link.
#[derive(Debug, Clone, Default)]
pub(super) struct SourceSeries {
    /// The SiK radio's own RADIO_STATUS source (51/68).
    pub(crate) radio: bool,
    /// Earlier sessions of a continuous link, summed.
    carried: Figures,
    /// This session's counters as last shown.
    shown: Figures,
    /// This session's latest table, if the source was heard in it.
    latest: Option<Latest>,
    /// How much later than its quickest its newest stamped frame came
    /// (seconds), if its frames carry a clock stamp...
    pub(crate) age_s: Option<f64>,
    /// ...and all its frames' ages so far, counted.
    pub(crate) age_counts: Option<AgeCounts>,
}

impl SourceSeries {
    fn update(&mut self, s: &SourceSummary, ended: bool) {
        let pending = if ended { 0 } else { s.lost_pending };
        let figures = Figures::of(s, pending);
        self.radio = s.radio;
        self.shown = self.shown.max(figures);
        self.latest = Some(Latest {
            figures,
            pending,
            frames_per_s: s.frames_per_s,
            silent: s.silences.last().is_some_and(|x| x.ongoing),
        });
    }

    /// A new session: this one's figures become history.
    pub(super) fn carry(&mut self) {
        let last = self.latest.map_or(Figures::default(), |l| l.figures);
        // Every pending loss settled: what a session that has ended proved.
        let settled = Figures {
            lost_settled: last.seq.lost,
            ..last
        };
        self.carried = self.carried.plus(self.shown.max(settled));
        self.shown = Figures::default();
        self.latest = None;
    }

    /// The counters, earlier sessions included.
    pub(super) fn counters(&self) -> Figures {
        self.carried.plus(self.shown)
    }

    /// The figures as last told, earlier sessions included (a ratio's
    /// or the direction split's input: `lost` is not settled).
    fn told(&self) -> Figures {
        let latest = self.latest.map_or(Figures::default(), |l| l.figures);
        self.carried.plus(latest)
    }

    /// The sequence as last told, earlier sessions included.
    pub(super) fn seq(&self) -> SeqCounts {
        self.told().seq
    }

    /// Lost over the numbers the sequence accounts for.
    pub(super) fn loss_ratio(&self) -> Option<f64> {
        let seq = self.seq();
        let numbered = seq.numbered();
        (numbered > 0).then(|| seq.lost as f64 / numbered as f64)
    }

    /// pymavlink's `packet_loss()`, as a ratio: loss over count + loss.
    pub(super) fn pymav_loss_ratio(&self) -> Option<f64> {
        let told = self.told();
        let (count, loss) = (told.pymav_count, told.pymav_loss);
        (count + loss > 0).then(|| loss as f64 / (count + loss) as f64)
    }

    pub(super) fn pending(&self) -> Option<u64> {
        self.latest.map(|l| l.pending)
    }

    pub(super) fn frames_per_s(&self) -> Option<f64> {
        self.latest?.frames_per_s
    }

    /// Whether a silence is on now; `None` when not heard this session.
    pub(super) fn silent(&self) -> Option<bool> {
        self.latest.map(|l| l.silent)
    }
}

/// Every source of one link.
pub(super) type Sources = BTreeMap<SysComp, SourceSeries>;

/// The table as told at a tick (`ended` false) or at the end of the
/// session. Sources beyond [`MAX_SOURCES`] are left out.
/// Each source's age now and its ages counted, as told with the table.
pub(super) fn update_ages(sources: &mut Sources, now: &SourcesNow) {
    for (id, age) in &now.ages {
        if let Some(s) = sources.get_mut(id) {
            s.age_s = Some(age.age_ms / 1e3);
        }
    }
    for (id, counts) in &now.age_counts {
        if let Some(s) = sources.get_mut(id) {
            s.age_counts = Some(*counts);
        }
    }
}

pub(super) fn update(sources: &mut Sources, table: &TableSummary, ended: bool) {
    for s in &table.sources {
        if sources.len() < MAX_SOURCES || sources.contains_key(&s.source) {
            sources.entry(s.source).or_default().update(s, ended);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::engine::probe::passive::tracker::SourceTable;

    const MS: Nanos = 1_000_000;
    const A: SysComp = SysComp::new(1, 1);

    /// A table fed `seqs` from source A, one every 20 ms from `t0`.
    fn feed(table: &mut SourceTable, seqs: &[u8], t0: Nanos) -> Nanos {
        let mut at = t0;
        for &s in seqs {
            table.on_frame(A, s, 30, 20, at);
            at += 20 * MS;
        }
        at - 20 * MS
    }

    #[test]
    fn a_late_frame_never_takes_a_counter_back() {
        let mut table = SourceTable::new(None, 4);
        let mut sources = Sources::default();
        // 3 and 4 skipped: counted lost, but either may still come.
        let at = feed(&mut table, &[0, 1, 2, 5, 6], 0);
        update(&mut sources, &table.summary(at), false);
        let a = sources.get(&A).unwrap();
        assert_eq!(a.seq().lost, 2);
        assert_eq!(a.counters().lost_settled, 0);
        assert_eq!(a.pending(), Some(2));
        assert_eq!(a.loss_ratio(), Some(2.0 / 7.0));
        // 3 comes late: reordered; the ratio drops, no counter does.
        let at = feed(&mut table, &[3], at + 5 * MS);
        update(&mut sources, &table.summary(at), false);
        let a = sources.get(&A).unwrap();
        assert_eq!((a.seq().lost, a.seq().reordered), (1, 1));
        assert_eq!(a.counters().lost_settled, 0);
        // The run ends: 4 is lost for good.
        update(&mut sources, &table.summary(at), true);
        let a = sources.get(&A).unwrap();
        assert_eq!(a.counters().lost_settled, 1);
        assert_eq!(a.counters().seq.received, 6);
        assert_eq!(a.pending(), Some(0));
    }

    #[test]
    fn a_new_session_carries_the_counters_on() {
        let mut sources = Sources::default();
        let mut first = SourceTable::new(None, 4);
        let at = feed(&mut first, &[0, 1, 3, 4], 0);
        update(&mut sources, &first.summary(at), false);
        assert_eq!(sources.get(&A).unwrap().counters().lost_settled, 0);
        // The link breaks and is reopened: the pending loss of the first
        // session is settled, and the second starts from there.
        sources.values_mut().for_each(SourceSeries::carry);
        let a = sources.get(&A).unwrap();
        assert_eq!(a.counters().lost_settled, 1);
        assert_eq!((a.silent(), a.frames_per_s()), (None, None));
        let mut second = SourceTable::new(None, 4);
        let at = feed(&mut second, &[200, 202, 203], 0);
        update(&mut sources, &second.summary(at + 2_000 * MS), false);
        let a = sources.get(&A).unwrap();
        assert_eq!(a.counters().seq.received, 7);
        // 201 is settled by the silence two seconds after 203.
        assert_eq!(a.counters().lost_settled, 2);
        assert_eq!(a.counters().silences, 1);
        assert_eq!(a.silent(), Some(true));
        assert_eq!(a.loss_ratio(), Some(2.0 / 9.0));
    }

    #[test]
    fn sources_are_capped() {
        let mut table = SourceTable::new(None, 64);
        for sysid in 1..=40 {
            table.on_frame(SysComp::new(sysid, 1), 0, 0, 20, 0);
        }
        let mut sources = Sources::default();
        update(&mut sources, &table.summary(0), false);
        assert_eq!(sources.len(), MAX_SOURCES);
        // Those kept go on being updated.
        table.on_frame(SysComp::new(1, 1), 1, 0, 20, MS);
        update(&mut sources, &table.summary(MS), false);
        let one = sources.get(&SysComp::new(1, 1)).unwrap();
        assert_eq!(one.counters().seq.received, 2);
    }
}
