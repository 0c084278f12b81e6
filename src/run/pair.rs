//! The pair report of a run over several links (issue 41): every link's
//! received frames go to one [`PairTracker`] on one clock as the links
//! run, and its report follows the links' summaries. The run's links
//! share one thread, so one tracker behind a `RefCell` serves them all.

use std::cell::RefCell;
use std::io::{self, Write};
use std::rc::Rc;

use tokio::time::Instant;

use crate::cli::Format;
use crate::engine::pair::{PairConfig, PairTracker};
use crate::engine::Nanos;
use crate::output::pair as report;
use crate::transport::recording::Watch;
use crate::transport::Inbound;

/// The run's tracker and the clock its links share.
pub(super) struct Pairs {
    tracker: Rc<RefCell<PairTracker>>,
    origin: Instant,
}

/// One link's way into the tracker.
struct LinkWatch {
    tracker: Rc<RefCell<PairTracker>>,
    link: usize,
    origin: Instant,
}

/// Nanoseconds from `origin` to `at` (0 before it).
fn since(origin: Instant, at: Instant) -> Nanos {
    at.saturating_duration_since(origin).as_nanos() as Nanos
}

impl Watch for LinkWatch {
    fn received(&self, inbound: &[Inbound]) {
        let mut tracker = self.tracker.borrow_mut();
        for i in inbound {
            tracker.on_frame(self.link, &i.frame, since(self.origin, i.at));
        }
    }
}

impl Pairs {
    /// A tracker for the run's `links` links.
    pub(super) fn new(links: usize) -> Self {
        Pairs {
            tracker: Rc::new(RefCell::new(PairTracker::new(links, PairConfig::default()))),
            origin: Instant::now(),
        }
    }

    /// What the link at `place` on the command line tells the tracker by.
    pub(super) fn watch(&self, place: usize) -> Rc<dyn Watch> {
        Rc::new(LinkWatch {
            tracker: self.tracker.clone(),
            link: place,
            origin: self.origin,
        })
    }

    /// Writes the report in `format` when a source was heard on two links
    /// or more (`names`: the links by place), and flushes.
    pub(super) fn write(
        &self,
        format: Format,
        names: &[&str],
        out: &mut impl Write,
    ) -> io::Result<()> {
        // The links have ended: no copy can come, every window is closed.
        let summary = self.tracker.borrow().summary(Nanos::MAX);
        if summary.sources.is_empty() {
            return Ok(());
        }
        match format {
            Format::Json => report::write_json(out, &summary, names)?,
            Format::Text => report::write_text(out, &summary, names)?,
        }
        out.flush()
    }
}
