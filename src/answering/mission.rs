//! The mission `mavping respond` and `sim:` serve: `count` items laid out
//! as ArduPilot keeps a mission (item 0 is home, then a takeoff, then
//! waypoints on a circle around home), each following from its sequence
//! number alone.

use crate::frame::transfer::{MissionItem, Target};

/// The most items served.
pub(crate) const MAX_ITEMS: u16 = 10_000;

/// MAV_CMD_NAV_WAYPOINT and MAV_CMD_NAV_TAKEOFF.
const NAV_WAYPOINT: u16 = 16;
const NAV_TAKEOFF: u16 = 22;
/// MAV_FRAME_GLOBAL (home, above sea level) and
/// MAV_FRAME_GLOBAL_RELATIVE_ALT (the rest, above home), as ArduPilot
/// sends them in both MISSION_ITEM and MISSION_ITEM_INT.
const FRAME_GLOBAL: u8 = 0;
const FRAME_RELATIVE_ALT: u8 = 3;
/// Home: ArduPilot SITL's default location (CMAC), in degrees × 10^7.
const HOME: (i32, i32) = (-353_632_621, 1_491_652_374);
const HOME_ALT: f32 = 584.0;
/// The waypoints' circle: about 110 m of latitude.
const RADIUS_E7: f64 = 10_000.0;

/// MAV_MISSION_TYPE_MISSION: the only list with items; the fence and the
/// rally points are served empty.
pub(crate) const TYPE_MISSION: u8 = 0;

/// MAV_MISSION_RESULT values we send.
pub(crate) mod result {
    pub(crate) const DENIED: u8 = 14;
    pub(crate) const INVALID_SEQUENCE: u8 = 13;
}

/// `count` read-only mission items.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Mission {
    pub(crate) count: u16,
}

impl Mission {
    /// Items of the list `mission_type`.
    pub(crate) fn count_of(&self, mission_type: u8) -> u16 {
        if mission_type == TYPE_MISSION {
            self.count
        } else {
            0
        }
    }

    /// Item `seq` of the list `mission_type` for `target`, as
    /// MISSION_ITEM_INT (`int`) or MISSION_ITEM; `None` past the end.
    pub(crate) fn item(
        &self,
        seq: u16,
        mission_type: u8,
        int: bool,
        target: Target,
    ) -> Option<MissionItem> {
        if seq >= self.count_of(mission_type) {
            return None;
        }
        let (command, frame, alt) = match seq {
            0 => (NAV_WAYPOINT, FRAME_GLOBAL, HOME_ALT),
            1 => (NAV_TAKEOFF, FRAME_RELATIVE_ALT, 30.0),
            _ => (NAV_WAYPOINT, FRAME_RELATIVE_ALT, 50.0),
        };
        let (lat, lon) = if seq < 2 {
            HOME
        } else {
            let legs = f64::from(self.count - 2).max(1.0);
            let angle = f64::from(seq - 2) / legs * std::f64::consts::TAU;
            (
                HOME.0 + (RADIUS_E7 * angle.cos()).round() as i32,
                HOME.1 + (RADIUS_E7 * angle.sin()).round() as i32,
            )
        };
        Some(MissionItem {
            target,
            seq,
            mission_type,
            int,
            command,
            frame,
            lat,
            lon,
            alt,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn home_takeoff_then_a_circle() {
        let m = Mission { count: 5 };
        let to = Target {
            system: 255,
            component: 190,
        };
        let home = m.item(0, TYPE_MISSION, true, to).unwrap();
        assert_eq!(
            (home.command, home.frame, home.lat, home.alt),
            (16, 0, HOME.0, 584.0)
        );
        assert_eq!(m.item(1, TYPE_MISSION, true, to).unwrap().command, 22);
        let first = m.item(2, TYPE_MISSION, false, to).unwrap();
        assert_eq!((first.lat - HOME.0, first.lon - HOME.1), (10_000, 0));
        assert!(!first.int && first.target == to);
        // Three waypoints a third of the circle apart.
        let third = m.item(3, TYPE_MISSION, true, to).unwrap();
        assert_eq!((third.lat - HOME.0, third.lon - HOME.1), (-5_000, 8_660));
        assert_eq!(m.item(5, TYPE_MISSION, true, to), None);
        // The fence and rally lists are empty.
        assert_eq!((m.count_of(1), m.count_of(2)), (0, 0));
        assert_eq!(m.item(0, 1, true, to), None);
    }
}
