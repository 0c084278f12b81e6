//! What every link is to the engine: the [`Transport`] trait, a received
//! frame ([`Inbound`]), a link's failures and clock. Its own file, below
//! `mod.rs`: the links `mod.rs` opens (`sim/`, `tlog/`, ...) implement it
//! without naming the module that opens them.

use std::fmt;
use std::future::Future;
use std::io;
use std::time::Duration;

use serde::Serialize;
use thiserror::Error;
use tokio::time::Instant;

use super::outbox::{Outbox, To};
use crate::frame::signing::SignedBytes;
use crate::frame::{self, Frame, Kind, ScanStats};

/// Which peer of a link a frame came from (a UDP peer address, a TCP
/// client), so an answer can go back the same way. Links with one peer use 0.
pub(crate) type PathId = u32;

/// One received frame, when it arrived, and from which path.
#[derive(Debug, Clone)]
pub struct Inbound {
    pub(crate) frame: Frame,
    pub(crate) at: Instant,
    pub(crate) path: PathId,
    /// The frame's bytes when it is signed, for the signature check
    /// ([`crate::frame::signing::Gate`]); `None` for unsigned frames.
    pub(crate) signature: Option<SignedBytes>,
    /// The frame's bytes as received, kept only on a link told to
    /// ([`Transport::keep_raw`]) for a recording (`--tlog`), which takes
    /// them.
    pub(crate) raw: Option<Box<[u8]>>,
}

impl Inbound {
    /// The inbound form of one whole frame the scanner handed over as
    /// `kind`, with its bytes when `keep_raw` (a damaged frame too: a
    /// recording keeps what arrived, as QGroundControl's logs do).
    pub(crate) fn of(raw: &[u8], kind: Kind, at: Instant, path: PathId, keep_raw: bool) -> Self {
        Inbound {
            frame: frame::decode_as(raw, kind),
            at,
            path,
            signature: SignedBytes::of(raw),
            raw: keep_raw.then(|| raw.into()),
        }
    }
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
    /// A recorded link (a telemetry log) reached its end: the run is
    /// over, cleanly, not failed.
    #[error("end of the log")]
    End,
}

impl LinkError {
    pub(crate) fn io(context: impl Into<String>, source: io::Error) -> Self {
        LinkError::Io {
            context: context.into(),
            source,
        }
    }

    /// The same error with its OS error replaced by `f`'s (advice added).
    pub(crate) fn map_io(self, f: impl FnOnce(io::Error) -> io::Error) -> Self {
        match self {
            LinkError::Io { context, source } => LinkError::Io {
                context,
                source: f(source),
            },
            other => other,
        }
    }
}

/// Where a frame's receive time comes from. Reports (the text summary's
/// schedule line, JSON's `rx_clock`) show it as [`RxClock::as_str`] says.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum RxClock {
    /// The kernel stamped the datagram when it arrived (SO_TIMESTAMPNS):
    /// how late we read it does not change its RTT.
    #[serde(rename = "kernel receive timestamps (SO_TIMESTAMPNS)")]
    Kernel,
    /// Stamped when our read returned: read promptly to keep RTTs honest.
    #[serde(rename = "user-space receive timestamps")]
    UserSpace,
    /// The simulated link's exact arrival times.
    #[serde(rename = "simulated arrival times")]
    Simulated,
    /// A telemetry log's stamps, as the ground station wrote them.
    #[serde(rename = "the log's time stamps")]
    Log,
}

impl RxClock {
    pub(crate) fn as_str(self) -> &'static str {
        match self {
            RxClock::Kernel => "kernel receive timestamps (SO_TIMESTAMPNS)",
            RxClock::UserSpace => "user-space receive timestamps",
            RxClock::Simulated => "simulated arrival times",
            RxClock::Log => "the log's time stamps",
        }
    }
}

impl fmt::Display for RxClock {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

/// How a link meets its peers, for advice when nothing is heard.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LinkKind {
    /// Waits for peers to send first (udpin, tcpin).
    Listening,
    /// Sends to one address it was given (udpout, tcp client).
    Connecting,
    /// Sends to a broadcast address.
    Broadcast,
    /// A serial port.
    Serial,
    /// The simulated link.
    Simulated,
    /// A telemetry log, read.
    Log,
}

