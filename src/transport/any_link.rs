//! Any of mavping's links as one type ([`Link`]): opened from the
//! connection string, and each [`Transport`] call handed to whichever
//! link it is, so the engine is written once. Its own file because it is
//! the one place that names every kind of link.

use std::time::Duration;

use tokio::time::Instant;

use super::address::LinkSpec;
use super::link::{Inbound, LinkError, LinkKind, PathId, RxClock, Transport};
use super::options::LinkOptions;
use super::outbox::Outbox;
use super::{m2r, serial, sim, stream, tcp, tlog, udp, ws};
use crate::frame::ScanStats;

/// Any of mavping's links, so the engine is written once.
pub(crate) enum Link {
    Udp(udp::UdpLink),
    Tcp(stream::StreamLink<tcp::TcpConnector>),
    TcpIn(tcp::TcpServer),
    Serial(stream::StreamLink<serial::SerialConnector>),
    Sim(sim::SimLink),
    Tlog(tlog::TlogLink),
    Ws(ws::WsClient),
    WsIn(ws::WsServer),
    M2r(m2r::M2rClient),
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
            LinkSpec::Ws(url) => {
                Link::Ws(ws::WsClient::connect(url, &options.route, &options.trust).await?)
            }
            LinkSpec::WsIn(a) => Link::WsIn(ws::WsServer::listen(a, &options.route).await?),
            LinkSpec::M2r(url) => {
                Link::M2r(m2r::M2rClient::connect(url, &options.route, &options.trust).await?)
            }
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
            Link::Ws($l) => $body,
            Link::WsIn($l) => $body,
            Link::M2r($l) => $body,
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
