//! The transfers a ground station makes at connect, served read-only:
//! the parameter list, the mission and a file ([`TransferServer`]).
//!
//! A probe's request draws one reply; a PARAM_REQUEST_LIST or a
//! BurstReadFile draws hundreds. So nothing is sent here: what a request
//! draws is queued, and the caller takes it frame by frame
//! ([`TransferServer::next`]) at the pace it chooses, as an autopilot
//! streams its parameters at what its link takes. The queue is bounded
//! whatever a client asks: one list and one burst at a time (a new
//! PARAM_REQUEST_LIST restarts the list, as on ArduPilot and PX4; a new
//! burst replaces the last), and at most [`MAX_QUEUED`] single replies
//! (the rest dropped and counted).

use std::collections::VecDeque;

use serde::Serialize;

use super::ftp::{Burst, FtpAnswer, FtpServer};
use super::mission::{result, Mission};
use super::params::ParamSet;
use crate::frame::transfer::{ftp_op, Target};
use crate::frame::{Frame, Msg, SysComp, Transfer};

/// Single replies (a parameter read, a mission item, an FTP reply)
/// waiting at once; past it they are dropped and counted.
pub(crate) const MAX_QUEUED: usize = 1024;

/// What is served.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct ServeSpec {
    pub(crate) params: u16,
    pub(crate) mission: u16,
    pub(crate) file_size: u32,
}

/// What `mavping respond` and `sim:` serve unless told: a parameter set
/// and a mission of a small vehicle's size, and a 64 KiB file.
pub(crate) const DEFAULT_SERVE: ServeSpec = ServeSpec {
    params: 500,
    mission: 20,
    file_size: 65_536,
};
/// Transfer frames a second at most unless told: a fast link's pace (a
/// 500-parameter list in half a second); a slow one paces itself.
pub(crate) const DEFAULT_TRANSFER_RATE: f64 = 1000.0;

/// The frames a transfer sends, by message (FTP by ACK and NAK).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Kind {
    ParamValue,
    MissionCount,
    MissionItemInt,
    MissionItem,
    MissionAck,
    FtpAck,
    FtpNak,
}

/// Frames of each [`Kind`].
#[derive(Debug, Default, Clone, Copy, PartialEq, Eq, Serialize)]
pub(crate) struct KindCounts {
    pub(crate) param_value: u64,
    pub(crate) mission_count: u64,
    pub(crate) mission_item_int: u64,
    pub(crate) mission_item: u64,
    pub(crate) mission_ack: u64,
    pub(crate) ftp_ack: u64,
    pub(crate) ftp_nak: u64,
}

impl KindCounts {
    pub(crate) fn add(&mut self, kind: Kind) {
        *match kind {
            Kind::ParamValue => &mut self.param_value,
            Kind::MissionCount => &mut self.mission_count,
            Kind::MissionItemInt => &mut self.mission_item_int,
            Kind::MissionItem => &mut self.mission_item,
            Kind::MissionAck => &mut self.mission_ack,
            Kind::FtpAck => &mut self.ftp_ack,
            Kind::FtpNak => &mut self.ftp_nak,
        } += 1;
    }

    pub(crate) fn total(&self) -> u64 {
        self.param_value
            + self.mission_count
            + self.mission_item_int
            + self.mission_item
            + self.mission_ack
            + self.ftp_ack
            + self.ftp_nak
    }

    /// "12 PARAM_VALUE, 3 FTP ACK": the kinds with frames.
    pub(crate) fn list(&self) -> String {
        some(&[
            (self.param_value, "PARAM_VALUE"),
            (self.mission_count, "MISSION_COUNT"),
            (self.mission_item_int, "MISSION_ITEM_INT"),
            (self.mission_item, "MISSION_ITEM"),
            (self.mission_ack, "MISSION_ACK"),
            (self.ftp_ack, "FTP ACK"),
            (self.ftp_nak, "FTP NAK"),
        ])
    }
}

