//! `--passive` as text: the start line, and the summary as a table per
//! source with the link's totals, pymavlink's figure beside ours, and the
//! silences.

use std::io::{self, Write};

use super::{per_second, TextReporter};
use crate::engine::observe::StartInfo;
use crate::engine::summary::passive::{PassiveSummary, PerLink, Silence, SourceSummary};
use crate::transport::tlog::LogFacts;
use crate::verdict::{Check, Verdict};

impl<W: Write> TextReporter<W> {
    pub(super) fn passive_start(
        &mut self,
        info: &StartInfo,
        heartbeat: bool,
        log: bool,
    ) -> io::Result<()> {
        writeln!(
            self.out,
            "MAVPING {} from {}: PASSIVE, no probes; {}",
            info.link,
            info.ours,
            if log {
                "a telemetry log, read on its own clock (--passive implied); nothing sent"
            } else if heartbeat {
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

/// What a telemetry log held: its span on the wall clock, its records,
/// its stamps, and what was not a record.
fn write_log(out: &mut impl Write, log: &LogFacts) -> io::Result<()> {
    let st = &log.stamps;
    let wall = |us: u64| {
        let t = std::time::SystemTime::UNIX_EPOCH + std::time::Duration::from_micros(us);
        humantime::format_rfc3339_micros(t).to_string()
    };
    let r = &log.records;
    writeln!(
        out,
        "log: {} records from {} to {} (stamps {}){}",
        r.records,
        wall(st.first_us),
        wall(st.latest_us),
        if st.whole_ms {
            "all whole milliseconds, as QGroundControl writes them"
        } else {
            "in microseconds"
        },
        if log.complete {
            ", read to its end"
        } else {
            ", stopped before its end"
        },
    )?;
    if r.junk_bytes > 0 {
        writeln!(
            out,
            "log: {} bytes of junk between records, in {} stretches, skipped ({} began with a \
             frame that failed its CRC)",
            r.junk_bytes, r.junk_stretches, r.bad_crc
        )?;
    }
    if r.truncated_bytes > 0 {
        writeln!(
            out,
            "log: its last record is cut short ({} bytes)",
            r.truncated_bytes
        )?;
    }
    if r.unknown_id > 0 {
        writeln!(
            out,
            "log: {} records of message ids this build does not know, skipped (pymavlink counts \
             them in no loss either)",
            r.unknown_id
        )?;
    }
    if st.behind > 0 || st.steps > 0 {
        writeln!(
            out,
            "log: {} records stamped behind the latest (dated at it), {} clock steps (the time \
             goes on from the latest, no gap)",
            st.behind, st.steps
        )?;
    }
    Ok(())
}

/// The table per MAVProxy link, and the sources on none.
fn write_links(out: &mut impl Write, s: &PassiveSummary, per: &PerLink) -> io::Result<()> {
    writeln!(
        out,
        "per MAVProxy link (the stamps' two lowest bits; link 3 is what MAVProxy sent):"
    )?;
    writeln!(
        out,
        "link {:<9} {:<22} {:>9} {:>7} {:>7} {:>5} {:>7} {:>8} {:>9} {:>9}",
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
    for l in &per.links {
        for r in &l.table.sources {
            write!(out, "{:<4} ", l.link)?;
            row(out, s, r)?;
        }
    }
    if !per.unlinked.is_empty() {
        let ids: Vec<String> = per.unlinked.iter().map(ToString::to_string).collect();
        writeln!(
            out,
            "on no link: {} (the low bits of their stamps vary as a clock's: MAVProxy logs what \
             its outputs send with a plain stamp)",
            ids.join(", ")
        )?;
    }
    Ok(())
}

/// The summary of a passive run.
pub(super) fn write_summary(
    out: &mut impl Write,
    s: &PassiveSummary,
    verdict: &Verdict,
) -> io::Result<()> {
    let t = &s.table.totals;
    if let Some(log) = &s.log {
        write_log(out, log)?;
    }
    writeln!(
        out,
        "{:.1} s {}, {} sources heard, {} frames{}",
        s.duration_s,
        if s.log.is_some() {
            "of log"
        } else {
            "listened"
        },
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
    if let Some(per) = &s.per_link {
        write_links(out, s, per)?;
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
