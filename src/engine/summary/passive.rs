//! What a passive run hands back: per source, what its packet sequence
//! proved (received, lost, duplicate, reordered), its silences and rates,
//! pymavlink's figure beside ours, and the link's totals. Built by the
//! passive probe's tracker; every report format renders it.

use crate::engine::age::SourceAge;
use crate::engine::answers::AnswerSummary;
use crate::engine::hint::Hint;
use crate::engine::link_node::LinkNodeSummary;
use crate::engine::probe::passive::flight::FlightSummary;
use crate::engine::probe::passive::round_trips::RoundTripSummary;
use crate::engine::radio::RadioSummary;
use crate::engine::roster::Identity;
use crate::engine::Nanos;
use crate::frame::signing::SigningSummary;
use crate::frame::{ScanStats, SysComp};
use crate::transport::tlog::LogFacts;
use crate::transport::RxClock;

/// A `--passive` run on one link.
#[derive(Debug, Clone)]
pub(crate) struct PassiveSummary {
    pub(crate) link: String,
    pub(crate) ours: SysComp,
    /// Our HEARTBEAT went out at 1 Hz (routers send only to what they hear).
    pub(crate) heartbeat: bool,
    pub(crate) duration_s: f64,
    pub(crate) table: TableSummary,
    /// What each source said it is, from its HEARTBEAT.
    pub(crate) identities: Vec<(SysComp, Identity)>,
    /// Frames with our own ids (echoed back by a router): not a source.
    pub(crate) own_frames: u64,
    pub(crate) radios: Vec<RadioSummary>,
    /// Nodes heard by their LINK_NODE_STATUS (the vehicle's own view).
    pub(crate) link_node: Vec<LinkNodeSummary>,
    pub(crate) frames: ScanStats,
    pub(crate) rx_clock: RxClock,
    pub(crate) interrupted: bool,
    pub(crate) link_error: Option<String>,
    pub(crate) signing: SigningSummary,
    /// The vehicle's TIMESYNC and PING requests answered.
    pub(crate) answered: AnswerSummary,
    /// How old each source's frames were when they arrived, above its
    /// baseline, from their own clock stamps.
    pub(crate) age: Vec<SourceAge>,
    /// What the figures suggest (a queue building).
    pub(crate) hints: Vec<Hint>,
    /// Read from a telemetry log: what the log held (set by the run, from
    /// the link).
    pub(crate) log: Option<LogFacts>,
    /// A log's figures per MAVProxy link, when its stamps carry link
    /// numbers.
    pub(crate) per_link: Option<PerLink>,
    /// A log's requests matched to their replies by the stamps.
    pub(crate) round_trips: Option<RoundTripSummary>,
    /// A log's flight: its windows' summary, silences and bursts.
    pub(crate) flight: Option<FlightSummary>,
}

impl PassiveSummary {
    /// A source's identity, if it sent a HEARTBEAT.
    pub(crate) fn identity(&self, id: SysComp) -> Option<&Identity> {
        self.identities
            .iter()
            .find(|(s, _)| *s == id)
            .map(|(_, i)| i)
    }

    /// Sources heard, the radio aside.
    pub(crate) fn heard(&self) -> impl Iterator<Item = &SourceSummary> {
        self.table.sources.iter().filter(|s| !s.radio)
    }
}

/// The sequence counts of one source.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize)]
pub(crate) struct SeqCounts {
    /// Every frame with a good CRC, duplicates included.
    pub(crate) received: u64,
    /// Frames whose CRC failed with their header whole (damaged, or of a
    /// dialect whose CRC differs): they arrived, and filled their number.
    pub(crate) damaged: u64,
    /// Sequence numbers skipped and not (yet) filled by a late frame.
    pub(crate) lost: u64,
    /// Frames whose number had been seen already.
    pub(crate) duplicate: u64,
    /// Frames that came after a later one and filled their gap.
    pub(crate) reordered: u64,
    /// Times the accounting restarted on a frame the sequence could not
    /// place (after a long silence, or exactly 128 away).
    pub(crate) resyncs: u64,
}

