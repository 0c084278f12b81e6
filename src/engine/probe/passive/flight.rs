//! The flight as a timeline, for a telemetry log: fixed windows of log
//! time, each with the frames received and lost (every source but the
//! radio's own, as the link's totals), the radio's RADIO_STATUS figures
//! and how far the vehicle was; and, between them, the link's silences
//! and its loss bursts.
//!
//! - **Constant memory.** A window is handed out as it closes (the driver
//!   tells it to the observers) and forgotten; only the window under way,
//!   a few events not yet told ([`PENDING`]), the [`WORST`] windows by
//!   loss and the [`KEPT`] longest silences and bursts are kept.
//! - **Loss per window** is what the source table's totals grew by in it:
//!   the driver closes a window with the totals as they stand before the
//!   first frame at or after its end is taken, so the windows add up to
//!   the summary's figures. A late frame moves a loss back (see the
//!   tracker), so a window's `lost` can be negative.
//! - **Distance** is from the first position (GLOBAL_POSITION_INT, else
//!   GPS_RAW_INT with at least a 2D fix; 0/0 is "no position yet") of the
//!   first system that sends one, or from its HOME_POSITION once one
//!   comes: the ground distance by haversine, and the slant range with
//!   the altitude difference. A window gives its last position's.
//! - **Silences** are gaps of at least the silence threshold between two
//!   frames of any source but a radio's own (compid 68 or 240): nothing
//!   came over the link. A silence carries the followed radio's figures
//!   during it, min/mean/max in its kind's units ([`RadioKind`]: told
//!   from what it sends, or `--radio-type`), and a diagnosis where the
//!   figures support one ([`Diagnosis`]): the remote figures cleared
//!   (SiK lost the link), the vehicle's radio no longer hearing the
//!   ground, both signals at the floor (range), the signal fine and the
//!   noise up (interference), or the radio link fine throughout.
//! - **A loss burst** is a run of consecutive windows each losing at least
//!   [`BURST_LOSS_PCT`] of their frames.

use hdrhistogram::Histogram;
use std::collections::VecDeque;

use serde::Serialize;

use crate::engine::radio::{
    is_radio_ids, Evidence, Field, PairFilter, RadioKind, RadioType, RawHistogram,
    SinceBootCounter, SIK_STEPS_PER_DB, WEAK_FADE_MARGIN_DB,
};
use crate::engine::Nanos;
use crate::frame::{Fix, FixKind, Frame, Msg, RadioStatus, SysComp};

/// The windows' length unless told otherwise: a few hundred frames of a
/// usual telemetry stream, short beside a flight.
pub(crate) const DEFAULT_WINDOW_NS: Nanos = 10_000_000_000;
/// A gap this long with nothing over the link is a silence (unless `--gap`).
pub(crate) const DEFAULT_SILENCE_NS: Nanos = 2_000_000_000;
/// A window losing at least this share of its frames is part of a burst.
pub(crate) const BURST_LOSS_PCT: f64 = 10.0;
/// Windows kept for the summary: the most lossy.
pub(crate) const WORST: usize = 5;
/// Silences and bursts kept for the summary: the longest.
pub(crate) const KEPT: usize = 5;
/// Events closed and not yet told: the driver tells them after each batch
/// of frames, which covers at most a second of log time.
pub(crate) const PENDING: usize = 64;
/// The mean Earth radius (IUGG), metres.
pub(crate) const EARTH_RADIUS_M: f64 = 6_371_008.8;
/// 255 in RADIO_STATUS's 8-bit figures means unknown.
const UNKNOWN: u8 = 255;
/// A SiK fade margin under this is a radio hearing only noise.
const AT_THE_FLOOR_DB: f64 = 3.0;
/// Noise this much above its level before the silence is interference.
const NOISE_RISE_DB: f64 = 6.0;
/// mLRS: an RSSI at or under this is weak (its modes' sensitivity is
/// about -105 to -112 dBm)...
const MLRS_WEAK_DBM: f64 = -105.0;
/// ...and one at or above this is fine.
const MLRS_FINE_DBM: f64 = -100.0;
/// An SNR this low (dB) is a link near its limit.
const LOW_SNR_DB: f64 = 3.0;
/// ExpressLRS: a link quality at or above this (%) is fine.
const ELRS_FINE_LQ: f64 = 90.0;

/// Where the vehicle was, against the origin.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub(crate) struct Range {
    /// Along the ground (haversine), metres.
    pub(crate) ground_m: f64,
    /// In a straight line: ground and altitude difference, metres.
    pub(crate) distance_m: f64,
    /// Above mean sea level, metres.
    pub(crate) alt_m: f64,
}

/// The radio's figures in a window: the means of its reports (unknown
/// values left out) and what its error counter grew by.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub(crate) struct RadioWindow {
    pub(crate) reports: u64,
    pub(crate) rssi: Option<f64>,
    pub(crate) remrssi: Option<f64>,
    pub(crate) noise: Option<f64>,
    pub(crate) remnoise: Option<f64>,
    /// Wrap-safe growth of `rxerrors` from the report before the window's
    /// first to its last.
    pub(crate) rxerrors: u64,
}

/// One window of log time, `start` to `end` (ns since the log's first
/// record). Serialised as the JSON `flight_window` line's figures, which
/// the line follows its place and its times with (so they are skipped
/// here).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub(crate) struct FlightWindow {
    /// Its place, from 0.
    #[serde(skip)]
    pub(crate) index: u64,
    #[serde(skip)]
    pub(crate) start: Nanos,
    #[serde(skip)]
    pub(crate) end: Nanos,
    pub(crate) received: u64,
    /// Of `received`, frames whose number had been seen already.
    pub(crate) duplicate: u64,
    pub(crate) lost: i64,
    /// `100 * lost / (lost + distinct received)`; `None` with neither.
    pub(crate) loss_pct: Option<f64>,
    pub(crate) radio: Option<RadioWindow>,
    /// At the window's last position.
    pub(crate) range: Option<Range>,
    /// The vehicle's frames' age above its baseline in the window, by
    /// their own clock stamps: a queue that grew there.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(crate) age: Option<WindowAge>,
}

/// Ages above the baseline in one window, ms.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub(crate) struct WindowAge {
    pub(crate) p99_ms: f64,
    pub(crate) max_ms: f64,
}

/// A silence or a loss burst, `start` to `end`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub(crate) struct Span {
    pub(crate) start: Nanos,
    pub(crate) end: Nanos,
    /// Frames received and lost in it (a burst's windows; 0 for a silence).
    pub(crate) received: u64,
    pub(crate) lost: i64,
    /// Still on at the end of the log.
    pub(crate) ongoing: bool,
    /// A silence: the followed radio's figures during it.
    pub(crate) radio: Option<Box<SilenceRadio>>,
}

