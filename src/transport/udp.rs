//! UDP: `udpin` listens and pings every peer it hears; `udpout` sends to one
//! address from an ephemeral port; `udpbcast` sends to a broadcast address
//! and hears whoever answers. Each datagram is parsed on its own.

use std::io;
use std::net::SocketAddr;

use tokio::net::{lookup_host, UdpSocket};
use tokio::time::Instant;

use super::address::HostPort;
use super::{push_datagram, Inbound, LinkError, PathId, Transport};
use crate::frame::ScanStats;

/// At most this many peers are remembered on a listening socket; more than
/// that is a flood or a misconfiguration, and memory must stay bounded.
const MAX_PEERS: usize = 64;
/// Datagrams drained per wake-up before yielding to the timers.
const DRAIN_BATCH: usize = 64;

enum Mode {
    /// Peers learned from what we hear.
    Listen { peers: Vec<SocketAddr> },
    /// One fixed peer; the socket is connected so ICMP errors surface.
    Connected { peer: SocketAddr },
    /// Requests go to a broadcast address; answers come from each system's
    /// own address, learned like udpin's peers so one can be answered alone.
    Broadcast {
        target: SocketAddr,
        peers: Vec<SocketAddr>,
    },
}

pub struct UdpLink {
    socket: UdpSocket,
    mode: Mode,
    buf: Box<[u8]>,
    stats: ScanStats,
}

pub(crate) async fn resolve(addr: &HostPort) -> Result<SocketAddr, LinkError> {
    let mut addrs = lookup_host((addr.host.as_str(), addr.port))
        .await
        .map_err(|e| LinkError::io(format!("cannot resolve {addr}"), e))?;
    addrs.next().ok_or_else(|| {
        LinkError::io(
            format!("cannot resolve {addr}"),
            io::Error::new(io::ErrorKind::NotFound, "no address found"),
        )
    })
}

impl UdpLink {
    fn with(socket: UdpSocket, mode: Mode) -> Self {
        UdpLink {
            socket,
            mode,
            buf: vec![0; 65536].into_boxed_slice(),
            stats: ScanStats::default(),
        }
    }

    /// `udpin:HOST:PORT`
    pub async fn listen(addr: &HostPort) -> Result<Self, LinkError> {
        let local = resolve(addr).await?;
        let socket = UdpSocket::bind(local)
            .await
            .map_err(|e| LinkError::io(format!("cannot listen on udp {addr}"), e))?;
        Ok(Self::with(socket, Mode::Listen { peers: Vec::new() }))
    }

    /// `udpout:HOST:PORT`
    pub async fn connect(addr: &HostPort) -> Result<Self, LinkError> {
        let peer = resolve(addr).await?;
        let local: SocketAddr = if peer.is_ipv6() {
            "[::]:0".parse().expect("valid literal")
        } else {
            "0.0.0.0:0".parse().expect("valid literal")
        };
        let socket = UdpSocket::bind(local)
            .await
            .map_err(|e| LinkError::io("cannot open a udp socket", e))?;
        socket
            .connect(peer)
            .await
            .map_err(|e| LinkError::io(format!("cannot send to udp {addr}"), e))?;
        Ok(Self::with(socket, Mode::Connected { peer }))
    }

    /// `udpbcast:ADDR:PORT`
    pub async fn broadcast(addr: &HostPort) -> Result<Self, LinkError> {
        let target = resolve(addr).await?;
        if target.is_ipv6() {
            return Err(LinkError::io(
                format!("cannot broadcast to udp {addr}"),
                io::Error::new(
                    io::ErrorKind::InvalidInput,
                    "IPv6 has no broadcast; use an IPv4 broadcast address",
                ),
            ));
        }
        let local: SocketAddr = "0.0.0.0:0".parse().expect("valid literal");
        let socket = UdpSocket::bind(local)
            .await
            .map_err(|e| LinkError::io("cannot open a udp socket", e))?;
        // Without SO_BROADCAST the kernel refuses to send to a broadcast
        // address (EACCES).
        socket
            .set_broadcast(true)
            .map_err(|e| LinkError::io(format!("cannot broadcast to udp {addr}"), e))?;
        Ok(Self::with(
            socket,
            Mode::Broadcast {
                target,
                peers: Vec::new(),
            },
        ))
    }

    pub fn local_addr(&self) -> io::Result<SocketAddr> {
        self.socket.local_addr()
    }

