//! The round trip split into its two directions ([`RoundTripSplit`]), and
//! the absolute one-way age where the clock offset is known with bounds
//! ([`absolute_age`]).
//!
//! In an exchange we send at `t0`, the responder stamps its reply with
//! its clock `x` (TIMESYNC's `tc1`; a signed PING reply's signature; a
//! PING reply's `time_usec` is our own echoed and is no use), and the
//! reply arrives at `t3`. `x − t0` is the uplink's delay plus the clocks'
//! offset, `t3 − x` the downlink's minus it. Each above its own floor is
//! that direction's queue. The two floors' slopes are one clock pair's
//! drift with opposite signs, so they are fitted together: of the common
//! slopes the one whose two floors sit highest (the narrowest band for
//! the offset), so a queue growing in one direction through the whole
//! run cannot pass for drift while the other direction holds still.

use std::collections::VecDeque;

use hdrhistogram::Histogram;

use super::super::clock_offset::ClockSummary;
use super::super::Nanos;
use super::envelope::{lower_hull, Envelope, Point, MAX_DRIFT_PPM, MIN_DRIFT_SPAN_NS};

/// Exchanges held back until later ones have refined the floors.
const LOOKAHEAD: usize = 64;
/// Slopes whose two floors sit within this of the highest (ns) fit the
/// exchanges equally well.
const NEAR_TOP_NS: f64 = 1e6;

/// One exchange, relative to each direction's envelope.
#[derive(Debug, Clone, Copy)]
struct Exchange {
    up: Point,
    down: Point,
}

/// Each direction's delay above its floor, ns, for one exchange.
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize)]
pub(crate) struct SplitNow {
    pub(crate) round_trip_ms: f64,
    pub(crate) uplink_ms: f64,
    pub(crate) downlink_ms: f64,
}

/// What the split read the responder's side from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub(crate) enum SplitBy {
    /// Its clock in its replies (TIMESYNC's `tc1`, a signature).
    #[default]
    ReplyClock,
    /// Its telemetry's age at each reply (replies without its clock: PING).
    TelemetryAge,
}

/// The split's figures over the run: each direction's queue above its
/// floor, p50/p99/max (ms), and the drift the floors share.
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize)]
pub(crate) struct SplitSummary {
    pub(crate) by: SplitBy,
    pub(crate) exchanges: u64,
    pub(crate) uplink_p50_ms: f64,
    pub(crate) uplink_p99_ms: f64,
    pub(crate) uplink_max_ms: f64,
    pub(crate) downlink_p50_ms: f64,
    pub(crate) downlink_p99_ms: f64,
    pub(crate) downlink_max_ms: f64,
    pub(crate) drift_ppm: Option<f64>,
}

/// The running split of one responder's exchanges: see the module's
/// documentation. Memory is constant: two envelopes, a few held exchanges
/// and the queue's samples as figures.
#[derive(Debug, Clone, Default)]
pub(crate) struct RoundTripSplit {
    envelopes: Option<(Envelope, Envelope)>,
    ring: VecDeque<Exchange>,
    up_hist: Quantiles,
    down_hist: Quantiles,
    exchanges: u64,
    now: Option<SplitNow>,
}

/// Queue delays as a histogram (µs, three significant digits, to an
/// hour), as [`super::one_way`] keeps ages: enough for p50/p99 of a
/// queue; the max is exact.
#[derive(Debug, Clone)]
struct Quantiles {
    hist: Histogram<u32>,
    max_ms: f64,
}

impl Default for Quantiles {
    fn default() -> Self {
        Quantiles {
            hist: Histogram::new_with_bounds(1, MAX_US, 3).expect("valid histogram bounds"),
            max_ms: 0.0,
        }
    }
}

/// The longest queue delay the histogram tells apart: an hour.
const MAX_US: u64 = 3_600_000_000;

impl Quantiles {
    fn record(&mut self, ms: f64) {
        let us = ((ms.max(0.0) * 1e3).round() as u64).clamp(1, MAX_US);
        self.hist.saturating_record(us);
        self.max_ms = self.max_ms.max(ms);
    }

    fn quantile(&self, q: f64) -> f64 {
        (self.hist.value_at_quantile(q) as f64 / 1e3).min(self.max_ms)
    }
}

