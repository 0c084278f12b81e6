//! `--probe ftp`: a file read over MAVLink FTP as MAVProxy's `ftp get`
//! reads it, and nothing written. OpenFileRO, then BurstReadFile from the
//! start: the vehicle streams the file until a packet says the burst is
//! complete (or a NAK says the file ended). What the burst left out
//! inside the file is read piece by piece (ReadFile, a window at a time,
//! each asked again after the timeout up to the retries); what it left at
//! the end is asked for by a new burst from there. A burst that goes
//! quiet for one timeout is over. TerminateSession ends the session, done
//! or not.

use super::asks::{Asks, Overdue};
use super::attempt::{Counts, Ending, Peer, Protocol};
use super::progress::Progress;
use crate::engine::Nanos;
use crate::frame::transfer::{ftp_error, ftp_op, Ftp, FtpData, FTP_DATA_MAX};
use crate::frame::{SysComp, Transfer};

const OPEN: u32 = u32::MAX;
const BURST: u32 = u32::MAX - 1;
/// Bytes asked for in one packet.
const CHUNK: u32 = FTP_DATA_MAX as u32;

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Phase {
    Opening,
    /// A burst streams from the session.
    Bursting,
    /// Reading the pieces the bursts left out.
    Filling,
    Ended(Ending),
}

#[derive(Debug)]
pub(crate) struct FtpDownload {
    peer: Peer,
    path: String,
    asks: Asks,
    window: usize,
    phase: Phase,
    started: bool,
    seq: u16,
    session: u8,
    size: u32,
    /// The byte ranges that arrived, sorted, merged.
    have: Vec<(u32, u32)>,
    /// The furthest byte a burst has reached (+ 1): what a burst brings
    /// above it is the first pass.
    extent: u32,
    /// The last burst went quiet instead of completing: the next is a
    /// re-request.
    quiet: bool,
    /// Bursts that went quiet.
    quiet_bursts: u64,
    /// The open was sent again (its answer may have been lost), and the
    /// sessions reset after that.
    open_resent: bool,
    reset_sent: bool,
    /// A NAK's error code, once refused.
    nak: Option<u8>,
    progress: Progress,
    counts: Counts,
}

impl FtpDownload {
    pub(crate) fn new(
        target: SysComp,
        path: &str,
        timeout: Nanos,
        retries: u8,
        window: u8,
        now: Nanos,
    ) -> Self {
        FtpDownload {
            peer: Peer::new(target),
            path: path.to_string(),
            asks: Asks::new(timeout, retries),
            window: usize::from(window.max(1)),
            phase: Phase::Opening,
            started: false,
            seq: 0,
            session: 0,
            size: 0,
            have: Vec::new(),
            extent: 0,
            quiet: false,
            quiet_bursts: 0,
            open_resent: false,
            reset_sent: false,
            nak: None,
            progress: Progress::new(now),
            counts: Counts::default(),
        }
    }

    fn packet(&mut self, opcode: u8, offset: u32, size: u8, data: FtpData) -> Transfer {
        self.seq = self.seq.wrapping_add(1);
        self.counts.requests += 1;
        Transfer::Ftp(Ftp {
            target: self.peer.to(),
            seq: self.seq,
            session: self.session,
            opcode,
            size,
            req_opcode: 0,
            burst_complete: 0,
            offset,
            data,
        })
    }

    fn open(&mut self) -> Transfer {
        let path = self.path.clone();
        let size = path.len().min(FTP_DATA_MAX) as u8;
        self.packet(
            ftp_op::OPEN_FILE_RO,
            0,
            size,
            FtpData::head(path.as_bytes()),
        )
    }

    fn burst(&mut self, offset: u32) -> Transfer {
        self.packet(
            ftp_op::BURST_READ_FILE,
            offset,
            CHUNK as u8,
            FtpData::head(&[]),
        )
    }

    fn read(&mut self, offset: u32) -> Transfer {
        let len = self.missing_from(offset).min(CHUNK);
        self.packet(ftp_op::READ_FILE, offset, len as u8, FtpData::head(&[]))
    }

