//! Byte-stream links with one peer (a TCP client, a serial port), and how
//! they survive a lost connection when `--reconnect` asks for it.
//!
//! A stream carries no message boundaries, so one [`StreamScanner`] keeps a
//! partial frame between reads and resynchronises after junk. While the
//! link is down, `send` succeeds without writing: the requests of that
//! period time out and count as lost, which is what the link did to them.
//!
//! Writing never waits for the peer: a frame goes to the kernel at once
//! if it takes it, else to a bounded [`OutQueue`] drained whenever the
//! session waits on the link; a frame that does not fit is refused and
//! counted. A peer that stops reading thus costs requests, not the run:
//! the deadline and Ctrl-C still end it.

use std::future::poll_fn;
use std::io::{self, Write};
use std::pin::Pin;
use std::task::{Context, Poll};
use std::time::Duration;

use tokio::io::{AsyncRead, AsyncWrite, ReadBuf};
use tokio::time::{sleep_until, Instant};

use super::out_queue::OutQueue;
use super::outbox::Outbox;
use super::{Inbound, LinkError, LinkKind, PathId, Transport};
use crate::frame::{ScanStats, StreamScanner};

/// Wait before the first reconnection attempt; doubled after each failure.
const FIRST_RETRY: Duration = Duration::from_millis(100);
/// Longest wait between attempts: a radio plugged back in is found quickly.
const MAX_RETRY: Duration = Duration::from_secs(5);
const READ_BUF: usize = 16 * 1024;

/// Opens the underlying stream; called again for each reconnection.
#[allow(async_fn_in_trait)] // used with concrete types only
pub(crate) trait Connect {
    type Stream: AsyncRead + AsyncWrite + Unpin;
    /// How this kind of link meets its peer.
    const KIND: LinkKind;
    /// The link as the user named it, for messages.
    fn name(&self) -> &str;
    /// What the end of the stream means on this kind of link.
    fn eof_reason(&self) -> &'static str {
        "closed by the peer"
    }
    /// Whether a read error is this kind of link's end all the same (a
    /// serial device that went away may say EIO rather than end of file).
    fn is_hangup(&self, _e: &io::Error) -> bool {
        false
    }
    async fn connect(&self) -> io::Result<Self::Stream>;
}

enum State<S> {
    Up(S),
    Down {
        since: Instant,
        attempt: u32,
        retry_at: Instant,
    },
}

pub(crate) struct StreamLink<C: Connect> {
    connector: C,
    reconnect: bool,
    state: State<C::Stream>,
    scanner: StreamScanner,
    /// What the scanners of earlier connections saw.
    earlier: ScanStats,
    buf: Box<[u8]>,
    /// Finished down periods; the current one is added by `downtime`.
    downtime: Duration,
    out: OutQueue,
    /// Frames carry their bytes (`--tlog`).
    keep_raw: bool,
}

fn backoff(attempt: u32) -> Duration {
    FIRST_RETRY
        .saturating_mul(1u32 << attempt.saturating_sub(1).min(16))
        .min(MAX_RETRY)
}

/// One line on stderr, the form every mavping message has.
fn notice(msg: std::fmt::Arguments<'_>) {
    let _ = writeln!(io::stderr(), "mavping: {msg}");
}

impl<C: Connect> StreamLink<C> {
    /// Connects once; a failure here ends the run even with `reconnect`,
    /// since a wrong device or address is a usage error, not a lost link.
    pub(crate) async fn open(connector: C, reconnect: bool) -> Result<Self, LinkError> {
        let stream = connector
            .connect()
            .await
            .map_err(|e| LinkError::io(format!("cannot open {}", connector.name()), e))?;
        Ok(Self::with(connector, reconnect, State::Up(stream)))
    }

    fn with(connector: C, reconnect: bool, state: State<C::Stream>) -> Self {
        StreamLink {
            connector,
            reconnect,
            state,
            scanner: StreamScanner::new(),
            earlier: ScanStats::default(),
            buf: vec![0; READ_BUF].into_boxed_slice(),
            downtime: Duration::ZERO,
            out: OutQueue::default(),
            keep_raw: false,
        }
    }

