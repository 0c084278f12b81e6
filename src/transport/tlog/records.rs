//! A telemetry log's bytes as records: 8 bytes of big-endian microseconds
//! since the Unix epoch, then one MAVLink frame (v1 or v2, maybe signed),
//! checked by the frame scanner. Pure: bytes in, records out, no I/O.
//!
//! Rules:
//! - **Aligned.** Where a record is due (the file's start, or where the
//!   last one ended), a stamp followed by a whole frame the scanner
//!   accepts is a record, whatever its stamp says (the clock deals with
//!   stamps that jump: [`super::stamps`]).
//! - **Unchecked.** A frame nothing can check out is a record only where
//!   the log says it is one: its stamp within 3 days of the last good one,
//!   and the next record place holding a good record stamped near it, or
//!   another unchecked one (checked the same way in its turn), or the log's
//!   end. Two kinds: an id this build does not know (`unknown_id`), and a
//!   known id whose CRC fails with its header whole (`damaged`: the frame
//!   arrived, damaged or in a dialect whose CRC differs, as the 1,949
//!   DISTANCE_SENSOR frames of pymavlink issue 807's log). Both are
//!   delivered with their kind: their headers fill their source's
//!   sequence. (That log has 6 damaged records right after another one,
//!   3 of them 1/194's: "followed by a good record" alone would call them
//!   junk.)
//! - **Junk.** Anything else starts a stretch of junk. The scan moves one
//!   byte at a time until a record that the scanner accepts *and* whose
//!   stamp is within 3 days of the last good stamp (pymavlink's bound,
//!   `mavlogfile.scan_timestamp`). With no good stamp yet (junk at the
//!   start of the file), a record must follow that lines up: a good
//!   frame, its stamp within 3 days. Every byte skipped is counted, and
//!   each stretch once.
//! - **End.** Bytes at the end that cannot make a record: at a record's
//!   place, a last record cut short (a ground station killed while it
//!   wrote); inside junk, more junk.
//!
//! The caller keeps a bounded buffer: [`Splitter::next`] says how many
//! leading bytes it is finished with, and never needs more than two
//! records' worth ([`MAX_RECORD`] each) to decide.

use serde::Serialize;

use crate::frame::scanner::{IFLAG_SIGNED, STX_V1, STX_V2};
use crate::frame::{scan_datagram_all, Kind, ScanStats};

/// The stamp before each frame.
pub(crate) const STAMP_LEN: usize = 8;
#[cfg(test)]
/// The longest record: a stamp and the longest frame.
pub(crate) const MAX_RECORD: usize = STAMP_LEN + crate::frame::scanner::MAX_FRAME_LEN;
/// A stamp this far from the last good one cannot be a record's after
/// junk: pymavlink's bound (3 days, in µs).
pub(crate) const PLAUSIBLE_US: u64 = 3 * 24 * 3600 * 1_000_000;
/// MAVLink 2: header, CRC, signature.
const V2_OVERHEAD: usize = 12;
const V1_OVERHEAD: usize = 8;
const SIGNATURE_LEN: usize = 13;

/// What the log held besides its records' frames.
#[derive(Debug, Default, Clone, Copy, PartialEq, Eq, Serialize)]
pub(crate) struct RecordStats {
    /// Records whose frame the scanner accepted (delivered).
    pub(crate) records: u64,
    /// Records whose frame's message id this build does not know: lined
    /// up, delivered with their header only.
    pub(crate) unknown_id: u64,
    /// Records whose frame failed its CRC with its header whole, lined up:
    /// delivered as damaged frames. Never also in `bad_crc`.
    pub(crate) damaged: u64,
    /// Bytes between records that were not a record.
    pub(crate) junk_bytes: u64,
    /// Stretches of junk (each a re-synchronisation).
    pub(crate) junk_stretches: u64,
    /// Candidate frames at a record's place that failed their CRC (or a
    /// MAVLink 1 length) and did not line up, each the start of a stretch
    /// of junk.
    pub(crate) bad_crc: u64,
    /// Bytes of a last record cut short (0: the log ends on a record).
    pub(crate) truncated_bytes: u64,
}