    fn end(&mut self, ending: Ending, out: &mut Vec<Transfer>) {
        if self.phase != Phase::Opening {
            let end = self.packet(ftp_op::TERMINATE_SESSION, 0, 0, FtpData::head(&[]));
            out.push(end);
        }
        self.phase = Phase::Ended(ending);
        self.asks.clear();
    }

    /// Adds `[start, end)` to what arrived; the bytes new to it.
    fn arrived(&mut self, start: u32, end: u32) -> u64 {
        let before: u64 = self.have.iter().map(|&(a, b)| u64::from(b - a)).sum();
        let at = self.have.partition_point(|&(_, b)| b < start);
        let mut merged = (start, end);
        while let Some(&(a, b)) = self.have.get(at) {
            if a > merged.1 {
                break;
            }
            merged = (merged.0.min(a), merged.1.max(b));
            self.have.remove(at);
        }
        self.have.insert(at, merged);
        let after: u64 = self.have.iter().map(|&(a, b)| u64::from(b - a)).sum();
        after - before
    }

    /// Bytes missing from `offset` to the next that arrived (or the end).
    fn missing_from(&self, offset: u32) -> u32 {
        let next = self
            .have
            .iter()
            .map(|&(a, _)| a)
            .find(|&a| a > offset)
            .unwrap_or(self.size);
        next.min(self.size).saturating_sub(offset)
    }

    /// The first missing offset at or after `from`, if any.
    fn first_missing(&self, from: u32) -> Option<u32> {
        let mut at = from;
        for &(a, b) in &self.have {
            if a <= at && at < b {
                at = b;
            }
        }
        (at < self.size).then_some(at)
    }

    /// The highest byte that arrived, + 1.
    fn reached(&self) -> u32 {
        self.have.last().map_or(0, |&(_, b)| b)
    }

    fn on_open(&mut self, f: &Ftp, now: Nanos, out: &mut Vec<Transfer>) {
        if self.phase != Phase::Opening || f.req_opcode != ftp_op::OPEN_FILE_RO {
            return;
        }
        self.asks.answered(OPEN);
        self.session = f.session;
        let head = f.data.bytes(f.offset, f.size);
        self.size = u32::from_le_bytes([head[0], head[1], head[2], head[3]]);
        self.progress.total(u64::from(self.size), now);
        if self.size == 0 {
            self.end(Ending::Complete, out);
            return;
        }
        self.phase = Phase::Bursting;
        self.asks.ask(BURST, now);
        let burst = self.burst(0);
        out.push(burst);
    }

    fn on_data(&mut self, f: &Ftp, now: Nanos, out: &mut Vec<Transfer>) {
        if f.session != self.session || self.phase == Phase::Opening {
            return;
        }
        let end = f.offset.saturating_add(u32::from(f.size)).min(self.size);
        let new = self.arrived(f.offset, end);
        self.counts.duplicates += u64::from(new == 0 && end > f.offset);
        if f.req_opcode == ftp_op::BURST_READ_FILE {
            // Bytes below the extent came again or late; above it, new.
            self.counts.first_pass += u64::from(end.saturating_sub(f.offset.max(self.extent)));
            self.extent = self.extent.max(end);
        }
        if f.req_opcode == ftp_op::READ_FILE && self.asks.answered(f.offset).is_some() && new > 0 {
            self.counts.re_requests_answered += 1;
        }
        self.progress.advance(self.progress.done() + new, now);
        if self.progress.complete() {
            self.end(Ending::Complete, out);
            return;
        }
        if f.req_opcode == ftp_op::BURST_READ_FILE && self.phase == Phase::Bursting {
            // The burst is alive: its quiet timer starts again.
            self.asks.answered(BURST);
            if f.burst_complete == 0 {
                self.asks.ask(BURST, now);
            } else {
                self.burst_over(now, out);
            }
        }
    }

    /// The burst ended (its last packet, EOF, or quiet): fill what it
    /// left out.
    fn burst_over(&mut self, now: Nanos, out: &mut Vec<Transfer>) {
        self.asks.answered(BURST);
        self.phase = Phase::Filling;
        self.fill(now, out);
    }

