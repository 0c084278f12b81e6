//! What the packet sequence adds to an exposition: a passive link's
//! families per source (`mavping_source_*`: counters that only grow, and
//! gauges of rate, loss and silence, pymavlink's figure named as such),
//! and an echo run's loss by direction per responder
//! (`mavping_direction_*`), split by the summary's own formula.

use super::exposition::{Exposition, Family, Figure, SeriesFigure};
use super::sources::SourceSeries;
use super::Metrics;
use crate::engine::age::AGE_BOUNDS_MS;
use crate::engine::summary::{Direction, ProbeName};
use crate::frame::SysComp;

impl Metrics {
    /// A source's labels: the radio's own RADIO_STATUS source is marked,
    /// so a sum over a link's sources can leave it out, as the link's
    /// totals do.
    fn source_labels(&self, id: SysComp, s: &SourceSeries) -> String {
        let radio = if s.radio { ",radio=\"true\"" } else { "" };
        format!("{}{radio}", self.radio_labels(id))
    }
}

/// A source's counters (counts below 2^53, exact as `f64`), then its
/// gauges.
const SOURCE: [SeriesFigure<SourceSeries>; 16] = [
    Figure::counter(
        "mavping_source_received_total",
        "Frames received from the source, duplicates included (--passive: its own packet sequence).",
        |s| Some(s.counters().seq.received as f64),
    ),
    Figure::counter(
        "mavping_source_damaged_total",
        "Whole frames from the source whose CRC failed (damaged on the way, or a dialect whose CRC differs): they arrived, so their numbers are not lost; not in mavping_source_received_total.",
        |s| Some(s.counters().seq.damaged as f64),
    ),
    Figure::counter(
        "mavping_source_lost_total",
        "Frames its packet sequence proves lost, counted once no late frame can fill the gap (128 behind its latest frame, in a silence, or at the run's end); mavping_source_lost_pending holds the rest.",
        |s| Some(s.counters().lost_settled as f64),
    ),
    Figure::counter(
        "mavping_source_duplicate_total",
        "Frames whose sequence number had been received already.",
        |s| Some(s.counters().seq.duplicate as f64),
    ),
    Figure::counter(
        "mavping_source_reordered_total",
        "Frames that came after a later one and filled their gap.",
        |s| Some(s.counters().seq.reordered as f64),
    ),
    Figure::counter(
        "mavping_source_resyncs_total",
        "Times the count restarted on a frame the sequence could not place (after a long silence, or 128 away).",
        |s| Some(s.counters().seq.resyncs as f64),
    ),
    Figure::counter(
        "mavping_source_bytes_total",
        "Frame bytes received from the source, duplicates included.",
        |s| Some(s.counters().bytes as f64),
    ),
    Figure::counter(
        "mavping_source_silences_total",
        "Times the source was heard from nothing for longer than the gap (--gap), an ongoing silence included.",
        |s| Some(s.counters().silences as f64),
    ),
    Figure::counter(
        "mavping_source_silence_seconds_total",
        "Time the source spent in silences, an ongoing one up to the latest count (once a second).",
        |s| Some(s.counters().silence_ns as f64 / 1e9),
    ),
    Figure::counter(
        "mavping_source_pymavlink_lost_total",
        "pymavlink's loss count for the same frames (mavutil: (seq - expected) % 256 at each mismatch, so a duplicate costs it 255), to compare with MAVProxy's link or mavloss.py; not mavping's.",
        |s| Some(s.counters().pymav_loss as f64),
    ),
    Figure::gauge(
        "mavping_source_lost_pending",
        "Frames counted lost that may still arrive late and be reordered (within 127 of the latest frame, outside a silence): not in mavping_source_lost_total yet.",
        |s| s.pending().map(|p| p as f64),
    ),
    Figure::gauge(
        "mavping_source_loss_ratio",
        "Lost over the frames its sequence numbered (received once or lost), since it was first heard (0 to 1).",
        SourceSeries::loss_ratio,
    ),
    Figure::gauge(
        "mavping_source_pymavlink_loss_ratio",
        "pymavlink's figure, not mavping's: its loss over count + loss, as MAVProxy's link and mavloss.py show it (a duplicate or a swap costs it about 255 frames).",
        SourceSeries::pymav_loss_ratio,
    ),
    Figure::gauge(
        "mavping_source_frames_per_second",
        "Frames per second from the source's first frame to its latest, in this session of the link.",
        SourceSeries::frames_per_s,
    ),
    Figure::gauge(
        "mavping_source_age_seconds",
        "How much later than its quickest the source's newest stamped frame arrived: receive time minus the frame's own clock stamp, above that difference's lower envelope with the clocks' drift fitted (a queue's delay; absent without stamps).",
        |s| s.age_s,
    ),
    Figure::gauge(
        "mavping_source_silent",
        "1 while the source is in a silence (heard from nothing for longer than the gap), 0 while it is heard.",
        |s| s.silent().map(|on| f64::from(u8::from(on))),
    ),
];

