//! `--passive` as text: the start line, the interim lines (`-Q`,
//! SIGQUIT), and the summary as a table per source with the link's
//! totals, pymavlink's figure beside ours, each source's busiest messages
//! and its silences.

use std::io::{self, Write};

use super::format::{identity, if_any, per_second, percent_or_dash, whole_or};
use super::summary::write_failures;
use super::TextReporter;
use crate::engine::observe::StartInfo;
use crate::engine::probe::passive::PassivePlan;
use crate::engine::summary::passive::{
    LinkTotals, MsgCount, PassiveSummary, PerLink, Silence, SourceSummary,
};
use crate::engine::summary::PassiveInterim;
use crate::frame::codec::message_name;
use crate::transport::tlog::LogFacts;
use crate::verdict::Verdict;

/// Message ids named per source under the table; the rest are counted.
const TOP_MSG_IDS: usize = 4;

impl<W: Write> TextReporter<W> {
    pub(super) fn passive_start(&mut self, info: &StartInfo, plan: &PassivePlan) -> io::Result<()> {
        let sent = if plan.log {
            "a telemetry log, read on its own clock (--passive implied); nothing sent"
        } else if plan.heartbeat {
            "our HEARTBEAT at 1 Hz (--no-heartbeat for none)"
        } else {
            "nothing sent (--no-heartbeat)"
        };
        self.start_line(info, format_args!("PASSIVE, no probes; {sent}"))
    }

    /// `[12.0 s] 1/1: 600 received, 3 lost (0.50%), 1 duplicate, 2
    /// reordered, 0 silences, 50.0 frames/s`, a line per source.
    pub(super) fn write_passive_interim(&mut self, figures: &PassiveInterim) -> io::Result<()> {
        if figures.table.sources.is_empty() {
            self.interim_head(figures.at)?;
            writeln!(self.out, "nothing heard yet")?;
        }
        for r in &figures.table.sources {
            self.interim_head(figures.at)?;
            let role = match (r.radio, r.ground) {
                (true, _) => " (radio)",
                (_, true) => " (the ground station's own)",
                _ => "",
            };
            let damaged = if_any(r.counts.damaged, |n| format!("{n} damaged, "));
            let [received, lost, loss, duplicate, reordered, silences, per_s, _] =
                source_figures(r);
            let age = figures.ages.iter().find(|a| a.source == r.source);
            let age = age.map_or(String::new(), |a| {
                let h = &a.headline;
                format!(
                    ", age p99 {:.1} ms (max {:.1}) above baseline",
                    h.p99_ms, h.max_ms
                )
            });
            writeln!(
                self.out,
                "{}{role}: {received} received, {damaged}{lost} lost ({loss}), {duplicate} duplicate, {reordered} reordered, {silences} silences, {per_s} frames/s{age}",
                r.source,
            )?;
        }
        self.out.flush()
    }
}

fn seconds(ns: u64) -> String {
    format!("{:.3} s", ns as f64 / 1e9)
}

/// A source's figures as its table row and its interim line give them:
/// received, lost, loss, duplicate, reordered, silences, frames/s, B/s.
fn source_figures(r: &SourceSummary) -> [String; 8] {
    let c = &r.counts;
    [
        c.received.to_string(),
        c.lost.to_string(),
        percent_or_dash(r.loss_pct),
        c.duplicate.to_string(),
        c.reordered.to_string(),
        r.silence_count.to_string(),
        r.frames_per_s.map_or_else(|| "-".into(), per_second),
        whole_or(r.bytes_per_s, "-"),
    ]
}

/// The source table: its column names after `lead` (the per-link table's
/// link column), then a row per source.
fn write_table<'a>(
    out: &mut impl Write,
    lead: &str,
    s: &PassiveSummary,
    rows: impl IntoIterator<Item = (String, &'a SourceSummary)>,
) -> io::Result<()> {
    let titles = [
        "received", "lost", "loss", "dup", "reorder", "silences", "frames/s", "B/s",
    ];
    write!(out, "{lead}")?;
    table_line(out, "source", "identity", titles.map(String::from))?;
    for (lead, r) in rows {
        let who = match s.identity(r.source) {
            Some(i) => identity(i),
            None if r.radio => "radio".into(),
            None => "-".into(),
        };
        write!(out, "{lead}")?;
        table_line(out, &r.source.to_string(), &who, source_figures(r))?;
    }
    Ok(())
}

