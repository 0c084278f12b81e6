//! `--tlog FILE`: a link that records every frame it receives and sends to
//! a telemetry log, forwarding every call to the link it wraps; and tells
//! what it receives to whatever else the run watches across its links
//! ([`Watch`]: the pair report). The engine knows nothing of it; the batched sends (`send_all`) stay one system
//! call, and a run without `--tlog` only checks an `Option` per call.
//!
//! - A received frame is written with its receive time (the kernel's stamp
//!   where the link has one), a sent frame with the time taken just before
//!   its write, both as wall-clock microseconds: the clock's reading when
//!   the recording began plus the monotonic time since.
//! - The links of one run share one file, each received frame marked with
//!   its link's index in the stamp's two lowest bits and what mavping sent
//!   with 3, as MAVProxy does ([`writer`](super::tlog::writer)).
//! - A damaged frame (its CRC failed, its header whole: the scanner's
//!   [`Kind::Damaged`](crate::frame::Kind)) is recorded as it arrived, as
//!   QGroundControl records one: read back, it is a damaged record again,
//!   where a logger that kept only good frames would leave its number lost.
//! - A frame the link did not write is not recorded: nothing is sent while
//!   a listening link has no peer, and a byte stream refuses the tail of a
//!   burst it cannot queue ([`Transport::refused`]).

use std::cell::RefCell;
use std::fs::File;
use std::io::{self, BufWriter};
use std::path::{Path, PathBuf};
use std::rc::Rc;
use std::time::{Duration, SystemTime};

use tokio::time::Instant;

use super::tlog::writer::{TlogWriter, SENT};
use super::{Inbound, LinkError, LinkKind, Outbox, PathId, RxClock, Transport};
use crate::frame::ScanStats;

/// Output buffer: a few hundred frames between writes at any rate.
const BUFFER: usize = 64 * 1024;

type Log = Rc<RefCell<TlogWriter<BufWriter<File>>>>;

/// The file a run records to; each link records through its [`Tap`].
pub(crate) struct Recording {
    log: Log,
    path: PathBuf,
    /// The monotonic and the wall clock at the recording's start.
    origin: (Instant, u64),
}

impl Recording {
    /// Creates (or truncates) `path`, as `--samples` and `--plot` do.
    pub(crate) fn create(path: &Path) -> io::Result<Self> {
        let file = File::create(path)?;
        let wall_us = SystemTime::now()
            .duration_since(SystemTime::UNIX_EPOCH)
            .unwrap_or_default()
            .as_micros() as u64;
        Ok(Recording {
            log: Rc::new(RefCell::new(TlogWriter::new(BufWriter::with_capacity(
                BUFFER, file,
            )))),
            path: path.to_path_buf(),
            origin: (Instant::now(), wall_us),
        })
    }

    pub(crate) fn path(&self) -> &Path {
        &self.path
    }

    /// What the `index`-th link of the run records through.
    pub(crate) fn tap(&self, index: usize) -> Tap {
        Tap {
            log: self.log.clone(),
            origin: self.origin,
            link: index.min(usize::from(SENT) - 1) as u8,
        }
    }

    /// Flushes the log; how many records it holds, or the first write
    /// error of the run.
    pub(crate) fn finish(&self) -> io::Result<u64> {
        self.log.borrow_mut().finish()
    }
}

/// One link's way into the run's log.
pub(crate) struct Tap {
    log: Log,
    origin: (Instant, u64),
    /// The link bits of what this link receives.
    link: u8,
}

impl Tap {
    fn micros(&self, at: Instant) -> u64 {
        let (t0, wall_us) = self.origin;
        let since = at.saturating_duration_since(t0);
        let before = t0.saturating_duration_since(at);
        (wall_us + as_micros(since)).saturating_sub(as_micros(before))
    }

    fn sent(&self, at: Instant, frame: &[u8]) {
        self.log.borrow_mut().record(self.micros(at), SENT, frame);
    }

    /// Writes every frame of `inbound` not written yet, and lets its bytes
    /// go.
    fn received(&self, inbound: &mut [Inbound]) {
        let mut log = self.log.borrow_mut();
        for frame in inbound {
            if let Some(raw) = frame.raw.take() {
                log.record(self.micros(frame.at), self.link, &raw);
            }
        }
    }
}

fn as_micros(d: Duration) -> u64 {
    d.as_micros() as u64
}

/// What else a run watches of the frames every link receives, across its
/// links (the pair report of several links): told each frame once, in
/// the order received.
pub(crate) trait Watch {
    fn received(&self, inbound: &[Inbound]);

    /// A frame the link wrote at `at` (as the recording has it).
    fn sent(&self, at: Instant, frame: &[u8]);
}

