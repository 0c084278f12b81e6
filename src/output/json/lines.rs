//! What every line is made of: the [`Line`] enum of every `type`, the
//! [`Lines`] that write them (the wall clock, the link a line names), the
//! [`Stamp`] a responder's timed event starts with, and the `start` line.

use std::io::{self, Write};

use serde::Serialize;

use super::units::seconds;
use super::{command, echo, flight, heard, passive, sweep};
use crate::engine::summary::{EchoInterim, Interim, PassiveInterim, ProbeName};
use crate::engine::sweep_report::SweepConfig;
use crate::engine::CommandSpec;
use crate::engine::Nanos;
use crate::frame::SysComp;
use crate::output::{StartInfo, WallClock};

pub(crate) const SCHEMA_VERSION: u32 = 2;

/// One line of the output, by its `type`.
#[derive(Serialize)]
#[serde(untagged)]
pub(super) enum Line<'a> {
    // Boxed: once a run each, and much larger than the others.
    Start(Box<Start<'a>>),
    Waiting(heard::Waiting),
    Responder(heard::Heard<'a>),
    Reply(echo::Reply),
    Lost(echo::Lost),
    Late(echo::Again),
    Duplicate(echo::Again),
    Stale(Stamp),
    Radio(heard::Radio<'a>),
    Interim(echo::Interim),
    PassiveInterim(Box<passive::Interim<'a>>),
    Step(sweep::Step<'a>),
    Summary(Box<echo::Summary<'a>>),
    Ack(command::Ack),
    CommandFailed(command::Failed),
    Skipped(command::Skipped),
    LateAck(command::AckAgain),
    DuplicateAck(command::AckAgain),
    CommandSummary(Box<command::Summary<'a>>),
    PassiveSummary(Box<passive::Summary<'a>>),
    FlightWindow(flight::Window<'a>),
    FlightSilence(flight::Timed),
    FlightBurst(flight::Timed),
}

impl Line<'_> {
    /// The start and summary lines always name their link; the others
    /// only in a run of several links, at their end.
    fn names_its_link(&self) -> bool {
        match self {
            Line::Start(_)
            | Line::Summary(_)
            | Line::CommandSummary(_)
            | Line::PassiveSummary(_) => true,
            Line::Waiting(_)
            | Line::Responder(_)
            | Line::Reply(_)
            | Line::Lost(_)
            | Line::Late(_)
            | Line::Duplicate(_)
            | Line::Stale(_)
            | Line::Radio(_)
            | Line::Interim(_)
            | Line::PassiveInterim(_)
            | Line::Step(_)
            | Line::Ack(_)
            | Line::CommandFailed(_)
            | Line::Skipped(_)
            | Line::LateAck(_)
            | Line::DuplicateAck(_)
            | Line::FlightWindow(_)
            | Line::FlightSilence(_)
            | Line::FlightBurst(_) => false,
        }
    }
}

/// A line and, when it does not name it itself, its link.
#[derive(Serialize)]
struct Linked<'a> {
    #[serde(flatten)]
    line: &'a Line<'a>,
    #[serde(skip_serializing_if = "Option::is_none")]
    link: Option<&'a str>,
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

    /// Writes `line` and its newline.
    pub(super) fn write(&self, out: &mut impl Write, line: &Line<'_>) -> io::Result<()> {
        let link = if line.names_its_link() {
            None
        } else {
            self.link.as_deref()
        };
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
    pub(super) fn start<'a>(&'a self, info: &'a StartInfo) -> Line<'a> {
        Line::Start(Box::new(Start {
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
        }))
    }

    /// The line of the figures so far.
    pub(super) fn interim<'a>(&self, figures: &'a Interim) -> Option<Line<'a>> {
        if let Some(echo) = figures.get::<EchoInterim>() {
            return Some(self.echo_interim(echo));
        }
        figures
            .get::<PassiveInterim>()
            .map(|passive| self.passive_interim(passive))
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
