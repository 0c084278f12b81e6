//! One received frame as the rest of mavping sees it ([`Frame`]): its
//! header figures, its decoded message and the clock stamps it carries
//! ([`Stamps`]).

use super::codec::Version;
use super::msg::Msg;
use super::sys_comp::SysComp;

/// One received frame: CRC checked, unless its `msg` is [`Msg::Damaged`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Frame {
    pub version: Version,
    /// The sender, from the frame header.
    pub source: SysComp,
    /// The header's 8-bit packet sequence (not the PING seq).
    pub(crate) packet_seq: u8,
    pub(crate) msgid: u32,
    pub(crate) signed: bool,
    /// Bytes on the wire, header to signature.
    pub(crate) len: u16,
    /// The frame's checksum as on the wire (little-endian bytes read as
    /// sent), also of a damaged frame: with the source, sequence and id it
    /// tells the same frame heard on two links from another.
    pub(crate) crc: u16,
    pub msg: Msg,
    /// The sender's clock readings the frame carries, for its age.
    pub(crate) stamps: Stamps,
}

/// Which of the sender's clocks a [`Stamp`] reads. Two stamps of one
/// sender on the same clock are comparable; stamps on different clocks
/// are not (each has its own offset and drift).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub(crate) enum StampClock {
    /// Milliseconds since the sender booted, 32-bit: wraps after 49.7 days.
    BootMs,
    /// Microseconds since the sender booted (a `time_usec` too small to
    /// be Unix time: MAVLink lets the sender choose, the receiver tells
    /// them apart by magnitude).
    BootUs,
    /// Microseconds since the Unix epoch (GPS or network time).
    UnixUs,
    /// TIMESYNC's clock in ns: since boot on ArduPilot and PX4, Unix time
    /// on some companions; one sender keeps to one.
    TimesyncNs,
    /// A MAVLink 2 signature's timestamp: 10 µs units since 2015-01-01
    /// 00:00 UTC. ArduPilot moves it to GPS time in whole seconds and
    /// otherwise adds one unit a frame, so it is a coarse clock there.
    Signature,
}

impl StampClock {
    /// The clock in words, as the text reports name it.
    pub(crate) const fn words(self) -> &'static str {
        match self {
            StampClock::BootMs => "boot-time ms",
            StampClock::BootUs => "boot-time µs",
            StampClock::UnixUs => "Unix-time",
            StampClock::TimesyncNs => "TIMESYNC",
            StampClock::Signature => "signature",
        }
    }

    /// Whether the clock runs at the sender's real rate: a signature's
    /// does not (pymavlink adds one unit a frame and ArduPilot steps it to
    /// GPS time in whole seconds), so its ages are shown but judge nothing.
    pub(crate) const fn keeps_time(self) -> bool {
        !matches!(self, StampClock::Signature)
    }

    /// Nanoseconds in one unit of the clock.
    pub(crate) const fn unit_ns(self) -> u64 {
        match self {
            StampClock::BootMs => 1_000_000,
            StampClock::BootUs | StampClock::UnixUs => 1_000,
            StampClock::TimesyncNs => 1,
            StampClock::Signature => 10_000,
        }
    }
}

/// When the sender read the clock it stamped: what an age from the
/// stamp measures. Kept apart because only a send stamp measures the link.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub(crate) enum StampMeaning {
    /// Read as the message was built: SYSTEM_TIME, TIMESYNC, a signature,
    /// HIGH_LATENCY2, and the messages ArduPilot stamps with its clock at
    /// send (ATTITUDE, the IMU and pressure messages; PX4 puts the newest
    /// estimate's or sensor sample's time there, a few ms before sending).
    Sent,
    /// The time of a measurement or estimate that may be much older than
    /// the frame: a GPS fix (GPS_RAW_INT), a position (GLOBAL_POSITION_INT
    /// and LOCAL_POSITION_NED: PX4 and ArduPilot before 4.0 stamp them
    /// with the estimate's or the fix's time). The age includes how old
    /// the data was when sent.
    Sampled,
}

/// One reading of a sender's clock, in the clock's own units as on the
/// wire (a 32-bit ms count still wrapped).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Stamp {
    pub(crate) clock: StampClock,
    pub(crate) meaning: StampMeaning,
    pub(crate) value: u64,
}

/// The stamps of one frame: up to two from its message (SYSTEM_TIME
/// carries boot and Unix time) and the signature's, if signed.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub(crate) struct Stamps {
    pub(crate) message: [Option<Stamp>; 2],
    pub(crate) signature: Option<Stamp>,
}

impl Stamps {
    /// Every stamp the frame carries.
    pub(crate) fn iter(&self) -> impl Iterator<Item = Stamp> + '_ {
        self.message
            .iter()
            .chain([&self.signature])
            .flatten()
            .copied()
    }
}

/// A MAVLink 2 frame from `source` carrying `msg`, its header figures 0:
/// what unit tests of the engine hand it.
#[cfg(test)]
pub(crate) fn test_frame(source: SysComp, msg: Msg) -> Frame {
    Frame {
        version: Version::V2,
        source,
        packet_seq: 0,
        msgid: 0,
        signed: false,
        len: 0,
        crc: 0,
        msg,
        stamps: Stamps::default(),
    }
}
