use std::process::ExitCode;

use clap::Parser;
use mavping::{app, cli::Cli, config::Config, verdict::exit};

fn main() -> ExitCode {
    let cli = Cli::parse();
    if let Some(kind) = cli.generate {
        return match app::generate(kind, &mut std::io::stdout()) {
            Ok(()) => ExitCode::SUCCESS,
            Err(e) => {
                app::print_error(&e);
                ExitCode::from(exit::ERROR)
            }
        };
    }
    match Config::try_from(&cli.ping) {
        Ok(config) => app::run(config),
        Err(e) => {
            app::print_error(&e);
            ExitCode::from(exit::ERROR)
        }
    }
}