    /// Asks for what is missing: pieces inside what arrived one by one, a
    /// window at a time; the tail past it by a new burst.
    fn fill(&mut self, now: Nanos, out: &mut Vec<Transfer>) {
        let reached = self.reached();
        let mut from = 0;
        while self.asks.in_flight() < self.window {
            let Some(offset) = self.first_missing(from) else {
                break;
            };
            if offset >= reached {
                if self.asks.in_flight() == 0 {
                    self.phase = Phase::Bursting;
                    self.asks.ask(BURST, now);
                    // Going on after a complete burst asks for nothing again.
                    self.counts.re_requests += u64::from(std::mem::take(&mut self.quiet));
                    let burst = self.burst(offset);
                    out.push(burst);
                }
                return;
            }
            let len = self.missing_from(offset).min(CHUNK);
            from = offset + len;
            if self.asks.is_pending(offset) {
                continue;
            }
            self.asks.ask(offset, now);
            self.counts.re_requests += 1;
            let read = self.read(offset);
            out.push(read);
        }
    }

    fn on_nak(&mut self, f: &Ftp, now: Nanos, out: &mut Vec<Transfer>) {
        let error = f.data.bytes(f.offset, f.size)[0];
        if f.req_opcode == ftp_op::BURST_READ_FILE && error == ftp_error::EOF {
            if self.phase == Phase::Bursting {
                self.burst_over(now, out);
            }
            return;
        }
        if matches!(
            f.req_opcode,
            ftp_op::TERMINATE_SESSION | ftp_op::RESET_SESSIONS
        ) {
            return;
        }
        if self.reopen_after_lost_ack(f.req_opcode, error, now, out) {
            return;
        }
        self.nak = Some(error);
        self.end(Ending::Refused, out);
    }

    /// An open sent again after its ACK was lost finds the session it
    /// opened held (ArduPilot and `mavping respond` keep one): NAK Fail
    /// or NoSessionsAvailable. Then, once, the sessions are reset and the
    /// file opened again, as QGroundControl resets them. A first open
    /// refused that way is someone else's session, and a refusal.
    fn reopen_after_lost_ack(
        &mut self,
        req: u8,
        error: u8,
        now: Nanos,
        out: &mut Vec<Transfer>,
    ) -> bool {
        let held = matches!(error, ftp_error::FAIL | ftp_error::NO_SESSIONS_AVAILABLE);
        if req != ftp_op::OPEN_FILE_RO || !held || !self.open_resent || self.reset_sent {
            return false;
        }
        self.reset_sent = true;
        let reset = self.packet(ftp_op::RESET_SESSIONS, 0, 0, FtpData::head(&[]));
        out.push(reset);
        self.asks.ask(OPEN, now);
        self.counts.re_requests += 1;
        let open = self.open();
        out.push(open);
        true
    }
}

impl Protocol for FtpDownload {
    fn poll(&mut self, now: Nanos, out: &mut Vec<Transfer>) {
        if !self.started {
            self.started = true;
            self.asks.ask(OPEN, now);
            let open = self.open();
            out.push(open);
            return;
        }
        let mut due = Vec::new();
        self.asks.overdue(now, |key, o| due.push((key, o)));
        for (key, fate) in due {
            match (key, fate) {
                (OPEN, Overdue::Resend(_)) => {
                    self.open_resent = true;
                    self.counts.re_requests += 1;
                    let open = self.open();
                    out.push(open);
                }
                (OPEN, Overdue::GiveUp) => self.end(Ending::NoAnswer, out),
                // A quiet burst is over; not asked again as such.
                (BURST, _) => {
                    self.quiet = true;
                    self.quiet_bursts += 1;
                    self.asks.answered(BURST);
                    self.burst_over(now, out);
                }
                (offset, Overdue::Resend(_)) => {
                    self.counts.re_requests += 1;
                    let read = self.read(offset);
                    out.push(read);
                }
                (_, Overdue::GiveUp) => self.end(Ending::Stalled, out),
            }
            if matches!(self.phase, Phase::Ended(_)) {
                return;
            }
        }
        if self.phase == Phase::Filling {
            self.fill(now, out);
        }
    }

