//! How old frames are when they arrive, from the senders' own clocks:
//! pure, synchronous, time passed in, constant memory per clock.
//!
//! - [`AgeTracker`]: per source and stamp clock, each frame's age above
//!   that clock's baseline (the floor of receive − stamp, its drift
//!   fitted: [`envelope`]), live ([`AgeNow`]) and over the run
//!   ([`SourceAge`]).
//! - [`RoundTripSplit`]: a round trip's growth split into uplink and
//!   downlink from the responder's stamp in its reply.
//! - [`absolute_age`]: the absolute one-way age where the TIMESYNC clock
//!   offset is known with bounds.
//!
//! Without a shared clock only the age above the baseline is known: the
//! baseline is the least delay the link gave (plus whatever the sender
//! spends between stamping and sending), so a link that is constantly
//! 160 ms late reads 0 here; its growth is what shows.

mod envelope;
mod one_way;
mod split;
#[cfg(test)]
mod tests;

use std::collections::HashMap;

use serde::Serialize;

pub(crate) use envelope::MAX_DRIFT_PPM;
use split::absolute_age;
pub(crate) use split::{AgedSplit, RoundTripSplit, SplitBy, SplitSummary};

use self::one_way::OneWay;
use super::clock_offset::ClockSummary;
use super::hint::{Hint, HintCode};
use super::Nanos;
use crate::frame::{Frame, Stamp, StampClock, StampMeaning, SysComp};

/// Clocks tracked at most (source × clock × meaning): beyond, new ones
/// are ignored, so a flood of spoofed sources cannot grow memory.
pub(crate) const MAX_CLOCKS: usize = 256;

/// One sender clock: a source's stamps on one clock with one meaning.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
struct Key {
    source: SysComp,
    clock: StampClock,
    meaning: StampMeaning,
}

/// A 32-bit ms clock made monotonic across its wrap at 49.7 days.
#[derive(Debug, Clone, Copy, Default)]
struct Unwrap {
    last: Option<u64>,
    wraps: u64,
}

impl Unwrap {
    /// A step back of more than half the range is a wrap; a smaller one
    /// is a reboot or reorder, for the envelope to judge.
    fn unwrap(&mut self, value: u64) -> u64 {
        const RANGE: u64 = 1 << 32;
        if let Some(last) = self.last {
            if value < last && last - value > RANGE / 2 {
                self.wraps += 1;
            } else if value > last && value - last > RANGE / 2 && self.wraps > 0 {
                // A straggler from before the wrap.
                return (self.wraps - 1) * RANGE + value;
            }
        }
        self.last = Some(value);
        self.wraps * RANGE + value
    }
}

#[derive(Debug, Clone, Default)]
struct ClockAge {
    unwrap: Unwrap,
    one_way: OneWay,
}

/// Each source's frames' ages, per stamp clock.
#[derive(Debug, Clone, Default)]
pub(crate) struct AgeTracker {
    clocks: HashMap<Key, ClockAge>,
    /// Each source's frames' ages so far, counted into [`AGE_BOUNDS_MS`].
    counts: HashMap<SysComp, AgeCounts>,
    /// Each source's oldest frame since the last [`AgeTracker::take_window_max`]
    /// (ms): a queue's peak between two tellings, which the newest age
    /// alone misses.
    window_max: HashMap<SysComp, f64>,
}

/// The upper bounds (ms) a source's frames' ages are counted under: a
/// histogram an exporter can show as it is.
pub(crate) const AGE_BOUNDS_MS: [f64; 12] = [
    1.0, 5.0, 10.0, 25.0, 50.0, 100.0, 250.0, 500.0, 1000.0, 2500.0, 5000.0, 10000.0,
];

/// A source's frames' ages above its baseline so far: how many fell at
/// or under each of [`AGE_BOUNDS_MS`] and above the last (not cumulative),
/// their sum and their number.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub(crate) struct AgeCounts {
    pub(crate) buckets: [u64; AGE_BOUNDS_MS.len() + 1],
    pub(crate) sum_ms: f64,
    pub(crate) count: u64,
}

impl AgeCounts {
    fn record(&mut self, age_ms: f64) {
        self.buckets[AGE_BOUNDS_MS.partition_point(|&b| b < age_ms)] += 1;
        self.sum_ms += age_ms;
        self.count += 1;
    }
}

