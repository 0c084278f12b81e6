//! What every MAVLink system on a link needs, whatever it measures or
//! answers: a session clock, its own HEARTBEAT on schedule, a frame sender
//! (packet sequence and signing) and the signing gate for what comes in.
//! Used by the echo and command sessions and by `mavping respond`.

use std::time::Duration;

use tokio::time::{sleep_until, Instant};

use super::Nanos;
use crate::frame::signing::{self, Gate, SignedBytes, Signer};
use crate::frame::{self, Frame, Header, Msg, SysComp, Version};
use crate::transport::{LinkError, Transport};

/// The wall clock at session time 0, and how far off it may be: the two
/// clocks cannot be read at one instant, and a thread preempted between
/// the reads would put the wall clock late by however long it waited.
/// TIMESYNC's causal bounds widen by `within` so they stay true anyway.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct WallAtZero {
    pub(crate) wall: std::time::SystemTime,
    pub(crate) within: Duration,
}

impl WallAtZero {
    #[cfg(test)]
    /// Exactly `wall` (tests, and clocks that are not read).
    pub(crate) fn exactly(wall: std::time::SystemTime) -> Self {
        WallAtZero {
            wall,
            within: Duration::ZERO,
        }
    }
}

/// Readings of the monotonic-wall-monotonic triple taken to find a tight
/// one: one is nearly always tight (tens of ns), unless the thread was
/// preempted in every try.
const PAIR_TRIES: usize = 8;

/// Session time: nanoseconds since the session started, from the
/// monotonic clock (tokio's, so a paused runtime's virtual time too).
pub(crate) struct Clock {
    epoch: Instant,
    wall_at_zero: WallAtZero,
}

impl Clock {
    pub(crate) fn start() -> Self {
        let (epoch, wall_at_zero) = read_together();
        Clock {
            epoch,
            wall_at_zero,
        }
    }

    /// The wall clock at session time 0.
    pub(crate) fn wall_at_zero(&self) -> WallAtZero {
        self.wall_at_zero
    }

    pub(crate) fn ns(&self, t: Instant) -> Nanos {
        t.saturating_duration_since(self.epoch).as_nanos() as Nanos
    }

    pub(crate) fn now(&self) -> Nanos {
        self.ns(Instant::now())
    }

    pub(crate) fn at(&self, ns: Nanos) -> Instant {
        self.epoch + Duration::from_nanos(ns)
    }

    /// Sleeps until session time `wake`, or forever when there is none.
    pub(crate) async fn sleep_until(&self, wake: Option<Nanos>) {
        match wake {
            Some(ns) => sleep_until(self.at(ns)).await,
            None => std::future::pending().await,
        }
    }
}

/// The monotonic clock and the wall clock at that moment: of several
/// readings bracketed by the monotonic clock, the narrowest, with the wall
/// time taken to the bracket's middle and half its width as the error.
fn read_together() -> (Instant, WallAtZero) {
    let bracket = || {
        let before = Instant::now();
        let wall = std::time::SystemTime::now();
        let gap = Instant::now().saturating_duration_since(before);
        (before, wall, gap)
    };
    let (epoch, wall, gap) = (0..PAIR_TRIES)
        .map(|_| bracket())
        .min_by_key(|&(_, _, gap)| gap)
        .expect("PAIR_TRIES > 0");
    let half = gap / 2;
    let wall = WallAtZero {
        wall: wall.checked_sub(half).unwrap_or(wall),
        within: gap.saturating_sub(half),
    };
    (epoch, wall)
}

/// A HEARTBEAT a second: routers and MAVSDK learn who is on the link from
/// it. `None` due time means it is off (`--no-heartbeat`).
pub(crate) struct Heartbeat {
    msg: Msg,
    next: Option<Nanos>,
}

const HEARTBEAT_PERIOD_NS: Nanos = 1_000_000_000;

impl Heartbeat {
    /// We are a ground station (MAV_TYPE_GCS); the first is due at once.
    pub(crate) fn ground_station(on: bool) -> Self {
        Heartbeat {
            msg: Msg::Heartbeat {
                mav_type: frame::mav_type::GCS,
                autopilot: frame::AUTOPILOT_INVALID,
            },
            next: on.then_some(0),
        }
    }

