//! What a byte-stream link has accepted but its peer has not yet taken:
//! bounded, so a peer that stops reading (a pty nobody reads, a TCP peer
//! that stalls, a serial port held off by flow control) costs a refused
//! frame, never a blocked run.

/// Bytes the queue holds at most, beyond the kernel's own buffer: a few
/// hundred ms of a 57600-baud radio, so the requests waiting here add
/// little to a round trip before the link refuses more.
pub(super) const MAX_QUEUED: usize = 4096;

#[derive(Debug, Default)]
pub(super) struct OutQueue {
    buf: Vec<u8>,
    /// Bytes of `buf` already written.
    start: usize,
    /// Frames refused because they did not fit.
    refused: u64,
}

impl OutQueue {
    /// Takes `frame` whole if it fits, else refuses it (counted): a frame
    /// is never split between the wire and the floor.
    pub(super) fn offer(&mut self, frame: &[u8]) -> bool {
        if self.len() + frame.len() > MAX_QUEUED {
            self.refused += 1;
            return false;
        }
        if self.start == self.buf.len() {
            self.buf.clear();
            self.start = 0;
        }
        self.buf.extend_from_slice(frame);
        true
    }

    /// Refuses a frame without offering it (the rest of a burst after the
    /// first refusal, so what was sent is always a prefix of it).
    pub(super) fn refuse(&mut self) {
        self.refused += 1;
    }

    /// What is waiting to be written.
    pub(super) fn waiting(&self) -> &[u8] {
        &self.buf[self.start..]
    }

    /// `n` bytes of [`waiting`](Self::waiting) were written.
    pub(super) fn written(&mut self, n: usize) {
        self.start = (self.start + n).min(self.buf.len());
        if self.start == self.buf.len() {
            self.buf.clear();
            self.start = 0;
        }
    }

    pub(super) fn len(&self) -> usize {
        self.buf.len() - self.start
    }

    pub(super) fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The connection broke: what waited was for it.
    pub(super) fn clear(&mut self) {
        self.buf.clear();
        self.start = 0;
    }

    pub(super) fn refused(&self) -> u64 {
        self.refused
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frames_are_taken_whole_or_refused_and_the_queue_stays_bounded() {
        let mut q = OutQueue::default();
        let frame = [7u8; 100];
        let fit = MAX_QUEUED / frame.len();
        for _ in 0..fit {
            assert!(q.offer(&frame));
        }
        assert!(!q.offer(&frame), "the queue is full");
        assert_eq!(q.refused(), 1);
        assert_eq!(q.len(), fit * 100);
        // Half a frame written: its other half stays first in line.
        q.written(50);
        assert_eq!(q.waiting().len(), fit * 100 - 50);
        let room = MAX_QUEUED - q.len();
        assert!(q.offer(&vec![1u8; room]), "room for {room} bytes");
        assert!(!q.offer(&[1u8; 1]));
        assert_eq!(q.len(), MAX_QUEUED);
        q.written(q.len());
        assert!(q.is_empty());
        assert!(q.offer(&frame));
        assert_eq!(q.refused(), 2);
        assert_eq!(q.waiting(), &frame[..]);
    }
}