/// A source's newest age above baseline, on its headline clock.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub(crate) struct AgeNow {
    pub(crate) clock: StampClock,
    pub(crate) meaning: StampMeaning,
    /// The newest stamped frame's age above the baseline known when it
    /// arrived.
    pub(crate) age_ms: f64,
    /// When it arrived (ns of session time): a stale figure is old news.
    #[serde(skip)]
    pub(crate) at: Nanos,
}

/// One clock's figures over the run.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub(crate) struct ClockAgeSummary {
    pub(crate) clock: StampClock,
    pub(crate) meaning: StampMeaning,
    pub(crate) samples: u64,
    /// Age above the baseline: percentiles (3 significant digits) and max.
    pub(crate) p50_ms: f64,
    pub(crate) p90_ms: f64,
    pub(crate) p99_ms: f64,
    pub(crate) max_ms: f64,
    /// Their clock's rate against ours as the floor's slope (positive:
    /// theirs runs slow); `None` until the stamps span 10 s.
    pub(crate) drift_ppm: Option<f64>,
    /// Baselines started again: the clock went back (a reboot) or jumped.
    pub(crate) restarts: u32,
    /// Stamps that fitted no baseline (a bad clock), left out.
    pub(crate) rejected: u64,
    /// How far the baselines the ages were measured against were from the
    /// final one, at most (ms): the online answer's error.
    pub(crate) baseline_error_ms: f64,
}

/// One source's ages: its headline clock's and every clock's.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub(crate) struct SourceAge {
    pub(crate) source: SysComp,
    pub(crate) headline: ClockAgeSummary,
    pub(crate) clocks: Vec<ClockAgeSummary>,
    /// The headline's ages as absolute one-way delays, where the source
    /// answered TIMESYNC and its clock offset has bounds.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(crate) absolute: Option<AbsoluteAgeSummary>,
}

/// A source's headline ages as absolute one-way delays (ms): its
/// baseline placed by its TIMESYNC clock offset, whose causal bounds
/// (widened by the drift they allow) bound the baseline and so every
/// age above it alike.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub(crate) struct AbsoluteAgeSummary {
    /// The quickest frames' one-way delay: the baseline's.
    pub(crate) baseline_ms: f64,
    pub(crate) baseline_lower_ms: f64,
    pub(crate) baseline_upper_ms: f64,
    /// The headline's p50, p99 and max above the baseline, plus it.
    pub(crate) p50_ms: f64,
    pub(crate) p99_ms: f64,
    pub(crate) max_ms: f64,
}

/// The longest one-way delay a baseline can be: a bound beyond it says
/// the stamps are on another clock than TIMESYNC's (a Unix time where
/// `tc1` counts from boot), not that the link is a minute long.
const MAX_BASELINE_NS: i128 = 60_000_000_000;
/// A baseline's upper bound below zero by more than this says the same:
/// ms stamps read up to 1 ms early, so a little below is rounding.
const BASELINE_SLACK_NS: i128 = 1_000_000;

/// Which clock speaks for a source, best first. Send stamps first: a
/// sample stamp's age includes how old the data was when sent (a GPS
/// fix at 5 Hz up to 200 ms), not the link's delay. Among them the boot
/// clocks (ArduPilot stamps most telemetry with it at send, often), then
/// TIMESYNC and Unix time; the signature last: ArduPilot advances it in
/// whole seconds of GPS time and one unit a frame between, so its ages
/// saw-tooth by up to a second. More samples break ties.
fn rank(clock: StampClock, meaning: StampMeaning) -> u8 {
    let by_clock = match clock {
        StampClock::BootMs | StampClock::BootUs => 0,
        StampClock::TimesyncNs => 1,
        StampClock::UnixUs => 2,
        StampClock::Signature => 3,
    };
    match meaning {
        StampMeaning::Sent => by_clock,
        StampMeaning::Sampled => 4 + by_clock,
    }
}

