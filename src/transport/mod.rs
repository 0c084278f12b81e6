//! Links: every transport hands the engine whole, CRC-checked frames with a
//! receive timestamp, and sends a frame to every peer it knows.
//!
//! Our own transports, not the `mavlink` crate's connections: those answer
//! only the last UDP peer, take one TCP client, drop v1 frames by default
//! and hide CRC errors — each fatal to a ping tool.

pub(crate) mod address;
mod advice;
mod link;
#[cfg(not(mavping_portable))]
mod mmsg;
mod out_queue;
pub(crate) mod outbox;
pub(crate) mod recording;
pub(crate) mod route;
pub(crate) mod rx_time;
pub(crate) mod serial;
pub mod sim;
#[cfg(mavping_portable)]
mod single;
pub(crate) mod stream;
pub(crate) mod tcp;
pub(crate) mod tlog;
pub mod udp;

use std::time::Duration;

use tokio::time::Instant;

use crate::frame::ScanStats;
pub use address::LinkSpec;
pub(crate) use link::push_datagram;
pub(crate) use link::{Inbound, LinkError, LinkKind, PathId, RxClock, Transport};
pub(crate) use outbox::{Outbox, To};

/// An IP address family, for `-4` and `-6`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Family {
    V4,
    V6,
}

/// How to open a link, beyond its connection string.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct LinkOptions {
    /// Baud rate of a serial port whose connection string names none.
    pub(crate) baud: u32,
    /// Reopen a tcp client or serial link that breaks, instead of ending;
    /// on `udpout:` an ICMP "port unreachable" does not end the link.
    pub(crate) reconnect: bool,
    /// With `reconnect`: a tcp client whose peer is not up yet ("connection
    /// refused") starts down and keeps trying, as after a loss (`mavping
    /// respond`, which may start before the pinger it answers).
    pub(crate) wait_for_peer: bool,
    /// Address family, local address and interface of IP links.
    pub(crate) route: route::Route,
}

impl Default for LinkOptions {
    fn default() -> Self {
        LinkOptions {
            baud: serial::DEFAULT_BAUD,
            reconnect: false,
            wait_for_peer: false,
            route: route::Route::default(),
        }
    }
}

/// Any of mavping's links, so the engine is written once.
pub(crate) enum Link {
    Udp(udp::UdpLink),
    Tcp(stream::StreamLink<tcp::TcpConnector>),
    TcpIn(tcp::TcpServer),
    Serial(stream::StreamLink<serial::SerialConnector>),
    Sim(sim::SimLink),
    Tlog(tlog::TlogLink),
}

impl Link {
    /// Opens the link a connection string names.
    pub(crate) async fn open(spec: &LinkSpec, options: &LinkOptions) -> Result<Link, LinkError> {
        Ok(match spec {
            LinkSpec::UdpIn(a) => Link::Udp(udp::UdpLink::listen(a, &options.route).await?),
            LinkSpec::UdpOut(a) => {
                let link = udp::UdpLink::connect(a, &options.route).await?;
                Link::Udp(if options.reconnect {
                    link.keep_going_when_refused()
                } else {
                    link
                })
            }
            LinkSpec::UdpBcast(a) => Link::Udp(udp::UdpLink::broadcast(a, &options.route).await?),
            LinkSpec::TcpOut(a) => {
                let connector = tcp::TcpConnector::new(a, options.route.clone());
                Link::Tcp(if options.reconnect && options.wait_for_peer {
                    stream::StreamLink::open_or_wait(connector).await?
                } else {
                    stream::StreamLink::open(connector, options.reconnect).await?
                })
            }
            LinkSpec::TcpIn(a) => Link::TcpIn(tcp::TcpServer::listen(a, &options.route).await?),
            LinkSpec::Serial { path, baud } => Link::Serial(
                stream::StreamLink::open(
                    serial::SerialConnector::new(path, baud.unwrap_or(options.baud)),
                    options.reconnect,
                )
                .await?,
            ),
            LinkSpec::Sim(params) => Link::Sim(sim::SimLink::new((**params).clone())),
            LinkSpec::Tlog(path) => Link::Tlog(tlog::TlogLink::open(path).await?),
        })
    }
}

/// Calls the same method on whichever link this is.
macro_rules! each_link {
    ($link:expr, $l:ident => $body:expr) => {
        match $link {
            Link::Udp($l) => $body,
            Link::Tcp($l) => $body,
            Link::TcpIn($l) => $body,
            Link::Serial($l) => $body,
            Link::Sim($l) => $body,
            Link::Tlog($l) => $body,
        }
    };
}

impl Transport for Link {
    async fn send(&mut self, frame: &[u8]) -> Result<Instant, LinkError> {
        each_link!(self, l => l.send(frame).await)
    }

    async fn send_to(&mut self, path: PathId, frame: &[u8]) -> Result<Instant, LinkError> {
        each_link!(self, l => l.send_to(path, frame).await)
    }

    async fn send_all(&mut self, outbox: &Outbox) -> Result<Instant, LinkError> {
        each_link!(self, l => l.send_all(outbox).await)
    }

    async fn recv(&mut self, out: &mut Vec<Inbound>) -> Result<(), LinkError> {
        each_link!(self, l => l.recv(out).await)
    }

    fn read_waiting(&mut self, out: &mut Vec<Inbound>) -> Result<bool, LinkError> {
        each_link!(self, l => l.read_waiting(out))
    }

    fn has_peers(&self) -> bool {
        each_link!(self, l => l.has_peers())
    }

    fn scan_stats(&self) -> ScanStats {
        each_link!(self, l => l.scan_stats())
    }

    fn downtime(&self) -> Duration {
        each_link!(self, l => l.downtime())
    }

    fn refused(&self) -> u64 {
        each_link!(self, l => l.refused())
    }

    fn unreachable(&self) -> u64 {
        each_link!(self, l => l.unreachable())
    }

    fn rx_clock(&self) -> RxClock {
        each_link!(self, l => l.rx_clock())
    }

    fn kind(&self) -> LinkKind {
        each_link!(self, l => l.kind())
    }

    fn next_wake(&mut self, at: Option<Instant>) {
        each_link!(self, l => l.next_wake(at))
    }

    fn keep_raw(&mut self) {
        each_link!(self, l => l.keep_raw())
    }
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
