//! One step of a sweep: what it sent and what came back, and the figures
//! it is reported with. Pure: events and byte counters are handed in with
//! their times. Memory is one RTT histogram per step being measured.

use std::time::Duration;

use crate::engine::matcher::MatchEvent;
use crate::engine::radio::{RadioReport, SinceBootCounter, UNKNOWN};
use crate::engine::stats::RttStats;
pub(crate) use crate::engine::sweep_report::{Phase, StepFigures, StepRadio, StepRtt};
use crate::engine::Nanos;
use crate::frame::SysComp;

impl Phase {
    pub(crate) fn name(self) -> &'static str {
        match self {
            Phase::Baseline => "baseline",
            Phase::Ramp => "ramp",
            Phase::Refine => "refine",
            Phase::Loaded => "loaded",
        }
    }

    /// Steps that take part in finding the knee.
    pub(crate) fn sweeps(self) -> bool {
        matches!(self, Phase::Ramp | Phase::Refine)
    }
}

/// One step to run.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct PlannedStep {
    pub(crate) phase: Phase,
    pub(crate) rate_hz: f64,
    /// The `--load` streams are on during it.
    pub(crate) load: bool,
    /// Requests it sends: the rate over the step's duration, at least one.
    pub(crate) count: u64,
    /// The rate of the step before again, which failed on latency alone.
    pub(crate) retry: bool,
}

impl PlannedStep {
    pub(crate) fn new(phase: Phase, rate_hz: f64, load: bool, duration: Duration) -> Self {
        PlannedStep {
            phase,
            rate_hz,
            load,
            count: ((rate_hz * duration.as_secs_f64()).round() as u64).max(1),
            retry: false,
        }
    }

    /// The same step once more.
    pub(crate) fn retried(self) -> Self {
        PlannedStep {
            retry: true,
            ..self
        }
    }

    pub(crate) fn interval_ns(&self) -> u64 {
        (1e9 / self.rate_hz).round().max(1.0) as u64
    }
}

/// A step passes the knee test when it loses less than this share...
pub(crate) const KNEE_MAX_LOSS: f64 = 0.01;
/// ...and its p99 stays under this many times the first step's...
pub(crate) const KNEE_MAX_P99_RATIO: f64 = 2.0;
/// ...or rose by less than this over it, in µs: what a bufferbloat test
/// grades A (under 30 ms). On a link whose first p99 is 0.1 ms (a fast
/// queue, loopback), twice that is one scheduling hiccup of a busy
/// machine; a queue that grows within a step rises past this in a second
/// at a tenth over its capacity.
pub(crate) const KNEE_MIN_P99_RISE_US: f64 = 30_000.0;

/// The p99 a step must stay under against the first sweep step's.
pub(crate) fn p99_limit_us(reference_p99_us: f64) -> f64 {
    (KNEE_MAX_P99_RATIO * reference_p99_us).max(reference_p99_us + KNEE_MIN_P99_RISE_US)
}

impl StepFigures {
    /// Whether these figures pass the knee test against the first sweep
    /// step's p99.
    pub(crate) fn passes(&self, reference_p99_us: f64) -> bool {
        self.complete
            && self.received > 0
            && self.loss_ratio < KNEE_MAX_LOSS
            && self
                .rtt
                .is_some_and(|r| r.p99_us < p99_limit_us(reference_p99_us))
    }

    /// It failed the knee test on its p99 alone (it lost under 1 %): the
    /// rate is tried once more before it counts as failed.
    pub(crate) fn failed_on_latency_alone(&self) -> bool {
        self.passed == Some(false)
            && self.complete
            && self.received > 0
            && self.loss_ratio < KNEE_MAX_LOSS
    }

    /// Bytes per second both ways.
    pub(crate) fn wire_bytes_per_s(&self) -> f64 {
        self.tx_bytes_per_s + self.rx_bytes_per_s
    }

    #[cfg(test)]
    pub(crate) fn test(phase: Phase, rate: f64, loss: f64) -> Self {
        StepFigures {
            index: 0,
            phase,
            load: false,
            offered_hz: rate,
            achieved_hz: rate,
            start_s: 0.0,
            duration_s: 1.0,
            requests: 100,
            received: (100.0 * (1.0 - loss)) as u64,
            lost: (100.0 * loss) as u64,
            late: 0,
            loss_ratio: loss,
            rtt: Some(StepRtt {
                p50_us: 10_000.0,
                p99_us: 12_000.0,
                max_us: 13_000.0,
            }),
            tx_bytes_per_s: rate * 21.0,
            rx_bytes_per_s: rate * 26.0,
            radio: None,
            complete: true,
            passed: None,
            retry: false,
        }
    }
}

