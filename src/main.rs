use std::process::ExitCode;

use clap::Parser;

fn main() -> ExitCode {
    let cli = mavping::cli::Cli::parse();
    match mavping::config::Config::try_from(&cli.ping) {
        Ok(config) => mavping::app::run(config),
        Err(e) => {
            mavping::app::print_error(&e);
            ExitCode::from(mavping::app::exit::ERROR)
        }
    }
}
