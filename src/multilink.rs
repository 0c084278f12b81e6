//! Several links side by side (`mavping LINK1 LINK2 ...`, like fping with
//! several hosts): one session per link, each with its own sequence space,
//! pending table and report, run concurrently in one task on the one
//! runtime and sharing the schedule parameters and the stop signal
//! (count, deadline, Ctrl-C).
//!
//! - A link that cannot be opened or fails ends only itself: its error
//!   line goes to stderr at once, naming the link; the others go on.
//! - Thresholds and `--expect` apply to each link. The exit code is the
//!   worst over the links: 2 when any link failed (the check could not be
//!   done there, even if the others answered), else 1 when any link broke
//!   a threshold or heard no reply, else 0.
//! - Text: per-reply lines are prefixed with `[LINK] `; the summaries
//!   follow at the end, one per link in command-line order, each under its
//!   `--- LINK mavping statistics ---` header. JSON: every object carries
//!   `"link"`. `--samples` gains a `link` column, `--hgrm` a section per
//!   link and responder, `--prometheus` a series per link (its `link`
//!   label), `--live` a section per link. Sessions share one thread, so sends wait on tokio's timer
//!   (about 1 ms resolution) instead of spinning; the RTT is still taken
//!   from the actual send time.

use std::future::Future;
use std::io::{self, BufWriter, IsTerminal, Write};
use std::pin::Pin;
use std::sync::Arc;
use std::task::Poll;
use std::time::{SystemTime, UNIX_EPOCH};

use tokio::sync::Notify;

use crate::app::{self, print_error};
use crate::cli::Format;
use crate::config::{Config, Probe};
use crate::engine::capacity::{self, WireBudget};
use crate::engine::session::{self, Outcome, SessionConfig};
use crate::engine::summary::Summary;
use crate::output::json::JsonReporter;
use crate::output::live::LiveLinks;
use crate::output::samples::SampleLog;
use crate::output::text::TextReporter;
use crate::output::{Event, Fanout, Prefixed, Reporter, Shared, StartInfo, WallClock};
use crate::probe::ping::PingProbe;
use crate::probe::timesync::TimesyncProbe;
use crate::transport::{Link, LinkSpec};
use crate::verdict::{self, exit, Thresholds, Verdict};

/// Polls every future until all are done; outputs in the input order.
/// The sessions share one task, so their reports can share stdout.
async fn join_all<F: Future>(futures: Vec<F>) -> Vec<F::Output> {
    let mut futures: Vec<Pin<Box<F>>> = futures.into_iter().map(Box::pin).collect();
    let mut outputs: Vec<Option<F::Output>> = futures.iter().map(|_| None).collect();
    std::future::poll_fn(|cx| {
        let mut pending = false;
        for (f, out) in futures.iter_mut().zip(outputs.iter_mut()) {
            if out.is_none() {
                match f.as_mut().poll(cx) {
                    Poll::Ready(v) => *out = Some(v),
                    Poll::Pending => pending = true,
                }
            }
        }
        if pending {
            Poll::Pending
        } else {
            Poll::Ready(())
        }
    })
    .await;
    outputs.into_iter().flatten().collect()
}

/// Text for one of several links: reply lines prefixed with the link as
/// they happen; the summary unprefixed, under its own header.
struct LinkText<W: Write> {
    events: TextReporter<Prefixed<Shared<W>>>,
    summary: TextReporter<Shared<W>>,
}

impl<W: Write> Reporter for LinkText<W> {
    fn start(&mut self, info: &StartInfo) -> io::Result<()> {
        self.events.start(info)
    }
    fn event(&mut self, event: &Event<'_>) -> io::Result<()> {
        self.events.event(event)
    }
    fn summary(&mut self, summary: &Summary, verdict: &Verdict) -> io::Result<()> {
        self.summary.summary(summary, verdict)
    }
    fn flush(&mut self) -> io::Result<()> {
        self.events.flush()
    }
}

/// `--live` for one of several links: its section of the view as it
/// goes, then its text summary once the view is closed.
struct LinkLive<W: Write> {
    view: crate::output::live::LiveLink,
    summary: TextReporter<Shared<W>>,
}

impl<W: Write> Reporter for LinkLive<W> {
    fn start(&mut self, info: &StartInfo) -> io::Result<()> {
        self.view.start(info)
    }
    fn event(&mut self, event: &Event<'_>) -> io::Result<()> {
        self.view.event(event)
    }
    fn summary(&mut self, summary: &Summary, verdict: &Verdict) -> io::Result<()> {
        self.summary.summary(summary, verdict)
    }
}