/// The transfer requests heard, by kind.
#[derive(Debug, Default, Clone, Copy, PartialEq, Eq, Serialize)]
pub(crate) struct TransferRequests {
    pub(crate) param_lists: u64,
    pub(crate) param_reads: u64,
    /// ...of which for no parameter of ours: not answered, as ArduPilot.
    pub(crate) param_reads_unknown: u64,
    pub(crate) mission_lists: u64,
    /// MISSION_REQUEST_INT and the older MISSION_REQUEST...
    pub(crate) mission_requests_int: u64,
    pub(crate) mission_requests: u64,
    /// ...of which past the end: a MISSION_ACK with an error.
    pub(crate) mission_requests_invalid: u64,
    /// The clients' MISSION_ACKs: each ends a download.
    pub(crate) mission_acks: u64,
    /// MISSION_COUNTs: uploads, refused (MAV_MISSION_DENIED).
    pub(crate) mission_uploads_refused: u64,
    pub(crate) ftp_requests: u64,
}

impl TransferRequests {
    pub(crate) fn total(&self) -> u64 {
        self.param_lists
            + self.param_reads
            + self.mission_lists
            + self.mission_requests_int
            + self.mission_requests
            + self.mission_acks
            + self.mission_uploads_refused
            + self.ftp_requests
    }
}

/// What was served: the requests, and the frames each caller sent or
/// dropped (its link emulation) as it took them.
#[derive(Debug, Default, Clone, Copy, PartialEq, Eq, Serialize)]
pub(crate) struct ServedCounts {
    pub(crate) requests: TransferRequests,
    pub(crate) sent: KindCounts,
    pub(crate) dropped: KindCounts,
    /// Frames sent twice by the link emulation (`--dup`).
    pub(crate) duplicated: u64,
    /// PARAM_REQUEST_LISTs that restarted a list still being sent.
    pub(crate) list_restarts: u64,
    /// Single replies dropped because [`MAX_QUEUED`] were waiting.
    pub(crate) overflow: u64,
}

impl ServedCounts {
    /// A frame taken from the server: sent, or dropped by the link
    /// emulation.
    pub(crate) fn frame(&mut self, kind: Kind, sent: bool) {
        if sent {
            self.sent.add(kind);
        } else {
            self.dropped.add(kind);
        }
    }
}

/// "3 PARAM_VALUE, 1 FTP ACK": the named counts above 0, or "none".
fn some(each: &[(u64, &str)]) -> String {
    let some: Vec<String> = each
        .iter()
        .filter(|(n, _)| *n > 0)
        .map(|(n, name)| format!("{n} {name}"))
        .collect();
    if some.is_empty() {
        "none".into()
    } else {
        some.join(", ")
    }
}

impl std::fmt::Display for ServedCounts {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let r = &self.requests;
        let requests = some(&[
            (r.param_lists, "PARAM_REQUEST_LIST"),
            (r.param_reads, "PARAM_REQUEST_READ"),
            (r.param_reads_unknown, "of them for no parameter"),
            (r.mission_lists, "MISSION_REQUEST_LIST"),
            (r.mission_requests_int, "MISSION_REQUEST_INT"),
            (r.mission_requests, "MISSION_REQUEST"),
            (r.mission_requests_invalid, "of them past the end"),
            (r.mission_acks, "MISSION_ACK"),
            (r.mission_uploads_refused, "uploads refused"),
            (r.ftp_requests, "FTP"),
        ]);
        write!(
            f,
            "transfers: {} requests ({requests}), {} frames sent ({}), {} dropped ({}), {} doubled",
            r.total(),
            self.sent.total(),
            self.sent.list(),
            self.dropped.total(),
            self.dropped.list(),
            self.duplicated
        )?;
        if self.list_restarts > 0 {
            write!(f, ", {} lists restarted", self.list_restarts)?;
        }
        if self.overflow > 0 {
            write!(f, ", {} replies dropped (queue full)", self.overflow)?;
        }
        Ok(())
    }
}

/// Whether `target` is `id`'s: broadcast (0) or its own ids.
fn ours(id: SysComp, target: Target) -> bool {
    (target.system == 0 || target.system == id.sysid)
        && (target.component == 0 || target.component == id.compid)
}

/// The kind of a frame the server sends.
fn kind_of(t: &Transfer) -> Kind {
    match t {
        Transfer::MissionCount { .. } => Kind::MissionCount,
        Transfer::MissionItem(item) if item.int => Kind::MissionItemInt,
        Transfer::MissionItem(_) => Kind::MissionItem,
        Transfer::MissionAck { .. } => Kind::MissionAck,
        Transfer::Ftp(f) if f.opcode == ftp_op::ACK => Kind::FtpAck,
        Transfer::Ftp(_) => Kind::FtpNak,
        _ => Kind::ParamValue,
    }
}

