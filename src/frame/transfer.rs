//! The messages of the transfers a ground station makes at connect: the
//! parameter list (PARAM_*), the mission (MISSION_*) and MAVLink FTP
//! (FILE_TRANSFER_PROTOCOL), as [`Transfer`] values inside
//! [`Msg::Transfer`](super::Msg::Transfer).
//!
//! A [`Frame`](super::Frame) is copied on every path through the engine,
//! so what it holds stays small: an FTP packet keeps the first
//! [`FTP_HEAD`] bytes of its data (a path, a file's size, a NAK's error),
//! and the data a file server sends is named by where it comes from
//! ([`FtpData::Pattern`]), not carried.

/// Bytes of an FTP packet's data a frame keeps: the longest path a
/// `mavping respond` file is named by, and more than any size or error.
pub const FTP_HEAD: usize = 40;
/// Bytes of data one FTP packet carries at most (251 less its 12-byte header).
pub const FTP_DATA_MAX: usize = 239;

/// One transfer message, as sent or received.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Transfer {
    /// PARAM_REQUEST_LIST: send every parameter.
    ParamRequestList { target: Target },
    /// PARAM_REQUEST_READ: one parameter, by index (or by name when the
    /// index is -1).
    ParamRequestRead {
        target: Target,
        id: ParamId,
        index: i16,
    },
    /// PARAM_VALUE: one parameter, with where it is in the list.
    ParamValue(ParamValue),
    /// MISSION_REQUEST_LIST: how many items has the mission?
    MissionRequestList { target: Target, mission_type: u8 },
    /// MISSION_COUNT: the answer.
    MissionCount {
        target: Target,
        count: u16,
        mission_type: u8,
    },
    /// MISSION_REQUEST_INT (`int`) or the older MISSION_REQUEST: item `seq`.
    MissionRequest {
        target: Target,
        seq: u16,
        mission_type: u8,
        int: bool,
    },
    /// MISSION_ITEM_INT (`int`) or MISSION_ITEM.
    MissionItem(MissionItem),
    /// MISSION_ACK: the transfer's end (`result` a MAV_MISSION_RESULT).
    MissionAck {
        target: Target,
        result: u8,
        mission_type: u8,
    },
    /// FILE_TRANSFER_PROTOCOL.
    Ftp(Ftp),
}

impl Transfer {
    /// Whom it is for; PARAM_VALUE names no one.
    pub fn target(&self) -> Option<Target> {
        match *self {
            Transfer::ParamRequestList { target }
            | Transfer::ParamRequestRead { target, .. }
            | Transfer::MissionRequestList { target, .. }
            | Transfer::MissionCount { target, .. }
            | Transfer::MissionRequest { target, .. }
            | Transfer::MissionAck { target, .. }
            | Transfer::MissionItem(MissionItem { target, .. })
            | Transfer::Ftp(Ftp { target, .. }) => Some(target),
            Transfer::ParamValue(_) => None,
        }
    }
}

/// Whom a request is for (or a reply to).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Target {
    pub system: u8,
    pub component: u8,
}

/// A parameter's name: up to 16 bytes, NUL-padded when shorter.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct ParamId(pub [u8; 16]);

impl ParamId {
    /// `name`'s first 16 bytes.
    pub fn new(name: &str) -> Self {
        let mut id = [0u8; 16];
        let n = name.len().min(16);
        id[..n].copy_from_slice(&name.as_bytes()[..n]);
        ParamId(id)
    }

    /// The name as text (what is not UTF-8 replaced).
    pub fn name(&self) -> String {
        let end = self.0.iter().position(|&b| b == 0).unwrap_or(16);
        String::from_utf8_lossy(&self.0[..end]).into_owned()
    }
}

/// PARAM_VALUE's figures.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ParamValue {
    pub id: ParamId,
    pub value: f32,
    /// MAV_PARAM_TYPE.
    pub param_type: u8,
    /// Parameters the sender has.
    pub count: u16,
    /// This one's place among them; 65535 when it is sent unasked (a
    /// change, not a list).
    pub index: u16,
}

/// A mission item's figures (MISSION_ITEM_INT, or MISSION_ITEM with its
/// position in degrees).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MissionItem {
    pub target: Target,
    pub seq: u16,
    pub mission_type: u8,
    /// MISSION_ITEM_INT (true) or MISSION_ITEM.
    pub int: bool,
    /// MAV_CMD.
    pub command: u16,
    /// MAV_FRAME.
    pub frame: u8,
    /// Degrees × 10^7.
    pub lat: i32,
    pub lon: i32,
    /// Metres.
    pub alt: f32,
}