/// "LINK: ERROR", unless the error already names the link.
fn link_error_line(link: &str, error: &str) -> String {
    if error.contains(link) {
        error.to_string()
    } else {
        format!("{link}: {error}")
    }
}

/// An opened link, ready to run.
struct LinkRun<'a> {
    /// Its place on the command line.
    index: usize,
    spec: &'a LinkSpec,
    link: Link,
    session: SessionConfig,
    wire: Option<WireBudget>,
}

/// One link's session, from its open link to its outcome. With `announce`,
/// prints the link's error line as soon as it fails, while the others go on.
async fn run_link(
    config: &Config,
    run: LinkRun<'_>,
    wall: WallClock,
    report: &mut Fanout<'_>,
    stop: Arc<Notify>,
    announce: bool,
) -> Outcome {
    let LinkRun {
        spec,
        mut link,
        session,
        ..
    } = run;
    let outcome = match &config.probe {
        Probe::Timesync { target } => {
            let base = if matches!(spec, LinkSpec::Sim(_)) {
                0
            } else {
                wall.micros_since_epoch() * 1_000
            };
            let probe = TimesyncProbe::new(base, *target);
            session::run(&session, &mut link, probe, report, stop).await
        }
        _ => {
            let probe = PingProbe::new(wall.micros_since_epoch());
            session::run(&session, &mut link, probe, report, stop).await
        }
    };
    if let Some(e) = outcome.summary.link_error.as_ref().filter(|_| announce) {
        print_error(&link_error_line(&session.link_name, e));
    }
    outcome
}

/// The thresholds of the `index`-th link: every link's, and the
/// responders `--expect LINK=ID` expects there.
fn thresholds_of(config: &Config, index: usize) -> Thresholds {
    let mut t = config.thresholds.clone();
    t.expect.extend(
        config
            .expect_on
            .iter()
            .filter(|(i, _)| *i == index)
            .map(|(_, id)| *id),
    );
    t
}

/// The exit code over all links: any error wins, then any failure.
pub fn overall_exit(codes: impl IntoIterator<Item = u8>) -> u8 {
    let codes: Vec<u8> = codes.into_iter().collect();
    if codes.contains(&exit::ERROR) {
        exit::ERROR
    } else if codes.contains(&exit::FAILED) {
        exit::FAILED
    } else {
        exit::OK
    }
}

