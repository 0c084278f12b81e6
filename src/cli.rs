//! Command-line arguments as typed; [`crate::config`] validates them.

use std::path::PathBuf;
use std::time::Duration;

use clap::{ArgAction, Parser, Subcommand, ValueEnum};
use thiserror::Error;

use crate::engine::load::LoadSpec;
use crate::frame::SysComp;
use crate::telemetry::StreamSpec;
use crate::units::{parse_duration, parse_percent, DurationError};
use crate::verdict::{Expected, RttLimit, UnknownRttFigure};

/// Flags set from the environment take what people write for a yes or
/// a no (`1`, `yes`, `on`, `true`; `0`, `no`, `off`, `false`), not only
/// clap's `true`/`false`.
fn boolish() -> clap::builder::BoolishValueParser {
    clap::builder::BoolishValueParser::new()
}

/// `mavping --help` ends with examples, the connection strings and the
/// exit codes (the man page has the same).
pub(crate) const EXAMPLES: &[(&str, &str)] = &[
    (
        "mavping udp:127.0.0.1:14550",
        "listen where a SITL, vehicle or router sends; ping every system heard",
    ),
    (
        "mavping udpout:192.168.1.10:14550",
        "send to a system that listens (a router, a companion computer)",
    ),
    ("mavping serial:/dev/ttyUSB0:57600", "a SiK telemetry radio"),
    (
        "mavping -c 20 -i 100ms --json -q --max-loss 5% --max-rtt p99=50ms udp:0.0.0.0:14550",
        "a CI health check: exit 0, 1 or 2",
    ),
    (
        "mavping --probe timesync udp:127.0.0.1:14550",
        "TIMESYNC only (what ArduPilot answers; the default finds it alone); also its clock offset",
    ),
    (
        "mavping -f links.txt -Q 10s",
        "every link in a file, an interim summary every 10 s",
    ),
    (
        "mavping respond udpin:0.0.0.0:14550",
        "the other end: answer PING, TIMESYNC and commands",
    ),
];

/// Connection strings and exit codes, after the examples in `--help`.
const FORMS_AND_STATUS: &str = "\
Connection strings:
  udp:HOST:PORT, udpin:HOST:PORT or HOST:PORT  listen; ping every system heard
  udpout:HOST:PORT                             send to one address
  udpbcast:ADDR:PORT                           broadcast; hear every system on the segment
  tcp:HOST:PORT (tcpout:)                      connect; tcpin:HOST:PORT listens for clients
  serial:DEVICE[:BAUD] or /dev/DEVICE          a serial port (--baud, default 115200)
  sim:[?key=value&...]                         the built-in simulated link
  tlog:FILE, FILE.tlog or tlog:- (stdin)       a telemetry log, read on its own clock (passive)
  IPv6 hosts go in brackets: udpout:[::1]:14550. Several connections are pinged side by
  side, each with its own sequence numbers and report.

Exit status:
  0    a responder answered on every link and every threshold held
  1    no reply, an expected responder missing, or a threshold broken
  2    usage error, an output that cannot be written, or a link that could not be opened
       or failed
  130  a second Ctrl-C";

/// The command line as parsed: the derive's, with the examples, connection
/// strings and exit codes after the long help.
pub fn command() -> clap::Command {
    use clap::CommandFactory;
    let mut text = String::from("Examples:\n");
    for (line, what) in EXAMPLES {
        text.push_str(&format!("  {line}\n      {what}\n"));
    }
    text.push('\n');
    text.push_str(FORMS_AND_STATUS);
    Cli::command().after_long_help(text)
}

/// Options that take a value accept a negative number (`-i -1`), so it
/// reaches the value parser and a clear error; positionals do not, so
/// `-4` and `-6` stay flags.
#[derive(Debug, Parser)]
#[command(
    name = "mavping",
    version,
    about = "Measure MAVLink link latency and loss: ping for drones and radios",
    long_about = "Measure MAVLink link latency and loss: ping for drones and radios.\n\n\
        Sends MAVLink PING requests on a schedule over UDP, TCP, serial or a simulated link, \
        matches each reply to its request by sequence and responder, and reports per-responder \
        RTT, loss, late and duplicate replies; a responder that does not answer PING (ArduPilot \
        answers only TIMESYNC) is asked by TIMESYNC instead (--probe auto, the default). \
        --probe ping sends PING only; --probe timesync TIMESYNC only, and measures each \
        responder's clock offset and drift; \
        --probe command re-sends a COMMAND_LONG until acknowledged. `mavping respond` is the \
        other end: a MAVLink system that answers all three.",
    after_help = "Examples, connection strings and exit codes: mavping --help"
)]
#[command(args_conflicts_with_subcommands = true, subcommand_negates_reqs = true)]
pub struct Cli {
    #[command(flatten)]
    pub(crate) ping: PingArgs,

    /// Print shell completions or the man page (for packagers)
    #[arg(
        allow_negative_numbers = true,
        long,
        value_enum,
        hide = true,
        value_name = "KIND"
    )]
    pub(crate) generate: Option<Generate>,

    #[command(subcommand)]
    pub mode: Option<Mode>,
}

/// The schemes a connection string starts with, for completion.
const SCHEMES: [&str; 10] = [
    "udp:",
    "udpin:",
    "udpout:",
    "udpbcast:",
    "tcp:",
    "tcpin:",
    "tcpout:",
    "serial:",
    "tlog:",
    "sim:",
];

