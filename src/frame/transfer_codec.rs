//! [`Transfer`] messages to and from the wire. Written through the
//! `mavlink` crate's structs (its CRC extras and trimming); read straight
//! from the payload at the fields' offsets, so a MAV_CMD, frame or
//! parameter type newer than our dialect still reads (the crate refuses a
//! message with an enum value it does not know, and a mission item it
//! refused would be asked for again for ever). The tests hold every
//! offset to the crate's own serialisation.

use mavlink::dialects::ardupilotmega as dialect;
use num_traits::FromPrimitive;

use super::dialect::ids;
use super::transfer::{
    pattern_byte, Ftp, FtpData, MissionItem, ParamId, ParamValue, Target, Transfer, FTP_DATA_MAX,
};

/// `t` as the crate's message.
#[allow(deprecated)] // MISSION_REQUEST and MISSION_ITEM: what MAVProxy still sends.
pub(super) fn to_mavlink(t: &Transfer) -> dialect::MavMessage {
    use dialect::MavMessage as M;
    match *t {
        Transfer::ParamRequestList { target } => {
            M::PARAM_REQUEST_LIST(dialect::PARAM_REQUEST_LIST_DATA {
                target_system: target.system,
                target_component: target.component,
            })
        }
        Transfer::ParamRequestRead { target, id, index } => {
            M::PARAM_REQUEST_READ(dialect::PARAM_REQUEST_READ_DATA {
                param_index: index,
                target_system: target.system,
                target_component: target.component,
                param_id: id.0.into(),
            })
        }
        Transfer::ParamValue(p) => M::PARAM_VALUE(dialect::PARAM_VALUE_DATA {
            param_value: p.value,
            param_count: p.count,
            param_index: p.index,
            param_id: p.id.0.into(),
            param_type: dialect::MavParamType::from_u8(p.param_type).unwrap_or_default(),
        }),
        Transfer::MissionRequestList {
            target,
            mission_type,
        } => M::MISSION_REQUEST_LIST(dialect::MISSION_REQUEST_LIST_DATA {
            target_system: target.system,
            target_component: target.component,
            mission_type: mission_type_of(mission_type),
        }),
        Transfer::MissionCount {
            target,
            count,
            mission_type,
        } => M::MISSION_COUNT(dialect::MISSION_COUNT_DATA {
            count,
            target_system: target.system,
            target_component: target.component,
            mission_type: mission_type_of(mission_type),
            opaque_id: 0,
        }),
        Transfer::MissionRequest {
            target,
            seq,
            mission_type,
            int,
        } => {
            if int {
                M::MISSION_REQUEST_INT(dialect::MISSION_REQUEST_INT_DATA {
                    seq,
                    target_system: target.system,
                    target_component: target.component,
                    mission_type: mission_type_of(mission_type),
                })
            } else {
                M::MISSION_REQUEST(dialect::MISSION_REQUEST_DATA {
                    seq,
                    target_system: target.system,
                    target_component: target.component,
                    mission_type: mission_type_of(mission_type),
                })
            }
        }
        Transfer::MissionItem(item) => mission_item(&item),
        Transfer::MissionAck {
            target,
            result,
            mission_type,
        } => M::MISSION_ACK(dialect::MISSION_ACK_DATA {
            target_system: target.system,
            target_component: target.component,
            mavtype: dialect::MavMissionResult::from_u8(result).unwrap_or_default(),
            mission_type: mission_type_of(mission_type),
            opaque_id: 0,
        }),
        Transfer::Ftp(f) => M::FILE_TRANSFER_PROTOCOL(dialect::FILE_TRANSFER_PROTOCOL_DATA {
            target_network: 0,
            target_system: f.target.system,
            target_component: f.target.component,
            payload: ftp_payload(&f),
        }),
    }
}

fn mission_type_of(value: u8) -> dialect::MavMissionType {
    dialect::MavMissionType::from_u8(value).unwrap_or_default()
}

