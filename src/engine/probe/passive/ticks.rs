//! When the table of sources is told to observers while a run goes on:
//! once a second of session time (the virtual clock's on simulated and
//! logged links), so exporters, the live view, samples and plots follow
//! the sequence figures without a per-frame event.

use crate::engine::Nanos;

/// Session time between two tellings of the table.
pub(crate) const SOURCES_EVERY_NS: Nanos = 1_000_000_000;

/// A once-a-second timer a driver keeps beside its table.
#[derive(Debug, Clone)]
pub(crate) struct Ticks {
    next: Nanos,
    due: Option<Nanos>,
}

impl Default for Ticks {
    fn default() -> Self {
        Ticks {
            next: SOURCES_EVERY_NS,
            due: None,
        }
    }
}

impl Ticks {
    /// When the session should wake for the next telling.
    pub(crate) fn next_deadline(&self) -> Nanos {
        self.next
    }

    /// Notes a telling due at `now`; tellings missed while the session was
    /// busy become one (the table is cumulative, so nothing is lost).
    pub(crate) fn expire(&mut self, now: Nanos) {
        if now < self.next {
            return;
        }
        self.due = Some(now);
        let behind = (now - self.next) / SOURCES_EVERY_NS + 1;
        self.next += behind * SOURCES_EVERY_NS;
    }

    /// The time of the telling due, once.
    pub(crate) fn take(&mut self) -> Option<Nanos> {
        self.due.take()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_telling_per_second_and_missed_ones_merge() {
        let mut t = Ticks::default();
        t.expire(999_999_999);
        assert_eq!(t.take(), None);
        t.expire(1_000_000_000);
        assert_eq!(t.take(), Some(1_000_000_000));
        assert_eq!(t.take(), None);
        assert_eq!(t.next_deadline(), 2_000_000_000);
        // Busy for 3.5 s: one telling, the next on the second after.
        t.expire(4_500_000_000);
        assert_eq!(t.take(), Some(4_500_000_000));
        assert_eq!(t.next_deadline(), 5_000_000_000);
    }
}
