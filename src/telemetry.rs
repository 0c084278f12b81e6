//! What a vehicle sends unasked: telemetry streams (`MSG@HZ`) and the
//! schedule each keeps. Shared by the simulated link's responders
//! (`sim:?stream=...`) and by `mavping respond --stream`, as
//! [`crate::answering`] is for the answers.
//!
//! The names and rates are `--load`'s ([`LoadSpec`]), less `BYTES` and
//! plus `HEARTBEAT`: a stream of HEARTBEAT sets the rate of the sender's
//! own HEARTBEAT (1 Hz by default), it is not a second one.

use std::fmt;
use std::str::FromStr;

use serde::Serialize;
use thiserror::Error;

use crate::frame::{self, Header, Msg, Version};

/// Filler payload per frame: 117-byte frames in MAVLink 2, about a
/// telemetry burst's size, so a byte rate is many frames, not a few.
pub(crate) const FILLER_PAYLOAD: u8 = 100;
/// The highest rate a stream takes (frames/s, or bytes/s for filler).
pub(crate) const MAX_LOAD_RATE: f64 = 1_000_000.0;

/// What a stream sends.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "SCREAMING_SNAKE_CASE")]
pub(crate) enum LoadKind {
    Attitude,
    GlobalPositionInt,
    /// Filler at a rate in bytes per second.
    Bytes,
}

impl LoadKind {
    pub(crate) fn name(self) -> &'static str {
        match self {
            LoadKind::Attitude => "ATTITUDE",
            LoadKind::GlobalPositionInt => "GLOBAL_POSITION_INT",
            LoadKind::Bytes => "BYTES",
        }
    }

    /// The message a frame of this stream carries (filler for `BYTES`).
    pub(crate) fn msg(self, time_boot_ms: u32) -> Msg {
        match self {
            LoadKind::Attitude => Msg::Attitude { time_boot_ms },
            LoadKind::GlobalPositionInt => Msg::GlobalPositionInt { time_boot_ms },
            LoadKind::Bytes => Msg::Filler {
                len: FILLER_PAYLOAD,
            },
        }
    }
}

/// One `--load` stream: a message at a rate (frames per second), or
/// `BYTES` at a rate in bytes per second.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct LoadSpec {
    pub(crate) kind: LoadKind,
    pub(crate) rate: f64,
}

/// What a `--load` stream looks like, for its errors.
const EXPECTED_LOAD: &str =
    "expected MSG@RATE: ATTITUDE@HZ, GLOBAL_POSITION_INT@HZ or BYTES@BYTES_PER_S, e.g. ATTITUDE@50";

/// What is wrong with a `--load` stream; the text given is quoted.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
pub(crate) enum LoadSpecError {
    #[error("'{0}': {EXPECTED_LOAD}", EXPECTED_LOAD = EXPECTED_LOAD)]
    NotMsgAtRate(String),
    #[error("'{text}': unknown message {name}; {EXPECTED_LOAD}", EXPECTED_LOAD = EXPECTED_LOAD)]
    UnknownMessage { text: String, name: String },
    /// The rate is not a number in (0, [`MAX_LOAD_RATE`]]; `BYTES`' is in
    /// bytes per second, the messages' in messages per second.
    #[error(
        "'{text}': the rate must be a number above 0 and at most {MAX_LOAD_RATE} ({})",
        if *bytes { "bytes per second" } else { "messages per second" },
        MAX_LOAD_RATE = MAX_LOAD_RATE
    )]
    Rate { text: String, bytes: bool },
}

impl FromStr for LoadSpec {
    type Err = LoadSpecError;

    fn from_str(s: &str) -> Result<Self, LoadSpecError> {
        let (name, rate) = s
            .split_once('@')
            .ok_or_else(|| LoadSpecError::NotMsgAtRate(s.to_string()))?;
        let kind = match name.trim().to_ascii_uppercase().as_str() {
            "ATTITUDE" => LoadKind::Attitude,
            "GLOBAL_POSITION_INT" => LoadKind::GlobalPositionInt,
            "BYTES" => LoadKind::Bytes,
            other => {
                return Err(LoadSpecError::UnknownMessage {
                    text: s.to_string(),
                    name: other.to_string(),
                })
            }
        };
        let rate: f64 = rate
            .trim()
            .parse()
            .ok()
            .filter(|r: &f64| r.is_finite() && *r > 0.0 && *r <= MAX_LOAD_RATE)
            .ok_or_else(|| LoadSpecError::Rate {
                text: s.to_string(),
                bytes: kind == LoadKind::Bytes,
            })?;
        Ok(LoadSpec { kind, rate })
    }
}

impl fmt::Display for LoadSpec {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}@{}", self.kind.name(), self.rate)
    }
}

