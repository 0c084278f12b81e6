//! Text lines and summary of the echo probes (PING, TIMESYNC).

use std::io::{self, Write};

use super::format::{counted, if_any, ms, ms_each, ms_us, per_second, rate, who};
use super::summary::{
    write_ages, write_answered, write_failures, write_histogram, write_rtt, write_sent,
    write_signing,
};
use super::TextReporter;
use crate::engine::age::{SplitBy, SplitSummary};
use crate::engine::capacity::WireBudget;
use crate::engine::clock_offset::MIN_DRIFT_SPAN_S;
use crate::engine::hint::HintCode;
use crate::engine::matcher::{Counts, MatchEvent};
use crate::engine::summary::{
    Direction, EchoInterim, EchoSummary, ProbeName, ResponderSummary, ScheduleSummary,
};
use crate::engine::Nanos;
use crate::output::prometheus::Outcome;
use crate::output::StartInfo;
use crate::verdict::Verdict;

/// Requests per second above which per-reply lines are summarised.
pub(super) const MAX_LINE_RATE: f64 = 100.0;
const PROGRESS_EVERY_NS: Nanos = 1_000_000_000;

#[derive(Default)]
pub(super) struct Progress {
    window_start: Nanos,
    /// The window's events, counted as the exporter counts them.
    counts: Counts,
    last_rtt: Option<Nanos>,
}

impl<W: Write> TextReporter<W> {
    pub(super) fn echo_start(&mut self, info: &StartInfo) -> io::Result<()> {
        let summarised = !self.every_reply && 1.0 / info.interval.as_secs_f64() > MAX_LINE_RATE;
        let mut lines = "";
        if summarised {
            self.progress = Some(Progress::default());
            lines = " (one status line per second; --every-reply for all)";
        }
        // Auto sends PING to all, TIMESYNC only to some: say both.
        let (probe, also) = match info.probe {
            ProbeName::Auto => ("PING".to_string(), " (TIMESYNC where PING is not answered)"),
            p => (p.as_str().to_uppercase(), ""),
        };
        let rate = rate(info.interval);
        let timeout = humantime::format_duration(info.timeout);
        self.start_line(
            info,
            format_args!("{probe} {rate}{also}, timeout {timeout}{lines}"),
        )
    }

    /// A reply, loss, late, duplicate or stale reply: a line each, or a
    /// count in the status line of a fast run.
    pub(super) fn match_line(&mut self, e: &MatchEvent) -> io::Result<()> {
        if self.progress.is_some() {
            return self.tally(e);
        }
        self.stamp(e.at())?;
        let (responder, seq) = (e.responder(), e.seq().unwrap_or_default());
        // Replies in time, late and again share a line, told apart by its
        // head and tail.
        let (head, tail) = match *e {
            MatchEvent::Reply { out_of_order, .. } => {
                let order = if out_of_order { " (out of order)" } else { "" };
                ("", format!("{order}{}", self.radio_note(e.at())))
            }
            MatchEvent::Late { .. } => ("late ", " (after the timeout)".into()),
            MatchEvent::Duplicate { .. } => ("", " (DUP!)".into()),
            MatchEvent::Lost { .. } => {
                let timeout = humantime::format_duration(self.timeout);
                return writeln!(
                    self.out,
                    "no reply from {responder}: seq={seq} (timeout {timeout})"
                );
            }
            MatchEvent::Stale { .. } => {
                return writeln!(
                    self.out,
                    "stale reply from {responder}: matches no request we hold"
                );
            }
        };
        let time = ms(e.rtt().unwrap_or_default());
        writeln!(
            self.out,
            "{head}reply from {responder}: seq={seq} time={time} ms{tail}"
        )
    }

    /// `[12.0 s] 1/1: 120 sent, 118 received, 2 lost (1.67%), 0 late, 0
    /// duplicate; rtt p50/p99 = 21.304/25.611 ms`, a line per responder.
    pub(super) fn write_interim(&mut self, figures: &EchoInterim) -> io::Result<()> {
        if figures.responders.is_empty() {
            self.interim_head(figures.at)?;
            let requests = figures.requests;
            return writeln!(self.out, "{requests} requests sent, no replies yet");
        }
        for r in &figures.responders {
            self.interim_head(figures.at)?;
            let rtt = r.rtt.as_ref().map_or_else(String::new, |t| {
                format!("; rtt p50/p99 = {} ms", ms_each(&[t.p50_us, t.p99_us]))
            });
            writeln!(self.out, "{}: {}{rtt}", r.id, counts(r))?;
        }
        self.out.flush()
    }

