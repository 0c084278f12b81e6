//! Every run of every kind through every format: what exhaustive matches
//! over the events once guarded, now that a format implements only the
//! kinds it shows. Each format must take every event and summary without
//! an error, and show what it is for from each kind it shows.
#![cfg(test)]

use super::json::JsonReporter;
use super::live::LiveState;
use super::plot::Plot;
use super::prometheus::Metrics;
use super::runs::{kind, Borrowed, Run, Told, RUNS};
use super::samples::SampleLog;
use super::text::TextReporter;
use super::{Reporter, StartInfo, WallClock};
use crate::engine::c2::C2Report;
use crate::engine::clock_offset::ClockSummary;
use crate::engine::kind::KindValue;
use crate::engine::link_node::LinkNodeReport;
use crate::engine::matcher::MatchEvent;
use crate::engine::observe::RadioHeard;
use crate::engine::probe::command::CommandEvent;
use crate::engine::probe::passive::flight::FlightEvent;
use crate::engine::probe::passive::SourcesNow;
use crate::engine::roster::Identity;
use crate::engine::summary::passive::PassiveSummary;
use crate::engine::summary::{
    CommandSummary, EchoInterim, EchoSummary, KindSummary, LinkSummary, PassiveInterim,
};
use crate::engine::sweep_report::StepFigures;
use crate::engine::Nanos;
use crate::frame::SysComp;
use crate::verdict::Verdict;
use std::collections::BTreeSet;
use std::io;

/// Tells `out` a whole run, as a session would.
fn tell_run(out: &mut dyn Reporter, run: Run, borrowed: &Borrowed) {
    for told in run.told(borrowed) {
        match &told {
            Told::Start(info) => out.start(info),
            Told::Event(event) => out.tell(event),
            Told::Interim(figures) => out.interim(figures),
            Told::Summary(summary, verdict) => out.summary(summary, verdict),
        }
        .unwrap_or_else(|e| panic!("{run:?}: {e}"));
    }
}

/// The run tells replies or losses, or sources' figures: what the
/// samples and the live view show as it goes (the command probe's and a
/// sweep's figures are in their summaries and step rows). The samples
/// also end a passive run's rows with its summary (`at_end`); the live
/// view is closed by then.
fn measures(run: Run, borrowed: &Borrowed, at_end: bool) -> bool {
    run.told(borrowed).iter().any(|t| match t {
        Told::Event(e) => e.kind::<MatchEvent>().is_some() || e.kind::<SourcesNow>().is_some(),
        Told::Summary(s, _) => at_end && s.get::<PassiveSummary>().is_some(),
        _ => false,
    })
}

