//! A system/component address on a MAVLink network ([`SysComp`]), and
//! the ids mavping sends as: the one type every module names, apart from
//! the messages.

/// A system/component address on a MAVLink network.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, serde::Serialize)]
pub struct SysComp {
    pub sysid: u8,
    pub compid: u8,
}

impl SysComp {
    /// The ids mavping sends as unless told otherwise, in the CLI and in
    /// `mavping serve` alike. Not 255/190: that is QGroundControl's and
    /// Mission Planner's, whose frames MAVSDK-based stacks drop and whose
    /// loss ArduPilot's GCS failsafe watches.
    pub(crate) const OURS: SysComp = SysComp::new(250, 190);

    pub const fn new(sysid: u8, compid: u8) -> Self {
        SysComp { sysid, compid }
    }
}

impl std::fmt::Display for SysComp {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}/{}", self.sysid, self.compid)
    }
}
