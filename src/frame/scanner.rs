//! Finds whole, CRC-valid MAVLink frames in bytes that may hold junk.
//!
//! Two entry points share one scanning rule:
//! - [`scan_datagram`]: a UDP datagram is parsed on its own, so a junk or
//!   truncated datagram can never swallow the next datagram's frame (the
//!   pymavlink failure measured in FIELD-NOTES).
//! - [`StreamScanner`]: serial and TCP carry a byte stream; a frame may be
//!   split across reads, so the unfinished tail is kept for the next read.
//!
//! A candidate that fails (bad CRC, unsupported flags, unknown id that does
//! not line up with a following frame) is rejected and the scan restarts one
//! byte after its start byte, so a real frame that overlaps junk is found.

use mavlink::dialects::ardupilotmega::MavMessage;
use mavlink::Message;

/// MAVLink 1 start-of-frame marker.
pub const STX_V1: u8 = 0xFE;
/// MAVLink 2 start-of-frame marker.
pub const STX_V2: u8 = 0xFD;
/// MAVLink 2 incompatibility flag: the frame carries a 13-byte signature.
pub const IFLAG_SIGNED: u8 = 0x01;
const SIGNATURE_LEN: usize = 13;
const V1_HEADER: usize = 6; // STX, len, seq, sys, comp, msgid
const V2_HEADER: usize = 10; // STX, len, incompat, compat, seq, sys, comp, msgid x3
const CHECKSUM_LEN: usize = 2;
/// The largest possible frame: v2 header, 255 payload bytes, CRC, signature.
pub const MAX_FRAME_LEN: usize = V2_HEADER + 255 + CHECKSUM_LEN + SIGNATURE_LEN;

/// What the scanner saw besides good frames. Every byte that is not part of
/// a good frame or an unknown-but-aligned frame is counted in `skipped_bytes`.
#[derive(Debug, Default, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub struct ScanStats {
    /// Frames with a valid CRC.
    pub frames: u64,
    /// Candidates of a known message whose CRC did not match.
    pub bad_crc: u64,
    /// Well-aligned frames of a message id this build does not know.
    pub unknown_id: u64,
    /// Bytes dropped while resynchronising (junk, broken frames).
    pub skipped_bytes: u64,
    /// Datagrams (or stream ends) that stopped in the middle of a frame.
    pub truncated: u64,
}

impl ScanStats {
    pub fn add(&mut self, other: &ScanStats) {
        self.frames += other.frames;
        self.bad_crc += other.bad_crc;
        self.unknown_id += other.unknown_id;
        self.skipped_bytes += other.skipped_bytes;
        self.truncated += other.truncated;
    }
}

/// CRC_EXTRA for a message id, or `None` when the dialect does not know it.
pub(crate) fn extra_crc(msgid: u32) -> Option<u8> {
    let crc = MavMessage::extra_crc(msgid);
    // The generated table answers 0 for unknown ids; 0 is also a legal value.
    if crc != 0 || MavMessage::default_message_from_id(msgid).is_some() {
        Some(crc)
    } else {
        None
    }
}

/// Length of the frame starting at `buf[0]` once enough of its header is
/// there, `Ok(None)` if more bytes are needed, `Err(())` if the header can
/// never start a frame.
fn frame_len(buf: &[u8]) -> Result<Option<usize>, ()> {
    match buf[0] {
        STX_V1 => Ok(buf
            .get(1)
            .map(|&len| V1_HEADER + usize::from(len) + CHECKSUM_LEN)),
        STX_V2 => {
            if buf.len() < 3 {
                return Ok(None);
            }
            let incompat = buf[2];
            if incompat & !IFLAG_SIGNED != 0 {
                return Err(());
            }
            let signature = if incompat & IFLAG_SIGNED != 0 {
                SIGNATURE_LEN
            } else {
                0
            };
            Ok(Some(
                V2_HEADER + usize::from(buf[1]) + CHECKSUM_LEN + signature,
            ))
        }
        _ => Err(()),
    }
}