/// Shell completion of a connection string: the schemes, serial devices
/// (`/dev/tty*`, `/dev/serial/...`, `/dev/pts/...`) after `serial:` or for
/// a bare path, and files after `tlog:`.
pub(crate) fn complete_link(
    current: &std::ffi::OsStr,
) -> Vec<clap_complete::engine::CompletionCandidate> {
    use clap_complete::engine::CompletionCandidate;
    let current = current.to_string_lossy();
    // A log's file is looked for from the current directory, a serial
    // device's from /dev/.
    let (scheme, path, home) = if let Some(path) = current.strip_prefix("serial:") {
        ("serial:", path, "/dev/")
    } else if let Some(path) = current.strip_prefix("tlog:") {
        ("tlog:", path, "")
    } else if current.starts_with('/') {
        ("", current.as_ref(), "/dev/")
    } else {
        return SCHEMES
            .iter()
            .filter(|s| s.starts_with(current.as_ref()))
            .map(|s| CompletionCandidate::new(*s))
            .collect();
    };
    let (dir, prefix) = match path.rfind('/') {
        Some(i) => (&path[..=i], &path[i + 1..]),
        None => (home, path),
    };
    let serial_like =
        |name: &str| dir != "/dev/" || name.starts_with("tty") || name == "serial" || name == "pts";
    let Ok(entries) = std::fs::read_dir(if dir.is_empty() { "." } else { dir }) else {
        return Vec::new();
    };
    let mut out: Vec<String> = entries
        .flatten()
        .filter_map(|e| {
            let name = e.file_name().to_string_lossy().into_owned();
            let is_dir = e.file_type().is_ok_and(|t| t.is_dir());
            (name.starts_with(prefix) && serial_like(&name))
                .then(|| format!("{scheme}{dir}{name}{}", if is_dir { "/" } else { "" }))
        })
        .collect();
    out.sort();
    out.into_iter().map(CompletionCandidate::new).collect()
}

/// What is wrong with a `[FIGURE=]DURATION` RTT limit.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
pub(crate) enum RttLimitError {
    /// Not an RTT figure (the message lists them).
    #[error(transparent)]
    Figure(UnknownRttFigure),
    #[error(transparent)]
    Duration(#[from] DurationError),
}

/// `[FIGURE=]DURATION`, e.g. `p99=50ms` or `200ms` (the maximum).
pub(crate) fn parse_rtt_limit(s: &str) -> Result<RttLimit, RttLimitError> {
    let (figure, limit) = match s.split_once('=') {
        Some((figure, limit)) => (figure.parse().map_err(RttLimitError::Figure)?, limit),
        None => (crate::verdict::RttFigure::Max, s),
    };
    Ok(RttLimit {
        figure,
        limit: parse_duration(limit)?,
    })
}

/// `--expect`: a responder, on every link or on one (`LINK=ID`).
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct ExpectArg {
    /// The connection string it is scoped to, as given.
    pub(crate) link: Option<String>,
    pub(crate) id: Expected,
}

/// What is wrong with an `--expect` value; the text given is quoted.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
pub(crate) enum ExpectArgError {
    #[error("'{0}' is not LINK=SYSID or LINK=SYSID/COMPID (1-255)")]
    Scoped(String),
    #[error(transparent)]
    Id(#[from] ExpectedError),
}

/// Not `SYSID` or `SYSID/COMPID` (1-255); the text given is quoted.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
#[error("'{0}' is not SYSID or SYSID/COMPID (1-255)")]
pub(crate) struct ExpectedError(pub String);

/// `SYSID[/COMPID]`, or `LINK=SYSID[/COMPID]` for one of several links
/// (split at the last `=`, since connection strings may hold one).
pub(crate) fn parse_expect_arg(s: &str) -> Result<ExpectArg, ExpectArgError> {
    match s.rsplit_once('=') {
        Some((link, id)) if !link.is_empty() => Ok(ExpectArg {
            link: Some(link.to_string()),
            id: parse_expected(id).map_err(|_| ExpectArgError::Scoped(s.to_string()))?,
        }),
        _ => Ok(ExpectArg {
            link: None,
            id: parse_expected(s)?,
        }),
    }
}

/// `SYSID` or `SYSID/COMPID`, each 1-255.
pub(crate) fn parse_expected(s: &str) -> Result<Expected, ExpectedError> {
    let id = |part: &str| -> Result<u8, ExpectedError> {
        part.parse::<u8>()
            .ok()
            .filter(|&v| v != 0)
            .ok_or_else(|| ExpectedError(s.to_string()))
    };
    Ok(match s.split_once('/') {
        Some((sys, comp)) => Expected {
            sysid: id(sys)?,
            compid: Some(id(comp)?),
        },
        None => Expected {
            sysid: id(s)?,
            compid: None,
        },
    })
}

/// `--report`: the reports a run can add to its own.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub(crate) enum ReportKind {
    /// The command-and-control link report.
    C2,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub(crate) enum Format {
    /// Ping-like lines and a summary
    Text,
    /// Newline-delimited JSON events
    Json,
}

/// `--radio-type`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub(crate) enum RadioTypeArg {
    /// Tell them apart by their ids, HEARTBEAT, report rate and constant fields
    Auto,
    /// SiK / RFD900: dBm ~ raw / 1.9 - 127, noise a noise floor (fade margin)
    Sik,
    /// mLRS: -120..-50 dBm as 0..254, noise = 10 - SNR
    Mlrs,
    /// ExpressLRS: rssi = link quality x 2.55, remrssi = -dBm, noise = SNR
    Elrs,
    /// mavesp8266 WiFi bridge: remnoise and rxerrors are % lost
    Esp,
    /// Raw figures only: no dBm, no fade margin
    Raw,
}

impl From<RadioTypeArg> for crate::engine::radio::RadioType {
    fn from(a: RadioTypeArg) -> Self {
        use crate::engine::radio::RadioType as T;
        match a {
            RadioTypeArg::Auto => T::Auto,
            RadioTypeArg::Sik => T::Sik,
            RadioTypeArg::Mlrs => T::Mlrs,
            RadioTypeArg::Elrs => T::Elrs,
            RadioTypeArg::Esp => T::Esp,
            RadioTypeArg::Raw => T::Raw,
        }
    }
}

/// What `--generate` writes to stdout.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub(crate) enum Generate {
    CompleteBash,
    CompleteZsh,
    CompleteFish,
    CompletePowershell,
    CompleteElvish,
    /// mavping(1)
    Man,
    /// mavping-respond(1)
    ManRespond,
    /// mavping-compare(1)
    ManCompare,
}

