//! The responder model ([`SimResponder`]): one simulated system's
//! answering core, its packet sequence, its HEARTBEAT and telemetry
//! timetables, and the bookkeeping of which of its frames arrived.

use std::collections::HashMap;

use super::truth::SimTruth;
use crate::answering::ResponderCore;
use crate::frame::Header;
use crate::telemetry::{Schedule, StreamKind};

pub(super) struct SimResponder {
    pub(super) core: ResponderCore,
    pub(super) packet_seq: u8,
    /// Its HEARTBEAT's timetable (`heartbeat=on`), and its telemetry's.
    pub(super) heartbeat: Option<Schedule>,
    pub(super) streams: Vec<(StreamKind, Schedule)>,
    pub(super) truth: SimTruth,
    /// A reply of its has been put on its way (delivered or spiked): the
    /// pinger's window for it opens at the first such exchange.
    pub(super) replied: bool,
    /// Frames it numbered so far: the index of the next one (its packet
    /// sequence is this index plus one, modulo 256).
    pub(super) numbered: u64,
    /// The highest index that has arrived at mavping.
    pub(super) latest_arrived: Option<u64>,
    /// Frames with more than one copy on its way: copies still to arrive.
    pub(super) copies_due: HashMap<u64, u8>,
}

impl SimResponder {
    /// The header of the next frame it sends, and the frame's index.
    pub(super) fn header(&mut self) -> (Header, u64) {
        self.packet_seq = self.packet_seq.wrapping_add(1);
        let index = self.numbered;
        self.numbered += 1;
        self.truth.down.sent += 1;
        let header = Header {
            sysid: self.core.id.sysid,
            compid: self.core.id.compid,
            seq: self.packet_seq,
        };
        (header, index)
    }

    /// A frame of its reached mavping: a first copy, maybe reordered, or
    /// an extra one.
    pub(super) fn arrived(&mut self, index: u64) {
        let copy = match self.copies_due.get_mut(&index) {
            Some(left) => {
                *left -= 1;
                let copy = *left == 0;
                if copy {
                    self.copies_due.remove(&index);
                }
                copy
            }
            None => false,
        };
        let down = &mut self.truth.down;
        if copy {
            down.duplicates_arrived += 1;
            return;
        }
        down.delivered += 1;
        down.reordered += u64::from(self.latest_arrived.is_some_and(|l| index < l));
        self.latest_arrived = Some(self.latest_arrived.map_or(index, |l| l.max(index)));
    }
}
