//! Property tests of the frame scanner and the matcher (the same code the
//! fuzz targets in fuzz/ exercise), run on every `cargo test`.

use std::collections::{HashMap, HashSet};

use crate::common::frame_oracle::{good_frames, isolated};
use mavlink::dialects::ardupilotmega::MavMessage;
use mavlink::Message;
use mavping::engine::matcher::{Lookup, MatchEvent, Matcher};
use mavping::frame::scanner::{MAX_FRAME_LEN, MAX_PENDING};
use mavping::frame::{
    encode, scan_datagram, scan_datagram_all, Header, Msg, ScanStats, StreamScanner, SysComp,
    Version,
};
use proptest::prelude::*;

// ---------------------------------------------------------------- scanner

#[derive(Debug, Clone, Copy)]
enum Kind {
    V1,
    V2,
    Signed,
}

/// A byte that is a start byte more often than chance: frames whose
/// payload holds start bytes are where junk can line up inside them.
fn stx_rich_byte() -> impl Strategy<Value = u8> {
    prop_oneof![4 => any::<u8>(), 1 => Just(0xFD), 1 => Just(0xFE)]
}

fn message() -> impl Strategy<Value = Msg> {
    prop_oneof![
        (
            prop::array::uniform8(stx_rich_byte()),
            prop::array::uniform4(stx_rich_byte()),
            any::<u8>(),
            any::<u8>()
        )
            .prop_map(|(t, s, ts, tc)| Msg::Ping {
                time_usec: u64::from_le_bytes(t),
                seq: u32::from_le_bytes(s),
                target_system: ts,
                target_component: tc,
            }),
        (any::<i64>(), any::<i64>()).prop_map(|(tc1, ts1)| Msg::Timesync {
            tc1,
            ts1,
            target_system: 0,
            target_component: 0,
        }),
        (any::<u8>(), any::<u8>()).prop_map(|(mav_type, autopilot)| Msg::Heartbeat {
            mav_type,
            autopilot
        }),
    ]
}

/// A real frame: v1, v2, or v2 with the signed flag and a 13-byte
/// signature (the scanner checks the CRC, which covers the flag; the
/// signature itself is checked elsewhere).
fn frame() -> impl Strategy<Value = Vec<u8>> {
    (
        prop_oneof![Just(Kind::V1), Just(Kind::V2), Just(Kind::Signed)],
        message(),
        any::<(u8, u8, u8)>(),
        any::<[u8; 13]>(),
    )
        .prop_map(|(kind, msg, (sysid, compid, seq), signature)| {
            let version = if matches!(kind, Kind::V1) {
                Version::V1
            } else {
                Version::V2
            };
            let mut out = Vec::new();
            encode(&mut out, version, Header { sysid, compid, seq }, &msg);
            if matches!(kind, Kind::Signed) {
                out[2] |= 0x01;
                let end = 10 + usize::from(out[1]);
                let msgid = u32::from_le_bytes([out[7], out[8], out[9], 0]);
                let crc = mavlink::calculate_crc(&out[1..end], MavMessage::extra_crc(msgid));
                out[end..end + 2].copy_from_slice(&crc.to_le_bytes());
                out.extend_from_slice(&signature);
            }
            out
        })
}

/// Junk that holds no start byte, so it can never begin a frame.
fn clean_junk() -> impl Strategy<Value = Vec<u8>> {
    prop::collection::vec(
        any::<u8>().prop_filter("no STX", |b| *b != 0xFD && *b != 0xFE),
        0..40,
    )
}

/// Arbitrary junk, rich in start bytes and plausible lengths.
fn hostile_junk() -> impl Strategy<Value = Vec<u8>> {
    prop::collection::vec(
        prop_oneof![3 => any::<u8>(), 1 => Just(0xFD), 1 => Just(0xFE), 1 => Just(0x00), 1 => Just(0xFF)],
        0..60,
    )
}

/// Read sizes, cycled; 0 stands for an empty read then a 1-byte one.
fn splits() -> impl Strategy<Value = Vec<usize>> {
    prop::collection::vec(0usize..70, 1..12)
}

fn stream(data: &[u8], splits: &[usize]) -> (Vec<Vec<u8>>, ScanStats, usize) {
    let mut scanner = StreamScanner::new();
    let mut frames = Vec::new();
    let mut rest = data;
    for &size in splits.iter().cycle() {
        if rest.is_empty() {
            break;
        }
        if size == 0 {
            scanner.push(&[], &mut |f| frames.push(f.to_vec()));
        }
        let (now, later) = rest.split_at(size.clamp(1, rest.len()));
        scanner.push(now, &mut |f| frames.push(f.to_vec()));
        assert!(scanner.pending_bytes() <= MAX_PENDING);
        rest = later;
    }
    (frames, scanner.stats, scanner.pending_bytes())
}

