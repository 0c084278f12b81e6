//! The radios' own figures: RADIO_STATUS (message 109), or its forerunner
//! RADIO (166), which telemetry radios inject into the stream. Per radio:
//! what kind it is and why ([`super::radio_kind`]), min/mean/max of each
//! figure as sent and in the kind's own units, and how much the since-boot
//! error counters grew during the run. A report sent twice, as RADIO and
//! as RADIO_STATUS (SiK 2013-2016), counts once.
//!
//! Pure: the session feeds reports and HEARTBEATs with their times;
//! nothing here reads a clock. Memory is bounded by [`MAX_RADIOS`].

use std::collections::{BTreeMap, VecDeque};

use serde::ser::SerializeMap;
use serde::{Serialize, Serializer};

use super::hint::{Hint, HintCode};
pub use super::radio_kind::RadioType;
pub(crate) use super::radio_kind::{
    sik_dbm, Evidence, Field, Judgement, PairFilter, RadioKind, COMP_TELEMETRY_RADIO,
    COMP_UDP_BRIDGE, UNKNOWN,
};
use super::Nanos;
use crate::frame::SysComp;

/// A spoofing flood cannot grow memory beyond this many radios.
pub(crate) const MAX_RADIOS: usize = 16;
/// SiK's default system id.
pub(crate) const SIK_SYSID: u8 = 51;
/// A SiK fade margin under this many dB leaves little room before the
/// link drops.
pub(crate) const WEAK_FADE_MARGIN_DB: f64 = 10.0;
/// SiK's RSSI steps per dB.
pub(crate) const SIK_STEPS_PER_DB: f64 = 1.9;
/// Below this much of its transmit buffer free, a radio is overloaded.
pub(crate) const LOW_TXBUF_PERCENT: u8 = 20;
/// Losses needed while the buffer is low before the hint speaks.
const MIN_LOSSES_FOR_HINT: u64 = 3;
/// Buffer state changes remembered, to judge each request by the state
/// when it was sent (its outcome is decided a timeout later).
const MAX_BUFFER_CHANGES: usize = 256;

/// One RADIO_STATUS as received: the frame's own struct, under the name
/// the engine and the reports know it by.
pub(crate) use crate::frame::RadioStatus as RadioReport;

/// SiK's default ids, 51/68: a radio even before its first RADIO_STATUS.
pub(crate) fn is_sik_default(id: SysComp) -> bool {
    id.sysid == SIK_SYSID && id.compid == COMP_TELEMETRY_RADIO
}

/// The ids radios send as (compid 68, or mavesp8266's 240): a source
/// whose frames are the radio's own, not the link's traffic.
pub(crate) fn is_radio_ids(id: SysComp) -> bool {
    id.compid == COMP_TELEMETRY_RADIO || id.compid == COMP_UDP_BRIDGE
}

/// Min / mean / max of one figure over the reports that knew it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub(crate) struct Range {
    pub(crate) min: f64,
    pub(crate) mean: f64,
    pub(crate) max: f64,
    /// Reports that carried a known value.
    pub(crate) samples: u64,
}

#[derive(Debug, Clone, Copy, Default)]
struct Figure {
    min: i32,
    max: i32,
    sum: i64,
    n: u64,
}

impl Figure {
    fn record(&mut self, v: i32) {
        if self.n == 0 {
            self.min = v;
            self.max = v;
        } else {
            self.min = self.min.min(v);
            self.max = self.max.max(v);
        }
        self.sum += i64::from(v);
        self.n += 1;
    }

    fn known(&mut self, v: u8) {
        if v != UNKNOWN {
            self.record(i32::from(v));
        }
    }

    fn range(&self) -> Option<Range> {
        (self.n > 0).then(|| Range {
            min: f64::from(self.min),
            mean: self.sum as f64 / self.n as f64,
            max: f64::from(self.max),
            samples: self.n,
        })
    }
}

/// How often each value of one 8-bit figure came: whatever kind a radio
/// turns out to be, its figures convert exactly from this.
#[derive(Clone, PartialEq, Eq)]
pub(crate) struct RawHistogram(Box<[u64; 256]>);

impl Default for RawHistogram {
    fn default() -> Self {
        RawHistogram(Box::new([0; 256]))
    }
}

impl std::fmt::Debug for RawHistogram {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "RawHistogram({} values)", self.count())
    }
}

impl RawHistogram {
    pub(crate) fn record(&mut self, v: u8) {
        self.0[usize::from(v)] += 1;
    }