impl SeqCounts {
    /// Sequence numbers the source used that the count accounts for: each
    /// received once or lost.
    pub(crate) fn numbered(&self) -> u64 {
        self.received + self.damaged - self.duplicate + self.lost
    }

    /// Two counters' figures together.
    pub(crate) fn plus(&self, o: &SeqCounts) -> SeqCounts {
        SeqCounts {
            received: self.received + o.received,
            damaged: self.damaged + o.damaged,
            lost: self.lost + o.lost,
            duplicate: self.duplicate + o.duplicate,
            reordered: self.reordered + o.reordered,
            resyncs: self.resyncs + o.resyncs,
        }
    }
}

/// pymavlink's loss figure for the same frames, as `mavutil` computes it.
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize)]
pub(crate) struct PymavFigure {
    /// `mav_count`: every frame.
    pub(crate) count: u64,
    /// `mav_loss`: the sum of `(seq - expected) % 256` over mismatches.
    pub(crate) loss: u64,
    /// `packet_loss()`: `100 * loss / (count + loss)`, 0 with no frames.
    pub(crate) loss_pct: f64,
}

impl PymavFigure {
    pub(crate) fn new(count: u64, loss: u64) -> Self {
        PymavFigure {
            count,
            loss,
            loss_pct: percent(loss, count + loss).unwrap_or(0.0),
        }
    }
}

/// A time the source was not heard for longer than the threshold.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub(crate) struct Silence {
    /// The arrival of the last frame before it.
    pub(crate) start: Nanos,
    /// From that frame to the one after it (to the summary, if ongoing).
    pub(crate) length_ns: Nanos,
    /// Frames the source would have sent in it at its usual rate; `None`
    /// while no rate was settled (a second of the source's frames).
    pub(crate) frames_estimated: Option<u64>,
    /// The frames the sequence proves lost across it (included in
    /// `lost`): its gap, modulo 256 where the pause may hide wraps of the
    /// counter; `None` after a restart of the counter, or while ongoing.
    /// `Some(0)`: no number missing: the frames were delayed, not lost.
    pub(crate) seq_lost: Option<u64>,
    /// Where the pause is too long for the 8-bit counter to span at the
    /// source's rate: the likely number lost, `seq_lost` plus the wraps
    /// the rate suggests (the difference is not in `lost`); `None` when
    /// it could span it, nothing is missing, or no rate was settled.
    pub(crate) lost_estimated: Option<u64>,
    /// The counter started again at 0 after it: the source restarted.
    pub(crate) restart: bool,
    /// Still on when the summary was taken.
    pub(crate) ongoing: bool,
}

/// Frames of one message id.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub(crate) struct MsgCount {
    pub(crate) id: u32,
    pub(crate) count: u64,
}