/// Modes other than measuring.
#[derive(Debug, Subcommand)]
pub enum Mode {
    /// Be a well-behaved MAVLink system that answers PING, TIMESYNC and COMMAND_LONG and serves
    /// parameters, a mission and a file, read-only
    Respond(RespondArgs),
    /// Probe links for Prometheus: /probe?target=LINK on request (the multi-target exporter
    /// pattern) and continuous links at /metrics
    #[command(
        long_about = "Probe links for Prometheus.\n\n\
            GET /probe?target=LINK[&module=NAME][&count=N&interval=D&timeout=D&probe=KIND] runs one \
            bounded probe and answers with its metrics, within the scrape's timeout \
            (X-Prometheus-Scrape-Timeout-Seconds). Only targets the configuration allows are \
            opened (--allow, or allow = [...] in --config); with none, every target is refused. \
            Continuous links (--link, or [[link]] in --config) are probed all the time and shown \
            at /metrics with a `link` label, beside the exporter's own health. SIGHUP rereads \
            --config; running links that did not change keep going, history and all.",
        after_help = "See docs/monitoring.md for the configuration file, the metrics and a \
            Prometheus scrape configuration."
    )]
    Serve(ServeArgs),
    /// Compare two saved runs (mavping --json ... > FILE): loss and median RTT differences with
    /// 95 % intervals
    #[command(
        long_about = "Compare two saved runs: the same link on two days, radio A against radio B.\n\n\
            Reads two files of `mavping --json` lines (a probe run's summary, a passive run's or \
            a telemetry log's passive_summary), pairs their links by name (or the only summary \
            of each) and their responders or sources by SYSID/COMPID, and shows for each: loss \
            in A and B and the difference B - A with its 95 % interval (Newcombe's hybrid score \
            method); the median RTT shift B - A with a bootstrap interval from each run's RTT \
            histogram; frame ages; and for two telemetry logs, loss by distance from their flight \
            windows. Exit 0 when compared (a comparison is not a check; see --fail-if-worse), 2 \
            when a file is not mavping's JSON or nothing is in both.",
        after_help = "See docs/compare.md for the statistics and an example."
    )]
    Compare(CompareArgs),
}

/// What to send.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub(crate) enum ProbeKind {
    /// PING, and TIMESYNC to each responder that shows it does not answer PING (ArduPilot)
    Auto,
    /// MAVLink PING (PX4, QGroundControl, MAVSDK answer it)
    Ping,
    /// TIMESYNC: answered everywhere, ArduPilot included; also measures clock offset
    Timesync,
    /// COMMAND_LONG re-sent until its COMMAND_ACK arrives
    Command,
    /// Download every parameter (PARAM_REQUEST_LIST, then what it missed by index)
    Params,
    /// Download the mission (MISSION_REQUEST_LIST, then each item), read-only
    Mission,
    /// Read a file over MAVLink FTP (--path), read-only
    Ftp,
}

