//! The ages against a truth the tests make: a sender's clock with an
//! offset of hours and drift of ±100 ppm, stamping in whole ms, over a
//! link that jitters, loses frames, batches them, and queues.

use super::envelope::MAX_BUCKETS;
use super::one_way::OneWay;
use super::*;
use crate::engine::clock_offset::ClockSummary;
use crate::frame::{test_frame, Msg};

const MS: f64 = 1e6;
const S: f64 = 1e9;

/// xorshift64*: the same jitter and loss every run.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        (self.0.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// A queue that is empty until `start`, grows to `peak` over `rise`, then
/// drains over `fall` (ns of our time to ns of delay).
fn ramp(s: f64, start: f64, rise: f64, fall: f64, peak: f64) -> f64 {
    if s < start || s > start + rise + fall {
        0.0
    } else if s <= start + rise {
        peak * (s - start) / rise
    } else {
        peak * (1.0 - (s - start - rise) / fall)
    }
}

/// One stamped frame of the truth.
#[derive(Debug, Clone, Copy)]
struct Sent {
    /// Our receive time, ns.
    at: Nanos,
    /// Their clock's stamp, ns (whole ms).
    stamp_ns: i128,
    /// Its delay above the link's least, ns.
    above_ns: f64,
}

struct Link {
    offset_ns: f64,
    drift_ppm: f64,
    rate_hz: f64,
    seconds: f64,
    loss: f64,
    /// Receive times rounded up to this (a batching logger), ns; 0: none.
    batch_ns: f64,
    queue: fn(f64) -> f64,
}

impl Link {
    fn frames(&self, seed: u64) -> Vec<Sent> {
        let mut rng = Rng(seed);
        let base = 20.0 * MS;
        let mut out = Vec::new();
        let n = (self.seconds * self.rate_hz) as u64;
        for k in 0..n {
            let s = 1.0 * S + k as f64 * S / self.rate_hz;
            let delay = base + 3.0 * MS * rng.next() + (self.queue)(s);
            if rng.next() < self.loss {
                continue;
            }
            let mut t = s + delay;
            if self.batch_ns > 0.0 {
                t = (t / self.batch_ns).ceil() * self.batch_ns;
            }
            let theirs = self.offset_ns + s * (1.0 + self.drift_ppm / 1e6);
            let stamp_ns = ((theirs / MS).floor() * MS) as i128;
            out.push(Sent {
                at: t as Nanos,
                stamp_ns,
                above_ns: t - s - base,
            });
        }
        out
    }
}

fn queue_down(s: f64) -> f64 {
    ramp(s, 20.0 * S, 8.0 * S, 4.0 * S, 1.5 * S)
}

fn quiet(_: f64) -> f64 {
    0.0
}

/// Within 10 ms or 5 % of the truth.
fn close(got_ns: f64, truth_ns: f64) -> bool {
    (got_ns - truth_ns).abs() <= (10.0 * MS).max(0.05 * truth_ns)
}

fn quantile(mut v: Vec<f64>, q: f64) -> f64 {
    v.sort_by(f64::total_cmp);
    v[((q * v.len() as f64).ceil() as usize).max(1) - 1]
}

/// Feeds `frames` one by one, checking each live age after the first
/// 10 s (drift fitted) and the run's figures against the truth.
fn check_one_way(frames: &[Sent]) -> OneWay {
    let mut one = OneWay::default();
    let first = frames[0].at;
    for f in frames {
        one.record(f.at, f.stamp_ns);
        let (_, live) = one.now().expect("a live age");
        if f.at > first + 10 * S as u64 {
            assert!(
                close(live, f.above_ns),
                "live {} ms, truth {} ms at {} s",
                live / MS,
                f.above_ns / MS,
                f.at as f64 / S
            );
        }
    }
    let fig = one.figures().expect("figures");
    let truth: Vec<f64> = frames.iter().map(|f| f.above_ns).collect();
    for (got, q) in [(fig.p50_ns, 0.5), (fig.p99_ns, 0.99)] {
        let want = quantile(truth.clone(), q);
        assert!(
            close(got, want),
            "p{q}: {} ms vs {} ms",
            got / MS,
            want / MS
        );
    }
    let max = truth.iter().copied().fold(0.0, f64::max);
    assert!(
        close(fig.max_ns, max),
        "max {} vs {}",
        fig.max_ns / MS,
        max / MS
    );
    assert_eq!((fig.restarts, fig.rejected), (0, 0));
    one
}

