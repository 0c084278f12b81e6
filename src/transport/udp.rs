//! UDP: `udpin` listens and pings every peer it hears; `udpout` sends to one
//! address from an ephemeral port; `udpbcast` sends to a broadcast address
//! and hears whoever answers. Each datagram is parsed on its own.

use std::io;
use std::net::SocketAddr;

use std::os::fd::AsRawFd;

use nix::sys::socket::{self as nixsock, ControlMessageOwned, MsgFlags, SockaddrStorage};
use nix::sys::time::TimeSpec;
use tokio::io::Interest;
use tokio::net::UdpSocket;
use tokio::time::Instant;

use super::address::HostPort;
use super::route::{resolve, Route};
use super::rx_time::RxTime;
use super::{push_datagram, Inbound, LinkError, LinkKind, PathId, RxClock, Transport};
use crate::frame::ScanStats;

/// At most this many peers are remembered on a listening socket; more than
/// that is a flood or a misconfiguration, and memory must stay bounded.
const MAX_PEERS: usize = 64;
/// Datagrams drained per wake-up before yielding to the timers.
const DRAIN_BATCH: usize = 64;
/// Socket buffers asked for: at 150k PINGs/s the default 208 KiB receive
/// buffer drops 0.1-3 % of replies, 4 MiB none (FIELD-NOTES). The kernel
/// caps it at net.core.rmem_max; what was granted is logged.
const SOCKET_BUFFER: usize = 4 << 20;

enum Mode {
    /// Peers learned from what we hear.
    Listen { peers: Vec<SocketAddr> },
    /// One fixed peer; the socket is connected so ICMP errors surface.
    Connected {
        peer: SocketAddr,
        /// ICMP "port unreachable" is logged, not fatal.
        refused_is_transient: bool,
    },
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
    recv_buffer: usize,
    kernel_timestamps: bool,
    /// Kernel stamps (wall clock) to the monotonic clock, steps excluded.
    rx_time: RxTime,
}

fn socket_addr(addr: &SockaddrStorage) -> Option<SocketAddr> {
    if let Some(v4) = addr.as_sockaddr_in() {
        Some(SocketAddr::from((v4.ip(), v4.port())))
    } else {
        addr.as_sockaddr_in6()
            .map(|v6| SocketAddr::from((v6.ip(), v6.port())))
    }
}

impl UdpLink {
    fn with(socket: UdpSocket, mode: Mode) -> Self {
        let sock = socket2::SockRef::from(&socket);
        let _ = sock.set_recv_buffer_size(SOCKET_BUFFER);
        let _ = sock.set_send_buffer_size(SOCKET_BUFFER);
        let recv_buffer = sock.recv_buffer_size().unwrap_or(0);
        tracing::info!(recv_buffer, "udp receive buffer granted");
        // Kernel receive timestamps take our own wake-up delay out of the
        // RTT: a reply is timed when it reached the socket, not when we
        // got round to reading it.
        let kernel_timestamps =
            nixsock::setsockopt(&socket, nixsock::sockopt::ReceiveTimestampns, &true).is_ok();
        UdpLink {
            socket,
            mode,
            buf: vec![0; 65536].into_boxed_slice(),
            stats: ScanStats::default(),
            recv_buffer,
            kernel_timestamps,
            rx_time: RxTime::new(),
        }
    }

    /// Receive buffer the kernel granted, in bytes (Linux reports twice the
    /// usable size).
    pub fn recv_buffer(&self) -> usize {
        self.recv_buffer
    }

    /// `udpin:HOST:PORT`
    pub async fn listen(addr: &HostPort, route: &Route) -> Result<Self, LinkError> {
        let local = resolve(addr, route.family).await?;
        let socket = route.udp(local, &format!("cannot listen on udp {addr}"))?;
        Ok(Self::with(socket, Mode::Listen { peers: Vec::new() }))
    }

    /// `udpout:HOST:PORT`
    pub async fn connect(addr: &HostPort, route: &Route) -> Result<Self, LinkError> {
        let peer = resolve(addr, route.family).await?;
        let local = route.local_for(peer)?;
        let socket = route.udp(local, &format!("cannot send from udp {local}"))?;
        socket
            .connect(peer)
            .await
            .map_err(|e| LinkError::io(format!("cannot send to udp {addr}"), e))?;
        Ok(Self::with(
            socket,
            Mode::Connected {
                peer,
                refused_is_transient: false,
            },
        ))
    }

    /// ICMP "port unreachable" from a `udpout:` peer no longer ends the
    /// link: the peer may not be up yet or may come back (`--reconnect`,
    /// and always for `mavping respond`, which may start before its pinger).
    pub fn keep_going_when_refused(mut self) -> Self {
        if let Mode::Connected {
            refused_is_transient,
            ..
        } = &mut self.mode
        {
            *refused_is_transient = true;
        }
        self
    }

