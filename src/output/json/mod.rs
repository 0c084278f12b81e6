//! `--json`: newline-delimited JSON, one object per event. The schema is
//! `schema/mavping-events.schema.json`; bump
//! [`SCHEMA_VERSION`](lines::SCHEMA_VERSION) on any
//! change that could break a consumer.
//!
//! Every line is a `Serialize` value whose members are written in the
//! order they are declared, so that order is the output's: keep it. The
//! figures in a line are the engine's own types, named and ordered by
//! their serde attributes (a change there is a change here; the command
//! probe's events are their lines); a line's struct adds only what the
//! line says itself (`type`, times, the link, the verdict) and borrows or
//! flattens the rest. The echo probes' lines are in [`echo`], the command
//! probe's summary in [`command`], a sweep's in [`sweep`], the C2 link
//! report's line in [`c2`]; `tests` holds
//! every line the runs write to the schema.
//!
//! This file declares and re-exports, and hands each [`Reporter`] call to
//! the file that makes its line; every line is written through [`Lines`]
//! (`lines.rs`).

mod c2;
mod command;
mod echo;
mod flight;
mod heard;
mod lines;
mod passive;
mod reporter;
mod round_trips;
mod sweep;
#[cfg(test)]
mod tests;
mod units;

use std::io::{self, Write};

use self::lines::{Lines, Whole};
use super::Reporter;
use crate::engine::c2::C2Report;
use crate::engine::kind::KindValue;
use crate::engine::matcher::MatchEvent;
use crate::engine::observe::RadioHeard;
use crate::engine::probe::passive::flight::FlightEvent;
use crate::engine::roster::Identity;
use crate::engine::summary::passive::PassiveSummary;
use crate::engine::summary::{EchoInterim, EchoSummary, KindSummary, PassiveInterim};
use crate::engine::sweep_report::StepFigures;
use crate::frame::SysComp;
use crate::output::StartInfo;
use crate::verdict::Verdict;
pub(crate) use lines::SCHEMA_VERSION;
pub(crate) use reporter::JsonReporter;

impl<W: Write> Reporter for JsonReporter<W> {
    fn start(&mut self, info: &StartInfo) -> io::Result<()> {
        self.lines.starts(info);
        if self.quiet {
            return Ok(());
        }
        Lines::write_named(&mut self.out, &self.lines.start(info))
    }

    fn matched(&mut self, event: &MatchEvent) -> io::Result<()> {
        self.event_line(Some(self.lines.match_line(event)))
    }

    fn heard(&mut self, id: SysComp, identity: &Identity) -> io::Result<()> {
        self.event_line(Some(self.lines.heard_line(id, identity)))
    }

    fn radio(&mut self, radio: &RadioHeard<'_>) -> io::Result<()> {
        self.event_line(self.lines.radio_line(radio))
    }

    fn waiting_for_peer(&mut self) -> io::Result<()> {
        self.event_line(Some(Lines::waiting_line()))
    }

    fn step(&mut self, step: &StepFigures) -> io::Result<()> {
        self.event_line(Some(self.lines.step(step)))
    }

    fn flight(&mut self, event: &FlightEvent) -> io::Result<()> {
        self.flight_line(event)
    }

    /// A kind's event written whole, as the command probe's are.
    fn other_event(&mut self, value: &dyn KindValue) -> io::Result<()> {
        value
            .serialized()
            .map_or(Ok(()), |line| self.own_line(line))
    }

    fn flush(&mut self) -> io::Result<()> {
        self.out.flush()
    }

    fn echo_interim(&mut self, figures: &EchoInterim) -> io::Result<()> {
        let line = self.lines.echo_interim(figures);
        self.interim_line(&line)
    }

    fn passive_interim(&mut self, figures: &PassiveInterim) -> io::Result<()> {
        let line = self.lines.passive_interim(figures);
        self.interim_line(&line)
    }

    fn echo_summary(&mut self, s: &EchoSummary, verdict: &Verdict) -> io::Result<()> {
        let line = echo::Summary::of(s, verdict, self.lines.link_or(&s.link));
        Self::summary_line(&mut self.out, &line)
    }

    /// A log's last, partial, window ends with the log: told here.
    fn passive_summary(&mut self, s: &PassiveSummary, verdict: &Verdict) -> io::Result<()> {
        if let Some(f) = s.flight.as_ref() {
            self.flight_ends(f)?;
        }
        let line = passive::Summary::of(s, verdict, self.lines.link_or(&s.link), &self.lines);
        Self::summary_line(&mut self.out, &line)
    }

    /// A summary, in quiet mode too: written as the summary line is, and
    /// before it (the summary stays the run's last line).
    fn c2_report(&mut self, link: &str, report: &C2Report) -> io::Result<()> {
        let line = c2::Report::of(self.lines.link_or(link), report);
        Lines::write_named(&mut self.out, &line)
    }

    /// A kind's summary written whole, as the command probe's is.
    fn other_summary(&mut self, s: &dyn KindSummary, verdict: &Verdict) -> io::Result<()> {
        match s.serialized() {
            Some((name, figures)) => {
                let line = Whole::of(name, figures, verdict, self.lines.link_or(s.link()));
                Self::summary_line(&mut self.out, &line)
            }
            None => Ok(()),
        }
    }
}
