//! `--probe params`: every parameter, as QGroundControl and Mission
//! Planner fetch them. PARAM_REQUEST_LIST, then every PARAM_VALUE counted
//! by its `param_index` of `param_count`. The list is over when no
//! parameter has come for one timeout; each one it missed is then asked
//! for by index (PARAM_REQUEST_READ), a window of them at a time, each
//! asked again after the timeout up to the retries. A list request never
//! answered is sent again the same way.
//!
//! A PARAM_VALUE with index 65535 is a change the vehicle tells unasked,
//! not part of the list: it is counted as heard and nothing else.

use super::asks::{Asks, Overdue};
use super::attempt::{Counts, Ending, Peer, Protocol};
use super::progress::Progress;
use crate::engine::Nanos;
use crate::frame::transfer::{ParamId, ParamValue};
use crate::frame::{SysComp, Transfer};

/// The list request's key among the reads' indices.
const LIST: u32 = u32::MAX;
/// `param_index` of a parameter sent unasked.
const UNASKED: u16 = u16::MAX;

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Phase {
    /// The list is coming (or its request is unanswered).
    Listing,
    /// Asking for what the list missed.
    Reading,
    Ended(Ending),
}

#[derive(Debug)]
pub(crate) struct ParamsDownload {
    peer: Peer,
    timeout: Nanos,
    window: usize,
    asks: Asks,
    phase: Phase,
    list_sent: bool,
    /// The last PARAM_VALUE of the list and its index.
    last_listed: Option<(Nanos, u16)>,
    /// Parameters at the list's end that never came with it.
    list_tail: Option<u32>,
    /// One bit per parameter: arrived.
    have: Vec<u64>,
    count: Option<u16>,
    /// The next index to look at for one to ask for.
    cursor: u32,
    progress: Progress,
    counts: Counts,
}

impl ParamsDownload {
    pub(crate) fn new(
        target: SysComp,
        timeout: Nanos,
        retries: u8,
        window: u8,
        now: Nanos,
    ) -> Self {
        ParamsDownload {
            peer: Peer::new(target),
            timeout,
            window: usize::from(window.max(1)),
            asks: Asks::new(timeout, retries),
            phase: Phase::Listing,
            list_sent: false,
            last_listed: None,
            list_tail: None,
            have: Vec::new(),
            count: None,
            cursor: 0,
            progress: Progress::new(now),
            counts: Counts::default(),
        }
    }

    fn has(&self, index: u16) -> bool {
        self.have[usize::from(index) / 64] & (1 << (index % 64)) != 0
    }

    fn read(&self, index: u16) -> Transfer {
        Transfer::ParamRequestRead {
            target: self.peer.to(),
            id: ParamId::default(),
            index: index as i16,
        }
    }

    fn end(&mut self, ending: Ending) {
        self.phase = Phase::Ended(ending);
        self.asks.clear();
    }

    /// `p.count` parameters: the first value sets the table, a larger
    /// count later grows it (a vehicle that added parameters).
    fn size_to(&mut self, count: u16, now: Nanos) {
        if self.count.is_some_and(|c| c >= count) {
            return;
        }
        self.count = Some(count);
        self.have.resize(usize::from(count).div_ceil(64), 0);
        self.progress.total(u64::from(count), now);
    }

    fn take(&mut self, p: &ParamValue, now: Nanos) {
        self.size_to(p.count, now);
        let count = self.count.unwrap_or(0);
        if p.index >= count {
            return;
        }
        if self.phase == Phase::Listing {
            self.last_listed = Some((now, p.index));
            self.asks.answered(LIST);
        }
        let asked = self.asks.answered(u32::from(p.index)).is_some();
        if self.has(p.index) {
            self.counts.duplicates += 1;
            return;
        }
        self.have[usize::from(p.index) / 64] |= 1 << (p.index % 64);
        self.counts.re_requests_answered += u64::from(asked);
        if self.phase == Phase::Listing {
            self.counts.first_pass += 1;
        }
        self.progress.advance(self.progress.done() + 1, now);
        if self.progress.complete() {
            self.end(Ending::Complete);
        }
    }

    /// How many parameters after the list's last one all failed to come
    /// with it: what a vehicle that stopped sending looks like (one lost
    /// last frame does not, so two at least).
    fn missing_tail(&self, last: u16) -> Option<u32> {
        let count = self.count?;
        let tail = u32::from(count) - u32::from(last) - 1;
        let all_missing = (last + 1..count).all(|i| !self.has(i));
        (tail >= 2 && all_missing).then_some(tail)
    }

