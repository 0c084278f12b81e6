//! Writes a telemetry log (`--tlog FILE`): what a live run received and
//! sent, record by record, in the format every tool reads (8 bytes of
//! big-endian microseconds since the Unix epoch, then the frame as on the
//! wire). Pure: stamps and bytes in, records out to any writer.
//!
//! - **MAVProxy's convention for the two lowest bits**: `(usec & !3) |
//!   link`, the link being the index of the run's link a frame came in on
//!   (0, 1, 2) and 3 what mavping itself sent. pymavlink reads them as
//!   MAVProxy's (`msg._link`), every other tool as 3 µs at most; mavping's
//!   own reader splits its per-link figures by them.
//! - **In order of time**: a stamp behind the latest record's (a frame
//!   the kernel stamped before a send that was logged first, because it
//!   was read after it) is written at the latest, as a logger that stamps
//!   when it reads (pymavlink's) would have.
//! - **One error ends the writing, not the run**: the first write error is
//!   kept and nothing more is written; the caller reports it at the end.

use std::io::{self, Write};

/// The link bits of what mavping sent (MAVProxy's own-frames mark).
pub(crate) const SENT: u8 = 3;
/// The most links one log can tell apart by their bits (0, 1, 2).
pub(crate) const MAX_LINKS: usize = 3;
/// Buffered output reaches the file at least this often (µs of stamps),
/// so a long run's log can be read while it grows.
const FLUSH_EVERY_US: u64 = 1_000_000;
/// The bits MAVProxy's link number takes.
const LINK_BITS: u64 = 3;

/// A telemetry log being written.
pub(crate) struct TlogWriter<W: Write> {
    out: W,
    /// The latest record's stamp, link bits cleared.
    latest_us: u64,
    last_flush_us: u64,
    records: u64,
    /// The first write error; nothing is written after it.
    failed: Option<io::Error>,
}

impl<W: Write> TlogWriter<W> {
    /// A log written to `out`, which should be buffered.
    pub(crate) fn new(out: W) -> Self {
        TlogWriter {
            out,
            latest_us: 0,
            last_flush_us: 0,
            records: 0,
            failed: None,
        }
    }

    /// Writes one record: `frame` (one whole frame's bytes) at `us`
    /// microseconds since the Unix epoch, on `link` (0 to 3).
    pub(crate) fn record(&mut self, us: u64, link: u8, frame: &[u8]) {
        if self.failed.is_some() {
            return;
        }
        let us = (us & !LINK_BITS).max(self.latest_us);
        self.latest_us = us;
        let stamp = us | (u64::from(link) & LINK_BITS);
        let mut written = self
            .out
            .write_all(&stamp.to_be_bytes())
            .and_then(|()| self.out.write_all(frame));
        if written.is_ok() && us.saturating_sub(self.last_flush_us) >= FLUSH_EVERY_US {
            self.last_flush_us = us;
            written = self.out.flush();
        }
        match written {
            Ok(()) => self.records += 1,
            Err(e) => self.failed = Some(e),
        }
    }

    #[cfg(test)]
    /// Records written whole so far.
    pub(crate) fn records(&self) -> u64 {
        self.records
    }

    /// Flushes what is buffered; the first error of the whole log if
    /// there was one.
    pub(crate) fn finish(&mut self) -> io::Result<u64> {
        if let Some(e) = self.failed.take() {
            // Reported once; later calls see the same log as failed.
            self.failed = Some(io::Error::new(e.kind(), e.to_string()));
            return Err(e);
        }
        match self.out.flush() {
            Ok(()) => Ok(self.records),
            Err(e) => {
                self.failed = Some(io::Error::new(e.kind(), e.to_string()));
                Err(e)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const T0: u64 = 1_764_500_000_000_000;

    fn records(bytes: &[u8]) -> Vec<(u64, Vec<u8>)> {
        // Test frames are 3 bytes long.
        bytes
            .chunks(11)
            .map(|r| {
                (
                    u64::from_be_bytes(r[..8].try_into().unwrap()),
                    r[8..].to_vec(),
                )
            })
            .collect()
    }

    #[test]
    fn records_are_a_big_endian_stamp_with_link_bits_then_the_frame() {
        let mut w = TlogWriter::new(Vec::new());
        w.record(T0 + 7, 0, b"abc");
        w.record(T0 + 1001, SENT, b"def");
        w.record(T0 + 2002, 2, b"ghi");
        assert_eq!(w.finish().unwrap(), 3);
        assert_eq!(
            records(&w.out),
            vec![
                (T0 + 4, b"abc".to_vec()),
                ((T0 + 1000) | 3, b"def".to_vec()),
                ((T0 + 2000) | 2, b"ghi".to_vec()),
            ]
        );
    }

    #[test]
    fn a_stamp_behind_the_latest_is_written_at_the_latest() {
        let mut w = TlogWriter::new(Vec::new());
        w.record(T0 + 500, SENT, b"req");
        w.record(T0 + 300, 0, b"old");
        w.record(T0 + 900, 0, b"new");
        let stamps: Vec<u64> = records(&w.out).into_iter().map(|r| r.0).collect();
        assert_eq!(stamps, vec![(T0 + 500) | 3, T0 + 500, T0 + 900]);
    }

    /// Takes `room` bytes, then fails as a full disk does.
    struct Full {
        room: usize,
        flushes: usize,
    }

    impl Write for Full {
        fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
            if self.room == 0 {
                return Err(io::Error::from(io::ErrorKind::StorageFull));
            }
            let n = buf.len().min(self.room);
            self.room -= n;
            Ok(n)
        }
        fn flush(&mut self) -> io::Result<()> {
            self.flushes += 1;
            Ok(())
        }
    }

    #[test]
    fn the_first_write_error_stops_the_writing_and_is_told_at_the_end() {
        let mut w = TlogWriter::new(Full {
            room: 25,
            flushes: 0,
        });
        for i in 0..5 {
            w.record(T0 + i, 0, b"abc");
        }
        // Two whole records fit, the third was cut: nothing after it.
        assert_eq!(w.records(), 2);
        let e = w.finish().unwrap_err();
        assert_eq!(e.kind(), io::ErrorKind::StorageFull);
        assert!(w.finish().is_err(), "a failed log stays failed");
    }

    #[test]
    fn a_long_run_reaches_the_file_once_a_second() {
        let mut w = TlogWriter::new(Full {
            room: usize::MAX,
            flushes: 0,
        });
        for ms in 0..3000 {
            w.record(T0 + ms * 1000, 0, b"abc");
        }
        // The first record, then one a second of stamps.
        assert_eq!(w.out.flushes, 3);
    }
}