impl LoadSpec {
    /// Bytes of one of this stream's frames as `version` (and signed)
    /// puts it on the wire.
    pub(crate) fn frame_bytes(&self, version: Version, signed: bool) -> u64 {
        let mut bytes = Vec::new();
        let header = Header {
            sysid: 1,
            compid: 1,
            seq: 0,
        };
        // Signed frames are MAVLink 2, 13 bytes longer.
        let version = if signed { Version::V2 } else { version };
        frame::encode(&mut bytes, version, header, &self.kind.msg(1));
        bytes.len() as u64 + if signed { 13 } else { 0 }
    }

    /// Frames per second.
    pub(crate) fn frame_rate(&self, version: Version, signed: bool) -> f64 {
        match self.kind {
            LoadKind::Bytes => self.rate / self.frame_bytes(version, signed) as f64,
            _ => self.rate,
        }
    }

    /// Bytes per second on the wire.
    pub(crate) fn bytes_per_s(&self, version: Version, signed: bool) -> f64 {
        self.frame_rate(version, signed) * self.frame_bytes(version, signed) as f64
    }
}

/// The highest rate a stream takes, in messages per second.
pub(crate) const MAX_STREAM_RATE: f64 = 10_000.0;

/// What a stream sends.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "SCREAMING_SNAKE_CASE")]
pub(crate) enum StreamKind {
    Attitude,
    GlobalPositionInt,
    /// The sender's own HEARTBEAT, at this rate instead of 1 Hz.
    Heartbeat,
}

impl StreamKind {
    pub(crate) fn name(self) -> &'static str {
        match self {
            StreamKind::Attitude => LoadKind::Attitude.name(),
            StreamKind::GlobalPositionInt => LoadKind::GlobalPositionInt.name(),
            StreamKind::Heartbeat => "HEARTBEAT",
        }
    }

    /// The message at `time_boot_ms` on the sender's clock; a HEARTBEAT
    /// is the sender's own, `heartbeat`.
    pub(crate) fn msg(self, time_boot_ms: u32, heartbeat: &Msg) -> Msg {
        match self {
            StreamKind::Attitude => LoadKind::Attitude.msg(time_boot_ms),
            StreamKind::GlobalPositionInt => LoadKind::GlobalPositionInt.msg(time_boot_ms),
            StreamKind::Heartbeat => *heartbeat,
        }
    }
}

/// One stream: a message at a rate in messages per second.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct StreamSpec {
    pub(crate) kind: StreamKind,
    pub(crate) rate: f64,
}

const EXPECTED_STREAM: &str =
    "expected MSG@HZ: ATTITUDE@HZ, GLOBAL_POSITION_INT@HZ or HEARTBEAT@HZ, e.g. ATTITUDE@50";

/// What is wrong with a stream; the text given is quoted.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
pub(crate) enum StreamSpecError {
    #[error("'{0}': {EXPECTED_STREAM}", EXPECTED_STREAM = EXPECTED_STREAM)]
    NotMsgAtHz(String),
    #[error("'{text}': unknown message {name}; {EXPECTED_STREAM}", EXPECTED_STREAM = EXPECTED_STREAM)]
    UnknownMessage { text: String, name: String },
    #[error(
        "'{0}': the rate must be a number above 0 and at most {MAX_STREAM_RATE} (messages per second)",
        MAX_STREAM_RATE = MAX_STREAM_RATE
    )]
    Rate(String),
    #[error("{0} is streamed twice: give each message once")]
    Twice(&'static str),
}

impl FromStr for StreamSpec {
    type Err = StreamSpecError;

    fn from_str(s: &str) -> Result<Self, StreamSpecError> {
        let (name, rate) = s
            .split_once('@')
            .ok_or_else(|| StreamSpecError::NotMsgAtHz(s.to_string()))?;
        let rate_error = || StreamSpecError::Rate(s.to_string());
        let spec = if name.trim().eq_ignore_ascii_case("HEARTBEAT") {
            // `--load` has no HEARTBEAT: its rate as a telemetry one.
            let load: LoadSpec = format!("ATTITUDE@{rate}")
                .parse()
                .map_err(|_| rate_error())?;
            StreamSpec {
                kind: StreamKind::Heartbeat,
                rate: load.rate,
            }
        } else {
            let load: LoadSpec = s.parse().map_err(|e| match e {
                LoadSpecError::NotMsgAtRate(_) => StreamSpecError::NotMsgAtHz(s.to_string()),
                LoadSpecError::UnknownMessage { name, .. } => StreamSpecError::UnknownMessage {
                    text: s.to_string(),
                    name,
                },
                LoadSpecError::Rate { .. } => rate_error(),
            })?;
            let kind = match load.kind {
                LoadKind::Attitude => StreamKind::Attitude,
                LoadKind::GlobalPositionInt => StreamKind::GlobalPositionInt,
                LoadKind::Bytes => {
                    return Err(StreamSpecError::UnknownMessage {
                        text: s.to_string(),
                        name: "BYTES".into(),
                    })
                }
            };
            StreamSpec {
                kind,
                rate: load.rate,
            }
        };
        if spec.rate > MAX_STREAM_RATE {
            return Err(rate_error());
        }
        Ok(spec)
    }
}

