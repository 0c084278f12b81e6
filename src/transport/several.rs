//! Several links as one transport ([`Several`]): `mavping respond` on a
//! radio and an LTE modem serves one identity, with one packet sequence,
//! on both, as a vehicle with two links does. What goes to every peer (a
//! HEARTBEAT, a stream) goes out on every link, the same bytes; an answer
//! goes back only on the link and peer its request came from.
//!
//! A frame's path carries its link: the link's index above
//! [`LINK_SHIFT`] bits, the link's own path below.

use std::time::Duration;

use futures_util::future::select_all;
use tokio::time::Instant;

use super::any_link::Link;
use super::link::{Inbound, LinkError, LinkKind, PathId, RxClock, Transport};
use super::outbox::{Outbox, To};
use crate::frame::ScanStats;

/// Bits of a path left to the link's own paths (its peers, numbered
/// upwards): 16 million, more than any link meets.
const LINK_SHIFT: u32 = 24;
const OWN_PATH: PathId = (1 << LINK_SHIFT) - 1;

/// The link a path of a [`Several`] came on (0 for a path of one link).
pub(crate) fn link_of(path: PathId) -> usize {
    (path >> LINK_SHIFT) as usize
}

/// What went through one link, counted as the transport saw it.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub(crate) struct Traffic {
    /// Frames received (damaged ones too).
    pub(crate) received: u64,
    /// Frames written: to every peer, or to one.
    pub(crate) sent: u64,
    /// Of those, the frames written to one peer only (answers, greetings):
    /// no other link carried them.
    pub(crate) to_one: u64,
}

pub(crate) struct Several {
    links: Vec<Link>,
    /// Each link's frames of one `recv`, before their paths are joined.
    inbound: Vec<Vec<Inbound>>,
    /// Each link's share of a batch to send.
    outboxes: Vec<Outbox>,
    traffic: Vec<Traffic>,
}

impl Several {
    pub(crate) fn new(links: Vec<Link>) -> Self {
        let n = links.len();
        assert!(n > 0 && n <= 1 << (PathId::BITS - LINK_SHIFT), "{n} links");
        Several {
            links,
            inbound: (0..n).map(|_| Vec::new()).collect(),
            outboxes: (0..n).map(|_| Outbox::default()).collect(),
            traffic: vec![Traffic::default(); n],
        }
    }

    /// What went through each link, in the order given.
    pub(crate) fn traffic(&self) -> &[Traffic] {
        &self.traffic
    }

    /// Moves link `k`'s frames to `out`, their paths joined with `k`.
    fn collect(&mut self, k: usize, out: &mut Vec<Inbound>) {
        let frames = &mut self.inbound[k];
        self.traffic[k].received += frames.len() as u64;
        out.extend(frames.drain(..).map(|mut i| {
            i.path = join(k, i.path);
            i
        }));
    }
}

/// Link `k`'s own `path` as a path of the whole. A frame with no path to
/// answer on (a full peer table) keeps having none.
fn join(k: usize, path: PathId) -> PathId {
    if path == PathId::MAX {
        return PathId::MAX;
    }
    ((k as PathId) << LINK_SHIFT) | (path & OWN_PATH)
}

/// A path of the whole as (link, the link's own path).
fn split(path: PathId) -> (usize, PathId) {
    (link_of(path), path & OWN_PATH)
}

impl Transport for Several {
    async fn send(&mut self, frame: &[u8]) -> Result<Instant, LinkError> {
        let mut first = None;
        for (link, traffic) in self.links.iter_mut().zip(&mut self.traffic) {
            let at = link.send(frame).await?;
            traffic.sent += 1;
            first.get_or_insert(at);
        }
        Ok(first.unwrap_or_else(Instant::now))
    }

    async fn send_to(&mut self, path: PathId, frame: &[u8]) -> Result<Instant, LinkError> {
        let (k, own) = split(path);
        let Some(link) = self.links.get_mut(k) else {
            return Ok(Instant::now());
        };
        let at = link.send_to(own, frame).await?;
        self.traffic[k].sent += 1;
        self.traffic[k].to_one += 1;
        Ok(at)
    }

