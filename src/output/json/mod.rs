//! `--json`: newline-delimited JSON, one object per event. The schema is
//! `schema/mavping-events.schema.json`; bump [`SCHEMA_VERSION`] on any
//! change that could break a consumer.
//!
//! Every line is a [`Line`]: a struct per `type`, whose members are written
//! in the order they are declared, so that order is the output's: keep it.
//! The echo probes' lines are in [`echo`], the command probe's in
//! [`command`], a sweep's in [`sweep`]; `tests` checks one of each against
//! the schema.

mod command;
mod echo;
mod flight;
mod heard;
mod passive;
mod round_trips;
mod sweep;
#[cfg(test)]
mod tests;

use std::io::{self, Write};

use serde::Serialize;

use super::{Reporter, RunKind, StartInfo, WallClock};
use crate::engine::matcher::MatchEvent;
use crate::engine::observe::{CommandEvent, RadioHeard};
use crate::engine::probe::passive::flight::FlightEvent;
use crate::engine::roster::Identity;
use crate::engine::summary::passive::PassiveSummary;
use crate::engine::summary::ProbeName;
use crate::engine::summary::{CommandSummary, Interim, Summary};
use crate::engine::sweep_report::StepFigures;
use crate::engine::Nanos;
use crate::frame::SysComp;
use crate::verdict::Verdict;

pub(crate) const SCHEMA_VERSION: u32 = 2;

/// One line of the output, by its `type`.
#[derive(Serialize)]
#[serde(untagged)]
enum Line<'a> {
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
    Step(sweep::Step),
    Summary(Box<echo::Summary<'a>>),
    Ack(command::Ack),
    CommandFailed(command::Failed),
    Skipped(command::Skipped),
    LateAck(command::AckAgain),
    DuplicateAck(command::AckAgain),
    CommandSummary(Box<command::Summary<'a>>),
    PassiveSummary(Box<passive::Summary<'a>>),
    FlightWindow(flight::Window),
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
struct Start<'a> {
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
    sweep: Option<sweep::Plan>,
}

/// What every timed event of a responder starts with: its type, session
/// seconds, wall time and the responder.
#[derive(Serialize)]
struct Stamp {
    r#type: &'static str,
    t_s: f64,
    time: String,
    responder: SysComp,
}

pub(crate) struct JsonReporter<W: Write> {
    out: W,
    /// Only the summary object (`--json -q`).
    quiet: bool,
    lines: Lines,
}

/// What the lines are made of besides the run's own figures.
struct Lines {
    wall: WallClock,
    /// With several links, every object names its link.
    link: Option<String>,
    /// The run is a command probe's: only its own events are written.
    command: bool,
}

impl<W: Write> JsonReporter<W> {
    pub(crate) fn new(out: W, quiet: bool, wall: WallClock) -> Self {
        JsonReporter {
            out,
            quiet,
            lines: Lines {
                wall,
                link: None,
                command: false,
            },
        }
    }

    #[cfg(test)]
    pub(crate) fn into_inner(self) -> W {
        self.out
    }

    /// Adds `"link": LINK` to every event (the start and summary objects
    /// always carry it), for runs over several links.
    pub(crate) fn with_link(mut self, link: Option<String>) -> Self {
        self.lines.link = link;
        self
    }
}

impl Lines {
    /// Notes what the run is: a command probe's writes its own events only.
    fn starts(&mut self, info: &StartInfo) {
        self.command = matches!(info.run, RunKind::Command(_));
    }

    /// Writes `line` and its newline.
    fn write(&self, out: &mut impl Write, line: &Line<'_>) -> io::Result<()> {
        let link = if line.names_its_link() {
            None
        } else {
            self.link.as_deref()
        };
        serde_json::to_writer(&mut *out, &Linked { line, link })?;
        out.write_all(b"\n")
    }

    /// The link as a line that names it says it: the one given with
    /// [`JsonReporter::with_link`], else the run's own.
    fn link_or<'a>(&'a self, own: &'a str) -> &'a str {
        self.link.as_deref().unwrap_or(own)
    }

    /// The `start` line.
    fn start<'a>(&'a self, info: &'a StartInfo) -> Line<'a> {
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
            command: info.run.command().map(command::Spec::of),
            sweep: info.run.steps().map(sweep::Plan::of),
        }))
    }

    /// The line of the figures so far.
    fn interim<'a>(&self, figures: &'a Interim) -> Line<'a> {
        match figures {
            Interim::Echo(e) => self.echo_interim(e),
            Interim::Passive(p) => self.passive_interim(p),
        }
    }

    /// What every timed event of a responder starts with.
    fn stamp(&self, r#type: &'static str, t: Nanos, responder: SysComp) -> Stamp {
        Stamp {
            r#type,
            t_s: seconds(t),
            time: self.wall.rfc3339(t),
            responder,
        }
    }
}

