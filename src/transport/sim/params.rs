//! The `sim:` connection string's query: `sim:?key=value&...`, parsed
//! and validated, and printed back in the form reports name the link by.

use std::fmt;
use std::time::Duration;

use thiserror::Error;

use super::radio::{AirParams, DEFAULT_TDM_ROUND};
use crate::answering::ftp::MAX_FILE_SIZE;
use crate::answering::mission::MAX_ITEMS;
use crate::answering::params::MAX_PARAMS;
use crate::answering::transfers::{ServeSpec, DEFAULT_SERVE, DEFAULT_TRANSFER_RATE};
use crate::frame::SysComp;
use crate::telemetry::{self, StreamSpec, StreamSpecError};
use crate::units::{
    parse_duration, parse_duration_up_to, parse_percent, DurationError, PercentError,
};

/// The radio's transmit buffer when `buffer=` does not say.
pub const DEFAULT_BUFFER_BYTES: u64 = 1024;

#[derive(Debug, Clone, PartialEq)]
pub struct SimParams {
    pub(crate) responders: u16,
    /// sysid of the first responder; the others follow (1, 2, 3, ...).
    pub(crate) first_sysid: u8,
    pub(crate) compid: u8,
    /// One-way delay.
    pub(crate) delay: Duration,
    /// Extra one-way delay, uniform in [0, jitter], drawn per direction.
    pub(crate) jitter: Duration,
    /// Share of exchanges lost, 0..=1.
    pub(crate) loss: f64,
    /// Share of replies delivered twice.
    pub(crate) dup: f64,
    /// Share of replies held back by `hold` (arrive after later replies).
    pub(crate) reorder: f64,
    pub(crate) hold: Duration,
    pub(crate) seed: u64,
    /// Paused tokio clock: deterministic output, no waiting.
    pub(crate) virtual_clock: bool,
    /// False: responders are ArduPilot: their HEARTBEAT says so, and they
    /// answer TIMESYNC but never PING.
    pub(crate) answer_ping: bool,
    pub(crate) heartbeat: bool,
    /// Responders' clocks read `offset + (1 + drift·1e-6)·t`, t = ns since
    /// the link opened: the truth a TIMESYNC measurement is held against.
    pub(crate) clock_offset_ns: i64,
    pub(crate) drift_ppm: f64,
    /// A serial radio link at this baud: every frame takes its bytes x 10
    /// bits of wire time, requests and replies share it (half duplex, as
    /// SiK), and a bounded buffer drops what does not fit.
    pub(crate) baud: Option<u32>,
    /// Emit RADIO_STATUS as 51/68 once a second, following the link.
    pub(crate) radio: bool,
    /// The radio's transmit buffer: what waits for the wire (or the air)
    /// beyond it is dropped.
    pub(crate) buffer: u64,
    /// A radio pair with its own air rate, TDM and ECC behind UARTs at
    /// `baud` ([`super::radio`]); without it, `baud` is one half-duplex
    /// wire.
    pub(crate) air: Option<AirParams>,
    /// A link outage: from `start` after the link opened, for `length`,
    /// every request and reply is lost...
    pub(crate) outage: Option<(Duration, Duration)>,
    /// ...and again every `outage_every` after that (weeks of simulated
    /// monitoring with an outage every few hours).
    pub(crate) outage_every: Option<Duration>,
    /// Share of replies hit by a delay spike of `spike_delay` extra.
    pub(crate) spike: f64,
    pub(crate) spike_delay: Duration,
    /// Telemetry each responder sends unasked (`stream=`), as a vehicle
    /// does; a HEARTBEAT stream sets the rate of its HEARTBEAT.
    pub(crate) streams: Vec<StreamSpec>,
    /// Shares of the frames a responder sends (telemetry, HEARTBEAT,
    /// replies) lost, delivered twice and held back by `hold` on their way
    /// to mavping, after they were numbered: what a passive loss count
    /// sees in the sequence numbers.
    pub(crate) loss_down: f64,
    pub(crate) dup_down: f64,
    pub(crate) reorder_down: f64,
    /// Share of the frames mavping sends lost on the way to each
    /// responder (each responder draws its own).
    pub(crate) loss_up: f64,
    /// Share of the frames mavping sends that reach a responder twice (a
    /// request heard twice is answered twice; each responder draws its
    /// own).
    pub(crate) dup_up: f64,
    /// A queue on the way to the responders (`queue_up=`) or back
    /// (`queue_down=`): the delay a relay or modem buffer adds, growing
    /// and draining, with no frame lost.
    pub(crate) queue_up: Option<Queue>,
    pub(crate) queue_down: Option<Queue>,
    /// The paths a responder's frames reach mavping by (`paths=`), each
    /// with its own faults after the link's; empty: the one path of a
    /// link without the key.
    pub(crate) paths: Vec<PathParams>,
    /// The parameters, mission and file each responder serves
    /// (`params=`, `mission=`, `file=`), and the most transfer frames it
    /// sends a second (`transfer_rate=`); a slower wire paces them.
    pub(crate) serve: ServeSpec,
    pub(crate) transfer_rate: f64,
}

/// The most paths one link has (`paths=`): a MAVProxy log numbers its
/// links in a stamp's two low bits, so four is what one log can tell
/// apart; the setups that need it (a radio and LTE, two modems) have two
/// or three. It also bounds a frame's copies (two each with `dup_down=`).
pub(crate) const MAX_PATHS: usize = 4;

/// One path of a vehicle heard on several (`paths=`): what it does to its
/// copy of each frame the responders send, after the link's own faults.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub(crate) struct PathParams {
    /// Share of its copies lost (`path_loss=`).
    pub(crate) loss: f64,
    /// Added to the delay the link gave the frame (`path_delay=`).
    pub(crate) delay: Duration,
    /// From `start` after the link opened, for `length`, the frames the
    /// responders send are lost on this path (`path_outage=`).
    pub(crate) outage: Option<Outage>,
}

/// An outage's start after the link opened, and its length.
pub(crate) type Outage = (Duration, Duration);

/// How a `path_` list shows one path's entry, `None` for its default.
type PathEntry = fn(&PathParams) -> Option<String>;

/// A queue that grows from nothing to `peak` over `rise` from the link's
/// opening, then drains as fast: a one-way delay that changes while the
/// link loses nothing, the truth an age or a direction split is held to.
/// Its delay changes by less than its own length per second (`peak` <
/// `rise`), so it keeps the frames in order, as a queue does.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Queue {
    pub(crate) peak: Duration,
    pub(crate) rise: Duration,
}

