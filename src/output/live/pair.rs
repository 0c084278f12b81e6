//! The pair report's section of `--live`: a row per link a source is
//! heard on (its frames, the share it brought first, what only it
//! brought, its own loss, its lag behind the first copy, its frames
//! behind a newer one) under the merged stream's row. Drawn below the links' sections, from the pair
//! tracker's figures the run hands over every second.

use super::state::{RowView, Screen, Strip};
use super::view::{figure, PAIR};
use crate::engine::pair::{PairSummary, SourcePair};
use crate::engine::Nanos;

/// The section's title.
const TITLE: &str = "the same sources on several links";

/// The section for `summary` at `now`, its links named by `ways`; none
/// while no source was heard on two.
pub(crate) fn pair_screen(summary: &PairSummary, ways: &[&str], now: Nanos) -> Option<Screen> {
    if summary.sources.is_empty() {
        return None;
    }
    let rows = summary
        .sources
        .iter()
        .flat_map(|source| source_rows(source, ways))
        .collect();
    Some(Screen {
        link: TITLE.into(),
        probe: None,
        now,
        status: format!(
            " · lag in ms · copies within {:.0} s",
            summary.window_ms / 1e3
        ),
        kind: &PAIR,
        rows,
    })
}

/// The merged stream's row (its frames are the distinct ones, its loss
/// the numbers lost on every link), then one per link that heard
/// `source`.
fn source_rows<'a>(source: &'a SourcePair, ways: &'a [&str]) -> impl Iterator<Item = RowView> + 'a {
    let merged = RowView {
        cells: vec![
            (source.source.to_string(), false),
            ("merged".into(), false),
            (source.distinct_frames.to_string(), false),
            ("-".into(), false),
            ("-".into(), false),
            (
                figure(source.lost_on_every_link_pct, 2),
                source.lost_on_every_link > 0,
            ),
            ("-".into(), false),
            ("-".into(), false),
            ("-".into(), false),
        ],
        strip: Strip::Note(format!(
            "de-dup window {} ms",
            figure(source.dedup_window_p999_ms, 1)
        )),
        quiet: false,
    };
    let links = source.links.iter().map(move |link| RowView {
        cells: vec![
            (String::new(), false),
            (
                ways.get(link.link).copied().unwrap_or("?").to_string(),
                false,
            ),
            (link.frames.to_string(), false),
            (figure(link.first_pct, 1), false),
            (link.only.to_string(), false),
            (figure(link.lost_pct, 2), link.lost > 0),
            (figure(link.lag_p50_ms, 1), false),
            (figure(link.lag_p99_ms, 1), false),
            (link.stale.to_string(), false),
        ],
        strip: Strip::Note(String::new()),
        quiet: false,
    });
    std::iter::once(merged).chain(links)
}

#[cfg(test)]
mod tests {
    use ratatui::backend::TestBackend;
    use ratatui::Terminal;

    use super::*;
    use crate::engine::pair::LinkPair;
    use crate::frame::SysComp;
    use crate::output::live::view;

    fn link(link: usize, frames: u64, first: f64, lost: u64, lag: f64) -> LinkPair {
        LinkPair {
            link,
            frames,
            damaged: 0,
            duplicates: 0,
            first: 0,
            first_pct: Some(first),
            only: lost * 2,
            only_undecided: 0,
            lost,
            lost_pct: Some(lost as f64 / 10.0),
            lag_p50_ms: Some(lag),
            lag_p99_ms: Some(lag + 1.5),
            lag_max_ms: Some(lag + 2.0),
            stale: 3,
            stale_first: 1,
            lag_sum: (0.0, 0),
        }
    }

    fn summary() -> PairSummary {
        PairSummary {
            window_ms: 5000.0,
            sources: vec![SourcePair {
                source: SysComp::new(1, 1),
                distinct_frames: 998,
                lost_on_every_link: 2,
                lost_on_every_link_pct: Some(0.2),
                copies: 900,
                dedup_window_p999_ms: Some(81.4),
                copy_lag_max_ms: Some(82.0),
                late_beyond_window: 0,
                conflicts: 0,
                links: vec![link(0, 950, 90.0, 0, 0.0), link(2, 948, 10.0, 40, 80.0)],
            }],
            single_link_sources: Vec::new(),
            uncopied_sources: Vec::new(),
            conflicting_sources: Vec::new(),
            untracked_frames: 0,
        }
    }

    fn frame(width: u16, pair: Option<&Screen>) -> String {
        let mut terminal = Terminal::new(TestBackend::new(width, 8)).unwrap();
        terminal.draw(|f| view::render(f, &[], pair)).unwrap();
        terminal.backend().to_string()
    }

    #[test]
    fn a_row_per_link_under_the_merged_streams() {
        let ways = ["udp:0.0.0.0:14550", "radio", "udp:0.0.0.0:14551"];
        let screen = pair_screen(&summary(), &ways, 3_000_000_000).unwrap();
        insta::assert_snapshot!("pair_120_columns", frame(120, Some(&screen)));
        // Narrower: the least needed columns go, the links stay named.
        let narrow = frame(80, Some(&screen));
        assert!(narrow.contains("udp:0.0.0.0:14551"), "{narrow}");
        assert!(!narrow.contains("frames"), "{narrow}");
        assert!(narrow.contains("lag p99"), "{narrow}");
    }

    #[test]
    fn no_section_before_a_source_is_heard_on_two_links() {
        let mut empty = summary();
        empty.sources.clear();
        assert!(pair_screen(&empty, &[], 0).is_none());
    }
}
