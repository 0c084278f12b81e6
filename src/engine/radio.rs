//! The radios' own figures: RADIO_STATUS (message 109), which telemetry
//! radios inject into the stream. Per radio: min/mean/max of each figure
//! and how much the since-boot error counters grew during the run.
//!
//! Pure: the session feeds reports with their times; nothing here reads a
//! clock. Memory is bounded by [`MAX_RADIOS`].

use std::collections::{BTreeMap, VecDeque};

use serde::Serialize;

use super::hint::{Hint, HintCode};
use super::Nanos;
use crate::frame::SysComp;

/// RADIO_STATUS's "unknown" for its 8-bit figures.
pub const UNKNOWN: u8 = 255;
/// A spoofing flood cannot grow memory beyond this many radios.
pub const MAX_RADIOS: usize = 16;
/// The component id telemetry radios (SiK and others) use.
pub const COMP_TELEMETRY_RADIO: u8 = 68;
/// SiK's default system id.
pub const SIK_SYSID: u8 = 51;
/// SiK reports RSSI in units of about 1/1.9 dB; a fade margin under this
/// many dB leaves little room before the link drops.
pub const WEAK_FADE_MARGIN_DB: f64 = 10.0;
/// Below this much of its transmit buffer free, a radio is overloaded.
pub const LOW_TXBUF_PERCENT: u8 = 20;
/// Losses needed while the buffer is low before the hint speaks.
const MIN_LOSSES_FOR_HINT: u64 = 3;
/// Buffer state changes remembered, to judge each request by the state
/// when it was sent (its outcome is decided a timeout later).
const MAX_BUFFER_CHANGES: usize = 256;

/// One RADIO_STATUS as received: the frame's own struct, under the name
/// the engine and the reports know it by.
pub use crate::frame::RadioStatus as RadioReport;

/// SiK's RSSI scale to dBm. Approximate: the chip's curve, not a
/// calibrated measurement.
pub fn sik_dbm(raw: f64) -> f64 {
    raw / 1.9 - 127.0
}

/// SiK's default ids, 51/68: a radio even before its first RADIO_STATUS.
pub fn is_sik_default(id: SysComp) -> bool {
    id.sysid == SIK_SYSID && id.compid == COMP_TELEMETRY_RADIO
}

/// Whether a source looks like a SiK radio, whose raw figures the dBm
/// formula applies to.
pub fn is_sik(id: SysComp) -> bool {
    id.compid == COMP_TELEMETRY_RADIO
}

/// Min / mean / max of one figure over the reports that knew it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Range {
    pub min: f64,
    pub mean: f64,
    pub max: f64,
    /// Reports that carried a known value.
    pub samples: u64,
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

/// A since-boot u16 counter: what it grew by since it was first seen.
/// Each step is taken modulo 2^16, so a wrap (65 530 → 5) counts as 11,
/// not −65 525; but a fall from well below the top is the radio counting
/// again from 0 after a restart, and counts as the new value.
#[derive(Debug, Clone, Copy, Default)]
pub struct SinceBootCounter {
    last: Option<u16>,
    grown: u64,
}

/// A fall from at or above this is a wrap; from below, a restart.
const WRAP_ZONE: u16 = 0xF000;

impl SinceBootCounter {
    pub fn record(&mut self, v: u16) {
        if let Some(last) = self.last {
            self.grown += u64::from(if v < last && last < WRAP_ZONE {
                v
            } else {
                v.wrapping_sub(last)
            });
        }
        self.last = Some(v);
    }

    pub fn grown(&self) -> u64 {
        self.grown
    }
}

#[derive(Debug, Clone)]
struct Radio {
    reports: u64,
    first_at: Nanos,
    latest: RadioReport,
    rssi: Figure,
    remrssi: Figure,
    noise: Figure,
    remnoise: Figure,
    fade: Figure,
    remfade: Figure,
    txbuf: Figure,
    rxerrors: SinceBootCounter,
    fixed: SinceBootCounter,
}

/// The end-of-run figures of one radio.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RadioSummary {
    pub id: SysComp,
    pub reports: u64,
    /// Raw values as the radio reports them (255 = unknown, skipped).
    pub rssi: Option<Range>,
    pub remrssi: Option<Range>,
    pub noise: Option<Range>,
    pub remnoise: Option<Range>,
    /// RSSI − noise, raw units, per report where both are known.
    pub fade_margin: Option<Range>,
    pub remote_fade_margin: Option<Range>,
    /// Percent of the radio's transmit buffer free.
    pub txbuf: Option<Range>,
    /// What the since-boot counters grew by during the run (wrap-safe).
    pub rxerrors_delta: u64,
    pub fixed_delta: u64,
    /// SiK only: approximate dBm of RSSI and fade margin in dB.
    pub approx_dbm: Option<ApproxDbm>,
    pub latest: RadioReport,
}

