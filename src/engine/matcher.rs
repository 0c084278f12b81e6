//! Matches replies to requests and keeps exact per-responder counts.
//!
//! Pure and synchronous: every call takes the time as an argument, so tests
//! drive it with exact timestamps. Memory is fixed at construction: requests
//! live in a ring of `capacity` slots, and each responder keeps one bit per
//! slot saying whether it answered the request held there (cleared when the
//! slot takes a new request).
//!
//! Rules (from the MAVLink PING protocol and mavping's spec):
//! - A responder's accounting window starts at the first request it
//!   answered, in time or late (the seed: "do not start detecting dropped
//!   packets until after the first responses"). Requests before it are not
//!   charged to it (`not_charged`): a system that boots, or a link that
//!   comes up, after the run started is not blamed for the time before.
//!   A late first answer opens the window too: a responder whose every
//!   reply is late (a satellite link's 70 s round trip against a 2 s
//!   timeout) is 100 % lost with its late replies, not "0 sent". The
//!   window moves back to an older request answered later (reordering),
//!   and the requests from there that were already decided are charged
//!   then, as lost (nothing of them came in time: it would have opened
//!   the window earlier).
//!   That is [`Window::FirstAnswer`], for runs that stream. A run whose
//!   target was named (a `/probe` of `mavping serve`) charges every
//!   request to every responder from the first ([`Window::FromStart`]):
//!   there, a responder that misses the first requests has lost them.
//! - When a request's timeout passes, every responder whose window includes
//!   it and that has not answered it gets it counted as lost.
//! - A first reply after the timeout is late (the request stays lost); a
//!   second reply to the same request is a duplicate; a reply whose request
//!   is unknown, overwritten, or whose echoed token differs is stale.
//! - For each responder, `sent = received + lost` once requests are decided,
//!   and every request issued is exactly one of: not charged (before its
//!   window), sent (decided, or answered while still in time), in flight.

use std::collections::HashMap;

use serde::Serialize;

use super::stats::RttStats;
use super::Nanos;
use crate::frame::SysComp;

/// How a reply names the request it answers.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Lookup {
    /// By wire sequence number, and the token must equal what was sent
    /// (PING: seq, with time_usec as token).
    Seq { seq: u32, token: u64 },
    /// By token alone (TIMESYNC: ts1).
    Token(u64),
}

/// What the matcher decided, in the order it decided it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MatchEvent {
    Reply {
        responder: SysComp,
        seq: u32,
        rtt: Nanos,
        sent_at: Nanos,
        at: Nanos,
        out_of_order: bool,
        first_from_responder: bool,
    },
    Late {
        responder: SysComp,
        seq: u32,
        rtt: Nanos,
        sent_at: Nanos,
        at: Nanos,
    },
    Duplicate {
        responder: SysComp,
        seq: u32,
        rtt: Nanos,
        sent_at: Nanos,
        at: Nanos,
    },
    Lost {
        responder: SysComp,
        seq: u32,
        sent_at: Nanos,
        at: Nanos,
    },
    Stale {
        responder: SysComp,
        at: Nanos,
    },
}

impl crate::engine::kind::KindValue for MatchEvent {}

impl MatchEvent {
    /// When it was decided (session time).
    pub(crate) fn at(&self) -> Nanos {
        match *self {
            MatchEvent::Reply { at, .. }
            | MatchEvent::Late { at, .. }
            | MatchEvent::Duplicate { at, .. }
            | MatchEvent::Lost { at, .. }
            | MatchEvent::Stale { at, .. } => at,
        }
    }

    /// Who answered (or, for a loss, was asked).
    pub(crate) fn responder(&self) -> SysComp {
        match *self {
            MatchEvent::Reply { responder, .. }
            | MatchEvent::Late { responder, .. }
            | MatchEvent::Duplicate { responder, .. }
            | MatchEvent::Lost { responder, .. }
            | MatchEvent::Stale { responder, .. } => responder,
        }
    }

