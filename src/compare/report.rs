//! Two saved runs side by side: which links and sources are compared,
//! and each one's loss difference, median RTT shift and frame ages.

use serde::Serialize;
use thiserror::Error;

use super::bands::{compare_bands, Bands};
use super::bootstrap::{median_shift, Model, RESAMPLES, SEED};
use super::input::{Age, Counts, Figures, LinkRun, Passive, Responder, RunFile, Source};
use super::interval::newcombe;
use crate::frame::SysComp;

/// What to compare.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub(crate) struct Options {
    /// Only this system (and component, when given).
    pub(crate) source: Option<SourceFilter>,
    /// The distance bands' width; chosen from the farthest window if not.
    pub(crate) band_m: Option<f64>,
}

/// `--source SYSID[/COMPID]`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct SourceFilter {
    pub(crate) sysid: u8,
    pub(crate) compid: Option<u8>,
}

impl std::fmt::Display for SourceFilter {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self.compid {
            Some(compid) => write!(f, "{}/{compid}", self.sysid),
            None => write!(f, "{}", self.sysid),
        }
    }
}

impl SourceFilter {
    fn admits(&self, id: SysComp) -> bool {
        id.sysid == self.sysid && self.compid.is_none_or(|c| c == id.compid)
    }
}

/// The comparison of two files; serialised as the `compare` JSON line.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub(crate) struct Report {
    pub(crate) a: String,
    pub(crate) b: String,
    pub(crate) method: Method,
    pub(crate) links: Vec<LinkComparison>,
    /// Links paired but of different kinds (a probe run and a passive
    /// one): their losses measure different things.
    pub(crate) not_compared: Vec<Mismatch>,
    pub(crate) only_in_a: Vec<String>,
    pub(crate) only_in_b: Vec<String>,
    /// A responder's or source's loss (or a passive link's as a whole) is
    /// higher in B, its interval above 0: what `--fail-if-worse` fails on.
    pub(crate) b_loses_more: bool,
}

/// How the figures were drawn, for a reader of the JSON.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub(crate) struct Method {
    pub(crate) confidence: f64,
    pub(crate) loss: &'static str,
    pub(crate) rtt_p50: &'static str,
    pub(crate) resamples: usize,
    pub(crate) seed: u64,
}

const METHOD: Method = Method {
    confidence: 0.95,
    loss: "newcombe_hybrid_score",
    rtt_p50: "bootstrap_histogram_uniform_within_bucket",
    resamples: RESAMPLES,
    seed: SEED,
};

/// What kind of run a summary is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub(crate) enum RunKind {
    Probe,
    Passive,
    Log,
}

/// Why two summaries were paired.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub(crate) enum PairedBy {
    /// The same link in both files.
    Link,
    /// Different links, the only summary in each file.
    OnlySummary,
}

/// A link of each file, compared.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub(crate) struct LinkComparison {
    pub(crate) a_link: String,
    pub(crate) b_link: String,
    pub(crate) paired_by: PairedBy,
    pub(crate) a_kind: RunKind,
    pub(crate) b_kind: RunKind,
    /// The responders' or sources' ids differ, and each summary had one:
    /// those two are compared.
    pub(crate) ids_differ: bool,
    pub(crate) rows: Vec<Row>,
    /// A passive run's link as a whole (every source but the radio and
    /// the ground station); not with `--source`.
    pub(crate) totals: Option<LossComparison>,
    /// Two telemetry logs: loss by distance.
    pub(crate) bands: Option<Bands>,
    pub(crate) only_in_a: Vec<SysComp>,
    pub(crate) only_in_b: Vec<SysComp>,
}

/// Two links paired and not compared.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub(crate) struct Mismatch {
    pub(crate) a_link: String,
    pub(crate) a_kind: RunKind,
    pub(crate) b_link: String,
    pub(crate) b_kind: RunKind,
}

/// What a responder or source is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub(crate) enum Role {
    Responder,
    Source,
    Radio,
}