/// One radio figure over a silence: as sent, and in its kind's unit.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub(crate) struct SilenceFigure {
    /// As text names it (`remote rssi`, `link quality`, `snr`).
    pub(crate) label: &'static str,
    /// `dBm`, `dB`, `%`; `raw` where the kind gives the field no unit.
    pub(crate) unit: &'static str,
    pub(crate) min: f64,
    pub(crate) mean: f64,
    pub(crate) max: f64,
    /// The bytes as sent (255, unknown, left out).
    pub(crate) raw_min: f64,
    pub(crate) raw_mean: f64,
    pub(crate) raw_max: f64,
}

/// What the radio's figures say about a silence; given only where they
/// support it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub(crate) enum Diagnosis {
    /// SiK: its remote figures were 0 throughout: it clears them once it
    /// has heard nothing from the other radio for ~3 s.
    RemoteCleared,
    /// mLRS: no remote figures (255) throughout.
    RemoteUnknown,
    /// The vehicle's radio no longer heard the ground: its figures (the
    /// remote ones; ExpressLRS's link quality) at the floor while the
    /// ground side heard it.
    UplinkLost,
    /// Both sides' signals weak: range (or an antenna).
    Range,
    /// The signal fine and the noise up (or the SNR down): interference.
    Interference,
    /// The radio link's figures stayed good: the silence is not the radio.
    RadioFine,
}

/// The followed radio during a silence.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub(crate) struct SilenceRadio {
    pub(crate) id: SysComp,
    pub(crate) kind: RadioKind,
    /// Its reports during the silence (none: its figures are `None`).
    pub(crate) reports: u64,
    pub(crate) rssi: Option<SilenceFigure>,
    pub(crate) remrssi: Option<SilenceFigure>,
    pub(crate) noise: Option<SilenceFigure>,
    pub(crate) remnoise: Option<SilenceFigure>,
    /// The `noise` field's mean in the silence less its mean over the
    /// rest of the log, in dB where the kind gives it one (SiK: the noise
    /// floor's rise; mLRS, ExpressLRS: the SNR's change).
    pub(crate) noise_change_db: Option<f64>,
    pub(crate) diagnosis: Option<Diagnosis>,
}

impl Span {
    pub(crate) fn length_ns(&self) -> Nanos {
        self.end.saturating_sub(self.start)
    }

    pub(crate) fn loss_pct(&self) -> Option<f64> {
        loss_pct(self.received, self.lost)
    }
}

/// What the timeline tells, in order.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum FlightEvent {
    Window(FlightWindow),
    Silence(Span),
    Burst(Span),
}

impl crate::engine::kind::KindValue for FlightEvent {}

/// The link's totals as the source table has them (the radio left out).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub(crate) struct Totals {
    pub(crate) received: u64,
    pub(crate) duplicate: u64,
    pub(crate) lost: u64,
}

/// Where the distances are measured from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub(crate) enum OriginKind {
    FirstFix,
    Home,
}

#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub(crate) struct Origin {
    pub(crate) kind: OriginKind,
    pub(crate) lat_deg: f64,
    pub(crate) lon_deg: f64,
    pub(crate) alt_m: f64,
    /// The system whose positions are read.
    pub(crate) vehicle: SysComp,
}

/// The timeline's summary, at the end of the log.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub(crate) struct FlightSummary {
    pub(crate) window_ns: Nanos,
    pub(crate) silence_ns: Nanos,
    pub(crate) burst_loss_pct: f64,
    /// Windows told, the last (partial) one included.
    pub(crate) windows: u64,
    /// Windows closed while [`PENDING`] were waiting: counted, not told.
    pub(crate) untold: u64,
    /// The last window, up to the end of the log (told with the summary).
    pub(crate) last: Option<FlightWindow>,
    /// A burst the last window ended: told with it, as every other burst
    /// is told with the window that ends it.
    pub(crate) last_burst: Option<Span>,
    /// The most lossy windows, worst first.
    pub(crate) worst: Vec<FlightWindow>,
    pub(crate) silence_count: u64,
    pub(crate) silences: Vec<Span>,
    pub(crate) burst_count: u64,
    pub(crate) bursts: Vec<Span>,
    pub(crate) origin: Option<Origin>,
    /// The farthest window (by its last position), and its loss.
    pub(crate) farthest: Option<FlightWindow>,
    pub(crate) positions: u64,
    pub(crate) radio: Option<SysComp>,
    /// What the followed radio is, as the whole log shows it.
    pub(crate) radio_kind: Option<RadioKind>,
    pub(crate) radio_evidence: Vec<String>,
}

impl FlightSummary {
    /// The silences and the bursts counted but not kept in the lists (the
    /// shorter ones).
    pub(crate) fn unlisted(&self) -> (u64, u64) {
        let more = |count: u64, kept: usize| count.saturating_sub(kept as u64);
        let silences = more(self.silence_count, self.silences.len());
        (silences, more(self.burst_count, self.bursts.len()))
    }
}

/// The window under way.
#[derive(Debug, Clone, Default)]
struct Current {
    index: u64,
    start: Nanos,
    /// The table's totals when it began.
    totals: Totals,
    reports: u64,
    sums: [f64; 4],
    counts: [u64; 4],
    /// The radio's error counter's growth when it began.
    rxerrors_at_start: u64,
    range: Option<Range>,
    /// The vehicle's frames' ages in it, µs (made at the first).
    ages: Option<Histogram<u64>>,
}

#[derive(Debug, Clone)]
pub(crate) struct Flight {
    window_ns: Nanos,
    silence_ns: Nanos,
    current: Current,
    pending: VecDeque<FlightEvent>,
    untold: u64,
    told: u64,
    last_frame: Option<Nanos>,
    burst: Option<Span>,
    worst: Vec<FlightWindow>,
    silence_count: u64,
    silences: Vec<Span>,
    burst_count: u64,
    bursts: Vec<Span>,
    vehicle: Option<SysComp>,
    /// The vehicle sends GLOBAL_POSITION_INT: its GPS_RAW_INT is not read.
    estimates: bool,
    origin: Option<Origin>,
    positions: u64,
    farthest: Option<FlightWindow>,
    radio: Option<SysComp>,
    rxerrors: SinceBootCounter,
    /// `--radio-type`, and what the followed radio sent that tells its kind.
    radio_type: RadioType,
    evidence: Evidence,
    pair: PairFilter,
    /// Its reports since the last frame over the link (a silence's, when
    /// the next frame ends one), and all of them: rssi, remrssi, noise,
    /// remnoise by [`Field::index`].
    quiet: [RawHistogram; 4],
    quiet_reports: u64,
    all: [RawHistogram; 4],
}