impl Queue {
    /// The delay it adds to a frame entering it `since` the link opened.
    pub(crate) fn delay_at(&self, since: Duration) -> Duration {
        let rise = self.rise.as_secs_f64();
        let t = since.as_secs_f64();
        let share = if t <= rise {
            t / rise
        } else {
            (2.0 - t / rise).max(0.0)
        };
        self.peak.mul_f64(share)
    }

    /// `PEAK@RISE`, e.g. `1.5s@8s`.
    fn parse(key: &str, value: &str) -> Result<Self, Problem> {
        let expected = "PEAK@RISE, a peak shorter than its rise, e.g. 1.5s@8s";
        let (peak, rise) = value
            .split_once('@')
            .ok_or_else(|| Problem::expected(key, value, expected))?;
        let part = |p| duration(key, p).map_err(|_| Problem::expected(key, value, expected));
        let (peak, rise) = (part(peak)?, part(rise)?);
        if rise.is_zero() || peak >= rise {
            return Err(Problem::expected(key, value, expected));
        }
        Ok(Queue { peak, rise })
    }
}

impl fmt::Display for Queue {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        // Seconds as numbers: humantime's "1s 500ms" has a space.
        write!(
            f,
            "{}s@{}s",
            self.peak.as_secs_f64(),
            self.rise.as_secs_f64()
        )
    }
}

impl Default for SimParams {
    fn default() -> Self {
        SimParams {
            responders: 1,
            first_sysid: 1,
            compid: 1,
            delay: Duration::from_millis(10),
            jitter: Duration::from_millis(2),
            loss: 0.0,
            dup: 0.0,
            reorder: 0.0,
            hold: Duration::from_millis(50),
            seed: 1,
            virtual_clock: false,
            answer_ping: true,
            heartbeat: true,
            clock_offset_ns: 0,
            drift_ppm: 0.0,
            baud: None,
            radio: false,
            buffer: DEFAULT_BUFFER_BYTES,
            air: None,
            outage: None,
            outage_every: None,
            spike: 0.0,
            spike_delay: Duration::from_millis(500),
            streams: Vec::new(),
            loss_down: 0.0,
            dup_down: 0.0,
            reorder_down: 0.0,
            loss_up: 0.0,
            dup_up: 0.0,
            queue_up: None,
            queue_down: None,
            paths: Vec::new(),
            serve: DEFAULT_SERVE,
            transfer_rate: DEFAULT_TRANSFER_RATE,
        }
    }
}

/// The keys `sim:` accepts, for error messages and the README.
pub const SIM_KEYS: &str = "responders=N (1-1000), sysid=N, compid=N, delay=DURATION, \
jitter=DURATION, loss=PCT, dup=PCT, reorder=PCT, hold=DURATION, seed=N, clock=real|virtual, \
ping=on|off, heartbeat=on|off, offset=[-]DURATION, drift=PPM, baud=N, radio=on|off, \
buffer=BYTES, air=BITS_PER_S, duty=PCT, ecc=on|off, tdm=DURATION, outage=START+LENGTH, \
outage_every=DURATION, spike=PCT, spike_delay=DURATION, stream=MSG@HZ[,MSG@HZ...], \
loss_down=PCT, dup_down=PCT, reorder_down=PCT, loss_up=PCT, dup_up=PCT, queue_up=PEAK@RISE, \
queue_down=PEAK@RISE, paths=N (1-4), path_loss=PCT[,PCT...], path_delay=DURATION[,DURATION...], \
path_outage=none|START+LENGTH[,...], params=N (0-10000), mission=N (0-10000), \
file=BYTES (0-1073741824), transfer_rate=HZ";

/// What is wrong with a `sim:` query: which key, and why (or which keys
/// go together).
#[derive(Debug, Clone, PartialEq, Eq, Error)]
#[error(transparent)]
pub struct SimParamsError(Problem);

#[derive(Debug, Clone, PartialEq, Eq, Error)]
enum Problem {
    /// A value its key does not take.
    #[error("{key}={value}: expected {expected}")]
    Expected {
        key: String,
        value: String,
        expected: &'static str,
    },
    #[error("{key}={value}: {source}")]
    Duration {
        key: String,
        value: String,
        source: DurationError,
    },
    #[error("{key}={value}: {source}")]
    Percent {
        key: String,
        value: String,
        source: PercentError,
    },
    #[error("{key}={value}: {source}")]
    Stream {
        key: String,
        value: String,
        source: StreamSpecError,
    },
    /// The streams together (each message once).
    #[error("stream=: {0}")]
    Streams(StreamSpecError),
    #[error("'{0}' is not key=value; keys: {SIM_KEYS}")]
    NotKeyValue(String),
    #[error("{0}= is given twice: give each key once")]
    Twice(String),
    #[error("unknown key '{0}'; keys: {SIM_KEYS}")]
    UnknownKey(String),
    /// A key (with its value when it matters) that needs another.
    #[error("{key} needs {needs}")]
    Needs { key: String, needs: &'static str },
    #[error(
        "outage_every={}: must be longer than the outage ({})",
        humantime::format_duration(*.every),
        humantime::format_duration(*.outage)
    )]
    OutageEvery { every: Duration, outage: Duration },
    #[error("too many responders for the sysid range")]
    TooManyResponders,
    /// A `path_` list whose length is not `paths=`.
    #[error("{key}={value}: {given} given for paths={paths}: give one per path")]
    PathCount {
        key: &'static str,
        value: String,
        given: usize,
        paths: usize,
    },
}

impl Problem {
    fn expected(key: &str, value: &str, expected: &'static str) -> Self {
        Problem::Expected {
            key: key.to_string(),
            value: value.to_string(),
            expected,
        }
    }
}

/// `64000`, `64k`, `1.5M`: bits per second.
fn bit_rate(key: &str, value: &str) -> Result<u32, Problem> {
    let (number, scale) = match value.strip_suffix(['k', 'K']) {
        Some(n) => (n, 1e3),
        None => match value.strip_suffix('M') {
            Some(n) => (n, 1e6),
            None => (value, 1.0),
        },
    };
    number
        .parse::<f64>()
        .ok()
        .map(|v| v * scale)
        .filter(|v| (1_000.0..=10_000_000.0).contains(v))
        .map(|v| v.round() as u32)
        .ok_or_else(|| {
            Problem::expected(
                key,
                value,
                "an air rate from 1k to 10M bits per second, e.g. 64k",
            )
        })
}

