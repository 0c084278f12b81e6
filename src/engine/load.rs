//! Background load sent beside the probes (`--load MSG@RATE`), the RRUL
//! idea: PING's RTT measured while the link also carries the telemetry a
//! vehicle really sends. Load frames are messages no MAVLink system
//! answers (telemetry, or filler in a V2_EXTENSION of an experimental
//! type), so responders ignore them and nothing comes back to match.
//!
//! Each stream keeps its own absolute schedule, like the probes: frame *n*
//! at start + (*n* + *u*) × period, with *u* drawn uniformly in [0, 1) for
//! each frame. The rate is exact, and a vehicle's telemetry (on its own
//! clock) does not move in step with our requests: without the draw, a
//! 50 Hz stream beside 10 PINGs/s would meet every request at the same
//! phase, and never delay one or always delay it. The draws are seeded:
//! runs on the simulated link repeat exactly.

use rand::rngs::SmallRng;
use rand::{Rng, SeedableRng};
use serde::Serialize;

use super::link_io::{Clock, Sender};
use super::Nanos;
use crate::frame::Version;
// The `MSG@RATE` stream spec is telemetry's (it parses `sim:?stream=` and
// `respond --stream` too); the load sends it.
pub(crate) use crate::telemetry::{LoadKind, LoadSpec};
use crate::transport::{LinkError, Transport};

/// Most frames one stream sends back to back before the session reads
/// the link again.
const MAX_BURST: usize = 64;

/// What a stream sent, for the summary.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub(crate) struct LoadSummary {
    pub(crate) message: &'static str,
    /// As given: frames/s, or bytes/s for `BYTES`.
    pub(crate) rate: f64,
    pub(crate) frame_bytes: u64,
    pub(crate) frames: u64,
    pub(crate) bytes: u64,
}

struct Stream {
    spec: LoadSpec,
    period_ns: f64,
    frame_bytes: u64,
    /// When the stream was (re)started, and frames sent since.
    start: Option<Nanos>,
    issued: u64,
    /// Where in its period the next frame goes, in [0, 1).
    phase: f64,
    rng: SmallRng,
    frames: u64,
    bytes: u64,
}

impl Stream {
    fn next_due(&self) -> Option<Nanos> {
        let start = self.start?;
        Some(start + ((self.issued as f64 + self.phase) * self.period_ns) as Nanos)
    }
}

/// Every `--load` stream of a session, on or off.
pub(crate) struct Load {
    streams: Vec<Stream>,
}

impl Load {
    pub(crate) fn new(specs: &[LoadSpec], version: Version, signed: bool) -> Self {
        Load {
            streams: specs
                .iter()
                .enumerate()
                .map(|(i, &spec)| {
                    let mut rng = SmallRng::seed_from_u64(i as u64);
                    Stream {
                        spec,
                        period_ns: 1e9 / spec.frame_rate(version, signed),
                        frame_bytes: spec.frame_bytes(version, signed),
                        start: None,
                        issued: 0,
                        phase: rng.gen(),
                        rng,
                        frames: 0,
                        bytes: 0,
                    }
                })
                .collect(),
        }
    }

    pub(crate) fn is_empty(&self) -> bool {
        self.streams.is_empty()
    }

    /// Starts every stream at `now` (no-op for those already on).
    pub(crate) fn start(&mut self, now: Nanos) {
        for s in &mut self.streams {
            if s.start.is_none() {
                s.start = Some(now);
                s.issued = 0;
            }
        }
    }

    pub(crate) fn stop(&mut self) {
        for s in &mut self.streams {
            s.start = None;
        }
    }

    /// When the next frame is due, if any stream is on.
    pub(crate) fn next_due(&self) -> Option<Nanos> {
        self.streams.iter().filter_map(Stream::next_due).min()
    }

