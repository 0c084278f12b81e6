//! The portable path's datagram I/O (build.rs): one datagram per system
//! call through tokio's own non-blocking calls, no kernel receive stamps,
//! no GSO/GRO. The interface is `mmsg.rs`'s, so `udp.rs` is one file for
//! both paths: a "batch" here is a loop of single reads or writes that
//! stops at the first that would block.

use std::io;
use std::net::SocketAddr;

use tokio::net::UdpSocket;

use super::rx_time::WallNs;

/// Messages read per [`RecvBatch::recv`].
pub(crate) const RECV_BATCH: usize = 16;
/// Datagrams per [`SendBatch::send`].
pub(crate) const SEND_BATCH: usize = 32;
/// Room for each message read: what UDP allows.
const SLOT: usize = 65_536;

pub(crate) type Fd<'a> = &'a UdpSocket;
pub(crate) type Addr = SocketAddr;

pub(crate) fn fd(socket: &UdpSocket) -> Fd<'_> {
    socket
}

// The same signature as mmsg.rs's, whose addresses may be of any family.
#[allow(clippy::unnecessary_wraps)]
pub(crate) fn socket_addr(addr: &Addr) -> Option<SocketAddr> {
    Some(*addr)
}

/// No kernel receive stamps here: replies are timed when read, and the
/// summary says so (`RxClock::UserSpace`).
pub(crate) fn kernel_stamps(_socket: &UdpSocket) -> bool {
    false
}

/// No UDP GRO here: each datagram is its own read.
pub(crate) fn join_arrivals(_socket: &UdpSocket) {}

/// Windows reports an ICMP "port unreachable" to a UDP socket as a reset
/// connection (WSAECONNRESET); the link's policy knows it as refused.
pub(crate) fn as_refused(e: io::Error) -> io::Error {
    if e.kind() == io::ErrorKind::ConnectionReset {
        io::Error::new(io::ErrorKind::ConnectionRefused, e)
    } else {
        e
    }
}

/// One message read.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct Received {
    pub(crate) len: usize,
    pub(crate) from: Option<SocketAddr>,
    /// Always `None`: no kernel stamps on this path.
    pub(crate) kernel: Option<WallNs>,
    /// Always `None`: no GRO on this path.
    pub(crate) segment: Option<usize>,
}

/// Buffers for the reads, reused for every read.
pub(crate) struct RecvBatch {
    slab: Box<[u8]>,
    received: Box<[Received]>,
}

impl RecvBatch {
    pub(crate) fn new() -> Self {
        RecvBatch {
            slab: vec![0; SLOT * RECV_BATCH].into_boxed_slice(),
            received: vec![Received::default(); RECV_BATCH].into_boxed_slice(),
        }
    }

    /// Reads what is waiting, up to [`RECV_BATCH`] datagrams, without
    /// blocking: how many (`WouldBlock` when none). An error after the
    /// first datagram ends the batch; the next call returns it.
    pub(crate) fn recv(&mut self, socket: Fd<'_>) -> io::Result<usize> {
        let RecvBatch { slab, received } = self;
        let mut count = 0;
        for (slot, r) in slab.chunks_mut(SLOT).zip(received.iter_mut()) {
            match socket.try_recv_from(slot) {
                Ok((len, from)) => {
                    *r = Received {
                        len,
                        from: Some(from),
                        ..Received::default()
                    };
                    count += 1;
                }
                Err(e) if count == 0 => return Err(as_refused(e)),
                Err(_) => break,
            }
        }
        Ok(count)
    }

    /// The `i`-th message of the last read, and what it was.
    pub(crate) fn message(&self, i: usize) -> (&[u8], &Received) {
        let r = &self.received[i];
        let slot = &self.slab[i * SLOT..(i + 1) * SLOT];
        (&slot[..r.len.min(SLOT)], r)
    }
}

