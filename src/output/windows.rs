//! A passive run's sources window by window: the engine tells the table
//! of sources cumulatively, once a second ([`SourcesNow`]); the samples,
//! the plot and the live view want what each source did in each window.
//! Pure: a window is the difference of two tables.
//!
//! [`SourcesNow`]: crate::engine::probe::passive::SourcesNow

use std::collections::BTreeMap;

use crate::engine::summary::passive::{SeqCounts, TableSummary};
use crate::engine::Nanos;
use crate::frame::SysComp;

/// What one source did between two tellings of the table.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Window {
    pub(crate) source: SysComp,
    /// The SiK radio's own RADIO_STATUS source.
    pub(crate) radio: bool,
    /// Session time, ns: from the previous telling (0 at first) to this one.
    pub(crate) start: Nanos,
    pub(crate) end: Nanos,
    /// Frames, duplicates included.
    pub(crate) received: u64,
    /// Numbers skipped in this window, less the earlier windows' gaps its
    /// late frames filled: negative when more were filled than skipped,
    /// so that the windows add up to the run's count.
    pub(crate) lost: i64,
    pub(crate) duplicate: u64,
    pub(crate) reordered: u64,
    pub(crate) bytes: u64,
}

impl Window {
    /// Frames a second over the window; `None` for an empty window.
    pub(crate) fn frames_per_s(&self) -> Option<f64> {
        let ns = self.end.saturating_sub(self.start);
        (ns > 0).then(|| self.received as f64 * 1e9 / ns as f64)
    }

    #[cfg(test)]
    /// `100 * lost / (lost + distinct frames)` over the window, never below
    /// 0; `None` with nothing to compare.
    pub(crate) fn loss_pct(&self) -> Option<f64> {
        let lost = self.lost.max(0) as f64;
        let whole = lost + self.received.saturating_sub(self.duplicate) as f64;
        (whole > 0.0).then(|| 100.0 * lost / whole)
    }

    /// Nothing happened in it.
    pub(crate) fn is_empty(&self) -> bool {
        self.received == 0 && self.lost == 0 && self.reordered == 0 && self.bytes == 0
    }
}

/// Turns successive tables into windows. Bounded as the table is (its
/// tracked sources and the radio).
#[derive(Debug, Clone, Default)]
pub(crate) struct Windows {
    last_at: Nanos,
    /// Each source's counts and bytes at the last telling.
    last: BTreeMap<SysComp, (SeqCounts, u64)>,
}

impl Windows {
    /// The window ending at `at` of every source in `table` (sources first
    /// heard in it start from nothing), in the table's order.
    pub(crate) fn next(&mut self, at: Nanos, table: &TableSummary) -> Vec<Window> {
        let start = self.last_at.min(at);
        let windows = table
            .sources
            .iter()
            .map(|s| {
                let was = self.last.insert(s.source, (s.counts, s.bytes));
                let (then, bytes) = was.unwrap_or_default();
                let now = &s.counts;
                Window {
                    source: s.source,
                    radio: s.radio,
                    start,
                    end: at,
                    received: now.received.saturating_sub(then.received),
                    lost: now.lost as i64 - then.lost as i64,
                    duplicate: now.duplicate.saturating_sub(then.duplicate),
                    reordered: now.reordered.saturating_sub(then.reordered),
                    bytes: s.bytes.saturating_sub(bytes),
                }
            })
            .collect();
        self.last_at = at;
        windows
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::engine::probe::passive::tracker::SourceTable;

    const MS: Nanos = 1_000_000;

    #[test]
    fn windows_add_up_to_the_table_even_when_a_late_frame_fills_an_old_gap() {
        let (a, b) = (SysComp::new(1, 1), SysComp::new(2, 1));
        let mut table = SourceTable::new(None, 32);
        let mut windows = Windows::default();
        let mut all = Vec::new();
        // 1/1 skips 3 in the first second; it comes in the second.
        for (seq, at) in [(0, 100), (1, 200), (2, 300), (4, 900)] {
            table.on_frame(a, seq, 30, 40, at * MS);
        }
        all.extend(windows.next(1_000 * MS, &table.summary(1_000 * MS)));
        // 2/1 is first heard in the second window; 1/1 sends 4 twice.
        for (seq, at) in [(3, 1_100), (4, 1_200), (5, 1_300)] {
            table.on_frame(a, seq, 30, 40, at * MS);
        }
        table.on_frame(b, 7, 0, 21, 1_500 * MS);
        all.extend(windows.next(2_000 * MS, &table.summary(2_000 * MS)));
        // The last, partial, window.
        table.on_frame(a, 7, 30, 40, 2_100 * MS);
        let end = table.summary(2_250 * MS);
        all.extend(windows.next(2_250 * MS, &end));

        let first = all[0];
        assert_eq!((first.source, first.start, first.end), (a, 0, 1_000 * MS));
        assert_eq!((first.received, first.lost, first.reordered), (4, 1, 0));
        assert_eq!(first.frames_per_s(), Some(4.0));
        assert_eq!(first.loss_pct(), Some(20.0));
        let second = all[1];
        assert_eq!((second.start, second.end), (1_000 * MS, 2_000 * MS));
        assert_eq!(
            (
                second.received,
                second.lost,
                second.duplicate,
                second.reordered
            ),
            (3, -1, 1, 1)
        );
        assert_eq!(second.loss_pct(), Some(0.0));
        assert_eq!((all[2].source, all[2].received), (b, 1));
        let last = all[3];
        assert_eq!((last.received, last.lost, last.end), (1, 1, 2_250 * MS));
        assert_eq!(last.frames_per_s(), Some(4.0));
        assert!(!last.is_empty());
        assert!(all[4].is_empty(), "{:?}", all[4]);

        for s in &end.sources {
            let mine = all.iter().filter(|w| w.source == s.source);
            let sum = |f: fn(&Window) -> i64| mine.clone().map(f).sum::<i64>();
            assert_eq!(sum(|w| w.received as i64), s.counts.received as i64);
            assert_eq!(sum(|w| w.lost), s.counts.lost as i64);
            assert_eq!(sum(|w| w.duplicate as i64), s.counts.duplicate as i64);
            assert_eq!(sum(|w| w.reordered as i64), s.counts.reordered as i64);
            assert_eq!(sum(|w| w.bytes as i64), s.bytes as i64);
        }
    }
}