/// The next thing in the bytes.
#[derive(Debug, PartialEq, Eq)]
pub(crate) enum Found<'a> {
    /// A record: its raw stamp, its frame's bytes and what the frame is.
    Record {
        stamp: u64,
        frame: &'a [u8],
        kind: Kind,
    },
    /// More bytes are needed to decide.
    NeedMore,
    /// Nothing more will come and nothing more is there.
    End,
}

/// What a record's place holds.
enum Candidate {
    /// Not enough bytes to tell.
    Need,
    /// A stamp and a frame the scanner accepts, `len` bytes long.
    Good(usize),
    /// A stamp and a whole frame nothing checks: an id the scanner does not
    /// know, or a known one whose CRC fails.
    Unchecked(usize, Kind),
    /// Not a record.
    Bad { bad_crc: bool },
}

/// The frame length a header claims, if it can start a frame.
fn claimed_len(frame: &[u8]) -> Option<usize> {
    match frame[0] {
        STX_V1 => Some(V1_OVERHEAD + usize::from(frame[1])),
        STX_V2 if frame[2] & !IFLAG_SIGNED == 0 => {
            let signature = if frame[2] & IFLAG_SIGNED != 0 {
                SIGNATURE_LEN
            } else {
                0
            };
            Some(V2_OVERHEAD + usize::from(frame[1]) + signature)
        }
        _ => None,
    }
}

/// The big-endian stamp at `buf[at..]`.
fn stamp_at(buf: &[u8], at: usize) -> u64 {
    let mut b = [0u8; STAMP_LEN];
    b.copy_from_slice(&buf[at..at + STAMP_LEN]);
    u64::from_be_bytes(b)
}

/// What the record place at `buf[at]` holds; the scanner's figures for an
/// accepted frame go to `scan`.
fn candidate(buf: &[u8], at: usize, scan: &mut ScanStats) -> Candidate {
    // Three header bytes tell a frame's length (MAVLink 2's flags).
    if buf.len() < at + STAMP_LEN + 3 {
        return Candidate::Need;
    }
    let frame = &buf[at + STAMP_LEN..];
    let Some(len) = claimed_len(frame) else {
        return Candidate::Bad { bad_crc: false };
    };
    if frame.len() < len {
        return Candidate::Need;
    }
    let mut one = ScanStats::default();
    let mut whole = None;
    // Taken whole, the frame is the only thing in its extent.
    scan_datagram_all(&frame[..len], &mut one, &mut |raw, kind| {
        whole = (raw.len() == len).then_some(kind);
    });
    match whole {
        Some(Kind::Good) => {
            scan.add(&one);
            Candidate::Good(len)
        }
        Some(kind) => Candidate::Unchecked(len, kind),
        // A failed CRC is junk when a good frame starts inside the extent.
        None => Candidate::Bad {
            bad_crc: one.bad_crc > 0,
        },
    }
}

/// Whether two stamps are within pymavlink's bound of each other.
fn near(a: u64, b: u64) -> bool {
    a.abs_diff(b) <= PLAUSIBLE_US
}

/// Splits a log into records; see the module's rules.
#[derive(Debug, Default)]
pub(crate) struct Splitter {
    /// The last good record's stamp.
    last_stamp: Option<u64>,
    /// Inside a stretch of junk (the next record must be plausible).
    in_junk: bool,
    /// The scanner's figures over the records' frames.
    scan: ScanStats,
    stats: RecordStats,
}

impl Splitter {
    pub(crate) fn stats(&self) -> RecordStats {
        self.stats
    }

    /// The scanner's figures over the frames delivered, with the junk as
    /// its skipped bytes and a cut last record as truncated.
    pub(crate) fn scan_stats(&self) -> ScanStats {
        ScanStats {
            unknown_id: self.stats.unknown_id,
            bad_crc: self.stats.bad_crc,
            damaged: self.stats.damaged,
            skipped_bytes: self.stats.junk_bytes + self.stats.truncated_bytes,
            truncated: u64::from(self.stats.truncated_bytes > 0),
            ..self.scan
        }
    }

