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

use futures_util::future::join_all;
use tokio::sync::Notify;

use super::exports::Exports;
use super::one_link::measure;
use crate::cli::Format;
use crate::config::{Config, LinkConfig, Probe};
use crate::engine::capacity::{self, WireBudget};
use crate::engine::session::{Controls, Measurement};
use crate::engine::summary::LinkSummary;
use crate::exit::Ending;
use crate::output::json::JsonReporter;
use crate::output::live::LiveView;
use crate::output::text::TextReporter;
use crate::output::{Fanout, Reporter, Shared, WallClock};
use crate::stderr;
use crate::transport::Link;
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

/// An opened link, ready to run.
struct LinkRun<'a> {
    config: &'a LinkConfig,
    link: Link,
    wire: Option<WireBudget>,
}

/// One link's session, from its open link to its outcome. With `announce`,
/// prints the link's error line as soon as it fails, while others go on.
async fn measure_announced(
    run: LinkRun<'_>,
    probe: &Probe,
    wall: WallClock,
    observer: &mut Fanout<'_>,
    controls: Controls,
    announce: bool,
) -> Measurement {
    let LinkRun { config, link, .. } = run;
    let outcome = measure(config, link, probe, wall, observer, &controls).await;
    if let Some(e) = outcome.summary.link_error().filter(|_| announce) {
        stderr::error(&error_line(true, &config.name, e));
    }
    outcome
}

/// Standard output for the reports. Locked for the run, except under the
/// live view, which draws to it from its own thread.
fn stdout(live: bool) -> Shared<Box<dyn Write>> {
    // Buffered: a write per line would pace the engine at high rates. The
    // session flushes before it blocks and every 50 ms while busy.
    Shared::new(if live {
        Box::new(BufWriter::new(io::stdout()))
    } else {
        Box::new(BufWriter::new(io::stdout().lock()))
    })
}

