//! How a command line that does not parse is told: one line, clap's
//! suggestion when it has one, examples when the connection is missing.

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
