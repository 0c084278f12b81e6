//! Which bytes hold good MAVLink frames, stated from the MAVLink framing
//! rules and the `mavlink` crate's dialect (CRC_EXTRA, which ids exist,
//! MAVLink 1 payload lengths), without the scanner's code. The property
//! tests and the `scanner` fuzz target (which includes this file) check the
//! scanner against it: every good frame that overlaps no other good frame
//! is delivered.

use std::ops::Range;

use mavlink::dialects::ardupilotmega::MavMessage;
use mavlink::{MavlinkVersion, Message};

/// The extent of every whole good frame in `data`: a known message id, a
/// matching CRC, supported incompatibility flags and, in MAVLink 1, the
/// message's own payload length. Overlapping ones included.
pub fn good_frames(data: &[u8]) -> Vec<Range<usize>> {
    (0..data.len())
        .filter_map(|at| {
            let len = good_frame_len(&data[at..])?;
            Some(at..at + len)
        })
        .collect()
}

/// The good frames that share no byte with another good frame: the ones
/// no rule has to choose between.
pub fn isolated(frames: &[Range<usize>]) -> Vec<Range<usize>> {
    frames
        .iter()
        .filter(|f| {
            !frames
                .iter()
                .any(|g| g != *f && g.start < f.end && f.start < g.end)
        })
        .cloned()
        .collect()
}

fn good_frame_len(b: &[u8]) -> Option<usize> {
    let (header, msgid, signature) = match *b.first()? {
        0xFE => (6, u32::from(*b.get(5)?), 0),
        0xFD => {
            let flags = *b.get(2)?;
            if flags > 1 {
                return None;
            }
            let id = u32::from_le_bytes([*b.get(7)?, *b.get(8)?, *b.get(9)?, 0]);
            (10, id, 13 * usize::from(flags))
        }
        _ => return None,
    };
    let payload = usize::from(*b.get(1)?);
    let total = header + payload + 2 + signature;
    if b.len() < total {
        return None;
    }
    let default = MavMessage::default_message_from_id(msgid)?;
    if b[0] == 0xFE && default.ser(MavlinkVersion::V1, &mut [0; 255]) != payload {
        return None;
    }
    let crc = mavlink::calculate_crc(&b[1..header + payload], MavMessage::extra_crc(msgid));
    (crc.to_le_bytes() == b[header + payload..header + payload + 2]).then_some(total)
}