fn table_line(out: &mut impl Write, source: &str, who: &str, f: [String; 8]) -> io::Result<()> {
    let [received, lost, loss, dup, reorder, silences, per_s, bytes] = f;
    writeln!(
        out,
        "{source:<9} {who:<22} {received:>9} {lost:>7} {loss:>7} {dup:>5} {reorder:>7} {silences:>8} {per_s:>9} {bytes:>9}"
    )
}

/// `messages: 1/1 ATTITUDE 49.9/s, GLOBAL_POSITION_INT 5.0/s, HEARTBEAT
/// 1.0/s`: a source's busiest message ids, by name where the dialect
/// knows it, each at its share of the source's rate (its count where the
/// rate is not known), then how many more.
fn write_messages(out: &mut impl Write, r: &SourceSummary) -> io::Result<()> {
    if r.msg_ids.is_empty() {
        return Ok(());
    }
    let each: Vec<String> = r
        .msg_ids
        .iter()
        .take(TOP_MSG_IDS)
        .map(|m| match r.msg_rate(m) {
            Some(rate) => format!("{} {}/s", id_name(m.id), per_second(rate)),
            None => id_count(m),
        })
        .collect();
    let more = r.msg_ids.len().saturating_sub(TOP_MSG_IDS);
    let rest: u64 = r.msg_ids.iter().skip(TOP_MSG_IDS).map(|m| m.count).sum();
    let rest = rest + r.msg_ids_other;
    let tail = match (more, r.msg_ids_other) {
        (0, 0) => String::new(),
        (0, _) => format!(", and more ids ({rest} frames)"),
        (n, 0) => format!(", and {n} more ids ({rest} frames)"),
        (n, _) => format!(", and {n}+ more ids ({rest} frames)"),
    };
    writeln!(out, "messages: {} {}{tail}", r.source, each.join(", "))
}

/// `damaged: 1/194 1949 frames whose CRC failed (DISTANCE_SENSOR ×1949)
/// ...`: frames that arrived with their header whole but failed their
/// CRC, by id, where a source had any.
fn write_damaged(out: &mut impl Write, r: &SourceSummary) -> io::Result<()> {
    if r.counts.damaged == 0 {
        return Ok(());
    }
    let ids = name_counts(&r.damaged_ids);
    writeln!(
        out,
        "damaged: {} {} frames whose CRC failed ({ids}): they arrived, so their numbers are not \
         lost (damage on the way, or a dialect whose CRC differs)",
        r.source, r.counts.damaged
    )
}

fn write_silence(out: &mut impl Write, r: &SourceSummary, silence: &Silence) -> io::Result<()> {
    let still = if silence.ongoing {
        " (still silent)"
    } else {
        ""
    };
    let (length, from) = (seconds(silence.length_ns), seconds(silence.start));
    let figures = silence_figures(silence);
    writeln!(
        out,
        "silence: {} heard nothing for {length} from {from}{still}: {figures}",
        r.source
    )
}

/// What the sequence proves across a silence, and what the rate suggests.
fn silence_figures(silence: &Silence) -> String {
    if silence.restart {
        return "its counter started again at 0 (the source restarted): no loss counted".into();
    }
    match (
        silence.seq_lost,
        silence.lost_estimated,
        silence.frames_estimated,
    ) {
        (Some(0), None, _) => {
            "no number missing across it: delayed (or not sent), none lost".into()
        }
        (Some(lost), Some(likely), _) if likely > lost => format!(
            "{lost} frames lost by the sequence, ~{likely} likely at its rate (its 8-bit counter \
             wrapped in it, as the rate says: the {} more are not counted)",
            likely - lost
        ),
        (Some(lost), _, _) => format!("{lost} frames lost, counted by the sequence"),
        (None, _, Some(est)) => format!("~{est} frames at its rate so far"),
        (None, _, None) => "its rate was not known yet".into(),
    }
}

