//! `--probe mission`: the mission as a ground station reads it, and
//! nothing written. MISSION_REQUEST_LIST until MISSION_COUNT answers;
//! then each item in turn by MISSION_REQUEST_INT (the protocol asks one
//! at a time), each asked again after the timeout up to the retries;
//! then MISSION_ACK, which ends the vehicle's side. A MISSION_ACK from
//! the vehicle while items are wanted is a refusal. A vehicle that
//! answers with MISSION_ITEM (degrees in floats) is read the same.

use super::asks::{Asks, Overdue};
use super::attempt::{Counts, Ending, Peer, Protocol};
use super::progress::Progress;
use crate::engine::Nanos;
use crate::frame::codec;
use crate::frame::{SysComp, Transfer};

/// MAV_MISSION_TYPE_MISSION.
const MISSION: u8 = 0;
/// MAV_MISSION_ACCEPTED.
const ACCEPTED: u8 = 0;
/// The count request's key among the items' numbers.
const COUNT: u32 = u32::MAX;

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Phase {
    Counting,
    /// Waiting for item `seq` of `count`.
    Items {
        seq: u16,
        count: u16,
    },
    Ended(Ending),
}

#[derive(Debug)]
pub(crate) struct MissionDownload {
    peer: Peer,
    asks: Asks,
    phase: Phase,
    started: bool,
    /// A refusal's MAV_MISSION_RESULT.
    refused: Option<u8>,
    progress: Progress,
    counts: Counts,
}

impl MissionDownload {
    pub(crate) fn new(target: SysComp, timeout: Nanos, retries: u8, now: Nanos) -> Self {
        MissionDownload {
            peer: Peer::new(target),
            asks: Asks::new(timeout, retries),
            phase: Phase::Counting,
            started: false,
            refused: None,
            progress: Progress::new(now),
            counts: Counts::default(),
        }
    }

    fn request(&self, seq: u16) -> Transfer {
        Transfer::MissionRequest {
            target: self.peer.to(),
            seq,
            mission_type: MISSION,
            int: true,
        }
    }

    fn end(&mut self, ending: Ending) {
        self.phase = Phase::Ended(ending);
        self.asks.clear();
    }

    /// Asks for item `seq`, or, past the last, ends with our ACK.
    fn next_item(&mut self, seq: u16, count: u16, now: Nanos, out: &mut Vec<Transfer>) {
        if seq >= count {
            out.push(Transfer::MissionAck {
                target: self.peer.to(),
                result: ACCEPTED,
                mission_type: MISSION,
            });
            self.counts.requests += 1;
            self.end(Ending::Complete);
            return;
        }
        self.phase = Phase::Items { seq, count };
        self.asks.ask(u32::from(seq), now);
        self.counts.requests += 1;
        out.push(self.request(seq));
    }

    fn on_count(&mut self, count: u16, now: Nanos, out: &mut Vec<Transfer>) {
        if self.phase != Phase::Counting {
            // A repeat of the answer (our request went twice).
            self.counts.duplicates += 1;
            return;
        }
        self.asks.answered(COUNT);
        self.progress.total(u64::from(count), now);
        self.next_item(0, count, now, out);
    }

    fn on_item(&mut self, seq: u16, now: Nanos, out: &mut Vec<Transfer>) {
        let Phase::Items { seq: wanted, count } = self.phase else {
            return;
        };
        if seq != wanted {
            // An answer to a request sent again, come after the first.
            self.counts.duplicates += 1;
            return;
        }
        if let Some(attempts) = self.asks.answered(u32::from(seq)) {
            if attempts == 1 {
                self.counts.first_pass += 1;
            } else {
                self.counts.re_requests_answered += 1;
            }
        }
        self.progress.advance(u64::from(seq) + 1, now);
        self.next_item(seq + 1, count, now, out);
    }
}

