//! From a validated [`Config`] to an exit code: runtime, logging, signals,
//! link, probe, report, verdict, exports.

use std::fs::File;
use std::io::{self, BufWriter, IsTerminal, Write};
use std::process::ExitCode;
use std::sync::Arc;
use std::time::{SystemTime, UNIX_EPOCH};

use clap::CommandFactory;
use tokio::sync::Notify;

use crate::cli::{Cli, Format, Generate, Mode};
use crate::config::{Config, Probe, RespondConfig};
use crate::engine::session::{self, Outcome};
use crate::engine::{capacity, command_session};
use crate::multilink;
use crate::output::json::JsonReporter;
use crate::output::live::LiveReporter;
use crate::output::plot::PlotReporter;
use crate::output::prometheus::PrometheusReporter;
use crate::output::samples::SampleLog;
use crate::output::text::TextReporter;
use crate::output::{hgrm, Fanout, Reporter, WallClock};
use crate::probe::ping::PingProbe;
use crate::probe::timesync::TimesyncProbe;
use crate::respond;
use crate::transport::{Link, LinkSpec};
use crate::verdict::{self, exit};

/// A second Ctrl-C leaves at once, as shells expect (128 + SIGINT).
const INTERRUPTED_TWICE: i32 = 130;

/// Prints one error line on stderr, in the same form everywhere.
pub fn print_error(error: &dyn std::fmt::Display) {
    let _ = writeln!(io::stderr(), "mavping: {error}");
}

/// A command-line parse error on one line (`mavping: ...`, exit 2), as
/// every other usage error; help and version print as clap prints them.
pub fn usage_error(error: &clap::Error) -> ExitCode {
    use clap::error::ErrorKind;
    if matches!(
        error.kind(),
        ErrorKind::DisplayHelp
            | ErrorKind::DisplayVersion
            | ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand
    ) {
        let _ = error.print();
        return ExitCode::from(u8::try_from(error.exit_code()).unwrap_or(2));
    }
    let text = error.render().to_string();
    let line = text.lines().next().unwrap_or("bad arguments");
    let line = line.strip_prefix("error: ").unwrap_or(line);
    print_error(&format_args!("{line} (see --help)"));
    ExitCode::from(exit::ERROR)
}

/// `--generate`: completions and the man page, from the clap definition.
pub fn generate(kind: Generate, out: &mut dyn Write) -> io::Result<()> {
    use clap_complete::Shell;
    let mut cmd = Cli::command();
    let shell = match kind {
        Generate::CompleteBash => Shell::Bash,
        Generate::CompleteZsh => Shell::Zsh,
        Generate::CompleteFish => Shell::Fish,
        Generate::CompletePowershell => Shell::PowerShell,
        Generate::CompleteElvish => Shell::Elvish,
        Generate::Man => return clap_mangen::Man::new(cmd).render(out),
    };
    clap_complete::generate(shell, &mut cmd, "mavping", out);
    Ok(())
}

fn init_logging(verbose: u8) {
    use tracing_subscriber::EnvFilter;
    let default = match verbose {
        0 => "warn",
        1 => "info",
        2 => "debug",
        _ => "trace",
    };
    let filter = EnvFilter::try_from_env("MAVPING_LOG").unwrap_or_else(|_| EnvFilter::new(default));
    let _ = tracing_subscriber::fmt()
        .with_env_filter(filter)
        .with_writer(io::stderr)
        .try_init();
}

/// First Ctrl-C (or SIGTERM): stop and print the summary. Second: leave now.
pub(crate) fn watch_signals(stop: Arc<Notify>) {
    tokio::spawn(async move {
        #[cfg(unix)]
        let mut term =
            tokio::signal::unix::signal(tokio::signal::unix::SignalKind::terminate()).ok();
        for round in 0..2 {
            #[cfg(unix)]
            let terminated = async {
                match term.as_mut() {
                    Some(t) => {
                        t.recv().await;
                    }
                    None => std::future::pending().await,
                }
            };
            #[cfg(not(unix))]
            let terminated = std::future::pending::<()>();
            tokio::select! {
                r = tokio::signal::ctrl_c() => if r.is_err() { return },
                _ = terminated => {}
            }
            if round == 0 {
                stop.notify_one();
            } else {
                std::process::exit(INTERRUPTED_TWICE);
            }
        }
    });
}

pub(crate) fn create(path: &std::path::Path, what: &str) -> Result<BufWriter<File>, String> {
    File::create(path)
        .map(BufWriter::new)
        .map_err(|e| format!("cannot write {what} {}: {e}", path.display()))
}

