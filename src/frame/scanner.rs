//! Finds whole, CRC-valid MAVLink frames in bytes that may hold junk.
//!
//! Two entry points share one scanning rule:
//! - [`scan_datagram`]: a UDP datagram is parsed on its own, so a junk or
//!   truncated datagram can never swallow the next datagram's frame (the
//!   pymavlink failure measured in FIELD-NOTES).
//! - [`StreamScanner`]: serial and TCP carry a byte stream; a frame may be
//!   split across reads, so the unfinished tail is kept for the next read.
//!
//! A candidate that fails (bad CRC, a MAVLink 1 length its message never
//! has, unsupported flags, an unknown id that does not line up with a
//! following frame or has a good frame starting inside it) is rejected and
//! the scan restarts one byte after its start byte, so a real frame that
//! overlaps junk is found. The rule this gives: every whole good frame that
//! overlaps no other good frame is delivered (on a stream, by the read that
//! brings its last byte).
//!
//! Two kinds of candidate are not junk although nothing checks them out,
//! because the bytes around them say they are whole frames: an id the
//! dialect does not know ([`Kind::Unknown`]), and a known id whose CRC (or
//! MAVLink 1 length) fails ([`Kind::Damaged`]: damaged on the way, or sent
//! in a dialect whose CRC differs, as pymavlink issue 807's DISTANCE_SENSOR).
//! Either is taken whole, never byte by byte, only when no good frame starts
//! inside it and it lines up: an unknown id with the data's end or a
//! start byte; a damaged frame with the end of a datagram or with a good
//! frame right after it. Their headers (source, sequence number, id) are
//! what the link's sequence figures need: they arrived, so their numbers
//! are not lost. [`scan_datagram`] and [`StreamScanner::push`] hand over
//! good frames only; the `_all` forms hand over all three kinds.

use std::sync::OnceLock;

use mavlink::dialects::ardupilotmega::MavMessage;
use mavlink::{MavlinkVersion, Message};

/// MAVLink 1 start-of-frame marker.
pub(crate) const STX_V1: u8 = 0xFE;
/// MAVLink 2 start-of-frame marker.
pub(crate) const STX_V2: u8 = 0xFD;
/// MAVLink 2 incompatibility flag: the frame carries a 13-byte signature.
pub(crate) const IFLAG_SIGNED: u8 = 0x01;
const SIGNATURE_LEN: usize = 13;
const V1_HEADER: usize = 6; // STX, len, seq, sys, comp, msgid
const V2_HEADER: usize = 10; // STX, len, incompat, compat, seq, sys, comp, msgid x3
const CHECKSUM_LEN: usize = 2;
/// The largest possible frame: v2 header, 255 payload bytes, CRC, signature.
pub const MAX_FRAME_LEN: usize = V2_HEADER + 255 + CHECKSUM_LEN + SIGNATURE_LEN;
/// The most a [`StreamScanner`] keeps between reads. The tail is one
/// unfinished candidate (at most one frame; exactly one whole frame when an
/// unknown id waits for the next byte to show it lines up, found by the
/// fuzzer), or a whole candidate waiting for the next one to be whole: a
/// lined-up unknown id waiting for a candidate that starts inside it (at
/// most 279 + 278 bytes), or a damaged frame waiting for the frame after
/// it to prove good: a whole frame and all but the last byte of the
/// next, at most 280 + 279.
pub const MAX_PENDING: usize = 2 * MAX_FRAME_LEN - 1;

/// What a candidate the scanner hands over is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    /// A known message, its CRC checked.
    Good,
    /// A known message whose CRC (or MAVLink 1 length) fails, lined up
    /// with what follows: a whole frame that arrived damaged (or in a
    /// dialect whose CRC differs). Only its header can be believed.
    Damaged,
    /// A message id the dialect does not know, lined up with what follows:
    /// nothing to check it against, its header believed.
    Unknown,
}

/// What the scanner saw besides good frames. Every byte that is not part of
/// a good, a damaged or an unknown-but-aligned frame is counted in
/// `skipped_bytes`.
#[derive(Debug, Default, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub struct ScanStats {
    /// Frames with a valid CRC.
    pub frames: u64,
    /// Candidates of a known message whose CRC did not match (or, in
    /// MAVLink 1, whose length is not that message's) and that nothing
    /// showed to be a whole frame: junk, skipped byte by byte. Never also
    /// in `damaged`.
    pub bad_crc: u64,
    /// Whole frames of a known message whose CRC did not match, lined up
    /// with what follows ([`Kind::Damaged`]): skipped whole, their headers
    /// delivered. Never also in `bad_crc`.
    pub damaged: u64,
    /// Well-aligned frames of a message id this build does not know.
    pub unknown_id: u64,
    /// Bytes dropped while resynchronising (junk, broken frames), not
    /// those of damaged or unknown-id frames.
    pub skipped_bytes: u64,
    /// Datagrams (or stream ends) that stopped in the middle of a frame.
    pub truncated: u64,
    /// Bytes of the frames with a valid CRC: what the link delivered, for
    /// throughput figures (a sweep's bytes/s per step).
    #[serde(skip)]
    pub(crate) frame_bytes: u64,
}