/// Everything known about one source.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub(crate) struct SourceSummary {
    pub(crate) source: SysComp,
    /// The SiK radio's own RADIO_STATUS source (out of the link's totals).
    pub(crate) radio: bool,
    /// In a telemetry log, the ground station's own frames, logged as it
    /// sent them (out of the link's totals: not what the link delivered).
    pub(crate) ground: bool,
    pub(crate) counts: SeqCounts,
    /// `100 * lost / (lost + distinct frames received)`; `None` with
    /// nothing to compare.
    pub(crate) loss_pct: Option<f64>,
    /// Of `lost`, the numbers a late frame may still fill (and move to
    /// `reordered`): within the window behind the latest frame, outside a
    /// silence. `lost - lost_pending` never decreases, which is what a
    /// counter of losses needs (Prometheus).
    #[serde(skip)]
    pub(crate) lost_pending: u64,
    pub(crate) pymav: PymavFigure,
    /// Frame bytes, duplicates included.
    pub(crate) bytes: u64,
    pub(crate) first_seen: Nanos,
    pub(crate) last_seen: Nanos,
    /// Arrival rates from the first to the last frame (the first frame
    /// starts the span, so it is not counted); `None` on a zero span.
    pub(crate) frames_per_s: Option<f64>,
    pub(crate) bytes_per_s: Option<f64>,
    /// The usual time per sequence step, once known.
    pub(crate) interval_ns: Option<Nanos>,
    /// The longest pause the source makes in a second, as a rule (a
    /// logger's batches), once a second is in: no silence is shorter than
    /// 1.5 times it.
    pub(crate) routine_pause_ns: Option<Nanos>,
    /// The first silences and the longest later ones, by start, then the
    /// ongoing one if any.
    pub(crate) silences: Vec<Silence>,
    /// All silences, ongoing included.
    pub(crate) silence_count: u64,
    /// Silences not in the list.
    pub(crate) silences_omitted: u64,
    /// Total length of all silences.
    pub(crate) silence_ns: Nanos,
    /// What the silences too long for the counter to span likely hid
    /// beyond the sequence's gap: the wraps the rate suggests (never also
    /// in `lost`).
    pub(crate) silence_frames_estimated: u64,
    /// Frames by message id, most frequent first (the first
    /// `MAX_MSG_IDS` distinct ids seen).
    pub(crate) msg_ids: Vec<MsgCount>,
    /// Frames of ids seen after that many distinct ones.
    pub(crate) msg_ids_other: u64,
    /// Damaged frames by message id, most frequent first.
    pub(crate) damaged_ids: Vec<MsgCount>,
    /// A second sender numbering frames under the same ids with a counter
    /// of its own (two programs, or one on two channels), counted on its
    /// own; its figures are in `counts` too.
    pub(crate) second_counter: Option<SecondCounter>,
}

impl SourceSummary {
    /// A message id's share of the source's rate, where the rate is known.
    pub(crate) fn msg_rate(&self, m: &MsgCount) -> Option<f64> {
        let received = self.counts.received;
        let rate = self.frames_per_s.filter(|_| received > 0)?;
        Some(rate * m.count as f64 / received as f64)
    }
}

/// A second counter under one source's ids.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub(crate) struct SecondCounter {
    pub(crate) counts: SeqCounts,
    /// Its frames by message id, most frequent first.
    pub(crate) msg_ids: Vec<MsgCount>,
}

/// Frames from sources beyond the table's cap: counted, not tracked.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize)]
pub(crate) struct Untracked {
    /// Distinct sources.
    pub(crate) sources: u64,
    pub(crate) frames: u64,
    pub(crate) bytes: u64,
}

/// The link as a whole: every tracked source but the radio.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub(crate) struct LinkTotals {
    pub(crate) sources: u64,
    pub(crate) counts: SeqCounts,
    /// As [`SourceSummary::loss_pct`], over the sums.
    pub(crate) loss_pct: Option<f64>,
    /// pymavlink's link-wide `mav_count`/`mav_loss` (it too leaves the
    /// radio out; untracked sources are not in it; the ground station's
    /// own frames in a log are, as `mavloss.py` counts them).
    pub(crate) pymav: PymavFigure,
    pub(crate) bytes: u64,
    pub(crate) silence_count: u64,
    pub(crate) silence_frames_estimated: u64,
    /// Frames from the radio's own source (counted, not in the totals).
    pub(crate) radio_received: u64,
    /// Frames the ground station logged as it sent them (not in the
    /// totals).
    pub(crate) ground_received: u64,
}

