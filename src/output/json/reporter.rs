//! The JSON reporter: where its lines go, and which it writes (`-q`
//! keeps the summary only, a command run its commands' own events).

use std::io::{self, Write};

use serde::Serialize;

use super::lines::Lines;
use crate::output::WallClock;

pub(crate) struct JsonReporter<W: Write> {
    pub(super) out: W,
    /// Only the summary object (`--json -q`).
    pub(super) quiet: bool,
    pub(super) lines: Lines,
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

impl<W: Write> JsonReporter<W> {
    /// Writes the summary line, in quiet mode too, and pushes it out.
    pub(super) fn summary_line(out: &mut W, line: &impl Serialize) -> io::Result<()> {
        Lines::write_named(out, line)?;
        out.flush()
    }

    /// Writes the line of the figures so far, in quiet mode too (that is
    /// what `-Q` is for), and pushes it out.
    pub(super) fn interim_line(&mut self, line: &impl Serialize) -> io::Result<()> {
        self.lines.write(&mut self.out, line)?;
        self.out.flush()
    }

    /// Writes an event's line, except in quiet mode and in a command run,
    /// which writes only its own kind's lines ([`Self::own_line`]).
    pub(super) fn event_line(&mut self, line: Option<impl Serialize>) -> io::Result<()> {
        match line {
            Some(line) if !self.lines.command => self.own_line(line),
            _ => Ok(()),
        }
    }

    /// Writes the line of a kind's event written whole, except in quiet
    /// mode.
    pub(super) fn own_line(&mut self, line: impl Serialize) -> io::Result<()> {
        if self.quiet {
            return Ok(());
        }
        self.lines.write(&mut self.out, &line)
    }
}