    /// Each link's share in one `send_all`, so a UDP link still writes a
    /// batch with one system call.
    async fn send_all(&mut self, outbox: &Outbox) -> Result<Instant, LinkError> {
        let mut to_one = vec![0; self.links.len()];
        for (frame, to) in outbox.frames() {
            match to {
                To::Every => self
                    .outboxes
                    .iter_mut()
                    .for_each(|o| o.push(frame, To::Every)),
                To::Path(path) => {
                    let (k, own) = split(path);
                    if let Some(o) = self.outboxes.get_mut(k) {
                        o.push(frame, To::Path(own));
                        to_one[k] += 1;
                    }
                }
            }
        }
        let mut first = None;
        let mut failed = None;
        let each = self
            .links
            .iter_mut()
            .zip(&self.outboxes)
            .zip(self.traffic.iter_mut().zip(to_one));
        for ((link, outbox), (traffic, to_one)) in each {
            if outbox.is_empty() || failed.is_some() {
                continue;
            }
            match link.send_all(outbox).await {
                Ok(at) => {
                    traffic.sent += outbox.len() as u64;
                    traffic.to_one += to_one;
                    first.get_or_insert(at);
                }
                Err(e) => failed = Some(e),
            }
        }
        // Nothing of this batch is left for the next.
        self.outboxes.iter_mut().for_each(Outbox::clear);
        match failed {
            Some(e) => Err(e),
            None => Ok(first.unwrap_or_else(Instant::now)),
        }
    }

    /// Waits on every link at once; cancel-safe as each link's `recv` is.
    async fn recv(&mut self, out: &mut Vec<Inbound>) -> Result<(), LinkError> {
        let waits = self
            .links
            .iter_mut()
            .zip(&mut self.inbound)
            .map(|(link, inbound)| Box::pin(link.recv(inbound)));
        let (received, k, _) = select_all(waits).await;
        received?;
        self.collect(k, out);
        Ok(())
    }

    fn read_waiting(&mut self, out: &mut Vec<Inbound>) -> Result<bool, LinkError> {
        let mut any = false;
        for k in 0..self.links.len() {
            any |= self.links[k].read_waiting(&mut self.inbound[k])?;
            self.collect(k, out);
        }
        Ok(any)
    }

    fn has_peers(&self) -> bool {
        self.links.iter().any(Transport::has_peers)
    }

    fn scan_stats(&self) -> ScanStats {
        let mut all = ScanStats::default();
        for link in &self.links {
            all.add(&link.scan_stats());
        }
        all
    }

    fn rx_clock(&self) -> RxClock {
        self.links[0].rx_clock()
    }

    fn downtime(&self) -> Duration {
        self.links
            .iter()
            .map(Transport::downtime)
            .max()
            .unwrap_or_default()
    }

    fn refused(&self) -> u64 {
        self.links.iter().map(Transport::refused).sum()
    }

    fn unreachable(&self) -> u64 {
        self.links.iter().map(Transport::unreachable).sum()
    }

    fn kind(&self) -> LinkKind {
        self.links[0].kind()
    }

    fn next_wake(&mut self, at: Option<Instant>) {
        self.links.iter_mut().for_each(|l| l.next_wake(at));
    }

    fn keep_raw(&mut self) {
        self.links.iter_mut().for_each(Transport::keep_raw);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_path_keeps_its_link_and_its_own_number() {
        for (k, own) in [(0, 0), (0, 7), (1, 0), (3, 12_345), (255, OWN_PATH)] {
            let path = join(k, own);
            assert_eq!(split(path), (k, own));
            assert_eq!(link_of(path), k);
        }
        assert_eq!(join(2, PathId::MAX), PathId::MAX);
        // One link's paths are its own.
        assert_eq!(link_of(41), 0);
    }
}
