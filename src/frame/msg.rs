//! The messages mavping acts on ([`Msg`]) and the figures some of them
//! carry (RADIO_STATUS, LINK_NODE_STATUS, a position): what a decoded
//! frame holds, kept apart from the frame's header figures.

/// The messages mavping acts on. Field names follow the MAVLink definitions.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Msg {
    Heartbeat {
        mav_type: u8,
        autopilot: u8,
    },
    Ping {
        time_usec: u64,
        seq: u32,
        target_system: u8,
        target_component: u8,
    },
    Timesync {
        tc1: i64,
        ts1: i64,
        target_system: u8,
        target_component: u8,
    },
    CommandLong {
        command: u16,
        confirmation: u8,
        target_system: u8,
        target_component: u8,
        params: [f32; 7],
    },
    CommandAck {
        command: u16,
        result: u8,
        target_system: u8,
        target_component: u8,
    },
    RadioStatus(RadioStatus),
    /// A node's LINK_NODE_STATUS: its own count of what it received and
    /// lost on the link it sends this on.
    LinkNodeStatus(LinkNodeStatus),
    /// Telemetry a vehicle streams (`--load ATTITUDE@HZ`): plausible,
    /// non-zero figures, so MAVLink 2 trims nothing and the frame is as
    /// long as a real one.
    Attitude {
        time_boot_ms: u32,
    },
    /// `--load GLOBAL_POSITION_INT@HZ`, as [`Msg::Attitude`].
    GlobalPositionInt {
        time_boot_ms: u32,
    },
    /// A position received (GLOBAL_POSITION_INT, GPS_RAW_INT or
    /// HOME_POSITION), for the flight's distance; also sent by tests.
    Fix(Fix),
    /// Filler bytes (`--load BYTES@RATE`): a V2_EXTENSION of `len` payload
    /// bytes with a message type from the range MAVLink leaves to local
    /// experiments, so no system acts on it.
    Filler {
        len: u8,
    },
    /// A parameter, mission or file transfer's message.
    Transfer(super::Transfer),
    /// Any other message: valid frame, contents not needed (or an id the
    /// dialect does not know, lined up with what follows: see
    /// [`Kind::Unknown`](super::Kind::Unknown)).
    Other,
    /// A whole frame whose CRC failed
    /// ([`Kind::Damaged`](super::Kind::Damaged)): only its header (source,
    /// sequence number, id, length) is known. It fills its source's
    /// sequence, and is nothing else: no system is heard by it, no request
    /// or reply matched.
    Damaged,
}

impl Msg {
    /// The system a targeted message is addressed to; none for a message
    /// without a target or addressed to all (0).
    pub(crate) fn addressed_to(&self) -> Option<u8> {
        let to = match self {
            Msg::Ping { target_system, .. }
            | Msg::Timesync { target_system, .. }
            | Msg::CommandLong { target_system, .. }
            | Msg::CommandAck { target_system, .. } => *target_system,
            Msg::Transfer(t) => t.target()?.system,
            _ => return None,
        };
        (to != 0).then_some(to)
    }
}

/// A radio's RADIO_STATUS (message 109, or its forerunner RADIO, 166: the
/// frame's `msgid` tells which): its link figures, as received and
/// as the engine and the reports keep them (`engine::radio::RadioReport`).
/// 255 in the 8-bit figures means unknown; `rxerrors` and `fixed` count
/// since the radio booted and wrap.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize)]
pub struct RadioStatus {
    pub rssi: u8,
    pub remrssi: u8,
    pub txbuf: u8,
    pub noise: u8,
    pub remnoise: u8,
    pub rxerrors: u16,
    pub fixed: u16,
}

/// A node's LINK_NODE_STATUS (message 8, MAVLink common, work in
/// progress): PX4 sends it at 1 Hz on most links, with its own count of
/// the messages it received and lost there (by their packet sequence),
/// its parse errors and buffer overflows. The message counters are 32-bit
/// and the others 16-bit, all since the node booted, and they wrap;
/// `timestamp` is milliseconds since boot.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize)]
pub struct LinkNodeStatus {
    pub(crate) timestamp: u64,
    /// Percent of the transmit and receive buffers free.
    pub(crate) tx_buf: u8,
    pub(crate) rx_buf: u8,
    /// Bytes per second.
    pub(crate) tx_rate: u32,
    pub(crate) rx_rate: u32,
    /// Bytes it could not parse.
    pub(crate) rx_parse_err: u16,
    pub(crate) tx_overflows: u16,
    pub(crate) rx_overflows: u16,
    pub(crate) messages_sent: u32,
    pub(crate) messages_received: u32,
    pub(crate) messages_lost: u32,
}

/// Where a vehicle says it is, or its home. Only the figures a range
/// needs: the rest of each message stays in the frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Fix {
    pub(crate) kind: FixKind,
    /// Degrees × 10^7, as on the wire.
    pub(crate) lat: i32,
    pub(crate) lon: i32,
    /// Millimetres above mean sea level.
    pub(crate) alt_mm: i32,
}

impl Fix {
    /// Whether it places the vehicle: a home always, an estimate once it
    /// is not 0/0, a GPS fix of 2D or better unless the vehicle's
    /// estimates are being read (`estimates`), which are better.
    pub(crate) fn usable(&self, estimates: bool) -> bool {
        match self.kind {
            FixKind::Home => true,
            FixKind::Estimate => !(self.lat == 0 && self.lon == 0),
            FixKind::Gps { fix_type } => fix_type >= 2 && !estimates,
        }
    }

    /// Latitude and longitude in degrees, altitude in metres.
    pub(crate) fn degrees(&self) -> (f64, f64, f64) {
        (
            f64::from(self.lat) / 1e7,
            f64::from(self.lon) / 1e7,
            f64::from(self.alt_mm) / 1e3,
        )
    }
}

/// Which message a [`Fix`] came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum FixKind {
    /// GLOBAL_POSITION_INT: the autopilot's estimate (0/0 before it has one).
    Estimate,
    /// GPS_RAW_INT, with its GPS_FIX_TYPE (2 and up: a position).
    Gps { fix_type: u8 },
    /// HOME_POSITION.
    Home,
}
