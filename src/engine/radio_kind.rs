//! Which radio sent a RADIO_STATUS, told from what it sends, and what its
//! figures mean. RADIO_STATUS's fields are "device dependent": the same
//! byte is a SiK radio's RSSI in ~1/1.9 dB steps, an mLRS module's RSSI on
//! ArduPilot's −120…−50 dBm scale, or an ExpressLRS receiver's link
//! quality in percent. Reading one as another gives numbers that look
//! right and are not, so every conversion here is by kind, and the kind
//! comes with the evidence for it.
//!
//! - **SiK / RFD900** (ArduPilot/SiK `mavlink.c`): compid 68 (sysid 51,
//!   "3D"), no HEARTBEAT; rssi/remrssi on the Si1000's scale
//!   (dBm ≈ raw / 1.9 − 127), noise/remnoise a noise floor on the same
//!   scale, rxerrors/fixed since-boot counters, txbuf % free; about 1 Hz.
//!   From 2013 to 2016 each report went out twice, as RADIO (166) and as
//!   RADIO_STATUS (109) under one packet sequence number; before 2013 as
//!   RADIO only (openLRSng too sends RADIO only, as 51/68).
//! - **mLRS** (`mavlink_interface_tx.h`): 51/68 too, and with its MAVLink
//!   component enabled a HEARTBEAT from 51/68 (MAV_TYPE_GENERIC,
//!   MAV_AUTOPILOT_INVALID). rssi/remrssi = `rssi_i8_to_ap(dBm)`:
//!   −120…−50 dBm to 0…254 rounded, 255 invalid; noise = 10 − SNR clamped
//!   to 0…127 (not a noise floor); remnoise 255, rxerrors and fixed 0,
//!   txbuf 100 (the ground module).
//! - **ExpressLRS** receiver in MAVLink mode (`SerialMavlink.cpp`): 255/68
//!   by default, 100 Hz; rssi = trunc(link quality × 2.55), remrssi the
//!   uplink RSSI's magnitude (dBm = −remrssi), noise the uplink SNR as an
//!   `int8` (dB), remnoise/rxerrors/fixed 0, txbuf its input buffer's % free.
//! - **mavesp8266** WiFi bridge (`mavesp8266_gcs.cpp`): compid 240
//!   (MAV_COMP_ID_UDP_BRIDGE) under the vehicle's sysid; rssi the WiFi
//!   RSSI as an `int8` in station mode (0 otherwise), remnoise the % of
//!   the vehicle's (serial) messages lost, rxerrors the % of the ground's
//!   (UDP) messages lost.
//! - **Unknown**: the raw figures only.
//!
//! Pure: the figures and times are passed in.

use serde::Serialize;

use super::Nanos;
use crate::frame::{self, SysComp};

/// 255 in RADIO_STATUS's 8-bit figures means unknown (where the kind
/// does not use it as a value).
pub(crate) const UNKNOWN: u8 = 255;
/// MAV_COMP_ID_TELEMETRY_RADIO: SiK, mLRS and ExpressLRS send as it.
pub(crate) const COMP_TELEMETRY_RADIO: u8 = 68;
/// MAV_COMP_ID_UDP_BRIDGE: mavesp8266's RADIO_STATUS.
pub(crate) const COMP_UDP_BRIDGE: u8 = 240;
/// ExpressLRS's receiver sends as 255/68 unless told otherwise.
pub(crate) const ELRS_SYSID: u8 = 255;
/// Reports per second at or above which a compid-68 radio is ExpressLRS
/// (it sends 100 a second; SiK and mLRS one).
pub(crate) const ELRS_MIN_RATE: f64 = 20.0;
/// Reports before a field's constancy counts as evidence.
pub(crate) const MIN_REPORTS: u64 = 3;
/// Reports before their rate does.
pub(crate) const MIN_RATE_REPORTS: u64 = 5;
const MAV_TYPE_GENERIC: u8 = 0;

/// `--radio-type`: how radios are read. `Auto` tells them apart by what
/// they send; the others read every radio as that kind (`Raw`: none).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum RadioType {
    #[default]
    Auto,
    Sik,
    Mlrs,
    Elrs,
    Esp,
    Raw,
}

