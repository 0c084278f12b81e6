//! Kernel receive timestamps on the monotonic clock.
//!
//! `SO_TIMESTAMPNS` stamps a datagram on the wall clock (CLOCK_REALTIME);
//! mavping measures on the monotonic clock (CLOCK_MONOTONIC, which
//! `Instant` reads on Linux). A stamp is converted by its age: the wall
//! clock now minus the stamp, taken off the monotonic clock now. That is
//! right while the wall clock runs with the monotonic one; a step of the
//! wall clock (an NTP step, `date -s`, a resume from suspend, during which
//! CLOCK_MONOTONIC stands still and the wall clock does not) between the
//! kernel's stamp and our read would bend the age by the step. So:
//!
//! - the offset between the two clocks is followed from reading to
//!   reading. Linux keeps CLOCK_REALTIME as CLOCK_MONOTONIC plus an offset
//!   that only a step, a resume from suspend or a leap second changes (an
//!   NTP slew adjusts both clocks' rate alike), so when the offset moved,
//!   the wall clock stepped in between: stamps taken before that reading
//!   are not trusted (such a datagram is timed when it was read, as on
//!   links without kernel stamps);
//! - whatever the stamp says, a datagram arrived after the socket was last
//!   found empty and before it was read: the arrival is clamped to that
//!   window, so no step of any size moves it further than our own reading
//!   delay does without kernel stamps.
//!
//! The clocks are read through [`Clocks`], so tests step them. A stamp is
//! the wall clock in ns since the epoch ([`WallNs`]), whatever system
//! call brought it (the portable path has none: every datagram is timed
//! at its read).

use std::time::{Duration, SystemTime};

use tokio::time::Instant;

/// A stamp older than this is not trusted (the socket cannot hold a
/// datagram that long while we read it every few milliseconds).
const MAX_QUEUE_AGE: Duration = Duration::from_secs(10);
/// A change of the wall-minus-monotonic offset beyond this between two
/// readings is a step, not the gap between reading one clock and the
/// other. A smaller step can move an arrival by at most this much, and
/// never before the socket was last found empty.
const STEP_TOLERANCE_NS: i128 = 1_000_000;

/// A kernel receive stamp: the wall clock, ns since the epoch.
pub(crate) type WallNs = i128;

/// Reads the monotonic and the wall clock together.
pub(crate) trait Clocks {
    fn now(&self) -> (Instant, SystemTime);
}

/// The system's clocks.
#[derive(Debug, Default, Clone, Copy)]
pub(crate) struct SystemClocks;

impl Clocks for SystemClocks {
    fn now(&self) -> (Instant, SystemTime) {
        // The wall clock first: a thread preempted between the two reads
        // then sees the monotonic clock late, which puts an arrival later,
        // never earlier, than it was. An arrival placed early could come
        // before the reply's TIMESYNC stamp and break the clock bounds'
        // causality; late only widens them.
        let wall = SystemTime::now();
        (Instant::now(), wall)
    }
}

/// Both clocks read together, once for a batch of datagrams.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Reading {
    now: Instant,
    /// The wall clock, ns since the epoch.
    wall: i128,
}

/// Converts one socket's kernel receive stamps to the monotonic clock.
#[derive(Debug)]
pub(crate) struct RxTime<C = SystemClocks> {
    clocks: C,
    /// The last reading: the wall clock (ns since the epoch) and the
    /// monotonic clock.
    last: Option<(i128, Instant)>,
    /// Stamps before this wall time (ns) may predate a step: not trusted.
    trust_from: Option<i128>,
    /// When the socket was last found empty: anything read later arrived
    /// after it.
    empty_at: Option<Instant>,
}

fn wall_ns(t: SystemTime) -> i128 {
    match t.duration_since(SystemTime::UNIX_EPOCH) {
        Ok(d) => d.as_nanos() as i128,
        Err(e) => -(e.duration().as_nanos() as i128),
    }
}

impl RxTime {
    /// For a socket just opened: nothing can have reached it before now.
    pub(crate) fn new() -> Self {
        RxTime::with_clocks(SystemClocks)
    }
}

impl Default for RxTime {
    fn default() -> Self {
        RxTime::new()
    }
}

impl<C: Clocks> RxTime<C> {
    /// For a socket just opened, on `clocks`.
    pub(crate) fn with_clocks(clocks: C) -> Self {
        let mut rx = RxTime {
            clocks,
            last: None,
            trust_from: None,
            empty_at: None,
        };
        rx.drained();
        rx
    }

