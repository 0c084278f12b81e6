//! What an output format is: a follower of a session that takes the
//! events of the kinds it shows and leaves the rest. Each kind of event
//! and each kind of summary has a method here whose default hands it to
//! [`Reporter::other_event`] or [`Reporter::other_summary`] (as ripgrep's
//! `Sink`), where JSON and text write any kind's value whole as it
//! serialises and every other format does nothing. So a format implements
//! what it shows, and a new kind costs no format any code.
//! That every format takes every event and summary of every kind without
//! failing is a test (`every_format.rs`), not an exhaustive match.

use std::io;

use crate::engine::c2::C2Report;
use crate::engine::clock_offset::ClockSummary;
use crate::engine::kind::KindValue;
use crate::engine::link_node::LinkNodeReport;
use crate::engine::matcher::MatchEvent;
use crate::engine::observe::{Event, Observer, RadioHeard, StartInfo};
use crate::engine::probe::command::CommandEvent;
use crate::engine::probe::passive::flight::FlightEvent;
use crate::engine::probe::passive::SourcesNow;
use crate::engine::roster::Identity;
use crate::engine::summary::passive::PassiveSummary;
use crate::engine::summary::EchoSummary;
use crate::engine::summary::{
    CommandSummary, EchoInterim, Interim, KindSummary, LinkSummary, PassiveInterim,
};
use crate::engine::sweep_report::StepFigures;
use crate::engine::Nanos;
use crate::frame::SysComp;
use crate::verdict::Verdict;

/// An output format. Every method has a default: a format that shows no
/// radios has no `radio`, one that writes nothing at the end no summary.
#[allow(unused_variables)]
pub(crate) trait Reporter {
    /// What the run is, told first.
    fn start(&mut self, info: &StartInfo) -> io::Result<()> {
        Ok(())
    }

    /// An echo probe's reply, loss, late, duplicate or stale reply.
    fn matched(&mut self, event: &MatchEvent) -> io::Result<()> {
        self.other_event(event)
    }

    /// A command's transmission, acknowledgement or failure.
    fn command(&mut self, event: &CommandEvent) -> io::Result<()> {
        self.other_event(event)
    }

    /// A system's first HEARTBEAT.
    fn heard(&mut self, id: SysComp, identity: &Identity) -> io::Result<()> {
        Ok(())
    }

    /// A radio's report (see [`Event::Radio`]).
    fn radio(&mut self, radio: &RadioHeard<'_>) -> io::Result<()> {
        Ok(())
    }

    /// A node's LINK_NODE_STATUS.
    fn link_node(
        &mut self,
        id: SysComp,
        at: Nanos,
        report: &LinkNodeReport,
        first: bool,
    ) -> io::Result<()> {
        Ok(())
    }

    /// A TIMESYNC responder's clock offset so far.
    fn clock(&mut self, id: SysComp, at: Nanos, clock: &ClockSummary) -> io::Result<()> {
        Ok(())
    }

    /// Nothing to send to yet.
    fn waiting_for_peer(&mut self) -> io::Result<()> {
        Ok(())
    }

    /// Requests put on the wire so far.
    fn progress(&mut self, at: Nanos, requests: u64) -> io::Result<()> {
        Ok(())
    }

    /// A step of a run in steps ended.
    fn step(&mut self, step: &StepFigures) -> io::Result<()> {
        self.other_event(step)
    }

    /// Every source's sequence figures so far, once a second.
    fn sources(&mut self, now: &SourcesNow) -> io::Result<()> {
        Ok(())
    }

    /// A telemetry log's timeline: a window, a silence or a burst.
    fn flight(&mut self, event: &FlightEvent) -> io::Result<()> {
        self.other_event(event)
    }

    /// A kind's own event that this format has no method for: written
    /// whole by the formats that write every kind's (JSON and text, where
    /// the value is [`KindValue::serialized`]), shown by no other. A
    /// kind's event methods above come here unless a format takes them.
    fn other_event(&mut self, value: &dyn KindValue) -> io::Result<()> {
        Ok(())
    }

    /// The link failed; the session ends.
    fn link_failed(&mut self, at: Nanos, error: &str) -> io::Result<()> {
        Ok(())
    }

    /// Pushes buffered output to the reader.
    fn flush(&mut self) -> io::Result<()> {
        Ok(())
    }

    /// An echo run's figures so far (`-Q`, SIGQUIT).
    fn echo_interim(&mut self, figures: &EchoInterim) -> io::Result<()> {
        Ok(())
    }

