//! The dialect's numbers and names mavping uses: message ids, MAV_TYPE
//! and MAV_AUTOPILOT values, and their human names; constants the
//! codec, the probes and the reports share.

use super::codec;

/// MAVLink message ids mavping names.
pub(crate) mod ids {
    pub(crate) const HEARTBEAT: u32 = 0;
    pub(crate) const LINK_NODE_STATUS: u32 = 8;
    pub(crate) const GPS_RAW_INT: u32 = 24;
    pub(crate) const GLOBAL_POSITION_INT: u32 = 33;
    pub(crate) const PING: u32 = 4;
    pub(crate) const COMMAND_LONG: u32 = 76;
    pub(crate) const COMMAND_ACK: u32 = 77;
    pub(crate) const RADIO_STATUS: u32 = 109;
    /// RADIO_STATUS's forerunner (ardupilotmega), the same fields: SiK
    /// before 2016 and openLRSng send it.
    pub(crate) const RADIO: u32 = 166;
    pub(crate) const TIMESYNC: u32 = 111;
    pub(crate) const HOME_POSITION: u32 = 242;
    pub(crate) const PARAM_REQUEST_READ: u32 = 20;
    pub(crate) const PARAM_REQUEST_LIST: u32 = 21;
    pub(crate) const PARAM_VALUE: u32 = 22;
    pub(crate) const MISSION_ITEM: u32 = 39;
    pub(crate) const MISSION_REQUEST: u32 = 40;
    pub(crate) const MISSION_REQUEST_LIST: u32 = 43;
    pub(crate) const MISSION_COUNT: u32 = 44;
    pub(crate) const MISSION_ACK: u32 = 47;
    pub(crate) const MISSION_REQUEST_INT: u32 = 51;
    pub(crate) const MISSION_ITEM_INT: u32 = 73;
    pub(crate) const FILE_TRANSFER_PROTOCOL: u32 = 110;
}

/// MAV_TYPE values mavping treats specially.
pub(crate) mod mav_type {
    pub(crate) const GCS: u8 = 6;
    pub(crate) const ONBOARD_CONTROLLER: u8 = 18;
}

/// MAV_AUTOPILOT_INVALID: what a GCS puts in its HEARTBEAT.
pub(crate) const AUTOPILOT_INVALID: u8 = 8;

/// MAV_AUTOPILOT_ARDUPILOTMEGA: every ArduPilot vehicle.
pub(crate) const AUTOPILOT_ARDUPILOT: u8 = 3;

/// Human name of a MAV_TYPE value ("quadrotor"), from the dialect.
pub(crate) fn vehicle_type_name(value: u8) -> String {
    codec::enum_name::<mavlink::dialects::ardupilotmega::MavType>(u32::from(value), "MAV_TYPE_")
}

/// Human name of a MAV_AUTOPILOT value ("px4", "ardupilotmega").
pub(crate) fn autopilot_name(value: u8) -> String {
    codec::enum_name::<mavlink::dialects::ardupilotmega::MavAutopilot>(
        u32::from(value),
        "MAV_AUTOPILOT_",
    )
}