fn datagram(data: &[u8]) -> (Vec<Vec<u8>>, ScanStats) {
    let mut stats = ScanStats::default();
    let mut frames = Vec::new();
    scan_datagram(data, &mut stats, &mut |f| frames.push(f.to_vec()));
    (frames, stats)
}

/// `frame` with its CRC broken (its header, payload and signature kept).
fn damaged(mut frame: Vec<u8>) -> Vec<u8> {
    let header = if frame[0] == 0xFE { 6 } else { 10 };
    let crc = header + usize::from(frame[1]);
    frame[crc] ^= 0x5A;
    frame
}

/// Every frame of every kind, fed in `splits` read sizes, as (bytes, kind).
fn stream_all(
    data: &[u8],
    splits: &[usize],
) -> (Vec<(Vec<u8>, mavping::frame::Kind)>, ScanStats, usize) {
    let mut scanner = StreamScanner::new();
    let mut found = Vec::new();
    let mut rest = data;
    for &size in splits.iter().cycle() {
        if rest.is_empty() {
            break;
        }
        let (now, later) = rest.split_at(size.clamp(1, rest.len()));
        scanner.push_all(now, &mut |f, k| found.push((f.to_vec(), k)));
        assert!(scanner.pending_bytes() <= MAX_PENDING);
        rest = later;
    }
    (found, scanner.stats, scanner.pending_bytes())
}

/// A false header: MAVLink 1 with any length and an id the dialect may or
/// may not know (14 it does not), or MAVLink 2 with an unknown id, so its
/// claimed extent can end anywhere in what follows.
fn false_header() -> impl Strategy<Value = Vec<u8>> {
    prop_oneof![
        (
            any::<u8>(),
            any::<[u8; 3]>(),
            prop_oneof![Just(14u8), Just(4), any::<u8>()]
        )
            .prop_map(|(len, [a, b, c], id)| vec![0xFE, len, a, b, c, id]),
        (any::<u8>(), 0u8..=1, any::<[u8; 3]>()).prop_map(|(len, flags, [a, b, c])| vec![
            0xFD, len, flags, 0, a, b, c, 0xEE, 0xEE, 0xEE
        ]),
    ]
}

/// What comes before a real frame in a hostile byte stream: junk, a false
/// header, or a copy of a frame cut short.
fn hazard() -> impl Strategy<Value = Vec<u8>> {
    prop_oneof![
        2 => hostile_junk(),
        2 => (hostile_junk(), false_header()).prop_map(|(mut j, h)| { j.extend(h); j }),
        1 => (frame(), any::<prop::sample::Index>()).prop_map(|(f, i)| f[..i.index(f.len())].to_vec()),
    ]
}