/// Options of a measurement run (the default command).
#[derive(Debug, clap::Args)]
pub(crate) struct PingArgs {
    /// Where to ping (several: side by side, each reported on its own)
    ///
    /// udp:HOST:PORT (listen), udpout:HOST:PORT, udpbcast:ADDR:PORT, tcp:HOST:PORT,
    /// tcpin:HOST:PORT, serial:DEVICE[:BAUD], sim:[?...], tlog:FILE; see the list below
    #[arg(
        value_name = "CONNECTION",
        env = "MAVPING_LINK",
        required_unless_present_any = ["generate", "file"],
        num_args = 1..,
        add = clap_complete::engine::ArgValueCompleter::new(complete_link)
    )]
    pub(crate) links: Vec<String>,

    /// Our MAVLink system id
    ///
    /// The header of our requests. Not 255: 255/190 is QGroundControl's and
    /// Mission Planner's, which MAVSDK-based ground stations ignore and
    /// ArduPilot's GCS failsafe listens to
    #[arg(
        help_heading = "What to send",
        allow_negative_numbers = true,
        long,
        value_name = "ID",
        default_value_t = SysComp::OURS.sysid,
        env = "MAVPING_SYSID"
    )]
    pub(crate) sysid: u8,

    /// Our MAVLink component id
    #[arg(
        help_heading = "What to send",
        allow_negative_numbers = true,
        long,
        value_name = "ID",
        default_value_t = SysComp::OURS.compid,
        env = "MAVPING_COMPID"
    )]
    pub(crate) compid: u8,

    /// MAVLink version of our requests (replies of either version are accepted)
    #[arg(help_heading = "What to send", allow_negative_numbers = true, long = "mavlink", value_name = "1|2", default_value_t = 2,
          value_parser = clap::value_parser!(u8).range(1..=2))]
    pub(crate) mavlink_version: u8,

    /// Do not send our 1 Hz GCS HEARTBEAT (MAVSDK ignores PINGs from systems it has not heard)
    #[arg(help_heading = "What to send", long)]
    pub(crate) no_heartbeat: bool,

    /// Do not answer the vehicle's TIMESYNC and PING requests (answered by default, one reply
    /// each, as a ground station does: ArduPilot and PX4 time the link by them)
    #[arg(help_heading = "What to send", long)]
    pub(crate) no_answer: bool,

    /// Sequence number of the first request (to test wrap-around)
    #[arg(
        help_heading = "What to send",
        allow_negative_numbers = true,
        long,
        value_name = "SEQ",
        default_value_t = 0,
        hide = true
    )]
    pub(crate) first_seq: u32,
    /// Send no probes: count each source's frames, losses, duplicates and silences from their
    /// packet sequence numbers (our HEARTBEAT stays on unless --no-heartbeat; implied, with
    /// nothing sent, on a tlog: link)
    #[arg(help_heading = "What to send", long, conflicts_with_all = ["probe", "count", "sweep", "load"])]
    pub(crate) passive: bool,

    /// --passive: a source silent this long is in a silence (default: 5 of its usual intervals, at least 1s)
    #[arg(help_heading = "What to send", long, value_name = "DURATION", value_parser = parse_duration)]
    pub(crate) gap: Option<Duration>,

    /// What to send: ping, timesync (also ArduPilot; measures clock offset), command, or a download: params, mission, ftp
    #[arg(help_heading = "What to send", allow_negative_numbers = true, long, value_enum, value_name = "PROBE", default_value_t = ProbeKind::Auto,
          env = "MAVPING_PROBE")]
    pub(crate) probe: ProbeKind,

    /// Address requests to SYS/COMP (timesync: default 0/0, everyone; command, params, mission, ftp: default 1/1)
    #[arg(
        help_heading = "What to send",
        allow_negative_numbers = true,
        long,
        value_name = "SYS/COMP",
        env = "MAVPING_TARGET"
    )]
    pub(crate) target: Option<String>,

    /// --probe command: MAV_CMD name or id, then up to 7 params, comma-separated
    #[arg(
        help_heading = "What to send",
        allow_negative_numbers = true,
        long,
        value_name = "CMD[,P1,...]",
        default_value = "REQUEST_MESSAGE,0"
    )]
    pub(crate) command: String,

    /// --probe command: re-send an unacknowledged command this often
    #[arg(help_heading = "What to send", allow_negative_numbers = true, long, value_name = "DURATION", value_parser = parse_duration, default_value = "100ms")]
    pub(crate) retry_interval: Duration,

    /// --probe ftp: the file to read (ArduPilot serves its parameters as @PARAM/param.pck)
    #[arg(
        help_heading = "What to send",
        long,
        value_name = "PATH",
        default_value = "@PARAM/param.pck"
    )]
    pub(crate) path: String,

    /// --probe command, params, mission, ftp: re-sends of a request before it counts as failed
    #[arg(
        help_heading = "What to send",
        allow_negative_numbers = true,
        long,
        value_name = "N",
        default_value_t = 3
    )]
    pub(crate) retries: u8,

    /// Stop after sending COUNT requests (and waiting for their replies)
    #[arg(
        help_heading = "Timing",
        allow_negative_numbers = true,
        short = 'c',
        long,
        value_name = "COUNT",
        env = "MAVPING_COUNT"
    )]
    pub(crate) count: Option<u64>,

    /// Time between requests, e.g. 1s, 100ms, 0.01
    #[arg(help_heading = "Timing", allow_negative_numbers = true, short = 'i', long, value_name = "DURATION", value_parser = parse_duration,
          conflicts_with = "rate", env = "MAVPING_INTERVAL")]
    pub(crate) interval: Option<Duration>,

    /// Requests per second (instead of --interval)
    #[arg(
        help_heading = "Timing",
        allow_negative_numbers = true,
        long,
        value_name = "HZ",
        env = "MAVPING_RATE"
    )]
    pub(crate) rate: Option<f64>,

    /// Stop after this long, whatever is still in flight
    #[arg(help_heading = "Timing", allow_negative_numbers = true, short = 'w', long, value_name = "DURATION", value_parser = parse_duration,
          env = "MAVPING_DEADLINE")]
    pub(crate) deadline: Option<Duration>,

    /// On a listening link, give up when no system is heard in DURATION
    ///
    /// On udp:, udpin: and tcpin: links. Default with -c: the time the count
    /// takes plus the timeout; without -c: wait for ever
    #[arg(help_heading = "Timing", allow_negative_numbers = true, long, value_name = "DURATION", value_parser = parse_duration, env = "MAVPING_WAIT")]
    pub(crate) wait: Option<Duration>,

    /// How long to wait for each reply before counting it lost
    #[arg(help_heading = "Timing", allow_negative_numbers = true, short = 'W', long, value_name = "DURATION", value_parser = parse_duration,
          default_value = "2s", env = "MAVPING_TIMEOUT")]
    pub(crate) timeout: Duration,

    /// Find the link's capacity: ramp the rate in steps until it loses, and name the knee
    ///
    /// Steps at 2, 5, 10, 20, 50, ... requests/s (from --rate or -i when given) up to
    /// --sweep-max, each --step long; then bisects around the knee: the highest rate that
    /// lost under 1% with a p99 under twice the first step's or less than 30 ms over it (a
    /// rate that fails on latency alone is tried once more). Grades the latency the link
    /// adds under load, A+ to F as bufferbloat tests do. Ctrl-C stops at once with the steps
    /// so far
    #[arg(help_heading = "Capacity", long)]
    pub(crate) sweep: bool,

    /// --sweep: the highest rate to offer [default: twice what a serial link's baud rate
    /// carries, else 1000]
    #[arg(
        help_heading = "Capacity",
        allow_negative_numbers = true,
        long,
        value_name = "HZ"
    )]
    pub(crate) sweep_max: Option<f64>,

    /// --sweep: stop ramping once a step loses more than PCT [default: 20%]
    #[arg(help_heading = "Capacity", allow_negative_numbers = true, long, value_name = "PCT", value_parser = parse_percent)]
    pub(crate) sweep_loss: Option<f64>,

    /// How long each step of --sweep or --load sends [default: 5s]
    #[arg(help_heading = "Capacity", allow_negative_numbers = true, long, value_name = "DURATION", value_parser = parse_duration)]
    pub(crate) step: Option<Duration>,

    /// Background load beside the probes: MSG@RATE, repeatable
    ///
    /// ATTITUDE@HZ, GLOBAL_POSITION_INT@HZ (telemetry as a vehicle sends it) or
    /// BYTES@BYTES_PER_S (filler), messages no system answers. Without --sweep: one step
    /// without the load, one with it, at --rate (default 10/s), and by how much the load
    /// raised the RTT
    #[arg(help_heading = "Capacity", allow_negative_numbers = true, long, value_name = "MSG@RATE",
          value_parser = clap::value_parser!(LoadSpec))]
    pub(crate) load: Vec<LoadSpec>,

    /// Print only the summary
    #[arg(help_heading = "Output", short = 'q', long)]
    pub(crate) quiet: bool,

    /// Quiet, and an interim summary every DURATION (also on Ctrl-\ / SIGQUIT)
    #[arg(help_heading = "Output", allow_negative_numbers = true, short = 'Q', long = "interim", value_name = "DURATION",
          value_parser = parse_duration)]
    pub(crate) interim: Option<Duration>,

    /// Start each reply and loss line with its Unix time, as ping -D
    ///
    /// [1764510000.123456] reply from 1/1: ...
    #[arg(help_heading = "Output", short = 'D', long = "timestamps")]
    pub(crate) timestamps: bool,

    /// Accepted for ping users: overdue replies are always reported
    ///
    /// A "no reply from ..." line is printed when a request's timeout passes
    #[arg(help_heading = "Output", short = 'O')]
    pub(crate) report_outstanding: bool,

    /// Print a line for every reply even above 100 requests/s (where one
    /// status line per second is printed instead)
    #[arg(help_heading = "Output", long)]
    pub(crate) every_reply: bool,

    /// More logs on stderr (-v info, -vv debug, -vvv trace); or set MAVPING_LOG
    #[arg(help_heading = "Output", short = 'v', long, action = ArgAction::Count)]
    pub(crate) verbose: u8,

    /// Output format
    #[arg(
        help_heading = "Output",
        long,
        value_enum,
        default_value = "text",
        env = "MAVPING_FORMAT"
    )]
    pub(crate) format: Format,

    /// Same as --format json: newline-delimited JSON events on stdout
    #[arg(help_heading = "Output", long)]
    pub(crate) json: bool,

    /// Write each responder's RTT distribution in HdrHistogram's .hgrm format
    #[arg(
        help_heading = "Output",
        allow_negative_numbers = true,
        long,
        value_name = "FILE"
    )]
    pub(crate) hgrm: Option<PathBuf>,

    /// Write one CSV row per reply or loss (sysid,compid,seq,sent_s,rtt_us,status, then the latest RADIO_STATUS figures)
    #[arg(
        help_heading = "Output",
        allow_negative_numbers = true,
        long,
        value_name = "FILE"
    )]
    pub(crate) samples: Option<PathBuf>,

    /// Full-screen live view (q or Ctrl-C to stop); plain text when stdout is not a terminal
    #[arg(help_heading = "Output", long, env = "MAVPING_LIVE", value_parser = boolish())]
    pub(crate) live: bool,

    /// Serve Prometheus metrics at http://ADDR:PORT/metrics while the run goes on
    #[arg(
        help_heading = "Output",
        allow_negative_numbers = true,
        long,
        value_name = "ADDR:PORT",
        env = "MAVPING_PROMETHEUS"
    )]
    pub(crate) prometheus: Option<String>,

    /// At the end, write the run's metrics to FILE.prom for node_exporter's textfile collector
    /// (written to a temporary file, then renamed: never seen half-written)
    #[arg(
        help_heading = "Output",
        allow_negative_numbers = true,
        long,
        value_name = "FILE.prom"
    )]
    pub(crate) prometheus_textfile: Option<PathBuf>,

    /// At the end, draw RTT over time and the RTT distribution to FILE.svg
    #[arg(
        help_heading = "Output",
        allow_negative_numbers = true,
        long,
        value_name = "FILE.svg"
    )]
    pub(crate) plot: Option<PathBuf>,

    /// Record every frame received and sent to FILE, a telemetry log that
    /// mavping (tlog:FILE), pymavlink and MAVProxy read
    #[arg(
        help_heading = "Output",
        allow_negative_numbers = true,
        long,
        value_name = "FILE"
    )]
    pub(crate) tlog: Option<PathBuf>,

    /// Add a report: c2, the command-and-control link report (availability, continuity,
    /// latency and loss each way, outages by duration and distance, failsafe replay)
    #[arg(
        help_heading = "C2 link report",
        allow_negative_numbers = true,
        long,
        value_name = "KIND",
        value_enum
    )]
    pub(crate) report: Option<ReportKind>,

    /// C2 report: the link is up while a frame from the vehicle came within DURATION
    #[arg(help_heading = "C2 link report", allow_negative_numbers = true, long, value_name = "DURATION", value_parser = parse_duration, default_value = "2s")]
    pub(crate) up_within: Duration,

    /// C2 report: continuity counts round trips completed within DURATION (default: -W)
    #[arg(help_heading = "C2 link report", allow_negative_numbers = true, long, value_name = "DURATION", value_parser = parse_duration)]
    pub(crate) continuity_within: Option<Duration>,

    /// C2 report: the width of the distance bands, metres
    #[arg(
        help_heading = "C2 link report",
        allow_negative_numbers = true,
        long,
        value_name = "METRES",
        default_value_t = crate::engine::c2::DEFAULT_DISTANCE_BAND_M
    )]
    pub(crate) distance_band: f64,

    /// C2 report: replay a failsafe: ardupilot-copter, ardupilot-plane, ardupilot-rover, px4
    /// (settings changed as px4:timeout=5s), or custom:message=heartbeat|timesync|any,rate=HZ,
    /// timeout=DURATION[,long-timeout=DURATION][,direction=up|down]; repeatable
    /// (default: the vehicle's autopilot's preset)
    #[arg(
        help_heading = "C2 link report",
        allow_negative_numbers = true,
        long,
        value_name = "MODEL"
    )]
    pub(crate) failsafe: Vec<String>,

    /// Fail (exit 1) when a responder loses more than PCT, e.g. 5% or 0.5
    #[arg(help_heading = "Thresholds", allow_negative_numbers = true, long, value_name = "PCT", value_parser = parse_percent, env = "MAVPING_MAX_LOSS")]
    pub(crate) max_loss: Option<f64>,

    /// Fail when an RTT figure is above a limit: [p50|p90|p99|p99.9|mean|max=]DURATION
    /// (default figure: max); repeatable, e.g. --max-rtt p99=50ms
    #[arg(help_heading = "Thresholds", allow_negative_numbers = true, long, value_name = "[FIGURE=]DURATION", value_parser = parse_rtt_limit)]
    pub(crate) max_rtt: Vec<RttLimit>,

    /// Fail when a responder's jitter is above DURATION
    #[arg(help_heading = "Thresholds", allow_negative_numbers = true, long, value_name = "DURATION", value_parser = parse_duration)]
    pub(crate) max_jitter: Option<Duration>,

    /// Fail when the p99 age of a source's frames above its baseline (how much later than
    /// its quickest they arrive, from their own clock stamps) is above DURATION
    #[arg(help_heading = "Thresholds", allow_negative_numbers = true, long, value_name = "DURATION", value_parser = parse_duration)]
    pub(crate) max_age: Option<Duration>,

    /// --probe params, mission, ftp: fail when a download takes longer than DURATION to complete
    #[arg(help_heading = "Thresholds", allow_negative_numbers = true, long, value_name = "DURATION", value_parser = parse_duration)]
    pub(crate) max_transfer_time: Option<Duration>,

    /// Fail when the C2 link's availability is under PCT (implies --report c2)
    #[arg(help_heading = "Thresholds", allow_negative_numbers = true, long, value_name = "PCT", value_parser = parse_percent)]
    pub(crate) min_availability: Option<f64>,

    /// Fail when the C2 link's continuity is under PCT (implies --report c2)
    #[arg(help_heading = "Thresholds", allow_negative_numbers = true, long, value_name = "PCT", value_parser = parse_percent)]
    pub(crate) min_continuity: Option<f64>,

    /// A responder that must answer: SYSID or SYSID/COMPID (on every link), or
    /// LINK=SYSID[/COMPID] (on that one of several links); repeatable
    #[arg(help_heading = "Thresholds", allow_negative_numbers = true, long, value_name = "[LINK=]SYSID[/COMPID]", value_parser = parse_expect_arg)]
    pub(crate) expect: Vec<ExpectArg>,

    /// Fail unless at least N responders answer
    #[arg(
        help_heading = "Thresholds",
        allow_negative_numbers = true,
        long,
        value_name = "N"
    )]
    pub(crate) min_responders: Option<usize>,

    /// Read links from FILE too (- is standard input), as fping -f
    ///
    /// One link per line; # starts a comment
    #[arg(
        help_heading = "Links",
        allow_negative_numbers = true,
        short = 'f',
        long = "file",
        value_name = "FILE"
    )]
    pub(crate) file: Option<PathBuf>,

    /// Resolve host names to IPv4 addresses only
    #[arg(help_heading = "Links", short = '4', conflicts_with = "ipv6")]
    pub(crate) ipv4: bool,

    /// Resolve host names to IPv6 addresses only
    #[arg(help_heading = "Links", short = '6')]
    pub(crate) ipv6: bool,

    /// Send from this local address (udpout:, udpbcast:, tcp:): ADDR or ADDR:PORT
    #[arg(
        help_heading = "Links",
        allow_negative_numbers = true,
        long,
        value_name = "ADDR[:PORT]",
        env = "MAVPING_BIND"
    )]
    pub(crate) bind: Option<String>,

    /// Send and receive through this network interface only
    ///
    /// SO_BINDTODEVICE, e.g. wlan0 or an LTE modem's wwan0 (before Linux 5.7 it needs
    /// CAP_NET_RAW)
    #[arg(
        help_heading = "Links",
        allow_negative_numbers = true,
        short = 'I',
        long,
        value_name = "IFACE",
        env = "MAVPING_INTERFACE"
    )]
    pub(crate) interface: Option<String>,

    /// When a tcp or serial link breaks, reconnect with backoff instead of
    /// ending the run; on udpout an ICMP "port unreachable" does not end it
    /// (pings sent while down count as lost)
    #[arg(help_heading = "Links", long, env = "MAVPING_RECONNECT", value_parser = boolish())]
    pub(crate) reconnect: bool,

    /// wss:// and m2rs:// links trust the CA certificates in FILE (PEM) instead of the system's
    #[arg(
        help_heading = "Links",
        long,
        value_name = "FILE",
        env = "MAVPING_CACERT"
    )]
    pub(crate) cacert: Option<std::path::PathBuf>,
    /// Baud rate of a serial device whose connection string names none
    #[arg(help_heading = "Serial", allow_negative_numbers = true, long, value_name = "BAUD", default_value_t = crate::transport::serial::DEFAULT_BAUD,
          env = "MAVPING_BAUD")]
    pub(crate) baud: u32,

    /// How to read radios' RADIO_STATUS: auto tells SiK, mLRS, ExpressLRS and ESP8266 bridges
    /// apart by what they send; the others read every radio as that kind (raw: figures as sent)
    ///
    /// Each kind's fields mean different things: SiK's rssi is ~1.9 steps per dB, mLRS's
    /// -120..-50 dBm as 0..254, ExpressLRS's the link quality. Reports name the kind and the
    /// evidence for it; dBm, SNR and fade margins are given only on a known scale
    #[arg(help_heading = "Serial", long, value_enum, value_name = "KIND", default_value_t = RadioTypeArg::Auto,
          env = "MAVPING_RADIO_TYPE")]
    pub(crate) radio_type: RadioTypeArg,

    #[command(flatten, next_help_heading = "Signing")]
    pub(crate) signing: SigningArgs,

    /// With a signing key: refuse unsigned replies too (wrongly signed and
    /// replayed ones are always refused); refused frames are counted, never
    /// measured
    #[arg(help_heading = "Signing", long, env = "MAVPING_REQUIRE_SIGNED", value_parser = boolish())]
    pub(crate) require_signed: bool,
}

