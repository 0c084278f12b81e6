//! A telemetry log's timeline as JSON: a `flight_window` line per window
//! of log time as it closes (the last, partial, one just before the
//! summary), a `flight_silence` or `flight_burst` line as each ends, and
//! the `flight` object of the `passive_summary`. Each time is given twice:
//! since the log's first record (`t_s`, `end_t_s`) and as the log's wall
//! clock (`time`, `end_time`).

use std::io::{self, Write};

use serde::Serialize;

use super::lines::Lines;
use super::units::seconds;
use super::JsonReporter;
use crate::engine::probe::passive::flight::{
    diagnosis_text, FlightEvent, FlightSummary, FlightWindow, Origin, SilenceRadio, Span,
};
use crate::engine::radio::RadioKind;
use crate::frame::SysComp;

/// A window: its place and times, then its figures as the engine
/// serialises them.
#[derive(Serialize)]
pub(super) struct Window<'a> {
    r#type: &'static str,
    index: u64,
    t_s: f64,
    end_t_s: f64,
    time: String,
    end_time: String,
    #[serde(flatten)]
    figures: &'a FlightWindow,
}

#[derive(Serialize)]
pub(super) struct Timed {
    r#type: &'static str,
    t_s: f64,
    end_t_s: f64,
    time: String,
    end_time: String,
    length_s: f64,
    received: u64,
    lost: i64,
    loss_pct: Option<f64>,
    ongoing: bool,
    /// A silence: the followed radio's figures during it.
    radio: Option<SpanRadio>,
}

/// The radio during a silence, and its diagnosis in words.
#[derive(Serialize)]
pub(super) struct SpanRadio {
    #[serde(flatten)]
    radio: SilenceRadio,
    diagnosis_text: Option<String>,
}

/// The summary's `flight` object.
#[derive(Serialize)]
pub(super) struct Summary<'a> {
    window_s: f64,
    silence_s: f64,
    burst_loss_pct: f64,
    windows: u64,
    untold: u64,
    positions: u64,
    origin: Option<&'a Origin>,
    radio: Option<SysComp>,
    radio_kind: Option<RadioKind>,
    radio_evidence: &'a [String],
    farthest: Option<Window<'a>>,
    worst: Vec<Window<'a>>,
    silence_count: u64,
    silences: Vec<Timed>,
    burst_count: u64,
    bursts: Vec<Timed>,
}

impl Lines {
    pub(super) fn flight_window<'a>(&self, w: &'a FlightWindow) -> Window<'a> {
        Window {
            r#type: "flight_window",
            index: w.index,
            t_s: seconds(w.start),
            end_t_s: seconds(w.end),
            time: self.wall.rfc3339(w.start),
            end_time: self.wall.rfc3339(w.end),
            figures: w,
        }
    }

    pub(super) fn flight_span(&self, kind: &'static str, s: &Span) -> Timed {
        Timed {
            r#type: kind,
            t_s: seconds(s.start),
            end_t_s: seconds(s.end),
            time: self.wall.rfc3339(s.start),
            end_time: self.wall.rfc3339(s.end),
            length_s: seconds(s.length_ns()),
            received: s.received,
            lost: s.lost,
            loss_pct: s.loss_pct(),
            ongoing: s.ongoing,
            radio: s.radio.as_deref().map(|&radio| SpanRadio {
                radio,
                diagnosis_text: diagnosis_text(s),
            }),
        }
    }

    pub(super) fn flight_summary<'a>(&self, f: &'a FlightSummary) -> Summary<'a> {
        let spans = |kind, v: &[Span]| v.iter().map(|s| self.flight_span(kind, s)).collect();
        Summary {
            window_s: seconds(f.window_ns),
            silence_s: seconds(f.silence_ns),
            burst_loss_pct: f.burst_loss_pct,
            windows: f.windows,
            untold: f.untold,
            positions: f.positions,
            origin: f.origin.as_ref(),
            radio: f.radio,
            radio_kind: f.radio_kind,
            radio_evidence: &f.radio_evidence,
            farthest: f.farthest.as_ref().map(|w| self.flight_window(w)),
            worst: f.worst.iter().map(|w| self.flight_window(w)).collect(),
            silence_count: f.silence_count,
            silences: spans("flight_silence", &f.silences),
            burst_count: f.burst_count,
            bursts: spans("flight_burst", &f.bursts),
        }
    }
}

impl<W: Write> JsonReporter<W> {
    /// The line of a window closed, or of a silence or burst ended.
    pub(super) fn flight_line(&mut self, e: &FlightEvent) -> io::Result<()> {
        match e {
            FlightEvent::Window(w) => self.event_line(Some(self.lines.flight_window(w))),
            FlightEvent::Silence(s) => {
                self.event_line(Some(self.lines.flight_span("flight_silence", s)))
            }
            FlightEvent::Burst(b) => {
                self.event_line(Some(self.lines.flight_span("flight_burst", b)))
            }
        }
    }

    /// The log's last, partial, window and the burst still on when it
    /// ended, just before the summary (not with `-q`).
    pub(super) fn flight_ends(&mut self, f: &FlightSummary) -> io::Result<()> {
        if self.quiet {
            return Ok(());
        }
        if let Some(last) = f.last.as_ref() {
            let line = self.lines.flight_window(last);
            self.lines.write(&mut self.out, &line)?;
        }
        if let Some(b) = f.last_burst.as_ref() {
            let line = self.lines.flight_span("flight_burst", b);
            self.lines.write(&mut self.out, &line)?;
        }
        Ok(())
    }
}