/// One responder (probe runs) or source (passive runs) in both.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub(crate) struct Row {
    pub(crate) role: Role,
    pub(crate) a_id: SysComp,
    pub(crate) b_id: SysComp,
    pub(crate) loss: LossComparison,
    /// Probe runs where both had replies.
    pub(crate) rtt_p50: Option<ShiftComparison>,
    /// Where both summaries give the source's frame ages.
    pub(crate) age: Option<AgeComparison>,
}

/// Which way B differs from A, as far as the interval tells.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub(crate) enum Finding {
    /// The interval is above 0.
    BHigher,
    /// The interval is below 0.
    BLower,
    /// The interval holds 0.
    NoClearDifference,
    /// A run with nothing to count.
    NoData,
}

impl Finding {
    fn of(low: f64, high: f64) -> Finding {
        if low > 0.0 {
            Finding::BHigher
        } else if high < 0.0 {
            Finding::BLower
        } else {
            Finding::NoClearDifference
        }
    }
}

/// A loss count: `lost` of `of`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub(crate) struct Loss {
    pub(crate) lost: u64,
    pub(crate) of: u64,
    pub(crate) pct: Option<f64>,
}

impl Loss {
    fn new(lost: u64, of: u64) -> Loss {
        Loss {
            lost,
            of,
            pct: (of > 0).then(|| 100.0 * lost.min(of) as f64 / of as f64),
        }
    }
}

/// Loss in A and B, and B - A in percentage points with its 95 %
/// interval (Newcombe's hybrid score interval).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub(crate) struct LossComparison {
    pub(crate) a: Loss,
    pub(crate) b: Loss,
    pub(crate) difference_pp: Option<f64>,
    pub(crate) low_pp: Option<f64>,
    pub(crate) high_pp: Option<f64>,
    pub(crate) finding: Finding,
}

impl LossComparison {
    pub(crate) fn new(a_lost: u64, a_of: u64, b_lost: u64, b_of: u64) -> Self {
        let d = newcombe(a_lost, a_of, b_lost, b_of);
        LossComparison {
            a: Loss::new(a_lost, a_of),
            b: Loss::new(b_lost, b_of),
            difference_pp: d.map(|d| 100.0 * d.estimate),
            low_pp: d.map(|d| 100.0 * d.low),
            high_pp: d.map(|d| 100.0 * d.high),
            finding: d.map_or(Finding::NoData, |d| Finding::of(d.low, d.high)),
        }
    }

    fn of_counts(a: Counts, b: Counts) -> Self {
        LossComparison::new(a.lost, a.numbered, b.lost, b.numbered)
    }
}

/// The median RTT in A and B, µs, and B - A with its bootstrap interval.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub(crate) struct ShiftComparison {
    pub(crate) a_p50_us: f64,
    pub(crate) b_p50_us: f64,
    pub(crate) shift_us: f64,
    pub(crate) low_us: f64,
    pub(crate) high_us: f64,
    pub(crate) finding: Finding,
}

/// A source's frame age headline in A and B, ms; a summary keeps only
/// these percentiles, so no interval.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub(crate) struct AgeComparison {
    pub(crate) a_p50_ms: f64,
    pub(crate) b_p50_ms: f64,
    pub(crate) p50_change_ms: f64,
    pub(crate) a_p99_ms: f64,
    pub(crate) b_p99_ms: f64,
    pub(crate) p99_change_ms: f64,
}

/// Why two files cannot be compared.
#[derive(Debug, Error, PartialEq)]
pub(crate) enum CompareError {
    #[error(
        "no link is in both files and one holds several (A {a}: {a_links}; B {b}: {b_links}): \
         save each link's run on its own, or the same links in both"
    )]
    NoCommonLink {
        a: String,
        a_links: String,
        b: String,
        b_links: String,
    },
    #[error("nothing to compare: {0}")]
    Nothing(String),
}

