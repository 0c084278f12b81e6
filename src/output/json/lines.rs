//! What every line is made of: the [`Lines`] that write them (the wall
//! clock, the link a line names), the
//! [`Stamp`] a responder's timed event starts with, and the `start` line.

use std::io::{self, Write};

use serde::Serialize;

use super::command;
use super::units::seconds;
use crate::engine::probe::transfer::TransferSpec;
use crate::engine::summary::ProbeName;
use crate::engine::sweep_report::SweepConfig;
use crate::engine::CommandSpec;
use crate::engine::Nanos;
use crate::frame::SysComp;
use crate::output::{StartInfo, WallClock};
use crate::verdict::Verdict;

pub(crate) const SCHEMA_VERSION: u32 = 2;

/// A line and, when it does not name it itself, its link.
#[derive(Serialize)]
struct Linked<'a, T> {
    #[serde(flatten)]
    line: &'a T,
    #[serde(skip_serializing_if = "Option::is_none")]
    link: Option<&'a str>,
}

/// The summary line of a kind that is written whole (the command
/// probe's `command_summary`): the link as named, the kind's figures as
/// they serialise, then what the line says itself.
#[derive(Serialize)]
pub(super) struct Whole<'a> {
    link: &'a str,
    #[serde(flatten)]
    figures: &'a dyn erased_serde::Serialize,
    r#type: &'static str,
    schema_version: u32,
    verdict: &'a Verdict,
    exit_code: u8,
}

impl<'a> Whole<'a> {
    pub(super) fn of(
        name: &'static str,
        figures: &'a dyn erased_serde::Serialize,
        verdict: &'a Verdict,
        link: &'a str,
    ) -> Self {
        Whole {
            link,
            figures,
            r#type: name,
            schema_version: SCHEMA_VERSION,
            verdict,
            exit_code: verdict.exit_code(),
        }
    }
}

/// The `start` line: what the run is about to do.
#[derive(Serialize)]
pub(super) struct Start<'a> {
    r#type: &'static str,
    schema_version: u32,
    mavping_version: &'static str,
    time: String,
    link: &'a str,
    probe: ProbeName,
    ours: SysComp,
    interval_s: f64,
    rate_hz: f64,
    timeout_s: f64,
    count: Option<u64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    command: Option<command::Spec>,
    #[serde(skip_serializing_if = "Option::is_none")]
    sweep: Option<&'a SweepConfig>,
    #[serde(skip_serializing_if = "Option::is_none")]
    transfer: Option<&'a TransferSpec>,
}

/// What every timed event of a responder starts with: its type, session
/// seconds, wall time and the responder.
#[derive(Serialize)]
pub(super) struct Stamp {
    r#type: &'static str,
    t_s: f64,
    time: String,
    responder: SysComp,
}

/// What the lines are made of besides the run's own figures.
pub(super) struct Lines {
    pub(super) wall: WallClock,
    /// With several links, every object names its link.
    pub(super) link: Option<String>,
    /// The run is a command probe's: only its own events are written.
    pub(super) command: bool,
}

impl Lines {
    /// Notes what the run is: a command probe's writes its own events only.
    pub(super) fn starts(&mut self, info: &StartInfo) {
        self.command = info.plan::<CommandSpec>().is_some();
    }

    /// Writes an event's `line` and its newline; in a run of several
    /// links, the line ends with its link.
    pub(super) fn write(&self, out: &mut impl Write, line: &impl Serialize) -> io::Result<()> {
        Self::write_linked(out, line, self.link.as_deref())
    }

    /// Writes a line that names its link itself (the start and summary
    /// lines) and its newline.
    pub(super) fn write_named(out: &mut impl Write, line: &impl Serialize) -> io::Result<()> {
        Self::write_linked(out, line, None)
    }

    fn write_linked<T: Serialize>(
        out: &mut impl Write,
        line: &T,
        link: Option<&str>,
    ) -> io::Result<()> {
        serde_json::to_writer(&mut *out, &Linked { line, link })?;
        out.write_all(b"\n")
    }

    /// The link as a line that names it says it: the one given with
    /// [`JsonReporter::with_link`](super::JsonReporter::with_link), else
    /// the run's own.
    pub(super) fn link_or<'a>(&'a self, own: &'a str) -> &'a str {
        self.link.as_deref().unwrap_or(own)
    }

    /// The `start` line.
    pub(super) fn start<'a>(&'a self, info: &'a StartInfo) -> Start<'a> {
        Start {
            r#type: "start",
            schema_version: SCHEMA_VERSION,
            mavping_version: env!("CARGO_PKG_VERSION"),
            time: self.wall.rfc3339(0),
            link: self.link_or(&info.link),
            probe: info.probe,
            ours: info.ours,
            interval_s: info.interval.as_secs_f64(),
            rate_hz: 1.0 / info.interval.as_secs_f64(),
            timeout_s: info.timeout.as_secs_f64(),
            count: info.count,
            command: info.plan::<CommandSpec>().map(command::Spec::of),
            sweep: info.plan::<SweepConfig>(),
            transfer: info.plan::<TransferSpec>(),
        }
    }

    /// What every timed event of a responder starts with.
    pub(super) fn stamp(&self, r#type: &'static str, t: Nanos, responder: SysComp) -> Stamp {
        Stamp {
            r#type,
            t_s: seconds(t),
            time: self.wall.rfc3339(t),
            responder,
        }
    }
}
