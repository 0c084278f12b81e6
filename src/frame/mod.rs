//! MAVLink frames as the rest of mavping sees them.
//!
//! The `mavlink` crate's types stay inside this module: transports hand the
//! engine a [`Frame`] with the few messages a latency tool cares about
//! decoded into [`Msg`], and everything else reduced to its id.

pub(crate) mod codec;
mod dialect;
pub(crate) mod json;
mod msg;
mod received;
pub mod scanner;
pub(crate) mod signing;
mod sys_comp;
pub mod transfer;
mod transfer_codec;

pub use codec::{decode, decode_as, encode, Header, Version};
pub(crate) use dialect::{
    autopilot_name, ids, mav_type, vehicle_type_name, AUTOPILOT_ARDUPILOT, AUTOPILOT_INVALID,
};
pub(crate) use msg::FixKind;
pub use msg::{Fix, LinkNodeStatus, Msg, RadioStatus};
pub use received::Frame;
#[cfg(test)]
pub(crate) use received::{test_frame, Stamps};
pub(crate) use received::{Stamp, StampClock, StampMeaning};
pub use scanner::{scan_datagram, scan_datagram_all, Kind, ScanStats, StreamScanner};
pub use sys_comp::SysComp;
pub use transfer::Transfer;
