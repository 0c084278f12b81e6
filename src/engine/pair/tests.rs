//! The pair against truth the tests control: a simulated vehicle sending
//! numbered frames on several links with known drops and delays, and
//! constructed cases for each rule.

use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};

use super::seq::SeqCount;
use super::*;
use crate::frame::{test_frame, Msg};

const MS: Nanos = 1_000_000;
const VEHICLE: SysComp = SysComp::new(1, 1);
const HEARTBEAT: u32 = 0;
const ATTITUDE: u32 = 30;

fn frame(source: SysComp, seq: u8, msgid: u32, crc: u16) -> Frame {
    let mut f = test_frame(source, Msg::Other);
    f.packet_seq = seq;
    f.msgid = msgid;
    f.crc = crc;
    f
}

/// The vehicle's frame `i`: a HEARTBEAT every tenth, whose bytes (and so
/// CRC) depend on its sequence number only, so it recurs every 256
/// frames; ATTITUDEs between, each with a CRC of its own.
fn vehicle_frame(i: usize) -> Frame {
    let seq = i as u8;
    if i.is_multiple_of(10) {
        frame(VEHICLE, seq, HEARTBEAT, 0xBE00 ^ u16::from(seq))
    } else {
        let crc = (i as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 48;
        frame(VEHICLE, seq, ATTITUDE, crc as u16)
    }
}

fn pair(tracker: &PairTracker, at: Nanos) -> SourcePair {
    let summary = tracker.summary(at);
    assert_eq!(summary.sources.len(), 1, "{summary:?}");
    summary.sources[0].clone()
}

/// A link of the simulated vehicle: each frame delayed by `delay` plus
/// up to `jitter`, dropped `drop_pct` % of the time.
#[derive(Clone, Copy)]
struct Path {
    delay: Nanos,
    jitter: Nanos,
    drop_pct: f64,
}

/// The vehicle's `n` frames, one every `period`, on each path: when each
/// arrived on each link (the first and last on every link, so each link's
/// own count spans them all).
fn simulate(n: usize, period: Nanos, paths: &[Path], seed: u64) -> Vec<Vec<Option<Nanos>>> {
    let mut rng = StdRng::seed_from_u64(seed);
    (0..n)
        .map(|i| {
            let sent = i as u64 * period;
            paths
                .iter()
                .map(|p| {
                    let kept = i == 0 || i + 1 == n || !rng.gen_bool(p.drop_pct / 100.0);
                    let jitter = rng.gen_range(0..=p.jitter);
                    kept.then_some(sent + p.delay + jitter)
                })
                .collect()
        })
        .collect()
}

/// Every arrival in the order the links delivered them: (at, link, frame).
fn arrivals(truth: &[Vec<Option<Nanos>>]) -> Vec<(Nanos, usize, usize)> {
    let mut events: Vec<_> = truth
        .iter()
        .enumerate()
        .flat_map(|(i, links)| {
            links
                .iter()
                .enumerate()
                .filter_map(move |(l, at)| at.map(|at| (at, l, i)))
        })
        .collect();
    events.sort_unstable();
    events
}

/// What each link's figures must be, counted from the truth.
#[derive(Debug, Default)]
struct Expected {
    frames: u64,
    first: u64,
    only: u64,
    stale: u64,
    stale_first: u64,
    lags: Vec<Nanos>,
}

/// The nearest-rank quantile of sorted `v`, in ms.
fn rank_ms(v: &[Nanos], q: f64) -> f64 {
    let rank = ((q * v.len() as f64).ceil() as usize).clamp(1, v.len());
    v[rank - 1] as f64 / 1e6
}

fn expected(truth: &[Vec<Option<Nanos>>], links: usize) -> (Vec<Expected>, Vec<Nanos>) {
    let mut per_link: Vec<Expected> = (0..links).map(|_| Expected::default()).collect();
    let mut copy_lags = Vec::new();
    for frame in truth {
        let heard: Vec<(Nanos, usize)> = (0..links)
            .filter_map(|l| frame[l].map(|at| (at, l)))
            .collect();
        let Some(&(first_at, first)) = heard.iter().min() else {
            continue;
        };
        per_link[first].first += 1;
        if heard.len() == 1 {
            per_link[first].only += 1;
        }
        for &(at, l) in &heard {
            per_link[l].frames += 1;
            if heard.len() > 1 {
                per_link[l].lags.push(at - first_at);
            }
            if l != first {
                copy_lags.push(at - first_at);
            }
        }
    }
    let mut newest: Vec<Option<usize>> = vec![None; links];
    let mut seen = vec![false; truth.len()];
    for (_, l, i) in arrivals(truth) {
        let others = (0..links)
            .filter(|&o| o != l)
            .filter_map(|o| newest[o])
            .max();
        if others.is_some_and(|n| i < n) {
            per_link[l].stale += 1;
            per_link[l].stale_first += u64::from(!seen[i]);
        }
        seen[i] = true;
        newest[l] = Some(newest[l].map_or(i, |n| n.max(i)));
    }
    for e in &mut per_link {
        e.lags.sort_unstable();
    }
    copy_lags.sort_unstable();
    (per_link, copy_lags)
}

fn close(got: Option<f64>, want: f64, what: &str) {
    let got = got.unwrap_or_else(|| panic!("{what}: none"));
    assert!(
        (got - want).abs() <= 1.0,
        "{what}: {got} ms, truth {want} ms"
    );
}

/// Runs the simulated vehicle over `paths` and holds every figure to the
/// truth: counts exact, lags within 1 ms.
fn check_against_truth(n: usize, period: Nanos, paths: &[Path], seed: u64) {
    let truth = simulate(n, period, paths, seed);
    let mut tracker = PairTracker::new(paths.len(), PairConfig::default());
    let events = arrivals(&truth);
    for &(at, link, i) in &events {
        tracker.on_frame(link, &vehicle_frame(i), at);
    }
    let end = events.last().unwrap().0 + DEFAULT_WINDOW + 1;
    let got = pair(&tracker, end);
    let (want, copy_lags) = expected(&truth, paths.len());
    let union = truth
        .iter()
        .filter(|f| f.iter().any(Option::is_some))
        .count() as u64;
    assert_eq!(got.distinct_frames, union);
    assert_eq!(got.lost_on_every_link, n as u64 - union);
    assert_eq!(got.copies, copy_lags.len() as u64);
    assert_eq!((got.late_beyond_window, got.conflicts), (0, 0));
    let links: &[LinkPair] = &got.links;
    assert_eq!(links.len(), paths.len());
    for (l, (link, e)) in links.iter().zip(&want).enumerate() {
        let what = format!("seed {seed} link {l}");
        assert_eq!(link.link, l);
        assert_eq!(link.frames, e.frames, "{what}");
        assert_eq!(link.first, e.first, "{what}");
        assert_eq!(link.only, e.only, "{what}");
        assert_eq!(link.only_undecided, 0, "{what}");
        assert_eq!(link.lost, n as u64 - e.frames, "{what}");
        assert_eq!(
            (link.stale, link.stale_first),
            (e.stale, e.stale_first),
            "{what}"
        );
        assert_eq!((link.damaged, link.duplicates), (0, 0));
        close(link.lag_p50_ms, rank_ms(&e.lags, 0.5), &what);
        close(link.lag_p99_ms, rank_ms(&e.lags, 0.99), &what);
        close(link.lag_max_ms, rank_ms(&e.lags, 1.0), &what);
    }
    close(
        got.dedup_window_p999_ms,
        rank_ms(&copy_lags, 0.999),
        "p99.9",
    );
    close(got.copy_lag_max_ms, rank_ms(&copy_lags, 1.0), "max");
}

/// The case: one link losing 10 % at 20 ms, the other 2 % at
/// 100 ms (first only where the fast one dropped), with jitter that
/// reorders the slow one.
#[test]
fn two_links_match_the_truth_exactly() {
    let fast = Path {
        delay: 20 * MS,
        jitter: 10 * MS,
        drop_pct: 10.0,
    };
    let slow = Path {
        delay: 100 * MS,
        jitter: 90 * MS,
        drop_pct: 2.0,
    };
    for seed in 1..=4 {
        check_against_truth(3_000, 20 * MS, &[fast, slow], seed);
    }
}

/// Three links, each sometimes first; a fast source (2 ms apart) whose
/// lags span dozens of sequence numbers.
#[test]
fn three_links_match_the_truth_exactly() {
    let paths = [
        Path {
            delay: 5 * MS,
            jitter: 30 * MS,
            drop_pct: 20.0,
        },
        Path {
            delay: 15 * MS,
            jitter: 20 * MS,
            drop_pct: 5.0,
        },
        Path {
            delay: 60 * MS,
            jitter: 40 * MS,
            drop_pct: 30.0,
        },
    ];
    check_against_truth(20_000, 2 * MS, &paths, 7);
}

/// The same figures hold on the truth's side: the drops made are the
/// drops counted (a simulation that dropped nothing would pass above).
#[test]
fn the_simulation_drops_and_reorders() {
    let fast = Path {
        delay: 20 * MS,
        jitter: 10 * MS,
        drop_pct: 10.0,
    };
    let slow = Path {
        delay: 100 * MS,
        jitter: 90 * MS,
        drop_pct: 2.0,
    };
    let truth = simulate(3_000, 20 * MS, &[fast, slow], 1);
    let (want, _) = expected(&truth, 2);
    assert!(want[0].only > 0 && want[1].only > 0);
    assert!(want[0].first > 0 && want[1].first > 0);
    assert!(want[1].stale > 0 && want[0].stale_first + want[1].stale_first > 0);
    assert!(truth.iter().any(|f| f.iter().all(Option::is_none)));
}

/// A HEARTBEAT with the same bytes recurs with the same sequence number
/// and CRC every 256 frames: the one link B alone delivered is a new
/// frame, not a copy of the one 256 earlier, though both are in the
/// window.
#[test]
fn a_recurring_heartbeat_is_not_a_copy() {
    let heartbeat = |i: usize| frame(VEHICLE, i as u8, HEARTBEAT, 0xBE00);
    let mut events = Vec::new();
    for i in 0..600 {
        let sent = i as u64 * 10 * MS;
        if i != 256 {
            events.push((sent + 20 * MS, 0, i));
        }
        if i == 0 || i == 256 {
            events.push((sent + 500 * MS, 1, i));
        }
    }
    events.sort_unstable();
    let mut tracker = PairTracker::new(2, PairConfig::default());
    for &(at, link, i) in &events {
        tracker.on_frame(link, &heartbeat(i), at);
    }
    const {
        assert!(
            256 * 10 * MS + 480 * MS < DEFAULT_WINDOW,
            "within the window"
        )
    };
    let got = pair(&tracker, 10_000 * MS);
    assert_eq!((got.distinct_frames, got.copies), (600, 1));
    assert_eq!((got.lost_on_every_link, got.conflicts), (0, 0));
    let b = &got.links[1];
    assert_eq!((b.frames, b.first, b.only), (2, 1, 1));
    assert_eq!(b.lag_max_ms, Some(480.0));
    // Both came behind newer numbers link A had delivered; the second was
    // a first copy, so it jumps back even behind de-duplication.
    assert_eq!((b.stale, b.stale_first), (2, 1));
    assert_eq!((got.links[0].lost, got.links[0].only), (1, 598));
}

/// Copies behind a newer number another link delivered are stale; a
/// first copy behind one is stale first.
#[test]
fn stale_copies_are_counted_exactly() {
    let mut tracker = PairTracker::new(2, PairConfig::default());
    let steps: [(usize, u8, Nanos); 12] = [
        (0, 1, 10),
        (0, 2, 20),
        (0, 3, 30),
        (0, 4, 40),
        (1, 2, 45), // stale: A has 4
        (1, 5, 50), // new, not stale
        (0, 5, 55), // copy, B's newest is 5: not behind
        (1, 4, 60), // stale: A has 5
        (0, 6, 70),
        (1, 3, 80), // stale: A has 6
        (1, 8, 90), // new
        (0, 7, 95), // first copy behind B's 8: stale first
    ];
    for (link, seq, ms) in steps {
        tracker.on_frame(link, &vehicle_frame(usize::from(seq)), ms * MS);
    }
    let got = pair(&tracker, 100 * MS);
    let (a, b) = (&got.links[0], &got.links[1]);
    assert_eq!((a.stale, a.stale_first), (1, 1));
    assert_eq!((b.stale, b.stale_first), (3, 0));
    assert_eq!((got.distinct_frames, got.copies), (8, 4));
    assert_eq!((a.first, b.first), (6, 2));
}

/// A source heard on one link only is listed apart, with nothing paired.
#[test]
fn a_source_on_one_link_is_listed_apart() {
    let gimbal = SysComp::new(1, 154);
    let mut tracker = PairTracker::new(2, PairConfig::default());
    for i in 0..10 {
        let at = i as u64 * 20 * MS;
        tracker.on_frame(0, &vehicle_frame(i), at);
        tracker.on_frame(1, &vehicle_frame(i), at + MS);
        tracker.on_frame(1, &frame(gimbal, i as u8, ATTITUDE, i as u16), at);
    }
    let summary = tracker.summary(300 * MS);
    assert_eq!(summary.sources.len(), 1);
    assert_eq!(summary.sources[0].source, VEHICLE);
    assert_eq!(
        summary.single_link_sources,
        vec![SingleLinkSource {
            source: gimbal,
            link: 1,
            frames: 10,
            damaged: 0,
        }]
    );
}

/// A damaged frame's number arrived, on its link and the pair's, but it
/// is never new, first or a copy.
#[test]
fn damaged_frames_are_counted_apart() {
    let mut tracker = PairTracker::new(2, PairConfig::default());
    for i in 0..10 {
        let at = i as u64 * 20 * MS;
        if i != 5 {
            tracker.on_frame(0, &vehicle_frame(i), at);
        }
        let mut f = vehicle_frame(i);
        if i == 5 {
            f.msg = Msg::Damaged;
        }
        tracker.on_frame(1, &f, at + MS);
    }
    let got = pair(&tracker, 300 * MS);
    assert_eq!((got.distinct_frames, got.copies), (9, 9));
    assert_eq!(got.lost_on_every_link, 0);
    let (a, b) = (&got.links[0], &got.links[1]);
    assert_eq!((a.frames, a.lost, a.first), (9, 1, 9));
    assert_eq!(
        (b.frames, b.damaged, b.lost, b.first, b.only),
        (9, 1, 0, 0, 0)
    );
}

/// The same frame again on its link is a duplicate; another frame under a
/// number in use, a conflict; the same frame after the window, late.
#[test]
fn duplicates_conflicts_and_late_copies_are_neither_new_nor_copies() {
    let config = PairConfig {
        window: 1_000 * MS,
        ..PairConfig::default()
    };
    let mut tracker = PairTracker::new(2, config);
    tracker.on_frame(0, &frame(VEHICLE, 1, ATTITUDE, 7), 0);
    tracker.on_frame(0, &frame(VEHICLE, 1, ATTITUDE, 7), MS);
    tracker.on_frame(1, &frame(VEHICLE, 1, ATTITUDE, 8), 2 * MS);
    tracker.on_frame(0, &frame(VEHICLE, 2, ATTITUDE, 9), 10 * MS);
    tracker.on_frame(1, &frame(VEHICLE, 2, ATTITUDE, 9), 1_011 * MS);
    // Two copies: more than the conflicts, so one vehicle on two links.
    for seq in [3, 4] {
        let at = 1_100 * MS + u64::from(seq) * MS;
        tracker.on_frame(0, &frame(VEHICLE, seq, ATTITUDE, 10), at);
        tracker.on_frame(1, &frame(VEHICLE, seq, ATTITUDE, 10), at + MS);
    }
    let got = pair(&tracker, 3_000 * MS);
    assert_eq!((got.distinct_frames, got.copies), (4, 2));
    assert_eq!((got.conflicts, got.late_beyond_window), (1, 1));
    let (a, b) = (&got.links[0], &got.links[1]);
    assert_eq!((a.frames, a.duplicates, a.first, a.only), (5, 1, 4, 2));
    assert_eq!((b.frames, b.first, b.only), (4, 0, 0));
    assert_eq!(b.lag_max_ms, Some(1.0));
}

/// Two senders under one id, each on its own link, whose frames are
/// alike now and then (two simulated vehicles): as many frames under a
/// number in use as copies, so no pair, but a source said apart.
#[test]
fn as_many_conflicts_as_copies_are_two_senders_not_one_vehicle() {
    let mut tracker = PairTracker::new(2, PairConfig::default());
    for seq in 0..10u8 {
        let at = u64::from(seq) * 20 * MS;
        // Their HEARTBEATs alike, every fifth frame; the rest differ.
        let (a, b) = if seq % 5 == 0 { (1, 1) } else { (2, 3) };
        tracker.on_frame(0, &frame(VEHICLE, seq, ATTITUDE, a), at);
        tracker.on_frame(1, &frame(VEHICLE, seq, ATTITUDE, b), at + MS);
    }
    let summary = tracker.summary(Nanos::MAX);
    assert!(summary.sources.is_empty(), "{summary:?}");
    assert_eq!(summary.conflicting_sources, [VEHICLE]);
}

/// Frames one link alone delivered stay undecided while a copy may still
/// come, and are decided once the window closes.
#[test]
fn only_one_link_is_decided_when_the_window_closes() {
    let mut tracker = PairTracker::new(2, PairConfig::default());
    for i in 0..5 {
        let at = i as u64 * 20 * MS;
        tracker.on_frame(0, &vehicle_frame(i), at);
        if i < 3 {
            tracker.on_frame(1, &vehicle_frame(i), at + 30 * MS);
        }
    }
    let soon = pair(&tracker, 100 * MS);
    assert_eq!((soon.links[0].only, soon.links[0].only_undecided), (2, 2));
    let later = pair(&tracker, 80 * MS + DEFAULT_WINDOW + 1);
    assert_eq!((later.links[0].only, later.links[0].only_undecided), (2, 0));
    assert_eq!(later.links[0].lag_max_ms, Some(0.0));
    assert_eq!(later.links[1].lag_p50_ms, Some(30.0));
}

/// Frames of links and sources beyond the tracker's are counted, not
/// matched.
#[test]
fn links_and_sources_beyond_the_caps_are_counted() {
    let config = PairConfig {
        max_sources: 2,
        ..PairConfig::default()
    };
    let mut tracker = PairTracker::new(2, config);
    for sysid in 1..=4 {
        tracker.on_frame(0, &frame(SysComp::new(sysid, 1), 0, ATTITUDE, 1), 0);
    }
    tracker.on_frame(2, &vehicle_frame(1), MS);
    tracker.on_frame(usize::MAX, &vehicle_frame(1), MS);
    let summary = tracker.summary(MS);
    assert_eq!(summary.untracked_frames, 4);
    assert_eq!(summary.single_link_sources.len(), 2);
}

/// A million frames: a vehicle on two links and a flood of sources and
/// numbers no ring or map may grow with.
#[test]
fn a_million_frames_keep_memory_bounded() {
    let mut tracker = PairTracker::new(2, PairConfig::default());
    let mut rng = StdRng::seed_from_u64(3);
    let mut at = 0;
    let mut step = 0;
    let mut feed = |tracker: &mut PairTracker, steps: usize| {
        for i in step..step + steps {
            at += 100_000;
            // Each vehicle frame on link 0, then on link 1.
            tracker.on_frame(i % 2, &vehicle_frame(i / 2), at);
            // Never the vehicle's ids: its counts stay exact.
            let source = SysComp::new(rng.gen_range(2..=255), rng.gen());
            let flood = frame(source, rng.gen(), rng.gen_range(0..300), rng.gen());
            tracker.on_frame(rng.gen_range(0..2), &flood, at);
        }
        step += steps;
    };
    feed(&mut tracker, 50_000);
    let early = tracker.bytes();
    feed(&mut tracker, 450_000);
    assert_eq!(tracker.bytes(), early);
    assert_eq!(tracker.sources.len(), DEFAULT_MAX_SOURCES);
    assert!(early < 4 << 20, "{early} bytes");
    let summary = tracker.summary(at);
    assert!(summary.untracked_frames > 400_000);
    let vehicle = summary
        .sources
        .iter()
        .find(|s| s.source == VEHICLE)
        .unwrap();
    assert_eq!(
        (vehicle.distinct_frames, vehicle.copies),
        (250_000, 250_000)
    );
    assert_eq!(vehicle.lost_on_every_link, 0);
}

/// The light sequence count: gaps lost, late frames fill them, a frame
/// behind the first fills the numbers between as lost, wraps unwrap.
#[test]
fn the_sequence_count_fills_gaps_and_unwraps() {
    let mut count = SeqCount::default();
    for seq in [10u8, 11, 14, 12, 11, 8] {
        count.take(seq);
    }
    // 10..=14 and 8: 13 lost, 9 lost (behind the first), 11 again.
    assert_eq!((count.lost(), count.numbers()), (2, 7));
    let first = count.line(10);
    for seq in (15..=255).chain(0..=20) {
        count.take(seq);
    }
    assert_eq!(count.lost(), 2);
    assert_eq!(count.line(10), first + 256);
    assert_eq!(count.head(), Some(first + 256 + 10));
    assert_eq!(count.line(200), first + 190, "76 behind the head");
}

/// Frames as the codec decodes them: the same bytes on two links are one
/// frame; a HEARTBEAT's bytes do recur 256 frames later, which is why the
/// sequence rule is there.
#[test]
fn decoded_frames_pair_by_their_wire_crc() {
    use crate::frame::{decode, encode, Header, Version};
    let wire = |i: usize, msg: &Msg| {
        let mut bytes = Vec::new();
        let header = Header {
            sysid: 1,
            compid: 1,
            seq: i as u8,
        };
        encode(&mut bytes, Version::V2, header, msg);
        decode(&bytes)
    };
    let heartbeat = Msg::Heartbeat {
        mav_type: 2,
        autopilot: 3,
    };
    let attitude = |i: usize| Msg::Attitude {
        time_boot_ms: i as u32 * 10,
    };
    assert_eq!(wire(3, &heartbeat), wire(259, &heartbeat));
    assert_ne!(wire(3, &attitude(3)).crc, wire(259, &attitude(259)).crc);
    let mut tracker = PairTracker::new(2, PairConfig::default());
    for i in 0..600 {
        let msg = if i % 5 == 0 { heartbeat } else { attitude(i) };
        let at = i as u64 * 10 * MS;
        tracker.on_frame(0, &wire(i, &msg), at);
        if i % 3 != 0 {
            tracker.on_frame(1, &wire(i, &msg), at + 7 * MS);
        }
    }
    let got = pair(&tracker, 7_000 * MS);
    assert_eq!((got.distinct_frames, got.copies), (600, 400));
    assert_eq!(
        (got.links[0].only, got.links[1].lag_max_ms),
        (200, Some(7.0))
    );
}

/// The summary's JSON names carry their units.
#[test]
fn the_summary_serialises_with_units_in_its_names() {
    let mut tracker = PairTracker::new(2, PairConfig::default());
    tracker.on_frame(0, &vehicle_frame(1), 0);
    tracker.on_frame(1, &vehicle_frame(1), 5 * MS);
    let json = serde_json::to_value(tracker.summary(10 * MS)).unwrap();
    assert_eq!(json["window_ms"], 5000.0);
    let source = &json["sources"][0];
    assert_eq!(source["source"]["sysid"], 1);
    assert_eq!(source["dedup_window_p999_ms"], 5.0);
    let link = &source["links"][1];
    assert_eq!(link["lag_max_ms"], 5.0);
    assert_eq!(link["first_pct"], 0.0);
    assert_eq!(source["links"][0]["first_pct"], 100.0);
}

/// A source whose frames two links split between them, none on both (a
/// router balancing; a log's clock bits read as links), is no pair.
#[test]
fn a_source_split_between_links_is_uncopied_not_a_pair() {
    let mut tracker = PairTracker::new(2, PairConfig::default());
    for i in 0..100 {
        tracker.on_frame(i % 2, &vehicle_frame(i), i as u64 * 20 * MS);
    }
    let summary = tracker.summary(Nanos::MAX);
    assert!(summary.sources.is_empty(), "{summary:?}");
    assert_eq!(summary.uncopied_sources, [VEHICLE]);
}

/// Links are read in turns (two logs' batches): the slow link's frames
/// may be taken before the fast link's earlier copies. The first copy is
/// the one that came first, and the lags are measured from it, whatever
/// the order they were taken in.
#[test]
fn the_first_copy_is_the_earliest_whatever_order_they_are_taken_in() {
    let mut tracker = PairTracker::new(2, PairConfig::default());
    // Batches of 10 frames, the slow link's (30 ms later) taken first.
    for batch in 0..10 {
        let frames = batch * 10..batch * 10 + 10;
        for i in frames.clone() {
            tracker.on_frame(1, &vehicle_frame(i), i as u64 * 20 * MS + 30 * MS);
        }
        for i in frames {
            tracker.on_frame(0, &vehicle_frame(i), i as u64 * 20 * MS);
        }
    }
    let got = pair(&tracker, Nanos::MAX);
    let (fast, slow) = (&got.links[0], &got.links[1]);
    assert_eq!((fast.first, slow.first), (100, 0), "{got:?}");
    assert_eq!(fast.lag_max_ms, Some(0.0));
    assert_eq!((slow.lag_p50_ms, slow.lag_max_ms), (Some(30.0), Some(30.0)));
    // The slow link's frames came after the fast link's newer ones (30 ms
    // behind, a frame every 20 ms), though taken before them; the fast
    // link's never did.
    assert_eq!(fast.stale, 0, "{got:?}");
    assert_eq!(slow.stale, 99, "{got:?}");
}