fn header_len(stx: u8) -> usize {
    if stx == STX_V1 {
        V1_HEADER
    } else {
        V2_HEADER
    }
}

fn message_id(frame: &[u8]) -> u32 {
    if frame[0] == STX_V1 {
        u32::from(frame[5])
    } else {
        u32::from_le_bytes([frame[7], frame[8], frame[9], 0])
    }
}

fn crc_matches(frame: &[u8], extra: u8) -> bool {
    let end = header_len(frame[0]) + usize::from(frame[1]);
    let expected = u16::from_le_bytes([frame[end], frame[end + 1]]);
    mavlink::calculate_crc(&frame[1..end], extra) == expected
}

enum Step {
    /// A good frame of this length starts here.
    Frame(usize),
    /// An unknown message that lines up with what follows: skip it whole.
    Unknown(usize),
    /// Not a frame: resume one byte later.
    Reject { bad_crc: bool },
    /// The candidate runs past the data we have.
    NeedMore,
}

/// True when `frame` (exactly one frame long) is a known message with a
/// matching CRC.
fn is_good_frame(frame: &[u8]) -> bool {
    extra_crc(message_id(frame)).is_some_and(|extra| crc_matches(frame, extra))
}

/// Whether a good frame starts at each offset of the scanned bytes, worked
/// out at most once per offset (kept across reads of a stream): every
/// candidate looks inside its extent, so without this crafted junk read a
/// byte at a time could cost a CRC per byte per candidate. Allocated only
/// when a start byte is found inside a candidate.
#[derive(Default)]
struct Inner {
    /// Per offset: 0 not known yet (or the frame is not all there yet),
    /// 1 no good frame, otherwise 2 + the good frame's length.
    known: Vec<u16>,
}

impl Inner {
    /// True when a good frame starts at `buf[at]` and ends by `end`.
    fn good_at(&mut self, buf: &[u8], at: usize, end: usize) -> bool {
        if self.known.len() < buf.len() {
            self.known.resize(buf.len(), 0);
        }
        if self.known[at] == 0 {
            self.known[at] = match frame_len(&buf[at..]) {
                Err(()) => 1,
                Ok(Some(len)) if at + len <= buf.len() => {
                    if is_good_frame(&buf[at..at + len]) {
                        2 + len as u16
                    } else {
                        1
                    }
                }
                // Not all there yet: decided when more bytes come.
                Ok(_) => return false,
            };
        }
        self.known[at] >= 2 && at + usize::from(self.known[at] - 2) <= end
    }

    /// The first `done` bytes of the stream buffer were consumed.
    fn consumed(&mut self, done: usize) {
        if self.known.len() > done {
            self.known.drain(..done);
        } else {
            self.known.clear();
        }
    }
}

/// True when a whole good frame lies inside the candidate at `buf[start]`
/// whose claimed extent is `len` bytes (as far as the bytes are there). Such a candidate is junk
/// whose length field lies (or a frame tunnelled in a payload, which loses
/// to the frame inside): rejecting it at once means a real frame behind a
/// false start byte is found without waiting for the bytes the false one
/// claims, which on a quiet serial link could hold it back indefinitely.
/// The answer depends only on bytes within the extent, so a byte stream
/// gives the same frames whatever its read splits. The price, on streams
/// only: a good frame whose payload happens to hold another good frame
/// (about once in ten million) loses to it. A datagram is judged whole
/// first (see `judge`).
fn hides_a_good_frame(buf: &[u8], start: usize, len: usize, inner: &mut Inner) -> bool {
    let end = (start + len).min(buf.len());
    let mut i = start + 1;
    while let Some(offset) = buf[i..end].iter().position(|&b| b == STX_V1 || b == STX_V2) {
        let at = i + offset;
        if inner.good_at(buf, at, end) {
            return true;
        }
        i = at + 1;
    }
    false
}