/// MAVLink 2 signing, for `mavping` and `mavping respond`.
#[derive(Debug, clap::Args)]
pub(crate) struct SigningArgs {
    /// MAVLink 2 signing key: 64 hex characters (the 32-byte secret) or a
    /// passphrase, hashed with SHA-256 as MAVProxy does. Signs what we send
    /// and checks what we receive. Prefer MAVPING_SIGNING_KEY or
    /// --signing-key-file: a command line ends up in shell history
    #[arg(
        allow_negative_numbers = true,
        long,
        value_name = "KEY",
        env = "MAVPING_SIGNING_KEY",
        hide_env_values = true
    )]
    pub(crate) signing_key: Option<String>,

    /// Read the signing key from FILE (its content, trimmed)
    #[arg(
        allow_negative_numbers = true,
        long,
        value_name = "FILE",
        env = "MAVPING_SIGNING_KEY_FILE"
    )]
    pub(crate) signing_key_file: Option<PathBuf>,

    /// Link id in the signature of our frames (0-255)
    #[arg(
        allow_negative_numbers = true,
        long,
        value_name = "ID",
        default_value_t = 0,
        env = "MAVPING_SIGNING_LINK_ID"
    )]
    pub(crate) signing_link_id: u8,
}

/// Options of `mavping respond`.
#[derive(Debug, clap::Args)]
pub struct RespondArgs {
    /// Where to answer: udpin:HOST:PORT (every peer), udpout:HOST:PORT, sim:...
    ///
    /// Several: one identity on each, as a vehicle with two links (the same
    /// HEARTBEATs and streamed frames on every link, each answer on the
    /// link its request came on)
    #[arg(value_name = "CONNECTION", required = true, num_args = 1..)]
    pub(crate) links: Vec<String>,