/// What a telemetry log held: its span on the wall clock, its records,
/// its stamps, and what was not a record.
fn write_log(out: &mut impl Write, log: &LogFacts) -> io::Result<()> {
    let st = &log.stamps;
    let wall = |us: u64| {
        let t = std::time::SystemTime::UNIX_EPOCH + std::time::Duration::from_micros(us);
        humantime::format_rfc3339_micros(t).to_string()
    };
    let r = &log.records;
    let stamps = if st.whole_ms {
        "all whole milliseconds, as QGroundControl writes them"
    } else {
        "in microseconds"
    };
    let end = if log.complete {
        "read to its end"
    } else {
        "stopped before its end"
    };
    let (from, to) = (wall(st.first_us), wall(st.latest_us));
    writeln!(
        out,
        "log: {} records from {from} to {to} (stamps {stamps}), {end}",
        r.records
    )?;
    let notes = [
        (
            r.junk_bytes,
            format!(
                "{} bytes of junk between records, in {} stretches, skipped ({} began with a \
                 frame that failed its CRC)",
                r.junk_bytes, r.junk_stretches, r.bad_crc
            ),
        ),
        (
            r.truncated_bytes,
            format!("its last record is cut short ({} bytes)", r.truncated_bytes),
        ),
        (
            r.damaged,
            format!(
                "{} records whose frame failed its CRC, whole between records: damaged frames, \
                 their headers read (pymavlink calls them BAD_DATA)",
                r.damaged
            ),
        ),
        (
            r.unknown_id,
            format!(
                "{} records of message ids this build does not know, lined up between records: \
                 their headers read (pymavlink calls them BAD_DATA)",
                r.unknown_id
            ),
        ),
        (
            st.behind + st.steps,
            format!(
                "{} records stamped behind the latest (dated at it), {} clock steps (the time \
                 goes on from the latest, no gap)",
                st.behind, st.steps
            ),
        ),
    ];
    for (_, note) in notes.iter().filter(|(n, _)| *n > 0) {
        writeln!(out, "log: {note}")?;
    }
    Ok(())
}

/// The table per MAVProxy link, and the sources on none.
fn write_links(out: &mut impl Write, s: &PassiveSummary, per: &PerLink) -> io::Result<()> {
    writeln!(
        out,
        "per MAVProxy link (the stamps' two lowest bits; link 3 is what MAVProxy sent):"
    )?;
    let rows = per.links.iter().flat_map(|l| {
        let lead = format!("{:<4} ", l.link);
        l.table.sources.iter().map(move |r| (lead.clone(), r))
    });
    write_table(out, "link ", s, rows)?;
    if !per.unlinked.is_empty() {
        let ids: Vec<String> = per.unlinked.iter().map(ToString::to_string).collect();
        writeln!(
            out,
            "on no link: {} (the low bits of their stamps vary as a clock's: MAVProxy logs what \
             its outputs send with a plain stamp)",
            ids.join(", ")
        )?;
    }
    Ok(())
}

