//! Several links' frames laid in the order they came ([`TimeMerge`]):
//! each link's session reads its socket in batches, so one link's frames
//! may be taken hundreds ahead of another's that came at the same time
//! (a busy machine: a few ms of 50,000 frames a second). Matched in the
//! order taken, a copy would fall more than half the 8-bit sequence
//! behind and count as a new frame. So each link's frames wait in its
//! queue, and leave in time order once every link that is sending has
//! taken frames as late as them (a link that has taken none yet holds
//! them too: its first batch may be read after another's). Pure, time
//! passed in.
//!
//! A link that falls silent holds the others back [`TimeMerge::hold`] at
//! most; memory is bounded by [`TimeMerge::cap`] frames in all.

use std::collections::VecDeque;

use crate::engine::Nanos;

/// How long a link's silence may hold the others' frames.
pub(crate) const DEFAULT_HOLD: Nanos = 500_000_000;
/// Frames held in all: beyond, the earliest leave at once.
pub(crate) const DEFAULT_CAP: usize = 16_384;

#[derive(Debug, Clone)]
pub(crate) struct TimeMerge<T> {
    /// Each link's frames not yet left, in the order taken (their times
    /// rise on one link).
    queues: Vec<VecDeque<(Nanos, T)>>,
    /// The time of each link's latest frame taken, once it took one.
    latest: Vec<Option<Nanos>>,
    held: usize,
    hold: Nanos,
    cap: usize,
}

impl<T> TimeMerge<T> {
    /// A merge of `links` links (more are taken as they come): frames
    /// wait for each of them, until it takes a frame or `hold` passes.
    pub(crate) fn new(links: usize, hold: Nanos, cap: usize) -> Self {
        TimeMerge {
            queues: (0..links).map(|_| VecDeque::new()).collect(),
            latest: vec![None; links],
            held: 0,
            hold,
            cap,
        }
    }

    /// Link `link` took `item`, come at `at`.
    pub(crate) fn push(&mut self, link: usize, at: Nanos, item: T) {
        if self.queues.len() <= link {
            self.queues.resize_with(link + 1, VecDeque::new);
            self.latest.resize(link + 1, None);
        }
        // A link's times rise; one that went back (a log's stamps) is
        // taken as if it came with the one before.
        let at = self.latest[link].map_or(at, |l| at.max(l));
        self.latest[link] = Some(at);
        self.queues[link].push_back((at, item));
        self.held += 1;
    }

    /// The next frame in time order that may leave: every link that took
    /// frames has taken one as late, or the latest taken is `hold` past
    /// it, or more than `cap` are held.
    pub(crate) fn pop_ready(&mut self) -> Option<(usize, Nanos, T)> {
        let (link, at) = self.earliest()?;
        // A link yet to take a frame may still bring earlier ones: its
        // first batch, read after another link's.
        let every = match self.latest.iter().copied().collect::<Option<Vec<_>>>() {
            Some(latest) => latest.into_iter().min().unwrap_or(0),
            None => 0,
        };
        let newest = self.latest.iter().flatten().max().copied().unwrap_or(0);
        let ready = at <= every || at.saturating_add(self.hold) <= newest || self.held > self.cap;
        ready.then(|| self.pop(link))?
    }

    /// The next frame in time order, whatever is still to come: at the
    /// end, when nothing more is.
    pub(crate) fn pop_any(&mut self) -> Option<(usize, Nanos, T)> {
        let (link, _) = self.earliest()?;
        self.pop(link)
    }

    /// Frames held now.
    #[cfg(test)]
    pub(crate) fn held(&self) -> usize {
        self.held
    }

    /// The link whose next frame came first, and when.
    fn earliest(&self) -> Option<(usize, Nanos)> {
        self.queues
            .iter()
            .enumerate()
            .filter_map(|(k, q)| q.front().map(|&(at, _)| (k, at)))
            .min_by_key(|&(k, at)| (at, k))
    }

    fn pop(&mut self, link: usize) -> Option<(usize, Nanos, T)> {
        let (at, item) = self.queues[link].pop_front()?;
        self.held -= 1;
        Some((link, at, item))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn drain(m: &mut TimeMerge<u32>) -> Vec<(usize, Nanos, u32)> {
        std::iter::from_fn(|| m.pop_ready()).collect()
    }

    #[test]
    fn frames_leave_in_time_order_once_every_link_caught_up() {
        let mut m = TimeMerge::new(2, 1_000, 100);
        // Link 0's batch taken whole before link 1's first.
        for (i, at) in [10, 20, 30, 40].into_iter().enumerate() {
            m.push(0, at, i as u32);
        }
        // Link 1 has taken nothing yet: its first may come earlier.
        assert!(drain(&mut m).is_empty());
        m.push(1, 40, 30);
        let left: Vec<u32> = drain(&mut m).iter().map(|f| f.2).collect();
        assert_eq!(left, [0, 1, 2, 3, 30]);
        for (i, at) in [50, 60, 70].into_iter().enumerate() {
            m.push(0, at, 10 + i as u32);
        }
        for (i, at) in [45, 55, 65].into_iter().enumerate() {
            m.push(1, at, 20 + i as u32);
        }
        // Up to 65, link 1's latest: interleaved by time; 70 waits.
        let left: Vec<u32> = drain(&mut m).iter().map(|f| f.2).collect();
        assert_eq!(left, [20, 10, 21, 11, 22]);
        assert_eq!(m.held(), 1);
        m.push(1, 75, 23);
        let left: Vec<u32> = drain(&mut m).iter().map(|f| f.2).collect();
        assert_eq!(left, [12]);
        assert_eq!(m.pop_any().map(|f| f.2), Some(23));
        assert!(m.pop_any().is_none());
    }

    #[test]
    fn a_silent_link_holds_the_others_for_the_hold_at_most() {
        let mut m = TimeMerge::new(2, 100, 1_000);
        m.push(1, 0, 0);
        assert_eq!(drain(&mut m).len(), 1);
        // Link 1 falls silent at 0; link 0's frames wait 100 at most.
        for at in (10..=300).step_by(10) {
            m.push(0, at, at as u32);
        }
        let left: Vec<Nanos> = drain(&mut m).iter().map(|f| f.1).collect();
        assert_eq!(left, (10..=200).step_by(10).collect::<Vec<Nanos>>());
    }

    #[test]
    fn beyond_the_cap_the_earliest_leave() {
        let mut m = TimeMerge::new(2, Nanos::MAX, 3);
        m.push(1, 0, 0);
        drain(&mut m);
        for at in 1..=5 {
            m.push(0, at, at as u32);
        }
        assert_eq!(drain(&mut m).len(), 2);
        assert_eq!(m.held(), 3);
    }

    #[test]
    fn a_time_that_went_back_keeps_its_links_order() {
        let mut m = TimeMerge::new(1, 1_000, 100);
        m.push(0, 50, 1);
        m.push(0, 40, 2);
        assert_eq!(m.pop_any(), Some((0, 50, 1)));
        assert_eq!(m.pop_any(), Some((0, 50, 2)));
    }
}