impl RadioType {
    pub(crate) fn as_str(self) -> &'static str {
        match self {
            RadioType::Auto => "auto",
            RadioType::Sik => "sik",
            RadioType::Mlrs => "mlrs",
            RadioType::Elrs => "elrs",
            RadioType::Esp => "esp",
            RadioType::Raw => "raw",
        }
    }

    /// The kind this setting imposes, if any.
    fn forced(self) -> Option<RadioKind> {
        match self {
            RadioType::Auto => None,
            RadioType::Sik => Some(RadioKind::Sik),
            RadioType::Mlrs => Some(RadioKind::Mlrs),
            RadioType::Elrs => Some(RadioKind::Elrs),
            RadioType::Esp => Some(RadioKind::Esp),
            RadioType::Raw => Some(RadioKind::Unknown),
        }
    }
}

/// What a radio is; JSON and Prometheus name it by its [`RadioKind::key`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(into = "&'static str")]
pub(crate) enum RadioKind {
    Sik,
    Mlrs,
    Elrs,
    Esp,
    Unknown,
}

/// RADIO_STATUS's four 8-bit signal fields.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Field {
    Rssi,
    Remrssi,
    Noise,
    Remnoise,
}

impl Field {
    pub(crate) const ALL: [Field; 4] = [Field::Rssi, Field::Remrssi, Field::Noise, Field::Remnoise];

    pub(crate) fn of(self, r: &frame::RadioStatus) -> u8 {
        match self {
            Field::Rssi => r.rssi,
            Field::Remrssi => r.remrssi,
            Field::Noise => r.noise,
            Field::Remnoise => r.remnoise,
        }
    }

    pub(crate) fn index(self) -> usize {
        self as usize
    }
}

/// What one field means for one kind of radio.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Meaning {
    /// Its name in JSON (`rssi_dbm`, `snr_db`, `link_quality_pct`).
    pub(crate) key: &'static str,
    /// Its name in text (`rssi`, `uplink rssi`, `snr`).
    pub(crate) label: &'static str,
    pub(crate) unit: &'static str,
    /// The raw byte to the unit; `None` where the byte says "unknown".
    pub(crate) convert: fn(u8) -> Option<f64>,
    /// How exact the conversion is, as text says it.
    pub(crate) note: &'static str,
}

/// SiK's RSSI scale to dBm: the Si1000's curve, approximate.
pub(crate) fn sik_dbm(raw: f64) -> f64 {
    raw / 1.9 - 127.0
}

fn sik(v: u8) -> Option<f64> {
    (v != UNKNOWN).then(|| sik_dbm(f64::from(v)))
}

/// mLRS's `rssi_i8_to_ap`: (dBm + 120) × 254 / 70 rounded, so whole dBm
/// come back exactly by rounding (0 is −120 dBm or less, 254 −50 or more).
pub(crate) fn mlrs_dbm(v: u8) -> Option<f64> {
    (v != UNKNOWN).then(|| (f64::from(v) * 70.0 / 254.0).round() - 120.0)
}

/// mLRS's noise field: 10 − SNR, clamped to 0…127 (0: SNR 10 dB or more).
fn mlrs_snr(v: u8) -> Option<f64> {
    (v != UNKNOWN).then(|| 10.0 - f64::from(v))
}

/// ExpressLRS's rssi: `(uint8_t)(LQ * 2.55)`, the product in double (so
/// 100 % is sent as 254, 60 % as 153). Its whole percent comes back exactly
/// as the one that encodes to `v`; a byte no LQ gives, as `v / 2.55`.
pub(crate) fn elrs_lq(v: u8) -> Option<f64> {
    if v == UNKNOWN {
        return None;
    }
    let near = (f64::from(v) / 2.55).round();
    let exact = [near - 1.0, near, near + 1.0]
        .into_iter()
        .find(|&lq| (0.0..=100.0).contains(&lq) && (lq * 2.55) as u8 == v);
    Some(exact.unwrap_or(f64::from(v) / 2.55))
}

/// ExpressLRS's remrssi: the uplink RSSI's magnitude.
fn elrs_uplink_dbm(v: u8) -> Option<f64> {
    (v != UNKNOWN).then(|| -f64::from(v))
}

/// An `int8` sent as its byte (ExpressLRS's SNR: 255 is −1 dB, not unknown).
#[allow(clippy::unnecessary_wraps)] // a `Meaning::convert`, whose bytes may be unknown
fn signed(v: u8) -> Option<f64> {
    Some(f64::from(v as i8))
}

