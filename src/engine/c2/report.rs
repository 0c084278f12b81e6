//! The C2 link report's figures, as every format reads them: the JSON
//! `c2_report` line serialises this whole (after its `type` and `link`).

use serde::Serialize;

/// What the report measured the link against, stated in it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub(crate) struct C2Rule {
    /// The link is up while a frame from the vehicle came within this.
    pub(crate) up_within_s: f64,
    /// A round trip completed within this counts for continuity.
    pub(crate) continuity_within_s: f64,
    /// The width of the distance bands, metres.
    pub(crate) distance_band_m: f64,
    /// The availability the distance bands are held to (`--min-availability`,
    /// else 99 %).
    pub(crate) availability_floor_pct: f64,
}

/// Round trips completed within the continuity time, of those decided.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub(crate) struct Continuity {
    /// Answered within `continuity_within_s`.
    pub(crate) within: u64,
    /// Answered, late or not, plus those never answered.
    pub(crate) transactions: u64,
    pub(crate) pct: f64,
    /// Where the round trips came from: `probes` (ours), `log` (requests
    /// and replies recorded in a log), `commands`.
    pub(crate) from: &'static str,
}

/// p50/p99/p99.9 of one delay, ms.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub(crate) struct Percentiles {
    pub(crate) count: u64,
    pub(crate) p50_ms: f64,
    pub(crate) p99_ms: f64,
    pub(crate) p999_ms: f64,
    pub(crate) max_ms: f64,
}

/// One direction's delay above its least, where the responder's stamps
/// split round trips (p50/p99/max only: the split keeps no p99.9).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub(crate) struct OneWay {
    pub(crate) p50_ms: f64,
    pub(crate) p99_ms: f64,
    pub(crate) max_ms: f64,
}

#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub(crate) struct Latency {
    pub(crate) round_trip: Option<Percentiles>,
    /// Queueing above the least delay each way: the round trip's growth
    /// split by the responder's own stamps (TIMESYNC, PING).
    pub(crate) uplink: Option<OneWay>,
    pub(crate) downlink: Option<OneWay>,
    /// `round_trip_split`, or `frame_age`: the vehicle's frames' age above
    /// their quickest by its own clock stamps (how old the telemetry is),
    /// where no round trip was split.
    pub(crate) downlink_from: Option<&'static str>,
}

#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub(crate) struct DirectionLoss {
    /// Of the vehicle's frames, by their sequence numbers.
    pub(crate) downlink_pct: Option<f64>,
    /// The vehicle's own LINK_NODE_STATUS count where it sends one, else
    /// from the round trip's loss and the downlink's (the direction split).
    pub(crate) uplink_pct: Option<f64>,
    /// `link_node_status` or `direction_split`.
    pub(crate) uplink_from: Option<&'static str>,
    pub(crate) round_trip_pct: Option<f64>,
}

/// Outages of one duration band.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub(crate) struct Band {
    /// `<1s`, `1-3s`, `3-10s`, `10-30s`, `>30s`.
    pub(crate) band: &'static str,
    pub(crate) count: u64,
    pub(crate) total_s: f64,
}

/// One outage: the link down by the rule, `start_s` (since the run or
/// log began) for `duration_s`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub(crate) struct Outage {
    pub(crate) start_s: f64,
    pub(crate) duration_s: f64,
    /// The silence it came from: the gap between the vehicle's frames.
    pub(crate) silence_s: f64,
    /// How far the vehicle was when it began (its last position), metres.
    pub(crate) distance_m: Option<f64>,
    /// Still down when the run ended.
    pub(crate) open: bool,
    /// When it began on the log's clock (a log) or the wall clock (a
    /// live run), to the second.
    pub(crate) at_utc: Option<String>,
}

#[derive(Debug, Clone, PartialEq, Serialize)]
pub(crate) struct Outages {
    pub(crate) count: u64,
    pub(crate) total_s: f64,
    pub(crate) bands: Vec<Band>,
    /// The longest, longest first.
    pub(crate) longest: Vec<Outage>,
}

/// The link's down time over the run, in equal bins from its start.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub(crate) struct Timeline {
    pub(crate) bin_s: f64,
    pub(crate) down_s: Vec<f64>,
}

