//! How the session waits for a time. tokio's timer rounds to the
//! millisecond, too coarse for a schedule of 1,000 requests a second and
//! more, and spinning for the remainder costs a core. So a real-time
//! session waits on the kernel's high-resolution timers, on an absolute
//! deadline (no drift from the time spent deciding to sleep):
//!
//! - [`Waiter`]: a `timerfd` the runtime watches alongside the link, so a
//!   reply still wakes the session at once;
//! - [`block_until`]: `clock_nanosleep(TIMER_ABSTIME)` that nothing else
//!   wakes, for fast schedules on links that date each datagram themselves
//!   (a reply read late keeps its kernel timestamp), so the session wakes
//!   once per send, not once per send and once per reply.
//!
//! Either way it wakes within the kernel's wake-up latency (timer slack set
//! to 1 µs). A session on a virtual clock (the simulated link) waits on
//! tokio's timer, which is what moves that clock.

// Registering the timerfd with tokio's reactor is the crate's one unsafe
// call (the descriptor must stay open while registered): the rest of the
// crate denies unsafe code (Cargo.toml's [lints]).
#![allow(unsafe_code)]

use std::io;
use std::os::fd::{AsFd, AsRawFd, RawFd};
use std::time::Duration;

use nix::sys::time::TimeSpec;
use nix::sys::timerfd::{ClockId, Expiration, TimerFd, TimerFlags, TimerSetTimeFlags};
use nix::time::{clock_gettime, clock_nanosleep, ClockNanosleepFlags};
use tokio::io::unix::AsyncFd;
use tokio::io::Interest;

use super::link_io::Clock;
use super::Nanos;

/// Session time `at` as a point on CLOCK_MONOTONIC, which is the clock the
/// session's own clock reads (std's `Instant` on Linux); a time already
/// past maps to now.
fn monotonic(clock: &Clock, at: Nanos) -> io::Result<TimeSpec> {
    let now_ts = clock_gettime(nix::time::ClockId::CLOCK_MONOTONIC)?;
    let ahead = at.saturating_sub(clock.now());
    Ok(now_ts + TimeSpec::from_duration(Duration::from_nanos(ahead)))
}

/// Blocks the thread until session time `at`, or a signal. Only for
/// real-time sessions, and only briefly: nothing else on the thread runs
/// meanwhile.
pub(crate) fn block_until(clock: &Clock, at: Nanos) {
    if let Ok(deadline) = monotonic(clock, at) {
        // EINTR (a signal) ends the sleep early; the caller looks again.
        let _ = clock_nanosleep(
            nix::time::ClockId::CLOCK_MONOTONIC,
            ClockNanosleepFlags::TIMER_ABSTIME,
            &deadline,
        );
    }
}

/// Lets the OS wake us within a few µs of a requested time instead of the
/// default 50 µs slack (Linux); harmless where it is not supported.
pub(crate) fn tighten_timer_slack() {
    #[cfg(target_os = "linux")]
    let _ = nix::sys::prctl::set_timerslack(1_000);
}

/// A timerfd, as the runtime's readiness wants it.
struct Timer(TimerFd);

impl AsRawFd for Timer {
    fn as_raw_fd(&self) -> RawFd {
        self.0.as_fd().as_raw_fd()
    }
}

/// Waits for a session time in a `select!`: precisely on a timerfd, or on
/// tokio's timer where the clock is virtual or no timerfd can be had.
pub(crate) struct Waiter(How);

enum How {
    Tokio,
    Precise {
        timer: AsyncFd<Timer>,
        /// The time the timer is set for, so waiting again for the same
        /// time costs no system call.
        armed: Option<Nanos>,
    },
}

impl Waiter {
    /// A precise waiter when `precise` and the system has timerfd.
    pub(crate) fn new(precise: bool) -> Self {
        if !precise {
            return Waiter(How::Tokio);
        }
        let flags = TimerFlags::TFD_NONBLOCK | TimerFlags::TFD_CLOEXEC;
        let registered = TimerFd::new(ClockId::CLOCK_MONOTONIC, flags)
            .map_err(io::Error::from)
            .and_then(|fd| {
                // SAFETY: `Timer` owns its descriptor (the OwnedFd inside
                // TimerFd) and always returns that one, so it stays open and
                // the same for as long as the AsyncFd holds the Timer.
                unsafe { AsyncFd::register_with_interest(Timer(fd), Interest::READABLE) }
                    .map_err(|e| e.into_parts().1)
            });
        match registered {
            Ok(timer) => Waiter(How::Precise { timer, armed: None }),
            Err(e) => {
                tracing::info!(error = %e, "no timerfd: sends are paced on tokio's 1 ms timer");
                Waiter(How::Tokio)
            }
        }
    }

    /// Waits until session time `wake`, or forever when there is none.
    /// Cancel-safe: dropped before it fires, the timer stays set, and
    /// waiting again for the same time costs nothing more.
    pub(crate) async fn until(&mut self, clock: &Clock, wake: Option<Nanos>) {
        let Some(at) = wake else {
            return std::future::pending().await;
        };
        let How::Precise { timer, armed } = &mut self.0 else {
            return clock.sleep_until(Some(at)).await;
        };
        if *armed != Some(at) {
            let set = monotonic(clock, at).and_then(|deadline| {
                timer
                    .get_ref()
                    .0
                    .set(
                        Expiration::OneShot(deadline),
                        TimerSetTimeFlags::TFD_TIMER_ABSTIME,
                    )
                    .map_err(io::Error::from)
            });
            if let Err(e) = set {
                tracing::debug!(error = %e, "timerfd_settime failed; tokio's timer instead");
                return clock.sleep_until(Some(at)).await;
            }
            *armed = Some(at);
        }
        loop {
            let Ok(mut ready) = timer.readable().await else {
                return clock.sleep_until(Some(at)).await;
            };
            // Reading the expiry count clears it; nothing to read yet means
            // the readiness was stale (the timer was set again since).
            let fired = ready.try_io(|t| {
                let mut count = [0u8; 8];
                nix::unistd::read(t.get_ref().0.as_fd(), &mut count).map_err(io::Error::from)
            });
            if let Ok(Ok(_)) = fired {
                *armed = None;
                return;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[tokio::test]
    async fn the_precise_waiter_wakes_at_the_time_asked_not_before() {
        let clock = Clock::start();
        let mut waiter = Waiter::new(true);
        assert!(matches!(waiter.0, How::Precise { .. }));
        for k in 1..=3 {
            let at = clock.now() + k * 300_000;
            waiter.until(&clock, Some(at)).await;
            assert!(clock.now() >= at);
        }
        // A time already past returns at once.
        waiter.until(&clock, Some(0)).await;
    }

    #[tokio::test]
    async fn a_cancelled_wait_leaves_the_timer_set_for_the_same_time() {
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
        let at = clock.now() + 500_000;
        block_until(&clock, at);
        assert!(clock.now() >= at);
    }
}