    /// The next index neither arrived nor asked for, from the cursor.
    fn next_missing(&mut self) -> Option<u16> {
        let count = u32::from(self.count?);
        while self.cursor < count {
            let index = self.cursor as u16;
            self.cursor += 1;
            if !self.has(index) && !self.asks.is_pending(u32::from(index)) {
                return Some(index);
            }
        }
        None
    }

    fn poll_listing(&mut self, now: Nanos, out: &mut Vec<Transfer>) {
        if !self.list_sent {
            self.list_sent = true;
            self.asks.ask(LIST, now);
            self.counts.requests += 1;
            out.push(Transfer::ParamRequestList {
                target: self.peer.to(),
            });
            return;
        }
        match self.last_listed {
            // Answered: the list is over once it has been quiet a timeout.
            Some((at, last)) if now >= at + self.timeout => {
                self.phase = Phase::Reading;
                self.list_tail = self.missing_tail(last);
            }
            Some(_) => {}
            None => self.resend_list(now, out),
        }
    }

    fn resend_list(&mut self, now: Nanos, out: &mut Vec<Transfer>) {
        let mut fate = None;
        self.asks.overdue(now, |_, o| fate = Some(o));
        match fate {
            Some(Overdue::Resend(_)) => {
                self.counts.requests += 1;
                self.counts.re_requests += 1;
                out.push(Transfer::ParamRequestList {
                    target: self.peer.to(),
                });
            }
            Some(Overdue::GiveUp) => self.end(Ending::NoAnswer),
            None => {}
        }
    }

    fn poll_reading(&mut self, now: Nanos, out: &mut Vec<Transfer>) {
        let before = out.len();
        let mut resend = Vec::new();
        self.asks.overdue(now, |key, o| {
            if let Overdue::Resend(_) = o {
                resend.push(key as u16);
            }
        });
        for index in resend {
            out.push(self.read(index));
        }
        while self.asks.in_flight() < self.window {
            let Some(index) = self.next_missing() else {
                break;
            };
            self.asks.ask(u32::from(index), now);
            out.push(self.read(index));
        }
        let sent = (out.len() - before) as u64;
        self.counts.requests += sent;
        self.counts.re_requests += sent;
        if self.asks.in_flight() == 0 {
            self.end(Ending::Stalled);
        }
    }
}

impl Protocol for ParamsDownload {
    fn poll(&mut self, now: Nanos, out: &mut Vec<Transfer>) {
        if self.phase == Phase::Listing {
            self.poll_listing(now, out);
        }
        if self.phase == Phase::Reading {
            self.poll_reading(now, out);
        }
    }

    fn on_message(
        &mut self,
        from: SysComp,
        msg: &Transfer,
        bytes: u16,
        now: Nanos,
        _out: &mut Vec<Transfer>,
    ) {
        let Transfer::ParamValue(p) = msg else {
            return;
        };
        if matches!(self.phase, Phase::Ended(_)) || !self.peer.accepts(from) {
            return;
        }
        self.progress.heard(bytes, now);
        if p.index != UNASKED {
            self.take(p, now);
        }
    }

    fn next_deadline(&self) -> Option<Nanos> {
        match self.phase {
            Phase::Ended(_) => None,
            Phase::Listing => match self.last_listed {
                Some((at, _)) => Some(at + self.timeout),
                None => self.asks.next_deadline(),
            },
            Phase::Reading => self.asks.next_deadline(),
        }
    }

    fn ending(&self) -> Option<Ending> {
        match self.phase {
            Phase::Ended(e) => Some(e),
            _ => None,
        }
    }

    fn reason(&self) -> Option<String> {
        let count = self.count?;
        let (_, last) = self.last_listed?;
        let missing = u64::from(count) - self.progress.done();
        let stopped = self
            .list_tail
            .map(|tail| format!("the list's last {tail} never came with it (after index {last}); "))
            .unwrap_or_default();
        (missing > 0 || !stopped.is_empty()).then(|| {
            format!(
                "{stopped}{} of {count} missing after the list, {} re-requests answered, {missing} \
                 never arrived",
                u64::from(count) - self.counts.first_pass,
                self.counts.re_requests_answered
            )
        })
    }

