//! Many datagrams per system call. At hundreds of thousands of PINGs a
//! second, the kernel's work per datagram is most of what both ends spend
//! (docs/performance.md), so:
//!
//! - equal-sized datagrams to one address leave as one UDP GSO send
//!   (`UDP_SEGMENT`): the kernel carries them as one packet and cuts them
//!   apart only where it must (on loopback, not at all);
//! - others leave together through `sendmmsg`;
//! - reads take up to [`RECV_BATCH`] messages per `recvmmsg`, each with its
//!   kernel receive timestamp, and a message that UDP GRO made of several
//!   same-sized datagrams from one sender (`UDP_GRO`) is cut back into them.
//!
//! Measured on loopback (2-core VM), per datagram: sendmmsg 1.5 µs and
//! recvmmsg 1.0 µs; GSO 0.10 µs and GRO 0.06 µs.

use std::io::{self, IoSlice, IoSliceMut};
use std::net::SocketAddr;
use std::os::fd::{AsRawFd, RawFd};

use nix::sys::socket::{
    self as nixsock, ControlMessage, ControlMessageOwned, MsgFlags, MultiHeaders, SockaddrStorage,
};
use nix::sys::time::TimeSpec;
use tokio::net::UdpSocket;

use super::rx_time::WallNs;

/// What the calls below take a socket as (the portable path's
/// `single.rs` takes the socket itself).
pub(super) type Fd<'a> = RawFd;
/// A datagram's address as the calls below carry it.
pub(super) type Addr = SockaddrStorage;

pub(super) fn fd(socket: &UdpSocket) -> Fd<'_> {
    socket.as_raw_fd()
}

pub(super) fn socket_addr(addr: &Addr) -> Option<SocketAddr> {
    if let Some(v4) = addr.as_sockaddr_in() {
        Some(SocketAddr::from((v4.ip(), v4.port())))
    } else {
        addr.as_sockaddr_in6()
            .map(|v6| SocketAddr::from((v6.ip(), v6.port())))
    }
}

/// Asks the kernel to stamp each datagram as it reaches the socket
/// (SO_TIMESTAMPNS): whether it will.
pub(super) fn kernel_stamps(socket: &UdpSocket) -> bool {
    nixsock::setsockopt(socket, nixsock::sockopt::ReceiveTimestampns, &true).is_ok()
}

/// Same-sized datagrams from one sender that arrive together (a GSO send,
/// or what a NIC coalesces) come up as one message (UDP_GRO), cut apart
/// again by the reader: one read for a whole burst. They share one
/// receive timestamp, as they arrived together.
pub(super) fn join_arrivals(socket: &UdpSocket) {
    let _ = nixsock::setsockopt(socket, nixsock::sockopt::UdpGroSegment, &true);
}

/// Linux names an ICMP "port unreachable" ECONNREFUSED already (the
/// portable path's has Windows' name to translate).
pub(super) fn as_refused(e: std::io::Error) -> std::io::Error {
    e
}

/// Messages per `recvmmsg`.
pub(super) const RECV_BATCH: usize = 16;
/// Datagrams per `sendmmsg`.
pub(super) const SEND_BATCH: usize = 32;
/// Segments in one GSO send: Linux took 64 at most until 6.x.
const MAX_SEGMENTS: usize = 64;
/// Bytes in one GSO send (a UDP datagram's payload limit, with room for
/// headers).
const MAX_GSO_BYTES: usize = 65_000;
/// Room for each message read: what UDP allows, since GRO may join up to
/// 64 KiB of datagrams into one. The slab is allocated zeroed, so pages no
/// datagram reached are never made resident.
const SLOT: usize = 65_536;

/// One message read.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct Received {
    pub(crate) len: usize,
    pub(crate) from: Option<SockaddrStorage>,
    /// When the kernel queued it (SO_TIMESTAMPNS), on the wall clock.
    pub(crate) kernel: Option<WallNs>,
    /// UDP GRO joined several datagrams of this size (the last may be
    /// shorter) into this message.
    pub(crate) segment: Option<usize>,
}

