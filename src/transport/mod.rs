//! Links: every transport hands the engine whole, CRC-checked frames with a
//! receive timestamp, and sends a frame to every peer it knows.
//!
//! Our own transports, not the `mavlink` crate's connections: those answer
//! only the last UDP peer, take one TCP client, drop v1 frames by default
//! and hide CRC errors — each fatal to a ping tool.

pub mod address;
pub mod sim;
pub mod udp;

use std::io;

use thiserror::Error;
use tokio::time::Instant;

use crate::frame::{self, Frame, ScanStats};
pub use address::LinkSpec;

/// Which peer of a link a frame came from (a UDP peer address, a TCP
/// client), so an answer can go back the same way. Links with one peer use 0.
pub type PathId = u32;

/// One received frame, when it arrived, and from which path.
#[derive(Debug, Clone, Copy)]
pub struct Inbound {
    pub frame: Frame,
    pub at: Instant,
    pub path: PathId,
}

#[derive(Debug, Error)]
pub enum LinkError {
    #[error("{context}: {source}")]
    Io {
        context: String,
        #[source]
        source: io::Error,
    },
    #[error("{0}")]
    Closed(String),
}

impl LinkError {
    pub fn io(context: impl Into<String>, source: io::Error) -> Self {
        LinkError::Io {
            context: context.into(),
            source,
        }
    }
}

/// What every link does. `recv` must be cancel-safe: the engine races it
/// against its timers and drops it when a timer wins.
#[allow(async_fn_in_trait)] // used with concrete types only, never boxed
pub trait Transport {
    /// Sends one frame to every peer; returns the time just after the write.
    async fn send(&mut self, frame: &[u8]) -> Result<Instant, LinkError>;
    /// Sends one frame to one path only (answers: never amplify).
    async fn send_to(&mut self, path: PathId, frame: &[u8]) -> Result<Instant, LinkError>;
    /// Waits for data and appends the frames in it to `out`.
    async fn recv(&mut self, out: &mut Vec<Inbound>) -> Result<(), LinkError>;
    /// False while there is nobody to send to (udpin before a peer is heard).
    fn has_peers(&self) -> bool {
        true
    }
    /// What the frame scanner has skipped and rejected so far.
    fn scan_stats(&self) -> ScanStats;
}

/// Scans one datagram and appends its frames, all stamped `at`.
pub(crate) fn push_datagram(
    data: &[u8],
    at: Instant,
    path: PathId,
    stats: &mut ScanStats,
    out: &mut Vec<Inbound>,
) {
    frame::scan_datagram(data, stats, &mut |raw| {
        out.push(Inbound {
            frame: frame::decode(raw),
            at,
            path,
        })
    });
}

/// Any of mavping's links, so the engine is written once.
pub enum Link {
    Udp(udp::UdpLink),
    Sim(sim::SimLink),
}

impl Link {
    /// Opens the link a connection string names.
    pub async fn open(spec: &LinkSpec) -> Result<Link, LinkError> {
        match spec {
            LinkSpec::UdpIn(a) => Ok(Link::Udp(udp::UdpLink::listen(a).await?)),
            LinkSpec::UdpOut(a) => Ok(Link::Udp(udp::UdpLink::connect(a).await?)),
            LinkSpec::Sim(params) => Ok(Link::Sim(sim::SimLink::new(params.clone()))),
            other => Err(LinkError::Closed(format!(
                "{other}: this transport is not available in this build yet"
            ))),
        }
    }
}

impl Transport for Link {
    async fn send(&mut self, frame: &[u8]) -> Result<Instant, LinkError> {
        match self {
            Link::Udp(l) => l.send(frame).await,
            Link::Sim(l) => l.send(frame).await,
        }
    }

    async fn send_to(&mut self, path: PathId, frame: &[u8]) -> Result<Instant, LinkError> {
        match self {
            Link::Udp(l) => l.send_to(path, frame).await,
            Link::Sim(l) => l.send_to(path, frame).await,
        }
    }

    async fn recv(&mut self, out: &mut Vec<Inbound>) -> Result<(), LinkError> {
        match self {
            Link::Udp(l) => l.recv(out).await,
            Link::Sim(l) => l.recv(out).await,
        }
    }

    fn has_peers(&self) -> bool {
        match self {
            Link::Udp(l) => l.has_peers(),
            Link::Sim(l) => l.has_peers(),
        }
    }

    fn scan_stats(&self) -> ScanStats {
        match self {
            Link::Udp(l) => l.scan_stats(),
            Link::Sim(l) => l.scan_stats(),
        }
    }
}