/// True when a good frame lies wholly inside `frame`, after its start byte.
fn holds_a_good_frame(frame: &[u8]) -> bool {
    !datagram(&frame[1..]).0.is_empty()
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    /// Issue 21: every whole good frame that overlaps no other good frame
    /// (by the independent oracle in common/frame_oracle.rs) is delivered,
    /// whatever junk, false headers or cut copies come before it: by a
    /// datagram scan, at its place; by a stream, in any read splits, by the
    /// read that brings its last byte. Nothing but good frames is delivered.
    #[test]
    fn every_isolated_good_frame_is_delivered(
        parts in prop::collection::vec((hazard(), frame()), 1..8),
        splits in splits(),
    ) {
        let data: Vec<u8> = parts.iter().flat_map(|(h, f)| h.iter().chain(f)).copied().collect();
        let good = good_frames(&data);
        let must = isolated(&good);

        let base = data.as_ptr() as usize;
        let mut delivered = Vec::new();
        scan_datagram(&data, &mut ScanStats::default(), &mut |f| {
            let at = f.as_ptr() as usize - base;
            delivered.push(at..at + f.len());
        });
        for f in &must {
            prop_assert!(delivered.contains(f), "{f:?} not delivered: {delivered:?} {data:02x?}");
        }
        for f in &delivered {
            prop_assert!(good.contains(f), "{f:?} is not a good frame");
        }

        for f in &must {
            let (frames, _, _) = stream(&data[..f.end], &splits);
            prop_assert_eq!(frames.last(), Some(&data[f.clone()].to_vec()), "{:?} {:02x?}", f, data);
        }
    }

    /// Valid frames between junk that holds no start byte, read in any
    /// split: every frame is found, in order, and exactly the junk bytes
    /// are skipped. The datagram scan agrees.
    #[test]
    fn every_frame_found_and_only_junk_skipped(
        parts in prop::collection::vec((clean_junk(), frame()), 0..12),
        tail in clean_junk(),
        splits in splits(),
    ) {
        let mut data = Vec::new();
        let mut expected = Vec::new();
        let mut junk = 0u64;
        for (j, f) in &parts {
            data.extend_from_slice(j);
            data.extend_from_slice(f);
            junk += j.len() as u64;
            expected.push(f.clone());
        }
        data.extend_from_slice(&tail);
        junk += tail.len() as u64;

        let (frames, stats, pending) = stream(&data, &splits);
        prop_assert_eq!(&frames, &expected);
        prop_assert_eq!(stats.frames, expected.len() as u64);
        prop_assert_eq!(stats.skipped_bytes, junk);
        prop_assert_eq!((stats.bad_crc, stats.unknown_id, stats.truncated), (0, 0, 0));
        prop_assert_eq!(pending, 0);

        let (frames, stats) = datagram(&data);
        prop_assert_eq!(&frames, &expected);
        prop_assert_eq!(stats.skipped_bytes, junk);
        prop_assert_eq!((stats.bad_crc, stats.unknown_id, stats.truncated), (0, 0, 0));
    }

    /// Good frames, some right after a damaged one (a real frame whose CRC
    /// was broken), with junk that holds no start byte between: every
    /// damaged frame is delivered once as damaged at its place, every good
    /// one as good, by a datagram scan and by a stream in any read splits
    /// alike; only the junk is skipped.
    #[test]
    fn damaged_frames_before_good_ones_are_delivered_whatever_the_reads(
        parts in prop::collection::vec((clean_junk(), prop::option::of(frame()), frame()), 1..10),
        splits in splits(),
    ) {
        use mavping::frame::Kind as K;
        let mut data = Vec::new();
        let mut expected = Vec::new();
        let mut junk = 0u64;
        for (j, d, f) in &parts {
            data.extend_from_slice(j);
            junk += j.len() as u64;
            if let Some(d) = d {
                let d = damaged(d.clone());
                data.extend_from_slice(&d);
                expected.push((d, K::Damaged));
            }
            data.extend_from_slice(f);
            expected.push((f.clone(), K::Good));
        }
        let (found, stats, pending) = stream_all(&data, &splits);
        prop_assert_eq!(&found, &expected);
        prop_assert_eq!((stats.skipped_bytes, stats.bad_crc, pending), (junk, 0, 0));
        let damaged_count = expected.iter().filter(|e| e.1 == K::Damaged).count() as u64;
        prop_assert_eq!(stats.damaged, damaged_count);

        let mut dgram_stats = ScanStats::default();
        let mut dgram = Vec::new();
        scan_datagram_all(&data, &mut dgram_stats, &mut |f, k| dgram.push((f.to_vec(), k)));
        prop_assert_eq!(&dgram, &expected);
        prop_assert_eq!(dgram_stats, stats);
    }

    /// Arbitrary junk (start bytes, lying lengths, cut frames) between
    /// valid frames: no panic, the same result whatever the split, every
    /// byte accounted for, and the stream's frames are a prefix of what the
    /// datagram scan of the same bytes finds.
    #[test]
    fn hostile_bytes_are_split_invariant_and_accounted(
        parts in prop::collection::vec((hazard(), frame(), 0usize..=100), 0..10),
        splits in splits(),
    ) {
        let mut data = Vec::new();
        for (j, f, keep) in &parts {
            data.extend_from_slice(j);
            // Some frames are cut short (keep% of their bytes).
            let n = (f.len() * keep).div_ceil(100).max(1);
            data.extend_from_slice(&f[..n.min(f.len())]);
        }
        let (whole, whole_stats, whole_pending) = stream(&data, &[data.len().max(1)]);
        let (split, split_stats, split_pending) = stream(&data, &splits);
        prop_assert_eq!(&whole, &split);
        prop_assert_eq!(whole_stats, split_stats);
        prop_assert_eq!(whole_pending, split_pending);

        let frame_bytes: u64 = whole.iter().map(|f| f.len() as u64).sum();
        let accounted = frame_bytes + whole_stats.skipped_bytes + whole_pending as u64;
        prop_assert!(accounted <= data.len() as u64);
        // Unknown-id and damaged frames are taken whole, neither delivered
        // as good nor skipped.
        let unchecked = data.len() as u64 - accounted;
        let whole_unchecked = whole_stats.unknown_id + whole_stats.damaged;
        prop_assert!(unchecked >= 8 * whole_unchecked);
        prop_assert!(unchecked <= MAX_FRAME_LEN as u64 * whole_unchecked);

        let (dgram, dgram_stats) = datagram(&data);
        // A datagram keeps a good frame whose payload holds another good
        // frame; a stream lets the inner one win. Otherwise they agree.
        if !dgram.iter().any(|f| holds_a_good_frame(f)) {
            prop_assert!(dgram.len() >= whole.len());
            prop_assert_eq!(&dgram[..whole.len()], &whole[..]);
        }
        let frame_bytes: u64 = dgram.iter().map(|f| f.len() as u64).sum();
        prop_assert!(frame_bytes + dgram_stats.skipped_bytes <= data.len() as u64);
    }

    /// UDP: a datagram is parsed on its own, so whatever junk (or cut
    /// frame) came in the previous datagram, the next one's frame is found.
    #[test]
    fn junk_datagram_never_costs_the_next_frame(junk in hostile_junk(), f in frame()) {
        let mut stats = ScanStats::default();
        let mut frames = Vec::new();
        scan_datagram(&junk, &mut stats, &mut |x| frames.push(x.to_vec()));
        let before = frames.len();
        scan_datagram(&f, &mut stats, &mut |x| frames.push(x.to_vec()));
        prop_assert_eq!(frames.len(), before + 1);
        prop_assert_eq!(frames.last().unwrap(), &f);
    }
}