impl Flight {
    pub(crate) fn new(window_ns: Nanos, silence_ns: Nanos, radio_type: RadioType) -> Self {
        Flight {
            window_ns: window_ns.max(1),
            silence_ns,
            current: Current::default(),
            pending: VecDeque::new(),
            untold: 0,
            told: 0,
            last_frame: None,
            burst: None,
            worst: Vec::new(),
            silence_count: 0,
            silences: Vec::new(),
            burst_count: 0,
            bursts: Vec::new(),
            vehicle: None,
            estimates: false,
            origin: None,
            positions: 0,
            farthest: None,
            radio: None,
            rxerrors: SinceBootCounter::default(),
            radio_type,
            evidence: Evidence::default(),
            pair: PairFilter::default(),
            quiet: Default::default(),
            quiet_reports: 0,
            all: Default::default(),
        }
    }

    /// The window under way ends at or before `at`: the driver closes it
    /// (with [`Flight::close`]) before it takes anything at `at`.
    pub(crate) fn due(&self, at: Nanos) -> bool {
        at >= self.end()
    }

    fn end(&self) -> Nanos {
        self.current.start.saturating_add(self.window_ns)
    }

    /// Closes the window under way, the table's totals being `totals`, and
    /// begins the next.
    pub(crate) fn close(&mut self, totals: Totals) {
        let end = self.end();
        let window = self.window(end, totals);
        self.next_window(end, totals);
        self.after_window(&window);
        self.push(FlightEvent::Window(window));
    }

    /// Takes one frame in: its time for the silences, a RADIO_STATUS (or
    /// RADIO: a report sent as both counts once), a radio's HEARTBEAT or
    /// a position.
    pub(crate) fn on_received(&mut self, frame: &Frame, at: Nanos) {
        self.take(frame.source, frame.msgid, frame.packet_seq, &frame.msg, at);
    }

    #[cfg(test)]
    /// [`Flight::on_received`] of a frame from `source` carrying `msg`.
    pub(crate) fn on_frame(&mut self, source: SysComp, msg: &Msg, at: Nanos) {
        self.take(source, crate::frame::ids::RADIO_STATUS, 0, msg, at);
    }

    fn take(&mut self, source: SysComp, msgid: u32, seq: u8, msg: &Msg, at: Nanos) {
        if !is_radio_ids(source) && self.radio != Some(source) {
            self.heard(at);
        }
        match msg {
            Msg::RadioStatus(r) => self.radio_status(source, msgid, seq, r, at),
            Msg::Heartbeat {
                mav_type,
                autopilot,
            } if self.radio == Some(source) => self.evidence.heartbeat(*mav_type, *autopilot),
            Msg::Fix(f) => self.fix(source, f),
            _ => {}
        }
    }

    /// The age above its baseline of a frame from `source` (its clock
    /// stamps'): kept for the window when `source` is the vehicle.
    pub(crate) fn age(&mut self, source: SysComp, age_ms: f64) {
        if self.vehicle.is_some_and(|v| v != source) || is_radio_ids(source) {
            return;
        }
        let ages = self.current.ages.get_or_insert_with(|| {
            // µs to an hour, two significant digits: a window's p99.
            Histogram::new_with_bounds(1, 3_600_000_000, 2).expect("valid bounds")
        });
        ages.saturating_record((age_ms * 1e3).max(1.0) as u64);
    }

