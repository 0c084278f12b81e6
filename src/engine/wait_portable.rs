//! How the session waits for a time on the portable path (every system
//! but Linux, and Linux with `--features portable`): no timerfd and no
//! `clock_nanosleep`, so the runtime's timer, which rounds up to the
//! millisecond, takes the wait to within [`SPIN_NS`] of the deadline and
//! a spin that yields to the runtime does the rest. The spin keeps a
//! 1 kHz schedule on time at the price of CPU (docs/performance.md has
//! both paths' figures); a reply still wakes the session at once, since
//! the runtime polls the link at every yield. A session on a virtual
//! clock (the simulated link) waits on tokio's timer alone, which is what
//! moves that clock.

use std::time::Duration;

use super::link_io::Clock;
use super::Nanos;

/// What is left to the spin: tokio's timer fires up to a millisecond
/// late, so it is asked to wake this much before the deadline.
const SPIN_NS: Nanos = 1_500_000;

/// Blocks the thread until session time `at`: a sleep for all but the
/// last [`SPIN_NS`], then a spin. (The session calls it only on links the
/// kernel dates, which the portable path has none of; kept for the one
/// interface both paths share.)
pub(crate) fn block_until(clock: &Clock, at: Nanos) {
    let ahead = at.saturating_sub(clock.now());
    if ahead > SPIN_NS {
        std::thread::sleep(Duration::from_nanos(ahead - SPIN_NS));
    }
    while clock.now() < at {
        std::hint::spin_loop();
    }
}

/// Timer slack is a Linux knob; nothing to tighten here.
pub(crate) fn tighten_timer_slack() {}

/// Waits for a session time in a `select!`: tokio's timer, then a spin
/// for the sub-millisecond remainder when `precise`.
pub(crate) struct Waiter {
    precise: bool,
}

impl Waiter {
    pub(crate) fn new(precise: bool) -> Self {
        Waiter { precise }
    }

    /// Waits until session time `wake`, or forever when there is none.
    /// Cancel-safe: it holds no state between polls but the deadline.
    pub(crate) async fn until(&mut self, clock: &Clock, wake: Option<Nanos>) {
        let Some(at) = wake else {
            return std::future::pending().await;
        };
        if !self.precise {
            return clock.sleep_until(Some(at)).await;
        }
        if at.saturating_sub(clock.now()) > SPIN_NS {
            clock.sleep_until(Some(at - SPIN_NS)).await;
        }
        // Yielding, not spinning in place: the runtime polls the link (and
        // the signals) between turns, so a reply is not held up.
        while clock.now() < at {
            tokio::task::yield_now().await;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[tokio::test]
    async fn the_waiter_wakes_at_the_time_asked_not_before() {
        let clock = Clock::start();
        let mut waiter = Waiter::new(true);
        for k in [1, 3, 7] {
            let at = clock.now() + k * 300_000;
            waiter.until(&clock, Some(at)).await;
            assert!(clock.now() >= at);
        }
        waiter.until(&clock, Some(0)).await;
    }

    #[tokio::test]
    async fn a_cancelled_wait_can_be_waited_again() {
        let clock = Clock::start();
        let mut waiter = Waiter::new(true);
        let at = clock.now() + 50_000_000;
        let cancelled =
            tokio::time::timeout(Duration::from_millis(1), waiter.until(&clock, Some(at)));
        assert!(cancelled.await.is_err());
        waiter.until(&clock, Some(at)).await;
        assert!(clock.now() >= at);
    }

    #[test]
    fn blocking_sleep_ends_at_the_deadline() {
        let clock = Clock::start();
        for ahead in [500_000, 3_000_000] {
            let at = clock.now() + ahead;
            block_until(&clock, at);
            assert!(clock.now() >= at);
        }
    }
}