    fn on_message(
        &mut self,
        from: SysComp,
        msg: &Transfer,
        bytes: u16,
        now: Nanos,
        out: &mut Vec<Transfer>,
    ) {
        let Transfer::Ftp(f) = msg else {
            return;
        };
        if matches!(self.phase, Phase::Ended(_)) || !self.peer.accepts(from) {
            return;
        }
        self.progress.heard(bytes, now);
        match (f.opcode, f.req_opcode) {
            (ftp_op::ACK, ftp_op::OPEN_FILE_RO) => self.on_open(f, now, out),
            (ftp_op::ACK, ftp_op::BURST_READ_FILE | ftp_op::READ_FILE) => {
                self.on_data(f, now, out);
            }
            (ftp_op::NAK, _) => self.on_nak(f, now, out),
            _ => {}
        }
    }

    fn next_deadline(&self) -> Option<Nanos> {
        self.asks.next_deadline()
    }

    fn ending(&self) -> Option<Ending> {
        match self.phase {
            Phase::Ended(e) => Some(e),
            _ => None,
        }
    }

    fn reason(&self) -> Option<String> {
        if let Some(error) = self.nak {
            return Some(format!("NAK {} for {}", error_name(error), self.path));
        }
        match self.phase {
            Phase::Ended(Ending::Complete) | Phase::Opening => None,
            _ => Some(format!(
                "{} of {} bytes arrived, {} bursts went quiet",
                self.progress.done(),
                self.size,
                self.quiet_bursts
            )),
        }
    }

    fn progress(&self) -> &Progress {
        &self.progress
    }

    fn counts(&self) -> Counts {
        Counts {
            given_up: self.asks.given_up,
            ..self.counts
        }
    }

    fn responder(&self) -> Option<SysComp> {
        self.peer.responder()
    }

    fn close(&mut self, out: &mut Vec<Transfer>) {
        if !matches!(self.phase, Phase::Ended(_) | Phase::Opening) {
            let end = self.packet(ftp_op::TERMINATE_SESSION, 0, 0, FtpData::head(&[]));
            out.push(end);
        }
    }
}

