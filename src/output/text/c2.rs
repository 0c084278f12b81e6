//! The C2 link report in words (`--report c2`), after the run's
//! statistics block and under a heading of its own: the rule it was
//! measured by, availability, continuity, latency, loss each way, the
//! outages by band and the longest, availability by distance, and each
//! failsafe model replayed. Written for a reader of a safety case: every
//! figure says what it is of, lines stay within 100 columns.

use std::io::{self, Write};

use super::format::{counted, percent_or_dash};
use crate::engine::c2::{
    C2Report, DistanceBand, FailsafeReplay, Latency, OneWay, Outage, Outages, Trip,
};

/// Where a line of listed items wraps.
const WIDTH: usize = 100;

/// The whole section, its heading first.
pub(super) fn write_report(out: &mut impl Write, link: &str, r: &C2Report) -> io::Result<()> {
    writeln!(out, "--- {link} C2 link report ---")?;
    writeln!(
        out,
        "rule: up: a frame from the vehicle within {:.1} s; continuity: round trips within {:.1} s",
        r.rule.up_within_s, r.rule.continuity_within_s
    )?;
    match r.availability_pct {
        Some(pct) => writeln!(
            out,
            "availability {pct:.2}% (down {:.1} s of {:.1} s), {} from the vehicle",
            r.down_s,
            r.duration_s,
            counted(r.frames, "frame")
        )?,
        None => writeln!(
            out,
            "availability unknown: the vehicle was never heard in {:.1} s",
            r.duration_s
        )?,
    }
    match &r.continuity {
        Some(c) => writeln!(
            out,
            "continuity {}/{} round trips within {:.1} s ({:.2}%, from {})",
            c.within, c.transactions, r.rule.continuity_within_s, c.pct, c.from
        )?,
        None => writeln!(out, "continuity unknown: no round trip was decided")?,
    }
    write_latency(out, &r.latency)?;
    let l = &r.loss;
    let from = match l.uplink_from.filter(|_| l.uplink_pct.is_some()) {
        Some("link_node_status") => " (the vehicle's LINK_NODE_STATUS)",
        Some(_) => " (split from the round trip)",
        None => "",
    };
    writeln!(
        out,
        "loss downlink {}, uplink {}{from}, round trip {}",
        percent_or_dash(l.downlink_pct),
        percent_or_dash(l.uplink_pct),
        percent_or_dash(l.round_trip_pct)
    )?;
    write_outages(out, &r.outages)?;
    write_distance(out, r)?;
    if r.failsafes.is_empty() {
        // Only without --failsafe: the vehicle named no preset's autopilot.
        writeln!(
            out,
            "failsafe: none replayed: no ArduPilot or PX4 vehicle heard (--failsafe MODEL names one)"
        )?;
    }
    for f in &r.failsafes {
        write_failsafe(out, f)?;
    }
    Ok(())
}

fn write_latency(out: &mut impl Write, l: &Latency) -> io::Result<()> {
    match &l.round_trip {
        Some(p) => writeln!(
            out,
            "latency round trip p50/p99/p99.9 = {:.1}/{:.1}/{:.1} ms, max {:.1} ms ({})",
            p.p50_ms,
            p.p99_ms,
            p.p999_ms,
            p.max_ms,
            counted(p.count, "round trip")
        )?,
        None => writeln!(out, "latency round trip unknown: no round trip completed")?,
    }
    let one_way = |out: &mut dyn Write, name: &str, w: &OneWay| {
        writeln!(
            out,
            "  {name} above its least p50/p99 = {:.1}/{:.1} ms, max {:.1} ms",
            w.p50_ms, w.p99_ms, w.max_ms
        )
    };
    if let Some(w) = &l.uplink {
        one_way(out, "uplink", w)?;
    }
    match (&l.downlink, l.downlink_from) {
        (Some(w), Some("frame_age")) => writeln!(
            out,
            "  downlink: the vehicle's frames' age above their quickest p50/p99 = {:.1}/{:.1} ms, \
             max {:.1} ms",
            w.p50_ms, w.p99_ms, w.max_ms
        )?,
        (Some(w), _) => one_way(out, "downlink", w)?,
        (None, _) => {}
    }
    Ok(())
}

