use std::process::ExitCode;

use clap::FromArgMatches;
use mavping::{cli, exit, run};

fn main() -> ExitCode {
    if let Some(ending) = run::completion() {
        return ExitCode::from(exit::code(&ending));
    }
    let parsed = cli::command()
        .try_get_matches()
        .and_then(|matches| cli::Cli::from_arg_matches(&matches));
    let ending = match parsed {
        Ok(cli) => run::main(&cli),
        Err(error) => run::usage_error(&error),
    };
    ExitCode::from(exit::code(&ending))
}
