//! The uplink as our probes found it, for the failsafe replay: a request
//! the vehicle answered reached it; one it did not is taken as lost on
//! the way up (inferred: the reply may have been the one lost). Between
//! two requests the uplink stays as the earlier found it, and a message
//! the failsafe watches, sent at its rate, is delivered while it is up.
//!
//! Outcomes come as requests are decided, not in the order they were
//! sent (a reply before an earlier request's timeout): they wait here
//! until every request sent before them is decided, which is at most a
//! reply timeout, so memory holds the requests of one timeout.

use std::collections::BTreeMap;

use super::failsafe::Replay;
use crate::engine::Nanos;

/// A watched message's times at its rate, and its replay.
#[derive(Debug, Clone)]
pub(crate) struct Paced {
    pub(crate) replay: Replay,
    period: Nanos,
    next: Nanos,
}

impl Paced {
    pub(crate) fn new(replay: Replay) -> Self {
        let period = (1e9 / replay.model.rate_hz).round().max(1.0) as Nanos;
        Paced {
            replay,
            period,
            next: 0,
        }
    }

    /// The messages sent before `until`, delivered or not.
    pub(crate) fn send_until(&mut self, until: Nanos, delivered: impl Fn(Nanos) -> bool) {
        while self.next < until {
            self.replay.message(self.next, delivered(self.next));
            self.next += self.period;
        }
    }
}

/// The uplink as our requests found it.
#[derive(Debug, Clone)]
pub(crate) struct ProbedUplink {
    /// Decided, by the time they were sent: reached the vehicle or not.
    waiting: BTreeMap<Nanos, bool>,
    /// Since when the uplink has been as found, and how.
    since: Nanos,
    up: bool,
    /// How long a request can stay undecided, and a margin.
    horizon: Nanos,
    outcomes: u64,
    pub(crate) paced: Vec<Paced>,
}

impl ProbedUplink {
    pub(crate) fn new(timeout: Nanos, paced: Vec<Paced>) -> Self {
        ProbedUplink {
            waiting: BTreeMap::new(),
            since: 0,
            // The start is as if a request had just been answered.
            up: true,
            horizon: timeout.saturating_add(1_000_000_000),
            outcomes: 0,
            paced,
        }
    }

    /// Requests decided.
    pub(crate) fn outcomes(&self) -> u64 {
        self.outcomes
    }

    /// The requests before the first decided one went unanswered (the
    /// matcher counts a responder's losses from its first answer on, and
    /// none for one never heard): the uplink was down from the start.
    pub(crate) fn unanswered_from_start(&mut self) {
        if self.since == 0 && self.waiting.keys().next().is_none_or(|&s| s > 0) {
            self.up = false;
        }
    }

    /// The request sent at `sent_at` reached the vehicle or not, decided
    /// at `at`. A late reply after a loss turns it to reached.
    pub(crate) fn decided(&mut self, sent_at: Nanos, reached: bool, at: Nanos) {
        if sent_at < self.since {
            return;
        }
        let e = self.waiting.entry(sent_at).or_insert(reached);
        *e |= reached;
        self.outcomes += 1;
        self.play(at.saturating_sub(self.horizon));
    }

    /// Plays the requests sent before `before`: every one of them is decided.
    fn play(&mut self, before: Nanos) {
        while let Some(entry) = self.waiting.first_entry() {
            if *entry.key() >= before {
                break;
            }
            let (sent_at, reached) = entry.remove_entry();
            self.until(sent_at);
            self.since = sent_at;
            self.up = reached;
        }
    }

    fn until(&mut self, t: Nanos) {
        let up = self.up;
        for p in &mut self.paced {
            p.send_until(t, |_| up);
        }
    }

    /// Everything to `end`.
    pub(crate) fn finish(mut self, end: Nanos) -> Vec<Replay> {
        self.play(Nanos::MAX);
        self.until(end.saturating_add(1));
        self.paced.into_iter().map(|p| p.replay).collect()
    }
}
