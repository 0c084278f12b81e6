//! Text of a sweep (`--sweep`) or a `--load` run: the first line says
//! what will be sent, a table row per step as it ends, and the summary's
//! verdict lines (the knee beside what the baud rate alone allows,
//! queueing, the load's effect).

use std::io::{self, Write};

use super::format::{counted, ms_us, whole_or};
use super::TextReporter;
use crate::engine::capacity::WireBudget;
use crate::engine::sweep::step::Phase;
use crate::engine::sweep::step::{StepFigures, KNEE_MAX_LOSS};
use crate::engine::sweep::verdict::{Queueing, SweepEnd, SweepSummary};
use crate::engine::sweep::{MaxFrom, PlanKind, SweepConfig};
use crate::output::StartInfo;

/// A rate as people write it: `2`, `12.5`, `153.8`.
fn hz(v: f64) -> String {
    let places = usize::from((v - v.round()).abs() >= 0.05);
    format!("{v:.places$}")
}

/// What the `--load` streams send, e.g. `; load ATTITUDE@50/s +
/// BYTES@1000 B/s (3000 B/s on the wire)`; nothing without a load.
fn load_line(c: &SweepConfig) -> String {
    if c.load.is_empty() {
        return String::new();
    }
    let streams: Vec<String> = c
        .load
        .iter()
        .map(|l| match l.kind {
            crate::engine::load::LoadKind::Bytes => format!("BYTES@{} B/s", hz(l.rate)),
            _ => format!("{}@{}/s", l.kind.name(), hz(l.rate)),
        })
        .collect();
    format!(
        "; load {} ({:.0} B/s on the wire)",
        streams.join(" + "),
        c.load_bytes_per_s
    )
}

/// The table's columns: title and width (the phase is left-aligned, the
/// figures right-aligned), so the header and the rows share one layout.
const COLUMNS: [(&str, usize); 13] = [
    ("step", 4),
    ("phase", 11),
    ("rate/s", 7),
    ("achieved", 9),
    ("sent", 7),
    ("recv", 7),
    ("lost", 6),
    ("loss%", 7),
    ("late", 5),
    ("p50 ms", 10),
    ("p99 ms", 10),
    ("tx B/s", 9),
    ("rx B/s", 9),
];

/// One line of the table: each value in its column, then the knee test.
fn columns(values: [&str; 13], knee: &str) -> String {
    let mut line = String::new();
    for (i, ((_, width), value)) in COLUMNS.iter().zip(values).enumerate() {
        match i {
            1 => line.push_str(&format!(" {value:<width$}")),
            _ => line.push_str(&format!("{value:>width$}")),
        }
    }
    line + "  " + knee
}

fn header() -> String {
    columns(COLUMNS.map(|(title, _)| title), "knee")
}

impl<W: Write> TextReporter<W> {
    /// The first line: what will be sent.
    pub(super) fn sweep_start(&mut self, info: &StartInfo, c: &SweepConfig) -> io::Result<()> {
        let step = humantime::format_duration(c.step);
        let probe = info.probe.as_str().to_uppercase();
        let loaded = !c.load.is_empty();
        let what = match c.plan {
            PlanKind::Sweep {
                first_hz,
                max_hz,
                max_from,
                loss_limit,
            } => {
                let why = match max_from {
                    MaxFrom::Given => String::new(),
                    MaxFrom::Baud { baud, capacity_hz } => format!(
                        " (twice the ~{}/s that {baud} baud carries; --sweep-max to change)",
                        hz(capacity_hz.floor())
                    ),
                    MaxFrom::Default => {
                        " (the default for links without a baud rate; --sweep-max to change)".into()
                    }
                };
                let (first, max, limit) = (hz(first_hz), hz(max_hz), loss_limit * 100.0);
                let baseline = if loaded {
                    format!(", first {step} at {first}/s without the load")
                } else {
                    String::new()
                };
                format!(
                    "{probe} sweep from {first}/s up to {max}/s{why}, {step} a step, stopping past \
                     {limit:.0}% loss{baseline}"
                )
            }
            PlanKind::Load { rate_hz } => format!(
                "{probe} {}/s, {step} without the load then {step} with it",
                hz(rate_hz)
            ),
        };
        let load = load_line(c);
        let timeout = humantime::format_duration(info.timeout);
        self.start_line(info, format_args!("{what}{load}, timeout {timeout}"))
    }

    /// A step's row; the first comes under the table's header.
    pub(super) fn step_row(&mut self, s: &StepFigures) -> io::Result<()> {
        if self.steps_shown == 0 {
            writeln!(self.out, "{}", header())?;
        }
        self.steps_shown += 1;
        writeln!(self.out, "{}", row(s))
    }
}

/// Why a step failed the knee test, or that it passed.
fn knee_mark(s: &StepFigures) -> &'static str {
    match s.passed {
        Some(true) => "ok",
        Some(false) if s.received == 0 => "no replies",
        Some(false) if s.loss_ratio >= KNEE_MAX_LOSS => "loss",
        Some(false) => "p99",
        None if !s.complete => "cut short",
        None => "-",
    }
}

