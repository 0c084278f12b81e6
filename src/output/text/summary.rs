//! The lines several kinds' summaries share: what was sent, the RTT
//! figures and their histogram, the signing gate, the requests answered,
//! the failed thresholds.

use std::io::{self, Write};

use super::format::{counted, if_any, ms_each, ms_us};
use crate::engine::age::SourceAge;
use crate::engine::answers::AnswerSummary;
use crate::engine::stats::{Bucket, RttSummary};
use crate::frame::signing::SigningSummary;
use crate::frame::StampMeaning;
use crate::verdict::{Check, Verdict};

/// `30 requests sent in 0.640 s`, and how many were still in flight.
pub(super) fn write_sent(
    out: &mut impl Write,
    what: &str,
    duration_s: f64,
    in_flight: u64,
) -> io::Result<()> {
    let still = if_any(in_flight, |n| {
        format!(", {n} still in flight (not counted)")
    });
    writeln!(out, "{what} sent in {duration_s:.3} s{still}")
}

/// `  rtt min/mean/max/stddev = …` and the percentiles under it (the
/// echo probes' with the jitter), for an RTT or a time to ack alike.
pub(super) fn write_rtt(
    out: &mut impl Write,
    what: &str,
    t: &RttSummary,
    jitter: bool,
) -> io::Result<()> {
    let spread = ms_each(&[t.min_us, t.mean_us, t.max_us, t.stddev_us]);
    let percentiles = ms_each(&[t.p50_us, t.p90_us, t.p99_us, t.p999_us]);
    writeln!(out, "  {what} min/mean/max/stddev = {spread} ms")?;
    write!(out, "  {what} p50/p90/p99/p99.9   = {percentiles} ms")?;
    if jitter {
        write!(out, ", jitter {} ms", ms_us(t.jitter_us))?;
    }
    writeln!(out)
}

/// An RTT histogram: a bar per bucket, the longest 40 wide.
pub(super) fn write_histogram(out: &mut impl Write, histogram: &[Bucket]) -> io::Result<()> {
    let most = histogram.iter().map(|b| b.count).max().unwrap_or(0).max(1);
    for b in histogram {
        const WIDTH: u64 = 40;
        let bar = "#".repeat((b.count * WIDTH).div_ceil(most) as usize);
        let low = ms_us(b.low_us);
        writeln!(out, "  {low:>9} ms |{bar:<40}| {}", b.count)?;
    }
    Ok(())
}

/// One line: what the signing gate let through and what it refused
/// (refused frames were never measured); without a key, only when signed
/// frames came (their signatures could not be checked).
pub(super) fn write_signing(out: &mut impl Write, s: &SigningSummary) -> io::Result<()> {
    match s.link_id {
        Some(link_id) => {
            let gate = if s.required {
                "signatures required"
            } else {
                "unsigned accepted"
            };
            writeln!(out, "signing (link id {link_id}, {gate}): {}", s.counts)
        }
        None if s.counts.signed_unchecked > 0 => writeln!(
            out,
            "signing (no key): {} signed frames accepted unchecked, {} unsigned",
            s.counts.signed_unchecked, s.counts.unsigned
        ),
        None => Ok(()),
    }
}

/// One line, when the vehicle asked us anything: the requests we
/// answered as a ground station does.
pub(super) fn write_answered(out: &mut impl Write, a: &AnswerSummary) -> io::Result<()> {
    if a.is_none() {
        return Ok(());
    }
    let (timesync, ping) = (a.counts.timesync_requests, a.counts.ping_requests);
    let flood = if_any(a.unanswered, |n| {
        format!(", {n} of them not answered (more than 64 at once)")
    });
    writeln!(
        out,
        "answered the vehicle's requests: {timesync} TIMESYNC, {ping} PING{flood}"
    )
}

/// Each source's age above its baseline, by its headline clock: how much
/// later than its quickest its frames arrived.
pub(super) fn write_ages(out: &mut impl Write, ages: &[SourceAge]) -> io::Result<()> {
    if ages.is_empty() {
        return Ok(());
    }
    writeln!(
        out,
        "age above baseline, from the frames' own clock stamps:"
    )?;
    for a in ages {
        let h = &a.headline;
        let when = match h.meaning {
            StampMeaning::Sent => "at send",
            StampMeaning::Sampled => "sample times",
        };
        let drift = h
            .drift_ppm
            .map_or(String::new(), |d| format!("; clock drift {d:+.1} ppm"));
        let restarts = if_any(u64::from(h.restarts), |n| {
            format!("; {}", counted(n, "restart"))
        });
        writeln!(
            out,
            "  {} ({} {when}): p50 {:.1} ms, p90 {:.1} ms, p99 {:.1} ms, max {:.1} ms over {} \
             frames{drift}{restarts}",
            a.source,
            h.clock.words(),
            h.p50_ms,
            h.p90_ms,
            h.p99_ms,
            h.max_ms,
            h.samples
        )?;
        if let Some(abs) = &a.absolute {
            writeln!(
                out,
                "    one way, by its TIMESYNC clock offset: baseline {:.1} ms (between {:.1} and \
                 {:.1} ms), p50 {:.1} ms, p99 {:.1} ms, max {:.1} ms (each as uncertain as the \
                 baseline)",
                abs.baseline_ms,
                abs.baseline_lower_ms,
                abs.baseline_upper_ms,
                abs.p50_ms,
                abs.p99_ms,
                abs.max_ms
            )?;
        }
    }
    Ok(())
}

/// The thresholds that failed; "no reply at all" is already plain above.
pub(super) fn write_failures(out: &mut impl Write, verdict: &Verdict) -> io::Result<()> {
    for f in verdict.failures.iter().filter(|f| f.check != Check::Reply) {
        writeln!(out, "FAILED {}: {}", f.check, f.message)?;
    }
    Ok(())
}