/// Judges the candidate at `whole[start]` (a start byte). `at_end` says
/// no more bytes will follow `whole` (end of a datagram).
fn judge(whole: &[u8], start: usize, at_end: bool, inner: &mut Inner) -> Step {
    let buf = &whole[start..];
    let len = match frame_len(buf) {
        Err(()) => return Step::Reject { bad_crc: false },
        Ok(None) => return Step::NeedMore,
        Ok(Some(len)) => len,
    };
    // A datagram holds every byte, so nothing waits on a false start: a
    // whole frame that checks out is taken, whatever its payload holds, as
    // every MAVLink parser reads a datagram. (A payload's bytes pass as a
    // frame of their own about once in ten million frames: a PING request
    // whose time_usec and seq held a good MAVLink 1 frame was lost to it in
    // a simulated soak.) A stream still lets the frame inside win; see
    // `hides_a_good_frame`.
    if at_end && buf.len() >= len && is_good_frame(&buf[..len]) {
        return Step::Frame(len);
    }
    if hides_a_good_frame(whole, start, len, inner) {
        return Step::Reject { bad_crc: false };
    }
    if buf.len() < len {
        return Step::NeedMore;
    }
    let frame = &buf[..len];
    match extra_crc(message_id(frame)) {
        Some(extra) if crc_matches(frame, extra) => Step::Frame(len),
        Some(_) => Step::Reject { bad_crc: true },
        // An id we cannot check: believe its length only when the frame ends
        // exactly where the data ends or another start byte follows.
        None => match buf.get(len) {
            Some(&next) if next == STX_V1 || next == STX_V2 => Step::Unknown(len),
            Some(_) => Step::Reject { bad_crc: false },
            None if at_end => Step::Unknown(len),
            None => Step::NeedMore,
        },
    }
}

/// Scans `buf`, calling `on_frame` with each good frame. Returns how many
/// leading bytes are finished with; with `at_end` that is all of them.
fn scan(
    buf: &[u8],
    at_end: bool,
    stats: &mut ScanStats,
    inner: &mut Inner,
    on_frame: &mut dyn FnMut(&[u8]),
) -> usize {
    let mut pos = 0;
    loop {
        let Some(offset) = buf[pos..].iter().position(|&b| b == STX_V1 || b == STX_V2) else {
            stats.skipped_bytes += (buf.len() - pos) as u64;
            return buf.len();
        };
        stats.skipped_bytes += offset as u64;
        pos += offset;
        match judge(buf, pos, at_end, inner) {
            Step::Frame(len) => {
                stats.frames += 1;
                on_frame(&buf[pos..pos + len]);
                pos += len;
            }
            Step::Unknown(len) => {
                stats.unknown_id += 1;
                pos += len;
            }
            Step::Reject { bad_crc } => {
                stats.bad_crc += u64::from(bad_crc);
                stats.skipped_bytes += 1;
                pos += 1;
            }
            Step::NeedMore if at_end => {
                // Nothing more will come; the rest may still hide a frame
                // behind a false start byte, so reject this start only.
                let rest = &buf[pos + 1..];
                if !rest.iter().any(|&b| b == STX_V1 || b == STX_V2) {
                    stats.truncated += 1;
                    stats.skipped_bytes += (buf.len() - pos) as u64;
                    return buf.len();
                }
                stats.skipped_bytes += 1;
                pos += 1;
            }
            Step::NeedMore => return pos,
        }
    }
}

/// Scans one datagram on its own.
pub fn scan_datagram(datagram: &[u8], stats: &mut ScanStats, on_frame: &mut dyn FnMut(&[u8])) {
    scan(datagram, true, stats, &mut Inner::default(), on_frame);
}

/// Scanner for a byte stream: keeps an unfinished frame between reads.
/// Its buffer never grows past a few frames, whatever the input.
pub struct StreamScanner {
    buf: Vec<u8>,
    inner: Inner,
    pub stats: ScanStats,
}

