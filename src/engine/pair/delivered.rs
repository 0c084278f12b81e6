//! What one link delivered of one source lately, and when: to tell a
//! frame that came behind a newer one another link had already brought
//! (stale). Links are read in turns (a socket's batches, two logs'
//! pages), so frames are not taken in the order they came: a frame may
//! turn out stale when a newer one that came before it is taken after it.

use std::collections::VecDeque;

use crate::engine::Nanos;

/// Numbers behind the newest that a question can still be about: frames
/// further behind are late, and never asked about (`recent.rs`).
const HORIZON: u64 = 128;
/// One per value of the 8-bit sequence, as in `recent.rs`.
const SLOTS: usize = 256;

/// A frame the link delivered.
#[derive(Debug, Clone, Copy, Default)]
struct Taken {
    /// Its place on the source's line; 0 for a slot never used (lines
    /// start far from 0: `seq.rs`).
    line: u64,
    at: Nanos,
    stale: bool,
    first: bool,
}

/// Stale frames found, and how many of them were first copies.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub(super) struct Stale {
    pub(super) frames: u64,
    pub(super) first: u64,
}

#[derive(Debug)]
pub(super) struct Delivered {
    /// The steps of the link's newest number over time: sorted by time,
    /// each step's number above the one before, so the newest by any
    /// time is the last step at or before it. About one step per number
    /// within the horizon.
    steps: VecDeque<(Nanos, u64)>,
    /// Each frame delivered lately, in its number's slot.
    taken: Box<[Taken]>,
    /// The time of the latest frame taken.
    latest: Nanos,
}

impl Default for Delivered {
    /// Made at its most, so that its memory is the same all run.
    fn default() -> Self {
        Delivered {
            steps: Self::steps(),
            taken: vec![Taken::default(); SLOTS].into_boxed_slice(),
            latest: 0,
        }
    }
}

impl Clone for Delivered {
    /// At its most too: a derived clone would shrink the steps to fit.
    fn clone(&self) -> Self {
        let mut steps = Self::steps();
        steps.extend(self.steps.iter().copied());
        Delivered {
            steps,
            taken: self.taken.clone(),
            latest: self.latest,
        }
    }
}

impl Delivered {
    /// Room for the horizon's numbers, one step before, one coming.
    fn steps() -> VecDeque<(Nanos, u64)> {
        VecDeque::with_capacity(HORIZON as usize + 3)
    }

    /// The frame at `line` came at `at`; `stale` and `first` as counted.
    pub(super) fn take(&mut self, line: u64, at: Nanos, stale: bool, first: bool) {
        self.taken[slot(line)] = Taken {
            line,
            at,
            stale,
            first,
        };
        self.latest = self.latest.max(at);
        self.step(line, at);
    }

    fn step(&mut self, line: u64, at: Nanos) {
        let by = self.steps.partition_point(|&(when, _)| when <= at);
        if by > 0 && self.steps[by - 1].1 >= line {
            return;
        }
        // Later steps this one reaches no longer rise.
        let covered = self
            .steps
            .range(by..)
            .take_while(|&&(_, n)| n <= line)
            .count();
        self.steps.drain(by..by + covered);
        self.steps.insert(by, (at, line));
        let newest = self.steps.back().map_or(line, |&(_, n)| n);
        while self.steps.len() > 1 && self.steps[1].1 + HORIZON < newest {
            self.steps.pop_front();
        }
    }

    /// The newest number delivered at or before `at`.
    pub(super) fn newest_by(&self, at: Nanos) -> Option<u64> {
        let by = self.steps.partition_point(|&(when, _)| when <= at);
        by.checked_sub(1).map(|i| self.steps[i].1)
    }

    /// Another link delivered `line` at `at`: the frames this link
    /// delivered behind it, no earlier, were stale. Marks and counts
    /// those not counted yet.
    pub(super) fn overtaken(&mut self, line: u64, at: Nanos) -> Stale {
        let mut found = Stale::default();
        // Taken in time order (the usual case): nothing came after it.
        if self.latest < at {
            return found;
        }
        for behind in line.saturating_sub(HORIZON)..line {
            let taken = &mut self.taken[slot(behind)];
            if taken.line == behind && taken.at >= at && !taken.stale {
                taken.stale = true;
                found.frames += 1;
                found.first += u64::from(taken.first);
            }
        }
        found
    }

    /// The frame at `line` is (or is no longer) the first copy; whether
    /// it was counted stale.
    pub(super) fn set_first(&mut self, line: u64, first: bool) -> bool {
        let taken = &mut self.taken[slot(line)];
        if taken.line != line {
            return false;
        }
        taken.first = first;
        taken.stale
    }

    #[cfg(test)]
    pub(super) fn bytes(&self) -> usize {
        self.steps.capacity() * std::mem::size_of::<(Nanos, u64)>()
            + std::mem::size_of_val(&*self.taken)
    }

    #[cfg(test)]
    fn steps_held(&self) -> usize {
        self.steps.len()
    }
}

fn slot(line: u64) -> usize {
    (line % SLOTS as u64) as usize
}

#[cfg(test)]
mod tests {
    use super::*;

    const L: u64 = 1 << 40;

    #[test]
    fn the_newest_by_a_time_is_the_last_step_before_it() {
        let mut d = Delivered::default();
        assert_eq!(d.newest_by(100), None);
        // Taken out of time order: 5 at 50 after 7 at 70.
        d.take(L + 7, 70, false, true);
        d.take(L + 5, 50, false, true);
        d.take(L + 6, 80, false, true);
        assert_eq!(d.newest_by(49), None);
        assert_eq!(d.newest_by(50), Some(L + 5));
        assert_eq!(d.newest_by(69), Some(L + 5));
        assert_eq!(d.newest_by(70), Some(L + 7));
        assert_eq!(d.newest_by(1000), Some(L + 7));
        // A higher number earlier hides the later, lower ones.
        d.take(L + 9, 60, false, true);
        assert_eq!(d.newest_by(65), Some(L + 9));
        assert_eq!(d.newest_by(75), Some(L + 9));
        assert_eq!(d.steps_held(), 2);
    }

    #[test]
    fn it_holds_only_the_horizon() {
        let mut d = Delivered::default();
        let bytes = d.bytes();
        for i in 0..100_000u64 {
            d.take(L + i, i * 10, false, true);
        }
        assert!(d.steps_held() <= HORIZON as usize + 2, "{}", d.steps_held());
        assert_eq!(d.bytes(), bytes);
        assert_eq!(d.newest_by(99_999 * 10), Some(L + 99_999));
        assert_eq!(d.newest_by(99_990 * 10 + 5), Some(L + 99_990));
    }

    #[test]
    fn frames_taken_before_a_newer_one_that_came_earlier_are_overtaken() {
        let mut d = Delivered::default();
        // 1..=4 came at 100..=400, one of them (3) already stale.
        for i in 1..=4 {
            d.take(L + i, i * 100, i == 3, i % 2 == 0);
        }
        // Another link's 3 at 150: 1 came before it, 2 after; 3 and 4 are
        // not behind it.
        assert_eq!(
            d.overtaken(L + 3, 150),
            Stale {
                frames: 1,
                first: 1
            }
        );
        // Its 5 at 150: 4 too now; 2 and 3 counted already.
        assert_eq!(
            d.overtaken(L + 5, 150),
            Stale {
                frames: 1,
                first: 1
            }
        );
        // After them all: nothing.
        assert_eq!(d.overtaken(L + 9, 401), Stale::default());
        assert!(d.set_first(L + 3, true));
        assert!(!d.set_first(L + 1, true));
    }
}
