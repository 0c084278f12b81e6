//! TCP: `tcp:`/`tcpout:` connects to a router or SITL as a client;
//! `tcpin:` listens and pings every connected client.
//!
//! Each tcpin client is a byte stream of its own, so each has its own
//! scanner: a partial frame from one client must never join bytes of another.

use std::future::poll_fn;
use std::io;
use std::net::SocketAddr;
use std::task::Poll;
use std::time::Duration;

use tokio::io::AsyncWriteExt;
use tokio::net::{TcpListener, TcpStream};
use tokio::time::Instant;

use super::address::HostPort;
use super::advice;
use super::route::{resolve, Route};
use super::stream::Connect;
use super::{Inbound, LinkError, LinkKind, PathId, Transport};
use crate::frame::{ScanStats, StreamScanner};

/// Clients beyond this are refused: memory stays bounded.
const MAX_CLIENTS: usize = 64;
/// A client that does not take our bytes for this long is dropped, so one
/// stuck client cannot stall the requests to all the others.
const WRITE_STALL: Duration = Duration::from_secs(1);
const READ_BUF: usize = 16 * 1024;

/// `tcp:HOST:PORT`: the connector behind a reconnecting [`super::stream::StreamLink`].
pub(crate) struct TcpConnector {
    addr: HostPort,
    route: Route,
    name: String,
}

impl TcpConnector {
    pub(crate) fn new(addr: &HostPort, route: Route) -> Self {
        TcpConnector {
            addr: addr.clone(),
            route,
            name: format!("tcp:{addr}"),
        }
    }
}

impl Connect for TcpConnector {
    type Stream = TcpStream;
    const KIND: LinkKind = LinkKind::Connecting;

    fn name(&self) -> &str {
        &self.name
    }

    async fn connect(&self) -> io::Result<TcpStream> {
        // Resolved on every attempt: a router's address may change while down.
        let link = |e: LinkError| io::Error::other(e.to_string());
        let peer = resolve(&self.addr, self.route.family).await.map_err(link)?;
        let socket = self.route.tcp(peer).map_err(link)?;
        if let Some(bind) = self.route.bind {
            socket
                .bind(self.route.local_for(peer).map_err(link)?)
                .map_err(|e| {
                    io::Error::new(e.kind(), format!("cannot send from tcp {bind}: {e}"))
                })?;
        }
        let stream = socket.connect(peer).await?;
        // A PING is a few dozen bytes: Nagle would hold it back for an ACK.
        stream.set_nodelay(true)?;
        Ok(stream)
    }
}

/// A listening TCP socket for `scheme` (`tcpin`, `wsin`) at `addr`,
/// failures said in `what`'s words ("cannot listen on tcp ...").
pub(crate) async fn listener(
    scheme: &str,
    what: &str,
    addr: &HostPort,
    route: &Route,
) -> Result<TcpListener, LinkError> {
    let local = resolve(addr, route.family).await?;
    let socket = route.tcp(local)?;
    // As std's TcpListener::bind: a restarted server must not wait for
    // its old connections' TIME_WAIT.
    socket
        .set_reuseaddr(true)
        .and_then(|()| socket.bind(local))
        .and_then(|()| socket.listen(1024))
        .map_err(|e| {
            let e = advice::listening(scheme, addr, local, e);
            LinkError::io(format!("cannot listen on {what} {addr}"), e)
        })
}

struct Client {
    path: PathId,
    peer: SocketAddr,
    stream: TcpStream,
    scanner: StreamScanner,
}

/// `tcpin:HOST:PORT`: a listening socket and the clients it accepted.
pub(crate) struct TcpServer {
    listener: TcpListener,
    clients: Vec<Client>,
    next_path: PathId,
    /// What the scanners of departed clients saw.
    departed: ScanStats,
    buf: Box<[u8]>,
    /// Frames carry their bytes (`--tlog`).
    keep_raw: bool,
}

impl TcpServer {
    pub(crate) async fn listen(addr: &HostPort, route: &Route) -> Result<Self, LinkError> {
        let listener = listener("tcpin", "tcp", addr, route).await?;
        Ok(TcpServer {
            listener,
            clients: Vec::new(),
            next_path: 0,
            departed: ScanStats::default(),
            buf: vec![0; READ_BUF].into_boxed_slice(),
            keep_raw: false,
        })
    }