    /// Connects, or when nothing listens there yet, starts down and tries
    /// again with backoff as after a loss; any other failure (a name that
    /// does not resolve, an unreachable network) ends the run as `open`'s.
    pub(crate) async fn open_or_wait(connector: C) -> Result<Self, LinkError> {
        let first = connector.connect().await;
        let stream = match first {
            Err(e) if e.kind() == io::ErrorKind::ConnectionRefused => None,
            other => Some(
                other.map_err(|e| LinkError::io(format!("cannot open {}", connector.name()), e))?,
            ),
        };
        let now = Instant::now();
        let state = match stream {
            Some(stream) => State::Up(stream),
            None => {
                let delay = backoff(1);
                notice(format_args!(
                    "{}: nothing listening yet; connecting (attempt 1 in {})",
                    connector.name(),
                    humantime::format_duration(delay)
                ));
                State::Down {
                    since: now,
                    attempt: 1,
                    retry_at: now + delay,
                }
            }
        };
        Ok(Self::with(connector, true, state))
    }

    /// The connection broke: end the run, or start reconnecting.
    fn lost(&mut self, e: io::Error) -> Result<(), LinkError> {
        if !self.reconnect {
            let name = self.connector.name();
            let hangup = e.kind() == io::ErrorKind::UnexpectedEof || self.connector.is_hangup(&e);
            return Err(if hangup {
                LinkError::Closed(format!("{name}: {}", self.connector.eof_reason()))
            } else {
                LinkError::io(format!("{name}: link failed"), e)
            });
        }
        // A frame cut by the break can never be finished, and what waited
        // to be written was for the connection that broke.
        self.out.clear();
        let old = std::mem::take(&mut self.scanner);
        self.earlier.add(&old.stats);
        if old.pending_bytes() > 0 {
            self.earlier.truncated += 1;
            self.earlier.skipped_bytes += old.pending_bytes() as u64;
        }
        let now = Instant::now();
        let delay = backoff(1);
        notice(format_args!(
            "{} lost ({}); reconnecting (attempt 1 in {})",
            self.connector.name(),
            if e.kind() == io::ErrorKind::UnexpectedEof {
                self.connector.eof_reason().to_string()
            } else {
                e.to_string()
            },
            humantime::format_duration(delay)
        ));
        self.state = State::Down {
            since: now,
            attempt: 1,
            retry_at: now + delay,
        };
        Ok(())
    }

    async fn try_reconnect(&mut self) {
        let State::Down { since, attempt, .. } = self.state else {
            return;
        };
        match self.connector.connect().await {
            Ok(stream) => {
                let down = since.elapsed();
                self.downtime += down;
                notice(format_args!(
                    "{} reconnected after {:.3} s",
                    self.connector.name(),
                    down.as_secs_f64()
                ));
                self.state = State::Up(stream);
            }
            Err(e) => {
                let attempt = attempt + 1;
                let delay = backoff(attempt);
                notice(format_args!(
                    "{} still down ({e}); reconnecting (attempt {attempt} in {})",
                    self.connector.name(),
                    humantime::format_duration(delay)
                ));
                self.state = State::Down {
                    since,
                    attempt,
                    retry_at: Instant::now() + delay,
                };
            }
        }
    }

    /// Queues `frame` (or refuses it) and writes what the peer takes now.
    fn write(&mut self, frame: &[u8]) -> Result<Instant, LinkError> {
        let sent = Instant::now();
        if matches!(self.state, State::Up(_)) && self.out.offer(frame) {
            let mut cx = Context::from_waker(std::task::Waker::noop());
            if let Poll::Ready(Err(e)) = self.poll_drain(&mut cx) {
                self.lost(e)?;
            }
        }
        Ok(sent)
    }