fn kind(run: &LinkRun) -> RunKind {
    match &run.figures {
        Figures::Probe(_) => RunKind::Probe,
        Figures::Passive(p) if p.windows.is_some() => RunKind::Log,
        Figures::Passive(_) => RunKind::Passive,
    }
}

/// Compares `b` against `a`: links paired by name (or the only summary
/// of each), in each the responders or sources in both.
pub(crate) fn compare(a: &RunFile, b: &RunFile, options: &Options) -> Result<Report, CompareError> {
    let pairs = pair_links(a, b)?;
    let mut report = Report {
        a: a.name.clone(),
        b: b.name.clone(),
        method: METHOD,
        links: Vec::new(),
        not_compared: Vec::new(),
        only_in_a: unpaired(&a.runs, pairs.iter().map(|p| p.0)),
        only_in_b: unpaired(&b.runs, pairs.iter().map(|p| p.1)),
        b_loses_more: false,
    };
    for (ra, rb, paired_by) in pairs {
        match compare_link(ra, rb, paired_by, options) {
            Some(link) => report.links.push(link),
            None => report.not_compared.push(Mismatch {
                a_link: ra.link.clone(),
                a_kind: kind(ra),
                b_link: rb.link.clone(),
                b_kind: kind(rb),
            }),
        }
    }
    if report
        .links
        .iter()
        .all(|l| l.rows.is_empty() && l.totals.is_none())
    {
        return Err(CompareError::Nothing(nothing_reason(&report, options)));
    }
    report.b_loses_more = report.links.iter().any(|l| {
        l.rows
            .iter()
            .map(|r| &r.loss)
            .chain(&l.totals)
            .any(|c| c.finding == Finding::BHigher)
    });
    Ok(report)
}

type Pair<'a> = (&'a LinkRun, &'a LinkRun, PairedBy);

fn pair_links<'a>(a: &'a RunFile, b: &'a RunFile) -> Result<Vec<Pair<'a>>, CompareError> {
    let same: Vec<Pair<'a>> = a
        .runs
        .iter()
        .filter_map(|ra| {
            let rb = b.runs.iter().find(|rb| rb.link == ra.link)?;
            Some((ra, rb, PairedBy::Link))
        })
        .collect();
    if !same.is_empty() {
        return Ok(same);
    }
    match (a.runs.as_slice(), b.runs.as_slice()) {
        ([ra], [rb]) => Ok(vec![(ra, rb, PairedBy::OnlySummary)]),
        _ => Err(CompareError::NoCommonLink {
            a: a.name.clone(),
            a_links: names(&a.runs),
            b: b.name.clone(),
            b_links: names(&b.runs),
        }),
    }
}

fn names(runs: &[LinkRun]) -> String {
    let names: Vec<&str> = runs.iter().map(|r| r.link.as_str()).collect();
    names.join(", ")
}

fn unpaired<'a>(
    runs: &[LinkRun],
    paired: impl Iterator<Item = &'a LinkRun> + Clone,
) -> Vec<String> {
    runs.iter()
        .filter(|r| !paired.clone().any(|p| std::ptr::eq(p, *r)))
        .map(|r| r.link.clone())
        .collect()
}

fn nothing_reason(report: &Report, options: &Options) -> String {
    if report.links.is_empty() {
        return "a probe run's loss (requests unanswered) and a passive run's (frames missing \
                from a sequence) are not the same measure"
            .into();
    }
    let ids = |ids: &[SysComp]| {
        let ids: Vec<String> = ids.iter().map(SysComp::to_string).collect();
        if ids.is_empty() {
            "none".to_string()
        } else {
            ids.join(", ")
        }
    };
    let link = &report.links[0];
    let filter = options
        .source
        .map_or(String::new(), |f| format!("--source {f} leaves "));
    format!(
        "no responder or source is in both ({filter}A: {}; B: {})",
        ids(&link.only_in_a),
        ids(&link.only_in_b)
    )
}