/// The common drift of the two floors: of the candidate slopes (each
/// floor's own hull edges), the one whose two floors are highest in sum.
/// Returns (slope, uplink intercept, downlink intercept) in each
/// envelope's frame.
fn joint_fit(up: &Envelope, down: &Envelope) -> (f64, f64, f64) {
    let up_hull = lower_hull(&up.points());
    let down_hull = lower_hull(&down.points());
    let floor = |hull: &[Point], b: f64| {
        hull.iter()
            .map(|p| p.d as f64 - b * p.t as f64)
            .fold(f64::INFINITY, f64::min)
    };
    let span = up.span().min(down.span());
    let limit = MAX_DRIFT_PPM / 1e6;
    let slopes = |hull: &[Point], sign: f64| -> Vec<f64> {
        hull.windows(2)
            .map(|e| sign * (e[1].d - e[0].d) as f64 / (e[1].t - e[0].t) as f64)
            .collect()
    };
    let mut candidates = vec![0.0];
    if span >= MIN_DRIFT_SPAN_NS {
        candidates.extend(slopes(&up_hull, 1.0));
        candidates.extend(slopes(&down_hull, -1.0));
    }
    let sums: Vec<(f64, f64)> = candidates
        .into_iter()
        .map(|b| b.clamp(-limit, limit))
        .map(|b| (floor(&up_hull, b) + floor(&down_hull, -b), b))
        .collect();
    let top = sums.iter().map(|s| s.0).fold(f64::NEG_INFINITY, f64::max);
    // The sum is flat where only one direction pins the slope (a queue
    // growing all run in the other): there, the slope nearest what the
    // directions fit alone, leaving out one steeper than any drift.
    let alone: Vec<f64> = [up.current_line().b, -down.current_line().b]
        .into_iter()
        .filter(|b| b.abs() < limit * 0.999)
        .collect();
    let target = if alone.is_empty() {
        0.0
    } else {
        alone.iter().sum::<f64>() / alone.len() as f64
    };
    let best = sums
        .iter()
        .filter(|s| s.0 >= top - NEAR_TOP_NS)
        .min_by(|x, y| (x.1 - target).abs().total_cmp(&(y.1 - target).abs()))
        .copied()
        .unwrap_or((top, 0.0));
    let b = best.1;
    (b, floor(&up_hull, b), floor(&down_hull, -b))
}

impl RoundTripSplit {
    /// One exchange: sent at `sent_at`, answered with their clock at
    /// `theirs_ns` (ns on their clock), received at `at`.
    pub(crate) fn record(&mut self, sent_at: Nanos, theirs_ns: i128, at: Nanos) {
        let up_raw = theirs_ns - i128::from(sent_at);
        let down_raw = i128::from(at) - theirs_ns;
        let (up_env, down_env) = self
            .envelopes
            .get_or_insert_with(|| (Envelope::new(at, up_raw), Envelope::new(at, down_raw)));
        let ex = Exchange {
            up: up_env.relative(at, up_raw),
            down: down_env.relative(at, down_raw),
        };
        up_env.push(ex.up);
        down_env.push(ex.down);
        self.exchanges += 1;
        let fit = joint_fit(up_env, down_env);
        let (up_ms, down_ms) = above(fit, ex);
        self.now = Some(SplitNow {
            round_trip_ms: up_ms + down_ms,
            uplink_ms: up_ms,
            downlink_ms: down_ms,
        });
        if self.ring.len() == LOOKAHEAD {
            if let Some(old) = self.ring.pop_front() {
                let (u, d) = above(fit, old);
                self.up_hist.record(u);
                self.down_hist.record(d);
            }
        }
        self.ring.push_back(ex);
    }

    /// The newest exchange's split, against the floors known then. Not in
    /// the live view yet (issue 40's closing note).
    #[cfg_attr(not(test), allow(dead_code))]
    pub(crate) fn now(&self) -> Option<SplitNow> {
        self.now
    }

    /// The figures over the run, held exchanges measured against the
    /// final floors.
    pub(crate) fn summary(&self) -> Option<SplitSummary> {
        let (up_env, down_env) = self.envelopes.as_ref()?;
        let fit = joint_fit(up_env, down_env);
        let (mut up, mut down) = (self.up_hist.clone(), self.down_hist.clone());
        for &ex in &self.ring {
            let (u, d) = above(fit, ex);
            up.record(u);
            down.record(d);
        }
        let span = up_env.span().min(down_env.span());
        Some(SplitSummary {
            by: SplitBy::ReplyClock,
            exchanges: self.exchanges,
            uplink_p50_ms: up.quantile(0.5),
            uplink_p99_ms: up.quantile(0.99),
            uplink_max_ms: up.max_ms,
            downlink_p50_ms: down.quantile(0.5),
            downlink_p99_ms: down.quantile(0.99),
            downlink_max_ms: down.max_ms,
            // The uplink's raw delay grows as their clock gains on ours.
            drift_ppm: (span >= MIN_DRIFT_SPAN_NS).then_some(fit.0 * 1e6),
        })
    }

    #[cfg(test)]
    pub(crate) fn stored_points(&self) -> usize {
        self.envelopes
            .as_ref()
            .map_or(0, |(u, d)| u.stored_points() + d.stored_points())
    }
}