    fn stopped_after(&self) -> Option<u64> {
        self.list_tail?;
        self.last_listed.map(|(_, last)| u64::from(last))
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

    const MS: Nanos = 1_000_000;
    const VEHICLE: SysComp = SysComp::new(1, 1);

    fn value(index: u16, count: u16) -> Transfer {
        Transfer::ParamValue(ParamValue {
            id: ParamId::new(&format!("P{index}")),
            value: f32::from(index),
            param_type: 9,
            count,
            index,
        })
    }

    fn reads(out: &[Transfer]) -> Vec<i16> {
        out.iter()
            .filter_map(|t| match t {
                Transfer::ParamRequestRead { index, .. } => Some(*index),
                _ => None,
            })
            .collect()
    }

    fn download() -> ParamsDownload {
        ParamsDownload::new(SysComp::new(1, 0), 1_000 * MS, 2, 2, 0)
    }

    #[test]
    fn a_whole_list_is_complete_on_its_first_pass() {
        let mut d = download();
        let mut out = Vec::new();
        d.poll(0, &mut out);
        assert!(matches!(out[..], [Transfer::ParamRequestList { .. }]));
        for i in 0..10 {
            d.on_message(
                VEHICLE,
                &value(i, 10),
                37,
                (10 + u64::from(i)) * MS,
                &mut out,
            );
        }
        assert_eq!(d.ending(), Some(Ending::Complete));
        assert_eq!(d.responder(), Some(VEHICLE));
        let c = d.counts();
        assert_eq!((c.first_pass, c.re_requests, c.requests), (10, 0, 1));
        assert_eq!(d.progress().figures(20 * MS).time_to_100_ms, Some(19.0));
        assert_eq!(d.reason(), None);
    }

    #[test]
    fn what_the_list_missed_is_read_by_index_a_window_at_a_time() {
        let mut d = download();
        let mut out = Vec::new();
        d.poll(0, &mut out);
        for i in [0, 1, 3, 4, 6, 7] {
            d.on_message(VEHICLE, &value(i, 10), 37, 10 * MS, &mut out);
        }
        // Quiet for less than a timeout: still the list.
        out.clear();
        d.poll(1_009 * MS, &mut out);
        assert!(out.is_empty());
        d.poll(1_010 * MS, &mut out);
        assert_eq!(reads(&out), [2, 5]);
        out.clear();
        d.on_message(VEHICLE, &value(2, 10), 37, 1_020 * MS, &mut out);
        d.poll(1_020 * MS, &mut out);
        assert_eq!(reads(&out), [8]);
        out.clear();
        // 5 and 8 unanswered: asked again; 9 waits for the window.
        d.poll(2_010 * MS, &mut out);
        assert_eq!(reads(&out), [5]);
        for i in [5, 8, 9] {
            d.on_message(VEHICLE, &value(i, 10), 37, 2_100 * MS, &mut out);
        }
        assert_eq!(d.ending(), Some(Ending::Complete));
        let c = d.counts();
        assert_eq!(c.first_pass, 6);
        // 2, 5, 8, then 5 again; 9 came by itself.
        assert_eq!(
            (c.re_requests, c.re_requests_answered, c.requests),
            (4, 3, 5)
        );
    }

    #[test]
    fn a_parameter_never_answered_is_given_up_and_the_download_stalls() {
        let mut d = download();
        let mut out = Vec::new();
        d.poll(0, &mut out);
        for i in [0, 1, 2] {
            d.on_message(VEHICLE, &value(i, 4), 37, 10 * MS, &mut out);
        }
        d.poll(1_010 * MS, &mut out);
        d.poll(2_010 * MS, &mut out);
        d.poll(3_010 * MS, &mut out);
        assert_eq!(d.ending(), None);
        d.poll(4_010 * MS, &mut out);
        assert_eq!(d.ending(), Some(Ending::Stalled));
        assert_eq!(reads(&out), [3, 3, 3]);
        assert_eq!(d.counts().given_up, 1);
        assert_eq!(
            d.reason().unwrap(),
            "1 of 4 missing after the list, 0 re-requests \
             answered, 1 never arrived"
        );
    }

    #[test]
    fn an_unanswered_list_is_asked_again_then_given_up() {
        let mut d = download();
        let mut out = Vec::new();
        for t in [0, 1_000, 2_000, 3_000] {
            d.poll(t * MS, &mut out);
        }
        assert_eq!(out.len(), 3);
        assert_eq!(d.ending(), Some(Ending::NoAnswer));
        assert_eq!(d.counts().re_requests, 2);
    }

    #[test]
    fn others_values_unasked_changes_and_repeats_are_told_apart() {
        let mut d = download();
        let mut out = Vec::new();
        d.poll(0, &mut out);
        d.on_message(VEHICLE, &value(0, 3), 37, MS, &mut out);
        // Another component of the system, once the autopilot answered.
        d.on_message(SysComp::new(1, 100), &value(1, 3), 37, MS, &mut out);
        d.on_message(VEHICLE, &value(UNASKED, 3), 37, MS, &mut out);
        d.on_message(VEHICLE, &value(0, 3), 37, MS, &mut out);
        assert_eq!(d.progress().done(), 1);
        assert_eq!(d.counts().duplicates, 1);
        assert_eq!(d.progress().figures(MS).frames, 3);
    }
}