/// One FILE_TRANSFER_PROTOCOL packet: its header and what the frame keeps
/// of its data.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ftp {
    pub target: Target,
    /// The packet's sequence number: a reply carries its request's + 1.
    pub seq: u16,
    pub session: u8,
    /// The operation (a request), or ACK 128 / NAK 129 (a reply).
    pub opcode: u8,
    /// Bytes of data.
    pub size: u8,
    /// The request a reply answers.
    pub req_opcode: u8,
    /// A burst's last packet.
    pub burst_complete: u8,
    pub offset: u32,
    pub data: FtpData,
}

/// What an FTP packet's data is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FtpData {
    /// The first [`FTP_HEAD`] bytes (the rest, up to `size`, not kept).
    Head([u8; FTP_HEAD]),
    /// `size` bytes of [`pattern_byte`] from `offset`: what `mavping
    /// respond`'s file holds, made when the frame is written.
    Pattern,
}

impl FtpData {
    /// `bytes`' first [`FTP_HEAD`].
    pub fn head(bytes: &[u8]) -> Self {
        let mut head = [0u8; FTP_HEAD];
        let n = bytes.len().min(FTP_HEAD);
        head[..n].copy_from_slice(&bytes[..n]);
        FtpData::Head(head)
    }

    /// The kept bytes (a pattern's are made).
    pub fn bytes(&self, offset: u32, size: u8) -> [u8; FTP_HEAD] {
        match self {
            FtpData::Head(head) => *head,
            FtpData::Pattern => {
                let mut head = [0u8; FTP_HEAD];
                for (i, b) in head.iter_mut().take(usize::from(size)).enumerate() {
                    *b = pattern_byte(offset + i as u32);
                }
                head
            }
        }
    }
}

/// The byte at `offset` of the file `mavping respond` serves: not a
/// repeat of a short period, so a block read at the wrong offset differs.
pub fn pattern_byte(offset: u32) -> u8 {
    let x = offset.wrapping_mul(2_654_435_761);
    (x >> 24) as u8 ^ (offset >> 8) as u8
}

/// The MAVLink FTP operations mavping sends or serves.
pub mod ftp_op {
    pub const TERMINATE_SESSION: u8 = 1;
    pub const RESET_SESSIONS: u8 = 2;
    pub const LIST_DIRECTORY: u8 = 3;
    pub const OPEN_FILE_RO: u8 = 4;
    pub const READ_FILE: u8 = 5;
    pub const BURST_READ_FILE: u8 = 15;
    pub const ACK: u8 = 128;
    pub const NAK: u8 = 129;
}

/// MAVLink FTP's NAK error codes (the first data byte).
pub mod ftp_error {
    pub const FAIL: u8 = 1;
    pub const FAIL_ERRNO: u8 = 2;
    pub const INVALID_DATA_SIZE: u8 = 3;
    pub const INVALID_SESSION: u8 = 4;
    pub const NO_SESSIONS_AVAILABLE: u8 = 5;
    pub const EOF: u8 = 6;
    pub const UNKNOWN_COMMAND: u8 = 7;
    pub const FILE_EXISTS: u8 = 8;
    pub const FILE_PROTECTED: u8 = 9;
    pub const FILE_NOT_FOUND: u8 = 10;
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_param_id_keeps_sixteen_bytes_and_reads_back() {
        assert_eq!(ParamId::new("SYSID_THISMAV").name(), "SYSID_THISMAV");
        let long = ParamId::new("ABCDEFGHIJKLMNOPQRS");
        assert_eq!(long.name(), "ABCDEFGHIJKLMNOP");
    }

    #[test]
    fn the_pattern_does_not_repeat_within_a_block() {
        let block: Vec<u8> = (0..239).map(pattern_byte).collect();
        let shifted: Vec<u8> = (1..240).map(pattern_byte).collect();
        assert_ne!(block, shifted);
        let data = FtpData::Pattern.bytes(1000, 3);
        assert_eq!(
            &data[..4],
            &[
                pattern_byte(1000),
                pattern_byte(1001),
                pattern_byte(1002),
                0
            ]
        );
    }
}