fn percent(key: &str, value: &str) -> Result<f64, Problem> {
    parse_percent(value).map_err(|source| Problem::Percent {
        key: key.to_string(),
        value: value.to_string(),
        source,
    })
}

fn duration(key: &str, value: &str) -> Result<Duration, Problem> {
    parse_duration_up_to(value, Duration::from_secs(3600)).map_err(|source| Problem::Duration {
        key: key.to_string(),
        value: value.to_string(),
        source,
    })
}

fn switch(key: &str, value: &str) -> Result<bool, Problem> {
    match value {
        "on" | "1" | "true" | "yes" => Ok(true),
        "off" | "0" | "false" | "no" => Ok(false),
        _ => Err(Problem::expected(key, value, "on or off")),
    }
}

fn number<T: std::str::FromStr>(key: &str, value: &str, range: &'static str) -> Result<T, Problem> {
    value
        .parse()
        .map_err(|_| Problem::expected(key, value, range))
}

/// The radio keys that mean something only beside `air=`.
#[derive(Default)]
struct AirKeys {
    air: Option<u32>,
    duty: Option<f64>,
    ecc: Option<bool>,
    tdm: Option<Duration>,
}

impl AirKeys {
    /// The radio pair's air side, if `air=` was given (it needs `baud=`).
    fn params(self, baud: Option<u32>) -> Result<Option<AirParams>, Problem> {
        let Some(air_bps) = self.air else {
            let given = [
                (self.duty.is_some(), "duty"),
                (self.ecc.is_some(), "ecc"),
                (self.tdm.is_some(), "tdm"),
            ];
            return match given.iter().find(|(set, _)| *set) {
                Some((_, key)) => Err(Problem::Needs {
                    key: format!("{key}="),
                    needs: "air=BITS_PER_S (e.g. baud=57600&air=64k)",
                }),
                None => Ok(None),
            };
        };
        if baud.is_none() {
            return Err(Problem::Needs {
                key: format!("air={air_bps}"),
                needs: "baud=N: the radios' serial side (e.g. baud=57600&air=64k)",
            });
        }
        Ok(Some(AirParams {
            air_bps,
            duty: self.duty.unwrap_or(1.0),
            ecc: self.ecc.unwrap_or(false),
            tdm_round: self.tdm.unwrap_or(DEFAULT_TDM_ROUND),
        }))
    }
}

/// The path keys, read in any order and checked together once the
/// query is read: each list's length is `paths=`.
#[derive(Default)]
struct PathKeys {
    paths: Option<usize>,
    /// Each list with its value as given, for the error that counts it.
    loss: Option<(String, Vec<f64>)>,
    delay: Option<(String, Vec<Duration>)>,
    outage: Option<(String, Vec<Option<Outage>>)>,
}

/// A `path_` list: one entry a path, comma-separated, each read by
/// `entry`.
fn list<T>(
    value: &str,
    entry: impl Fn(&str) -> Result<T, Problem>,
) -> Result<(String, Vec<T>), Problem> {
    let entries = value.split(',').map(entry).collect::<Result<_, _>>()?;
    Ok((value.to_string(), entries))
}

/// `none` or `START+LENGTH`: one path's outage.
fn path_outage(key: &str, value: &str, entry: &str) -> Result<Option<Outage>, Problem> {
    if entry == "none" {
        return Ok(None);
    }
    let expected = "none or START+LENGTH for each path, e.g. path_outage=none,30s+5s";
    let (start, length) = entry
        .split_once('+')
        .ok_or_else(|| Problem::expected(key, value, expected))?;
    let part = |p| duration(key, p).map_err(|_| Problem::expected(key, value, expected));
    Ok(Some((part(start)?, part(length)?)))
}

impl PathKeys {
    fn set(&mut self, key: &str, value: &str) -> Result<(), Problem> {
        // An entry's problem names the whole list, as the user wrote it.
        let whole = |p: Problem| match p {
            Problem::Percent { key, source, .. } => Problem::Percent {
                key,
                value: value.to_string(),
                source,
            },
            Problem::Duration { key, source, .. } => Problem::Duration {
                key,
                value: value.to_string(),
                source,
            },
            other => other,
        };
        match key {
            "paths" => {
                let range = "1 to 4 (a MAVProxy log numbers four links)";
                self.paths = Some(bounded(key, value, 1..=MAX_PATHS, range)?);
            }
            "path_loss" => self.loss = Some(list(value, |e| percent(key, e).map_err(whole))?),
            "path_delay" => self.delay = Some(list(value, |e| duration(key, e).map_err(whole))?),
            "path_outage" => self.outage = Some(list(value, |e| path_outage(key, value, e))?),
            _ => return Err(Problem::UnknownKey(key.to_string())),
        }
        Ok(())
    }

    /// The paths, or none without `paths=` (then no `path_` key may be
    /// given).
    fn params(self) -> Result<Vec<PathParams>, Problem> {
        let given = [
            ("path_loss", self.loss.as_ref().map(|(v, l)| (v, l.len()))),
            ("path_delay", self.delay.as_ref().map(|(v, l)| (v, l.len()))),
            (
                "path_outage",
                self.outage.as_ref().map(|(v, l)| (v, l.len())),
            ),
        ];
        let Some(paths) = self.paths else {
            return match given.iter().find(|(_, list)| list.is_some()) {
                Some((key, _)) => Err(Problem::Needs {
                    key: format!("{key}="),
                    needs:
                        "paths=N: how many paths the frames take (e.g. paths=2&path_loss=10%,2%)",
                }),
                None => Ok(Vec::new()),
            };
        };
        for (key, list) in given {
            if let Some((value, given)) = list.filter(|(_, n)| *n != paths) {
                return Err(Problem::PathCount {
                    key,
                    value: value.clone(),
                    given,
                    paths,
                });
            }
        }
        Ok((0..paths)
            .map(|k| PathParams {
                loss: self.loss.as_ref().map_or(0.0, |(_, l)| l[k]),
                delay: self.delay.as_ref().map_or(Duration::ZERO, |(_, l)| l[k]),
                outage: self.outage.as_ref().and_then(|(_, l)| l[k]),
            })
            .collect())
    }
}

