//! "Send until acknowledged" (the seed's message management) for
//! COMMAND_LONG: which commands are pending, when each is re-sent, when it
//! has failed, and exact per-target counts.
//!
//! Pure and synchronous: time is passed in, decisions come out as
//! [`CommandEvent`]s (the session turns `Send` into a frame on the wire).
//! Rules:
//! - Pending commands are keyed by (target, command): MAVLink allows one
//!   command of an id in flight per target. A command due while the
//!   previous one with its key is still pending is **skipped** (counted),
//!   so the schedule is never silently delayed.
//! - Attempt k (1-based) goes out at first + (k-1) x retry interval, with
//!   `confirmation = k - 1`; after the last attempt the command fails one
//!   retry interval later.
//! - An ACK removes its entry only if present. An ACK for a key whose last
//!   command failed is **late**; any further ACK for a key already
//!   decided is a **duplicate**. Neither changes the other counts.

use std::collections::BTreeMap;

use super::CommandEvent;
use crate::engine::roster::Roster;
use crate::engine::stats::RttStats;
use crate::engine::summary::{AckResult, CommandTargetSummary, HISTOGRAM_ROWS};
use crate::engine::Nanos;
use crate::frame::SysComp;

type Key = (SysComp, u16);

#[derive(Debug, Clone, Copy)]
struct Pending {
    n: u64,
    first: Nanos,
    attempts: u32,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Fate {
    Acked,
    Failed,
    /// Failed, then its late ACK came.
    LateAcked,
}

/// Exact figures for one target.
#[derive(Clone)]
pub(crate) struct TargetStats {
    pub(crate) id: SysComp,
    /// Commands put on the wire (skipped ones are not).
    pub(crate) commands: u64,
    pub(crate) acknowledged: u64,
    pub(crate) failed: u64,
    pub(crate) skipped: u64,
    pub(crate) late_acks: u64,
    pub(crate) duplicate_acks: u64,
    /// `by_attempts[k - 1]`: commands acknowledged after k transmissions.
    pub(crate) by_attempts: Vec<u64>,
    /// From the first transmission to the ACK.
    pub(crate) time_to_ack: RttStats,
    /// MAV_RESULT of each acknowledged command.
    pub(crate) results: BTreeMap<u8, u64>,
}

pub(crate) struct CommandTracker {
    retry_interval: Nanos,
    max_attempts: u32,
    next_n: u64,
    pending: BTreeMap<Key, Pending>,
    last: BTreeMap<Key, Fate>,
    targets: Vec<TargetStats>,
    /// ACKs for a command we never sent that target.
    unmatched_acks: u64,
}

/// Whether an ACK from `from` can answer a command sent to `target`
/// (component 0 addresses every component of the system).
fn answers(target: SysComp, from: SysComp) -> bool {
    target.sysid == from.sysid && (target.compid == 0 || target.compid == from.compid)
}

impl CommandTracker {
    /// `retries`: re-sends after the first transmission.
    pub(crate) fn new(retry_interval: Nanos, retries: u8) -> Self {
        CommandTracker {
            retry_interval,
            max_attempts: u32::from(retries) + 1,
            next_n: 0,
            pending: BTreeMap::new(),
            last: BTreeMap::new(),
            targets: Vec::new(),
            unmatched_acks: 0,
        }
    }

    fn stats(&mut self, id: SysComp) -> &mut TargetStats {
        // Targets come from the configuration, not from the wire: a few.
        let i = match self.targets.iter().position(|t| t.id == id) {
            Some(i) => i,
            None => {
                self.targets.push(TargetStats {
                    id,
                    commands: 0,
                    acknowledged: 0,
                    failed: 0,
                    skipped: 0,
                    late_acks: 0,
                    duplicate_acks: 0,
                    by_attempts: vec![0; self.max_attempts as usize],
                    time_to_ack: RttStats::new(),
                    results: BTreeMap::new(),
                });
                self.targets.len() - 1
            }
        };
        &mut self.targets[i]
    }

    /// A new command is due at `now`: sends it, or skips it while the
    /// previous one with its key is pending.
    pub(crate) fn start(
        &mut self,
        target: SysComp,
        command: u16,
        now: Nanos,
        out: &mut impl FnMut(CommandEvent),
    ) {
        self.poll(now, out);
        let key = (target, command);
        if self.pending.contains_key(&key) {
            self.stats(target).skipped += 1;
            out(CommandEvent::Skipped {
                target,
                command,
                at: now,
            });
            return;
        }
        let n = self.next_n;
        self.next_n += 1;
        self.pending.insert(
            key,
            Pending {
                n,
                first: now,
                attempts: 1,
            },
        );
        self.stats(target).commands += 1;
        out(CommandEvent::Send {
            n,
            target,
            command,
            attempt: 1,
        });
    }

