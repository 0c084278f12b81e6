//! `tlog:FILE` and `tlog:-` (standard input): a telemetry log read as a
//! link, on the log's own clock. Every ground station records one
//! (QGroundControl, Mission Planner, MAVProxy, mavlink-router); the
//! passive figures of a live link come out of it the same way.
//!
//! - **Streaming, in constant memory.** The file is read in chunks of
//!   [`READ_CHUNK`] on tokio's blocking pool (while a read is under way a
//!   paused clock does not move, so the log's time never runs ahead of
//!   its bytes), split into records ([`records`]) in a buffer of at most
//!   a chunk and two records, each frame checked by the frame scanner.
//! - **The log's clock.** The run is on tokio's paused clock, as
//!   `sim:?clock=virtual`: session time 0 is the first record and each
//!   record arrives at its stamp ([`stamps`]). Before each wait the
//!   session says when it wakes next ([`Transport::next_wake`]); one
//!   `recv` then hands over every record due by then (up to
//!   [`MAX_BATCH`]), after sleeping to the last one's time, so a frame is
//!   never seen before its time and a second's tick or a `-w` deadline
//!   falls exactly between records. A two-hour log is read in seconds.
//! - **The end of the log ends the run**, cleanly ([`LinkError::End`]),
//!   once the clock has reached the last record.
//! - **Nothing is sent**: `send` is refused; a passive session without
//!   our HEARTBEAT never calls it.
//! - The stamps' two lowest bits (MAVProxy's link number) are each
//!   frame's path, for per-link figures.

pub(crate) mod records;
pub(crate) mod stamps;
pub(crate) mod writer;

use std::fmt;
use std::io::{self, Read};
use std::path::Path;
use std::time::{Duration, SystemTime};

use serde::Serialize;
use tokio::task::JoinHandle;
use tokio::time::{sleep_until, Instant};

use super::link::{Inbound, LinkError, LinkKind, PathId, RxClock, Transport};
use crate::frame::signing::SignedBytes;
use crate::frame::{self, Frame, ScanStats};
use records::{Found, RecordStats, Splitter};
use stamps::{LogClock, StampFacts};

/// Bytes read at a time.
pub(crate) const READ_CHUNK: usize = 256 * 1024;
/// The most records one `recv` hands over.
pub(crate) const MAX_BATCH: usize = 4096;
/// How much of the log's start is kept, to say what a file that holds no
/// record is instead.
const SNIFF_LEN: usize = 4096;

/// Which log: a file, or standard input (`-`).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct TlogPath(pub String);

impl TlogPath {
    pub(crate) fn is_stdin(&self) -> bool {
        self.0 == "-"
    }
}

impl fmt::Display for TlogPath {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "tlog:{}", self.0)
    }
}

/// What a log held and how far it was read, for the summary.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub(crate) struct LogFacts {
    pub(crate) records: RecordStats,
    pub(crate) stamps: StampFacts,
    /// The run read the log to its end (not stopped by `-w` or Ctrl-C).
    pub(crate) complete: bool,
}

type Reader = Box<dyn Read + Send>;
type Reading = JoinHandle<(Reader, Vec<u8>, io::Result<usize>)>;

/// The log's bytes, read on the blocking pool.
struct Input {
    /// Idle: the reader and its chunk. Taken while a read is under way.
    idle: Option<(Reader, Vec<u8>)>,
    /// A read under way, kept across a cancelled `recv`.
    reading: Option<Reading>,
    eof: bool,
}

impl Input {
    /// Appends the next chunk to `buf` (nothing at the end of the input).
    /// Cancel-safe: a read under way is picked up by the next call.
    async fn read_into(&mut self, buf: &mut Vec<u8>) -> io::Result<()> {
        if self.reading.is_none() {
            let (mut reader, mut chunk) = self.idle.take().expect("idle between reads");
            self.reading = Some(tokio::task::spawn_blocking(move || {
                chunk.resize(READ_CHUNK, 0);
                let read = loop {
                    match reader.read(&mut chunk) {
                        Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
                        other => break other,
                    }
                };
                (reader, chunk, read)
            }));
        }
        let done = self.reading.as_mut().expect("a read under way").await;
        self.reading = None;
        let (reader, chunk, read) = done.map_err(io::Error::other)?;
        let read = read.inspect(|&n| buf.extend_from_slice(&chunk[..n]));
        self.idle = Some((reader, chunk));
        self.eof = matches!(read, Ok(0));
        read.map(|_| ())
    }
}