#[test]
fn a_growing_queue_shows_above_the_baseline_whatever_the_offset_and_drift() {
    for (offset_h, drift_ppm) in [(3.0, 100.0), (-5.0, -100.0), (0.5, 0.0)] {
        let link = Link {
            offset_ns: offset_h * 3600.0 * S,
            drift_ppm,
            rate_hz: 50.0,
            seconds: 60.0,
            loss: 0.1,
            batch_ns: 0.0,
            queue: queue_down,
        };
        let one = check_one_way(&link.frames(7));
        let fig = one.figures().unwrap();
        // The floor's slope is the drift (their clock fast: d falls).
        let drift = fig.drift_ppm.expect("fitted over 60 s");
        assert!(
            (drift + drift_ppm).abs() < 20.0,
            "{drift} ppm vs {drift_ppm}"
        );
        assert!(fig.max_ns > 1.45 * S);
        assert!(
            fig.baseline_error_ns < 10.0 * MS,
            "{}",
            fig.baseline_error_ns
        );
    }
}

#[test]
fn a_quiet_link_reads_near_zero() {
    let link = Link {
        offset_ns: 7200.0 * S,
        drift_ppm: 80.0,
        rate_hz: 10.0,
        seconds: 120.0,
        loss: 0.0,
        batch_ns: 0.0,
        queue: quiet,
    };
    let one = check_one_way(&link.frames(3));
    assert!(one.figures().unwrap().max_ns < 5.0 * MS);
}

/// A logger that writes once a second (vtol.tlog): the first frame of a
/// batch waited a second for it, and that is what its age says.
#[test]
fn batched_receive_times_show_the_batch_wait() {
    let link = Link {
        offset_ns: 1000.0 * S,
        drift_ppm: -30.0,
        rate_hz: 100.0,
        seconds: 60.0,
        loss: 0.02,
        batch_ns: 1.05 * S,
        queue: quiet,
    };
    let frames = link.frames(11);
    let one = check_one_way(&frames);
    let fig = one.figures().unwrap();
    assert!(
        fig.max_ns > 0.95 * S && fig.max_ns < 1.1 * S,
        "{}",
        fig.max_ns
    );
}

#[test]
fn a_reboot_starts_a_new_baseline_and_bad_stamps_are_left_out() {
    let link = Link {
        offset_ns: 600.0 * S,
        drift_ppm: 50.0,
        rate_hz: 20.0,
        seconds: 40.0,
        loss: 0.0,
        batch_ns: 0.0,
        queue: quiet,
    };
    let mut frames = link.frames(5);
    // Rebooted at 25 s: its clock starts again from 0 (plus boot time).
    let reboot = frames.iter().position(|f| f.at > 25 * S as u64).unwrap();
    let at_reboot = frames[reboot].stamp_ns;
    for f in &mut frames[reboot..] {
        f.stamp_ns = f.stamp_ns - at_reboot + 3_000 * MS as i128;
    }
    let mut one = OneWay::default();
    for (i, f) in frames.iter().enumerate() {
        one.record(f.at, f.stamp_ns);
        // Two wild stamps (an hour ahead, a day behind), each alone.
        if i == 100 || i == 500 {
            one.record(f.at, f.stamp_ns + 3600 * S as i128);
            one.record(f.at + 1, f.stamp_ns - 86_400 * S as i128);
        }
    }
    let fig = one.figures().unwrap();
    assert_eq!(fig.restarts, 1);
    assert_eq!(fig.rejected, 4);
    assert!(fig.max_ns < 10.0 * MS, "{} ms", fig.max_ns / MS);
}