    /// Re-sends and fails whatever is due at `now`.
    pub(crate) fn poll(&mut self, now: Nanos, out: &mut impl FnMut(CommandEvent)) {
        let mut failed: Vec<Key> = Vec::new();
        for (&(target, command), p) in &mut self.pending {
            // Fixed plan: a late wake-up sends every attempt that is due.
            while p.first + u64::from(p.attempts) * self.retry_interval <= now {
                if p.attempts >= self.max_attempts {
                    failed.push((target, command));
                    break;
                }
                p.attempts += 1;
                out(CommandEvent::Send {
                    n: p.n,
                    target,
                    command,
                    attempt: p.attempts,
                });
            }
        }
        for key in failed {
            let p = self.pending.remove(&key).expect("collected from pending");
            self.last.insert(key, Fate::Failed);
            self.stats(key.0).failed += 1;
            out(CommandEvent::Failed {
                n: p.n,
                target: key.0,
                command: key.1,
                attempts: p.attempts,
            });
        }
    }

    /// A COMMAND_ACK (already checked to be addressed to us) from `from`.
    pub(crate) fn on_ack(
        &mut self,
        from: SysComp,
        command: u16,
        result: u8,
        at: Nanos,
        out: &mut impl FnMut(CommandEvent),
    ) {
        // Decide what was due before the ACK arrived: an ACK after the
        // last retry interval is late, whatever the wake-up order.
        self.poll(at, out);
        let pending = self
            .pending
            .keys()
            .copied()
            .find(|&(target, c)| c == command && answers(target, from));
        if let Some(key) = pending {
            let p = self.pending.remove(&key).expect("found above");
            self.last.insert(key, Fate::Acked);
            let time_to_ack = at.saturating_sub(p.first);
            let s = self.stats(key.0);
            s.acknowledged += 1;
            s.by_attempts[p.attempts as usize - 1] += 1;
            s.time_to_ack.record(time_to_ack);
            *s.results.entry(result).or_default() += 1;
            out(CommandEvent::Acked {
                n: p.n,
                target: key.0,
                from,
                command,
                result,
                attempts: p.attempts,
                time_to_ack,
            });
            return;
        }
        let decided = self
            .last
            .iter_mut()
            .find(|((target, c), _)| *c == command && answers(*target, from));
        match decided {
            Some(((target, _), fate)) if *fate == Fate::Failed => {
                *fate = Fate::LateAcked;
                let target = *target;
                self.stats(target).late_acks += 1;
                out(CommandEvent::LateAck {
                    from,
                    command,
                    result,
                });
            }
            Some(((target, _), _)) => {
                let target = *target;
                self.stats(target).duplicate_acks += 1;
                out(CommandEvent::DuplicateAck {
                    from,
                    command,
                    result,
                });
            }
            None => self.unmatched_acks += 1,
        }
    }

    /// When the next re-send or failure is due.
    pub(crate) fn next_deadline(&self) -> Option<Nanos> {
        self.pending
            .values()
            .map(|p| p.first + u64::from(p.attempts) * self.retry_interval)
            .min()
    }

    pub(crate) fn idle(&self) -> bool {
        self.pending.is_empty()
    }

    /// Commands still pending (neither acknowledged nor failed).
    pub(crate) fn in_flight(&self) -> u64 {
        self.pending.len() as u64
    }

    pub(crate) fn targets(&self) -> &[TargetStats] {
        &self.targets
    }

