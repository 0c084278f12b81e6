//! The log on standard error (`-v`, `MAVPING_LOG`): what level, which
//! targets, colour only at a terminal.

use std::io;

pub(super) fn init_logging(verbose: u8) {
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
