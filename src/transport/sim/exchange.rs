//! One request's exchange with one simulated responder: whether it hears
//! the request (`loss_up=`, `dup_up=`), the fate of each reply it sends
//! (`loss=`, `spike=`, `reorder=`, `dup=` and the per-direction faults),
//! and the ground truth of what the link did to them.

use std::time::Duration;

use tokio::time::Instant;

use super::deliveries::{Copies, Payload};
use super::link::SimLink;
use super::outgoing::{Reply, Sends};
use crate::frame::{self, Frame, Header, Msg};

/// When the copies of a frame were heard, past the first's arrival:
/// none, the first, or both.
fn heard_at(heard: &Heard) -> [Option<Duration>; 2] {
    match heard {
        Heard::Lost => [None, None],
        Heard::Once => [Some(Duration::ZERO), None],
        Heard::Twice(later) => [Some(Duration::ZERO), Some(*later)],
    }
}

/// How a frame we sent reached one responder.
enum Heard {
    Lost,
    Once,
    /// Twice (`dup_up=`): the copy this much later.
    Twice(Duration),
}

/// A reply's fate, drawn when its request was sent: when it arrives,
/// whether a spike delayed it, and when an extra copy of it follows.
#[derive(Clone, Copy)]
struct ReplyDraw {
    at: Instant,
    spiked: bool,
    again: Option<Instant>,
}

impl SimLink {
    /// Whether responder `i` hears a frame mavping sent: lost on the way
    /// (`loss_up=`), or heard twice (`dup_up=`), drawn for each responder;
    /// counted.
    fn heard_by(&mut self, i: usize) -> Heard {
        let lost = self.vehicle_chance(self.params.loss_up);
        let up = &mut self.responders[i].truth.up;
        up.sent += 1;
        up.dropped += u64::from(lost);
        if lost {
            return Heard::Lost;
        }
        // Drawn only when asked for, so seeds keep their other faults.
        if !self.vehicle_chance(self.params.dup_up) {
            return Heard::Once;
        }
        // The copy comes one more leg behind, as a `dup_down=` copy does.
        let later = self.vehicle_one_way();
        self.responders[i].truth.up.duplicated += 1;
        Heard::Twice(later)
    }

    /// Responder `i` and `request`, sent at `now` and through the link's
    /// wire (or radios) at `sent_done`: the replies it sends, each copy of
    /// the request answered when it arrives, scheduled to be numbered.
    pub(super) fn exchange(&mut self, i: usize, request: &Frame, now: Instant, sent_done: Instant) {
        let heard = self.heard_by(i);
        let Some(reply) = self.responders[i].core.answer(request, 0) else {
            if matches!(request.msg, Msg::Transfer(_)) {
                self.transfer_heard(i, request, heard_at(&heard), now, sent_done);
            }
            return;
        };
        let r = &mut self.responders[i];
        r.truth.answered += 1;
        let again = match heard {
            Heard::Lost => {
                r.truth.dropped(r.replied);
                r.truth.up.requests_dropped += 1;
                return;
            }
            Heard::Once => None,
            Heard::Twice(later) => {
                r.truth.up.requests_duplicated += 1;
                Some(later)
            }
        };
        if self.in_outage(now) {
            let r = &mut self.responders[i];
            r.truth.dropped(r.replied);
            r.truth.outage += 1;
            return;
        }
        // Loss is drawn once per exchange: request or reply leg. The reply
        // is not sent, so not numbered: no gap in the responder's sequence
        // (for one, `loss_down=`).
        if self.chance(self.params.loss) {
            let r = &mut self.responders[i];
            r.truth.dropped(r.replied);
            return;
        }
        let up = self.one_way() + self.queued_up(now);
        let version = request.version;
        let mut draws = [None, None];
        let mut replies = [None, None];
        // When the responder sends each reply: once it has the request.
        let mut sends = [now; 2];
        let mut overflowed = false;
        for (k, extra) in [Some(Duration::ZERO), again].into_iter().enumerate() {
            let Some(extra) = extra else { continue };
            let msg = self.stamped(reply, sent_done, now, up + extra);
            // The reply's length: its header is written when it is sent.
            let mut out = Vec::new();
            let header = Header {
                sysid: 0,
                compid: 0,
                seq: 0,
            };
            frame::encode(&mut out, version, header, &msg);
            match self.downlink(sent_done + extra, up, out.len()) {
                Some(reply_done) => draws[k] = self.draw_reply(reply_done),
                None => overflowed = true,
            }
            // Sent (and numbered) once the responder has the request.
            sends[k] = sent_done + extra + up;
            replies[k] = Some((msg, self.ns(sends[k])));
        }
        let copies = self.reply_copies(i, draws, sends, overflowed);
        for (reply, copies) in replies.into_iter().zip(copies) {
            if let Some((msg, ns)) = reply {
                let reply = Reply {
                    msg,
                    version,
                    copies,
                };
                self.schedule(ns, i, Sends::Reply(Box::new(reply)));
            }
        }
    }

