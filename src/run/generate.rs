//! `--generate`: shell completions and the man pages, from the clap
//! definition. Completions are clap_complete's dynamic ones: the shell asks
//! `mavping` itself (`COMPLETE=bash mavping -- ...`), so connection strings
//! complete too (`udp<TAB>`, `serial:/dev/tty<TAB>`) and hidden options
//! never show.

use std::io::{self, Write};

use clap::Command;
use clap_complete::env::{Bash, Elvish, EnvCompleter, Fish, Powershell, Zsh};
use roff::{bold, italic, roman, Roff};

use crate::cli::{self, Generate};

/// The environment variable the completion scripts set.
pub(crate) const COMPLETE_VAR: &str = "COMPLETE";

pub(crate) fn generate(kind: Generate, out: &mut dyn Write) -> io::Result<()> {
    let shell: &dyn EnvCompleter = match kind {
        Generate::CompleteBash => &Bash,
        Generate::CompleteZsh => &Zsh,
        Generate::CompleteFish => &Fish,
        Generate::CompletePowershell => &Powershell,
        Generate::CompleteElvish => &Elvish,
        Generate::Man => return man_mavping(out),
        Generate::ManRespond => return man_respond(out),
        Generate::ManCompare => return man_compare(out),
    };
    shell.write_registration(COMPLETE_VAR, "mavping", "mavping", "mavping", out)
}

/// `[-c|--count COUNT]`, `[-q|--quiet]`: every option a user may give,
/// with its value.
fn synopsis(cmd: &Command, name: &str) -> Roff {
    let mut line = vec![bold(name)];
    for arg in cmd.get_arguments().filter(|a| !a.is_hide_set()) {
        if arg.is_positional() {
            continue;
        }
        let mut flag = String::new();
        if let Some(short) = arg.get_short() {
            flag.push('-');
            flag.push(short);
        }
        if let Some(long) = arg.get_long() {
            if !flag.is_empty() {
                flag.push('|');
            }
            flag.push_str("--");
            flag.push_str(long);
        }
        line.push(roman(" ["));
        line.push(bold(flag));
        let takes_value = arg.get_action().takes_values();
        if takes_value {
            let value = arg
                .get_value_names()
                .and_then(|v| v.first())
                .map_or_else(|| "VALUE".to_string(), |v| v.to_string());
            line.push(roman(" "));
            line.push(italic(value));
        }
        line.push(roman("]"));
    }
    for arg in cmd.get_positionals() {
        let value = arg
            .get_value_names()
            .and_then(|v| v.first())
            .map_or_else(|| arg.get_id().to_string(), |v| v.to_string());
        line.push(roman(" "));
        line.push(italic(value));
        if arg.get_num_args().is_some_and(|n| n.max_values() > 1) {
            line.push(roman("..."));
        }
    }
    let mut roff = Roff::new();
    roff.control("SH", ["SYNOPSIS"]).text(line);
    roff
}

/// A `.SH` section of `.TP` items.
fn items(title: &str, items: &[(&str, &str)]) -> Roff {
    let mut roff = Roff::new();
    roff.control("SH", [title]);
    for (term, what) in items {
        roff.control("TP", [])
            .text([bold(*term)])
            .text([roman(*what)]);
    }
    roff
}

fn page(
    cmd: Command,
    name: &'static str,
    usage: &str,
    examples: &[(&str, &str)],
    extra: &[Roff],
    out: &mut dyn Write,
) -> io::Result<()> {
    let man = clap_mangen::Man::new(cmd.clone().name(name).version(env!("CARGO_PKG_VERSION")));
    man.render_title(out)?;
    man.render_name_section(out)?;
    synopsis(&cmd, usage).to_writer(out)?;
    man.render_description_section(out)?;
    man.render_options_section(out)?;
    items("EXAMPLES", examples).to_writer(out)?;
    for section in extra {
        section.to_writer(out)?;
    }
    man.render_version_section(out)
}

fn see_also(page: &str) -> Roff {
    let mut roff = Roff::new();
    roff.control("SH", ["SEE ALSO"])
        .text([bold(page), roman(", and the README and docs/ of mavping")]);
    roff
}

