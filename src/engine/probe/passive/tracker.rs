//! Loss accounting from the 8-bit packet sequence every MAVLink sender
//! puts in its frames: per source, exact where the sequence proves it,
//! and honest where it cannot.
//!
//! Pure and synchronous: each frame comes with its arrival time as
//! [`Nanos`]; nothing here reads a clock or does I/O. Memory is constant
//! for a run of any length (fixed bitmaps, capped lists and maps).
//!
//! Rules, per source (a [`SeqTracker`]):
//! - **Window.** A frame `k` ahead of the last one (the *head*), for `k` in
//!   1..=127, is new: the `k - 1` numbers skipped are **lost**, and it
//!   becomes the head. A frame 0..=127 behind the head is looked up in a
//!   256-bit bitmap of the numbers seen: seen before, it is a
//!   **duplicate**; not seen, it fills a gap: one frame moves from lost to
//!   **reordered**. A frame behind the first one of the run (still within
//!   127) fills the numbers between as lost and counts as reordered, so a
//!   run that starts on a swapped pair counts 0 lost.
//! - **Far behind.** A frame exactly 128 away is ahead and behind at once;
//!   the tracker **resynchronises** on it (it becomes the head, nothing is
//!   counted lost, `resyncs` counts it). Every other distance falls in the
//!   window, so a source restarting without a pause shows as a gap or as
//!   duplicates: the sequence alone cannot tell.
//! - **Far frames wait.** A frame more than 32 (`REACH`) from the head either
//!   way waits for the next frame: back within reach of the head, the far
//!   one was another sender's (below); anything else, the counter moved
//!   there (a burst of losses, or a restart).
//! - **A second counter.** Frames another sender numbered under the same
//!   ids (QGroundControl's REQUEST_DATA_STREAM, numbered 1 to 7 over and
//!   over between its MANUAL_CONTROL frames) are read on their own
//!   counter: steps ahead count as anywhere, a step back restarts it. Its
//!   figures join the source's once it has numbered 3 frames;
//!   fewer are stray frames, received and nothing else.
//! - **Usual interval and routine pause** ([`super::rate`]): the time per
//!   sequence step over the source's last one to five seconds, in whole
//!   seconds of its own time (a logger's batches a second apart, whole-ms
//!   stamps and start-up bursts cannot bend it), and the longest pause it
//!   makes in a second, as a rule.
//! - **Silence.** No frame from the source for longer than the threshold:
//!   the `gap` given, or else 5 usual intervals but at least 1 s (5 s while
//!   no interval is known: 5 heartbeats), and never under 1.5 routine
//!   pauses. Once a second sets the usual interval, a gap of 64 of them is
//!   a silence (routine pauses aside), so a fast source's outage cannot
//!   hide in the window. A silence is listed with its start (the last
//!   frame before it), its length (to the frame after it) and the frames
//!   the source would have sent in it at its settled rate.
//! - **Across a silence** the sequence proves at least its gap, modulo
//!   256: always counted lost (`seq_lost`). Where the silence holds 128
//!   frames or more at the settled rate, wraps may hide in it: the likely
//!   number (`lost_estimated`, the gap plus the wraps nearest the rate) is
//!   said, and the wraps go to `silence_frames_estimated`, never to
//!   `lost`. No number missing: delayed, nothing lost. A counter starting
//!   again at 0 after a silence it cannot span: a restart, nothing lost.
//!   No frame from before a silence fills a gap after it.
//! - A silence still on when the summary is taken is listed as `ongoing`,
//!   with nothing lost in it yet.
//! - **Damaged frames** ([`SeqTracker::on_damaged`]) take their number as
//!   a frame does and are counted apart, never as lost.
//! - **pymavlink's figure**, beside ours and labelled: as
//!   `mavutil.post_message` computes it, `expected = (last + 1) % 256`, on
//!   a mismatch `loss += (seq - expected) % 256`, every frame counted, loss
//!   % = loss / (count + loss). A duplicate costs it 255, a swap 256, and
//!   a silence whatever its length is modulo 256.
//!
//! A [`SourceTable`] keeps one tracker per (sysid, compid), up to a cap
//! (frames of sources beyond it are counted, not tracked), with the SiK
//! radio's injected RADIO_STATUS (source 51/68, "3D") kept apart: tracked
//! and flagged as a radio, but out of the link's totals, as pymavlink
//! leaves it out of its own. In a log, sources marked as the ground
//! station's own ([`SourceTable::set_ground`]) are out of the totals too.

use super::rate::Rate;
use crate::engine::radio::is_radio_ids;
use crate::engine::summary::passive::{
    percent, LinkTotals, MsgCount, PymavFigure, SecondCounter, SeqCounts, Silence, SourceSummary,
    TableSummary, Untracked,
};
use crate::engine::Nanos;
use crate::frame::SysComp;

/// How far ahead or behind the head a frame is still read as part of the
/// same stream (half the sequence space, less the ambiguous middle).
const WINDOW: u8 = 127;
/// The silence threshold is this many usual intervals...
const SILENCE_INTERVALS: u64 = 5;
/// ...but at least this long: shorter pauses are a bursty source's rhythm,
/// not silences.
const SILENCE_FLOOR: Nanos = 1_000_000_000;
/// The usual interval assumed before the source shows its own: HEARTBEAT's
/// period, which every component keeps.
const FIRST_INTERVAL: Nanos = 1_000_000_000;
/// A gap of this many usual intervals is a silence whatever the threshold.
const SILENCE_CAP_INTERVALS: u64 = 64;
/// A silence shorter than this many frames at the usual rate is spanned by
/// the sequence (half of 256: room for a rate estimate off by 2x).
const SPAN_FRAMES: u64 = 128;
/// Frames this far ahead of or behind a counter's head are read at once;
/// farther ones wait for the next frame ([`SeqTracker::route`]). Past
/// any short loss burst or reorder a link makes, and short of the
/// distances two interleaved counters drift apart by.
const REACH: u8 = 32;
/// A pause longer than 3/2 of the routine pause (in halves: 3) may be a
/// silence: the batches of a logger a second apart never are.
const ROUTINE_FACTOR_X2: u64 = 3;
/// A silence with no number missing across it may be the source's (or
/// its logger's) rhythm up to this long; a longer one never sets it.
const ROUTINE_MAX: Nanos = 2_000_000_000;
/// Frames a second counter under the same ids must have numbered to be
/// reported as one; fewer are stray frames, received and nothing else.
const SECOND_COUNTER_FRAMES: u64 = 3;
/// Silences listed: the first ones...
const KEEP_FIRST_SILENCES: usize = 8;
/// ...and the longest of the later ones.
const KEEP_LONGEST_SILENCES: usize = 8;
/// Distinct message ids counted per source; later new ids share "other".
const MAX_MSG_IDS: usize = 32;
/// Sources tracked by a [`SourceTable`] unless told otherwise.
pub const DEFAULT_MAX_SOURCES: usize = 32;
/// The SiK radio's injected RADIO_STATUS comes from sysid '3', compid 'D'.
pub(crate) const RADIO_SOURCE: SysComp = SysComp::new(b'3', b'D');

/// Sequence state of the current stretch (since the start or the last
/// resync).
#[derive(Debug, Clone, Copy)]
struct SeqState {
    head: u8,
    /// Arrival of the head frame.
    head_at: Nanos,
    /// Numbers accounted in this stretch, head included (each seen or
    /// lost).
    span: u64,
    /// Bit `n` set: number `n` seen. Valid for numbers in the span within
    /// 127 of the head.
    seen: [u64; 4],
}

/// Where a frame landed in the sequence.
enum Step {
    /// `k` ahead: the new head, `k - 1` lost.
    Ahead(u8),
    Duplicate,
    /// Filled a gap counted lost.
    Filled,
    /// Behind the stretch's first frame: it, and `lost` numbers between.
    BeforeStart {
        lost: u64,
    },
    Resync,
}

impl SeqState {
    fn new(seq: u8, at: Nanos) -> Self {
        let mut s = SeqState {
            head: seq,
            head_at: at,
            span: 1,
            seen: [0; 4],
        };
        s.mark(seq, true);
        s
    }

    fn mark(&mut self, seq: u8, seen: bool) {
        let (word, bit) = (usize::from(seq / 64), seq % 64);
        if seen {
            self.seen[word] |= 1 << bit;
        } else {
            self.seen[word] &= !(1 << bit);
        }
    }

    fn is_seen(&self, seq: u8) -> bool {
        self.seen[usize::from(seq / 64)] & (1 << (seq % 64)) != 0
    }

    fn advance(&mut self, ahead: u8, at: Nanos) {
        for k in 1..ahead {
            self.mark(self.head.wrapping_add(k), false);
        }
        self.head = self.head.wrapping_add(ahead);
        self.mark(self.head, true);
        self.head_at = at;
        self.span += u64::from(ahead);
    }

    /// Numbers counted lost that a late frame may still fill: unseen,
    /// behind the head within the window and the stretch.
    fn pending(&self) -> u64 {
        let reach = self.span.saturating_sub(1).min(u64::from(WINDOW));
        (1..=reach)
            .filter(|&k| !self.is_seen(self.head.wrapping_sub(k as u8)))
            .count() as u64
    }