    pub(crate) fn count(&self) -> u64 {
        self.0.iter().sum()
    }

    pub(crate) fn clear(&mut self) {
        self.0.fill(0);
    }

    /// What `self` holds beyond `part` (a part of it).
    pub(crate) fn minus(&self, part: &RawHistogram) -> RawHistogram {
        let mut out = self.clone();
        for (o, p) in out.0.iter_mut().zip(part.0.iter()) {
            *o = o.saturating_sub(*p);
        }
        out
    }

    /// Min / mean / max of the values `convert` knows.
    pub(crate) fn range(&self, convert: impl Fn(u8) -> Option<f64>) -> Option<Range> {
        let (mut min, mut max, mut sum, mut n) = (f64::INFINITY, f64::NEG_INFINITY, 0.0, 0u64);
        for (v, &c) in self.0.iter().enumerate() {
            let Some(x) = (c > 0).then(|| convert(v as u8)).flatten() else {
                continue;
            };
            min = min.min(x);
            max = max.max(x);
            sum += x * c as f64;
            n += c;
        }
        (n > 0).then(|| Range {
            min,
            mean: sum / n as f64,
            max,
            samples: n,
        })
    }

    /// The raw values, 255 (unknown) left out.
    pub(crate) fn raw_range(&self) -> Option<Range> {
        self.range(|v| (v != UNKNOWN).then_some(f64::from(v)))
    }
}

/// A since-boot u16 counter: what it grew by since it was first seen.
/// Each step is taken modulo 2^16, so a wrap (65 530 → 5) counts as 11,
/// not −65 525; but a fall from well below the top is the radio counting
/// again from 0 after a restart, and counts as the new value.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct SinceBootCounter {
    last: Option<u16>,
    grown: u64,
}

/// A fall from at or above this is a wrap; from below, a restart.
const WRAP_ZONE: u16 = 0xF000;

impl SinceBootCounter {
    pub(crate) fn record(&mut self, v: u16) {
        if let Some(last) = self.last {
            self.grown += u64::from(if v < last && last < WRAP_ZONE {
                v
            } else {
                v.wrapping_sub(last)
            });
        }
        self.last = Some(v);
    }

    pub(crate) fn grown(&self) -> u64 {
        self.grown
    }
}

#[derive(Debug, Clone)]
struct Radio {
    reports: u64,
    latest: RadioReport,
    evidence: Evidence,
    judgement: Judgement,
    pair: PairFilter,
    /// rssi, remrssi, noise, remnoise, by [`Field::index`].
    raw: [RawHistogram; 4],
    fade: Figure,
    remfade: Figure,
    txbuf: Figure,
    /// `rxerrors` as sent (mavesp8266's is a percentage).
    rxerrors_values: Figure,
    rxerrors: SinceBootCounter,
    fixed: SinceBootCounter,
}

/// One figure in the units its radio's kind gives it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct KindFigure {
    /// Its name in JSON (`rssi_dbm`).
    pub(crate) key: &'static str,
    /// Its name in text (`remote rssi`).
    pub(crate) label: &'static str,
    pub(crate) unit: &'static str,
    /// How exact the conversion is.
    pub(crate) note: &'static str,
    pub(crate) range: Range,
}

/// A radio's figures in its kind's units, in the order text shows them;
/// JSON has them as an object by key.
#[derive(Debug, Clone, Default, PartialEq)]
pub(crate) struct Converted(pub Vec<KindFigure>);

impl Converted {
    #[cfg(test)]
    pub(crate) fn get(&self, key: &str) -> Option<&KindFigure> {
        self.0.iter().find(|f| f.key == key)
    }
}

impl Serialize for Converted {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        #[derive(Serialize)]
        struct Value<'a> {
            #[serde(flatten)]
            range: &'a Range,
            unit: &'static str,
        }
        let mut map = s.serialize_map(Some(self.0.len()))?;
        for f in &self.0 {
            map.serialize_entry(
                f.key,
                &Value {
                    range: &f.range,
                    unit: f.unit,
                },
            )?;
        }
        map.end()
    }
}