    /// The path of a sender, learning it as a peer if it is new. Senders
    /// beyond MAX_PEERS get a path that `send_to` ignores.
    fn path_of(&mut self, from: SocketAddr) -> PathId {
        match &mut self.mode {
            Mode::Connected { .. } => 0,
            Mode::Listen { peers } | Mode::Broadcast { peers, .. } => {
                match peers.iter().position(|p| *p == from) {
                    Some(i) => i as PathId,
                    None if peers.len() < MAX_PEERS => {
                        tracing::info!(%from, "new udp peer");
                        peers.push(from);
                        (peers.len() - 1) as PathId
                    }
                    None => PathId::MAX,
                }
            }
        }
    }

    fn failed(&self, e: io::Error) -> LinkError {
        match &self.mode {
            Mode::Connected { peer } if e.kind() == io::ErrorKind::ConnectionRefused => {
                LinkError::io(
                    format!(
                        "udp {peer} is unreachable (ICMP port unreachable: nothing listening?)"
                    ),
                    e,
                )
            }
            _ => LinkError::io("udp link failed", e),
        }
    }

    /// One datagram if one is waiting, without blocking.
    fn try_one(&mut self) -> io::Result<Option<(usize, SocketAddr)>> {
        let r = match &self.mode {
            Mode::Listen { .. } | Mode::Broadcast { .. } => {
                self.socket.try_recv_from(&mut self.buf)
            }
            Mode::Connected { peer } => self.socket.try_recv(&mut self.buf).map(|n| (n, *peer)),
        };
        match r {
            Ok(x) => Ok(Some(x)),
            Err(e) if e.kind() == io::ErrorKind::WouldBlock => Ok(None),
            Err(e) => Err(e),
        }
    }

    fn take(&mut self, len: usize, from: SocketAddr, at: Instant, out: &mut Vec<Inbound>) {
        let before = out.len();
        push_datagram(&self.buf[..len], at, PathId::MAX, &mut self.stats, out);
        // Only a sender of real MAVLink becomes a peer, not a port scanner.
        if out.len() > before {
            let path = self.path_of(from);
            for inbound in &mut out[before..] {
                inbound.path = path;
            }
        }
    }
}

impl Transport for UdpLink {
    async fn send(&mut self, frame: &[u8]) -> Result<Instant, LinkError> {
        match &self.mode {
            Mode::Connected { .. } => {
                self.socket.send(frame).await.map_err(|e| self.failed(e))?;
            }
            Mode::Listen { peers } => {
                for peer in peers {
                    if let Err(e) = self.socket.send_to(frame, peer).await {
                        // One vanished peer must not end a listening link.
                        tracing::debug!(%peer, error = %e, "send failed");
                    }
                }
            }
            Mode::Broadcast { target, .. } => {
                self.socket
                    .send_to(frame, target)
                    .await
                    .map_err(|e| LinkError::io(format!("cannot broadcast to udp {target}"), e))?;
            }
        }
        Ok(Instant::now())
    }

    async fn send_to(&mut self, path: PathId, frame: &[u8]) -> Result<Instant, LinkError> {
        match &self.mode {
            Mode::Connected { .. } => {
                self.socket.send(frame).await.map_err(|e| self.failed(e))?;
            }
            Mode::Listen { peers } | Mode::Broadcast { peers, .. } => {
                if let Some(peer) = peers.get(path as usize) {
                    if let Err(e) = self.socket.send_to(frame, peer).await {
                        tracing::debug!(%peer, error = %e, "send failed");
                    }
                }
            }
        }
        Ok(Instant::now())
    }

    async fn recv(&mut self, out: &mut Vec<Inbound>) -> Result<(), LinkError> {
        loop {
            let readable = self.socket.readable().await;
            readable.map_err(|e| self.failed(e))?;
            let at = Instant::now();
            let mut got_any = false;
            for _ in 0..DRAIN_BATCH {
                match self.try_one() {
                    Ok(Some((len, from))) => {
                        got_any = true;
                        self.take(len, from, at, out);
                    }
                    Ok(None) => break,
                    // A listening socket can see ECONNREFUSED from an ICMP
                    // error to one of its peers: not a reason to stop.
                    Err(e)
                        if !matches!(self.mode, Mode::Connected { .. })
                            && e.kind() == io::ErrorKind::ConnectionRefused =>
                    {
                        continue
                    }
                    Err(e) => return Err(self.failed(e)),
                }
            }
            if got_any {
                return Ok(());
            }
        }
    }

    fn has_peers(&self) -> bool {
        match &self.mode {
            Mode::Listen { peers } => !peers.is_empty(),
            Mode::Connected { .. } | Mode::Broadcast { .. } => true,
        }
    }

    fn scan_stats(&self) -> ScanStats {
        self.stats
    }
}