/// `None` when one is a probe run and the other passive.
fn compare_link(
    a: &LinkRun,
    b: &LinkRun,
    paired_by: PairedBy,
    options: &Options,
) -> Option<LinkComparison> {
    let mut link = LinkComparison {
        a_link: a.link.clone(),
        b_link: b.link.clone(),
        paired_by,
        a_kind: kind(a),
        b_kind: kind(b),
        ids_differ: false,
        rows: Vec::new(),
        totals: None,
        bands: None,
        only_in_a: Vec::new(),
        only_in_b: Vec::new(),
    };
    match (&a.figures, &b.figures) {
        (Figures::Probe(ra), Figures::Probe(rb)) => {
            let matched = match_ids(ra, rb, |r| r.id, options.source);
            link.rows = matched
                .pairs
                .iter()
                .map(|(x, y)| responder_row(x, y, a, b))
                .collect();
            link.fill_ids(&matched);
        }
        (Figures::Passive(pa), Figures::Passive(pb)) => {
            passive_link(&mut link, pa, pb, a, b, options)
        }
        _ => return None,
    }
    Some(link)
}

impl LinkComparison {
    fn fill_ids<T>(&mut self, matched: &Matched<'_, T>) {
        self.ids_differ = matched.ids_differ;
        self.only_in_a = matched.only_a.clone();
        self.only_in_b = matched.only_b.clone();
    }
}

fn passive_link(
    link: &mut LinkComparison,
    pa: &Passive,
    pb: &Passive,
    a: &LinkRun,
    b: &LinkRun,
    options: &Options,
) {
    // The ground station's frames are logged as it sent them: no loss.
    let heard =
        |p: &Passive| -> Vec<Source> { p.sources.iter().filter(|s| !s.ground).cloned().collect() };
    let (sa, sb) = (heard(pa), heard(pb));
    let matched = match_ids(&sa, &sb, |s| s.id, options.source);
    link.rows = matched
        .pairs
        .iter()
        .map(|(x, y)| Row {
            role: if x.radio || y.radio {
                Role::Radio
            } else {
                Role::Source
            },
            a_id: x.id,
            b_id: y.id,
            loss: LossComparison::of_counts(x.counts, y.counts),
            rtt_p50: None,
            age: ages(a, x.id, b, y.id),
        })
        .collect();
    link.fill_ids(&matched);
    if options.source.is_none() {
        link.totals = Some(LossComparison::of_counts(pa.totals, pb.totals));
    }
    if let (Some(wa), Some(wb)) = (&pa.windows, &pb.windows) {
        link.bands = Some(compare_bands(wa, wb, options.band_m));
    }
}

fn responder_row(in_a: &Responder, in_b: &Responder, a: &LinkRun, b: &LinkRun) -> Row {
    let models = (Model::new(&in_a.histogram), Model::new(&in_b.histogram));
    let rtt = match (in_a.p50_us, in_b.p50_us, models) {
        (Some(a_p50), Some(b_p50), (Some(a_model), Some(b_model))) => {
            let shift = median_shift(&a_model, &b_model, a_p50, b_p50);
            Some(ShiftComparison {
                a_p50_us: a_p50,
                b_p50_us: b_p50,
                shift_us: shift.estimate,
                low_us: shift.low,
                high_us: shift.high,
                finding: Finding::of(shift.low, shift.high),
            })
        }
        _ => None,
    };
    Row {
        role: Role::Responder,
        a_id: in_a.id,
        b_id: in_b.id,
        loss: LossComparison::new(in_a.lost, in_a.sent, in_b.lost, in_b.sent),
        rtt_p50: rtt,
        age: ages(a, in_a.id, b, in_b.id),
    }
}