    /// The socket was just found empty (a read would block).
    pub(crate) fn drained(&mut self) {
        let reading = self.read();
        self.empty_at(reading);
    }

    /// The socket was found empty just before `reading` (a batch read
    /// came back short): what is read later arrived after it.
    pub(crate) fn empty_at(&mut self, reading: Reading) {
        self.empty_at = Some(reading.now);
    }

    /// When a datagram just read, stamped `kernel` by the kernel (if it
    /// was), reached the socket, on the monotonic clock. (The socket reads
    /// a batch with one [`RxTime::read`] and [`RxTime::arrival_at`] each.)
    #[cfg(test)]
    fn arrival(&mut self, kernel: Option<WallNs>) -> Instant {
        let reading = self.read();
        self.arrival_at(reading, kernel)
    }

    /// Reads the clocks once for a batch of datagrams just read.
    pub(crate) fn read(&mut self) -> Reading {
        let (now, wall) = self.reading();
        Reading { now, wall }
    }

    /// When a datagram of the batch read just before `reading` was taken,
    /// stamped `kernel` by the kernel (if it was), reached the socket, on
    /// the monotonic clock.
    pub(crate) fn arrival_at(&self, reading: Reading, kernel: Option<WallNs>) -> Instant {
        let Reading { now, wall } = reading;
        let Some(stamp) = kernel else {
            return now;
        };
        let age = wall - stamp;
        if self.trust_from.is_some_and(|from| stamp < from)
            || age < 0
            || age > MAX_QUEUE_AGE.as_nanos() as i128
        {
            return now;
        }
        let at = now
            .checked_sub(Duration::from_nanos(age as u64))
            .unwrap_or(now);
        match self.empty_at {
            Some(empty) if at < empty => empty.min(now),
            _ => at,
        }
    }

    /// Reads the clocks (monotonic, wall ns). When the wall clock moved
    /// against the monotonic one since the last reading, it stepped in
    /// between: stamps before now are not trusted.
    fn reading(&mut self) -> (Instant, i128) {
        let (now, wall) = self.clocks.now();
        let wall = wall_ns(wall);
        let stepped = self.last.is_some_and(|(last_wall, last)| {
            let mono = now.saturating_duration_since(last).as_nanos() as i128;
            ((wall - last_wall) - mono).abs() > STEP_TOLERANCE_NS
        });
        if stepped {
            tracing::info!("the wall clock stepped: kernel receive stamps before it are not used");
            self.trust_from = Some(wall);
        }
        self.last = Some((wall, now));
        (now, wall)
    }
}

#[cfg(test)]
mod tests {
    use std::cell::Cell;
    use std::rc::Rc;

    use super::*;

    const MS: u64 = 1_000_000;

    /// Clocks a test moves: both advance together unless the test steps
    /// one of them.
    #[derive(Clone)]
    struct Fake {
        base: Instant,
        mono_ns: Rc<Cell<u64>>,
        wall_ns: Rc<Cell<i128>>,
    }

    impl Fake {
        fn new() -> Self {
            Fake {
                base: Instant::now(),
                mono_ns: Rc::new(Cell::new(0)),
                wall_ns: Rc::new(Cell::new(1_764_500_000 * 1_000_000_000)),
            }
        }
        /// Time passes.
        fn advance(&self, ns: u64) {
            self.mono_ns.set(self.mono_ns.get() + ns);
            self.wall_ns.set(self.wall_ns.get() + i128::from(ns));
        }
        /// The wall clock alone jumps (NTP step, `date -s`; or a suspend,
        /// during which CLOCK_MONOTONIC stands still).
        fn step_wall(&self, ns: i128) {
            self.wall_ns.set(self.wall_ns.get() + ns);
        }
        /// What the kernel stamps a datagram arriving now with.
        fn stamp(&self) -> WallNs {
            self.wall_ns.get()
        }
        fn mono(&self) -> Instant {
            self.base + Duration::from_nanos(self.mono_ns.get())
        }
    }

    impl Clocks for Fake {
        fn now(&self) -> (Instant, SystemTime) {
            let wall = SystemTime::UNIX_EPOCH + Duration::from_nanos(self.wall_ns.get() as u64);
            (self.mono(), wall)
        }
    }

