//! One download, as every protocol runs it ([`Protocol`]) and as it is
//! reported when it ends ([`AttemptFigures`]).

use serde::Serialize;

use super::progress::{Progress, ProgressFigures};
use crate::engine::Nanos;
use crate::frame::{SysComp, Transfer};

/// How a download ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub(crate) enum Ending {
    /// Everything arrived.
    Complete,
    /// The opening request was never answered.
    NoAnswer,
    /// Answers came, then stopped, and asking again brought no more.
    Stalled,
    /// The target refused it (a NAK, a MISSION_ACK with an error).
    Refused,
    /// The run ended first (its deadline, Ctrl-C, the link).
    Cut,
}

/// A protocol's own counts, beside its [`Progress`].
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize)]
pub(crate) struct Counts {
    /// Requests put on the wire, re-sends included.
    pub(crate) requests: u64,
    /// Units that came without being asked for again: the list's first
    /// pass, items and blocks answered at their first request.
    pub(crate) first_pass: u64,
    /// Requests sent again, or sent for what the first pass missed.
    pub(crate) re_requests: u64,
    /// Of those, how many brought what they asked for.
    pub(crate) re_requests_answered: u64,
    /// Units that came again after they had arrived.
    pub(crate) duplicates: u64,
    /// Pieces given up after their last re-send.
    pub(crate) given_up: u64,
}

/// One download protocol's bookkeeping: pure, time passed in, requests
/// handed out to send.
pub(crate) trait Protocol: std::fmt::Debug {
    /// Puts what is due at `now` in `out` (the opening request, re-sends)
    /// and decides what ran out of time.
    fn poll(&mut self, now: Nanos, out: &mut Vec<Transfer>);
    /// A transfer message from `from`, `bytes` long on the wire.
    fn on_message(
        &mut self,
        from: SysComp,
        msg: &Transfer,
        bytes: u16,
        now: Nanos,
        out: &mut Vec<Transfer>,
    );
    /// When something next runs out of time.
    fn next_deadline(&self) -> Option<Nanos>;
    /// How it ended, once it has.
    fn ending(&self) -> Option<Ending>;
    /// Why it ended as it did, in words, when the protocol knows more
    /// than its ending says (a NAK's error, where the list stopped).
    fn reason(&self) -> Option<String>;
    /// Where a list stopped coming by itself, when what should have
    /// followed never came with it: the last unit it brought.
    fn stopped_after(&self) -> Option<u64> {
        None
    }
    fn progress(&self) -> &Progress;
    fn counts(&self) -> Counts;
    /// Who answered.
    fn responder(&self) -> Option<SysComp>;
    /// The run is ending: what is sent to close it (an FTP session's
    /// end), if anything.
    fn close(&mut self, _out: &mut Vec<Transfer>) {}
}

/// One download's figures: the `transfer` JSON line, a line of text.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(tag = "type", rename = "transfer")]
pub(crate) struct AttemptFigures {
    /// 1 for the first download of the run.
    pub(crate) attempt: u32,
    pub(crate) responder: Option<SysComp>,
    pub(crate) ending: Ending,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(crate) reason: Option<String>,
    /// The list stopped after this index, the rest never coming with it.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(crate) stopped_after: Option<u64>,
    pub(crate) unit: &'static str,
    #[serde(flatten)]
    pub(crate) progress: ProgressFigures,
    #[serde(flatten)]
    pub(crate) counts: Counts,
    /// What the first pass left out (total less first pass).
    pub(crate) missing_first_pass: Option<u64>,
    /// On a link with a baud rate (serial, `sim:?baud=`): the least time
    /// the target's frames of the download take on the wire, start and
    /// stop bits counted.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(crate) wire_floor_ms: Option<f64>,
    pub(crate) duration_ms: f64,
}

impl crate::engine::kind::KindValue for AttemptFigures {
    fn serialized(&self) -> Option<&dyn erased_serde::Serialize> {
        Some(self)
    }
}

/// `protocol`'s figures as attempt `attempt`, begun at `started`, ended
/// at `now` (`ending` if the protocol had not ended by itself).
pub(crate) fn figures_of(
    protocol: &dyn Protocol,
    attempt: u32,
    started: Nanos,
    now: Nanos,
) -> AttemptFigures {
    let progress = protocol.progress().figures(now);
    let counts = protocol.counts();
    AttemptFigures {
        attempt,
        responder: protocol.responder(),
        ending: protocol.ending().unwrap_or(Ending::Cut),
        reason: protocol.reason(),
        stopped_after: protocol.stopped_after(),
        unit: "",
        missing_first_pass: progress.total.map(|t| t.saturating_sub(counts.first_pass)),
        wire_floor_ms: None,
        progress,
        counts,
        duration_ms: now.saturating_sub(started) as f64 / 1e6,
    }
}

/// Whom a download asks, and who answers: the target, or, when it names
/// no component, the first of its system's to answer (kept after).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Peer {
    target: SysComp,
    answered_by: Option<SysComp>,
}

impl Peer {
    pub(crate) fn new(target: SysComp) -> Self {
        Peer {
            target,
            answered_by: None,
        }
    }

    /// Whether a frame from `from` is the target's (the first that is
    /// fixes the component).
    pub(crate) fn accepts(&mut self, from: SysComp) -> bool {
        if let Some(r) = self.answered_by {
            return r == from;
        }
        let ok = from.sysid == self.target.sysid
            && (self.target.compid == 0 || from.compid == self.target.compid);
        if ok {
            self.answered_by = Some(from);
        }
        ok
    }

    /// Where requests go: to whoever answered, else the target.
    pub(crate) fn to(&self) -> crate::frame::transfer::Target {
        let to = self.answered_by.unwrap_or(self.target);
        crate::frame::transfer::Target {
            system: to.sysid,
            component: to.compid,
        }
    }

    pub(crate) fn responder(&self) -> Option<SysComp> {
        self.answered_by
    }
}