    fn take(&mut self, seq: u8, at: Nanos) -> Step {
        let ahead = seq.wrapping_sub(self.head);
        if (1..=WINDOW).contains(&ahead) {
            self.advance(ahead, at);
            return Step::Ahead(ahead);
        }
        let behind = self.head.wrapping_sub(seq);
        if behind > WINDOW {
            *self = SeqState::new(seq, at);
            return Step::Resync;
        }
        let span = u8::try_from(self.span).unwrap_or(u8::MAX);
        if behind < span {
            if self.is_seen(seq) {
                return Step::Duplicate;
            }
            self.mark(seq, true);
            return Step::Filled;
        }
        // Behind the first frame of the stretch (span <= behind <= 127):
        // the stretch grows back to it.
        for k in span..behind {
            self.mark(self.head.wrapping_sub(k), false);
        }
        self.mark(seq, true);
        self.span = u64::from(behind) + 1;
        Step::BeforeStart {
            lost: u64::from(behind - span),
        }
    }
}

/// The bounded list of silences: the first few, and the longest of the
/// rest.
#[derive(Debug, Clone, Default)]
struct SilenceLog {
    first: Vec<Silence>,
    longest: Vec<Silence>,
    count: u64,
    omitted: u64,
    total_ns: Nanos,
    /// What the pauses the counter may have wrapped in likely hid beyond
    /// the sequence's gap.
    wraps_estimated: u64,
}

impl SilenceLog {
    fn push(&mut self, s: Silence) {
        self.count += 1;
        self.total_ns = self.total_ns.saturating_add(s.length_ns);
        if let (Some(floor), Some(likely)) = (s.seq_lost, s.lost_estimated) {
            self.wraps_estimated += likely - floor;
        }
        if self.first.len() < KEEP_FIRST_SILENCES {
            self.first.push(s);
        } else if self.longest.len() < KEEP_LONGEST_SILENCES {
            self.longest.push(s);
        } else {
            self.omitted += 1;
            let shortest = self
                .longest
                .iter_mut()
                .min_by_key(|kept| kept.length_ns)
                .expect("the list is full");
            if s.length_ns > shortest.length_ns {
                *shortest = s;
            }
        }
    }
}

/// Exact frame counts for the first `MAX_MSG_IDS` distinct message ids.
#[derive(Debug, Clone, Default)]
struct MsgIds {
    kept: Vec<MsgCount>,
    other: u64,
}

impl MsgIds {
    fn count(&mut self, id: u32) {
        if let Some(m) = self.kept.iter_mut().find(|m| m.id == id) {
            m.count += 1;
        } else if self.kept.len() < MAX_MSG_IDS {
            self.kept.push(MsgCount { id, count: 1 });
        } else {
            self.other += 1;
        }
    }

    /// Every frame counted.
    fn total(&self) -> u64 {
        self.kept.iter().map(|m| m.count).sum::<u64>() + self.other
    }

    fn by_count(&self) -> Vec<MsgCount> {
        let mut v = self.kept.clone();
        v.sort_unstable_by(|a, b| b.count.cmp(&a.count).then(a.id.cmp(&b.id)));
        v
    }
}

/// One source's sequence accounting: see the module's rules.
#[derive(Debug, Clone)]
pub struct SeqTracker {
    gap: Option<Nanos>,
    state: Option<SeqState>,
    /// The main counter's figures.
    counts: SeqCounts,
    /// A second counter under the same ids, once a frame was shown to
    /// belong to neither the main counter's reach nor its gaps.
    second: Option<Counter>,
    /// A frame far from the main counter's head, waiting for the next
    /// frame to say whether the counter jumped there or another sender
    /// numbered it.
    deferred: Option<Deferred>,
    pymav_last: Option<u8>,
    pymav_loss: u64,
    bytes: u64,
    first_len: u64,
    first_seen: Nanos,
    last_seen: Nanos,
    rate: Rate,
    /// The silence threshold and the rate's epoch it was worked out at.
    threshold: (u64, Nanos),
    silences: SilenceLog,
    msg_ids: MsgIds,
    damaged_ids: MsgIds,
    second_ids: MsgIds,
}

/// A frame held back by one frame; see [`SeqTracker::route`].
#[derive(Debug, Clone, Copy)]
struct Deferred {
    seq: u8,
    msg_id: u32,
    at: Nanos,
    damaged: bool,
}

/// A second sender's counter under the same ids.
#[derive(Debug, Clone)]
struct Counter {
    state: SeqState,
    counts: SeqCounts,
}

impl Counter {
    /// `seq` is within [`REACH`] of its head, either way.
    fn near(&self, seq: u8) -> bool {
        near(&self.state, seq)
    }
}

fn near(state: &SeqState, seq: u8) -> bool {
    let ahead = seq.wrapping_sub(state.head);
    (1..=REACH).contains(&ahead) || state.head.wrapping_sub(seq) <= REACH
}

/// A frame received whole, or one whose CRC failed with its header whole.
fn tally(counts: &mut SeqCounts, damaged: bool) {
    if damaged {
        counts.damaged += 1;
    } else {
        counts.received += 1;
    }
}

/// Counts where a frame landed in a counter's sequence; the steps ahead,
/// for the rate.
fn count_step(counts: &mut SeqCounts, step: Step) -> Option<u64> {
    match step {
        Step::Ahead(k) => {
            counts.lost += u64::from(k - 1);
            return Some(u64::from(k));
        }
        Step::Duplicate => counts.duplicate += 1,
        Step::Filled => {
            counts.lost -= 1;
            counts.reordered += 1;
        }
        Step::BeforeStart { lost } => {
            counts.lost += lost;
            counts.reordered += 1;
        }
        Step::Resync => counts.resyncs += 1,
    }
    None
}

impl SeqTracker {
    /// A tracker whose silences are gaps longer than `gap`, or, with
    /// `None`, than the default threshold (module docs).
    pub(crate) fn new(gap: Option<Nanos>) -> Self {
        SeqTracker {
            gap,
            state: None,
            counts: SeqCounts::default(),
            second: None,
            deferred: None,
            pymav_last: None,
            pymav_loss: 0,
            bytes: 0,
            first_len: 0,
            first_seen: 0,
            last_seen: 0,
            rate: Rate::new(0),
            threshold: (u64::MAX, 0),
            silences: SilenceLog::default(),
            msg_ids: MsgIds::default(),
            damaged_ids: MsgIds::default(),
            second_ids: MsgIds::default(),
        }
    }

    /// Takes one frame: its header sequence, message id, length on the
    /// wire and arrival time (not earlier than the previous frame's).
    pub(crate) fn on_frame(&mut self, seq: u8, msg_id: u32, len_bytes: usize, at: Nanos) {
        self.msg_ids.count(msg_id);
        self.pymav(seq);
        self.take(seq, msg_id, len_bytes, at, false);
    }

    /// Takes a frame whose CRC failed but whose header is whole: it
    /// arrived, damaged (or in a dialect whose CRC differs), so it fills
    /// its number and is counted apart. pymavlink never sees it.
    pub(crate) fn on_damaged(&mut self, seq: u8, msg_id: u32, len_bytes: usize, at: Nanos) {
        self.damaged_ids.count(msg_id);
        self.take(seq, msg_id, len_bytes, at, true);
    }

    fn take(&mut self, seq: u8, msg_id: u32, len_bytes: usize, at: Nanos, damaged: bool) {
        let len = u64::try_from(len_bytes).unwrap_or(u64::MAX);
        self.bytes = self.bytes.saturating_add(len);
        let threshold = self.cached_threshold();
        if self.state.is_none() {
            self.state = Some(SeqState::new(seq, at));
            tally(&mut self.counts, damaged);
            self.rate = Rate::new(at);
            self.first_len = len;
            self.first_seen = at;
            self.last_seen = at;
            return;
        }
        let elapsed = at.saturating_sub(self.last_seen);
        self.last_seen = self.last_seen.max(at);
        if elapsed > threshold {
            self.flush();
            tally(&mut self.counts, damaged);
            self.end_silence(seq, at, elapsed);
            return;
        }
        self.rate.pause(elapsed);
        if let Some(d) = self.deferred.take() {
            self.resolve(d, seq);
        } else if self.second.is_none() {
            // Most frames: the next number, or near it, of the one counter.
            let state = self.state.as_ref().expect("a frame was taken");
            if near(state, seq) {
                return self.main_takes(Deferred {
                    seq,
                    msg_id,
                    at,
                    damaged,
                });
            }
        }
        self.route(Deferred {
            seq,
            msg_id,
            at,
            damaged,
        });
    }

    /// A frame within reach of the main counter's head is its; one that
    /// continues the second counter is that one's; any other waits for the
    /// next frame ([`Self::resolve`]). Without the wait, another sender's
    /// frame under the same ids (QGroundControl's REQUEST_DATA_STREAM,
    /// numbered 1 to 7 between its MANUAL_CONTROL frames) read as a jump
    /// of the main counter: a hundred lost, then a hundred reordered.
    fn route(&mut self, f: Deferred) {
        let state = self.state.as_ref().expect("a frame was taken");
        let ahead = f.seq.wrapping_sub(state.head);
        let behind = state.head.wrapping_sub(f.seq);
        let second = self.second.as_ref().is_some_and(|c| c.near(f.seq));
        match (second, near(state, f.seq)) {
            // The main counter's next number, or a near one nothing else
            // claims.
            (false, true) => self.main_takes(f),
            (true, true) if ahead == 1 => self.main_takes(f),
            // Behind the main head but going on from the second's: the
            // second sender's.
            (true, true) if behind <= REACH => self.second_takes(f),
            (true, false) => self.second_takes(f),
            _ => self.deferred = Some(f),
        }
    }