// ---------------------------------------------------------------- matcher

const MS: u64 = 1_000_000;
const TIMEOUT: u64 = 20 * MS;

#[derive(Debug, Clone)]
enum Op {
    /// Advance time by this many ms, then send a request.
    Send(u8),
    /// Advance time (ms).
    Wait(u8),
    /// A reply from responder `who` to the request `back` places before the
    /// newest, with the right token or a wrong one.
    Reply {
        who: u8,
        back: u8,
        wrong_token: bool,
    },
    /// A reply for a seq never sent (ahead of the newest).
    Unsent {
        who: u8,
        ahead: u8,
    },
    Expire,
}

fn op() -> impl Strategy<Value = Op> {
    prop_oneof![
        4 => (0u8..8).prop_map(Op::Send),
        1 => (0u8..30).prop_map(Op::Wait),
        6 => (0u8..3, 0u8..12, prop::bool::weighted(0.1))
            .prop_map(|(who, back, wrong_token)| Op::Reply { who, back, wrong_token }),
        1 => (0u8..3, 1u8..50).prop_map(|(who, ahead)| Op::Unsent { who, ahead }),
        1 => Just(Op::Expire),
    ]
}

#[derive(Debug, Default, Clone, PartialEq, Eq)]
struct Model {
    window_start: Option<u64>,
    answered: HashSet<u64>,
    received: u64,
    late: u64,
    duplicate: u64,
    stale: u64,
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    /// Random sends, in-time/late/duplicate/reordered replies from three
    /// responders, wrong tokens and never-sent seqs, against a model that
    /// states the rules directly: every count equals the model's.
    #[test]
    fn matcher_agrees_with_a_simple_model(
        ops in prop::collection::vec(op(), 0..300),
        first_seq in prop_oneof![Just(0u32), Just(u32::MAX - 20), any::<u32>()],
        by_token in any::<bool>(),
    ) {
        // Large enough that no request is ever overwritten.
        let mut m = Matcher::new(TIMEOUT, 1024, first_seq);
        let mut now = 0u64;
        let mut sent: Vec<(u64, u64)> = Vec::new(); // (sent_at, token)
        let mut model: HashMap<SysComp, Model> = HashMap::new();
        let mut events = Vec::new();
        for op in ops {
            match op {
                Op::Send(dt) => {
                    now += u64::from(dt) * MS;
                    m.expire(now, &mut |e| events.push(e));
                    let token = 1_000 + sent.len() as u64 * 10;
                    m.on_send(token, now, &mut |e| events.push(e));
                    sent.push((now, token));
                }
                Op::Wait(dt) => now += u64::from(dt) * MS,
                Op::Expire => m.expire(now, &mut |e| events.push(e)),
                Op::Reply { who, back, wrong_token } => {
                    let Some(n) = (sent.len() as u64).checked_sub(1 + u64::from(back)) else {
                        continue;
                    };
                    let id = SysComp::new(who + 1, 1);
                    let (sent_at, token) = sent[n as usize];
                    let token = if wrong_token { token + 5 } else { token };
                    let lookup = if by_token {
                        Lookup::Token(token)
                    } else {
                        Lookup::Seq { seq: first_seq.wrapping_add(n as u32), token }
                    };
                    m.on_reply(id, lookup, now, &mut |e| events.push(e));
                    let r = model.entry(id).or_default();
                    if wrong_token {
                        r.stale += 1;
                    } else if !r.answered.insert(n) {
                        r.duplicate += 1;
                    } else if now >= sent_at + TIMEOUT {
                        // A late first answer opens the window too.
                        r.late += 1;
                        r.window_start = Some(r.window_start.map_or(n, |w| w.min(n)));
                    } else {
                        r.received += 1;
                        r.window_start = Some(r.window_start.map_or(n, |w| w.min(n)));
                    }
                }
                Op::Unsent { who, ahead } => {
                    let id = SysComp::new(who + 1, 1);
                    let n = sent.len() as u64 + u64::from(ahead);
                    let lookup = if by_token {
                        Lookup::Token(1_000 + n * 10 + 3)
                    } else {
                        Lookup::Seq { seq: first_seq.wrapping_add(n as u32), token: 1_000 + n * 10 }
                    };
                    m.on_reply(id, lookup, now, &mut |e| events.push(e));
                    model.entry(id).or_default().stale += 1;
                }
            }
        }
        m.expire(u64::MAX / 2, &mut |e| events.push(e));
        prop_assert_eq!(m.next_deadline(), None);
        prop_assert_eq!(m.responders().len(), model.len());
        let mut lost_events: HashMap<SysComp, u64> = HashMap::new();
        for e in &events {
            if let MatchEvent::Lost { responder, .. } = e {
                *lost_events.entry(*responder).or_default() += 1;
            }
        }
        for r in m.responders() {
            let want = &model[&r.id];
            let c = r.counts;
            let window: Vec<u64> = match want.window_start {
                Some(w) => (w..sent.len() as u64).collect(),
                None => Vec::new(),
            };
            prop_assert_eq!(c.received, want.received, "{}", r.id);
            prop_assert_eq!(c.late, want.late, "{}", r.id);
            prop_assert_eq!(c.duplicate, want.duplicate, "{}", r.id);
            prop_assert_eq!(c.stale, want.stale, "{}", r.id);
            prop_assert_eq!(c.sent, window.len() as u64, "{}", r.id);
            // Every answered request lies in the window (it starts at the
            // oldest one), so the rest of the window is lost, late or not.
            prop_assert_eq!(c.lost, window.len() as u64 - want.received, "{}", r.id);
            prop_assert_eq!(c.sent, c.received + c.lost, "{}", r.id);
            prop_assert_eq!(lost_events.get(&r.id).copied().unwrap_or(0), c.lost, "{}", r.id);
            prop_assert!(c.late <= c.lost, "{}", r.id);
        }
        // Every request is charged, or before the window, exactly once.
        prop_assert_eq!(m.finish(), 0);
        for r in m.responders() {
            let c = r.counts;
            let before = model[&r.id].window_start.unwrap_or(sent.len() as u64);
            prop_assert_eq!(c.not_charged, before, "{}", r.id);
            prop_assert_eq!(c.not_charged + c.sent + c.in_flight, sent.len() as u64, "{}", r.id);
        }
    }
}

/// Found by the fuzzer: a whole maximal frame of an unknown id, held back
/// until the next byte shows whether it lines up, is a tail of exactly
/// MAX_FRAME_LEN bytes (a debug assertion said "less than").
#[test]
fn maximal_unknown_frame_at_the_end_of_a_read_is_held_whole() {
    let mut frame = vec![0xFD, 255, 0x01, 0, 0, 1, 1, 0xEE, 0xEE, 0xEE];
    frame.resize(MAX_FRAME_LEN, 0x42);
    let mut scanner = StreamScanner::new();
    scanner.push(&frame, &mut |_| panic!("not a good frame"));
    assert_eq!(scanner.pending_bytes(), MAX_FRAME_LEN);
    // The next frame shows it lined up: it is skipped whole as unknown.
    let mut next = Vec::new();
    encode(
        &mut next,
        Version::V2,
        Header {
            sysid: 1,
            compid: 1,
            seq: 0,
        },
        &Msg::Heartbeat {
            mav_type: 2,
            autopilot: 12,
        },
    );
    let mut found = 0;
    scanner.push(&next, &mut |_| found += 1);
    assert_eq!(
        (found, scanner.stats.unknown_id, scanner.stats.skipped_bytes),
        (1, 1, 0)
    );
}
