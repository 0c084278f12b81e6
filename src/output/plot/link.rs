//! The run's one [`Plot`], and each link's way into it ([`PlotLink`]).

use std::cell::RefCell;
use std::rc::Rc;

use super::data::PlotData;
use super::frame::PlotError;
use crate::engine::pair::PairSummary;
use crate::engine::summary::passive::TableSummary;
use crate::engine::Nanos;
use crate::frame::SysComp;
use crate::output::windows::Windows;

/// `--plot`: collects every link's samples during the run; the run draws
/// it once every link has ended.
#[derive(Default)]
pub(crate) struct Plot {
    pub(super) data: Rc<RefCell<PlotData>>,
}

impl Plot {
    /// The reporter of the next link.
    pub(crate) fn link(&self) -> PlotLink {
        let mut data = self.data.borrow_mut();
        data.links.push(String::new());
        PlotLink {
            data: self.data.clone(),
            index: data.links.len() - 1,
            windows: None,
        }
    }

    /// The pair report so far, at `at`, its links by place.
    pub(crate) fn on_pair(&self, at: Nanos, summary: &PairSummary) {
        self.data.borrow_mut().on_pair(at, summary);
    }

    /// Draws the SVG document.
    pub(crate) fn svg(&self) -> Result<String, PlotError> {
        self.data.borrow().svg()
    }
}

/// One link's samples into the [`Plot`].
pub(crate) struct PlotLink {
    pub(super) data: Rc<RefCell<PlotData>>,
    pub(super) index: usize,
    /// A passive run's sources, window by window (set at its start).
    pub(super) windows: Option<Windows>,
}

impl PlotLink {
    /// The windows ending at `at` of a passive run's sources, with each
    /// source's oldest frame's age (ms) in them.
    pub(super) fn windows(&mut self, at: Nanos, table: &TableSummary, ages: &[(SysComp, f64)]) {
        if let Some(windows) = self.windows.as_mut() {
            let next = windows.next(at, table);
            self.data.borrow_mut().on_windows(self.index, &next, ages);
        }
    }
}
