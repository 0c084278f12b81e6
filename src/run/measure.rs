//! A measurement run over one or more links (`mavping LINK...`, like fping
//! with several hosts). One link is a list of one: every link gets its own
//! session, sequence space, pending table and report, run concurrently in
//! one task and sharing the schedule parameters and the stop signal.
//!
//! - A link that cannot be opened or fails ends only itself: its error
//!   line names the link (when there are several) and the others go on.
//! - Thresholds and `--expect` apply to each link; the exit code is the
//!   worst over the links ([`crate::exit`]).
//! - Text: one link prints as ping does; with several, per-reply lines are
//!   prefixed with `[LINK] ` and the summaries follow at the end, in
//!   command-line order. JSON: with several links every object carries
//!   `"link"`. `--samples` gains a `link` column, `--hgrm` a section per
//!   link and responder, `--prometheus` a series per link, `--plot` a line
//!   per link and responder, `--live` a section per link.

use std::io::{self, BufWriter, IsTerminal, Write};
use std::sync::Arc;
use std::time::{Duration, SystemTime};

use futures_util::future::join_all;
use tokio::sync::Notify;

use super::exports::Exports;
use super::one_link::{measure_recorded, Taps};
use super::pair::Pairs;
use crate::cli::Format;
use crate::config::{Config, LinkConfig, OutputConfig, Probe};
use crate::engine::observe::OutputFate;
use crate::engine::session::{Controls, Measurement};
use crate::engine::summary::passive::PassiveSummary;
use crate::exit::{Ending, LinkEnd};
use crate::output::json::JsonReporter;
use crate::output::live::LiveView;
use crate::output::text::TextReporter;
use crate::output::{Fanout, Reporter, Shared, WallClock};
use crate::stderr;
use crate::transport::{Link, LinkSpec};
use crate::verdict;

/// Raises every one of `to` whenever `from` is raised (once, or each time
/// when `repeat`): one signal reaches every link's session.
fn forward(from: &Arc<Notify>, to: Vec<Arc<Notify>>, repeat: bool) {
    let from = from.clone();
    tokio::spawn(async move {
        loop {
            from.notified().await;
            for n in &to {
                n.notify_one();
            }
            if !repeat {
                return;
            }
        }
    });
}

/// An error line of one of several links: "LINK: ERROR", unless the error
/// already names the link; one link's errors need no name.
fn error_line(several: bool, link: &str, error: &str) -> String {
    if !several || error.contains(link) {
        error.to_string()
    } else {
        format!("{link}: {error}")
    }
}

/// One link of the run, carried from its open link to its judgement.
struct LinkRun<'a> {
    config: &'a LinkConfig,
    link: Link,
    /// The wall clock at its session's time 0: the run's start, or a
    /// telemetry log's first stamp.
    wall: WallClock,
    /// Attached once every link is open (a live view takes the screen
    /// only after the errors and warnings are printed).
    report: Fanout<'a>,
    controls: Controls,
    /// Its way into the `--tlog` recording and the pair report.
    taps: Taps,
}

/// A link whose session ended.
struct Finished<'a> {
    config: &'a LinkConfig,
    report: Fanout<'a>,
    measurement: Measurement,
}

/// Where the run's reports go: standard output, and the live view when
/// there is one.
struct Screen {
    view: Option<LiveView>,
    stdout: Shared<Box<dyn Write>>,
}

impl Screen {
    /// Takes the terminal for `--live` when there is one.
    fn open(out: &OutputConfig, controls: &Controls) -> Result<Self, Ending> {
        let live = out.live && io::stdout().is_terminal();
        if out.live && !live {
            stderr::error(&"--live needs a terminal; printing text");
        }
        let view = match live.then(|| LiveView::start(controls.stop.clone())) {
            None => None,
            Some(Ok(view)) => Some(view),
            Some(Err(e)) => {
                stderr::error(&format_args!("--live: {e}"));
                return Err(Ending::Refused);
            }
        };
        // Buffered: a write per line would pace the engine at high rates.
        // The session flushes before it blocks and every 50 ms while busy.
        // Locked for the run, except under the live view, which draws to
        // it from its own thread.
        let stdout: Box<dyn Write> = if live {
            Box::new(BufWriter::new(io::stdout()))
        } else {
            Box::new(BufWriter::new(io::stdout().lock()))
        };
        Ok(Screen {
            view,
            stdout: Shared::new(stdout),
        })
    }

