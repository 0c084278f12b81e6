//! `--live` in a passive run: a row per source from the table the engine
//! tells once a second ([`Event::Sources`]), never from a per-frame event.
//! Each source keeps its latest figures and its last [`RECENT`] seconds
//! (frames, and whether any were lost) for the strip.
//!
//! [`Event::Sources`]: crate::engine::observe::Event::Sources

use std::collections::BTreeMap;

use super::state::RECENT;
use crate::engine::roster::Identity;
use crate::engine::summary::passive::{SeqCounts, TableSummary};
use crate::engine::Nanos;
use crate::frame::SysComp;
use crate::output::windows::Windows;

/// Identities kept for sources not (yet) in the table: as many as it
/// tracks, and some.
const MAX_HEARD: usize = 64;

/// One second of a source, as the strip shows it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Second {
    pub(crate) frames: u64,
    /// Its sequence skipped numbers in it.
    pub(crate) lost: bool,
}

/// Who a system says it is, as a row shows it: `vehicle autopilot`.
pub(super) fn heard_as(identity: &Identity) -> String {
    format!("{} {}", identity.vehicle, identity.autopilot_said())
}

/// A passive run's sources, as the view follows them.
#[derive(Debug, Clone, Default)]
pub(super) struct Sources {
    windows: Windows,
    /// Each source's row, but for who it is (filled in when drawn).
    sources: BTreeMap<SysComp, SourceRow>,
    /// `vehicle autopilot` from each system's first HEARTBEAT.
    heard: BTreeMap<SysComp, String>,
}

impl Sources {
    pub(super) fn heard(&mut self, id: SysComp, identity: &Identity) {
        if self.heard.len() < MAX_HEARD || self.heard.contains_key(&id) {
            self.heard.insert(id, heard_as(identity));
        }
    }

    /// The table as of `at`: each source's figures, and its latest second.
    pub(super) fn table(&mut self, at: Nanos, table: &TableSummary) {
        for (w, s) in self.windows.next(at, table).iter().zip(&table.sources) {
            let t = self.sources.entry(s.source).or_default();
            t.radio = s.radio;
            t.counts = s.counts;
            t.loss_pct = s.loss_pct;
            t.silences = s.silence_count;
            t.rate = w.frames_per_s();
            if t.recent.len() == RECENT {
                t.recent.remove(0);
            }
            t.recent.push(Second {
                frames: w.received,
                lost: w.lost > 0,
            });
        }
    }

    /// The rows to draw, by source.
    pub(super) fn rows(&self) -> Vec<SourceRow> {
        self.sources
            .iter()
            .map(|(id, s)| SourceRow {
                id: id.to_string(),
                identity: self
                    .heard
                    .get(id)
                    .cloned()
                    .or_else(|| s.radio.then(|| "radio".to_string())),
                ..s.clone()
            })
            .collect()
    }
}

/// One source's row.
#[derive(Debug, Clone, Default)]
pub(crate) struct SourceRow {
    pub(crate) id: String,
    /// What its HEARTBEAT said it is; `radio` for the SiK radio's own.
    pub(crate) identity: Option<String>,
    pub(crate) radio: bool,
    pub(crate) counts: SeqCounts,
    pub(crate) loss_pct: Option<f64>,
    pub(crate) silences: u64,
    /// Frames a second in the latest second.
    pub(crate) rate: Option<f64>,
    pub(crate) recent: Vec<Second>,
}