/// mavesp8266's WiFi RSSI: an `int8` dBm in station mode, 0 otherwise.
fn esp_rssi(v: u8) -> Option<f64> {
    (v >= 128).then(|| f64::from(v as i8))
}

fn percent(v: u8) -> Option<f64> {
    (v <= 100).then_some(f64::from(v))
}

const SIK_NOTE: &str = "approximate, SiK scale";

impl From<RadioKind> for &'static str {
    fn from(kind: RadioKind) -> Self {
        kind.key()
    }
}

impl RadioKind {
    /// As machines read it: JSON's `kind` and Prometheus's `kind` label.
    pub(crate) fn key(self) -> &'static str {
        match self {
            RadioKind::Sik => "sik",
            RadioKind::Mlrs => "mlrs",
            RadioKind::Elrs => "elrs",
            RadioKind::Esp => "esp",
            RadioKind::Unknown => "unknown",
        }
    }

    /// As reports name it.
    pub(crate) fn name(self) -> &'static str {
        match self {
            RadioKind::Sik => "SiK",
            RadioKind::Mlrs => "mLRS",
            RadioKind::Elrs => "ExpressLRS",
            RadioKind::Esp => "ESP8266 WiFi bridge",
            RadioKind::Unknown => "unknown radio",
        }
    }

    /// What `field` means for this kind; `None`: nothing known (a
    /// constant, or unknown units).
    pub(crate) fn meaning(self, field: Field) -> Option<Meaning> {
        let m = |key, label, unit, convert: fn(u8) -> Option<f64>, note| {
            Some(Meaning {
                key,
                label,
                unit,
                convert,
                note,
            })
        };
        match (self, field) {
            (RadioKind::Sik, Field::Rssi) => m("rssi_dbm", "rssi", "dBm", sik, SIK_NOTE),
            (RadioKind::Sik, Field::Remrssi) => {
                m("remrssi_dbm", "remote rssi", "dBm", sik, SIK_NOTE)
            }
            (RadioKind::Sik, Field::Noise) => m("noise_dbm", "noise floor", "dBm", sik, SIK_NOTE),
            (RadioKind::Sik, Field::Remnoise) => {
                m("remnoise_dbm", "remote noise floor", "dBm", sik, SIK_NOTE)
            }
            (RadioKind::Mlrs, Field::Rssi) => m(
                "rssi_dbm",
                "rssi",
                "dBm",
                mlrs_dbm,
                "mLRS scale: -120..-50 dBm as 0..254",
            ),
            (RadioKind::Mlrs, Field::Remrssi) => m(
                "remrssi_dbm",
                "remote rssi",
                "dBm",
                mlrs_dbm,
                "mLRS scale: -120..-50 dBm as 0..254",
            ),
            (RadioKind::Mlrs, Field::Noise) => m(
                "snr_db",
                "snr",
                "dB",
                mlrs_snr,
                "mLRS: noise = 10 - SNR, 0..127",
            ),
            (RadioKind::Elrs, Field::Rssi) => m(
                "link_quality_pct",
                "link quality",
                "%",
                elrs_lq,
                "ExpressLRS: rssi = LQ x 2.55",
            ),
            (RadioKind::Elrs, Field::Remrssi) => m(
                "remrssi_dbm",
                "uplink rssi",
                "dBm",
                elrs_uplink_dbm,
                "ExpressLRS: remrssi = -dBm",
            ),
            (RadioKind::Elrs, Field::Noise) => m(
                "snr_db",
                "snr",
                "dB",
                signed,
                "ExpressLRS: noise = uplink SNR",
            ),
            (RadioKind::Esp, Field::Rssi) => m(
                "rssi_dbm",
                "wifi rssi",
                "dBm",
                esp_rssi,
                "mavesp8266: station mode only",
            ),
            (RadioKind::Esp, Field::Remnoise) => m(
                "vehicle_lost_pct",
                "vehicle msgs lost",
                "%",
                percent,
                "mavesp8266: remnoise = % of the vehicle's lost",
            ),
            _ => None,
        }
    }

    /// Whether `noise`/`remnoise` are noise floors on the RSSI's scale,
    /// so that RSSI − noise is a fade margin.
    pub(crate) fn has_fade_margin(self) -> bool {
        self == RadioKind::Sik
    }

    /// Whether `txbuf` is the radio's free buffer, which a sender can
    /// overrun.
    pub(crate) fn txbuf_is_free_buffer(self) -> bool {
        matches!(self, RadioKind::Sik | RadioKind::Mlrs | RadioKind::Elrs)
    }

    /// Whether `rxerrors`/`fixed` count the radio's receive errors.
    pub(crate) fn counts_errors(self) -> bool {
        self == RadioKind::Sik
    }

    /// mavesp8266's `rxerrors` is the % of the ground's messages lost.
    pub(crate) fn rxerrors_is_gcs_lost_pct(self) -> bool {
        self == RadioKind::Esp
    }
}