/// The end-of-run figures of one radio.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub(crate) struct RadioSummary {
    pub(crate) id: SysComp,
    pub(crate) reports: u64,
    /// What it is and why.
    #[serde(flatten)]
    pub(crate) judgement: Judgement,
    /// Raw values as the radio reports them (255 = unknown, skipped).
    pub(crate) rssi: Option<Range>,
    pub(crate) remrssi: Option<Range>,
    pub(crate) noise: Option<Range>,
    pub(crate) remnoise: Option<Range>,
    /// RSSI − noise, raw units, per report where both are known: SiK only
    /// (elsewhere `noise` is no noise floor).
    pub(crate) fade_margin: Option<Range>,
    pub(crate) remote_fade_margin: Option<Range>,
    /// Percent of the radio's transmit buffer free.
    pub(crate) txbuf: Option<Range>,
    /// What the since-boot counters grew by during the run (wrap-safe).
    pub(crate) rxerrors_delta: u64,
    pub(crate) fixed_delta: u64,
    /// The figures in the units the kind defines: dBm, SNR, link quality.
    pub(crate) converted: Converted,
    /// SiK only: approximate dBm of RSSI and fade margin in dB.
    pub(crate) approx_dbm: Option<ApproxDbm>,
    pub(crate) latest: RadioReport,
}

/// SiK's figures converted with [`sik_dbm`]; approximate by nature.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub(crate) struct ApproxDbm {
    pub(crate) rssi: Option<Range>,
    pub(crate) remrssi: Option<Range>,
    pub(crate) fade_margin_db: Option<Range>,
    pub(crate) remote_fade_margin_db: Option<Range>,
}

fn map_range(r: Option<Range>, f: impl Fn(f64) -> f64) -> Option<Range> {
    r.map(|r| Range {
        min: f(r.min),
        mean: f(r.mean),
        max: f(r.max),
        samples: r.samples,
    })
}

/// All radios heard, keyed by their MAVLink source.
#[derive(Debug, Default)]
pub(crate) struct Radios {
    /// `--radio-type`.
    setting: RadioType,
    radios: BTreeMap<SysComp, Radio>,
    /// HEARTBEATs from radio ids (compid 68 or 240) not yet heard as a
    /// radio: mLRS's may come before its first RADIO_STATUS.
    heartbeats: BTreeMap<SysComp, (u8, u8)>,
    /// Replies and losses decided while the latest report said the buffer
    /// was low, and while it did not: (lost, decided).
    low: (u64, u64),
    normal: (u64, u64),
    /// (since, low): when the buffer turned low or not, oldest first.
    buffer: VecDeque<(Nanos, bool)>,
}

/// What taking a report did.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Recorded {
    /// The radio's first report.
    pub(crate) first: bool,
    /// Its kind is not what it was before this report.
    pub(crate) kind_changed: bool,
}

/// How losses split between a low and a normal radio buffer.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub(crate) struct LossByTxbuf {
    pub(crate) lost_while_low: u64,
    pub(crate) decided_while_low: u64,
    pub(crate) lost_otherwise: u64,
    pub(crate) decided_otherwise: u64,
}

impl Radios {
    /// Radios read as `setting` says (`--radio-type`).
    pub(crate) fn new(setting: RadioType) -> Self {
        Radios {
            setting,
            ..Radios::default()
        }
    }

    #[cfg(test)]
    /// Records a RADIO_STATUS; returns true for a radio's first one.
    /// Reports from radios beyond [`MAX_RADIOS`] are ignored.
    pub(crate) fn record(&mut self, id: SysComp, r: RadioReport, at: Nanos) -> bool {
        self.take(id, crate::frame::ids::RADIO_STATUS, 0, r, at)
            .is_some_and(|t| t.first)
    }