/// Runs every link of `config` side by side; how it ended.
pub async fn run(config: &Config, controls: Controls) -> Ending {
    let exports = match Exports::open(config) {
        Ok(exports) => exports,
        Err(e) => {
            stderr::error(&e);
            return Ending::Refused;
        }
    };
    let several = config.links.len() > 1;
    let opened = join_all(
        config
            .links
            .iter()
            .map(|l| Link::open(&l.spec, &config.link_options)),
    )
    .await;
    let wall = WallClock::starting(config.virtual_clock());
    // Errors and warnings first, before a live view takes the screen.
    let mut unopened = Vec::new();
    let mut runs = Vec::new();
    for (link_config, opened) in config.links.iter().zip(opened) {
        let name = &link_config.name;
        let link = match opened {
            Ok(link) => link,
            Err(e) => {
                stderr::error(&error_line(several, name, &e.to_string()));
                unopened.push(name);
                continue;
            }
        };
        let session = &link_config.session;
        let wire = match config.probe {
            Probe::Command(_) => None,
            _ => capacity::for_link(&link_config.spec, &config.link_options, session),
        };
        // A USB CDC port or a pty passes what it gets at once: the warning
        // is for a real UART (the summary says which it was, from the RTTs).
        // A sweep means to go past it; its first line says how far.
        let warning = wire
            .filter(|_| !link_config.spec.may_ignore_baud() && session.sweep.is_none())
            .and_then(|w| w.warning(1.0 / session.interval.as_secs_f64()));
        if let Some(w) = warning {
            stderr::warning(&error_line(several, name, &w));
        }
        runs.push(LinkRun {
            config: link_config,
            link,
            wire,
        });
    }
    let out = &config.output;
    let live = out.live && io::stdout().is_terminal();
    if out.live && !live {
        stderr::error(&"--live needs a terminal; printing text");
    }
    let mut view = None;
    if live {
        match LiveView::start(controls.stop.clone()) {
            Ok(v) => view = Some(v),
            Err(e) => {
                stderr::error(&format_args!("--live: {e}"));
                return Ending::Refused;
            }
        }
    }
    let stdout = stdout(live);
    let mut reports: Vec<Fanout<'_>> = Vec::new();
    for (index, run) in runs.iter().enumerate() {
        let name = &run.config.name;
        let mut reporters: Vec<Box<dyn Reporter>> = Vec::new();
        match (out.format, &view) {
            // The view shows the run; the text summaries follow it.
            (Format::Text, Some(view)) => {
                reporters.push(Box::new(view.link()));
                reporters.push(Box::new(TextReporter::new(stdout.clone(), true)));
            }
            (Format::Text, None) => reporters.push(Box::new(
                TextReporter::new(stdout.clone(), out.quiet)
                    .every_reply(out.every_reply)
                    .timestamps(out.timestamps.then_some(wall))
                    .prefixed(several.then(|| format!("[{name}] "))),
            )),
            (Format::Json, _) => reporters.push(Box::new(
                JsonReporter::new(stdout.clone(), out.quiet, wall)
                    .with_link(several.then(|| name.clone())),
            )),
        }
        reporters.extend(exports.reporters(index, name));
        reports.push(Fanout { reporters });
    }
    for (k, name) in unopened.iter().enumerate() {
        exports.unopened(runs.len() + k, name);
    }
    // Each session gets its own controls, all raised by the run's.
    let per_link: Vec<Controls> = runs.iter().map(|_| Controls::default()).collect();
    forward(
        &controls.stop,
        per_link.iter().map(|c| c.stop.clone()).collect(),
        false,
    );
    forward(
        &controls.interim,
        per_link.iter().map(|c| c.interim.clone()).collect(),
        true,
    );
    let wires: Vec<Option<WireBudget>> = runs.iter().map(|r| r.wire).collect();
    let thresholds: Vec<_> = runs.iter().map(|r| &r.config.thresholds).collect();
    let announce = several && view.is_none();
    let mut sessions = Vec::new();
    for ((run, report), controls) in runs.into_iter().zip(reports.iter_mut()).zip(per_link) {
        sessions.push(measure_announced(
            run,
            &config.probe,
            wall,
            report,
            controls,
            announce,
        ));
    }
    // One task for every session, so their reports can share stdout; each
    // session is polled when its own waker fires, not whenever any does
    // (100 links would otherwise cost 100 polls per wake-up).
    let mut outcomes = join_all(sessions).await;
    if let Some(mut view) = view {
        if let Err(e) = view.close() {
            stderr::error(&format_args!("--live: {e}"));
        }
    }
    if !announce {
        for outcome in &outcomes {
            if let Some(e) = outcome.summary.link_error() {
                stderr::error(&error_line(several, outcome.summary.link(), e));
            }
        }
    }
    let mut links = Vec::new();
    let mut output_closed = false;
    let separate = out.format == Format::Text && (out.quiet || live);
    for (i, ((outcome, report), wire)) in outcomes
        .iter_mut()
        .zip(reports.iter_mut())
        .zip(wires)
        .enumerate()
    {
        if let (LinkSummary::Echo(summary), Some(w)) = (&mut outcome.summary, wire) {
            summary.apply_wire(w);
        }
        let verdict = verdict::judge_link(&outcome.summary, thresholds[i]);
        // Quiet summaries are not preceded by a blank line: separate them.
        if separate && i > 0 {
            output_closed |= writeln!(stdout.clone()).is_err();
        }
        output_closed |=
            outcome.output_closed || report.summary(&outcome.summary, &verdict).is_err();
        links.push(verdict.end());
    }
    links.extend(unopened.iter().map(|_| crate::exit::LinkEnd {
        link_failed: true,
        checks_held: false,
    }));
    let exports_failed = match exports.finish(&outcomes) {
        Ok(()) => false,
        Err(e) => {
            stderr::error(&e);
            true
        }
    };
    Ending::Measured {
        links,
        output_closed,
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
