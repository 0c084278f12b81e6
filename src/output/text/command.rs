//! Text lines and summary of the command probe.

use std::io::{self, Write};

use super::format::{ms, ms_us, rate};
use super::histogram::write_histogram;
use super::signing::write_signing;
use super::TextReporter;
use crate::engine::probe::command::CommandEvent;
use crate::engine::stats::RttSummary;
use crate::engine::summary::CommandSummary;
use crate::engine::CommandSpec;
use crate::frame::codec;
use crate::output::StartInfo;

impl<W: Write> TextReporter<W> {
    pub(super) fn command_start(&mut self, info: &StartInfo, spec: &CommandSpec) -> io::Result<()> {
        writeln!(
            self.out,
            "MAVPING {} from {}: COMMAND_LONG {} to {} {}, re-sent every {} up to {} times",
            info.link,
            info.ours,
            codec::command_name(spec.command).to_uppercase(),
            spec.target,
            rate(info.interval),
            humantime::format_duration(spec.retry_interval),
            spec.retries
        )
    }

    pub(super) fn command_event(&mut self, event: &CommandEvent) -> io::Result<()> {
        match *event {
            // Re-sends are not news; the ACK line says how many it took.
            CommandEvent::Send { .. } => Ok(()),
            CommandEvent::Acked {
                n,
                from,
                result,
                attempts,
                time_to_ack,
                ..
            } => writeln!(
                self.out,
                "ack from {from}: cmd={n} {} attempts={attempts} time={} ms",
                codec::result_name(result),
                ms(time_to_ack)
            ),
            CommandEvent::Failed {
                n,
                target,
                attempts,
                ..
            } => writeln!(
                self.out,
                "no ack from {target}: cmd={n} after {attempts} attempts"
            ),
            CommandEvent::Skipped { target, .. } => writeln!(
                self.out,
                "skipped a command to {target}: the previous one is still unacknowledged"
            ),
            CommandEvent::LateAck { from, result, .. } => writeln!(
                self.out,
                "late ack from {from}: {} (the command had already failed)",
                codec::result_name(result)
            ),
            CommandEvent::DuplicateAck { from, result, .. } => writeln!(
                self.out,
                "ack from {from}: {} (DUP!)",
                codec::result_name(result)
            ),
        }
    }
}

fn write_time_to_ack(out: &mut impl Write, t: &RttSummary) -> io::Result<()> {
    writeln!(
        out,
        "  time to ack min/mean/max/stddev = {}/{}/{}/{} ms",
        ms_us(t.min_us),
        ms_us(t.mean_us),
        ms_us(t.max_us),
        ms_us(t.stddev_us)
    )?;
    writeln!(
        out,
        "  time to ack p50/p90/p99/p99.9   = {}/{}/{}/{} ms",
        ms_us(t.p50_us),
        ms_us(t.p90_us),
        ms_us(t.p99_us),
        ms_us(t.p999_us)
    )
}

pub(super) fn write_summary(out: &mut impl Write, s: &CommandSummary) -> io::Result<()> {
    let sent = s.commands();
    write!(
        out,
        "{sent} {} commands sent in {:.3} s",
        s.command_name.to_uppercase(),
        s.duration_s
    )?;
    if s.in_flight > 0 {
        write!(out, ", {} still in flight (not counted)", s.in_flight)?;
    }
    writeln!(out)?;
    for t in &s.targets {
        let who = match &t.identity {
            Some(i) => format!("{} ({}, {})", t.id, i.vehicle, i.autopilot_said()),
            None => t.id.to_string(),
        };
        writeln!(
            out,
            "{who}: {} commands, {} acknowledged, {} failed, {} skipped, {} late acks, {} duplicate acks",
            t.commands, t.acknowledged, t.failed, t.skipped, t.late_acks, t.duplicate_acks
        )?;
        let attempts: Vec<String> = t
            .attempts
            .iter()
            .enumerate()
            .filter(|(_, &count)| count > 0)
            .map(|(i, count)| format!("{}x{count}", i + 1))
            .collect();
        if !attempts.is_empty() {
            writeln!(out, "  attempts until ack: {}", attempts.join(", "))?;
        }
        if let Some(tta) = &t.time_to_ack {
            write_time_to_ack(out, tta)?;
            write_histogram(out, &t.histogram)?;
        }
        if !t.results.is_empty() {
            let results: Vec<String> = t
                .results
                .iter()
                .map(|r| format!("{} {}", r.name, r.count))
                .collect();
            writeln!(out, "  ack results: {}", results.join(", "))?;
        }
    }
    super::link_node::write_link_nodes(out, &s.link_node)?;
    if s.unmatched_acks > 0 {
        writeln!(
            out,
            "{} acks for commands we did not send",
            s.unmatched_acks
        )?;
    }
    write_signing(out, &s.signing)?;
    for hint in &s.hints {
        writeln!(out, "hint: {}", hint.text)?;
    }
    Ok(())
}