fn ages(a: &LinkRun, a_id: SysComp, b: &LinkRun, b_id: SysComp) -> Option<AgeComparison> {
    let find = |run: &LinkRun, id: SysComp| -> Option<Age> {
        run.ages.iter().find(|g| g.id == id).copied()
    };
    let (x, y) = (find(a, a_id)?, find(b, b_id)?);
    Some(AgeComparison {
        a_p50_ms: x.p50_ms,
        b_p50_ms: y.p50_ms,
        p50_change_ms: y.p50_ms - x.p50_ms,
        a_p99_ms: x.p99_ms,
        b_p99_ms: y.p99_ms,
        p99_change_ms: y.p99_ms - x.p99_ms,
    })
}

/// Items of A and B paired by id.
struct Matched<'a, T> {
    pairs: Vec<(&'a T, &'a T)>,
    ids_differ: bool,
    only_a: Vec<SysComp>,
    only_b: Vec<SysComp>,
}

/// The ids in both, in A's order; when none is, and each side has one,
/// those two (a vehicle renumbered between the runs).
fn match_ids<'a, T>(
    a: &'a [T],
    b: &'a [T],
    id: impl Fn(&T) -> SysComp,
    filter: Option<SourceFilter>,
) -> Matched<'a, T> {
    let admitted = |xs: &'a [T]| -> Vec<&'a T> {
        xs.iter()
            .filter(|x| filter.is_none_or(|f| f.admits(id(x))))
            .collect()
    };
    let (a, b) = (admitted(a), admitted(b));
    let mut pairs: Vec<(&T, &T)> = a
        .iter()
        .filter_map(|x| Some((*x, *b.iter().find(|y| id(y) == id(x))?)))
        .collect();
    let mut ids_differ = false;
    if let ([x], [y], true) = (a.as_slice(), b.as_slice(), pairs.is_empty()) {
        pairs.push((*x, *y));
        ids_differ = true;
    }
    let left = |xs: &[&T], first: bool| -> Vec<SysComp> {
        xs.iter()
            .filter(|x| {
                !pairs
                    .iter()
                    .any(|p| std::ptr::eq(if first { p.0 } else { p.1 }, **x))
            })
            .map(|x| id(x))
            .collect()
    };
    Matched {
        only_a: left(&a, true),
        only_b: left(&b, false),
        pairs,
        ids_differ,
    }
}

#[cfg(test)]
mod tests {
    use super::super::bootstrap::Bucket;
    use super::super::input::Window;
    use super::*;

    fn responder(id: (u8, u8), sent: u64, lost: u64, base_us: f64) -> Responder {
        Responder {
            id: SysComp::new(id.0, id.1),
            sent,
            lost,
            p50_us: (sent > lost).then_some(base_us + 1000.0),
            histogram: if sent > lost {
                vec![Bucket {
                    low: base_us,
                    high: base_us + 2000.0,
                    count: sent - lost,
                }]
            } else {
                vec![]
            },
        }
    }

    fn probe(link: &str, responders: Vec<Responder>) -> LinkRun {
        LinkRun {
            link: link.into(),
            figures: Figures::Probe(responders),
            ages: vec![],
        }
    }

    fn file(name: &str, runs: Vec<LinkRun>) -> RunFile {
        RunFile {
            name: name.into(),
            runs,
        }
    }

    fn one(name: &str, run: LinkRun) -> RunFile {
        file(name, vec![run])
    }

    #[test]
    fn a_responder_losing_more_in_b_is_found_with_its_interval() {
        let a = one(
            "a",
            probe("sim:", vec![responder((1, 1), 1000, 50, 20_000.0)]),
        );
        let b = one(
            "b",
            probe("sim:", vec![responder((1, 1), 1000, 80, 60_000.0)]),
        );
        let r = compare(&a, &b, &Options::default()).unwrap();
        assert_eq!(r.links.len(), 1);
        let link = &r.links[0];
        assert_eq!(link.paired_by, PairedBy::Link);
        let row = &link.rows[0];
        let loss = &row.loss;
        assert!((loss.difference_pp.unwrap() - 3.0).abs() < 1e-9);
        // As interval.rs's hand computation: [0.8387, 5.1952] points.
        assert!((loss.low_pp.unwrap() - 0.8387).abs() < 1e-4);
        assert!((loss.high_pp.unwrap() - 5.1952).abs() < 1e-4);
        assert_eq!(loss.finding, Finding::BHigher);
        let rtt = row.rtt_p50.unwrap();
        assert!((rtt.shift_us - 40_000.0).abs() < 1e-9);
        assert_eq!(rtt.finding, Finding::BHigher);
        assert!(r.b_loses_more);
        // The other way round B loses less, and that fails nothing.
        let back = compare(&b, &a, &Options::default()).unwrap();
        assert_eq!(back.links[0].rows[0].loss.finding, Finding::BLower);
        assert!(!back.b_loses_more);
    }

