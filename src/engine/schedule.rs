//! When each request is due: the n-th goes out at start + n x interval.
//!
//! Sending on an absolute schedule (not "sleep, then send") keeps the rate
//! from drifting and stops a slow reply from delaying the next request, so
//! there is no coordinated omission.

use super::Nanos;

#[derive(Debug, Clone)]
pub(crate) struct Schedule {
    start: Nanos,
    interval: Nanos,
    limit: Option<u64>,
    issued: u64,
}

impl Schedule {
    pub(crate) fn new(start: Nanos, interval: Nanos, limit: Option<u64>) -> Self {
        Schedule {
            start,
            interval,
            limit,
            issued: 0,
        }
    }

    /// Planned send time of request `n`.
    pub(crate) fn planned(&self, n: u64) -> Nanos {
        self.start.saturating_add(n.saturating_mul(self.interval))
    }

    /// Planned time of the next request, or `None` when all are issued.
    pub(crate) fn next_due(&self) -> Option<Nanos> {
        if self.finished() {
            None
        } else {
            Some(self.planned(self.issued))
        }
    }

    /// Takes the next request if it is due at `now`, returning its number and
    /// planned time. Call in a loop: at rates above the timer's resolution
    /// several requests are due at one wake-up.
    pub(crate) fn take_due(&mut self, now: Nanos) -> Option<(u64, Nanos)> {
        let planned = self.next_due()?;
        if planned > now {
            return None;
        }
        let n = self.issued;
        self.issued += 1;
        Some((n, planned))
    }

    pub(crate) fn issued(&self) -> u64 {
        self.issued
    }

    pub(crate) fn finished(&self) -> bool {
        self.limit.is_some_and(|limit| self.issued >= limit)
    }

    /// Stops issuing (deadline or Ctrl-C).
    pub(crate) fn stop(&mut self) {
        self.limit = Some(self.issued);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn late_wake_up_releases_every_due_request_without_drift() {
        let mut s = Schedule::new(1_000, 100, Some(10));
        assert_eq!(s.take_due(999), None);
        // Woken 350 ns late: requests 0..=3 are due now, 4 stays on plan.
        let due: Vec<_> = std::iter::from_fn(|| s.take_due(1_350)).collect();
        assert_eq!(due, vec![(0, 1_000), (1, 1_100), (2, 1_200), (3, 1_300)]);
        assert_eq!(s.next_due(), Some(1_400));
    }

    #[test]
    fn count_limits_and_stop() {
        let mut s = Schedule::new(0, 10, Some(2));
        assert!(s.take_due(100).is_some());
        assert!(s.take_due(100).is_some());
        assert!(s.take_due(100).is_none());
        assert!(s.finished());
        let mut unlimited = Schedule::new(0, 10, None);
        unlimited.take_due(0);
        unlimited.stop();
        assert!(unlimited.finished());
        assert_eq!(unlimited.issued(), 1);
    }
}
