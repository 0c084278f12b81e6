//! Who is on the link: systems heard by their HEARTBEAT, for the summary
//! ("1/1: quadrotor, px4") and for the hint when a system never answers.

use std::collections::BTreeMap;

use serde::Serialize;

use super::Nanos;
use crate::frame::{self, SysComp};

#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Identity {
    pub mav_type: u8,
    pub autopilot: u8,
    pub vehicle: String,
    pub autopilot_name: String,
    #[serde(skip)]
    pub first_heard: Nanos,
}

impl Identity {
    /// GCS software, radios and other non-vehicles: they are not expected to
    /// answer probes, so they get no "never answered" hint.
    pub fn is_vehicle_like(&self) -> bool {
        self.mav_type != frame::mav_type::GCS && self.autopilot != frame::AUTOPILOT_INVALID
    }
}

/// Systems heard, bounded so a spoofing flood cannot grow memory.
#[derive(Default)]
pub struct Roster {
    systems: BTreeMap<SysComp, Identity>,
}

const MAX_SYSTEMS: usize = 1024;

impl Roster {
    /// Records a HEARTBEAT; returns true the first time a system is heard.
    pub fn heard(&mut self, source: SysComp, mav_type: u8, autopilot: u8, at: Nanos) -> bool {
        if self.systems.contains_key(&source) || self.systems.len() >= MAX_SYSTEMS {
            return false;
        }
        self.systems.insert(
            source,
            Identity {
                mav_type,
                autopilot,
                vehicle: frame::vehicle_type_name(mav_type),
                autopilot_name: frame::autopilot_name(autopilot),
                first_heard: at,
            },
        );
        true
    }

    pub fn get(&self, id: SysComp) -> Option<&Identity> {
        self.systems.get(&id)
    }

    pub fn iter(&self) -> impl Iterator<Item = (&SysComp, &Identity)> {
        self.systems.iter()
    }
}
