//! Text lines and summary of the download probes (`--probe params`,
//! `mission`, `ftp`): a line per download as it ends, the downloads
//! added up, the round trip beside them.

use std::io::{self, Write};

use super::format::rate;
use super::summary::{write_answered, write_rtt, write_signing};
use super::TextReporter;
use crate::engine::probe::transfer::{
    AttemptFigures, Ending, TransferKind, TransferSpec, TransferSummary,
};
use crate::output::StartInfo;

/// What the download fetches, in words.
fn what(kind: &TransferKind) -> String {
    match kind {
        TransferKind::Params => "PARAMS".into(),
        TransferKind::Mission => "MISSION".into(),
        TransferKind::Ftp { path } => format!("FTP {path}"),
    }
}

fn secs(ms: f64) -> String {
    format!("{:.2} s", ms / 1e3)
}

/// A rate in units a second, bytes as kB.
fn per_s(value: f64, unit: &str) -> String {
    if unit == "bytes" {
        format!("{:.1} kB/s", value / 1e3)
    } else {
        format!("{value:.1} {unit}/s")
    }
}

impl<W: Write> TextReporter<W> {
    pub(super) fn transfer_start(
        &mut self,
        info: &StartInfo,
        spec: &TransferSpec,
    ) -> io::Result<()> {
        self.start_line(
            info,
            format_args!(
                "{} from {}, asked again after {} up to {} times; PING or TIMESYNC {} beside",
                what(&spec.kind),
                spec.target,
                humantime::format_duration(spec.timeout),
                spec.retries,
                rate(info.interval),
            ),
        )
    }

    pub(super) fn transfer_line(&mut self, a: &AttemptFigures) -> io::Result<()> {
        writeln!(self.out, "{}", attempt_line(a))
    }
}

/// One download in a line: how it ended, how long it took, what the
/// first pass missed and what asking again brought.
pub(super) fn attempt_line(a: &AttemptFigures) -> String {
    let p = &a.progress;
    let total = p.total.map_or_else(|| "?".into(), |t| t.to_string());
    let from = a
        .responder
        .map(|r| format!(" from {r}"))
        .unwrap_or_default();
    let mut line = match a.ending {
        Ending::Complete => format!(
            "download {}{from}: complete, {total} {} in {}",
            a.attempt,
            a.unit,
            secs(p.time_to_100_ms.unwrap_or(a.duration_ms))
        ),
        ending => format!(
            "download {}{from}: {}, {} of {total} {} in {}",
            a.attempt,
            ending_words(ending),
            p.received,
            a.unit,
            secs(a.duration_ms)
        ),
    };
    if let Some(t95) = p.time_to_95_ms.filter(|_| a.ending == Ending::Complete) {
        line += &format!(" (95 % at {})", secs(t95));
    }
    if let Some(rate) = p.per_s {
        line += &format!(", {}", per_s(rate, a.unit));
    }
    if let Some(wire) = p.wire_bytes_per_s.filter(|_| p.received > 0) {
        line += &format!(", {} on the wire", per_s(wire, "bytes"));
    }
    if let (Some(floor), Some(done)) = (a.wire_floor_ms, p.time_to_100_ms) {
        line += &format!(
            " (the wire's floor for its bytes {}, {:.0} %)",
            secs(floor),
            floor * 100.0 / done
        );
    }
    if let Some(missing) = a.missing_first_pass {
        let c = &a.counts;
        line += &format!(
            "; first pass {} ({missing} missing), {} re-requests, {} answered",
            c.first_pass, c.re_requests, c.re_requests_answered
        );
    }
    if p.longest_stall_ms >= 1_000.0 {
        line += &format!(
            "; longest stall {} at {}",
            secs(p.longest_stall_ms),
            p.stalled_at
        );
    }
    if let Some(reason) = &a.reason {
        line += &format!(": {reason}");
    }
    line
}

fn ending_words(e: Ending) -> &'static str {
    match e {
        Ending::Complete => "complete",
        Ending::NoAnswer => "no answer",
        Ending::Stalled => "stalled",
        Ending::Refused => "refused",
        Ending::Cut => "cut short",
    }
}

pub(super) fn write_summary(out: &mut impl Write, s: &TransferSummary) -> io::Result<()> {
    writeln!(
        out,
        "{} downloads ({}), {} complete, {} failed, {:.1} s",
        s.attempts,
        match &s.plan.kind {
            TransferKind::Ftp { path } => format!("ftp {path}"),
            kind => what(kind).to_lowercase(),
        },
        s.complete,
        s.failed(),
        s.duration_s
    )?;
    if let Some(t) = &s.time_to_complete {
        writeln!(
            out,
            "time to complete min/p50/p90/max = {:.3}/{:.3}/{:.3}/{:.3} s",
            t.min_ms / 1e3,
            t.p50_ms / 1e3,
            t.p90_ms / 1e3,
            t.max_ms / 1e3
        )?;
    }
    writeln!(
        out,
        "{} requests; the first passes missed {} in all, {} re-requests, {} given up",
        s.requests, s.missing_first_pass, s.re_requests, s.given_up
    )?;
    if let Some(first) = &s.first_failed {
        writeln!(out, "first failed: {}", attempt_line(first))?;
    }
    if let Some(last) = &s.last {
        writeln!(out, "last: {}", attempt_line(last))?;
    }
    match &s.latency {
        Some(l) => {
            let c = &l.counts;
            writeln!(
                out,
                "round trips beside, {}: {} sent, {} received, {} lost",
                l.responder, c.sent, c.received, c.lost
            )?;
            if let Some(rtt) = &l.rtt {
                write_rtt(out, "rtt", rtt, true)?;
            }
        }
        None => writeln!(out, "round trips beside: no answer")?,
    }
    super::link_node::write_link_nodes(out, &s.link_node)?;
    write_signing(out, &s.signing)?;
    write_answered(out, &s.answered)?;
    for hint in &s.hints {
        writeln!(out, "hint: {}", hint.text)?;
    }
    Ok(())
}