    /// The events closed since the last call, in order.
    pub(crate) fn drain(&mut self) -> impl Iterator<Item = FlightEvent> + '_ {
        self.pending.drain(..)
    }

    /// The summary at `at`, the end of the log: the window under way is
    /// the last, an open burst or a silence still on is listed as ongoing.
    pub(crate) fn summary(&self, at: Nanos, totals: Totals) -> FlightSummary {
        let mut s = self.clone();
        let mut last_burst = None;
        let last = (at > s.current.start || s.told == 0).then(|| {
            let w = s.window(at.max(s.current.start), totals);
            let open = s.burst.clone();
            s.after_window(&w);
            if s.burst.is_none() {
                last_burst = open;
            }
            w
        });
        if let Some(mut b) = s.burst.take() {
            b.ongoing = true;
            s.keep_burst(b);
        }
        if let Some(from) = s
            .last_frame
            .filter(|&f| at.saturating_sub(f) >= s.silence_ns)
        {
            let radio = s.silence_radio();
            s.keep_silence(Span {
                start: from,
                end: at,
                received: 0,
                lost: 0,
                ongoing: true,
                radio,
            });
        }
        let judgement = s.radio.map(|id| s.evidence.judge(id, s.radio_type));
        FlightSummary {
            window_ns: s.window_ns,
            silence_ns: s.silence_ns,
            burst_loss_pct: BURST_LOSS_PCT,
            windows: s.told + s.untold + u64::from(last.is_some()),
            untold: s.untold,
            last,
            last_burst,
            worst: s.worst,
            silence_count: s.silence_count,
            silences: s.silences,
            burst_count: s.burst_count,
            bursts: s.bursts,
            origin: s.origin,
            farthest: s.farthest,
            positions: s.positions,
            radio: s.radio,
            radio_kind: judgement.as_ref().map(|j| j.kind),
            radio_evidence: judgement.map(|j| j.evidence).unwrap_or_default(),
        }
    }

    fn window(&self, end: Nanos, totals: Totals) -> FlightWindow {
        let c = &self.current;
        let received = totals.received.saturating_sub(c.totals.received);
        let duplicate = totals.duplicate.saturating_sub(c.totals.duplicate);
        let lost = totals.lost as i64 - c.totals.lost as i64;
        let mean = |k: usize| (c.counts[k] > 0).then(|| c.sums[k] / c.counts[k] as f64);
        FlightWindow {
            index: c.index,
            start: c.start,
            end,
            received,
            duplicate,
            lost,
            loss_pct: loss_pct(received.saturating_sub(duplicate), lost),
            radio: (c.reports > 0).then(|| RadioWindow {
                reports: c.reports,
                rssi: mean(0),
                remrssi: mean(1),
                noise: mean(2),
                remnoise: mean(3),
                rxerrors: self.rxerrors.grown() - c.rxerrors_at_start,
            }),
            range: c.range,
            age: c.ages.as_ref().map(|h| WindowAge {
                p99_ms: h.value_at_quantile(0.99) as f64 / 1e3,
                max_ms: h.max() as f64 / 1e3,
            }),
        }
    }

    fn next_window(&mut self, start: Nanos, totals: Totals) {
        self.current = Current {
            index: self.current.index + 1,
            start,
            totals,
            rxerrors_at_start: self.rxerrors.grown(),
            ..Current::default()
        };
    }

    /// What a closed window changes: the worst and farthest kept, a burst
    /// begun, grown or ended.
    fn after_window(&mut self, w: &FlightWindow) {
        self.keep_worst(*w);
        if let Some(r) = w.range {
            let farther = self
                .farthest
                .and_then(|f| f.range)
                .is_none_or(|f| r.distance_m > f.distance_m);
            if farther {
                self.farthest = Some(*w);
            }
        }
        let bursting = w.loss_pct.is_some_and(|p| p >= BURST_LOSS_PCT);
        match (&mut self.burst, bursting) {
            (Some(b), true) => {
                b.end = w.end;
                b.received += w.received;
                b.lost += w.lost;
            }
            (None, true) => {
                self.burst = Some(Span {
                    start: w.start,
                    end: w.end,
                    received: w.received,
                    lost: w.lost,
                    ongoing: false,
                    radio: None,
                });
            }
            (Some(_), false) => {
                let b = self.burst.take().expect("a burst under way");
                self.keep_burst(b.clone());
                self.push(FlightEvent::Burst(b));
            }
            (None, false) => {}
        }
    }

    fn heard(&mut self, at: Nanos) {
        if let Some(last) = self.last_frame {
            if at.saturating_sub(last) >= self.silence_ns {
                let s = Span {
                    start: last,
                    end: at,
                    received: 0,
                    lost: 0,
                    ongoing: false,
                    radio: self.silence_radio(),
                };
                self.keep_silence(s.clone());
                self.push(FlightEvent::Silence(s));
            }
        }
        self.last_frame = Some(at);
        if self.quiet_reports > 0 {
            self.quiet_reports = 0;
            self.quiet.iter_mut().for_each(RawHistogram::clear);
        }
    }

    /// The followed radio's figures since the last frame over the link:
    /// a silence's, as it ends (or at the end of the log).
    fn silence_radio(&self) -> Option<Box<SilenceRadio>> {
        let id = self.radio?;
        let kind = self.evidence.judge(id, self.radio_type).kind;
        let figure = |field: Field| {
            let h = &self.quiet[field.index()];
            let raw = h.raw_range()?;
            let meaning = kind.meaning(field);
            let (label, unit, converted) = match meaning {
                Some(m) => (m.label, m.unit, h.range(m.convert)?),
                None => (raw_label(field), "raw", raw),
            };
            Some(SilenceFigure {
                label,
                unit,
                min: converted.min,
                mean: converted.mean,
                max: converted.max,
                raw_min: raw.min,
                raw_mean: raw.mean,
                raw_max: raw.max,
            })
        };
        let before: [RawHistogram; 4] = std::array::from_fn(|i| self.all[i].minus(&self.quiet[i]));
        Some(Box::new(SilenceRadio {
            id,
            kind,
            reports: self.quiet_reports,
            rssi: figure(Field::Rssi),
            remrssi: figure(Field::Remrssi),
            noise: figure(Field::Noise),
            remnoise: figure(Field::Remnoise),
            noise_change_db: kind
                .meaning(Field::Noise)
                .filter(|m| m.unit == "dBm" || m.unit == "dB")
                .and_then(|m| {
                    let during = self.quiet[Field::Noise.index()].range(m.convert)?;
                    let was = before[Field::Noise.index()].range(m.convert)?;
                    Some(during.mean - was.mean)
                }),
            diagnosis: (self.quiet_reports > 0)
                .then(|| diagnose(kind, &self.quiet, &before))
                .flatten(),
        }))
    }

    /// The first radio heard is the one followed.
    fn radio_status(&mut self, source: SysComp, msgid: u32, seq: u8, r: &RadioStatus, at: Nanos) {
        if *self.radio.get_or_insert(source) != source {
            return;
        }
        if self.pair.repeats(msgid, seq, r) {
            self.evidence.report(msgid, r, at, true);
            return;
        }
        self.evidence.report(msgid, r, at, false);
        for field in Field::ALL {
            self.quiet[field.index()].record(field.of(r));
            self.all[field.index()].record(field.of(r));
        }
        self.quiet_reports += 1;
        self.rxerrors.record(r.rxerrors);
        let c = &mut self.current;
        c.reports += 1;
        for (k, v) in [r.rssi, r.remrssi, r.noise, r.remnoise]
            .into_iter()
            .enumerate()
        {
            if v != UNKNOWN {
                c.sums[k] += f64::from(v);
                c.counts[k] += 1;
            }
        }
    }

    fn fix(&mut self, source: SysComp, f: &Fix) {
        if !f.usable(self.estimates) || *self.vehicle.get_or_insert(source) != source {
            return;
        }
        let (lat, lon, alt) = f.degrees();
        if f.kind == FixKind::Home {
            self.origin = Some(Origin {
                kind: OriginKind::Home,
                lat_deg: lat,
                lon_deg: lon,
                alt_m: alt,
                vehicle: source,
            });
            return;
        }
        self.estimates |= f.kind == FixKind::Estimate;
        self.positions += 1;
        let o = *self.origin.get_or_insert(Origin {
            kind: OriginKind::FirstFix,
            lat_deg: lat,
            lon_deg: lon,
            alt_m: alt,
            vehicle: source,
        });
        let ground = haversine_m((o.lat_deg, o.lon_deg), (lat, lon));
        self.current.range = Some(Range {
            ground_m: ground,
            distance_m: ground.hypot(alt - o.alt_m),
            alt_m: alt,
        });
    }

    fn push(&mut self, e: FlightEvent) {
        if self.pending.len() >= PENDING {
            self.untold += 1;
            return;
        }
        if matches!(e, FlightEvent::Window(_)) {
            self.told += 1;
        }
        self.pending.push_back(e);
    }

    fn keep_worst(&mut self, w: FlightWindow) {
        let Some(pct) = w.loss_pct.filter(|&p| p > 0.0) else {
            return;
        };
        let at = self
            .worst
            .iter()
            .position(|k| k.loss_pct.unwrap_or(0.0) < pct)
            .unwrap_or(self.worst.len());
        if at < WORST {
            self.worst.insert(at, w);
            self.worst.truncate(WORST);
        }
    }

    fn keep_silence(&mut self, s: Span) {
        self.silence_count += 1;
        keep_longest(&mut self.silences, s);
    }

    fn keep_burst(&mut self, b: Span) {
        self.burst_count += 1;
        keep_longest(&mut self.bursts, b);
    }
}

fn raw_label(field: Field) -> &'static str {
    match field {
        Field::Rssi => "rssi",
        Field::Remrssi => "remote rssi",
        Field::Noise => "noise",
        Field::Remnoise => "remote noise",
    }
}

/// The mean of one field, converted, over `h`.
fn mean(h: &RawHistogram, convert: impl Fn(u8) -> Option<f64>) -> Option<f64> {
    h.range(convert).map(|r| r.mean)
}