    /// The frame after a deferred one: back within reach of the main
    /// counter's head, the deferred frame was another sender's; anything
    /// else, the main counter moved there (a burst of losses, a restart).
    fn resolve(&mut self, d: Deferred, next: u8) {
        let state = self.state.as_ref().expect("a frame was taken");
        let jumped = (1..=WINDOW).contains(&d.seq.wrapping_sub(state.head))
            && (1..=REACH).contains(&next.wrapping_sub(d.seq));
        if !jumped && near(state, next) {
            self.second_takes(d);
        } else {
            self.main_takes(d);
        }
    }

    /// Settles a deferred frame with no next frame to judge it by (a
    /// silence followed it): ahead, the main counter jumped there; behind,
    /// it is stray, as nothing may fill a gap once a silence was told.
    fn flush(&mut self) {
        let Some(d) = self.deferred.take() else {
            return;
        };
        let head = self.state.as_ref().expect("a frame was taken").head;
        if d.seq.wrapping_sub(head) <= WINDOW + 1 {
            self.main_takes(d);
        } else {
            self.second_takes(d);
        }
    }

    fn main_takes(&mut self, f: Deferred) {
        let state = self.state.as_mut().expect("a frame was taken");
        tally(&mut self.counts, f.damaged);
        let step = state.take(f.seq, f.at);
        let resync = matches!(step, Step::Resync);
        if let Some(k) = count_step(&mut self.counts, step) {
            self.rate.step(k, f.at);
        }
        if resync {
            self.rate.rebase(f.at);
        }
    }

    fn second_takes(&mut self, f: Deferred) {
        if !f.damaged {
            self.second_ids.count(f.msg_id);
        }
        match &mut self.second {
            // Ahead, a step; anything else, the counter starting again: a
            // second sender's counter seen so far (QGroundControl's
            // REQUEST_DATA_STREAM) numbers each round of requests from 1.
            Some(c) => {
                tally(&mut c.counts, f.damaged);
                let ahead = f.seq.wrapping_sub(c.state.head);
                if (1..=REACH).contains(&ahead) {
                    let step = c.state.take(f.seq, f.at);
                    count_step(&mut c.counts, step);
                } else {
                    c.state = SeqState::new(f.seq, f.at);
                    c.counts.resyncs += 1;
                }
            }
            None => {
                let mut counts = SeqCounts::default();
                tally(&mut counts, f.damaged);
                self.second = Some(Counter {
                    state: SeqState::new(f.seq, f.at),
                    counts,
                });
            }
        }
    }

    /// The first frame after a silence of `elapsed`: what the sequence
    /// proves across it, and what the rate suggests it hid.
    fn end_silence(&mut self, seq: u8, at: Nanos, elapsed: Nanos) {
        let state = self.state.as_mut().expect("a frame was taken");
        // Only a settled rate says anything of a pause: before a second is
        // in, a logger's first batch (140 frames on a few stamps) would
        // make a pause of a second hold hundreds.
        let frames = self
            .rate
            .interval()
            .filter(|_| self.rate.settled())
            .map(|i| frames_in(elapsed, i));
        let ahead = seq.wrapping_sub(state.head);
        let mut silence = Silence {
            start: at - elapsed,
            length_ns: elapsed,
            frames_estimated: frames,
            seq_lost: None,
            lost_estimated: None,
            restart: false,
            ongoing: false,
        };
        // A counter that starts again at 0 after a pause: the source
        // restarted (ArduPilot's SITL rebooting in flight_logs.tlog), and
        // its gap is no loss.
        let spanned = frames.is_some_and(|f| f < SPAN_FRAMES) && (1..=WINDOW).contains(&ahead);
        if seq == 0 && ahead != 1 && !spanned {
            silence.restart = true;
            self.silences.push(silence);
            *state = SeqState::new(seq, at);
            self.counts.resyncs += 1;
            self.rate.rebase(at);
            return;
        }
        // At least the sequence's gap was numbered and not heard, whatever
        // the pause hid besides.
        let floor = u64::from(ahead.wrapping_sub(1));
        silence.seq_lost = Some(floor);
        // No number missing is what a pause that lost nothing shows every
        // time, and a loss of exactly 256 k frames once in 256: delayed.
        if !spanned && floor > 0 {
            silence.lost_estimated = frames.map(|f| nearest_wrap(floor, f));
        }
        self.silences.push(silence);
        self.counts.lost += floor;
        // Nothing before the silence may fill a gap any more (the silence
        // was told with nothing pending); the gap across it may.
        if ahead == 0 {
            *state = SeqState::new(seq, at);
        } else {
            state.seen = [u64::MAX; 4];
            state.advance(ahead, at);
        }
        if floor == 0 && elapsed < ROUTINE_MAX {
            // Nothing missing, and short: the source's rhythm (a logger's
            // batches, told as silences before their rhythm was known).
            self.rate.pause(elapsed);
        }
        if spanned || floor == 0 {
            // The sequence proves the steps in it: steps like any other.
            // (Left out, a window of bursts would lose the pauses between.)
            self.rate.step(u64::from(ahead), at);
        } else {
            self.rate.skip(at);
        }
    }

    /// pymavlink's `post_message` accounting, to the letter.
    fn pymav(&mut self, seq: u8) {
        if let Some(last) = self.pymav_last {
            let expected = last.wrapping_add(1);
            if seq != expected {
                // u8 wrapping subtraction is Python's non-negative `% 256`.
                self.pymav_loss += u64::from(seq.wrapping_sub(expected));
            }
        }
        self.pymav_last = Some(seq);
    }

    /// [`Self::threshold`], worked out again only when the rate moved: it
    /// is asked for at every frame.
    fn cached_threshold(&mut self) -> Nanos {
        let epoch = self.rate.epoch();
        if self.threshold.0 != epoch {
            self.threshold = (epoch, self.threshold());
        }
        self.threshold.1
    }

    /// How long a pause must last to be a silence: see [`threshold`]; the
    /// cap waits for the usual interval to be settled, and without a
    /// `gap` given, a pause the source makes routinely is never one.
    fn threshold(&self) -> Nanos {
        let interval = self.rate.interval();
        let settled = interval.filter(|_| self.rate.settled());
        let t = threshold(self.gap, interval, settled);
        match (self.gap, self.rate.routine_pause()) {
            (None, Some(routine)) => t.max(routine.saturating_mul(ROUTINE_FACTOR_X2) / 2),
            _ => t,
        }
    }

    /// The figures as a summary taken now reports them: a deferred frame
    /// has not been placed by the next one yet, so it is received and
    /// nothing else (taken as the main counter's, a loss shown now could
    /// go again).
    fn settled_now(&self) -> std::borrow::Cow<'_, SeqTracker> {
        let Some(d) = self.deferred else {
            return std::borrow::Cow::Borrowed(self);
        };
        let mut t = self.clone();
        t.deferred = None;
        tally(&mut t.counts, d.damaged);
        std::borrow::Cow::Owned(t)
    }

    /// The source's counts: every counter's, and the frames of a second
    /// counter too small to be one.
    pub(crate) fn counts(&self) -> SeqCounts {
        let t = self.settled_now();
        match &t.second {
            Some(c) if c.counts.received + c.counts.damaged >= SECOND_COUNTER_FRAMES => {
                t.counts.plus(&c.counts)
            }
            Some(c) => SeqCounts {
                received: t.counts.received + c.counts.received,
                damaged: t.counts.damaged + c.counts.damaged,
                ..t.counts
            },
            None => t.counts,
        }
    }

    /// A second sender's counter, once it has numbered enough frames to
    /// be one.
    fn second_counter(&self) -> Option<SecondCounter> {
        let c = self.second.as_ref()?;
        (c.counts.received + c.counts.damaged >= SECOND_COUNTER_FRAMES).then(|| SecondCounter {
            counts: c.counts,
            msg_ids: self.second_ids.by_count(),
        })
    }

    /// pymavlink's figure for this source alone.
    pub(crate) fn pymav_figure(&self) -> PymavFigure {
        PymavFigure::new(self.msg_ids.total(), self.pymav_loss)
    }

    #[cfg(test)]
    /// The usual time per sequence step, once known.
    pub(crate) fn interval(&self) -> Option<Nanos> {
        self.rate.interval()
    }

    /// The silence running at `at`, if the source has been quiet for
    /// longer than the threshold.
    fn ongoing(&self, at: Nanos) -> Option<Silence> {
        self.state?;
        let elapsed = at.saturating_sub(self.last_seen);
        (elapsed > self.threshold()).then(|| Silence {
            start: self.last_seen,
            length_ns: elapsed,
            frames_estimated: self.rate.interval().map(|i| frames_in(elapsed, i)),
            seq_lost: None,
            lost_estimated: None,
            restart: false,
            ongoing: true,
        })
    }

    /// The figures as of `at` (the end of the run, or now): a silence
    /// still on then is included.
    pub(crate) fn summary(&self, source: SysComp, at: Nanos) -> SourceSummary {
        let t = self.settled_now();
        let mut silences: Vec<Silence> = t
            .silences
            .first
            .iter()
            .chain(&t.silences.longest)
            .copied()
            .collect();
        silences.sort_by_key(|s| s.start);
        let mut log_count = t.silences.count;
        let mut silence_ns = t.silences.total_ns;
        // After a silence no frame can fill a gap (the next one advances or
        // resynchronises), so nothing is pending in one.
        let second_pending = t
            .second
            .as_ref()
            .filter(|c| c.counts.received + c.counts.damaged >= SECOND_COUNTER_FRAMES)
            .map_or(0, |c| c.state.pending());
        let mut lost_pending = t.state.map_or(0, |s| s.pending()) + second_pending;
        if let Some(s) = t.ongoing(at) {
            lost_pending = 0;
            log_count += 1;
            silence_ns = silence_ns.saturating_add(s.length_ns);
            silences.push(s);
        }
        let c = t.counts();
        let span = t.last_seen - t.first_seen;
        let arrived = c.received + c.damaged;
        SourceSummary {
            source,
            radio: is_radio_ids(source),
            ground: false,
            counts: c,
            loss_pct: percent(c.lost, c.numbered()),
            lost_pending,
            pymav: t.pymav_figure(),
            bytes: t.bytes,
            first_seen: t.first_seen,
            last_seen: t.last_seen,
            frames_per_s: per_second(arrived.saturating_sub(1), span),
            bytes_per_s: per_second(t.bytes.saturating_sub(t.first_len), span),
            interval_ns: t.rate.interval(),
            routine_pause_ns: t.rate.routine_pause(),
            silences,
            silence_count: log_count,
            silences_omitted: t.silences.omitted,
            silence_ns,
            silence_frames_estimated: t.silences.wraps_estimated,
            msg_ids: t.msg_ids.by_count(),
            msg_ids_other: t.msg_ids.other,
            damaged_ids: t.damaged_ids.by_count(),
            second_counter: t.second_counter(),
        }
    }
}

