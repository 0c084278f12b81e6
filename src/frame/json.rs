//! mavlink2rest's JSON: one MAVLink message as a text, the `mavlink`
//! crate's serde form of the message beside the frame's header —
//! `{"header":{"system_id":1,"component_id":1,"sequence":7},
//! "message":{"type":"PING","time_usec":..,"seq":..,..}}`, enums as
//! `{"type":"MAV_TYPE_GCS"}`, bit flags as `"FLAG_A | FLAG_B"`. What
//! mavlink2rest and mavlink-server (which adds `"message_id"` to the
//! header) send on their WebSockets and take from them.
//!
//! Here, beside the scanner, because the crate's types stay in `frame`: a
//! link hands over text and gets frame bytes back.

use mavlink::dialects::ardupilotmega::MavMessage;
use mavlink::{MAVLinkV2MessageRaw, MavHeader, MavlinkVersion, Message};
use serde::Deserialize;
use serde_json::{Map, Value};

use super::scanner::{header_len, STX_V1};

/// What one text turned out to be.
#[derive(Debug, PartialEq)]
pub(crate) enum FromJson {
    /// A MAVLink 2 frame of the message, with the header's ids and
    /// sequence.
    Frame(Vec<u8>),
    /// A message of a type this build's dialect does not know.
    Unknown(String),
    /// Not a message, and why.
    NotMessage(String),
}

/// One whole, CRC-checked frame as mavlink2rest's JSON; `None` for a
/// message id the dialect does not know (it has no JSON form).
pub(crate) fn to_json(raw: &[u8]) -> Option<String> {
    let (version, seq, sysid, compid, msgid) = if raw[0] == STX_V1 {
        (
            MavlinkVersion::V1,
            raw[2],
            raw[3],
            raw[4],
            u32::from(raw[5]),
        )
    } else {
        let id = u32::from_le_bytes([raw[7], raw[8], raw[9], 0]);
        (MavlinkVersion::V2, raw[4], raw[5], raw[6], id)
    };
    let payload = &raw[header_len(raw[0])..][..usize::from(raw[1])];
    let message = MavMessage::parse(version, msgid, payload).ok()?;
    let header = MavHeader {
        system_id: u32::from(sysid),
        component_id: compid,
        sequence: seq,
    };
    let envelope = serde_json::json!({ "header": header, "message": message });
    serde_json::to_string(&envelope).ok()
}

/// One text from a mavlink2rest WebSocket, read.
pub(crate) fn from_json(text: &str) -> FromJson {
    match read(text) {
        Ok(frame) => frame,
        Err(why) => FromJson::NotMessage(why),
    }
}

fn read(text: &str) -> Result<FromJson, String> {
    let value: Value = serde_json::from_str(text).map_err(|e| format!("not JSON ({e})"))?;
    let Value::Object(mut top) = value else {
        return Err("JSON but not an object".into());
    };
    let (Some(Value::Object(header)), Some(Value::Object(mut message))) =
        (top.remove("header"), top.remove("message"))
    else {
        return Err("JSON without a \"header\" and a \"message\" object".into());
    };
    let Some(name) = message.get("type").and_then(Value::as_str) else {
        return Err("a \"message\" without a \"type\"".into());
    };
    if MavMessage::message_id_from_name(name).is_none() {
        return Ok(FromJson::Unknown(name.to_string()));
    }
    let name = name.to_string();
    let header = MavHeader {
        system_id: u32::from(id_field(&header, "system_id")?),
        component_id: id_field(&header, "component_id")?,
        sequence: id_field(&header, "sequence")?,
    };
    flags_from_bits(&mut message);
    let message = Value::Object(message);
    let message = match MavMessage::deserialize(&message) {
        Ok(message) => message,
        // Older crates wrote char arrays as numbers: read them as text.
        Err(e) => serde_json::from_value(strings_from_numbers(message))
            .map_err(|_| format!("a {name} this dialect cannot read ({e})"))?,
    };
    let mut raw = MAVLinkV2MessageRaw::new();
    raw.serialize_message(header, &message);
    Ok(FromJson::Frame(raw.raw_bytes().to_vec()))
}

