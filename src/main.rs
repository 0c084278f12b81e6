use std::process::ExitCode;

use clap::Parser;

fn main() -> ExitCode {
    mavping::app::main(&mavping::cli::Cli::parse())
}