    /// A companion-computer-like system, not a vehicle (`mavping respond`):
    /// it answers probes but flies nothing.
    pub(crate) fn onboard_controller() -> Self {
        Heartbeat {
            msg: Msg::Heartbeat {
                mav_type: frame::mav_type::ONBOARD_CONTROLLER,
                autopilot: frame::AUTOPILOT_INVALID,
            },
            next: Some(0),
        }
    }

    /// When the next one is due.
    pub(crate) fn next(&self) -> Option<Nanos> {
        self.next
    }

    pub(crate) fn msg(&self) -> &Msg {
        &self.msg
    }

    /// Sends the HEARTBEAT to every peer when it is due, and schedules the
    /// next one a period after the one due (no drift).
    pub(crate) async fn send_if_due<T: Transport>(
        &mut self,
        link: &mut T,
        sender: &mut Sender,
        now: Nanos,
    ) -> Result<(), LinkError> {
        if let Some(due) = self.next.filter(|&due| due <= now) {
            link.send(sender.frame(&self.msg)).await?;
            self.next = Some(due + HEARTBEAT_PERIOD_NS);
        }
        Ok(())
    }
}

/// Serialises our frames into one reused buffer: our ids, the running
/// packet sequence, and a signature when signing is on.
pub(crate) struct Sender {
    buf: Vec<u8>,
    packet_seq: u8,
    ours: SysComp,
    version: Version,
    signer: Option<Signer>,
    /// Bytes of every frame built, for throughput figures.
    bytes: u64,
}

impl Sender {
    pub(crate) fn new(ours: SysComp, version: Version, signer: Option<Signer>) -> Self {
        Sender {
            buf: Vec::with_capacity(frame::scanner::MAX_FRAME_LEN),
            packet_seq: 0,
            ours,
            version,
            signer,
            bytes: 0,
        }
    }

    /// Bytes of every frame built so far (each is sent once built).
    pub(crate) fn bytes(&self) -> u64 {
        self.bytes
    }

    /// `msg` as our next frame (no allocation per frame).
    pub(crate) fn frame(&mut self, msg: &Msg) -> &[u8] {
        self.frame_as(self.version, msg)
    }

    /// `msg` in MAVLink `version`; signed frames are MAVLink 2 whatever is
    /// asked (only MAVLink 2 can carry a signature).
    pub(crate) fn frame_as(&mut self, version: Version, msg: &Msg) -> &[u8] {
        self.buf.clear();
        let header = Header {
            sysid: self.ours.sysid,
            compid: self.ours.compid,
            seq: self.packet_seq,
        };
        self.packet_seq = self.packet_seq.wrapping_add(1);
        match self.signer.as_mut() {
            Some(signer) => {
                frame::encode(&mut self.buf, Version::V2, header, msg);
                signer.sign(&mut self.buf, 0, signing::timestamp_now());
            }
            None => frame::encode(&mut self.buf, version, header, msg),
        }
        self.bytes += self.buf.len() as u64;
        &self.buf
    }

    /// The last frame built, to send again or keep.
    pub(crate) fn last(&self) -> &[u8] {
        &self.buf
    }
}

/// Whether the signing gate (if any) lets `frame` through; what it refuses
/// reaches nothing else, and is counted by the gate.
pub(crate) fn admitted(gate: &mut Gate, frame: &Frame, signature: Option<&SignedBytes>) -> bool {
    let radio = matches!(frame.msg, Msg::RadioStatus(_));
    let verdict = gate.judge(frame.source, signature, radio);
    if !verdict.accepted() {
        tracing::debug!(from = %frame.source, msgid = frame.msgid, ?verdict, "frame refused");
    }
    verdict.accepted()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_wall_clock_at_zero_lies_between_readings_before_and_after() {
        let before = std::time::SystemTime::now();
        let clock = Clock::start();
        let after = std::time::SystemTime::now();
        let at_zero = clock.wall_at_zero();
        assert!(at_zero.wall + at_zero.within >= before, "{at_zero:?}");
        assert!(at_zero.wall <= after, "{at_zero:?}");
    }
}
