//! A light count of one stream's 8-bit packet sequence: its loss, and
//! each number unwrapped onto a line that never wraps, so a frame 256
//! numbers later is told from the one before.
//!
//! The rules are the passive tracker's window
//! ([`crate::engine::probe::passive::tracker`]) without its silences,
//! second counters and far frames: one pair report holds every link and
//! the merged stream to the same count, so their losses compare. A
//! number 1..=127 ahead of the head is new (the ones skipped lost); one
//! 1..=127 behind fills a gap or is a duplicate; one exactly 128 away
//! restarts the count there, nothing lost. A burst of 128 or more lost in
//! a row reads as fewer (modulo 256), as it does to every counter of the
//! sequence.

/// Where the first number of a stream lands on the line: far from 0, so
/// a frame behind the first one still has a place.
const BASE: u64 = 1 << 40;
/// Half the sequence space: a number this far either way is ambiguous.
const HALF: u8 = 128;

/// The newest number counted: on the wire and on the line.
#[derive(Debug, Clone, Copy)]
struct Head {
    seq: u8,
    line: u64,
}

#[derive(Debug, Clone, Default)]
pub(super) struct SeqCount {
    head: Option<Head>,
    /// Numbers accounted (seen or lost) since the first frame.
    numbers: u64,
    /// Numbers accounted since the first frame or the last restart: how
    /// far back the bitmap says what was seen.
    stretch: u64,
    lost: u64,
    /// Bit `n` set: number `n` seen, for the 127 numbers behind the head.
    seen: [u64; 4],
}

impl SeqCount {
    /// The place of `seq` on the line: the number nearest the head with
    /// those low 8 bits (ahead on a tie).
    pub(super) fn line(&self, seq: u8) -> u64 {
        match self.head {
            None => BASE + u64::from(seq),
            Some(head) => {
                let ahead = seq.wrapping_sub(head.seq);
                if ahead == 0 || ahead > HALF {
                    head.line - u64::from(head.seq.wrapping_sub(seq))
                } else {
                    head.line + u64::from(ahead)
                }
            }
        }
    }

    /// The newest number on the line, once a frame came.
    pub(super) fn head(&self) -> Option<u64> {
        self.head.map(|h| h.line)
    }

    pub(super) fn lost(&self) -> u64 {
        self.lost
    }

    /// Numbers accounted, seen or lost: what the loss is a share of.
    pub(super) fn numbers(&self) -> u64 {
        self.numbers
    }

    /// Counts a frame numbered `seq`.
    pub(super) fn take(&mut self, seq: u8) {
        let Some(head) = self.head else {
            self.restart(seq, BASE + u64::from(seq));
            return;
        };
        let ahead = seq.wrapping_sub(head.seq);
        let behind = head.seq.wrapping_sub(seq);
        if ahead == HALF {
            self.restart(seq, head.line + u64::from(HALF));
        } else if (1..HALF).contains(&ahead) {
            for k in 1..ahead {
                self.mark(head.seq.wrapping_add(k), false);
            }
            self.mark(seq, true);
            self.lost += u64::from(ahead - 1);
            self.numbers += u64::from(ahead);
            self.stretch += u64::from(ahead);
            self.head = Some(Head {
                seq,
                line: head.line + u64::from(ahead),
            });
        } else if u64::from(behind) < self.stretch {
            if !self.is_seen(seq) {
                self.mark(seq, true);
                self.lost = self.lost.saturating_sub(1);
            }
        } else {
            // Behind the first number: the ones between were lost.
            let added = u64::from(behind) + 1 - self.stretch;
            self.mark(seq, true);
            self.lost += added - 1;
            self.numbers += added;
            self.stretch += added;
        }
    }

    fn restart(&mut self, seq: u8, line: u64) {
        self.seen = [0; 4];
        self.mark(seq, true);
        self.head = Some(Head { seq, line });
        self.numbers += 1;
        self.stretch = 1;
    }

    fn mark(&mut self, seq: u8, seen: bool) {
        let (word, bit) = (usize::from(seq / 64), seq % 64);
        if seen {
            self.seen[word] |= 1 << bit;
        } else {
            self.seen[word] &= !(1 << bit);
        }
    }

    fn is_seen(&self, seq: u8) -> bool {
        self.seen[usize::from(seq / 64)] & (1 << (seq % 64)) != 0
    }
}
