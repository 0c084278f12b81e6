//! The requests of one download that wait for an answer: each asked
//! again after the timeout, given up after its re-sends. Pure: time is
//! passed in.

use std::collections::BTreeMap;

use crate::engine::Nanos;

/// What became of a request whose time ran out.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Overdue {
    /// Send it again (its attempt number, from 2).
    Resend(u32),
    /// Its last attempt went unanswered.
    GiveUp,
}

/// Requests in flight by key (a parameter's index, an item's number, a
/// file offset), each with when it went last and how often.
#[derive(Debug, Clone)]
pub(crate) struct Asks {
    timeout: Nanos,
    retries: u32,
    pending: BTreeMap<u32, (Nanos, u32)>,
    /// Re-sends so far, and of those requests how many were answered.
    pub(crate) resent: u64,
    pub(crate) answered_after_resend: u64,
    pub(crate) given_up: u64,
}

impl Asks {
    pub(crate) fn new(timeout: Nanos, retries: u8) -> Self {
        Asks {
            timeout,
            retries: u32::from(retries),
            pending: BTreeMap::new(),
            resent: 0,
            answered_after_resend: 0,
            given_up: 0,
        }
    }

    /// `key` was sent for the first time at `now`.
    pub(crate) fn ask(&mut self, key: u32, now: Nanos) {
        self.pending.insert(key, (now, 1));
    }

    /// `key` was answered; its attempts, if it was pending.
    pub(crate) fn answered(&mut self, key: u32) -> Option<u32> {
        let (_, attempts) = self.pending.remove(&key)?;
        if attempts > 1 {
            self.answered_after_resend += 1;
        }
        Some(attempts)
    }

    pub(crate) fn is_pending(&self, key: u32) -> bool {
        self.pending.contains_key(&key)
    }

    pub(crate) fn in_flight(&self) -> usize {
        self.pending.len()
    }

    /// Forgets every request (the transfer moved on or ended).
    pub(crate) fn clear(&mut self) {
        self.pending.clear();
    }

    /// The requests whose time ran out by `now`, each with its fate: one
    /// to send again is counted and timed from `now`.
    pub(crate) fn overdue(&mut self, now: Nanos, mut each: impl FnMut(u32, Overdue)) {
        let due: Vec<u32> = self
            .pending
            .iter()
            .filter(|(_, &(at, _))| at + self.timeout <= now)
            .map(|(&k, _)| k)
            .collect();
        for key in due {
            let entry = self.pending.get_mut(&key).expect("listed above");
            if entry.1 > self.retries {
                self.pending.remove(&key);
                self.given_up += 1;
                each(key, Overdue::GiveUp);
            } else {
                entry.0 = now;
                entry.1 += 1;
                self.resent += 1;
                each(key, Overdue::Resend(entry.1));
            }
        }
    }

    /// When the next request runs out of time.
    pub(crate) fn next_deadline(&self) -> Option<Nanos> {
        self.pending
            .values()
            .map(|&(at, _)| at + self.timeout)
            .min()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_request_is_sent_again_then_given_up() {
        let mut asks = Asks::new(100, 2);
        asks.ask(7, 0);
        asks.ask(9, 50);
        assert_eq!(asks.next_deadline(), Some(100));
        let mut seen = Vec::new();
        asks.overdue(100, |k, o| seen.push((k, o)));
        assert_eq!(seen, [(7, Overdue::Resend(2))]);
        asks.overdue(150, |k, o| seen.push((k, o)));
        assert_eq!(asks.answered(9), Some(2));
        asks.overdue(200, |k, o| seen.push((k, o)));
        asks.overdue(300, |k, o| seen.push((k, o)));
        assert_eq!(
            seen,
            [
                (7, Overdue::Resend(2)),
                (9, Overdue::Resend(2)),
                (7, Overdue::Resend(3)),
                (7, Overdue::GiveUp)
            ]
        );
        assert_eq!(
            (asks.resent, asks.answered_after_resend, asks.given_up),
            (3, 1, 1)
        );
        assert_eq!(asks.next_deadline(), None);
    }
}
