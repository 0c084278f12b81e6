//! Numbers as the text shows them: milliseconds as ping prints them,
//! rates and the request interval.

use crate::engine::Nanos;

/// Milliseconds with µs resolution, as ping prints them.
pub(super) fn ms(ns: Nanos) -> String {
    format!("{:.3}", ns as f64 / 1e6)
}

pub(super) fn ms_us(us: f64) -> String {
    format!("{:.3}", us / 1e3)
}

/// A rate with one decimal, or three significant digits below 0.1/s (a
/// PING every 30 s is 0.0333/s, not "0.0/s").
pub(super) fn per_second(hz: f64) -> String {
    if hz >= 0.1 || hz <= 0.0 || !hz.is_finite() {
        format!("{hz:.1}")
    } else {
        let decimals = (-hz.log10()).ceil() as usize + 2;
        format!("{hz:.decimals$}")
    }
}

pub(super) fn rate(interval: std::time::Duration) -> String {
    let per_s = 1.0 / interval.as_secs_f64();
    if per_s >= 1.0 && per_s.fract() == 0.0 {
        format!("{per_s}/s")
    } else {
        format!("every {}", humantime::format_duration(interval))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn slow_rates_keep_three_significant_digits() {
        assert_eq!(per_second(5.0), "5.0");
        assert_eq!(per_second(0.1), "0.1");
        assert_eq!(per_second(1.0 / 30.0), "0.0333");
        assert_eq!(per_second(1.0 / 3600.0), "0.000278");
        assert_eq!(per_second(0.0), "0.0");
    }
}