/// What the radio's figures during a silence (`quiet`) say, against the
/// rest of the log (`before`): only what they support.
fn diagnose(
    kind: RadioKind,
    quiet: &[RawHistogram; 4],
    before: &[RawHistogram; 4],
) -> Option<Diagnosis> {
    let h = |f: Field| &quiet[f.index()];
    let b = |f: Field| &before[f.index()];
    let raw = |v: u8| (v != UNKNOWN).then_some(f64::from(v));
    match kind {
        RadioKind::Sik => {
            let (rssi, remrssi) = (h(Field::Rssi).raw_range()?, h(Field::Remrssi).raw_range());
            let remnoise = h(Field::Remnoise).raw_range();
            if remrssi.is_some_and(|r| r.max == 0.0) && remnoise.is_some_and(|r| r.max == 0.0) {
                return Some(Diagnosis::RemoteCleared);
            }
            let noise = mean(h(Field::Noise), raw)?;
            let local_fade = (rssi.mean - noise) / SIK_STEPS_PER_DB;
            let remote_fade = remrssi
                .zip(remnoise)
                .map(|(r, n)| (r.mean - n.mean) / SIK_STEPS_PER_DB);
            let rise = |f: Field| {
                let was = mean(b(f), raw)?;
                Some((mean(h(f), raw)? - was) / SIK_STEPS_PER_DB)
            };
            let noise_rise = rise(Field::Noise)
                .into_iter()
                .chain(rise(Field::Remnoise))
                .fold(f64::NEG_INFINITY, f64::max);
            let rssi_held = rise(Field::Rssi).is_none_or(|d| d > -AT_THE_FLOOR_DB);
            if remote_fade.is_some_and(|f| f < AT_THE_FLOOR_DB) && local_fade >= WEAK_FADE_MARGIN_DB
            {
                Some(Diagnosis::UplinkLost)
            } else if noise_rise >= NOISE_RISE_DB && rssi_held {
                Some(Diagnosis::Interference)
            } else if local_fade < WEAK_FADE_MARGIN_DB
                && remote_fade.is_some_and(|f| f < WEAK_FADE_MARGIN_DB)
            {
                Some(Diagnosis::Range)
            } else if local_fade >= WEAK_FADE_MARGIN_DB
                && remote_fade.is_some_and(|f| f >= WEAK_FADE_MARGIN_DB)
            {
                Some(Diagnosis::RadioFine)
            } else {
                None
            }
        }
        RadioKind::Mlrs => {
            let dbm = |f: Field| {
                let m = kind.meaning(f)?;
                h(f).range(m.convert)
            };
            let remrssi_raw = h(Field::Remrssi);
            if remrssi_raw.count() > 0 && remrssi_raw.raw_range().is_none() {
                return Some(Diagnosis::RemoteUnknown);
            }
            let (rssi, remrssi) = (dbm(Field::Rssi)?, dbm(Field::Remrssi)?);
            let snr = dbm(Field::Noise);
            let snr_before = kind
                .meaning(Field::Noise)
                .and_then(|m| b(Field::Noise).range(m.convert));
            if remrssi_raw.raw_range().is_some_and(|r| r.max == 0.0) && rssi.mean >= MLRS_FINE_DBM {
                Some(Diagnosis::UplinkLost)
            } else if rssi.mean <= MLRS_WEAK_DBM && remrssi.mean <= MLRS_WEAK_DBM {
                Some(Diagnosis::Range)
            } else if rssi.mean >= MLRS_FINE_DBM
                && remrssi.mean >= MLRS_FINE_DBM
                && snr.zip(snr_before).is_some_and(|(s, was)| {
                    s.mean < LOW_SNR_DB && was.mean - s.mean >= NOISE_RISE_DB
                })
            {
                Some(Diagnosis::Interference)
            } else if rssi.mean >= MLRS_FINE_DBM
                && remrssi.mean >= MLRS_FINE_DBM
                && snr.is_none_or(|s| s.mean >= LOW_SNR_DB)
            {
                Some(Diagnosis::RadioFine)
            } else {
                None
            }
        }
        RadioKind::Elrs => {
            let m = kind.meaning(Field::Rssi)?;
            let lq = h(Field::Rssi).range(m.convert)?;
            if lq.max == 0.0 {
                Some(Diagnosis::UplinkLost)
            } else if lq.min >= ELRS_FINE_LQ {
                Some(Diagnosis::RadioFine)
            } else {
                None
            }
        }
        RadioKind::Esp | RadioKind::Unknown => None,
    }
}

/// A silence's diagnosis in words, with the figures it rests on.
pub(crate) fn diagnosis_text(span: &Span) -> Option<String> {
    let r = span.radio.as_ref()?;
    let d = r.diagnosis?;
    let secs = span.length_ns() as f64 / 1e9;
    let mean = |f: &Option<SilenceFigure>| {
        f.map_or_else(String::new, |f| match f.unit {
            "raw" => format!("{:.0}", f.mean),
            "%" => format!("{:.0}%", f.mean),
            unit => format!("{:.0} {unit}", f.mean),
        })
    };
    let local = match r.kind {
        RadioKind::Sik => format!(
            "local rssi {}, noise floor {}",
            mean(&r.rssi),
            mean(&r.noise)
        ),
        _ => format!("local rssi {}", mean(&r.rssi)),
    };
    let text = match d {
        Diagnosis::RemoteCleared => {
            let deaf = r.rssi.zip(r.noise).is_some_and(|(rssi, noise)| {
                (rssi.raw_mean - noise.raw_mean) / SIK_STEPS_PER_DB < AT_THE_FLOOR_DB
            });
            format!(
                "remote RSSI 0 for {secs:.0} s: the ground radio heard nothing from the \
                 vehicle's (SiK clears the remote figures after ~3 s without a packet); \
                 {} ({local})",
                if deaf {
                    "it heard only noise itself"
                } else {
                    "its own figures"
                }
            )
        }
        Diagnosis::RemoteUnknown => format!(
            "remote RSSI unknown (255) for {secs:.0} s: no figures came back from the \
             vehicle's radio ({local})"
        ),
        Diagnosis::UplinkLost if r.kind == RadioKind::Elrs => format!(
            "link quality 0% for {secs:.0} s: the vehicle's receiver stopped hearing the ground"
        ),
        Diagnosis::UplinkLost => format!(
            "remote RSSI {} for {secs:.0} s while the ground heard the vehicle's radio \
             ({local}): the vehicle's radio stopped hearing the ground",
            mean(&r.remrssi)
        ),
        Diagnosis::Range => format!(
            "local RSSI {} and remote RSSI {} both weak, the noise as before: range (or an antenna)",
            mean(&r.rssi),
            mean(&r.remrssi)
        ),
        Diagnosis::Interference => {
            let change = r.noise_change_db.unwrap_or(0.0);
            let (what, way) = if r.kind == RadioKind::Sik {
                ("noise floor", "up")
            } else {
                ("SNR", "down")
            };
            format!(
                "RSSI held ({}) and the {what} {way} {:.0} dB (to {}) against the rest of \
                 the log: interference",
                mean(&r.rssi),
                change.abs(),
                mean(&r.noise)
            )
        }
        Diagnosis::RadioFine => "the radio link's figures stayed good throughout: not the \
                                 radio; the vehicle, its serial port or the ground side stopped"
            .to_string(),
    };
    Some(text)
}

/// Keeps the [`KEPT`] longest of `spans`, in time order.
fn keep_longest(spans: &mut Vec<Span>, s: Span) {
    spans.push(s);
    if spans.len() > KEPT {
        let shortest = spans
            .iter()
            .enumerate()
            .min_by_key(|(_, k)| k.length_ns())
            .map(|(i, _)| i)
            .expect("not empty");
        spans.remove(shortest);
    }
    spans.sort_by_key(|k| k.start);
}