    /// The request's sequence number; a stale reply matches none.
    pub(crate) fn seq(&self) -> Option<u32> {
        match *self {
            MatchEvent::Reply { seq, .. }
            | MatchEvent::Late { seq, .. }
            | MatchEvent::Duplicate { seq, .. }
            | MatchEvent::Lost { seq, .. } => Some(seq),
            MatchEvent::Stale { .. } => None,
        }
    }

    /// When the request was sent; a stale reply matches none.
    pub(crate) fn sent_at(&self) -> Option<Nanos> {
        match *self {
            MatchEvent::Reply { sent_at, .. }
            | MatchEvent::Late { sent_at, .. }
            | MatchEvent::Duplicate { sent_at, .. }
            | MatchEvent::Lost { sent_at, .. } => Some(sent_at),
            MatchEvent::Stale { .. } => None,
        }
    }

    /// The round trip, where a reply came for a request we held.
    pub(crate) fn rtt(&self) -> Option<Nanos> {
        match *self {
            MatchEvent::Reply { rtt, .. }
            | MatchEvent::Late { rtt, .. }
            | MatchEvent::Duplicate { rtt, .. } => Some(rtt),
            MatchEvent::Lost { .. } | MatchEvent::Stale { .. } => None,
        }
    }
}

/// Where a responder's accounting window opens.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum Window {
    /// At the first request it answered (in time or late): a responder
    /// that joins a streaming run late is not blamed for the time before.
    #[default]
    FirstAnswer,
    /// At the run's first request: its target was named, so every request
    /// counts. The requests decided before a responder is first heard are
    /// charged then, so the ring must hold every request of the run.
    FromStart,
}

/// Exact per-responder counts. Every request issued is counted once in
/// `not_charged`, `sent` or `in_flight`.
#[derive(Debug, Default, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct Counts {
    /// Requests in this responder's window whose fate is decided.
    pub sent: u64,
    /// Requests before its window, i.e. before the first request it
    /// answered (in time or late): not charged to it.
    pub not_charged: u64,
    /// Requests in its window still within their timeout, unanswered by
    /// it: neither received nor lost (yet).
    pub in_flight: u64,
    pub received: u64,
    pub lost: u64,
    /// First replies that came after the timeout (each also counted lost).
    pub late: u64,
    pub duplicate: u64,
    /// In-time replies to a request older than one already answered.
    pub out_of_order: u64,
    /// Replies addressed to us that match no request we hold.
    pub stale: u64,
}

impl Counts {
    /// Lost share of sent, 0 when nothing was sent.
    pub(crate) fn loss_ratio(&self) -> f64 {
        if self.sent == 0 {
            0.0
        } else {
            self.lost as f64 / self.sent as f64
        }
    }
}

/// One responder's state.
pub struct Responder {
    pub id: SysComp,
    pub counts: Counts,
    pub rtt: RttStats,
    /// One bit per ring slot: this responder answered the request held
    /// there. Empty until its first matched reply, so spoofed ids cost
    /// little.
    answered: Vec<u64>,
    window_start: Option<u64>,
    highest: Option<u64>,
}

impl Responder {
    fn new(id: SysComp) -> Self {
        Responder {
            id,
            counts: Counts::default(),
            rtt: RttStats::new(),
            answered: Vec::new(),
            window_start: Option::None,
            highest: Option::None,
        }
    }

    fn in_window(&self, n: u64) -> bool {
        self.window_start.is_some_and(|start| start <= n)
    }

    /// Whether it answered the request held in slot `idx`.
    fn has_answered(&self, idx: usize) -> bool {
        self.answered
            .get(idx / 64)
            .is_some_and(|word| word & (1 << (idx % 64)) != 0)
    }

    /// A request in its window decided without its answer: sent, lost.
    fn charge_lost(
        &mut self,
        seq: u32,
        sent_at: Nanos,
        at: Nanos,
        out: &mut impl FnMut(MatchEvent),
    ) {
        self.counts.sent += 1;
        self.counts.lost += 1;
        out(MatchEvent::Lost {
            responder: self.id,
            seq,
            sent_at,
            at,
        });
    }

    fn set_answered(&mut self, idx: usize, answered: bool) {
        if let Some(word) = self.answered.get_mut(idx / 64) {
            let bit = 1 << (idx % 64);
            if answered {
                *word |= bit;
            } else {
                *word &= !bit;
            }
        }
    }
}

