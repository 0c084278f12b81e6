//! Requests out on one link, replies heard on each ([`Matrix`]): what
//! MAVProxy's `ping` samples once, continuously. Every TIMESYNC request a
//! link sends is kept by its token (`ts1`, our clock: unique across the
//! run's links) until its timeout; a reply carrying that token is counted
//! in the cell (link it went out on, link it came back on), its round
//! trip on the one clock every link shares. Pure, time passed in; memory
//! bounded by the requests within a timeout ([`MAX_PENDING`]) and the
//! cells (links squared, [`MAX_LINKS`] each way).

use std::collections::{BTreeMap, HashMap, VecDeque};

use super::lag::Lag;
use crate::engine::summary::passive::percent;
use crate::engine::Nanos;

/// Requests kept waiting for replies: beyond, the oldest are let go
/// early (counted in the cells as sent, their late replies as unknown).
pub(crate) const MAX_PENDING: usize = 4096;
/// Links told apart each way.
pub(crate) const MAX_LINKS: usize = 16;

#[derive(Debug, Clone)]
struct Pending {
    out: usize,
    sent_at: Nanos,
    /// The links a reply came back on (bit per link): a second is a
    /// duplicate.
    heard: u32,
}

#[derive(Debug, Clone)]
struct Cell {
    replies: u64,
    duplicates: u64,
    rtt: Lag,
}

/// The matrix so far: see the module's documentation.
#[derive(Debug, Clone)]
pub(crate) struct Matrix {
    timeout: Nanos,
    pending: HashMap<u64, Pending>,
    /// Tokens in the order sent, for expiry.
    order: VecDeque<(Nanos, u64)>,
    requests: [u64; MAX_LINKS],
    cells: BTreeMap<(usize, usize), Cell>,
    /// Replies with no request of ours within its timeout: late, or not
    /// ours (another ground station's).
    unknown_replies: u64,
}

/// One cell: requests out on `out`, replies heard on `back`.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub(crate) struct MatrixCell {
    pub(crate) out: usize,
    pub(crate) back: usize,
    /// Requests sent on `out` (whose timeout passed, or are answered
    /// here).
    pub(crate) requests: u64,
    pub(crate) replies: u64,
    /// Of the requests, those with no reply on `back`.
    pub(crate) lost_pct: Option<f64>,
    pub(crate) duplicates: u64,
    pub(crate) rtt_p50_ms: Option<f64>,
    pub(crate) rtt_p99_ms: Option<f64>,
    pub(crate) rtt_max_ms: Option<f64>,
}

#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub(crate) struct MatrixSummary {
    /// Requests sent per link (by index).
    pub(crate) requests: Vec<u64>,
    pub(crate) cells: Vec<MatrixCell>,
    pub(crate) unknown_replies: u64,
}

impl Matrix {
    pub(crate) fn new(timeout: Nanos) -> Self {
        Matrix {
            timeout,
            pending: HashMap::new(),
            order: VecDeque::new(),
            requests: [0; MAX_LINKS],
            cells: BTreeMap::new(),
            unknown_replies: 0,
        }
    }

    /// A request with `token` went out on link `out` at `at`.
    pub(crate) fn on_request(&mut self, out: usize, token: u64, at: Nanos) {
        if out >= MAX_LINKS || self.pending.contains_key(&token) {
            return;
        }
        self.expire(at);
        if self.order.len() >= MAX_PENDING {
            if let Some((_, oldest)) = self.order.pop_front() {
                self.pending.remove(&oldest);
            }
        }
        self.requests[out] += 1;
        self.pending.insert(
            token,
            Pending {
                out,
                sent_at: at,
                heard: 0,
            },
        );
        self.order.push_back((at, token));
    }

    /// A reply carrying `token` came back on link `back` at `at`.
    pub(crate) fn on_reply(&mut self, back: usize, token: u64, at: Nanos) {
        self.expire(at);
        let timeout = self.timeout;
        let Some(p) = self.pending.get_mut(&token).filter(|_| back < MAX_LINKS) else {
            self.unknown_replies += 1;
            return;
        };
        let cell = self.cells.entry((p.out, back)).or_insert_with(|| Cell {
            replies: 0,
            duplicates: 0,
            rtt: Lag::new(timeout),
        });
        if p.heard & (1 << back) != 0 {
            cell.duplicates += 1;
            return;
        }
        p.heard |= 1 << back;
        cell.replies += 1;
        cell.rtt.record(at.saturating_sub(p.sent_at));
    }

