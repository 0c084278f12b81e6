//! One source heard on one or more links: each frame matched to the
//! frames heard before it, and counted on the link that delivered it.

use super::lag::Lag;
use super::recent::{Key, Recent, Seen};
use super::seq::SeqCount;
use super::side::Side;
use crate::engine::Nanos;
use crate::frame::{Frame, Msg};

#[derive(Debug, Clone)]
pub(super) struct SourceState {
    pub(super) recent: Recent,
    /// The merged stream: each frame's first copy, and damaged frames.
    pub(super) merged: SeqCount,
    pub(super) sides: Vec<Side>,
    /// Every later copy's lag behind the first: what a de-duplication
    /// period must cover.
    pub(super) copy_lag: Option<Lag>,
    pub(super) distinct: u64,
    pub(super) copies: u64,
    pub(super) late: u64,
    pub(super) conflicts: u64,
}

impl SourceState {
    pub(super) fn new(links: usize) -> Self {
        SourceState {
            recent: Recent::default(),
            merged: SeqCount::default(),
            sides: vec![Side::default(); links],
            copy_lag: None,
            distinct: 0,
            copies: 0,
            late: 0,
            conflicts: 0,
        }
    }

    /// Links that delivered anything of the source.
    pub(super) fn links_heard(&self) -> usize {
        self.sides.iter().filter(|s| s.heard()).count()
    }

    pub(super) fn on_frame(&mut self, link: u8, frame: &Frame, at: Nanos, window: Nanos) {
        let l = usize::from(link);
        let seq = frame.packet_seq;
        // A damaged frame's number arrived (it is not lost, on its link or
        // the pair's), but its bytes cannot say which frame it was.
        if frame.msg == Msg::Damaged {
            self.sides[l].damaged += 1;
            self.sides[l].own.take(seq);
            self.merged.take(seq);
            return;
        }
        self.sides[l].frames += 1;
        self.sides[l].own.take(seq);
        let line = self.merged.line(seq);
        let key = Key {
            msgid: frame.msgid,
            crc: frame.crc,
        };
        match self.recent.see(line, key, link, at, window) {
            Seen::New => {
                self.distinct += 1;
                self.sides[l].first += 1;
                self.sides[l].only += 1;
                self.merged.take(seq);
                self.newest(l, line, true);
            }
            Seen::Copy { before } => {
                let lag = at.saturating_sub(before.first_at);
                self.copies += 1;
                if before.links.is_power_of_two() {
                    let first = &mut self.sides[usize::from(before.first_link)];
                    first.only -= 1;
                    first.record_lag(0, window);
                }
                self.sides[l].record_lag(lag, window);
                self.copy_lag
                    .get_or_insert_with(|| Lag::new(window))
                    .record(lag);
                self.newest(l, line, false);
            }
            Seen::Again => self.sides[l].again += 1,
            Seen::Late => self.late += 1,
            Seen::Conflict => self.conflicts += 1,
        }
    }

    /// Bytes held beyond the struct, for the tests of the memory bound.
    #[cfg(test)]
    pub(super) fn bytes(&self) -> usize {
        let lags = self.sides.iter().filter_map(|s| s.lag.as_ref());
        self.recent.bytes()
            + self.sides.capacity() * std::mem::size_of::<Side>()
            + lags
                .chain(self.copy_lag.as_ref())
                .map(Lag::bytes)
                .sum::<usize>()
    }

    /// Counts the frame at `line` stale on link `l` if another link had
    /// delivered a newer number, and moves the link's newest on.
    fn newest(&mut self, l: usize, line: u64, first: bool) {
        let others = self
            .sides
            .iter()
            .enumerate()
            .filter(|&(i, _)| i != l)
            .filter_map(|(_, s)| s.newest)
            .max();
        let side = &mut self.sides[l];
        if others.is_some_and(|newest| line < newest) {
            side.stale += 1;
            side.stale_first += u64::from(first);
        }
        side.newest = Some(side.newest.map_or(line, |n| n.max(line)));
    }
}
