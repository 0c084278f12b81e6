//! What a run in steps (`--sweep`, `--load`) is and what it reports: its
//! validated config, each step's figures and the verdict over them. The
//! types alone, at the engine's level, so that the session's config and
//! what it tells the world name them without naming `sweep/`, which
//! builds and fills them (their methods live there).

use std::time::Duration;

use serde::{Serialize, Serializer};

use super::load::{LoadSpec, LoadSummary};
use crate::frame::SysComp;

/// Where a sweep's highest rate came from.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(tag = "from", rename_all = "snake_case")]
pub(crate) enum MaxFrom {
    /// `--sweep-max`.
    Given,
    /// Twice what the link's baud rate carries: the safe default on a
    /// serial link (or a simulated radio).
    Baud { baud: u32, capacity_hz: f64 },
    /// The default for links without a baud rate.
    Default,
}

/// What the steps are.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub(crate) enum PlanKind {
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

/// A run in steps, validated. Serialised as the JSON `start` line's
/// `sweep`, in this order.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SweepConfig {
    #[serde(flatten)]
    pub(crate) plan: PlanKind,
    /// How long each step sends.
    #[serde(rename = "step_s", serialize_with = "seconds")]
    pub(crate) step: Duration,
    /// Background load, on in every step but the unloaded baseline.
    #[serde(serialize_with = "streams")]
    pub(crate) load: Vec<LoadSpec>,
    /// What the load puts on the wire, in this session's MAVLink version
    /// and signing.
    pub(crate) load_bytes_per_s: f64,
}

impl crate::engine::kind::KindValue for SweepConfig {}

fn seconds<S: Serializer>(d: &Duration, s: S) -> Result<S::Ok, S::Error> {
    s.serialize_f64(d.as_secs_f64())
}

/// Each `--load` stream as given: its message by name, and its rate.
fn streams<S: Serializer>(load: &[LoadSpec], s: S) -> Result<S::Ok, S::Error> {
    #[derive(Serialize)]
    struct Stream {
        message: &'static str,
        rate: f64,
    }
    s.collect_seq(load.iter().map(|l| Stream {
        message: l.kind.name(),
        rate: l.rate,
    }))
}

/// What a step is for.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub(crate) enum Phase {
    /// With `--load`: the first rate without the load, for comparison.
    Baseline,
    /// Climbing the 1-2-5 series.
    Ramp,
    /// Bisecting around the knee.
    Refine,
    /// `--load` without a sweep: the same rate as the baseline, loaded.
    Loaded,
}

/// A step's RTT figures over every responder's in-time replies, in µs
/// (the step names the unit once: `rtt_us`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub(crate) struct StepRtt {
    #[serde(rename = "p50")]
    pub(crate) p50_us: f64,
    #[serde(rename = "p99")]
    pub(crate) p99_us: f64,
    #[serde(rename = "max")]
    pub(crate) max_us: f64,
}

/// The radio's own figures during a step (the first radio heard).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub(crate) struct StepRadio {
    pub(crate) id: SysComp,
    pub(crate) reports: u64,
    /// Least and mean % of its transmit buffer free.
    pub(crate) txbuf_min: Option<u8>,
    pub(crate) txbuf_mean: Option<f64>,
    pub(crate) rssi_mean: Option<f64>,
    pub(crate) remrssi_mean: Option<f64>,
    /// What its since-boot receive-error counter grew by during the step.
    pub(crate) rxerrors_delta: u64,
}