/// The time spent in one distance band and how much of it the link was down.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub(crate) struct DistanceBand {
    pub(crate) from_m: f64,
    pub(crate) to_m: f64,
    pub(crate) observed_s: f64,
    pub(crate) down_s: f64,
    pub(crate) availability_pct: f64,
    /// Outages that began in the band.
    pub(crate) outages: u64,
}

/// A failsafe trip: the timeout passed with no message delivered.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub(crate) struct Trip {
    /// When it tripped, s since the start.
    pub(crate) at_s: f64,
    /// Until the next message delivered (or the end: `open`).
    pub(crate) lasted_s: f64,
    pub(crate) open: bool,
    /// Also past the long timeout (ArduPlane's FS_LONG_TIMEOUT).
    pub(crate) long: bool,
}

/// One failsafe model played against the link.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub(crate) struct FailsafeReplay {
    /// `ardupilot-copter`, `ardupilot-plane`, `ardupilot-rover`, `px4`, `custom`.
    pub(crate) model: String,
    /// The autopilot's parameter and its value, e.g. `FS_GCS_TIMEOUT=5s`.
    pub(crate) setting: String,
    /// `up`: the vehicle checks the ground station's messages;
    /// `down`: the ground station checks the vehicle's.
    pub(crate) direction: &'static str,
    pub(crate) message: &'static str,
    pub(crate) rate_hz: f64,
    pub(crate) timeout_s: f64,
    pub(crate) long_timeout_s: Option<f64>,
    /// What the deliveries are: `received` (the vehicle's frames as they
    /// came), `probes` (the requests the vehicle answered), `downlink`
    /// (the ground station's messages, taken as delivered while the
    /// downlink was up: inferred).
    pub(crate) basis: &'static str,
    /// True when deliveries were inferred rather than seen.
    pub(crate) inferred: bool,
    /// Messages played, and of them delivered.
    pub(crate) messages: u64,
    pub(crate) delivered: u64,
    pub(crate) trips: u64,
    pub(crate) long_trips: u64,
    /// The first trips, in order.
    pub(crate) trip_list: Vec<Trip>,
    /// The longest wait between deliveries that did not trip, and its
    /// margin to the timeout: how close the link came.
    pub(crate) closest_wait_s: Option<f64>,
    pub(crate) closest_margin_s: Option<f64>,
    pub(crate) closest_at_s: Option<f64>,
    /// Trips expected over the run had the measured loss of this
    /// message's direction struck each message alone (independently):
    /// rate × duration × (1 − p) × p^k, k messages a timeout.
    pub(crate) expected_if_independent: Option<f64>,
}

/// The C2 link report of one link's run.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub(crate) struct C2Report {
    pub(crate) rule: C2Rule,
    /// The start on the log's clock (a log) or the wall clock (a live run).
    pub(crate) started_utc: Option<String>,
    /// From the run's (or log's) start to its end, s.
    pub(crate) duration_s: f64,
    /// Of it, the link down by the rule.
    pub(crate) down_s: f64,
    /// `None` before the vehicle was ever heard.
    pub(crate) availability_pct: Option<f64>,
    /// Frames from the vehicle counted.
    pub(crate) frames: u64,
    pub(crate) continuity: Option<Continuity>,
    pub(crate) latency: Latency,
    pub(crate) loss: DirectionLoss,
    pub(crate) outages: Outages,
    /// When it was down.
    pub(crate) timeline: Timeline,
    /// Where the vehicle's positions were known.
    pub(crate) distance: Vec<DistanceBand>,
    /// The nearest band whose availability fell under the floor.
    pub(crate) availability_under_floor_from_m: Option<f64>,
    pub(crate) failsafes: Vec<FailsafeReplay>,
}

impl C2Report {
    /// Puts the run's time 0 at `origin` (a log's first record, a live
    /// run's wall clock): when it started and each listed outage began.
    pub(crate) fn date(&mut self, origin: std::time::SystemTime) {
        let at = |s: f64| origin + std::time::Duration::from_secs_f64(s.max(0.0));
        self.started_utc = Some(humantime::format_rfc3339_micros(origin).to_string());
        for o in &mut self.outages.longest {
            o.at_utc = Some(humantime::format_rfc3339_seconds(at(o.start_s)).to_string());
        }
    }
}

impl crate::engine::kind::KindValue for C2Report {
    fn serialized(&self) -> Option<&dyn erased_serde::Serialize> {
        Some(self)
    }
}
