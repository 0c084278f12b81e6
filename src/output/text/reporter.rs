//! The text reporter: where its lines go (through the link's prefix, the
//! summary under its own header), and which it shows (`-q`, `-D`,
//! `--every-reply`, what kind of run it is).

use std::fmt::Arguments;
use std::io::{self, Write};

use super::echo;
use crate::engine::radio::{RadioKind, RadioReport};
use crate::engine::Nanos;
use crate::frame::SysComp;
use crate::output::{Prefixed, StartInfo, WallClock};

pub(crate) struct TextReporter<W: Write> {
    /// Event lines go through the link's prefix (with several links);
    /// the summary is written unprefixed, under its own header.
    pub(super) out: Prefixed<W>,
    /// Only the summary (`-q`).
    pub(super) quiet: bool,
    /// A command run shows its commands' fate only.
    pub(super) commands: bool,
    /// A run in steps shows each step, not each reply; a download run
    /// each download (its TIMESYNC replies go to the summary).
    pub(super) in_steps: bool,
    pub(super) timeout: std::time::Duration,
    /// Print every reply even at high rates (`--every-reply`).
    pub(super) every_reply: bool,
    /// Above [`echo::MAX_LINE_RATE`] requests/s: one status line per
    /// second instead of a line per event, so printing never paces the
    /// engine.
    pub(super) progress: Option<echo::Progress>,
    /// The latest RADIO_STATUS and its radio's kind, and when a reply
    /// line last showed one.
    pub(super) radio: Option<(SysComp, RadioReport, RadioKind)>,
    pub(super) radio_shown: Option<Nanos>,
    /// `-D`: each event line starts with its Unix time, as `ping -D`.
    pub(super) timestamps: Option<WallClock>,
    /// Step rows printed as the steps ended; the summary shows the rest.
    pub(super) steps_shown: usize,
    /// The C2 link report, told before the summary and written after its
    /// statistics block.
    pub(super) c2: Option<String>,
}

impl<W: Write> TextReporter<W> {
    pub(crate) fn new(out: W, quiet: bool) -> Self {
        TextReporter {
            out: Prefixed::new(out, None),
            quiet,
            commands: false,
            in_steps: false,
            timeout: std::time::Duration::ZERO,
            every_reply: false,
            progress: None,
            radio: None,
            radio_shown: None,
            timestamps: None,
            steps_shown: 0,
            c2: None,
        }
    }

    /// Event lines start with `[UNIX.MICROS] ` on `wall` (`-D`).
    pub(crate) fn timestamps(mut self, wall: Option<WallClock>) -> Self {
        self.timestamps = wall;
        self
    }

    /// The `-D` stamp of an event at session time `at`, if asked for.
    pub(super) fn stamp(&mut self, at: Nanos) -> io::Result<()> {
        let Some(wall) = self.timestamps else {
            return Ok(());
        };
        let since = wall
            .at(at)
            .duration_since(std::time::UNIX_EPOCH)
            .unwrap_or_default();
        let (secs, micros) = (since.as_secs(), since.subsec_micros());
        write!(self.out, "[{secs}.{micros:06}] ")
    }

    /// `[12.0 s] ` after the `-D` stamp: how interim and status lines
    /// start.
    pub(super) fn interim_head(&mut self, at: Nanos) -> io::Result<()> {
        self.stamp(at)?;
        write!(self.out, "[{:.1} s] ", at as f64 / 1e9)
    }

    /// The first line, as ping's: `MAVPING LINK from OURS: ` and `what`.
    pub(super) fn start_line(&mut self, info: &StartInfo, what: Arguments<'_>) -> io::Result<()> {
        writeln!(self.out, "MAVPING {} from {}: {what}", info.link, info.ours)
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

    /// The summary, under its header as ping's; written unprefixed. The
    /// C2 link report, if one came, follows under its own.
    pub(super) fn summary_block(
        &mut self,
        link: &str,
        write: impl FnOnce(&mut W) -> io::Result<()>,
    ) -> io::Result<()> {
        let quiet = self.quiet;
        let out = self.out.inner();
        if !quiet {
            writeln!(out)?;
        }
        writeln!(out, "--- {link} mavping statistics ---")?;
        write(out)?;
        self.c2_block()
    }

    /// The C2 link report held for after the statistics, if any.
    pub(super) fn c2_block(&mut self) -> io::Result<()> {
        let c2 = self.c2.take();
        let out = self.out.inner();
        if let Some(c2) = c2 {
            if !self.quiet {
                writeln!(out)?;
            }
            out.write_all(c2.as_bytes())?;
        }
        out.flush()
    }

    /// Writes an event's line if event lines are shown: not in quiet
    /// mode, and not in a command run, which shows its commands' fate only.
    pub(super) fn if_shown(
        &mut self,
        write: impl FnOnce(&mut Self) -> io::Result<()>,
    ) -> io::Result<()> {
        if self.quiet || self.commands {
            return Ok(());
        }
        write(self)
    }
}
