//! The command-and-control (C2) link report: availability, continuity,
//! latency, loss each way, outages by duration and by distance, and what
//! autopilots' link failsafes would have done on the same deliveries.
//! Pure and synchronous, time passed in, constant memory over a run or
//! a log of any length.

mod config;
mod failsafe;
mod outages;
mod position;
mod report;
mod summary_figures;
mod timeline;
mod tracker;
mod uplink;
mod watching;

pub(crate) use config::C2Config;
pub(crate) use config::{DEFAULT_DISTANCE_BAND_M, DEFAULT_FLOOR_PCT, DEFAULT_UP_WITHIN};
pub(crate) use failsafe::FailsafeModel;
pub(crate) use tracker::C2Tracker;
pub(crate) use watching::Watching;

pub(crate) use report::{
    Band, C2Report, DistanceBand, FailsafeReplay, Latency, OneWay, Outage, Outages, Trip,
};
// The report's other parts, which only the formats' fixtures build.
#[cfg(test)]
pub(crate) use report::{C2Rule, Continuity, DirectionLoss, Percentiles, Timeline};
