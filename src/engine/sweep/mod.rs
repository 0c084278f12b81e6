//! Finding where a link breaks (`--sweep`), and latency under load
//! (`--load`): the same session as any echo run, with a schedule whose
//! rate changes at each step and figures per step.
//!
//! - [`plan`]: which rate each step offers (a 1-2-5 ramp, then bisection
//!   around the knee).
//! - [`step`]: one step's counts, RTT, bytes per second and radio figures.
//! - [`verdict`]: the knee, bufferbloat and the load's effect.
//! - [`driver`]: the session driver that runs the steps, and [`driver::run`].
//!
//! This file and the pure parts name nothing of the session, so the
//! session's events and summary can carry a sweep's figures.

pub mod driver;
pub mod plan;
pub mod step;
pub mod verdict;

use std::time::Duration;

use serde::Serialize;

use super::load::LoadSpec;

/// Where a sweep's highest rate came from.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(tag = "from", rename_all = "snake_case")]
pub enum MaxFrom {
    /// `--sweep-max`.
    Given,
    /// Twice what the link's baud rate carries: the safe default on a
    /// serial link (or a simulated radio).
    Baud { baud: u32, capacity_hz: f64 },
    /// The default for links without a baud rate.
    Default,
}

/// What the steps are.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum PlanKind {
    /// `--sweep`: ramp the rate from `first_hz` to `max_hz` and find the
    /// knee; stop ramping past `loss_limit` (a share, 0..=1).
    Sweep {
        first_hz: f64,
        max_hz: f64,
        max_from: MaxFrom,
        loss_limit: f64,
    },
    /// `--load` alone: one step at `rate_hz` without the load, one with.
    Load { rate_hz: f64 },
}

/// A run in steps, validated.
#[derive(Debug, Clone, PartialEq)]
pub struct SweepConfig {
    pub plan: PlanKind,
    /// How long each step sends.
    pub step: Duration,
    /// Background load, on in every step but the unloaded baseline.
    pub load: Vec<LoadSpec>,
    /// What the load puts on the wire, in this session's MAVLink version
    /// and signing.
    pub load_bytes_per_s: f64,
}