    #[test]
    fn links_pair_by_name_or_as_the_only_summary_of_each() {
        let r1 = || responder((1, 1), 100, 1, 20_000.0);
        let a = one("a", probe("udp:1", vec![r1()]));
        let b = one("b", probe("udp:2", vec![r1()]));
        let r = compare(&a, &b, &Options::default()).unwrap();
        assert_eq!(r.links[0].paired_by, PairedBy::OnlySummary);
        assert_eq!(
            (r.links[0].a_link.as_str(), r.links[0].b_link.as_str()),
            ("udp:1", "udp:2")
        );
        let a = file("a", vec![probe("x", vec![r1()]), probe("y", vec![r1()])]);
        let b = file("b", vec![probe("y", vec![r1()]), probe("z", vec![r1()])]);
        let r = compare(&a, &b, &Options::default()).unwrap();
        assert_eq!(r.links.len(), 1);
        assert_eq!(r.links[0].a_link, "y");
        assert_eq!(
            (r.only_in_a.clone(), r.only_in_b.clone()),
            (vec!["x".to_string()], vec!["z".to_string()])
        );
        let b = file("b", vec![probe("z", vec![r1()]), probe("w", vec![r1()])]);
        let err = compare(&a, &b, &Options::default()).unwrap_err();
        assert!(matches!(err, CompareError::NoCommonLink { .. }), "{err}");
        assert!(err.to_string().contains("A a: x, y; B b: z, w"), "{err}");
    }

    #[test]
    fn ids_pair_by_id_or_the_only_one_of_each_and_nothing_in_common_is_an_error() {
        let a = one("a", probe("l", vec![responder((1, 1), 100, 1, 1e4)]));
        let b = one("b", probe("l", vec![responder((2, 1), 100, 5, 1e4)]));
        let r = compare(&a, &b, &Options::default()).unwrap();
        assert!(r.links[0].ids_differ);
        assert_eq!(r.links[0].rows[0].b_id, SysComp::new(2, 1));
        let b = one(
            "b",
            probe(
                "l",
                vec![
                    responder((2, 1), 100, 5, 1e4),
                    responder((3, 1), 100, 5, 1e4),
                ],
            ),
        );
        let err = compare(&a, &b, &Options::default()).unwrap_err();
        assert_eq!(
            err.to_string(),
            "nothing to compare: no responder or source is in both (A: 1/1; B: 2/1, 3/1)"
        );
        let only = Options {
            source: Some(SourceFilter {
                sysid: 3,
                compid: None,
            }),
            ..Options::default()
        };
        let err = compare(&a, &b, &only).unwrap_err();
        assert_eq!(
            err.to_string(),
            "nothing to compare: no responder or source is in both (--source 3 leaves A: none; B: 3/1)"
        );
    }

    #[test]
    fn source_picks_one_responder_and_a_run_without_replies_has_no_rtt() {
        let a = one(
            "a",
            probe(
                "l",
                vec![
                    responder((1, 1), 100, 1, 1e4),
                    responder((2, 1), 100, 100, 1e4),
                ],
            ),
        );
        let b = one(
            "b",
            probe(
                "l",
                vec![
                    responder((1, 1), 100, 1, 1e4),
                    responder((2, 1), 100, 3, 1e4),
                ],
            ),
        );
        let all = compare(&a, &b, &Options::default()).unwrap();
        assert_eq!(all.links[0].rows.len(), 2);
        assert!(all.links[0].rows[1].rtt_p50.is_none());
        let only = Options {
            source: Some(SourceFilter {
                sysid: 2,
                compid: Some(1),
            }),
            ..Options::default()
        };
        let r = compare(&a, &b, &only).unwrap();
        assert_eq!(r.links[0].rows.len(), 1);
        assert_eq!(r.links[0].rows[0].a_id, SysComp::new(2, 1));
        assert_eq!(r.links[0].rows[0].loss.finding, Finding::BLower);
    }