/// The radio's reports during a step.
#[derive(Debug, Clone, Copy)]
struct RadioTally {
    id: SysComp,
    reports: u64,
    txbuf_min: Option<u8>,
    txbuf: (u64, u64),
    rssi: (u64, u64),
    remrssi: (u64, u64),
    rxerrors: SinceBootCounter,
}

impl RadioTally {
    /// Following `id`, whose rxerrors read `rxerrors` before the step
    /// (unknown: counted from its first report in the step).
    fn new(id: SysComp, rxerrors: Option<u16>) -> Self {
        let mut counter = SinceBootCounter::default();
        if let Some(v) = rxerrors {
            counter.record(v);
        }
        RadioTally {
            id,
            reports: 0,
            txbuf_min: None,
            txbuf: (0, 0),
            rssi: (0, 0),
            remrssi: (0, 0),
            rxerrors: counter,
        }
    }
}

fn add(sum: &mut (u64, u64), v: u8) {
    if v != UNKNOWN {
        sum.0 += u64::from(v);
        sum.1 += 1;
    }
}

fn mean(sum: (u64, u64)) -> Option<f64> {
    (sum.1 > 0).then(|| sum.0 as f64 / sum.1 as f64)
}

/// A step being measured.
#[derive(Clone)]
pub(crate) struct StepTally {
    pub(crate) plan: PlannedStep,
    /// When the step began (its requests are those sent from then on).
    pub(crate) start: Nanos,
    requests: u64,
    first_sent: Option<Nanos>,
    last_sent: Nanos,
    received: u64,
    lost: u64,
    late: u64,
    rtt: RttStats,
    last_reply: Option<Nanos>,
    /// Byte counters at the start (sent, received), and when it sent its
    /// last request (then, sent).
    bytes_at_start: (u64, u64),
    sending_end: Option<(Nanos, u64)>,
    radio: Option<RadioTally>,
}

impl StepTally {
    /// A step beginning at `start`, with the link's byte counters then
    /// (sent, received) and the latest rxerrors of the radio followed.
    pub(crate) fn new(
        plan: PlannedStep,
        start: Nanos,
        bytes: (u64, u64),
        radio: Option<(SysComp, u16)>,
    ) -> Self {
        StepTally {
            plan,
            start,
            requests: 0,
            first_sent: None,
            last_sent: start,
            received: 0,
            lost: 0,
            late: 0,
            rtt: RttStats::new(),
            last_reply: None,
            bytes_at_start: bytes,
            sending_end: None,
            radio: radio.map(|(id, rxerrors)| RadioTally::new(id, Some(rxerrors))),
        }
    }

    /// `n` requests went out at `at`.
    pub(crate) fn sent(&mut self, n: u64, at: Nanos) {
        if n == 0 {
            return;
        }
        self.first_sent.get_or_insert(at);
        self.last_sent = at;
        self.requests += n;
    }

    /// The last request went out at `at`, with `tx_bytes` sent by then.
    pub(crate) fn sending_done(&mut self, at: Nanos, tx_bytes: u64) {
        if self.sending_end.is_none() {
            self.sending_end = Some((at, tx_bytes));
        }
    }

    pub(crate) fn sending_finished(&self) -> bool {
        self.sending_end.is_some()
    }

    /// When the step's time is up: its requests at its rate take that long
    /// (the load, if any, runs until then).
    pub(crate) fn nominal_end(&self) -> Nanos {
        self.start + self.plan.count * self.plan.interval_ns()
    }

    /// Some request of it was lost (or answered late): its replies may
    /// still be queued somewhere on the link.
    pub(crate) fn lost_any(&self) -> bool {
        self.lost + self.late > 0
    }

    /// Whether an event about a request sent at `sent_at` is this step's.
    pub(crate) fn owns(&self, sent_at: Nanos) -> bool {
        sent_at >= self.start
    }

    pub(crate) fn on_event(&mut self, e: &MatchEvent) {
        match *e {
            MatchEvent::Reply { rtt, .. } => {
                self.received += 1;
                self.rtt.record(rtt);
            }
            MatchEvent::Lost { .. } => self.lost += 1,
            MatchEvent::Late { .. } => self.late += 1,
            MatchEvent::Duplicate { .. } | MatchEvent::Stale { .. } => {}
        }
        // Every reply that came, in time or not, is traffic the step drew.
        if let MatchEvent::Reply { at, .. }
        | MatchEvent::Late { at, .. }
        | MatchEvent::Duplicate { at, .. } = *e
        {
            self.last_reply = Some(self.last_reply.map_or(at, |t| t.max(at)));
        }
    }