#[allow(deprecated)]
fn mission_item(item: &MissionItem) -> dialect::MavMessage {
    use dialect::MavMessage as M;
    let command = dialect::MavCmd::from_u16(item.command).unwrap_or_default();
    let frame = dialect::MavFrame::from_u8(item.frame).unwrap_or_default();
    let (target_system, target_component) = (item.target.system, item.target.component);
    let mission_type = mission_type_of(item.mission_type);
    if item.int {
        M::MISSION_ITEM_INT(dialect::MISSION_ITEM_INT_DATA {
            x: item.lat,
            y: item.lon,
            z: item.alt,
            seq: item.seq,
            command,
            target_system,
            target_component,
            frame,
            autocontinue: 1,
            mission_type,
            ..Default::default()
        })
    } else {
        M::MISSION_ITEM(dialect::MISSION_ITEM_DATA {
            x: item.lat as f32 / 1e7,
            y: item.lon as f32 / 1e7,
            z: item.alt,
            seq: item.seq,
            command,
            target_system,
            target_component,
            frame,
            autocontinue: 1,
            mission_type,
            ..Default::default()
        })
    }
}

/// An FTP packet's 251 bytes: its header, then its data.
fn ftp_payload(f: &Ftp) -> [u8; 251] {
    let mut p = [0u8; 251];
    p[0..2].copy_from_slice(&f.seq.to_le_bytes());
    p[2] = f.session;
    p[3] = f.opcode;
    p[4] = f.size;
    p[5] = f.req_opcode;
    p[6] = f.burst_complete;
    p[8..12].copy_from_slice(&f.offset.to_le_bytes());
    let size = usize::from(f.size).min(FTP_DATA_MAX);
    let data = &mut p[12..12 + size];
    match f.data {
        FtpData::Head(head) => {
            let n = size.min(head.len());
            data[..n].copy_from_slice(&head[..n]);
        }
        FtpData::Pattern => {
            for (i, b) in data.iter_mut().enumerate() {
                *b = pattern_byte(f.offset.wrapping_add(i as u32));
            }
        }
    }
    p
}

/// Whether `msgid` is a transfer message [`from_payload`] reads.
pub(super) fn is_transfer(msgid: u32) -> bool {
    matches!(
        msgid,
        ids::PARAM_REQUEST_READ
            | ids::PARAM_REQUEST_LIST
            | ids::PARAM_VALUE
            | ids::MISSION_ITEM
            | ids::MISSION_REQUEST
            | ids::MISSION_REQUEST_LIST
            | ids::MISSION_COUNT
            | ids::MISSION_ACK
            | ids::MISSION_REQUEST_INT
            | ids::MISSION_ITEM_INT
            | ids::FILE_TRANSFER_PROTOCOL
    )
}

/// Reads a payload's little-endian fields; bytes past its end were
/// trimmed zeros (MAVLink 2).
struct Fields<'a>(&'a [u8]);

impl Fields<'_> {
    fn u8(&self, at: usize) -> u8 {
        self.0.get(at).copied().unwrap_or(0)
    }
    fn u16(&self, at: usize) -> u16 {
        u16::from_le_bytes([self.u8(at), self.u8(at + 1)])
    }
    fn u32(&self, at: usize) -> u32 {
        u32::from_le_bytes([
            self.u8(at),
            self.u8(at + 1),
            self.u8(at + 2),
            self.u8(at + 3),
        ])
    }
    fn f32(&self, at: usize) -> f32 {
        f32::from_bits(self.u32(at))
    }
    fn target(&self, at: usize) -> Target {
        Target {
            system: self.u8(at),
            component: self.u8(at + 1),
        }
    }
    fn bytes<const N: usize>(&self, at: usize) -> [u8; N] {
        std::array::from_fn(|i| self.u8(at + i))
    }
}

