use std::process::ExitCode;

use clap::Parser;
use mavping::{cli::Cli, exit, run};

fn main() -> ExitCode {
    let ending = match Cli::try_parse() {
        Ok(cli) => run::main(&cli),
        Err(error) => run::usage_error(&error),
    };
    ExitCode::from(exit::code(&ending))
}