    fn source(id: (u8, u8), lost: u64, numbered: u64) -> Source {
        Source {
            id: SysComp::new(id.0, id.1),
            radio: id == (51, 68),
            ground: id.0 == 255,
            counts: Counts { lost, numbered },
        }
    }

    fn passive(link: &str, sources: Vec<Source>, windows: Option<Vec<Window>>) -> LinkRun {
        let totals =
            sources
                .iter()
                .filter(|s| !s.radio && !s.ground)
                .fold(Counts::default(), |t, s| Counts {
                    lost: t.lost + s.counts.lost,
                    numbered: t.numbered + s.counts.numbered,
                });
        LinkRun {
            link: link.into(),
            figures: Figures::Passive(Passive {
                sources,
                totals,
                windows,
            }),
            ages: vec![Age {
                id: SysComp::new(1, 1),
                p50_ms: 2.0,
                p99_ms: 10.0,
            }],
        }
    }

    #[test]
    fn passive_runs_compare_sources_the_radio_and_the_whole_link_not_the_ground() {
        let a = one(
            "a",
            passive(
                "udp:",
                vec![
                    source((1, 1), 10, 1000),
                    source((51, 68), 0, 50),
                    source((255, 190), 0, 9),
                ],
                None,
            ),
        );
        let b = one(
            "b",
            passive(
                "udp:",
                vec![
                    source((1, 1), 12, 1000),
                    source((51, 68), 1, 50),
                    source((255, 190), 0, 9),
                ],
                None,
            ),
        );
        let r = compare(&a, &b, &Options::default()).unwrap();
        let link = &r.links[0];
        assert_eq!(
            (link.a_kind, link.b_kind),
            (RunKind::Passive, RunKind::Passive)
        );
        let roles: Vec<Role> = link.rows.iter().map(|r| r.role).collect();
        assert_eq!(roles, [Role::Source, Role::Radio]);
        let age = link.rows[0].age.unwrap();
        assert_eq!((age.p50_change_ms, age.p99_change_ms), (0.0, 0.0));
        let totals = link.totals.unwrap();
        assert_eq!((totals.a.lost, totals.a.of, totals.b.lost), (10, 1000, 12));
        assert!(link.bands.is_none());
        assert!(!r.b_loses_more);
    }

    #[test]
    fn two_logs_compare_by_distance_and_a_probe_run_is_not_a_passive_one() {
        let windows = |lost: i64| {
            Some(vec![Window {
                received: 990,
                lost,
                distance_m: Some(150.0),
            }])
        };
        let a = one(
            "a",
            passive("tlog:a", vec![source((1, 1), 10, 1000)], windows(10)),
        );
        let b = one(
            "b",
            passive("tlog:b", vec![source((1, 1), 90, 1000)], windows(90)),
        );
        let r = compare(&a, &b, &Options::default()).unwrap();
        let bands = r.links[0].bands.as_ref().unwrap();
        assert_eq!(bands.width_m, Some(20.0));
        assert_eq!(bands.bands[0].from_m, 140.0);
        assert_eq!(bands.bands[0].loss.finding, Finding::BHigher);
        assert!(r.b_loses_more);
        let p = one("p", probe("sim:", vec![responder((1, 1), 100, 1, 1e4)]));
        let err = compare(&a, &p, &Options::default()).unwrap_err();
        assert!(err.to_string().contains("not the same measure"), "{err}");
    }
}
