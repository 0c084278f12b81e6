//! `--live` in a passive run: a row per source from the table the engine
//! tells once a second ([`Event::Sources`]), never from a per-frame event.
//! Each source keeps its latest figures and its last [`RECENT`] seconds
//! (frames, and whether any were lost) for the strip.
//!
//! [`Event::Sources`]: crate::engine::observe::Event::Sources

use std::collections::BTreeMap;

use super::state::{Cells, RowView, Strip, RECENT};
use super::view::figure;
use crate::engine::probe::passive::SourcesNow;
use crate::engine::roster::Identity;
use crate::frame::SysComp;
use crate::output::windows::Windows;

/// An age above baseline this high (ms) is shown as a problem: a queue.
pub(super) const AGE_SHOWN_MS: f64 = 100.0;

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
    /// Each source's figures; who it is is filled in when drawn.
    sources: BTreeMap<SysComp, Source>,
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
    pub(super) fn table(&mut self, now: &SourcesNow) {
        let table = &now.table;
        for (w, s) in self.windows.next(now.at, table).iter().zip(&table.sources) {
            let t = self.sources.entry(s.source).or_default();
            let c = &s.counts;
            t.radio = s.radio;
            // How much later than its quickest its newest stamped frame came.
            let age = now.ages.iter().find(|(id, _)| *id == s.source);
            let age_ms = age.map(|(_, a)| a.age_ms);
            t.figures = vec![
                (c.received.to_string(), false),
                (c.lost.to_string(), c.lost > 0),
                (figure(s.loss_pct, 1), c.lost > 0),
                (c.duplicate.to_string(), false),
                (c.reordered.to_string(), false),
                (s.silence_count.to_string(), s.silence_count > 0),
                (figure(w.frames_per_s(), 1), false),
                (figure(age_ms, 0), age_ms.is_some_and(|a| a >= AGE_SHOWN_MS)),
            ];
            if t.recent.len() == RECENT {
                t.recent.remove(0);
            }
            t.recent.push(Second {
                frames: w.received,
                lost: w.lost > 0,
            });
        }
    }

    /// The rows to draw, by source: who it is, then its figures.
    pub(super) fn rows(&self) -> Vec<RowView> {
        self.sources
            .iter()
            .map(|(id, s)| {
                let unheard = if s.radio { "radio" } else { "-" };
                let identity = self.heard.get(id).map_or(unheard, String::as_str);
                let mut cells = vec![(id.to_string(), false), (identity.to_string(), false)];
                cells.extend(s.figures.iter().cloned());
                RowView {
                    cells,
                    strip: Strip::Seconds(s.recent.clone()),
                    quiet: s.radio,
                }
            })
            .collect()
    }
}

/// What is kept of a source between tables.
#[derive(Debug, Clone, Default)]
struct Source {
    /// The SiK radio's own reports, `radio` when no HEARTBEAT said more.
    radio: bool,
    /// Its figures after who it is, as of the latest table.
    figures: Cells,
    recent: Vec<Second>,
}
