//! The MAVLink FTP server of `mavping respond` and `sim:`: one file,
//! [`SERVED_PATH`], read-only, served as ArduPilot's server serves a file
//! (one session, a burst of up to [`BURST_PACKETS`] packets with
//! `burst_complete` on the last, an end-of-file NAK past the end). Its
//! bytes are [`pattern_byte`](crate::frame::transfer::pattern_byte) of
//! their offset, so a download can be checked byte for byte.

use crate::frame::transfer::{ftp_error, ftp_op, Ftp, FtpData, Target, FTP_DATA_MAX};

/// The one file served.
pub(crate) const SERVED_PATH: &str = "/mavping.bin";
/// The most bytes the file has: FTP offsets are 32 bits, and a file this
/// big already takes minutes on a fast link.
pub(crate) const MAX_FILE_SIZE: u32 = 1 << 30;
/// Packets one BurstReadFile draws at most, as ArduPilot's server: the
/// client asks for the next burst from where this one ended.
pub(crate) const BURST_PACKETS: u16 = 500;
/// A session with no request this long is closed when another client
/// opens the file (ArduPilot's FTP_SESSION_TIMEOUT): a client that went
/// away does not hold the one session for ever.
pub(crate) const SESSION_TIMEOUT_NS: u64 = 3_000_000_000;

/// The operations that would change the file system: refused.
const WRITES: std::ops::RangeInclusive<u8> = 6..=13;

#[derive(Debug, Clone, Copy)]
struct Open {
    session: u8,
    last_ns: u64,
}

/// The file server's state: the file's size and the open session.
#[derive(Debug, Clone)]
pub(crate) struct FtpServer {
    pub(crate) size: u32,
    open: Option<Open>,
}

/// What one request draws.
#[derive(Debug, PartialEq)]
pub(crate) enum FtpAnswer {
    One(Ftp),
    Burst(Burst),
    /// A reply from a client (an ACK or NAK): nothing.
    Nothing,
}

/// A burst being served: each [`Burst::next`] is its next packet.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Burst {
    reply: Ftp,
    /// Bytes each packet carries (what the client asked for, at most 239).
    packet: u8,
    left: u16,
    file_size: u32,
    done: bool,
}

impl Burst {
    /// The burst's next packet: data from where the last ended, the last
    /// one marked `burst_complete`; past the end of the file an
    /// end-of-file NAK ends it.
    pub(crate) fn next(&mut self) -> Option<Ftp> {
        if self.done {
            return None;
        }
        let mut out = self.reply;
        self.reply.seq = self.reply.seq.wrapping_add(1);
        if out.offset >= self.file_size {
            self.done = true;
            return Some(nak(out, ftp_error::EOF, true));
        }
        let n = (self.file_size - out.offset).min(u32::from(self.packet)) as u8;
        self.left -= 1;
        self.done = self.left == 0;
        out.size = n;
        out.burst_complete = u8::from(self.done);
        out.data = FtpData::Pattern;
        self.reply.offset += u32::from(n);
        Some(out)
    }
}

fn nak(mut reply: Ftp, error: u8, last: bool) -> Ftp {
    reply.opcode = ftp_op::NAK;
    reply.size = 1;
    reply.data = FtpData::head(&[error]);
    reply.burst_complete = u8::from(last);
    reply
}

impl FtpServer {
    pub(crate) fn new(size: u32) -> Self {
        FtpServer { size, open: None }
    }

    /// Whether `path` (as a request carries it, maybe NUL-padded) is ours.
    fn is_served(path: &[u8]) -> bool {
        let end = path.iter().position(|&b| b == 0).unwrap_or(path.len());
        let path = &path[..end];
        path == SERVED_PATH.as_bytes() || path == &SERVED_PATH.as_bytes()[1..]
    }

