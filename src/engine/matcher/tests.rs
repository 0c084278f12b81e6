use proptest::prelude::*;

use super::*;

const MS: Nanos = 1_000_000;
const A: SysComp = SysComp::new(1, 1);
const B: SysComp = SysComp::new(2, 1);

/// Drives a matcher and keeps every event it emits.
struct Harness {
    m: Matcher,
    events: Vec<MatchEvent>,
}

impl Harness {
    fn new(timeout: Nanos, capacity: usize, first_seq: u32) -> Self {
        Harness {
            m: Matcher::new(timeout, capacity, first_seq),
            events: Vec::new(),
        }
    }
    fn send(&mut self, at: Nanos) -> Issued {
        let events = &mut self.events;
        self.m.on_send(at / 1000, at, &mut |e| events.push(e))
    }
    fn reply(&mut self, who: SysComp, issued: Issued, sent_at: Nanos, at: Nanos) {
        let events = &mut self.events;
        let lookup = Lookup::Seq {
            seq: issued.seq,
            token: sent_at / 1000,
        };
        self.m.on_reply(who, lookup, at, &mut |e| events.push(e));
    }
    fn expire(&mut self, now: Nanos) {
        let events = &mut self.events;
        self.m.expire(now, &mut |e| events.push(e));
    }
    fn counts(&self, who: SysComp) -> Counts {
        self.m.responder(who).unwrap().counts
    }
}

#[test]
fn replies_in_time_are_received_with_exact_rtt() {
    let mut h = Harness::new(100 * MS, 64, 0);
    let r = h.send(0);
    h.reply(A, r, 0, 3 * MS);
    assert!(matches!(
        h.events[0],
        MatchEvent::Reply { rtt, seq: 0, first_from_responder: true, .. } if rtt == 3 * MS
    ));
    h.expire(200 * MS);
    let c = h.counts(A);
    assert_eq!((c.sent, c.received, c.lost), (1, 1, 0));
}

#[test]
fn window_starts_at_first_answered_request() {
    let mut h = Harness::new(10 * MS, 64, 0);
    let reqs: Vec<_> = (0..5).map(|i| h.send(i * 20 * MS)).collect();
    // Requests 0 and 1 went unanswered before A was ever heard.
    h.reply(A, reqs[2], 40 * MS, 41 * MS);
    h.reply(A, reqs[4], 80 * MS, 81 * MS);
    h.expire(1000 * MS);
    let c = h.counts(A);
    assert_eq!((c.sent, c.received, c.lost), (3, 2, 1));
    let lost: Vec<u32> = h
        .events
        .iter()
        .filter_map(|e| match e {
            MatchEvent::Lost { seq, .. } => Some(*seq),
            _ => None,
        })
        .collect();
    assert_eq!(lost, vec![3]);
}

#[test]
fn late_duplicate_and_stale_are_told_apart() {
    let mut h = Harness::new(10 * MS, 64, 0);
    let r0 = h.send(0);
    let r1 = h.send(MS);
    h.reply(A, r0, 0, 2 * MS); // received
    h.reply(A, r0, 0, 3 * MS); // duplicate
    h.reply(A, r1, MS, 50 * MS); // late: r1 timed out at 11 ms
    h.reply(A, r1, MS, 51 * MS); // duplicate of the late reply
    h.reply(A, Issued { n: 99, seq: 99 }, 0, 52 * MS); // never sent
    h.reply(A, r0, 12345, 53 * MS); // wrong echoed token
    let c = h.counts(A);
    assert_eq!(c.received, 1);
    assert_eq!(c.lost, 1);
    assert_eq!(c.late, 1);
    assert_eq!(c.duplicate, 2);
    assert_eq!(c.stale, 2);
    assert_eq!(c.sent, 2);
}

#[test]
fn several_responders_have_separate_windows_and_counts() {
    let mut h = Harness::new(10 * MS, 64, 0);
    let reqs: Vec<_> = (0..4).map(|i| h.send(i * 100 * MS)).collect();
    for (i, r) in reqs.iter().enumerate() {
        let t = i as u64 * 100 * MS;
        h.reply(A, *r, t, t + MS);
        if i >= 2 {
            h.reply(B, *r, t, t + 2 * MS);
        }
    }
    h.expire(10_000 * MS);
    assert_eq!(h.counts(A).sent, 4);
    assert_eq!(h.counts(B).sent, 2);
    assert_eq!(h.counts(B).received, 2);
    assert_eq!(h.m.responders().len(), 2);
}