/// The summary of a passive run.
pub(super) fn write_summary(
    out: &mut impl Write,
    s: &PassiveSummary,
    verdict: &Verdict,
) -> io::Result<()> {
    let t = &s.table.totals;
    if let Some(log) = &s.log {
        write_log(out, log)?;
    }
    let how = if s.log.is_some() {
        "of log"
    } else {
        "listened"
    };
    let others = match (t.radio_received, t.ground_received) {
        (0, 0) => String::new(),
        (r, 0) => format!(" (and {r} from the radio)"),
        (0, g) => format!(" (and {g} the ground station logged as it sent them)"),
        (r, g) => {
            format!(" (and {r} from the radio, {g} the ground station logged as it sent them)")
        }
    };
    writeln!(
        out,
        "{:.1} s {how}, {} sources heard, {} frames{others}",
        s.duration_s, t.sources, t.counts.received
    )?;
    if s.table.sources.iter().all(|r| r.ground) {
        writeln!(out, "nothing heard")?;
    } else {
        let rows = s.table.sources.iter().filter(|r| !r.ground);
        write_table(out, "", s, rows.map(|r| (String::new(), r)))?;
        write_link_line(out, t)?;
    }
    write_ground(out, s)?;
    if let Some(per) = &s.per_link {
        write_links(out, s, per)?;
    }
    super::link_node::write_link_nodes(out, &s.link_node)?;
    super::summary::write_answered(out, &s.answered)?;
    super::summary::write_ages(out, &s.age)?;
    if let Some(rt) = &s.round_trips {
        super::round_trips::write_round_trips(out, rt, s.log.as_ref())?;
    }
    for r in &s.table.sources {
        write_messages(out, r)?;
    }
    for r in &s.table.sources {
        write_damaged(out, r)?;
        write_second_counter(out, r)?;
    }
    // A ground station's pauses in what it sent say nothing of the link.
    for r in s.table.sources.iter().filter(|r| !r.ground) {
        for silence in &r.silences {
            write_silence(out, r, silence)?;
        }
        if r.silences_omitted > 0 {
            writeln!(out, "silence: {} and {} more", r.source, r.silences_omitted)?;
        }
    }
    for r in &s.radios {
        super::heard::write_radio(out, r)?;
    }
    if let (Some(f), Some(log)) = (&s.flight, &s.log) {
        super::flight::write_flight(out, f, super::flight::LogClock(log.stamps.first_us))?;
    }
    let u = &s.table.untracked;
    if u.sources > 0 {
        writeln!(
            out,
            "{} more sources beyond the table's cap: {} frames, counted, not tracked",
            u.sources, u.frames
        )?;
    }
    writeln!(out, "receive times: {}", s.rx_clock)?;
    for hint in &s.hints {
        writeln!(out, "hint: {}", hint.text)?;
    }
    write_failures(out, verdict)
}

/// `link:`, the totals of every source but the radio's and the ground
/// station's own.
fn write_link_line(out: &mut impl Write, t: &LinkTotals) -> io::Result<()> {
    let (c, loss) = (&t.counts, percent_or_dash(t.loss_pct));
    let damaged = if_any(c.damaged, |n| format!(", {n} damaged"));
    let wrapped = if_any(t.silence_frames_estimated, |n| {
        format!(", ~{n} more likely lost in silences the 8-bit counter wrapped in")
    });
    writeln!(
        out,
        "link: {} received, {} lost ({loss}), {} duplicate, {} reordered{damaged}{wrapped}; \
         pymavlink's figure: {} lost ({:.2}%)",
        c.received, c.lost, c.duplicate, c.reordered, t.pymav.loss, t.pymav.loss_pct
    )
}

/// A log's ground station's own frames, apart: logged as it sent them,
/// so their gaps are what the logger did not record, not the link's loss.
fn write_ground(out: &mut impl Write, s: &PassiveSummary) -> io::Result<()> {
    if !s.table.sources.iter().any(|r| r.ground) {
        return Ok(());
    }
    writeln!(
        out,
        "the ground station's own frames (logged as it sent them: not the link's; their gaps are \
         numbers it did not log):"
    )?;
    let rows = s.table.sources.iter().filter(|r| r.ground);
    write_table(out, "", s, rows.map(|r| (String::new(), r)))
}

/// `two senders behind 255/190: ...`: a second counter under one id.
fn write_second_counter(out: &mut impl Write, r: &SourceSummary) -> io::Result<()> {
    let Some(c) = &r.second_counter else {
        return Ok(());
    };
    let (numbered, ids) = (
        c.counts.received + c.counts.damaged,
        name_counts(&c.msg_ids),
    );
    writeln!(
        out,
        "two senders behind {}: a second counter numbered {numbered} of its frames ({ids}), \
         counted on its own: {} lost, {} restarts of its count",
        r.source, c.counts.lost, c.counts.resyncs
    )
}