/// `floor + 256 k`, for the `k >= 0` nearest to `frames`: the frames a
/// pause the 8-bit counter may have wrapped in most likely numbered.
fn nearest_wrap(floor: u64, frames: u64) -> u64 {
    let wraps = (frames.saturating_sub(floor) + 128) / 256;
    floor + 256 * wraps
}
/// The silence threshold for a source with usual interval `interval`,
/// capped at 64 of `settled` (the interval once a full bucket set it).
fn threshold(gap: Option<Nanos>, interval: Option<Nanos>, settled: Option<Nanos>) -> Nanos {
    let base = gap.unwrap_or_else(|| {
        interval
            .unwrap_or(FIRST_INTERVAL)
            .saturating_mul(SILENCE_INTERVALS)
            .max(SILENCE_FLOOR)
    });
    settled.map_or(base, |i| base.min(i.saturating_mul(SILENCE_CAP_INTERVALS)))
}

/// Frames sent strictly inside a gap of `elapsed` at one per `interval`
/// (rounded; the frame that ends the gap is not one of them).
fn frames_in(elapsed: Nanos, interval: Nanos) -> u64 {
    (elapsed.saturating_add(interval / 2) / interval).saturating_sub(1)
}

/// `amount` per second over `span_ns`; `None` for an empty span. (`f64`
/// is exact for these magnitudes, to well under a ppb.)
fn per_second(amount: u64, span_ns: Nanos) -> Option<f64> {
    (span_ns > 0).then(|| amount as f64 * 1e9 / span_ns as f64)
}

/// One [`SeqTracker`] per source, in constant memory.
#[derive(Debug, Clone)]
pub struct SourceTable {
    gap: Option<Nanos>,
    max_sources: usize,
    /// In the order first heard; at most `max_sources`, so a scan is
    /// short, and the last one found is tried first (most frames come in
    /// runs from one source).
    sources: Vec<(SysComp, SeqTracker)>,
    last: usize,
    /// The SiK radio's source, apart (not against the cap).
    radio: Option<SeqTracker>,
    /// Sources that are the ground station's own frames (a log's).
    ground: Vec<SysComp>,
    untracked: Untracked,
    /// One bit per (sysid, compid): untracked sources already counted.
    untracked_seen: Box<[u64]>,
}

impl SourceTable {
    /// A table tracking up to `max_sources` sources (the radio aside), each
    /// with silences longer than `gap` (or the default threshold).
    pub fn new(gap: Option<Nanos>, max_sources: usize) -> Self {
        SourceTable {
            gap,
            max_sources,
            sources: Vec::new(),
            last: 0,
            radio: None,
            ground: Vec::new(),
            untracked: Untracked::default(),
            untracked_seen: vec![0; 65536 / 64].into_boxed_slice(),
        }
    }

    /// The silence threshold it was made with.
    pub(crate) fn gap(&self) -> Option<Nanos> {
        self.gap
    }

    /// Takes one received frame.
    #[inline]
    pub fn on_frame(&mut self, source: SysComp, seq: u8, msg_id: u32, len_bytes: usize, at: Nanos) {
        if let Some(t) = self.tracker(source, len_bytes) {
            t.on_frame(seq, msg_id, len_bytes, at);
        }
    }

    /// Takes a frame whose CRC failed with its header whole
    /// ([`SeqTracker::on_damaged`]).
    pub(crate) fn on_damaged(
        &mut self,
        source: SysComp,
        seq: u8,
        msg_id: u32,
        len_bytes: usize,
        at: Nanos,
    ) {
        if let Some(t) = self.tracker(source, len_bytes) {
            t.on_damaged(seq, msg_id, len_bytes, at);
        }
    }

    /// Marks `source` as the ground station's own (in a log: frames it
    /// logged as it sent them), out of the link's totals from now on.
    pub(crate) fn set_ground(&mut self, source: SysComp) {
        if self.ground.len() < self.max_sources && !self.ground.contains(&source) {
            self.ground.push(source);
        }
    }

    /// The tracker of `source`, made if there is room; `None` (the frame
    /// counted as untracked) if not.
    fn tracker(&mut self, source: SysComp, len_bytes: usize) -> Option<&mut SeqTracker> {
        let gap = self.gap;
        if source == RADIO_SOURCE {
            return Some(self.radio.get_or_insert_with(|| SeqTracker::new(gap)));
        }
        let found = match self.sources.get(self.last) {
            Some((id, _)) if *id == source => Some(self.last),
            _ => self.sources.iter().position(|(id, _)| *id == source),
        };
        if let Some(i) = found.or_else(|| {
            (self.sources.len() < self.max_sources).then(|| {
                self.sources.push((source, SeqTracker::new(gap)));
                self.sources.len() - 1
            })
        }) {
            self.last = i;
            return Some(&mut self.sources[i].1);
        }
        let i = usize::from(source.sysid) << 8 | usize::from(source.compid);
        let (word, bit) = (i / 64, i % 64);
        if self.untracked_seen[word] & (1 << bit) == 0 {
            self.untracked_seen[word] |= 1 << bit;
            self.untracked.sources += 1;
        }
        self.untracked.frames += 1;
        self.untracked.bytes = self
            .untracked
            .bytes
            .saturating_add(u64::try_from(len_bytes).unwrap_or(u64::MAX));
        None
    }

    /// The tracker of one source, if tracked.
    pub fn source(&self, id: SysComp) -> Option<&SeqTracker> {
        if id == RADIO_SOURCE {
            self.radio.as_ref()
        } else {
            self.sources.iter().find(|(s, _)| *s == id).map(|(_, t)| t)
        }
    }