    /// Whether a record place after junk (or holding a frame nothing
    /// checks: `unchecked`), stamped `stamp`, is a record. `None`: more
    /// bytes are needed to tell.
    fn plausible(
        &self,
        stamp: u64,
        unchecked: bool,
        buf: &[u8],
        next: usize,
        at_end: bool,
    ) -> Option<bool> {
        if self.last_stamp.is_some_and(|last| !near(stamp, last)) {
            return Some(false);
        }
        if self.last_stamp.is_some() && !unchecked {
            return Some(true);
        }
        // No good stamp yet, or a frame nothing checks: the next record
        // must line up (a lone frame after junk is more likely a frame the
        // junk holds). The log may end after an unchecked one, and an
        // unchecked one may follow it (its own next decides whether it is
        // a record in its turn).
        match candidate(buf, next, &mut ScanStats::default()) {
            Candidate::Need if at_end => Some(unchecked && next == buf.len()),
            Candidate::Need => None,
            Candidate::Good(_) => Some(near(stamp_at(buf, next), stamp)),
            Candidate::Unchecked(..) if unchecked => Some(near(stamp_at(buf, next), stamp)),
            Candidate::Unchecked(..) | Candidate::Bad { .. } => Some(false),
        }
    }

    /// The next record in `buf`, and how many leading bytes are finished
    /// with (the caller drops them before the next call). `at_end`: no
    /// bytes will follow `buf`.
    pub(crate) fn next<'a>(&mut self, buf: &'a [u8], at_end: bool) -> (Found<'a>, usize) {
        let mut at = 0;
        loop {
            let mut scan = ScanStats::default();
            let (len, kind) = match candidate(buf, at, &mut scan) {
                Candidate::Need if at_end => return (self.end(buf.len() - at), buf.len()),
                Candidate::Need => return (Found::NeedMore, at),
                Candidate::Good(len) => (len, Kind::Good),
                Candidate::Unchecked(len, kind) => (len, kind),
                Candidate::Bad { bad_crc } => {
                    self.count_bad_crc(bad_crc);
                    self.junk_byte();
                    at += 1;
                    continue;
                }
            };
            // A frame that cannot be checked is believed only where it
            // lines up, as a good one after junk.
            let record = (kind == Kind::Good && !self.in_junk) || {
                let stamp = stamp_at(buf, at);
                let next = at + STAMP_LEN + len;
                match self.plausible(stamp, kind != Kind::Good, buf, next, at_end) {
                    None => return (Found::NeedMore, at),
                    Some(record) => record,
                }
            };
            if !record {
                self.count_bad_crc(kind == Kind::Damaged);
                self.junk_byte();
                at += 1;
                continue;
            }
            self.in_junk = false;
            let stamp = stamp_at(buf, at);
            let end = at + STAMP_LEN + len;
            match kind {
                Kind::Unknown => self.stats.unknown_id += 1,
                Kind::Damaged => self.stats.damaged += 1,
                Kind::Good => {
                    // Only a checked frame vouches for its stamp.
                    self.last_stamp = Some(stamp);
                    self.scan.add(&scan);
                    self.stats.records += 1;
                }
            }
            let frame = &buf[at + STAMP_LEN..end];
            return (Found::Record { stamp, frame, kind }, end);
        }
    }

    /// One byte of junk, and a stretch begun if it is the first.
    fn junk_byte(&mut self) {
        if !self.in_junk {
            self.in_junk = true;
            self.stats.junk_stretches += 1;
        }
        self.stats.junk_bytes += 1;
    }

    /// A candidate at a record's place failed its CRC and is junk: counted
    /// once, where its stretch begins.
    fn count_bad_crc(&mut self, bad_crc: bool) {
        if !self.in_junk {
            self.stats.bad_crc += u64::from(bad_crc);
        }
    }

    /// `rest` bytes are left that can make no record.
    fn end(&mut self, rest: usize) -> Found<'static> {
        if rest > 0 {
            if self.in_junk {
                self.stats.junk_bytes += rest as u64;
            } else {
                self.stats.truncated_bytes += rest as u64;
            }
        }
        Found::End
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frame::codec::{encode, Header, Version};
    use crate::frame::Msg;

    const T0: u64 = 1_764_500_000_000_000;

    fn frame(version: Version, seq: u8) -> Vec<u8> {
        let mut out = Vec::new();
        encode(
            &mut out,
            version,
            Header {
                sysid: 1,
                compid: 1,
                seq,
            },
            &Msg::Attitude {
                time_boot_ms: u32::from(seq) * 20,
            },
        );
        out
    }

    fn record(stamp: u64, version: Version, seq: u8) -> Vec<u8> {
        let mut out = stamp.to_be_bytes().to_vec();
        out.extend(frame(version, seq));
        out
    }

    /// Every good record of `data`, fed `chunk` bytes at a time, as
    /// (stamp, packet seq), and the figures.
    fn split(data: &[u8], chunk: usize) -> (Vec<(u64, u8)>, RecordStats) {
        let (records, stats) = split_all(data, chunk);
        let good = records
            .into_iter()
            .filter(|r| r.2 == Kind::Good)
            .map(|r| (r.0, r.1))
            .collect();
        (good, stats)
    }

    /// Every record of `data`, fed `chunk` bytes at a time, as (stamp,
    /// packet seq, kind), and the figures.
    fn split_all(data: &[u8], chunk: usize) -> (Vec<(u64, u8, Kind)>, RecordStats) {
        let mut s = Splitter::default();
        let mut buf = Vec::new();
        let mut fed = 0;
        let mut out = Vec::new();
        loop {
            let at_end = fed == data.len();
            let (found, used) = s.next(&buf, at_end);
            let got = match found {
                Found::Record { stamp, frame, kind } => {
                    Some((stamp, crate::frame::decode_as(frame, kind), kind))
                }
                Found::NeedMore => None,
                Found::End => break,
            };
            buf.drain(..used);
            match got {
                Some((stamp, f, kind)) => out.push((stamp, f.packet_seq, kind)),
                None => {
                    let take = chunk.min(data.len() - fed);
                    buf.extend_from_slice(&data[fed..fed + take]);
                    fed += take;
                }
            }
            assert!(buf.len() <= 2 * MAX_RECORD + chunk);
        }
        (out, s.stats())
    }

    fn log(n: u8) -> Vec<u8> {
        (0..n)
            .flat_map(|i| {
                let v = if i % 3 == 0 { Version::V1 } else { Version::V2 };
                record(T0 + u64::from(i) * 20_000, v, i)
            })
            .collect()
    }

    #[test]
    fn records_come_out_whole_whatever_the_reads() {
        let data = log(50);
        for chunk in [1, 7, 300, 1 << 16] {
            let (records, stats) = split(&data, chunk);
            assert_eq!(records.len(), 50, "chunk {chunk}");
            assert_eq!(records[49], (T0 + 49 * 20_000, 49));
            assert_eq!(
                stats,
                RecordStats {
                    records: 50,
                    ..RecordStats::default()
                }
            );
        }
    }

    /// A record of 1/1's ATTITUDE numbered `seq` whose CRC is broken.
    fn damaged(stamp: u64, version: Version, seq: u8) -> Vec<u8> {
        let mut out = record(stamp, version, seq);
        *out.last_mut().unwrap() ^= 0xFF;
        out
    }

    #[test]
    fn junk_between_records_is_counted_and_skipped() {
        let mut data = log(3);
        // Junk with start bytes in it, then a frame whose CRC is broken and
        // that lines up with nothing: junk too.
        data.extend([0xFD, 0x09, 0x00, 0xFE, 1, 2, 3]);
        let broken = damaged(T0 + 60_000, Version::V2, 3);
        data.extend(&broken);
        data.extend([0x42; 3]);
        data.extend(record(T0 + 80_000, Version::V2, 4));
        for chunk in [1, 5, 4096] {
            let (records, stats) = split_all(&data, chunk);
            let seqs: Vec<u8> = records.iter().map(|r| r.1).collect();
            assert_eq!(seqs, [0, 1, 2, 4], "chunk {chunk}");
            assert_eq!(stats.junk_stretches, 1);
            assert_eq!(stats.junk_bytes as usize, 7 + broken.len() + 3);
            assert_eq!((stats.damaged, stats.bad_crc), (0, 0));
            assert_eq!(stats.truncated_bytes, 0);
        }
    }

    #[test]
    fn damaged_records_between_good_ones_are_delivered_as_damaged() {
        // Good, damaged, good, two damaged in a row, good, then a damaged
        // one lined up with nothing (junk after it), and the log's end.
        let mut data = log(2);
        data.extend(damaged(T0 + 40_000, Version::V2, 2));
        data.extend(record(T0 + 60_000, Version::V1, 3));
        data.extend(damaged(T0 + 80_000, Version::V1, 4));
        data.extend(damaged(T0 + 80_000, Version::V2, 5));
        data.extend(record(T0 + 100_000, Version::V2, 6));
        let lone = damaged(T0 + 120_000, Version::V2, 7);
        data.extend(&lone);
        data.extend([0x42; 5]);
        data.extend(record(T0 + 140_000, Version::V2, 8));
        data.extend(damaged(T0 + 160_000, Version::V2, 9));
        for chunk in [1, 9, 4096] {
            let (records, stats) = split_all(&data, chunk);
            let (good, bad) = (Kind::Good, Kind::Damaged);
            let expected = [
                (0, good),
                (1, good),
                (2, bad),
                (3, good),
                (4, bad),
                (5, bad),
                (6, good),
                (8, good),
                (9, bad),
            ];
            let got: Vec<(u8, Kind)> = records.iter().map(|r| (r.1, r.2)).collect();
            assert_eq!(got, expected, "chunk {chunk}");
            assert_eq!(records[2].0, T0 + 40_000, "at its stamp");
            assert_eq!(
                (stats.records, stats.damaged, stats.bad_crc),
                (5, 4, 1),
                "chunk {chunk}"
            );
            assert_eq!(
                (stats.junk_stretches, stats.junk_bytes as usize),
                (1, lone.len() + 5)
            );
        }
    }

    #[test]
    fn a_damaged_record_far_from_the_last_good_stamp_is_junk() {
        let mut data = log(2);
        let far = damaged(T0 + 4 * 24 * 3600 * 1_000_000, Version::V2, 2);
        data.extend(&far);
        data.extend(record(T0 + 60_000, Version::V2, 3));
        let (records, stats) = split_all(&data, 64);
        let seqs: Vec<u8> = records.iter().map(|r| r.1).collect();
        assert_eq!(seqs, [0, 1, 3]);
        assert_eq!((stats.damaged, stats.bad_crc), (0, 1));
        assert_eq!(stats.junk_bytes as usize, far.len());
    }

    #[test]
    fn a_record_after_junk_needs_a_stamp_near_the_last_good_one() {
        let mut data = log(2);
        data.extend([0x55; 5]);
        // A good frame whose stamp is 4 days off: junk too.
        data.extend(record(T0 + 4 * 24 * 3600 * 1_000_000, Version::V2, 2));
        data.extend(record(T0 + 60_000, Version::V2, 3));
        let (records, stats) = split(&data, 64);
        let seqs: Vec<u8> = records.iter().map(|r| r.1).collect();
        assert_eq!(seqs, [0, 1, 3]);
        assert_eq!(stats.junk_stretches, 1);
    }

    #[test]
    fn an_aligned_record_is_taken_whatever_its_stamp() {
        // A clock step at a record boundary is the clock's business.
        let mut data = log(2);
        data.extend(record(T0 + 9 * 24 * 3600 * 1_000_000, Version::V2, 2));
        let (records, stats) = split(&data, 64);
        assert_eq!(records.len(), 3);
        assert_eq!(stats.junk_bytes, 0);
    }

    #[test]
    fn junk_before_the_first_record_needs_two_records_in_a_row() {
        let mut data = vec![0x00, 0xFE, 0x21, 0x13];
        // A lone good frame with a stamp that is not a time: a frame the
        // junk happens to hold, which the next record does not line up with.
        data.extend(record(42, Version::V1, 9));
        data.extend([0x77; 3]);
        data.extend(log(3));
        let (records, stats) = split(&data, 16);
        let seqs: Vec<u8> = records.iter().map(|r| r.1).collect();
        assert_eq!(seqs, [0, 1, 2]);
        assert_eq!(stats.junk_stretches, 1);
        assert_eq!(
            stats.junk_bytes as usize,
            4 + 8 + frame(Version::V1, 9).len() + 3
        );
    }

    #[test]
    fn a_last_record_cut_short_is_truncated_not_junk() {
        let mut data = log(4);
        let cut = record(T0 + 100_000, Version::V2, 4);
        data.extend(&cut[..cut.len() - 5]);
        let (records, stats) = split(&data, 100);
        assert_eq!(records.len(), 4);
        assert_eq!(stats.truncated_bytes as usize, cut.len() - 5);
        assert_eq!(stats.junk_bytes, 0);
    }

    #[test]
    fn bytes_that_are_not_a_log_give_no_record() {
        // A raw MAVLink stream (no stamps), text, zeros.
        let mut raw = Vec::new();
        for i in 0..20 {
            raw.extend(frame(Version::V2, i));
        }
        let text = b"hello, this is not a telemetry log at all\n".repeat(20);
        for data in [raw, text, vec![0u8; 1000], Vec::new()] {
            let (records, stats) = split(&data, 64);
            assert!(records.is_empty(), "{stats:?}");
            assert_eq!(stats.junk_bytes + stats.truncated_bytes, data.len() as u64);
        }
    }

    #[test]
    fn unknown_ids_at_a_records_place_are_delivered_whole() {
        let mut data = log(2);
        // MAVLink 2, id 0xABCDEF (unknown), 4 payload bytes.
        let mut unknown = (T0 + 40_000).to_be_bytes().to_vec();
        unknown.extend([
            0xFD, 4, 0, 0, 2, 1, 1, 0xEF, 0xCD, 0xAB, 1, 2, 3, 4, 0x12, 0x34,
        ]);
        data.extend(&unknown);
        data.extend(record(T0 + 60_000, Version::V2, 3));
        let (records, stats) = split_all(&data, 64);
        let got: Vec<(u8, Kind)> = records.iter().map(|r| (r.1, r.2)).collect();
        let expected = [
            (0, Kind::Good),
            (1, Kind::Good),
            (2, Kind::Unknown),
            (3, Kind::Good),
        ];
        assert_eq!(got, expected);
        assert_eq!((stats.records, stats.unknown_id), (3, 1));
        assert_eq!(stats.junk_bytes, 0);
    }

    #[test]
    fn junk_that_looks_like_a_stamp_and_a_header_poisons_nothing() {
        // Eight zero bytes (a stamp of 1970), then a MAVLink 2 header
        // claiming 28 bytes: what follows is no frame of a known id, or an
        // unknown id whose next record does not line up.
        let mut data = log(3);
        data.extend([0, 0, 0, 0, 0, 0, 0, 0, 0xFD, 0x1C, 0, 0]);
        for i in 3..6u8 {
            data.extend(record(T0 + u64::from(i) * 20_000, Version::V2, i));
        }
        let (records, stats) = split(&data, 4096);
        let seqs: Vec<u8> = records.iter().map(|r| r.1).collect();
        assert_eq!(seqs, [0, 1, 2, 3, 4, 5]);
        assert_eq!((stats.junk_bytes, stats.unknown_id), (12, 0));
    }

    proptest::proptest! {
        /// Records of both versions with junk (no start bytes) between any
        /// of them, read in chunks of any size: every record comes out, in
        /// order, and every junk byte is counted.
        #[test]
        fn every_record_survives_junk_and_any_reads(
            records in proptest::collection::vec(
                (proptest::bool::ANY, proptest::collection::vec(0u8..0xFD, 0..40)),
                1..60,
            ),
            chunk in 1usize..600,
        ) {
            let mut data = Vec::new();
            let mut junk = 0;
            for (i, (v1, after)) in records.iter().enumerate() {
                let version = if *v1 { Version::V1 } else { Version::V2 };
                data.extend(record(T0 + i as u64 * 20_000, version, i as u8));
                data.extend(after);
                junk += after.len() as u64;
            }
            let (out, stats) = split(&data, chunk);
            let seqs: Vec<u8> = out.iter().map(|r| r.1).collect();
            let expected: Vec<u8> = (0..records.len()).map(|i| i as u8).collect();
            proptest::prop_assert_eq!(seqs, expected);
            proptest::prop_assert_eq!(stats.junk_bytes + stats.truncated_bytes, junk);
        }
    }
}