/// A header field, which MAVLink 2 carries in one byte.
fn id_field(header: &Map<String, Value>, name: &str) -> Result<u8, String> {
    header
        .get(name)
        .and_then(Value::as_u64)
        .and_then(|v| u8::try_from(v).ok())
        .ok_or_else(|| format!("a header whose \"{name}\" is not a number 0-255"))
}

/// Bit flags written as `{"bits": 81}` (the form of the crate's releases
/// on bitflags 1, which older mavlink2rest builds and Cockpit use) become
/// the `"0x51"` today's crate reads.
fn flags_from_bits(message: &mut Map<String, Value>) {
    for value in message.values_mut() {
        let Value::Object(field) = value else {
            continue;
        };
        if field.len() != 1 {
            continue;
        }
        if let Some(bits) = field.get("bits").and_then(Value::as_u64) {
            *value = Value::String(format!("{bits:#x}"));
        }
    }
}

/// Arrays of bytes made text up to the first NUL: `char[N]` fields as
/// the crate wrote them before it had a string type for them (0.15 and
/// older, which older mavlink2rest builds use).
fn strings_from_numbers(mut message: Value) -> Value {
    let Value::Object(fields) = &mut message else {
        return message;
    };
    for value in fields.values_mut() {
        let Value::Array(items) = value else {
            continue;
        };
        let bytes: Option<Vec<u8>> = items
            .iter()
            .map(|v| v.as_u64().and_then(|b| u8::try_from(b).ok()))
            .collect();
        if let Some(bytes) = bytes {
            let end = bytes.iter().position(|&b| b == 0).unwrap_or(bytes.len());
            *value = Value::String(String::from_utf8_lossy(&bytes[..end]).into_owned());
        }
    }
    message
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frame::{decode, Msg};

    fn v2(header: MavHeader, message: &MavMessage) -> Vec<u8> {
        let mut raw = MAVLinkV2MessageRaw::new();
        raw.serialize_message(header, message);
        raw.raw_bytes().to_vec()
    }

    // PING is deprecated in the XML, and still what vehicles answer.
    #[allow(deprecated)]
    fn ping() -> MavMessage {
        MavMessage::PING(mavlink::dialects::ardupilotmega::PING_DATA {
            time_usec: 1_733_400_000_123_456,
            seq: 42,
            target_system: 0,
            target_component: 0,
        })
    }

    #[test]
    fn a_ping_is_written_as_mavlink2rest_writes_it() {
        let header = MavHeader {
            system_id: 255,
            component_id: 190,
            sequence: 7,
        };
        let json = to_json(&v2(header, &ping())).unwrap();
        assert_eq!(
            json,
            r#"{"header":{"system_id":255,"component_id":190,"sequence":7},"message":{"type":"PING","time_usec":1733400000123456,"seq":42,"target_system":0,"target_component":0}}"#
        );
    }

    #[test]
    fn a_heartbeat_has_its_enums_as_objects_and_its_flags_as_names() {
        use mavlink::dialects::ardupilotmega::*;
        let hb = MavMessage::HEARTBEAT(HEARTBEAT_DATA {
            custom_mode: 4,
            mavtype: MavType::MAV_TYPE_QUADROTOR,
            autopilot: MavAutopilot::MAV_AUTOPILOT_ARDUPILOTMEGA,
            base_mode: MavModeFlag::MAV_MODE_FLAG_SAFETY_ARMED
                | MavModeFlag::MAV_MODE_FLAG_CUSTOM_MODE_ENABLED,
            system_status: MavState::MAV_STATE_ACTIVE,
            mavlink_version: 3,
        });
        let json = to_json(&v2(MavHeader::default(), &hb)).unwrap();
        assert!(
            json.contains(r#""mavtype":{"type":"MAV_TYPE_QUADROTOR"}"#),
            "{json}"
        );
        assert!(
            json.contains(
                r#""base_mode":"MAV_MODE_FLAG_SAFETY_ARMED | MAV_MODE_FLAG_CUSTOM_MODE_ENABLED""#
            ),
            "{json}"
        );
        // And back, to the same frame.
        let FromJson::Frame(raw) = from_json(&json) else {
            panic!("{json}")
        };
        assert_eq!(raw, v2(MavHeader::default(), &hb));
    }

    #[test]
    fn a_message_read_becomes_a_frame_with_the_header_s_ids_and_sequence() {
        // As mavlink-server writes it: message_id in the header, pretty.
        let text = r#"{
          "header": {"system_id": 1, "component_id": 1, "sequence": 200, "message_id": 4},
          "message": {"type": "PING", "time_usec": 1733400000123456, "seq": 42,
                      "target_system": 255, "target_component": 190}
        }"#;
        let FromJson::Frame(raw) = from_json(text) else {
            panic!()
        };
        let frame = decode(&raw);
        assert_eq!((frame.source.sysid, frame.source.compid), (1, 1));
        assert_eq!(frame.packet_seq, 200);
        assert!(
            matches!(frame.msg, Msg::Ping { seq: 42, .. }),
            "{:?}",
            frame.msg
        );
    }

    #[test]
    fn flags_as_bits_are_read_too() {
        let text = r#"{"header":{"system_id":1,"component_id":1,"sequence":0},
          "message":{"type":"HEARTBEAT","custom_mode":0,"mavtype":{"type":"MAV_TYPE_SUBMARINE"},
          "autopilot":{"type":"MAV_AUTOPILOT_ARDUPILOTMEGA"},"base_mode":{"bits":129},
          "system_status":{"type":"MAV_STATE_STANDBY"},"mavlink_version":3}}"#;
        let FromJson::Frame(raw) = from_json(text) else {
            panic!("{:?}", from_json(text))
        };
        // base_mode is the payload's byte 6.
        assert_eq!(raw[10 + 6], 129);
    }

    #[test]
    fn char_arrays_as_numbers_are_read_as_text() {
        let mut text = [0u8; 50];
        text[..5].copy_from_slice(b"Armed");
        let numbers: Vec<String> = text.iter().map(u8::to_string).collect();
        let json = format!(
            r#"{{"header":{{"system_id":1,"component_id":1,"sequence":3}},
              "message":{{"type":"STATUSTEXT","severity":{{"type":"MAV_SEVERITY_INFO"}},
              "text":[{}],"id":0,"chunk_seq":0}}}}"#,
            numbers.join(",")
        );
        let FromJson::Frame(raw) = from_json(&json) else {
            panic!("{:?}", from_json(&json))
        };
        // severity, then the text; MAVLink 2 trims the zeros after it.
        assert_eq!(&raw[10..raw.len() - 2], b"\x06Armed");
        // A byte array stays one: a TUNNEL's payload is numbers today too.
        let tunnel = r#"{"header":{"system_id":1,"component_id":1,"sequence":0},
          "message":{"type":"TUNNEL","target_system":0,"target_component":0,"payload_type":{"type":"MAV_TUNNEL_PAYLOAD_TYPE_UNKNOWN"},"payload_length":1,
          "payload":[7,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0]}}"#;
        assert!(
            matches!(from_json(tunnel), FromJson::Frame(_)),
            "{:?}",
            from_json(tunnel)
        );
    }

    #[test]
    fn what_is_not_a_message_says_why_and_unknown_types_are_named() {
        for (text, says) in [
            ("Ok(14)", "not JSON"),
            ("[1,2]", "not an object"),
            (r#"{"error":"MAVLink callback does not exist."}"#, "without"),
            (r#"{"header":{},"message":{}}"#, "without a \"type\""),
            (
                r#"{"header":{"system_id":300,"component_id":1,"sequence":0},"message":{"type":"PING"}}"#,
                "system_id",
            ),
            (
                r#"{"header":{"system_id":1,"component_id":1,"sequence":0},"message":{"type":"PING","seq":"x"}}"#,
                "a PING this dialect cannot read",
            ),
        ] {
            match from_json(text) {
                FromJson::NotMessage(why) => assert!(why.contains(says), "{text}: {why}"),
                other => panic!("{text}: {other:?}"),
            }
        }
        assert_eq!(
            from_json(r#"{"header":{},"message":{"type":"NO_SUCH_MESSAGE"}}"#),
            FromJson::Unknown("NO_SUCH_MESSAGE".into())
        );
    }
}