/// A signed duration up to ten years: `1.5s`, `-250ms`, `+2h`.
fn offset_ns(key: &str, value: &str) -> Result<i64, Problem> {
    let (negative, magnitude) = match value.strip_prefix('-') {
        Some(rest) => (true, rest),
        None => (false, value.strip_prefix('+').unwrap_or(value)),
    };
    let ns = humantime::parse_duration(magnitude)
        .ok()
        .and_then(|d| i64::try_from(d.as_nanos()).ok())
        .filter(|ns| *ns <= 10 * 365 * 86_400 * 1_000_000_000)
        .ok_or_else(|| {
            Problem::expected(key, value, "a duration up to 10 years, e.g. 1.5s or -250ms")
        })?;
    Ok(if negative { -ns } else { ns })
}

/// A whole number within `range`, said as `expected` when it is not.
fn bounded<T>(
    key: &str,
    value: &str,
    range: impl std::ops::RangeBounds<T>,
    expected: &'static str,
) -> Result<T, Problem>
where
    T: std::str::FromStr + PartialOrd,
{
    let n: T = number(key, value, expected)?;
    if !range.contains(&n) {
        return Err(Problem::expected(key, value, expected));
    }
    Ok(n)
}

impl SimParams {
    /// Parses the part after `sim:`: empty, or `?key=value&key=value`.
    pub fn parse(query: &str) -> Result<Self, SimParamsError> {
        Self::parse_query(query).map_err(SimParamsError)
    }

    fn parse_query(query: &str) -> Result<Self, Problem> {
        let mut p = SimParams::default();
        let mut air = AirKeys::default();
        let mut paths = PathKeys::default();
        let query = query.strip_prefix('?').unwrap_or(query);
        let mut seen: Vec<&str> = Vec::new();
        for pair in query.split('&').filter(|s| !s.is_empty()) {
            let (key, value) = pair
                .split_once('=')
                .ok_or_else(|| Problem::NotKeyValue(pair.to_string()))?;
            // `loss=5%&loss=6%` would silently mean 6 %; streams add up.
            if key != "stream" && seen.contains(&key) {
                return Err(Problem::Twice(key.to_string()));
            }
            seen.push(key);
            if key == "paths" || key.starts_with("path_") {
                paths.set(key, value)?;
            } else {
                p.set(key, value, &mut air)?;
            }
        }
        p.air = air.params(p.baud)?;
        p.paths = paths.params()?;
        p.check()?;
        Ok(p)
    }

    /// Sets one key of the query.
    fn set(&mut self, key: &str, value: &str, air: &mut AirKeys) -> Result<(), Problem> {
        match key {
            "responders" => self.responders = bounded(key, value, 1..=1000, "1 to 1000")?,
            "sysid" => self.first_sysid = bounded(key, value, 1..=255, "1 to 255")?,
            "compid" => self.compid = bounded(key, value, 1..=255, "1 to 255")?,
            "delay" => self.delay = duration(key, value)?,
            "jitter" => self.jitter = duration(key, value)?,
            "hold" => self.hold = duration(key, value)?,
            "loss" => self.loss = percent(key, value)?,
            "dup" => self.dup = percent(key, value)?,
            "reorder" => self.reorder = percent(key, value)?,
            "seed" => self.seed = number(key, value, "a whole number")?,
            "ping" => self.answer_ping = switch(key, value)?,
            "heartbeat" => self.heartbeat = switch(key, value)?,
            "outage" => {
                let (start, length) = value.split_once('+').ok_or_else(|| {
                    Problem::expected(key, value, "START+LENGTH, e.g. outage=30s+5s")
                })?;
                self.outage = Some((duration(key, start)?, duration(key, length)?));
            }
            "outage_every" => {
                self.outage_every =
                    Some(parse_duration(value).map_err(|source| Problem::Duration {
                        key: key.to_string(),
                        value: value.to_string(),
                        source,
                    })?)
            }
            "spike" => self.spike = percent(key, value)?,
            "spike_delay" => self.spike_delay = duration(key, value)?,
            "stream" => self
                .streams
                .extend(
                    telemetry::parse_list(value).map_err(|source| Problem::Stream {
                        key: key.to_string(),
                        value: value.to_string(),
                        source,
                    })?,
                ),
            "loss_down" => self.loss_down = percent(key, value)?,
            "dup_down" => self.dup_down = percent(key, value)?,
            "reorder_down" => self.reorder_down = percent(key, value)?,
            "loss_up" => self.loss_up = percent(key, value)?,
            "dup_up" => self.dup_up = percent(key, value)?,
            "queue_up" => self.queue_up = Some(Queue::parse(key, value)?),
            "queue_down" => self.queue_down = Some(Queue::parse(key, value)?),
            "clock" | "offset" | "drift" => self.set_clock(key, value)?,
            "params" | "mission" | "file" | "transfer_rate" => self.set_serve(key, value)?,
            "baud" | "radio" | "buffer" | "air" | "duty" | "ecc" | "tdm" => {
                self.set_radio(key, value, air)?
            }
            _ => return Err(Problem::UnknownKey(key.to_string())),
        }
        Ok(())
    }

    /// What the responders serve: `params=`, `mission=`, `file=`,
    /// `transfer_rate=`.
    fn set_serve(&mut self, key: &str, value: &str) -> Result<(), Problem> {
        match key {
            "params" => self.serve.params = bounded(key, value, 0..=MAX_PARAMS, "0 to 10000")?,
            "mission" => self.serve.mission = bounded(key, value, 0..=MAX_ITEMS, "0 to 10000")?,
            "file" => {
                let bytes = "0 to 1073741824 bytes";
                self.serve.file_size = bounded(key, value, 0..=MAX_FILE_SIZE, bytes)?;
            }
            _ => {
                let hz = "frames a second above 0, at most 1000000";
                self.transfer_rate = number(key, value, hz)?;
                if !(self.transfer_rate > 0.0 && self.transfer_rate <= 1e6) {
                    return Err(Problem::expected(key, value, hz));
                }
            }
        }
        Ok(())
    }