/// Runs every link of `config` side by side and returns the exit code.
pub async fn run(config: &Config) -> u8 {
    let stop = Arc::new(Notify::new());
    app::watch_signals(stop.clone());
    // Exports are opened before the links, so a bad path fails first.
    let samples = match config
        .samples
        .as_deref()
        .map(|p| app::create(p, "--samples"))
    {
        Some(Err(e)) => {
            print_error(&e);
            return exit::ERROR;
        }
        Some(Ok(file)) => Some(Shared::new(file)),
        None => None,
    };
    let prometheus = match app::prometheus(config) {
        Ok(p) => p,
        Err(e) => {
            print_error(&e);
            return exit::ERROR;
        }
    };
    let opened = join_all(
        config
            .links
            .iter()
            .map(|spec| Link::open(spec, &config.link_options))
            .collect(),
    )
    .await;
    let wall = WallClock {
        start: if config.virtual_clock() {
            UNIX_EPOCH
        } else {
            SystemTime::now()
        },
    };
    // Errors and warnings first, before a live view takes the screen.
    let mut open_failed = false;
    let mut runs = Vec::new();
    for (index, (spec, opened)) in config.links.iter().zip(opened).enumerate() {
        let name = &config.link_names[index];
        let link = match opened {
            Ok(link) => link,
            Err(e) => {
                print_error(&link_error_line(name, &e.to_string()));
                open_failed = true;
                continue;
            }
        };
        let mut session = config.session.clone();
        session.link_name = name.clone();
        let wire = capacity::for_link(spec, &config.link_options, &session);
        if let Some(w) = wire.and_then(|w| w.warning(1.0 / session.interval.as_secs_f64())) {
            let _ = writeln!(io::stderr(), "mavping: warning: {name}: {w}");
        }
        runs.push(LinkRun {
            index,
            spec,
            link,
            session,
            wire,
        });
    }
    // Not locked: the live view draws to stdout from its own thread.
    let stdout = Shared::new(BufWriter::new(io::stdout()));
    let live = config.live && io::stdout().is_terminal();
    if config.live && !live {
        let _ = writeln!(
            io::stderr(),
            "mavping: --live needs a terminal; printing text"
        );
    }
    let mut view = None;
    if live {
        match LiveLinks::start(stop.clone()) {
            Ok(v) => view = Some(v),
            Err(e) => {
                print_error(&format!("--live: {e}"));
                return exit::ERROR;
            }
        }
    }
    let mut reports: Vec<Fanout<'_>> = Vec::new();
    for run in &runs {
        let name = &run.session.link_name;
        let main: Box<dyn Reporter> = match (config.format, &view) {
            // The view shows the run; the text summaries follow it.
            (Format::Text, Some(view)) => Box::new(LinkLive {
                view: view.link(),
                summary: TextReporter::new(stdout.clone(), true),
            }),
            (Format::Text, None) => Box::new(LinkText {
                events: TextReporter::new(
                    Prefixed::new(stdout.clone(), format!("[{name}] ")),
                    config.quiet,
                )
                .every_reply(config.every_reply),
                summary: TextReporter::new(stdout.clone(), config.quiet),
            }),
            (Format::Json, _) => Box::new(
                JsonReporter::new(stdout.clone(), config.quiet, wall).with_link(name.clone()),
            ),
        };
        let mut reporters = vec![main];
        if let Some(file) = &samples {
            reporters.push(Box::new(
                SampleLog::new(file.clone()).for_link(name, reports.is_empty()),
            ));
        }
        if let Some(p) = &prometheus {
            reporters.push(Box::new(p.link(reports.len())));
        }
        reports.push(Fanout { reporters });
    }
    // Each session gets its own stop signal, all raised by the one.
    let stops: Vec<Arc<Notify>> = runs.iter().map(|_| Arc::new(Notify::new())).collect();
    let forward = stops.clone();
    tokio::spawn(async move {
        stop.notified().await;
        for s in &forward {
            s.notify_one();
        }
    });
    let mut done = Vec::new();
    let mut futures = Vec::new();
    for ((run, report), stop) in runs.into_iter().zip(reports.iter_mut()).zip(stops) {
        done.push((run.index, run.wire));
        // Under the live view, error lines wait until it is closed.
        futures.push(run_link(config, run, wall, report, stop, view.is_none()));
    }
    let outcomes = join_all(futures).await;
    if let Some(mut view) = view {
        if let Err(e) = view.close() {
            print_error(&format!("--live: {e}"));
        }
        for outcome in &outcomes {
            if let Some(e) = &outcome.summary.link_error {
                print_error(&link_error_line(&outcome.summary.link, e));
            }
        }
    }
    let mut codes = Vec::new();
    let mut output_closed = false;
    let mut finished = Vec::new();
    for ((mut outcome, mut report), (index, wire)) in outcomes.into_iter().zip(reports).zip(done) {
        if let Some(w) = wire {
            capacity::apply(&mut outcome.summary, w);
        }
        let verdict = verdict::judge(&outcome.summary, &thresholds_of(config, index));
        // Quiet summaries are not preceded by a blank line: separate them.
        let separate = config.format == Format::Text && (config.quiet || live);
        if separate && !finished.is_empty() {
            output_closed |= writeln!(stdout.clone()).is_err();
        }
        output_closed |=
            outcome.output_closed || report.summary(&outcome.summary, &verdict).is_err();
        codes.push(verdict.exit_code);
        finished.push(outcome);
    }
    if open_failed {
        codes.push(exit::ERROR);
    }
    if let Some(path) = &config.hgrm {
        if let Err(e) = app::write_hgrm(path, &finished) {
            print_error(&e);
            return exit::ERROR;
        }
    }
    let code = overall_exit(codes);
    // A closed stdout (`| head`) is the reader's choice, not a failure.
    if output_closed && code != exit::ERROR {
        exit::OK
    } else {
        code
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn any_link_error_makes_the_run_an_error() {
        assert_eq!(overall_exit([exit::OK, exit::OK]), exit::OK);
        assert_eq!(overall_exit([exit::OK, exit::FAILED]), exit::FAILED);
        assert_eq!(
            overall_exit([exit::FAILED, exit::ERROR, exit::OK]),
            exit::ERROR
        );
    }

    #[test]
    fn error_lines_name_the_link_once() {
        assert_eq!(
            link_error_line("udpout:127.0.0.1:9", "udp link failed: refused"),
            "udpout:127.0.0.1:9: udp link failed: refused"
        );
        assert_eq!(
            link_error_line(
                "serial:/dev/x:57600",
                "cannot open serial:/dev/x:57600: gone"
            ),
            "cannot open serial:/dev/x:57600: gone"
        );
    }

    #[tokio::test]
    async fn join_all_keeps_the_input_order() {
        let futures: Vec<_> = [3u64, 1, 2]
            .into_iter()
            .map(|n| async move {
                for _ in 0..n {
                    tokio::task::yield_now().await;
                }
                n
            })
            .collect();
        assert_eq!(join_all(futures).await, vec![3, 1, 2]);
    }
}