/// Whether a field kept one value in every report.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
struct Constant<T> {
    value: Option<T>,
    varied: bool,
}

impl<T: Copy + PartialEq> Constant<T> {
    fn record(&mut self, v: T) {
        match self.value {
            None => self.value = Some(v),
            Some(was) if was != v => self.varied = true,
            Some(_) => {}
        }
    }

    fn always(&self) -> Option<T> {
        self.value.filter(|_| !self.varied)
    }
}

/// What a radio sent that tells its kind: its reports' rate, the fields
/// that never changed, the messages they came as, a HEARTBEAT from its ids.
#[derive(Debug, Clone, Default, PartialEq)]
pub(crate) struct Evidence {
    reports: u64,
    first_at: Nanos,
    last_at: Nanos,
    heartbeat: Option<(u8, u8)>,
    remnoise: Constant<u8>,
    rxerrors: Constant<u16>,
    fixed: Constant<u16>,
    txbuf: Constant<u8>,
    /// Reports that came as RADIO (166), and as RADIO_STATUS (109).
    as_radio: u64,
    as_status: u64,
    /// Reports sent twice, as RADIO and as RADIO_STATUS.
    pairs: u64,
}

/// What a radio is, and why.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub(crate) struct Judgement {
    pub(crate) kind: RadioKind,
    /// `auto`, or the `--radio-type` that set it.
    pub(crate) radio_type: RadioType,
    /// The evidence, each a clause: "HEARTBEAT type GENERIC, autopilot
    /// INVALID from 51/68".
    pub(crate) evidence: Vec<String>,
}

impl Judgement {
    /// `mLRS (HEARTBEAT type GENERIC, autopilot INVALID from 51/68;
    /// remnoise always 255)`.
    pub(crate) fn describe(&self) -> String {
        format!("{} ({})", self.kind.name(), self.evidence.join("; "))
    }
}

impl Evidence {
    /// A report, as message `msgid` (109 or 166), at `at`; `paired` when it
    /// was the second of a RADIO + RADIO_STATUS pair (then only counted
    /// as such).
    pub(crate) fn report(&mut self, msgid: u32, r: &frame::RadioStatus, at: Nanos, paired: bool) {
        if paired {
            self.pairs += 1;
            return;
        }
        if self.reports == 0 {
            self.first_at = at;
        }
        self.reports += 1;
        self.last_at = at;
        if msgid == frame::ids::RADIO {
            self.as_radio += 1;
        } else {
            self.as_status += 1;
        }
        self.remnoise.record(r.remnoise);
        self.rxerrors.record(r.rxerrors);
        self.fixed.record(r.fixed);
        self.txbuf.record(r.txbuf);
    }

    /// A HEARTBEAT from the radio's own ids.
    pub(crate) fn heartbeat(&mut self, mav_type: u8, autopilot: u8) {
        self.heartbeat = Some((mav_type, autopilot));
    }

    /// Reports per second, once there are enough to say.
    pub(crate) fn rate(&self) -> Option<f64> {
        let span = self.last_at.saturating_sub(self.first_at);
        (self.reports >= MIN_RATE_REPORTS && span > 0)
            .then(|| (self.reports - 1) as f64 / (span as f64 / 1e9))
    }

    fn settled<T: Copy + PartialEq>(&self, c: &Constant<T>) -> Option<T> {
        (self.reports >= MIN_REPORTS).then(|| c.always()).flatten()
    }

    fn errors_always_zero(&self) -> bool {
        self.settled(&self.rxerrors) == Some(0) && self.settled(&self.fixed) == Some(0)
    }

