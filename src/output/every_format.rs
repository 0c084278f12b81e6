//! Every run of every kind through every format: what exhaustive matches
//! over the events once guarded, now that a format implements only the
//! kinds it shows. Each format must take every event and summary without
//! an error, and show what it is for from each kind it shows.
#![cfg(test)]

use super::json::JsonReporter;
use super::live::LiveState;
use super::plot::Plot;
use super::prometheus::Metrics;
use super::runs::{Borrowed, Run, Told, RUNS};
use super::samples::SampleLog;
use super::text::TextReporter;
use super::{Event, Reporter, WallClock};
use crate::engine::summary::LinkSummary;

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
        Told::Event(Event::Match(_) | Event::Sources { .. }) => true,
        Told::Summary(LinkSummary::Passive(_), _) => at_end,
        _ => false,
    })
}

/// What kinds of event the runs tell, by name: the runs must tell every
/// kind, or the formats are not tested on it.
fn kind(event: &Event<'_>) -> &'static str {
    match event {
        Event::Match(_) => "match",
        Event::Command(_) => "command",
        Event::Heard { .. } => "heard",
        Event::Radio(_) => "radio",
        Event::LinkNode { .. } => "link_node",
        Event::Clock { .. } => "clock",
        Event::WaitingForPeer => "waiting",
        Event::Progress { .. } => "progress",
        Event::Step(_) => "step",
        Event::Sources { .. } => "sources",
        Event::Flight(_) => "flight",
        Event::LinkFailed { .. } => "link_failed",
    }
}

#[test]
fn the_runs_tell_every_kind_of_event_and_summary() {
    let borrowed = Borrowed::new();
    let mut kinds = std::collections::BTreeSet::new();
    for run in RUNS {
        for told in run.told(&borrowed) {
            match told {
                Told::Event(e) => kinds.insert(kind(&e)),
                Told::Interim(_) => kinds.insert("interim"),
                Told::Summary(s, _) => kinds.insert(match s {
                    LinkSummary::Echo(_) => "echo_summary",
                    LinkSummary::Command(_) => "command_summary",
                    LinkSummary::Passive(_) => "passive_summary",
                }),
                Told::Start(_) => kinds.insert("start"),
            };
        }
    }
    let all = [
        "match",
        "command",
        "heard",
        "radio",
        "link_node",
        "clock",
        "progress",
        "step",
        "sources",
        "flight",
        "interim",
        "echo_summary",
        "command_summary",
        "passive_summary",
        "start",
    ];
    let missing: Vec<_> = all.iter().filter(|k| !kinds.contains(*k)).collect();
    assert!(missing.is_empty(), "no run tells {missing:?}");
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
        let last: serde_json::Value = serde_json::from_str(text.lines().last().unwrap()).unwrap();
        let kind = last["type"].as_str().unwrap();
        assert!(kind.ends_with("summary"), "{run:?}: {kind}");
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
            Run::Echo(_) | Run::Sweep(_) => "mavping_received_total",
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