#[derive(Debug, Clone, Copy, Default)]
struct Slot {
    /// n + 1 of the request held here; 0 when never used.
    n1: u64,
    token: u64,
    sent_at: Nanos,
}

/// A request as the matcher issued it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Issued {
    pub(crate) n: u64,
    pub seq: u32,
}

/// At most this many distinct responders are tracked; replies from more
/// (a spoofing flood) are counted in `untracked` instead of growing memory.
pub(crate) const MAX_RESPONDERS: usize = 4096;

pub struct Matcher {
    timeout: Nanos,
    window: Window,
    first_seq: u32,
    slots: Vec<Slot>,
    mask: u64,
    next_n: u64,
    /// Oldest request whose timeout has not been processed.
    next_expiry: u64,
    responders: Vec<Responder>,
    index: HashMap<SysComp, usize>,
    untracked: u64,
}

impl Matcher {
    /// `capacity` is rounded up to a power of two; it must exceed the number
    /// of requests sent within one timeout (the engine sizes it as twice
    /// that, so late replies are recognised for about one more timeout).
    pub fn new(timeout: Nanos, capacity: usize, first_seq: u32) -> Self {
        let capacity = capacity.max(2).next_power_of_two();
        Matcher {
            timeout,
            window: Window::default(),
            first_seq,
            slots: vec![Slot::default(); capacity],
            mask: capacity as u64 - 1,
            next_n: 0,
            next_expiry: 0,
            responders: Vec::new(),
            index: HashMap::new(),
            untracked: 0,
        }
    }

    /// Where each responder's window opens (by default, at its first
    /// answer).
    pub(crate) fn with_window(mut self, window: Window) -> Self {
        self.window = window;
        self
    }

    fn idx(&self, n: u64) -> usize {
        (n & self.mask) as usize
    }

    fn seq_of(&self, n: u64) -> u32 {
        self.first_seq.wrapping_add(n as u32)
    }

    /// Records a request sent at `sent_at` carrying `token`. Tokens must
    /// increase strictly when replies are looked up by token.
    pub fn on_send(
        &mut self,
        token: u64,
        sent_at: Nanos,
        out: &mut impl FnMut(MatchEvent),
    ) -> Issued {
        let n = self.next_n;
        let capacity = self.slots.len() as u64;
        // The slot's previous request must be decided before it is reused.
        // Sized correctly this never triggers; if it does, those requests
        // are decided now (as at a timeout) rather than silently forgotten.
        if n >= capacity && self.next_expiry <= n - capacity {
            self.decide_through(n - capacity, sent_at, out);
        }
        let idx = self.idx(n);
        for r in &mut self.responders {
            r.set_answered(idx, false);
        }
        self.slots[idx] = Slot {
            n1: n + 1,
            token,
            sent_at,
        };
        self.next_n += 1;
        Issued {
            n,
            seq: self.seq_of(n),
        }
    }

    /// When the oldest undecided request times out.
    pub fn next_deadline(&self) -> Option<Nanos> {
        (self.next_expiry < self.next_n)
            .then(|| self.slots[self.idx(self.next_expiry)].sent_at + self.timeout)
    }

    /// Decides every request whose timeout has passed at `now`.
    pub fn expire(&mut self, now: Nanos, out: &mut impl FnMut(MatchEvent)) {
        while let Some(deadline) = self.next_deadline() {
            if deadline > now {
                break;
            }
            self.decide(self.next_expiry, deadline, out);
            self.next_expiry += 1;
        }
    }

    fn decide_through(&mut self, last: u64, at: Nanos, out: &mut impl FnMut(MatchEvent)) {
        while self.next_expiry <= last {
            self.decide(self.next_expiry, at, out);
            self.next_expiry += 1;
        }
    }

    fn decide(&mut self, n: u64, at: Nanos, out: &mut impl FnMut(MatchEvent)) {
        let idx = self.idx(n);
        let seq = self.seq_of(n);
        let sent_at = self.slots[idx].sent_at;
        for r in self.responders.iter_mut().filter(|r| r.in_window(n)) {
            if r.has_answered(idx) {
                r.counts.sent += 1;
            } else {
                r.charge_lost(seq, sent_at, at, out);
            }
        }
    }