/// The names of the `Reporter` methods a run reached: the dispatch of
/// each kind's own values by their type is what it checks.
#[derive(Default)]
struct Reached(BTreeSet<&'static str>);

impl Reached {
    // What every `Reporter` method returns.
    #[allow(clippy::unnecessary_wraps)]
    fn note(&mut self, name: &'static str) -> io::Result<()> {
        self.0.insert(name);
        Ok(())
    }
}

impl Reporter for Reached {
    fn start(&mut self, _: &StartInfo) -> io::Result<()> {
        self.note("start")
    }
    fn matched(&mut self, _: &MatchEvent) -> io::Result<()> {
        self.note("match")
    }
    fn command(&mut self, _: &CommandEvent) -> io::Result<()> {
        self.note("command")
    }
    fn heard(&mut self, _: SysComp, _: &Identity) -> io::Result<()> {
        self.note("heard")
    }
    fn radio(&mut self, _: &RadioHeard<'_>) -> io::Result<()> {
        self.note("radio")
    }
    fn link_node(&mut self, _: SysComp, _: Nanos, _: &LinkNodeReport, _: bool) -> io::Result<()> {
        self.note("link_node")
    }
    fn clock(&mut self, _: SysComp, _: Nanos, _: &ClockSummary) -> io::Result<()> {
        self.note("clock")
    }
    fn waiting_for_peer(&mut self) -> io::Result<()> {
        self.note("waiting")
    }
    fn progress(&mut self, _: Nanos, _: u64) -> io::Result<()> {
        self.note("progress")
    }
    fn step(&mut self, _: &StepFigures) -> io::Result<()> {
        self.note("step")
    }
    fn sources(&mut self, _: &SourcesNow) -> io::Result<()> {
        self.note("sources")
    }
    fn flight(&mut self, _: &FlightEvent) -> io::Result<()> {
        self.note("flight")
    }
    fn link_failed(&mut self, _: Nanos, _: &str) -> io::Result<()> {
        self.note("link_failed")
    }
    fn echo_interim(&mut self, _: &EchoInterim) -> io::Result<()> {
        self.note("echo_interim")
    }
    fn passive_interim(&mut self, _: &PassiveInterim) -> io::Result<()> {
        self.note("passive_interim")
    }
    fn echo_summary(&mut self, _: &EchoSummary, _: &Verdict) -> io::Result<()> {
        self.note("echo_summary")
    }
    fn command_summary(&mut self, _: &CommandSummary, _: &Verdict) -> io::Result<()> {
        self.note("command_summary")
    }
    fn passive_summary(&mut self, _: &PassiveSummary, _: &Verdict) -> io::Result<()> {
        self.note("passive_summary")
    }
    fn c2_report(&mut self, _: &str, _: &C2Report) -> io::Result<()> {
        self.note("c2_report")
    }
}

/// The runs tell every kind of event, figures so far and summary, and
/// each reaches the method of its kind: else the formats are not tested
/// on it, or a kind's values are dropped on their way to them.
#[test]
fn the_runs_tell_every_kind_and_each_reaches_its_method() {
    let borrowed = Borrowed::new();
    let mut reached = Reached::default();
    for run in RUNS {
        tell_run(&mut reached, run, &borrowed);
    }
    let all = [
        "start",
        "match",
        "command",
        "heard",
        "radio",
        "link_node",
        "clock",
        "waiting",
        "progress",
        "step",
        "sources",
        "flight",
        "link_failed",
        "echo_interim",
        "passive_interim",
        "echo_summary",
        "command_summary",
        "passive_summary",
        "c2_report",
    ];
    let missing: Vec<_> = all.iter().filter(|k| !reached.0.contains(*k)).collect();
    assert!(missing.is_empty(), "no run reaches {missing:?}");
}

/// The run names its kind in the summary the text shows for it.
#[test]
fn text_shows_every_run_and_its_events() {
    let borrowed = Borrowed::new();
    for run in RUNS {
        for quiet in [false, true] {
            let mut out = TextReporter::new(Vec::new(), quiet);
            tell_run(&mut out, run, &borrowed);
            let text = String::from_utf8(out.into_inner()).unwrap();
            assert_eq!(text.matches("mavping statistics ---").count(), 1, "{text}");
            let c2 = matches!(run, Run::C2);
            assert_eq!(text.matches("C2 link report ---").count(), usize::from(c2));
            // Quiet: the summary and the interim lines only.
            assert_eq!(quiet, !text.starts_with("MAVPING "), "{run:?}: {text}");
        }
    }
}

#[test]
fn json_ends_every_run_with_its_summary() {
    let borrowed = Borrowed::new();
    for run in RUNS {
        let mut out = JsonReporter::new(Vec::new(), false, WallClock::starting(true));
        tell_run(&mut out, run, &borrowed);
        let text = String::from_utf8(out.into_inner()).unwrap();
        let lines: Vec<serde_json::Value> = text
            .lines()
            .map(|l| serde_json::from_str(l).unwrap())
            .collect();
        let kind = lines.last().unwrap()["type"].as_str().unwrap();
        assert!(kind.ends_with("summary"), "{run:?}: {kind}");
        // The C2 link report, where there is one, just before it.
        let c2: Vec<_> = lines.iter().map(|l| l["type"] == "c2_report").collect();
        let before_last = c2.len() >= 2 && c2[c2.len() - 2];
        assert_eq!(c2.iter().filter(|&&c| c).count(), usize::from(before_last));
        assert_eq!(before_last, matches!(run, Run::C2), "{run:?}");
    }
}

#[test]
fn prometheus_has_figures_of_every_run() {
    let borrowed = Borrowed::new();
    for run in RUNS {
        let mut metrics = Metrics::default();
        tell_run(&mut metrics, run, &borrowed);
        let text = metrics.render();
        let family = match run {
            Run::Passive | Run::Log => "mavping_source_received_total",
            Run::Command => "mavping_requests_total",
            Run::Transfer => "mavping_transfer_downloads_total",
            Run::Echo(_) | Run::Sweep(_) => "mavping_received_total",
            Run::C2 => "mavping_c2_availability_ratio",
        };
        assert!(text.contains(family), "{run:?}: {text}");
    }
}

#[test]
fn samples_have_rows_of_every_run_that_measures() {
    let borrowed = Borrowed::new();
    for run in RUNS {
        let mut log = SampleLog::new(Vec::new());
        tell_run(&mut log, run, &borrowed);
        let rows = String::from_utf8(log.into_inner()).unwrap().lines().count();
        // A row per reply or loss, or per source and second.
        assert_eq!(
            rows > 1,
            measures(run, &borrowed, true),
            "{run:?}: {rows} rows"
        );
    }
}

#[test]
fn the_plot_draws_every_run() {
    let borrowed = Borrowed::new();
    for run in RUNS {
        let plot = Plot::default();
        tell_run(&mut plot.link(), run, &borrowed);
        let svg = plot.svg().unwrap_or_else(|e| panic!("{run:?}: {e}"));
        assert!(svg.starts_with("<svg"), "{run:?}");
        // A run with a C2 link report gets its page, whatever its kind.
        let c2 = svg.contains("mavping C2 link report: sim:?seed=1, 600.0 s");
        assert_eq!(c2, matches!(run, Run::C2), "{run:?}");
    }
}

#[test]
fn the_live_view_has_a_row_for_every_run_that_hears_someone() {
    let borrowed = Borrowed::new();
    for run in RUNS {
        let mut state = LiveState::default();
        tell_run(&mut state, run, &borrowed);
        let screen = state.screen();
        assert_eq!(
            !screen.rows.is_empty(),
            measures(run, &borrowed, false),
            "{run:?}"
        );
    }
}

/// A kind no format has code for, as a new kind is before its formats
/// show it: an event and a summary written whole.
#[derive(Debug, serde::Serialize)]
#[serde(tag = "type", rename = "novel")]
struct Novel {
    n: u64,
}

impl KindValue for Novel {
    fn serialized(&self) -> Option<&dyn erased_serde::Serialize> {
        Some(self)
    }
}

#[derive(Debug, serde::Serialize)]
struct NovelSummary {
    #[serde(skip)]
    link: String,
    seen: u64,
}

impl KindSummary for NovelSummary {
    fn link(&self) -> &str {
        &self.link
    }
    fn link_error(&self) -> Option<&str> {
        None
    }
    fn serialized(&self) -> Option<(&'static str, &dyn erased_serde::Serialize)> {
        Some(("novel_summary", self))
    }
}

/// A new kind costs the JSON and text formats nothing: its events and
/// summary are written as they serialise (JSON with the link and the
/// verdict's exit code, text a line per event and a figure per line),
/// and every other format takes them and shows nothing of them.
#[test]
fn a_kind_no_format_knows_is_written_whole_by_json_and_text_and_passed_over_by_the_rest() {
    let summary = LinkSummary::new(NovelSummary {
        link: "sim:".into(),
        seen: 3,
    });
    // Until the verdict judges it, a new kind's run fails.
    let verdict = crate::verdict::judge_link(&summary, &super::runs::thresholds());
    assert_eq!(verdict.exit_code(), crate::exit::ERROR);
    let run = [
        Told::Event(kind(Novel { n: 7 })),
        Told::Summary(summary, verdict),
    ];
    let mut json = JsonReporter::new(Vec::new(), false, WallClock::starting(true));
    let mut text = TextReporter::new(Vec::new(), false);
    let mut metrics = Metrics::default();
    let mut state = LiveState::default();
    for out in [
        &mut json as &mut dyn Reporter,
        &mut text,
        &mut metrics,
        &mut state,
    ] {
        for told in &run {
            match told {
                Told::Event(event) => out.tell(event),
                Told::Summary(summary, verdict) => out.summary(summary, verdict),
                _ => unreachable!(),
            }
            .unwrap();
        }
    }
    let lines = String::from_utf8(json.into_inner()).unwrap();
    assert_eq!(
        lines,
        "{\"type\":\"novel\",\"n\":7}\n\
         {\"link\":\"sim:\",\"seen\":3,\"type\":\"novel_summary\",\"schema_version\":2,\
         \"verdict\":{\"ok\":false,\"exit_code\":2,\"failures\":[]},\"exit_code\":2}\n"
    );
    assert_eq!(
        String::from_utf8(text.into_inner()).unwrap(),
        "novel: n=7\n\n--- sim: mavping statistics ---\nseen: 3\n"
    );
    assert!(state.screen().rows.is_empty());
}

/// A passive run's live row shows each source's age now, marked as a
/// problem past 100 ms (the run's fixture: 1/1's newest frame 240 ms late).
#[test]
fn the_live_view_shows_how_late_a_sources_newest_frame_came() {
    let borrowed = Borrowed::new();
    let mut state = LiveState::default();
    tell_run(&mut state, Run::Passive, &borrowed);
    let screen = state.screen();
    let ages: Vec<_> = screen
        .rows
        .iter()
        .map(|r| r.cells.last().cloned())
        .collect();
    assert_eq!(ages, [Some(("240".to_string(), true))]);
}

/// The exporter gauges each source's age now (the fixture's 1/1: 240 ms).
#[test]
fn the_exporter_gauges_how_late_a_sources_newest_frame_came() {
    let borrowed = Borrowed::new();
    let mut metrics = Metrics::default();
    tell_run(&mut metrics, Run::Passive, &borrowed);
    let text = metrics.render();
    let line = text
        .lines()
        .find(|l| l.starts_with("mavping_source_age_seconds{"))
        .unwrap_or_else(|| panic!("no age gauge in\n{text}"));
    assert!(
        line.contains("sysid=\"1\"") && line.ends_with(" 0.24"),
        "{line}"
    );
    assert_eq!(text.matches("mavping_source_age_seconds{").count(), 1);
    // And all its frames' ages so far, as a histogram (cumulative).
    let sample = |suffix: &str, le: Option<&str>| {
        text.lines()
            .find(|l| {
                l.starts_with(&format!("mavping_source_frame_age_seconds_{suffix}{{"))
                    && le.is_none_or(|le| l.contains(&format!("le=\"{le}\"")))
            })
            .and_then(|l| l.rsplit(' ').next())
            .unwrap_or_else(|| panic!("no {suffix} {le:?} in\n{text}"))
            .to_string()
    };
    assert_eq!(sample("bucket", Some("0.001")), "30");
    assert_eq!(sample("bucket", Some("0.1")), "30");
    assert_eq!(sample("bucket", Some("0.25")), "38");
    assert_eq!(sample("bucket", Some("0.5")), "40");
    assert_eq!(sample("bucket", Some("+Inf")), "40");
    assert_eq!(sample("sum", None), "3.5");
    assert_eq!(sample("count", None), "40");
    assert!(text.contains("# TYPE mavping_source_frame_age_seconds histogram"));
}
