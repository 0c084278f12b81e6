//! The pair report of a run over several links, after the links'
//! summaries: per source heard on two links or more, the merged stream
//! and each link's part in it ([`PairSummary`]), as text or one JSON
//! line (`pair_summary`).

use std::io::{self, Write};

use serde::Serialize;

use super::json::SCHEMA_VERSION;
use crate::engine::pair::matrix::{MatrixCell, MatrixSummary};
use crate::engine::pair::{LinkPair, PairSummary, SourcePair};

/// The JSON line: the links by place, then the figures.
#[derive(Serialize)]
struct Line<'a> {
    r#type: &'static str,
    schema_version: u32,
    /// The links as given on the command line: a figure's `link` is an
    /// index into them.
    links: &'a [&'a str],
    #[serde(flatten)]
    summary: &'a PairSummary,
}

pub(crate) fn write_json(out: &mut impl Write, s: &PairSummary, names: &[&str]) -> io::Result<()> {
    let line = Line {
        r#type: "pair_summary",
        schema_version: SCHEMA_VERSION,
        links: names,
        summary: s,
    };
    serde_json::to_writer(&mut *out, &line)?;
    writeln!(out)
}

/// `v` with `places` decimals and its unit, or `-`.
fn figure(v: Option<f64>, places: usize, unit: &str) -> String {
    v.map_or("-".to_string(), |v| format!("{v:.places$}{unit}"))
}

pub(crate) fn write_text(out: &mut impl Write, s: &PairSummary, names: &[&str]) -> io::Result<()> {
    writeln!(
        out,
        "\n--- the same sources on several links (a frame's copies matched by source, \
         sequence, message and CRC within {:.0} s) ---",
        s.window_ms / 1e3
    )?;
    for source in &s.sources {
        write_source(out, source, names)?;
    }
    if !s.uncopied_sources.is_empty() {
        let ids: Vec<String> = s.uncopied_sources.iter().map(|id| id.to_string()).collect();
        writeln!(
            out,
            "heard on several links but no frame on two (split between them, not copied): {}",
            ids.join(", ")
        )?;
    }
    if !s.conflicting_sources.is_empty() {
        let ids: Vec<String> = s
            .conflicting_sources
            .iter()
            .map(|id| id.to_string())
            .collect();
        writeln!(
            out,
            "heard on several links with other frames under the same numbers (two senders under one id, not copies): {}",
            ids.join(", ")
        )?;
    }
    if s.untracked_frames > 0 {
        writeln!(
            out,
            "{} frames of sources beyond the tracked ones, not matched",
            s.untracked_frames
        )?;
    }
    Ok(())
}

fn write_source(out: &mut impl Write, s: &SourcePair, names: &[&str]) -> io::Result<()> {
    writeln!(
        out,
        "{}: {} distinct frames, {} lost on every link ({}); {} later copies, a \
         de-duplication window of {} catches 99.9% of them (the latest {})",
        s.source,
        s.distinct_frames,
        s.lost_on_every_link,
        figure(s.lost_on_every_link_pct, 2, "%"),
        s.copies,
        figure(s.dedup_window_p999_ms, 1, " ms"),
        figure(s.copy_lag_max_ms, 1, " ms"),
    )?;
    for l in &s.links {
        write_link(out, l, names)?;
    }
    let odd = s.late_beyond_window + s.conflicts;
    if odd > 0 {
        writeln!(
            out,
            "  {} copies after the window, {} other frames under a number in use (a second \
             sender, a restart)",
            s.late_beyond_window, s.conflicts
        )?;
    }
    Ok(())
}

fn write_link(out: &mut impl Write, l: &LinkPair, names: &[&str]) -> io::Result<()> {
    let name = names.get(l.link).copied().unwrap_or("?");
    let undecided = if l.only_undecided > 0 {
        format!(" ({} still in the window)", l.only_undecided)
    } else {
        String::new()
    };
    writeln!(
        out,
        "  [{name}] {} frames, {} lost alone ({}); first {} ({}), only it {}{undecided}\n    \
         lag behind the first copy p50 {}, p99 {}, max {}; {} behind a newer frame (the map \
         jumps back), {} of them first copies",
        l.frames,
        l.lost,
        figure(l.lost_pct, 2, "%"),
        l.first,
        figure(l.first_pct, 1, "%"),
        l.only,
        figure(l.lag_p50_ms, 1, " ms"),
        figure(l.lag_p99_ms, 1, " ms"),
        figure(l.lag_max_ms, 1, " ms"),
        l.stale,
        l.stale_first,
    )
}

/// The matrix's JSON line: the links by place, then the cells.
#[derive(Serialize)]
struct MatrixLine<'a> {
    r#type: &'static str,
    schema_version: u32,
    /// The requests' message: TIMESYNC or PING.
    message: &'a str,
    links: &'a [&'a str],
    #[serde(flatten)]
    matrix: &'a MatrixSummary,
}

pub(crate) fn write_matrix_json(
    out: &mut impl Write,
    message: &str,
    m: &MatrixSummary,
    names: &[&str],
) -> io::Result<()> {
    let line = MatrixLine {
        r#type: "link_matrix",
        schema_version: SCHEMA_VERSION,
        message,
        links: names,
        matrix: m,
    };
    serde_json::to_writer(&mut *out, &line)?;
    writeln!(out)
}

pub(crate) fn write_matrix_text(
    out: &mut impl Write,
    message: &str,
    m: &MatrixSummary,
    names: &[&str],
) -> io::Result<()> {
    let name = |k: usize| names.get(k).copied().unwrap_or("?");
    writeln!(
        out,
        "\n--- {message} requests out on one link, replies heard on each ---"
    )?;
    for (out_link, &requests) in m.requests.iter().enumerate() {
        writeln!(out, "out on [{}]: {requests} requests", name(out_link))?;
        for c in m.cells.iter().filter(|c| c.out == out_link) {
            write_cell(out, c, name(c.back))?;
        }
    }
    if m.unknown_replies > 0 {
        writeln!(
            out,
            "{} replies to no request of ours within its timeout (late, or another's)",
            m.unknown_replies
        )?;
    }
    Ok(())
}

fn write_cell(out: &mut impl Write, c: &MatrixCell, back: &str) -> io::Result<()> {
    let duplicates = if c.duplicates > 0 {
        format!(", {} duplicate", c.duplicates)
    } else {
        String::new()
    };
    writeln!(
        out,
        "  back on [{back}]: {} replies ({} lost){duplicates}, rtt p50 {}, p99 {}, max {}",
        c.replies,
        figure(c.lost_pct, 1, "%"),
        figure(c.rtt_p50_ms, 1, " ms"),
        figure(c.rtt_p99_ms, 1, " ms"),
        figure(c.rtt_max_ms, 1, " ms"),
    )
}
