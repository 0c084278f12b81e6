//! A radio's series: its latest RADIO_STATUS, and its wrapping error
//! counters followed into counters that only grow.

use crate::engine::radio::{RadioKind, RadioReport, SinceBootCounter};

/// One radio: its latest RADIO_STATUS, and its error counters turned into
/// counters that only grow (the radio's own are 16 bits and wrap, and
/// start again from 0 when it restarts).
#[derive(Debug, Clone, Copy)]
pub(super) struct RadioSeries {
    pub(super) latest: RadioReport,
    /// What the radio is, as the run judges it so far: what its fields
    /// mean.
    pub(super) kind: RadioKind,
    pub(super) rxerrors: SinceBootCounter,
    pub(super) fixed: SinceBootCounter,
}

impl RadioSeries {
    pub(super) fn new(kind: RadioKind) -> Self {
        RadioSeries {
            latest: RadioReport::default(),
            kind,
            rxerrors: SinceBootCounter::default(),
            fixed: SinceBootCounter::default(),
        }
    }

    pub(super) fn record(&mut self, report: RadioReport, kind: RadioKind) {
        self.kind = kind;
        self.latest = report;
        self.rxerrors.record(report.rxerrors);
        self.fixed.record(report.fixed);
    }
}