    /// The reporter of one link's run on this screen.
    fn reporter(
        &self,
        out: &OutputConfig,
        name: &str,
        several: bool,
        wall: WallClock,
    ) -> Vec<Box<dyn Reporter>> {
        let stdout = self.stdout.clone();
        match (out.format, &self.view) {
            // The view shows the run; the text summaries follow it.
            (Format::Text, Some(view)) => vec![
                Box::new(view.link()),
                Box::new(TextReporter::new(stdout, true)),
            ],
            (Format::Text, None) => vec![Box::new(
                TextReporter::new(stdout, out.quiet)
                    .every_reply(out.every_reply)
                    .timestamps(out.timestamps.then_some(wall))
                    .prefixed(several.then(|| format!("[{name}] "))),
            )],
            (Format::Json, _) => vec![Box::new(
                JsonReporter::new(stdout, out.quiet, wall)
                    .with_link(several.then(|| name.to_string())),
            )],
        }
    }

    fn close(&mut self) {
        if let Some(mut view) = self.view.take() {
            if let Err(e) = view.close() {
                stderr::error(&format_args!("--live: {e}"));
            }
        }
    }
}

/// Opens every link; the ones that opened, and the names of the others.
/// Errors and warnings are printed here, before a live view takes the
/// screen.
async fn open(config: &Config) -> (Vec<(&LinkConfig, Link)>, Vec<(&str, String)>) {
    let several = config.links.len() > 1;
    let opening = config
        .links
        .iter()
        .map(|l| Link::open(&l.spec, &config.link_options));
    let mut opened = Vec::new();
    let mut unopened = Vec::new();
    for (link_config, result) in config.links.iter().zip(join_all(opening).await) {
        let name = &link_config.name;
        match result {
            Ok(link) => {
                if let Some(w) = baud_warning(link_config) {
                    stderr::warning(&error_line(several, name, &w));
                }
                opened.push((link_config, link));
            }
            Err(e) => {
                stderr::error(&error_line(several, name, &e.to_string()));
                unopened.push((name.as_str(), e.to_string()));
            }
        }
    }
    (opened, unopened)
}

/// A rate the baud rate cannot carry. A USB CDC port or a pty passes what
/// it gets at once: the warning is for a real UART (the summary says which
/// it was, from the RTTs). A sweep means to go past it; its first line
/// says how far.
fn baud_warning(link: &LinkConfig) -> Option<String> {
    let session = &link.session;
    session
        .wire
        .filter(|_| !link.spec.may_ignore_baud() && session.sweep.is_none())
        .and_then(|w| w.warning(1.0 / session.interval.as_secs_f64()))
}

/// Gives each opened link its reports and its own controls, all raised
/// by the run's.
fn attach<'a>(
    opened: Vec<(&'a LinkConfig, Link)>,
    config: &'a Config,
    screen: &Screen,
    exports: &Exports,
    controls: &Controls,
    wall: WallClock,
    pairs: Option<&Pairs>,
) -> Vec<LinkRun<'a>> {
    let several = config.links.len() > 1;
    // Logs read together are laid on one clock by their first stamps (a
    // flight's logs from two ground stations), for the pair report.
    let first_log = opened
        .iter()
        .filter_map(|(_, link)| match link {
            Link::Tlog(log) => Some(log.started()),
            _ => None,
        })
        .min();
    let runs: Vec<LinkRun<'a>> = opened
        .into_iter()
        .enumerate()
        .map(|(index, (link_config, link))| {
            let name = &link_config.name;
            let wall = match &link {
                Link::Tlog(log) => WallClock {
                    start: log.started(),
                },
                _ => wall,
            };
            let mut reporters = screen.reporter(&config.output, name, several, wall);
            reporters.extend(exports.reporters(index, name));
            // Its stamps' link bits are its place on the command line,
            // whichever links failed to open.
            let place = config
                .links
                .iter()
                .position(|l| std::ptr::eq(l, link_config))
                .unwrap_or(index);
            let log = matches!(link, Link::Tlog(_));
            let watch = pairs.map(|p| p.watch(place, after(first_log, &link), log));
            LinkRun {
                config: link_config,
                link,
                wall,
                report: Fanout::new(reporters),
                controls: Controls::default(),
                taps: Taps {
                    tlog: exports.tap(place),
                    watch,
                    out_link: u8::try_from(place)
                        .ok()
                        .filter(|&p| several && p < OUT_LINKS),
                },
            }
        })
        .collect();
    forward(
        &controls.stop,
        runs.iter().map(|r| r.controls.stop.clone()).collect(),
        false,
    );
    forward(
        &controls.interim,
        runs.iter().map(|r| r.controls.interim.clone()).collect(),
        true,
    );
    runs
}

