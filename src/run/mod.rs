//! From parsed arguments to how the run ended: validation, logging, the
//! runtime, signals, then a measurement ([`ping`]), a responder
//! ([`respond`]) or the Prometheus exporter ([`serve`]). `main` turns the
//! [`Ending`] into the exit code.

mod exports;
mod measure;
mod ping;
mod respond;
mod serve;
mod signals;

use std::future::Future;
use std::io::{self, Write};
use std::sync::Arc;

use clap::CommandFactory;
use tokio::sync::Notify;

use crate::cli::{Cli, Generate, Mode};
use crate::config::{Config, RespondConfig, ServeConfig};
use crate::exit::Ending;
use crate::stderr;

/// A command-line parse error on one line (`mavping: ...`), as every
/// other usage error; help and version print as clap prints them.
pub fn usage_error(error: &clap::Error) -> Ending {
    use clap::error::ErrorKind;
    if matches!(
        error.kind(),
        ErrorKind::DisplayHelp
            | ErrorKind::DisplayVersion
            | ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand
    ) {
        let _ = error.print();
        return if error.exit_code() == 0 {
            Ending::Done
        } else {
            Ending::Refused
        };
    }
    let text = error.render().to_string();
    let line = text.lines().next().unwrap_or("bad arguments");
    let line = line.strip_prefix("error: ").unwrap_or(line);
    stderr::error(&format_args!("{line} (see --help)"));
    Ending::Refused
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

/// Runs `run` on a current-thread runtime (paused for a virtual clock)
/// against the signals: the first Ctrl-C stops it, a second abandons it.
fn block_on<F, R>(paused: bool, run: F) -> Ending
where
    F: FnOnce(Arc<Notify>) -> R,
    R: Future<Output = Ending>,
{
    let mut builder = tokio::runtime::Builder::new_current_thread();
    builder.enable_all();
    if paused {
        builder.start_paused(true);
    }
    let runtime = match builder.build() {
        Ok(rt) => rt,
        Err(e) => {
            stderr::error(&format_args!("cannot start the async runtime: {e}"));
            return Ending::Refused;
        }
    };
    let stop = Arc::new(Notify::new());
    let run = run(stop.clone());
    // A LocalSet: the HTTP server's handlers run sessions, which stay on
    // this one thread.
    tokio::task::LocalSet::new().block_on(&runtime, async move {
        tokio::select! {
            biased;
            () = signals::stop_then_leave(stop) => Ending::InterruptedTwice,
            ending = run => ending,
        }
    })
}

/// Validates, then runs what the command line asks for.
pub fn main(cli: &Cli) -> Ending {
    if let Some(kind) = cli.generate {
        return match generate(kind, &mut io::stdout()) {
            Ok(()) => Ending::Done,
            Err(e) => {
                stderr::error(&e);
                Ending::Refused
            }
        };
    }
    match &cli.mode {
        Some(Mode::Respond(args)) => match RespondConfig::try_from(args) {
            Ok(config) => {
                init_logging(config.verbose);
                let paused = config.link.is_virtual();
                block_on(
                    paused,
                    |stop| async move { respond::run(&config, stop).await },
                )
            }
            Err(e) => {
                stderr::error(&e);
                Ending::Refused
            }
        },
        Some(Mode::Serve(args)) => match ServeConfig::try_from(args) {
            Ok(config) => {
                init_logging(config.verbose);
                block_on(false, |stop| async move { serve::run(&config, stop).await })
            }
            Err(e) => {
                stderr::error(&e);
                Ending::Refused
            }
        },
        None => match Config::try_from(&cli.ping) {
            Ok(config) => {
                init_logging(config.verbose);
                let paused = config.virtual_clock();
                block_on(paused, |stop| async move { ping::run(&config, stop).await })
            }
            Err(e) => {
                stderr::error(&e);
                Ending::Refused
            }
        },
    }
}