/// The outages by band, as a table, then the longest.
fn write_outages(out: &mut impl Write, o: &Outages) -> io::Result<()> {
    writeln!(out, "outages: {}, {:.1} s in all", o.count, o.total_s)?;
    if o.count > 0 {
        writeln!(out, "  {:<8} {:>6} {:>9}", "band", "count", "total")?;
        for b in &o.bands {
            writeln!(out, "  {:<8} {:>6} {:>7.1} s", b.band, b.count, b.total_s)?;
        }
    }
    if o.longest.is_empty() {
        return Ok(());
    }
    writeln!(out, "longest outages:")?;
    writeln!(
        out,
        "  {:>9} {:>9} {:>9} {:>9}  at",
        "start", "duration", "silence", "distance"
    )?;
    for x in &o.longest {
        writeln!(out, "{}", outage_row(x))?;
    }
    Ok(())
}

fn outage_row(x: &Outage) -> String {
    let distance = x
        .distance_m
        .map_or_else(|| "-".into(), |m| format!("{m:.0} m"));
    let open = if x.open { "  (open at end)" } else { "" };
    let at = x.at_utc.as_deref().unwrap_or("-");
    format!(
        "  {:>7.1} s {:>7.1} s {:>7.1} s {distance:>9}  {at}{open}",
        x.start_s, x.duration_s, x.silence_s
    )
}

/// The distance bands, held to the floor, and where availability fell
/// under it.
fn write_distance(out: &mut impl Write, r: &C2Report) -> io::Result<()> {
    let floor = r.rule.availability_floor_pct;
    if r.distance.is_empty() {
        return writeln!(out, "distance bands: no position of the vehicle known");
    }
    writeln!(
        out,
        "distance bands of {:.0} m (held to {floor:.2}% availability):",
        r.rule.distance_band_m
    )?;
    writeln!(
        out,
        "  {:<13} {:>10} {:>13} {:>8}",
        "from-to m", "observed", "availability", "outages"
    )?;
    for d in &r.distance {
        writeln!(out, "{}", distance_row(d, floor))?;
    }
    if let Some(m) = r.availability_under_floor_from_m {
        writeln!(out, "availability under {floor:.2}% from {m:.0} m")?;
    }
    Ok(())
}

fn distance_row(d: &DistanceBand, floor: f64) -> String {
    let range = format!("{:.0}-{:.0}", d.from_m, d.to_m);
    let under = if d.availability_pct < floor {
        "  under the floor"
    } else {
        ""
    };
    format!(
        "  {range:<13} {:>8.1} s {:>12.2}% {:>8}{under}",
        d.observed_s, d.availability_pct, d.outages
    )
}

/// One failsafe model's replay: what it watches, what was delivered,
/// its trips, the closest call, what independent losses would give.
fn write_failsafe(out: &mut impl Write, f: &FailsafeReplay) -> io::Result<()> {
    let inferred = if f.inferred { " (inferred)" } else { "" };
    writeln!(out, "failsafe {}: {}", f.model, f.setting)?;
    let watches = format!("{}@{}Hz", f.message, f.rate_hz);
    let who = match f.direction {
        "up" => format!("the vehicle checks the ground station's {watches}"),
        "down" => format!("the ground station checks the vehicle's {watches}"),
        other => format!("{other} {watches}"),
    };
    writeln!(
        out,
        "  {} ({who}), basis {}{inferred}",
        f.direction, f.basis
    )?;
    let long = if f.long_timeout_s.is_some() {
        format!(" ({} long)", f.long_trips)
    } else {
        String::new()
    };
    writeln!(
        out,
        "  delivered {}/{} messages, {}{long}",
        f.delivered,
        f.messages,
        counted(f.trips, "trip")
    )?;
    if !f.trip_list.is_empty() {
        let listed = f.trip_list.len() as u64;
        let head = if listed < f.trips {
            format!("  the first {listed} tripped at:")
        } else {
            "  tripped at:".to_string()
        };
        let items: Vec<String> = f.trip_list.iter().map(trip_item).collect();
        for line in wrapped(&head, &items) {
            writeln!(out, "{line}")?;
        }
    }
    if let (Some(wait), Some(margin)) = (f.closest_wait_s, f.closest_margin_s) {
        let at = f
            .closest_at_s
            .map_or_else(String::new, |t| format!(" at {t:.1} s"));
        writeln!(
            out,
            "  closest call: a {wait:.1} s wait{at}, {margin:.1} s short of the {:.1} s timeout",
            f.timeout_s
        )?;
    }
    if let Some(e) = f.expected_if_independent {
        writeln!(
            out,
            "  expected if each message were lost independently: {} trips",
            two_significant(e)
        )?;
    }
    Ok(())
}