    /// Takes a report that came as message `msgid` (RADIO_STATUS or RADIO)
    /// with packet sequence number `seq`. `None`: not counted, as the
    /// second of a RADIO + RADIO_STATUS pair, or from a radio beyond
    /// [`MAX_RADIOS`].
    pub(crate) fn take(
        &mut self,
        id: SysComp,
        msgid: u32,
        seq: u8,
        r: RadioReport,
        at: Nanos,
    ) -> Option<Recorded> {
        let first = !self.radios.contains_key(&id);
        if first && self.radios.len() >= MAX_RADIOS {
            return None;
        }
        let setting = self.setting;
        let heartbeat = self.heartbeats.remove(&id);
        let radio = self.radios.entry(id).or_insert_with(|| {
            let mut evidence = Evidence::default();
            if let Some((mav_type, autopilot)) = heartbeat {
                evidence.heartbeat(mav_type, autopilot);
            }
            Radio {
                reports: 0,
                latest: r,
                judgement: evidence.judge(id, setting),
                evidence,
                pair: PairFilter::default(),
                raw: Default::default(),
                fade: Figure::default(),
                remfade: Figure::default(),
                txbuf: Figure::default(),
                rxerrors_values: Figure::default(),
                rxerrors: SinceBootCounter::default(),
                fixed: SinceBootCounter::default(),
            }
        });
        if radio.pair.repeats(msgid, seq, &r) {
            radio.evidence.report(msgid, &r, at, true);
            return None;
        }
        radio.evidence.report(msgid, &r, at, false);
        let was = radio.judgement.kind;
        radio.judgement = radio.evidence.judge(id, setting);
        let kind = radio.judgement.kind;
        radio.reports += 1;
        radio.latest = r;
        for field in Field::ALL {
            radio.raw[field.index()].record(field.of(&r));
        }
        if r.rssi != UNKNOWN && r.noise != UNKNOWN {
            radio.fade.record(i32::from(r.rssi) - i32::from(r.noise));
        }
        if r.remrssi != UNKNOWN && r.remnoise != UNKNOWN {
            radio
                .remfade
                .record(i32::from(r.remrssi) - i32::from(r.remnoise));
        }
        radio.txbuf.known(r.txbuf);
        radio.rxerrors_values.record(i32::from(r.rxerrors));
        radio.rxerrors.record(r.rxerrors);
        radio.fixed.record(r.fixed);
        // Only a buffer a sender can overrun says the radio is overloaded.
        if r.txbuf != UNKNOWN && kind.txbuf_is_free_buffer() {
            let low = r.txbuf < LOW_TXBUF_PERCENT;
            if self.buffer.back().is_none_or(|&(_, was)| was != low) {
                if self.buffer.len() == MAX_BUFFER_CHANGES {
                    self.buffer.pop_front();
                }
                self.buffer.push_back((at, low));
            }
        }
        Some(Recorded {
            first,
            kind_changed: !first && kind != was,
        })
    }

    /// A HEARTBEAT from `id`: evidence of its kind if it is (or may yet
    /// be) a radio. Returns true when a radio's kind changed with it.
    pub(crate) fn heartbeat(&mut self, id: SysComp, mav_type: u8, autopilot: u8) -> bool {
        if let Some(radio) = self.radios.get_mut(&id) {
            radio.evidence.heartbeat(mav_type, autopilot);
            let was = radio.judgement.kind;
            radio.judgement = radio.evidence.judge(id, self.setting);
            return radio.judgement.kind != was;
        }
        let room = self.heartbeats.len() < MAX_RADIOS || self.heartbeats.contains_key(&id);
        if is_radio_ids(id) && room {
            self.heartbeats.insert(id, (mav_type, autopilot));
        }
        false
    }

    /// What a radio is and why, as things stand.
    pub(crate) fn judgement(&self, id: SysComp) -> Option<&Judgement> {
        self.radios.get(&id).map(|r| &r.judgement)
    }

    /// A radio's latest report.
    pub(crate) fn latest(&self, id: SysComp) -> Option<RadioReport> {
        self.radios.get(&id).map(|r| r.latest)
    }

    /// A reply or a loss was decided for a request sent at `sent_at`;
    /// counted against the buffer's state then. Requests sent before the
    /// first report (or the oldest one remembered) are not counted.
    pub(crate) fn outcome(&mut self, lost: bool, sent_at: Nanos) {
        let Some(&(_, low)) = self
            .buffer
            .iter()
            .rev()
            .find(|&&(since, _)| since <= sent_at)
        else {
            return;
        };
        let bucket = if low { &mut self.low } else { &mut self.normal };
        bucket.0 += u64::from(lost);
        bucket.1 += 1;
    }

    pub(crate) fn loss_by_txbuf(&self) -> LossByTxbuf {
        LossByTxbuf {
            lost_while_low: self.low.0,
            decided_while_low: self.low.1,
            lost_otherwise: self.normal.0,
            decided_otherwise: self.normal.1,
        }
    }

    pub(crate) fn summaries(&self) -> Vec<RadioSummary> {
        self.radios.iter().map(|(&id, r)| summary(id, r)).collect()
    }
}

