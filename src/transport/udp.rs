//! UDP: `udpin` listens and pings every peer it hears; `udpout` sends to one
//! address from an ephemeral port; `udpbcast` sends to a broadcast address
//! and hears whoever answers. Each datagram is parsed on its own.

use std::cell::Cell;
use std::io;
use std::net::SocketAddr;

use tokio::io::Interest;
use tokio::net::UdpSocket;
use tokio::time::Instant;

use super::address::HostPort;
use super::advice;
// Linux reads and writes many datagrams a call; the portable path one
// (build.rs): the same interface.
#[cfg(not(mavping_portable))]
use super::mmsg;
use super::route::{resolve, Route};
use super::rx_time::RxTime;
#[cfg(mavping_portable)]
use super::single as mmsg;
use super::{push_datagram, Inbound, LinkError, LinkKind, Outbox, PathId, RxClock, To, Transport};
use crate::frame::ScanStats;
use mmsg::{socket_addr, Addr, Datagram, RecvBatch, SendBatch, RECV_BATCH, SEND_BATCH};

/// At most this many peers are remembered on a listening socket; more than
/// that is a flood or a misconfiguration, and memory must stay bounded.
const MAX_PEERS: usize = 64;
/// Messages read per wake-up at most, before the session sends what is
/// due and checks its timers.
const DRAIN_LIMIT: usize = 4 * RECV_BATCH;
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
        /// How many were, for the diagnosis.
        unreachable: Cell<u64>,
    },
    /// Requests go to a broadcast address; answers come from each system's
    /// own address, learned like udpin's peers so one can be answered alone.
    Broadcast {
        target: SocketAddr,
        peers: Vec<SocketAddr>,
    },
}