    /// Our MAVLink system id
    #[arg(
        allow_negative_numbers = true,
        long,
        value_name = "ID",
        default_value_t = 1
    )]
    pub(crate) sysid: u8,

    /// Our MAVLink component id
    #[arg(
        allow_negative_numbers = true,
        long,
        value_name = "ID",
        default_value_t = 1
    )]
    pub(crate) compid: u8,

    /// Hold every reply (and transfer frame) this long (one-way link emulation)
    #[arg(allow_negative_numbers = true, long, value_name = "DURATION", value_parser = parse_duration, default_value = "0s")]
    pub(crate) delay: Duration,

    /// Extra delay per reply, uniform in [0, jitter]
    #[arg(allow_negative_numbers = true, long, value_name = "DURATION", value_parser = parse_duration, default_value = "0s")]
    pub(crate) jitter: Duration,

    /// Drop this share of replies and transfer frames, e.g. 10 or 10% (streamed frames have
    /// --stream-drop)
    #[arg(
        allow_negative_numbers = true,
        long,
        value_name = "PCT",
        value_parser = parse_percent,
        default_value = "0"
    )]
    pub(crate) drop: f64,

    /// Send this share of replies and transfer frames twice (not streamed frames)
    #[arg(
        allow_negative_numbers = true,
        long,
        value_name = "PCT",
        value_parser = parse_percent,
        default_value = "0"
    )]
    pub(crate) dup: f64,

    /// Random seed for --jitter, --drop and --dup (and the streams' phases and --stream-drop)
    #[arg(
        allow_negative_numbers = true,
        long,
        value_name = "N",
        default_value_t = 1
    )]
    pub(crate) seed: u64,

    /// Stream telemetry to every peer, as a vehicle: MSG@HZ, repeatable or a comma list
    ///
    /// MSG is ATTITUDE, GLOBAL_POSITION_INT or HEARTBEAT (our HEARTBEAT at that rate
    /// instead of 1 Hz), e.g. --stream ATTITUDE@50,GLOBAL_POSITION_INT@5. Streams start
    /// at once, each from a random phase of its period, and every frame takes the next of
    /// the packet sequence numbers our replies and HEARTBEATs take. Not delayed, dropped or
    /// doubled by --delay, --jitter, --drop or --dup (those are for replies)
    #[arg(
        long,
        value_name = "MSG@HZ",
        value_delimiter = ',',
        action = ArgAction::Append,
        value_parser = clap::value_parser!(StreamSpec)
    )]
    pub(crate) stream: Vec<StreamSpec>,

    /// Drop this share of streamed frames: each is numbered, then not sent (the gap a lost
    /// frame leaves in the sequence numbers), and counted
    #[arg(
        allow_negative_numbers = true,
        long,
        value_name = "PCT",
        value_parser = parse_percent,
        default_value = "0"
    )]
    pub(crate) stream_drop: f64,

    /// Answer only TIMESYNC and commands, not PING (like ArduPilot)
    #[arg(long)]
    pub(crate) no_ping: bool,

    /// Parameters served, read-only: MAVPING_0000 upwards, all sent on PARAM_REQUEST_LIST,
    /// one on PARAM_REQUEST_READ (0 serves none; at most 10000)
    #[arg(
        help_heading = "Transfers",
        allow_negative_numbers = true,
        long,
        value_name = "N",
        default_value_t = 500
    )]
    pub(crate) params: i64,

    /// Mission items served, read-only: home, a takeoff, then waypoints (0 serves an empty
    /// mission; at most 10000)
    #[arg(
        help_heading = "Transfers",
        allow_negative_numbers = true,
        long,
        value_name = "N",
        default_value_t = 20
    )]
    pub(crate) mission: i64,

    /// Bytes of the file served by MAVLink FTP as /mavping.bin, read-only (at most 1 GiB)
    #[arg(
        help_heading = "Transfers",
        allow_negative_numbers = true,
        long,
        value_name = "BYTES",
        default_value_t = 65536
    )]
    pub(crate) file_size: i64,

    /// Frames a second the transfers are sent at, at most: a parameter list, a burst of the
    /// file, and the replies to re-requests share it. Each frame is then held, dropped or
    /// doubled by --delay, --jitter, --drop and --dup as replies are
    #[arg(
        help_heading = "Transfers",
        allow_negative_numbers = true,
        long,
        value_name = "HZ",
        default_value_t = 1000.0
    )]
    pub(crate) transfer_rate: f64,

    /// Baud rate of a serial device whose connection string names none
    #[arg(allow_negative_numbers = true, long, value_name = "BAUD", default_value_t = crate::transport::serial::DEFAULT_BAUD)]
    pub(crate) baud: u32,

    /// With a key (below), sign our replies and answer only correctly
    /// signed, not replayed requests
    #[command(flatten)]
    pub(crate) signing: SigningArgs,

    /// More logs on stderr (-v info, -vv debug)
    #[arg(short = 'v', long, action = ArgAction::Count)]
    pub(crate) verbose: u8,
}