fn man_mavping(out: &mut dyn Write) -> io::Result<()> {
    let connections = items(
        "CONNECTION STRINGS",
        &[
            (
                "udp:HOST:PORT, udpin:HOST:PORT, HOST:PORT",
                "listen; ping every system heard",
            ),
            ("udpout:HOST:PORT", "send to one address"),
            (
                "udpbcast:ADDR:PORT",
                "broadcast; hear every system on the segment",
            ),
            ("tcp:HOST:PORT, tcpout:HOST:PORT", "connect to a TCP server"),
            (
                "tcpin:HOST:PORT",
                "listen for TCP clients; ping every client",
            ),
            (
                "serial:DEVICE[:BAUD], /dev/DEVICE",
                "a serial port (--baud, default 115200)",
            ),
            ("sim:[?key=value&...]", "the built-in simulated link"),
        ],
    );
    let exit = items(
        "EXIT STATUS",
        &[
            ("0", "a responder answered on every link and every threshold held; also when standard output was closed early"),
            ("1", "no reply at all (or no system heard within --wait), an expected responder missing, or a threshold broken"),
            ("2", "usage error, an output file that cannot be written, or a link that could not be opened or failed"),
            ("130", "a second Ctrl-C or SIGTERM"),
        ],
    );
    let mut cmd = cli::command();
    cmd.build();
    page(
        cmd,
        "mavping",
        "mavping",
        cli::EXAMPLES,
        &[
            connections,
            exit,
            see_also("mavping-respond(1), mavping-compare(1)"),
        ],
        out,
    )
}

fn man_respond(out: &mut dyn Write) -> io::Result<()> {
    let mut cmd = cli::command();
    cmd.build();
    let respond = cmd
        .find_subcommand("respond")
        .cloned()
        .expect("the respond subcommand");
    let exit = items(
        "EXIT STATUS",
        &[
            (
                "0",
                "stopped by Ctrl-C or SIGTERM; the last line gives its counts",
            ),
            (
                "2",
                "usage error, or the link could not be opened or failed",
            ),
            ("130", "a second Ctrl-C or SIGTERM"),
        ],
    );
    page(
        respond,
        "mavping-respond",
        "mavping respond",
        &[
            (
                "mavping respond udpin:0.0.0.0:14550",
                "answer every pinger that sends to port 14550",
            ),
            (
                "mavping respond --delay 20ms --jitter 5ms --drop 2% udpout:10.0.0.2:14550",
                "a link emulator: hold, jitter and drop replies",
            ),
            (
                "mavping respond --no-ping serial:/dev/ttyUSB0:57600",
                "answer TIMESYNC and commands only, as ArduPilot",
            ),
            (
                "mavping respond --stream ATTITUDE@50,GLOBAL_POSITION_INT@5 --stream-drop 2% udpout:127.0.0.1:14550",
                "a vehicle's telemetry, every frame numbered, 2% of it lost",
            ),
        ],
        &[exit, see_also("mavping(1)")],
        out,
    )
}

fn man_compare(out: &mut dyn Write) -> io::Result<()> {
    let mut cmd = cli::command();
    cmd.build();
    let compare = cmd
        .find_subcommand("compare")
        .cloned()
        .expect("the compare subcommand");
    let exit = items(
        "EXIT STATUS",
        &[
            ("0", "compared (a comparison is not a check)"),
            (
                "1",
                "--fail-if-worse, and a responder's, source's or passive link's loss is higher \
                 in B, its 95 % interval above 0",
            ),
            (
                "2",
                "usage error, a file missing or not mavping's JSON lines, nothing in both \
                 files, or the report could not be written",
            ),
        ],
    );
    page(
        compare,
        "mavping-compare",
        "mavping compare",
        &[
            (
                "mavping --json -c 3000 -q udpout:10.0.0.2:14550 > monday.json",
                "save a run (the same again on Tuesday, as tuesday.json)",
            ),
            (
                "mavping compare monday.json tuesday.json",
                "loss and median RTT differences with their 95 % intervals",
            ),
            (
                "mavping --json tlog:rfd900.tlog > rfd900.json",
                "save a telemetry log's summary and flight windows",
            ),
            (
                "mavping compare --band-m 200 rfd900.json sik.json",
                "two flights: loss by distance in bands of 200 m",
            ),
            (
                "mavping compare --fail-if-worse --source 1/1 before.json after.json",
                "exit 1 when 1/1 loses more in after.json",
            ),
        ],
        &[exit, see_also("mavping(1)")],
        out,
    )
}