fn stamped(
    source: SysComp,
    msg: Msg,
    clock: StampClock,
    meaning: StampMeaning,
    value: u64,
) -> Frame {
    let mut frame = test_frame(source, msg);
    frame.stamps.message[0] = Some(Stamp {
        clock,
        meaning,
        value,
    });
    frame
}

/// A 32-bit ms clock wraps after 49.7 days: the ages go on, no reboot.
#[test]
fn the_ms_clock_wraps_without_a_restart() {
    let link = Link {
        offset_ns: 0.0,
        drift_ppm: 20.0,
        rate_hz: 50.0,
        seconds: 40.0,
        loss: 0.05,
        batch_ns: 0.0,
        queue: queue_down,
    };
    let source = SysComp::new(1, 1);
    let mut tracker = AgeTracker::default();
    let start_ms = (1u64 << 32) - 15_000;
    for f in link.frames(9) {
        let ms = (start_ms + (f.stamp_ns / MS as i128) as u64) & 0xFFFF_FFFF;
        let frame = stamped(
            source,
            Msg::Other,
            StampClock::BootMs,
            StampMeaning::Sent,
            ms,
        );
        tracker.on_frame(&frame, f.at);
        if f.at > 11 * S as u64 {
            let now = tracker.now(source).unwrap();
            assert!(
                close(now.age_ms * MS, f.above_ns),
                "{} vs {}",
                now.age_ms,
                f.above_ns / MS
            );
        }
    }
    let summary = tracker.summary();
    assert_eq!(summary.len(), 1);
    assert_eq!(summary[0].headline.restarts, 0);
    assert!(summary[0].headline.max_ms > 1450.0);
}

/// A source's send stamps speak for it, not its sample stamps.
#[test]
fn send_stamps_are_the_headline() {
    let source = SysComp::new(1, 1);
    let mut tracker = AgeTracker::default();
    for k in 0..200u64 {
        let at = 1_000_000_000 + k * 20_000_000;
        // Positions stamped with a fix time 150 ms older than the frame.
        let position = stamped(
            source,
            Msg::Other,
            StampClock::BootMs,
            StampMeaning::Sampled,
            5_000 + k * 20 - 150 * (k % 2),
        );
        let attitude = stamped(
            source,
            Msg::Other,
            StampClock::BootMs,
            StampMeaning::Sent,
            5_000 + k * 20,
        );
        // A sample time's age is the data's, not the link's: no frame
        // age (the window and histogram figures) from it.
        assert_eq!(tracker.on_frame(&position, at), None);
        tracker.on_frame(&attitude, at);
        assert_eq!(tracker.on_frame(&position, at), None);
    }
    let summary = tracker.summary();
    assert_eq!(summary[0].headline.meaning, StampMeaning::Sent);
    assert_eq!(summary[0].clocks.len(), 2);
    assert!(summary[0].headline.max_ms < 2.0);
    let sampled = summary[0].clocks[1];
    assert_eq!(sampled.meaning, StampMeaning::Sampled);
    assert!((sampled.max_ms - 150.0).abs() < 2.0, "{}", sampled.max_ms);
    assert_eq!(tracker.now(source).unwrap().meaning, StampMeaning::Sent);
    let json = serde_json::to_value(&summary[0]).unwrap();
    assert_eq!(json["headline"]["clock"], "boot_ms");
    assert!(json["headline"]["p99_ms"].is_number());
}

#[test]
fn memory_stays_bounded_over_a_million_stamps() {
    let mut one = OneWay::default();
    let mut rng = Rng(1);
    for k in 0..1_000_000u64 {
        // 100 Hz for 2.8 hours, drifting 100 ppm, jittering 5 ms.
        let at = k * 10_000_000 + (5.0 * MS * rng.next()) as u64;
        let stamp = i128::from(k * 10_000_000) * 1_000_100 / 1_000_000;
        one.record(at, stamp);
    }
    let fig = one.figures().unwrap();
    assert!(fig.stored_points <= MAX_BUCKETS, "{}", fig.stored_points);
    assert!(fig.max_ns < 10.0 * MS);
    assert_eq!(fig.samples, 1_000_000);

    let mut split = RoundTripSplit::default();
    for k in 0..200_000u64 {
        let t0 = k * 100_000_000;
        split.record(t0, i128::from(t0) + 5_000_000, t0 + 10_000_000);
    }
    assert!(split.stored_points() <= 2 * MAX_BUCKETS);
}

