//! The command-and-control (C2) link report: availability, continuity,
//! latency, loss each way, outages by duration and by distance, and what
//! autopilots' link failsafes would have done on the same deliveries.
//! Pure and synchronous, time passed in, constant memory over a run or
//! a log of any length.

mod report;

pub(crate) use report::{
    Band, C2Report, C2Rule, Continuity, DirectionLoss, DistanceBand, FailsafeReplay, Latency,
    OneWay, Outage, Outages, Percentiles, Trip,
};