/// A link, recorded when it has a tap, watched when it has a watch.
pub(crate) struct Recorded<T> {
    link: T,
    tap: Option<Tap>,
    watch: Option<Rc<dyn Watch>>,
    /// The frames of `out` the watch was told: the session drains `out`
    /// between calls, but a cancelled `recv` leaves what it pushed.
    watched: usize,
}

impl<T: Transport> Recorded<T> {
    /// `link`, recorded through `tap` if there is one.
    pub(crate) fn new(mut link: T, tap: Option<Tap>) -> Self {
        if tap.is_some() {
            link.keep_raw();
        }
        Recorded {
            link,
            tap,
            watch: None,
            watched: 0,
        }
    }

    /// The link, its received frames also told to `watch`.
    pub(crate) fn watched(mut self, watch: Option<Rc<dyn Watch>>) -> Self {
        self.watch = watch;
        self
    }

    /// Tells the watch the frames of `out` it was not told yet.
    fn watch(&mut self, out: &[Inbound]) {
        let Some(watch) = &self.watch else { return };
        if out.len() < self.watched {
            self.watched = 0;
        }
        watch.received(&out[self.watched..]);
        self.watched = out.len();
    }

    /// The link itself.
    pub(crate) fn inner(&self) -> &T {
        &self.link
    }

    /// Records and tells the watch what `out` holds that they have not
    /// had.
    fn take(&mut self, out: &mut [Inbound]) {
        self.watch(out);
        if let Some(tap) = &self.tap {
            tap.received(out);
        }
    }

    /// Records `frame` sent at `at`, and tells the watch, unless the link
    /// refused it.
    fn sent(&self, at: Instant, frame: &[u8], refused_before: u64) {
        if self.link.refused() == refused_before {
            self.written(at, frame);
        }
    }

    /// Records a frame the link wrote, and tells the watch.
    fn written(&self, at: Instant, frame: &[u8]) {
        if let Some(tap) = &self.tap {
            tap.sent(at, frame);
        }
        if let Some(watch) = &self.watch {
            watch.sent(at, frame);
        }
    }
}

impl<T: Transport> Transport for Recorded<T> {
    async fn send(&mut self, frame: &[u8]) -> Result<Instant, LinkError> {
        let (peers, refused) = (self.link.has_peers(), self.link.refused());
        let at = self.link.send(frame).await?;
        if peers {
            self.sent(at, frame, refused);
        }
        Ok(at)
    }

    async fn send_to(&mut self, path: PathId, frame: &[u8]) -> Result<Instant, LinkError> {
        let refused = self.link.refused();
        let at = self.link.send_to(path, frame).await?;
        self.sent(at, frame, refused);
        Ok(at)
    }

    async fn send_all(&mut self, outbox: &Outbox) -> Result<Instant, LinkError> {
        let (peers, refused) = (self.link.has_peers(), self.link.refused());
        let at = self.link.send_all(outbox).await?;
        if self.tap.is_some() || self.watch.is_some() {
            // What a byte stream refuses of a burst is always its tail.
            let refused = (self.link.refused() - refused) as usize;
            let written = outbox.len().saturating_sub(refused);
            for (frame, to) in outbox.frames().take(written) {
                if peers || matches!(to, super::To::Path(_)) {
                    self.written(at, frame);
                }
            }
        }
        Ok(at)
    }

    // Cancel-safe as the link's: frames a cancelled call left in `out`
    // still hold their bytes and are written on the next call.
    async fn recv(&mut self, out: &mut Vec<Inbound>) -> Result<(), LinkError> {
        if self.tap.is_none() && self.watch.is_none() {
            return self.link.recv(out).await;
        }
        self.take(out);
        let received = self.link.recv(out).await;
        self.take(out);
        received
    }

    fn read_waiting(&mut self, out: &mut Vec<Inbound>) -> Result<bool, LinkError> {
        self.take(out);
        let waiting = self.link.read_waiting(out);
        self.take(out);
        waiting
    }

    fn has_peers(&self) -> bool {
        self.link.has_peers()
    }

    fn scan_stats(&self) -> ScanStats {
        self.link.scan_stats()
    }

    fn rx_clock(&self) -> RxClock {
        self.link.rx_clock()
    }

    fn downtime(&self) -> Duration {
        self.link.downtime()
    }

    fn refused(&self) -> u64 {
        self.link.refused()
    }

    fn unreachable(&self) -> u64 {
        self.link.unreachable()
    }

    fn kind(&self) -> LinkKind {
        self.link.kind()
    }

    fn next_wake(&mut self, at: Option<Instant>) {
        self.link.next_wake(at)
    }

    fn keep_raw(&mut self) {
        self.link.keep_raw()
    }
}
