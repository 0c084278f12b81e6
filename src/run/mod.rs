//! From parsed arguments to how the run ended: validation, logging, the
//! runtime, signals, then a measurement ([`measure`]), a responder
//! ([`respond`]) or the Prometheus exporter ([`serve`]). `main` turns the
//! [`Ending`] into the exit code.

mod exports;
pub(crate) mod generate;
mod measure;
mod one_link;
mod respond;
mod serve;
mod signals;

pub use serve::handler_for as serve_handler;

use std::future::Future;
use std::io;

use crate::cli::{self, Cli, Mode};
use crate::config::{Config, RespondConfig, ServeConfig};
use crate::engine::session::Controls;
use crate::exit::Ending;
use crate::stderr;

/// Where to start when no connection is given, as `ping` shows usage.
const EXAMPLES: &str = "for example:
  mavping udp:127.0.0.1:14550          listen where a vehicle, SITL or router sends
  mavping udpout:192.168.1.10:14550    send to a system that listens
  mavping serial:/dev/ttyUSB0:57600    a telemetry radio
(see --help)";

/// A command-line parse error on one line (`mavping: ...`), as every
/// other usage error, with clap's suggestion when it has one ("did you
/// mean"); help and version print as clap prints them. A missing
/// connection gets examples.
pub fn usage_error(error: &clap::Error) -> Ending {
    use clap::error::{ContextKind, ErrorKind};
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
    let missing: Vec<String> = match error.get(ContextKind::InvalidArg) {
        Some(clap::error::ContextValue::Strings(names)) => names.clone(),
        Some(clap::error::ContextValue::String(name)) => vec![name.clone()],
        _ => Vec::new(),
    };
    if error.kind() == ErrorKind::MissingRequiredArgument {
        let names: Vec<&str> = missing
            .iter()
            .map(|n| n.trim_end_matches("...").trim_matches(['<', '>']))
            .collect();
        let names = names.join(", ");
        let respond = error.render().to_string().contains("mavping respond");
        if names == "CONNECTION" && respond {
            stderr::error(&format_args!(
                "missing CONNECTION: where to answer, for example:\n  \
                 mavping respond udpin:0.0.0.0:14550\n(see mavping respond --help)"
            ));
        } else if names == "CONNECTION" {
            stderr::error(&format_args!(
                "missing CONNECTION: where to ping, {EXAMPLES}"
            ));
        } else {
            stderr::error(&format_args!("missing {names} (see --help)"));
        }
        return Ending::Refused;
    }
    let text = error.render().to_string();
    let line = text.lines().next().unwrap_or("bad arguments");
    let line = line.strip_prefix("error: ").unwrap_or(line);
    // clap's "tip: a similar argument exists: '--count'" lines.
    let tips: Vec<&str> = text
        .lines()
        .filter_map(|l| l.trim().strip_prefix("tip: "))
        .collect();
    if tips.is_empty() {
        stderr::error(&format_args!("{line} (see --help)"));
    } else {
        stderr::error(&format_args!("{line}; {} (see --help)", tips.join("; ")));
    }
    Ending::Refused
}

fn init_logging(verbose: u8) {
    use tracing_subscriber::filter::Targets;
    use tracing_subscriber::layer::SubscriberExt;
    use tracing_subscriber::util::SubscriberInitExt;
    let default = match verbose {
        0 => "warn",
        1 => "info",
        2 => "debug",
        _ => "trace",
    };
    // `target=level` lists (RUST_LOG's common form) without EnvFilter's
    // span and field matching, whose regex engine was 1.05 MB of the
    // 7.64 MB static binary; a list that does not parse falls back to the
    // default.
    let filter = std::env::var("MAVPING_LOG")
        .ok()
        .and_then(|spec| spec.parse::<Targets>().ok())
        .unwrap_or_else(|| default.parse().unwrap_or_default());
    let fmt = tracing_subscriber::fmt::layer()
        .with_writer(io::stderr)
        // Colour only for a person at a terminal, not in a log file.
        .with_ansi(io::IsTerminal::is_terminal(&io::stderr()));
    let _ = tracing_subscriber::registry()
        .with(fmt)
        .with(filter)
        .try_init();
}

/// Runs `run` on a current-thread runtime (paused for a virtual clock)
/// against the signals: the first Ctrl-C stops it, a second abandons it.
fn block_on<F, R>(paused: bool, run: F) -> Ending
where
    F: FnOnce(Controls) -> R,
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
    let controls = Controls::default();
    let run = run(controls.clone());
    // A LocalSet: the HTTP server's handlers run sessions, which stay on
    // this one thread.
    let ending = tokio::task::LocalSet::new().block_on(&runtime, async move {
        tokio::select! {
            biased;
            () = signals::watch(controls) => Ending::InterruptedTwice,
            ending = run => ending,
        }
    });
    // A read of standard input may still be blocked on the blocking pool
    // (a telemetry log on a pipe that went quiet): do not wait for it.
    runtime.shutdown_background();
    ending
}

/// Answers the shell's completion request, when this run is one
/// (`COMPLETE=bash mavping -- ...`, set by the completion scripts).
pub fn completion() -> Option<Ending> {
    let env = clap_complete::CompleteEnv::with_factory(cli::command)
        .var(generate::COMPLETE_VAR)
        .completer("mavping");
    let current_dir = std::env::current_dir().ok();
    match env.try_complete(std::env::args_os(), current_dir.as_deref()) {
        Ok(true) => Some(Ending::Done),
        Ok(false) => None,
        Err(e) => Some(usage_error(&e)),
    }
}

/// Validates, then runs what the command line asks for.
pub fn main(cli: &Cli) -> Ending {
    if let Some(kind) = cli.generate {
        return match generate::generate(kind, &mut io::stdout()) {
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
            Ok(config) if config.check => serve::check(&config),
            Ok(config) => {
                init_logging(config.verbose);
                let config = std::rc::Rc::new(config);
                block_on(false, |controls| async move {
                    serve::run(config, controls).await
                })
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
                block_on(paused, |controls| async move {
                    measure::run(&config, controls).await
                })
            }
            Err(e) => {
                stderr::error(&e);
                Ending::Refused
            }
        },
    }
}
