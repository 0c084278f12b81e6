//! Turning [`Msg`] into wire bytes and wire bytes into [`Frame`], with the
//! `mavlink` crate doing the serialisation, CRC and field layout.

use mavlink::dialects::ardupilotmega as dialect;
use mavlink::{MAVLinkV1MessageRaw, MAVLinkV2MessageRaw, MavHeader, MavlinkVersion, Message};
use num_traits::FromPrimitive;

use super::received::{Stamp, StampClock, StampMeaning, Stamps};
use super::scanner::{header_len, Kind, IFLAG_SIGNED, STX_V1};
use super::signing::signature_timestamp;
use super::{ids, Fix, FixKind, Frame, LinkNodeStatus, Msg, RadioStatus, SysComp};

#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum Version {
    V1,
    V2,
}

/// Header fields we choose when sending.
#[derive(Debug, Clone, Copy)]
pub struct Header {
    pub sysid: u8,
    pub compid: u8,
    /// The 8-bit packet sequence in the frame header.
    pub seq: u8,
}

/// V2_EXTENSION's message types from 32768 up are for local experiments
/// and never registered: a system that meets one ignores the message.
pub(crate) const FILLER_MESSAGE_TYPE: u16 = 0xFFFF;
/// Non-zero, so MAVLink 2 trims none of the filler.
const FILLER_BYTE: u8 = 0x55;

// RADIO_STATUS's one conversion each way between the dialect's struct and
// mavping's own.
impl From<RadioStatus> for dialect::RADIO_STATUS_DATA {
    fn from(r: RadioStatus) -> Self {
        dialect::RADIO_STATUS_DATA {
            rxerrors: r.rxerrors,
            fixed: r.fixed,
            rssi: r.rssi,
            remrssi: r.remrssi,
            txbuf: r.txbuf,
            noise: r.noise,
            remnoise: r.remnoise,
        }
    }
}

// RADIO (166) has RADIO_STATUS's fields under the older name.
#[allow(deprecated)]
impl From<dialect::RADIO_DATA> for RadioStatus {
    fn from(d: dialect::RADIO_DATA) -> Self {
        RadioStatus {
            rssi: d.rssi,
            remrssi: d.remrssi,
            txbuf: d.txbuf,
            noise: d.noise,
            remnoise: d.remnoise,
            rxerrors: d.rxerrors,
            fixed: d.fixed,
        }
    }
}

impl From<dialect::RADIO_STATUS_DATA> for RadioStatus {
    fn from(d: dialect::RADIO_STATUS_DATA) -> Self {
        RadioStatus {
            rssi: d.rssi,
            remrssi: d.remrssi,
            txbuf: d.txbuf,
            noise: d.noise,
            remnoise: d.remnoise,
            rxerrors: d.rxerrors,
            fixed: d.fixed,
        }
    }
}

// LINK_NODE_STATUS's, the same way.
impl From<LinkNodeStatus> for dialect::LINK_NODE_STATUS_DATA {
    fn from(l: LinkNodeStatus) -> Self {
        dialect::LINK_NODE_STATUS_DATA {
            timestamp: l.timestamp,
            tx_rate: l.tx_rate,
            rx_rate: l.rx_rate,
            messages_sent: l.messages_sent,
            messages_received: l.messages_received,
            messages_lost: l.messages_lost,
            rx_parse_err: l.rx_parse_err,
            tx_overflows: l.tx_overflows,
            rx_overflows: l.rx_overflows,
            tx_buf: l.tx_buf,
            rx_buf: l.rx_buf,
        }
    }
}

impl From<dialect::LINK_NODE_STATUS_DATA> for LinkNodeStatus {
    fn from(d: dialect::LINK_NODE_STATUS_DATA) -> Self {
        LinkNodeStatus {
            timestamp: d.timestamp,
            tx_buf: d.tx_buf,
            rx_buf: d.rx_buf,
            tx_rate: d.tx_rate,
            rx_rate: d.rx_rate,
            rx_parse_err: d.rx_parse_err,
            tx_overflows: d.tx_overflows,
            rx_overflows: d.rx_overflows,
            messages_sent: d.messages_sent,
            messages_received: d.messages_received,
            messages_lost: d.messages_lost,
        }
    }
}

// PING is marked superseded by TIMESYNC, yet PX4, QGC and MAVSDK answer it.
#[allow(deprecated)]
fn to_mavlink(msg: &Msg) -> dialect::MavMessage {
    use dialect::MavMessage as M;
    match *msg {
        Msg::Heartbeat {
            mav_type,
            autopilot,
        } => M::HEARTBEAT(dialect::HEARTBEAT_DATA {
            mavtype: dialect::MavType::from_u8(mav_type).unwrap_or_default(),
            autopilot: dialect::MavAutopilot::from_u8(autopilot).unwrap_or_default(),
            mavlink_version: 3,
            ..Default::default()
        }),
        Msg::Ping {
            time_usec,
            seq,
            target_system,
            target_component,
        } => M::PING(dialect::PING_DATA {
            time_usec,
            seq,
            target_system,
            target_component,
        }),
        Msg::Timesync {
            tc1,
            ts1,
            target_system,
            target_component,
        } => M::TIMESYNC(dialect::TIMESYNC_DATA {
            tc1,
            ts1,
            target_system,
            target_component,
        }),
        Msg::CommandLong {
            command,
            confirmation,
            target_system,
            target_component,
            params,
        } => M::COMMAND_LONG(dialect::COMMAND_LONG_DATA {
            param1: params[0],
            param2: params[1],
            param3: params[2],
            param4: params[3],
            param5: params[4],
            param6: params[5],
            param7: params[6],
            command: dialect::MavCmd::from_u16(command).unwrap_or_default(),
            target_system,
            target_component,
            confirmation,
        }),
        Msg::CommandAck {
            command,
            result,
            target_system,
            target_component,
        } => M::COMMAND_ACK(dialect::COMMAND_ACK_DATA {
            command: dialect::MavCmd::from_u16(command).unwrap_or_default(),
            result: dialect::MavResult::from_u8(result).unwrap_or_default(),
            target_system,
            target_component,
            ..Default::default()
        }),
        Msg::RadioStatus(r) => M::RADIO_STATUS(r.into()),
        Msg::LinkNodeStatus(l) => M::LINK_NODE_STATUS(l.into()),
        Msg::Fix(f) => fix_message(f),
        Msg::Attitude { .. } | Msg::GlobalPositionInt { .. } | Msg::Filler { .. } => load(msg),
        Msg::Transfer(t) => super::transfer_codec::to_mavlink(&t),
        Msg::Other | Msg::Damaged => unreachable!("{msg:?} is never sent"),
    }
}

