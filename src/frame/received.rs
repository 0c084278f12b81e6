//! One received frame as the rest of mavping sees it ([`Frame`]): its
//! header figures and its decoded message.

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
    pub msg: Msg,
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
        msg,
    }
}
