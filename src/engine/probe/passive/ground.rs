//! Which sources are the recording ground station's own frames: the
//! passive driver's (a log's) and the C2 report's (any run's).

use crate::frame::{mav_type, Frame, Msg, SysComp};

/// The ground station's own ids in a log, by evidence: a HEARTBEAT of
/// type GCS, and every component of a system so identified
/// (QGroundControl sends as 255/190 and 255/0). MAVProxy's link 3 (what
/// it sent) is decided with the links, at the end.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct GroundIds {
    /// One bit per system id.
    systems: [u64; 4],
}

impl GroundIds {
    /// Whether `frame` is the ground station's, learning from it. (A
    /// frame on MAVProxy's link 3 is not evidence yet: the stamps' low
    /// bits are links only if the log shows it, at its end.)
    pub(crate) fn sees(&mut self, frame: &Frame) -> bool {
        let gcs_heartbeat = matches!(
            frame.msg,
            Msg::Heartbeat { mav_type, .. } if mav_type == mav_type::GCS
        );
        if gcs_heartbeat {
            let s = frame.source.sysid;
            self.systems[usize::from(s / 64)] |= 1 << (s % 64);
        }
        self.sees_id(frame.source)
    }

    /// Whether `id` is known as the ground station's.
    pub(crate) fn sees_id(&self, id: SysComp) -> bool {
        let s = id.sysid;
        self.systems[usize::from(s / 64)] & (1 << (s % 64)) != 0
    }
}