    /// Counts a match event into the status line; prints it once a second.
    fn tally(&mut self, e: &MatchEvent) -> io::Result<()> {
        let Some(p) = self.progress.as_mut() else {
            return Ok(());
        };
        if let Some((_, outcome)) = Outcome::of_match(e) {
            outcome.count(&mut p.counts);
        }
        if let MatchEvent::Reply { rtt, .. } = *e {
            p.last_rtt = Some(rtt);
        }
        let at = e.at();
        let window = at.saturating_sub(p.window_start);
        if window < PROGRESS_EVERY_NS {
            return Ok(());
        }
        let (c, window_s) = (&p.counts, window as f64 / 1e9);
        let last_rtt = p.last_rtt.map_or("-".into(), ms);
        let line = format!(
            "{} replies, {} lost, {} late, {} duplicate in the last {window_s:.1} s; last rtt \
             {last_rtt} ms",
            c.received, c.lost, c.late, c.duplicate
        );
        *p = Progress {
            window_start: at,
            ..Progress::default()
        };
        let note = self.radio_note(at);
        self.interim_head(at)?;
        writeln!(self.out, "{line}{note}")
    }
}

/// Signed seconds with µs resolution, exact even for clocks counting from
/// 1970 (an f64 would lose the µs there).
fn offset(ns: i128) -> String {
    let sign = if ns < 0 { '-' } else { '+' };
    let us = (ns.unsigned_abs() + 500) / 1_000;
    format!("{sign}{}.{:06} s", us / 1_000_000, us % 1_000_000)
}

fn percent(ratio: f64) -> String {
    let p = ratio * 100.0;
    let places = if p > 0.0 && p < 10.0 { 2 } else { 1 };
    format!("{p:.places$}%")
}

/// `120 sent, 118 received, 2 lost (1.67%), 0 late, 0 duplicate`: a
/// responder's counts, in its interim line and its summary alike.
fn counts(r: &ResponderSummary) -> String {
    let (c, loss) = (&r.counts, percent(r.loss_ratio));
    format!(
        "{} sent, {} received, {} lost ({loss}), {} late, {} duplicate",
        c.sent, c.received, c.lost, c.late, c.duplicate
    )
}

fn write_responder(out: &mut impl Write, r: &ResponderSummary) -> io::Result<()> {
    let c = &r.counts;
    let who = who(r.id, r.identity.as_ref());
    let via = r.probe.map_or_else(String::new, |p| {
        format!(" via {}", p.as_str().to_uppercase())
    });
    let stale = if_any(c.stale, |n| format!(", {n} stale"));
    let in_flight = if_any(c.in_flight, |n| format!(", {n} in flight"));
    write!(
        out,
        "{who}{via}: {}, {} out of order{stale}{in_flight}",
        counts(r),
        c.out_of_order
    )?;
    // Said, so that the requests add up: not charged + sent + in flight.
    if c.not_charged > 0 {
        let (earlier, why) = if c.sent + c.in_flight == 0 {
            ("", "it answered none")
        } else {
            ("earlier ", "sent before its first answer")
        };
        let requests = counted(c.not_charged, &format!("{earlier}request"));
        write!(out, "; {requests} not charged ({why})")?;
    }
    writeln!(out)?;
    if let Some(d) = &r.direction {
        write_direction(out, d)?;
    }
    let Some(rtt) = &r.rtt else {
        return Ok(());
    };
    write_rtt(out, "rtt", rtt, true)?;
    if let Some(clock) = &r.clock {
        let drift = match (clock.drift_ppm, clock.drift_stderr_ppm) {
            (Some(d), Some(e)) => format!("{d:+.2} ± {e:.2} ppm"),
            _ => format!("not measured (needs {MIN_DRIFT_SPAN_S} s of exchanges)"),
        };
        let bounds = match clock.bounds_ns {
            Some((lower, upper)) => format!("between {} and {}", offset(lower), offset(upper)),
            None => "its causal bounds do not intersect".to_string(),
        };
        let (offset, spread) = (offset(clock.offset_ns), ms_us(clock.spread_ns / 1e3));
        writeln!(
            out,
            "  clock offset {offset} ({bounds}), spread {spread} ms, drift {drift} ({} samples)",
            clock.samples
        )?;
    }
    if let Some(split) = &r.split {
        write_split(out, split)?;
    }
    write_histogram(out, &r.histogram)
}

/// Which way the round trip queued, by the responder's clock in its
/// replies or its telemetry's age: each direction above its quickest.
fn write_split(out: &mut impl Write, s: &SplitSummary) -> io::Result<()> {
    let round_trip = s.uplink_max_ms.max(0.0) + s.downlink_max_ms.max(0.0);
    let by = match s.by {
        SplitBy::ReplyClock => "its clock",
        SplitBy::TelemetryAge => "its telemetry's age",
    };
    writeln!(
        out,
        "  queues by {by}: round trip up to +{:.1} ms above its quickest: uplink p99 +{:.1} \
         ms (max +{:.1}), downlink p99 +{:.1} ms (max +{:.1}) over {} exchanges",
        round_trip,
        s.uplink_p99_ms,
        s.uplink_max_ms,
        s.downlink_p99_ms,
        s.downlink_max_ms,
        s.exchanges
    )
}