/// One step as reported; serialised as the JSON `step` line's figures
/// and the summary's steps, in this order.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub(crate) struct StepFigures {
    /// 1 for the first step.
    pub(crate) index: u32,
    pub(crate) phase: Phase,
    /// The `--load` streams were on.
    pub(crate) load: bool,
    pub(crate) offered_hz: f64,
    /// Requests sent over the time from the first to the last.
    pub(crate) achieved_hz: f64,
    /// When its first request went out, in seconds since the run started.
    pub(crate) start_s: f64,
    /// From its first request to its last.
    pub(crate) duration_s: f64,
    pub(crate) requests: u64,
    /// In-time replies, summed over responders.
    pub(crate) received: u64,
    pub(crate) lost: u64,
    pub(crate) late: u64,
    /// lost / (received + lost).
    pub(crate) loss_ratio: f64,
    #[serde(rename = "rtt_us")]
    pub(crate) rtt: Option<StepRtt>,
    /// Bytes per second we sent (probes, load, HEARTBEAT) while the step
    /// sent, and received (every valid frame) from its start until it
    /// ended, over the time it sent or until its last reply came, whichever
    /// is longer (a queue delivers after the sending ends): the step's own
    /// traffic each way.
    pub(crate) tx_bytes_per_s: f64,
    pub(crate) rx_bytes_per_s: f64,
    pub(crate) radio: Option<StepRadio>,
    /// False when the run ended (Ctrl-C, deadline, link failure) before the
    /// step did: it is shown, never judged.
    pub(crate) complete: bool,
    /// The knee test (sweep steps only): loss under 1 % and p99 under
    /// twice the first sweep step's or less than 30 ms over it.
    pub(crate) passed: Option<bool>,
    /// The rate of the step before, run again because that one failed the
    /// knee test on latency alone: one burst behind a scheduling hiccup
    /// queues as a link does, so a rate fails on latency only twice in a
    /// row, and this step decides.
    pub(crate) retry: bool,
}

impl crate::engine::kind::KindValue for StepFigures {}

/// The highest rate the link carried cleanly: the step with the highest
/// offered rate that passed the knee test.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub(crate) struct Knee {
    pub(crate) step: u32,
    pub(crate) rate_hz: f64,
    pub(crate) achieved_hz: f64,
    /// Bytes per second on the wire, both ways and each way.
    pub(crate) bytes_per_s: f64,
    pub(crate) tx_bytes_per_s: f64,
    pub(crate) rx_bytes_per_s: f64,
    pub(crate) p99_us: f64,
    pub(crate) loss_ratio: f64,
    /// The lowest rate above it that failed; none when every rate tried
    /// above passed or none was tried (then the capacity is higher still).
    pub(crate) failed_above_hz: Option<f64>,
}

/// The latency a queue adds under load, on the scale bufferbloat tests
/// grade it (Waveform's, DSLReports'): A+ under 5 ms, A under 30, B under
/// 60, C under 200, D under 400, F beyond.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Serialize)]
pub(crate) enum Grade {
    #[serde(rename = "A+")]
    APlus,
    A,
    B,
    C,
    D,
    F,
}

/// Whether the link queues before it drops: the highest p99 of a step
/// that still lost under 1 %, against the first sweep step's.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub(crate) struct Queueing {
    /// The latency added under load graded C or worse (60 ms or more).
    pub(crate) bufferbloat: bool,
    /// `added_us` on the bufferbloat tests' scale.
    pub(crate) grade: Grade,
    pub(crate) reference_p99_us: f64,
    pub(crate) worst_p99_us: f64,
    pub(crate) worst_at_hz: f64,
    /// `worst_p99_us - reference_p99_us`: the delay the queue added
    /// before the link dropped anything.
    pub(crate) added_us: f64,
    /// The lowest rate at which a step lost 1 % or more, if any did.
    pub(crate) lost_at_hz: Option<f64>,
}

/// The RTT with the `--load` streams on against without, at one rate.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub(crate) struct LoadEffect {
    pub(crate) rate_hz: f64,
    pub(crate) unloaded_p50_us: f64,
    pub(crate) unloaded_p99_us: f64,
    pub(crate) loaded_p50_us: f64,
    pub(crate) loaded_p99_us: f64,
    pub(crate) p99_rise_us: f64,
    pub(crate) p99_ratio: f64,
}

/// Why the steps ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub(crate) enum SweepEnd {
    /// Every step planned was run.
    Planned,
    /// A ramp step lost more than the limit; the steps after it refined
    /// below it.
    LossLimit,
    /// Nothing answered a step: the sweep went no further.
    NoReplies,
    Interrupted,
    Deadline,
    LinkFailed,
}

/// A sweep's (or a `--load` run's) steps and what they say.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub(crate) struct SweepSummary {
    /// `sweep`, or `load` for `--load` without `--sweep`.
    pub(crate) kind: &'static str,
    pub(crate) steps: Vec<StepFigures>,
    /// The first sweep step's p99, which the knee test compares against.
    pub(crate) reference_p99_us: Option<f64>,
    pub(crate) knee: Option<Knee>,
    pub(crate) queueing: Option<Queueing>,
    pub(crate) load: Vec<LoadSummary>,
    pub(crate) load_effect: Option<LoadEffect>,
    pub(crate) ending: SweepEnd,
}