    /// The fields that never changed, as evidence: mLRS's and
    /// ExpressLRS's constants.
    fn constants(&self) -> Vec<String> {
        let mut out = Vec::new();
        if let Some(v) = self
            .settled(&self.remnoise)
            .filter(|&v| v == 0 || v == UNKNOWN)
        {
            out.push(format!("remnoise always {v}"));
        }
        if self.errors_always_zero() {
            out.push("rxerrors and fixed always 0".into());
        }
        out
    }

    fn rate_text(&self) -> Option<String> {
        self.rate().map(|r| {
            if r >= 10.0 {
                format!("~{r:.0} reports/s")
            } else {
                format!("{r:.1} reports/s")
            }
        })
    }

    /// What the messages say about a SiK: RADIO alone is SiK before 2013
    /// (or openLRSng); in pairs, SiK from 2013 to 2016.
    fn messages(&self) -> Option<String> {
        if self.pairs > 0 {
            Some("RADIO (166) beside each RADIO_STATUS, as SiK 2013-2016 sends".into())
        } else if self.as_radio > 0 && self.as_status == 0 {
            Some("RADIO (166) only, as SiK before 2013 and openLRSng send".into())
        } else {
            None
        }
    }

    /// The radio `id`'s kind under `setting`.
    pub(crate) fn judge(&self, id: SysComp, setting: RadioType) -> Judgement {
        let (kind, evidence) = match setting.forced() {
            Some(kind) => (kind, vec![format!("--radio-type {}", setting.as_str())]),
            None => self.auto(id),
        };
        Judgement {
            kind,
            radio_type: setting,
            evidence,
        }
    }

    fn auto(&self, id: SysComp) -> (RadioKind, Vec<String>) {
        if id.compid == COMP_UDP_BRIDGE {
            return (
                RadioKind::Esp,
                vec![format!(
                    "compid {COMP_UDP_BRIDGE} (UDP bridge), as mavesp8266 sends its RADIO_STATUS"
                )],
            );
        }
        if id.compid != COMP_TELEMETRY_RADIO {
            return (
                RadioKind::Unknown,
                vec![format!(
                    "{id}: compid {} is no radio's (SiK, mLRS and ExpressLRS send as 68, mavesp8266 as 240)",
                    id.compid
                )],
            );
        }
        if let Some((mav_type, autopilot)) = self.heartbeat {
            let said = format!(
                "HEARTBEAT type {}, autopilot {} from {id}",
                frame::vehicle_type_name(mav_type).to_uppercase(),
                frame::autopilot_name(autopilot).to_uppercase()
            );
            if mav_type == MAV_TYPE_GENERIC && autopilot == frame::AUTOPILOT_INVALID {
                let mut evidence = vec![said];
                evidence.extend(self.constants());
                return (RadioKind::Mlrs, evidence);
            }
            return (
                RadioKind::Unknown,
                vec![format!(
                    "{said}: SiK sends none, mLRS type GENERIC, autopilot INVALID"
                )],
            );
        }
        let rate = self.rate();
        if rate.is_some_and(|r| r >= ELRS_MIN_RATE) {
            let mut evidence = vec![self.rate_text().expect("a rate")];
            if id.sysid == ELRS_SYSID {
                evidence.push(format!("{id}, an ExpressLRS receiver's default ids"));
            }
            evidence.extend(self.constants());
            return (RadioKind::Elrs, evidence);
        }
        if id.sysid == ELRS_SYSID && rate.is_none() {
            return (
                RadioKind::Elrs,
                vec![format!(
                    "{id}, an ExpressLRS receiver's default ids (its 100 reports/s not yet seen)"
                )],
            );
        }
        if self.settled(&self.remnoise) == Some(UNKNOWN) && self.errors_always_zero() {
            return (
                RadioKind::Mlrs,
                vec![format!(
                    "no HEARTBEAT, but remnoise always 255 and rxerrors and fixed always 0 over {} reports, \
                     as mLRS sends them (a SiK reports its remote noise and counts errors)",
                    self.reports
                )],
            );
        }
        let mut evidence = vec![format!("compid 68 and no HEARTBEAT from {id}")];
        evidence.extend(self.rate_text());
        evidence.extend(self.messages());
        (RadioKind::Sik, evidence)
    }
}