/// Options of `mavping serve`.
#[derive(Debug, Clone, clap::Args)]
pub struct ServeArgs {
    /// Where to serve /probe and /metrics: a numeric ADDR:PORT [default: 127.0.0.1:9465, or
    /// listen in --config]
    #[arg(long, value_name = "ADDR:PORT", env = "MAVPING_LISTEN")]
    pub(crate) listen: Option<String>,

    /// TOML file with allowed targets, modules, continuous links and max_concurrent; reread
    /// on SIGHUP
    #[arg(long, value_name = "FILE", env = "MAVPING_SERVE_CONFIG")]
    pub(crate) config: Option<PathBuf>,

    /// Let /probe open targets matching PATTERN, e.g. 'udpout:127.0.0.1:*' ('*' stands for
    /// one part of an address: a port, an octet, a name; '**' for anything); repeatable
    #[arg(long, value_name = "PATTERN")]
    pub(crate) allow: Vec<String>,

    /// Probe LINK all the time (PING every second) and show it at /metrics; repeatable
    #[arg(long = "link", value_name = "LINK")]
    pub(crate) links: Vec<String>,

    /// Most /probe requests running at once; more are answered 503 [default: 16, or
    /// max_concurrent in --config]
    #[arg(long, value_name = "N")]
    pub(crate) max_concurrent: Option<usize>,