    fn find(&self, lookup: Lookup) -> Option<u64> {
        match lookup {
            Lookup::Seq { seq, token } => {
                let n_low = u64::from(seq.wrapping_sub(self.first_seq));
                let slot = self.slots[self.idx(n_low)];
                let n = slot.n1.checked_sub(1)?;
                (n as u32 == n_low as u32 && slot.token == token).then_some(n)
            }
            Lookup::Token(token) => {
                // Tokens rise with n: binary search the requests still held.
                let (mut lo, mut hi) = (
                    self.next_n.saturating_sub(self.slots.len() as u64),
                    self.next_n,
                );
                while lo < hi {
                    let mid = lo + (hi - lo) / 2;
                    let slot = self.slots[self.idx(mid)];
                    match slot.token.cmp(&token) {
                        std::cmp::Ordering::Equal => return Some(mid),
                        std::cmp::Ordering::Less => lo = mid + 1,
                        std::cmp::Ordering::Greater => hi = mid,
                    }
                }
                None
            }
        }
    }

    fn responder_index(&mut self, id: SysComp) -> Option<usize> {
        if let Some(&i) = self.index.get(&id) {
            return Some(i);
        }
        if self.responders.len() >= MAX_RESPONDERS {
            self.untracked += 1;
            return None;
        }
        self.responders.push(Responder::new(id));
        self.index.insert(id, self.responders.len() - 1);
        Some(self.responders.len() - 1)
    }

    /// Handles a reply addressed to us from `responder`, received at `at`.
    pub fn on_reply(
        &mut self,
        responder: SysComp,
        lookup: Lookup,
        at: Nanos,
        out: &mut impl FnMut(MatchEvent),
    ) {
        // Decide everything due by the reply's own timestamp first, so
        // "late" means exactly "after the timeout".
        self.expire(at, out);
        let Some(ri) = self.responder_index(responder) else {
            return;
        };
        let Some(n) = self.find(lookup) else {
            self.responders[ri].counts.stale += 1;
            out(MatchEvent::Stale { responder, at });
            return;
        };
        let capacity = self.slots.len();
        let idx = self.idx(n);
        let seq = self.seq_of(n);
        let sent_at = self.slots[idx].sent_at;
        let rtt = at.saturating_sub(sent_at);
        let expired = n < self.next_expiry;
        let r = &mut self.responders[ri];
        if r.answered.is_empty() {
            r.answered = vec![0; capacity.div_ceil(64)];
        }
        if r.has_answered(idx) {
            r.counts.duplicate += 1;
            out(MatchEvent::Duplicate {
                responder,
                seq,
                rtt,
                sent_at,
                at,
            });
            return;
        }
        r.set_answered(idx, true);
        if self.window == Window::FromStart && r.window_start.is_none() {
            self.open_window_from_start(ri, at, out);
        }
        if expired {
            self.open_window_at(ri, n, at, out);
            let r = &mut self.responders[ri];
            r.counts.late += 1;
            out(MatchEvent::Late {
                responder,
                seq,
                rtt,
                sent_at,
                at,
            });
            return;
        }
        let r = &mut self.responders[ri];
        let first = r.counts.received == 0;
        // A reordered reply to an older, still undecided request moves the
        // window back: nothing from it on has been decided yet.
        if r.window_start.is_none_or(|start| n < start) {
            r.window_start = Some(n);
        }
        let out_of_order = r.highest.is_some_and(|h| n < h);
        r.highest = Some(r.highest.map_or(n, |h| h.max(n)));
        r.counts.received += 1;
        r.counts.out_of_order += u64::from(out_of_order);
        r.rtt.record(rtt);
        out(MatchEvent::Reply {
            responder,
            seq,
            rtt,
            sent_at,
            at,
            out_of_order,
            first_from_responder: first,
        });
    }