    pub(crate) fn unmatched_acks(&self) -> u64 {
        self.unmatched_acks
    }
}

impl CommandTracker {
    /// Each target's figures, for the summary.
    pub(crate) fn summaries(&self, roster: &Roster) -> Vec<CommandTargetSummary> {
        self.targets()
            .iter()
            .map(|t| CommandTargetSummary {
                id: t.id,
                commands: t.commands,
                acknowledged: t.acknowledged,
                failed: t.failed,
                skipped: t.skipped,
                late_acks: t.late_acks,
                duplicate_acks: t.duplicate_acks,
                attempts: t.by_attempts.clone(),
                time_to_ack: t.time_to_ack.summary(),
                histogram: t.time_to_ack.distribution(HISTOGRAM_ROWS),
                results: t
                    .results
                    .iter()
                    .map(|(&result, &count)| AckResult {
                        result,
                        name: crate::frame::codec::result_name(result),
                        count,
                    })
                    .collect(),
                identity: roster.get(t.id).cloned(),
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const T: SysComp = SysComp::new(1, 1);
    const MS: Nanos = 1_000_000;

    fn run(
        t: &mut CommandTracker,
        f: impl FnOnce(&mut CommandTracker, &mut Vec<CommandEvent>),
    ) -> Vec<CommandEvent> {
        let mut events = Vec::new();
        f(t, &mut events);
        events
    }

    fn sends(events: &[CommandEvent]) -> Vec<u32> {
        events
            .iter()
            .filter_map(|e| match e {
                CommandEvent::Send { attempt, .. } => Some(*attempt),
                _ => None,
            })
            .collect()
    }

    #[test]
    fn acked_on_the_third_attempt() {
        let mut t = CommandTracker::new(100 * MS, 3);
        let e = run(&mut t, |t, e| t.start(T, 512, 0, &mut |x| e.push(x)));
        assert_eq!(sends(&e), vec![1]);
        assert_eq!(t.next_deadline(), Some(100 * MS));
        let e = run(&mut t, |t, e| t.poll(100 * MS, &mut |x| e.push(x)));
        assert_eq!(sends(&e), vec![2]);
        let e = run(&mut t, |t, e| t.poll(200 * MS, &mut |x| e.push(x)));
        assert_eq!(sends(&e), vec![3]);
        let e = run(&mut t, |t, e| {
            t.on_ack(T, 512, 0, 201 * MS, &mut |x| e.push(x))
        });
        assert_eq!(
            e,
            vec![CommandEvent::Acked {
                n: 0,
                target: T,
                from: T,
                command: 512,
                result: 0,
                attempts: 3,
                time_to_ack: 201 * MS
            }]
        );
        let s = &t.targets()[0];
        assert_eq!((s.commands, s.acknowledged, s.failed), (1, 1, 0));
        assert_eq!(s.by_attempts, vec![0, 0, 1, 0]);
        assert_eq!(s.results.get(&0), Some(&1));
        assert!(t.idle());
    }

    #[test]
    fn never_acked_fails_after_the_last_retry_then_late_and_duplicate() {
        let mut t = CommandTracker::new(100 * MS, 2);
        let mut e = Vec::new();
        t.start(T, 512, 0, &mut |x| e.push(x));
        // A very late wake-up: both re-sends are due, and then the failure.
        t.poll(350 * MS, &mut |x| e.push(x));
        assert_eq!(sends(&e), vec![1, 2, 3]);
        assert!(matches!(
            e.last(),
            Some(CommandEvent::Failed { attempts: 3, .. })
        ));
        t.on_ack(T, 512, 0, 360 * MS, &mut |x| e.push(x));
        t.on_ack(T, 512, 0, 361 * MS, &mut |x| e.push(x));
        // Someone else's command: not ours to count.
        t.on_ack(SysComp::new(9, 1), 512, 0, 362 * MS, &mut |x| e.push(x));
        let s = &t.targets()[0];
        assert_eq!(
            (
                s.commands,
                s.acknowledged,
                s.failed,
                s.late_acks,
                s.duplicate_acks
            ),
            (1, 0, 1, 1, 1)
        );
        assert_eq!(t.unmatched_acks(), 1);
        assert!(s.time_to_ack.summary().is_none());
    }

    #[test]
    fn one_in_flight_per_key_the_next_is_skipped() {
        let mut t = CommandTracker::new(100 * MS, 5);
        let mut e = Vec::new();
        t.start(T, 512, 0, &mut |x| e.push(x));
        t.start(T, 512, 50 * MS, &mut |x| e.push(x));
        // Another command id to the same target may fly alongside.
        t.start(T, 400, 60 * MS, &mut |x| e.push(x));
        let s = &t.targets()[0];
        assert_eq!((s.commands, s.skipped), (2, 1));
        assert_eq!(t.in_flight(), 2);
        t.on_ack(T, 512, 0, 70 * MS, &mut |x| e.push(x));
        t.start(T, 512, 80 * MS, &mut |x| e.push(x));
        assert_eq!(t.targets()[0].commands, 3);
    }

    #[test]
    fn an_ack_from_any_component_answers_a_component_0_target() {
        let mut t = CommandTracker::new(100 * MS, 0);
        let mut e = Vec::new();
        t.start(SysComp::new(1, 0), 512, 0, &mut |x| e.push(x));
        t.on_ack(SysComp::new(1, 5), 512, 4, 10 * MS, &mut |x| e.push(x));
        assert_eq!(t.targets()[0].acknowledged, 1);
        assert_eq!(t.targets()[0].results.get(&4), Some(&1));
    }

    proptest::proptest! {
        /// Whatever the ACK times, duplicates and losses: every command sent
        /// ends acknowledged, failed or in flight, exactly once.
        #[test]
        fn every_command_is_decided_once(
            acks in proptest::collection::vec((0u64..2_000, 0u8..3), 0..60),
            retries in 0u8..5,
        ) {
            let mut t = CommandTracker::new(100 * MS, retries);
            let mut acks: Vec<(u64, u8)> = acks;
            acks.sort_unstable();
            let mut next_start = 0;
            for (at_ms, copies) in acks {
                while next_start <= at_ms {
                    t.start(T, 512, next_start * MS, &mut |_| {});
                    next_start += 150;
                }
                for _ in 0..copies {
                    t.on_ack(T, 512, 0, at_ms * MS, &mut |_| {});
                }
            }
            t.poll(10_000 * MS, &mut |_| {});
            if let Some(s) = t.targets().first() {
                proptest::prop_assert_eq!(s.commands, s.acknowledged + s.failed + t.in_flight());
                proptest::prop_assert_eq!(s.by_attempts.iter().sum::<u64>(), s.acknowledged);
                proptest::prop_assert_eq!(s.time_to_ack.count(), s.acknowledged);
                proptest::prop_assert!(s.late_acks <= s.failed);
            }
        }
    }
}
