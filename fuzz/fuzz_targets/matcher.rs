//! The matcher fed arbitrary sends, replies (right, wrong or unknown
//! tokens and seqs, from a few responders), expiries and a finish.
//! Invariants: no panic; once every request is decided, each responder's
//! `sent == received + lost`, `late <= lost`, and every request issued is
//! counted once in `not_charged + sent + in_flight`; counts equal the
//! events it emitted; RTTs are never negative and only in-time replies are
//! measured.
#![no_main]

use std::collections::HashMap;

use libfuzzer_sys::fuzz_target;
use mavping::engine::matcher::{Lookup, MatchEvent, Matcher};
use mavping::frame::SysComp;

#[derive(Default, Debug)]
struct Tally {
    reply: u64,
    late: u64,
    dup: u64,
    lost: u64,
    stale: u64,
}

fuzz_target!(|data: &[u8]| {
    if data.len() < 3 {
        return;
    }
    let timeout = 1 + u64::from(data[0]) * 1_000;
    let capacity = 1 + usize::from(data[1] % 64);
    let first_seq = u32::MAX - u32::from(data[2]);
    let by_token = data[2] & 1 == 1;
    let mut m = Matcher::new(timeout, capacity, first_seq);
    let mut now: u64 = 0;
    let mut sent: Vec<(u32, u64)> = Vec::new(); // (seq, token)
    let mut tally: HashMap<SysComp, Tally> = HashMap::new();
    let record = |e: MatchEvent, tally: &mut HashMap<SysComp, Tally>| {
        let (who, t) = match e {
            MatchEvent::Reply {
                responder,
                rtt,
                sent_at,
                at,
                ..
            } => {
                assert_eq!(rtt, at - sent_at);
                (responder, 0)
            }
            MatchEvent::Late { responder, .. } => (responder, 1),
            MatchEvent::Duplicate { responder, .. } => (responder, 2),
            MatchEvent::Lost { responder, .. } => (responder, 3),
            MatchEvent::Stale { responder, .. } => (responder, 4),
        };
        let e = tally.entry(who).or_default();
        match t {
            0 => e.reply += 1,
            1 => e.late += 1,
            2 => e.dup += 1,
            3 => e.lost += 1,
            _ => e.stale += 1,
        }
    };
    for op in data[3..].chunks(2) {
        let (kind, arg) = (op[0], op.get(1).copied().unwrap_or(0));
        now += u64::from(kind >> 4) * 97;
        match kind & 0x3 {
            0 => {
                // Tokens rise strictly (TIMESYNC needs it); time only rises.
                let token = now * 1_000 + sent.len() as u64;
                let issued = m.on_send(token, now, &mut |e| record(e, &mut tally));
                sent.push((issued.seq, token));
            }
            1 | 2 => {
                let who = SysComp::new(1 + (arg & 0x3), 1);
                let back = usize::from(arg >> 2);
                let (seq, token) = match sent.len().checked_sub(1 + back) {
                    Some(i) => sent[i],
                    None => (arg.into(), 7),
                };
                let token = if kind & 0x8 != 0 { token ^ 1 } else { token };
                let lookup = if by_token {
                    Lookup::Token(token)
                } else {
                    Lookup::Seq { seq, token }
                };
                m.on_reply(who, lookup, now, &mut |e| record(e, &mut tally));
            }
            _ => m.expire(now, &mut |e| record(e, &mut tally)),
        }
    }
    // Either every request is decided, or the run stops with some in flight.
    let decide_all = data[2] & 2 == 0;
    if decide_all {
        m.expire(u64::MAX, &mut |e| record(e, &mut tally));
    }
    let unanswered = m.finish();
    assert_eq!(m.next_deadline(), None);
    for r in m.responders() {
        let c = r.counts;
        let t = tally.remove(&r.id).unwrap_or_default();
        assert_eq!(c.sent, c.received + c.lost, "{:?} {c:?}", r.id);
        assert!(c.late <= c.lost, "{:?} {c:?}", r.id);
        assert_eq!(c.received, t.reply, "{:?}", r.id);
        assert_eq!(c.late, t.late);
        assert_eq!(c.duplicate, t.dup);
        assert_eq!(c.lost, t.lost);
        assert_eq!(c.stale, t.stale);
        assert!(c.out_of_order <= c.received);
        assert_eq!(r.rtt.count(), c.received);
    }
    assert!(tally.is_empty(), "events for unknown responders: {tally:?}");
    let issued = sent.len() as u64;
    for r in m.responders() {
        let c = r.counts;
        assert!(c.in_flight <= unanswered, "{:?} {c:?}", r.id);
        assert!(!decide_all || c.in_flight == 0, "{:?} {c:?}", r.id);
        assert_eq!(
            c.not_charged + c.sent + c.in_flight,
            issued,
            "{:?} {c:?}",
            r.id
        );
    }
});
