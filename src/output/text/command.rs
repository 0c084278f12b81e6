//! Text lines and summary of the command probe.

use std::io::{self, Write};

use super::format::{ms, rate, who};
use super::summary::{write_answered, write_histogram, write_rtt, write_sent, write_signing};
use super::TextReporter;
use crate::engine::probe::command::CommandEvent;
use crate::engine::summary::CommandSummary;
use crate::engine::CommandSpec;
use crate::frame::codec;
use crate::output::StartInfo;

impl<W: Write> TextReporter<W> {
    pub(super) fn command_start(&mut self, info: &StartInfo, spec: &CommandSpec) -> io::Result<()> {
        self.start_line(
            info,
            format_args!(
                "COMMAND_LONG {} to {} {}, re-sent every {} up to {} times",
                codec::command_name(spec.command).to_uppercase(),
                spec.target,
                rate(info.interval),
                humantime::format_duration(spec.retry_interval),
                spec.retries
            ),
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

pub(super) fn write_summary(out: &mut impl Write, s: &CommandSummary) -> io::Result<()> {
    let name = s.command_name.to_uppercase();
    let sent = format!("{} {name} commands", s.commands());
    write_sent(out, &sent, s.duration_s, s.in_flight)?;
    for t in &s.targets {
        let who = who(t.id, t.identity.as_ref());
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
            write_rtt(out, "time to ack", tta, false)?;
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
    write_answered(out, &s.answered)?;
    for hint in &s.hints {
        writeln!(out, "hint: {}", hint.text)?;
    }
    Ok(())
}