/// A passive link's sources, each family once across the links.
pub(super) fn write_sources(out: &mut Exposition, links: &[&Metrics]) {
    let series = || {
        links
            .iter()
            .filter(|m| m.probe == Some(ProbeName::Passive))
            .flat_map(|m| {
                m.sources
                    .iter()
                    .map(move |(id, s)| (m.source_labels(*id, s), s))
            })
    };
    out.figures(&SOURCE, series);
    write_age_histogram(out, series);
}

const FRAME_AGE: Family = Family::histogram(
    "mavping_source_frame_age_seconds",
    "The source's frames' ages above its baseline, by their own clock stamps: how much later than its quickest each arrived (see mavping_source_age_seconds for the newest).",
);

/// Each source's frames' ages counted, as a histogram, for the sources
/// whose frames carry a clock stamp.
fn write_age_histogram<'a, I>(out: &mut Exposition, series: impl Fn() -> I)
where
    I: Iterator<Item = (String, &'a SourceSeries)>,
{
    let counted = || series().filter_map(|(l, s)| Some((l, s.age_counts?)));
    if counted().next().is_none() {
        return;
    }
    out.header(&FRAME_AGE);
    let name = |part| format!("{}_{part}", FRAME_AGE.name);
    for (labels, c) in counted() {
        let mut cumulative = 0;
        for (i, count) in c.buckets.iter().enumerate() {
            cumulative += count;
            let le = AGE_BOUNDS_MS
                .get(i)
                .map_or("+Inf".into(), |ms| (ms / 1e3).to_string());
            out.sample(
                &name("bucket"),
                &format!("{labels},le=\"{le}\""),
                cumulative,
            );
        }
        out.sample(&name("sum"), &labels, c.sum_ms / 1e3);
        out.sample(&name("count"), &labels, c.count);
    }
}

const DIRECTION_LOSS: Family = Family::gauge(
    "mavping_direction_loss_ratio",
    "A probed responder's loss by direction (0 to 1): round_trip of its requests, down of its own frames by their packet sequence, up inferred as 1 - (1 - round_trip) / (1 - down). Shown once there is loss to split; up is left out when the split cannot hold (mavping_direction_split_consistent 0) or every frame down was lost.",
);

const DIRECTION_STDERR: Family = Family::gauge(
    "mavping_direction_loss_stderr",
    "Standard error of the inferred loss ratio (direction=\"up\"), from the binomial errors of the round trip and the downlink.",
);

const DIRECTION_CONSISTENT: Family = Family::gauge(
    "mavping_direction_split_consistent",
    "1 when the split holds; 0 when the downlink alone loses more than the round trip by over two standard errors: the responder's sequence does not number just what it sends us on this link (a router re-sequencing, or merged links), so no up figure is shown.",
);

/// The uplink's loss, only where the split holds.
fn uplink(d: &Direction) -> Option<f64> {
    d.uplink_loss.filter(|_| d.consistent)
}

/// Every echo responder's loss by direction.
pub(super) fn write_directions(out: &mut Exposition, links: &[&Metrics]) {
    let splits = || {
        links.iter().flat_map(|m| {
            m.responders.iter().filter_map(move |(id, s)| {
                let d = s.direction(m.sources.get(id))?;
                Some((m.labels(*id), d))
            })
        })
    };
    let with = |labels: &str, direction: &str| format!("{labels},direction=\"{direction}\"");
    out.family(
        &DIRECTION_LOSS,
        splits().flat_map(|(l, d)| {
            let up = uplink(&d).map(|up| (with(&l, "up"), up));
            [
                Some((with(&l, "round_trip"), d.round_trip_loss)),
                Some((with(&l, "down"), d.downlink_loss)),
                up,
            ]
            .into_iter()
            .flatten()
        }),
    );
    out.family(
        &DIRECTION_STDERR,
        splits().filter_map(|(l, d)| Some((with(&l, "up"), uplink(&d).and(d.uplink_stderr)?))),
    );
    out.family(
        &DIRECTION_CONSISTENT,
        splits().map(|(l, d)| (l, u8::from(d.consistent))),
    );
}

#[cfg(test)]
mod tests {
    use super::super::render::render;
    use super::super::test_support::{has, test_start as info};
    use super::*;
    use crate::engine::matcher::MatchEvent;
    use crate::engine::observe::{Observer, StartInfo};
    use crate::engine::probe::passive::tracker::{SourceTable, RADIO_SOURCE};
    use crate::engine::probe::passive::{PassivePlan, SourcesNow};
    use crate::engine::summary::LinkSummary;
    use crate::engine::Nanos;
    use crate::output::runs::kind;
    use crate::output::Reporter;

    const MS: Nanos = 1_000_000;

    fn passive_start(link: &str) -> StartInfo {
        StartInfo {
            probe: ProbeName::Passive,
            plan: Some(std::sync::Arc::new(PassivePlan {
                heartbeat: true,
                log: false,
            })),
            ..info(link)
        }
    }

    /// Frames of `source`, by sequence number, one every 20 ms from `t0`.
    fn frames(table: &mut SourceTable, source: SysComp, seqs: &[u8], t0: Nanos) {
        for (i, &seq) in seqs.iter().enumerate() {
            table.on_frame(source, seq, 30, 40, t0 + i as Nanos * 20 * MS);
        }
    }

    /// A passive link: 1/1 loses 3 and 4, doubles 6 and swaps 8 and 9;
    /// 2/1 went quiet long ago; the SiK radio's own source.
    fn passive_link() -> (Metrics, SourceTable) {
        let mut m = Metrics::default();
        m.on_start(&passive_start("udp:0.0.0.0:14550"));
        let mut table = SourceTable::new(None, 32);
        frames(&mut table, SysComp::new(2, 1), &[0, 1, 2], 0);
        frames(
            &mut table,
            SysComp::new(1, 1),
            &[0, 1, 2, 5, 6, 6, 7, 9, 8, 10],
            3_000 * MS,
        );
        frames(&mut table, RADIO_SOURCE, &[7, 8, 10], 3_000 * MS);
        (m, table)
    }

    #[test]
    fn a_passive_link_shows_each_source_as_counters_and_gauges() {
        let (mut m, table) = passive_link();
        let at = 3_200 * MS;
        m.event(&kind(SourcesNow {
            at,
            table: table.summary(at),
            ages: Vec::new(),
            age_counts: Vec::new(),
            age_max: Vec::new(),
        }))
        .unwrap();
        let text = render(&[&m]);
        let one = r#"link="udp:0.0.0.0:14550",sysid="1",compid="1""#;
        let two = r#"link="udp:0.0.0.0:14550",sysid="2",compid="1""#;
        let radio = r#"link="udp:0.0.0.0:14550",sysid="51",compid="68",radio="true""#;
        has(&text, "# TYPE mavping_source_lost_total counter");
        has(&text, &format!("mavping_source_received_total{{{one}}} 10"));
        // 3 and 4 may still come: pending, not yet in the counter.
        has(&text, &format!("mavping_source_lost_total{{{one}}} 0"));
        has(&text, &format!("mavping_source_lost_pending{{{one}}} 2"));
        has(&text, &format!("mavping_source_duplicate_total{{{one}}} 1"));
        has(&text, &format!("mavping_source_reordered_total{{{one}}} 1"));
        has(&text, &format!("mavping_source_bytes_total{{{one}}} 400"));
        has(
            &text,
            &format!("mavping_source_loss_ratio{{{one}}} {}", 2.0 / 11.0),
        );
        // pymavlink: 2 for the gap, 255 for the duplicate, 255 + 1 for the
        // swap.
        has(
            &text,
            &format!("mavping_source_pymavlink_lost_total{{{one}}} 513"),
        );
        has(
            &text,
            &format!(
                "mavping_source_pymavlink_loss_ratio{{{one}}} {}",
                513.0 / 523.0
            ),
        );
        has(&text, &format!("mavping_source_silent{{{one}}} 0"));
        has(
            &text,
            &format!("mavping_source_frames_per_second{{{one}}} 50"),
        );
        // 2/1, quiet for 3.16 s: in a silence, counted as one.
        has(&text, &format!("mavping_source_silent{{{two}}} 1"));
        has(&text, &format!("mavping_source_silences_total{{{two}}} 1"));
        has(
            &text,
            &format!("mavping_source_silence_seconds_total{{{two}}} 3.16"),
        );
        // The radio's source, marked.
        has(
            &text,
            &format!("mavping_source_received_total{{{radio}}} 3"),
        );
        has(&text, &format!("mavping_source_lost_pending{{{radio}}} 1"));

        // The run ends: what was pending is lost for good.
        let end = LinkSummary::new(passive_summary(&table, at));
        let verdict = crate::verdict::judge_link(&end, &crate::verdict::Thresholds::default());
        m.summary(&end, &verdict).unwrap();
        let text = render(&[&m]);
        has(&text, &format!("mavping_source_lost_total{{{one}}} 2"));
        has(&text, &format!("mavping_source_lost_pending{{{one}}} 0"));
        has(&text, &format!("mavping_source_lost_total{{{radio}}} 1"));
        // A passive run has no responders: no echo families.
        assert!(!text.contains("mavping_sent_total"), "{text}");
        assert!(!text.contains("mavping_direction"), "{text}");
    }

    fn passive_summary(
        table: &SourceTable,
        at: Nanos,
    ) -> crate::engine::summary::passive::PassiveSummary {
        crate::engine::summary::passive::PassiveSummary {
            link: "udp:0.0.0.0:14550".into(),
            ours: SysComp::new(250, 190),
            heartbeat: true,
            duration_s: at as f64 / 1e9,
            table: table.summary(at),
            identities: vec![],
            own_frames: 0,
            radios: vec![],
            link_node: vec![],
            frames: crate::frame::ScanStats::default(),
            rx_clock: crate::transport::RxClock::Kernel,
            interrupted: false,
            link_error: None,
            signing: crate::frame::signing::SigningSummary {
                key: false,
                required: false,
                link_id: None,
                counts: crate::frame::signing::SigningCounts::default(),
            },
            answered: crate::engine::answers::AnswerSummary::default(),
            age: Vec::new(),
            hints: Vec::new(),
            log: None,
            per_link: None,
            round_trips: None,
            flight: None,
        }
    }

    /// Every family a passive link and a split add, byte for byte.
    #[test]
    fn the_sequence_families_byte_for_byte() {
        let (mut m, table) = passive_link();
        m.on_sources(&table.summary(3_200 * MS), false);
        let (echo, _) = echo_link(100);
        insta::assert_snapshot!("passive", render(&[&m, &echo]));
    }

    /// An echo link whose 1/1 lost 20 of 100 requests, and whose own
    /// An echo run's metrics after 100 requests to 1/1, every fifth lost.
    fn lost_every_fifth() -> (Metrics, SysComp) {
        let mut m = Metrics::default();
        m.on_start(&info("sim:"));
        let r = SysComp::new(1, 1);
        for seq in 0..100 {
            m.on_event(&if seq % 5 == 0 {
                MatchEvent::Lost {
                    responder: r,
                    seq,
                    sent_at: 0,
                    at: 0,
                }
            } else {
                MatchEvent::Reply {
                    responder: r,
                    seq,
                    rtt: 1_000_000,
                    sent_at: 0,
                    at: 0,
                    out_of_order: false,
                    first_from_responder: seq == 1,
                }
            });
        }
        (m, r)
    }

    /// frames, `numbered` of them, lost every 20th.
    fn echo_link(numbered: u64) -> (Metrics, SysComp) {
        let (mut m, r) = lost_every_fifth();
        let mut table = SourceTable::new(None, 32);
        let seqs: Vec<u8> = (0..numbered)
            .filter(|i| i % 20 != 10)
            .map(|i| i as u8)
            .collect();
        frames(&mut table, r, &seqs, 0);
        m.on_sources(&table.summary(numbered * 20 * MS), false);
        (m, r)
    }

    #[test]
    fn an_echo_run_splits_its_loss_as_the_summary_does() {
        let (m, _) = echo_link(100);
        let text = render(&[&m]);
        let l = r#"link="sim:",probe="ping",sysid="1",compid="1""#;
        // The summary's formula on the same counts: 20 of 100 requests,
        // 5 of 100 frames.
        let d = Direction::split(0.2, 100, 100, 5).unwrap();
        has(
            &text,
            &format!("mavping_direction_loss_ratio{{{l},direction=\"round_trip\"}} 0.2"),
        );
        has(
            &text,
            &format!("mavping_direction_loss_ratio{{{l},direction=\"down\"}} 0.05"),
        );
        has(
            &text,
            &format!(
                "mavping_direction_loss_ratio{{{l},direction=\"up\"}} {}",
                d.uplink_loss.unwrap()
            ),
        );
        has(
            &text,
            &format!(
                "mavping_direction_loss_stderr{{{l},direction=\"up\"}} {}",
                d.uplink_stderr.unwrap()
            ),
        );
        has(
            &text,
            &format!("mavping_direction_split_consistent{{{l}}} 1"),
        );
        // An echo run's sources are not a passive run's families.
        assert!(!text.contains("mavping_source_"), "{text}");
    }

    #[test]
    fn no_up_figure_where_the_split_cannot_hold() {
        // 20% round trip, but 40 of 100 frames down: the sequence does not
        // number only what comes to us.
        let (mut m, r) = lost_every_fifth();
        let mut table = SourceTable::new(None, 32);
        let seqs: Vec<u8> = (0..100u8).filter(|i| i % 5 >= 2).collect();
        frames(&mut table, r, &seqs, 0);
        // In a silence: every gap settled, the ratio exact.
        m.on_sources(&table.summary(100 * 20 * MS + 5_000 * MS), false);
        let text = render(&[&m]);
        let l = r#"link="sim:",probe="ping",sysid="1",compid="1""#;
        has(
            &text,
            &format!("mavping_direction_split_consistent{{{l}}} 0"),
        );
        assert!(!text.contains("direction=\"up\""), "{text}");
        has(
            &text,
            &format!(
                "mavping_direction_loss_ratio{{{l},direction=\"down\"}} {}",
                38.0 / 98.0
            ),
        );

        // Nothing lost either way: nothing to split, nothing shown.
        let mut clean = Metrics::default();
        clean.on_start(&info("sim:"));
        clean.on_event(&MatchEvent::Reply {
            responder: r,
            seq: 0,
            rtt: 1,
            sent_at: 0,
            at: 0,
            out_of_order: false,
            first_from_responder: true,
        });
        let mut table = SourceTable::new(None, 32);
        frames(&mut table, r, &[0, 1, 2], 0);
        clean.on_sources(&table.summary(60 * MS), false);
        assert!(!render(&[&clean]).contains("mavping_direction"));
    }

    #[test]
    fn at_the_end_the_split_is_the_summarys() {
        let (mut m, r) = echo_link(100);
        let direction = Direction::split(0.25, 100, 200, 10);
        let responder = crate::engine::summary::ResponderSummary {
            id: r,
            counts: crate::engine::matcher::Counts::default(),
            loss_ratio: 0.25,
            rtt: None,
            histogram: vec![],
            identity: None,
            probe: None,
            clock: None,
            direction,
            split: None,
        };
        m.on_summary(&crate::engine::summary::EchoSummary {
            responders: vec![responder],
            ..crate::engine::summary::EchoSummary::empty("sim:", 4)
        });
        let text = render(&[&m]);
        let l = r#"link="sim:",probe="ping",sysid="1",compid="1""#;
        has(
            &text,
            &format!("mavping_direction_loss_ratio{{{l},direction=\"round_trip\"}} 0.25"),
        );
        has(
            &text,
            &format!("mavping_direction_loss_ratio{{{l},direction=\"down\"}} 0.05"),
        );
        // A new session of the link (mavping serve) splits live again.
        m.on_start(&info("sim:"));
        let text = render(&[&m]);
        has(
            &text,
            &format!("mavping_direction_loss_ratio{{{l},direction=\"round_trip\"}} 0.2"),
        );
    }
}