/// Serves the parameters, the mission and the file of one system; `R` is
/// where a reply goes (the path and MAVLink version its request came by).
#[derive(Debug)]
pub(crate) struct TransferServer<R> {
    id: SysComp,
    params: ParamSet,
    mission: Mission,
    ftp: FtpServer,
    singles: VecDeque<(R, Transfer)>,
    /// The list being sent: to whom, and the next index.
    list: Option<(R, u16)>,
    burst: Option<(R, Burst)>,
    /// The list and a burst take turns.
    burst_turn: bool,
    pub(crate) counts: ServedCounts,
}

impl<R: Copy> TransferServer<R> {
    pub(crate) fn new(id: SysComp, spec: ServeSpec) -> Self {
        TransferServer {
            id,
            params: ParamSet { count: spec.params },
            mission: Mission {
                count: spec.mission,
            },
            ftp: FtpServer::new(spec.file_size),
            singles: VecDeque::new(),
            list: None,
            burst: None,
            burst_turn: false,
            counts: ServedCounts::default(),
        }
    }

    fn queue(&mut self, to: R, reply: Transfer) {
        if self.singles.len() >= MAX_QUEUED {
            self.counts.overflow += 1;
        } else {
            self.singles.push_back((to, reply));
        }
    }

    /// Takes `frame` if it is a transfer request for us: queues what it
    /// draws, to go back by `to`; `now_ns` is the server's clock (FTP's
    /// session timeout). False for any other frame.
    pub(crate) fn request(&mut self, frame: &Frame, to: R, now_ns: u64) -> bool {
        let Msg::Transfer(t) = frame.msg else {
            return false;
        };
        if frame.source == self.id {
            return false;
        }
        let from = Target {
            system: frame.source.sysid,
            component: frame.source.compid,
        };
        match t {
            Transfer::ParamRequestList { target } if ours(self.id, target) => {
                self.counts.requests.param_lists += 1;
                if self.params.count > 0 {
                    self.counts.list_restarts += u64::from(self.list.is_some());
                    self.list = Some((to, 0));
                }
            }
            Transfer::ParamRequestRead { target, id, index } if ours(self.id, target) => {
                self.counts.requests.param_reads += 1;
                match self
                    .params
                    .lookup(index, &id)
                    .and_then(|i| self.params.get(i))
                {
                    Some(value) => self.queue(to, Transfer::ParamValue(value)),
                    None => self.counts.requests.param_reads_unknown += 1,
                }
            }
            Transfer::Ftp(f) if ours(self.id, f.target) => {
                self.counts.requests.ftp_requests += 1;
                match self.ftp.request(&f, from, now_ns) {
                    FtpAnswer::One(reply) => self.queue(to, Transfer::Ftp(reply)),
                    FtpAnswer::Burst(burst) => self.burst = Some((to, burst)),
                    FtpAnswer::Nothing => {}
                }
            }
            _ => return self.mission_request(&t, from, to),
        }
        true
    }

    /// The mission's part of [`TransferServer::request`].
    fn mission_request(&mut self, t: &Transfer, from: Target, to: R) -> bool {
        let id = self.id;
        let r = &mut self.counts.requests;
        let reply = match *t {
            Transfer::MissionRequestList {
                target,
                mission_type,
            } if ours(id, target) => {
                r.mission_lists += 1;
                Transfer::MissionCount {
                    target: from,
                    count: self.mission.count_of(mission_type),
                    mission_type,
                }
            }
            Transfer::MissionRequest {
                target,
                seq,
                mission_type,
                int,
            } if ours(id, target) => {
                *if int {
                    &mut r.mission_requests_int
                } else {
                    &mut r.mission_requests
                } += 1;
                match self.mission.item(seq, mission_type, int, from) {
                    Some(item) => Transfer::MissionItem(item),
                    None => {
                        r.mission_requests_invalid += 1;
                        Transfer::MissionAck {
                            target: from,
                            result: result::INVALID_SEQUENCE,
                            mission_type,
                        }
                    }
                }
            }
            Transfer::MissionAck { target, .. } if ours(id, target) => {
                r.mission_acks += 1;
                return true;
            }
            // An upload: refused, the mission is read-only.
            Transfer::MissionCount {
                target,
                mission_type,
                ..
            } if ours(id, target) => {
                r.mission_uploads_refused += 1;
                Transfer::MissionAck {
                    target: from,
                    result: result::DENIED,
                    mission_type,
                }
            }
            _ => return false,
        };
        self.queue(to, reply);
        true
    }