    /// Lets go of the requests whose timeout has passed by `now`.
    fn expire(&mut self, now: Nanos) {
        while let Some(&(sent, token)) = self.order.front() {
            if now.saturating_sub(sent) <= self.timeout {
                break;
            }
            self.order.pop_front();
            self.pending.remove(&token);
        }
    }

    /// The cells, every pair of links that carried a request and a reply.
    pub(crate) fn summary(&self) -> MatrixSummary {
        let links = self
            .requests
            .iter()
            .rposition(|&n| n > 0)
            .map_or(0, |k| k + 1)
            .max(self.cells.keys().map(|&(_, b)| b + 1).max().unwrap_or(0));
        let cells = self
            .cells
            .iter()
            .map(|(&(out, back), c)| MatrixCell {
                out,
                back,
                requests: self.requests[out],
                replies: c.replies,
                lost_pct: percent(
                    self.requests[out].saturating_sub(c.replies),
                    self.requests[out],
                ),
                duplicates: c.duplicates,
                rtt_p50_ms: c.rtt.quantile_ms(0.5),
                rtt_p99_ms: c.rtt.quantile_ms(0.99),
                rtt_max_ms: c.rtt.max(),
            })
            .collect();
        MatrixSummary {
            requests: self.requests[..links].to_vec(),
            cells,
            unknown_replies: self.unknown_replies,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const MS: Nanos = 1_000_000;

    /// Requests alternate between two links; every reply comes back on
    /// both, link 1's copy 30 ms later, a few dropped: each cell counts
    /// what came back on it, a second copy on one link is a duplicate, a
    /// reply after the timeout or to no request of ours is unknown.
    #[test]
    fn each_cell_counts_the_replies_heard_on_its_link() {
        let mut m = Matrix::new(500 * MS);
        for k in 0..100u64 {
            let (out, at) = ((k % 2) as usize, k * 100 * MS);
            m.on_request(out, 1_000 + k, at);
            if k % 10 != 3 {
                m.on_reply(0, 1_000 + k, at + 20 * MS);
            }
            if k % 7 != 0 {
                m.on_reply(1, 1_000 + k, at + 50 * MS);
            }
        }
        m.on_reply(1, 1_001, 1_000 * MS + 50 * MS); // late: expired
        m.on_reply(0, 9, 10_000 * MS); // not ours
        m.on_request(0, 5_000, 20_000 * MS);
        m.on_reply(0, 5_000, 20_000 * MS + 10 * MS);
        m.on_reply(0, 5_000, 20_000 * MS + 11 * MS);
        let s = m.summary();
        assert_eq!(s.requests, [51, 50]);
        let cell = |out, back| {
            s.cells
                .iter()
                .find(|c| c.out == out && c.back == back)
                .unwrap()
        };
        // Out on 0 (even k) all came back on 0 (k % 10 == 3 is odd), and
        // the extra request's; out on 1, ten did not (3, 13, ..., 93).
        assert_eq!(cell(0, 0).replies, 51);
        assert_eq!(cell(0, 0).duplicates, 1);
        assert_eq!(cell(1, 0).replies, 40);
        assert_eq!(cell(0, 1).replies, 50 - 8); // even k ≡ 0 mod 7: 0,14,...,98
        assert_eq!(cell(1, 1).replies, 50 - 7); // odd k ≡ 0 mod 7: 7,21,...,91
        assert_eq!(cell(0, 1).rtt_p50_ms, Some(50.0));
        assert_eq!(cell(1, 0).rtt_max_ms, Some(20.0));
        assert_eq!(s.unknown_replies, 2);
    }

    #[test]
    fn pending_requests_stay_bounded() {
        let mut m = Matrix::new(u64::MAX / 4);
        for k in 0..100_000u64 {
            m.on_request(0, k + 1, k);
        }
        assert!(m.pending.len() <= MAX_PENDING && m.order.len() <= MAX_PENDING);
        assert_eq!(m.summary().requests, [100_000]);
    }
}