    /// `udpbcast:ADDR:PORT`
    pub async fn broadcast(addr: &HostPort, route: &Route) -> Result<Self, LinkError> {
        let target = resolve(addr, route.family).await?;
        if target.is_ipv6() {
            return Err(LinkError::io(
                format!("cannot broadcast to udp {addr}"),
                io::Error::new(
                    io::ErrorKind::InvalidInput,
                    "IPv6 has no broadcast; use an IPv4 broadcast address",
                ),
            ));
        }
        let local = route.local_for(target)?;
        let socket = route.udp(local, &format!("cannot send from udp {local}"))?;
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

    /// Whether `e` is an ICMP "port unreachable" that this link shrugs off
    /// (see [`UdpLink::keep_going_when_refused`]).
    fn refused_is_transient(&self, e: &io::Error) -> bool {
        let transient = e.kind() == io::ErrorKind::ConnectionRefused
            && matches!(
                self.mode,
                Mode::Connected {
                    refused_is_transient: true,
                    ..
                }
            );
        if transient {
            tracing::debug!(error = %e, "udp peer unreachable for now");
        }
        transient
    }

    fn failed(&self, e: io::Error) -> LinkError {
        match &self.mode {
            Mode::Connected { peer, .. } if e.kind() == io::ErrorKind::ConnectionRefused => {
                LinkError::Closed(format!(
                    "nothing listening at {peer} (ICMP port unreachable); if the vehicle sends \
                     to this port, listen: udp:{peer}"
                ))
            }
            _ => LinkError::io("udp link failed", e),
        }
    }

    /// One datagram if one is waiting, without blocking, with the time it
    /// reached the socket.
    fn try_one(&mut self) -> io::Result<Option<(usize, SocketAddr, Instant)>> {
        let UdpLink {
            socket,
            buf,
            mode,
            rx_time,
            ..
        } = self;
        let fd = socket.as_raw_fd();
        let r = socket.try_io(Interest::READABLE, || {
            let mut iov = [io::IoSliceMut::new(&mut buf[..])];
            let mut cmsg = nix::cmsg_space!(TimeSpec);
            let msg = nixsock::recvmsg::<SockaddrStorage>(
                fd,
                &mut iov,
                Some(&mut cmsg),
                MsgFlags::MSG_DONTWAIT,
            )
            .map_err(io::Error::from)?;
            let kernel = msg.cmsgs().ok().and_then(|mut c| {
                c.find_map(|c| match c {
                    ControlMessageOwned::ScmTimestampns(ts) => Some(ts),
                    _ => None,
                })
            });
            let from = msg.address.as_ref().and_then(socket_addr);
            Ok((msg.bytes, from, kernel))
        });
        match r {
            Ok((len, from, kernel)) => {
                let at = rx_time.arrival(kernel);
                let from = match (from, &*mode) {
                    (Some(from), _) => from,
                    (None, Mode::Connected { peer, .. }) => *peer,
                    (None, _) => return Ok(None),
                };
                Ok(Some((len, from, at)))
            }
            Err(e) if e.kind() == io::ErrorKind::WouldBlock => {
                rx_time.drained();
                Ok(None)
            }
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
        // Stamped before the write: an RTT may include the send syscall but
        // can never be shorter than the true round trip.
        let sent = Instant::now();
        match &self.mode {
            Mode::Connected { .. } => {
                if let Err(e) = self.socket.send(frame).await {
                    if !self.refused_is_transient(&e) {
                        return Err(self.failed(e));
                    }
                }
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
        Ok(sent)
    }

    async fn send_to(&mut self, path: PathId, frame: &[u8]) -> Result<Instant, LinkError> {
        let sent = Instant::now();
        match &self.mode {
            Mode::Connected { .. } => {
                if let Err(e) = self.socket.send(frame).await {
                    if !self.refused_is_transient(&e) {
                        return Err(self.failed(e));
                    }
                }
            }
            Mode::Listen { peers } | Mode::Broadcast { peers, .. } => {
                if let Some(peer) = peers.get(path as usize) {
                    if let Err(e) = self.socket.send_to(frame, peer).await {
                        tracing::debug!(%peer, error = %e, "send failed");
                    }
                }
            }
        }
        Ok(sent)
    }

    async fn recv(&mut self, out: &mut Vec<Inbound>) -> Result<(), LinkError> {
        loop {
            let readable = self.socket.readable().await;
            readable.map_err(|e| self.failed(e))?;
            let mut got_any = false;
            for _ in 0..DRAIN_BATCH {
                // Each datagram carries its own arrival time: one stamp for a
                // whole batch would date late arrivals too early.
                match self.try_one() {
                    Ok(Some((len, from, at))) => {
                        got_any = true;
                        self.take(len, from, at, out);
                    }
                    Ok(None) => break,
                    // A listening socket can see ECONNREFUSED from an ICMP
                    // error to one of its peers: not a reason to stop.
                    Err(e)
                        if e.kind() == io::ErrorKind::ConnectionRefused
                            && (!matches!(self.mode, Mode::Connected { .. })
                                || self.refused_is_transient(&e)) =>
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

    fn kind(&self) -> LinkKind {
        match self.mode {
            Mode::Listen { .. } => LinkKind::Listening,
            Mode::Connected { .. } => LinkKind::Connecting,
            Mode::Broadcast { .. } => LinkKind::Broadcast,
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

    fn rx_clock(&self) -> RxClock {
        if self.kernel_timestamps {
            RxClock::Kernel
        } else {
            RxClock::UserSpace
        }
    }
}
