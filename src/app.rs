//! From a validated [`Config`] to an exit code: runtime, logging, signals,
//! link, probe, report.

use std::io::{self, Write};
use std::process::ExitCode;
use std::sync::Arc;
use std::time::{SystemTime, UNIX_EPOCH};

use tokio::sync::Notify;

use crate::cli::{Cli, Mode};
use crate::config::{Config, Probe, RespondConfig};
use crate::engine::command_session;
use crate::engine::session::{self, Outcome};
use crate::output::text::TextReporter;
use crate::probe::ping::PingProbe;
use crate::probe::timesync::TimesyncProbe;
use crate::respond;
use crate::transport::{Link, LinkSpec};

/// Exit codes, as ping and fping use them.
pub mod exit {
    /// Every expectation held.
    pub const OK: u8 = 0;
    /// No reply at all (or, later, a threshold broken).
    pub const NO_REPLY: u8 = 1;
    /// Usage error, or the link could not be opened or failed.
    pub const ERROR: u8 = 2;
    /// A second Ctrl-C: leave at once, as shells expect (128 + SIGINT).
    pub const INTERRUPTED_TWICE: i32 = 130;
}

/// Prints one error line on stderr, in the same form everywhere.
pub fn print_error(error: &dyn std::fmt::Display) {
    let _ = writeln!(io::stderr(), "mavping: {error}");
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
fn watch_signals(stop: Arc<Notify>) {
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
                std::process::exit(exit::INTERRUPTED_TWICE);
            }
        }
    });
}

fn exit_code(outcome: &Outcome) -> u8 {
    if outcome.summary.link_error.is_some() {
        exit::ERROR
    } else if outcome.output_closed || outcome.summary.any_reply() {
        exit::OK
    } else {
        exit::NO_REPLY
    }
}

async fn run_ping(config: &Config) -> u8 {
    let stop = Arc::new(Notify::new());
    watch_signals(stop.clone());
    let mut link = match Link::open(&config.link).await {
        Ok(link) => link,
        Err(e) => {
            print_error(&e);
            return exit::ERROR;
        }
    };
    let wall_start_ns = SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map(|d| d.as_nanos() as u64)
        .unwrap_or(0);
    let stdout = io::stdout().lock();
    let mut reporter = TextReporter::new(stdout, config.quiet);
    let outcome = match &config.probe {
        Probe::Ping => {
            let probe = PingProbe::new(wall_start_ns / 1_000);
            session::run(&config.session, &mut link, probe, &mut reporter, stop).await
        }
        Probe::Timesync { target } => {
            // The simulated link has no wall clock: its responders count
            // from its start, and so do we there (reproducible output).
            let base = if matches!(config.link, LinkSpec::Sim(_)) {
                0
            } else {
                wall_start_ns
            };
            let probe = TimesyncProbe::new(base, *target);
            session::run(&config.session, &mut link, probe, &mut reporter, stop).await
        }
        Probe::Command(spec) => {
            let outcome =
                command_session::run(&config.session, spec, &mut link, &mut reporter, stop).await;
            if let Some(e) = &outcome.summary.link_error {
                print_error(e);
            }
            return outcome.exit_code();
        }
    };
    if let Some(e) = &outcome.summary.link_error {
        print_error(e);
    }
    exit_code(&outcome)
}

async fn run_respond(config: &RespondConfig) -> u8 {
    let stop = Arc::new(Notify::new());
    watch_signals(stop.clone());
    let mut link = match Link::open(&config.link).await {
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
    let result = match &cli.mode {
        Some(Mode::Respond(args)) => RespondConfig::try_from(args).map(respond),
        None => Config::try_from(&cli.ping).map(run),
    };
    result.unwrap_or_else(|e| {
        print_error(&e);
        ExitCode::from(exit::ERROR)
    })
}