/// A position as the message it came from.
fn fix_message(f: Fix) -> dialect::MavMessage {
    use dialect::MavMessage as M;
    match f.kind {
        FixKind::Estimate => M::GLOBAL_POSITION_INT(dialect::GLOBAL_POSITION_INT_DATA {
            lat: f.lat,
            lon: f.lon,
            alt: f.alt_mm,
            ..Default::default()
        }),
        FixKind::Gps { fix_type } => M::GPS_RAW_INT(dialect::GPS_RAW_INT_DATA {
            lat: f.lat,
            lon: f.lon,
            alt: f.alt_mm,
            fix_type: dialect::GpsFixType::from_u8(fix_type).unwrap_or_default(),
            ..Default::default()
        }),
        FixKind::Home => M::HOME_POSITION(dialect::HOME_POSITION_DATA {
            latitude: f.lat,
            longitude: f.lon,
            altitude: f.alt_mm,
            ..Default::default()
        }),
    }
}

/// The messages of `--load`: plausible telemetry, and filler bytes.
fn load(msg: &Msg) -> dialect::MavMessage {
    use dialect::MavMessage as M;
    match *msg {
        Msg::Attitude { time_boot_ms } => M::ATTITUDE(dialect::ATTITUDE_DATA {
            time_boot_ms,
            roll: 0.05,
            pitch: -0.02,
            yaw: 1.57,
            rollspeed: 0.001,
            pitchspeed: -0.002,
            yawspeed: 0.003,
        }),
        Msg::GlobalPositionInt { time_boot_ms } => {
            M::GLOBAL_POSITION_INT(dialect::GLOBAL_POSITION_INT_DATA {
                time_boot_ms,
                lat: 473_977_420,
                lon: 85_455_940,
                alt: 488_000,
                relative_alt: 20_000,
                vx: 120,
                vy: -35,
                vz: 4,
                hdg: 27_000,
            })
        }
        Msg::Filler { len } => {
            let mut payload = [0u8; 249];
            let len = usize::from(len).min(payload.len());
            payload[..len].fill(FILLER_BYTE);
            M::V2_EXTENSION(dialect::V2_EXTENSION_DATA {
                message_type: FILLER_MESSAGE_TYPE,
                target_network: 0,
                target_system: 0,
                target_component: 0,
                payload,
            })
        }
        _ => unreachable!("not a load message"),
    }
}

/// Appends one serialised frame to `out`.
pub fn encode(out: &mut Vec<u8>, version: Version, header: Header, msg: &Msg) {
    let header = MavHeader {
        system_id: u32::from(header.sysid),
        component_id: header.compid,
        sequence: header.seq,
    };
    let message = to_mavlink(msg);
    match version {
        Version::V1 => {
            let mut raw = MAVLinkV1MessageRaw::new();
            raw.serialize_message(header, &message);
            out.extend_from_slice(raw.raw_bytes());
        }
        Version::V2 => {
            let mut raw = MAVLinkV2MessageRaw::new();
            raw.serialize_message(header, &message);
            out.extend_from_slice(raw.raw_bytes());
        }
    }
}

/// Decodes a frame the scanner handed over as `kind`: a good one whole; of
/// a damaged one or one of an unknown id only the header, which is all
/// that can be believed ([`Msg::Damaged`], [`Msg::Other`]).
pub fn decode_as(raw: &[u8], kind: Kind) -> Frame {
    match kind {
        Kind::Good => decode(raw),
        Kind::Damaged => Frame {
            msg: Msg::Damaged,
            ..header_of(raw)
        },
        Kind::Unknown => header_of(raw),
    }
}

/// Decodes a frame the scanner has already CRC-checked.
pub fn decode(raw: &[u8]) -> Frame {
    let frame = header_of(raw);
    let payload = &raw[header_len(raw[0])..][..usize::from(raw[1])];
    let signature = frame
        .signed
        .then(|| signature_timestamp(raw))
        .flatten()
        .map(|value| Stamp {
            clock: StampClock::Signature,
            meaning: StampMeaning::Sent,
            value,
        });
    Frame {
        msg: decode_payload(frame.version, frame.msgid, payload),
        stamps: Stamps {
            message: message_stamps(frame.msgid, payload),
            signature,
        },
        ..frame
    }
}

/// Microseconds at least this large are Unix time (after 2001); a count
/// since boot would need 31 years of uptime. MAVLink's `time_usec` fields
/// leave the choice to the sender and the magnitude to the receiver.
const UNIX_US_FROM: u64 = 1_000_000_000_000_000;