fn loss_pct(distinct: u64, lost: i64) -> Option<f64> {
    let lost = lost.max(0) as f64;
    let whole = lost + distinct as f64;
    (whole > 0.0).then(|| 100.0 * lost / whole)
}

/// The great-circle distance between two (lat, lon) in degrees, metres.
pub(crate) fn haversine_m(a: (f64, f64), b: (f64, f64)) -> f64 {
    let (la1, lo1) = (a.0.to_radians(), a.1.to_radians());
    let (la2, lo2) = (b.0.to_radians(), b.1.to_radians());
    let h = ((la2 - la1) / 2.0).sin().powi(2)
        + la1.cos() * la2.cos() * ((lo2 - lo1) / 2.0).sin().powi(2);
    2.0 * EARTH_RADIUS_M * h.sqrt().min(1.0).asin()
}

#[cfg(test)]
mod tests {
    /// The SiK radio's own ids (51/68), as the source table names them.
    const RADIO_SOURCE: SysComp = SysComp::new(51, 68);
    use super::*;

    const S: Nanos = 1_000_000_000;
    const VEHICLE: SysComp = SysComp::new(1, 1);

    fn flight(window_ns: Nanos, silence_ns: Nanos) -> Flight {
        Flight::new(window_ns, silence_ns, RadioType::Auto)
    }

    fn windows(f: &mut Flight) -> Vec<FlightWindow> {
        f.drain()
            .filter_map(|e| match e {
                FlightEvent::Window(w) => Some(w),
                _ => None,
            })
            .collect()
    }

    /// A 50 Hz stream for `seconds`, `lost(second)` frames lost each
    /// second, fed as the driver does: due windows closed with the totals
    /// before the frame is taken.
    fn stream(f: &mut Flight, seconds: u64, lost: impl Fn(u64) -> u64) -> Totals {
        let mut t = Totals::default();
        for n in 0..seconds * 50 {
            let at = n * S / 50;
            while f.due(at) {
                f.close(t);
            }
            let second = n / 50;
            // The first `lost(second)` frames of each second are gaps.
            if n % 50 < lost(second) {
                t.lost += 1;
                continue;
            }
            t.received += 1;
            f.on_frame(VEHICLE, &Msg::Other, at);
        }
        t
    }

    #[test]
    fn windows_count_what_the_totals_grew_by_and_add_up() {
        let mut f = flight(10 * S, DEFAULT_SILENCE_NS);
        // Seconds 20 to 29 lose 5 of 50 each: window 2 loses 50 of 500.
        let t = stream(&mut f, 35, |s| if (20..30).contains(&s) { 5 } else { 0 });
        let w = windows(&mut f);
        assert_eq!(w.len(), 3);
        assert_eq!(
            w.iter()
                .map(|w| (w.start / S, w.end / S, w.received, w.lost))
                .collect::<Vec<_>>(),
            [(0, 10, 500, 0), (10, 20, 500, 0), (20, 30, 450, 50)]
        );
        assert_eq!(w[2].loss_pct, Some(10.0));
        let s = f.summary(35 * S, t);
        let last = s.last.unwrap();
        assert_eq!((last.start, last.end, last.received), (30 * S, 35 * S, 250));
        assert_eq!(s.windows, 4);
        assert_eq!(s.worst.len(), 1);
        assert_eq!(s.worst[0].index, 2);
        // 10 % is a burst: the one window.
        assert_eq!(s.burst_count, 1);
        assert_eq!((s.bursts[0].start, s.bursts[0].end), (20 * S, 30 * S));
        assert_eq!(s.bursts[0].lost, 50);
    }

    #[test]
    fn consecutive_lossy_windows_are_one_burst_and_its_end_is_told() {
        let mut f = flight(S, DEFAULT_SILENCE_NS);
        let t = stream(&mut f, 12, |s| match s {
            3..=5 => 10,
            7 => 2,
            _ => 0,
        });
        let bursts: Vec<Span> = f
            .drain()
            .filter_map(|e| match e {
                FlightEvent::Burst(b) => Some(b),
                _ => None,
            })
            .collect();
        // Seconds 3 to 5 (20 %); second 7 loses 4 %: no burst.
        assert_eq!(bursts.len(), 1);
        assert_eq!((bursts[0].start, bursts[0].end), (3 * S, 6 * S));
        assert_eq!((bursts[0].received, bursts[0].lost), (120, 30));
        assert_eq!(bursts[0].loss_pct(), Some(20.0));
        let s = f.summary(12 * S, t);
        assert!(s.last_burst.is_none());
        // Worst first; the three 20 % windows, then second 7's.
        let worst: Vec<u64> = s.worst.iter().map(|w| w.index).collect();
        assert_eq!(worst, [3, 4, 5, 7]);
    }

    #[test]
    fn a_burst_the_last_window_ends_is_handed_over_with_it() {
        let mut f = Flight::new(S, DEFAULT_SILENCE_NS, RadioType::Auto);
        // Seconds 8 and 9 lose 20 %; the last, partial, window (from 10 s)
        // loses nothing: it ends the burst, and only the summary sees it.
        let t = stream(&mut f, 11, |s| if (8..10).contains(&s) { 10 } else { 0 });
        assert!(!f.drain().any(|e| matches!(e, FlightEvent::Burst(_))));
        let s = f.summary(10 * S + S / 2, t);
        let b = s.last_burst.expect("the burst the last window ended");
        assert_eq!(
            (b.start, b.end, b.lost, b.ongoing),
            (8 * S, 10 * S, 20, false)
        );
        assert_eq!(s.burst_count, 1);
        // A burst still on at the end is ongoing, not ended.
        let mut f = Flight::new(S, DEFAULT_SILENCE_NS, RadioType::Auto);
        let t = stream(&mut f, 11, |s| if s >= 8 { 10 } else { 0 });
        let s = f.summary(11 * S, t);
        assert!(s.last_burst.is_none());
        assert!(s.bursts[0].ongoing);
    }

    #[test]
    fn a_silence_is_told_with_its_start_and_end_and_windows_go_on_empty() {
        let mut f = flight(10 * S, 2 * S);
        let mut t = Totals::default();
        let mut feed = |f: &mut Flight, at: Nanos| {
            while f.due(at) {
                f.close(t);
            }
            t.received += 1;
            f.on_frame(VEHICLE, &Msg::Other, at);
        };
        feed(&mut f, S);
        // The radio's own frames are not the link talking.
        f.on_frame(RADIO_SOURCE, &Msg::Other, 20 * S);
        feed(&mut f, 25 * S + 500_000_000);
        let events: Vec<FlightEvent> = f.drain().collect();
        assert_eq!(events.len(), 3, "{events:?}");
        // The windows it spans close first, the second one empty.
        assert!(matches!(events[0], FlightEvent::Window(w) if w.received == 1));
        assert!(
            matches!(events[1], FlightEvent::Window(w) if w.received == 0 && w.loss_pct.is_none())
        );
        let FlightEvent::Silence(s) = &events[2] else {
            panic!("{events:?}")
        };
        assert_eq!((s.start, s.end), (S, 25 * S + 500_000_000));
        // Quiet again to the end of the log: an ongoing silence.
        let s = f.summary(40 * S, t);
        assert_eq!(s.silence_count, 2);
        assert!(s.silences[1].ongoing);
        assert_eq!(s.silences[1].end, 40 * S);
    }

