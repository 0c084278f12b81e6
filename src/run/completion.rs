//! The shell's completion requests (`COMPLETE=bash mavping -- ...`),
//! answered before any run.

use super::generate;
use super::usage::usage_error;
use crate::cli;
use crate::exit::Ending;

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
