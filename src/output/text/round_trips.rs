//! The round trips recovered from a telemetry log, as text: a line per
//! requester → responder with its counts and RTT figures, the stamps'
//! resolution and what the figure includes.

use std::io::{self, Write};

use super::format::ms_each;
use crate::engine::probe::passive::round_trips::{PairSummary, RequesterSummary, RoundTripSummary};
use crate::frame::SysComp;
use crate::transport::tlog::LogFacts;

/// Nothing when the log held no exchange.
pub(super) fn write_round_trips(
    out: &mut impl Write,
    rt: &RoundTripSummary,
    log: Option<&LogFacts>,
) -> io::Result<()> {
    if rt.pairs.is_empty() && rt.requesters.is_empty() {
        return Ok(());
    }
    let resolution = match log {
        Some(l) if l.stamps.whole_ms => "whole milliseconds, as QGroundControl writes them",
        _ => "microseconds",
    };
    writeln!(
        out,
        "round trips recovered from the log's stamps ({resolution}; unanswered after {}):",
        humantime::format_duration(std::time::Duration::from_secs_f64(rt.timeout_s))
    )?;
    for p in &rt.pairs {
        write_pair(out, p)?;
    }
    for r in &rt.requesters {
        write_requests(out, r)?;
    }
    if rt.untracked > 0 {
        writeln!(
            out,
            "  and {} requests or replies beyond the tables' caps, not matched",
            rt.untracked
        )?;
    }
    writeln!(
        out,
        "  (a frame the ground station sent is stamped when it wrote it, one it received when \
         it read it: the RTT is the link both ways and the responder's time)"
    )
}

/// `timesync 255/190 -> 1/1: 98 matched, 2 unanswered; rtt n=98
/// min/p50/p90/p99/max = ... ms`.
fn write_pair(out: &mut impl Write, p: &PairSummary) -> io::Result<()> {
    let c = &p.counts;
    let mut parts = vec![format!("{} matched", c.matched)];
    parts.extend(any_of(&[(
        c.after_retransmission,
        "of them after a retransmission (measured from the last attempt)",
    )]));
    parts.push(format!("{} unanswered", c.unanswered));
    parts.extend(any_of(&[
        (c.late, "late"),
        (c.duplicate, "duplicate"),
        (c.no_request, "with no request in the log"),
    ]));
    let rtt = p.rtt.map_or_else(String::new, |r| {
        let figures = ms_each(&[r.min_us, r.p50_us, r.p90_us, r.p99_us, r.max_us]);
        format!("; rtt n={} min/p50/p90/p99/max = {figures} ms", c.matched)
    });
    let responder = named(p.responder, "any (none heard answering)");
    let requester = named(p.requester, "(no requester named)");
    let (kind, parts) = (p.kind.as_str(), parts.join(", "));
    writeln!(out, "  {kind} {requester} -> {responder}: {parts}{rtt}")
}

/// `3 late`: each count with what it counts, where there are any.
fn any_of(counts: &[(u64, &str)]) -> Vec<String> {
    let any = counts.iter().filter(|(n, _)| *n > 0);
    any.map(|(n, what)| format!("{n} {what}")).collect()
}

/// The ids, or `unnamed` for 0/0: the log named none.
fn named(id: SysComp, unnamed: &str) -> String {
    if id == SysComp::new(0, 0) {
        unnamed.into()
    } else {
        id.to_string()
    }
}

/// `requests: timesync from 255/190: 100 (1 logged again)`.
fn write_requests(out: &mut impl Write, r: &RequesterSummary) -> io::Result<()> {
    let (c, kind) = (&r.counts, r.kind.as_str());
    let repeats = if kind == "command" {
        "retransmissions"
    } else {
        "logged again"
    };
    let extra = any_of(&[
        (c.repeats, repeats),
        (c.evicted, "pushed out of the table in flight"),
        (c.in_flight_at_end, "in flight when the log ended"),
    ]);
    let extra = if extra.is_empty() {
        String::new()
    } else {
        format!(" ({})", extra.join(", "))
    };
    writeln!(
        out,
        "  requests: {kind} from {}: {}{extra}",
        r.requester, c.requests
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::engine::probe::passive::round_trips::RoundTrips;
    use crate::frame::{Frame, Msg, SysComp, Version};

    const MS: u64 = 1_000_000;

    fn frame(sysid: u8, msg: Msg) -> Frame {
        Frame {
            version: Version::V2,
            source: SysComp::new(sysid, 1),
            packet_seq: 0,
            msgid: 0,
            signed: false,
            len: 0,
            crc: 0,
            msg,
            stamps: crate::frame::Stamps::default(),
        }
    }

    fn timesync(tc1: i64, ts1: i64) -> Msg {
        Msg::Timesync {
            tc1,
            ts1,
            target_system: 0,
            target_component: 0,
        }
    }

    #[test]
    fn a_line_per_pair_and_per_requester_and_nothing_without_exchanges() {
        let mut rt = RoundTrips::new(2_000 * MS);
        let mut out = Vec::new();
        write_round_trips(&mut out, &rt.summary(0), None).unwrap();
        assert!(out.is_empty());
        // 255/1 syncs with 1/1: 12 ms, then nothing; a reply to a request
        // before the log; 3/1 pings anyone and nobody answers.
        rt.on_frame(&frame(255, timesync(0, 10)), 0);
        rt.on_frame(&frame(1, timesync(7, 10)), 12 * MS);
        rt.on_frame(&frame(255, timesync(0, 20)), 1_000 * MS);
        rt.on_frame(&frame(1, timesync(7, 5)), 1_100 * MS);
        let ping = Msg::Ping {
            time_usec: 1,
            seq: 1,
            target_system: 0,
            target_component: 0,
        };
        rt.on_frame(&frame(3, ping), 1_200 * MS);
        write_round_trips(&mut out, &rt.summary(9_000 * MS), None).unwrap();
        assert_eq!(
            String::from_utf8(out).unwrap(),
            "round trips recovered from the log's stamps (microseconds; unanswered after 2s):\n\
             \x20 timesync (no requester named) -> 1/1: 0 matched, 0 unanswered, 1 with no request in the log\n\
             \x20 timesync 255/1 -> 1/1: 1 matched, 1 unanswered; rtt n=1 min/p50/p90/p99/max = 12.000/12.000/12.000/12.000/12.000 ms\n\
             \x20 ping 3/1 -> any (none heard answering): 0 matched, 1 unanswered\n\
             \x20 requests: timesync from 255/1: 2\n\
             \x20 requests: ping from 3/1: 1\n\
             \x20 (a frame the ground station sent is stamped when it wrote it, one it received when \
             it read it: the RTT is the link both ways and the responder's time)\n"
        );
    }
}
