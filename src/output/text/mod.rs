//! Human output, modelled on ping: a line per reply as it happens, then a
//! summary per responder. Echo probes' lines and summary are in
//! [`echo`], the command probe's in [`command`]; this file holds what both
//! share.

mod command;
mod echo;
mod flight;
mod heard;
mod link_node;
mod passive;
mod round_trips;
mod sweep;

use std::io::{self, Write};

use super::{Prefixed, Reporter, RunKind, StartInfo, WallClock};
use crate::engine::matcher::MatchEvent;
use crate::engine::observe::{CommandEvent, RadioHeard};
use crate::engine::radio::{RadioKind, RadioReport};
use crate::engine::roster::Identity;
use crate::engine::stats::Bucket;
use crate::engine::summary::passive::PassiveSummary;
use crate::engine::summary::{CommandSummary, EchoInterim, PassiveInterim, Summary};
use crate::engine::sweep_report::StepFigures;
use crate::engine::Nanos;
use crate::frame::signing::SigningSummary;
use crate::frame::SysComp;
use crate::verdict::Verdict;

pub(crate) struct TextReporter<W: Write> {
    /// Event lines go through the link's prefix (with several links);
    /// the summary is written unprefixed, under its own header.
    out: Prefixed<W>,
    /// Only the summary (`-q`).
    quiet: bool,
    /// What kind of run it is, which decides what event lines show.
    run: RunKind,
    timeout: std::time::Duration,
    /// Print every reply even at high rates (`--every-reply`).
    every_reply: bool,
    /// Above [`echo::MAX_LINE_RATE`] requests/s: one status line per
    /// second instead of a line per event, so printing never paces the
    /// engine.
    progress: Option<echo::Progress>,
    /// The latest RADIO_STATUS and its radio's kind, and when a reply
    /// line last showed one.
    radio: Option<(SysComp, RadioReport, RadioKind)>,
    radio_shown: Option<Nanos>,
    /// `-D`: each event line starts with its Unix time, as `ping -D`.
    timestamps: Option<WallClock>,
    /// Step rows printed as the steps ended; the summary shows the rest.
    steps_shown: usize,
}

impl<W: Write> TextReporter<W> {
    pub(crate) fn new(out: W, quiet: bool) -> Self {
        TextReporter {
            out: Prefixed::new(out, None),
            quiet,
            run: RunKind::Echo,
            timeout: std::time::Duration::ZERO,
            every_reply: false,
            progress: None,
            radio: None,
            radio_shown: None,
            timestamps: None,
            steps_shown: 0,
        }
    }

    /// Event lines start with `[UNIX.MICROS] ` on `wall` (`-D`).
    pub(crate) fn timestamps(mut self, wall: Option<WallClock>) -> Self {
        self.timestamps = wall;
        self
    }

    /// The `-D` stamp of an event at session time `at`, if asked for.
    fn stamp(&mut self, at: Nanos) -> io::Result<()> {
        let Some(wall) = self.timestamps else {
            return Ok(());
        };
        let since = wall
            .at(at)
            .duration_since(std::time::UNIX_EPOCH)
            .unwrap_or_default();
        write!(
            self.out,
            "[{}.{:06}] ",
            since.as_secs(),
            since.subsec_micros()
        )
    }

    /// A line per reply whatever the rate.
    pub(crate) fn every_reply(mut self, every: bool) -> Self {
        self.every_reply = every;
        self
    }

    /// Event lines start with `[LINK] ` (one of several links).
    pub(crate) fn prefixed(mut self, prefix: Option<String>) -> Self {
        self.out = Prefixed::new(self.out.into_inner(), prefix);
        self
    }

    #[cfg(test)]
    pub(crate) fn into_inner(self) -> W {
        self.out.into_inner()
    }
}

impl<W: Write> TextReporter<W> {
    /// The summary's header, as ping's; the summary is written unprefixed.
    fn summary_head(&mut self, link: &str) -> io::Result<&mut W> {
        let quiet = self.quiet;
        let out = self.out.inner();
        if !quiet {
            writeln!(out)?;
        }
        writeln!(out, "--- {link} mavping statistics ---")?;
        Ok(out)
    }

    /// Event lines other than a command's are shown: not in quiet mode,
    /// and not in a command run, which shows its commands' fate only.
    fn shows_events(&self) -> bool {
        !self.quiet && self.run.command().is_none()
    }
}

impl<W: Write> Reporter for TextReporter<W> {
    fn start(&mut self, info: &StartInfo) -> io::Result<()> {
        self.timeout = info.timeout;
        self.run = info.run.clone();
        if self.quiet {
            return Ok(());
        }
        match &info.run {
            RunKind::Echo => self.echo_start(info),
            RunKind::Steps(plan) => self.sweep_start(info, plan),
            RunKind::Command(spec) => self.command_start(info, spec),
            RunKind::Passive { heartbeat, log } => self.passive_start(info, *heartbeat, *log),
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
        if self.shows_events() && self.run.steps().is_none() {
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
    fn echo_summary(&mut self, s: &Summary, verdict: &Verdict) -> io::Result<()> {
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

/// Milliseconds with µs resolution, as ping prints them.
fn ms(ns: Nanos) -> String {
    format!("{:.3}", ns as f64 / 1e6)
}

fn ms_us(us: f64) -> String {
    format!("{:.3}", us / 1e3)
}

/// A rate with one decimal, or three significant digits below 0.1/s (a
/// PING every 30 s is 0.0333/s, not "0.0/s").
fn per_second(hz: f64) -> String {
    if hz >= 0.1 || hz <= 0.0 || !hz.is_finite() {
        format!("{hz:.1}")
    } else {
        let decimals = (-hz.log10()).ceil() as usize + 2;
        format!("{hz:.decimals$}")
    }
}

fn rate(interval: std::time::Duration) -> String {
    let per_s = 1.0 / interval.as_secs_f64();
    if per_s >= 1.0 && per_s.fract() == 0.0 {
        format!("{per_s}/s")
    } else {
        format!("every {}", humantime::format_duration(interval))
    }
}

fn write_histogram(out: &mut impl Write, histogram: &[Bucket]) -> io::Result<()> {
    let most = histogram.iter().map(|b| b.count).max().unwrap_or(0).max(1);
    for b in histogram {
        const WIDTH: u64 = 40;
        let bar = (b.count * WIDTH).div_ceil(most) as usize;
        writeln!(
            out,
            "  {:>9} ms |{:<40}| {}",
            ms_us(b.low_us),
            "#".repeat(bar),
            b.count
        )?;
    }
    Ok(())
}

/// One line: what the signing gate let through and what it refused
/// (refused frames were never measured); without a key, only when signed
/// frames came (their signatures could not be checked).
fn write_signing(out: &mut impl Write, s: &SigningSummary) -> io::Result<()> {
    match s.link_id {
        Some(link_id) => writeln!(
            out,
            "signing (link id {link_id}, {}): {}",
            if s.required {
                "signatures required"
            } else {
                "unsigned accepted"
            },
            s.counts
        ),
        None if s.counts.signed_unchecked > 0 => writeln!(
            out,
            "signing (no key): {} signed frames accepted unchecked, {} unsigned",
            s.counts.signed_unchecked, s.counts.unsigned
        ),
        None => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn slow_rates_keep_three_significant_digits() {
        assert_eq!(per_second(5.0), "5.0");
        assert_eq!(per_second(0.1), "0.1");
        assert_eq!(per_second(1.0 / 30.0), "0.0333");
        assert_eq!(per_second(1.0 / 3600.0), "0.000278");
        assert_eq!(per_second(0.0), "0.0");
    }
}