impl fmt::Display for StreamSpec {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}@{}", self.kind.name(), self.rate)
    }
}

/// `ATTITUDE@50,GLOBAL_POSITION_INT@5`: a comma-separated list.
pub(crate) fn parse_list(text: &str) -> Result<Vec<StreamSpec>, StreamSpecError> {
    let specs = text
        .split(',')
        .map(str::parse)
        .collect::<Result<Vec<StreamSpec>, _>>()?;
    check_distinct(&specs)?;
    Ok(specs)
}

/// Each message streamed once: two rates for one message mean nothing.
pub(crate) fn check_distinct(specs: &[StreamSpec]) -> Result<(), StreamSpecError> {
    for (i, s) in specs.iter().enumerate() {
        if specs[..i].iter().any(|t| t.kind == s.kind) {
            return Err(StreamSpecError::Twice(s.kind.name()));
        }
    }
    Ok(())
}

/// The rate of HEARTBEAT among `specs`, if it is streamed.
pub(crate) fn heartbeat_rate(specs: &[StreamSpec]) -> Option<f64> {
    specs
        .iter()
        .find(|s| s.kind == StreamKind::Heartbeat)
        .map(|s| s.rate)
}

/// A stream's timetable, as an autopilot's scheduler keeps one: frame *n*
/// at `phase + n × period` (nanoseconds since the sender started), with
/// `phase` a share of the period, so the rate is exact.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Schedule {
    period_ns: f64,
    phase_ns: f64,
    issued: u64,
}

impl Schedule {
    /// `rate` frames a second, the first `phase` (0 to 1) of a period in.
    pub(crate) fn new(rate: f64, phase: f64) -> Self {
        let period_ns = 1e9 / rate;
        Schedule {
            period_ns,
            phase_ns: phase * period_ns,
            issued: 0,
        }
    }

    /// When the next frame is due.
    pub(crate) fn due_ns(&self) -> u64 {
        (self.phase_ns + self.issued as f64 * self.period_ns).round() as u64
    }

    /// The next frame was sent: on to the one after.
    pub(crate) fn advance(&mut self) {
        self.issued += 1;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn streams_parse_and_bad_ones_say_why() {
        let s = parse_list("ATTITUDE@50,global_position_int@2.5,HEARTBEAT@2").unwrap();
        assert_eq!(
            s.iter().map(|s| (s.kind, s.rate)).collect::<Vec<_>>(),
            [
                (StreamKind::Attitude, 50.0),
                (StreamKind::GlobalPositionInt, 2.5),
                (StreamKind::Heartbeat, 2.0)
            ]
        );
        assert_eq!(s[0].to_string(), "ATTITUDE@50");
        assert_eq!(heartbeat_rate(&s), Some(2.0));
        assert_eq!(heartbeat_rate(&s[..1]), None);
        for (bad, needle) in [
            ("ATTITUDE", "expected MSG@HZ"),
            ("BYTES@100", "unknown message BYTES"),
            ("RAW_IMU@100", "unknown message RAW_IMU"),
            ("ATTITUDE@0", "above 0"),
            ("HEARTBEAT@fast", "above 0"),
            ("ATTITUDE@20000", "at most 10000"),
            ("ATTITUDE@5,ATTITUDE@10", "ATTITUDE is streamed twice"),
            ("ATTITUDE@5,", "''"),
        ] {
            let e = parse_list(bad).unwrap_err().to_string();
            assert!(e.contains(needle), "{bad}: {e}");
            assert!(!e.contains('\n'), "{bad}: {e}");
        }
        assert_eq!(
            "HEARTBEAT@-1"
                .parse::<StreamSpec>()
                .unwrap_err()
                .to_string(),
            "'HEARTBEAT@-1': the rate must be a number above 0 and at most 10000 \
             (messages per second)"
        );
    }

    #[test]
    fn a_schedule_keeps_its_phase_and_an_exact_rate() {
        let mut s = Schedule::new(50.0, 0.25);
        assert_eq!(s.due_ns(), 5_000_000);
        for _ in 0..1000 {
            s.advance();
        }
        assert_eq!(s.due_ns(), 20_005_000_000);
        let mut h = Schedule::new(1.0, 0.0);
        assert_eq!(h.due_ns(), 0);
        h.advance();
        assert_eq!(h.due_ns(), 1_000_000_000);
    }
}