impl Protocol for MissionDownload {
    fn poll(&mut self, now: Nanos, out: &mut Vec<Transfer>) {
        if !self.started {
            self.started = true;
            self.asks.ask(COUNT, now);
            self.counts.requests += 1;
            out.push(Transfer::MissionRequestList {
                target: self.peer.to(),
                mission_type: MISSION,
            });
            return;
        }
        let before = out.len();
        let mut fate = None;
        self.asks.overdue(now, |key, o| fate = Some((key, o)));
        match (fate, self.phase) {
            (Some((_, Overdue::Resend(_))), Phase::Counting) => {
                out.push(Transfer::MissionRequestList {
                    target: self.peer.to(),
                    mission_type: MISSION,
                });
            }
            (Some((key, Overdue::Resend(_))), _) => out.push(self.request(key as u16)),
            (Some((_, Overdue::GiveUp)), Phase::Counting) => self.end(Ending::NoAnswer),
            (Some((_, Overdue::GiveUp)), _) => self.end(Ending::Stalled),
            (None, _) => return,
        }
        if out.len() > before {
            self.counts.requests += 1;
            self.counts.re_requests += 1;
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
        let wanted = match *msg {
            Transfer::MissionCount { mission_type, .. }
            | Transfer::MissionAck { mission_type, .. } => mission_type == MISSION,
            Transfer::MissionItem(item) => item.mission_type == MISSION,
            _ => false,
        };
        if !wanted || matches!(self.phase, Phase::Ended(_)) || !self.peer.accepts(from) {
            return;
        }
        self.progress.heard(bytes, now);
        match *msg {
            Transfer::MissionCount { count, .. } => self.on_count(count, now, out),
            Transfer::MissionItem(item) => self.on_item(item.seq, now, out),
            Transfer::MissionAck { result, .. } => {
                self.refused = Some(result);
                self.end(Ending::Refused);
            }
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
        if let Some(result) = self.refused {
            return Some(format!(
                "the vehicle ended it with MISSION_ACK ({})",
                codec::mission_result_name(result)
            ));
        }
        match self.phase {
            Phase::Ended(Ending::Stalled) | Phase::Items { .. } => {
                let got = self.progress.done();
                let total = self.progress.total_known().unwrap_or(0);
                Some(format!("item {got} of {total} never came"))
            }
            _ => None,
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
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frame::transfer::{MissionItem, Target};

    const MS: Nanos = 1_000_000;
    const VEHICLE: SysComp = SysComp::new(1, 1);

    fn count(n: u16) -> Transfer {
        Transfer::MissionCount {
            target: Target::default(),
            count: n,
            mission_type: MISSION,
        }
    }

    fn item(seq: u16) -> Transfer {
        Transfer::MissionItem(MissionItem {
            target: Target::default(),
            seq,
            mission_type: MISSION,
            int: true,
            command: 16,
            frame: 6,
            lat: 1,
            lon: 2,
            alt: 3.0,
        })
    }

    fn requested(out: &[Transfer]) -> Vec<u16> {
        out.iter()
            .filter_map(|t| match t {
                Transfer::MissionRequest { seq, .. } => Some(*seq),
                _ => None,
            })
            .collect()
    }

    #[test]
    fn each_item_in_turn_then_our_ack() {
        let mut d = MissionDownload::new(SysComp::new(1, 0), 500 * MS, 2, 0);
        let mut out = Vec::new();
        d.poll(0, &mut out);
        assert!(matches!(out[..], [Transfer::MissionRequestList { .. }]));
        out.clear();
        d.on_message(VEHICLE, &count(3), 14, 10 * MS, &mut out);
        assert_eq!(requested(&out), [0]);
        d.on_message(VEHICLE, &item(0), 51, 20 * MS, &mut out);
        // Item 1 lost: asked again after the timeout.
        d.poll(520 * MS, &mut out);
        d.on_message(VEHICLE, &item(1), 51, 530 * MS, &mut out);
        d.on_message(VEHICLE, &item(2), 51, 540 * MS, &mut out);
        assert_eq!(requested(&out), [0, 1, 1, 2]);
        assert!(matches!(
            out.last(),
            Some(Transfer::MissionAck { result: 0, .. })
        ));
        assert_eq!(d.ending(), Some(Ending::Complete));
        let c = d.counts();
        assert_eq!(
            (c.first_pass, c.re_requests, c.re_requests_answered),
            (2, 1, 1)
        );
        assert_eq!(c.requests, 6);
        assert_eq!(d.progress().figures(540 * MS).time_to_100_ms, Some(540.0));
    }

    #[test]
    fn an_empty_mission_is_acknowledged_at_once() {
        let mut d = MissionDownload::new(SysComp::new(1, 1), 500 * MS, 2, 0);
        let mut out = Vec::new();
        d.poll(0, &mut out);
        d.on_message(VEHICLE, &count(0), 14, 5 * MS, &mut out);
        assert_eq!(d.ending(), Some(Ending::Complete));
        assert!(matches!(out.last(), Some(Transfer::MissionAck { .. })));
    }

    #[test]
    fn a_refusal_and_a_stall_say_why() {
        let mut d = MissionDownload::new(SysComp::new(1, 1), 500 * MS, 1, 0);
        let mut out = Vec::new();
        d.poll(0, &mut out);
        d.on_message(VEHICLE, &count(5), 14, 5 * MS, &mut out);
        d.on_message(VEHICLE, &item(0), 51, 6 * MS, &mut out);
        d.poll(506 * MS, &mut out);
        d.poll(1_006 * MS, &mut out);
        assert_eq!(d.ending(), Some(Ending::Stalled));
        assert_eq!(d.reason().unwrap(), "item 1 of 5 never came");

        let mut d = MissionDownload::new(SysComp::new(1, 1), 500 * MS, 1, 0);
        d.poll(0, &mut out);
        let ack = Transfer::MissionAck {
            target: Target::default(),
            result: 3,
            mission_type: MISSION,
        };
        d.on_message(VEHICLE, &ack, 12, 5 * MS, &mut out);
        assert_eq!(d.ending(), Some(Ending::Refused));
        assert_eq!(
            d.reason().unwrap(),
            "the vehicle ended it with MISSION_ACK (unsupported)"
        );
    }

    #[test]
    fn an_unanswered_list_request_is_no_answer() {
        let mut d = MissionDownload::new(SysComp::new(1, 1), 500 * MS, 1, 0);
        let mut out = Vec::new();
        for t in [0, 500, 1_000] {
            d.poll(t * MS, &mut out);
        }
        assert_eq!(out.len(), 2);
        assert_eq!(d.ending(), Some(Ending::NoAnswer));
    }
}