/// The little-endian unsigned field of `width` bytes at `offset`: bytes
/// past the end of a MAVLink 2 payload were trimmed zeros.
fn field(payload: &[u8], offset: usize, width: usize) -> u64 {
    let mut bytes = [0u8; 8];
    let end = payload.len().min(offset + width);
    if offset < end {
        bytes[..end - offset].copy_from_slice(&payload[offset..end]);
    }
    u64::from_le_bytes(bytes)
}

/// A stamp of `value` on `clock`; none for 0, what senders put in a
/// field whose clock they do not have (no GPS, no RTC).
fn stamp(clock: StampClock, meaning: StampMeaning, value: u64) -> Option<Stamp> {
    (value != 0).then_some(Stamp {
        clock,
        meaning,
        value,
    })
}

/// A `time_usec`: since boot or since 1970, told apart by magnitude.
fn stamp_us(meaning: StampMeaning, value: u64) -> Option<Stamp> {
    let clock = if value >= UNIX_US_FROM {
        StampClock::UnixUs
    } else {
        StampClock::BootUs
    };
    stamp(clock, meaning, value)
}

/// The clock stamps in a good frame's payload, read at their offsets
/// without decoding the message (the passive path meets 100k frames a
/// second). MAVLink orders fields by size, so each stamp is its message's
/// first field, SYSTEM_TIME's boot time the second (after the Unix time)
/// and TIMESYNC's `ts1` the second; the tests check each offset against
/// the `mavlink` crate's own serialisation.
fn message_stamps(msgid: u32, payload: &[u8]) -> [Option<Stamp>; 2] {
    use StampClock::{BootMs, TimesyncNs};
    use StampMeaning::{Sampled, Sent};
    let boot_ms = |meaning| stamp(BootMs, meaning, field(payload, 0, 4));
    match msgid {
        // SYSTEM_TIME: Unix time (0 until the sender has it), boot time.
        2 => [
            stamp(BootMs, Sent, field(payload, 8, 4)),
            stamp_us(Sent, field(payload, 0, 8)),
        ],
        // PING: only a request (targets 0) carries the sender's own clock;
        // a reply echoes the requester's.
        4 if field(payload, 12, 2) == 0 => [stamp_us(Sent, field(payload, 0, 8)), None],
        // TIMESYNC: a reply's tc1 is the responder's clock at reply, a
        // request's ts1 (tc1 0) the requester's at send. Negative: junk.
        111 => {
            let tc1 = field(payload, 0, 8);
            let own = if tc1 == 0 { field(payload, 8, 8) } else { tc1 };
            let own = if own >> 63 == 0 { own } else { 0 };
            [stamp(TimesyncNs, Sent, own), None]
        }
        // ATTITUDE, ATTITUDE_QUATERNION, SCALED_IMU/2/3, SCALED_PRESSURE/2/3,
        // HIGH_LATENCY2.
        30 | 31 | 26 | 116 | 129 | 29 | 137 | 143 | 235 => [boot_ms(Sent), None],
        // RAW_IMU, HIGHRES_IMU.
        27 | 105 => [stamp_us(Sent, field(payload, 0, 8)), None],
        // GLOBAL_POSITION_INT, LOCAL_POSITION_NED.
        33 | 32 => [boot_ms(Sampled), None],
        // GPS_RAW_INT: the fix's time (boot or, in newer ArduPilot, GPS).
        24 => [stamp_us(Sampled, field(payload, 0, 8)), None],
        _ => [None, None],
    }
}

/// The header's figures of a whole frame, its message [`Msg::Other`].
fn header_of(raw: &[u8]) -> Frame {
    let (version, packet_seq, sysid, compid, msgid, signed) = if raw[0] == STX_V1 {
        (
            Version::V1,
            raw[2],
            raw[3],
            raw[4],
            u32::from(raw[5]),
            false,
        )
    } else {
        (
            Version::V2,
            raw[4],
            raw[5],
            raw[6],
            u32::from_le_bytes([raw[7], raw[8], raw[9], 0]),
            raw[2] & IFLAG_SIGNED != 0,
        )
    };
    // The scanner hands over whole frames; a shorter slice reads 0.
    let crc_at = header_len(raw[0]) + usize::from(raw[1]);
    let crc = raw
        .get(crc_at..crc_at + 2)
        .map_or(0, |b| u16::from_le_bytes([b[0], b[1]]));
    Frame {
        version,
        source: SysComp::new(sysid, compid),
        packet_seq,
        msgid,
        signed,
        // A frame is at most 280 bytes.
        len: u16::try_from(raw.len()).unwrap_or(u16::MAX),
        crc,
        msg: Msg::Other,
        stamps: Stamps::default(),
    }
}

