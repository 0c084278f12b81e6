//! The wire between mavping and the responders: one shared half-duplex
//! wire at `baud=` with its buffer, or the radio pair of `air=`; when a
//! frame is through, or that a full buffer drops it.

use std::time::Duration;

use tokio::time::Instant;

use super::link::SimLink;

/// The shared wire of a `baud=` link: when it is next free.
#[derive(Default)]
pub(super) struct Wire {
    pub(super) free_at: Option<Instant>,
}

impl SimLink {
    /// Wire time of `bytes` at the link's baud.
    fn wire_time(&self, bytes: usize) -> Duration {
        let baud = u64::from(self.params.baud.unwrap_or(u32::MAX));
        Duration::from_nanos(bytes as u64 * 10 * 1_000_000_000 / baud)
    }

    /// Bytes waiting for the wire at `now`.
    pub(super) fn backlog_bytes(&self, now: Instant) -> u64 {
        let Some(baud) = self.params.baud else {
            return 0;
        };
        let wait = self
            .wire
            .free_at
            .map_or(Duration::ZERO, |t| t.saturating_duration_since(now));
        (wait.as_nanos() * u128::from(baud) / 10 / 1_000_000_000) as u64
    }

    /// Puts `bytes` on the shared wire: when their last bit is sent, or
    /// None when the buffer is full and they are dropped.
    fn serialise(&mut self, now: Instant, bytes: usize) -> Option<Instant> {
        if self.params.baud.is_none() {
            return Some(now);
        }
        if self.backlog_bytes(now) + bytes as u64 > self.params.buffer {
            return None;
        }
        let start = self.wire.free_at.map_or(now, |t| t.max(now));
        let done = start + self.wire_time(bytes);
        self.wire.free_at = Some(done);
        Some(done)
    }

    /// When a responder's side of the link has sent what it was given by
    /// `at`: the shared wire's, or the remote radio's serial port; `at`
    /// without `baud=`.
    pub(super) fn responder_free_at(&self, at: Instant) -> Instant {
        let free = match self.pair.as_ref() {
            Some(pair) => Some(self.instant(pair.remote_uart_free_ns())),
            None => self.wire.free_at,
        };
        free.map_or(at, |t| t.max(at))
    }

    /// A frame we send at `now`: when the responders have it, or `None`
    /// when a full buffer drops it.
    pub(super) fn uplink(&mut self, now: Instant, bytes: usize) -> Option<Instant> {
        let at = self.ns(now);
        match self.pair.as_mut() {
            Some(pair) => {
                let done = pair.uplink(at, bytes as u64).ok()?;
                Some(self.instant(done))
            }
            None => self.serialise(now, bytes),
        }
    }

    /// A reply to a request the responder has from `request_done` on,
    /// answered `up` later: when it reaches us but for the return leg's
    /// delay, or `None` when a full buffer drops it.
    pub(super) fn downlink(
        &mut self,
        request_done: Instant,
        up: Duration,
        bytes: usize,
    ) -> Option<Instant> {
        let at = self.ns(request_done + up);
        match self.pair.as_mut() {
            Some(pair) => {
                let done = pair.downlink(at, bytes as u64).ok()?;
                Some(self.instant(done))
            }
            // One shared wire: the reply is queued for it when the request
            // is, so the wire's order is the requests' order.
            None => self.serialise(request_done, bytes).map(|done| done + up),
        }
    }
}
