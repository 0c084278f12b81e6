//! Command-line arguments as typed; [`crate::config`] validates them.

use std::path::PathBuf;
use std::time::Duration;

use clap::{ArgAction, Parser, Subcommand, ValueEnum};

use crate::units::{parse_duration, parse_percent};
use crate::verdict::{Expected, RttLimit};

#[derive(Debug, Parser)]
#[command(
    name = "mavping",
    version,
    about = "Measure MAVLink link latency and loss: ping for drones and radios",
    long_about = "Measure MAVLink link latency and loss: ping for drones and radios.\n\n\
        Sends MAVLink PING requests on a schedule over UDP, TCP, serial or a simulated link, \
        matches each reply to its request by sequence and responder, and reports per-responder \
        RTT, loss, late and duplicate replies. --probe timesync uses TIMESYNC instead (ArduPilot \
        answers nothing else) and also measures each responder's clock offset and drift; \
        --probe command re-sends a COMMAND_LONG until acknowledged. `mavping respond` is the \
        other end: a MAVLink system that answers all three.",
    after_help = "Connection strings: udpin:HOST:PORT (also udp:HOST:PORT or HOST:PORT) listens and \
        pings every peer heard; udpout:HOST:PORT sends to one address; udpbcast:ADDR:PORT broadcasts; \
        tcp:HOST:PORT (tcpout:) connects, tcpin:HOST:PORT listens and pings every client; \
        serial:DEVICE[:BAUD] or a bare /dev/... path opens a serial port; sim:[?key=value&...] \
        is the built-in simulated link (see the README). IPv6 hosts go in brackets: [::1]:14550.\n\n\
        Several connections are pinged side by side on the same schedule, each with its own \
        sequence numbers and report; thresholds and --expect apply to each link.\n\n\
        Exit status: 0 when a responder answered (on every link), 1 when none did, 2 on usage \
        or link errors (on any link)."
)]
#[command(args_conflicts_with_subcommands = true, subcommand_negates_reqs = true)]
// `-i -1` reaches the value parser (and a clear error), not "unexpected argument".
#[command(allow_negative_numbers = true)]
pub struct Cli {
    #[command(flatten)]
    pub ping: PingArgs,

    /// Print shell completions or the man page (for packagers)
    #[arg(long, value_enum, hide = true, value_name = "KIND")]
    pub generate: Option<Generate>,

    #[command(subcommand)]
    pub mode: Option<Mode>,
}

/// `[FIGURE=]DURATION`, e.g. `p99=50ms` or `200ms` (the maximum).
pub fn parse_rtt_limit(s: &str) -> Result<RttLimit, String> {
    let (figure, limit) = match s.split_once('=') {
        Some((figure, limit)) => (figure.parse()?, limit),
        None => (crate::verdict::RttFigure::Max, s),
    };
    Ok(RttLimit {
        figure,
        limit: parse_duration(limit)?,
    })
}

/// `--expect`: a responder, on every link or on one (`LINK=ID`).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ExpectArg {
    /// The connection string it is scoped to, as given.
    pub link: Option<String>,
    pub id: Expected,
}

/// `SYSID[/COMPID]`, or `LINK=SYSID[/COMPID]` for one of several links
/// (split at the last `=`, since connection strings may hold one).
pub fn parse_expect_arg(s: &str) -> Result<ExpectArg, String> {
    match s.rsplit_once('=') {
        Some((link, id)) if !link.is_empty() => Ok(ExpectArg {
            link: Some(link.to_string()),
            id: parse_expected(id)
                .map_err(|_| format!("'{s}' is not LINK=SYSID or LINK=SYSID/COMPID (1-255)"))?,
        }),
        _ => Ok(ExpectArg {
            link: None,
            id: parse_expected(s)?,
        }),
    }
}