/// A record taken from the log, not yet handed over.
struct Record {
    t: u64,
    path: PathId,
    frame: Frame,
    signature: Option<SignedBytes>,
}

impl Record {
    fn inbound(self, origin: Instant) -> Inbound {
        Inbound {
            frame: self.frame,
            at: origin + Duration::from_nanos(self.t),
            path: self.path,
            signature: self.signature,
            raw: None,
        }
    }
}

/// What the log gave on one look at its buffer.
enum Parsed {
    Record(Record),
    NeedMore,
    End,
}

/// What `recv` does next.
enum Next {
    /// Hand the batch over once the clock reaches its last record.
    Deliver(Instant),
    Read,
    End,
}

pub(crate) struct TlogLink {
    name: String,
    input: Input,
    /// Bytes read and not yet finished with, from `pos`.
    buf: Vec<u8>,
    pos: usize,
    splitter: Splitter,
    clock: LogClock,
    /// The session's time 0 (the first `recv`).
    origin: Option<Instant>,
    /// When the session wakes next.
    horizon: Option<Instant>,
    /// The next record, beyond the batch being made.
    next: Option<Record>,
    batch: Vec<Inbound>,
    /// The last session time the batch being made may take.
    batch_until: Option<u64>,
    /// The log's first bytes, to name what a file without records is.
    sniff: Vec<u8>,
    complete: bool,
}

impl TlogLink {
    /// Opens the log and reads up to its first record: a file that holds
    /// none (not a log, empty, a directory) is refused before the run.
    pub(crate) async fn open(path: &TlogPath) -> Result<TlogLink, LinkError> {
        let name = path.to_string();
        let reader: Reader = if path.is_stdin() {
            Box::new(io::stdin())
        } else {
            let file = Path::new(&path.0);
            let cannot = |e| LinkError::io(format!("cannot open {name}"), e);
            if std::fs::metadata(file).map_err(cannot)?.is_dir() {
                return Err(LinkError::Closed(format!(
                    "cannot read {name}: it is a directory, not a telemetry log"
                )));
            }
            Box::new(std::fs::File::open(file).map_err(cannot)?)
        };
        let mut link = TlogLink {
            name,
            input: Input {
                idle: Some((reader, Vec::with_capacity(READ_CHUNK))),
                reading: None,
                eof: false,
            },
            buf: Vec::with_capacity(2 * READ_CHUNK),
            pos: 0,
            splitter: Splitter::default(),
            clock: LogClock::default(),
            origin: None,
            horizon: None,
            next: None,
            batch: Vec::with_capacity(MAX_BATCH),
            batch_until: None,
            sniff: Vec::new(),
            complete: false,
        };
        loop {
            match link.parse() {
                Parsed::Record(r) => {
                    link.next = Some(r);
                    return Ok(link);
                }
                Parsed::NeedMore => link.read().await?,
                Parsed::End => return Err(LinkError::Closed(link.no_record())),
            }
        }
    }

    /// Why a log that ended before its first record is none.
    fn no_record(&self) -> String {
        let stats = self.splitter.stats();
        let bytes = stats.junk_bytes + stats.truncated_bytes;
        let what = if bytes == 0 {
            "it is empty".to_string()
        } else if stats.truncated_bytes > 0 {
            format!("its {bytes} bytes are one record cut short")
        } else if holds_frames(&self.sniff) {
            format!(
                "its {bytes} bytes hold MAVLink frames without time stamps \
                 (a raw capture, not a .tlog)"
            )
        } else if is_text(&self.sniff) {
            format!("its {bytes} bytes are text")
        } else {
            format!("no record (an 8-byte time stamp, then a MAVLink frame) in its {bytes} bytes")
        };
        format!("{}: not a telemetry log: {what}", self.name)
    }

    /// Reads the next chunk, dropping what is finished with first.
    async fn read(&mut self) -> Result<(), LinkError> {
        self.buf.drain(..self.pos);
        self.pos = 0;
        let before = self.buf.len();
        self.input
            .read_into(&mut self.buf)
            .await
            .map_err(|e| LinkError::io(format!("cannot read {}", self.name), e))?;
        if self.sniff.len() < SNIFF_LEN {
            let take = (SNIFF_LEN - self.sniff.len()).min(self.buf.len() - before);
            self.sniff
                .extend_from_slice(&self.buf[before..before + take]);
        }
        Ok(())
    }