/// Buffers for `recvmmsg`, reused for every read.
pub(super) struct RecvBatch {
    slab: Box<[u8]>,
    /// What the last read returned, one entry per slot.
    received: Box<[Received]>,
}

impl RecvBatch {
    pub(super) fn new() -> Self {
        RecvBatch {
            slab: vec![0; SLOT * RECV_BATCH].into_boxed_slice(),
            received: vec![Received::default(); RECV_BATCH].into_boxed_slice(),
        }
    }

    /// Reads what is waiting, up to [`RECV_BATCH`] messages, with one
    /// non-blocking system call: how many (`WouldBlock` when none).
    pub(super) fn recv(&mut self, fd: RawFd) -> io::Result<usize> {
        let RecvBatch { slab, received } = self;
        // New headers for every call: the kernel shrinks each header's
        // control length to what it wrote, and nix does not restore it, so
        // reused headers would lose the timestamp or GRO size of a later
        // datagram that needs more room (nix-rust/nix#2813).
        let mut headers = MultiHeaders::<SockaddrStorage>::preallocate(
            RECV_BATCH,
            Some(nix::cmsg_space!(TimeSpec, i32)),
        );
        let mut slots = slab.chunks_mut(SLOT);
        let mut iovs: [[IoSliceMut<'_>; 1]; RECV_BATCH] =
            std::array::from_fn(|_| [IoSliceMut::new(slots.next().unwrap_or_default())]);
        let results = nixsock::recvmmsg(
            fd,
            &mut headers,
            iovs.iter_mut(),
            MsgFlags::MSG_DONTWAIT,
            None,
        )
        .map_err(io::Error::from)?;
        let mut count = 0;
        for (slot, msg) in received.iter_mut().zip(results) {
            let mut r = Received {
                len: msg.bytes,
                from: msg.address,
                ..Received::default()
            };
            let cmsgs = msg.cmsgs();
            if cmsgs.is_err() {
                tracing::debug!("control data cut short (MSG_CTRUNC): no receive timestamp");
            }
            for cmsg in cmsgs.into_iter().flatten() {
                match cmsg {
                    ControlMessageOwned::ScmTimestampns(ts) => {
                        r.kernel =
                            Some(i128::from(ts.tv_sec()) * 1_000_000_000 + i128::from(ts.tv_nsec()))
                    }
                    ControlMessageOwned::UdpGroSegments(size) if size > 0 => {
                        r.segment = Some(size as usize)
                    }
                    _ => {}
                }
            }
            *slot = r;
            count += 1;
        }
        Ok(count)
    }

    /// The `i`-th message of the last read, and what it was.
    pub(super) fn message(&self, i: usize) -> (&[u8], &Received) {
        let r = &self.received[i];
        let slot = &self.slab[i * SLOT..(i + 1) * SLOT];
        (&slot[..r.len.min(SLOT)], r)
    }
}

/// A datagram to send, and to whom (`None` on a connected socket).
pub(super) type Datagram<'a> = (&'a [u8], Option<SockaddrStorage>);

/// How the datagrams at the head of a queue go out: how many, and whether
/// as one GSO send. A GSO group is datagrams to one address, all of the
/// first one's size but the last, which may be shorter.
pub(super) fn next_send(datagrams: &[Datagram<'_>], gso: bool) -> (usize, bool) {
    let group = if gso { gso_group(datagrams) } else { 1 };
    if group >= 2 {
        return (group, true);
    }
    // Datagrams that form no group go out together.
    let mut run = 1;
    while run < datagrams.len().min(SEND_BATCH) && !(gso && gso_group(&datagrams[run..]) >= 2) {
        run += 1;
    }
    (run, false)
}

fn gso_group(datagrams: &[Datagram<'_>]) -> usize {
    let Some(&(first, to)) = datagrams.first() else {
        return 0;
    };
    let size = first.len();
    let mut bytes = size;
    let mut n = 1;
    for &(frame, addr) in &datagrams[1..] {
        if n == MAX_SEGMENTS
            || addr != to
            || frame.len() > size
            || bytes + frame.len() > MAX_GSO_BYTES
        {
            break;
        }
        n += 1;
        bytes += frame.len();
        if frame.len() < size {
            break; // a shorter one ends the group
        }
    }
    n
}

/// Headers for `sendmmsg`, reused for every write.
pub(super) struct SendBatch {
    plain: MultiHeaders<SockaddrStorage>,
    /// One message carrying the GSO segment size.
    segmented: MultiHeaders<SockaddrStorage>,
}

impl SendBatch {
    pub(super) fn new() -> Self {
        SendBatch {
            plain: MultiHeaders::preallocate(SEND_BATCH, None),
            segmented: MultiHeaders::preallocate(1, Some(nix::cmsg_space!(u16))),
        }
    }

    /// Sends datagrams with one system call, each to its own address: how
    /// many the kernel took, at least one, or the first one's error.
    pub(super) fn send(&mut self, fd: RawFd, datagrams: &[Datagram<'_>]) -> io::Result<usize> {
        let n = datagrams.len().min(SEND_BATCH);
        let iovs: [[IoSlice<'_>; 1]; SEND_BATCH] =
            std::array::from_fn(|i| [IoSlice::new(datagrams.get(i).map_or(&[], |d| d.0))]);
        let addrs: [Option<SockaddrStorage>; SEND_BATCH] =
            std::array::from_fn(|i| datagrams.get(i).and_then(|d| d.1));
        let no_cmsgs: [ControlMessage<'_>; 0] = [];
        let sent = nixsock::sendmmsg(
            fd,
            &mut self.plain,
            &iovs[..n],
            &addrs[..n],
            no_cmsgs,
            MsgFlags::MSG_DONTWAIT,
        )
        .map_err(io::Error::from)?;
        Ok(sent.count())
    }

    /// Sends a GSO group (see [`next_send`]) as one packet the kernel cuts
    /// into its datagrams: all of them, or the error.
    pub(super) fn send_group(&mut self, fd: RawFd, group: &[Datagram<'_>]) -> io::Result<usize> {
        let n = group.len().min(MAX_SEGMENTS);
        let iovs: [IoSlice<'_>; MAX_SEGMENTS] =
            std::array::from_fn(|i| IoSlice::new(group.get(i).map_or(&[], |d| d.0)));
        let size = group.first().map_or(0, |d| d.0.len()) as u16;
        let segments = [ControlMessage::UdpGsoSegments(&size)];
        let message = [&iovs[..n]];
        let addr = [group.first().and_then(|d| d.1)];
        nixsock::sendmmsg(
            fd,
            &mut self.segmented,
            &message,
            addr,
            segments,
            MsgFlags::MSG_DONTWAIT,
        )
        .map_err(io::Error::from)?;
        Ok(n)
    }
}

/// Errors that say the socket or the route cannot do GSO: send the
/// datagrams one by one instead.
pub(super) fn gso_unsupported(e: &io::Error) -> bool {
    matches!(
        e.raw_os_error(),
        Some(nix::libc::EINVAL | nix::libc::EIO | nix::libc::ENOPROTOOPT | nix::libc::EOPNOTSUPP)
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::net::UdpSocket;
    use std::os::fd::AsRawFd;

    fn pair(gro: bool) -> (UdpSocket, UdpSocket) {
        let a = UdpSocket::bind("127.0.0.1:0").unwrap();
        let b = UdpSocket::bind("127.0.0.1:0").unwrap();
        b.connect(a.local_addr().unwrap()).unwrap();
        nixsock::setsockopt(&a, nixsock::sockopt::ReceiveTimestampns, &true).unwrap();
        nixsock::setsockopt(&a, nixsock::sockopt::UdpGroSegment, &gro).unwrap();
        (a, b)
    }

    /// Every datagram `a` receives, cut back apart where GRO joined them.
    fn drain(a: &UdpSocket, recv: &mut RecvBatch) -> Vec<Vec<u8>> {
        let mut got = Vec::new();
        loop {
            let n = match recv.recv(a.as_raw_fd()) {
                Ok(n) => n,
                Err(e) if e.kind() == io::ErrorKind::WouldBlock => return got,
                Err(e) => panic!("{e}"),
            };
            for i in 0..n {
                let (data, r) = recv.message(i);
                assert!(r.kernel.is_some());
                let port = r.from.unwrap().as_sockaddr_in().unwrap().port();
                assert_ne!(port, 0);
                match r.segment {
                    Some(size) => got.extend(data.chunks(size).map(<[u8]>::to_vec)),
                    None => got.push(data.to_vec()),
                }
            }
        }
    }

    fn send_all(b: &UdpSocket, datagrams: &[Datagram<'_>], gso: bool) -> usize {
        let mut send = SendBatch::new();
        let (mut done, mut calls) = (0, 0);
        while done < datagrams.len() {
            let (len, grouped) = next_send(&datagrams[done..], gso);
            let rest = &datagrams[done..done + len];
            done += if grouped {
                send.send_group(b.as_raw_fd(), rest).unwrap()
            } else {
                send.send(b.as_raw_fd(), rest).unwrap()
            };
            calls += 1;
        }
        calls
    }

    #[test]
    fn datagrams_come_back_whole_and_in_order_whichever_way_they_went() {
        // Runs of equal sizes (GSO groups), a shorter one ending a run,
        // odd sizes, and more than a batch of each.
        let mut payloads: Vec<Vec<u8>> = Vec::new();
        for i in 0..100u8 {
            payloads.push(vec![i; 30]);
        }
        payloads.push(vec![200; 12]);
        for i in 0..40u8 {
            payloads.push(vec![i; 1 + i as usize]);
        }
        let datagrams: Vec<Datagram<'_>> = payloads.iter().map(|p| (&p[..], None)).collect();
        for (gso, gro) in [(false, false), (true, false), (true, true), (false, true)] {
            let (a, b) = pair(gro);
            let calls = send_all(&b, &datagrams, gso);
            if gso {
                assert!(calls < 50, "{calls} calls");
            }
            let got = drain(&a, &mut RecvBatch::new());
            assert_eq!(got, payloads, "gso {gso} gro {gro}");
        }
    }

    #[test]
    fn every_read_keeps_its_timestamp_and_segment_size_however_the_last_one_went() {
        let (a, b) = pair(true);
        let mut recv = RecvBatch::new();
        let frames = [[1u8; 30]; 4];
        let group: Vec<Datagram<'_>> = frames.iter().map(|f| (&f[..], None)).collect();
        let mut send = SendBatch::new();
        for round in 0..3 {
            b.send(&[round; 30]).unwrap();
            assert_eq!(drain(&a, &mut recv), vec![vec![round; 30]]);
            send.send_group(b.as_raw_fd(), &group).unwrap();
            assert_eq!(drain(&a, &mut recv).len(), 4, "round {round}");
            let (_, r) = recv.message(0);
            assert_eq!(r.segment, Some(30));
        }
    }

    #[test]
    fn groups_are_one_address_and_one_size_with_a_shorter_last() {
        let (x, y) = (
            SockaddrStorage::from(std::net::SocketAddr::from(([127, 0, 0, 1], 1))),
            None,
        );
        let big = [0u8; 30];
        let small = [0u8; 20];
        let q: Vec<Datagram<'_>> = vec![
            (&big[..], y),
            (&big[..], y),
            (&small[..], y),
            (&big[..], y),
            (&big[..], Some(x)),
            (&big[..], Some(x)),
        ];
        assert_eq!(next_send(&q, true), (3, true));
        assert_eq!(next_send(&q[3..], true), (1, false));
        assert_eq!(next_send(&q[4..], true), (2, true));
        assert_eq!(next_send(&q, false), (6, false));
        let many: Vec<Datagram<'_>> = (0..100).map(|_| (&big[..], y)).collect();
        assert_eq!(next_send(&many, true), (MAX_SEGMENTS, true));
        assert_eq!(next_send(&many, false), (SEND_BATCH, false));
    }
}