    /// Everything, as of `at` (the end of the run, or now).
    pub(crate) fn summary(&self, at: Nanos) -> TableSummary {
        let mut sources: Vec<SourceSummary> = self
            .sources
            .iter()
            .map(|(id, t)| SourceSummary {
                ground: self.ground.contains(id),
                ..t.summary(*id, at)
            })
            .collect();
        if let Some(r) = &self.radio {
            sources.push(r.summary(RADIO_SOURCE, at));
        }
        sources.sort_by_key(|s| s.source);
        let totals = LinkTotals::of(&sources);
        TableSummary {
            sources,
            totals,
            untracked: self.untracked,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const MS: Nanos = 1_000_000;
    const S: Nanos = 1_000 * MS;
    const SRC: SysComp = SysComp::new(1, 1);

    fn counts(received: u64, lost: u64, duplicate: u64, reordered: u64, resyncs: u64) -> SeqCounts {
        SeqCounts {
            received,
            damaged: 0,
            lost,
            duplicate,
            reordered,
            resyncs,
        }
    }

    /// Feeds frames given by their position in the source's own stream
    /// (sequence = position mod 256), each sent at position x `interval`
    /// and arriving then (or with the previous frame, if that came later).
    fn feed(t: &mut SeqTracker, positions: &[u64], interval: Nanos) {
        let mut at = 0;
        for &p in positions {
            at = (p * interval).max(at);
            t.on_frame((p % 256) as u8, 0, 20, at);
        }
    }

    fn tracked(positions: &[u64], interval: Nanos) -> SeqTracker {
        let mut t = SeqTracker::new(None);
        feed(&mut t, positions, interval);
        t
    }

    #[test]
    fn an_in_order_stream_loses_nothing() {
        let all: Vec<u64> = (0..100).collect();
        let t = tracked(&all, 20 * MS);
        assert_eq!(t.counts(), counts(100, 0, 0, 0, 0));
        assert_eq!(t.pymav_figure(), PymavFigure::new(100, 0));
        assert_eq!(t.interval(), Some(20 * MS));
        let s = t.summary(SRC, 99 * 20 * MS);
        assert_eq!(s.loss_pct, Some(0.0));
        assert_eq!(s.bytes, 2000);
        assert_eq!(s.frames_per_s, Some(50.0));
        assert_eq!(s.bytes_per_s, Some(1000.0));
        assert!(s.silences.is_empty());
        assert_eq!(s.msg_ids, vec![MsgCount { id: 0, count: 100 }]);
    }

    #[test]
    fn single_gaps_count_exactly() {
        let p: Vec<u64> = (0..50).filter(|p| ![10, 20, 21, 22].contains(p)).collect();
        let t = tracked(&p, 20 * MS);
        assert_eq!(t.counts(), counts(46, 4, 0, 0, 0));
        assert_eq!(t.pymav_figure().loss, 4);
        assert_eq!(t.summary(SRC, 0).loss_pct, Some(8.0));
    }

    #[test]
    fn the_sequence_wraps_many_times() {
        // Five wraps, with gaps across 255 -> 0 and at 0.
        let p: Vec<u64> = (0..1300)
            .filter(|p| ![255, 256, 512, 1023].contains(p))
            .collect();
        let t = tracked(&p, 10 * MS);
        assert_eq!(t.counts(), counts(1296, 4, 0, 0, 0));
        assert_eq!(t.pymav_figure().loss, 4);
    }

    #[test]
    fn a_duplicate_is_one_duplicate_and_costs_pymavlink_255() {
        let t = tracked(&[0, 1, 2, 3, 4, 5, 5, 6, 7, 8], 20 * MS);
        assert_eq!(t.counts(), counts(10, 0, 1, 0, 0));
        assert_eq!(t.pymav_figure(), PymavFigure::new(10, 255));
        // An older duplicate too.
        let t = tracked(&[0, 1, 2, 3, 4, 5, 2, 6], 20 * MS);
        assert_eq!(t.counts(), counts(8, 0, 1, 0, 0));
    }

    #[test]
    fn a_swap_is_one_reordered_frame_and_costs_pymavlink_256() {
        let t = tracked(&[0, 1, 2, 3, 4, 6, 5, 7, 8], 20 * MS);
        assert_eq!(t.counts(), counts(9, 0, 0, 1, 0));
        assert_eq!(t.pymav_figure().loss, 256);
        // Across the wrap.
        let t = tracked(&[253, 254, 256, 255, 257], 20 * MS);
        assert_eq!(t.counts(), counts(5, 0, 0, 1, 0));
    }

    #[test]
    fn a_reorder_after_a_gap_fills_one_of_it() {
        let t = tracked(&[0, 1, 2, 3, 4, 8, 5, 9, 10], 20 * MS);
        assert_eq!(t.counts(), counts(9, 2, 0, 1, 0));
        // The same late frame again is a duplicate, not another fill.
        let t = tracked(&[0, 1, 2, 3, 4, 8, 5, 5, 9], 20 * MS);
        assert_eq!(t.counts(), counts(9, 2, 1, 1, 0));
    }

    #[test]
    fn a_run_starting_on_a_swap_loses_nothing() {
        let t = tracked(&[1, 0, 2, 3], 20 * MS);
        assert_eq!(t.counts(), counts(4, 0, 0, 1, 0));
        // Behind the start by more than one: the numbers between are lost.
        let t = tracked(&[10, 7, 11], 20 * MS);
        assert_eq!(t.counts(), counts(3, 2, 0, 1, 0));
        let t = tracked(&[10, 7, 11, 8, 9], 20 * MS);
        assert_eq!(t.counts(), counts(5, 0, 0, 3, 0));
    }

    /// Feeds sequence numbers as they come, one every `step`.
    fn arriving(seqs: &[u8], step: Nanos) -> SeqTracker {
        let mut t = SeqTracker::new(None);
        for (i, &s) in seqs.iter().enumerate() {
            t.on_frame(s, 0, 20, i as u64 * step);
        }
        t
    }

    #[test]
    fn a_frame_128_away_resynchronises() {
        let t = arriving(&[0, 1, 2, 3, 131, 132], 20 * MS);
        assert_eq!(t.counts(), counts(6, 0, 0, 0, 1));
        // ...from which the count goes on.
        let t = arriving(&[0, 1, 2, 3, 131, 133], 20 * MS);
        assert_eq!(t.counts(), counts(6, 1, 0, 0, 1));
        // 127 ahead, and the next frame back by the head: another
        // sender's frame (stray: received, nothing else), not 124 lost.
        let t = arriving(&[0, 1, 2, 3, 130, 4, 5], 20 * MS);
        assert_eq!(t.counts(), counts(7, 0, 0, 0, 0));
        // Within reach either way: read at once.
        let t = arriving(&[0, 1, 2, 3, 30, 4, 5], 20 * MS);
        assert_eq!(t.counts(), counts(7, 24, 0, 2, 0));
    }

    /// 10 Hz for 2 s (positions 0..=20), then `missing` frames lost in a
    /// row, then 10 more.
    fn outage(missing: u64) -> SeqTracker {
        let p: Vec<u64> = (0..=20).chain(21 + missing..31 + missing).collect();
        tracked(&p, 100 * MS)
    }

    #[test]
    fn a_silence_shorter_than_128_frames_is_counted_lost() {
        let t = outage(30);
        assert_eq!(t.counts(), counts(31, 30, 0, 0, 0));
        let s = t.summary(SRC, 60 * 100 * MS);
        assert_eq!(
            s.silences,
            vec![Silence {
                start: 2 * S,
                length_ns: 3_100 * MS,
                frames_estimated: Some(30),
                seq_lost: Some(30),
                lost_estimated: None,
                restart: false,
                ongoing: false,
            }]
        );
        assert_eq!((s.silence_count, s.silence_frames_estimated), (1, 0));
        assert_eq!(s.pymav.loss, 30);
        // Up to 127 frames: still spanned.
        let t = outage(120);
        assert_eq!(t.counts().lost, 120);
    }

    #[test]
    fn a_silence_over_255_frames_counts_its_gap_and_estimates_the_wraps() {
        // 600 frames (60 s at 10 Hz): 600 mod 256 = 88 is what the
        // sequence proves, and what pymavlink counts; the rate says two
        // wraps more, apart.
        let t = outage(600);
        assert_eq!(t.counts(), counts(31, 88, 0, 0, 0));
        assert_eq!(t.pymav_figure().loss, 88);
        let s = t.summary(SRC, 630 * 100 * MS);
        assert_eq!(s.silences.len(), 1);
        assert_eq!(s.silences[0].frames_estimated, Some(600));
        assert_eq!(s.silences[0].seq_lost, Some(88));
        assert_eq!(s.silences[0].lost_estimated, Some(600));
        assert_eq!(s.silence_frames_estimated, 512);
        assert_eq!(s.silence_ns, 60_100 * MS);
        // 128..=255 frames: the gap, and no wrap is likelier.
        let t = outage(200);
        assert_eq!(t.counts(), counts(31, 200, 0, 0, 0));
        assert_eq!(t.summary(SRC, 0).silences[0].lost_estimated, Some(200));
        // Exactly 256: the sequence shows nothing missing, which a pause
        // with nothing lost shows every time and a loss once in 256: read
        // as delayed, none lost.
        let t = outage(256);
        assert_eq!(t.counts(), counts(31, 0, 0, 0, 0));
        assert_eq!(t.summary(SRC, 0).silences[0].lost_estimated, None);
        assert_eq!(t.pymav_figure().loss, 0);
    }

    #[test]
    fn a_frame_behind_after_a_silence_is_a_restart() {
        // 10 Hz, then 5 s quiet, then the source starts again at 0.
        let mut t = SeqTracker::new(None);
        for p in 0..=40u64 {
            t.on_frame(p as u8, 0, 20, p * 100 * MS);
        }
        for p in 0..5u64 {
            t.on_frame(p as u8, 0, 20, 9 * S + p * 100 * MS);
        }
        assert_eq!(t.counts(), counts(46, 0, 0, 0, 1));
    }

    #[test]
    fn with_no_rate_known_a_silence_counts_its_gap() {
        let mut t = SeqTracker::new(None);
        t.on_frame(0, 0, 20, 0);
        t.on_frame(10, 0, 20, 6 * S);
        assert_eq!(t.counts(), counts(2, 9, 0, 0, 0));
        let s = t.summary(SRC, 6 * S);
        assert_eq!(s.silences[0].frames_estimated, None);
        assert_eq!(s.silence_frames_estimated, 0);
    }

    /// Frames sent in bursts of `burst`, `spacing` apart within a burst,
    /// a burst every `every`, by stream position; `lost` positions are
    /// not delivered.
    fn bursts(n: u64, burst: u64, spacing: Nanos, every: Nanos, lost: &[u64]) -> SeqTracker {
        let mut t = SeqTracker::new(None);
        for p in (0..n).filter(|p| !lost.contains(p)) {
            t.on_frame(
                (p % 256) as u8,
                0,
                20,
                p / burst * every + p % burst * spacing,
            );
        }
        t
    }

    #[test]
    fn a_source_whose_first_frames_come_together_is_still_counted() {
        // Two frames 80 µs apart, then one every 200 ms (a radio's
        // RADIO_STATUS sent twice at start-up): the first step is no
        // usual interval, and must not make every later pause a silence
        // (each resynchronising, so no loss would ever be counted).
        let mut t = SeqTracker::new(None);
        t.on_frame(0, 0, 20, 0);
        for p in 1..60u64 {
            if p % 10 != 5 {
                t.on_frame(p as u8, 0, 20, 80_000 + (p - 1) * 200 * MS);
            }
        }
        assert_eq!(t.counts(), counts(54, 6, 0, 0, 0));
        assert_eq!(t.summary(SRC, 58 * 200 * MS).silence_count, 0);
        let interval = t.interval().unwrap();
        assert!((100 * MS..=200 * MS).contains(&interval), "{interval}");
    }

    #[test]
    fn a_source_sending_in_bursts_is_counted_exactly() {
        // An autopilot's scheduler sends its messages together: 5 frames
        // 50 µs apart every 20 ms (4 ms a frame on average), 1000 frames
        // with 10 lost, the sequence wrapping 3 times.
        let lost = [7, 8, 100, 333, 334, 335, 600, 777, 901, 950];
        let t = bursts(1000, 5, 50_000, 20 * MS, &lost);
        assert_eq!(t.counts(), counts(990, 10, 0, 0, 0));
        assert_eq!(t.summary(SRC, 199 * 20 * MS).silence_count, 0);
        // 100,000 frames/s sent in batches of 50 every 0.5 ms (a sender's
        // sendmmsg), 20 lost in runs, the sequence wrapping 400 times.
        let lost: Vec<u64> = (1..=20).map(|i| i * 4_999).collect();
        let t = bursts(100_000, 50, 100, 500_000, &lost);
        assert_eq!(t.counts(), counts(99_980, 20, 0, 0, 0));
        let interval = t.interval().unwrap();
        assert!((8_000..=12_000).contains(&interval), "{interval}");
        // A second's outage (250 frames at its rate) is a silence; its
        // gap is counted, and no wrap is likelier than none.
        let gone: Vec<u64> = (500..750).collect();
        let t = bursts(1000, 5, 50_000, 20 * MS, &gone);
        assert_eq!(t.counts(), counts(750, 250, 0, 0, 0));
        let s = t.summary(SRC, 199 * 20 * MS);
        assert_eq!(s.silence_count, 1);
        let estimated = s.silences[0].frames_estimated.unwrap();
        assert!((200..=300).contains(&estimated), "{estimated}");
    }

    #[test]
    fn a_batch_stamped_alike_costs_one_restart_not_the_rest_of_the_run() {
        // 300 frames with one arrival time (a backlog read at once), then
        // 100,000 frames/s in batches of 50 every 0.5 ms, 10 lost after.
        let mut t = SeqTracker::new(None);
        let lost: Vec<u64> = (1..=10).map(|i| 1_000 + i * 1_777).collect();
        for p in (0..20_000u64).filter(|p| !lost.contains(p)) {
            let at = if p < 300 {
                0
            } else {
                p / 50 * 500_000 + p % 50 * 100
            };
            t.on_frame((p % 256) as u8, 0, 20, at);
        }
        // A rate of no time is no reason for a silence under the 1 s
        // floor before a second is in: nothing restarts.
        assert_eq!(t.counts(), counts(19_990, 10, 0, 0, 0));
        let interval = t.interval().unwrap();
        assert!((8_000..=12_000).contains(&interval), "{interval}");
    }

    #[test]
    fn a_fast_source_gets_a_silence_under_the_floor() {
        // 1 kHz: 64 ms without a frame is a silence although under 1 s,
        // and 300 frames lost in 0.3 s are 44 proven and 300 likely.
        let p: Vec<u64> = (0..2000).chain(2300..2400).collect();
        let t = tracked(&p, MS);
        assert_eq!(t.counts(), counts(2100, 44, 0, 0, 0));
        let s = t.summary(SRC, 2399 * MS);
        assert_eq!(s.silences[0].frames_estimated, Some(300));
        assert_eq!(s.silences[0].lost_estimated, Some(300));
        // And 100 lost in a row, under 128: counted.
        let p: Vec<u64> = (0..500).chain(600..700).collect();
        let t = tracked(&p, MS);
        assert_eq!(t.counts(), counts(600, 100, 0, 0, 0));
    }

    #[test]
    fn a_given_gap_sets_the_threshold() {
        let mut t = SeqTracker::new(Some(300 * MS));
        let p: Vec<u64> = (0..=12).chain([17, 18]).collect();
        feed(&mut t, &p, 100 * MS);
        let s = t.summary(SRC, 1_800 * MS);
        assert_eq!(t.counts(), counts(15, 4, 0, 0, 0));
        assert_eq!(s.silences.len(), 1);
        assert_eq!(s.silences[0].seq_lost, Some(4));
        assert_eq!(s.silences[0].frames_estimated, Some(4));
        // Before a second of the source is in, its rate says nothing.
        let mut t = SeqTracker::new(Some(300 * MS));
        feed(&mut t, &[0, 1, 2, 3, 8, 9], 100 * MS);
        let s = t.summary(SRC, 900 * MS);
        assert_eq!(t.counts(), counts(6, 4, 0, 0, 0));
        assert_eq!(s.silences[0].frames_estimated, None);
    }

    #[test]
    fn a_silence_still_on_at_the_end_is_ongoing() {
        let p: Vec<u64> = (0..20).collect();
        let t = tracked(&p, 100 * MS);
        assert!(t.summary(SRC, 2_500 * MS).silences.is_empty());
        let s = t.summary(SRC, 19 * 100 * MS + 10 * S);
        assert_eq!(
            s.silences,
            vec![Silence {
                start: 1_900 * MS,
                length_ns: 10 * S,
                frames_estimated: Some(99),
                seq_lost: None,
                lost_estimated: None,
                restart: false,
                ongoing: true,
            }]
        );
        // Nothing is known lost in it until a frame says how many.
        assert_eq!(s.silence_frames_estimated, 0);
    }

    #[test]
    fn a_gap_is_pending_until_it_leaves_the_window_or_a_silence_starts() {
        // 5 and 6 skipped: both may still arrive.
        let mut t = tracked(&[0, 1, 2, 3, 4, 7, 8], 20 * MS);
        let pending = |t: &SeqTracker, at| t.summary(SRC, at).lost_pending;
        assert_eq!((t.counts().lost, pending(&t, 160 * MS)), (2, 2));
        // 5 arrives late: reordered, one still pending.
        t.on_frame(5, 0, 20, 170 * MS);
        assert_eq!((t.counts().lost, pending(&t, 170 * MS)), (1, 1));
        // 127 behind the head 6 may still come; 128 behind it cannot.
        feed(&mut t, &(9..=133).collect::<Vec<_>>(), 20 * MS);
        assert_eq!((t.counts().lost, pending(&t, 133 * 20 * MS)), (1, 1));
        feed(&mut t, &[134], 20 * MS);
        assert_eq!((t.counts().lost, pending(&t, 134 * 20 * MS)), (1, 0));
        // A new gap, then the source goes quiet: in a silence nothing can
        // fill it any more.
        feed(&mut t, &[136], 20 * MS);
        assert_eq!(pending(&t, 136 * 20 * MS), 1);
        assert_eq!(pending(&t, 136 * 20 * MS + 2 * S), 0);
    }

    #[test]
    fn the_silence_list_keeps_the_first_and_the_longest() {
        let mut t = SeqTracker::new(None);
        let mut at = 0;
        let mut seq = 0u8;
        // 30 silences, of 2 s .. 31 s (and the 100 ms step), in a 10 Hz
        // stream.
        for i in 0..31u64 {
            if i > 0 {
                at += (i + 1) * S;
            }
            for _ in 0..20 {
                t.on_frame(seq, 0, 20, at);
                seq = seq.wrapping_add(1);
                at += 100 * MS;
            }
        }
        let s = t.summary(SRC, at - 100 * MS);
        assert_eq!(s.silence_count, 30);
        assert_eq!(s.silences.len(), 16);
        assert_eq!(s.silences_omitted, 14);
        let lengths: Vec<Nanos> = s.silences.iter().map(|s| s.length_ns / S).collect();
        // Each is (i + 2) s plus the 100 ms step: 2..=9 first, then the
        // longest 8: 24..=31.
        let want: Vec<Nanos> = (2..=9).chain(24..=31).collect();
        assert_eq!(lengths, want);
        assert!(s.silences.windows(2).all(|w| w[0].start < w[1].start));
    }

    #[test]
    fn message_ids_are_capped_with_an_other_bucket() {
        let mut t = SeqTracker::new(None);
        let mut seq = 0u8;
        for id in 0..40u32 {
            for _ in 0..=id % 3 {
                t.on_frame(seq, id, 10, u64::from(seq) * MS);
                seq = seq.wrapping_add(1);
            }
        }
        let s = t.summary(SRC, 0);
        assert_eq!(s.msg_ids.len(), MAX_MSG_IDS);
        assert_eq!(s.msg_ids[0], MsgCount { id: 2, count: 3 });
        let kept: u64 = s.msg_ids.iter().map(|m| m.count).sum();
        assert_eq!(kept + s.msg_ids_other, s.counts.received);
        // Ids 32..40 came after the cap: 3 + 1 + 2 + 3 + 1 + 2 + 3 + 1.
        assert_eq!(s.msg_ids_other, 16);
    }

    #[test]
    fn the_table_keeps_the_radio_apart_and_caps_sources() {
        let mut table = SourceTable::new(None, 2);
        let a = SysComp::new(1, 1);
        let b = SysComp::new(255, 190);
        for i in 0..10u64 {
            let at = i * 100 * MS;
            let seq = i as u8;
            // a loses frame 5; b is clean; the radio loses half (which
            // would be link loss if counted).
            if i != 5 {
                table.on_frame(a, seq, 30, 30, at);
            }
            table.on_frame(b, seq, 0, 21, at);
            table.on_frame(RADIO_SOURCE, seq * 2, 109, 17, at);
            table.on_frame(SysComp::new(2, 1), seq, 0, 21, at);
            table.on_frame(SysComp::new(3, 1), seq, 0, 21, at);
        }
        let s = table.summary(900 * MS);
        let ids: Vec<(SysComp, bool)> = s.sources.iter().map(|s| (s.source, s.radio)).collect();
        assert_eq!(ids, vec![(a, false), (RADIO_SOURCE, true), (b, false)]);
        assert_eq!(s.totals.sources, 2);
        assert_eq!(s.totals.counts, counts(19, 1, 0, 0, 0));
        assert_eq!(s.totals.pymav, PymavFigure::new(19, 1));
        assert_eq!(s.totals.loss_pct, Some(5.0));
        assert_eq!(s.totals.bytes, 9 * 30 + 10 * 21);
        assert_eq!(s.totals.radio_received, 10);
        assert_eq!(s.sources[1].counts, counts(10, 9, 0, 0, 0));
        assert_eq!(
            s.untracked,
            Untracked {
                sources: 2,
                frames: 20,
                bytes: 420
            }
        );
        assert_eq!(table.source(a).map(|t| t.counts().lost), Some(1));
        assert!(table.source(SysComp::new(2, 1)).is_none());
        assert!(serde_json::to_string(&s).is_ok());
    }

    /// vtol.tlog's shape: a source at `rate` frames/s whose frames reach
    /// the log in batches every `period` (whole milliseconds, 20 frames on
    /// a stamp), `lost` positions not delivered, and after `pause_at` a
    /// pause of `pause` that delays the frames numbered in it (none lost).
    fn logged_in_batches(n: u64, lost: &[u64], pause_at: u64, pause: Nanos) -> SeqTracker {
        let mut t = SeqTracker::new(None);
        let (per_batch, period) = (140, 1_250 * MS);
        for p in (0..n).filter(|p| !lost.contains(p)) {
            let batch = p / per_batch;
            let mut at = batch * period + (p % per_batch) / 20 * 30 * MS;
            if batch >= pause_at {
                at += pause;
            }
            t.on_frame((p % 256) as u8, 0, 20, at);
        }
        t
    }

    #[test]
    fn a_logger_writing_batches_a_second_apart_makes_no_silences() {
        let lost = [1_000, 1_001, 2_799, 3_100, 3_101, 3_102];
        let t = logged_in_batches(5_600, &lost, u64::MAX, 0);
        assert_eq!(t.counts(), counts(5_594, 6, 0, 0, 0));
        let s = t.summary(SRC, 50 * S);
        // The first pauses, before a second of its rhythm was in, are the
        // only ones told, and as delayed: no number is missing across them.
        assert!(s.silence_count <= 2, "{:?}", s.silences);
        assert!(s.silences.iter().all(|x| x.seq_lost == Some(0)));
        assert_eq!(s.routine_pause_ns, Some(1_070 * MS));
        let i = s.interval_ns.unwrap();
        assert!((8 * MS..=10 * MS).contains(&i), "{i}");
    }

    #[test]
    fn a_pause_well_beyond_the_routine_one_is_a_silence_and_delayed_if_nothing_is_missing() {
        // Batch 20 comes 1.2 s late (2.27 s after the one before), every
        // number in it.
        let t = logged_in_batches(5_600, &[], 20, 1_200 * MS);
        let s = t.summary(SRC, 60 * S);
        let long: Vec<_> = s
            .silences
            .iter()
            .filter(|x| x.length_ns > 2 * S && !x.ongoing)
            .collect();
        assert_eq!(long.len(), 1, "{:?}", s.silences);
        assert_eq!((long[0].seq_lost, long[0].lost_estimated), (Some(0), None));
        assert_eq!(s.counts.lost, 0);
    }

    #[test]
    fn an_outage_that_wraps_the_counter_counts_its_gap_and_estimates_the_wraps() {
        // 490 frames lost in a batch's place (vtol.tlog's 4.2 s): 490 mod
        // 256 = 234 proven, 490 likely.
        let lost: Vec<u64> = (2_800..3_290).collect();
        let t = logged_in_batches(5_600, &lost, u64::MAX, 0);
        let s = t.summary(SRC, 60 * S);
        assert_eq!(s.counts.lost, 234);
        let outage = s.silences.iter().find(|x| x.length_ns > 3 * S).unwrap();
        assert_eq!(
            (outage.seq_lost, outage.lost_estimated),
            (Some(234), Some(490))
        );
        assert_eq!(s.silence_frames_estimated, 256);
    }

    #[test]
    fn a_counter_starting_again_at_0_after_a_silence_is_a_restart_not_a_loss() {
        // 7,000 frames/s (ArduPilot's SITL sped up), 1 s of nothing, then
        // the counter from 0.
        let mut t = SeqTracker::new(None);
        let mut at = 0;
        for p in 0..20_000u64 {
            at = p * 1_000_000 / 7;
            t.on_frame((p % 256) as u8, 0, 20, at);
        }
        for p in 0..1_000u64 {
            t.on_frame((p % 256) as u8, 0, 20, at + S + p * 1_000_000 / 7);
        }
        let s = t.summary(SRC, at + 2 * S);
        assert_eq!(s.counts, counts(21_000, 0, 0, 0, 1));
        assert!(s.silences[0].restart);
        assert_eq!(s.silences[0].seq_lost, None);
    }

    #[test]
    fn damaged_frames_fill_their_numbers_and_are_counted_apart() {
        let mut t = SeqTracker::new(None);
        for p in 0..100u64 {
            if p % 10 == 3 {
                t.on_damaged((p % 256) as u8, 132, 30, p * 20 * MS);
            } else if p != 50 {
                t.on_frame((p % 256) as u8, 0, 20, p * 20 * MS);
            }
        }
        let s = t.summary(SRC, 100 * 20 * MS);
        assert_eq!(s.counts.received, 89);
        assert_eq!((s.counts.damaged, s.counts.lost), (10, 1));
        assert_eq!(s.damaged_ids, vec![MsgCount { id: 132, count: 10 }]);
        assert_eq!(s.loss_pct, Some(1.0));
        // pymavlink never sees a damaged frame: each costs it one.
        assert_eq!(s.pymav, PymavFigure::new(89, 11));
    }

    #[test]
    fn a_second_sender_behind_one_id_is_counted_on_its_own() {
        // QGroundControl's 255/190 in qgc_ardusub: MANUAL_CONTROL numbered
        // by one counter, a REQUEST_DATA_STREAM every 13th frame numbered
        // 1 to 7 by another, the main counter skipping the number it spent.
        let mut t = SeqTracker::new(None);
        let (mut main, mut other, mut at) = (100u64, 0u64, 0);
        for i in 0..2_000u64 {
            at += 40 * MS;
            if i % 13 == 12 {
                main += 1;
                t.on_frame((other % 7 + 1) as u8, 66, 20, at);
                other += 1;
            } else {
                t.on_frame((main % 256) as u8, 69, 20, at);
                main += 1;
            }
        }
        let s = t.summary(SRC, at);
        let second = s.second_counter.expect("two counters");
        // Where the second counter's number is the main one's next (about
        // one frame in 256 here), the sequence cannot tell whose it is:
        // the main counter's, and the second shows one lost.
        let taken_by_main = other - second.counts.received;
        assert!(taken_by_main <= 2, "{second:?}");
        assert!(second.counts.lost <= taken_by_main);
        assert_eq!(second.msg_ids[0].id, 66);
        // The main counter loses exactly the numbers it spent elsewhere,
        // and nothing is reordered or duplicate.
        assert_eq!(s.counts.received, 2_000);
        assert_eq!((s.counts.duplicate, s.counts.reordered), (0, 0));
        assert_eq!(s.counts.lost, other - taken_by_main + second.counts.lost);
        assert!(s.counts.lost <= other);
    }

    #[test]
    fn every_radios_own_source_is_out_of_the_totals() {
        // ExpressLRS's receiver sends RADIO_STATUS as 255/68, a WiFi
        // bridge as x/240: radios' own frames, not the link's traffic.
        let mut table = SourceTable::new(None, DEFAULT_MAX_SOURCES);
        let (v, elrs, esp) = (
            SysComp::new(1, 1),
            SysComp::new(255, 68),
            SysComp::new(1, 240),
        );
        for p in 0..50u64 {
            table.on_frame(v, p as u8, 0, 20, p * 20 * MS);
            table.on_frame(elrs, (p * 3) as u8, 109, 20, p * 20 * MS);
            table.on_frame(esp, p as u8, 109, 20, p * 20 * MS);
        }
        let s = table.summary(50 * 20 * MS);
        assert_eq!(s.totals.counts, counts(50, 0, 0, 0, 0));
        assert_eq!(s.totals.radio_received, 100);
        assert!(s.sources.iter().filter(|x| x.radio).count() == 2);
    }

    #[test]
    fn the_ground_station_is_out_of_the_totals() {
        let mut table = SourceTable::new(None, DEFAULT_MAX_SOURCES);
        let (v, g) = (SysComp::new(1, 1), SysComp::new(255, 190));
        for p in 0..50u64 {
            table.on_frame(v, p as u8, 0, 20, p * 20 * MS);
            if p % 13 != 0 {
                table.on_frame(g, p as u8, 69, 20, p * 20 * MS);
            }
        }
        table.set_ground(g);
        let s = table.summary(50 * 20 * MS);
        assert_eq!(s.totals.counts, counts(50, 0, 0, 0, 0));
        assert_eq!(s.totals.ground_received, 46);
        assert!(s.sources.iter().any(|x| x.source == g && x.ground));
    }

    /// What happens to each frame the source sends, in the property test.
    #[derive(Debug, Clone, Copy)]
    enum Fate {
        Delivered,
        Dropped,
        /// Delivered, and a copy right after it.
        Doubled,
        /// Delivered after the next delivered frame.
        Swapped,
    }

    fn fate() -> impl proptest::strategy::Strategy<Value = Fate> {
        proptest::prop_oneof![
            12 => proptest::strategy::Just(Fate::Delivered),
            3 => proptest::strategy::Just(Fate::Dropped),
            1 => proptest::strategy::Just(Fate::Doubled),
            1 => proptest::strategy::Just(Fate::Swapped),
        ]
    }

    /// The frames delivered, by stream position, and the true counts. The
    /// first two frames are always delivered first (so the run starts at
    /// 0 with a rate known); no more than 20 in a row are dropped.
    fn deliver(fates: &[Fate]) -> (Vec<u64>, SeqCounts) {
        let mut out: Vec<u64> = Vec::new();
        let mut swap_at: Vec<usize> = Vec::new();
        let mut dropped_run = 0;
        for (p, f) in fates.iter().enumerate() {
            let p = p as u64;
            match (*f, p) {
                (_, 0..=1) => out.push(p),
                (Fate::Dropped, _) if dropped_run < 20 => dropped_run += 1,
                (Fate::Doubled, _) => {
                    dropped_run = 0;
                    out.extend([p, p]);
                }
                (Fate::Swapped, _) => {
                    dropped_run = 0;
                    swap_at.push(out.len());
                    out.push(p);
                }
                _ => {
                    dropped_run = 0;
                    out.push(p);
                }
            }
        }
        // Neighbours only: at 1 Hz, five positions apart is a silence, and
        // nothing from before a told silence may fill a gap after it.
        for i in swap_at {
            if i + 1 < out.len() && out[i + 1] - out[i] < 5 {
                out.swap(i, i + 1);
            }
        }
        // The truth, from the positions alone.
        let mut seen = std::collections::BTreeSet::new();
        let mut truth = SeqCounts::default();
        let mut highest = 0;
        for &p in &out {
            truth.received += 1;
            if !seen.insert(p) {
                truth.duplicate += 1;
            } else if p < highest {
                truth.reordered += 1;
            }
            highest = highest.max(p);
        }
        truth.lost = highest + 1 - seen.len() as u64;
        (out, truth)
    }

    proptest::proptest! {
        /// Drops (under the window), duplicates and adjacent swaps on a
        /// stream wrapping the sequence many times: the counts are exact,
        /// at rates fast and slow.
        #[test]
        fn counts_match_the_truth(
            fates in proptest::collection::vec(fate(), 1..3000),
            interval_ms in proptest::sample::select(vec![1u64, 20, 100, 1000]),
        ) {
            let (delivered, truth) = deliver(&fates);
            let t = tracked(&delivered, interval_ms * MS);
            let spanned = t.summary(SRC, 0).silences.iter().all(|s| s.seq_lost.is_some());
            proptest::prop_assert!(spanned);
            proptest::prop_assert_eq!(t.counts(), truth);
        }

        /// The same faults on a source that sends in bursts (an
        /// autopilot's scheduler: `burst` frames 50 µs apart, a burst every
        /// 20 or 100 ms): exact too, every pause spanned by the sequence.
        #[test]
        fn counts_match_the_truth_in_bursts(
            fates in proptest::collection::vec(fate(), 1..3000),
            burst in 1u64..=12,
            every_ms in proptest::sample::select(vec![20u64, 100]),
        ) {
            let (delivered, truth) = deliver(&fates);
            let mut t = SeqTracker::new(None);
            let mut at = 0;
            for &p in &delivered {
                at = (p / burst * every_ms * MS + p % burst * 50_000).max(at);
                t.on_frame((p % 256) as u8, 0, 20, at);
            }
            let spanned = t.summary(SRC, at).silences.iter().all(|s| s.seq_lost.is_some());
            proptest::prop_assert!(spanned);
            proptest::prop_assert_eq!(t.counts(), truth);
        }

        /// What a counter of losses shows, lost less pending, never goes
        /// down, frame after frame, whatever arrives; and it is at most
        /// the loss the sequence shows.
        #[test]
        fn settled_loss_never_decreases(
            frames in proptest::collection::vec((0u8..=255, 0u64..1_500), 1..600),
        ) {
            let mut t = SeqTracker::new(None);
            let (mut at, mut settled) = (0, 0);
            for &(s, step_ms) in &frames {
                at += step_ms * MS;
                t.on_frame(s, 0, 10, at);
                let summary = t.summary(SRC, at);
                let now = summary.counts.lost - summary.lost_pending;
                proptest::prop_assert!(now >= settled, "{} after {}", now, settled);
                settled = now;
            }
        }

        /// On a stream with drops, duplicates and swaps, the same; and once
        /// the source has gone quiet, nothing is pending: the settled loss
        /// is the truth.
        #[test]
        fn settled_loss_reaches_the_truth_in_a_silence(
            fates in proptest::collection::vec(fate(), 1..1500),
        ) {
            let (delivered, truth) = deliver(&fates);
            let mut t = SeqTracker::new(None);
            let (mut at, mut settled) = (0, 0);
            for &p in &delivered {
                at = (p * 20 * MS).max(at);
                t.on_frame((p % 256) as u8, 0, 20, at);
                let s = t.summary(SRC, at);
                proptest::prop_assert!(s.counts.lost - s.lost_pending >= settled);
                settled = s.counts.lost - s.lost_pending;
            }
            let quiet = t.summary(SRC, at + 2 * S);
            proptest::prop_assert_eq!(quiet.lost_pending, 0);
            proptest::prop_assert_eq!(quiet.counts.lost, truth.lost);
        }

        /// pymavlink's figure is its formula, frame by frame.
        #[test]
        fn the_pymavlink_figure_is_its_formula(seqs in proptest::collection::vec(0u8..=255, 0..500)) {
            let mut t = SeqTracker::new(None);
            let mut last: i64 = -1;
            let mut loss: i64 = 0;
            for (i, &s) in seqs.iter().enumerate() {
                t.on_frame(s, 0, 10, i as u64 * MS);
                let expected = (last + 1).rem_euclid(256);
                if last != -1 && expected != i64::from(s) {
                    loss += (i64::from(s) - expected).rem_euclid(256);
                }
                last = i64::from(s);
            }
            proptest::prop_assert_eq!(t.pymav_figure().loss, loss as u64);
            proptest::prop_assert_eq!(t.pymav_figure().count, seqs.len() as u64);
        }

        /// Whatever arrives, and whenever: no count underflows, and each
        /// frame after the first is at most one of duplicate, reordered or
        /// resync.
        #[test]
        fn any_input_is_accounted(
            frames in proptest::collection::vec((0u8..=255, 0u64..3_000), 1..500),
        ) {
            let mut t = SeqTracker::new(None);
            let mut at = 0;
            for &(s, step_ms) in &frames {
                at += step_ms * MS;
                t.on_frame(s, 0, 10, at);
            }
            let c = t.counts();
            proptest::prop_assert_eq!(c.received, frames.len() as u64);
            proptest::prop_assert!(c.duplicate + c.reordered + c.resyncs < c.received);
            let s = t.summary(SRC, at);
            proptest::prop_assert_eq!(s.silence_count, s.silences.len() as u64 + s.silences_omitted);
        }
    }
}