    /// The answer to `req` from `to`, at `now_ns` of the server's clock.
    pub(crate) fn request(&mut self, req: &Ftp, to: Target, now_ns: u64) -> FtpAnswer {
        if req.opcode >= ftp_op::ACK {
            return FtpAnswer::Nothing;
        }
        let reply = Ftp {
            target: to,
            seq: req.seq.wrapping_add(1),
            session: req.session,
            opcode: ftp_op::ACK,
            size: 0,
            req_opcode: req.opcode,
            burst_complete: 0,
            offset: req.offset,
            data: FtpData::head(&[]),
        };
        let data = req.data.bytes(req.offset, req.size);
        let data = &data[..usize::from(req.size).min(data.len())];
        let ours = self.open.filter(|o| o.session == req.session);
        if let Some(open) = self.open.as_mut().filter(|o| o.session == req.session) {
            open.last_ns = now_ns;
        }
        let one = match req.opcode {
            ftp_op::OPEN_FILE_RO => return FtpAnswer::One(self.open_ro(reply, data, now_ns)),
            ftp_op::TERMINATE_SESSION if ours.is_some() => {
                self.open = None;
                reply
            }
            ftp_op::RESET_SESSIONS => {
                self.open = None;
                reply
            }
            ftp_op::LIST_DIRECTORY => self.list(reply, data),
            ftp_op::TERMINATE_SESSION | ftp_op::READ_FILE | ftp_op::BURST_READ_FILE
                if ours.is_none() =>
            {
                nak(reply, ftp_error::INVALID_SESSION, false)
            }
            ftp_op::READ_FILE if req.offset >= self.size => nak(reply, ftp_error::EOF, false),
            ftp_op::READ_FILE => {
                let n = (self.size - req.offset).min(u32::from(packet_size(req.size)));
                Ftp {
                    size: n as u8,
                    data: FtpData::Pattern,
                    ..reply
                }
            }
            ftp_op::BURST_READ_FILE => {
                return FtpAnswer::Burst(Burst {
                    reply,
                    packet: packet_size(req.size),
                    left: BURST_PACKETS,
                    file_size: self.size,
                    done: false,
                })
            }
            op if WRITES.contains(&op) => nak(reply, ftp_error::FILE_PROTECTED, false),
            _ => nak(reply, ftp_error::UNKNOWN_COMMAND, false),
        };
        FtpAnswer::One(one)
    }

    fn open_ro(&mut self, reply: Ftp, path: &[u8], now_ns: u64) -> Ftp {
        let reply = Ftp { offset: 0, ..reply };
        if let Some(open) = self.open {
            if now_ns.saturating_sub(open.last_ns) < SESSION_TIMEOUT_NS {
                // The same session again is a retry whose ACK was lost:
                // ArduPilot's Fail, which clients take as "already open".
                let error = if open.session == reply.session {
                    ftp_error::FAIL
                } else {
                    ftp_error::NO_SESSIONS_AVAILABLE
                };
                return nak(reply, error, false);
            }
        }
        if !Self::is_served(path) {
            return nak(reply, ftp_error::FILE_NOT_FOUND, false);
        }
        self.open = Some(Open {
            session: reply.session,
            last_ns: now_ns,
        });
        Ftp {
            size: 4,
            data: FtpData::head(&self.size.to_le_bytes()),
            ..reply
        }
    }

    /// ListDirectory of `/`: our one file, as `F<name>\t<size>`.
    fn list(&self, reply: Ftp, path: &[u8]) -> Ftp {
        let end = path.iter().position(|&b| b == 0).unwrap_or(path.len());
        if !matches!(&path[..end], b"/" | b"" | b".") {
            return nak(reply, ftp_error::FILE_NOT_FOUND, false);
        }
        if reply.offset > 0 {
            return nak(reply, ftp_error::EOF, false);
        }
        let entry = format!("F{}\t{}\0", &SERVED_PATH[1..], self.size);
        Ftp {
            size: entry.len() as u8,
            data: FtpData::head(entry.as_bytes()),
            ..reply
        }
    }
}

