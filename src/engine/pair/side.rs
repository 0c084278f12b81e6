//! One link's share of one source: what it delivered, first, alone,
//! late, and what it lost on its own.

use super::delivered::Delivered;
use super::lag::Lag;
use super::seq::SeqCount;
use crate::engine::Nanos;

#[derive(Debug, Clone, Default)]
pub(super) struct Side {
    /// Good frames delivered, copies and repeats included.
    pub(super) frames: u64,
    pub(super) damaged: u64,
    /// Frames it had delivered already.
    pub(super) again: u64,
    /// Frames it delivered before any other link.
    pub(super) first: u64,
    /// Frames no other link delivered within the window.
    pub(super) only: u64,
    /// Frames (first or later copies) behind a newer number another link
    /// had already delivered.
    pub(super) stale: u64,
    /// Of those, the first copies: they jump back even behind a
    /// de-duplicating router.
    pub(super) stale_first: u64,
    /// Its own sequence, as the link alone would count it.
    pub(super) own: SeqCount,
    /// The numbers on the source's line it delivered, and when.
    pub(super) delivered: Delivered,
    /// Lag behind the first copy of each frame it delivered that another
    /// link delivered too (0 where it was first); made at its first lag.
    pub(super) lag: Option<Lag>,
}

impl Side {
    pub(super) fn heard(&self) -> bool {
        self.frames + self.damaged > 0
    }

    pub(super) fn record_lag(&mut self, ns: Nanos, window: Nanos) {
        self.lag.get_or_insert_with(|| Lag::new(window)).record(ns);
    }
}