    /// YAML file in the exporter-toolkit format (tls_server_config, basic_auth_users,
    /// http_server_config.headers): TLS, client certificates, basic auth; reread on reload
    #[arg(
        long = "web.config.file",
        value_name = "FILE",
        env = "MAVPING_WEB_CONFIG"
    )]
    pub(crate) web_config_file: Option<PathBuf>,

    /// Let POST /-/reload reread the configuration and web configuration, as SIGHUP does
    #[arg(long = "web.enable-lifecycle")]
    pub(crate) enable_lifecycle: bool,

    /// Check --config and --web.config.file, say what they hold, and exit (0 good, 2 bad)
    #[arg(long = "config.check")]
    pub(crate) config_check: bool,

    /// More logs on stderr (-v info, -vv debug)
    #[arg(short = 'v', long, action = ArgAction::Count)]
    pub(crate) verbose: u8,
}

/// Options of `mavping compare`.
#[derive(Debug, Clone, clap::Args)]
pub struct CompareArgs {
    /// The reference run: a file of `mavping --json` lines
    #[arg(value_name = "A.json")]
    pub(crate) a: PathBuf,

    /// The run compared with it
    #[arg(value_name = "B.json")]
    pub(crate) b: PathBuf,

    /// Write one JSON line (type compare) instead of text
    #[arg(long)]
    pub(crate) json: bool,

    /// Compare only this responder or source: SYSID/COMPID, or SYSID for every component
    #[arg(long, value_name = "SYSID[/COMPID]")]
    pub(crate) source: Option<String>,

    /// Width of the distance bands of two telemetry logs, in metres [default: 10, 20, 50,
    /// 100 ... whichever gives at most 8 bands]
    #[arg(allow_negative_numbers = true, long, value_name = "METRES")]
    pub(crate) band_m: Option<f64>,

    /// Exit 1 when B loses more than A: a responder's, source's or passive link's loss
    /// difference whose 95 % interval is above 0
    #[arg(long)]
    pub(crate) fail_if_worse: bool,
}