/// The transfer message in `payload`, by its offsets (wire order: fields
/// by size, extensions last).
pub(super) fn from_payload(msgid: u32, payload: &[u8]) -> Option<Transfer> {
    let f = Fields(payload);
    Some(match msgid {
        ids::PARAM_REQUEST_READ => Transfer::ParamRequestRead {
            index: f.u16(0) as i16,
            target: f.target(2),
            id: ParamId(f.bytes(4)),
        },
        ids::PARAM_REQUEST_LIST => Transfer::ParamRequestList {
            target: f.target(0),
        },
        ids::PARAM_VALUE => Transfer::ParamValue(ParamValue {
            value: f.f32(0),
            count: f.u16(4),
            index: f.u16(6),
            id: ParamId(f.bytes(8)),
            param_type: f.u8(24),
        }),
        ids::MISSION_ITEM | ids::MISSION_ITEM_INT => {
            let int = msgid == ids::MISSION_ITEM_INT;
            let (lat, lon) = if int {
                (f.u32(16) as i32, f.u32(20) as i32)
            } else {
                (degrees_e7(f.f32(16)), degrees_e7(f.f32(20)))
            };
            Transfer::MissionItem(MissionItem {
                lat,
                lon,
                alt: f.f32(24),
                seq: f.u16(28),
                command: f.u16(30),
                target: f.target(32),
                frame: f.u8(34),
                mission_type: f.u8(37),
                int,
            })
        }
        ids::MISSION_REQUEST | ids::MISSION_REQUEST_INT => Transfer::MissionRequest {
            seq: f.u16(0),
            target: f.target(2),
            mission_type: f.u8(4),
            int: msgid == ids::MISSION_REQUEST_INT,
        },
        ids::MISSION_REQUEST_LIST => Transfer::MissionRequestList {
            target: f.target(0),
            mission_type: f.u8(2),
        },
        ids::MISSION_COUNT => Transfer::MissionCount {
            count: f.u16(0),
            target: f.target(2),
            mission_type: f.u8(4),
        },
        ids::MISSION_ACK => Transfer::MissionAck {
            target: f.target(0),
            result: f.u8(2),
            mission_type: f.u8(3),
        },
        ids::FILE_TRANSFER_PROTOCOL => Transfer::Ftp(ftp_from(&f)),
        _ => return None,
    })
}

fn ftp_from(f: &Fields<'_>) -> Ftp {
    // target_network, target_system, target_component, then the packet.
    let p = Fields(f.0.get(3..).unwrap_or_default());
    let size = p.u8(4);
    let data_end = 12 + usize::from(size).min(FTP_DATA_MAX);
    let data = p.0.get(12..data_end.min(p.0.len())).unwrap_or_default();
    Ftp {
        target: f.target(1),
        seq: p.u16(0),
        session: p.u8(2),
        opcode: p.u8(3),
        size,
        req_opcode: p.u8(5),
        burst_complete: p.u8(6),
        offset: p.u32(8),
        data: FtpData::head(data),
    }
}

/// MISSION_ITEM's degrees as MISSION_ITEM_INT's degrees × 10^7.
fn degrees_e7(degrees: f32) -> i32 {
    (f64::from(degrees) * 1e7).round() as i32
}

#[cfg(test)]
mod tests {
    use super::super::codec::{decode, encode, Header, Version};
    use super::super::transfer::ftp_op;
    use super::super::Msg;
    use super::*;

    fn round_trip(t: Transfer, version: Version) -> Transfer {
        let mut out = Vec::new();
        let header = Header {
            sysid: 1,
            compid: 1,
            seq: 0,
        };
        encode(&mut out, version, header, &Msg::Transfer(t));
        match decode(&out).msg {
            Msg::Transfer(back) => back,
            other => panic!("{other:?}"),
        }
    }

    const TO: Target = Target {
        system: 1,
        component: 1,
    };