fn row(s: &StepFigures) -> String {
    // A retry is named as such: the rate of the row above, once more.
    let name = if s.retry { "retry" } else { s.phase.name() };
    let phase = match (s.phase, s.load) {
        (Phase::Ramp | Phase::Refine, true) => format!("{name}+load"),
        _ => name.to_string(),
    };
    let (p50, p99) = match s.rtt {
        Some(r) => (ms_us(r.p50_us), ms_us(r.p99_us)),
        None => ("-".into(), "-".into()),
    };
    let mut line = columns(
        [
            &s.index.to_string(),
            &phase,
            &hz(s.offered_hz),
            &format!("{:.1}", s.achieved_hz),
            &s.requests.to_string(),
            &s.received.to_string(),
            &s.lost.to_string(),
            &format!("{:.2}", s.loss_ratio * 100.0),
            &s.late.to_string(),
            &p50,
            &p99,
            &format!("{:.0}", s.tx_bytes_per_s),
            &format!("{:.0}", s.rx_bytes_per_s),
        ],
        knee_mark(s),
    );
    if let Some(r) = &s.radio {
        let min = r.txbuf_min.map_or("?".into(), |v| v.to_string());
        let [mean, rssi, remrssi] =
            [r.txbuf_mean, r.rssi_mean, r.remrssi_mean].map(|v| whole_or(v, "?"));
        line.push_str(&format!(
            "  radio {} txbuf min {min}% mean {mean}%, rssi {rssi} remrssi {remrssi}, rxerrors +{}",
            r.id, r.rxerrors_delta
        ));
    }
    line
}

/// The summary's part: the rows not shown as the run went (all of them
/// with `-q`; the step cut short by Ctrl-C), then what the steps say.
pub(super) fn write_summary(
    out: &mut impl Write,
    s: &SweepSummary,
    probe: &str,
    wire: Option<&WireBudget>,
    shown: usize,
) -> io::Result<()> {
    let rest = s.steps.get(shown..).unwrap_or_default();
    if !rest.is_empty() {
        writeln!(out, "{}", header())?;
        for step in rest {
            writeln!(out, "{}", row(step))?;
        }
    }
    let ending = match s.ending {
        SweepEnd::Planned => "every step planned was run",
        SweepEnd::LossLimit => "the ramp stopped where a step lost more than the limit",
        SweepEnd::NoReplies => "nothing answered, so the ramp went no further",
        SweepEnd::Interrupted => "interrupted; the steps so far are above",
        SweepEnd::Deadline => "the deadline ended it; the steps so far are above",
        SweepEnd::LinkFailed => "the link failed; the steps so far are above",
    };
    let steps = counted(s.steps.len() as u64, "step");
    writeln!(out, "{}: {steps}, {ending}", s.kind)?;
    let baud = wire.map_or_else(String::new, |w| {
        let carries = hz(w.max_rate_hz.floor());
        format!("; the baud rate alone says ~{carries}/s ({} baud)", w.baud)
    });
    if s.kind == "sweep" {
        write_knee(out, s, probe, &baud)?;
        if let Some(q) = &s.queueing {
            write_queueing(out, q)?;
        }
    }
    for l in &s.load {
        let rate = hz(l.rate);
        writeln!(
            out,
            "load {}@{rate}: {} frames of {} B, {} B sent",
            l.message, l.frames, l.frame_bytes, l.bytes
        )?;
    }
    if let Some(e) = &s.load_effect {
        let went = if e.p99_rise_us >= 0.0 { "rose" } else { "fell" };
        let (rate, rise_pct) = (hz(e.rate_hz), (e.p99_ratio - 1.0) * 100.0);
        let [p99_before, p99_after] = [e.unloaded_p99_us, e.loaded_p99_us].map(ms_us);
        let [p50_before, p50_after] = [e.unloaded_p50_us, e.loaded_p50_us].map(ms_us);
        writeln!(
            out,
            "under load: {probe} p99 at {rate}/s {went} from {p99_before} ms to {p99_after} ms: \
             {:+.3} ms ({rise_pct:+.0}%); p50 {p50_before} -> {p50_after} ms",
            e.p99_rise_us / 1e3
        )?;
    }
    Ok(())
}

/// Where the sweep found the knee, beside what the baud rate alone says.
fn write_knee(out: &mut impl Write, s: &SweepSummary, probe: &str, baud: &str) -> io::Result<()> {
    let Some(k) = &s.knee else {
        return writeln!(
            out,
            "knee: none: no step lost under 1% with a p99 under twice the first step's (or under \
             30 ms over it){baud}"
        );
    };
    let above = match k.failed_above_hz {
        Some(f) => format!("; {}/s failed", hz(f)),
        None => "; every rate tried passed, so the link carries more: raise --sweep-max".into(),
    };
    let (rate, loss, p99) = (hz(k.rate_hz), k.loss_ratio * 100.0, ms_us(k.p99_us));
    writeln!(
        out,
        "knee: {rate} {probe}s/s ({:.0} B/s on the wire: {:.0} out, {:.0} in) at step {}, loss \
         {loss:.2}%, p99 {p99} ms{above}{baud}",
        k.bytes_per_s, k.tx_bytes_per_s, k.rx_bytes_per_s, k.step
    )
}