/// `SYSID` or `SYSID/COMPID`, each 1-255.
pub fn parse_expected(s: &str) -> Result<Expected, String> {
    let id = |part: &str| -> Result<u8, String> {
        part.parse::<u8>()
            .ok()
            .filter(|&v| v != 0)
            .ok_or_else(|| format!("'{s}' is not SYSID or SYSID/COMPID (1-255)"))
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

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Format {
    /// Ping-like lines and a summary
    Text,
    /// Newline-delimited JSON events
    Json,
}

/// What `--generate` writes to stdout.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Generate {
    CompleteBash,
    CompleteZsh,
    CompleteFish,
    CompletePowershell,
    CompleteElvish,
    Man,
}

/// Modes other than measuring.
#[derive(Debug, Subcommand)]
pub enum Mode {
    /// Be a well-behaved MAVLink system that answers PING, TIMESYNC and COMMAND_LONG
    #[command(allow_negative_numbers = true)]
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
}

/// What to send.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum ProbeKind {
    /// MAVLink PING (PX4, QGroundControl, MAVSDK answer it)
    Ping,
    /// TIMESYNC: answered everywhere, ArduPilot included; also measures clock offset
    Timesync,
    /// COMMAND_LONG re-sent until its COMMAND_ACK arrives
    Command,
}