    #[test]
    fn every_transfer_message_reads_back_as_written_in_both_versions() {
        let messages = [
            Transfer::ParamRequestList { target: TO },
            Transfer::ParamRequestRead {
                target: TO,
                id: ParamId::new("RATE_RLL_P"),
                index: 412,
            },
            Transfer::ParamRequestRead {
                target: TO,
                id: ParamId::new("SYSID_THISMAV"),
                index: -1,
            },
            Transfer::ParamValue(ParamValue {
                id: ParamId::new("MAVPING_0007"),
                value: 7.5,
                param_type: 9,
                count: 1000,
                index: 7,
            }),
            Transfer::MissionRequestList {
                target: TO,
                mission_type: 0,
            },
            Transfer::MissionCount {
                target: TO,
                count: 42,
                mission_type: 0,
            },
            Transfer::MissionRequest {
                target: TO,
                seq: 41,
                mission_type: 0,
                int: true,
            },
            Transfer::MissionRequest {
                target: TO,
                seq: 3,
                mission_type: 0,
                int: false,
            },
            Transfer::MissionItem(MissionItem {
                target: TO,
                seq: 9,
                mission_type: 0,
                int: true,
                command: 16,
                frame: 6,
                lat: 473_977_420,
                lon: 85_455_940,
                alt: 30.5,
            }),
            Transfer::MissionAck {
                target: TO,
                result: 0,
                mission_type: 0,
            },
            Transfer::Ftp(Ftp {
                target: TO,
                seq: 513,
                session: 2,
                opcode: ftp_op::OPEN_FILE_RO,
                size: 16,
                req_opcode: 0,
                burst_complete: 0,
                offset: 0,
                data: FtpData::head(b"@PARAM/param.pck"),
            }),
        ];
        for version in [Version::V1, Version::V2] {
            for t in messages {
                assert_eq!(round_trip(t, version), t, "{version:?}");
            }
        }
    }

    #[test]
    fn a_mission_item_in_degrees_reads_to_the_same_position() {
        let item = MissionItem {
            target: TO,
            seq: 1,
            mission_type: 0,
            int: false,
            command: 16,
            frame: 3,
            lat: 473_977_420,
            lon: 85_455_940,
            alt: 12.0,
        };
        let Transfer::MissionItem(back) = round_trip(Transfer::MissionItem(item), Version::V2)
        else {
            panic!()
        };
        // An f32 holds degrees to about a metre at these latitudes.
        assert!((back.lat - item.lat).abs() < 100, "{}", back.lat);
        assert!((back.lon - item.lon).abs() < 100, "{}", back.lon);
    }

    #[test]
    fn a_command_our_dialect_does_not_know_still_reads() {
        let item = MissionItem {
            target: TO,
            seq: 5,
            mission_type: 0,
            int: true,
            command: 16,
            frame: 6,
            lat: 1,
            lon: 2,
            alt: 3.0,
        };
        let mut out = Vec::new();
        let header = Header {
            sysid: 1,
            compid: 1,
            seq: 0,
        };
        encode(
            &mut out,
            Version::V1,
            header,
            &Msg::Transfer(Transfer::MissionItem(item)),
        );
        // MAV_CMD 65000 is in no dialect: patch it in (V1: 6-byte header,
        // command at payload offset 30) and fix the CRC as a sender would.
        out[6 + 30..6 + 32].copy_from_slice(&65000u16.to_le_bytes());
        let crc_at = out.len() - 2;
        let crc = mavlink::calculate_crc(&out[1..crc_at], 38); // MISSION_ITEM_INT's extra
        out[crc_at..].copy_from_slice(&crc.to_le_bytes());
        let Msg::Transfer(Transfer::MissionItem(back)) = decode(&out).msg else {
            panic!("{:?}", decode(&out));
        };
        assert_eq!(back.command, 65000);
    }

    #[test]
    fn a_pattern_file_packet_carries_the_pattern_and_keeps_its_head() {
        let sent = Ftp {
            target: TO,
            seq: 7,
            session: 0,
            opcode: ftp_op::ACK,
            size: 239,
            req_opcode: ftp_op::BURST_READ_FILE,
            burst_complete: 1,
            offset: 4780,
            data: FtpData::Pattern,
        };
        let payload = ftp_payload(&sent);
        assert_eq!(payload[12 + 238], pattern_byte(4780 + 238));
        let Transfer::Ftp(back) = round_trip(Transfer::Ftp(sent), Version::V2) else {
            panic!()
        };
        assert_eq!(back.data, FtpData::Head(FtpData::Pattern.bytes(4780, 239)));
        assert_eq!(
            (back.size, back.offset, back.burst_complete),
            (239, 4780, 1)
        );
    }
}
