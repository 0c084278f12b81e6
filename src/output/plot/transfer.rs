//! `--plot` of a download run: each download's progress (percent of what
//! the target said there is) against the time since it began, one line a
//! download, and a legend row each with how it ended, its time to
//! complete and what its first pass missed: the figures the text and
//! JSON give. Bounded: the first [`DOWNLOADS`] downloads of each link,
//! each at most [`POINTS`] points (every other dropped when full).

use std::collections::BTreeMap;

use super::draw::{chart, line, Marks};
use super::frame::{self, DrawResult, Entry, Legend, PlotError};
use crate::engine::probe::transfer::{AttemptFigures, TransferProgress};

const DOWNLOADS: usize = 24;
const POINTS: usize = 2_048;
const PROGRESS_H: u32 = 420;
const NUMBER_W: i32 = 130;

/// One download's line and, once it ended, its figures.
#[derive(Debug, Clone, Default)]
pub(super) struct DownloadTrack {
    /// (seconds since it began, percent received).
    points: Vec<(f64, f64)>,
    figures: Option<AttemptFigures>,
}

/// A link's downloads, by number.
pub(super) type Downloads = BTreeMap<u32, DownloadTrack>;

/// A point of a download's progress.
pub(super) fn progress(downloads: &mut Downloads, p: &TransferProgress) {
    let Some(track) = track(downloads, p.attempt) else {
        return;
    };
    let percent = match p.total {
        Some(0) => 100.0,
        Some(total) => p.received as f64 * 100.0 / total as f64,
        None => 0.0,
    };
    if track.points.len() == POINTS {
        // Halve the resolution, keep the span.
        let kept: Vec<_> = track.points.iter().copied().step_by(2).collect();
        track.points = kept;
    }
    track.points.push((p.elapsed_ms / 1e3, percent));
}

/// A download ended.
pub(super) fn ended(downloads: &mut Downloads, a: &AttemptFigures) {
    if let Some(track) = track(downloads, a.attempt) {
        track.figures = Some(a.clone());
    }
}

fn track(downloads: &mut Downloads, attempt: u32) -> Option<&mut DownloadTrack> {
    if !downloads.contains_key(&attempt) && downloads.len() >= DOWNLOADS {
        return None;
    }
    Some(downloads.entry(attempt).or_default())
}

fn secs(ms: Option<f64>) -> Option<String> {
    ms.map(|ms| format!("{:.2}", ms / 1e3))
}

pub(super) fn svg(title: &str, entries: &[Entry<'_, DownloadTrack>]) -> Result<String, PlotError> {
    let rows = frame::rows(entries, |t| {
        let f = t.figures.as_ref();
        vec![
            f.map(|f| format!("{:?}", f.ending).to_lowercase()),
            f.and_then(|f| secs(f.progress.time_to_95_ms)),
            f.and_then(|f| secs(f.progress.time_to_100_ms)),
            f.and_then(|f| f.missing_first_pass.map(|m| m.to_string())),
            f.map(|f| f.counts.re_requests.to_string()),
        ]
    });
    let legend = Legend {
        heads: (
            "download",
            &[
                "ending",
                "95 % s",
                "100 % s",
                "1st pass missed",
                "re-requests",
            ],
        ),
        number_w: NUMBER_W,
        rows,
        empty: "no download",
    };
    frame::page(title, &legend, &[PROGRESS_H], |areas| {
        let end = entries
            .iter()
            .filter_map(|e| e.track.points.last().map(|p| p.0))
            .fold(1.0f64, f64::max);
        let descs = (Some("time since the download began (s)"), "received (%)");
        let mut chart = chart(
            &areas[0],
            "progress of each download",
            descs,
            0f64..end * 1.05,
            0f64..105.0,
        )?;
        for (k, e) in entries.iter().enumerate() {
            line(
                &mut chart,
                &e.look,
                &e.track.points,
                Marks::Spread(k, entries.len()),
            )?;
        }
        Ok(()) as DrawResult
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_download_keeps_its_span_when_its_points_are_halved() {
        let mut d = Downloads::new();
        for i in 0..=POINTS as u64 {
            let p = TransferProgress {
                attempt: 1,
                elapsed_ms: i as f64 * 250.0,
                received: i,
                total: Some(POINTS as u64),
            };
            progress(&mut d, &p);
        }
        let points = &d[&1].points;
        assert_eq!(points.len(), POINTS / 2 + 1);
        assert_eq!(points.first(), Some(&(0.0, 0.0)));
        assert_eq!(points.last().unwrap().1, 100.0);
        for n in 2..=DOWNLOADS as u32 + 5 {
            let p = TransferProgress {
                attempt: n,
                elapsed_ms: 0.0,
                received: 0,
                total: None,
            };
            progress(&mut d, &p);
        }
        assert_eq!(d.len(), DOWNLOADS);
    }
}