/// Which way the responder's losses were.
fn write_direction(out: &mut impl Write, d: &Direction) -> io::Result<()> {
    let down = percent(d.downlink_loss);
    let down = format!(
        "down {down} ({} of {} of its frames, by its sequence)",
        d.downlink_lost, d.downlink_frames
    );
    let round_trip = percent(d.round_trip_loss);
    match (d.uplink_loss, d.uplink_stderr) {
        _ if !d.consistent => writeln!(
            out,
            "  direction: {down} is more than the round trip's {round_trip}: its sequence does \
             not number just what it sends us on this link (a router re-sequencing or merging \
             links?), so no split"
        ),
        (Some(up), Some(e)) if d.late_share > 0.0 => writeln!(
            out,
            "  direction: round trip {round_trip} lost, of which {} came back late (a queue, not \
             loss): {} = up ~{} ± {} and {down}",
            percent(d.late_share),
            percent(d.round_trip_loss - d.late_share),
            percent(up),
            percent(e)
        ),
        (Some(up), Some(e)) => writeln!(
            out,
            "  direction: round trip {round_trip} lost = up ~{} ± {} and {down}",
            percent(up),
            percent(e)
        ),
        _ => writeln!(
            out,
            "  direction: {down}: nothing of its came back to split"
        ),
    }
}

pub(super) fn write_summary(
    out: &mut impl Write,
    s: &EchoSummary,
    verdict: &Verdict,
    steps_shown: usize,
) -> io::Result<()> {
    write_requests(out, s)?;
    for r in &s.responders {
        write_responder(out, r)?;
    }
    for r in &s.radios {
        super::heard::write_radio(out, r)?;
    }
    super::link_node::write_link_nodes(out, &s.link_node)?;
    if let Some(sweep) = &s.sweep {
        let probe = s.probe.as_str().to_uppercase();
        super::sweep::write_summary(out, sweep, &probe, s.wire.as_ref(), steps_shown)?;
    }
    if let Some(w) = &s.wire {
        write_wire(out, s, w)?;
    }
    write_link_faults(out, s)?;
    write_signing(out, &s.signing)?;
    write_answered(out, &s.answered)?;
    write_ages(out, &s.age)?;
    if let Some(p) = &s.schedule {
        write_schedule(out, s, p)?;
    }
    for hint in s.hints.iter().filter(|h| h.code != HintCode::NoPeerHeard) {
        writeln!(out, "hint: {}", hint.text)?;
    }
    write_failures(out, verdict)
}

/// `30 requests sent in 0.640 s`, and when nothing answered, why.
fn write_requests(out: &mut impl Write, s: &EchoSummary) -> io::Result<()> {
    let requests = format!("{} requests", s.requests);
    write_sent(out, &requests, s.duration_s, s.in_flight)?;
    // A listening link that gave up says so in its own words (the hint);
    // "no replies" would hide that nothing was ever heard.
    match s.hints.iter().find(|h| h.code == HintCode::NoPeerHeard) {
        Some(hint) => writeln!(out, "{}", hint.text),
        None if s.responders.is_empty() => writeln!(out, "no replies"),
        None => Ok(()),
    }
}

/// `wire: 57600 baud carries ...`: what the baud rate allows.
fn write_wire(out: &mut impl Write, s: &EchoSummary, w: &WireBudget) -> io::Result<()> {
    let unproven = w
        .ignorer
        .map(|device| format!(" (unproven on {device})"))
        .unwrap_or_default();
    let (carries, floor) = (w.max_rate_hz.floor(), ms_us(w.floor_us));
    write!(
        out,
        "wire{unproven}: {} baud carries ~{carries:.0} {}s/s; serialisation floor {floor} ms per \
         round trip (request {} B + reply {} B)",
        w.baud, w.message, w.request_bytes, w.reply_bytes
    )?;
    // The rest of the RTT is the radio's and the autopilot's.
    if let Some(p50) = s.smallest_p50_us() {
        let beyond = ms_us((p50 - w.floor_us).max(0.0));
        write!(out, ", {beyond} ms of the rtt p50 is beyond the wire")?;
    }
    writeln!(out)
}