    /// A RADIO_STATUS from `id`; only the radio the step follows counts.
    pub(crate) fn on_radio(&mut self, id: SysComp, r: &RadioReport) {
        let tally = self.radio.get_or_insert_with(|| RadioTally::new(id, None));
        if tally.id != id {
            return;
        }
        tally.reports += 1;
        if r.txbuf != UNKNOWN {
            tally.txbuf_min = Some(tally.txbuf_min.map_or(r.txbuf, |m| m.min(r.txbuf)));
        }
        add(&mut tally.txbuf, r.txbuf);
        add(&mut tally.rssi, r.rssi);
        add(&mut tally.remrssi, r.remrssi);
        tally.rxerrors.record(r.rxerrors);
    }

    /// The figures as of `now` (the step's end), with the link's byte
    /// counters then.
    pub(crate) fn figures(
        &self,
        index: u32,
        complete: bool,
        now: Nanos,
        bytes_now: (u64, u64),
    ) -> StepFigures {
        let first = self.first_sent.unwrap_or(self.start);
        let span = self.last_sent.saturating_sub(first) as f64 / 1e9;
        // The time it sent: to its last request and one interval more (N
        // requests at rate r take N / r), or until now if cut short.
        let (end, tx) = match self.sending_end {
            Some((at, tx)) => (at + self.plan.interval_ns(), tx),
            None => (now, bytes_now.0),
        };
        let rx = bytes_now.1;
        let rx_end = end.max(self.last_reply.unwrap_or(0));
        let per_s = |bytes: u64, until: Nanos| {
            let window = until.saturating_sub(self.start) as f64 / 1e9;
            if window > 0.0 {
                bytes as f64 / window
            } else {
                0.0
            }
        };
        let decided = self.received + self.lost;
        StepFigures {
            index,
            phase: self.plan.phase,
            load: self.plan.load,
            offered_hz: self.plan.rate_hz,
            // One request is no rate; two or more over their span are.
            achieved_hz: if self.requests > 1 && span > 0.0 {
                (self.requests - 1) as f64 / span
            } else {
                0.0
            },
            start_s: first as f64 / 1e9,
            duration_s: span,
            requests: self.requests,
            received: self.received,
            lost: self.lost,
            late: self.late,
            loss_ratio: if decided == 0 {
                0.0
            } else {
                self.lost as f64 / decided as f64
            },
            rtt: self.rtt.summary().map(|s| StepRtt {
                p50_us: s.p50_us,
                p99_us: s.p99_us,
                max_us: s.max_us,
            }),
            tx_bytes_per_s: per_s(tx.saturating_sub(self.bytes_at_start.0), end),
            rx_bytes_per_s: per_s(rx.saturating_sub(self.bytes_at_start.1), rx_end),
            radio: self.radio.filter(|r| r.reports > 0).map(|r| StepRadio {
                id: r.id,
                reports: r.reports,
                txbuf_min: r.txbuf_min,
                txbuf_mean: mean(r.txbuf),
                rssi_mean: mean(r.rssi),
                remrssi_mean: mean(r.remrssi),
                rxerrors_delta: r.rxerrors.grown(),
            }),
            complete,
            passed: None,
            retry: self.plan.retry,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn plan(rate: f64) -> PlannedStep {
        PlannedStep {
            phase: Phase::Ramp,
            rate_hz: rate,
            load: false,
            count: 10,
            retry: false,
        }
    }

    const R: SysComp = SysComp::new(1, 1);

    fn reply(sent_at: Nanos, rtt_ms: u64) -> MatchEvent {
        MatchEvent::Reply {
            responder: R,
            seq: 0,
            rtt: rtt_ms * 1_000_000,
            sent_at,
            at: sent_at + rtt_ms * 1_000_000,
            out_of_order: false,
            first_from_responder: false,
        }
    }

    #[test]
    fn counts_rates_and_bytes_are_exact() {
        // 10 requests at 10/s from t = 1 s; bytes counted from (500, 900).
        let mut t = StepTally::new(plan(10.0), 1_000_000_000, (500, 900), None);
        for i in 0..10u64 {
            let at = 1_000_000_000 + i * 100_000_000;
            t.sent(1, at);
            if i == 3 {
                t.on_event(&MatchEvent::Lost {
                    responder: R,
                    seq: 3,
                    sent_at: at,
                    at: at + 2_000_000_000,
                });
                t.on_event(&MatchEvent::Late {
                    responder: R,
                    seq: 3,
                    rtt: 2_500_000_000,
                    sent_at: at,
                    at: at + 2_500_000_000,
                });
            } else {
                t.on_event(&reply(at, 20 + i));
            }
        }
        // Sending ended at 1.9 s, after 210 B sent; 334 B came in until
        // the step ended at 5 s.
        t.sending_done(1_900_000_000, 710);
        assert!(t.owns(1_000_000_000) && !t.owns(999_999_999));
        let f = t.figures(3, true, 5_000_000_000, (9_999, 1_234));
        assert_eq!(
            (f.index, f.requests, f.received, f.lost, f.late),
            (3, 10, 9, 1, 1)
        );
        assert!((f.loss_ratio - 0.1).abs() < 1e-12);
        assert!((f.achieved_hz - 10.0).abs() < 1e-9, "{}", f.achieved_hz);
        assert!((f.duration_s - 0.9).abs() < 1e-9);
        // 210 B over the 1 s it sent (10 requests at 10/s); 334 B over the
        // time until its last reply, the late one at 3.8 s.
        assert!((f.tx_bytes_per_s - 210.0).abs() < 1e-9);
        assert!((f.rx_bytes_per_s - 334.0 / 2.8).abs() < 1e-9);
        // Replies that all came within the sending time are counted over it.
        let mut prompt = StepTally::new(plan(10.0), 1_000_000_000, (500, 900), None);
        for i in 0..10u64 {
            prompt.sent(1, 1_000_000_000 + i * 100_000_000);
            prompt.on_event(&reply(1_000_000_000 + i * 100_000_000, 20));
        }
        prompt.sending_done(1_900_000_000, 710);
        let g = prompt.figures(1, true, 2_000_000_000, (710, 1_160));
        assert!(
            (g.rx_bytes_per_s - 260.0).abs() < 1e-9,
            "{}",
            g.rx_bytes_per_s
        );
        let rtt = f.rtt.unwrap();
        // The histogram keeps three significant digits.
        assert!((rtt.p50_us - 25_000.0).abs() < 25.0, "{rtt:?}");
        assert_eq!(rtt.max_us, 29_000.0);
        assert_eq!(f.start_s, 1.0);
    }

    #[test]
    fn the_knee_test_needs_low_loss_and_a_p99_under_twice_the_first() {
        let mut f = StepFigures::test(Phase::Ramp, 10.0, 0.0);
        f.rtt = Some(StepRtt {
            p50_us: 60_000.0,
            p99_us: 80_000.0,
            max_us: 90_000.0,
        });
        assert!(f.passes(40_001.0));
        assert!(!f.passes(40_000.0), "p99 80 ms is twice 40 ms");
        // A fast link: twice 0.1 ms is a hiccup; 30 ms more is a queue.
        f.rtt = Some(StepRtt {
            p50_us: 200.0,
            p99_us: 20_000.0,
            max_us: 20_000.0,
        });
        assert!(f.passes(100.0), "20 ms over a 0.1 ms first p99 passes");
        f.rtt = Some(StepRtt {
            p50_us: 200.0,
            p99_us: 30_100.0,
            max_us: 30_100.0,
        });
        assert!(!f.passes(100.0), "30 ms over it fails");
        f.loss_ratio = 0.01;
        assert!(!f.passes(100_000.0), "1 % loss is not under 1 %");
        f.loss_ratio = 0.0;
        f.complete = false;
        assert!(!f.passes(100_000.0), "an interrupted step is never judged");
    }

    #[test]
    fn the_radio_figures_are_the_steps_own() {
        let radio = SysComp::new(51, 68);
        let report = |txbuf, rxerrors| RadioReport {
            rssi: 180,
            remrssi: UNKNOWN,
            txbuf,
            noise: 40,
            remnoise: 40,
            rxerrors,
            fixed: 0,
        };
        // The radio had counted 100 errors before this step.
        let mut t = StepTally::new(plan(5.0), 0, (0, 0), Some((radio, 100)));
        t.on_radio(radio, &report(90, 103));
        t.on_radio(SysComp::new(52, 68), &report(1, 60_000));
        t.on_radio(radio, &report(40, 110));
        let r = t.figures(1, true, 1, (0, 0)).radio.unwrap();
        assert_eq!((r.id, r.reports, r.txbuf_min), (radio, 2, Some(40)));
        assert_eq!((r.txbuf_mean, r.rssi_mean), (Some(65.0), Some(180.0)));
        assert_eq!((r.remrssi_mean, r.rxerrors_delta), (None, 10));
        // A step with no report has no radio figures.
        let quiet = StepTally::new(plan(5.0), 0, (0, 0), Some((radio, 110)));
        assert!(quiet.figures(2, true, 1, (0, 0)).radio.is_none());
    }
}