/// Bytes a read sends a packet: what was asked, 239 when 0 or more.
fn packet_size(asked: u8) -> u8 {
    if asked == 0 || usize::from(asked) > FTP_DATA_MAX {
        FTP_DATA_MAX as u8
    } else {
        asked
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const GCS: Target = Target {
        system: 255,
        component: 190,
    };

    fn req(opcode: u8, session: u8, offset: u32, data: &[u8]) -> Ftp {
        Ftp {
            target: Target {
                system: 1,
                component: 1,
            },
            seq: 10,
            session,
            opcode,
            size: data.len() as u8,
            req_opcode: 0,
            burst_complete: 0,
            offset,
            data: FtpData::head(data),
        }
    }

    fn one(answer: FtpAnswer) -> Ftp {
        match answer {
            FtpAnswer::One(f) => f,
            other => panic!("{other:?}"),
        }
    }

    fn error_of(f: &Ftp) -> (u8, u8) {
        (f.opcode, f.data.bytes(f.offset, f.size)[0])
    }

    #[test]
    fn open_read_and_end_of_file() {
        let mut s = FtpServer::new(1000);
        let open = one(s.request(&req(ftp_op::OPEN_FILE_RO, 3, 0, b"/mavping.bin"), GCS, 0));
        assert_eq!(
            (open.opcode, open.size, open.seq, open.session),
            (128, 4, 11, 3)
        );
        assert_eq!(&open.data.bytes(0, 4)[..4], &1000u32.to_le_bytes());
        let read = one(s.request(&req(ftp_op::READ_FILE, 3, 900, &[]), GCS, 1));
        assert_eq!((read.opcode, read.size, read.offset), (128, 100, 900));
        assert_eq!(read.data, FtpData::Pattern);
        let small = one(s.request(&req(ftp_op::READ_FILE, 3, 0, &[0; 80]), GCS, 1));
        assert_eq!(small.size, 80);
        let eof = one(s.request(&req(ftp_op::READ_FILE, 3, 1000, &[]), GCS, 1));
        assert_eq!(error_of(&eof), (129, ftp_error::EOF));
        // Another session's read, or a read with none open.
        let other = one(s.request(&req(ftp_op::READ_FILE, 4, 0, &[]), GCS, 1));
        assert_eq!(error_of(&other), (129, ftp_error::INVALID_SESSION));
        let end = one(s.request(&req(ftp_op::TERMINATE_SESSION, 3, 0, &[]), GCS, 1));
        assert_eq!(end.opcode, 128);
        let closed = one(s.request(&req(ftp_op::READ_FILE, 3, 0, &[]), GCS, 1));
        assert_eq!(error_of(&closed), (129, ftp_error::INVALID_SESSION));
    }

    #[test]
    fn one_session_other_paths_and_writes() {
        let mut s = FtpServer::new(10);
        let open = |s: &mut FtpServer, session, path: &[u8], at| {
            one(s.request(&req(ftp_op::OPEN_FILE_RO, session, 0, path), GCS, at))
        };
        let missing = open(&mut s, 0, b"@PARAM/param.pck?withdefaults=1", 0);
        assert_eq!(error_of(&missing), (129, ftp_error::FILE_NOT_FOUND));
        assert_eq!(open(&mut s, 0, b"mavping.bin", 0).opcode, 128);
        // A retry of the open: ArduPilot's Fail; another session: none left.
        assert_eq!(
            error_of(&open(&mut s, 0, b"/mavping.bin", 1)),
            (129, ftp_error::FAIL)
        );
        let busy = open(&mut s, 1, b"/mavping.bin", 2_999_999_999);
        assert_eq!(error_of(&busy), (129, ftp_error::NO_SESSIONS_AVAILABLE));
        // Idle past the timeout: the next client gets it.
        assert_eq!(open(&mut s, 1, b"/mavping.bin", 3_000_000_001).opcode, 128);
        let reset = one(s.request(&req(ftp_op::RESET_SESSIONS, 9, 0, &[]), GCS, 0));
        assert_eq!(reset.opcode, 128);
        assert_eq!(open(&mut s, 2, b"/mavping.bin", 0).opcode, 128);
        for write in 6..=13 {
            let refused = one(s.request(&req(write, 2, 0, b"/x"), GCS, 0));
            assert_eq!(
                error_of(&refused),
                (129, ftp_error::FILE_PROTECTED),
                "{write}"
            );
        }
        let crc = one(s.request(&req(14, 2, 0, b"/mavping.bin"), GCS, 0));
        assert_eq!(error_of(&crc), (129, ftp_error::UNKNOWN_COMMAND));
        let ack = req(ftp_op::ACK, 2, 0, &[]);
        assert_eq!(s.request(&ack, GCS, 0), FtpAnswer::Nothing);
        let list = one(s.request(&req(ftp_op::LIST_DIRECTORY, 2, 0, b"/"), GCS, 0));
        assert_eq!(&list.data.bytes(0, list.size)[..16], b"Fmavping.bin\t10\0");
    }

    fn burst(s: &mut FtpServer, offset: u32, size: u8) -> Vec<Ftp> {
        let asked = vec![0; usize::from(size)];
        let mut b = match s.request(&req(ftp_op::BURST_READ_FILE, 0, offset, &asked), GCS, 0) {
            FtpAnswer::Burst(b) => b,
            other => panic!("{other:?}"),
        };
        std::iter::from_fn(|| b.next()).collect()
    }

    #[test]
    fn a_burst_runs_to_the_end_then_naks_end_of_file() {
        let mut s = FtpServer::new(500);
        one(s.request(&req(ftp_op::OPEN_FILE_RO, 0, 0, b"/mavping.bin"), GCS, 0));
        let packets = burst(&mut s, 0, 0);
        let shape: Vec<(u8, u8, u32, u8, u16)> = packets
            .iter()
            .map(|p| (p.opcode, p.size, p.offset, p.burst_complete, p.seq))
            .collect();
        assert_eq!(
            shape,
            [
                (128, 239, 0, 0, 11),
                (128, 239, 239, 0, 12),
                (128, 22, 478, 0, 13),
                (129, 1, 500, 1, 14)
            ]
        );
        // From the end: the NAK alone.
        assert_eq!(burst(&mut s, 500, 0).len(), 1);
    }

    #[test]
    fn a_long_file_takes_bursts_of_five_hundred_packets() {
        let mut s = FtpServer::new(MAX_FILE_SIZE);
        one(s.request(&req(ftp_op::OPEN_FILE_RO, 0, 0, b"/mavping.bin"), GCS, 0));
        let packets = burst(&mut s, 1000, 100);
        assert_eq!(packets.len(), 500);
        assert!(packets[..499]
            .iter()
            .all(|p| p.burst_complete == 0 && p.size == 100));
        let last = packets[499];
        assert_eq!((last.burst_complete, last.offset), (1, 1000 + 499 * 100));
    }
}
