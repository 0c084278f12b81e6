//! The comparison as text: each link compared, a line per figure with A,
//! B, and B - A with its interval and what it says.

use std::io::{self, Write};

use super::bands::Bands;
use super::report::{
    AgeComparison, Finding, LinkComparison, LossComparison, PairedBy, Report, Role, Row, RunKind,
    ShiftComparison,
};

/// Writes the report.
pub(crate) fn write_text(out: &mut dyn Write, r: &Report) -> io::Result<()> {
    writeln!(out, "A: {}", r.a)?;
    writeln!(out, "B: {}", r.b)?;
    writeln!(
        out,
        "95 % intervals: loss by Newcombe's hybrid score method; median RTT by bootstrap \
         ({} resamples of each run's RTT histogram, seed {})",
        r.method.resamples, r.method.seed
    )?;
    for link in &r.links {
        writeln!(out)?;
        write_link(out, link)?;
    }
    for m in &r.not_compared {
        writeln!(out)?;
        writeln!(
            out,
            "not compared: A {} ({}) and B {} ({}): a probe run's loss (requests unanswered) \
             and a passive run's (frames missing from a sequence) are not the same measure",
            m.a_link,
            kind(m.a_kind),
            m.b_link,
            kind(m.b_kind)
        )?;
    }
    for (side, links) in [("A", &r.only_in_a), ("B", &r.only_in_b)] {
        if !links.is_empty() {
            writeln!(out)?;
            writeln!(out, "only in {side}, not compared: {}", links.join(", "))?;
        }
    }
    Ok(())
}

fn kind(k: RunKind) -> &'static str {
    match k {
        RunKind::Probe => "a probe run",
        RunKind::Passive => "a passive run",
        RunKind::Log => "a telemetry log",
    }
}

fn write_link(out: &mut dyn Write, link: &LinkComparison) -> io::Result<()> {
    match link.paired_by {
        PairedBy::Link => writeln!(out, "link {} (in both files)", link.a_link)?,
        PairedBy::OnlySummary => {
            writeln!(out, "link A {}", link.a_link)?;
            writeln!(
                out,
                "     B {} (the only summary in each file)",
                link.b_link
            )?;
        }
    }
    for row in &link.rows {
        write_row(out, row, link.ids_differ)?;
    }
    let unmatched = |ids: &[crate::frame::SysComp]| {
        let ids: Vec<String> = ids.iter().map(ToString::to_string).collect();
        ids.join(", ")
    };
    for (side, ids) in [("A", &link.only_in_a), ("B", &link.only_in_b)] {
        if !ids.is_empty() {
            writeln!(out, "  only in {side}: {}", unmatched(ids))?;
        }
    }
    // With one source, the link as a whole is that source again.
    let sources = link.rows.iter().filter(|r| r.role == Role::Source).count();
    if let Some(totals) = link.totals.as_ref().filter(|_| sources != 1) {
        writeln!(
            out,
            "  the link as a whole (every source but the radio and the ground station)"
        )?;
        loss_line(out, totals)?;
    }
    if let Some(bands) = &link.bands {
        write_bands(out, bands)?;
    }
    Ok(())
}

fn write_row(out: &mut dyn Write, row: &Row, ids_differ: bool) -> io::Result<()> {
    let what = match row.role {
        Role::Responder => "responder",
        Role::Source => "source",
        Role::Radio => "radio",
    };
    if ids_differ {
        writeln!(
            out,
            "  {what} {} in A, {} in B (the only one in each)",
            row.a_id, row.b_id
        )?;
    } else {
        writeln!(out, "  {what} {}", row.a_id)?;
    }
    loss_line(out, &row.loss)?;
    if let Some(rtt) = &row.rtt_p50 {
        rtt_line(out, rtt)?;
    }
    if let Some(age) = &row.age {
        age_lines(out, age)?;
    }
    Ok(())
}

/// `1.80 % (9/500)`, or `- (0/0)`.
fn loss_cell(lost: u64, of: u64, pct: Option<f64>) -> String {
    match pct {
        Some(p) => format!("{p:.2} % ({lost}/{of})"),
        None => format!("- ({lost}/{of})"),
    }
}