    /// Whether a frame waits to be sent.
    pub(crate) fn pending(&self) -> bool {
        !self.singles.is_empty() || self.list.is_some() || self.burst.is_some()
    }

    /// The next frame to send, where it goes and its kind: single replies
    /// first (a re-request is answered before the list goes on), then the
    /// list and a burst in turn.
    pub(crate) fn next(&mut self) -> Option<(R, Msg, Kind)> {
        let (to, t) = match self.singles.pop_front() {
            Some(single) => single,
            None => {
                self.burst_turn = !self.burst_turn;
                let from_burst = self.burst.is_some() && (self.burst_turn || self.list.is_none());
                if from_burst {
                    self.next_of_burst()?
                } else {
                    self.next_of_list()?
                }
            }
        };
        Some((to, Msg::Transfer(t), kind_of(&t)))
    }

    fn next_of_list(&mut self) -> Option<(R, Transfer)> {
        let (to, index) = self.list.as_mut()?;
        let to = *to;
        let value = self.params.get(*index);
        *index += 1;
        if *index >= self.params.count {
            self.list = None;
        }
        value.map(|v| (to, Transfer::ParamValue(v)))
    }

    fn next_of_burst(&mut self) -> Option<(R, Transfer)> {
        let (to, burst) = self.burst.as_mut()?;
        let to = *to;
        let packet = burst.next();
        if packet.is_none_or(|p| p.burst_complete == 1) {
            self.burst = None;
        }
        packet.map(|p| (to, Transfer::Ftp(p)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frame::test_frame as from;
    use crate::frame::transfer::{Ftp, FtpData, ParamId};

    const GCS: SysComp = SysComp::new(255, 190);
    const US: Target = Target {
        system: 1,
        component: 1,
    };

    fn server(params: u16, mission: u16, file_size: u32) -> TransferServer<u8> {
        TransferServer::new(
            SysComp::new(1, 1),
            ServeSpec {
                params,
                mission,
                file_size,
            },
        )
    }

    fn drain(s: &mut TransferServer<u8>) -> Vec<Transfer> {
        std::iter::from_fn(|| s.next())
            .map(|(_, msg, _)| match msg {
                Msg::Transfer(t) => t,
                other => panic!("{other:?}"),
            })
            .collect()
    }

    fn ask(s: &mut TransferServer<u8>, t: Transfer) -> bool {
        s.request(&from(GCS, Msg::Transfer(t)), 7, 0)
    }

    #[test]
    fn a_list_streams_every_parameter_and_a_read_answers_one() {
        let mut s = server(5, 0, 0);
        assert!(ask(&mut s, Transfer::ParamRequestList { target: US }));
        // Another system's request is not ours.
        let other = Target {
            system: 2,
            component: 1,
        };
        assert!(!ask(&mut s, Transfer::ParamRequestList { target: other }));
        let read = |index, name: &str| Transfer::ParamRequestRead {
            target: US,
            id: ParamId::new(name),
            index,
        };
        ask(&mut s, read(-1, "MAVPING_0003"));
        ask(&mut s, read(9, ""));
        let sent = drain(&mut s);
        let indices: Vec<u16> = sent
            .iter()
            .map(|t| match t {
                Transfer::ParamValue(p) => {
                    assert_eq!(p.count, 5);
                    p.index
                }
                other => panic!("{other:?}"),
            })
            .collect();
        // The read first, then the list; the unknown index unanswered.
        assert_eq!(indices, [3, 0, 1, 2, 3, 4]);
        let r = s.counts.requests;
        assert_eq!(
            (r.param_lists, r.param_reads, r.param_reads_unknown),
            (1, 2, 1)
        );
        assert!(!s.pending());
    }

    #[test]
    fn a_second_list_restarts_the_first() {
        let mut s = server(4, 0, 0);
        ask(&mut s, Transfer::ParamRequestList { target: US });
        s.next();
        s.next();
        ask(&mut s, Transfer::ParamRequestList { target: US });
        assert_eq!(drain(&mut s).len(), 4);
        assert_eq!(s.counts.list_restarts, 1);
    }

    #[test]
    fn a_mission_download_and_a_refused_upload() {
        let mut s = server(0, 3, 0);
        ask(
            &mut s,
            Transfer::MissionRequestList {
                target: US,
                mission_type: 0,
            },
        );
        for seq in [0, 2, 3] {
            ask(
                &mut s,
                Transfer::MissionRequest {
                    target: US,
                    seq,
                    mission_type: 0,
                    int: seq == 0,
                },
            );
        }
        ask(
            &mut s,
            Transfer::MissionAck {
                target: US,
                result: 0,
                mission_type: 0,
            },
        );
        ask(
            &mut s,
            Transfer::MissionCount {
                target: US,
                count: 2,
                mission_type: 0,
            },
        );
        let sent = drain(&mut s);
        let gcs = Target {
            system: 255,
            component: 190,
        };
        assert_eq!(
            sent[0],
            Transfer::MissionCount {
                target: gcs,
                count: 3,
                mission_type: 0
            }
        );
        let Transfer::MissionItem(first) = sent[1] else {
            panic!("{sent:?}")
        };
        assert!(first.int && first.seq == 0 && first.target == gcs);
        let Transfer::MissionItem(last) = sent[2] else {
            panic!("{sent:?}")
        };
        assert!(!last.int && last.seq == 2);
        let ack = |result| Transfer::MissionAck {
            target: gcs,
            result,
            mission_type: 0,
        };
        assert_eq!(sent[3..], [ack(13), ack(14)]);
        let r = s.counts.requests;
        assert_eq!(
            (
                r.mission_lists,
                r.mission_requests_int,
                r.mission_requests,
                r.mission_requests_invalid
            ),
            (1, 1, 2, 1)
        );
        assert_eq!((r.mission_acks, r.mission_uploads_refused), (1, 1));
    }

    fn ftp(opcode: u8, offset: u32, data: &[u8]) -> Transfer {
        Transfer::Ftp(Ftp {
            target: US,
            seq: 1,
            session: 0,
            opcode,
            size: data.len() as u8,
            req_opcode: 0,
            burst_complete: 0,
            offset,
            data: FtpData::head(data),
        })
    }

    #[test]
    fn a_burst_and_the_list_take_turns_and_singles_go_first() {
        let mut s = server(3, 0, 600);
        ask(&mut s, ftp(ftp_op::OPEN_FILE_RO, 0, b"/mavping.bin"));
        assert!(matches!(
            drain(&mut s)[..],
            [Transfer::Ftp(Ftp { opcode: 128, .. })]
        ));
        ask(&mut s, ftp(ftp_op::BURST_READ_FILE, 0, &[]));
        ask(&mut s, Transfer::ParamRequestList { target: US });
        ask(&mut s, ftp(ftp_op::READ_FILE, 100, &[]));
        let order: Vec<String> = drain(&mut s)
            .iter()
            .map(|t| match t {
                Transfer::ParamValue(p) => format!("p{}", p.index),
                Transfer::Ftp(f) if f.opcode == ftp_op::ACK => format!("d{}", f.offset),
                Transfer::Ftp(f) => format!("nak{}", f.offset),
                other => panic!("{other:?}"),
            })
            .collect();
        assert_eq!(
            order,
            ["d100", "p0", "d0", "p1", "d239", "p2", "d478", "nak600"]
        );
        assert_eq!(s.counts.requests.ftp_requests, 3);
    }

    #[test]
    fn single_replies_are_bounded() {
        let mut s = server(5, 0, 0);
        for _ in 0..MAX_QUEUED + 10 {
            ask(
                &mut s,
                Transfer::ParamRequestRead {
                    target: US,
                    id: ParamId::default(),
                    index: 1,
                },
            );
        }
        assert_eq!(s.counts.overflow, 10);
        assert_eq!(drain(&mut s).len(), MAX_QUEUED);
    }
}
