//! The pair report's figures: per source heard on two links or more, the
//! merged stream and each link's part in it. Field names are the JSON's,
//! units in the names.

use super::lag::Lag;
use super::side::Side;
use super::source::SourceState;
use crate::engine::summary::passive::percent;
use crate::engine::Nanos;
use crate::frame::SysComp;

/// De-duplication's quantile: the window that catches all but one copy
/// in a thousand.
const DEDUP_QUANTILE: f64 = 0.999;

#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub(crate) struct PairSummary {
    /// How long after a frame's first copy another still counts as its
    /// copy (the sequence may end it sooner).
    pub(crate) window_ms: f64,
    /// Sources heard on two links or more, by id.
    pub(crate) sources: Vec<SourcePair>,
    /// Sources heard on one link only: nothing to pair.
    pub(crate) single_link_sources: Vec<SingleLinkSource>,
    /// Sources heard on two links or more with no frame on two: their
    /// frames were split between the links, not copied (a router that
    /// balances; a log's stamps whose low bits are a clock's for them).
    pub(crate) uncopied_sources: Vec<SysComp>,
    /// Sources heard on two links or more under which as many other
    /// frames came under a number in use as copies: two senders under one
    /// id (two simulated vehicles, two responders started alike), whose
    /// alike frames match by chance, not one vehicle on several links.
    pub(crate) conflicting_sources: Vec<SysComp>,
    /// Frames of sources beyond the cap, and of links beyond the
    /// tracker's: not matched.
    pub(crate) untracked_frames: u64,
}

/// One source heard on two links or more.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub(crate) struct SourcePair {
    pub(crate) source: SysComp,
    /// Frames after de-duplication: first copies.
    pub(crate) distinct_frames: u64,
    /// Numbers of the merged stream no link delivered (lost on both, of
    /// two): the loss left after de-duplication.
    pub(crate) lost_on_every_link: u64,
    pub(crate) lost_on_every_link_pct: Option<f64>,
    /// Later copies matched to a first one.
    pub(crate) copies: u64,
    /// The lag behind the first copy that 99.9 % of later copies were
    /// within: the de-duplication period (mavlink-router's
    /// `DeDuplicationPeriod`) that would have caught them.
    pub(crate) dedup_window_p999_ms: Option<f64>,
    pub(crate) copy_lag_max_ms: Option<f64>,
    /// The same frame again after the window: counted as neither new nor
    /// a copy.
    pub(crate) late_beyond_window: u64,
    /// Another frame under a number in use within the window (a second
    /// sender under the same ids, or a restart): neither new nor a copy.
    pub(crate) conflicts: u64,
    /// Each link that heard the source, by index.
    pub(crate) links: Vec<LinkPair>,
}

/// One link's part in a source's merged stream.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub(crate) struct LinkPair {
    /// The link's index, as given to the tracker.
    pub(crate) link: usize,
    /// Good frames delivered, repeats included.
    pub(crate) frames: u64,
    pub(crate) damaged: u64,
    /// Frames it had delivered before: neither new nor copies.
    pub(crate) duplicates: u64,
    /// Frames it delivered before any other link.
    pub(crate) first: u64,
    /// Its first copies' share of the distinct frames.
    pub(crate) first_pct: Option<f64>,
    /// Frames no other link delivered within the window...
    pub(crate) only: u64,
    /// ...of which a copy may still come (inside the window).
    pub(crate) only_undecided: u64,
    /// Lost by its own sequence, as the link alone counts it.
    pub(crate) lost: u64,
    pub(crate) lost_pct: Option<f64>,
    /// Lag behind the first copy, over the frames it delivered that
    /// another link delivered too (0 where it was first).
    pub(crate) lag_p50_ms: Option<f64>,
    pub(crate) lag_p99_ms: Option<f64>,
    pub(crate) lag_max_ms: Option<f64>,
    /// Frames behind a newer number another link had already delivered:
    /// the vehicle jumps back on a map fed by both links.
    pub(crate) stale: u64,
    /// Of those, first copies: they jump back even behind de-duplication.
    pub(crate) stale_first: u64,
    /// Its lags summed (ns) and how many, so far: a plot's spans take
    /// their means from the difference between two tellings.
    #[serde(skip)]
    pub(crate) lag_sum: (f64, u64),
}

/// A source heard on one link only.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub(crate) struct SingleLinkSource {
    pub(crate) source: SysComp,
    pub(crate) link: usize,
    pub(crate) frames: u64,
    pub(crate) damaged: u64,
}

fn quantile(lag: Option<&Lag>, q: f64) -> Option<f64> {
    lag.and_then(|l| l.quantile_ms(q))
}

/// `ns` in ms, for a window.
pub(super) fn ms(ns: Nanos) -> f64 {
    ns as f64 / 1e6
}

impl SourcePair {
    pub(super) fn new(source: SysComp, state: &SourceState, at: Nanos, window: Nanos) -> Self {
        let mut undecided = vec![0; state.sides.len()];
        if let Some(head) = state.merged.head() {
            for link in state.recent.undecided(at, window, head) {
                undecided[usize::from(link)] += 1;
            }
        }
        let links = state
            .sides
            .iter()
            .enumerate()
            .filter(|(_, side)| side.heard())
            .map(|(link, side)| LinkPair::new(link, side, state.distinct, undecided[link]))
            .collect();
        let merged = &state.merged;
        SourcePair {
            source,
            distinct_frames: state.distinct,
            lost_on_every_link: merged.lost(),
            lost_on_every_link_pct: percent(merged.lost(), merged.numbers()),
            copies: state.copies,
            dedup_window_p999_ms: quantile(state.copy_lag.as_ref(), DEDUP_QUANTILE),
            copy_lag_max_ms: state.copy_lag.as_ref().and_then(Lag::max),
            late_beyond_window: state.late,
            conflicts: state.conflicts,
            links,
        }
    }
}

impl LinkPair {
    fn new(link: usize, side: &Side, distinct: u64, only_undecided: u64) -> Self {
        let lag = side.lag.as_ref();
        LinkPair {
            link,
            frames: side.frames,
            damaged: side.damaged,
            duplicates: side.again,
            first: side.first,
            first_pct: percent(side.first, distinct),
            only: side.only,
            only_undecided,
            lost: side.own.lost(),
            lost_pct: percent(side.own.lost(), side.own.numbers()),
            lag_p50_ms: quantile(lag, 0.5),
            lag_p99_ms: quantile(lag, 0.99),
            lag_max_ms: lag.and_then(Lag::max),
            stale: side.stale,
            stale_first: side.stale_first,
            lag_sum: lag.map_or((0.0, 0), Lag::sum),
        }
    }
}

impl SingleLinkSource {
    /// The source's one link, if it was heard on one only.
    pub(super) fn of(source: SysComp, state: &SourceState) -> Option<Self> {
        let mut heard = state.sides.iter().enumerate().filter(|(_, s)| s.heard());
        let (link, side) = heard.next()?;
        heard.next().is_none().then_some(SingleLinkSource {
            source,
            link,
            frames: side.frames,
            damaged: side.damaged,
        })
    }
}
