//! One source heard on one or more links: each frame matched to the
//! frames heard before it, and counted on the link that delivered it.

use super::lag::Lag;
use super::recent::{Key, Recent, Seen};
use super::seq::SeqCount;
use super::side::Side;
use super::Heard;
use crate::engine::Nanos;

#[derive(Debug, Clone)]
pub(super) struct SourceState {
    pub(super) recent: Recent,
    /// The merged stream: each frame's first copy, and damaged frames.
    pub(super) merged: SeqCount,
    pub(super) sides: Vec<Side>,
    /// Bit `n`: side `n` delivered anything (most of a tracker's sides
    /// never do: visiting only these keeps a frame's cost to the links
    /// that carry the source).
    heard: u64,
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
            sides: (0..links).map(|_| Side::default()).collect(),
            heard: 0,
            copy_lag: None,
            distinct: 0,
            copies: 0,
            late: 0,
            conflicts: 0,
        }
    }

    /// Links that delivered anything of the source.
    pub(super) fn links_heard(&self) -> usize {
        self.heard.count_ones() as usize
    }

    pub(super) fn on_frame(&mut self, link: u8, frame: &Heard, at: Nanos, window: Nanos) {
        let l = usize::from(link);
        let seq = frame.seq;
        self.heard |= 1 << l;
        // A damaged frame's number arrived (it is not lost, on its link or
        // the pair's), but its bytes cannot say which frame it was.
        if frame.damaged {
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
                self.newest(l, line, at, true);
            }
            Seen::Copy { before } => {
                self.copies += 1;
                let was_first = usize::from(before.first_link);
                // Taken after the first copy, but came before it: the
                // first is this one (exact with two links; with more, the
                // copies taken in between kept their lag behind the old
                // first).
                let earlier = at < before.first_at;
                let lag = at.abs_diff(before.first_at);
                if before.links.is_power_of_two() {
                    let first = &mut self.sides[was_first];
                    first.only -= 1;
                    first.record_lag(if earlier { lag } else { 0 }, window);
                }
                if earlier {
                    let was = &mut self.sides[was_first];
                    was.first -= 1;
                    if was.delivered.set_first(line, false) {
                        was.stale_first -= 1;
                    }
                    self.sides[l].first += 1;
                }
                self.sides[l].record_lag(if earlier { 0 } else { lag }, window);
                self.copy_lag
                    .get_or_insert_with(|| Lag::new(window))
                    .record(lag);
                self.newest(l, line, at, earlier);
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
        let delivered: usize = self.sides.iter().map(|s| s.delivered.bytes()).sum();
        self.recent.bytes()
            + delivered
            + self.sides.capacity() * std::mem::size_of::<Side>()
            + lags
                .chain(self.copy_lag.as_ref())
                .map(Lag::bytes)
                .sum::<usize>()
    }

    /// Counts the frame at `line`, come at `at`, stale on link `l` if
    /// another link had delivered a newer number by the time it came, and
    /// the other links' frames it finds stale (taken before it, come
    /// after it).
    fn newest(&mut self, l: usize, line: u64, at: Nanos, first: bool) {
        let mut stale = false;
        let mut others = self.heard & !(1 << l);
        while others != 0 {
            let side = &mut self.sides[others.trailing_zeros() as usize];
            others &= others - 1;
            stale |= side.delivered.newest_by(at).is_some_and(|n| line < n);
            let found = side.delivered.overtaken(line, at);
            side.stale += found.frames;
            side.stale_first += found.first;
        }
        let side = &mut self.sides[l];
        if stale {
            side.stale += 1;
            side.stale_first += u64::from(first);
        }
        side.delivered.take(line, at, stale, first);
    }
}