/// TIMESYNC exchanges at 10 Hz across a clock 2 h ahead drifting
/// ±100 ppm; one direction queues on a ramp.
fn split_run(
    up_queue: fn(f64) -> f64,
    down_queue: fn(f64) -> f64,
    drift_ppm: f64,
) -> (RoundTripSplit, f64, f64) {
    let mut rng = Rng(42);
    let mut split = RoundTripSplit::default();
    let (mut worst_up, mut worst_down) = (0.0f64, 0.0f64);
    for k in 0..600u64 {
        let t0 = 1.0 * S + k as f64 * 0.1 * S;
        let up = 15.0 * MS + 2.0 * MS * rng.next() + up_queue(t0);
        let reply = t0 + up;
        let down = 15.0 * MS + 2.0 * MS * rng.next() + down_queue(reply);
        let t3 = reply + down;
        let theirs = 7200.0 * S + reply * (1.0 + drift_ppm / 1e6);
        split.record(t0 as Nanos, theirs as i128, t3 as Nanos);
        if t0 > 11.0 * S {
            let now = split.now().unwrap();
            let (tu, td) = (up_queue(t0), down_queue(reply));
            worst_up = worst_up.max((now.uplink_ms * MS - tu).abs());
            worst_down = worst_down.max((now.downlink_ms * MS - td).abs());
        }
    }
    (split, worst_up / MS, worst_down / MS)
}

#[test]
fn the_split_puts_a_downlink_queue_on_the_downlink() {
    for drift in [100.0, -100.0] {
        let (split, up_err, down_err) = split_run(quiet, queue_down, drift);
        assert!(
            up_err < 10.0 && down_err < 10.0 + 0.05 * 1500.0,
            "{up_err} {down_err}"
        );
        let s = split.summary().unwrap();
        assert!((s.downlink_max_ms - 1500.0).abs() < 0.05 * 1500.0, "{s:?}");
        assert!(s.uplink_max_ms < 10.0, "{s:?}");
        assert!((s.drift_ppm.unwrap() - drift).abs() < 30.0, "{s:?}");
    }
}

#[test]
fn the_split_puts_an_uplink_queue_on_the_uplink() {
    for drift in [100.0, -100.0] {
        let (split, up_err, down_err) = split_run(queue_down, quiet, drift);
        assert!(
            down_err < 10.0 && up_err < 10.0 + 0.05 * 1500.0,
            "{up_err} {down_err}"
        );
        let s = split.summary().unwrap();
        assert!((s.uplink_max_ms - 1500.0).abs() < 0.05 * 1500.0, "{s:?}");
        assert!(s.downlink_max_ms < 10.0, "{s:?}");
    }
}

/// A queue that grows through the whole run is not mistaken for drift
/// when the other direction stays flat.
#[test]
fn the_split_keeps_a_queue_growing_all_run_apart_from_drift() {
    fn growing(s: f64) -> f64 {
        (s - 1.0 * S).max(0.0) * 0.02
    }
    let (split, _, _) = split_run(quiet, growing, 50.0);
    let s = split.summary().unwrap();
    assert!(s.downlink_max_ms > 1100.0, "{s:?}");
    assert!(s.uplink_max_ms < 10.0, "{s:?}");
}

