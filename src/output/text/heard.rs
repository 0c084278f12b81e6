//! What the link hears, whatever the run: a system's first HEARTBEAT, a
//! radio's reports (a line when it is first heard or its kind changes, a
//! note on reply lines), nobody yet; and the radios in the summary.

use std::io::{self, Write};

use super::{format, TextReporter};
use crate::engine::observe::RadioHeard;
use crate::engine::radio::{self, Field, RadioKind, RadioReport, RadioSummary};
use crate::engine::roster::Identity;
use crate::engine::Nanos;
use crate::frame::SysComp;

/// Reply lines carry the radio's figures at most this often.
const RADIO_NOTE_EVERY_NS: Nanos = 1_000_000_000;

impl<W: Write> TextReporter<W> {
    /// A radio's report: remembered for the reply lines; told at its first
    /// and when its kind changed, with what it is and why.
    pub(super) fn radio_line(&mut self, heard: &RadioHeard<'_>) -> io::Result<()> {
        let (id, kind) = (heard.id, heard.judgement.kind);
        self.radio = Some((id, heard.report, kind));
        if !heard.first && !heard.kind_changed {
            return Ok(());
        }
        self.stamp(heard.at)?;
        let what = heard.judgement.describe();
        let figures = radio_heard(kind, &heard.report);
        if heard.kind_changed {
            return writeln!(self.out, "radio {id} is {what}: {figures}");
        }
        writeln!(self.out, "heard radio {id}: {figures} — {what}")
    }

    pub(super) fn heard_line(&mut self, id: SysComp, identity: &Identity) -> io::Result<()> {
        self.stamp(identity.first_heard)?;
        writeln!(self.out, "heard {id}: {}", format::identity(identity))
    }

    pub(super) fn waiting_line(&mut self) -> io::Result<()> {
        self.stamp(0)?;
        writeln!(self.out, "waiting for a peer to send MAVLink...")
    }

    /// " [radio 51:68 rssi=… remrssi=… txbuf=…%]" when one is heard and
    /// the last note is at least a second old, so fast runs stay readable.
    pub(super) fn radio_note(&mut self, at: Nanos) -> String {
        let Some((id, r, kind)) = self.radio else {
            return String::new();
        };
        if self
            .radio_shown
            .is_some_and(|t| at.saturating_sub(t) < RADIO_NOTE_EVERY_NS)
        {
            return String::new();
        }
        self.radio_shown = Some(at);
        format!(" [radio {id} {}]", radio_figures(kind, &r))
    }
}

fn raw(v: u8) -> String {
    format::whole_or((v != radio::UNKNOWN).then_some(f64::from(v)), "?")
}

/// A figure in its kind's unit: whole numbers as such (mLRS's and
/// ExpressLRS's are whole dB), others to a tenth.
fn in_unit(v: f64, unit: &str) -> String {
    let sep = if unit == "%" { "" } else { " " };
    let places = usize::from(v.fract() != 0.0);
    format!("{v:.places$}{sep}{unit}")
}

/// The figures a kind gives a meaning to, in its units: `rssi -85 dBm,
/// remote rssi -90 dBm, snr 7 dB`; a SiK's and an unknown radio's raw,
/// as SiK users know them.
fn radio_figures(kind: RadioKind, r: &RadioReport) -> String {
    if matches!(kind, RadioKind::Sik | RadioKind::Unknown) {
        let [rssi, remrssi, txbuf] = [r.rssi, r.remrssi, r.txbuf].map(raw);
        return format!("rssi={rssi} remrssi={remrssi} txbuf={txbuf}%");
    }
    Field::ALL
        .into_iter()
        .filter_map(|f| {
            let m = kind.meaning(f)?;
            let v = (m.convert)(f.of(r)).map_or_else(|| "?".into(), |v| in_unit(v, m.unit));
            Some(format!("{} {v}", m.label))
        })
        .collect::<Vec<_>>()
        .join(", ")
}

/// A radio's first report (or the one its kind changed with) in full.
fn radio_heard(kind: RadioKind, r: &RadioReport) -> String {
    let figures = radio_figures(kind, r);
    match kind {
        RadioKind::Sik | RadioKind::Unknown => {
            let [noise, remnoise] = [r.noise, r.remnoise].map(raw);
            format!("{figures}, noise={noise} remnoise={remnoise}")
        }
        RadioKind::Esp => format!("{figures}, ground msgs lost {}%", r.rxerrors),
        RadioKind::Mlrs | RadioKind::Elrs => format!("{figures}, txbuf {}%", raw(r.txbuf)),
    }
}

/// A radio's block in a summary: what it is and why, its figures as
/// sent, then in its kind's units.
pub(super) fn write_radio(out: &mut impl Write, r: &RadioSummary) -> io::Result<()> {
    let kind = r.judgement.kind;
    writeln!(out, "radio {}: {}", r.id, r.judgement.describe())?;
    if kind.counts_errors() {
        writeln!(
            out,
            "  {} reports, rxerrors +{}, fixed +{} during the run",
            r.reports, r.rxerrors_delta, r.fixed_delta
        )?;
    } else {
        writeln!(out, "  {} reports", r.reports)?;
    }
    let rows = [
        ("rssi", r.rssi, ""),
        ("remote rssi", r.remrssi, ""),
        ("noise", r.noise, ""),
        ("remote noise", r.remnoise, ""),
        ("fade margin", r.fade_margin, ""),
        ("remote fade margin", r.remote_fade_margin, ""),
        ("txbuf free", r.txbuf, " %"),
    ];
    for (name, range, unit) in rows {
        if let Some(v) = range {
            writeln!(
                out,
                "  {name:<18} min/mean/max = {:.0}/{:.1}/{:.0}{unit} (raw)",
                v.min, v.mean, v.max
            )?;
        }
    }
    for f in &r.converted.0 {
        let v = f.range;
        let approximate = if kind == RadioKind::Sik { "~" } else { "" };
        writeln!(
            out,
            "  {:<18} {approximate}{:.1}/{:.1}/{:.1} {} ({})",
            f.label, v.min, v.mean, v.max, f.unit, f.note
        )?;
    }
    Ok(())
}