    /// A passive run's figures so far.
    fn passive_interim(&mut self, figures: &PassiveInterim) -> io::Result<()> {
        Ok(())
    }

    /// An echo run's summary (PING, TIMESYNC, a run in steps).
    fn echo_summary(&mut self, summary: &EchoSummary, verdict: &Verdict) -> io::Result<()> {
        self.other_summary(summary, verdict)
    }

    /// A command run's summary.
    fn command_summary(&mut self, summary: &CommandSummary, verdict: &Verdict) -> io::Result<()> {
        self.other_summary(summary, verdict)
    }

    /// A passive run's (or a telemetry log's) summary.
    fn passive_summary(&mut self, summary: &PassiveSummary, verdict: &Verdict) -> io::Result<()> {
        self.other_summary(summary, verdict)
    }

    /// The C2 link report over `link`'s run (`--report c2`), told just
    /// before that run's summary: JSON writes it as the line before the
    /// summary's, which stays the run's last; text holds it for after
    /// its statistics block.
    fn c2_report(&mut self, link: &str, report: &C2Report) -> io::Result<()> {
        Ok(())
    }

    /// A kind's summary that this format has no method for: as
    /// [`Reporter::other_event`], written whole where the summary is
    /// [`KindSummary::serialized`].
    fn other_summary(&mut self, summary: &dyn KindSummary, verdict: &Verdict) -> io::Result<()> {
        Ok(())
    }

    /// Every event, handed to the method of its kind; a format that
    /// passes events on whole ([`super::Fanout`]) takes them here.
    fn tell(&mut self, event: &Event<'_>) -> io::Result<()> {
        match *event {
            Event::Kind(value) => self.kind_event(value),
            Event::Heard { id, identity } => self.heard(id, identity),
            Event::Radio(ref radio) => self.radio(radio),
            Event::LinkNode {
                id,
                at,
                ref report,
                first,
            } => self.link_node(id, at, report, first),
            Event::Clock { id, at, ref clock } => self.clock(id, at, clock),
            Event::WaitingForPeer => self.waiting_for_peer(),
            Event::Progress { at, requests } => self.progress(at, requests),
            Event::LinkFailed { at, error } => self.link_failed(at, error),
        }
    }

    /// A kind's own event, by its type (the most frequent first). One
    /// that no method takes is shown by no format.
    fn kind_event(&mut self, value: &dyn KindValue) -> io::Result<()> {
        if let Some(e) = value.get::<MatchEvent>() {
            self.matched(e)
        } else if let Some(e) = value.get::<CommandEvent>() {
            self.command(e)
        } else if let Some(s) = value.get::<SourcesNow>() {
            self.sources(s)
        } else if let Some(step) = value.get::<StepFigures>() {
            self.step(step)
        } else if let Some(e) = value.get::<FlightEvent>() {
            self.flight(e)
        } else {
            self.other_event(value)
        }
    }

    /// The figures so far, by the kind of run.
    fn interim(&mut self, figures: &Interim) -> io::Result<()> {
        if let Some(echo) = figures.get::<EchoInterim>() {
            self.echo_interim(echo)
        } else if let Some(passive) = figures.get::<PassiveInterim>() {
            self.passive_interim(passive)
        } else {
            Ok(())
        }
    }

    /// The judged summary at the end, by the kind of run, after the C2
    /// link report over it when the run made one.
    fn summary(&mut self, summary: &LinkSummary, verdict: &Verdict) -> io::Result<()> {
        if let Some(c2) = summary.c2() {
            self.c2_report(summary.link(), c2)?;
        }
        if let Some(echo) = summary.get::<EchoSummary>() {
            self.echo_summary(echo, verdict)
        } else if let Some(command) = summary.get::<CommandSummary>() {
            self.command_summary(command, verdict)
        } else if let Some(passive) = summary.get::<PassiveSummary>() {
            self.passive_summary(passive, verdict)
        } else {
            self.other_summary(summary.kind(), verdict)
        }
    }
}

/// The engine tells its events to an [`Observer`]; a format is one by
/// being a [`Reporter`].
impl<R: Reporter + ?Sized> Observer for R {
    fn start(&mut self, info: &StartInfo) -> io::Result<()> {
        Reporter::start(self, info)
    }
    fn event(&mut self, event: &Event<'_>) -> io::Result<()> {
        self.tell(event)
    }
    fn flush(&mut self) -> io::Result<()> {
        Reporter::flush(self)
    }
    fn interim(&mut self, figures: &Interim) -> io::Result<()> {
        Reporter::interim(self, figures)
    }
}