#[test]
fn reordered_reply_before_timeout_is_received_and_out_of_order() {
    let mut h = Harness::new(100 * MS, 64, 0);
    let r0 = h.send(0);
    let r1 = h.send(MS);
    h.reply(A, r1, MS, 2 * MS);
    h.reply(A, r0, 0, 3 * MS);
    h.expire(1000 * MS);
    let c = h.counts(A);
    assert_eq!((c.sent, c.received, c.lost, c.out_of_order), (2, 2, 0, 1));
}

#[test]
fn sequence_wraps_at_u32_max() {
    let mut h = Harness::new(10 * MS, 8, u32::MAX - 1);
    let reqs: Vec<_> = (0..4).map(|i| h.send(i * MS)).collect();
    assert_eq!(
        reqs.iter().map(|r| r.seq).collect::<Vec<_>>(),
        vec![u32::MAX - 1, u32::MAX, 0, 1]
    );
    for (i, r) in reqs.iter().enumerate() {
        h.reply(A, *r, i as u64 * MS, i as u64 * MS + 500_000);
    }
    h.expire(100 * MS);
    assert_eq!(h.counts(A).received, 4);
    assert_eq!(h.counts(A).stale, 0);
}

#[test]
fn finish_leaves_unanswered_in_flight_requests_out() {
    let mut h = Harness::new(1000 * MS, 64, 0);
    let r0 = h.send(0);
    let _r1 = h.send(MS);
    h.reply(A, r0, 0, MS);
    assert!(!h.m.all_answered());
    assert_eq!(h.m.finish(), 1);
    let c = h.counts(A);
    assert_eq!((c.sent, c.received, c.lost), (1, 1, 0));
}

#[test]
fn lookup_by_token_finds_timesync_style_requests() {
    let mut m = Matcher::new(10 * MS, 16, 0);
    let mut sink = |_| {};
    for i in 0..40u64 {
        m.on_send(1_000 + i * 7, i * MS, &mut sink);
    }
    let mut events = Vec::new();
    m.on_reply(A, Lookup::Token(1_000 + 39 * 7), 39 * MS + 1, &mut |e| {
        events.push(e)
    });
    m.on_reply(
        A,
        Lookup::Token(1_000 + 39 * 7 + 1),
        39 * MS + 2,
        &mut |e| events.push(e),
    );
    m.on_reply(A, Lookup::Token(1_000), 39 * MS + 3, &mut |e| {
        events.push(e)
    });
    assert!(matches!(
        events[0],
        MatchEvent::Reply {
            seq: 39,
            rtt: 1,
            ..
        }
    ));
    assert!(matches!(events[1], MatchEvent::Stale { .. }));
    // Request 0 has been overwritten in the 16-slot ring.
    assert!(matches!(events[2], MatchEvent::Stale { .. }));
}

#[test]
fn overfull_ring_decides_old_requests_instead_of_forgetting_them() {
    let mut h = Harness::new(1_000_000 * MS, 4, 0);
    let r0 = h.send(0);
    h.reply(A, r0, 0, 1);
    for i in 1..10 {
        h.send(i * MS);
    }
    assert_eq!(h.counts(A).lost, 5);
    assert_eq!(h.counts(A).sent, 6);
}

#[derive(Debug, Clone)]
enum Fate {
    Lost,
    Once { delay_us: u64 },
    Twice { delay_us: u64, dup_after_us: u64 },
    Late { extra_us: u64 },
}

fn fate() -> impl Strategy<Value = Fate> {
    prop_oneof![
        1 => Just(Fate::Lost),
        6 => (0u64..30_000).prop_map(|delay_us| Fate::Once { delay_us }),
        1 => (0u64..30_000, 0u64..5_000)
            .prop_map(|(delay_us, dup_after_us)| Fate::Twice { delay_us, dup_after_us }),
        1 => (1u64..50_000).prop_map(|extra_us| Fate::Late { extra_us }),
    ]
}

