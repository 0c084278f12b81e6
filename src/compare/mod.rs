//! `mavping compare A.json B.json`: two runs saved with `--json`, made at
//! different times or places, side by side: each responder's or source's
//! loss difference with its 95 % interval, the median RTT shift with a
//! bootstrap interval, frame ages, and for two telemetry logs loss by
//! distance. Pure: text in, a [`Report`] out; `run/compare.rs` reads the
//! files and writes the report.
//!
//! - `input.rs`: a file's JSON lines into the figures compared;
//! - `report.rs`: which links and ids are compared, and the report;
//! - `interval.rs`: Wilson and Newcombe intervals for loss;
//! - `bootstrap.rs`: the median RTT shift from two histograms;
//! - `bands.rs`: flight windows into distance bands;
//! - `text.rs`: the report as text (JSON is its serialisation).

mod bands;
mod bootstrap;
mod input;
mod interval;
mod report;
mod text;

use std::io::{self, Write};

use serde::Serialize;

pub(crate) use input::{parse, InputError, RunFile, SCHEMA_VERSION};
pub(crate) use report::{compare, CompareError, Options, Report, SourceFilter};
pub(crate) use text::write_text;

/// The `compare` JSON line: the report, with its type, the schema's
/// version and the exit code.
#[derive(Serialize)]
struct Line<'a> {
    #[serde(rename = "type")]
    kind: &'static str,
    schema_version: u64,
    #[serde(flatten)]
    report: &'a Report,
    exit_code: u8,
}

/// Writes the report as one `compare` JSON line.
pub(crate) fn write_json(out: &mut dyn Write, report: &Report, exit_code: u8) -> io::Result<()> {
    let line = Line {
        kind: "compare",
        schema_version: SCHEMA_VERSION,
        report,
        exit_code,
    };
    serde_json::to_writer(&mut *out, &line)?;
    writeln!(out)
}
