//! The pair report as metrics (`--prometheus` with a source heard on
//! several links): a series per link and source for each link's part, a
//! series per source for the merged stream. Labels: `link` (the link, or
//! `LINK path N`), `sysid`, `compid`.

use super::exposition::{escape, Exposition, Figure, SeriesFigure};
use crate::engine::pair::{LinkPair, PairSummary, SourcePair};
use crate::frame::SysComp;

const LINK_FIGURES: [SeriesFigure<LinkPair>; 7] = [
    Figure::counter(
        "mavping_pair_frames_total",
        "Frames of the source the link delivered (several links to one source).",
        |l| Some(l.frames as f64),
    ),
    Figure::counter(
        "mavping_pair_first_frames_total",
        "Frames of the source the link delivered before any other link.",
        |l| Some(l.first as f64),
    ),
    Figure::counter(
        "mavping_pair_only_frames_total",
        "Frames of the source no other link delivered within the de-duplication window: what the link adds.",
        |l| Some(l.only as f64),
    ),
    Figure::counter(
        "mavping_pair_lost_total",
        "Frames of the source the link lost, by its own sequence alone.",
        |l| Some(l.lost as f64),
    ),
    Figure::gauge(
        "mavping_pair_lag_p50_seconds",
        "The link's lag behind the first copy of the source's frames, median, over the frames another link delivered too (0 where it was first).",
        |l| l.lag_p50_ms.map(|ms| ms / 1e3),
    ),
    Figure::gauge(
        "mavping_pair_lag_p99_seconds",
        "The link's lag behind the first copy of the source's frames, 99th percentile.",
        |l| l.lag_p99_ms.map(|ms| ms / 1e3),
    ),
    Figure::counter(
        "mavping_pair_stale_frames_total",
        "The source's frames the link delivered after a newer one had come on another link: a map fed by both jumps back.",
        |l| Some(l.stale as f64),
    ),
];

const SOURCE_FIGURES: [SeriesFigure<SourcePair>; 3] = [
    Figure::counter(
        "mavping_pair_distinct_frames_total",
        "The source's frames after de-duplication across its links.",
        |s| Some(s.distinct_frames as f64),
    ),
    Figure::counter(
        "mavping_pair_lost_on_every_link_total",
        "The source's frames no link delivered: the loss left after de-duplication.",
        |s| Some(s.lost_on_every_link as f64),
    ),
    Figure::gauge(
        "mavping_pair_dedup_window_seconds",
        "The lag behind the first copy 99.9 % of the source's later copies were within: the de-duplication period that would have caught them.",
        |s| s.dedup_window_p999_ms.map(|ms| ms / 1e3),
    ),
];

fn ids(id: SysComp) -> String {
    format!("sysid=\"{}\",compid=\"{}\"", id.sysid, id.compid)
}

/// The families of `summary`, its links named by `ways`; nothing when no
/// source was heard on two links.
pub(crate) fn render_pair(summary: &PairSummary, ways: &[&str]) -> String {
    let mut out = Exposition::default();
    out.figures(&SOURCE_FIGURES, || {
        summary.sources.iter().map(|s| (ids(s.source), s))
    });
    out.figures(&LINK_FIGURES, || {
        summary.sources.iter().flat_map(|s| {
            s.links.iter().map(move |l| {
                let way = ways.get(l.link).copied().unwrap_or("?");
                (format!("link=\"{}\",{}", escape(way), ids(s.source)), l)
            })
        })
    });
    out.0
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::engine::pair::{PairConfig, PairTracker};
    use crate::frame::{test_frame, Msg};

    #[test]
    fn each_link_and_source_has_its_series() {
        let mut tracker = PairTracker::new(2, PairConfig::default());
        for k in 0..30u8 {
            let mut frame = test_frame(SysComp::new(1, 1), Msg::Other);
            frame.packet_seq = k;
            frame.crc = u16::from(k);
            let at = u64::from(k) * 20_000_000;
            tracker.on_frame(0, &frame, at);
            if k % 3 != 0 {
                tracker.on_frame(1, &frame, at + 40_000_000);
            }
        }
        let text = render_pair(&tracker.summary(u64::MAX), &["radio", "lte \"1\""]);
        let line = |name: &str| {
            text.lines()
                .find(|l| l.starts_with(name))
                .unwrap_or_else(|| panic!("no {name} in {text}"))
                .to_string()
        };
        assert_eq!(
            line("mavping_pair_only_frames_total{link=\"radio\""),
            "mavping_pair_only_frames_total{link=\"radio\",sysid=\"1\",compid=\"1\"} 10"
        );
        assert_eq!(
            line("mavping_pair_lag_p50_seconds{link=\"lte \\\"1\\\"\""),
            "mavping_pair_lag_p50_seconds{link=\"lte \\\"1\\\"\",sysid=\"1\",compid=\"1\"} 0.04"
        );
        assert_eq!(
            line("mavping_pair_distinct_frames_total"),
            "mavping_pair_distinct_frames_total{sysid=\"1\",compid=\"1\"} 30"
        );
        assert!(text.contains("# TYPE mavping_pair_frames_total counter"));
    }
}