proptest! {
    /// Random loss, duplication, reordering (random delays across a 1 ms
    /// send interval), late replies and a start near the u32 wrap: the
    /// counts equal the ground truth exactly.
    #[test]
    fn counts_match_ground_truth(
        fates in prop::collection::vec(fate(), 1..300),
        first_seq in prop_oneof![Just(0u32), Just(u32::MAX - 50), any::<u32>()],
    ) {
        const TIMEOUT: Nanos = 40 * MS;
        let mut h = Harness::new(TIMEOUT, 128, first_seq);
        // Sends and replies in one timeline, as the engine sees them.
        // Kind 0 (send) sorts before a reply at the same instant.
        let mut timeline: Vec<(Nanos, u8, usize)> = Vec::new();
        for (i, f) in fates.iter().enumerate() {
            let sent_at = i as u64 * MS;
            timeline.push((sent_at, 0, i));
            match *f {
                Fate::Lost => {}
                Fate::Once { delay_us } => timeline.push((sent_at + delay_us * 1000, 1, i)),
                Fate::Twice { delay_us, dup_after_us } => {
                    timeline.push((sent_at + delay_us * 1000, 1, i));
                    timeline.push((sent_at + (delay_us + dup_after_us) * 1000 + 1, 1, i));
                }
                Fate::Late { extra_us } => timeline.push((sent_at + TIMEOUT + extra_us * 1000, 1, i)),
            }
        }
        timeline.sort_unstable();
        for (at, kind, i) in timeline {
            let sent_at = i as u64 * MS;
            if kind == 0 {
                h.expire(at);
                h.send(sent_at);
            } else {
                let issued = Issued { n: i as u64, seq: first_seq.wrapping_add(i as u32) };
                h.reply(A, issued, sent_at, at);
            }
        }
        h.expire(u64::MAX / 2);

        // The window opens at the first request answered at all, late too.
        let first = fates.iter().position(|f| !matches!(f, Fate::Lost));
        let c = h.m.responder(A).map(|r| r.counts).unwrap_or_default();
        let in_window = |i: usize| first.is_some_and(|f| i >= f);
        let expect_received = fates.iter().filter(|f| matches!(f, Fate::Once { .. } | Fate::Twice { .. })).count() as u64;
        let expect_dups = fates.iter().filter(|f| matches!(f, Fate::Twice { .. })).count() as u64;
        let expect_late = fates.iter().filter(|f| matches!(f, Fate::Late { .. })).count() as u64;
        let expect_sent = (0..fates.len()).filter(|&i| in_window(i)).count() as u64;
        let expect_lost = fates.iter().enumerate()
            .filter(|(i, f)| in_window(*i) && matches!(f, Fate::Lost | Fate::Late { .. }))
            .count() as u64;
        prop_assert_eq!(c.received, expect_received);
        prop_assert_eq!(c.duplicate, expect_dups);
        prop_assert_eq!(c.late, expect_late);
        prop_assert_eq!(c.sent, expect_sent);
        prop_assert_eq!(c.lost, expect_lost);
        prop_assert_eq!(c.sent, c.received + c.lost);
        prop_assert_eq!(c.stale, 0);
        prop_assert_eq!(h.m.finish(), 0);
        let c = h.m.responder(A).map(|r| r.counts);
        if let Some(c) = c {
            prop_assert_eq!(c.not_charged + c.sent + c.in_flight, fates.len() as u64);
        }
    }
}

/// The satellite link: every reply comes 70 s after its request, the
/// timeout is 2 s, a request goes every 30 s. The first late reply opens
/// the window; the requests decided before it are charged then.
#[test]
fn a_responder_whose_every_reply_is_late_is_all_lost_not_uncounted() {
    let mut h = Harness::new(2_000 * MS, 64, 0);
    let s = 30_000 * MS;
    let rtt = 70_000 * MS;
    let r0 = h.send(0);
    let r1 = h.send(s);
    h.expire(2 * s);
    let _r2 = h.send(2 * s);
    h.reply(A, r0, 0, rtt);
    // Requests 0, 1 and 2 were decided (2 at 62 s) before A was heard at
    // 70 s: charged now, lost.
    let lost: Vec<u32> = h
        .events
        .iter()
        .filter_map(|e| match e {
            MatchEvent::Lost { seq, at, .. } if *at == rtt => Some(*seq),
            _ => None,
        })
        .collect();
    assert_eq!(lost, vec![0, 1, 2]);
    assert!(matches!(
        h.events.last(),
        Some(MatchEvent::Late { seq: 0, .. })
    ));
    let _r3 = h.send(3 * s);
    h.reply(A, r1, s, s + rtt);
    let _r4 = h.send(4 * s);
    h.expire(4 * s + 2_000 * MS);
    assert_eq!(h.m.finish(), 0);
    let c = h.counts(A);
    assert_eq!(
        (
            c.not_charged,
            c.sent,
            c.received,
            c.lost,
            c.late,
            c.in_flight
        ),
        (0, 5, 0, 5, 2, 0)
    );
    let lost_events = h
        .events
        .iter()
        .filter(|e| matches!(e, MatchEvent::Lost { .. }))
        .count() as u64;
    assert_eq!(lost_events, c.lost);
}

