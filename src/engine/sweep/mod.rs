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

pub(crate) mod driver;
pub(crate) mod plan;
pub(crate) mod step;
pub(crate) mod verdict;

pub(crate) use crate::engine::sweep_report::{MaxFrom, PlanKind, SweepConfig};