/// Links numbered in TIMESYNC and PING tokens: MAVProxy's four bits.
const OUT_LINKS: u8 = 16;

/// How long after `first` (the earliest log's first stamp) `link`, a
/// log, began: its frames' times in the run's pair report are shifted by
/// it. Other links: 0.
fn after(first: Option<SystemTime>, link: &Link) -> Duration {
    match (first, link) {
        (Some(first), Link::Tlog(log)) => log.started().duration_since(first).unwrap_or_default(),
        _ => Duration::ZERO,
    }
}

/// One link's session, from its open link to its measurement. With
/// `announce`, prints the link's error line as soon as it fails, while
/// others go on.
async fn measure_one<'a>(run: LinkRun<'a>, probe: &Probe, announce: bool) -> Finished<'a> {
    let LinkRun {
        config,
        link,
        wall,
        mut report,
        controls,
        taps,
    } = run;
    let measurement =
        measure_recorded(config, link, taps, probe, wall, &mut report, &controls).await;
    if let Some(e) = measurement.summary.link_error().filter(|_| announce) {
        stderr::error(&error_line(true, &config.name, e));
    }
    Finished {
        config,
        report,
        measurement,
    }
}

/// Judges each link and writes its summary, in command-line order; how
/// each ended, and what became of the output.
fn judge(
    finished: &mut [Finished<'_>],
    stdout: &Shared<Box<dyn Write>>,
    separate: bool,
) -> (Vec<LinkEnd>, OutputFate) {
    let mut ends = Vec::new();
    let mut output = OutputFate::default();
    for (i, f) in finished.iter_mut().enumerate() {
        let verdict = verdict::judge_link(&f.measurement.summary, &f.config.thresholds);
        // Quiet summaries are not preceded by a blank line: separate them.
        if separate && i > 0 {
            output.note(&writeln!(stdout.clone()));
        }
        output.merge(f.measurement.output.clone());
        output.note(&f.report.summary(&f.measurement.summary, &verdict));
        ends.push(verdict.end);
    }
    output.note(&stdout.clone().flush());
    (ends, output)
}

/// Runs `sessions`, telling the exporters, the plot and the live view
/// the pair report every second and when they end.
async fn with_pair_figures<F: std::future::Future>(
    sessions: F,
    pairs: &Pairs,
    exports: &Exports,
    view: Option<&LiveView>,
    names: &[&str],
) -> F::Output {
    let tell = || {
        if exports.exports_metrics() {
            exports.run_figures(&pairs.metrics(names));
        }
        if let Some(view) = view {
            pairs.show(names, view);
        }
        if exports.plots() {
            let (at, summary) = pairs.by_link_now();
            exports.pair_by_link(at, &summary);
        }
    };
    tokio::pin!(sessions);
    let mut every = tokio::time::interval(std::time::Duration::from_secs(1));
    let finished = loop {
        tokio::select! {
            finished = &mut sessions => break finished,
            _ = every.tick() => tell(),
        }
    };
    pairs.finish();
    tell();
    finished
}

/// Whether each link's paths (by place) are ways a source's frames came
/// of their own: a telemetry log's only when its stamps carried MAVProxy's
/// link numbers (its summary's figures per link), every other link's
/// always (a simulated vehicle's paths, a listening link's peers).
fn paths_are_ways(config: &Config, finished: &[Finished<'_>]) -> Vec<bool> {
    config
        .links
        .iter()
        .map(|l| {
            let done = finished.iter().find(|f| std::ptr::eq(f.config, l));
            let log = done.and_then(|f| f.measurement.summary.get::<PassiveSummary>());
            match (&l.spec, log) {
                (LinkSpec::Tlog(_), Some(s)) => s.per_link.is_some(),
                _ => true,
            }
        })
        .collect()
}

/// Runs every link of `config` side by side; how it ended.
pub(super) async fn run(config: &Config, controls: Controls) -> Ending {
    let exports = match Exports::open(config) {
        Ok(exports) => exports,
        Err(e) => {
            stderr::error(&e);
            return Ending::Refused;
        }
    };
    let several = config.links.len() > 1;
    let (opened, unopened) = open(config).await;
    let wall = WallClock::starting(config.virtual_clock());
    let mut screen = match Screen::open(&config.output, &controls) {
        Ok(screen) => screen,
        Err(ending) => return ending,
    };
    // The same source heard several ways: matched across them as they run.
    let pairs = Pairs::of(&config.links, &config.probe);
    let runs = attach(
        opened,
        config,
        &screen,
        &exports,
        &controls,
        wall,
        pairs.as_ref(),
    );
    for (k, (name, error)) in unopened.iter().enumerate() {
        exports.unopened(runs.len() + k, name);
        if let Some(view) = &screen.view {
            view.unopened(name, error);
        }
    }
    let announce = several && screen.view.is_none();
    let live = screen.view.is_some();
    // One task for every session, so their reports can share stdout; each
    // session is polled when its own waker fires, not whenever any does
    // (100 links would otherwise cost 100 polls per wake-up).
    let sessions = runs
        .into_iter()
        .map(|run| measure_one(run, &config.probe, announce));
    let names: Vec<&str> = config.links.iter().map(|l| l.name.as_str()).collect();
    let view = screen.view.as_ref();
    let told = exports.exports_metrics() || exports.plots() || live;
    let mut finished = match pairs.as_ref().filter(|_| told) {
        Some(pairs) => with_pair_figures(join_all(sessions), pairs, &exports, view, &names).await,
        None => join_all(sessions).await,
    };
    screen.close();
    if !announce {
        for f in &finished {
            if let Some(e) = f.measurement.summary.link_error() {
                stderr::error(&error_line(several, f.measurement.summary.link(), e));
            }
        }
    }
    let out = &config.output;
    let separate = out.format == Format::Text && (out.quiet || live);
    let (mut links, mut output) = judge(&mut finished, &screen.stdout, separate);
    if let Some(pairs) = &pairs {
        let ways = paths_are_ways(config, &finished);
        output.note(&pairs.write(out.format, &names, &ways, &mut screen.stdout.clone()));
    }
    if let OutputFate::Failed(e) = &output {
        stderr::error(&format!("cannot write the output: {e}"));
    }
    links.extend(unopened.iter().map(|_| LinkEnd {
        link_failed: true,
        checks_held: false,
    }));
    let exports_failed = match exports.finish(finished.iter().map(|f| &f.measurement)) {
        Ok(()) => false,
        Err(e) => {
            stderr::error(&e);
            true
        }
    };
    Ending::Measured {
        links,
        output_failed: matches!(output, OutputFate::Failed(_)),
        exports_failed,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn error_lines_name_the_link_once() {
        assert_eq!(
            error_line(true, "udpout:127.0.0.1:9", "udp link failed: refused"),
            "udpout:127.0.0.1:9: udp link failed: refused"
        );
        assert_eq!(
            error_line(
                true,
                "serial:/dev/x:57600",
                "cannot open serial:/dev/x:57600: gone"
            ),
            "cannot open serial:/dev/x:57600: gone"
        );
        assert_eq!(error_line(false, "sim:", "gone"), "gone");
    }
}