    #[test]
    fn rxerrors_grow_across_a_wrap_per_window_and_rssi_is_the_mean() {
        let mut f = flight(10 * S, DEFAULT_SILENCE_NS);
        let radio = |rssi: u8, rxerrors: u16| {
            Msg::RadioStatus(RadioStatus {
                rssi,
                remrssi: 255,
                noise: 40,
                remnoise: 41,
                rxerrors,
                ..RadioStatus::default()
            })
        };
        f.on_frame(RADIO_SOURCE, &radio(200, 65_530), S);
        f.on_frame(RADIO_SOURCE, &radio(180, 65_534), 5 * S);
        f.close(Totals::default());
        f.on_frame(RADIO_SOURCE, &radio(150, 4), 15 * S);
        // Another radio's reports are not mixed in.
        f.on_frame(SysComp::new(52, 68), &radio(10, 9_000), 16 * S);
        f.close(Totals::default());
        let w = windows(&mut f);
        let r0 = w[0].radio.unwrap();
        assert_eq!((r0.reports, r0.rssi, r0.remrssi), (2, Some(190.0), None));
        assert_eq!((r0.noise, r0.rxerrors), (Some(40.0), 4));
        let r1 = w[1].radio.unwrap();
        // 65 534 → 4 through the wrap: 6.
        assert_eq!((r1.reports, r1.rssi, r1.rxerrors), (1, Some(150.0), 6));
    }

    #[test]
    fn haversine_matches_known_distances() {
        // One degree of latitude on this sphere: 2πR/360.
        let degree = 2.0 * std::f64::consts::PI * EARTH_RADIUS_M / 360.0;
        assert!((haversine_m((47.0, 8.0), (48.0, 8.0)) - degree).abs() < 1e-6);
        // Zürich to Geneva, about 224 km as the crow flies.
        let d = haversine_m((47.3769, 8.5417), (46.2044, 6.1432));
        assert!((d - 224_000.0).abs() < 2_000.0, "{d}");
        assert_eq!(haversine_m((10.0, 20.0), (10.0, 20.0)), 0.0);
    }

    fn fix(kind: FixKind, north_m: f64, alt_m: f64) -> Msg {
        let lat = 47.0 + (north_m / EARTH_RADIUS_M).to_degrees();
        Msg::Fix(Fix {
            kind,
            lat: (lat * 1e7).round() as i32,
            lon: 80_000_000,
            alt_mm: (alt_m * 1e3) as i32,
        })
    }

    #[test]
    fn distance_is_from_the_first_fix_then_from_home() {
        let mut f = flight(10 * S, DEFAULT_SILENCE_NS);
        // No position yet, then a 2D-less GPS: neither is a fix.
        let none = Msg::Fix(Fix {
            kind: FixKind::Estimate,
            lat: 0,
            lon: 0,
            alt_mm: 0,
        });
        f.on_frame(VEHICLE, &none, 0);
        f.on_frame(VEHICLE, &fix(FixKind::Gps { fix_type: 1 }, 500.0, 100.0), 0);
        f.on_frame(VEHICLE, &fix(FixKind::Estimate, 100.0, 100.0), S);
        f.on_frame(VEHICLE, &fix(FixKind::Estimate, 400.0, 140.0), 2 * S);
        // Once the vehicle sends estimates, its raw GPS is not read.
        f.on_frame(
            VEHICLE,
            &fix(FixKind::Gps { fix_type: 3 }, 9_000.0, 0.0),
            3 * S,
        );
        f.close(Totals::default());
        f.on_frame(VEHICLE, &fix(FixKind::Home, 0.0, 100.0), 11 * S);
        f.on_frame(VEHICLE, &fix(FixKind::Estimate, 1_000.0, 100.0), 12 * S);
        // Another system's positions are not the vehicle's.
        f.on_frame(
            SysComp::new(2, 1),
            &fix(FixKind::Estimate, 5e5, 0.0),
            13 * S,
        );
        f.close(Totals::default());
        let w = windows(&mut f);
        let r0 = w[0].range.unwrap();
        // 300 m north of the first fix, 40 m up: 500 m in a line.
        assert!((r0.ground_m - 300.0).abs() < 0.02, "{r0:?}");
        assert!((r0.distance_m - 300f64.hypot(40.0)).abs() < 0.02, "{r0:?}");
        assert_eq!(r0.alt_m, 140.0);
        let r1 = w[1].range.unwrap();
        assert!((r1.ground_m - 1_000.0).abs() < 0.02, "{r1:?}");
        let s = f.summary(20 * S, Totals::default());
        assert_eq!(s.origin.unwrap().kind, OriginKind::Home);
        assert_eq!(s.positions, 3);
        assert_eq!(s.farthest.unwrap().index, 1);
    }

    #[test]
    fn memory_is_bounded_over_a_day_of_windows() {
        let mut f = flight(S, DEFAULT_SILENCE_NS);
        let mut t = Totals::default();
        for n in 0..86_400u64 {
            // Every window loses something, every other one a burst.
            t.received += 90;
            t.lost += 1 + 20 * (n % 2);
            f.on_frame(VEHICLE, &Msg::Other, n * S + 1);
            f.close(t);
            assert!(f.pending.len() <= 3);
            f.drain().for_each(drop);
        }
        let s = f.summary(86_400 * S, t);
        assert_eq!(s.worst.len(), WORST);
        assert_eq!(s.bursts.len(), KEPT);
        assert_eq!(s.burst_count, 43_200);
        assert_eq!(s.unlisted(), (0, 43_200 - KEPT as u64));
        assert_eq!(s.untold, 0);
    }

    #[test]
    fn events_past_the_pending_bound_are_counted_not_kept() {
        let mut f = flight(S, DEFAULT_SILENCE_NS);
        for _ in 0..PENDING + 10 {
            f.close(Totals::default());
        }
        assert_eq!(f.pending.len(), PENDING);
        let s = f.summary(f.current.start, Totals::default());
        assert_eq!((s.windows, s.untold), (PENDING as u64 + 10, 10));
    }

    fn sik(rssi: u8, noise: u8, remrssi: u8, remnoise: u8) -> RadioStatus {
        RadioStatus {
            rssi,
            remrssi,
            txbuf: 95,
            noise,
            remnoise,
            rxerrors: 0,
            fixed: 0,
        }
    }