/// `420.5 s for 5.5 s (long)`, `599.5 s (open at end)`.
fn trip_item(t: &Trip) -> String {
    let lasted = if t.open {
        "open at end".to_string()
    } else {
        format!("for {:.1} s", t.lasted_s)
    };
    let long = if t.long { ", long" } else { "" };
    format!("{:.1} s ({lasted}{long})", t.at_s)
}

/// `head` and the items, comma-separated, on lines within [`WIDTH`]
/// (the next lines indented under the first item).
fn wrapped(head: &str, items: &[String]) -> Vec<String> {
    let indent = " ".repeat(head.len() + 1);
    let mut lines = vec![head.to_string()];
    for (i, item) in items.iter().enumerate() {
        let sep = if i + 1 < items.len() { "," } else { "" };
        let last = lines.last_mut().expect("a first line");
        if i > 0 && last.len() + 1 + item.len() + sep.len() > WIDTH {
            lines.push(format!("{indent}{item}{sep}"));
        } else {
            *last += &format!(" {item}{sep}");
        }
    }
    lines
}

/// An expectation to two significant digits, in scientific notation
/// below 0.01 (`1.5e-7`).
pub(crate) fn two_significant(v: f64) -> String {
    if v == 0.0 {
        "0".into()
    } else if v >= 0.01 {
        let decimals = (1 - v.log10().floor() as i32).max(0) as usize;
        format!("{v:.decimals$}")
    } else {
        format!("{v:.1e}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::output::runs::c2_report;

    fn text(r: &C2Report) -> String {
        let mut out = Vec::new();
        write_report(&mut out, "sim:", r).unwrap();
        String::from_utf8(out).unwrap()
    }

    #[test]
    fn the_report_reads_as_a_page_of_a_safety_case() {
        insta::assert_snapshot!(text(&c2_report()));
    }

    #[test]
    fn every_line_fits_in_100_columns() {
        let mut r = c2_report();
        // Ten listed trips of fourteen: they wrap.
        let f = &mut r.failsafes[1];
        f.trips = 14;
        f.trip_list = (0..10)
            .map(|k| Trip {
                at_s: 100.0 * f64::from(k) + 0.5,
                lasted_s: 12.5,
                open: false,
                long: k % 2 == 0,
            })
            .collect();
        let text = text(&r);
        for line in text.lines() {
            assert!(line.len() <= WIDTH, "{} columns: {line}", line.len());
        }
        assert!(
            text.contains("  the first 10 tripped at: 0.5 s (for 12.5 s, long),"),
            "{text}"
        );
        // Every trip listed once, across the wrapped lines.
        assert_eq!(text.matches("(for 12.5 s").count(), 10, "{text}");
    }

    #[test]
    fn what_is_unknown_is_said_so() {
        let mut r = c2_report();
        r.availability_pct = None;
        r.continuity = None;
        r.latency = Latency {
            round_trip: None,
            uplink: None,
            downlink: None,
            downlink_from: None,
        };
        r.loss.uplink_pct = None;
        r.outages = Outages {
            count: 0,
            total_s: 0.0,
            bands: vec![],
            longest: vec![],
        };
        r.distance.clear();
        r.availability_under_floor_from_m = None;
        r.failsafes.clear();
        assert_eq!(
            text(&r),
            "--- sim: C2 link report ---\n\
             rule: up: a frame from the vehicle within 2.0 s; continuity: round trips within 1.0 s\n\
             availability unknown: the vehicle was never heard in 600.0 s\n\
             continuity unknown: no round trip was decided\n\
             latency round trip unknown: no round trip completed\n\
             loss downlink 0.50%, uplink -, round trip 1.70%\n\
             outages: 0, 0.0 s in all\n\
             distance bands: no position of the vehicle known\n\
             failsafe: none replayed: no ArduPilot or PX4 vehicle heard (--failsafe MODEL names one)\n"
        );
    }

    #[test]
    fn expectations_keep_two_significant_digits() {
        assert_eq!(two_significant(0.0), "0");
        assert_eq!(two_significant(1.475e-7), "1.5e-7");
        assert_eq!(two_significant(0.0103), "0.010");
        assert_eq!(two_significant(0.012), "0.012");
        assert_eq!(two_significant(2.5), "2.5");
        assert_eq!(two_significant(14.3), "14");
    }
}
