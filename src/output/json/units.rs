//! Times and durations as the lines give them: seconds and microseconds.

use crate::engine::Nanos;

pub(super) fn seconds(t: Nanos) -> f64 {
    t as f64 / 1e9
}

pub(super) fn us(ns: Nanos) -> f64 {
    ns as f64 / 1e3
}
