//! Human output, modelled on ping: a line per reply as it happens, then a
//! summary per responder. Echo probes' lines and summary are in
//! [`echo`], the command probe's in [`command`]; the C2 link report
//! after the summary in [`c2`].
//!
//! This file declares and re-exports, and hands each [`Reporter`] call to
//! the file that writes its lines; the reporter itself is in
//! `reporter.rs`, and what the kinds of run share in `format.rs` (numbers,
//! who a system is) and `summary.rs` (summary lines).

mod c2;
mod command;
mod echo;
mod flight;
mod format;
mod heard;
mod link_node;
mod passive;
mod reporter;
mod round_trips;
mod summary;
mod sweep;
mod transfer;
mod whole;

use std::any::Any;
use std::io::{self, Write};

use super::{Reporter, StartInfo};
use crate::engine::c2::C2Report;
use crate::engine::kind::KindValue;
use crate::engine::matcher::MatchEvent;
use crate::engine::observe::RadioHeard;
use crate::engine::probe::command::CommandEvent;
use crate::engine::probe::passive::PassivePlan;
use crate::engine::probe::transfer::{
    AttemptFigures, TransferProgress, TransferSpec, TransferSummary,
};
use crate::engine::roster::Identity;
use crate::engine::summary::passive::PassiveSummary;
use crate::engine::summary::{
    CommandSummary, EchoInterim, EchoSummary, KindSummary, PassiveInterim,
};
use crate::engine::sweep_report::{StepFigures, SweepConfig};
use crate::engine::CommandSpec;
use crate::frame::SysComp;
use crate::verdict::Verdict;
pub(crate) use c2::two_significant;
pub(crate) use reporter::TextReporter;

impl<W: Write> Reporter for TextReporter<W> {
    fn start(&mut self, info: &StartInfo) -> io::Result<()> {
        self.timeout = info.timeout;
        self.commands = info.plan::<CommandSpec>().is_some();
        self.in_steps =
            info.plan::<SweepConfig>().is_some() || info.plan::<TransferSpec>().is_some();
        if self.quiet {
            return Ok(());
        }
        if let Some(plan) = info.plan::<SweepConfig>() {
            self.sweep_start(info, plan)
        } else if let Some(spec) = info.plan::<CommandSpec>() {
            self.command_start(info, spec)
        } else if let Some(spec) = info.plan::<TransferSpec>() {
            self.transfer_start(info, spec)
        } else if let Some(plan) = info.plan::<PassivePlan>() {
            self.passive_start(info, plan)
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

    /// A run in steps shows each step, not each reply (a download run
    /// each download).
    fn matched(&mut self, event: &MatchEvent) -> io::Result<()> {
        if self.in_steps {
            return Ok(());
        }
        self.if_shown(|t| t.match_line(event))
    }

    fn heard(&mut self, id: SysComp, identity: &Identity) -> io::Result<()> {
        self.if_shown(|t| t.heard_line(id, identity))
    }

    fn radio(&mut self, radio: &RadioHeard<'_>) -> io::Result<()> {
        self.if_shown(|t| t.radio_line(radio))
    }

    fn step(&mut self, step: &StepFigures) -> io::Result<()> {
        self.if_shown(|t| t.step_row(step))
    }

    fn waiting_for_peer(&mut self) -> io::Result<()> {
        self.if_shown(Self::waiting_line)
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
        self.summary_block(&s.link, |out| {
            echo::write_summary(out, s, verdict, steps_shown)
        })
    }

    fn command_summary(&mut self, s: &CommandSummary, _: &Verdict) -> io::Result<()> {
        self.summary_block(&s.link, |out| command::write_summary(out, s))
    }

    fn passive_summary(&mut self, s: &PassiveSummary, verdict: &Verdict) -> io::Result<()> {
        self.summary_block(&s.link, |out| passive::write_summary(out, s, verdict))
    }

    /// Held for after the summary's statistics block, `-q` or not.
    fn c2_report(&mut self, link: &str, report: &C2Report) -> io::Result<()> {
        let mut text = Vec::new();
        c2::write_report(&mut text, link, report)?;
        self.c2 = Some(String::from_utf8_lossy(&text).into_owned());
        Ok(())
    }

    /// A kind with no lines of its own: its event's figures on a line.
    fn other_event(&mut self, value: &dyn KindValue) -> io::Result<()> {
        // A download's progress is for the plot and JSON; its end is a line.
        if value.get::<TransferProgress>().is_some() {
            return Ok(());
        }
        if let Some(a) = value.get::<AttemptFigures>() {
            return self.if_shown(|t| t.transfer_line(a));
        }
        match value.serialized().and_then(whole::event_line) {
            Some(line) => self.if_shown(|t| writeln!(t.out.inner(), "{line}")),
            None => Ok(()),
        }
    }

    /// A kind with no summary of its own: its figures, one to a line.
    fn other_summary(&mut self, s: &dyn KindSummary, verdict: &Verdict) -> io::Result<()> {
        if let Some(t) = (s as &dyn Any).downcast_ref::<TransferSummary>() {
            return self.summary_block(&t.link, |out| {
                transfer::write_summary(out, t)?;
                summary::write_failures(out, verdict)
            });
        }
        let Some((_, figures)) = s.serialized() else {
            return self.c2_block();
        };
        self.summary_block(s.link(), |out| {
            whole::write_figures(out, figures)?;
            summary::write_failures(out, verdict)
        })
    }
}

#[cfg(test)]
mod tests;