#[test]
fn requests_before_the_first_answer_are_not_charged_and_counted_as_such() {
    let mut h = Harness::new(100 * MS, 64, 0);
    let reqs: Vec<_> = (0..6).map(|i| h.send(i * 10 * MS)).collect();
    // A is first heard answering request 3; request 5 is still in flight.
    h.reply(A, reqs[3], 30 * MS, 31 * MS);
    h.reply(A, reqs[4], 40 * MS, 41 * MS);
    let now = h.m.counts_now(h.m.responder(A).unwrap());
    assert_eq!(
        (now.not_charged, now.sent, now.in_flight),
        (3, 2, 1),
        "{now:?}"
    );
    assert_eq!(h.m.finish(), 1);
    let c = h.counts(A);
    assert_eq!(
        (c.not_charged, c.sent, c.received, c.lost, c.in_flight),
        (3, 2, 2, 0, 1)
    );
    assert_eq!(c.not_charged + c.sent + c.in_flight, 6);
}

#[test]
fn a_late_reply_older_than_the_window_moves_it_back_and_charges_the_gap() {
    let mut h = Harness::new(10 * MS, 64, 0);
    let reqs: Vec<_> = (0..4).map(|i| h.send(i * MS)).collect();
    // Request 2 answered in time; 0 and 1 decided lost to nobody.
    h.reply(A, reqs[2], 2 * MS, 3 * MS);
    h.expire(12 * MS);
    assert_eq!(h.counts(A).sent, 1);
    // Then request 0's reply comes, late: the window opens at 0, and 0 and
    // 1 are charged (lost); 2 was charged already.
    h.reply(A, reqs[0], 0, 12 * MS + 1);
    let c = h.counts(A);
    assert_eq!((c.sent, c.received, c.lost, c.late), (3, 1, 2, 1));
    h.expire(100 * MS);
    h.m.finish();
    let c = h.counts(A);
    assert_eq!(
        (c.not_charged, c.sent, c.received, c.lost, c.late),
        (0, 4, 1, 3, 1)
    );
}

/// A named target (`/probe`): the requests before its first answer are
/// its losses, charged when it is first heard (decided ones) or at their
/// timeout (the rest); the same replies streaming leave them uncharged.
#[test]
fn from_the_start_every_request_counts_for_a_late_first_answer() {
    for window in [Window::FromStart, Window::FirstAnswer] {
        let mut h = Harness::new(100 * MS, 64, 0);
        h.m = Matcher::new(100 * MS, 64, 0).with_window(window);
        let reqs: Vec<_> = (0..8).map(|i| h.send(i * 30 * MS)).collect();
        // Requests 0-3 were decided (at 100-190 ms) before A first answers
        // request 5 at 215 ms; 4 is still undecided, and stays unanswered.
        h.expire(214 * MS);
        h.reply(A, reqs[5], 150 * MS, 215 * MS);
        h.reply(A, reqs[6], 180 * MS, 219 * MS);
        h.reply(A, reqs[7], 210 * MS, 220 * MS);
        h.expire(1000 * MS);
        h.m.finish();
        let c = h.counts(A);
        let lost: Vec<u32> = h
            .events
            .iter()
            .filter_map(|e| match e {
                MatchEvent::Lost { seq, .. } => Some(*seq),
                _ => None,
            })
            .collect();
        let counts = (c.not_charged, c.sent, c.received, c.lost);
        match window {
            Window::FromStart => {
                assert_eq!(counts, (0, 8, 3, 5));
                assert_eq!(lost, vec![0, 1, 2, 3, 4]);
            }
            Window::FirstAnswer => {
                assert_eq!(counts, (5, 3, 3, 0));
                assert!(lost.is_empty(), "{lost:?}");
            }
        }
    }
}

/// From the start, a first answer that is late charges its own request
/// once (lost, and late), not twice.
#[test]
fn from_the_start_a_late_first_answer_is_charged_once() {
    let mut h = Harness::new(10 * MS, 64, 0);
    h.m = Matcher::new(10 * MS, 64, 0).with_window(Window::FromStart);
    let reqs: Vec<_> = (0..3).map(|i| h.send(i * MS)).collect();
    h.expire(50 * MS);
    h.reply(A, reqs[1], MS, 51 * MS);
    h.m.finish();
    let c = h.counts(A);
    assert_eq!((c.sent, c.received, c.lost, c.late), (3, 0, 3, 1));
}
