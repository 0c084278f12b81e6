//! What a session needs to know, already validated ([`SessionConfig`]),
//! and the command probe's request and retry policy ([`CommandSpec`]):
//! what the configuration hands the engine, apart from the engine's
//! parts that read it.

use std::time::Duration;

use super::{capacity, matcher, radio, sweep_report};
use crate::frame::signing::SigningConfig;
use crate::frame::{SysComp, Version};

/// What a session needs to know, already validated.
#[derive(Debug, Clone, PartialEq)]
pub struct SessionConfig {
    pub link_name: String,
    pub ours: SysComp,
    pub interval: Duration,
    pub count: Option<u64>,
    pub deadline: Option<Duration>,
    /// On a link that waits for peers to send first (udpin, tcpin): end
    /// the run when none is heard within this (`--wait`, or what `-c`
    /// would take plus the timeout).
    pub wait: Option<Duration>,
    /// An interim summary this often (`-Q`).
    pub interim: Option<Duration>,
    pub timeout: Duration,
    pub version: Version,
    /// Send our own HEARTBEAT at 1 Hz (MAVSDK and routers need it).
    pub heartbeat: bool,
    /// Answer the vehicle's TIMESYNC and PING requests, as a ground
    /// station does (`--no-answer`: not).
    pub answer: bool,
    /// Request slots in the matcher's ring.
    pub capacity: usize,
    /// Where each responder's accounting window opens: at its first answer
    /// (a streaming run), or at the run's first request (a `/probe`, whose
    /// target is named; the ring then holds every request of the run).
    pub window: matcher::Window,
    pub first_seq: u32,
    /// Wait for sends precisely (sub-millisecond) rather than on tokio's
    /// 1 ms timer. Off for the simulated link, whose paused virtual clock
    /// only moves while the runtime is idle, and where sessions share a
    /// thread.
    pub precise_pacing: bool,
    /// MAVLink 2 signing (`--signing-key`): sign what we send, check what
    /// we receive.
    pub signing: Option<SigningConfig>,
    /// `--sweep` or `--load`: the run goes in steps (echo probes only).
    pub sweep: Option<sweep_report::SweepConfig>,
    /// What the baud rate allows a serial (or simulated radio) link: set
    /// once by the configuration, reported by the echo probes' summary
    /// whatever the front end.
    pub wire: Option<capacity::WireBudget>,
    /// `--radio-type`: how radios' RADIO_STATUS figures are read.
    pub radio_type: radio::RadioType,
    /// `--report c2`: the C2 link report's settings.
    pub c2: Option<super::c2::C2Config>,
}

/// The command probe's request and retry policy.
#[derive(Debug, Clone, PartialEq)]
pub struct CommandSpec {
    pub(crate) target: SysComp,
    pub(crate) command: u16,
    pub(crate) params: [f32; 7],
    pub(crate) retry_interval: Duration,
    /// Re-sends after the first transmission.
    pub(crate) retries: u8,
}

impl crate::engine::kind::KindValue for CommandSpec {}