/// Every link's responders, one section each, in one file.
pub(crate) fn write_hgrm<'a>(
    path: &std::path::Path,
    outcomes: impl IntoIterator<Item = &'a Outcome>,
) -> Result<(), String> {
    let mut out = create(path, "--hgrm")?;
    for outcome in outcomes {
        for (id, hist) in &outcome.histograms {
            hgrm::write_section(&mut out, &outcome.summary.link, *id, hist)
                .map_err(|e| format!("cannot write --hgrm {}: {e}", path.display()))?;
        }
    }
    out.flush()
        .map_err(|e| format!("cannot write --hgrm {}: {e}", path.display()))
}

/// `--prometheus`: serving before the link opens, so a port in use fails
/// before anything is sent.
pub(crate) fn prometheus(config: &Config) -> Result<Option<PrometheusReporter>, String> {
    let Some(addr) = config.prometheus else {
        return Ok(None);
    };
    let (exporter, bound) = std::net::TcpListener::bind(addr)
        .and_then(PrometheusReporter::serve)
        .map_err(|e| format!("--prometheus {addr}: {e}"))?;
    // Says the port when 0 was asked for; scripts and tests read it.
    let _ = writeln!(
        io::stderr(),
        "mavping: serving metrics at http://{bound}/metrics"
    );
    Ok(Some(exporter))
}

/// `--prometheus` and `--plot`, set up before the link opens so a port in
/// use or a bad path fails before anything is sent.
fn views(config: &Config) -> Result<Vec<Box<dyn Reporter>>, String> {
    let mut views: Vec<Box<dyn Reporter>> = Vec::new();
    if let Some(exporter) = prometheus(config)? {
        views.push(Box::new(exporter));
    }
    if let Some(path) = &config.plot {
        let file = create(path, "--plot")?;
        views.push(Box::new(PlotReporter::new(
            file,
            path.display().to_string(),
        )));
    }
    Ok(views)
}

async fn run_ping(config: &Config) -> u8 {
    if config.links.len() > 1 {
        return multilink::run(config).await;
    }
    let stop = Arc::new(Notify::new());
    watch_signals(stop.clone());
    // Exports are opened before the link, so a bad path fails before we ping.
    let samples = match config.samples.as_deref().map(|p| create(p, "--samples")) {
        Some(Err(e)) => {
            print_error(&e);
            return exit::ERROR;
        }
        Some(Ok(file)) => Some(file),
        None => None,
    };
    let views = match views(config) {
        Ok(views) => views,
        Err(e) => {
            print_error(&e);
            return exit::ERROR;
        }
    };
    let mut link = match Link::open(config.link(), &config.link_options).await {
        Ok(link) => link,
        Err(e) => {
            print_error(&e);
            return exit::ERROR;
        }
    };
    let wall = WallClock {
        start: if config.virtual_clock() {
            UNIX_EPOCH
        } else {
            SystemTime::now()
        },
    };
    if let Probe::Command(spec) = &config.probe {
        // A command a second at most: line-buffered output is fine here.
        let stdout = io::stdout().lock();
        let outcome = match config.format {
            Format::Text => {
                let mut report = TextReporter::new(stdout, config.quiet);
                command_session::run(&config.session, spec, &mut link, &mut report, stop).await
            }
            Format::Json => {
                let mut report = JsonReporter::new(stdout, config.quiet, wall);
                command_session::run(&config.session, spec, &mut link, &mut report, stop).await
            }
        };
        if let Some(e) = &outcome.summary.link_error {
            print_error(e);
        }
        return outcome.exit_code();
    }
    let live = config.live && io::stdout().is_terminal();
    if config.live && !live {
        let _ = writeln!(
            io::stderr(),
            "mavping: --live needs a terminal; printing text"
        );
    }
    let wire = capacity::for_link(config.link(), &config.link_options, &config.session);
    if let Some(w) = wire.and_then(|w| w.warning(1.0 / config.session.interval.as_secs_f64())) {
        let _ = writeln!(io::stderr(), "mavping: warning: {w}");
    }
    let main: Box<dyn Reporter> = match config.format {
        // The view draws from its own thread: stdout must not be locked here.
        Format::Text if live => Box::new(LiveReporter::new(stop.clone())),
        // Buffered: a write per line would pace the engine at high rates.
        // The session flushes before it blocks and every 50 ms while busy.
        Format::Text => Box::new(
            TextReporter::new(BufWriter::new(io::stdout().lock()), config.quiet)
                .every_reply(config.every_reply),
        ),
        Format::Json => Box::new(JsonReporter::new(
            BufWriter::new(io::stdout().lock()),
            config.quiet,
            wall,
        )),
    };
    let mut reporters = vec![main];
    if let Some(file) = samples {
        reporters.push(Box::new(SampleLog::new(file)));
    }
    reporters.extend(views);
    let mut report = Fanout { reporters };
    let outcome = match &config.probe {
        Probe::Timesync { target } => {
            // The simulated link has no wall clock: its responders count
            // from its start, and so do we there (reproducible output).
            let base = if matches!(config.link(), LinkSpec::Sim(_)) {
                0
            } else {
                wall.micros_since_epoch() * 1_000
            };
            let probe = TimesyncProbe::new(base, *target);
            session::run(&config.session, &mut link, probe, &mut report, stop).await
        }
        _ => {
            let probe = PingProbe::new(wall.micros_since_epoch());
            session::run(&config.session, &mut link, probe, &mut report, stop).await
        }
    };
    // The simulated link's ground truth, for soak scripts (`-v`).
    if let Link::Sim(sim) = &link {
        for (id, t) in sim.truth() {
            tracing::info!(
                "sim truth {id}: answered={} dropped={} dropped_before_first={} delivered={} \
                 duplicated={} outage={} spiked={} spiked_before_first={}",
                t.answered,
                t.dropped,
                t.dropped_before_first,
                t.delivered,
                t.duplicated,
                t.outage,
                t.spiked,
                t.spiked_before_first
            );
        }
    }
    let mut outcome = outcome;
    if let Some(w) = wire {
        capacity::apply(&mut outcome.summary, w);
    }
    let verdict = verdict::judge(&outcome.summary, &config.thresholds);
    let output_closed =
        outcome.output_closed || report.summary(&outcome.summary, &verdict).is_err();
    if let Some(e) = &outcome.summary.link_error {
        print_error(e);
    }
    if let Some(path) = &config.hgrm {
        if let Err(e) = write_hgrm(path, [&outcome]) {
            print_error(&e);
            return exit::ERROR;
        }
    }
    // A closed stdout (`| head`) is the reader's choice, not a failure.
    if output_closed && verdict.exit_code != exit::ERROR {
        exit::OK
    } else {
        verdict.exit_code
    }
}

