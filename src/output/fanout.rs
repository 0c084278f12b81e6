//! One run, several formats: the chosen one, the sample log, the plot,
//! the exporter.

use std::io;

use super::{Event, Reporter, StartInfo};
use crate::engine::summary::{Interim, LinkSummary};
use crate::verdict::Verdict;

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
