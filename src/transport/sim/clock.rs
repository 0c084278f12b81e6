//! The clocks: a responder's own clock (offset and drift, for TIMESYNC),
//! and the link's time in nanoseconds since it opened (the radio pair's
//! time) and back.

use std::time::Duration;

use tokio::time::Instant;

use super::link::SimLink;

impl SimLink {
    /// A responder's clock at `t`.
    pub(super) fn clock_ns(&self, t: Instant) -> i64 {
        let t = (t - self.started).as_nanos() as i64;
        let drift = (t as f64 * self.params.drift_ppm * 1e-6).round() as i64;
        self.params
            .clock_offset_ns
            .saturating_add(t)
            .saturating_add(drift)
    }

    /// Nanoseconds since the link opened: the radio pair's time.
    pub(super) fn ns(&self, t: Instant) -> u64 {
        t.saturating_duration_since(self.started).as_nanos() as u64
    }

    pub(super) fn instant(&self, ns: u64) -> Instant {
        self.started + Duration::from_nanos(ns)
    }
}