/// The figures of `kind` in its units, in text's order: the four signal
/// fields, then (SiK) the fade margins, then (mavesp8266) the ground's
/// loss.
fn converted(
    kind: RadioKind,
    raw: &[RawHistogram; 4],
    fades: [Option<Range>; 2],
    rxerrors: Option<Range>,
) -> Converted {
    let mut out: Vec<KindFigure> = Field::ALL
        .into_iter()
        .filter_map(|field| {
            let m = kind.meaning(field)?;
            Some(KindFigure {
                key: m.key,
                label: m.label,
                unit: m.unit,
                note: m.note,
                range: raw[field.index()].range(m.convert)?,
            })
        })
        .collect();
    if kind.has_fade_margin() {
        for ((key, label), fade) in [
            ("fade_margin_db", "fade margin"),
            ("remote_fade_margin_db", "remote fade margin"),
        ]
        .into_iter()
        .zip(fades)
        {
            if let Some(range) = map_range(fade, |v| v / SIK_STEPS_PER_DB) {
                out.push(KindFigure {
                    key,
                    label,
                    unit: "dB",
                    note: "approximate, SiK scale",
                    range,
                });
            }
        }
    }
    if kind.rxerrors_is_gcs_lost_pct() {
        if let Some(range) = rxerrors {
            out.push(KindFigure {
                key: "gcs_lost_pct",
                label: "ground msgs lost",
                unit: "%",
                note: "mavesp8266: rxerrors = % of the ground's lost",
                range,
            });
        }
    }
    Converted(out)
}

fn summary(id: SysComp, r: &Radio) -> RadioSummary {
    let kind = r.judgement.kind;
    let sik = kind.has_fade_margin();
    let fade_margin = r.fade.range().filter(|_| sik);
    let remote_fade_margin = r.remfade.range().filter(|_| sik);
    let raw = |f: Field| r.raw[f.index()].raw_range();
    let approx_dbm = sik.then(|| ApproxDbm {
        rssi: map_range(raw(Field::Rssi), sik_dbm),
        remrssi: map_range(raw(Field::Remrssi), sik_dbm),
        fade_margin_db: map_range(fade_margin, |v| v / SIK_STEPS_PER_DB),
        remote_fade_margin_db: map_range(remote_fade_margin, |v| v / SIK_STEPS_PER_DB),
    });
    RadioSummary {
        id,
        reports: r.reports,
        judgement: r.judgement.clone(),
        rssi: raw(Field::Rssi),
        remrssi: raw(Field::Remrssi),
        noise: raw(Field::Noise),
        remnoise: raw(Field::Remnoise),
        fade_margin,
        remote_fade_margin,
        txbuf: r.txbuf.range(),
        rxerrors_delta: r.rxerrors.grown(),
        fixed_delta: r.fixed.grown(),
        converted: converted(
            kind,
            &r.raw,
            [r.fade.range(), r.remfade.range()],
            r.rxerrors_values.range(),
        ),
        approx_dbm,
        latest: r.latest,
    }
}

