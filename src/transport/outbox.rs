//! Frames queued to leave together: a burst of requests that fell due at
//! one wake-up, or the answers to one batch of requests. A link that can
//! write them all with one system call (UDP: `sendmmsg`) does; the others
//! write them one by one ([`super::Transport::send_all`]).

use super::link::PathId;

/// Where a queued frame goes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum To {
    /// Every peer of the link, as [`super::Transport::send`].
    Every,
    /// One path only, as [`super::Transport::send_to`].
    Path(PathId),
}

/// Queued frames, in order; reused between bursts so queueing does not
/// allocate once the run is warm.
#[derive(Debug, Default)]
pub struct Outbox {
    bytes: Vec<u8>,
    /// End offset in `bytes` and destination of each frame.
    frames: Vec<(usize, To)>,
}

impl Outbox {
    /// Queues a copy of `frame` for `to`.
    pub(crate) fn push(&mut self, frame: &[u8], to: To) {
        self.bytes.extend_from_slice(frame);
        self.frames.push((self.bytes.len(), to));
    }

    pub(crate) fn len(&self) -> usize {
        self.frames.len()
    }

    pub(crate) fn is_empty(&self) -> bool {
        self.frames.is_empty()
    }

    /// The queued frames in order, with where each goes.
    pub fn frames(&self) -> impl Iterator<Item = (&[u8], To)> + '_ {
        let mut start = 0;
        self.frames.iter().map(move |&(end, to)| {
            let frame = &self.bytes[start..end];
            start = end;
            (frame, to)
        })
    }

    /// Empties the box, keeping its memory.
    pub(crate) fn clear(&mut self) {
        self.bytes.clear();
        self.frames.clear();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frames_come_out_in_order_with_their_destinations() {
        let mut outbox = Outbox::default();
        outbox.push(b"abc", To::Every);
        outbox.push(b"", To::Path(3));
        outbox.push(b"de", To::Path(0));
        let frames: Vec<_> = outbox.frames().collect();
        assert_eq!(
            frames,
            vec![
                (&b"abc"[..], To::Every),
                (&b""[..], To::Path(3)),
                (&b"de"[..], To::Path(0))
            ]
        );
        assert_eq!(outbox.len(), 3);
        outbox.clear();
        assert!(outbox.is_empty());
        assert_eq!(outbox.frames().count(), 0);
    }
}