/// A datagram to send, and to whom (`None` on a connected socket).
pub(crate) type Datagram<'a> = (&'a [u8], Option<Addr>);

/// How the datagrams at the head of a queue go out: up to a batch, never
/// as a group (no GSO here).
pub(crate) fn next_send(datagrams: &[Datagram<'_>], _gso: bool) -> (usize, bool) {
    (datagrams.len().clamp(1, SEND_BATCH), false)
}

/// Nothing to keep between writes; the type mirrors `mmsg.rs`'s.
pub(crate) struct SendBatch;

impl SendBatch {
    pub(crate) fn new() -> Self {
        SendBatch
    }

    /// Sends datagrams one call each, each to its own address: how many
    /// went, at least one, or the first one's error (as `sendmmsg`).
    #[allow(clippy::unused_self)] // mmsg.rs's reuses its headers
    pub(crate) fn send(&mut self, socket: Fd<'_>, datagrams: &[Datagram<'_>]) -> io::Result<usize> {
        let n = datagrams.len().min(SEND_BATCH);
        for (i, &(frame, to)) in datagrams[..n].iter().enumerate() {
            let sent = match to {
                Some(addr) => socket.try_send_to(frame, addr),
                None => socket.try_send(frame),
            };
            match sent {
                Ok(_) => {}
                Err(e) if i == 0 => return Err(as_refused(e)),
                Err(_) => return Ok(i),
            }
        }
        Ok(n)
    }

    /// [`next_send`] makes no groups here; a group would go one by one.
    pub(crate) fn send_group(
        &mut self,
        socket: Fd<'_>,
        group: &[Datagram<'_>],
    ) -> io::Result<usize> {
        self.send(socket, group)
    }
}

/// No GSO is ever tried, so no error says it is missing.
pub(crate) fn gso_unsupported(_e: &io::Error) -> bool {
    false
}

#[cfg(test)]
mod tests {
    use super::*;

    async fn pair() -> (UdpSocket, UdpSocket) {
        let a = UdpSocket::bind("127.0.0.1:0").await.unwrap();
        let b = UdpSocket::bind("127.0.0.1:0").await.unwrap();
        b.connect(a.local_addr().unwrap()).await.unwrap();
        (a, b)
    }

    #[tokio::test]
    async fn datagrams_come_back_whole_and_in_order_a_batch_at_a_time() {
        let (a, b) = pair().await;
        let payloads: Vec<Vec<u8>> = (0..50u8).map(|i| vec![i; 1 + i as usize]).collect();
        let datagrams: Vec<Datagram<'_>> = payloads.iter().map(|p| (&p[..], None)).collect();
        let mut send = SendBatch::new();
        let mut done = 0;
        while done < datagrams.len() {
            let (len, grouped) = next_send(&datagrams[done..], true);
            assert!(!grouped);
            // As udp.rs does: a send that would block waits for room.
            match send.send(&b, &datagrams[done..done + len]) {
                Ok(n) => done += n,
                Err(e) if e.kind() == io::ErrorKind::WouldBlock => b.writable().await.unwrap(),
                Err(e) => panic!("{e}"),
            }
        }
        let mut recv = RecvBatch::new();
        let mut got = Vec::new();
        while got.len() < payloads.len() {
            a.readable().await.unwrap();
            let n = match recv.recv(&a) {
                Ok(n) => n,
                Err(e) if e.kind() == io::ErrorKind::WouldBlock => continue,
                Err(e) => panic!("{e}"),
            };
            assert!(n <= RECV_BATCH);
            for i in 0..n {
                let (data, r) = recv.message(i);
                assert_eq!(r.from, Some(b.local_addr().unwrap()));
                assert!(r.kernel.is_none());
                got.push(data.to_vec());
            }
        }
        assert_eq!(got, payloads);
        assert_eq!(recv.recv(&a).unwrap_err().kind(), io::ErrorKind::WouldBlock);
    }
}
