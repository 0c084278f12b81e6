//! From parsed arguments to how the run ended: validation, logging, the
//! runtime, signals, then a measurement ([`measure`]), a responder
//! ([`respond`]), the Prometheus exporter ([`serve`]) or two saved runs
//! compared ([`compare`]). `main` turns the [`Ending`] into the exit code.

mod compare;
mod completion;
mod exports;
pub(crate) mod generate;
mod logging;
mod measure;
mod one_link;
mod pair;
mod respond;
mod runtime;
mod serve;
mod signals;
mod usage;

pub use completion::completion;
pub use serve::handler_for as serve_handler;
pub use usage::usage_error;

use std::io;

use crate::cli::{Cli, Mode};
use crate::config::{CompareConfig, Config, RespondConfig, ServeConfig};
use crate::exit::Ending;
use crate::stderr;
use crate::transport::LinkSpec;
use logging::init_logging;
use runtime::block_on;

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
                // Several links share a virtual clock only if all are.
                let paused = config.links.iter().all(LinkSpec::is_virtual);
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
        Some(Mode::Compare(args)) => match CompareConfig::try_from(args) {
            Ok(config) => compare::run(&config),
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