fn loss_finding(f: Finding) -> &'static str {
    match f {
        Finding::BHigher => "B loses more",
        Finding::BLower => "B loses less",
        Finding::NoClearDifference => "no clear difference",
        Finding::NoData => "nothing counted in one run",
    }
}

/// `+8.40 pp [+5.63, +11.31]  B loses more`.
fn loss_difference(c: &LossComparison) -> String {
    match (c.difference_pp, c.low_pp, c.high_pp) {
        (Some(d), Some(l), Some(h)) => {
            format!("{d:+.2} pp [{l:+.2}, {h:+.2}]  {}", loss_finding(c.finding))
        }
        _ => loss_finding(c.finding).to_string(),
    }
}

fn loss_line(out: &mut dyn Write, c: &LossComparison) -> io::Result<()> {
    writeln!(
        out,
        "    loss        A {:<22} B {:<22} B-A {}",
        loss_cell(c.a.lost, c.a.of, c.a.pct),
        loss_cell(c.b.lost, c.b.of, c.b.pct),
        loss_difference(c)
    )
}

fn rtt_line(out: &mut dyn Write, s: &ShiftComparison) -> io::Result<()> {
    let finding = match s.finding {
        Finding::BHigher => "B slower",
        Finding::BLower => "B faster",
        Finding::NoClearDifference | Finding::NoData => "no clear shift",
    };
    let ms = |us: f64| us / 1000.0;
    writeln!(
        out,
        "    median RTT  A {:<22} B {:<22} B-A {:+.3} ms [{:+.3}, {:+.3}]  {finding}",
        format!("{:.3} ms", ms(s.a_p50_us)),
        format!("{:.3} ms", ms(s.b_p50_us)),
        ms(s.shift_us),
        ms(s.low_us),
        ms(s.high_us),
    )
}

fn age_lines(out: &mut dyn Write, a: &AgeComparison) -> io::Result<()> {
    for (label, x, y, d) in [
        ("age p50", a.a_p50_ms, a.b_p50_ms, a.p50_change_ms),
        ("age p99", a.a_p99_ms, a.b_p99_ms, a.p99_change_ms),
    ] {
        // Not "-0.0": a change that rounds to nothing has no sign.
        let d = if (d * 10.0).round() == 0.0 { 0.0 } else { d };
        writeln!(
            out,
            "    {label:<11} A {:<22} B {:<22} B-A {d:+.1} ms (no interval: a summary keeps \
             only its percentiles)",
            format!("{x:.1} ms"),
            format!("{y:.1} ms"),
        )?;
    }
    Ok(())
}

fn write_bands(out: &mut dyn Write, bands: &Bands) -> io::Result<()> {
    let Some(width) = bands.width_m else {
        let why = match (bands.a_windows, bands.b_windows) {
            (0, _) | (_, 0) => "a log has no flight windows (saved with -q?)",
            _ => "no flight window has a position",
        };
        return writeln!(out, "  loss by distance: none: {why}");
    };
    writeln!(
        out,
        "  loss by distance (flight windows by the distance at each one's last position, \
         bands of {width} m)"
    )?;
    for band in &bands.bands {
        let c = &band.loss;
        let difference = match (band.a_windows, band.b_windows) {
            (0, _) => "A was never this far".to_string(),
            (_, 0) => "B was never this far".to_string(),
            _ => loss_difference(c),
        };
        writeln!(
            out,
            "    {:<11} A {:<22} B {:<22} B-A {difference}",
            format!("{}-{} m", band.from_m, band.to_m),
            loss_cell(c.a.lost, c.a.of, c.a.pct),
            loss_cell(c.b.lost, c.b.of, c.b.pct),
        )?;
    }
    let no_position = bands.a_no_position + bands.b_no_position;
    if no_position > 0 {
        writeln!(
            out,
            "    windows with no position, in no band: A {}, B {}",
            bands.a_no_position, bands.b_no_position
        )?;
    }
    Ok(())
}