    /// The next record in the buffer, dated.
    fn parse(&mut self) -> Parsed {
        let (found, used) = self.splitter.next(&self.buf[self.pos..], self.input.eof);
        let parsed = match found {
            Found::Record { stamp, frame, kind } => {
                let (t, link) = self.clock.date(stamp);
                Parsed::Record(Record {
                    t,
                    path: PathId::from(link),
                    frame: frame::decode_as(frame, kind),
                    signature: SignedBytes::of(frame),
                })
            }
            Found::NeedMore => Parsed::NeedMore,
            Found::End => Parsed::End,
        };
        self.pos += used;
        parsed
    }

    /// Adds records to the batch: every one due by the session's next
    /// wake-up (at least the first), up to [`MAX_BATCH`].
    fn fill(&mut self, origin: Instant) -> Next {
        let horizon = self
            .horizon
            .map(|h| h.saturating_duration_since(origin).as_nanos() as u64);
        loop {
            if self.batch.len() >= MAX_BATCH {
                return self.ready(origin);
            }
            let record = match self.next.take() {
                Some(r) => r,
                None => match self.parse() {
                    Parsed::Record(r) => r,
                    // A batch goes without waiting for the next read.
                    Parsed::NeedMore | Parsed::End if !self.batch.is_empty() => {
                        return self.ready(origin)
                    }
                    Parsed::NeedMore => return Next::Read,
                    Parsed::End => return Next::End,
                },
            };
            let until = *self
                .batch_until
                .get_or_insert(horizon.map_or(record.t, |h| h.max(record.t)));
            if record.t > until {
                self.next = Some(record);
                return self.ready(origin);
            }
            self.batch.push(record.inbound(origin));
        }
    }

    /// Hands the batch over once the clock reaches its last record.
    fn ready(&self, origin: Instant) -> Next {
        Next::Deliver(self.batch.last().map_or(origin, |b| b.at))
    }

    /// The wall-clock time of session time 0: the first record's stamp.
    pub(crate) fn started(&self) -> SystemTime {
        let first = self.clock.facts().map_or(0, |f| f.first_us);
        SystemTime::UNIX_EPOCH + Duration::from_micros(first)
    }

    /// What the log held so far.
    pub(crate) fn facts(&self) -> Option<LogFacts> {
        Some(LogFacts {
            records: self.splitter.stats(),
            stamps: self.clock.facts()?,
            complete: self.complete,
        })
    }
}

/// Whether the bytes hold MAVLink frames as a stream would (no stamps).
fn holds_frames(bytes: &[u8]) -> bool {
    let mut stats = ScanStats::default();
    frame::scan_datagram(bytes, &mut stats, &mut |_| {});
    stats.frames >= 2
}

/// Whether the bytes read as text (printable ASCII or UTF-8, whitespace).
fn is_text(bytes: &[u8]) -> bool {
    // A chunk may end inside a character.
    let text = match std::str::from_utf8(bytes) {
        Ok(t) => t,
        Err(e) => std::str::from_utf8(&bytes[..e.valid_up_to()]).unwrap_or(""),
    };
    text.len() + 4 >= bytes.len()
        && text
            .chars()
            .all(|c| !c.is_control() || c.is_ascii_whitespace())
}

impl Transport for TlogLink {
    async fn send(&mut self, _frame: &[u8]) -> Result<Instant, LinkError> {
        Err(LinkError::Closed(format!(
            "{}: a telemetry log is only read; nothing is sent on it",
            self.name
        )))
    }

    async fn send_to(&mut self, _path: PathId, frame: &[u8]) -> Result<Instant, LinkError> {
        self.send(frame).await
    }

    /// Cancel-safe: a batch being made, the next record and a read under
    /// way all stay in the link; the only other wait is a sleep.
    async fn recv(&mut self, out: &mut Vec<Inbound>) -> Result<(), LinkError> {
        // The paused clock has not moved since the session's start.
        let origin = *self.origin.get_or_insert_with(Instant::now);
        loop {
            match self.fill(origin) {
                Next::Deliver(due) => {
                    sleep_until(due).await;
                    out.append(&mut self.batch);
                    self.batch_until = None;
                    return Ok(());
                }
                Next::Read => self.read().await?,
                Next::End => {
                    sleep_until(origin + Duration::from_nanos(self.clock.latest())).await;
                    self.complete = true;
                    return Err(LinkError::End);
                }
            }
        }
    }

