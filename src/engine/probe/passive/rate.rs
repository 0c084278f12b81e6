//! A source's usual interval and its routine pause: its time per sequence
//! step over the last few seconds of its own time, and the longest pause
//! it makes in a second, as a rule. Pure: times are passed in.
//!
//! Seconds, not steps or frames: real ground stations do not hand frames
//! over as they come. QGroundControl writes whole milliseconds and its
//! log in batches about once a second (vtol.tlog: 140 frames within
//! 0.2 s, then a 1.05 s pause), Mission Planner stamps a whole read at
//! once, and an autopilot's scheduler sends its messages together. A
//! window of 256 steps fell inside one batch, took 0.47 ms a frame for a
//! source sending 115 frames/s, and made each pause between batches a
//! silence of ~961 frames. A window of seconds holds whole batches and
//! the pauses between them. It is up to [`FULL_BUCKETS`] full buckets of
//! at least [`BUCKET_NS`] each, and the one filling; the mean's error is
//! at most one batch's length over the window's.
//!
//! The routine pause is the median, over the full buckets, of the longest
//! pause inside each: a pause the source (or its logger) makes every
//! second is routine, and a silence is a pause well beyond it. Pauses
//! that were silences are not recorded, so one outage never becomes the
//! rule.

use crate::engine::Nanos;

/// A bucket is full after this long.
const BUCKET_NS: Nanos = 1_000_000_000;
/// Full buckets kept behind the filling one.
const FULL_BUCKETS: usize = 4;

#[derive(Debug, Clone, Copy)]
struct Bucket {
    start: Nanos,
    /// Its length, once full (the window leaves out a silence skipped).
    span: Nanos,
    steps: u64,
    /// The longest pause between two frames inside it (silences aside).
    longest_pause: Nanos,
}

impl Bucket {
    fn at(start: Nanos) -> Self {
        Bucket {
            start,
            span: 0,
            steps: 0,
            longest_pause: 0,
        }
    }
}

#[derive(Debug, Clone)]
pub(super) struct Rate {
    /// The last full buckets, oldest first.
    full: [Option<Bucket>; FULL_BUCKETS],
    filling: Bucket,
    /// The arrival of the latest step's frame: where the window ends.
    head_at: Nanos,
    /// The interval before the count restarted: shown (and used for a
    /// silence's frames) until a step is seen again, never to settle.
    before: Option<Nanos>,
    /// The routine pause and the interval of the full buckets, worked out
    /// when a bucket fills: every frame asks for them.
    routine: Option<Nanos>,
    settled_interval: Option<Nanos>,
    /// Moves whenever the interval or the routine pause may have: what
    /// depends on them can be kept until it does.
    epoch: u64,
}

impl Rate {
    /// The source's first frame, at `at`.
    pub(super) fn new(at: Nanos) -> Self {
        Rate {
            full: [None; FULL_BUCKETS],
            filling: Bucket::at(at),
            head_at: at,
            before: None,
            routine: None,
            settled_interval: None,
            epoch: 0,
        }
    }

    /// A pause of `length` between two frames that was not a silence.
    pub(super) fn pause(&mut self, length: Nanos) {
        self.filling.longest_pause = self.filling.longest_pause.max(length);
    }

    /// The sequence moved `k` steps ahead with a frame arriving at `at`.
    pub(super) fn step(&mut self, k: u64, at: Nanos) {
        if !self.settled() {
            self.epoch += 1;
        }
        self.filling.steps += k;
        self.head_at = self.head_at.max(at);
        let span = self.head_at.saturating_sub(self.filling.start);
        if span >= BUCKET_NS {
            self.full.rotate_left(1);
            self.full[FULL_BUCKETS - 1] = Some(Bucket {
                span,
                ..self.filling
            });
            self.filling = Bucket::at(self.head_at);
            self.routine = self.median_longest_pause();
            self.epoch += 1;
            let span = self.full().map(|b| b.span).sum::<Nanos>();
            let steps = self.full().map(|b| b.steps).sum::<u64>();
            self.settled_interval = (steps > 0).then(|| (span / steps).max(1));
        }
    }

    /// A pause whose steps the sequence cannot tell was skipped: the
    /// window goes on from `at` without it (its steps and its time both
    /// left out), and the partial bucket before it is dropped.
    pub(super) fn skip(&mut self, at: Nanos) {
        self.filling = Bucket::at(at);
        self.head_at = at;
        self.epoch += 1;
    }

    /// See the field.
    pub(super) fn epoch(&self) -> u64 {
        self.epoch
    }

    fn full(&self) -> impl Iterator<Item = &Bucket> {
        self.full.iter().flatten()
    }

    /// Time and steps in the window.
    /// The usual time per step (at least 1 ns), once a step was seen.
    /// Whole buckets only, once there is one: each starts and ends on a
    /// frame, so with a logger's batches each holds whole periods, where
    /// the bucket filling may end inside a batch, at its densest.
    pub(super) fn interval(&self) -> Option<Nanos> {
        if self.settled() {
            return self.settled_interval.or(self.before);
        }
        let span = self.head_at.saturating_sub(self.filling.start);
        match self.filling.steps {
            0 => self.before,
            steps => Some((span / steps).max(1)),
        }
    }

    /// The routine pause: the median of the full buckets' longest pauses
    /// (the upper one of an even count), once a bucket is full.
    pub(super) fn routine_pause(&self) -> Option<Nanos> {
        self.routine
    }