    /// Writes queued bytes until the peer takes no more (`Pending`) or the
    /// queue is empty (`Ready(Ok)`).
    fn poll_drain(&mut self, cx: &mut Context<'_>) -> Poll<io::Result<()>> {
        let State::Up(stream) = &mut self.state else {
            return Poll::Ready(Ok(()));
        };
        while !self.out.is_empty() {
            match Pin::new(&mut *stream).poll_write(cx, self.out.waiting()) {
                Poll::Ready(Ok(0)) => return Poll::Ready(Err(io::ErrorKind::WriteZero.into())),
                Poll::Ready(Ok(n)) => self.out.written(n),
                Poll::Ready(Err(e)) if e.kind() == io::ErrorKind::Interrupted => {}
                Poll::Ready(Err(e)) => return Poll::Ready(Err(e)),
                Poll::Pending => return Poll::Pending,
            }
        }
        Poll::Ready(Ok(()))
    }

    /// Drains the queue while reading: ready with the bytes read (0: end
    /// of stream) or an error; pending while neither happened.
    fn poll_read_draining(&mut self, cx: &mut Context<'_>) -> Poll<io::Result<usize>> {
        if let Poll::Ready(Err(e)) = self.poll_drain(cx) {
            return Poll::Ready(Err(e));
        }
        let State::Up(stream) = &mut self.state else {
            return Poll::Ready(Ok(0));
        };
        let mut buf = ReadBuf::new(&mut self.buf);
        match Pin::new(stream).poll_read(cx, &mut buf) {
            Poll::Ready(Ok(())) => Poll::Ready(Ok(buf.filled().len())),
            Poll::Ready(Err(e)) => Poll::Ready(Err(e)),
            Poll::Pending => Poll::Pending,
        }
    }
}

impl<C: Connect> Transport for StreamLink<C> {
    async fn send(&mut self, frame: &[u8]) -> Result<Instant, LinkError> {
        self.write(frame)
    }

    /// Once a frame is refused, the rest of the box is too, so what went
    /// out is always a prefix of it.
    async fn send_all(&mut self, outbox: &Outbox) -> Result<Instant, LinkError> {
        let sent = Instant::now();
        let mut refusing = false;
        for (frame, _) in outbox.frames() {
            if refusing {
                self.out.refuse();
                continue;
            }
            let before = self.out.refused();
            self.write(frame)?;
            refusing = self.out.refused() > before;
        }
        Ok(sent)
    }

    fn refused(&self) -> u64 {
        self.out.refused()
    }

    fn kind(&self) -> LinkKind {
        C::KIND
    }

    fn keep_raw(&mut self) {
        self.keep_raw = true;
    }

    /// One peer: every path is the same stream.
    async fn send_to(&mut self, _path: PathId, frame: &[u8]) -> Result<Instant, LinkError> {
        self.write(frame)
    }

    // Cancel-safe: a read that has not completed consumed nothing, bytes
    // written left the queue as they went, a dropped sleep or connection
    // attempt is simply tried again.
    async fn recv(&mut self, out: &mut Vec<Inbound>) -> Result<(), LinkError> {
        loop {
            match &self.state {
                State::Up(_) => {
                    let read = poll_fn(|cx| self.poll_read_draining(cx)).await;
                    let at = Instant::now();
                    match read {
                        Ok(0) => self.lost(io::ErrorKind::UnexpectedEof.into())?,
                        Ok(n) => {
                            let keep = self.keep_raw;
                            self.scanner.push_all(&self.buf[..n], &mut |raw, kind| {
                                out.push(Inbound::of(raw, kind, at, 0, keep))
                            });
                            return Ok(());
                        }
                        Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
                        Err(e) => self.lost(e)?,
                    }
                }
                State::Down { retry_at, .. } => {
                    sleep_until(*retry_at).await;
                    self.try_reconnect().await;
                }
            }
        }
    }

    fn scan_stats(&self) -> ScanStats {
        let mut stats = self.earlier;
        stats.add(&self.scanner.stats);
        stats
    }

    fn downtime(&self) -> Duration {
        match self.state {
            State::Down { since, .. } => self.downtime + since.elapsed(),
            State::Up(_) => self.downtime,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn backoff_doubles_up_to_the_cap() {
        assert_eq!(backoff(1), Duration::from_millis(100));
        assert_eq!(backoff(2), Duration::from_millis(200));
        assert_eq!(backoff(4), Duration::from_millis(800));
        assert_eq!(backoff(7), MAX_RETRY);
        assert_eq!(backoff(u32::MAX), MAX_RETRY);
    }
}