/// SiK's figures converted with [`sik_dbm`]; approximate by nature.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ApproxDbm {
    pub rssi: Option<Range>,
    pub remrssi: Option<Range>,
    pub fade_margin_db: Option<Range>,
    pub remote_fade_margin_db: Option<Range>,
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
pub struct Radios {
    radios: BTreeMap<SysComp, Radio>,
    /// Replies and losses decided while the latest report said the buffer
    /// was low, and while it did not: (lost, decided).
    low: (u64, u64),
    normal: (u64, u64),
    /// (since, low): when the buffer turned low or not, oldest first.
    buffer: VecDeque<(Nanos, bool)>,
}

/// How losses split between a low and a normal radio buffer.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct LossByTxbuf {
    pub lost_while_low: u64,
    pub decided_while_low: u64,
    pub lost_otherwise: u64,
    pub decided_otherwise: u64,
}

impl Radios {
    /// Records a report; returns true for a radio's first one. Reports
    /// from radios beyond [`MAX_RADIOS`] are ignored.
    pub fn record(&mut self, id: SysComp, r: RadioReport, at: Nanos) -> bool {
        let first = !self.radios.contains_key(&id);
        if first && self.radios.len() >= MAX_RADIOS {
            return false;
        }
        let radio = self.radios.entry(id).or_insert_with(|| Radio {
            reports: 0,
            first_at: at,
            latest: r,
            rssi: Figure::default(),
            remrssi: Figure::default(),
            noise: Figure::default(),
            remnoise: Figure::default(),
            fade: Figure::default(),
            remfade: Figure::default(),
            txbuf: Figure::default(),
            rxerrors: SinceBootCounter::default(),
            fixed: SinceBootCounter::default(),
        });
        radio.reports += 1;
        radio.latest = r;
        radio.rssi.known(r.rssi);
        radio.remrssi.known(r.remrssi);
        radio.noise.known(r.noise);
        radio.remnoise.known(r.remnoise);
        if r.rssi != UNKNOWN && r.noise != UNKNOWN {
            radio.fade.record(i32::from(r.rssi) - i32::from(r.noise));
        }
        if r.remrssi != UNKNOWN && r.remnoise != UNKNOWN {
            radio
                .remfade
                .record(i32::from(r.remrssi) - i32::from(r.remnoise));
        }
        radio.txbuf.known(r.txbuf);
        if r.txbuf != UNKNOWN {
            let low = r.txbuf < LOW_TXBUF_PERCENT;
            if self.buffer.back().is_none_or(|&(_, was)| was != low) {
                if self.buffer.len() == MAX_BUFFER_CHANGES {
                    self.buffer.pop_front();
                }
                self.buffer.push_back((at, low));
            }
        }
        radio.rxerrors.record(r.rxerrors);
        radio.fixed.record(r.fixed);
        first
    }

    /// A reply or a loss was decided for a request sent at `sent_at`;
    /// counted against the buffer's state then. Requests sent before the
    /// first report (or the oldest one remembered) are not counted.
    pub fn outcome(&mut self, lost: bool, sent_at: Nanos) {
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

    pub fn loss_by_txbuf(&self) -> LossByTxbuf {
        LossByTxbuf {
            lost_while_low: self.low.0,
            decided_while_low: self.low.1,
            lost_otherwise: self.normal.0,
            decided_otherwise: self.normal.1,
        }
    }

    pub fn contains(&self, id: SysComp) -> bool {
        self.radios.contains_key(&id)
    }

    pub fn first_at(&self, id: SysComp) -> Option<Nanos> {
        self.radios.get(&id).map(|r| r.first_at)
    }

    pub fn summaries(&self) -> Vec<RadioSummary> {
        self.radios
            .iter()
            .map(|(&id, r)| {
                let fade_margin = r.fade.range();
                let remote_fade_margin = r.remfade.range();
                let approx_dbm = is_sik(id).then(|| ApproxDbm {
                    rssi: map_range(r.rssi.range(), sik_dbm),
                    remrssi: map_range(r.remrssi.range(), sik_dbm),
                    fade_margin_db: map_range(fade_margin, |v| v / 1.9),
                    remote_fade_margin_db: map_range(remote_fade_margin, |v| v / 1.9),
                });
                RadioSummary {
                    id,
                    reports: r.reports,
                    rssi: r.rssi.range(),
                    remrssi: r.remrssi.range(),
                    noise: r.noise.range(),
                    remnoise: r.remnoise.range(),
                    fade_margin,
                    remote_fade_margin,
                    txbuf: r.txbuf.range(),
                    rxerrors_delta: r.rxerrors.grown(),
                    fixed_delta: r.fixed.grown(),
                    approx_dbm,
                    latest: r.latest,
                }
            })
            .collect()
    }
}

/// Hints the radio figures support; none when the data is silent.
pub fn radio_hints(radios: &[RadioSummary], loss: LossByTxbuf) -> Vec<Hint> {
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
        if r.rxerrors_delta > 0 {
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

    const SIK: SysComp = SysComp {
        sysid: 51,
        compid: 68,
    };

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
        assert_eq!(radios.first_at(SIK), Some(1));
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
}