/// Options of a measurement run (the default command).
#[derive(Debug, clap::Args)]
pub struct PingArgs {
    /// Where to ping: udpin:HOST:PORT, udpout:HOST:PORT, udpbcast:ADDR:PORT, tcp:HOST:PORT,
    /// tcpin:HOST:PORT, serial:DEVICE[:BAUD], sim:[?...]; several links are pinged side by
    /// side, each reported on its own
    #[arg(
        value_name = "CONNECTION",
        env = "MAVPING_LINK",
        required_unless_present = "generate",
        num_args = 1..
    )]
    pub links: Vec<String>,

    /// Stop after sending COUNT requests (and waiting for their replies)
    #[arg(short = 'c', long, value_name = "COUNT", env = "MAVPING_COUNT")]
    pub count: Option<u64>,

    /// Time between requests, e.g. 1s, 100ms, 0.01
    #[arg(short = 'i', long, value_name = "DURATION", value_parser = parse_duration,
          conflicts_with = "rate", env = "MAVPING_INTERVAL")]
    pub interval: Option<Duration>,

    /// Requests per second (instead of --interval)
    #[arg(long, value_name = "HZ", env = "MAVPING_RATE")]
    pub rate: Option<f64>,

    /// Stop after this long, whatever is still in flight
    #[arg(short = 'w', long, value_name = "DURATION", value_parser = parse_duration,
          env = "MAVPING_DEADLINE")]
    pub deadline: Option<Duration>,

    /// How long to wait for each reply before counting it lost
    #[arg(short = 'W', long, value_name = "DURATION", value_parser = parse_duration,
          default_value = "2s", env = "MAVPING_TIMEOUT")]
    pub timeout: Duration,

    /// Print only the summary
    #[arg(short = 'q', long)]
    pub quiet: bool,

    /// Print a line for every reply even above 100 requests/s (where one
    /// status line per second is printed instead)
    #[arg(long)]
    pub every_reply: bool,

    /// Our MAVLink system id (the header of our requests)
    #[arg(long, value_name = "ID", default_value_t = 255, env = "MAVPING_SYSID")]
    pub sysid: u8,

    /// Our MAVLink component id
    #[arg(long, value_name = "ID", default_value_t = 190, env = "MAVPING_COMPID")]
    pub compid: u8,

    /// MAVLink version of our requests (replies of either version are accepted)
    #[arg(long = "mavlink", value_name = "1|2", default_value_t = 2,
          value_parser = clap::value_parser!(u8).range(1..=2))]
    pub mavlink_version: u8,

    /// Do not send our 1 Hz GCS HEARTBEAT (MAVSDK ignores PINGs from systems it has not heard)
    #[arg(long)]
    pub no_heartbeat: bool,

    /// Sequence number of the first request (to test wrap-around)
    #[arg(long, value_name = "SEQ", default_value_t = 0, hide = true)]
    pub first_seq: u32,

    /// More logs on stderr (-v info, -vv debug, -vvv trace); or set MAVPING_LOG
    #[arg(short = 'v', long, action = ArgAction::Count)]
    pub verbose: u8,

    /// Output format
    #[arg(long, value_enum, default_value = "text", env = "MAVPING_FORMAT")]
    pub format: Format,

    /// Same as --format json: newline-delimited JSON events on stdout
    #[arg(long)]
    pub json: bool,

    /// Fail (exit 1) when a responder loses more than PCT, e.g. 5% or 0.5
    #[arg(long, value_name = "PCT", value_parser = parse_percent, env = "MAVPING_MAX_LOSS")]
    pub max_loss: Option<f64>,

    /// Fail when an RTT figure is above a limit: [p50|p90|p99|p99.9|mean|max=]DURATION
    /// (default figure: max); repeatable, e.g. --max-rtt p99=50ms
    #[arg(long, value_name = "[FIGURE=]DURATION", value_parser = parse_rtt_limit)]
    pub max_rtt: Vec<RttLimit>,

    /// Fail when a responder's jitter is above DURATION
    #[arg(long, value_name = "DURATION", value_parser = parse_duration)]
    pub max_jitter: Option<Duration>,

    /// A responder that must answer: SYSID or SYSID/COMPID (on every link), or
    /// LINK=SYSID[/COMPID] (on that one of several links); repeatable
    #[arg(long, value_name = "[LINK=]SYSID[/COMPID]", value_parser = parse_expect_arg)]
    pub expect: Vec<ExpectArg>,

    /// Fail unless at least N responders answer
    #[arg(long, value_name = "N")]
    pub min_responders: Option<usize>,

    /// Write each responder's RTT distribution in HdrHistogram's .hgrm format
    #[arg(long, value_name = "FILE")]
    pub hgrm: Option<PathBuf>,

    /// Write one CSV row per reply or loss (sysid,compid,seq,sent_s,rtt_us,status, then the latest RADIO_STATUS figures)
    #[arg(long, value_name = "FILE")]
    pub samples: Option<PathBuf>,
    /// Baud rate of a serial device whose connection string names none
    #[arg(long, value_name = "BAUD", default_value_t = crate::transport::serial::DEFAULT_BAUD,
          env = "MAVPING_BAUD")]
    pub baud: u32,

    /// When a tcp or serial link breaks, reconnect with backoff instead of
    /// ending the run; on udpout an ICMP "port unreachable" does not end it
    /// (pings sent while down count as lost)
    #[arg(long, env = "MAVPING_RECONNECT")]
    pub reconnect: bool,
    /// What to send: ping, timesync (also ArduPilot; measures clock offset), command
    #[arg(long, value_enum, value_name = "PROBE", default_value_t = ProbeKind::Ping,
          env = "MAVPING_PROBE")]
    pub probe: ProbeKind,

    /// Address requests to SYS/COMP (timesync: default 0/0, everyone; command: default 1/1)
    #[arg(long, value_name = "SYS/COMP", env = "MAVPING_TARGET")]
    pub target: Option<String>,

    /// --probe command: MAV_CMD name or id, then up to 7 params, comma-separated
    #[arg(long, value_name = "CMD[,P1,...]", default_value = "REQUEST_MESSAGE,0")]
    pub command: String,

    /// --probe command: re-send an unacknowledged command this often
    #[arg(long, value_name = "DURATION", value_parser = parse_duration, default_value = "100ms")]
    pub retry_interval: Duration,

    /// --probe command: re-sends after the first before a command counts as failed
    #[arg(long, value_name = "N", default_value_t = 3)]
    pub retries: u8,

    /// Full-screen live view (q or Ctrl-C to stop); plain text when stdout is not a terminal
    #[arg(long, env = "MAVPING_LIVE")]
    pub live: bool,

    /// Serve Prometheus metrics at http://ADDR:PORT/metrics while the run goes on
    #[arg(long, value_name = "ADDR:PORT", env = "MAVPING_PROMETHEUS")]
    pub prometheus: Option<String>,

    /// At the end, draw RTT over time and the RTT distribution to FILE.svg
    #[arg(long, value_name = "FILE.svg")]
    pub plot: Option<PathBuf>,

    #[command(flatten)]
    pub signing: SigningArgs,

    /// With a signing key: refuse unsigned replies too (wrongly signed and
    /// replayed ones are always refused); refused frames are counted, never
    /// measured
    #[arg(long, env = "MAVPING_REQUIRE_SIGNED")]
    pub require_signed: bool,
}