/// What every link does. `recv` must be cancel-safe: the engine races it
/// against its timers and drops it when a timer wins.
#[allow(async_fn_in_trait)] // used with concrete types only, never boxed
pub trait Transport {
    /// Sends one frame to every peer; returns the time taken just before the
    /// write, so an RTT may include the write but is never shorter than
    /// the true round trip.
    async fn send(&mut self, frame: &[u8]) -> Result<Instant, LinkError>;
    /// Sends one frame to one path only (answers: never amplify).
    async fn send_to(&mut self, path: PathId, frame: &[u8]) -> Result<Instant, LinkError>;
    /// Sends every frame in `outbox`, in order, each to its destination;
    /// returns the time taken just before the first write. A link that can
    /// write them with one system call does; this default writes them one
    /// by one.
    async fn send_all(&mut self, outbox: &Outbox) -> Result<Instant, LinkError> {
        let mut first = None;
        for (frame, to) in outbox.frames() {
            let at = match to {
                To::Every => self.send(frame).await?,
                To::Path(path) => self.send_to(path, frame).await?,
            };
            first.get_or_insert(at);
        }
        Ok(first.unwrap_or_else(Instant::now))
    }
    /// Waits for data and appends the frames in it to `out`.
    async fn recv(&mut self, out: &mut Vec<Inbound>) -> Result<(), LinkError>;
    /// Appends the frames already waiting, without blocking; `Ok(false)`
    /// when nothing was. Called while the session sleeps on its own clock
    /// rather than in the runtime, so a link whose readiness the runtime
    /// tracks should read the socket itself (UDP does); this default polls
    /// `recv` once.
    fn read_waiting(&mut self, out: &mut Vec<Inbound>) -> Result<bool, LinkError> {
        let mut recv = std::pin::pin!(self.recv(out));
        let mut cx = std::task::Context::from_waker(std::task::Waker::noop());
        match recv.as_mut().poll(&mut cx) {
            std::task::Poll::Ready(r) => r.map(|()| true),
            std::task::Poll::Pending => Ok(false),
        }
    }
    /// False while there is nobody to send to (udpin before a peer is heard).
    fn has_peers(&self) -> bool {
        true
    }
    /// What the frame scanner has skipped and rejected so far.
    fn scan_stats(&self) -> ScanStats;
    /// How receive times are taken.
    fn rx_clock(&self) -> RxClock {
        RxClock::UserSpace
    }
    /// How long the link has been down in total (`--reconnect`).
    fn downtime(&self) -> Duration {
        Duration::ZERO
    }
    /// Frames refused so far because the peer is not taking what was
    /// sent (a byte stream whose queue is full); a burst refused is
    /// always its tail.
    fn refused(&self) -> u64 {
        0
    }
    /// ICMP "port unreachable" reports that the link shrugged off so far
    /// (`udpout:` with `--reconnect`): evidence that nothing listens there.
    fn unreachable(&self) -> u64 {
        0
    }
    /// How the link meets its peers.
    fn kind(&self) -> LinkKind;
    /// The session's next wake-up on its own timers, told before each
    /// wait. A link that replays recorded frames on the session's clock
    /// (a telemetry log) hands over in one `recv` every frame due by
    /// then and none later; live links ignore it.
    fn next_wake(&mut self, _at: Option<Instant>) {}
    /// From now on, every frame handed over carries its bytes
    /// ([`Inbound::raw`]): a recording (`--tlog`) writes them as they came.
    /// No default: a link that forgot would leave frames out of the file.
    fn keep_raw(&mut self);
}

/// Scans one datagram and appends its frames (damaged and unknown-id ones
/// too), all stamped `at`, with their bytes when `keep_raw`.
pub(crate) fn push_datagram(
    data: &[u8],
    at: Instant,
    path: PathId,
    keep_raw: bool,
    stats: &mut ScanStats,
    out: &mut Vec<Inbound>,
) {
    frame::scan_datagram_all(data, stats, &mut |raw, kind| {
        out.push(Inbound::of(raw, kind, at, path, keep_raw))
    });
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn receive_clocks_serialise_as_reports_show_them() {
        for clock in [
            RxClock::Kernel,
            RxClock::UserSpace,
            RxClock::Simulated,
            RxClock::Log,
        ] {
            assert_eq!(serde_json::to_value(clock).unwrap(), clock.as_str());
            assert_eq!(clock.to_string(), clock.as_str());
        }
        assert_eq!(RxClock::UserSpace.as_str(), "user-space receive timestamps");
    }
}
