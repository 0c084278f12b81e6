//! Numbers as the text shows them: milliseconds as ping prints them,
//! percentages, rates and the request interval; and who a system is.

use crate::engine::roster::Identity;
use crate::engine::Nanos;
use crate::frame::SysComp;

/// Milliseconds with µs resolution, as ping prints them.
pub(super) fn ms(ns: Nanos) -> String {
    format!("{:.3}", ns as f64 / 1e6)
}

pub(super) fn ms_us(us: f64) -> String {
    format!("{:.3}", us / 1e3)
}

/// Figures in ms, slash-separated as the `min/mean/max` lines give them.
pub(super) fn ms_each(us: &[f64]) -> String {
    let each: Vec<String> = us.iter().map(|&v| ms_us(v)).collect();
    each.join("/")
}

/// A percentage with two decimals, `-` where there is none.
pub(super) fn percent_or_dash(pct: Option<f64>) -> String {
    pct.map_or_else(|| "-".into(), |p| format!("{p:.2}%"))
}

/// A figure to the unit, `none` (`?`, `-`) where it is not known.
pub(super) fn whole_or(v: Option<f64>, none: &str) -> String {
    v.map_or_else(|| none.into(), |v| format!("{v:.0}"))
}

/// What a system said it is in its HEARTBEAT: `quadrotor, ArduPilot`.
pub(super) fn identity(i: &Identity) -> String {
    format!("{}, {}", i.vehicle, i.autopilot_said())
}

/// `1/1 (quadrotor, ArduPilot)`, or the ids alone if it said nothing.
pub(super) fn who(id: SysComp, said: Option<&Identity>) -> String {
    match said {
        Some(i) => format!("{id} ({})", identity(i)),
        None => id.to_string(),
    }
}

/// `1 silence`, `2 silences`.
pub(super) fn counted(n: u64, what: &str) -> String {
    format!("{n} {what}{}", if n == 1 { "" } else { "s" })
}

/// A line's optional part: `text` of the count where there is any,
/// nothing where there is none.
pub(super) fn if_any(n: u64, text: impl FnOnce(u64) -> String) -> String {
    if n == 0 {
        String::new()
    } else {
        text(n)
    }
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