/// An FTP error code's name, as the protocol's table gives it.
fn error_name(code: u8) -> String {
    let name = match code {
        ftp_error::FAIL => "Fail",
        ftp_error::FAIL_ERRNO => "FailErrno",
        ftp_error::INVALID_DATA_SIZE => "InvalidDataSize",
        ftp_error::INVALID_SESSION => "InvalidSession",
        ftp_error::NO_SESSIONS_AVAILABLE => "NoSessionsAvailable",
        ftp_error::EOF => "EOF",
        ftp_error::UNKNOWN_COMMAND => "UnknownCommand",
        ftp_error::FILE_EXISTS => "FileExists",
        ftp_error::FILE_PROTECTED => "FileProtected",
        ftp_error::FILE_NOT_FOUND => "FileNotFound",
        _ => return format!("error {code}"),
    };
    name.to_string()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frame::transfer::Target;

    const MS: Nanos = 1_000_000;
    const VEHICLE: SysComp = SysComp::new(1, 1);

    fn reply(req_opcode: u8, offset: u32, size: u8, complete: bool) -> Transfer {
        Transfer::Ftp(Ftp {
            target: Target::default(),
            seq: 0,
            session: 3,
            opcode: ftp_op::ACK,
            size,
            req_opcode,
            burst_complete: u8::from(complete),
            offset,
            data: FtpData::Pattern,
        })
    }

    fn opened(size: u32) -> Transfer {
        Transfer::Ftp(Ftp {
            target: Target::default(),
            seq: 0,
            session: 3,
            opcode: ftp_op::ACK,
            size: 4,
            req_opcode: ftp_op::OPEN_FILE_RO,
            burst_complete: 0,
            offset: 0,
            data: FtpData::head(&size.to_le_bytes()),
        })
    }

    fn ops(out: &[Transfer]) -> Vec<(u8, u32, u8)> {
        out.iter()
            .filter_map(|t| match t {
                Transfer::Ftp(f) => Some((f.opcode, f.offset, f.size)),
                _ => None,
            })
            .collect()
    }

    fn started(size: u32) -> (FtpDownload, Vec<Transfer>) {
        let mut d = FtpDownload::new(SysComp::new(1, 1), "/mavping.bin", 500 * MS, 2, 2, 0);
        let mut out = Vec::new();
        d.poll(0, &mut out);
        d.on_message(VEHICLE, &opened(size), 30, MS, &mut out);
        (d, out)
    }

    #[test]
    fn a_whole_burst_is_the_file() {
        let (mut d, mut out) = started(500);
        assert_eq!(
            ops(&out),
            [
                (ftp_op::OPEN_FILE_RO, 0, 12),
                (ftp_op::BURST_READ_FILE, 0, 239)
            ]
        );
        d.on_message(VEHICLE, &reply(15, 0, 239, false), 263, 2 * MS, &mut out);
        d.on_message(VEHICLE, &reply(15, 239, 239, false), 263, 3 * MS, &mut out);
        d.on_message(VEHICLE, &reply(15, 478, 22, true), 46, 4 * MS, &mut out);
        assert_eq!(d.ending(), Some(Ending::Complete));
        assert_eq!(ops(&out).last(), Some(&(ftp_op::TERMINATE_SESSION, 0, 0)));
        let c = d.counts();
        assert_eq!((c.first_pass, c.re_requests, c.duplicates), (500, 0, 0));
        assert_eq!(d.progress().figures(4 * MS).per_s, Some(125_000.0));
    }

    #[test]
    fn gaps_are_read_piece_by_piece_and_the_tail_by_a_new_burst() {
        let (mut d, mut out) = started(1_500);
        out.clear();
        // 0..239 lost, 239..478 and 717..956 came; the burst then quiet.
        d.on_message(VEHICLE, &reply(15, 239, 239, false), 263, 2 * MS, &mut out);
        d.on_message(VEHICLE, &reply(15, 717, 239, false), 263, 3 * MS, &mut out);
        d.poll(503 * MS, &mut out);
        assert_eq!(
            ops(&out),
            [(ftp_op::READ_FILE, 0, 239), (ftp_op::READ_FILE, 478, 239)]
        );
        out.clear();
        d.on_message(VEHICLE, &reply(5, 0, 239, false), 263, 510 * MS, &mut out);
        d.on_message(VEHICLE, &reply(5, 478, 239, false), 263, 511 * MS, &mut out);
        d.poll(511 * MS, &mut out);
        assert_eq!(ops(&out), [(ftp_op::BURST_READ_FILE, 956, 239)]);
        d.on_message(
            VEHICLE,
            &reply(15, 956, 239, false),
            263,
            520 * MS,
            &mut out,
        );
        d.on_message(
            VEHICLE,
            &reply(15, 1195, 239, false),
            263,
            521 * MS,
            &mut out,
        );
        d.on_message(VEHICLE, &reply(15, 1434, 66, true), 90, 522 * MS, &mut out);
        assert_eq!(d.ending(), Some(Ending::Complete));
        let c = d.counts();
        // What the first burst brought, and all the second did: past the
        // furthest byte the first was seen to send.
        assert_eq!(c.first_pass, 478 + 544);
        // The two reads, and the burst after the quiet one.
        assert_eq!((c.re_requests, c.re_requests_answered), (3, 2));
        assert_eq!(d.progress().done(), 1_500);
    }

    #[test]
    fn a_burst_that_completes_is_followed_by_the_next_and_nothing_is_asked_again() {
        // MAVSDK's bursts are 150 packets; here 2.
        let (mut d, mut out) = started(1_000);
        out.clear();
        d.on_message(VEHICLE, &reply(15, 0, 239, false), 263, 2 * MS, &mut out);
        d.on_message(VEHICLE, &reply(15, 239, 239, true), 263, 3 * MS, &mut out);
        assert_eq!(ops(&out), [(ftp_op::BURST_READ_FILE, 478, 239)]);
        d.on_message(VEHICLE, &reply(15, 478, 239, false), 263, 4 * MS, &mut out);
        d.on_message(VEHICLE, &reply(15, 717, 239, true), 263, 5 * MS, &mut out);
        d.on_message(VEHICLE, &reply(15, 956, 44, true), 68, 6 * MS, &mut out);
        assert_eq!(d.ending(), Some(Ending::Complete));
        let c = d.counts();
        assert_eq!((c.first_pass, c.re_requests), (1_000, 0));
    }

    #[test]
    fn a_nak_refuses_with_its_error_and_an_eof_ends_a_burst() {
        let mut d = FtpDownload::new(SysComp::new(1, 1), "/nope", 500 * MS, 2, 2, 0);
        let mut out = Vec::new();
        d.poll(0, &mut out);
        let nak = Transfer::Ftp(Ftp {
            target: Target::default(),
            seq: 0,
            session: 0,
            opcode: ftp_op::NAK,
            size: 1,
            req_opcode: ftp_op::OPEN_FILE_RO,
            burst_complete: 0,
            offset: 0,
            data: FtpData::head(&[ftp_error::FILE_NOT_FOUND]),
        });
        d.on_message(VEHICLE, &nak, 20, MS, &mut out);
        assert_eq!(d.ending(), Some(Ending::Refused));
        assert_eq!(d.reason().unwrap(), "NAK FileNotFound for /nope");

        let (mut d, mut out) = started(300);
        d.on_message(VEHICLE, &reply(15, 0, 239, false), 263, 2 * MS, &mut out);
        let eof = Transfer::Ftp(Ftp {
            target: Target::default(),
            seq: 0,
            session: 3,
            opcode: ftp_op::NAK,
            size: 1,
            req_opcode: ftp_op::BURST_READ_FILE,
            burst_complete: 0,
            offset: 239,
            data: FtpData::head(&[ftp_error::EOF]),
        });
        out.clear();
        d.on_message(VEHICLE, &eof, 20, 3 * MS, &mut out);
        // The tail (239..300) asked for by a new burst.
        assert_eq!(ops(&out), [(ftp_op::BURST_READ_FILE, 239, 239)]);
    }

    #[test]
    fn an_open_whose_ack_was_lost_resets_the_session_it_holds_once() {
        let mut d = FtpDownload::new(SysComp::new(1, 1), "/mavping.bin", 500 * MS, 3, 2, 0);
        let mut out = Vec::new();
        d.poll(0, &mut out);
        d.poll(500 * MS, &mut out);
        let held = Transfer::Ftp(Ftp {
            target: Target::default(),
            seq: 0,
            session: 0,
            opcode: ftp_op::NAK,
            size: 1,
            req_opcode: ftp_op::OPEN_FILE_RO,
            burst_complete: 0,
            offset: 0,
            data: FtpData::head(&[ftp_error::FAIL]),
        });
        out.clear();
        d.on_message(VEHICLE, &held, 20, 501 * MS, &mut out);
        assert_eq!(
            ops(&out),
            [
                (ftp_op::RESET_SESSIONS, 0, 0),
                (ftp_op::OPEN_FILE_RO, 0, 12)
            ]
        );
        assert_eq!(d.ending(), None);
        // Refused again: a refusal.
        d.on_message(VEHICLE, &held, 20, 502 * MS, &mut out);
        assert_eq!(d.ending(), Some(Ending::Refused));
        assert_eq!(d.reason().unwrap(), "NAK Fail for /mavping.bin");
    }

    #[test]
    fn an_unanswered_open_is_no_answer() {
        let mut d = FtpDownload::new(SysComp::new(1, 1), "/x", 500 * MS, 1, 2, 0);
        let mut out = Vec::new();
        for t in [0, 500, 1_000] {
            d.poll(t * MS, &mut out);
        }
        assert_eq!(d.ending(), Some(Ending::NoAnswer));
        assert_eq!(ops(&out).len(), 2);
    }
}
