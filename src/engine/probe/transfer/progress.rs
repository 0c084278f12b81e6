//! How far one download has got, over time: what every transfer reports
//! alike (its first answer, its time to 95 % and to 100 %, its longest
//! stall, the bytes it brought), whatever it counts in.

use serde::Serialize;

use crate::engine::Nanos;

/// One download's progress, told by its protocol as it happens.
#[derive(Debug, Clone, Default)]
pub(crate) struct Progress {
    started: Nanos,
    first_answer: Option<Nanos>,
    total: Option<u64>,
    done: u64,
    at_95: Option<Nanos>,
    at_100: Option<Nanos>,
    /// When `done` last grew (or the first answer came).
    last_advance: Option<Nanos>,
    longest_stall: Nanos,
    /// `done` when the longest stall began.
    stalled_at: u64,
    /// The target's frames of this transfer, and their bytes on the wire.
    frames: u64,
    wire_bytes: u64,
}

/// Progress in figures, as the attempt's summary and its events show it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub(crate) struct ProgressFigures {
    /// What the target said there is (parameters, items, bytes).
    pub(crate) total: Option<u64>,
    /// How much of it arrived.
    pub(crate) received: u64,
    pub(crate) time_to_first_ms: Option<f64>,
    pub(crate) time_to_95_ms: Option<f64>,
    pub(crate) time_to_100_ms: Option<f64>,
    /// The longest wait between two steps forward once answers came, and
    /// how much had arrived when it began.
    pub(crate) longest_stall_ms: f64,
    pub(crate) stalled_at: u64,
    /// The target's frames of this transfer and their bytes on the wire.
    pub(crate) frames: u64,
    pub(crate) wire_bytes: u64,
    /// Units (parameters, items, bytes) a second to 100 %.
    pub(crate) per_s: Option<f64>,
    /// Bytes on the wire a second, over the transfer.
    pub(crate) wire_bytes_per_s: Option<f64>,
}

fn ms(ns: Nanos) -> f64 {
    ns as f64 / 1e6
}

impl Progress {
    pub(crate) fn new(started: Nanos) -> Self {
        Progress {
            started,
            ..Progress::default()
        }
    }

    /// A frame of the transfer from the target, of `bytes` on the wire.
    pub(crate) fn heard(&mut self, bytes: u16, now: Nanos) {
        self.frames += 1;
        self.wire_bytes += u64::from(bytes);
        if self.first_answer.is_none() {
            self.first_answer = Some(now);
            self.last_advance = Some(now);
        }
    }

    /// The target said how much there is.
    pub(crate) fn total(&mut self, total: u64, now: Nanos) {
        self.total = Some(total);
        self.advance(self.done, now);
    }

    /// `done` of the total has arrived by `now`.
    pub(crate) fn advance(&mut self, done: u64, now: Nanos) {
        if done > self.done {
            if let Some(last) = self.last_advance {
                let stall = now.saturating_sub(last);
                if stall > self.longest_stall {
                    self.longest_stall = stall;
                    self.stalled_at = self.done;
                }
            }
            self.last_advance = Some(now);
            self.done = done;
        }
        let Some(total) = self.total else {
            return;
        };
        // 95 % of 0 is reached at once; of 19 items, at the 19th.
        if self.at_95.is_none() && self.done * 100 >= total * 95 {
            self.at_95 = Some(now);
        }
        if self.at_100.is_none() && self.done >= total {
            self.at_100 = Some(now);
        }
    }

    pub(crate) fn done(&self) -> u64 {
        self.done
    }

    pub(crate) fn total_known(&self) -> Option<u64> {
        self.total
    }

    pub(crate) fn complete(&self) -> bool {
        self.at_100.is_some()
    }

    /// The figures at `now` (the end of the attempt).
    pub(crate) fn figures(&self, now: Nanos) -> ProgressFigures {
        let since = |at: Option<Nanos>| at.map(|t| ms(t.saturating_sub(self.started)));
        // A stall still going at the end counts too.
        let open_stall = match (self.at_100, self.last_advance) {
            (None, Some(last)) => now.saturating_sub(last),
            _ => 0,
        };
        let (longest_stall, stalled_at) = if open_stall > self.longest_stall {
            (open_stall, self.done)
        } else {
            (self.longest_stall, self.stalled_at)
        };
        let to_100 = self.at_100.map(|t| t.saturating_sub(self.started));
        let elapsed = self.at_100.unwrap_or(now).saturating_sub(self.started);
        let rate = |n: u64, ns: Nanos| (ns > 0).then(|| n as f64 * 1e9 / ns as f64);
        ProgressFigures {
            total: self.total,
            received: self.done,
            time_to_first_ms: since(self.first_answer),
            time_to_95_ms: since(self.at_95),
            time_to_100_ms: since(self.at_100),
            longest_stall_ms: ms(longest_stall),
            stalled_at,
            frames: self.frames,
            wire_bytes: self.wire_bytes,
            per_s: to_100.and_then(|ns| rate(self.done, ns)),
            wire_bytes_per_s: rate(self.wire_bytes, elapsed),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const MS: Nanos = 1_000_000;

    #[test]
    fn times_to_95_and_100_and_the_longest_stall() {
        let mut p = Progress::new(1_000 * MS);
        p.heard(37, 1_010 * MS);
        p.total(20, 1_010 * MS);
        for i in 1..=18 {
            p.heard(37, (1_010 + i * 10) * MS);
            p.advance(i, (1_010 + i * 10) * MS);
        }
        assert!(p.figures(2_000 * MS).time_to_95_ms.is_none());
        // The 19th after a 500 ms wait: 95 %.
        p.advance(19, 1_690 * MS);
        p.advance(20, 1_700 * MS);
        let f = p.figures(3_000 * MS);
        assert_eq!(f.time_to_first_ms, Some(10.0));
        assert_eq!(f.time_to_95_ms, Some(690.0));
        assert_eq!(f.time_to_100_ms, Some(700.0));
        assert_eq!((f.longest_stall_ms, f.stalled_at), (500.0, 18));
        assert_eq!(f.per_s, Some(20.0 / 0.7));
        assert_eq!(f.wire_bytes, 19 * 37);
    }

    #[test]
    fn an_unfinished_transfer_ends_in_its_stall() {
        let mut p = Progress::new(0);
        p.heard(10, 100 * MS);
        p.total(10, 100 * MS);
        p.advance(3, 200 * MS);
        let f = p.figures(5_200 * MS);
        assert_eq!(f.time_to_100_ms, None);
        assert_eq!(f.per_s, None);
        assert_eq!((f.longest_stall_ms, f.stalled_at), (5_000.0, 3));
    }

    #[test]
    fn nothing_to_download_is_done_at_once() {
        let mut p = Progress::new(0);
        p.heard(10, 30 * MS);
        p.total(0, 30 * MS);
        assert!(p.complete());
        assert_eq!(p.figures(30 * MS).time_to_100_ms, Some(30.0));
    }
}