/// The second message of a RADIO + RADIO_STATUS pair: SiK from 2013 to
/// 2016 sent each report as both, one right after the other under one
/// packet sequence number, with the same figures. It is one report.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub(crate) struct PairFilter {
    last: Option<(u32, u8, frame::RadioStatus)>,
}

impl PairFilter {
    /// Whether this message repeats the one before it (the other message
    /// id, the same sequence number and figures).
    pub(crate) fn repeats(&mut self, msgid: u32, seq: u8, r: &frame::RadioStatus) -> bool {
        let repeat = self
            .last
            .is_some_and(|(m, s, last)| m != msgid && s == seq && last == *r);
        // A repeat closes the pair: a third message starts afresh.
        self.last = (!repeat).then_some((msgid, seq, *r));
        repeat
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frame::ids::{RADIO, RADIO_STATUS};
    use crate::frame::RadioStatus;

    const S: Nanos = 1_000_000_000;

    #[test]
    fn json_names_a_kind_by_its_key() {
        for (kind, key) in [
            (RadioKind::Sik, "sik"),
            (RadioKind::Mlrs, "mlrs"),
            (RadioKind::Elrs, "elrs"),
            (RadioKind::Esp, "esp"),
            (RadioKind::Unknown, "unknown"),
        ] {
            assert_eq!(kind.key(), key);
            assert_eq!(serde_json::to_value(kind).unwrap(), key);
        }
    }

    fn sik_report(rssi: u8, rxerrors: u16) -> RadioStatus {
        RadioStatus {
            rssi,
            remrssi: rssi - 10,
            txbuf: 95,
            noise: 40,
            remnoise: 38,
            rxerrors,
            fixed: 0,
        }
    }

    fn mlrs_report(rssi: u8) -> RadioStatus {
        RadioStatus {
            rssi,
            remrssi: rssi,
            txbuf: 100,
            noise: 3,
            remnoise: UNKNOWN,
            rxerrors: 0,
            fixed: 0,
        }
    }

    fn feed(ev: &mut Evidence, n: u64, every: Nanos, r: RadioStatus) {
        for i in 0..n {
            ev.report(RADIO_STATUS, &r, i * every, false);
        }
    }

    #[test]
    fn conversions_invert_what_each_radio_encodes() {
        // mLRS's rssi_i8_to_ap: (r * 254 + 35) / 70, r = dBm + 120.
        for dbm in -120i32..=-50 {
            let r = dbm + 120;
            let raw = ((r * 254 + 35) / 70) as u8;
            assert_eq!(mlrs_dbm(raw), Some(f64::from(dbm)), "{dbm}");
        }
        assert_eq!(mlrs_dbm(UNKNOWN), None);
        // ExpressLRS: (uint8_t)(LQ * 2.55), the product in double.
        for lq in 0u32..=100 {
            let raw = (f64::from(lq) * 2.55) as u8;
            assert_eq!(elrs_lq(raw), Some(f64::from(lq)), "{lq}");
        }
        assert_eq!(signed(251), Some(-5.0));
        assert_eq!(signed(255), Some(-1.0));
        assert_eq!(elrs_uplink_dbm(87), Some(-87.0));
        assert_eq!(esp_rssi((-61i8) as u8), Some(-61.0));
        assert_eq!(esp_rssi(0), None);
        assert_eq!(mlrs_snr(0), Some(10.0));
        assert!((sik(190).unwrap() - (190.0 / 1.9 - 127.0)).abs() < 1e-12);
    }

    #[test]
    fn sik_by_its_ids_and_silence() {
        let mut ev = Evidence::default();
        feed(&mut ev, 6, S, sik_report(150, 3));
        let j = ev.judge(SysComp::new(51, 68), RadioType::Auto);
        assert_eq!(j.kind, RadioKind::Sik);
        assert_eq!(
            j.describe(),
            "SiK (compid 68 and no HEARTBEAT from 51/68; 1.0 reports/s)"
        );
    }

    #[test]
    fn mlrs_by_its_heartbeat_or_its_constants() {
        let mut ev = Evidence::default();
        ev.report(RADIO_STATUS, &mlrs_report(120), 0, false);
        // Its first report alone: a SiK as far as anyone can tell.
        assert_eq!(
            ev.judge(SysComp::new(51, 68), RadioType::Auto).kind,
            RadioKind::Sik
        );
        ev.heartbeat(0, 8);
        feed(&mut ev, 3, S, mlrs_report(120));
        let j = ev.judge(SysComp::new(51, 68), RadioType::Auto);
        assert_eq!(
            j.describe(),
            "mLRS (HEARTBEAT type GENERIC, autopilot INVALID from 51/68; remnoise always 255; \
             rxerrors and fixed always 0)"
        );
        // Without its MAVLink component (no HEARTBEAT): the constants.
        let mut quiet = Evidence::default();
        feed(&mut quiet, 3, S, mlrs_report(120));
        let j = quiet.judge(SysComp::new(51, 68), RadioType::Auto);
        assert_eq!(j.kind, RadioKind::Mlrs, "{j:?}");
        // A SiK that happens to count no errors still reports remote noise.
        let mut sik = Evidence::default();
        feed(&mut sik, 10, S, sik_report(150, 0));
        assert_eq!(
            sik.judge(SysComp::new(51, 68), RadioType::Auto).kind,
            RadioKind::Sik
        );
    }

    #[test]
    fn elrs_by_its_rate_or_its_ids() {
        let r = RadioStatus {
            rssi: 254,
            remrssi: 60,
            txbuf: 97,
            noise: 9,
            ..RadioStatus::default()
        };
        let mut ev = Evidence::default();
        ev.report(RADIO_STATUS, &r, 0, false);
        let j = ev.judge(SysComp::new(255, 68), RadioType::Auto);
        assert_eq!(j.kind, RadioKind::Elrs);
        let mut ev = Evidence::default();
        feed(&mut ev, 100, S / 100, r);
        let j = ev.judge(SysComp::new(255, 68), RadioType::Auto);
        assert_eq!(
            j.describe(),
            "ExpressLRS (~100 reports/s; 255/68, an ExpressLRS receiver's default ids; \
             remnoise always 0; rxerrors and fixed always 0)"
        );
        // Another sysid: the rate alone.
        assert_eq!(
            ev.judge(SysComp::new(7, 68), RadioType::Auto).kind,
            RadioKind::Elrs
        );
        // 255/68 at 1 Hz is no ExpressLRS receiver.
        let mut slow = Evidence::default();
        feed(&mut slow, 6, S, sik_report(150, 0));
        assert_eq!(
            slow.judge(SysComp::new(255, 68), RadioType::Auto).kind,
            RadioKind::Sik
        );
    }

    #[test]
    fn esp_unknown_and_forced() {
        let ev = Evidence::default();
        assert_eq!(
            ev.judge(SysComp::new(1, 240), RadioType::Auto).kind,
            RadioKind::Esp
        );
        let j = ev.judge(SysComp::new(3, 1), RadioType::Auto);
        assert_eq!(j.kind, RadioKind::Unknown);
        let j = ev.judge(SysComp::new(3, 1), RadioType::Mlrs);
        assert_eq!(j.describe(), "mLRS (--radio-type mlrs)");
        assert_eq!(
            ev.judge(SysComp::new(51, 68), RadioType::Raw).kind,
            RadioKind::Unknown
        );
        let mut other = Evidence::default();
        other.heartbeat(2, 3);
        assert_eq!(
            other.judge(SysComp::new(51, 68), RadioType::Auto).kind,
            RadioKind::Unknown
        );
    }

    #[test]
    fn a_pair_is_one_report_and_radio_alone_is_old_sik() {
        let mut f = PairFilter::default();
        let r = sik_report(150, 0);
        assert!(!f.repeats(RADIO, 7, &r));
        assert!(f.repeats(RADIO_STATUS, 7, &r));
        // The next report: a new sequence number.
        assert!(!f.repeats(RADIO, 8, &r));
        // Same seq but other figures: two reports.
        assert!(!f.repeats(RADIO_STATUS, 8, &sik_report(151, 0)));
        // Two RADIO_STATUS with the same seq (a wrap): two reports.
        let mut g = PairFilter::default();
        assert!(!g.repeats(RADIO_STATUS, 1, &r));
        assert!(!g.repeats(RADIO_STATUS, 1, &r));

        let mut ev = Evidence::default();
        for i in 0..3 {
            ev.report(RADIO, &r, i * S, false);
        }
        let j = ev.judge(SysComp::new(51, 68), RadioType::Auto);
        assert!(
            j.describe()
                .contains("RADIO (166) only, as SiK before 2013"),
            "{j:?}"
        );
    }
}