#[allow(deprecated)] // PING: see to_mavlink
fn decode_payload(version: Version, msgid: u32, payload: &[u8]) -> Msg {
    use dialect::MavMessage as M;
    if super::transfer_codec::is_transfer(msgid) {
        return super::transfer_codec::from_payload(msgid, payload)
            .map_or(Msg::Other, Msg::Transfer);
    }
    if !matches!(
        msgid,
        ids::HEARTBEAT
            | ids::PING
            | ids::TIMESYNC
            | ids::COMMAND_LONG
            | ids::COMMAND_ACK
            | ids::RADIO_STATUS
            | ids::LINK_NODE_STATUS
            | ids::RADIO
            | ids::GLOBAL_POSITION_INT
            | ids::GPS_RAW_INT
            | ids::HOME_POSITION
    ) {
        return Msg::Other;
    }
    let version = match version {
        Version::V1 => MavlinkVersion::V1,
        Version::V2 => MavlinkVersion::V2,
    };
    match M::parse(version, msgid, payload) {
        Ok(M::HEARTBEAT(h)) => Msg::Heartbeat {
            mav_type: h.mavtype as u8,
            autopilot: h.autopilot as u8,
        },
        // A HEARTBEAT with an enum value newer than our dialect still tells
        // us a system is there: read the two bytes we show directly.
        Err(_) if msgid == ids::HEARTBEAT => Msg::Heartbeat {
            mav_type: payload.get(4).copied().unwrap_or(0),
            autopilot: payload.get(5).copied().unwrap_or(0),
        },
        Ok(M::PING(p)) => Msg::Ping {
            time_usec: p.time_usec,
            seq: p.seq,
            target_system: p.target_system,
            target_component: p.target_component,
        },
        Ok(M::TIMESYNC(t)) => Msg::Timesync {
            tc1: t.tc1,
            ts1: t.ts1,
            target_system: t.target_system,
            target_component: t.target_component,
        },
        Ok(M::COMMAND_LONG(c)) => Msg::CommandLong {
            command: c.command as u16,
            confirmation: c.confirmation,
            target_system: c.target_system,
            target_component: c.target_component,
            params: [
                c.param1, c.param2, c.param3, c.param4, c.param5, c.param6, c.param7,
            ],
        },
        Ok(M::COMMAND_ACK(a)) => Msg::CommandAck {
            command: a.command as u16,
            result: a.result as u8,
            target_system: a.target_system,
            target_component: a.target_component,
        },
        Ok(M::RADIO_STATUS(r)) => Msg::RadioStatus(r.into()),
        Ok(M::LINK_NODE_STATUS(l)) => Msg::LinkNodeStatus(l.into()),
        Ok(M::RADIO(r)) => Msg::RadioStatus(r.into()),
        Ok(M::GLOBAL_POSITION_INT(p)) => Msg::Fix(Fix {
            kind: FixKind::Estimate,
            lat: p.lat,
            lon: p.lon,
            alt_mm: p.alt,
        }),
        Ok(M::GPS_RAW_INT(g)) => Msg::Fix(Fix {
            kind: FixKind::Gps {
                fix_type: g.fix_type as u8,
            },
            lat: g.lat,
            lon: g.lon,
            alt_mm: g.alt,
        }),
        Ok(M::HOME_POSITION(h)) => Msg::Fix(Fix {
            kind: FixKind::Home,
            lat: h.latitude,
            lon: h.longitude,
            alt_mm: h.altitude,
        }),
        _ => Msg::Other,
    }
}

/// "MAV_TYPE_QUADROTOR" -> "quadrotor"; unknown values print as numbers.
pub(crate) fn enum_name<E: FromPrimitive + std::fmt::Debug>(value: u32, prefix: &str) -> String {
    match E::from_u32(value) {
        Some(e) => {
            let name = format!("{e:?}");
            name.strip_prefix(prefix)
                .unwrap_or(&name)
                .to_ascii_lowercase()
        }
        None => format!("unknown ({value})"),
    }
}

/// MAV_CMD id for a name like "MAV_CMD_REQUEST_MESSAGE" or "request_message".
pub(crate) fn command_id_from_name(name: &str) -> Option<u16> {
    let upper = name.to_ascii_uppercase();
    let full = if upper.starts_with("MAV_CMD_") {
        upper
    } else {
        format!("MAV_CMD_{upper}")
    };
    (0..=u16::MAX)
        .find(|&id| dialect::MavCmd::from_u16(id).is_some_and(|cmd| format!("{cmd:?}") == full))
}

/// Name of a MAV_CMD id ("request_message"), or the number when unknown.
pub(crate) fn command_name(id: u16) -> String {
    enum_name::<dialect::MavCmd>(u32::from(id), "MAV_CMD_")
}

/// Name of a message id ("ATTITUDE"), if the dialect knows it.
pub(crate) fn message_name(id: u32) -> Option<&'static str> {
    dialect::MavMessage::default_message_from_id(id).map(|m| m.message_name())
}

/// Name of a MAV_RESULT value ("accepted").
pub(crate) fn result_name(value: u8) -> String {
    enum_name::<dialect::MavResult>(u32::from(value), "MAV_RESULT_")
}

/// A MAV_MISSION_RESULT's name ("denied"); unknown values as numbers.
pub(crate) fn mission_result_name(value: u8) -> String {
    enum_name::<dialect::MavMissionResult>(u32::from(value), "MAV_MISSION_")
}

#[cfg(test)]
mod tests {
    use super::*;

    fn round_trip(version: Version, msg: Msg) -> Frame {
        let mut bytes = Vec::new();
        encode(
            &mut bytes,
            version,
            Header {
                sysid: 42,
                compid: 7,
                seq: 3,
            },
            &msg,
        );
        let mut frames = Vec::new();
        let mut stats = super::super::ScanStats::default();
        super::super::scan_datagram(&bytes, &mut stats, &mut |f| frames.push(decode(f)));
        assert_eq!(frames.len(), 1);
        frames[0]
    }

