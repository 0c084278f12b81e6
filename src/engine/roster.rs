//! Who is on the link: every system heard, by its HEARTBEAT (what it is:
//! "1/1: quadrotor, px4") and by its traffic (how many frames, signed or
//! in MAVLink 1), for the summary and for the diagnosis when a system
//! never answers.

use std::collections::BTreeMap;

use serde::Serialize;

use super::Nanos;
use crate::frame::{self, SysComp, Version};

pub(crate) use crate::frame::AUTOPILOT_ARDUPILOT;

#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Identity {
    pub(crate) mav_type: u8,
    pub(crate) autopilot: u8,
    pub(crate) vehicle: String,
    pub(crate) autopilot_name: String,
    #[serde(skip)]
    pub(crate) first_heard: Nanos,
}

impl Identity {
    /// GCS software, radios and other non-vehicles: they are not expected to
    /// answer probes, so they get no "never answered" hint.
    pub(crate) fn is_vehicle_like(&self) -> bool {
        self.mav_type != frame::mav_type::GCS && self.autopilot != frame::AUTOPILOT_INVALID
    }

    pub(crate) fn is_ardupilot(&self) -> bool {
        self.autopilot == AUTOPILOT_ARDUPILOT
    }

    /// The autopilot as text reports say it: MAV_AUTOPILOT_INVALID is what
    /// ground stations, companion programs and `mavping respond` send to
    /// say they are none, not a fault ("gcs, no autopilot").
    pub(crate) fn autopilot_said(&self) -> &str {
        if self.autopilot == frame::AUTOPILOT_INVALID {
            "no autopilot"
        } else {
            &self.autopilot_name
        }
    }
}

/// One system's traffic.
#[derive(Debug, Clone, Default, PartialEq)]
pub(crate) struct Source {
    /// From its first HEARTBEAT.
    pub(crate) identity: Option<Identity>,
    /// Frames of every kind, of which signed and MAVLink 1.
    pub(crate) frames: u64,
    pub(crate) signed: u64,
    pub(crate) v1: u64,
    /// Its newest signature timestamp, with ours when it came.
    pub(crate) signature: Option<SignedClock>,
    /// The systems its targeted messages (COMMAND_ACK, PING and TIMESYNC
    /// answers, MISSION_*, FTP...) were addressed to, by sysid.
    pub(crate) addressed: BTreeMap<u8, Addressed>,
}

/// A source's newest signature timestamp and what we would have stamped
/// at the moment it came (10 µs units since 2015-01-01): a vehicle far
/// ahead refuses our frames as too old (MAVLink 2 signing).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct SignedClock {
    pub(crate) theirs: u64,
    pub(crate) ours: u64,
}

/// A source's frames addressed to one system: how many, and the first
/// few message ids among them.
#[derive(Debug, Clone, Default, PartialEq)]
pub(crate) struct Addressed {
    pub(crate) frames: u64,
    pub(crate) msgids: Vec<u32>,
}

/// Systems a source's addressees are kept for, and message ids each.
const MAX_ADDRESSEES: usize = 16;
const MAX_MSGIDS: usize = 4;

/// Systems heard, bounded so a spoofing flood cannot grow memory.
#[derive(Default)]
pub(crate) struct Roster {
    sources: BTreeMap<SysComp, Source>,
}

const MAX_SYSTEMS: usize = 1024;

impl Roster {
    fn source(&mut self, id: SysComp) -> Option<&mut Source> {
        if !self.sources.contains_key(&id) && self.sources.len() >= MAX_SYSTEMS {
            return None;
        }
        Some(self.sources.entry(id).or_default())
    }

    /// Counts one frame from `source`.
    pub(crate) fn frame(&mut self, source: SysComp, version: Version, signed: bool) {
        if let Some(s) = self.source(source) {
            s.frames += 1;
            s.signed += u64::from(signed);
            s.v1 += u64::from(version == Version::V1);
        }
    }