impl LinkTotals {
    /// The totals of `sources`: the radio's own source (flagged) is left
    /// out and its frames counted apart.
    pub(crate) fn of(sources: &[SourceSummary]) -> Self {
        let mut c = SeqCounts::default();
        let (mut bytes, mut silence_count, mut unspanned, mut pymav_loss) = (0, 0, 0, 0);
        let mut pymav_count = 0;
        let (mut radio_received, mut ground_received) = (0, 0);
        let mut count = 0;
        for s in sources {
            if s.radio {
                radio_received += s.counts.received;
                continue;
            }
            // pymavlink's figure is the whole log's, as mavloss.py reads it:
            // the ground station's frames in it too.
            pymav_loss += s.pymav.loss;
            pymav_count += s.pymav.count;
            if s.ground {
                ground_received += s.counts.received;
                continue;
            }
            count += 1;
            c = c.plus(&s.counts);
            bytes += s.bytes;
            silence_count += s.silence_count;
            unspanned += s.silence_frames_estimated;
        }
        LinkTotals {
            sources: count,
            counts: c,
            loss_pct: percent(c.lost, c.numbered()),
            pymav: PymavFigure::new(pymav_count, pymav_loss),
            bytes,
            silence_count,
            silence_frames_estimated: unspanned,
            radio_received,
            ground_received,
        }
    }
}

/// The sources heard through one MAVProxy link: the stamps' two lowest
/// bits, 3 marking what MAVProxy itself sent.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub(crate) struct LinkTable {
    pub(crate) link: u8,
    pub(crate) table: TableSummary,
}

/// A telemetry log's figures per MAVProxy link.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub(crate) struct PerLink {
    /// By link number; only links that carried a source.
    pub(crate) links: Vec<LinkTable>,
    /// Sources whose stamps' low bits vary as a clock's do, not as a link
    /// number's (MAVProxy logs what its outputs send with a plain stamp):
    /// in no link's table.
    pub(crate) unlinked: Vec<SysComp>,
}

/// What a [`SourceTable`] reports.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub(crate) struct TableSummary {
    /// By source address; the radio, if heard, among them, flagged.
    pub(crate) sources: Vec<SourceSummary>,
    pub(crate) totals: LinkTotals,
    pub(crate) untracked: Untracked,
}

/// `100 * part / whole`; `None` for an empty whole. Counts stay far below
/// 2^53, where `f64` is exact.
pub(crate) fn percent(part: u64, whole: u64) -> Option<f64> {
    (whole > 0).then(|| 100.0 * part as f64 / whole as f64)
}

impl super::KindSummary for PassiveSummary {
    fn link(&self) -> &str {
        &self.link
    }
    fn link_error(&self) -> Option<&str> {
        self.link_error.as_deref()
    }
}

/// A passive run so far: every source's sequence figures (cumulative), as
/// the summary will give them.
#[derive(Debug, Clone)]
pub struct PassiveInterim {
    /// Session time, ns.
    pub(crate) at: Nanos,
    pub(crate) table: TableSummary,
    /// What each source said it is, from its HEARTBEAT.
    pub(crate) identities: Vec<(SysComp, Identity)>,
    /// Each source's age above its baseline so far.
    pub(crate) ages: Vec<SourceAge>,
}

impl crate::engine::kind::KindValue for PassiveInterim {}

#[cfg(test)]
mod tests {
    use crate::engine::probe::passive::tracker::SourceTable;
    use crate::frame::SysComp;

    #[test]
    fn a_message_is_at_its_share_of_the_source_rate() {
        let mut t = SourceTable::new(None, 32);
        // Four frames 100 ms apart (10 a second), three of them id 30.
        for (k, id) in [30u32, 30, 0, 30].into_iter().enumerate() {
            t.on_frame(SysComp::new(1, 1), k as u8, id, 40, k as u64 * 100_000_000);
        }
        let s = t.summary(1_000_000_000).sources.remove(0);
        let rate = |id| s.msg_rate(s.msg_ids.iter().find(|m| m.id == id).unwrap());
        assert_eq!(s.frames_per_s, Some(10.0));
        assert_eq!(rate(30), Some(7.5));
        assert_eq!(rate(0), Some(2.5));
        // One frame: no span, so no rate to share.
        let mut one = SourceTable::new(None, 32);
        one.on_frame(SysComp::new(2, 1), 0, 30, 40, 0);
        let s = one.summary(1).sources.remove(0);
        assert_eq!(s.msg_rate(&s.msg_ids[0]), None);
    }
}