/// The round trip split where the replies carry no clock of the
/// responder's but its telemetry does (PX4 answers PING and streams
/// ATTITUDE stamped at send): the downlink's queue is its newest frame's
/// age above its baseline when the reply came, the uplink's the round
/// trip above its quickest less that. Both ride one path down, so the
/// reply queued as the telemetry beside it did. Memory is constant.
#[derive(Debug, Clone, Default)]
pub(crate) struct AgedSplit {
    min_rtt: Option<Nanos>,
    /// (round trip ns, downlink queue ms), held until later exchanges
    /// have found the quickest round trip.
    ring: VecDeque<(Nanos, f64)>,
    up_hist: Quantiles,
    down_hist: Quantiles,
    exchanges: u64,
}

impl AgedSplit {
    /// One exchange: its round trip, and the responder's telemetry age
    /// (ms above its baseline) as its reply came.
    pub(crate) fn record(&mut self, rtt: Nanos, down_ms: f64) {
        self.min_rtt = Some(self.min_rtt.map_or(rtt, |m| m.min(rtt)));
        self.exchanges += 1;
        if self.ring.len() == LOOKAHEAD {
            if let Some((rtt, down)) = self.ring.pop_front() {
                let up = self.up_ms(rtt, down);
                self.up_hist.record(up);
                self.down_hist.record(down);
            }
        }
        self.ring.push_back((rtt, down_ms.max(0.0)));
    }

    fn up_ms(&self, rtt: Nanos, down_ms: f64) -> f64 {
        let above = rtt.saturating_sub(self.min_rtt.unwrap_or(rtt)) as f64 / 1e6;
        (above - down_ms).max(0.0)
    }

    pub(crate) fn summary(&self) -> Option<SplitSummary> {
        if self.exchanges == 0 {
            return None;
        }
        let (mut up, mut down) = (self.up_hist.clone(), self.down_hist.clone());
        for &(rtt, d) in &self.ring {
            up.record(self.up_ms(rtt, d));
            down.record(d);
        }
        Some(SplitSummary {
            by: SplitBy::TelemetryAge,
            exchanges: self.exchanges,
            uplink_p50_ms: up.quantile(0.5),
            uplink_p99_ms: up.quantile(0.99),
            uplink_max_ms: up.max_ms,
            downlink_p50_ms: down.quantile(0.5),
            downlink_p99_ms: down.quantile(0.99),
            downlink_max_ms: down.max_ms,
            drift_ppm: None,
        })
    }
}

/// Each direction's delay above its floor, ms.
fn above((b, a_up, a_down): (f64, f64, f64), ex: Exchange) -> (f64, f64) {
    let up = ex.up.d as f64 - (a_up + b * ex.up.t as f64);
    let down = ex.down.d as f64 - (a_down - b * ex.down.t as f64);
    (up.max(0.0) / 1e6, down.max(0.0) / 1e6)
}

/// A frame's absolute one-way age with bounds, ns.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub(crate) struct AbsoluteAge {
    pub(crate) age_ns: i128,
    /// The bounds the clock offset's causal bounds give, widened by the
    /// drift limit they assume over the time since our time 0; `None`
    /// when the offset has no bounds (its exchanges disagree).
    pub(crate) lower_ns: Option<i128>,
    pub(crate) upper_ns: Option<i128>,
}

/// The absolute age of a frame stamped `stamp_ns` on the responder's
/// TIMESYNC clock (its `tc1` clock: on ArduPilot and PX4 the boot clock,
/// so a `time_boot_ms` × 10^6 is on it too) and received at `at`, given
/// that responder's clock offset (`clock`, their clock minus ours at our
/// time 0, ours being `base_ns` + session time, as
/// [`ClockOffset::record`](super::super::clock_offset::ClockOffset::record)
/// takes it).
pub(crate) fn absolute_age(
    at: Nanos,
    stamp_ns: i128,
    clock: &ClockSummary,
    base_ns: i128,
) -> AbsoluteAge {
    let t = i128::from(at);
    let drift = clock.drift_ppm.unwrap_or(0.0);
    let drifted = (t as f64 * drift / 1e6).round() as i128;
    // Their clock read stamp_ns when ours read stamp_ns − offset(t).
    let age = |offset: i128, slack: i128| t + base_ns + offset + slack - stamp_ns;
    let widen = t * i128::from(clock.bounds_drift_limit_ppm) / 1_000_000 + 1;
    AbsoluteAge {
        age_ns: age(clock.offset_ns, drifted),
        lower_ns: clock.bounds_ns.map(|(lower, _)| age(lower, -widen)),
        upper_ns: clock.bounds_ns.map(|(_, upper)| age(upper, widen)),
    }
}