    #[test]
    fn messages_survive_a_round_trip_in_both_versions() {
        let messages = [
            Msg::Ping {
                time_usec: u64::MAX,
                seq: u32::MAX,
                target_system: 1,
                target_component: 2,
            },
            Msg::Ping {
                time_usec: 0,
                seq: 0,
                target_system: 0,
                target_component: 0,
            },
            Msg::Heartbeat {
                mav_type: 2,
                autopilot: 12,
            },
            Msg::CommandAck {
                command: 512,
                result: 0,
                target_system: 255,
                target_component: 190,
            },
            Msg::RadioStatus(RadioStatus {
                rssi: 200,
                remrssi: 180,
                txbuf: 90,
                noise: 40,
                remnoise: 41,
                rxerrors: 65535,
                fixed: 3,
            }),
            Msg::LinkNodeStatus(LinkNodeStatus {
                timestamp: 123_456_789,
                tx_buf: 90,
                rx_buf: 80,
                tx_rate: 12_000,
                rx_rate: 600,
                rx_parse_err: 3,
                tx_overflows: 65_535,
                rx_overflows: 1,
                messages_sent: 40_000,
                messages_received: u32::MAX,
                messages_lost: 12,
            }),
        ];
        for version in [Version::V1, Version::V2] {
            for msg in messages {
                let frame = round_trip(version, msg);
                let expected = match (version, msg) {
                    // COMMAND_ACK's target fields are MAVLink 2 extensions.
                    (
                        Version::V1,
                        Msg::CommandAck {
                            command, result, ..
                        },
                    ) => Msg::CommandAck {
                        command,
                        result,
                        target_system: 0,
                        target_component: 0,
                    },
                    _ => msg,
                };
                assert_eq!(frame.msg, expected, "{version:?}");
                assert_eq!(frame.source, SysComp::new(42, 7));
                assert_eq!(frame.version, version);
            }
        }
    }

    /// RADIO (166), as SiK sent it beside RADIO_STATUS until 2016 and
    /// openLRSng still does: read as the same figures, its id kept.
    #[test]
    #[allow(deprecated)]
    fn radio_166_reads_as_radio_status() {
        let data = dialect::RADIO_DATA {
            rxerrors: 513,
            fixed: 2,
            rssi: 190,
            remrssi: 170,
            txbuf: 88,
            noise: 41,
            remnoise: 39,
        };
        let header = MavHeader {
            system_id: 51,
            component_id: 68,
            sequence: 9,
        };
        let mut raw = MAVLinkV1MessageRaw::new();
        raw.serialize_message(header, &dialect::MavMessage::RADIO(data));
        let mut frames = Vec::new();
        let mut stats = super::super::ScanStats::default();
        super::super::scan_datagram(raw.raw_bytes(), &mut stats, &mut |f| frames.push(decode(f)));
        assert_eq!(frames.len(), 1);
        let f = frames[0];
        assert_eq!((f.msgid, f.packet_seq), (ids::RADIO, 9));
        assert_eq!(
            f.msg,
            Msg::RadioStatus(RadioStatus {
                rssi: 190,
                remrssi: 170,
                txbuf: 88,
                noise: 41,
                remnoise: 39,
                rxerrors: 513,
                fixed: 2,
            })
        );
        assert_eq!(message_name(166), Some("RADIO"));
    }

    #[test]
    fn timesync_targets_need_mavlink2() {
        let msg = Msg::Timesync {
            tc1: 0,
            ts1: 1_000_000_007,
            target_system: 1,
            target_component: 1,
        };
        assert_eq!(round_trip(Version::V2, msg).msg, msg);
    }

    #[test]
    fn load_frames_are_full_length_and_decode_as_other_messages_or_a_fix() {
        let len = |version, msg: Msg| {
            let mut bytes = Vec::new();
            let header = Header {
                sysid: 250,
                compid: 190,
                seq: 0,
            };
            encode(&mut bytes, version, header, &msg);
            bytes.len()
        };
        // 28-byte payloads, nothing trimmed: 12 + 28 in MAVLink 2.
        assert_eq!(len(Version::V2, Msg::Attitude { time_boot_ms: 1 }), 40);
        assert_eq!(len(Version::V1, Msg::Attitude { time_boot_ms: 1 }), 36);
        assert_eq!(
            len(Version::V2, Msg::GlobalPositionInt { time_boot_ms: 1 }),
            40
        );
        // Filler: 5 bytes of type and targets, then `len` bytes.
        assert_eq!(len(Version::V2, Msg::Filler { len: 100 }), 12 + 5 + 100);
        for msg in [Msg::Attitude { time_boot_ms: 7 }, Msg::Filler { len: 249 }] {
            assert_eq!(round_trip(Version::V2, msg).msg, Msg::Other);
        }
        // The load's GLOBAL_POSITION_INT is read back as the position it holds.
        let fix = round_trip(Version::V2, Msg::GlobalPositionInt { time_boot_ms: 7 }).msg;
        assert_eq!(
            fix,
            Msg::Fix(Fix {
                kind: FixKind::Estimate,
                lat: 473_977_420,
                lon: 85_455_940,
                alt_mm: 488_000,
            })
        );
    }

    #[test]
    fn positions_decode_from_the_three_messages_in_both_versions() {
        for kind in [
            FixKind::Estimate,
            FixKind::Gps { fix_type: 3 },
            FixKind::Home,
        ] {
            let fix = Fix {
                kind,
                lat: -337_000_001,
                lon: 1_512_000_002,
                alt_mm: 123_456,
            };
            for version in [Version::V1, Version::V2] {
                assert_eq!(round_trip(version, Msg::Fix(fix)).msg, Msg::Fix(fix));
            }
        }
    }