    /// A TIMESYNC reply reads the responder's clock when the request
    /// arrives, `up` after we sent it: that is what makes the NTP offset
    /// estimate unbiased. Other replies are as they are.
    fn stamped(&self, mut reply: Msg, sent_done: Instant, now: Instant, up: Duration) -> Msg {
        if let Msg::Timesync { tc1, .. } = &mut reply {
            // Through a radio pair the request arrives once it is through
            // the air.
            let read_at = if self.pair.is_some() { sent_done } else { now };
            *tc1 = self.clock_ns(read_at + up);
        }
        reply
    }

    /// Where a reply that has left the wire (or radios) at `reply_done`
    /// arrives, or `None`: lost on the way down.
    fn draw_reply(&mut self, reply_done: Instant) -> Option<ReplyDraw> {
        let mut at = reply_done + self.queued_down(reply_done) + self.one_way();
        // Drawn only when asked for, so seeds keep their faults.
        let spiked = self.chance(self.params.spike);
        if spiked {
            at += self.params.spike_delay;
        }
        let held = self.chance(self.params.reorder);
        // The responder's own faults: their own draws.
        let held_down = self.vehicle_chance(self.params.reorder_down);
        if held || held_down {
            at += self.params.hold;
        }
        let again = if self.chance(self.params.dup) {
            Some(at + self.one_way())
        } else if self.vehicle_chance(self.params.dup_down) {
            Some(at + self.vehicle_one_way())
        } else {
            None
        };
        if self.vehicle_chance(self.params.loss_down) {
            return None;
        }
        Some(ReplyDraw { at, spiked, again })
    }

    /// The exchange's truth from the fates of its replies (two when the
    /// request was heard twice), each sent at its `sent` and spread onto
    /// the paths: lost when no copy goes; else the first copy to arrive is
    /// its reply, and every other copy on its way a duplicate.
    fn reply_copies(
        &mut self,
        i: usize,
        draws: [Option<ReplyDraw>; 2],
        sent: [Instant; 2],
        overflowed: bool,
    ) -> [Option<Copies>; 2] {
        let mut out = [None, None];
        for (k, draw) in draws.iter().enumerate() {
            let Some(d) = draw else { continue };
            let mut copies = Copies::one(d.at, Payload::Plain);
            if let Some(again) = d.again {
                copies.push(again, Payload::Plain, 0);
            }
            let copies = self.on_paths(i, sent[k], &copies);
            out[k] = (!copies.as_slice().is_empty()).then_some(copies);
        }
        // On a tie the earlier reply's first copy: a reply's extra copy
        // comes after it.
        let first = out
            .iter()
            .enumerate()
            .filter_map(|(k, c)| c.as_ref().map(|c| (k, c)))
            .flat_map(|(k, c)| (0..).zip(c.as_slice()).map(move |(j, a)| (a.at, k, j)))
            .min()
            .map(|(_, k, j)| (k, j));
        let r = &mut self.responders[i];
        let Some(first) = first else {
            r.truth.dropped(r.replied);
            r.truth.overflowed += u64::from(overflowed);
            return [None, None];
        };
        r.replied = true;
        for (k, copies) in out.iter_mut().enumerate() {
            let Some(copies) = copies else { continue };
            let spiked = draws[k].is_some_and(|d| d.spiked);
            for (j, copy) in (0..).zip(copies.as_mut_slice()) {
                copy.payload = if (k, j) != first {
                    r.truth.duplicated += 1;
                    Payload::Duplicate(i)
                } else if spiked {
                    r.truth.spiked += 1;
                    Payload::Spiked(i)
                } else {
                    r.truth.delivered += 1;
                    Payload::Plain
                };
            }
        }
        out
    }
}