pub(crate) struct UdpLink {
    socket: UdpSocket,
    mode: Mode,
    rx: Receiver,
    send_batch: SendBatch,
    /// Equal-sized datagrams to one address leave as one GSO send, until
    /// the kernel refuses one.
    gso: bool,
    kernel_timestamps: bool,
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
        let kernel_timestamps = mmsg::kernel_stamps(&socket);
        mmsg::join_arrivals(&socket);
        UdpLink {
            socket,
            mode,
            rx: Receiver {
                batch: RecvBatch::new(),
                stats: ScanStats::default(),
                time: RxTime::new(),
                keep_raw: false,
            },
            send_batch: SendBatch::new(),
            gso: true,
            kernel_timestamps,
        }
    }

    /// `udpin:HOST:PORT`
    pub(crate) async fn listen(addr: &HostPort, route: &Route) -> Result<Self, LinkError> {
        let local = resolve(addr, route.family).await?;
        let socket = route
            .udp(local, &format!("cannot listen on udp {addr}"))
            .map_err(|e| e.map_io(|io| advice::listening("udp", addr, local, io)))?;
        Ok(Self::with(socket, Mode::Listen { peers: Vec::new() }))
    }

    /// `udpout:HOST:PORT`
    pub(crate) async fn connect(addr: &HostPort, route: &Route) -> Result<Self, LinkError> {
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
                unreachable: Cell::new(0),
            },
        ))
    }

    /// ICMP "port unreachable" from a `udpout:` peer no longer ends the
    /// link: the peer may not be up yet or may come back (`--reconnect`,
    /// and always for `mavping respond`, which may start before its pinger).
    pub(crate) fn keep_going_when_refused(mut self) -> Self {
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
    pub(crate) async fn broadcast(addr: &HostPort, route: &Route) -> Result<Self, LinkError> {
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
        if let SocketAddr::V4(v4) = target {
            if let Some(why) = advice::not_broadcast(*v4.ip()) {
                return Err(LinkError::io(
                    format!("cannot broadcast to udp {addr}"),
                    io::Error::new(io::ErrorKind::InvalidInput, why),
                ));
            }
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

    /// Whether `e` is an ICMP "port unreachable" that this link shrugs off
    /// (see [`UdpLink::keep_going_when_refused`]).
    fn refused_is_transient(&self, e: &io::Error) -> bool {
        self.mode.refused_is_transient(e)
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

    /// A UDP socket is never closed for reading, but on Windows an ICMP
    /// error can leave it reported as closed or failed with nothing to
    /// read (seen under Wine: `readable()` ready at once, every read
    /// WouldBlock, the session starved at 100 % CPU). The runtime keeps a
    /// closed state for good, so the pending error is taken (and judged as
    /// a read's would be) and the socket is registered afresh, on a
    /// duplicate of its handle.
    fn unstick(&mut self) -> Result<(), LinkError> {
        let sock = socket2::SockRef::from(&self.socket);
        if let Some(e) = sock.take_error().map_err(|e| self.failed(e))? {
            let e = mmsg::as_refused(e);
            if !self.mode.read_error_is_harmless(&e) {
                return Err(self.failed(e));
            }
        }
        tracing::debug!("udp socket reported closed with nothing to read: registered afresh");
        let fresh = sock
            .try_clone()
            .and_then(|dup| {
                dup.set_nonblocking(true)?;
                UdpSocket::from_std(dup.into())
            })
            .map_err(|e| self.failed(e))?;
        self.socket = fresh;
        Ok(())
    }

    /// Writes `datagrams` with as few system calls as the kernel allows,
    /// waiting when the socket buffer is full. A send the kernel refuses
    /// is judged alone: the others still go.
    async fn write(&mut self, datagrams: &[Datagram<'_>]) -> Result<(), LinkError> {
        let mut done = 0;
        while done < datagrams.len() {
            let (len, grouped) = mmsg::next_send(&datagrams[done..], self.gso);
            let next = &datagrams[done..done + len];
            let UdpLink {
                socket, send_batch, ..
            } = self;
            let fd = mmsg::fd(socket);
            let sent = socket.try_io(Interest::WRITABLE, || {
                if grouped {
                    send_batch.send_group(fd, next)
                } else {
                    send_batch.send(fd, next)
                }
            });
            match sent {
                Ok(n) => done += n,
                Err(e) if e.kind() == io::ErrorKind::WouldBlock => {
                    socket.writable().await.map_err(|e| self.failed(e))?;
                }
                Err(e) if grouped && mmsg::gso_unsupported(&e) => {
                    tracing::info!(error = %e, "no UDP GSO on this socket: datagrams go one by one");
                    self.gso = false;
                }
                Err(e) => {
                    match &self.mode {
                        Mode::Connected { .. } if self.refused_is_transient(&e) => {}
                        Mode::Connected { .. } => return Err(self.failed(e)),
                        // One vanished peer must not end a listening link.
                        Mode::Listen { .. } => tracing::debug!(error = %e, "send failed"),
                        Mode::Broadcast { target, .. } => {
                            return Err(LinkError::io(
                                format!("cannot broadcast to udp {target}"),
                                e,
                            ))
                        }
                    }
                    done += if grouped { len } else { 1 };
                }
            }
        }
        Ok(())
    }
}

impl Mode {
    /// The path of a sender, learning it as a peer if it is new. Senders
    /// beyond MAX_PEERS get a path that `send_to` ignores.
    fn path_of(&mut self, from: SocketAddr) -> PathId {
        match self {
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

    /// How many datagrams a frame for `to` becomes, and the address of the
    /// `k`-th (`None`: the connected peer).
    fn destinations(&self, to: To) -> usize {
        match (self, to) {
            (Mode::Connected { .. }, _) | (Mode::Broadcast { .. }, To::Every) => 1,
            (Mode::Listen { peers }, To::Every) => peers.len(),
            (Mode::Listen { peers } | Mode::Broadcast { peers, .. }, To::Path(p)) => {
                usize::from((p as usize) < peers.len())
            }
        }
    }

    fn destination(&self, to: To, k: usize) -> Option<Addr> {
        let addr = match (self, to) {
            (Mode::Connected { .. }, _) => return None,
            (Mode::Broadcast { target, .. }, To::Every) => *target,
            (Mode::Listen { peers }, To::Every) => peers[k],
            (Mode::Listen { peers } | Mode::Broadcast { peers, .. }, To::Path(p)) => {
                peers[p as usize]
            }
        };
        Some(Addr::from(addr))
    }

    /// Whether `e` is an ICMP "port unreachable" that a connected link
    /// shrugs off (see [`UdpLink::keep_going_when_refused`]).
    fn refused_is_transient(&self, e: &io::Error) -> bool {
        let Mode::Connected {
            refused_is_transient: true,
            unreachable,
            ..
        } = self
        else {
            return false;
        };
        if e.kind() != io::ErrorKind::ConnectionRefused {
            return false;
        }
        tracing::debug!(error = %e, "udp peer unreachable for now");
        unreachable.set(unreachable.get() + 1);
        true
    }

    /// A read error that is no reason to stop: a listening socket can see
    /// ECONNREFUSED from an ICMP error to one of its peers.
    fn read_error_is_harmless(&self, e: &io::Error) -> bool {
        e.kind() == io::ErrorKind::ConnectionRefused
            && (!matches!(self, Mode::Connected { .. }) || self.refused_is_transient(e))
    }
}

/// The receiving half of a UDP link: batched reads and what the frame
/// scanner made of them.
struct Receiver {
    batch: RecvBatch,
    stats: ScanStats,
    /// Kernel stamps (wall clock) to the monotonic clock, steps excluded.
    time: RxTime,
    /// Frames carry their bytes (`--tlog`).
    keep_raw: bool,
}

impl Receiver {
    /// Reads what is waiting, up to DRAIN_LIMIT messages, without blocking
    /// and without asking the runtime (its idea of readiness is stale while
    /// the session sleeps on its own clock). Each message carries its own
    /// arrival time: one stamp for a whole batch would date late arrivals
    /// too early. Returns how many messages were read and whether the
    /// socket was found empty.
    fn drain(
        &mut self,
        fd: mmsg::Fd<'_>,
        mode: &mut Mode,
        out: &mut Vec<Inbound>,
    ) -> io::Result<(usize, bool)> {
        let mut read = 0;
        let mut shrugged = 0;
        while read < DRAIN_LIMIT {
            let n = match self.batch.recv(fd) {
                Ok(n) => n,
                Err(e) if e.kind() == io::ErrorKind::WouldBlock => {
                    self.time.drained();
                    return Ok((read, true));
                }
                // Bounded: an error that does not clear must not hold the
                // session here.
                Err(e) if mode.read_error_is_harmless(&e) => {
                    shrugged += 1;
                    if shrugged == DRAIN_LIMIT {
                        return Ok((read, true));
                    }
                    continue;
                }
                Err(e) => return Err(e),
            };
            let reading = self.time.read();
            for i in 0..n {
                let (data, r) = self.batch.message(i);
                let from = match (r.from.as_ref().and_then(socket_addr), &*mode) {
                    (Some(from), _) => from,
                    (None, Mode::Connected { peer, .. }) => *peer,
                    (None, _) => continue,
                };
                let at = self.time.arrival_at(reading, r.kernel);
                let before = out.len();
                // Each datagram on its own, also those GRO joined.
                for datagram in data.chunks(r.segment.unwrap_or(data.len()).max(1)) {
                    push_datagram(
                        datagram,
                        at,
                        PathId::MAX,
                        self.keep_raw,
                        &mut self.stats,
                        out,
                    );
                }
                // Only a sender of real MAVLink becomes a peer, not a port scanner.
                if out.len() > before {
                    let path = mode.path_of(from);
                    for inbound in &mut out[before..] {
                        inbound.path = path;
                    }
                }
            }
            read += n;
            if n < RECV_BATCH {
                // The read came back short: the socket was empty then.
                self.time.empty_at(reading);
                return Ok((read, true));
            }
        }
        Ok((read, false))
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

    /// The whole box in as few system calls as the kernel allows (GSO,
    /// `sendmmsg`).
    async fn send_all(&mut self, outbox: &Outbox) -> Result<Instant, LinkError> {
        const QUEUE: usize = 4 * SEND_BATCH;
        let sent = Instant::now();
        let mut queue: [Datagram<'_>; QUEUE] = [(&[], None); QUEUE];
        let mut queued = 0;
        for (frame, to) in outbox.frames() {
            for k in 0..self.mode.destinations(to) {
                queue[queued] = (frame, self.mode.destination(to, k));
                queued += 1;
                if queued == QUEUE {
                    self.write(&queue).await?;
                    queued = 0;
                }
            }
        }
        self.write(&queue[..queued]).await?;
        Ok(sent)
    }

    async fn recv(&mut self, out: &mut Vec<Inbound>) -> Result<(), LinkError> {
        loop {
            let ready = self.socket.ready(Interest::READABLE).await;
            let ready = ready.map_err(|e| self.failed(e))?;
            let UdpLink {
                socket, mode, rx, ..
            } = self;
            let fd = mmsg::fd(socket);
            let mut read = 0;
            // Through try_io: a WouldBlock clears the runtime's readiness,
            // so a socket found empty is waited for again, not polled.
            let drained = socket.try_io(Interest::READABLE, || {
                let (n, emptied) = rx.drain(fd, mode, out)?;
                read = n;
                if emptied {
                    Err(io::ErrorKind::WouldBlock.into())
                } else {
                    Ok(())
                }
            });
            match drained {
                Err(e) if e.kind() != io::ErrorKind::WouldBlock => return Err(self.failed(e)),
                _ if read > 0 => return Ok(()),
                _ if ready.is_read_closed() || ready.is_error() => self.unstick()?,
                _ => {}
            }
        }
    }

    fn read_waiting(&mut self, out: &mut Vec<Inbound>) -> Result<bool, LinkError> {
        match self.rx.drain(mmsg::fd(&self.socket), &mut self.mode, out) {
            Ok((read, _)) => Ok(read > 0),
            Err(e) => Err(self.failed(e)),
        }
    }

    fn keep_raw(&mut self) {
        self.rx.keep_raw = true;
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
        self.rx.stats
    }

    fn unreachable(&self) -> u64 {
        match &self.mode {
            Mode::Connected { unreachable, .. } => unreachable.get(),
            Mode::Listen { .. } | Mode::Broadcast { .. } => 0,
        }
    }

    fn rx_clock(&self) -> RxClock {
        if self.kernel_timestamps {
            RxClock::Kernel
        } else {
            RxClock::UserSpace
        }
    }
}