/// MAVLink 2 signing, for `mavping` and `mavping respond`.
#[derive(Debug, clap::Args)]
pub struct SigningArgs {
    /// MAVLink 2 signing key: 64 hex characters (the 32-byte secret) or a
    /// passphrase, hashed with SHA-256 as MAVProxy does. Signs what we send
    /// and checks what we receive. Prefer MAVPING_SIGNING_KEY or
    /// --signing-key-file: a command line ends up in shell history
    #[arg(
        long,
        value_name = "KEY",
        env = "MAVPING_SIGNING_KEY",
        hide_env_values = true
    )]
    pub signing_key: Option<String>,

    /// Read the signing key from FILE (its content, trimmed)
    #[arg(long, value_name = "FILE", env = "MAVPING_SIGNING_KEY_FILE")]
    pub signing_key_file: Option<PathBuf>,

    /// Link id in the signature of our frames (0-255)
    #[arg(
        long,
        value_name = "ID",
        default_value_t = 0,
        env = "MAVPING_SIGNING_LINK_ID"
    )]
    pub signing_link_id: u8,
}

/// Options of `mavping respond`.
#[derive(Debug, clap::Args)]
pub struct RespondArgs {
    /// Where to answer: udpin:HOST:PORT (every peer), udpout:HOST:PORT, sim:...
    #[arg(value_name = "CONNECTION")]
    pub link: String,

    /// Our MAVLink system id
    #[arg(long, value_name = "ID", default_value_t = 1)]
    pub sysid: u8,

    /// Our MAVLink component id
    #[arg(long, value_name = "ID", default_value_t = 1)]
    pub compid: u8,

    /// Hold every reply this long (one-way link emulation)
    #[arg(long, value_name = "DURATION", value_parser = parse_duration, default_value = "0s")]
    pub delay: Duration,

    /// Extra delay per reply, uniform in [0, jitter]
    #[arg(long, value_name = "DURATION", value_parser = parse_duration, default_value = "0s")]
    pub jitter: Duration,

    /// Drop this share of replies, e.g. 10 or 10%
    #[arg(long, value_name = "PCT", default_value = "0")]
    pub drop: String,

    /// Send this share of replies twice
    #[arg(long, value_name = "PCT", default_value = "0")]
    pub dup: String,

    /// Random seed for --jitter, --drop and --dup
    #[arg(long, value_name = "N", default_value_t = 1)]
    pub seed: u64,

    /// Answer only TIMESYNC and commands, not PING (like ArduPilot)
    #[arg(long)]
    pub no_ping: bool,

    /// Baud rate of a serial device whose connection string names none
    #[arg(long, value_name = "BAUD", default_value_t = crate::transport::serial::DEFAULT_BAUD)]
    pub baud: u32,

    /// With a key (below), sign our replies and answer only correctly
    /// signed, not replayed requests
    #[command(flatten)]
    pub signing: SigningArgs,

    /// More logs on stderr (-v info, -vv debug)
    #[arg(short = 'v', long, action = ArgAction::Count)]
    pub verbose: u8,
}

/// Options of `mavping serve`.
#[derive(Debug, Clone, clap::Args)]
pub struct ServeArgs {
    /// Where to serve /probe and /metrics: a numeric ADDR:PORT [default: 127.0.0.1:9465, or
    /// listen in --config]
    #[arg(long, value_name = "ADDR:PORT", env = "MAVPING_LISTEN")]
    pub listen: Option<String>,

    /// TOML file with allowed targets, modules, continuous links and max_concurrent; reread
    /// on SIGHUP
    #[arg(long, value_name = "FILE", env = "MAVPING_SERVE_CONFIG")]
    pub config: Option<PathBuf>,

    /// Let /probe open targets matching PATTERN, e.g. 'udpout:127.0.0.1:*' ('*' stands for
    /// one part of an address: a port, an octet, a name; '**' for anything); repeatable
    #[arg(long, value_name = "PATTERN")]
    pub allow: Vec<String>,

    /// Probe LINK all the time (PING every second) and show it at /metrics; repeatable
    #[arg(long = "link", value_name = "LINK")]
    pub links: Vec<String>,

    /// Most /probe requests running at once; more are answered 503 [default: 16, or
    /// max_concurrent in --config]
    #[arg(long, value_name = "N")]
    pub max_concurrent: Option<usize>,

    /// More logs on stderr (-v info, -vv debug)
    #[arg(short = 'v', long, action = ArgAction::Count)]
    pub verbose: u8,
}