impl AgeTracker {
    /// Takes every stamp `frame` carries, received at `at`; the frame's
    /// age above its baseline (ms) by its best-ranked send stamp that
    /// keeps time, if that stamp fitted its baseline.
    pub(crate) fn on_frame(&mut self, frame: &Frame, at: Nanos) -> Option<f64> {
        let mut best: Option<(u8, f64)> = None;
        for stamp in frame.stamps.iter() {
            let age = self.on_stamp(frame.source, stamp, at);
            let rank = rank(stamp.clock, stamp.meaning);
            // A sample time's age includes how old the data was: not the
            // link's, so it speaks for no frame.
            let link_age = stamp.clock.keeps_time() && stamp.meaning == StampMeaning::Sent;
            if let Some(age) = age.filter(|_| link_age) {
                if best.is_none_or(|(r, _)| rank < r) {
                    best = Some((rank, age));
                }
            }
        }
        let age = best.map(|(_, age)| age)?;
        let room = self.counts.len() < MAX_CLOCKS || self.counts.contains_key(&frame.source);
        if room {
            self.counts.entry(frame.source).or_default().record(age);
            let max = self.window_max.entry(frame.source).or_insert(age);
            *max = max.max(age);
        }
        Some(age)
    }

    /// Each source's oldest frame's age (ms) since the last call, by
    /// source; the window starts afresh.
    pub(crate) fn take_window_max(&mut self) -> Vec<(SysComp, f64)> {
        let mut out: Vec<(SysComp, f64)> = self.window_max.drain().collect();
        out.sort_by_key(|&(source, _)| source);
        out
    }

    /// `source`'s frames' ages so far, counted.
    pub(crate) fn counts(&self, source: SysComp) -> Option<AgeCounts> {
        self.counts.get(&source).copied()
    }

    /// Takes one stamp; its age (ms) if it fitted its baseline.
    fn on_stamp(&mut self, source: SysComp, stamp: Stamp, at: Nanos) -> Option<f64> {
        let key = Key {
            source,
            clock: stamp.clock,
            meaning: stamp.meaning,
        };
        if !self.clocks.contains_key(&key) && self.clocks.len() >= MAX_CLOCKS {
            return None;
        }
        let entry = self.clocks.entry(key).or_default();
        let value = match stamp.clock {
            StampClock::BootMs => entry.unwrap.unwrap(stamp.value),
            _ => stamp.value,
        };
        let ns = i128::from(value) * i128::from(stamp.clock.unit_ns());
        entry.one_way.record(at, ns);
        let (when, age_ns) = entry.one_way.now()?;
        (when == at).then_some(age_ns / 1e6)
    }

    /// The headline clock of `source` among its keys with figures.
    fn headline(&self, source: SysComp) -> Option<(&Key, &ClockAge)> {
        self.clocks
            .iter()
            .filter(|(k, _)| k.source == source)
            .min_by_key(|(k, c)| {
                let samples = c.one_way.samples();
                (rank(k.clock, k.meaning), std::cmp::Reverse(samples))
            })
    }

    /// The newest age above baseline of `source`, on its headline clock.
    pub(crate) fn now(&self, source: SysComp) -> Option<AgeNow> {
        let (key, clock) = self.headline(source)?;
        let (at, age_ns) = clock.one_way.now()?;
        Some(AgeNow {
            clock: key.clock,
            meaning: key.meaning,
            age_ms: age_ns / 1e6,
            at,
        })
    }

    /// `age`'s headline as absolute one-way delays, given its source's
    /// TIMESYNC clock offset (`clock`, against our clock reading
    /// `base_ns` at time 0): when the offset has bounds and the baseline
    /// they place is a delay a link can have, else `None` (the stamps
    /// are on another clock than `tc1`'s).
    pub(crate) fn absolute(
        &self,
        age: &SourceAge,
        clock: &ClockSummary,
        base_ns: i128,
    ) -> Option<AbsoluteAgeSummary> {
        let h = &age.headline;
        let key = Key {
            source: age.source,
            clock: h.clock,
            meaning: h.meaning,
        };
        // At the baseline's start: the offset's bounds hold at our time 0
        // and widen with time by the drift they allow.
        let (at, floor) = self.clocks.get(&key)?.one_way.floor_at_start()?;
        // A frame on the floor, received at `at`, was stamped at `at − floor`.
        let on_floor = absolute_age(at, i128::from(at) - floor, clock, base_ns);
        let (lower, upper) = (on_floor.lower_ns?, on_floor.upper_ns?);
        if !h.clock.keeps_time() || upper < -BASELINE_SLACK_NS || lower > MAX_BASELINE_NS {
            return None;
        }
        let baseline_ms = on_floor.age_ns as f64 / 1e6;
        Some(AbsoluteAgeSummary {
            baseline_ms,
            // No frame arrives before it was sent: below 0 is ms rounding.
            baseline_lower_ms: lower.max(0) as f64 / 1e6,
            baseline_upper_ms: upper as f64 / 1e6,
            p50_ms: baseline_ms + h.p50_ms,
            p99_ms: baseline_ms + h.p99_ms,
            max_ms: baseline_ms + h.max_ms,
        })
    }

