use std::process::ExitCode;

use clap::Parser;

fn main() -> ExitCode {
    match mavping::cli::Cli::try_parse() {
        Ok(cli) => mavping::app::main(&cli),
        Err(error) => mavping::app::usage_error(&error),
    }
}