    fn median_longest_pause(&self) -> Option<Nanos> {
        let mut pauses = [0; FULL_BUCKETS];
        let mut n = 0;
        for b in self.full() {
            pauses[n] = b.longest_pause;
            n += 1;
        }
        pauses[..n].sort_unstable();
        pauses[..n].get(n / 2).copied()
    }

    /// A full bucket is behind the estimate: enough to judge a pause by
    /// it alone.
    pub(super) fn settled(&self) -> bool {
        self.full[FULL_BUCKETS - 1].is_some()
    }

    /// The count restarted at `at` (a frame it could not place, or a
    /// restart of the source's counter): the rate is measured afresh too.
    /// Kept instead, an estimate gone wrong (a batch of frames stamped
    /// alike makes a window of no time) would keep judging pauses by it.
    pub(super) fn rebase(&mut self, at: Nanos) {
        let (before, epoch) = (self.interval(), self.epoch);
        *self = Rate::new(at);
        self.before = before;
        self.epoch = epoch + 1;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const US: Nanos = 1_000;
    const MS: Nanos = 1_000_000;

    #[test]
    fn a_steady_source_has_its_interval_exactly() {
        let mut r = Rate::new(0);
        assert_eq!(r.interval(), None);
        for i in 1..=500u64 {
            r.step(1, i * 20 * MS);
            assert_eq!(r.interval(), Some(20 * MS), "{i}");
        }
        assert!(r.settled());
        // Lost frames are steps: the interval holds.
        r.step(5, 500 * 20 * MS + 5 * 20 * MS);
        assert_eq!(r.interval(), Some(20 * MS));
    }

    #[test]
    fn a_bursty_source_has_its_mean() {
        // 50 frames 100 ns apart every 0.5 ms: 10 µs a frame on average,
        // within a pause either way of it wherever the window ends.
        let mut r = Rate::new(0);
        for p in 1..500_000u64 {
            r.step(1, p / 50 * 500 * US + p % 50 * 100);
            if p > 256 {
                let i = r.interval().unwrap();
                assert!((8 * US..=12 * US).contains(&i), "{p}: {i}");
            }
        }
        // An autopilot's 5 frames every 20 ms.
        let mut r = Rate::new(0);
        for p in 1..1_000u64 {
            r.step(1, p / 5 * 20 * MS + p % 5 * 50 * US);
        }
        let i = r.interval().unwrap();
        assert!((3_500 * US..=4_500 * US).contains(&i), "{i}");
    }

    /// vtol.tlog's shape: 140 frames within 0.2 s (whole milliseconds, so
    /// most of them on one stamp), then a pause of 1.05 s.
    fn batches(r: &mut Rate, seconds: u64) -> Nanos {
        let period = 1_250 * MS;
        let mut at = 0;
        for b in 0..seconds * 4 / 5 {
            for f in 0..140u64 {
                let now = b * period + f / 20 * 30 * MS;
                if now > at {
                    r.pause(now - at);
                }
                at = now;
                r.step(1, at);
            }
        }
        at
    }

    #[test]
    fn batches_a_second_apart_have_the_mean_rate_and_their_pause_is_routine() {
        let mut r = Rate::new(0);
        batches(&mut r, 30);
        // 112 frames/s: 8.93 ms a frame, within one batch in the window.
        let i = r.interval().unwrap();
        assert!((8 * MS..=10 * MS).contains(&i), "{i}");
        // The pause between batches: 1.25 s less the batch's 0.18 s.
        assert_eq!(r.routine_pause(), Some(1_070 * MS));
    }

    #[test]
    fn it_settles_after_a_second() {
        let mut r = Rate::new(0);
        for p in 1..2_000u64 {
            r.step(1, p * 400 * US);
        }
        assert!(!r.settled());
        r.step(1, 1_000 * MS);
        assert!(r.settled());
        let mut slow = Rate::new(0);
        slow.step(1, 400 * MS);
        slow.step(1, 800 * MS);
        assert!(!slow.settled());
        slow.step(1, 1_200 * MS);
        assert!(slow.settled());
        assert_eq!(slow.interval(), Some(400 * MS));
    }

    #[test]
    fn a_restarted_count_measures_the_rate_afresh() {
        let mut r = Rate::new(0);
        r.step(300, 0);
        assert_eq!((r.interval(), r.settled()), (Some(1), false));
        r.rebase(5 * MS);
        assert_eq!((r.interval(), r.settled()), (Some(1), false));
        for p in 1..=100_000u64 {
            r.step(1, 5 * MS + p * 10 * US);
        }
        assert_eq!((r.interval(), r.settled()), (Some(10 * US), true));
    }

    #[test]
    fn a_rate_change_shows_within_the_window() {
        let mut r = Rate::new(0);
        let mut at = 0;
        for _ in 0..100 {
            at += 1_000 * MS;
            r.step(1, at);
        }
        assert_eq!(r.interval(), Some(1_000 * MS));
        // From 1 Hz to 100 Hz: six seconds later, the new rate.
        for _ in 0..600 {
            at += 10 * MS;
            r.step(1, at);
        }
        assert_eq!(r.interval(), Some(10 * MS));
    }

    #[test]
    fn the_routine_pause_is_a_median_so_one_long_pause_is_not_the_rule() {
        let mut r = Rate::new(0);
        let mut at = 0;
        for s in 0..6u64 {
            for _ in 0..50 {
                at += 20 * MS;
                r.step(1, at);
                r.pause(20 * MS);
            }
            if s == 3 {
                r.pause(900 * MS);
            }
        }
        assert_eq!(r.routine_pause(), Some(20 * MS));
    }
}