fn seconds(t: Nanos) -> f64 {
    t as f64 / 1e9
}

fn us(ns: Nanos) -> f64 {
    ns as f64 / 1e3
}

impl<W: Write> JsonReporter<W> {
    /// Writes the summary line, in quiet mode too, and pushes it out.
    fn summary_line(lines: &Lines, out: &mut W, line: &Line<'_>) -> io::Result<()> {
        lines.write(out, line)?;
        out.flush()
    }

    /// Writes an event's line: not in quiet mode, and in a command run
    /// only the command's own (`command`).
    fn event_line(&mut self, line: Option<Line<'_>>, command: bool) -> io::Result<()> {
        match line {
            Some(line) if !self.quiet && command == self.lines.command => {
                self.lines.write(&mut self.out, &line)
            }
            _ => Ok(()),
        }
    }
}

impl<W: Write> Reporter for JsonReporter<W> {
    fn start(&mut self, info: &StartInfo) -> io::Result<()> {
        self.lines.starts(info);
        if self.quiet {
            return Ok(());
        }
        self.lines.write(&mut self.out, &self.lines.start(info))
    }

    fn matched(&mut self, event: &MatchEvent) -> io::Result<()> {
        self.event_line(Some(self.lines.match_line(event)), false)
    }

    fn command(&mut self, event: &CommandEvent) -> io::Result<()> {
        self.event_line(command::line(event), true)
    }

    fn heard(&mut self, id: SysComp, identity: &Identity) -> io::Result<()> {
        self.event_line(Some(self.lines.heard_line(id, identity)), false)
    }

    fn radio(&mut self, radio: &RadioHeard<'_>) -> io::Result<()> {
        self.event_line(self.lines.radio_line(radio), false)
    }

    fn waiting_for_peer(&mut self) -> io::Result<()> {
        self.event_line(Some(Lines::waiting_line()), false)
    }

    fn step(&mut self, step: &StepFigures) -> io::Result<()> {
        self.event_line(Some(Line::Step(self.lines.step(step))), false)
    }

    fn flight(&mut self, event: &FlightEvent) -> io::Result<()> {
        self.event_line(Some(self.lines.flight_event(event)), false)
    }

    fn flush(&mut self) -> io::Result<()> {
        self.out.flush()
    }

    /// Written in quiet mode too: that is what `-Q` is for.
    fn interim(&mut self, figures: &Interim) -> io::Result<()> {
        self.lines
            .write(&mut self.out, &self.lines.interim(figures))?;
        self.out.flush()
    }

    fn echo_summary(&mut self, s: &Summary, verdict: &Verdict) -> io::Result<()> {
        let line = echo::Summary::of(s, verdict, self.lines.link_or(&s.link));
        Self::summary_line(&self.lines, &mut self.out, &Line::Summary(Box::new(line)))
    }

    fn command_summary(&mut self, s: &CommandSummary, verdict: &Verdict) -> io::Result<()> {
        let line = command::Summary::of(s, verdict, self.lines.link_or(&s.link));
        Self::summary_line(
            &self.lines,
            &mut self.out,
            &Line::CommandSummary(Box::new(line)),
        )
    }

    /// A log's last, partial, window ends with the log: told here.
    fn passive_summary(&mut self, s: &PassiveSummary, verdict: &Verdict) -> io::Result<()> {
        if let (Some(f), false) = (s.flight.as_ref(), self.quiet) {
            if let Some(last) = f.last.as_ref() {
                let line = Line::FlightWindow(self.lines.flight_window(last));
                self.lines.write(&mut self.out, &line)?;
            }
            if let Some(b) = f.last_burst.as_ref() {
                let line = Line::FlightBurst(self.lines.flight_span("flight_burst", b));
                self.lines.write(&mut self.out, &line)?;
            }
        }
        let line = passive::Summary::of(s, verdict, self.lines.link_or(&s.link), &self.lines);
        Self::summary_line(
            &self.lines,
            &mut self.out,
            &Line::PassiveSummary(Box::new(line)),
        )
    }
}