/// What the link did besides carrying replies: junk, replies from the
/// wrong peer, time down.
fn write_link_faults(out: &mut impl Write, s: &EchoSummary) -> io::Result<()> {
    let f = &s.frames;
    if f.bad_crc + f.damaged + f.skipped_bytes + f.unknown_id + f.truncated + s.foreign_replies > 0
    {
        writeln!(
            out,
            "link: {} bad CRC, {} damaged frames, {} bytes skipped, {} unknown messages, {} \
             truncated, {} replies to others",
            f.bad_crc, f.damaged, f.skipped_bytes, f.unknown_id, f.truncated, s.foreign_replies
        )?;
    }
    if s.wrong_path_replies > 0 {
        writeln!(
            out,
            "link: {} replies rejected: a responder's ids from another peer than the one it answered from",
            s.wrong_path_replies
        )?;
    }
    if s.downtime_s > 0.0 {
        writeln!(
            out,
            "link down {:.3} s in total while reconnecting (requests sent meanwhile count as lost)",
            s.downtime_s
        )?;
    }
    Ok(())
}

/// `schedule: 50/s achieved of 50/s, send lateness ...`.
fn write_schedule(out: &mut impl Write, s: &EchoSummary, p: &ScheduleSummary) -> io::Result<()> {
    let achieved = per_second(p.achieved_rate_hz);
    let requested = per_second(p.requested_rate_hz);
    let rate = match p.not_sent {
        0 => format!("{achieved}/s achieved of {requested}/s"),
        n => format!(
            "the link took {achieved}/s of {requested}/s ({n} requests not sent: it is not reading)"
        ),
    };
    let lateness = ms_each(&[p.lateness_p50_us, p.lateness_p99_us, p.lateness_max_us]);
    writeln!(
        out,
        "schedule: {rate}, send lateness p50/p99/max = {lateness} ms; {}",
        s.rx_clock
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::engine::observe::Observer;
    use crate::engine::observe::RadioHeard;
    use crate::engine::radio::{self, RadioKind, RadioReport};
    use crate::frame::SysComp;
    use crate::output::runs::kind;
    use crate::output::Event;

    fn reply(seq: u32, at: Nanos) -> Event<'static> {
        kind(MatchEvent::Reply {
            responder: SysComp::new(1, 1),
            seq,
            rtt: 1_000_000,
            sent_at: at - 1_000_000,
            at,
            out_of_order: false,
            first_from_responder: seq == 0,
        })
    }

    #[test]
    fn reply_lines_carry_the_radio_at_most_once_a_second() {
        let mut t = TextReporter::new(Vec::new(), false);
        let status = RadioReport {
            rssi: 200,
            remrssi: radio::UNKNOWN,
            txbuf: 90,
            noise: 40,
            remnoise: 60,
            rxerrors: 0,
            fixed: 0,
        };
        t.event(&reply(0, 10_000_000)).unwrap();
        let sik = radio::Judgement {
            kind: RadioKind::Sik,
            radio_type: radio::RadioType::Auto,
            evidence: vec!["compid 68 and no HEARTBEAT from 51/68".into()],
        };
        t.event(&Event::Radio(RadioHeard {
            id: SysComp::new(51, 68),
            at: 20_000_000,
            report: status,
            judgement: &sik,
            first: true,
            kind_changed: false,
        }))
        .unwrap();
        for (seq, at) in [(1, 30_000_000), (2, 500_000_000), (3, 1_030_000_000)] {
            t.event(&reply(seq, at)).unwrap();
        }
        let out = String::from_utf8(t.into_inner()).unwrap();
        let notes: Vec<&str> = out.lines().filter(|l| l.contains("[radio")).collect();
        assert_eq!(notes.len(), 2, "{out}");
        assert!(
            notes[0].contains("seq=1 ")
                && notes[0].ends_with("[radio 51/68 rssi=200 remrssi=? txbuf=90%]"),
            "{out}"
        );
        assert!(notes[1].contains("seq=3 "), "{out}");
    }

    /// `-D` stamps the lines written, and only them: events with no line
    /// (progress, clock estimates, sources) once left a stray stamp each.
    #[test]
    fn timestamps_go_on_written_lines_only() {
        let wall = crate::output::WallClock::starting(true);
        let mut t = TextReporter::new(Vec::new(), false).timestamps(Some(wall));
        t.event(&Event::Progress {
            at: 1_000_000_000,
            requests: 3,
        })
        .unwrap();
        t.event(&kind(MatchEvent::Lost {
            responder: SysComp::new(1, 1),
            seq: 4,
            sent_at: 200_000_000,
            at: 2_200_000_000,
        }))
        .unwrap();
        let out = String::from_utf8(t.into_inner()).unwrap();
        assert_eq!(out, "[2.200000] no reply from 1/1: seq=4 (timeout 0s)\n");
    }
}