    /// A late reply to the decided request `n` from responder `ri`: if `n`
    /// lies before its window, the window opens (or moves back) to `n`,
    /// and the requests from `n` that were decided without it are charged
    /// now, each lost (a reply in time to any of them would have opened
    /// the window there). All of them are still in the ring: `n` is.
    fn open_window_at(&mut self, ri: usize, n: u64, at: Nanos, out: &mut impl FnMut(MatchEvent)) {
        let r = &self.responders[ri];
        if r.in_window(n) {
            return;
        }
        let charged_from = r.window_start.unwrap_or(u64::MAX).min(self.next_expiry);
        for m in n..charged_from {
            let (seq, sent_at) = (self.seq_of(m), self.slots[self.idx(m)].sent_at);
            self.responders[ri].charge_lost(seq, sent_at, at, out);
        }
        self.responders[ri].window_start = Some(n);
    }

    /// A responder first heard in a run whose every request counts: the
    /// requests decided before are charged now, each lost.
    fn open_window_from_start(&mut self, ri: usize, at: Nanos, out: &mut impl FnMut(MatchEvent)) {
        let held_from = self.next_n.saturating_sub(self.slots.len() as u64);
        debug_assert_eq!(held_from, 0, "the ring holds every request of the run");
        self.open_window_at(ri, held_from, at, out);
    }

    /// Ends the run: requests still within their timeout are counted for the
    /// responders that already answered them, and otherwise left out (they
    /// are neither received nor lost: each responder's `in_flight`).
    /// Returns how many were unanswered by at least one responder.
    pub fn finish(&mut self) -> u64 {
        let mut in_flight = 0;
        for n in self.next_expiry..self.next_n {
            let idx = self.idx(n);
            let mut unanswered = false;
            for r in self.responders.iter_mut().filter(|r| r.in_window(n)) {
                if r.has_answered(idx) {
                    r.counts.sent += 1;
                } else {
                    r.counts.in_flight += 1;
                    unanswered = true;
                }
            }
            in_flight += u64::from(unanswered);
        }
        self.next_expiry = self.next_n;
        let issued = self.next_n;
        for r in &mut self.responders {
            r.counts.not_charged = r.window_start.unwrap_or(issued);
        }
        in_flight
    }

    /// True when at least one responder is known and every undecided
    /// request has been answered by every responder whose window covers it:
    /// after the last request, there is nothing left to wait for.
    pub(crate) fn all_answered(&self) -> bool {
        let active: Vec<&Responder> = self
            .responders
            .iter()
            .filter(|r| r.window_start.is_some())
            .collect();
        !active.is_empty()
            && (self.next_expiry..self.next_n).all(|n| {
                let idx = self.idx(n);
                active
                    .iter()
                    .all(|r| !r.in_window(n) || r.has_answered(idx))
            })
    }

    /// A responder's counts as if the run ended now, without ending it:
    /// undecided requests it already answered count as sent (as
    /// [`Matcher::finish`] counts them), the others in flight; and the
    /// requests before its window, not charged.
    pub(crate) fn counts_now(&self, r: &Responder) -> Counts {
        let mut counts = r.counts;
        for n in (self.next_expiry..self.next_n).filter(|&n| r.in_window(n)) {
            if r.has_answered(self.idx(n)) {
                counts.sent += 1;
            } else {
                counts.in_flight += 1;
            }
        }
        counts.not_charged = r.window_start.unwrap_or(self.next_n);
        counts
    }

    /// Requests still within their timeout, whoever answered them.
    pub(crate) fn undecided(&self) -> u64 {
        self.next_n - self.next_expiry
    }

    /// Requests issued so far.
    pub(crate) fn issued(&self) -> u64 {
        self.next_n
    }

    pub fn responders(&self) -> &[Responder] {
        &self.responders
    }

    /// The responders, for a summary that keeps them once the run is over.
    pub(crate) fn into_responders(self) -> Vec<Responder> {
        self.responders
    }

    #[cfg(test)]
    pub(crate) fn responder(&self, id: SysComp) -> Option<&Responder> {
        self.index.get(&id).map(|&i| &self.responders[i])
    }

    /// Replies from responders beyond [`MAX_RESPONDERS`].
    pub(crate) fn untracked(&self) -> u64 {
        self.untracked
    }
}

#[cfg(test)]
mod tests;