/// Whether the link queued before it dropped: the latency it added under
/// load, graded, and "bufferbloat" from grade C down.
fn write_queueing(out: &mut impl Write, q: &Queueing) -> io::Result<()> {
    let (grade, added) = (q.grade.as_str(), ms_us(q.added_us));
    let (at, worst) = (hz(q.worst_at_hz), ms_us(q.worst_p99_us));
    let reference = ms_us(q.reference_p99_us);
    if q.bufferbloat {
        return writeln!(
            out,
            "queueing: bufferbloat, grade {grade} (+{added} ms under load): at {at}/s the link lost \
             under 1% yet its p99 reached {worst} ms, over the first step's {reference} ms: it \
             queues before it drops"
        );
    }
    let then = match q.lost_at_hz {
        Some(rate) => format!(
            "; from {}/s it lost instead: the link drops before it queues",
            hz(rate)
        ),
        None => "; no step lost 1% or more".into(),
    };
    writeln!(
        out,
        "queueing: grade {grade} (+{added} ms under load), no bufferbloat: while it lost under 1%, \
         the p99 rose from the first step's {reference} ms to at most {worst} ms (at {at}/s){then}"
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::engine::sweep::verdict;

    fn summary() -> SweepSummary {
        let mut steps = vec![
            StepFigures::test(Phase::Ramp, 10.0, 0.0),
            StepFigures::test(Phase::Ramp, 20.0, 0.0),
            StepFigures::test(Phase::Ramp, 50.0, 0.3),
        ];
        for (i, s) in steps.iter_mut().enumerate() {
            s.index = i as u32 + 1;
            s.passed = Some(s.loss_ratio == 0.0);
        }
        SweepSummary {
            kind: "sweep",
            knee: verdict::knee(&steps),
            queueing: verdict::queueing(&steps),
            reference_p99_us: verdict::reference_p99(&steps),
            steps,
            load: vec![],
            load_effect: None,
            ending: SweepEnd::LossLimit,
        }
    }

    #[test]
    fn the_summary_names_the_knee_beside_the_baud_capacity() {
        let mut out = Vec::new();
        let wire = crate::engine::capacity::budget(57_600, crate::frame::Version::V2, 99, 1);
        write_summary(&mut out, &summary(), "PING", Some(&wire), 0).unwrap();
        let text = String::from_utf8(out).unwrap();
        let lines: Vec<&str> = text.lines().collect();
        let header = header();
        assert_eq!(lines[0], header);
        assert_eq!(lines.len(), 1 + 3 + 3, "{text}");
        assert!(lines[3].ends_with(" loss"), "{text}");
        assert!(
            lines[1].contains(" ramp ") && lines[1].ends_with(" ok"),
            "{text}"
        );
        assert!(
            text.contains("knee: 20 PINGs/s (940 B/s on the wire: 420 out, 520 in) at step 2")
                && text.contains("; 50/s failed; the baud rate alone says ~122/s (57600 baud)"),
            "{text}"
        );
        assert!(text.contains("drops before it queues"), "{text}");
        assert!(
            text.contains("queueing: grade A+ (+0.000 ms under load), no bufferbloat: "),
            "{text}"
        );
        // Rows line up under the header: every column ends where its
        // header does.
        for col in ["rate/s", "p99 ms", "rx B/s"] {
            let end = header.find(col).unwrap() + col.len();
            for row in &lines[1..4] {
                assert_ne!(row.as_bytes()[end - 1], b' ', "{col}: {row}");
                assert_eq!(row.as_bytes()[end], b' ', "{col}: {row}");
            }
        }
    }

    #[test]
    fn a_retry_is_named_in_its_row_and_a_bloated_queue_by_its_grade() {
        let mut s = StepFigures::test(Phase::Refine, 59.5, 0.0);
        (s.index, s.passed, s.retry) = (10, Some(false), true);
        let line = row(&s);
        assert!(line.starts_with("  10 retry         59.5 "), "{line}");
        assert!(line.ends_with("  p99"), "{line}");
        s.load = true;
        assert!(row(&s).contains(" retry+load "), "{}", row(&s));
        let mut summary = summary();
        let q = summary.queueing.as_mut().unwrap();
        (q.added_us, q.worst_p99_us) = (371_368.0, 383_368.0);
        q.grade = crate::engine::sweep::verdict::Grade::of(q.added_us);
        q.bufferbloat = q.grade.is_bufferbloat();
        let mut out = Vec::new();
        write_summary(&mut out, &summary, "TIMESYNC", None, 3).unwrap();
        let text = String::from_utf8(out).unwrap();
        assert!(
            text.contains("queueing: bufferbloat, grade D (+371.368 ms under load): at 20/s"),
            "{text}"
        );
        assert!(text.contains("knee: 20 TIMESYNCs/s ("), "{text}");
    }
}