    /// A request sent at 10 ms, its reply reaching the socket at 12 ms and
    /// read at `read_ms`, with `between` done to the clocks after the
    /// reply arrived; the RTT mavping measures.
    fn rtt_ms(read_ms: u64, between: impl Fn(&Fake)) -> f64 {
        let clocks = Fake::new();
        let mut rx = RxTime::with_clocks(clocks.clone());
        clocks.advance(10 * MS);
        let sent = clocks.mono();
        clocks.advance(MS);
        rx.drained();
        clocks.advance(MS);
        let stamp = clocks.stamp();
        between(&clocks);
        clocks.advance((read_ms - 12) * MS);
        let at = rx.arrival(Some(stamp));
        at.duration_since(sent).as_secs_f64() * 1e3
    }

    #[test]
    fn a_stamp_is_taken_back_by_its_age() {
        assert_eq!(rtt_ms(15, |_| {}), 2.0);
        assert_eq!(rtt_ms(12, |_| {}), 2.0);
    }

    #[test]
    fn a_wall_clock_step_between_stamp_and_read_does_not_bend_the_rtt() {
        // Forward 5 s, back 5 s, back an hour: the reply is timed at most
        // as late as its read (15 ms, 5 ms after the send), never earlier
        // than the socket was last found empty (11 ms).
        for step in [
            5_000 * i128::from(MS),
            -5_000 * i128::from(MS),
            -3_600_000 * i128::from(MS),
        ] {
            let rtt = rtt_ms(15, |c| c.step_wall(step));
            assert!((1.0..=5.0).contains(&rtt), "step {step} ns: rtt {rtt} ms");
        }
        // A step of 3 ms forward (it would read as 5 ms more) is caught
        // too: timed at the read.
        assert_eq!(rtt_ms(15, |c| c.step_wall(3 * i128::from(MS))), 5.0);
    }

    #[test]
    fn across_a_suspend_the_wall_clock_runs_on_and_the_monotonic_stands_still() {
        // Ten minutes asleep between the reply's arrival and its read: on
        // CLOCK_MONOTONIC nothing passed, so the RTT stays that of the
        // waking machine, not ten minutes, and not less than 1 ms.
        let rtt = rtt_ms(15, |c| c.step_wall(600_000 * i128::from(MS)));
        assert!((1.0..=5.0).contains(&rtt), "{rtt}");
    }

    #[test]
    fn after_a_step_new_stamps_are_trusted_again() {
        let clocks = Fake::new();
        let mut rx = RxTime::with_clocks(clocks.clone());
        clocks.advance(MS);
        clocks.step_wall(7_000 * i128::from(MS));
        rx.drained();
        clocks.advance(MS);
        let stamp = clocks.stamp();
        let arrived = clocks.mono();
        clocks.advance(3 * MS);
        assert_eq!(rx.arrival(Some(stamp)), arrived);
    }

    #[test]
    fn a_step_after_an_hour_without_a_reading_is_caught_too() {
        let clocks = Fake::new();
        let mut rx = RxTime::with_clocks(clocks.clone());
        clocks.advance(3_600_000 * MS);
        let stamp = clocks.stamp();
        clocks.step_wall(1_000 * i128::from(MS));
        clocks.advance(MS);
        assert_eq!(rx.arrival(Some(stamp)), clocks.mono());
    }

    #[test]
    fn a_step_too_small_to_see_cannot_date_a_reply_before_the_socket_was_empty() {
        // 0.9 ms forward, under the tolerance: the stamp reads 1.2 ms old
        // although the socket was empty 0.5 ms ago. The arrival is the
        // moment it was found empty, not before.
        let clocks = Fake::new();
        let mut rx = RxTime::with_clocks(clocks.clone());
        clocks.advance(5 * MS);
        rx.drained();
        let empty = clocks.mono();
        clocks.advance(MS / 5);
        let stamp = clocks.stamp();
        clocks.step_wall(9 * i128::from(MS) / 10);
        clocks.advance(3 * MS / 10);
        assert_eq!(rx.arrival(Some(stamp)), empty);
    }

    #[test]
    fn no_stamp_or_a_stale_one_is_timed_at_the_read() {
        let clocks = Fake::new();
        let mut rx = RxTime::with_clocks(clocks.clone());
        let stale = clocks.stamp();
        clocks.advance(20_000 * MS);
        let now = clocks.mono();
        assert_eq!(rx.arrival(None), now);
        assert_eq!(rx.arrival(Some(stale)), now);
    }
}
