//! Reports: each output format follows a session as an engine
//! [`Observer`] and renders the judged summary at the end ([`Reporter`]).

pub(crate) mod basic_auth;
#[cfg(test)]
mod every_format;
pub(crate) mod hgrm;
pub mod http;
pub(crate) mod json;
pub(crate) mod live;
pub(crate) mod plot;
pub mod prometheus;
mod reporter;
#[cfg(test)]
mod runs;
pub(crate) mod samples;
pub(crate) mod text;
pub(crate) mod textfile;
pub(crate) mod windows;

use std::io;
use std::time::{Duration, SystemTime};

pub(crate) use crate::engine::observe::{Event, RunKind, StartInfo};
use crate::engine::summary::{Interim, LinkSummary};
use crate::engine::Nanos;
use crate::verdict::Verdict;
pub(crate) use reporter::Reporter;

/// Session time to wall-clock time. The wall clock is read once at the
/// start (the UNIX epoch under the virtual clock, so output is reproducible)
/// and advanced by the monotonic session clock.
#[derive(Debug, Clone, Copy)]
pub(crate) struct WallClock {
    pub(crate) start: SystemTime,
}

impl WallClock {
    /// Now, or the UNIX epoch when the run is on a virtual clock.
    pub(crate) fn starting(virtual_clock: bool) -> Self {
        WallClock {
            start: if virtual_clock {
                SystemTime::UNIX_EPOCH
            } else {
                SystemTime::now()
            },
        }
    }

    pub(crate) fn at(&self, t: Nanos) -> SystemTime {
        self.start + Duration::from_nanos(t)
    }

    pub(crate) fn rfc3339(&self, t: Nanos) -> String {
        humantime::format_rfc3339_micros(self.at(t)).to_string()
    }

    pub(crate) fn micros_since_epoch(&self) -> u64 {
        self.start
            .duration_since(SystemTime::UNIX_EPOCH)
            .map_or(0, |d| d.as_micros() as u64)
    }
}

/// Several reporters fed the same run (the chosen format, the sample log,
/// the exporter...). One that fails to write is not written to again, and
/// the others go on: a closed stdout (`| head`) must not cost the plot,
/// the sample log or the exporter anything.
#[derive(Default)]
pub(crate) struct Fanout<'a> {
    reporters: Vec<(Box<dyn Reporter + 'a>, bool)>,
}

impl<'a> Fanout<'a> {
    pub(crate) fn new(reporters: Vec<Box<dyn Reporter + 'a>>) -> Self {
        Fanout {
            reporters: reporters.into_iter().map(|r| (r, true)).collect(),
        }
    }

    /// Calls `f` on each reporter still writing; the first error is told
    /// back, and the reporter that gave it is muted.
    fn each(&mut self, mut f: impl FnMut(&mut dyn Reporter) -> io::Result<()>) -> io::Result<()> {
        let mut result = Ok(());
        for (r, writing) in self.reporters.iter_mut().filter(|(_, w)| *w) {
            if let Err(e) = f(r.as_mut()) {
                *writing = false;
                if result.is_ok() {
                    result = Err(e);
                }
            }
        }
        result
    }
}

impl Reporter for Fanout<'_> {
    fn start(&mut self, info: &StartInfo) -> io::Result<()> {
        self.each(|r| r.start(info))
    }
    fn tell(&mut self, event: &Event<'_>) -> io::Result<()> {
        self.each(|r| r.tell(event))
    }
    fn flush(&mut self) -> io::Result<()> {
        self.each(|r| r.flush())
    }
    fn interim(&mut self, figures: &Interim) -> io::Result<()> {
        self.each(|r| r.interim(figures))
    }
    fn summary(&mut self, summary: &LinkSummary, verdict: &Verdict) -> io::Result<()> {
        self.each(|r| r.summary(summary, verdict))
    }
}

/// One writer shared by the reports of several links run side by side on
/// one thread (one tokio task joins them, so a `RefCell` suffices). A line
/// is written by one `writeln!` without an await in between, so lines of
/// different links never interleave.
pub(crate) struct Shared<W: io::Write>(pub std::rc::Rc<std::cell::RefCell<W>>);

impl<W: io::Write> Shared<W> {
    pub(crate) fn new(out: W) -> Self {
        Shared(std::rc::Rc::new(std::cell::RefCell::new(out)))
    }
}

impl<W: io::Write> Clone for Shared<W> {
    fn clone(&self) -> Self {
        Shared(self.0.clone())
    }
}

impl<W: io::Write> io::Write for Shared<W> {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        self.0.borrow_mut().write(buf)
    }
    fn write_all(&mut self, buf: &[u8]) -> io::Result<()> {
        self.0.borrow_mut().write_all(buf)
    }
    fn flush(&mut self) -> io::Result<()> {
        self.0.borrow_mut().flush()
    }
}

/// Starts every line with a fixed prefix (`[LINK] `), so per-reply lines
/// of several links can be told apart; without one, writes through.
pub(crate) struct Prefixed<W: io::Write> {
    out: W,
    prefix: Option<String>,
    at_line_start: bool,
}

impl<W: io::Write> Prefixed<W> {
    pub(crate) fn new(out: W, prefix: Option<String>) -> Self {
        Prefixed {
            out,
            prefix,
            at_line_start: true,
        }
    }
}

impl<W: io::Write> Prefixed<W> {
    /// The writer itself, bypassing the prefix.
    pub(crate) fn inner(&mut self) -> &mut W {
        &mut self.out
    }

    pub(crate) fn into_inner(self) -> W {
        self.out
    }
}

impl<W: io::Write> io::Write for Prefixed<W> {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        let Some(prefix) = &self.prefix else {
            return self.out.write(buf);
        };
        let mut rest = buf;
        while !rest.is_empty() {
            if self.at_line_start {
                self.out.write_all(prefix.as_bytes())?;
                self.at_line_start = false;
            }
            let end = rest
                .iter()
                .position(|&b| b == b'\n')
                .map_or(rest.len(), |i| i + 1);
            self.out.write_all(&rest[..end])?;
            self.at_line_start = rest[end - 1] == b'\n';
            rest = &rest[end..];
        }
        Ok(buf.len())
    }
    fn flush(&mut self) -> io::Result<()> {
        self.out.flush()
    }
}

#[cfg(test)]
mod tests {
    use std::io::Write;

    use super::*;

    #[test]
    fn prefixed_lines_share_one_writer() {
        let shared = Shared::new(Vec::new());
        let mut a = Prefixed::new(shared.clone(), Some("[a] ".into()));
        let mut b = Prefixed::new(shared.clone(), Some("[b] ".into()));
        let mut plain = Prefixed::new(shared.clone(), None);
        write!(a, "one").unwrap();
        writeln!(a, " line\ntwo").unwrap();
        writeln!(b, "three").unwrap();
        writeln!(plain, "four").unwrap();
        a.write_all(b"").unwrap();
        let out = String::from_utf8(shared.0.borrow().clone()).unwrap();
        assert_eq!(out, "[a] one line\n[a] two\n[b] three\nfour\n");
    }
}