    /// The responders' clocks: `clock=`, `offset=`, `drift=`.
    fn set_clock(&mut self, key: &str, value: &str) -> Result<(), Problem> {
        match key {
            "clock" => {
                self.virtual_clock = match value {
                    "virtual" => true,
                    "real" => false,
                    _ => return Err(Problem::expected(key, value, "real or virtual")),
                }
            }
            "offset" => self.clock_offset_ns = offset_ns(key, value)?,
            _ => {
                self.drift_ppm = number(key, value, "parts per million, -1000000 to 1000000")?;
                if !self.drift_ppm.is_finite() || self.drift_ppm.abs() > 1e6 {
                    return Err(Problem::expected(key, value, "-1000000 to 1000000 ppm"));
                }
            }
        }
        Ok(())
    }

    /// A radio link: `baud=`, `radio=`, `buffer=`, and the air keys.
    fn set_radio(&mut self, key: &str, value: &str, air: &mut AirKeys) -> Result<(), Problem> {
        match key {
            "baud" => {
                let baud = "a baud rate from 300 to 10000000";
                self.baud = Some(bounded(key, value, 300..=10_000_000, baud)?);
            }
            "radio" => self.radio = switch(key, value)?,
            "buffer" => {
                self.buffer = bounded(key, value, 16..=1 << 20, "16 to 1048576 bytes")?;
            }
            "air" => air.air = Some(bit_rate(key, value)?),
            "duty" => {
                let d = percent(key, value)?;
                if d <= 0.0 {
                    return Err(Problem::expected(key, value, "more than 0%"));
                }
                air.duty = Some(d);
            }
            "ecc" => air.ecc = Some(switch(key, value)?),
            _ => {
                let round = duration(key, value)?;
                if !(Duration::from_millis(1)..=Duration::from_secs(1)).contains(&round) {
                    return Err(Problem::expected(key, value, "1ms to 1s"));
                }
                air.tdm = Some(round);
            }
        }
        Ok(())
    }

    /// What no single key can check.
    fn check(&self) -> Result<(), Problem> {
        if self.baud.is_none() && self.buffer != DEFAULT_BUFFER_BYTES {
            return Err(Problem::Needs {
                key: "buffer=".into(),
                needs: "baud=N: only a serial radio link has a buffer",
            });
        }
        match (self.outage, self.outage_every) {
            (None, Some(_)) => {
                return Err(Problem::Needs {
                    key: "outage_every".into(),
                    needs: "outage=START+LENGTH",
                })
            }
            (Some((_, outage)), Some(every)) if every <= outage => {
                return Err(Problem::OutageEvery { every, outage })
            }
            _ => {}
        }
        telemetry::check_distinct(&self.streams).map_err(Problem::Streams)?;
        if let Some(rate) = telemetry::heartbeat_rate(&self.streams).filter(|_| !self.heartbeat) {
            return Err(Problem::Needs {
                key: format!("stream=HEARTBEAT@{rate}"),
                needs: "heartbeat=on (heartbeat=off sends none)",
            });
        }
        // Responders are numbered by sysid; the last one must still fit.
        if usize::from(self.first_sysid) + usize::from(self.responders) - 1 > 255 * 255 {
            return Err(Problem::TooManyResponders);
        }
        Ok(())
    }

    /// HEARTBEATs a second: 1, or what `stream=HEARTBEAT@HZ` says.
    pub(crate) fn heartbeat_rate(&self) -> Option<f64> {
        self.heartbeat
            .then(|| telemetry::heartbeat_rate(&self.streams).unwrap_or(1.0))
    }

    /// The ids of responder `i`: sysids count up from `first_sysid`, and
    /// past 255 the component id counts up too, so 1,000 stay distinct.
    pub(crate) fn responder_id(&self, i: u16) -> SysComp {
        let slot = usize::from(self.first_sysid) - 1 + usize::from(i);
        SysComp::new(
            (slot % 255 + 1) as u8,
            (usize::from(self.compid) - 1 + slot / 255) as u8 % 255 + 1,
        )
    }
}

impl fmt::Display for SimParams {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "sim:?responders={}&delay={}&jitter={}&loss={}%&dup={}%&reorder={}%&seed={}",
            self.responders,
            humantime::format_duration(self.delay),
            humantime::format_duration(self.jitter),
            self.loss * 100.0,
            self.dup * 100.0,
            self.reorder * 100.0,
            self.seed
        )?;
        // Keys that tell two links apart (two vehicles' ids; one answering
        // PING, one not), printed only when not the default so the usual
        // name stays short.
        let defaults = SimParams::default();
        if self.first_sysid != defaults.first_sysid {
            write!(f, "&sysid={}", self.first_sysid)?;
        }
        if self.compid != defaults.compid {
            write!(f, "&compid={}", self.compid)?;
        }
        if self.hold != defaults.hold {
            write!(f, "&hold={}", humantime::format_duration(self.hold))?;
        }
        if !self.answer_ping {
            write!(f, "&ping=off")?;
        }
        if !self.heartbeat {
            write!(f, "&heartbeat=off")?;
        }
        if self.clock_offset_ns != 0 {
            // Seconds as a number: humantime's "3s 250ms" has a space.
            write!(f, "&offset={}s", self.clock_offset_ns as f64 / 1e9)?;
        }
        if self.drift_ppm != 0.0 {
            write!(f, "&drift={}", self.drift_ppm)?;
        }
        if let Some(baud) = self.baud {
            write!(f, "&baud={baud}")?;
        }
        if let Some(air) = &self.air {
            write!(f, "&air={}", air.air_bps)?;
            if air.duty != 1.0 {
                write!(f, "&duty={}%", air.duty * 100.0)?;
            }
            if air.ecc {
                write!(f, "&ecc=on")?;
            }
            if air.tdm_round != DEFAULT_TDM_ROUND {
                write!(f, "&tdm={}", humantime::format_duration(air.tdm_round))?;
            }
        }
        if self.buffer != DEFAULT_BUFFER_BYTES {
            write!(f, "&buffer={}", self.buffer)?;
        }
        if self.radio {
            write!(f, "&radio=on")?;
        }
        if let Some((start, length)) = self.outage {
            write!(
                f,
                "&outage={}+{}",
                humantime::format_duration(start),
                humantime::format_duration(length)
            )?;
        }
        if let Some(every) = self.outage_every {
            write!(f, "&outage_every={}", humantime::format_duration(every))?;
        }
        if self.spike > 0.0 {
            write!(
                f,
                "&spike={}%&spike_delay={}",
                self.spike * 100.0,
                humantime::format_duration(self.spike_delay)
            )?;
        }
        if !self.streams.is_empty() {
            let streams: Vec<String> = self.streams.iter().map(ToString::to_string).collect();
            write!(f, "&stream={}", streams.join(","))?;
        }
        self.write_directions(f)?;
        self.write_paths(f)?;
        self.write_serve(f)
    }
}