impl Default for StreamScanner {
    fn default() -> Self {
        Self::new()
    }
}

impl StreamScanner {
    pub fn new() -> Self {
        StreamScanner {
            buf: Vec::with_capacity(4 * MAX_FRAME_LEN),
            inner: Inner::default(),
            stats: ScanStats::default(),
        }
    }

    /// Feeds bytes read from the stream.
    pub fn push(&mut self, data: &[u8], on_frame: &mut dyn FnMut(&[u8])) {
        if self.buf.is_empty() {
            // Fast path: no carried tail, scan the read in place.
            let done = scan(data, false, &mut self.stats, &mut self.inner, on_frame);
            self.inner.consumed(done);
            self.buf.extend_from_slice(&data[done..]);
        } else {
            self.buf.extend_from_slice(data);
            let done = scan(&self.buf, false, &mut self.stats, &mut self.inner, on_frame);
            self.inner.consumed(done);
            self.buf.drain(..done);
        }
        // The tail is one unfinished candidate, so it is at most one frame
        // (exactly one whole frame when an unknown id waits for the next
        // byte to show it lines up; found by the fuzzer).
        debug_assert!(self.buf.len() <= MAX_FRAME_LEN);
    }

    /// Bytes held back waiting for the rest of a frame.
    pub fn pending_bytes(&self) -> usize {
        self.buf.len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frame::codec::{encode, Header, Version};
    use crate::frame::Msg;

    fn ping_frame(version: Version, seq: u32) -> Vec<u8> {
        let mut out = Vec::new();
        encode(
            &mut out,
            version,
            Header {
                sysid: 1,
                compid: 1,
                seq: 7,
            },
            &Msg::Ping {
                time_usec: 123_456,
                seq,
                target_system: 255,
                target_component: 190,
            },
        );
        out
    }

    fn collect_datagram(data: &[u8]) -> (Vec<Vec<u8>>, ScanStats) {
        let mut stats = ScanStats::default();
        let mut frames = Vec::new();
        scan_datagram(data, &mut stats, &mut |f| frames.push(f.to_vec()));
        (frames, stats)
    }

    #[test]
    fn finds_v1_and_v2_frames_back_to_back() {
        let mut data = ping_frame(Version::V1, 1);
        data.extend(ping_frame(Version::V2, 2));
        let (frames, stats) = collect_datagram(&data);
        assert_eq!(frames.len(), 2);
        assert_eq!(stats.frames, 2);
        assert_eq!(stats.skipped_bytes, 0);
    }

    #[test]
    fn junk_before_a_frame_is_counted_and_skipped() {
        let mut data = vec![0x00, 0x11, 0x22];
        data.extend(ping_frame(Version::V2, 1));
        let (frames, stats) = collect_datagram(&data);
        assert_eq!(frames.len(), 1);
        assert_eq!(stats.skipped_bytes, 3);
    }

    #[test]
    fn false_start_byte_overlapping_a_real_frame_does_not_hide_it() {
        // A v1 start byte claiming a long payload swallows the real frame
        // unless the scan restarts one byte after the false start.
        let mut data = vec![STX_V1, 40, 0, 0, 0, 4];
        data.extend(ping_frame(Version::V2, 9));
        data.extend([0u8; 40]);
        let (frames, stats) = collect_datagram(&data);
        assert_eq!(frames.len(), 1, "{stats:?}");
        // Rejected for the good frame inside it, before any CRC check.
        assert_eq!((stats.bad_crc, stats.skipped_bytes), (0, 6 + 40));
    }

    #[test]
    fn lying_length_on_a_stream_does_not_hold_back_the_frame_behind_it() {
        // A false v1 start claiming 255 bytes, then one real frame, then
        // silence: the frame is delivered now, not when 263 bytes arrived.
        let mut data = vec![STX_V1, 255, 0, 1, 1, 4];
        data.extend(ping_frame(Version::V2, 9));
        let mut scanner = StreamScanner::new();
        let mut count = 0;
        scanner.push(&data, &mut |_| count += 1);
        assert_eq!(count, 1);
        assert_eq!(scanner.stats.skipped_bytes, 6);
        assert_eq!(scanner.pending_bytes(), 0);
    }

    /// From the simulated week's soak: request 8,569,819 (PING seq
    /// 3,569,819, time_usec 8,569,819,000, packet seq 85) holds, from its
    /// 14th byte, a MAVLink 1 frame of id 155 whose CRC checks out.
    const PING_HOLDING_A_V1_FRAME: &str = "fd0b000055fabe040000780fcdfe010000009b783607ae";

    #[test]
    fn a_datagram_keeps_a_good_frame_whose_payload_holds_another() {
        let bytes: Vec<u8> = (0..PING_HOLDING_A_V1_FRAME.len())
            .step_by(2)
            .map(|i| u8::from_str_radix(&PING_HOLDING_A_V1_FRAME[i..i + 2], 16).unwrap())
            .collect();
        let inner = &bytes[13..22];
        assert!(is_good_frame(inner), "the payload holds a good frame");
        let (frames, stats) = collect_datagram(&bytes);
        assert_eq!(frames, vec![bytes.clone()]);
        assert_eq!((stats.frames, stats.skipped_bytes), (1, 0));
        match crate::frame::decode(&frames[0]).msg {
            crate::frame::Msg::Ping { seq, time_usec, .. } => {
                assert_eq!((seq, time_usec), (3_569_819, 8_569_819_000))
            }
            other => panic!("{other:?}"),
        }
        // On a stream the frame inside wins (it cannot wait for the whole
        // outer frame without holding back real frames behind junk).
        let mut scanner = StreamScanner::new();
        let mut found = Vec::new();
        scanner.push(&bytes, &mut |f| found.push(f.to_vec()));
        assert_eq!(found, vec![inner.to_vec()]);
    }

    #[test]
    fn bad_crc_is_counted_not_fatal() {
        let mut bad = ping_frame(Version::V2, 1);
        let last = bad.len() - 1;
        bad[last] ^= 0xFF;
        bad.extend(ping_frame(Version::V2, 2));
        let (frames, stats) = collect_datagram(&bad);
        assert_eq!(frames.len(), 1);
        assert_eq!(stats.bad_crc, 1);
    }

    #[test]
    fn truncated_datagram_is_counted() {
        let frame = ping_frame(Version::V2, 1);
        let (frames, stats) = collect_datagram(&frame[..frame.len() - 3]);
        assert!(frames.is_empty());
        assert_eq!(stats.truncated, 1);
        assert_eq!(stats.skipped_bytes as usize, frame.len() - 3);
    }

    #[test]
    fn unknown_message_id_aligned_with_next_frame_is_skipped_whole() {
        let mut unknown = vec![STX_V2, 2, 0, 0, 0, 1, 1, 0xEE, 0xEE, 0xEE, 0xAA, 0xBB, 0, 0];
        unknown.extend(ping_frame(Version::V2, 3));
        let (frames, stats) = collect_datagram(&unknown);
        assert_eq!(frames.len(), 1);
        assert_eq!(stats.unknown_id, 1);
        assert_eq!(stats.skipped_bytes, 0);
    }

    #[test]
    fn stream_reassembles_frames_split_at_every_byte() {
        let mut data = ping_frame(Version::V2, 1);
        data.extend([0x42, STX_V2, 0x01]);
        data.extend(ping_frame(Version::V1, 2));
        data.extend(ping_frame(Version::V2, 3));
        for chunk in 1..data.len() {
            let mut scanner = StreamScanner::new();
            let mut count = 0;
            for piece in data.chunks(chunk) {
                scanner.push(piece, &mut |_| count += 1);
            }
            assert_eq!(count, 3, "chunk size {chunk}");
            assert_eq!(scanner.stats.skipped_bytes, 3, "chunk size {chunk}");
        }
    }
}