    /// Never called: a log's session is not paced precisely.
    fn read_waiting(&mut self, _out: &mut Vec<Inbound>) -> Result<bool, LinkError> {
        Ok(false)
    }

    fn next_wake(&mut self, at: Option<Instant>) {
        self.horizon = at;
    }

    fn scan_stats(&self) -> ScanStats {
        self.splitter.scan_stats()
    }

    fn rx_clock(&self) -> RxClock {
        RxClock::Log
    }

    fn kind(&self) -> LinkKind {
        LinkKind::Log
    }

    /// A log is never recorded (`--tlog` refuses one as input).
    fn keep_raw(&mut self) {}
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frame::codec::{encode, Header, Version};
    use crate::frame::Msg;

    const T0: u64 = 1_764_500_000_000_000;

    /// A log file of records 20 ms apart, packet sequence = index.
    fn log_file(name: &str, n: u8) -> std::path::PathBuf {
        let path = std::env::temp_dir().join(format!("mavping-{}-{name}.tlog", std::process::id()));
        let mut data = Vec::new();
        for i in 0..n {
            data.extend((T0 + u64::from(i) * 20_000).to_be_bytes());
            let header = Header {
                sysid: 1,
                compid: 1,
                seq: i,
            };
            encode(
                &mut data,
                Version::V2,
                header,
                &Msg::Attitude { time_boot_ms: 0 },
            );
        }
        std::fs::write(&path, data).unwrap();
        path
    }

    fn seqs(batch: &[Inbound]) -> Vec<u8> {
        batch.iter().map(|b| b.frame.packet_seq).collect()
    }

    #[tokio::test(start_paused = true)]
    async fn a_recv_hands_over_what_is_due_by_the_next_wake_and_no_later() {
        let path = log_file("batch", 10);
        let mut link = TlogLink::open(&TlogPath(path.display().to_string()))
            .await
            .unwrap();
        let t0 = Instant::now();
        let mut out = Vec::new();
        // The session wakes at 50 ms: records at 0, 20 and 40 ms.
        link.next_wake(Some(t0 + Duration::from_millis(50)));
        link.recv(&mut out).await.unwrap();
        assert_eq!(seqs(&out), [0, 1, 2]);
        assert_eq!(Instant::now() - t0, Duration::from_millis(40));
        assert_eq!(out[2].at - t0, Duration::from_millis(40));
        // A wake before the next record: that record alone, at its time.
        out.clear();
        link.next_wake(Some(t0 + Duration::from_millis(45)));
        link.recv(&mut out).await.unwrap();
        assert_eq!(seqs(&out), [3]);
        assert_eq!(Instant::now() - t0, Duration::from_millis(60));
        // Cancelled while waiting for its time, nothing is lost.
        out.clear();
        link.next_wake(Some(t0 + Duration::from_secs(1)));
        let cut = tokio::time::timeout(Duration::from_millis(5), link.recv(&mut out)).await;
        assert!(cut.is_err() && out.is_empty());
        link.recv(&mut out).await.unwrap();
        assert_eq!(seqs(&out), [4, 5, 6, 7, 8, 9]);
        // The end: once the clock is at the last record, a clean end.
        assert!(matches!(link.recv(&mut out).await, Err(LinkError::End)));
        assert_eq!(Instant::now() - t0, Duration::from_millis(180));
        let facts = link.facts().unwrap();
        assert!(facts.complete);
        assert_eq!(facts.records.records, 10);
        assert_eq!(
            link.started(),
            SystemTime::UNIX_EPOCH + Duration::from_micros(T0)
        );
        assert!(link.send(&[0]).await.is_err(), "nothing is sent on a log");
        let _ = std::fs::remove_file(path);
    }

    #[test]
    fn what_a_file_without_records_is_gets_a_name() {
        assert!(is_text(b"hello\nworld\t!"));
        assert!(!is_text(b"\x89PNG\r\n\x1a\n\0\0\0\rIHDR"));
        assert!(!holds_frames(b"hello"));
    }
}