async fn run_respond(config: &RespondConfig) -> u8 {
    let stop = Arc::new(Notify::new());
    watch_signals(stop.clone());
    let mut link = match Link::open(&config.link, &config.link_options).await {
        Ok(link) => link,
        Err(e) => {
            print_error(&e);
            return exit::ERROR;
        }
    };
    let mut out = io::stdout().lock();
    // Printed once the link is open: a test (or a person) knows from it
    // that requests will be heard.
    let _ = writeln!(
        out,
        "{}",
        respond::describe(config, &config.link.to_string())
    );
    let _ = out.flush();
    let (counts, error) = respond::run(config, &mut link, stop).await;
    let _ = writeln!(out, "respond {}: {counts}", config.id);
    let _ = out.flush();
    match error {
        Some(e) => {
            print_error(&e);
            exit::ERROR
        }
        None => exit::OK,
    }
}

fn runtime(paused: bool) -> Option<tokio::runtime::Runtime> {
    let mut builder = tokio::runtime::Builder::new_current_thread();
    builder.enable_all();
    if paused {
        builder.start_paused(true);
    }
    match builder.build() {
        Ok(rt) => Some(rt),
        Err(e) => {
            print_error(&format!("cannot start the async runtime: {e}"));
            None
        }
    }
}

/// Runs mavping with a validated configuration.
pub fn run(config: Config) -> ExitCode {
    init_logging(config.verbose);
    let Some(runtime) = runtime(config.virtual_clock()) else {
        return ExitCode::from(exit::ERROR);
    };
    ExitCode::from(runtime.block_on(run_ping(&config)))
}

/// Runs `mavping respond` with a validated configuration.
pub fn respond(config: RespondConfig) -> ExitCode {
    init_logging(config.verbose);
    let paused = matches!(&config.link, LinkSpec::Sim(p) if p.virtual_clock);
    let Some(runtime) = runtime(paused) else {
        return ExitCode::from(exit::ERROR);
    };
    ExitCode::from(runtime.block_on(run_respond(&config)))
}

/// From parsed arguments to an exit code: validates, then runs the mode.
pub fn main(cli: &Cli) -> ExitCode {
    if let Some(kind) = cli.generate {
        return match generate(kind, &mut io::stdout()) {
            Ok(()) => ExitCode::SUCCESS,
            Err(e) => {
                print_error(&e);
                ExitCode::from(exit::ERROR)
            }
        };
    }
    let result = match &cli.mode {
        Some(Mode::Respond(args)) => RespondConfig::try_from(args).map(respond),
        None => Config::try_from(&cli.ping).map(run),
    };
    result.unwrap_or_else(|e| {
        print_error(&e);
        ExitCode::from(exit::ERROR)
    })
}