/// Hints the radio figures support; none when the data is silent, and
/// none a radio's kind does not give its fields the meaning of.
pub(crate) fn radio_hints(radios: &[RadioSummary], loss: LossByTxbuf) -> Vec<Hint> {
    let mut hints = Vec::new();
    let ratio = |lost: u64, of: u64| {
        if of == 0 {
            0.0
        } else {
            lost as f64 / of as f64
        }
    };
    let low = ratio(loss.lost_while_low, loss.decided_while_low);
    // Concentrated: enough losses, and at least twice the rate seen with
    // room in the buffer.
    if loss.lost_while_low >= MIN_LOSSES_FOR_HINT
        && low >= 2.0 * ratio(loss.lost_otherwise, loss.decided_otherwise)
    {
        hints.push(Hint::new(HintCode::RadioOverloaded, format!(
            "loss concentrated while txbuf < {LOW_TXBUF_PERCENT} % free ({} of {} lost, against {} of {} otherwise): \
             the radio is overloaded — lower the rate",
            loss.lost_while_low, loss.decided_while_low, loss.lost_otherwise, loss.decided_otherwise
        )));
    }
    for r in radios {
        if let Some(a) = &r.approx_dbm {
            for (side, m) in [
                ("local", a.fade_margin_db),
                ("remote", a.remote_fade_margin_db),
            ] {
                if let Some(m) = m.filter(|m| m.min < WEAK_FADE_MARGIN_DB) {
                    hints.push(Hint::new(HintCode::RadioWeakSignal, format!(
                        "radio {}: {side} fade margin fell to ~{:.1} dB (under {WEAK_FADE_MARGIN_DB} dB): weak signal",
                        r.id, m.min
                    )));
                }
            }
        }
        if r.rxerrors_delta > 0 && r.judgement.kind.counts_errors() {
            hints.push(Hint::new(
                HintCode::RadioErrors,
                format!(
                    "radio {}: rxerrors grew by {} during the run: interference or range",
                    r.id, r.rxerrors_delta
                ),
            ));
        }
    }
    hints
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frame::ids;

    const SIK: SysComp = SysComp {
        sysid: 51,
        compid: 68,
    };
    const S: Nanos = 1_000_000_000;

    fn report(rssi: u8, noise: u8, txbuf: u8, rxerrors: u16, fixed: u16) -> RadioReport {
        RadioReport {
            rssi,
            remrssi: rssi.saturating_sub(10),
            txbuf,
            noise,
            remnoise: noise,
            rxerrors,
            fixed,
        }
    }

    #[test]
    fn figures_are_exact_and_unknown_is_skipped() {
        let mut radios = Radios::default();
        assert!(radios.record(SIK, report(200, 40, 90, 0, 0), 1));
        assert!(!radios.record(SIK, report(180, 50, UNKNOWN, 0, 0), 2));
        assert!(!radios.record(SIK, report(UNKNOWN, 60, 70, 0, 0), 3));
        let s = &radios.summaries()[0];
        assert_eq!(s.reports, 3);
        let rssi = s.rssi.unwrap();
        assert_eq!(
            (rssi.min, rssi.mean, rssi.max, rssi.samples),
            (180.0, 190.0, 200.0, 2)
        );
        let txbuf = s.txbuf.unwrap();
        assert_eq!((txbuf.min, txbuf.mean, txbuf.max), (70.0, 80.0, 90.0));
        // Only the two reports with both figures known: 160 and 130.
        let fade = s.fade_margin.unwrap();
        assert_eq!(
            (fade.min, fade.mean, fade.max, fade.samples),
            (130.0, 145.0, 160.0, 2)
        );
        let dbm = s.approx_dbm.unwrap().rssi.unwrap();
        assert!((dbm.max - (200.0 / 1.9 - 127.0)).abs() < 1e-9);
    }

    #[test]
    fn counters_grow_across_a_wrap() {
        let mut radios = Radios::default();
        for (rx, fixed) in [(65_500, 7), (65_530, 7), (5, 9), (20, 9)] {
            radios.record(SIK, report(100, 20, 50, rx, fixed), 0);
        }
        let s = &radios.summaries()[0];
        // 30 + 11 (65 530 → 5 through the wrap) + 15.
        assert_eq!(s.rxerrors_delta, 56);
        assert_eq!(s.fixed_delta, 2);
    }

    #[test]
    fn a_radio_that_restarts_counts_from_zero_again() {
        let mut c = SinceBootCounter::default();
        for v in [900, 1000, 4, 10] {
            c.record(v);
        }
        // 100, then 4 since the restart, then 6: not 65 540 through a wrap.
        assert_eq!(c.grown(), 110);
    }

    #[test]
    fn a_single_report_grows_nothing() {
        let mut radios = Radios::default();
        radios.record(SIK, report(100, 20, 50, 1234, 99), 0);
        let s = &radios.summaries()[0];
        assert_eq!((s.rxerrors_delta, s.fixed_delta), (0, 0));
        assert!(radio_hints(&radios.summaries(), radios.loss_by_txbuf()).is_empty());
    }

    #[test]
    fn radios_are_bounded() {
        let mut radios = Radios::default();
        for sysid in 0..=255u8 {
            radios.record(SysComp { sysid, compid: 68 }, report(1, 1, 1, 0, 0), 0);
        }
        assert_eq!(radios.summaries().len(), MAX_RADIOS);
    }

    #[test]
    fn hints_only_when_the_data_supports_them() {
        let mut radios = Radios::default();
        // Fade 100 raw ≈ 52.6 dB, no errors: nothing to say.
        radios.record(SIK, report(150, 50, 90, 10, 0), 0);
        radios.record(SIK, report(150, 50, 90, 10, 0), 1);
        assert!(radio_hints(&radios.summaries(), radios.loss_by_txbuf()).is_empty());
        // Fade 15 raw ≈ 7.9 dB (remote 5 raw ≈ 2.6 dB) and 3 new errors.
        radios.record(SIK, report(65, 50, 90, 13, 0), 2);
        let hints = radio_hints(&radios.summaries(), radios.loss_by_txbuf());
        assert_eq!(hints.len(), 3, "{hints:?}");
        assert!(
            hints[0].text.contains("local fade margin fell to ~7.9 dB"),
            "{hints:?}"
        );
        assert!(
            hints[1].text.contains("remote fade margin fell to ~2.6 dB"),
            "{hints:?}"
        );
        assert!(hints[2].text.contains("rxerrors grew by 3"), "{hints:?}");
    }

    #[test]
    fn overload_hint_needs_losses_concentrated_at_a_low_buffer() {
        let mut radios = Radios::default();
        // Before any report: not counted.
        radios.outcome(true, 0);
        radios.record(SIK, report(150, 50, 90, 0, 0), 10);
        radios.record(SIK, report(150, 50, 10, 0, 0), 20);
        for i in 0..10 {
            radios.outcome(i == 0, 15);
        }
        radios.outcome(true, 20);
        radios.outcome(true, 25);
        radios.outcome(false, 25);
        // Two losses at a low buffer: not yet evidence.
        assert!(radio_hints(&radios.summaries(), radios.loss_by_txbuf()).is_empty());
        radios.outcome(true, 21);
        let hints = radio_hints(&radios.summaries(), radios.loss_by_txbuf());
        assert_eq!(
            hints,
            [Hint::new(
                HintCode::RadioOverloaded,
                "loss concentrated while txbuf < 20 % free (3 of 4 lost, against 1 of 10 otherwise): \
                 the radio is overloaded — lower the rate"
            )]
        );
        // Unknown txbuf leaves the state as it was.
        radios.record(SIK, report(150, 50, UNKNOWN, 0, 0), 30);
        radios.outcome(false, 31);
        assert_eq!(radios.loss_by_txbuf().decided_while_low, 5);
    }

    #[test]
    fn non_sik_radios_get_no_dbm() {
        let mut radios = Radios::default();
        let other = SysComp {
            sysid: 3,
            compid: 1,
        };
        radios.record(other, report(15, 10, 90, 0, 0), 0);
        let s = &radios.summaries()[0];
        assert!(s.approx_dbm.is_none());
        // Raw units unknown: no fade-margin hint from a guess.
        assert!(radio_hints(&radios.summaries(), radios.loss_by_txbuf()).is_empty());
    }

    fn dbm(r: &RadioSummary, key: &str) -> (f64, f64, f64) {
        let f = r
            .converted
            .get(key)
            .unwrap_or_else(|| panic!("{key}: {r:?}"));
        (f.range.min, f.range.mean, f.range.max)
    }

    /// mLRS's RSSI for `dbm`, as its rssi_i8_to_ap encodes it.
    fn mlrs_raw(dbm: i32) -> u8 {
        (((dbm + 120) * 254 + 35) / 70) as u8
    }

    #[test]
    fn mlrs_is_read_on_its_scale_with_no_fade_margin() {
        let weak = |rxerrors| RadioReport {
            rssi: mlrs_raw(-85),
            remrssi: mlrs_raw(-90),
            txbuf: 100,
            // SNR 7 dB; read as a SiK noise floor, a fade margin of ~65 dB.
            noise: 3,
            remnoise: UNKNOWN,
            rxerrors,
            fixed: 0,
        };
        let mut radios = Radios::default();
        // Its HEARTBEAT may come before its first report.
        assert!(!radios.heartbeat(SIK, 0, 8));
        for i in 0..3 {
            radios.record(SIK, weak(0), i * S);
        }
        let s = &radios.summaries()[0];
        assert_eq!(s.judgement.kind, RadioKind::Mlrs);
        assert_eq!(dbm(s, "rssi_dbm"), (-85.0, -85.0, -85.0));
        assert_eq!(dbm(s, "remrssi_dbm"), (-90.0, -90.0, -90.0));
        assert_eq!(dbm(s, "snr_db"), (7.0, 7.0, 7.0));
        assert!(s.fade_margin.is_none() && s.approx_dbm.is_none(), "{s:?}");
        assert!(s.converted.get("noise_dbm").is_none());
        // The same bytes read as a SiK's (--radio-type sik): dBm on its
        // scale, a fade margin, and rxerrors as errors.
        let mut as_sik = Radios::new(RadioType::Sik);
        as_sik.record(SIK, weak(0), 0);
        as_sik.record(SIK, weak(5), S);
        let s = &as_sik.summaries()[0];
        assert_eq!(s.judgement.describe(), "SiK (--radio-type sik)");
        let rssi = dbm(s, "rssi_dbm").0;
        assert!((rssi - (f64::from(mlrs_raw(-85)) / 1.9 - 127.0)).abs() < 1e-9);
        assert!(s.fade_margin.is_some());
        let hints = radio_hints(&as_sik.summaries(), as_sik.loss_by_txbuf());
        assert!(
            hints.iter().any(|h| h.text.contains("rxerrors grew by 5")),
            "{hints:?}"
        );
    }

    #[test]
    fn a_heartbeat_after_the_first_report_changes_the_kind() {
        let mut radios = Radios::default();
        assert!(radios.record(SIK, report(100, 20, 100, 0, 0), 0));
        assert_eq!(radios.judgement(SIK).unwrap().kind, RadioKind::Sik);
        assert!(radios.heartbeat(SIK, 0, 8));
        assert_eq!(radios.judgement(SIK).unwrap().kind, RadioKind::Mlrs);
        // Again: no change.
        assert!(!radios.heartbeat(SIK, 0, 8));
        // A vehicle's HEARTBEAT is kept nowhere.
        assert!(!radios.heartbeat(SysComp::new(1, 1), 2, 3));
        assert!(radios.heartbeats.is_empty());
    }

    #[test]
    fn a_report_sent_as_radio_and_radio_status_counts_once() {
        let mut radios = Radios::default();
        let r = report(150, 50, 90, 7, 0);
        let first = radios.take(SIK, ids::RADIO, 4, r, 0).unwrap();
        assert!(first.first);
        assert_eq!(radios.take(SIK, ids::RADIO_STATUS, 4, r, 1), None);
        let next = report(160, 50, 90, 7, 0);
        assert!(radios.take(SIK, ids::RADIO, 5, next, S).is_some());
        assert_eq!(radios.take(SIK, ids::RADIO_STATUS, 5, next, S + 1), None);
        let s = &radios.summaries()[0];
        assert_eq!(s.reports, 2);
        // The mean is of two reports, not four.
        assert_eq!(s.rssi.unwrap().samples, 2);
        assert_eq!(s.rssi.unwrap().mean, 155.0);
        assert!(
            s.judgement
                .describe()
                .contains("RADIO (166) beside each RADIO_STATUS"),
            "{s:?}"
        );
    }

    #[test]
    fn elrs_gives_link_quality_uplink_rssi_and_snr() {
        let elrs = SysComp::new(255, 68);
        let mut radios = Radios::default();
        for (i, (lq, snr)) in [(98u32, -3i8), (100, 5)].into_iter().enumerate() {
            radios.record(
                elrs,
                RadioReport {
                    rssi: (f64::from(lq) * 2.55) as u8,
                    remrssi: 67,
                    txbuf: 90,
                    noise: snr as u8,
                    remnoise: 0,
                    rxerrors: 0,
                    fixed: 0,
                },
                i as Nanos * S / 100,
            );
        }
        let s = &radios.summaries()[0];
        assert_eq!(s.judgement.kind, RadioKind::Elrs);
        assert_eq!(dbm(s, "link_quality_pct"), (98.0, 99.0, 100.0));
        assert_eq!(dbm(s, "remrssi_dbm"), (-67.0, -67.0, -67.0));
        assert_eq!(dbm(s, "snr_db"), (-3.0, 1.0, 5.0));
        assert!(s.converted.get("rssi_dbm").is_none());
    }

    #[test]
    fn an_esp_bridge_reports_losses_not_errors() {
        let esp = SysComp::new(1, 240);
        let mut radios = Radios::default();
        for (i, lost) in [2u16, 6].into_iter().enumerate() {
            radios.record(
                esp,
                RadioReport {
                    rssi: (-61i8) as u8,
                    remrssi: 0,
                    txbuf: 10,
                    noise: 0,
                    remnoise: 4,
                    rxerrors: lost,
                    fixed: 0,
                },
                i as Nanos * S,
            );
        }
        let s = &radios.summaries()[0];
        assert_eq!(s.judgement.kind, RadioKind::Esp);
        assert_eq!(dbm(s, "rssi_dbm"), (-61.0, -61.0, -61.0));
        assert_eq!(dbm(s, "vehicle_lost_pct"), (4.0, 4.0, 4.0));
        assert_eq!(dbm(s, "gcs_lost_pct"), (2.0, 4.0, 6.0));
        // rxerrors "grew", but it is a percentage: no errors hint; and a
        // low txbuf (its queue) is no overloaded radio.
        radios.outcome(true, 5 * S);
        assert!(radios.buffer.is_empty());
        assert!(radio_hints(&radios.summaries(), radios.loss_by_txbuf()).is_empty());
    }
}