#[test]
fn absolute_age_carries_the_offset_bounds() {
    // Their clock is ours + 2 h; the offset known to ±3 ms, no drift.
    let offset = 7200 * S as i128;
    let clock = ClockSummary {
        offset_ns: offset + 1_000_000,
        uncertainty_ns: 3_000_000,
        bounds_ns: Some((offset - 2_000_000, offset + 4_000_000)),
        bounds_drift_limit_ppm: 200,
        spread_ns: 0.0,
        drift_ppm: None,
        drift_stderr_ppm: None,
        samples: 10,
    };
    let base = 1_700_000_000 * S as i128;
    // Sent at our time 10 s, received 80 ms later.
    let sent = 10 * S as i128;
    let stamp = base + offset + sent;
    let a = absolute_age(sent as Nanos + 80_000_000, stamp, &clock, base);
    assert_eq!(a.age_ns, 81_000_000);
    let (lower, upper) = (a.lower_ns.unwrap(), a.upper_ns.unwrap());
    assert!(lower <= 80_000_000 && 80_000_000 <= upper, "{a:?}");
    // 200 ppm over 10.08 s widens each side by about 2 ms.
    assert!(upper - lower < 11_000_000, "{a:?}");
}

/// The queue hint needs a send stamp on a clock that keeps time, frames
/// held late many in a row, and next to no loss.
#[test]
fn the_queue_hint_takes_a_real_clock_a_sustained_delay_and_no_loss() {
    let figures = |clock, meaning, p90_ms, max_ms| ClockAgeSummary {
        clock,
        meaning,
        samples: 400,
        p50_ms: 0.0,
        p90_ms,
        p99_ms: max_ms,
        max_ms,
        drift_ppm: None,
        restarts: 0,
        rejected: 0,
        baseline_error_ms: 0.0,
    };
    let age = |h| SourceAge {
        source: SysComp::new(1, 1),
        headline: h,
        clocks: vec![h],
        absolute: None,
    };
    let queue = age(figures(
        StampClock::BootMs,
        StampMeaning::Sent,
        900.0,
        1500.0,
    ));
    let hint = queue_building(&queue, 400, 4).expect("a queue");
    assert_eq!(hint.code, HintCode::QueueBuilding);
    assert!(hint.text.contains("up to 1.50 s") && hint.text.contains("lost 4 of 404"));
    // More than 1 % lost: a link that drops, not only queues.
    assert!(queue_building(&queue, 400, 5).is_none());
    // A spike (one frame in ten not late), a sample time, a signature.
    for other in [
        figures(StampClock::BootMs, StampMeaning::Sent, 20.0, 1500.0),
        figures(StampClock::BootMs, StampMeaning::Sampled, 900.0, 1500.0),
        figures(StampClock::Signature, StampMeaning::Sent, 900.0, 1500.0),
    ] {
        assert!(queue_building(&age(other), 400, 0).is_none(), "{other:?}");
    }
}

/// Each frame's age is counted once, under the first bound at or above
/// it, for the source that sent it.
#[test]
fn frames_ages_are_counted_per_source_under_their_bounds() {
    let mut counts = AgeCounts::default();
    for age in [0.5, 1.0, 1.5, 300.0, 20_000.0] {
        counts.record(age);
    }
    assert_eq!(counts.buckets, [2, 1, 0, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]);
    assert_eq!((counts.count, counts.sum_ms), (5, 20_303.0));
}

/// The window's max is its oldest frame's age, and the next window
/// starts afresh: a queue's peak between two tellings shows even when
/// the newest frame is quick again.
#[test]
fn the_window_max_is_the_oldest_frame_since_the_last_telling() {
    let source = SysComp::new(1, 1);
    let mut tracker = AgeTracker::default();
    let frame = |k: u64| {
        stamped(
            source,
            Msg::Other,
            StampClock::BootMs,
            StampMeaning::Sent,
            k * 20,
        )
    };
    // 50 frames on time, one held 300 ms, 50 more on time.
    for k in 0..101u64 {
        let held = if k == 50 { 300_000_000 } else { 0 };
        tracker.on_frame(&frame(k), k * 20_000_000 + held);
    }
    let window = tracker.take_window_max();
    assert_eq!(window.len(), 1);
    assert!((window[0].1 - 300.0).abs() < 1.0, "{window:?}");
    assert!(tracker.now(source).unwrap().age_ms < 1.0);
    assert!(tracker.take_window_max().is_empty());
    tracker.on_frame(&frame(101), 101 * 20_000_000);
    assert!(tracker.take_window_max()[0].1 < 1.0);
}