    /// The one frame `message` makes, serialised by the `mavlink` crate
    /// (not by mavping's encoder, so the offsets are checked against it).
    fn crate_frame(version: Version, message: &dialect::MavMessage) -> Frame {
        let header = MavHeader {
            system_id: 1,
            component_id: 1,
            sequence: 0,
        };
        let bytes = match version {
            Version::V1 => {
                let mut raw = MAVLinkV1MessageRaw::new();
                raw.serialize_message(header, message);
                raw.raw_bytes().to_vec()
            }
            Version::V2 => {
                let mut raw = MAVLinkV2MessageRaw::new();
                raw.serialize_message(header, message);
                raw.raw_bytes().to_vec()
            }
        };
        let mut frames = Vec::new();
        let mut stats = super::super::ScanStats::default();
        super::super::scan_datagram(&bytes, &mut stats, &mut |f| frames.push(decode(f)));
        assert_eq!(frames.len(), 1, "{message:?}");
        frames[0]
    }

    fn stamps(version: Version, message: &dialect::MavMessage) -> Vec<Read> {
        crate_frame(version, message)
            .stamps
            .iter()
            .map(|s| (s.clock, s.meaning, s.value))
            .collect()
    }

    /// A stamp's clock, meaning and value, as the tests compare them.
    type Read = (StampClock, StampMeaning, u64);

    const US_BOOT: u64 = 123_456_789_012;
    const US_UNIX: u64 = 1_700_000_000_123_456;