    /// 30 s of a 10 Hz vehicle with `radio` reporting `before` once a
    /// second, then 28 s of nothing from the vehicle while it reports
    /// `during`, then the vehicle again: the silence.
    fn silence_with(radio: SysComp, before: RadioStatus, during: RadioStatus) -> Span {
        silence_at(radio, 1, before, during)
    }

    /// [`silence_with`], the radio reporting `hz` times a second.
    fn silence_at(radio: SysComp, hz: u64, before: RadioStatus, during: RadioStatus) -> Span {
        let mut f = flight(10 * S, DEFAULT_SILENCE_NS);
        let mut t = Totals::default();
        for tick in 0..=6000u64 {
            let at = tick * S / 100;
            while f.due(at) {
                f.close(t);
            }
            let quiet = (3001..5800).contains(&tick);
            if tick % (100 / hz) == 5 % (100 / hz) {
                // Up to the vehicle's first frame after the silence.
                let r = if (3001..=5800).contains(&tick) {
                    during
                } else {
                    before
                };
                f.on_frame(radio, &Msg::RadioStatus(r), at);
            }
            if !quiet && tick % 10 == 0 {
                t.received += 1;
                f.on_frame(VEHICLE, &Msg::Other, at);
            }
        }
        let mut silences: Vec<Span> = f
            .drain()
            .filter_map(|e| match e {
                FlightEvent::Silence(s) => Some(s),
                _ => None,
            })
            .collect();
        assert_eq!(silences.len(), 1, "{silences:?}");
        silences.swap_remove(0)
    }

    const GOOD: RadioStatus = RadioStatus {
        rssi: 150,
        remrssi: 145,
        txbuf: 95,
        noise: 40,
        remnoise: 38,
        rxerrors: 0,
        fixed: 0,
    };

    #[test]
    fn a_sik_that_lost_the_link_clears_its_remote_figures() {
        let s = silence_with(RADIO_SOURCE, GOOD, sik(45, 40, 0, 0));
        assert_eq!((s.start, s.end), (30 * S, 58 * S));
        let r = s.radio.as_deref().unwrap();
        assert_eq!((r.kind, r.reports), (RadioKind::Sik, 28));
        let remrssi = r.remrssi.unwrap();
        assert_eq!((remrssi.raw_min, remrssi.raw_mean), (0.0, 0.0));
        let rssi = r.rssi.unwrap();
        assert_eq!((rssi.unit, rssi.raw_mean), ("dBm", 45.0));
        assert!((rssi.mean - (45.0 / 1.9 - 127.0)).abs() < 1e-9);
        assert_eq!(r.diagnosis, Some(Diagnosis::RemoteCleared));
        let text = diagnosis_text(&s).unwrap();
        assert!(
            text.starts_with("remote RSSI 0 for 28 s: the ground radio heard nothing"),
            "{text}"
        );
    }

    #[test]
    fn sik_silences_diagnosed_from_the_figures() {
        let cases = [
            // The remote radio hears only noise; the ground hears it fine.
            (sik(150, 40, 40, 39), Some(Diagnosis::UplinkLost)),
            // Noise up ~16 dB, signal held.
            (sik(150, 70, 145, 70), Some(Diagnosis::Interference)),
            // Both fade margins under 10 dB, noise as before.
            (sik(55, 40, 50, 38), Some(Diagnosis::Range)),
            // Nothing wrong with the radio link.
            (GOOD, Some(Diagnosis::RadioFine)),
            // Local fine, remote marginal but above the floor: no claim.
            (sik(150, 40, 50, 38), None),
        ];
        for (during, want) in cases {
            let s = silence_with(RADIO_SOURCE, GOOD, during);
            assert_eq!(s.radio.as_ref().unwrap().diagnosis, want, "{during:?}");
            assert_eq!(diagnosis_text(&s).is_some(), want.is_some());
        }
    }

    #[test]
    fn mlrs_and_elrs_silences_in_their_units() {
        // mLRS (told by its constants: remnoise 255, no errors): the
        // vehicle's module hears nothing (remote RSSI 0: -120 dBm or less)
        // while the ground hears it at -80 dBm.
        let mlrs = |rssi: u8, remrssi: u8| RadioStatus {
            rssi,
            remrssi,
            txbuf: 100,
            noise: 2,
            remnoise: 255,
            rxerrors: 0,
            fixed: 0,
        };
        // -80 dBm is 145, -85 dBm 127.
        let s = silence_with(RADIO_SOURCE, mlrs(145, 127), mlrs(145, 0));
        let r = s.radio.as_deref().unwrap();
        assert_eq!(r.kind, RadioKind::Mlrs);
        let remrssi = r.remrssi.unwrap();
        assert_eq!((remrssi.mean, remrssi.unit), (-120.0, "dBm"));
        assert_eq!(r.rssi.unwrap().mean, -80.0);
        assert_eq!(r.noise.unwrap().label, "snr");
        assert_eq!(r.diagnosis, Some(Diagnosis::UplinkLost));
        // ExpressLRS at 255/68: link quality 0 % throughout.
        let elrs = |lq: u8| RadioStatus {
            rssi: lq,
            remrssi: 70,
            txbuf: 90,
            noise: 8,
            remnoise: 0,
            rxerrors: 0,
            fixed: 0,
        };
        let s = silence_at(SysComp::new(255, 68), 100, elrs(254), elrs(0));
        let r = s.radio.as_deref().unwrap();
        assert_eq!(r.kind, RadioKind::Elrs);
        assert_eq!(
            (r.rssi.unwrap().label, r.rssi.unwrap().max),
            ("link quality", 0.0)
        );
        assert_eq!(r.diagnosis, Some(Diagnosis::UplinkLost));
        assert!(diagnosis_text(&s)
            .unwrap()
            .starts_with("link quality 0% for 28 s"));
    }

    #[test]
    fn radio_and_radio_status_pairs_count_once_in_a_window() {
        let mut f = flight(10 * S, DEFAULT_SILENCE_NS);
        let mut frame = |msgid, seq, rssi: u8, at| {
            let mut fr =
                crate::frame::test_frame(RADIO_SOURCE, Msg::RadioStatus(sik(rssi, 40, 140, 38)));
            fr.msgid = msgid;
            fr.packet_seq = seq;
            f.on_received(&fr, at);
        };
        for (seq, rssi) in [(1u8, 100u8), (2, 200)] {
            frame(crate::frame::ids::RADIO, seq, rssi, u64::from(seq) * S);
            frame(
                crate::frame::ids::RADIO_STATUS,
                seq,
                rssi,
                u64::from(seq) * S + 1,
            );
        }
        f.close(Totals::default());
        let w = windows(&mut f);
        let r = w[0].radio.unwrap();
        assert_eq!((r.reports, r.rssi), (2, Some(150.0)));
        let s = f.summary(20 * S, Totals::default());
        assert_eq!(s.radio_kind, Some(RadioKind::Sik));
        assert!(s
            .radio_evidence
            .join(" ")
            .contains("RADIO (166) beside each RADIO_STATUS"));
    }
}