/// The baseline placed by the TIMESYNC offset is the link's one-way
/// delay, within the offset's bounds; stamps on another clock than
/// `tc1`'s place it nowhere a link can be, and get no absolute figures.
#[test]
fn the_absolute_age_is_the_baseline_placed_by_the_clock_offset() {
    let source = SysComp::new(1, 1);
    // Their boot clock reads our session time + 1 h; the link
    // is 20 ms one way, and a queue of up to 300 ms builds at 10 s.
    let base = 1_700_000_000 * S as i128;
    let offset = -base + 3600 * S as i128;
    let clock = ClockSummary {
        offset_ns: offset + 2_000_000,
        uncertainty_ns: 20_000_000,
        bounds_ns: Some((offset - 18_000_000, offset + 22_000_000)),
        bounds_drift_limit_ppm: 200,
        spread_ns: 0.0,
        drift_ppm: None,
        drift_stderr_ppm: None,
        samples: 20,
    };
    let mut boot = AgeTracker::default();
    let mut unix = AgeTracker::default();
    for k in 0..1000u64 {
        let sent = 1_000_000_000 + k * 20_000_000;
        let queue = if (500..600).contains(&k) {
            300_000_000
        } else {
            0
        };
        let at = sent + 20_000_000 + queue;
        let ms = ((i128::from(sent) + base + offset) / 1_000_000) as u64;
        let stamp = |clock, value| stamped(source, Msg::Other, clock, StampMeaning::Sent, value);
        boot.on_frame(&stamp(StampClock::BootMs, ms), at);
        unix.on_frame(
            &stamp(StampClock::UnixUs, (sent / 1_000) + 1_600_000_000_000_000),
            at,
        );
    }
    let age = &boot.summary()[0];
    let abs = boot.absolute(age, &clock, base).expect("on tc1's clock");
    // ms stamps read up to 1 ms early: the baseline is 20 to 21 ms.
    assert!((abs.baseline_ms - 22.0).abs() <= 1.0, "{abs:?}");
    assert!(
        abs.baseline_lower_ms <= 20.0 && 21.0 <= abs.baseline_upper_ms,
        "{abs:?}"
    );
    assert!((abs.max_ms - 322.0).abs() <= 2.0, "{abs:?}");
    let json = serde_json::to_value(abs).unwrap();
    assert!(json["baseline_upper_ms"].is_number());
    let other = &unix.summary()[0];
    assert_eq!(unix.absolute(other, &clock, base), None);
    let unbounded = ClockSummary {
        bounds_ns: None,
        ..clock
    };
    assert_eq!(boot.absolute(age, &unbounded, base), None);
}

/// Clocks that rank alike (boot ms and boot µs) come in one order every
/// run, not the hash map's.
#[test]
fn clocks_of_equal_rank_are_listed_in_one_order() {
    let source = SysComp::new(1, 1);
    for seed in 0..8u64 {
        let mut tracker = AgeTracker::default();
        for k in 0..20u64 {
            let at = 1_000_000_000 + k * 20_000_000 + seed;
            let ms = stamped(
                source,
                Msg::Other,
                StampClock::BootMs,
                StampMeaning::Sent,
                k * 20,
            );
            let us = stamped(
                source,
                Msg::Other,
                StampClock::BootUs,
                StampMeaning::Sent,
                k * 20_000,
            );
            tracker.on_frame(&us, at);
            tracker.on_frame(&ms, at);
        }
        let clocks: Vec<StampClock> = tracker.summary()[0]
            .clocks
            .iter()
            .map(|c| c.clock)
            .collect();
        assert_eq!(clocks, [StampClock::BootMs, StampClock::BootUs]);
    }
}