    /// Every source's figures, by source, its clocks best first.
    pub(crate) fn summary(&self) -> Vec<SourceAge> {
        let mut keys: Vec<&Key> = self.clocks.keys().collect();
        // Whole keys break rank's ties (boot ms and µs rank alike), so the
        // order is the same every run.
        keys.sort_by_key(|k| (k.source, rank(k.clock, k.meaning), **k));
        let mut out: Vec<SourceAge> = Vec::new();
        for key in keys {
            let Some(s) = self.clocks[key].one_way.figures() else {
                continue;
            };
            let figures = ClockAgeSummary {
                clock: key.clock,
                meaning: key.meaning,
                samples: s.samples,
                p50_ms: s.p50_ns / 1e6,
                p90_ms: s.p90_ns / 1e6,
                p99_ms: s.p99_ns / 1e6,
                max_ms: s.max_ns / 1e6,
                drift_ppm: s.drift_ppm,
                restarts: s.restarts,
                rejected: s.rejected,
                baseline_error_ms: s.baseline_error_ns / 1e6,
            };
            match out.last_mut() {
                Some(last) if last.source == key.source => last.clocks.push(figures),
                _ => out.push(SourceAge {
                    source: key.source,
                    headline: figures,
                    clocks: vec![figures],
                    absolute: None,
                }),
            }
        }
        // The headline ranks first; among equal ranks, the most samples.
        for source in &mut out {
            if let Some(best) = source
                .clocks
                .iter()
                .min_by_key(|c| (rank(c.clock, c.meaning), std::cmp::Reverse(c.samples)))
            {
                source.headline = *best;
            }
        }
        out
    }
}

/// Above these (ms) a source's headline age is a queue, not jitter or a
/// spike: one frame in ten late by 100 ms (a queue holds many frames in a
/// row) and one at least by 250 ms.
const QUEUE_P90_MS: f64 = 100.0;
const QUEUE_MAX_MS: f64 = 250.0;

/// The queue hint, when `age`'s headline send stamps show frames held
/// ever later while the source lost at most 1 % of `received + lost`: a
/// buffer between it and here (a modem, a relay, a WebSocket over TCP)
/// delaying frames instead of dropping them.
pub(crate) fn queue_building(age: &SourceAge, received: u64, lost: u64) -> Option<Hint> {
    let h = &age.headline;
    let queued = h.meaning == StampMeaning::Sent
        && h.clock.keeps_time()
        && h.p90_ms >= QUEUE_P90_MS
        && h.max_ms >= QUEUE_MAX_MS
        && lost * 100 <= received + lost;
    queued.then(|| {
        Hint::new(
            HintCode::QueueBuilding,
            format!(
                "{}'s frames arrived up to {:.2} s later than its quickest (p90 {:.0} ms, p99 \
                 {:.0} ms above its baseline, by its {} stamps) while it lost {lost} of {}: a \
                 queue is building between it and here (bufferbloat), delaying frames instead \
                 of dropping them",
                age.source,
                h.max_ms / 1e3,
                h.p90_ms,
                h.p99_ms,
                h.clock.words(),
                received + lost
            ),
        )
    })
}

/// The queue hint of each source in `ages` whose frames came ever later
/// while it lost next to none, by `counts`: its frames received and lost.
pub(crate) fn queue_hints(
    ages: &[SourceAge],
    counts: impl Fn(SysComp) -> Option<(u64, u64)>,
) -> Vec<Hint> {
    ages.iter()
        .filter_map(|a| {
            let (received, lost) = counts(a.source)?;
            queue_building(a, received, lost)
        })
        .collect()
}
