//! What a C2 report is asked to measure against, already validated.

use std::time::Duration;

use super::failsafe::FailsafeModel;
use crate::engine::Nanos;

/// The availability floor the distance bands are held to without
/// `--min-availability`.
pub(crate) const DEFAULT_FLOOR_PCT: f64 = 99.0;
/// The availability rule unless told (`--up-within`): ArduPilot's and
/// PX4's GCS heartbeats come at 1 Hz, so two missed in a row.
pub(crate) const DEFAULT_UP_WITHIN: Duration = Duration::from_secs(2);
/// The distance bands' width unless told (`--distance-band`).
pub(crate) const DEFAULT_DISTANCE_BAND_M: f64 = 500.0;

#[derive(Debug, Clone, PartialEq)]
pub struct C2Config {
    /// The link is up while a frame from the vehicle came within this.
    pub(crate) up_within: Nanos,
    /// A round trip within this counts for continuity (at most the reply
    /// timeout: a later reply is a loss).
    pub(crate) continuity_within: Nanos,
    pub(crate) distance_band_m: f64,
    pub(crate) availability_floor_pct: f64,
    /// The models asked for; none: the preset of the vehicle's autopilot.
    pub(crate) failsafes: Vec<FailsafeModel>,
}