/// A duration as a `path_` list prints it: humantime's, without its
/// spaces ("1s500ms"), so a link's name has none.
fn compact(d: Duration) -> String {
    humantime::format_duration(d).to_string().replace(' ', "")
}

impl SimParams {
    /// What the responders serve, where not the defaults.
    fn write_serve(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let ServeSpec {
            params,
            mission,
            file_size,
        } = self.serve;
        for (key, value, default) in [
            ("params", u32::from(params), u32::from(DEFAULT_SERVE.params)),
            (
                "mission",
                u32::from(mission),
                u32::from(DEFAULT_SERVE.mission),
            ),
            ("file", file_size, DEFAULT_SERVE.file_size),
        ] {
            if value != default {
                write!(f, "&{key}={value}")?;
            }
        }
        if self.transfer_rate != DEFAULT_TRANSFER_RATE {
            write!(f, "&transfer_rate={}", self.transfer_rate)?;
        }
        Ok(())
    }

    /// The per-direction faults and queues, when set.
    fn write_directions(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (key, share) in [
            ("loss_down", self.loss_down),
            ("dup_down", self.dup_down),
            ("reorder_down", self.reorder_down),
            ("loss_up", self.loss_up),
            ("dup_up", self.dup_up),
        ] {
            if share > 0.0 {
                write!(f, "&{key}={}%", share * 100.0)?;
            }
        }
        for (key, queue) in [("queue_up", self.queue_up), ("queue_down", self.queue_down)] {
            if let Some(queue) = queue {
                write!(f, "&{key}={queue}")?;
            }
        }
        Ok(())
    }