    fn accept(&mut self, stream: TcpStream, peer: SocketAddr) {
        if self.clients.len() >= MAX_CLIENTS {
            tracing::warn!(%peer, "too many tcp clients; refused");
            return;
        }
        if let Err(e) = stream.set_nodelay(true) {
            tracing::debug!(%peer, error = %e, "cannot set TCP_NODELAY");
        }
        tracing::info!(%peer, "tcp client connected");
        self.clients.push(Client {
            path: self.next_path,
            peer,
            stream,
            scanner: StreamScanner::new(),
        });
        // Paths are never reused, so an answer meant for a departed client
        // cannot reach a newcomer.
        self.next_path = self.next_path.wrapping_add(1);
    }

    /// A client leaving is not a link failure: the others go on.
    fn remove(&mut self, index: usize, why: &str) {
        let client = self.clients.swap_remove(index);
        tracing::info!(peer = %client.peer, why, "tcp client left");
        self.departed.add(&client.scanner.stats);
        if client.scanner.pending_bytes() > 0 {
            self.departed.truncated += 1;
            self.departed.skipped_bytes += client.scanner.pending_bytes() as u64;
        }
    }

    async fn write_to(&mut self, index: usize, frame: &[u8]) -> bool {
        let stream = &mut self.clients[index].stream;
        matches!(
            tokio::time::timeout(WRITE_STALL, stream.write_all(frame)).await,
            Ok(Ok(()))
        )
    }
}

impl Transport for TcpServer {
    async fn send(&mut self, frame: &[u8]) -> Result<Instant, LinkError> {
        let sent = Instant::now();
        let mut i = 0;
        while i < self.clients.len() {
            if self.write_to(i, frame).await {
                i += 1;
            } else {
                self.remove(i, "write failed");
            }
        }
        Ok(sent)
    }

    fn kind(&self) -> LinkKind {
        LinkKind::Listening
    }

    fn keep_raw(&mut self) {
        self.keep_raw = true;
    }

    async fn send_to(&mut self, path: PathId, frame: &[u8]) -> Result<Instant, LinkError> {
        let sent = Instant::now();
        if let Some(i) = self.clients.iter().position(|c| c.path == path) {
            if !self.write_to(i, frame).await {
                self.remove(i, "write failed");
            }
        }
        Ok(sent)
    }

    // Cancel-safe: it only polls, and keeps no state outside `self`.
    // Returns after any read or new client, so the session sees new peers.
    async fn recv(&mut self, out: &mut Vec<Inbound>) -> Result<(), LinkError> {
        poll_fn(|cx| {
            let mut progress = false;
            loop {
                match self.listener.poll_accept(cx) {
                    Poll::Ready(Ok((stream, peer))) => {
                        self.accept(stream, peer);
                        progress = true;
                    }
                    // Out of file descriptors and the like: the clients we
                    // have still work, so keep serving them.
                    Poll::Ready(Err(e)) => {
                        tracing::warn!(error = %e, "tcp accept failed");
                        break;
                    }
                    Poll::Pending => break,
                }
            }
            let mut i = 0;
            while i < self.clients.len() {
                let client = &mut self.clients[i];
                let mut gone: Option<String> = None;
                loop {
                    match client.stream.poll_read_ready(cx) {
                        Poll::Pending => break,
                        Poll::Ready(Err(e)) => {
                            gone = Some(e.to_string());
                            break;
                        }
                        Poll::Ready(Ok(())) => {}
                    }
                    // WouldBlock clears the readiness; polling again then
                    // registers the waker, so no wake-up is missed.
                    match client.stream.try_read(&mut self.buf) {
                        Ok(0) => {
                            gone = Some("closed".into());
                            break;
                        }
                        Ok(n) => {
                            let at = Instant::now();
                            let path = client.path;
                            let keep = self.keep_raw;
                            client.scanner.push_all(&self.buf[..n], &mut |raw, kind| {
                                out.push(Inbound::of(raw, kind, at, path, keep))
                            });
                            progress = true;
                            break;
                        }
                        Err(e) if e.kind() == io::ErrorKind::WouldBlock => {}
                        Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
                        Err(e) => {
                            gone = Some(e.to_string());
                            break;
                        }
                    }
                }
                match gone {
                    Some(why) => {
                        self.remove(i, &why);
                        progress = true;
                    }
                    None => i += 1,
                }
            }
            if progress {
                Poll::Ready(Ok(()))
            } else {
                Poll::Pending
            }
        })
        .await
    }

    fn has_peers(&self) -> bool {
        !self.clients.is_empty()
    }

    fn scan_stats(&self) -> ScanStats {
        let mut stats = self.departed;
        for c in &self.clients {
            stats.add(&c.scanner.stats);
        }
        stats
    }
}
