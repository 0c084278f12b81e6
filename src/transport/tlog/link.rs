//! The link itself ([`TlogLink`]): records taken from the input, dated by
//! the log's clock, and handed over in batches as the paused clock
//! reaches them; the end of the log ends the run.

use std::io;
use std::path::Path;
use std::time::{Duration, SystemTime};

use tokio::time::{sleep_until, Instant};

use super::facts::LogFacts;
use super::input::{Input, Reader, READ_CHUNK};
use super::path::TlogPath;
use super::records::{Found, Splitter};
use super::sniff::{holds_frames, is_text, SNIFF_LEN};
use super::stamps::LogClock;
use crate::frame::signing::SignedBytes;
use crate::frame::{self, Frame, ScanStats};
use crate::transport::link::{Inbound, LinkError, LinkKind, PathId, RxClock, Transport};

/// The most records one `recv` hands over.
pub(crate) const MAX_BATCH: usize = 4096;

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
}