    /// `paths=` and each `path_` list that is not all defaults.
    fn write_paths(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.paths.is_empty() {
            return Ok(());
        }
        write!(f, "&paths={}", self.paths.len())?;
        // Each list with what a path without the fault shows.
        let lists: [(&str, &str, PathEntry); 3] = [
            ("path_loss", "0%", |p| {
                (p.loss > 0.0).then(|| format!("{}%", p.loss * 100.0))
            }),
            ("path_delay", "0s", |p| {
                (!p.delay.is_zero()).then(|| compact(p.delay))
            }),
            ("path_outage", "none", |p| {
                p.outage
                    .map(|(start, length)| format!("{}+{}", compact(start), compact(length)))
            }),
        ];
        for (key, default, entry) in lists {
            let entries: Vec<Option<String>> = self.paths.iter().map(entry).collect();
            if entries.iter().any(Option::is_some) {
                let shown: Vec<String> = entries
                    .into_iter()
                    .map(|e| e.unwrap_or_else(|| default.to_string()))
                    .collect();
                write!(f, "&{key}={}", shown.join(","))?;
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_queue_grows_to_its_peak_then_drains_as_fast() {
        let p = SimParams::parse("?queue_down=1.5s@8s&queue_up=20ms@1s").unwrap();
        let q = p.queue_down.unwrap();
        let at = |s: f64| q.delay_at(Duration::from_secs_f64(s)).as_secs_f64();
        for (t, delay) in [
            (0.0, 0.0),
            (4.0, 0.75),
            (8.0, 1.5),
            (12.0, 0.75),
            (16.0, 0.0),
        ] {
            assert!((at(t) - delay).abs() < 1e-9, "{t}: {}", at(t));
        }
        assert_eq!(at(100.0), 0.0);
        assert_eq!(p.queue_up.unwrap().peak, Duration::from_millis(20));
        let named = p.to_string();
        assert!(
            named.ends_with("&queue_up=0.02s@1s&queue_down=1.5s@8s"),
            "{named}"
        );
        for bad in ["1.5s", "9s@8s", "1s@0s", "x@8s"] {
            let e = SimParams::parse(&format!("?queue_down={bad}")).unwrap_err();
            assert!(
                e.to_string().starts_with(&format!("queue_down={bad}")),
                "{e}"
            );
        }
    }

    #[test]
    fn what_is_served_and_how_fast() {
        let p = SimParams::parse("?params=1000&mission=0&file=100&transfer_rate=50").unwrap();
        assert_eq!(
            (
                p.serve.params,
                p.serve.mission,
                p.serve.file_size,
                p.transfer_rate
            ),
            (1000, 0, 100, 50.0)
        );
        assert!(p
            .to_string()
            .ends_with("&params=1000&mission=0&file=100&transfer_rate=50"));
        let d = SimParams::default();
        assert_eq!(
            (
                d.serve.params,
                d.serve.mission,
                d.serve.file_size,
                d.transfer_rate
            ),
            (500, 20, 65536, 1000.0)
        );
        assert!(!d.to_string().contains("params="));
        for (query, error) in [
            ("?params=10001", "params=10001: expected 0 to 10000"),
            ("?mission=-1", "mission=-1: expected 0 to 10000"),
            (
                "?file=1073741825",
                "file=1073741825: expected 0 to 1073741824 bytes",
            ),
            (
                "?transfer_rate=0",
                "transfer_rate=0: expected frames a second above 0",
            ),
            (
                "?transfer_rate=nan",
                "transfer_rate=nan: expected frames a second above 0",
            ),
        ] {
            let e = SimParams::parse(query).unwrap_err().to_string();
            assert!(e.starts_with(error), "{query}: {e}");
        }
    }

    #[test]
    fn parses_every_key() {
        let p = SimParams::parse(
            "?responders=3&sysid=10&compid=2&delay=20ms&jitter=5ms&loss=2%&dup=1&reorder=0.5%\
             &hold=30ms&seed=7&clock=virtual&ping=off&heartbeat=on",
        )
        .unwrap();
        assert_eq!(p.responders, 3);
        assert_eq!(p.responder_id(2), SysComp::new(12, 2));
        assert_eq!(p.delay, Duration::from_millis(20));
        assert_eq!(p.jitter, Duration::from_millis(5));
        assert!((p.loss - 0.02).abs() < 1e-12);
        assert!((p.dup - 0.01).abs() < 1e-12);
        assert!((p.reorder - 0.005).abs() < 1e-12);
        assert_eq!(p.seed, 7);
        assert!(p.virtual_clock);
        assert!(!p.answer_ping);
        assert_eq!(SimParams::parse("").unwrap(), SimParams::default());
        let p = SimParams::parse("?offset=-1.5s&drift=-20.5").unwrap();
        assert_eq!(p.clock_offset_ns, -1_500_000_000);
        assert_eq!(p.drift_ppm, -20.5);
        assert_eq!(
            SimParams::parse("?offset=+250ms").unwrap().clock_offset_ns,
            250_000_000
        );
        let p = SimParams::parse("?outage=30s+5s&spike=1%&spike_delay=2s").unwrap();
        assert_eq!(
            p.outage,
            Some((Duration::from_secs(30), Duration::from_secs(5)))
        );
        assert!((p.spike - 0.01).abs() < 1e-12);
        assert_eq!(p.spike_delay, Duration::from_secs(2));
        assert_eq!(
            SimParams::parse(&p.to_string()[4..]).unwrap().outage,
            p.outage
        );
        let p = SimParams::parse("?outage=30m+45s&outage_every=6h").unwrap();
        assert_eq!(p.outage_every, Some(Duration::from_secs(6 * 3600)));
        assert!(p.to_string().ends_with("&outage=30m+45s&outage_every=6h"));
    }

    #[test]
    fn rejects_bad_values_with_the_reason() {
        for (q, needle) in [
            ("?loss=120%", "percentage"),
            ("?outage=5s", "START+LENGTH"),
            ("?outage=5s+2h", "at most 1h"),
            ("?outage_every=6h", "needs outage"),
            ("?outage=1h+5s&outage_every=5s", "longer than the outage"),
            ("?outage=1h+5s&outage_every=400d", "at most 365 days"),
            ("?spike=-1", "percentage"),
            ("?responders=0", "1 to 1000"),
            ("?delay=soon", "delay=soon"),
            ("?delay=2h", "at most 1h"),
            ("?warp=9", "unknown key 'warp'"),
            ("?loss", "not key=value"),
            ("?clock=fast", "real or virtual"),
            ("?offset=soon", "offset=soon"),
            ("?offset=20y", "up to 10 years"),
            ("?drift=2e6", "ppm"),
            ("?drift=fast", "parts per million"),
            ("?loss=5%&loss=6%", "loss= is given twice"),
            ("?clock=virtual&clock=real", "clock= is given twice"),
        ] {
            let err = SimParams::parse(q).unwrap_err().to_string();
            assert!(err.contains(needle), "{q}: {err}");
        }
    }

    #[test]
    fn links_that_differ_only_in_ids_or_answering_ping_print_apart_and_back() {
        let queries = [
            "",
            "?sysid=7",
            "?sysid=8",
            "?compid=2",
            "?ping=off",
            "?heartbeat=off",
            "?hold=80ms",
        ];
        let printed: Vec<String> = queries
            .iter()
            .map(|q| SimParams::parse(q).unwrap().to_string())
            .collect();
        for (i, name) in printed.iter().enumerate() {
            assert_eq!(
                SimParams::parse(&name[4..]).unwrap(),
                SimParams::parse(queries[i]).unwrap(),
                "{name}"
            );
            assert!(!printed[..i].contains(name), "{name} printed twice");
        }
        assert!(printed[1].ends_with("&sysid=7"), "{}", printed[1]);
        assert!(printed[4].ends_with("&ping=off"), "{}", printed[4]);
    }

    #[test]
    fn streams_and_per_direction_faults_parse_print_back_and_say_what_is_wrong() {
        let p = SimParams::parse(
            "?stream=ATTITUDE@50,GLOBAL_POSITION_INT@5&stream=HEARTBEAT@2&loss_down=10%\
             &dup_down=1&reorder_down=2%&loss_up=20%&dup_up=3%",
        )
        .unwrap();
        let streams: Vec<String> = p.streams.iter().map(ToString::to_string).collect();
        assert_eq!(
            streams,
            ["ATTITUDE@50", "GLOBAL_POSITION_INT@5", "HEARTBEAT@2"]
        );
        assert_eq!(p.heartbeat_rate(), Some(2.0));
        assert!((p.loss_down - 0.1).abs() < 1e-12 && (p.dup_down - 0.01).abs() < 1e-12);
        assert!((p.reorder_down - 0.02).abs() < 1e-12 && (p.loss_up - 0.2).abs() < 1e-12);
        assert!((p.dup_up - 0.03).abs() < 1e-12);
        let printed = p.to_string();
        assert!(
            printed.ends_with(
                "&stream=ATTITUDE@50,GLOBAL_POSITION_INT@5,HEARTBEAT@2&loss_down=10%\
                 &dup_down=1%&reorder_down=2%&loss_up=20%&dup_up=3%"
            ),
            "{printed}"
        );
        assert_eq!(SimParams::parse(&printed[4..]).unwrap(), p);
        // The default HEARTBEAT is 1 Hz; none with heartbeat=off.
        assert_eq!(SimParams::default().heartbeat_rate(), Some(1.0));
        let off = SimParams::parse("?heartbeat=off&stream=ATTITUDE@10").unwrap();
        assert_eq!(off.heartbeat_rate(), None);
        for (q, message) in [
            (
                "?stream=ATTITUDE",
                "stream=ATTITUDE: 'ATTITUDE': expected MSG@HZ: ATTITUDE@HZ, \
                 GLOBAL_POSITION_INT@HZ or HEARTBEAT@HZ, e.g. ATTITUDE@50",
            ),
            (
                "?stream=ATTITUDE@50,BYTES@100",
                "stream=ATTITUDE@50,BYTES@100: 'BYTES@100': unknown message BYTES; expected \
                 MSG@HZ: ATTITUDE@HZ, GLOBAL_POSITION_INT@HZ or HEARTBEAT@HZ, e.g. ATTITUDE@50",
            ),
            (
                "?stream=ATTITUDE@0",
                "stream=ATTITUDE@0: 'ATTITUDE@0': the rate must be a number above 0 and at \
                 most 10000 (messages per second)",
            ),
            (
                "?stream=ATTITUDE@5&stream=ATTITUDE@10",
                "stream=: ATTITUDE is streamed twice: give each message once",
            ),
            (
                "?stream=HEARTBEAT@5&heartbeat=off",
                "stream=HEARTBEAT@5 needs heartbeat=on (heartbeat=off sends none)",
            ),
            (
                "?loss_down=150",
                "loss_down=150: '150' is not a percentage from 0 to 100",
            ),
        ] {
            assert_eq!(SimParams::parse(q).unwrap_err().to_string(), message, "{q}");
        }
        for (q, key) in [
            ("?dup_down=x", "dup_down=x: "),
            ("?reorder_down=-1", "reorder_down=-1: "),
            ("?loss_up=101%", "loss_up=101%: "),
            ("?dup_up=often", "dup_up=often: "),
        ] {
            let err = SimParams::parse(q).unwrap_err().to_string();
            assert!(err.starts_with(key) && !err.contains('\n'), "{q}: {err}");
        }
    }

    #[test]
    fn a_thousand_responders_have_distinct_ids() {
        let p = SimParams::parse("?responders=1000").unwrap();
        let ids: std::collections::HashSet<_> = (0..1000).map(|i| p.responder_id(i)).collect();
        assert_eq!(ids.len(), 1000);
        assert!(ids.iter().all(|id| id.sysid != 0 && id.compid != 0));
    }

    #[test]
    fn baud_and_radio_parse_and_bad_values_are_refused() {
        let p = SimParams::parse("?baud=57600&radio=on").unwrap();
        assert_eq!((p.baud, p.radio), (Some(57_600), true));
        assert!(p.to_string().ends_with("&baud=57600&radio=on"));
        for bad in ["?baud=0", "?baud=fast", "?radio=maybe"] {
            assert!(SimParams::parse(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn radio_physics_keys_parse_print_back_and_need_their_partners() {
        let p =
            SimParams::parse("?baud=57600&air=64k&duty=50%&ecc=on&tdm=40ms&buffer=200").unwrap();
        let air = p.air.unwrap();
        assert_eq!((air.air_bps, air.duty, air.ecc), (64_000, 0.5, true));
        assert_eq!((air.tdm_round, p.buffer), (Duration::from_millis(40), 200));
        let printed = p.to_string();
        assert!(
            printed.ends_with("&baud=57600&air=64000&duty=50%&ecc=on&tdm=40ms&buffer=200"),
            "{printed}"
        );
        assert_eq!(SimParams::parse(&printed[4..]).unwrap(), p);
        // Defaults are left out of the name.
        let p = SimParams::parse("?baud=115200&air=1.5M").unwrap();
        assert!(p.to_string().ends_with("&baud=115200&air=1500000"), "{p}");
        assert_eq!(p.air.unwrap().tdm_round, DEFAULT_TDM_ROUND);
        for (q, needle) in [
            ("?air=64k", "needs baud=N"),
            ("?baud=57600&duty=50%", "duty= needs air="),
            ("?baud=57600&ecc=on", "ecc= needs air="),
            ("?buffer=200", "buffer= needs baud=N"),
            ("?baud=57600&air=fast", "expected an air rate"),
            ("?baud=57600&air=20M", "expected an air rate"),
            ("?baud=57600&air=64k&duty=0", "more than 0%"),
            ("?baud=57600&air=64k&tdm=5s", "1ms to 1s"),
            ("?baud=57600&buffer=2", "16 to 1048576"),
        ] {
            let err = SimParams::parse(q).unwrap_err().to_string();
            assert!(err.contains(needle), "{q}: {err}");
        }
    }

    #[test]
    fn paths_parse_print_back_and_say_what_is_wrong() {
        let p = SimParams::parse(
            "?paths=2&path_loss=10%,2%&path_delay=20ms,100ms&path_outage=none,30s+5s",
        )
        .unwrap();
        let ms = Duration::from_millis;
        assert_eq!(
            p.paths,
            [
                PathParams {
                    loss: 0.1,
                    delay: ms(20),
                    outage: None
                },
                PathParams {
                    loss: 0.02,
                    delay: ms(100),
                    outage: Some((ms(30_000), ms(5_000)))
                },
            ]
        );
        let printed = p.to_string();
        assert!(
            printed.ends_with(
                "&paths=2&path_loss=10%,2%&path_delay=20ms,100ms&path_outage=none,30s+5s"
            ),
            "{printed}"
        );
        assert_eq!(SimParams::parse(&printed[4..]).unwrap(), p);
        // Lists in any order, before paths=; all-default lists left out of
        // the name, and no space in it.
        let p = SimParams::parse("?path_delay=0,1.5s,20ms&paths=3").unwrap();
        let printed = p.to_string();
        assert!(
            printed.ends_with("&paths=3&path_delay=0s,1s500ms,20ms"),
            "{printed}"
        );
        assert_eq!(SimParams::parse(&printed[4..]).unwrap(), p);
        assert_eq!(p.paths[2].loss, 0.0);
        assert_eq!(
            SimParams::parse("?paths=1").unwrap().paths,
            [PathParams::default()]
        );
        assert!(SimParams::default().paths.is_empty());
        for (q, message) in [
            (
                "?paths=5",
                "paths=5: expected 1 to 4 (a MAVProxy log numbers four links)",
            ),
            (
                "?paths=0",
                "paths=0: expected 1 to 4 (a MAVProxy log numbers four links)",
            ),
            (
                "?path_loss=10%",
                "path_loss= needs paths=N: how many paths the frames take \
                 (e.g. paths=2&path_loss=10%,2%)",
            ),
            (
                "?paths=2&path_loss=10%",
                "path_loss=10%: 1 given for paths=2: give one per path",
            ),
            (
                "?path_delay=20ms,1s,2s&paths=2",
                "path_delay=20ms,1s,2s: 3 given for paths=2: give one per path",
            ),
            (
                "?paths=2&path_loss=10%,x",
                "path_loss=10%,x: 'x' is not a percentage from 0 to 100",
            ),
            (
                "?paths=2&path_delay=20ms,2h",
                "path_delay=20ms,2h: '2h': at most 1h",
            ),
            (
                "?paths=2&path_outage=none,30s",
                "path_outage=none,30s: expected none or START+LENGTH for each path, \
                 e.g. path_outage=none,30s+5s",
            ),
            (
                "?paths=2&paths=3",
                "paths= is given twice: give each key once",
            ),
        ] {
            assert_eq!(SimParams::parse(q).unwrap_err().to_string(), message, "{q}");
        }
        let err = SimParams::parse("?paths=2&path_jitter=1ms")
            .unwrap_err()
            .to_string();
        assert!(
            err.starts_with("unknown key 'path_jitter'; keys: "),
            "{err}"
        );
        assert!(err.contains("path_outage=none|START+LENGTH"), "{err}");
    }
}