    /// Every stamped message, each field non-zero and distinct, so a wrong
    /// offset reads another field's value.
    #[allow(deprecated)] // PING
    fn stamped_messages() -> Vec<(dialect::MavMessage, Vec<Read>)> {
        use dialect::MavMessage as M;
        use StampClock::{BootMs, BootUs, TimesyncNs, UnixUs};
        use StampMeaning::{Sampled, Sent};
        let ms = 0x0A0B_0C0D;
        let imu = dialect::SCALED_IMU_DATA {
            time_boot_ms: ms,
            xacc: 1,
            yacc: 2,
            zacc: 3,
            xgyro: 4,
            ygyro: 5,
            zgyro: 6,
            xmag: 7,
            ymag: 8,
            zmag: 9,
            temperature: 10,
        };
        let pressure = dialect::SCALED_PRESSURE_DATA {
            time_boot_ms: ms,
            press_abs: 1013.0,
            press_diff: 1.5,
            temperature: 2100,
            temperature_press_diff: 7,
        };
        vec![
            (
                M::SYSTEM_TIME(dialect::SYSTEM_TIME_DATA {
                    time_unix_usec: US_UNIX,
                    time_boot_ms: ms,
                }),
                vec![(BootMs, Sent, u64::from(ms)), (UnixUs, Sent, US_UNIX)],
            ),
            (
                M::SYSTEM_TIME(dialect::SYSTEM_TIME_DATA {
                    time_unix_usec: 0,
                    time_boot_ms: ms,
                }),
                vec![(BootMs, Sent, u64::from(ms))],
            ),
            (
                M::PING(dialect::PING_DATA {
                    time_usec: US_BOOT,
                    seq: 77,
                    target_system: 0,
                    target_component: 0,
                }),
                vec![(BootUs, Sent, US_BOOT)],
            ),
            (
                M::PING(dialect::PING_DATA {
                    time_usec: US_BOOT,
                    seq: 77,
                    target_system: 255,
                    target_component: 190,
                }),
                vec![],
            ),
            (
                M::TIMESYNC(dialect::TIMESYNC_DATA {
                    tc1: 5_000_000_007,
                    ts1: 9_000_000_011,
                    target_system: 1,
                    target_component: 2,
                }),
                vec![(TimesyncNs, Sent, 5_000_000_007)],
            ),
            (
                M::TIMESYNC(dialect::TIMESYNC_DATA {
                    tc1: 0,
                    ts1: 9_000_000_011,
                    target_system: 0,
                    target_component: 0,
                }),
                vec![(TimesyncNs, Sent, 9_000_000_011)],
            ),
            (
                M::ATTITUDE(dialect::ATTITUDE_DATA {
                    time_boot_ms: ms,
                    roll: 0.1,
                    pitch: 0.2,
                    yaw: 0.3,
                    rollspeed: 0.4,
                    pitchspeed: 0.5,
                    yawspeed: 0.6,
                }),
                vec![(BootMs, Sent, u64::from(ms))],
            ),
            (
                M::ATTITUDE_QUATERNION(dialect::ATTITUDE_QUATERNION_DATA {
                    time_boot_ms: ms,
                    q1: 0.5,
                    q2: 0.5,
                    q3: 0.5,
                    q4: 0.5,
                    rollspeed: 0.1,
                    pitchspeed: 0.2,
                    yawspeed: 0.3,
                    repr_offset_q: [0.1, 0.2, 0.3, 0.4],
                }),
                vec![(BootMs, Sent, u64::from(ms))],
            ),
            (
                M::SCALED_IMU(imu.clone()),
                vec![(BootMs, Sent, u64::from(ms))],
            ),
            (
                M::SCALED_IMU2(dialect::SCALED_IMU2_DATA {
                    time_boot_ms: ms,
                    xacc: 1,
                    yacc: 2,
                    zacc: 3,
                    xgyro: 4,
                    ygyro: 5,
                    zgyro: 6,
                    xmag: 7,
                    ymag: 8,
                    zmag: 9,
                    temperature: 10,
                }),
                vec![(BootMs, Sent, u64::from(ms))],
            ),
            (
                M::SCALED_IMU3(dialect::SCALED_IMU3_DATA {
                    time_boot_ms: ms,
                    xacc: 1,
                    yacc: 2,
                    zacc: 3,
                    xgyro: 4,
                    ygyro: 5,
                    zgyro: 6,
                    xmag: 7,
                    ymag: 8,
                    zmag: 9,
                    temperature: 10,
                }),
                vec![(BootMs, Sent, u64::from(ms))],
            ),
            (
                M::RAW_IMU(dialect::RAW_IMU_DATA {
                    time_usec: US_BOOT,
                    xacc: 1,
                    yacc: 2,
                    zacc: 3,
                    xgyro: 4,
                    ygyro: 5,
                    zgyro: 6,
                    xmag: 7,
                    ymag: 8,
                    zmag: 9,
                    id: 1,
                    temperature: 10,
                }),
                vec![(BootUs, Sent, US_BOOT)],
            ),
            (
                M::HIGHRES_IMU(dialect::HIGHRES_IMU_DATA {
                    time_usec: US_UNIX,
                    xacc: 1.0,
                    yacc: 2.0,
                    zacc: 3.0,
                    xgyro: 4.0,
                    ygyro: 5.0,
                    zgyro: 6.0,
                    xmag: 7.0,
                    ymag: 8.0,
                    zmag: 9.0,
                    abs_pressure: 10.0,
                    diff_pressure: 11.0,
                    pressure_alt: 12.0,
                    temperature: 13.0,
                    fields_updated: dialect::HighresImuUpdatedFlags::all(),
                    id: 1,
                }),
                vec![(UnixUs, Sent, US_UNIX)],
            ),
            (
                M::SCALED_PRESSURE(pressure.clone()),
                vec![(BootMs, Sent, u64::from(ms))],
            ),
            (
                M::SCALED_PRESSURE2(dialect::SCALED_PRESSURE2_DATA {
                    time_boot_ms: ms,
                    press_abs: 1013.0,
                    press_diff: 1.5,
                    temperature: 2100,
                    temperature_press_diff: 7,
                }),
                vec![(BootMs, Sent, u64::from(ms))],
            ),
            (
                M::SCALED_PRESSURE3(dialect::SCALED_PRESSURE3_DATA {
                    time_boot_ms: ms,
                    press_abs: 1013.0,
                    press_diff: 1.5,
                    temperature: 2100,
                    temperature_press_diff: 7,
                }),
                vec![(BootMs, Sent, u64::from(ms))],
            ),
            (
                M::HIGH_LATENCY2(dialect::HIGH_LATENCY2_DATA {
                    timestamp: ms,
                    latitude: 11,
                    longitude: 12,
                    custom_mode: 13,
                    altitude: 14,
                    target_altitude: 15,
                    target_distance: 16,
                    wp_num: 17,
                    heading: 18,
                    target_heading: 19,
                    throttle: 20,
                    airspeed: 21,
                    airspeed_sp: 22,
                    groundspeed: 23,
                    windspeed: 24,
                    wind_heading: 25,
                    eph: 26,
                    epv: 27,
                    temperature_air: 28,
                    climb_rate: 29,
                    battery: 30,
                    custom0: 31,
                    custom1: 32,
                    custom2: 33,
                    ..Default::default()
                }),
                vec![(BootMs, Sent, u64::from(ms))],
            ),
            (
                M::GLOBAL_POSITION_INT(dialect::GLOBAL_POSITION_INT_DATA {
                    time_boot_ms: ms,
                    lat: 1,
                    lon: 2,
                    alt: 3,
                    relative_alt: 4,
                    vx: 5,
                    vy: 6,
                    vz: 7,
                    hdg: 8,
                }),
                vec![(BootMs, Sampled, u64::from(ms))],
            ),
            (
                M::LOCAL_POSITION_NED(dialect::LOCAL_POSITION_NED_DATA {
                    time_boot_ms: ms,
                    x: 1.0,
                    y: 2.0,
                    z: 3.0,
                    vx: 4.0,
                    vy: 5.0,
                    vz: 6.0,
                }),
                vec![(BootMs, Sampled, u64::from(ms))],
            ),
            (
                M::GPS_RAW_INT(dialect::GPS_RAW_INT_DATA {
                    time_usec: US_BOOT,
                    lat: 1,
                    lon: 2,
                    alt: 3,
                    eph: 4,
                    epv: 5,
                    vel: 6,
                    cog: 7,
                    satellites_visible: 8,
                    ..Default::default()
                }),
                vec![(BootUs, Sampled, US_BOOT)],
            ),
        ]
    }

    #[test]
    fn stamps_are_read_at_the_offsets_the_crate_writes_them() {
        for (message, expected) in stamped_messages() {
            for version in [Version::V1, Version::V2] {
                assert_eq!(
                    stamps(version, &message),
                    expected,
                    "{version:?} {message:?}"
                );
            }
        }
        // A message without a clock, and a stamp of 0 (no clock yet), carry none.
        let attitude_at_0 = dialect::MavMessage::ATTITUDE(dialect::ATTITUDE_DATA::default());
        assert_eq!(stamps(Version::V2, &attitude_at_0), vec![]);
        let heartbeat = dialect::MavMessage::HEARTBEAT(dialect::HEARTBEAT_DATA::default());
        assert_eq!(stamps(Version::V2, &heartbeat), vec![]);
    }

