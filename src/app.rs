//! From a validated [`Config`] to an exit code: runtime, logging, signals,
//! link, probe, report.

use std::io::{self, Write};
use std::process::ExitCode;
use std::sync::Arc;
use std::time::{SystemTime, UNIX_EPOCH};

use tokio::sync::Notify;

use crate::config::Config;
use crate::engine::session::{self, Outcome};
use crate::output::text::TextReporter;
use crate::probe::ping::PingProbe;
use crate::transport::Link;

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
    let mut link = match Link::open(&config.link, &config.link_options).await {
        Ok(link) => link,
        Err(e) => {
            print_error(&e);
            return exit::ERROR;
        }
    };
    let wall_start_us = SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map(|d| d.as_micros() as u64)
        .unwrap_or(0);
    let stdout = io::stdout().lock();
    let mut reporter = TextReporter::new(stdout, config.quiet);
    let outcome = session::run(
        &config.session,
        &mut link,
        PingProbe::new(wall_start_us),
        &mut reporter,
        stop,
    )
    .await;
    if let Some(e) = &outcome.summary.link_error {
        print_error(e);
    }
    exit_code(&outcome)
}

/// Runs mavping with a validated configuration.
pub fn run(config: Config) -> ExitCode {
    init_logging(config.verbose);
    let mut builder = tokio::runtime::Builder::new_current_thread();
    builder.enable_all();
    if config.virtual_clock() {
        builder.start_paused(true);
    }
    let runtime = match builder.build() {
        Ok(rt) => rt,
        Err(e) => {
            print_error(&format!("cannot start the async runtime: {e}"));
            return ExitCode::from(exit::ERROR);
        }
    };
    ExitCode::from(runtime.block_on(run_ping(&config)))
}
