//! `sim:` — an in-process link with simulated responders and faults.
//!
//! Requests pass through the real encoder and scanner, are answered by the
//! same responder logic as `mavping respond`, and come back after a seeded
//! random delay, maybe dropped, duplicated or held back (reordered). With
//! `clock=virtual` the run uses tokio's paused clock: output is identical on
//! every run and a long simulation takes no wall time.
//!
//! Responders number every frame they send (HEARTBEAT, `stream=` telemetry,
//! replies) with one packet sequence, in the order they send them, as an
//! autopilot does: a reply is numbered when the responder has the request,
//! one leg after mavping sent it. The per-direction faults (`loss_down=`,
//! `dup_down=`, `reorder_down=`, `loss_up=`, `dup_up=`) act on numbered
//! frames (a request heard twice is answered twice), and
//! [`DownTruth`](truth::DownTruth) and [`UpTruth`](truth::UpTruth) count
//! what they did, for a passive loss count held against them.
//!
//! The model is in one file per concern: the [`responder`]s, the
//! [`faults`], the [`clock`]s, the [`wire`] (or the [`radio`] pair), what
//! the responders send ([`outgoing`]), what is on its way to mavping
//! ([`deliveries`]), one request's [`exchange`], the [`transfers`] they
//! serve (parameters, mission, a file), the near radio's
//! [`radio_status`], the [`paths`] of a vehicle heard on several, and the
//! ground [`truth`]; [`link`] holds them together
//! as a [`Transport`](crate::transport::Transport).

mod clock;
mod deliveries;
mod exchange;
mod faults;
mod link;
mod outgoing;
mod params;
mod paths;
pub(crate) mod radio;
mod radio_status;
mod responder;
mod transfers;
mod truth;
mod wire;

pub use link::SimLink;
pub use params::{SimParams, DEFAULT_BUFFER_BYTES, SIM_KEYS};
pub use truth::{QueueTruth, SimTruth};