/// `DISTANCE_SENSOR ×1949, id 60045 ×3`.
fn name_counts(ids: &[MsgCount]) -> String {
    let mut each: Vec<String> = ids.iter().take(TOP_MSG_IDS).map(id_count).collect();
    let more = ids.len().saturating_sub(TOP_MSG_IDS);
    if more > 0 {
        each.push(format!("{more} more ids"));
    }
    each.join(", ")
}

/// `DISTANCE_SENSOR ×1949`: an id and how many frames it had.
fn id_count(m: &MsgCount) -> String {
    format!("{} ×{}", id_name(m.id), m.count)
}

/// A message id by the dialect's name, `id N` where it has none.
fn id_name(id: u32) -> String {
    message_name(id).map_or_else(|| format!("id {id}"), String::from)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::engine::observe::Observer;
    use crate::engine::probe::passive::tracker::{SourceTable, RADIO_SOURCE};
    use crate::engine::summary::Interim;
    use crate::frame::SysComp;

    const MS: u64 = 1_000_000;

    /// 1/1: 100 sequence numbers 20 ms apart, 50 never sent; every tenth a
    /// HEARTBEAT, one of an id no dialect knows, the rest ATTITUDE. 2/1:
    /// six ids. And one RADIO_STATUS from the radio.
    fn table() -> SourceTable {
        let mut t = SourceTable::new(None, 32);
        for k in 0..100u64 {
            if k == 50 {
                continue;
            }
            let id = match k {
                _ if k % 10 == 0 => 0,
                55 => 65_000,
                _ => 30,
            };
            t.on_frame(SysComp::new(1, 1), k as u8, id, 40, k * 20 * MS);
        }
        for (k, id) in [1u32, 1, 1, 2, 2, 24, 33, 74, 147].into_iter().enumerate() {
            t.on_frame(SysComp::new(2, 1), k as u8, id, 30, k as u64 * 200 * MS);
        }
        t.on_frame(RADIO_SOURCE, 0, 109, 38, 500 * MS);
        t
    }

    #[test]
    fn the_busiest_messages_are_named_at_their_share_of_the_rate() {
        let summary = table().summary(2_000 * MS);
        let mut out = Vec::new();
        for r in &summary.sources {
            write_messages(&mut out, r).unwrap();
        }
        // 1/1: 98 frames in the 1.98 s after its first, 49.5 a second, of
        // which ATTITUDE is 89 of its 99 and HEARTBEAT 9 (50 was never
        // sent). 2/1: 5 a second, SYS_STATUS 3 of its 9 frames.
        assert_eq!(
            String::from_utf8(out).unwrap(),
            "messages: 1/1 ATTITUDE 44.5/s, HEARTBEAT 4.5/s, id 65000 0.5/s\n\
             messages: 2/1 SYS_STATUS 1.7/s, SYSTEM_TIME 1.1/s, GPS_RAW_INT 0.6/s, \
             GLOBAL_POSITION_INT 0.6/s, and 2 more ids (2 frames)\n\
             messages: 51/68 RADIO_STATUS ×1\n"
        );
    }

    #[test]
    fn an_interim_is_a_line_per_source_in_quiet_mode_too() {
        let table = table();
        let mut text = TextReporter::new(Vec::new(), true);
        let empty = SourceTable::new(None, 32).summary(MS);
        for (at, table) in [(MS, empty), (2_000 * MS, table.summary(2_000 * MS))] {
            text.interim(&Interim::new(PassiveInterim {
                at,
                table,
                identities: vec![],
                ages: vec![],
            }))
            .unwrap();
        }
        assert_eq!(
            String::from_utf8(text.into_inner()).unwrap(),
            "[0.0 s] nothing heard yet\n\
             [2.0 s] 1/1: 99 received, 1 lost (1.00%), 0 duplicate, 0 reordered, 0 silences, 49.5 frames/s\n\
             [2.0 s] 2/1: 9 received, 0 lost (0.00%), 0 duplicate, 0 reordered, 0 silences, 5.0 frames/s\n\
             [2.0 s] 51/68 (radio): 1 received, 0 lost (0.00%), 0 duplicate, 0 reordered, 0 silences, - frames/s\n"
        );
    }
}