    /// Records a signature timestamp `theirs` from `source`, heard when
    /// our signing clock read `ours`.
    pub(crate) fn signature(&mut self, source: SysComp, theirs: u64, ours: u64) {
        if let Some(s) = self.source(source) {
            if s.signature.is_none_or(|c| theirs >= c.theirs) {
                s.signature = Some(SignedClock { theirs, ours });
            }
        }
    }

    /// Records a frame of message `msgid` from `source` addressed to
    /// system `to`.
    pub(crate) fn addressed(&mut self, source: SysComp, to: u8, msgid: u32) {
        let Some(s) = self.source(source) else {
            return;
        };
        if !s.addressed.contains_key(&to) && s.addressed.len() >= MAX_ADDRESSEES {
            return;
        }
        let a = s.addressed.entry(to).or_default();
        a.frames += 1;
        if a.msgids.len() < MAX_MSGIDS && !a.msgids.contains(&msgid) {
            a.msgids.push(msgid);
        }
    }

    /// Records a HEARTBEAT; returns true the first time a system is heard.
    pub(crate) fn heard(
        &mut self,
        source: SysComp,
        mav_type: u8,
        autopilot: u8,
        at: Nanos,
    ) -> bool {
        let Some(s) = self.source(source) else {
            return false;
        };
        if s.identity.is_some() {
            return false;
        }
        s.identity = Some(Identity {
            mav_type,
            autopilot,
            vehicle: frame::vehicle_type_name(mav_type),
            autopilot_name: frame::autopilot_name(autopilot),
            first_heard: at,
        });
        true
    }

    pub(crate) fn get(&self, id: SysComp) -> Option<&Identity> {
        self.sources.get(&id).and_then(|s| s.identity.as_ref())
    }

    /// Systems heard by their HEARTBEAT.
    pub(crate) fn iter(&self) -> impl Iterator<Item = (&SysComp, &Identity)> {
        self.sources
            .iter()
            .filter_map(|(id, s)| s.identity.as_ref().map(|i| (id, i)))
    }

    /// Every system heard, by HEARTBEAT or any other frame.
    pub(crate) fn sources(&self) -> impl Iterator<Item = (&SysComp, &Source)> {
        self.sources.iter()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn traffic_and_identity_per_system_bounded() {
        let mut r = Roster::default();
        let id = SysComp::new(8, 1);
        r.frame(id, Version::V2, true);
        r.frame(id, Version::V1, false);
        assert!(r.get(id).is_none());
        assert!(r.heard(id, 2, 3, 5));
        assert!(!r.heard(id, 2, 3, 6));
        let s = r.sources().next().unwrap().1;
        assert_eq!((s.frames, s.signed, s.v1), (2, 1, 1));
        assert!(s.identity.as_ref().unwrap().is_ardupilot());
        for i in 0..2000u16 {
            r.frame(
                SysComp::new((i % 255) as u8 + 1, (i / 255) as u8 + 2),
                Version::V2,
                false,
            );
        }
        assert_eq!(r.sources().count(), MAX_SYSTEMS);
    }

    #[test]
    fn newest_signature_and_addressees_kept_bounded() {
        let mut r = Roster::default();
        let id = SysComp::new(1, 1);
        r.signature(id, 500, 100);
        r.signature(id, 400, 130);
        r.signature(id, 600, 140);
        let s = &r.sources[&id];
        assert_eq!(
            s.signature,
            Some(SignedClock {
                theirs: 600,
                ours: 140
            })
        );
        for msgid in [77, 77, 111, 4, 44, 47] {
            r.addressed(id, 255, msgid);
        }
        for to in 1..=40 {
            r.addressed(id, to, 77);
        }
        let s = &r.sources[&id];
        assert_eq!(s.addressed[&255].frames, 6);
        assert_eq!(s.addressed[&255].msgids, [77, 111, 4, 44]);
        assert_eq!(s.addressed.len(), MAX_ADDRESSEES);
    }
}
