//! Human output, modelled on ping: a line per reply as it happens, then a
//! summary per responder. Echo probes' lines and summary are in
//! [`echo`], the command probe's in [`command`].
//!
//! This file declares and re-exports, and hands each [`Reporter`] call to
//! the file that writes its lines; the reporter itself is in
//! `reporter.rs`, and what the kinds of run share in `format.rs` (numbers),
//! `histogram.rs` and `signing.rs`.

mod command;
mod echo;
mod flight;
mod format;
mod heard;
mod histogram;
mod link_node;
mod passive;
mod reporter;
mod round_trips;
mod signing;
mod sweep;

use std::io::{self, Write};

use super::{Reporter, StartInfo};
use crate::engine::matcher::MatchEvent;
use crate::engine::observe::RadioHeard;
use crate::engine::probe::command::CommandEvent;
use crate::engine::probe::passive::PassivePlan;
use crate::engine::roster::Identity;
use crate::engine::summary::passive::PassiveSummary;
use crate::engine::summary::{CommandSummary, EchoInterim, EchoSummary, PassiveInterim};
use crate::engine::sweep_report::{StepFigures, SweepConfig};
use crate::engine::CommandSpec;
use crate::frame::SysComp;
use crate::verdict::Verdict;
pub(crate) use reporter::TextReporter;

impl<W: Write> Reporter for TextReporter<W> {
    fn start(&mut self, info: &StartInfo) -> io::Result<()> {
        self.timeout = info.timeout;
        self.commands = info.plan::<CommandSpec>().is_some();
        self.in_steps = info.plan::<SweepConfig>().is_some();
        if self.quiet {
            return Ok(());
        }
        if let Some(plan) = info.plan::<SweepConfig>() {
            self.sweep_start(info, plan)
        } else if let Some(spec) = info.plan::<CommandSpec>() {
            self.command_start(info, spec)
        } else if let Some(plan) = info.plan::<PassivePlan>() {
            self.passive_start(info, plan.heartbeat, plan.log)
        } else {
            self.echo_start(info)
        }
    }

    fn command(&mut self, event: &CommandEvent) -> io::Result<()> {
        if self.quiet {
            return Ok(());
        }
        self.command_event(event)
    }

    /// A run in steps shows each step, not each reply.
    fn matched(&mut self, event: &MatchEvent) -> io::Result<()> {
        if self.shows_events() && !self.in_steps {
            self.match_line(event)
        } else {
            Ok(())
        }
    }

    fn heard(&mut self, id: SysComp, identity: &Identity) -> io::Result<()> {
        if self.shows_events() {
            self.heard_line(id, identity)
        } else {
            Ok(())
        }
    }

    fn radio(&mut self, radio: &RadioHeard<'_>) -> io::Result<()> {
        if self.shows_events() {
            self.radio_line(radio)
        } else {
            Ok(())
        }
    }

    fn step(&mut self, step: &StepFigures) -> io::Result<()> {
        if self.shows_events() {
            self.step_row(step)
        } else {
            Ok(())
        }
    }

    fn waiting_for_peer(&mut self) -> io::Result<()> {
        if self.shows_events() {
            self.waiting_line()
        } else {
            Ok(())
        }
    }

    fn flush(&mut self) -> io::Result<()> {
        self.out.flush()
    }

    /// A line per responder, in quiet mode too: that is what `-Q` is for.
    fn echo_interim(&mut self, figures: &EchoInterim) -> io::Result<()> {
        self.write_interim(figures)
    }

    fn passive_interim(&mut self, figures: &PassiveInterim) -> io::Result<()> {
        self.write_passive_interim(figures)
    }

    /// Steps not shown as they ended (-q, or cut short) are shown here.
    fn echo_summary(&mut self, s: &EchoSummary, verdict: &Verdict) -> io::Result<()> {
        let steps_shown = self.steps_shown;
        let out = self.summary_head(&s.link)?;
        echo::write_summary(out, s, verdict, steps_shown)?;
        out.flush()
    }

    fn command_summary(&mut self, s: &CommandSummary, _: &Verdict) -> io::Result<()> {
        let out = self.summary_head(&s.link)?;
        command::write_summary(out, s)?;
        out.flush()
    }

    fn passive_summary(&mut self, s: &PassiveSummary, verdict: &Verdict) -> io::Result<()> {
        let out = self.summary_head(&s.link)?;
        passive::write_summary(out, s, verdict)?;
        out.flush()
    }
}