impl ScanStats {
    pub(crate) fn add(&mut self, other: &ScanStats) {
        self.frames += other.frames;
        self.bad_crc += other.bad_crc;
        self.damaged += other.damaged;
        self.unknown_id += other.unknown_id;
        self.skipped_bytes += other.skipped_bytes;
        self.truncated += other.truncated;
        self.frame_bytes += other.frame_bytes;
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

/// The header's length of a frame starting with `stx`.
pub(crate) fn header_len(stx: u8) -> usize {
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

/// MAVLink's checksum (CRC-16/MCRF4XX), sixteen bytes a step: the
/// `mavlink` crate's goes a byte at a time, and was a fifth of reading a
/// telemetry log.
static X25: crc::Crc<u16, crc::Table<16>> =
    crc::Crc::<u16, crc::Table<16>>::new(&crc::CRC_16_MCRF4XX);

fn crc_matches(frame: &[u8], extra: u8) -> bool {
    let end = header_len(frame[0]) + usize::from(frame[1]);
    let expected = u16::from_le_bytes([frame[end], frame[end + 1]]);
    let mut digest = X25.digest();
    digest.update(&frame[1..end]);
    digest.update(&[extra]);
    digest.finalize() == expected
}

enum Step {
    /// A good frame of this length starts here.
    Frame(usize),
    /// An unknown message that lines up with what follows: skip it whole.
    Unknown(usize),
    /// A damaged frame that lines up with what follows: skip it whole.
    Damaged(usize),
    /// Not a frame: resume one byte later.
    Reject { bad_crc: bool },
    /// The candidate runs past the data we have.
    NeedMore,
}

/// The MAVLink 1 payload length of a message id the dialect knows. A
/// MAVLink 1 frame carries exactly the message's base fields (the ones
/// CRC_EXTRA covers), so any other length is junk; checking it makes a
/// chance CRC match in junk (1 in 65,536 for each false start byte with a
/// known id) 256 times rarer. Junk whose extent takes in the first bytes of
/// a real frame and passes the CRC by chance costs that frame (issue 21).
fn v1_payload_len(msgid: u8) -> Option<u8> {
    static LENGTHS: OnceLock<[Option<u8>; 256]> = OnceLock::new();
    LENGTHS.get_or_init(|| {
        let mut payload = [0u8; 255];
        std::array::from_fn(|id| {
            let msg = MavMessage::default_message_from_id(id as u32)?;
            u8::try_from(msg.ser(MavlinkVersion::V1, &mut payload)).ok()
        })
    })[usize::from(msgid)]
}

/// What a whole candidate is.
enum Check {
    /// A known message, right length, matching CRC.
    Good,
    /// A known message that fails its CRC or its MAVLink 1 length.
    Bad,
    /// An id the dialect does not know: nothing to check it against.
    Unknown,
}

/// Checks `frame` (exactly one claimed frame long).
fn check(frame: &[u8]) -> Check {
    let Some(extra) = extra_crc(message_id(frame)) else {
        return Check::Unknown;
    };
    let length_ok = frame[0] != STX_V1 || v1_payload_len(frame[5]) == Some(frame[1]);
    if length_ok && crc_matches(frame, extra) {
        Check::Good
    } else {
        Check::Bad
    }
}

/// A memo of good frames: whether one starts at each offset of the scanned
/// bytes, worked out at most once per offset (kept across reads of a
/// stream): every candidate looks inside its extent, so without this
/// crafted junk read a byte at a time could cost a CRC per byte per
/// candidate. Allocated only when a start byte is found inside a candidate.
#[derive(Default)]
struct FrameMemo {
    /// Per offset: 0 not known yet (or the frame is not all there yet),
    /// 1 no good frame, otherwise 2 + the good frame's length.
    known: Vec<u16>,
}

/// What starts at an offset, as far as the bytes there tell.
enum At {
    /// A whole good frame of this length.
    Good(usize),
    /// Never a good frame, whatever follows.
    NotGood,
    /// A candidate whose bytes are not all there yet.
    NotYet,
}

impl FrameMemo {
    fn frame_at(&mut self, buf: &[u8], at: usize) -> At {
        if self.known.len() < buf.len() {
            self.known.resize(buf.len(), 0);
        }
        if self.known[at] == 0 {
            self.known[at] = match frame_len(&buf[at..]) {
                Err(()) => 1,
                Ok(Some(len)) if at + len <= buf.len() => {
                    if matches!(check(&buf[at..at + len]), Check::Good) {
                        2 + len as u16
                    } else {
                        1
                    }
                }
                // Not all there yet: decided when more bytes come.
                Ok(_) => return At::NotYet,
            };
        }
        match self.known[at] {
            1 => At::NotGood,
            k => At::Good(usize::from(k - 2)),
        }
    }

    /// True when a good frame starts at `buf[at]` and ends by `end`.
    fn good_at(&mut self, buf: &[u8], at: usize, end: usize) -> bool {
        matches!(self.frame_at(buf, at), At::Good(len) if at + len <= end)
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

/// Offsets of the start bytes in `buf[from..to]`.
fn start_bytes(buf: &[u8], from: usize, to: usize) -> impl Iterator<Item = usize> + '_ {
    buf[from..to]
        .iter()
        .enumerate()
        .filter(|&(_, &b)| b == STX_V1 || b == STX_V2)
        .map(move |(i, _)| from + i)
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
fn hides_a_good_frame(buf: &[u8], start: usize, len: usize, memo: &mut FrameMemo) -> bool {
    let end = (start + len).min(buf.len());
    start_bytes(buf, start + 1, end).any(|at| memo.good_at(buf, at, end))
}

/// Whether a good frame starts inside the whole candidate of `len` bytes at
/// `buf[start]`, even one that runs on past its end: `Some(true)` yes,
/// `Some(false)` no, `None` not known until more bytes come. An unknown id
/// cannot be checked, so its extent is believed only when no checked frame
/// starts inside it: junk whose claimed extent ends inside a real frame,
/// where that frame happens to hold a start byte, otherwise "lines up" and
/// swallows the frame's first bytes (issue 21). A start byte inside whose
/// frame is not all there yet is decided by the bytes that complete it, or
/// at once when its extent already holds a whole good frame (it can never
/// be delivered then), so a good frame that follows is never held back.
fn good_frame_starts_inside(
    buf: &[u8],
    start: usize,
    len: usize,
    at_end: bool,
    memo: &mut FrameMemo,
) -> Option<bool> {
    let mut undecided = false;
    for at in start_bytes(buf, start + 1, start + len) {
        match memo.frame_at(buf, at) {
            At::Good(_) => return Some(true),
            At::NotGood => {}
            At::NotYet if at_end => {}
            At::NotYet => {
                undecided |= match frame_len(&buf[at..]) {
                    Ok(Some(claimed)) => !hides_a_good_frame(buf, at, claimed, memo),
                    _ => true,
                };
            }
        }
    }
    (!undecided).then_some(false)
}

/// Judges the candidate at `whole[start]` (a start byte). `at_end` says
/// no more bytes will follow `whole` (end of a datagram).
fn judge(whole: &[u8], start: usize, at_end: bool, memo: &mut FrameMemo) -> Step {
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
    if at_end && buf.len() >= len && matches!(check(&buf[..len]), Check::Good) {
        return Step::Frame(len);
    }
    if hides_a_good_frame(whole, start, len, memo) {
        return Step::Reject { bad_crc: false };
    }
    if buf.len() < len {
        return Step::NeedMore;
    }
    let frame = &buf[..len];
    match check(frame) {
        Check::Good => Step::Frame(len),
        Check::Bad => damaged_or_junk(whole, start, len, at_end, memo),
        // An id we cannot check: believe its length only when the frame
        // ends exactly where the data ends or another start byte follows,
        // and no checked frame starts inside it.
        Check::Unknown => match buf.get(len) {
            Some(&next) if next != STX_V1 && next != STX_V2 => Step::Reject { bad_crc: false },
            None if !at_end => Step::NeedMore,
            _ => match good_frame_starts_inside(whole, start, len, at_end, memo) {
                Some(false) => Step::Unknown(len),
                Some(true) => Step::Reject { bad_crc: false },
                None => Step::NeedMore,
            },
        },
    }
}

/// Whether a whole good frame starts at `buf[at]`: `None` while its bytes
/// are not all there (and its claimed extent holds no good frame, which
/// would rule it out at once).
fn good_frame_at(buf: &[u8], at: usize, at_end: bool, memo: &mut FrameMemo) -> Option<bool> {
    match memo.frame_at(buf, at) {
        At::Good(_) => Some(true),
        At::NotGood => Some(false),
        At::NotYet if at_end => Some(false),
        At::NotYet => match frame_len(&buf[at..]) {
            Ok(Some(claimed)) if hides_a_good_frame(buf, at, claimed, memo) => Some(false),
            _ => None,
        },
    }
}

/// Judges the whole candidate of `len` bytes at `whole[start]` whose check
/// failed. Its header is believed (a damaged frame) only on the evidence
/// that it is a whole frame: it ends where a datagram ends or where a good
/// frame starts, and no good frame starts inside it. Anything else is junk
/// (a false start byte whose claimed extent happens to end on a frame is
/// still junk when a good frame starts inside it). On a stream the frame
/// after it must be whole to tell, as for an unknown id.
fn damaged_or_junk(
    whole: &[u8],
    start: usize,
    len: usize,
    at_end: bool,
    memo: &mut FrameMemo,
) -> Step {
    // A good frame inside decides at once, before any wait for what
    // follows (which would hold that frame back).
    let inside = good_frame_starts_inside(whole, start, len, at_end, memo);
    if inside == Some(true) {
        return Step::Reject { bad_crc: true };
    }
    let next = start + len;
    let lined_up = if next == whole.len() {
        at_end.then_some(true)
    } else {
        good_frame_at(whole, next, at_end, memo)
    };
    match (lined_up, inside) {
        (Some(false), _) => Step::Reject { bad_crc: true },
        (Some(true), Some(false)) => Step::Damaged(len),
        _ => Step::NeedMore,
    }
}

/// Scans `buf`, calling `on_frame` with each good, damaged or unknown-id
/// frame. Returns how many leading bytes are finished with; with `at_end`
/// that is all of them.
fn scan(
    buf: &[u8],
    at_end: bool,
    stats: &mut ScanStats,
    memo: &mut FrameMemo,
    on_frame: &mut dyn FnMut(&[u8], Kind),
) -> usize {
    let mut pos = 0;
    loop {
        let Some(offset) = buf[pos..].iter().position(|&b| b == STX_V1 || b == STX_V2) else {
            stats.skipped_bytes += (buf.len() - pos) as u64;
            return buf.len();
        };
        stats.skipped_bytes += offset as u64;
        pos += offset;
        match judge(buf, pos, at_end, memo) {
            Step::Frame(len) => {
                stats.frames += 1;
                stats.frame_bytes += len as u64;
                on_frame(&buf[pos..pos + len], Kind::Good);
                pos += len;
            }
            Step::Unknown(len) => {
                stats.unknown_id += 1;
                on_frame(&buf[pos..pos + len], Kind::Unknown);
                pos += len;
            }
            Step::Damaged(len) => {
                stats.damaged += 1;
                on_frame(&buf[pos..pos + len], Kind::Damaged);
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

/// Scans one datagram on its own; `on_frame` gets the good frames.
pub fn scan_datagram(datagram: &[u8], stats: &mut ScanStats, on_frame: &mut dyn FnMut(&[u8])) {
    scan_datagram_all(datagram, stats, &mut good_only(on_frame));
}

/// Scans one datagram on its own; `on_frame` gets every frame, each with
/// its kind.
pub fn scan_datagram_all(
    datagram: &[u8],
    stats: &mut ScanStats,
    on_frame: &mut dyn FnMut(&[u8], Kind),
) {
    scan(datagram, true, stats, &mut FrameMemo::default(), on_frame);
}

/// A callback for every kind that passes on the good frames only.
fn good_only(on_frame: &mut dyn FnMut(&[u8])) -> impl FnMut(&[u8], Kind) + '_ {
    move |raw, kind| {
        if kind == Kind::Good {
            on_frame(raw);
        }
    }
}

/// Scanner for a byte stream: keeps an unfinished frame between reads.
/// Its buffer never holds more than [`MAX_PENDING`] bytes, whatever the input.
pub struct StreamScanner {
    buf: Vec<u8>,
    memo: FrameMemo,
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
            memo: FrameMemo::default(),
            stats: ScanStats::default(),
        }
    }

    /// Feeds bytes read from the stream; `on_frame` gets the good frames.
    pub fn push(&mut self, data: &[u8], on_frame: &mut dyn FnMut(&[u8])) {
        self.push_all(data, &mut good_only(on_frame));
    }

    /// Feeds bytes read from the stream; `on_frame` gets every frame, each
    /// with its kind.
    pub fn push_all(&mut self, data: &[u8], on_frame: &mut dyn FnMut(&[u8], Kind)) {
        if self.buf.is_empty() {
            // Fast path: no carried tail, scan the read in place.
            let done = scan(data, false, &mut self.stats, &mut self.memo, on_frame);
            self.memo.consumed(done);
            self.buf.extend_from_slice(&data[done..]);
        } else {
            self.buf.extend_from_slice(data);
            let done = scan(&self.buf, false, &mut self.stats, &mut self.memo, on_frame);
            self.memo.consumed(done);
            self.buf.drain(..done);
        }
        debug_assert!(self.buf.len() <= MAX_PENDING);
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
        ping_at(version, seq, 123_456)
    }

    fn ping_at(version: Version, seq: u32, time_usec: u64) -> Vec<u8> {
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
                time_usec,
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
        assert_eq!(stats.frame_bytes, data.len() as u64);
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

    /// A good MAVLink 2 frame (TUNNEL) whose payload carries a whole good
    /// MAVLink 1 PING frame. Found by the simulated week's soak: PING
    /// request 8,569,819 (time_usec 8,569,819,000, seq 3,569,819) held,
    /// from its 14th byte, a MAVLink 1 frame of id 155 whose CRC checked
    /// out and was lost to it. (Since the MAVLink 1 length check, that
    /// particular frame no longer passes; a tunnelled frame still does.)
    fn frame_in_a_tunnel() -> (Vec<u8>, Vec<u8>) {
        use mavlink::dialects::ardupilotmega::TUNNEL_DATA;
        let inner = ping_frame(Version::V1, 7);
        let mut payload = [0u8; 128];
        payload[..inner.len()].copy_from_slice(&inner);
        let tunnel = MavMessage::TUNNEL(TUNNEL_DATA {
            payload_length: inner.len() as u8,
            payload,
            ..TUNNEL_DATA::DEFAULT
        });
        let mut raw = mavlink::MAVLinkV2MessageRaw::new();
        let header = mavlink::MavHeader {
            system_id: 1,
            component_id: 1,
            sequence: 85,
        };
        raw.serialize_message(header, &tunnel);
        (raw.raw_bytes().to_vec(), inner)
    }

    #[test]
    fn a_datagram_keeps_a_good_frame_whose_payload_holds_another() {
        let (bytes, inner) = frame_in_a_tunnel();
        assert!(matches!(check(&inner), Check::Good));
        let (frames, stats) = collect_datagram(&bytes);
        assert_eq!(frames, vec![bytes.clone()]);
        assert_eq!((stats.frames, stats.skipped_bytes), (1, 0));
        // On a stream the frame inside wins (it cannot wait for the whole
        // outer frame without holding back real frames behind junk).
        let mut scanner = StreamScanner::new();
        let mut found = Vec::new();
        scanner.push(&bytes, &mut |f| found.push(f.to_vec()));
        assert_eq!(found, vec![inner]);
    }

    #[test]
    fn bad_crc_is_counted_not_fatal() {
        let mut bad = ping_frame(Version::V2, 1);
        let last = bad.len() - 1;
        bad[last] ^= 0xFF;
        bad.extend([0x42, 0x43]);
        bad.extend(ping_frame(Version::V2, 2));
        let (frames, stats) = collect_datagram(&bad);
        assert_eq!(frames.len(), 1);
        assert_eq!((stats.bad_crc, stats.damaged), (1, 0));
    }

    /// Every frame of every kind in `data` scanned as a datagram and as a
    /// stream split at every read size: the same each way.
    fn kinds_every_way(data: &[u8]) -> (Vec<(Vec<u8>, Kind)>, ScanStats) {
        let mut stats = ScanStats::default();
        let mut found = Vec::new();
        scan_datagram_all(data, &mut stats, &mut |f, k| found.push((f.to_vec(), k)));
        for chunk in 1..=data.len() {
            let mut scanner = StreamScanner::new();
            let mut streamed = Vec::new();
            for piece in data.chunks(chunk) {
                scanner.push_all(piece, &mut |f, k| streamed.push((f.to_vec(), k)));
            }
            assert_eq!(streamed, found, "read size {chunk}");
            assert_eq!(scanner.stats, stats, "read size {chunk}");
            assert_eq!(scanner.pending_bytes(), 0, "read size {chunk}");
        }
        (found, stats)
    }

    /// A PING from 1/1 numbered `seq` whose CRC is broken.
    fn damaged_ping(version: Version, seq: u8) -> Vec<u8> {
        let mut out = Vec::new();
        let header = Header {
            sysid: 1,
            compid: 1,
            seq,
        };
        let ping = Msg::Ping {
            time_usec: 123_456,
            seq: 9,
            target_system: 255,
            target_component: 190,
        };
        encode(&mut out, version, header, &ping);
        let crc = out.len() - 2;
        out[crc] ^= 0x5A;
        assert!(!out[1..].iter().any(|&b| b == STX_V1 || b == STX_V2));
        out
    }

    #[test]
    fn a_damaged_frame_between_good_ones_is_delivered_once_with_its_header() {
        for version in [Version::V1, Version::V2] {
            let before = ping_frame(Version::V2, 1);
            let damaged = damaged_ping(version, 200);
            let after = ping_frame(Version::V1, 2);
            let data = [&before[..], &damaged[..], &after[..]].concat();
            let (found, stats) = kinds_every_way(&data);
            assert_eq!(
                found,
                [
                    (before.clone(), Kind::Good),
                    (damaged.clone(), Kind::Damaged),
                    (after.clone(), Kind::Good)
                ]
            );
            assert_eq!(
                (
                    stats.frames,
                    stats.damaged,
                    stats.bad_crc,
                    stats.skipped_bytes
                ),
                (2, 1, 0, 0)
            );
            let frame = crate::frame::decode_as(&damaged, Kind::Damaged);
            assert_eq!(frame.msg, Msg::Damaged);
            assert_eq!(
                (frame.source, frame.packet_seq, frame.msgid, frame.version),
                (crate::frame::SysComp::new(1, 1), 200, 4, version)
            );
            assert_eq!(usize::from(frame.len), damaged.len());
        }
    }

    #[test]
    fn a_damaged_frame_ending_a_datagram_is_delivered() {
        let data = [ping_frame(Version::V2, 1), damaged_ping(Version::V2, 2)].concat();
        let mut stats = ScanStats::default();
        let mut kinds = Vec::new();
        scan_datagram_all(&data, &mut stats, &mut |_, k| kinds.push(k));
        assert_eq!(kinds, [Kind::Good, Kind::Damaged]);
        // On a stream, nothing yet says it is whole: it waits.
        let mut scanner = StreamScanner::new();
        let mut kinds = Vec::new();
        scanner.push_all(&data, &mut |_, k| kinds.push(k));
        assert_eq!(kinds, [Kind::Good]);
        assert_eq!(scanner.pending_bytes(), data.len() / 2);
    }

    #[test]
    fn a_damaged_looking_candidate_followed_by_junk_stays_junk() {
        let damaged = damaged_ping(Version::V2, 3);
        let after = ping_frame(Version::V2, 4);
        // Junk after it, and a start byte that starts no good frame.
        for junk in [&[0x42u8, 0x43][..], &[STX_V2, 0x03, 0x00, 0x00][..]] {
            let data = [&damaged[..], junk, &after[..]].concat();
            let (found, stats) = kinds_every_way(&data);
            assert_eq!(found, [(after.clone(), Kind::Good)], "{junk:02x?}");
            assert_eq!(
                (stats.damaged, stats.bad_crc, stats.skipped_bytes as usize),
                (0, 1, damaged.len() + junk.len()),
                "{junk:02x?}"
            );
        }
    }

    #[test]
    fn a_damaged_looking_candidate_with_a_good_frame_inside_is_junk() {
        // A MAVLink 1 PING header claiming 26 payload bytes that hold a
        // whole good frame, its extent lined up with a good frame after it.
        let inner = ping_frame(Version::V1, 5);
        let mut junk = vec![STX_V1, inner.len() as u8, 0, 1, 1, 4];
        junk.extend(&inner);
        junk.extend([0x11, 0x22]);
        let after = ping_frame(Version::V2, 6);
        let data = [&junk[..], &after[..]].concat();
        let (found, stats) = kinds_every_way(&data);
        assert_eq!(found, [(inner, Kind::Good), (after, Kind::Good)]);
        assert_eq!((stats.damaged, stats.skipped_bytes), (0, 8));
    }

    #[test]
    fn a_lying_start_after_a_damaged_frame_holds_back_no_good_frame() {
        // After the damaged frame, `FE FF` claims 263 bytes; the good frame
        // behind it is whole, so the false start can never be a good frame:
        // the damaged one is junk at once, and the good one delivered.
        let damaged = damaged_ping(Version::V2, 7);
        let after = ping_frame(Version::V2, 8);
        let data = [&damaged[..], &[STX_V1, 0xFF, 0x01, 0x01][..], &after[..]].concat();
        let mut scanner = StreamScanner::new();
        let mut found = Vec::new();
        scanner.push_all(&data, &mut |f, k| found.push((f.to_vec(), k)));
        assert_eq!(found, [(after, Kind::Good)]);
        assert_eq!(scanner.pending_bytes(), 0);
        assert_eq!((scanner.stats.damaged, scanner.stats.bad_crc), (0, 1));
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

    /// Scans `data` as a datagram and as a stream split at every byte
    /// (and in one piece): the frames found, the same each way.
    fn frames_every_way(data: &[u8]) -> Vec<Vec<u8>> {
        let (frames, _) = collect_datagram(data);
        for chunk in 1..=data.len() {
            let mut scanner = StreamScanner::new();
            let mut found = Vec::new();
            for piece in data.chunks(chunk) {
                scanner.push(piece, &mut |f| found.push(f.to_vec()));
            }
            assert_eq!(found, frames, "read size {chunk}");
        }
        frames
    }

    /// Issue 21, the exact bytes of a failure found by a seeded search of
    /// junk-prefixed PING replies: `FE 0D` claims 6 + 13 + 2 = 21 bytes
    /// with MAVLink 1 id 0x0E, which the dialect does not know, so its CRC
    /// cannot be checked. Its extent ends inside the real frame on a 0xFD
    /// of the frame's payload, so it "lined up" with a following start
    /// byte, was skipped whole as an unknown message and took the first 17
    /// bytes of the reply with it.
    #[test]
    fn unknown_id_junk_ending_inside_a_frame_does_not_swallow_it() {
        let junk = [0xFE, 0x0D, 0xD8, 0x59];
        let reply = [
            0xFD, 0x0E, 0x00, 0x00, 0xC2, 0x01, 0x01, 0x04, 0x00, 0x00, 0xF3, 0x56, 0x47, 0x4F,
            0x4D, 0x02, 0xBD, 0xFD, 0x9E, 0x04, 0xEE, 0xE7, 0xFF, 0xBE, 0x34, 0xAD,
        ];
        assert_eq!(collect_datagram(&reply).0, [reply.to_vec()]);
        let data = [&junk[..], &reply[..]].concat();
        assert_eq!(junk.len() + 21, 4 + 17 + 4, "the junk's extent ends inside");
        assert_eq!(data[junk.len() + 17], STX_V2, "on a start byte");
        assert_eq!(frames_every_way(&data), [reply.to_vec()]);
        let (_, stats) = collect_datagram(&data);
        assert_eq!(
            (stats.unknown_id, stats.skipped_bytes, stats.truncated),
            (0, 4, 0)
        );
    }

    /// Issue 21, the exact bytes of the second failure the search found:
    /// `FE 0E 82 FE FE FD` is a MAVLink 1 header of STATUSTEXT (id 253)
    /// claiming 14 payload bytes, whose 22-byte extent takes in the first 9
    /// bytes of the reply and whose CRC matches by chance (1 in 65,536). It
    /// was delivered as a frame and the reply was lost. STATUSTEXT is 51
    /// bytes in MAVLink 1, so the length now rules it out.
    #[test]
    fn chance_crc_match_with_a_wrong_v1_length_does_not_swallow_a_frame() {
        let junk = [
            0xA5, 0x25, 0xFD, 0xFE, 0x0E, 0x82, 0xFE, 0xFE, 0xFD, 0xFD, 0x51, 0x57, 0xF2,
        ];
        let reply = [
            0xFD, 0x0E, 0x00, 0x00, 0xA3, 0x01, 0x01, 0x04, 0x00, 0x00, 0x24, 0x9E, 0x52, 0x54,
            0x12, 0x6C, 0x19, 0xDE, 0x18, 0x32, 0xA9, 0x53, 0xFF, 0xBE, 0x20, 0xF6,
        ];
        let data = [&junk[..], &reply[..]].concat();
        let false_frame = &data[3..3 + 22];
        assert_eq!(message_id(false_frame), 253);
        assert!(crc_matches(false_frame, extra_crc(253).unwrap()));
        assert_eq!(v1_payload_len(253), Some(51));
        assert_eq!(frames_every_way(&data), [reply.to_vec()]);
        let (_, stats) = collect_datagram(&data);
        assert_eq!((stats.bad_crc, stats.skipped_bytes), (1, 13));
    }

    #[test]
    fn v1_lengths_come_from_the_dialect() {
        assert_eq!(v1_payload_len(0), Some(9)); // HEARTBEAT
        assert_eq!(v1_payload_len(4), Some(14)); // PING
        assert_eq!(v1_payload_len(77), Some(3)); // COMMAND_ACK: base fields only
        assert_eq!(v1_payload_len(14), None);
        assert_eq!(ping_frame(Version::V1, 1)[1], 14);
    }

    /// An unknown message (lined up with the start byte that follows it)
    /// whose last 12 bytes are the start of a real frame: `time_usec` of
    /// all 0xFD puts a start byte right after the unknown one's extent.
    fn unknown_holding_the_start_of(frame: &[u8]) -> Vec<u8> {
        let mut unknown = vec![STX_V2, 20, 0, 0, 0, 1, 1, 0xEE, 0xEE, 0xEE];
        unknown.extend([0x11; 10]);
        unknown.extend(&frame[..12]);
        assert_eq!(frame_len(&unknown), Ok(Some(unknown.len())));
        unknown
    }

    /// A PING whose `time_usec` is all 0xFD bytes.
    fn fd_ping() -> Vec<u8> {
        ping_at(Version::V2, 5, u64::MAX / 0xFF * 0xFD)
    }

    #[test]
    fn a_frame_starting_inside_an_unknown_message_is_found() {
        let frame = fd_ping();
        let unknown = unknown_holding_the_start_of(&frame);
        let data = [&unknown[..], &frame[12..]].concat();
        assert_eq!(frames_every_way(&data), std::slice::from_ref(&frame));
        let (_, stats) = collect_datagram(&data);
        assert_eq!((stats.unknown_id, stats.skipped_bytes), (0, 20));
    }

    #[test]
    fn stream_waits_for_a_frame_starting_inside_an_unknown_message() {
        let frame = fd_ping();
        let unknown = unknown_holding_the_start_of(&frame);
        let mut scanner = StreamScanner::new();
        let mut found = Vec::new();
        // The unknown message and the byte after it are there, the frame
        // starting inside it not yet: neither is decided.
        scanner.push(&unknown, &mut |f| found.push(f.to_vec()));
        scanner.push(&frame[12..13], &mut |f| found.push(f.to_vec()));
        assert!(found.is_empty());
        assert_eq!(scanner.pending_bytes(), unknown.len() + 1);
        assert_eq!(scanner.stats.unknown_id, 0);
        // Its last byte comes: the frame is delivered with it.
        scanner.push(&frame[13..], &mut |f| found.push(f.to_vec()));
        assert_eq!(found, [frame]);
        assert_eq!(scanner.pending_bytes(), 0);
        assert_eq!(
            (scanner.stats.unknown_id, scanner.stats.skipped_bytes),
            (0, 20)
        );
    }

    #[test]
    fn a_lying_start_inside_an_unknown_message_does_not_hold_back_the_next_frame() {
        // The unknown message ends in `FE FF` (a MAVLink 1 start claiming
        // 263 bytes); the frame after it is delivered at once, because the
        // false start's extent already holds it whole.
        let mut unknown = vec![STX_V2, 12, 0, 0, 0, 1, 1, 0xEE, 0xEE, 0xEE];
        unknown.extend([0x11; 10]);
        unknown.extend([STX_V1, 0xFF, 0x22, 0x33]);
        let frame = ping_frame(Version::V2, 4);
        let mut scanner = StreamScanner::new();
        let mut found = Vec::new();
        scanner.push(&[&unknown[..], &frame[..]].concat(), &mut |f| {
            found.push(f.to_vec())
        });
        assert_eq!(found, [frame]);
        assert_eq!(scanner.pending_bytes(), 0);
        assert_eq!(
            (scanner.stats.unknown_id, scanner.stats.skipped_bytes),
            (1, 0)
        );
    }

    /// A signed MAVLink 2 ENCAPSULATED_DATA frame with 255 payload bytes
    /// of 0x42 (the longest frame there is), its CRC good or not.
    fn longest_frame(good: bool) -> Vec<u8> {
        let mut frame = vec![STX_V2, 255, IFLAG_SIGNED, 0, 0, 1, 1, 131, 0, 0];
        frame.resize(V2_HEADER + 255, 0x42);
        let mut digest = X25.digest();
        digest.update(&frame[1..]);
        digest.update(&[extra_crc(131).unwrap()]);
        let crc = digest.finalize() ^ u16::from(!good);
        frame.extend(crc.to_le_bytes());
        frame.resize(MAX_FRAME_LEN, 0x42);
        frame
    }

    #[test]
    fn the_longest_tail_a_stream_keeps_is_max_pending() {
        // A longest damaged frame waits for the longest good frame after
        // it to be whole: all of one and all but the last byte of the other.
        let data = [longest_frame(false), longest_frame(true)].concat();
        assert!(matches!(check(&data[..MAX_FRAME_LEN]), Check::Bad));
        assert!(matches!(check(&data[MAX_FRAME_LEN..]), Check::Good));
        let mut scanner = StreamScanner::new();
        let (last, most) = data.split_last().unwrap();
        for byte in most {
            scanner.push_all(std::slice::from_ref(byte), &mut |_, _| panic!("no frame"));
        }
        assert_eq!(scanner.pending_bytes(), MAX_PENDING);
        let mut kinds = Vec::new();
        scanner.push_all(std::slice::from_ref(last), &mut |_, k| kinds.push(k));
        assert_eq!(kinds, [Kind::Damaged, Kind::Good]);
        assert_eq!(scanner.pending_bytes(), 0);
    }

    #[test]
    fn an_unknown_message_waits_for_a_candidate_inside_it() {
        // A maximal unknown message (signed, 255 payload bytes) lined up
        // with the `FE` after it, whose last byte starts a signed MAVLink 2
        // candidate of 254 payload bytes (the `FE`): both wait until that
        // candidate is whole, 279 + 279 bytes from the first start byte:
        // 557 are kept while its last byte is missing.
        let header = [STX_V2, 255, IFLAG_SIGNED, 0, 0, 1, 1, 0xEE, 0xEE, 0xEE];
        let mut data = header.to_vec();
        data.resize(MAX_FRAME_LEN - 1, 0x42);
        data.extend([STX_V2, STX_V1, IFLAG_SIGNED]);
        data.extend(&header[3..]);
        data.resize(MAX_PENDING - 2, 0x42);
        let mut scanner = StreamScanner::new();
        for byte in &data {
            scanner.push(std::slice::from_ref(byte), &mut |_| panic!("no frame"));
        }
        assert_eq!(scanner.pending_bytes(), MAX_PENDING - 2);
        assert_eq!(scanner.stats.unknown_id, 0);
        // Whole now, and not a good frame: the unknown message is skipped.
        scanner.push(&[0x42], &mut |_| panic!("no frame"));
        assert_eq!(scanner.stats.unknown_id, 1);
        assert_eq!(scanner.pending_bytes(), 0);
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

    #[test]
    fn the_table_crc_is_the_mavlink_crates() {
        let mut x: u32 = 12345;
        for len in 0..300usize {
            let data: Vec<u8> = (0..len)
                .map(|_| {
                    x = x.wrapping_mul(1_103_515_245).wrapping_add(12_345);
                    (x >> 16) as u8
                })
                .collect();
            let extra = (len % 251) as u8;
            let mut digest = X25.digest();
            digest.update(&data);
            digest.update(&[extra]);
            assert_eq!(
                digest.finalize(),
                mavlink::calculate_crc(&data, extra),
                "{len}"
            );
        }
    }
}
