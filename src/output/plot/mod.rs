//! `--plot FILE.svg`: collects what the plot shows while the run goes on.
//! The drawing is in `draw.rs`, colours and markers in `style.rs`; a
//! sweep's in `sweep.rs`, a passive run's (each source's rate, frame age
//! and loss over time) in `passive.rs`, a log's flight in `flight.rs`,
//! the age axis they share in `age.rs`, a download run's progress in
//! `transfer.rs`; a run with a C2 link report gets that report's page
//! instead (`c2.rs`).
//!
//! Memory is constant: each responder keeps [`SPANS`](data::SPANS) time
//! spans. When a sample falls past the last span, every span doubles in
//! width and neighbours merge, so a long run is drawn at a coarser time
//! resolution (the mean RTT of each span, and whether it lost anything),
//! never dropped.
//! The legend's loss and percentiles are the run's own summary figures.
//!
//! This file declares and re-exports, and hands a link's [`Reporter`]
//! calls to the [`Plot`]'s data (`data.rs`) through its [`PlotLink`]
//! (`link.rs`).

mod age;
mod c2;
mod data;
mod draw;
mod flight;
mod frame;
mod link;
mod passive;
mod spans;
mod style;
mod sweep;
mod transfer;

use std::io;

use super::windows::Windows;
use super::{Reporter, StartInfo};
use crate::engine::c2::C2Report;
use crate::engine::kind::KindValue;
use crate::engine::matcher::MatchEvent;
use crate::engine::probe::passive::flight::FlightEvent;
use crate::engine::probe::passive::PassivePlan;
use crate::engine::probe::passive::SourcesNow;
use crate::engine::probe::transfer::{AttemptFigures, TransferProgress};
use crate::engine::summary::passive::PassiveSummary;
use crate::engine::summary::EchoSummary;
use crate::engine::Nanos;
use crate::verdict::Verdict;
pub(crate) use frame::PlotError;
pub(crate) use link::{Plot, PlotLink};

impl Reporter for PlotLink {
    fn start(&mut self, info: &StartInfo) -> io::Result<()> {
        self.data.borrow_mut().links[self.index] = info.link.clone();
        self.windows = info.plan::<PassivePlan>().is_some().then(Windows::default);
        Ok(())
    }

    fn matched(&mut self, e: &MatchEvent) -> io::Result<()> {
        self.data.borrow_mut().on_event(self.index, e);
        Ok(())
    }

    fn sources(&mut self, now: &SourcesNow) -> io::Result<()> {
        self.windows(now.at, &now.table, &now.age_max);
        Ok(())
    }

    fn flight(&mut self, event: &FlightEvent) -> io::Result<()> {
        if let FlightEvent::Window(w) = event {
            let mut data = self.data.borrow_mut();
            data.flights.entry(self.index).or_default().window(w);
        }
        Ok(())
    }

    /// A download's progress and its end.
    fn other_event(&mut self, value: &dyn KindValue) -> io::Result<()> {
        let mut data = self.data.borrow_mut();
        if let Some(p) = value.get::<TransferProgress>() {
            transfer::progress(data.downloads.entry(self.index).or_default(), p);
        } else if let Some(a) = value.get::<AttemptFigures>() {
            transfer::ended(data.downloads.entry(self.index).or_default(), a);
        }
        Ok(())
    }

    fn c2_report(&mut self, _: &str, report: &C2Report) -> io::Result<()> {
        let mut data = self.data.borrow_mut();
        data.c2.insert(self.index, report.clone());
        Ok(())
    }

    fn echo_summary(&mut self, s: &EchoSummary, _: &Verdict) -> io::Result<()> {
        let mut data = self.data.borrow_mut();
        data.on_summary(self.index, &s.responders);
        if let Some(sweep) = &s.sweep {
            data.on_sweep(self.index, sweep);
        }
        Ok(())
    }

    /// The last, partial, window, and the figures for the legend. (The
    /// command probe sends no echo requests, so it has no lines.)
    fn passive_summary(&mut self, s: &PassiveSummary, _: &Verdict) -> io::Result<()> {
        // The ages since the last telling are not told: the last partial
        // span has no age point (the legend's p99 covers the whole run).
        self.windows((s.duration_s * 1e9) as Nanos, &s.table, &[]);
        let mut data = self.data.borrow_mut();
        data.on_sources(self.index, &s.table, &s.age);
        if let Some(f) = &s.flight {
            data.flights
                .entry(self.index)
                .or_default()
                .on_summary(f, &s.age);
        }
        Ok(())
    }
}
