//! A telemetry log's timeline as text, under its summary: the windows,
//! where distances are from and the farthest window, the worst windows by
//! loss, and the longest silences and loss bursts, each at its time since
//! the log began and on the log's own clock.

use std::io::{self, Write};
use std::time::{Duration, SystemTime};

use super::format::{counted, percent_or_dash, whole_or};
use crate::engine::probe::passive::flight::{
    diagnosis_text, FlightSummary, FlightWindow, OriginKind, SilenceFigure, Span,
};
use crate::engine::Nanos;

/// The log's clock: its first record's stamp, µs since the Unix epoch.
#[derive(Debug, Clone, Copy)]
pub(super) struct LogClock(pub u64);

impl LogClock {
    fn at(self, t: Nanos) -> String {
        let at = SystemTime::UNIX_EPOCH + Duration::from_micros(self.0) + Duration::from_nanos(t);
        humantime::format_rfc3339_seconds(at).to_string()
    }

    /// `120.0-130.0 s (10:15:20Z-10:15:30Z)`: since the log began, and on
    /// its clock.
    fn span(self, start: Nanos, end: Nanos) -> String {
        let (from, to) = (self.at(start), self.at(end));
        // The date once, from the start.
        let to = to.split_once('T').map_or(to.as_str(), |(_, time)| time);
        let (start_s, end_s) = (start as f64 / 1e9, end as f64 / 1e9);
        format!("{start_s:.1}-{end_s:.1} s ({from} to {to})")
    }
}

pub(super) fn write_flight(
    out: &mut impl Write,
    f: &FlightSummary,
    clock: LogClock,
) -> io::Result<()> {
    let (window_s, silence_s) = (f.window_ns as f64 / 1e9, f.silence_ns as f64 / 1e9);
    let silences = counted(f.silence_count, "silence");
    let bursts = counted(f.burst_count, "loss burst");
    writeln!(
        out,
        "flight: {} windows of {window_s:.0} s; {silences} (nothing but the radio for \
         {silence_s:.1} s or more), {bursts} (windows losing {:.0}% or more in a row)",
        f.windows, f.burst_loss_pct,
    )?;
    if let (Some(id), Some(kind)) = (f.radio, f.radio_kind) {
        let (kind, evidence) = (kind.name(), f.radio_evidence.join("; "));
        writeln!(out, "flight radio {id}: {kind} ({evidence})")?;
    }
    write_range(out, f, clock)?;
    for w in &f.worst {
        writeln!(out, "flight worst: {}", window(w, clock))?;
    }
    for s in &f.silences {
        writeln!(out, "flight silence: {}", span(s, clock, false))?;
        write_silence_radio(out, s)?;
    }
    for b in &f.bursts {
        writeln!(out, "flight burst: {}", span(b, clock, true))?;
    }
    let (silences, bursts) = f.unlisted();
    if silences + bursts > 0 {
        writeln!(
            out,
            "flight: {silences} shorter silences and {bursts} shorter bursts not listed (every one is in --json)"
        )?;
    }
    if f.untold > 0 {
        writeln!(out, "flight: {} windows not told (output behind)", f.untold)?;
    }
    Ok(())
}

/// Where distances are from, and the farthest window.
fn write_range(out: &mut impl Write, f: &FlightSummary, clock: LogClock) -> io::Result<()> {
    let Some(o) = &f.origin else {
        return writeln!(out, "flight: no position in the log, no distances");
    };
    let origin = match o.kind {
        OriginKind::FirstFix => "first fix",
        OriginKind::Home => "HOME_POSITION",
    };
    writeln!(
        out,
        "flight: {} positions of {}; distances from its {origin} ({:.7}, {:.7}, {:.1} m)",
        f.positions, o.vehicle, o.lat_deg, o.lon_deg, o.alt_m
    )?;
    if let Some(w) = &f.farthest {
        writeln!(out, "flight farthest: {}", window(w, clock))?;
    }
    Ok(())
}

/// `120.0-130.0 s (...): 450 received, 50 lost (10.00%); rssi 150/148
/// noise 40/41 rxerrors +12; 1203 m (ground 1200 m, alt 150.0 m)`.
fn window(w: &FlightWindow, clock: LogClock) -> String {
    let span = clock.span(w.start, w.end);
    let mut line = format!("{span}: {}", received_lost(w.received, w.lost, w.loss_pct));
    if let Some(r) = &w.radio {
        let [rssi, remrssi, noise, remnoise] =
            [r.rssi, r.remrssi, r.noise, r.remnoise].map(|v| whole_or(v, "-"));
        line += &format!(
            "; rssi {rssi}/{remrssi} noise {noise}/{remnoise} rxerrors +{}",
            r.rxerrors
        );
    }
    if let Some(r) = &w.range {
        line += &format!(
            "; {:.0} m (ground {:.0} m, alt {:.1} m)",
            r.distance_m, r.ground_m, r.alt_m
        );
    }
    if let Some(a) = &w.age {
        line += &format!("; age p99 {:.0} ms (max {:.0})", a.p99_ms, a.max_ms);
    }
    line
}

/// `450 received, 50 lost (10.00%)`: a window's or a burst's frames.
fn received_lost(received: u64, lost: impl std::fmt::Display, loss_pct: Option<f64>) -> String {
    format!(
        "{received} received, {lost} lost ({})",
        percent_or_dash(loss_pct)
    )
}

fn span(s: &Span, clock: LogClock, burst: bool) -> String {
    let (span, length_s) = (clock.span(s.start, s.end), s.length_ns() as f64 / 1e9);
    let mut line = format!("{span}, {length_s:.1} s");
    if burst {
        line += &format!(": {}", received_lost(s.received, s.lost, s.loss_pct()));
    }
    if s.ongoing {
        line += ", still on at the end of the log";
    }
    line
}

/// `rssi -98.4/-97.9 dBm (raw 54/56)`: min/mean in the kind's unit, and
/// as sent.
fn silence_figure(f: &SilenceFigure) -> String {
    if f.unit == "raw" {
        return format!("{} {:.0}/{:.1}", f.label, f.raw_min, f.raw_mean);
    }
    let sep = if f.unit == "%" { "" } else { " " };
    format!(
        "{} {:.1}/{:.1}{sep}{} (raw {:.0}/{:.1})",
        f.label, f.min, f.mean, f.unit, f.raw_min, f.raw_mean
    )
}

/// A silence's radio figures, min/mean, and what they say.
fn write_silence_radio(out: &mut impl Write, s: &Span) -> io::Result<()> {
    let Some(r) = &s.radio else { return Ok(()) };
    if r.reports == 0 {
        return writeln!(out, "  radio {}: no report during it", r.id);
    }
    let figures: Vec<String> = [&r.rssi, &r.remrssi, &r.noise, &r.remnoise]
        .into_iter()
        .flatten()
        .map(silence_figure)
        .collect();
    let (kind, figures) = (r.kind.name(), figures.join(", "));
    writeln!(
        out,
        "  radio {} ({kind}), {} reports, min/mean: {figures}",
        r.id, r.reports
    )?;
    if let Some(text) = diagnosis_text(s) {
        writeln!(out, "  diagnosis: {text}")?;
    }
    Ok(())
}
