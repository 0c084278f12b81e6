//! `--passive` as text: the start line, and the summary as a table per
//! source with the link's totals, pymavlink's figure beside ours, and the
//! silences.

use std::io::{self, Write};

use super::{per_second, TextReporter};
use crate::engine::observe::StartInfo;
use crate::engine::summary::passive::{PassiveSummary, Silence, SourceSummary};
use crate::verdict::{Check, Verdict};

impl<W: Write> TextReporter<W> {
    pub(super) fn passive_start(&mut self, info: &StartInfo, heartbeat: bool) -> io::Result<()> {
        writeln!(
            self.out,
            "MAVPING {} from {}: PASSIVE, no probes; {}",
            info.link,
            info.ours,
            if heartbeat {
                "our HEARTBEAT at 1 Hz (--no-heartbeat for none)"
            } else {
                "nothing sent (--no-heartbeat)"
            }
        )
    }
}

fn seconds(ns: u64) -> String {
    format!("{:.3} s", ns as f64 / 1e9)
}

/// A percentage for the table's loss column: two decimals, "-" for none.
fn loss_column(p: Option<f64>) -> String {
    p.map_or_else(|| "-".into(), |p| format!("{p:.2}%"))
}

fn row(out: &mut impl Write, s: &PassiveSummary, r: &SourceSummary) -> io::Result<()> {
    let who = match s.identity(r.source) {
        Some(i) => format!("{}, {}", i.vehicle, i.autopilot_name),
        None if r.radio => "radio".into(),
        None => "-".into(),
    };
    writeln!(
        out,
        "{:<9} {:<22} {:>9} {:>7} {:>7} {:>5} {:>7} {:>8} {:>9} {:>9}",
        r.source.to_string(),
        who,
        r.counts.received,
        r.counts.lost,
        loss_column(r.loss_pct),
        r.counts.duplicate,
        r.counts.reordered,
        r.silence_count,
        r.frames_per_s.map_or_else(|| "-".into(), per_second),
        r.bytes_per_s
            .map_or_else(|| "-".into(), |b| format!("{b:.0}")),
    )
}

fn write_silence(out: &mut impl Write, r: &SourceSummary, silence: &Silence) -> io::Result<()> {
    let frames = match (silence.seq_lost, silence.frames_estimated) {
        (Some(lost), _) => format!("{lost} frames lost, counted by the sequence"),
        (None, Some(est)) => {
            format!("~{est} frames at its rate, not counted lost (the sequence cannot span it)")
        }
        (None, None) => "its rate was not known yet".into(),
    };
    writeln!(
        out,
        "silence: {} heard nothing for {} from {}{}: {frames}",
        r.source,
        seconds(silence.length_ns),
        seconds(silence.start),
        if silence.ongoing {
            " (still silent)"
        } else {
            ""
        },
    )
}

/// The summary of a passive run.
pub(super) fn write_summary(
    out: &mut impl Write,
    s: &PassiveSummary,
    verdict: &Verdict,
) -> io::Result<()> {
    let t = &s.table.totals;
    writeln!(
        out,
        "{:.1} s listened, {} sources heard, {} frames{}",
        s.duration_s,
        t.sources,
        t.counts.received,
        if t.radio_received > 0 {
            format!(" (and {} from the radio)", t.radio_received)
        } else {
            String::new()
        }
    )?;
    if s.table.sources.is_empty() {
        writeln!(out, "nothing heard")?;
    } else {
        writeln!(
            out,
            "{:<9} {:<22} {:>9} {:>7} {:>7} {:>5} {:>7} {:>8} {:>9} {:>9}",
            "source",
            "identity",
            "received",
            "lost",
            "loss",
            "dup",
            "reorder",
            "silences",
            "frames/s",
            "B/s"
        )?;
        for r in &s.table.sources {
            row(out, s, r)?;
        }
        writeln!(
            out,
            "link: {} received, {} lost ({}), {} duplicate, {} reordered; pymavlink's figure: {} lost ({:.2}%)",
            t.counts.received,
            t.counts.lost,
            loss_column(t.loss_pct),
            t.counts.duplicate,
            t.counts.reordered,
            t.pymav.loss,
            t.pymav.loss_pct
        )?;
    }
    for r in &s.table.sources {
        for silence in &r.silences {
            write_silence(out, r, silence)?;
        }
        if r.silences_omitted > 0 {
            writeln!(out, "silence: {} and {} more", r.source, r.silences_omitted)?;
        }
    }
    let u = &s.table.untracked;
    if u.sources > 0 {
        writeln!(
            out,
            "{} more sources beyond the table's cap: {} frames, counted, not tracked",
            u.sources, u.frames
        )?;
    }
    writeln!(out, "receive times: {}", s.rx_clock)?;
    for f in &verdict.failures {
        match f.check {
            Check::Reply => {}
            _ => writeln!(out, "FAILED {}: {}", f.check, f.message)?,
        }
    }
    Ok(())
}
