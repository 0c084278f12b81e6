//! A log's stamps as the session's clock: time 0 is the first record, and
//! each record is dated by how far its stamp is past the latest one.
//! Pure: stamps in, session nanoseconds out.
//!
//! What the tools write, and how it is read:
//! - microseconds since the Unix epoch, big-endian (every tool);
//! - QGroundControl and pymavlink's own logger round them: QGroundControl
//!   writes milliseconds × 1000, pymavlink `usec & ~3`;
//! - MAVProxy puts its link number in the two lowest bits, `(usec & ~3) |
//!   link`, 3 marking what MAVProxy itself sent; frames it forwards from
//!   its outputs keep a plain stamp. So records are dated by the stamp
//!   less those bits (a 4 µs grid), and the bits are handed on as the
//!   frame's path for the per-link figures, which only evidence in the
//!   frames turns on (see the passive probe's `links`).
//!
//! Stamps that go back or leap are kept from bending the clock:
//! - up to [`JITTER_NS`] behind the latest, a record is dated at the
//!   latest (frames logged a little out of order);
//! - further behind, or more than 3 days ahead (pymavlink's bound), the
//!   clock was stepped (NTP, a log appended days later): the timeline goes
//!   on from the latest time with no gap, and the step is counted.

use serde::Serialize;

use super::records::PLAUSIBLE_US;

/// A stamp up to this far behind the latest is frames logged out of
/// order, not a clock step.
pub(crate) const JITTER_NS: u64 = 1_000_000_000;
/// MAVProxy's link number.
const LINK_BITS: u64 = 3;

/// What the stamps were like.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub(crate) struct StampFacts {
    /// The first record's stamp (µs since the Unix epoch, link bits
    /// cleared): the session's time 0.
    pub(crate) first_us: u64,
    /// The latest stamp seen (the same way).
    pub(crate) latest_us: u64,
    /// Records whose stamp was behind the latest (dated at the latest).
    pub(crate) behind: u64,
    /// Clock steps: a stamp more than 1 s behind or 3 days ahead.
    pub(crate) steps: u64,
    /// Every stamp was a whole millisecond (QGroundControl's ms × 1000).
    pub(crate) whole_ms: bool,
    /// Records by the stamps' two lowest bits (MAVProxy's link number).
    pub(crate) low_bits: [u64; 4],
}

/// Dates records by their stamps: see the module's rules.
#[derive(Debug, Clone, Default)]
pub(crate) struct LogClock {
    /// The latest stamp and the session time it was dated at.
    latest: Option<(u64, u64)>,
    facts: Option<StampFacts>,
}

impl LogClock {
    /// The session time (ns) of a record stamped `stamp`, and its link
    /// bits.
    pub(crate) fn date(&mut self, stamp: u64) -> (u64, u8) {
        let us = stamp & !LINK_BITS;
        let link = (stamp & LINK_BITS) as u8;
        let facts = self.facts.get_or_insert(StampFacts {
            first_us: us,
            latest_us: us,
            behind: 0,
            steps: 0,
            whole_ms: true,
            low_bits: [0; 4],
        });
        facts.low_bits[usize::from(link)] += 1;
        facts.whole_ms &= stamp.is_multiple_of(1000);
        let Some((latest_us, latest_t)) = self.latest else {
            self.latest = Some((us, 0));
            return (0, link);
        };
        let t = if us >= latest_us {
            let ahead = us - latest_us;
            if ahead > PLAUSIBLE_US {
                facts.steps += 1;
                latest_t
            } else {
                latest_t.saturating_add(ahead.saturating_mul(1000))
            }
        } else {
            let behind = (latest_us - us).saturating_mul(1000);
            if behind > JITTER_NS {
                facts.steps += 1;
            } else {
                facts.behind += 1;
                // Dated at the latest; the latest stays.
                return (latest_t, link);
            }
            latest_t
        };
        facts.latest_us = us;
        self.latest = Some((us, t));
        (t, link)
    }

    /// The stamps so far; `None` before the first record.
    pub(crate) fn facts(&self) -> Option<StampFacts> {
        self.facts
    }

    /// The session time of the latest record.
    pub(crate) fn latest(&self) -> u64 {
        self.latest.map_or(0, |(_, t)| t)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const T0: u64 = 1_764_500_000_000_000;

    #[test]
    fn time_zero_is_the_first_record_and_link_bits_are_not_time() {
        let mut c = LogClock::default();
        assert_eq!(c.date(T0 | 1), (0, 1));
        assert_eq!(c.date((T0 + 20_000) | 3), (20_000_000, 3));
        assert_eq!(c.date(T0 + 20_000), (20_000_000, 0));
        let f = c.facts().unwrap();
        assert_eq!(f.first_us, T0);
        assert_eq!(f.low_bits, [1, 1, 0, 1]);
        assert!(!f.whole_ms, "a link bit is not a whole millisecond");
        assert_eq!(f.behind, 0);
    }

    #[test]
    fn a_little_behind_is_dated_at_the_latest() {
        let mut c = LogClock::default();
        c.date(T0);
        c.date(T0 + 500_000);
        assert_eq!(c.date(T0 + 499_000).0, 500_000_000);
        // The latest stays: the next is dated from it.
        assert_eq!(c.date(T0 + 501_000).0, 501_000_000);
        assert_eq!(c.facts().unwrap().behind, 1);
        assert!(c.facts().unwrap().whole_ms);
    }

    #[test]
    fn a_clock_step_either_way_leaves_no_gap() {
        let mut c = LogClock::default();
        c.date(T0);
        c.date(T0 + 10_000_000);
        // Back an hour: NTP stepped the ground station's clock.
        assert_eq!(c.date(T0 - 3_600_000_000).0, 10_000_000_000);
        assert_eq!(c.date(T0 - 3_599_000_000).0, 11_000_000_000);
        // Ahead a week: a log appended to later.
        assert_eq!(c.date(T0 + 7 * 86_400_000_000).0, 11_000_000_000);
        assert_eq!(c.date(T0 + 7 * 86_400_000_000 + 20).0, 11_000_020_000);
        assert_eq!(c.facts().unwrap().steps, 2);
        // A pause of a day is a pause.
        assert_eq!(
            c.date(T0 + 8 * 86_400_000_000).0,
            11_000_020_000 + 86_399_999_980_000
        );
    }
}