    /// Sends every frame due now (at most a burst per stream).
    pub(crate) async fn send_due<T: Transport>(
        &mut self,
        link: &mut T,
        sender: &mut Sender,
        clock: &Clock,
    ) -> Result<(), LinkError> {
        for s in &mut self.streams {
            for _ in 0..MAX_BURST {
                let now = clock.now();
                if s.next_due().is_none_or(|due| due > now) {
                    break;
                }
                s.issued += 1;
                s.phase = s.rng.gen();
                let msg = s.spec.kind.msg((now / 1_000_000) as u32);
                let frame = sender.frame(&msg);
                let len = frame.len() as u64;
                link.send(frame).await?;
                s.frames += 1;
                s.bytes += len;
            }
        }
        Ok(())
    }

    pub(crate) fn summary(&self) -> Vec<LoadSummary> {
        self.streams
            .iter()
            .map(|s| LoadSummary {
                message: s.spec.kind.name(),
                rate: s.spec.rate,
                frame_bytes: s.frame_bytes,
                frames: s.frames,
                bytes: s.bytes,
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn specs_parse_and_bad_ones_say_why() {
        let a: LoadSpec = "ATTITUDE@50".parse().unwrap();
        assert_eq!((a.kind, a.rate), (LoadKind::Attitude, 50.0));
        assert_eq!(a.to_string(), "ATTITUDE@50");
        let g: LoadSpec = "global_position_int@2.5".parse().unwrap();
        assert_eq!((g.kind, g.rate), (LoadKind::GlobalPositionInt, 2.5));
        let b: LoadSpec = "BYTES@2000".parse().unwrap();
        assert_eq!(b.kind, LoadKind::Bytes);
        for (bad, needle) in [
            ("ATTITUDE", "expected MSG@RATE"),
            ("HEARTBEAT@1", "unknown message HEARTBEAT"),
            ("ATTITUDE@0", "above 0"),
            ("ATTITUDE@fast", "above 0"),
            ("BYTES@-5", "bytes per second"),
            ("ATTITUDE@1e9", "at most"),
        ] {
            let e = bad.parse::<LoadSpec>().unwrap_err().to_string();
            assert!(e.contains(needle), "{bad}: {e}");
        }
        assert_eq!(
            "ATTITUDE".parse::<LoadSpec>().unwrap_err().to_string(),
            "'ATTITUDE': expected MSG@RATE: ATTITUDE@HZ, GLOBAL_POSITION_INT@HZ or \
             BYTES@BYTES_PER_S, e.g. ATTITUDE@50"
        );
        assert_eq!(
            "BYTES@0".parse::<LoadSpec>().unwrap_err().to_string(),
            "'BYTES@0': the rate must be a number above 0 and at most 1000000 (bytes per second)"
        );
    }

    #[test]
    fn byte_rates_are_frames_of_filler() {
        let b: LoadSpec = "BYTES@1170".parse().unwrap();
        assert_eq!(b.frame_bytes(Version::V2, false), 117);
        assert!((b.frame_rate(Version::V2, false) - 10.0).abs() < 1e-9);
        assert!((b.bytes_per_s(Version::V2, false) - 1170.0).abs() < 1e-9);
        // Signed, each frame is 13 bytes longer: fewer of them.
        assert_eq!(b.frame_bytes(Version::V2, true), 130);
        let a: LoadSpec = "ATTITUDE@50".parse().unwrap();
        assert_eq!(a.bytes_per_s(Version::V2, false), 2000.0);
    }

    #[test]
    fn streams_keep_an_absolute_schedule_and_stop() {
        let mut load = Load::new(
            &[
                "ATTITUDE@100".parse().unwrap(),
                "BYTES@1170".parse().unwrap(),
            ],
            Version::V2,
            false,
        );
        assert_eq!(load.next_due(), None, "off until started");
        load.start(1_000);
        for s in &mut load.streams {
            s.phase = 0.5;
        }
        // Each frame somewhere in its period: here, half way.
        assert_eq!(load.next_due(), Some(5_001_000));
        load.streams[0].issued = 3;
        load.streams[1].issued = 1;
        // ATTITUDE's 4th frame at 35 ms, BYTES's 2nd at 150 ms.
        assert_eq!(load.next_due(), Some(35_001_000));
        load.stop();
        assert_eq!(load.next_due(), None);
    }
}