    /// MAVLink 2 trims a payload's trailing zeros: a stamp whose high bytes
    /// are zero (or the whole later field) is read with them restored.
    #[test]
    fn stamps_survive_zero_trimmed_payloads() {
        let message = dialect::MavMessage::SYSTEM_TIME(dialect::SYSTEM_TIME_DATA {
            time_unix_usec: US_UNIX,
            time_boot_ms: 5,
        });
        let frame = crate_frame(Version::V2, &message);
        assert_eq!(frame.len, 12 + 9, "the boot time's 3 high bytes trimmed");
        assert_eq!(
            frame.stamps.message,
            [
                stamp(StampClock::BootMs, StampMeaning::Sent, 5),
                stamp(StampClock::UnixUs, StampMeaning::Sent, US_UNIX),
            ]
        );
        let attitude = dialect::MavMessage::ATTITUDE(dialect::ATTITUDE_DATA {
            time_boot_ms: 0x0100,
            ..Default::default()
        });
        let frame = crate_frame(Version::V2, &attitude);
        assert_eq!(frame.len, 12 + 2);
        assert_eq!(
            frame.stamps.message[0],
            stamp(StampClock::BootMs, StampMeaning::Sent, 0x0100)
        );
        // A negative TIMESYNC clock is junk, not a stamp.
        let timesync = dialect::MavMessage::TIMESYNC(dialect::TIMESYNC_DATA {
            tc1: -5,
            ts1: 9,
            target_system: 1,
            target_component: 1,
        });
        assert_eq!(stamps(Version::V2, &timesync), vec![]);
    }

    /// A signed frame carries the signature's timestamp beside its
    /// message's own stamp; a damaged one carries none.
    #[test]
    fn a_signature_is_a_stamp_of_its_own() {
        let attitude = Msg::Attitude { time_boot_ms: 42 };
        let mut bytes = Vec::new();
        let header = Header {
            sysid: 1,
            compid: 1,
            seq: 0,
        };
        encode(&mut bytes, Version::V2, header, &attitude);
        let key = super::super::signing::SecretKey::from_bytes([7; 32]);
        super::super::signing::Signer::new(key, 3).sign(&mut bytes, 0, 0x0102_0304_0506);
        let frame = decode(&bytes);
        assert!(frame.signed);
        let got: Vec<_> = frame.stamps.iter().map(|s| (s.clock, s.value)).collect();
        assert_eq!(
            got,
            vec![
                (StampClock::BootMs, 42),
                (StampClock::Signature, 0x0102_0304_0506)
            ]
        );
        let damaged = decode_as(&bytes, Kind::Damaged);
        assert_eq!(damaged.stamps, Stamps::default());
    }

    /// The CRC a frame carries, computed here as MAVLink defines it (over
    /// the bytes after the start byte and the message's CRC_EXTRA), so a
    /// wrong offset or byte order in the codec fails.
    fn computed_crc(bytes: &[u8], msgid: u32) -> u16 {
        let end = super::super::scanner::header_len(bytes[0]) + usize::from(bytes[1]);
        let x25 = crc::Crc::<u16>::new(&crc::CRC_16_MCRF4XX);
        let mut digest = x25.digest();
        digest.update(&bytes[1..end]);
        digest.update(&[super::super::scanner::extra_crc(msgid).expect("known id")]);
        digest.finalize()
    }

    /// Every decode path carries the frame's checksum: MAVLink 1 and 2, a
    /// signed frame (the CRC sits before the signature), a damaged frame
    /// (its CRC as on the wire, not what the bytes would give) and an
    /// unknown id's (header only).
    #[test]
    fn the_wire_crc_is_carried_on_every_path() {
        let header = Header {
            sysid: 1,
            compid: 1,
            seq: 9,
        };
        let msg = Msg::Attitude { time_boot_ms: 42 };
        for version in [Version::V1, Version::V2] {
            let mut bytes = Vec::new();
            encode(&mut bytes, version, header, &msg);
            let frame = decode(&bytes);
            assert_eq!(frame.crc, computed_crc(&bytes, 30), "{version:?}");
            assert_ne!(frame.crc, 0);
            let unknown = decode_as(&bytes, Kind::Unknown);
            assert_eq!(unknown.crc, frame.crc);
            let mut damaged = bytes.clone();
            damaged[12] ^= 0x40;
            let damaged = decode_as(&damaged, Kind::Damaged);
            assert_eq!((damaged.msg, damaged.crc), (Msg::Damaged, frame.crc));
        }
        let mut bytes = Vec::new();
        encode(&mut bytes, Version::V2, header, &msg);
        let unsigned = decode(&bytes).crc;
        let key = super::super::signing::SecretKey::from_bytes([7; 32]);
        super::super::signing::Signer::new(key, 3).sign(&mut bytes, 0, 5);
        let signed = decode(&bytes);
        assert!(signed.signed);
        assert_eq!(signed.crc, computed_crc(&bytes, 30));
        assert_ne!(
            signed.crc, unsigned,
            "signing sets the incompat flag the CRC covers"
        );
    }

    #[test]
    fn names_come_from_the_dialect() {
        assert_eq!(super::super::vehicle_type_name(2), "quadrotor");
        assert_eq!(super::super::autopilot_name(12), "px4");
        assert_eq!(super::super::autopilot_name(3), "ardupilotmega");
        assert_eq!(super::super::vehicle_type_name(250), "unknown (250)");
        assert_eq!(command_id_from_name("request_message"), Some(512));
        assert_eq!(result_name(0), "accepted");
        assert_eq!(message_name(30), Some("ATTITUDE"));
        assert_eq!(message_name(109), Some("RADIO_STATUS"));
        assert_eq!(message_name(8), Some("LINK_NODE_STATUS"));
        assert_eq!(message_name(65_000), None);
    }
}
