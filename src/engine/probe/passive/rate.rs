//! A source's usual interval: its time per sequence step, over its last
//! 256 to 512 steps or one to two seconds, whichever comes first. Pure:
//! times are passed in.
//!
//! A mean over a window, not a per-step average: frames often arrive in
//! bursts (an autopilot's scheduler sends its messages together, a
//! sender or a router flushes a batch, a radio delivers a TDM round), and
//! an average that forgets within a burst falls to the spacing inside it,
//! which then makes every pause between bursts look like a long silence.
//! The window holds whole bursts and the pauses between them. It is two
//! buckets: the one filling, and the last full one.

use crate::engine::Nanos;

/// A bucket is full after this many steps...
const BUCKET_STEPS: u64 = 256;
/// ...or this long.
const BUCKET_NS: Nanos = 1_000_000_000;

#[derive(Debug, Clone, Copy)]
struct Bucket {
    start: Nanos,
    steps: u64,
}

#[derive(Debug, Clone)]
pub(super) struct Rate {
    /// The last full bucket, once there is one.
    full: Option<Bucket>,
    filling: Bucket,
    /// The arrival of the latest step's frame: where the window ends.
    head_at: Nanos,
    /// The interval before the count restarted: shown (and used for a
    /// silence's frames) until a step is seen again, never to settle.
    before: Option<Nanos>,
}

impl Rate {
    /// The source's first frame, at `at`.
    pub(super) fn new(at: Nanos) -> Self {
        Rate {
            full: None,
            filling: Bucket {
                start: at,
                steps: 0,
            },
            head_at: at,
            before: None,
        }
    }

    /// The sequence moved `k` steps ahead with a frame arriving at `at`.
    pub(super) fn step(&mut self, k: u64, at: Nanos) {
        self.filling.steps += k;
        self.head_at = self.head_at.max(at);
        let age = self.head_at.saturating_sub(self.filling.start);
        if self.filling.steps >= BUCKET_STEPS || age >= BUCKET_NS {
            self.full = Some(self.filling);
            self.filling = Bucket {
                start: self.head_at,
                steps: 0,
            };
        }
    }

    /// Time and steps in the window.
    fn window(&self) -> (Nanos, u64) {
        let start = self.full.map_or(self.filling.start, |b| b.start);
        let steps = self.full.map_or(0, |b| b.steps) + self.filling.steps;
        (self.head_at.saturating_sub(start), steps)
    }

    /// The usual time per step (at least 1 ns), once a step was seen.
    pub(super) fn interval(&self) -> Option<Nanos> {
        let (span, steps) = self.window();
        if steps == 0 {
            return self.before;
        }
        Some((span / steps).max(1))
    }

    /// A full bucket is behind the estimate (256 steps, or a second):
    /// enough to judge a pause by it alone.
    pub(super) fn settled(&self) -> bool {
        self.full.is_some()
    }

    /// The count restarted at `at` (after a silence it could not span, or
    /// a frame it could not place): the rate is measured afresh too. Kept
    /// instead, an estimate gone wrong (a batch of frames stamped alike
    /// makes a window of no time) would judge every pause a silence too
    /// long to span, each one restarting the count and none a step, for
    /// ever; afresh, it judges by the 1 s floor until a bucket is full.
    pub(super) fn rebase(&mut self, at: Nanos) {
        let before = self.interval();
        *self = Rate::new(at);
        self.before = before;
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
        // within a pause either way of it wherever the window ends (the
        // window holds 5 to 10 bursts).
        let mut r = Rate::new(0);
        for p in 1..5_000u64 {
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

    #[test]
    fn it_settles_after_256_steps_or_a_second() {
        let mut r = Rate::new(0);
        for p in 1..256u64 {
            r.step(1, p * MS / 2);
        }
        assert!(!r.settled());
        r.step(1, 128 * MS);
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
        // A window of no time (a batch stamped alike) gives 1 ns a step...
        let mut r = Rate::new(0);
        r.step(300, 0);
        assert_eq!((r.interval(), r.settled()), (Some(1), true));
        // ...and once the count restarts, it no longer settles anything
        // (shown until the next step) until a bucket of real steps is in.
        r.rebase(5 * MS);
        assert_eq!((r.interval(), r.settled()), (Some(1), false));
        for p in 1..=256u64 {
            r.step(1, 5 * MS + p * 10 * US);
        }
        assert_eq!((r.interval(), r.settled()), (Some(10 * US), true));
    }

    #[test]
    fn a_rate_change_shows_within_two_buckets() {
        let mut r = Rate::new(0);
        let mut at = 0;
        for _ in 0..100 {
            at += 1_000 * MS;
            r.step(1, at);
        }
        assert_eq!(r.interval(), Some(1_000 * MS));
        // From 1 Hz to 100 Hz: two seconds later, the new rate.
        for _ in 0..300 {
            at += 10 * MS;
            r.step(1, at);
        }
        assert_eq!(r.interval(), Some(10 * MS));
    }
}
