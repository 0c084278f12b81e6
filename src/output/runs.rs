//! Every kind of run as a format hears it: what a PING, TIMESYNC, sweep,
//! load, command, passive and telemetry-log run tell their reporters, in
//! order, with made-up but consistent figures. The JSON tests check each
//! line against the schema; `every_format.rs` sends every run through
//! every format.
#![cfg(test)]
use std::sync::Arc;
use std::time::Duration;

use crate::engine::age::{AgeCounts, AgeNow, ClockAgeSummary, SourceAge, SplitSummary};
use crate::engine::answers::AnswerSummary;
use crate::engine::c2::{
    Band, C2Report, C2Rule, Continuity, DirectionLoss, DistanceBand, FailsafeReplay, Latency,
    OneWay, Outage, Outages, Percentiles, Timeline, Trip,
};
use crate::engine::clock_offset::ClockSummary;
use crate::engine::hint::{Hint, HintCode};
use crate::engine::kind::KindValue;
use crate::engine::link_node::{LinkNodeReport, LinkNodeSummary, LinkNodes, UplinkComparison};
use crate::engine::load::{Load, LoadKind, LoadSpec};
use crate::engine::matcher::{Counts, MatchEvent};
use crate::engine::observe::RadioHeard;
use crate::engine::probe::command::CommandEvent;
use crate::engine::probe::passive::flight::{Flight, FlightEvent, FlightSummary, Totals};
use crate::engine::probe::passive::tracker::RADIO_SOURCE;
use crate::engine::probe::passive::{PassivePlan, SourcesNow};
use crate::engine::probe::transfer::{AttemptFigures, Ending, TransferProgress};
use crate::engine::radio::{Judgement, RadioKind, RadioReport, RadioType, Radios, UNKNOWN};
use crate::engine::roster::Identity;
use crate::engine::stats::RttStats;
use crate::engine::summary::ProbeName;
use crate::engine::summary::{
    AckResult, CommandSummary, CommandTargetSummary, EchoInterim, EchoSummary, Interim,
    LinkSummary, PassiveInterim, ResponderSummary, ScheduleSummary,
};
use crate::engine::sweep::step::{Phase, StepFigures, StepRadio};
use crate::engine::sweep::verdict::{self as sweep_verdict, SweepEnd, SweepSummary};
use crate::engine::sweep::{MaxFrom, PlanKind, SweepConfig};
use crate::engine::{capacity, CommandSpec};
use crate::frame::{ScanStats, StampClock, StampMeaning, SysComp, Version};
use crate::output::{Event, StartInfo};
use crate::transport::RxClock;
use crate::verdict::{self, Thresholds, Verdict};

/// A kind's own event as the engine tells it; a test's events live as
/// long as the test run.
pub(crate) fn kind<T: KindValue>(value: T) -> Event<'static> {
    Event::Kind(Box::leak(Box::new(value)))
}

/// The vehicle's requests a run answered: a PX4's PINGs and an
/// ArduPilot's TIMESYNCs, a few of them in a flood.
pub(crate) fn answered() -> AnswerSummary {
    AnswerSummary {
        counts: crate::answering::ResponderCounts {
            ping_requests: 4,
            timesync_requests: 12,
            ..Default::default()
        },
        unanswered: 1,
    }
}

/// A vehicle's frames held by a queue that grew to 1.5 s: its boot-time
/// stamps at send, and a GPS fix's sample stamps older still.
pub(crate) fn ages() -> Vec<SourceAge> {
    let clock = |clock, meaning, p50_ms, p99_ms, max_ms| ClockAgeSummary {
        clock,
        meaning,
        samples: 400,
        p50_ms,
        p90_ms: f64::midpoint(p50_ms, p99_ms),
        p99_ms,
        max_ms,
        drift_ppm: Some(21.5),
        restarts: 0,
        rejected: 0,
        baseline_error_ms: 0.4,
    };
    let sent = clock(
        StampClock::BootMs,
        StampMeaning::Sent,
        620.0,
        1480.0,
        1500.0,
    );
    let sampled = clock(
        StampClock::BootMs,
        StampMeaning::Sampled,
        710.0,
        1630.0,
        1650.0,
    );
    vec![SourceAge {
        source: SysComp::new(1, 1),
        headline: sent,
        clocks: vec![sent, sampled],
        absolute: None,
    }]
}

/// [`ages`] where the source answered TIMESYNC: its baseline 12 ms one
/// way, between 1 and 23 ms by its clock offset's bounds.
pub(crate) fn ages_by_timesync() -> Vec<SourceAge> {
    let mut ages = ages();
    let h = ages[0].headline;
    ages[0].absolute = Some(crate::engine::age::AbsoluteAgeSummary {
        baseline_ms: 12.0,
        baseline_lower_ms: 1.0,
        baseline_upper_ms: 23.0,
        p50_ms: 12.0 + h.p50_ms,
        p99_ms: 12.0 + h.p99_ms,
        max_ms: 12.0 + h.max_ms,
    });
    ages
}

/// The hint [`ages`] gives a source that lost nothing.
pub(crate) fn queue_hints() -> Vec<crate::engine::hint::Hint> {
    let age = &ages()[0];
    vec![crate::engine::age::queue_building(age, 400, 0).expect("a queue")]
}

/// The probe a test names.
pub(crate) fn probe_name(probe: &str) -> ProbeName {
    match probe {
        "ping" => ProbeName::Ping,
        "timesync" => ProbeName::Timesync,
        "params" => ProbeName::Params,
        _ => ProbeName::Command,
    }
}

pub(crate) const ONE: SysComp = SysComp {
    sysid: 1,
    compid: 1,
};
pub(crate) const TWO: SysComp = SysComp {
    sysid: 2,
    compid: 1,
};
pub(crate) const RADIO: SysComp = SysComp {
    sysid: 51,
    compid: 68,
};

pub(crate) fn start(probe: &'static str) -> StartInfo {
    StartInfo {
        link: "sim:?seed=1".into(),
        probe: probe_name(probe),
        ours: SysComp::new(250, 190),
        interval: Duration::from_millis(100),
        timeout: Duration::from_secs(2),
        count: Some(10),
        plan: None,
    }
}

pub(crate) fn identity() -> Identity {
    Identity {
        mav_type: 2,
        autopilot: 12,
        vehicle: "quadrotor".into(),
        autopilot_name: "px4".into(),
        first_heard: 12_000_000,
    }
}

pub(crate) fn radio_report(rssi: u8) -> RadioReport {
    RadioReport {
        rssi,
        remrssi: 150,
        txbuf: 90,
        noise: 40,
        remnoise: UNKNOWN,
        rxerrors: 3,
        fixed: 1,
    }
}

pub(crate) fn clock(bounds: bool) -> ClockSummary {
    ClockSummary {
        offset_ns: -2_000_000_123,
        uncertainty_ns: 1_500,
        bounds_ns: bounds.then_some((-2_000_001_623, -1_999_998_623)),
        bounds_drift_limit_ppm: 200,
        spread_ns: 312.25,
        drift_ppm: bounds.then_some(49.75),
        drift_stderr_ppm: bounds.then_some(0.125),
        samples: 42,
    }
}

pub(crate) fn responder(id: SysComp, answered: bool) -> ResponderSummary {
    let mut rtt = RttStats::new();
    if answered {
        for ms in [10, 11, 12, 15, 40] {
            rtt.record(ms * 1_000_000 + 123_456);
        }
    }
    let counts = Counts {
        sent: 6,
        not_charged: 1,
        in_flight: 1,
        received: if answered { 5 } else { 0 },
        lost: if answered { 1 } else { 6 },
        late: 1,
        duplicate: 2,
        out_of_order: 1,
        stale: 3,
    };
    ResponderSummary {
        id,
        counts,
        loss_ratio: counts.loss_ratio(),
        rtt: rtt.summary(),
        histogram: rtt.distribution(4),
        identity: answered.then(identity),
        probe: None,
        clock: None,
        // Which way it lost: 2 of its 40 frames on the way down.
        direction: answered
            .then(|| crate::engine::summary::Direction::split(0.2, 10, 40, 2))
            .flatten(),
        // A downlink queue on the way back, by TIMESYNC's tc1.
        split: answered.then_some(SplitSummary {
            by: crate::engine::age::SplitBy::ReplyClock,
            exchanges: 40,
            uplink_p50_ms: 0.4,
            uplink_p99_ms: 1.2,
            uplink_max_ms: 1.5,
            downlink_p50_ms: 610.0,
            downlink_p99_ms: 1470.0,
            downlink_max_ms: 1490.0,
            drift_ppm: Some(-12.5),
        }),
    }
}

pub(crate) fn radios() -> Vec<crate::engine::radio::RadioSummary> {
    let mut radios = Radios::default();
    radios.record(RADIO, radio_report(120), 1_000_000_000);
    radios.record(RADIO, radio_report(110), 2_000_000_000);
    radios.record(SysComp::new(52, 100), radio_report(UNKNOWN), 2_000_000_000);
    radios.summaries()
}

/// A vehicle's LINK_NODE_STATUS over a run: 2103 of its link received
/// and 12 lost; with `compared`, mavping's estimate for 1/1 beside it.
pub(crate) fn link_nodes(compared: bool) -> Vec<LinkNodeSummary> {
    let report = |timestamp, messages_received, messages_lost| LinkNodeReport {
        timestamp,
        messages_received,
        messages_lost,
        messages_sent: 3 * messages_received,
        rx_rate: 640,
        tx_rate: 12_000,
        tx_buf: 90,
        rx_buf: 100,
        ..LinkNodeReport::default()
    };
    let mut nodes = LinkNodes::default();
    nodes.record(ONE, report(1_000, 100, 3), 1_000_000_000);
    nodes.record(ONE, report(43_000, 2_203, 15), 43_000_000_000);
    let mut summaries = nodes.summaries();
    if compared {
        summaries[0].compared = Some(UplinkComparison {
            responder: ONE,
            estimate: 0.097,
            estimate_stderr: 0.013,
            vehicle: 12.0 / 2115.0,
            vehicle_stderr: 0.0016,
            sigmas: 7.0,
            agrees: false,
        });
    }
    summaries
}

pub(crate) fn echo_summary(probe: &'static str) -> EchoSummary {
    let mut first = responder(ONE, true);
    if probe == "timesync" {
        first.clock = Some(clock(true));
    }
    let mut second = responder(TWO, false);
    if probe == "timesync" {
        second.clock = Some(clock(false));
    }
    EchoSummary {
        probe: probe_name(probe),
        duration_s: 1.234,
        in_flight: 1,
        no_peer_heard_s: None,
        responders: vec![first, second],
        foreign_replies: 1,
        wrong_path_replies: 2,
        untracked_replies: 3,
        frames: ScanStats {
            frames: 40,
            bad_crc: 1,
            unknown_id: 2,
            skipped_bytes: 17,
            truncated: 1,
            ..ScanStats::default()
        },
        hints: vec![Hint::new(
            HintCode::RadioErrors,
            "51/68's receive errors grew",
        )],
        link_error: Some("the link broke".into()),
        downtime_s: 0.5,
        schedule: Some(ScheduleSummary {
            requested_rate_hz: 10.0,
            achieved_rate_hz: 9.999,
            lateness_p50_us: 12.5,
            lateness_p99_us: 80.0,
            lateness_max_us: 120.25,
            not_sent: 3,
        }),
        rx_clock: RxClock::Simulated,
        radios: radios(),
        wire: Some(capacity::budget(57_600, Version::V2, 99, 2)),
        link_node: link_nodes(true),
        age: if probe == "timesync" {
            ages_by_timesync()
        } else {
            Vec::new()
        },
        ..EchoSummary::empty("sim:?seed=1", 8)
    }
}

pub(crate) fn thresholds() -> Thresholds {
    Thresholds {
        max_loss: Some(0.01),
        ..Thresholds::default()
    }
}

/// What a run tells its reporter, in order.
pub(crate) enum Told<'a> {
    Start(StartInfo),
    Event(Event<'a>),
    Interim(Interim),
    Summary(LinkSummary, Verdict),
}

/// What the events of the runs borrow.
pub(crate) struct Borrowed {
    identity: Identity,
    /// A radio read as SiK, then as mLRS once its HEARTBEAT came.
    sik: Judgement,
    mlrs: Judgement,
    steps: Vec<StepFigures>,
    flight: (Vec<FlightEvent>, FlightSummary),
    /// A passive run's sources a second in.
    sources: SourcesNow,
}

impl Borrowed {
    pub(crate) fn new() -> Self {
        Borrowed {
            identity: identity(),
            sik: Judgement {
                kind: RadioKind::Sik,
                radio_type: RadioType::Auto,
                evidence: vec!["compid 68 and no HEARTBEAT from 51/68".into()],
            },
            mlrs: Judgement {
                kind: RadioKind::Mlrs,
                radio_type: RadioType::Auto,
                evidence: vec!["HEARTBEAT type GENERIC, autopilot INVALID from 51/68".into()],
            },
            steps: steps(),
            flight: flight(),
            sources: {
                let mut table = crate::engine::probe::passive::tracker::SourceTable::new(None, 2);
                for seq in [0, 1, 3] {
                    table.on_frame(ONE, seq, 30, 39, u64::from(seq) * 20_000_000);
                }
                SourcesNow {
                    at: 1_000_000_000,
                    table: table.summary(1_000_000_000),
                    // 1/1's newest frame a queue's 240 ms late.
                    ages: vec![(
                        SysComp::new(1, 1),
                        AgeNow {
                            clock: StampClock::BootMs,
                            meaning: StampMeaning::Sent,
                            age_ms: 240.0,
                            at: 1_000_000_000,
                        },
                    )],
                    // Its 40 frames so far: 30 at 1 ms or less, 8 under
                    // 250 ms, 2 under 500 ms; 3.5 s in all.
                    age_counts: vec![(
                        SysComp::new(1, 1),
                        AgeCounts {
                            buckets: [30, 0, 0, 0, 0, 0, 8, 2, 0, 0, 0, 0, 0],
                            sum_ms: 3500.0,
                            count: 40,
                        },
                    )],
                    // The oldest of them since the last telling.
                    age_max: vec![(SysComp::new(1, 1), 310.0)],
                }
            },
        }
    }
}

/// A log's timeline: a radio and a vehicle moving away, a window that
/// loses a fifth (a burst), a silence.
pub(crate) fn flight() -> (Vec<FlightEvent>, FlightSummary) {
    use crate::frame::{Fix, FixKind, Msg, RadioStatus};
    let s = 1_000_000_000;
    let mut f = Flight::new(10 * s, 2 * s, RadioType::Auto);
    let mut totals = Totals::default();
    let mut events = Vec::new();
    for k in 0..4u64 {
        let at = k * 10 * s + s;
        let status = RadioStatus {
            rssi: 200 - k as u8,
            remrssi: 190,
            noise: 40,
            remnoise: 255,
            rxerrors: 65_534u16.wrapping_add(k as u16),
            ..RadioStatus::default()
        };
        f.on_frame(RADIO_SOURCE, &Msg::RadioStatus(status), at);
        let fix = Fix {
            kind: FixKind::Estimate,
            lat: 470_000_000 + k as i32 * 10_000,
            lon: 80_000_000,
            alt_mm: 500_000,
        };
        // The positions are the vehicle's only frames, 10 s apart and
        // none at 21 s: two silences.
        if k != 2 {
            f.on_frame(ONE, &Msg::Fix(fix), at);
        }
        totals.received += 80;
        totals.lost += if k == 1 { 20 } else { 0 };
        f.close(totals);
        events.extend(f.drain());
    }
    let summary = f.summary(45 * s, totals);
    (events, summary)
}

/// A PING (or TIMESYNC) run: every echo event, figures so far, the summary.
pub(crate) fn echo_run<'a>(probe: &'static str, borrowed: &'a Borrowed) -> Vec<Told<'a>> {
    let reply = |seq, at, out_of_order| {
        kind(MatchEvent::Reply {
            responder: ONE,
            seq,
            rtt: 10_123_456,
            sent_at: at - 10_123_456,
            at,
            out_of_order,
            first_from_responder: seq == 0,
        })
    };
    let mut told = vec![Told::Start(start(probe))];
    told.extend(
        [
            Event::WaitingForPeer,
            Event::Heard {
                id: ONE,
                identity: &borrowed.identity,
            },
            reply(0, 110_123_456, false),
            reply(2, 310_000_001, true),
            kind(MatchEvent::Lost {
                responder: ONE,
                seq: 1,
                sent_at: 200_000_000,
                at: 2_200_000_000,
            }),
            kind(MatchEvent::Late {
                responder: ONE,
                seq: 1,
                rtt: 2_500_000_001,
                sent_at: 200_000_000,
                at: 2_700_000_001,
            }),
            kind(MatchEvent::Duplicate {
                responder: ONE,
                seq: 2,
                rtt: 12_000_000,
                sent_at: 300_000_000,
                at: 312_000_000,
            }),
            kind(MatchEvent::Stale {
                responder: TWO,
                at: 400_000_000,
            }),
            Event::Radio(RadioHeard {
                id: RADIO,
                at: 1_000_000_000,
                report: radio_report(120),
                judgement: &borrowed.sik,
                first: true,
                kind_changed: false,
            }),
            // Not written: only each radio's first report is, and those
            // its kind changed with.
            Event::Radio(RadioHeard {
                id: RADIO,
                at: 2_000_000_000,
                report: radio_report(110),
                judgement: &borrowed.sik,
                first: false,
                kind_changed: false,
            }),
            Event::Radio(RadioHeard {
                id: RADIO,
                at: 2_100_000_000,
                report: radio_report(110),
                judgement: &borrowed.mlrs,
                first: false,
                kind_changed: true,
            }),
            // Not written: the summary has the clock, the nodes' counts
            // and the link's error.
            Event::Progress {
                at: 1_000_000_000,
                requests: 4,
            },
            Event::LinkNode {
                id: ONE,
                at: 1_500_000_000,
                report: LinkNodeReport {
                    messages_received: 4,
                    ..LinkNodeReport::default()
                },
                first: true,
            },
            Event::Clock {
                id: ONE,
                at: 2_000_000_000,
                clock: clock(true),
            },
            Event::LinkFailed {
                at: 2_900_000_000,
                error: "the link broke",
            },
        ]
        .map(Told::Event),
    );
    told.push(Told::Interim(Interim::new(EchoInterim {
        at: 2_500_000_000,
        requests: 8,
        responders: vec![responder(ONE, true), responder(TWO, false)],
    })));
    let summary = echo_summary(probe);
    let verdict = verdict::judge(&summary, &thresholds());
    told.push(Told::Summary(LinkSummary::new(summary), verdict));
    told
}

pub(crate) fn steps() -> Vec<StepFigures> {
    let mut steps = vec![
        StepFigures::test(Phase::Baseline, 10.0, 0.0),
        StepFigures::test(Phase::Ramp, 10.0, 0.0),
        StepFigures::test(Phase::Ramp, 20.0, 0.0),
        StepFigures::test(Phase::Refine, 35.0, 0.002),
        StepFigures::test(Phase::Ramp, 50.0, 0.3),
        StepFigures::test(Phase::Loaded, 10.0, 0.0),
    ];
    for (i, s) in steps.iter_mut().enumerate() {
        s.index = i as u32 + 1;
        s.start_s = i as f64 * 1.1;
        s.load = matches!(s.phase, Phase::Loaded);
        s.passed = s.phase.sweeps().then_some(s.loss_ratio < 0.01);
    }
    steps[3].rtt = None;
    steps[4].complete = false;
    steps[5].radio = Some(StepRadio {
        id: RADIO,
        reports: 2,
        txbuf_min: Some(80),
        txbuf_mean: Some(85.5),
        rssi_mean: Some(110.0),
        remrssi_mean: None,
        rxerrors_delta: 1,
    });
    steps
}

pub(crate) fn load() -> Vec<LoadSpec> {
    vec![
        LoadSpec {
            kind: LoadKind::Attitude,
            rate: 20.0,
        },
        LoadSpec {
            kind: LoadKind::Bytes,
            rate: 100.5,
        },
    ]
}

/// A `--sweep` (or `--load`) run: its plan, a line per step, and the
/// summary with every step and what they say.
pub(crate) fn sweep_run(plan: PlanKind, borrowed: &Borrowed) -> Vec<Told<'_>> {
    let mut told = vec![Told::Start(StartInfo {
        count: None,
        plan: Some(Arc::new(SweepConfig {
            plan,
            step: Duration::from_millis(1500),
            load: load(),
            load_bytes_per_s: 1_234.5,
        })),
        ..start("ping")
    })];
    told.extend(borrowed.steps.iter().map(|s| Told::Event(Event::Kind(s))));
    let kind = match plan {
        PlanKind::Sweep { .. } => "sweep",
        PlanKind::Load { .. } => "load",
    };
    let steps = borrowed.steps.clone();
    let summary = EchoSummary {
        sweep: Some(Box::new(SweepSummary {
            kind,
            knee: sweep_verdict::knee(&steps),
            queueing: sweep_verdict::queueing(&steps),
            reference_p99_us: sweep_verdict::reference_p99(&steps),
            load: Load::new(&load(), Version::V2, false).summary(),
            load_effect: sweep_verdict::load_effect(&steps),
            steps,
            ending: SweepEnd::LossLimit,
        })),
        ..echo_summary("ping")
    };
    let verdict = verdict::judge(&summary, &Thresholds::default());
    told.push(Told::Summary(LinkSummary::new(summary), verdict));
    told
}

pub(crate) fn command_summary() -> CommandSummary {
    let mut time_to_ack = RttStats::new();
    time_to_ack.record(3_000_000);
    time_to_ack.record(103_500_000);
    CommandSummary {
        link: "sim:?seed=1".into(),
        ours: SysComp::new(250, 190),
        command: 512,
        command_name: "REQUEST_MESSAGE".into(),
        duration_s: 2.5,
        in_flight: 1,
        targets: vec![CommandTargetSummary {
            id: ONE,
            commands: 4,
            acknowledged: 2,
            failed: 1,
            skipped: 1,
            late_acks: 1,
            duplicate_acks: 1,
            attempts: vec![1, 1],
            time_to_ack: time_to_ack.summary(),
            histogram: time_to_ack.distribution(2),
            results: vec![AckResult {
                result: 0,
                name: "ACCEPTED".into(),
                count: 2,
            }],
            identity: Some(identity()),
        }],
        hints: vec![],
        unmatched_acks: 2,
        frames: ScanStats {
            frames: 12,
            ..ScanStats::default()
        },
        interrupted: true,
        link_error: None,
        signing: crate::frame::signing::Gate::new(None).summary(),
        answered: answered(),
        link_node: link_nodes(false),
    }
}

/// A `--probe command` run: every command event, and its summary.
pub(crate) fn command_run() -> Vec<Told<'static>> {
    let mut told = vec![Told::Start(StartInfo {
        plan: Some(Arc::new(CommandSpec {
            target: ONE,
            command: 512,
            // f32 params: written as the f64 they widen to.
            params: [0.0, 0.1, 2.5, -3.3, 1e-7, 65_535.0, 7.0],
            retry_interval: Duration::from_millis(100),
            retries: 3,
        })),
        ..start("command")
    })];
    told.extend(
        [
            // Not written: each transmission is in the summary's counts.
            CommandEvent::Send {
                n: 0,
                target: ONE,
                command: 512,
                attempt: 1,
            },
            CommandEvent::Acked {
                n: 0,
                target: ONE,
                from: ONE,
                command: 512,
                result: 0,
                attempts: 1,
                time_to_ack: 3_000_000,
            },
            CommandEvent::Failed {
                n: 1,
                target: ONE,
                command: 512,
                attempts: 4,
            },
            CommandEvent::Skipped {
                target: ONE,
                command: 512,
                at: 1_200_000_000,
            },
            CommandEvent::LateAck {
                from: ONE,
                command: 512,
                result: 0,
            },
            CommandEvent::DuplicateAck {
                from: ONE,
                command: 512,
                result: 4,
            },
        ]
        .map(|e| Told::Event(kind(e))),
    );
    // Not written: a command run writes its commands' events only.
    told.push(Told::Event(Event::WaitingForPeer));
    let summary = command_summary();
    let verdict = verdict::judge_command(&summary);
    told.push(Told::Summary(LinkSummary::new(summary), verdict));
    told
}

/// A download's figures: the first complete after re-reads, the second
/// stalled.
pub(crate) fn attempt(n: u32, complete: bool) -> AttemptFigures {
    use crate::engine::probe::transfer::attempt::Counts as TransferCounts;
    use crate::engine::probe::transfer::progress::ProgressFigures;
    AttemptFigures {
        attempt: n,
        responder: Some(ONE),
        ending: if complete {
            Ending::Complete
        } else {
            Ending::Stalled
        },
        reason: (!complete).then(|| {
            "2 of 10 missing after the list, 1 re-requests answered, 1 never arrived".into()
        }),
        stopped_after: (!complete).then_some(7),
        unit: "parameters",
        progress: ProgressFigures {
            total: Some(10),
            received: if complete { 10 } else { 9 },
            time_to_first_ms: Some(12.5),
            time_to_95_ms: complete.then_some(2_050.0),
            time_to_100_ms: complete.then_some(2_060.0),
            longest_stall_ms: 2_000.0,
            stalled_at: 8,
            frames: 11,
            wire_bytes: 407,
            per_s: complete.then_some(10.0 / 2.06),
            wire_bytes_per_s: Some(197.6),
        },
        counts: TransferCounts {
            requests: 3,
            first_pass: 8,
            re_requests: 2,
            re_requests_answered: if complete { 2 } else { 1 },
            duplicates: 1,
            given_up: u64::from(!complete),
        },
        missing_first_pass: Some(2),
        wire_floor_ms: complete.then_some(70.7),
        duration_ms: if complete { 2_060.0 } else { 8_000.0 },
    }
}

/// A `--probe params -c 2` run: its progress, two downloads (one
/// stalled), the TIMESYNC round trip beside them.
pub(crate) fn transfer_run() -> Vec<Told<'static>> {
    use crate::engine::probe::transfer::summary::{LatencyBeside, Tally};
    use crate::engine::probe::transfer::{TransferKind, TransferSpec, TransferSummary};
    let spec = TransferSpec {
        kind: TransferKind::Params,
        target: ONE,
        timeout: Duration::from_secs(2),
        retries: 3,
        window: 4,
    };
    let mut told = vec![Told::Start(StartInfo {
        plan: Some(Arc::new(spec.clone())),
        ..start("params")
    })];
    let progress = TransferProgress {
        attempt: 1,
        elapsed_ms: 250.0,
        received: 6,
        total: Some(10),
    };
    told.push(Told::Event(kind(progress)));
    let mut tally = Tally::default();
    for a in [attempt(1, true), attempt(2, false)] {
        tally.add(&a);
        told.push(Told::Event(kind(a)));
    }
    let mut rtt = RttStats::new();
    rtt.record(21_000_000);
    let summary = TransferSummary {
        link: "sim:?seed=1".into(),
        ours: SysComp::new(250, 190),
        plan: spec,
        duration_s: 12.1,
        attempts: tally.attempts,
        complete: tally.complete,
        time_to_complete: tally.times(),
        missing_first_pass: tally.missing_first_pass,
        requests: tally.requests,
        re_requests: tally.re_requests,
        given_up: tally.given_up,
        last: tally.last.clone(),
        first_failed: None,
        latency: Some(LatencyBeside {
            responder: ONE,
            counts: Counts {
                sent: 12,
                received: 11,
                lost: 1,
                ..Counts::default()
            },
            rtt: rtt.summary(),
        }),
        hints: vec![Hint::new(
            HintCode::TransferStalled,
            "the parameter list stopped coming and asking again did not finish it",
        )],
        frames: ScanStats {
            frames: 30,
            ..ScanStats::default()
        },
        interrupted: false,
        link_error: None,
        signing: crate::frame::signing::Gate::new(None).summary(),
        answered: answered(),
        link_node: link_nodes(false),
    };
    let verdict = verdict::judge_transfer(
        &summary,
        &Thresholds {
            max_transfer_time: Some(Duration::from_secs(2)),
            ..Thresholds::default()
        },
    );
    told.push(Told::Summary(LinkSummary::new(summary), verdict));
    told
}

/// A `--passive` run: two sources with losses, a duplicate, a swap and a
/// silence, the SiK radio apart, one source beyond a table of two.
pub(crate) fn passive_run(borrowed: &Borrowed) -> Vec<Told<'_>> {
    use crate::engine::probe::passive::tracker::SourceTable;
    use crate::engine::summary::passive::PassiveSummary;
    let mut table = SourceTable::new(None, 2);
    let ms = 1_000_000;
    let seqs: [u8; 10] = [0, 1, 2, 4, 4, 6, 5, 7, 8, 9];
    for (k, &seq) in seqs.iter().enumerate() {
        table.on_frame(ONE, seq, 30, 39, k as u64 * 20 * ms);
        table.on_frame(TWO, seq.wrapping_add(250), 0, 21, k as u64 * 20 * ms);
    }
    table.on_frame(RADIO_SOURCE, 0, 109, 38, 100 * ms);
    table.on_frame(SysComp::new(9, 9), 0, 0, 21, 100 * ms);
    // The figures so far, before the silence ended.
    let interim = Interim::new(PassiveInterim {
        at: 1_000 * ms,
        table: table.summary(1_000 * ms),
        identities: vec![(ONE, identity())],
        ages: ages(),
    });
    table.on_frame(ONE, 10, 30, 39, 3_000 * ms);
    let summary = PassiveSummary {
        link: "sim:?seed=1".into(),
        ours: SysComp::new(250, 190),
        heartbeat: true,
        duration_s: 3.5,
        table: table.summary(3_500 * ms),
        identities: vec![(ONE, identity())],
        own_frames: 1,
        radios: radios(),
        frames: ScanStats::default(),
        rx_clock: RxClock::Simulated,
        interrupted: false,
        link_error: None,
        signing: crate::frame::signing::Gate::new(None).summary(),
        answered: answered(),
        age: ages(),
        hints: queue_hints(),
        link_node: link_nodes(false),
        log: None,
        per_link: None,
        round_trips: None,
        flight: None,
    };
    let verdict = verdict::judge_passive(
        &summary,
        &Thresholds {
            max_loss: Some(0.01),
            ..Thresholds::default()
        },
    );
    vec![
        Told::Start(StartInfo {
            probe: ProbeName::Passive,
            count: None,
            plan: Some(Arc::new(PassivePlan {
                heartbeat: true,
                log: false,
            })),
            ..start("ping")
        }),
        Told::Event(Event::Kind(&borrowed.sources)),
        Told::Interim(interim),
        Told::Summary(LinkSummary::new(summary), verdict),
    ]
}

/// A telemetry log read: a vehicle on MAVProxy's links 0 and 1 (link 1
/// loses a frame), MAVProxy's own frames on link 3, junk and a cut last
/// record.
pub(crate) fn log_run(borrowed: &Borrowed) -> Vec<Told<'_>> {
    use crate::engine::probe::passive::links::per_link;
    use crate::engine::probe::passive::tracker::SourceTable;
    use crate::engine::summary::passive::PassiveSummary;
    use crate::transport::tlog::records::RecordStats;
    use crate::transport::tlog::stamps::StampFacts;
    use crate::transport::tlog::LogFacts;
    let ms = 1_000_000;
    let mut merged = SourceTable::new(None, 32);
    let mut paths: Vec<SourceTable> = (0..4).map(|_| SourceTable::new(None, 32)).collect();
    let mut feed = |source, seq: u8, link: usize, at| {
        merged.on_frame(source, seq, 30, 39, at);
        paths[link].on_frame(source, seq, 30, 39, at);
    };
    for seq in 0..40u8 {
        let at = u64::from(seq) * 20 * ms;
        feed(ONE, seq, 0, at);
        if seq != 7 {
            feed(ONE, seq, 1, at + ms);
        }
        feed(TWO, seq, 3, at + 2 * ms);
    }
    let table = merged.summary(800 * ms);
    let by_path: Vec<_> = paths.iter().map(|t| t.summary(800 * ms)).collect();
    let summary = PassiveSummary {
        link: "tlog:flight.tlog".into(),
        ours: SysComp::new(250, 190),
        heartbeat: false,
        duration_s: 0.8,
        per_link: per_link(&table, &by_path),
        round_trips: None,
        table,
        identities: vec![(ONE, identity())],
        own_frames: 0,
        radios: Vec::new(),
        frames: ScanStats::default(),
        rx_clock: RxClock::Log,
        interrupted: false,
        link_error: None,
        signing: crate::frame::signing::Gate::new(None).summary(),
        answered: answered(),
        age: ages(),
        hints: queue_hints(),
        link_node: vec![],
        flight: Some(borrowed.flight.1.clone()),
        log: Some(LogFacts {
            records: RecordStats {
                records: 119,
                unknown_id: 1,
                damaged: 2,
                junk_bytes: 12,
                junk_stretches: 1,
                bad_crc: 1,
                truncated_bytes: 5,
            },
            stamps: StampFacts {
                first_us: 1_764_500_000_000_000,
                latest_us: 1_764_500_000_782_000,
                behind: 0,
                steps: 0,
                whole_ms: false,
                low_bits: [40, 39, 0, 40],
            },
            complete: true,
        }),
    };
    assert!(summary.per_link.is_some());
    let verdict = verdict::judge_passive(&summary, &Thresholds::default());
    vec![Told::Start(StartInfo {
        link: "tlog:flight.tlog".into(),
        probe: ProbeName::Passive,
        count: None,
        plan: Some(Arc::new(PassivePlan {
            heartbeat: false,
            log: true,
        })),
        ..start("ping")
    })]
    .into_iter()
    .chain(
        borrowed
            .flight
            .0
            .iter()
            .map(|e| Told::Event(Event::Kind(e))),
    )
    .chain([Told::Summary(LinkSummary::new(summary), verdict)])
    .collect()
}

/// A C2 link report over a 600 s run, every part filled: outages in
/// three bands (one still open at the end, its distance unknown), four
/// distance bands (the farthest under the 99 % floor), and three
/// failsafes (ArduCopter's, ArduPlane's two stages, a ground station's
/// own check of the vehicle's TIMESYNC). Its figures agree with each
/// other: the outages add up to the down time, each outage is its
/// silence less the 2 s rule.
pub(crate) fn c2_report() -> C2Report {
    let outage = |start_s: f64, duration_s, distance_m, open| Outage {
        start_s,
        duration_s,
        silence_s: duration_s + 2.0,
        distance_m,
        open,
        at_utc: Some(format!("2026-12-05T10:{:02.0}:00Z", start_s / 60.0)),
    };
    let band = |band, count, total_s| Band {
        band,
        count,
        total_s,
    };
    let distance = |from_m: f64, observed_s: f64, down_s: f64, outages| DistanceBand {
        from_m,
        to_m: from_m + 250.0,
        observed_s,
        down_s,
        availability_pct: 100.0 * (observed_s - down_s) / observed_s,
        outages,
    };
    let trip = |at_s, lasted_s, open, long| Trip {
        at_s,
        lasted_s,
        open,
        long,
    };
    let up = |model: &str, setting: &str, timeout_s, long_timeout_s| FailsafeReplay {
        model: model.into(),
        setting: setting.into(),
        direction: "up",
        message: "HEARTBEAT",
        rate_hz: 1.0,
        timeout_s,
        long_timeout_s,
        basis: "downlink",
        inferred: true,
        messages: 600,
        delivered: 591,
        trips: 0,
        long_trips: 0,
        trip_list: vec![],
        closest_wait_s: None,
        closest_margin_s: None,
        closest_at_s: None,
        expected_if_independent: None,
    };
    C2Report {
        started_utc: Some("2026-12-05T10:00:00.000000Z".into()),
        rule: C2Rule {
            up_within_s: 2.0,
            continuity_within_s: 1.0,
            distance_band_m: 250.0,
            availability_floor_pct: 99.0,
        },
        duration_s: 600.0,
        down_s: 9.5,
        availability_pct: Some(100.0 * 590.5 / 600.0),
        frames: 5990,
        continuity: Some(Continuity {
            within: 1170,
            transactions: 1200,
            pct: 97.5,
            from: "probes",
        }),
        latency: Latency {
            round_trip: Some(Percentiles {
                count: 1180,
                p50_ms: 45.2,
                p99_ms: 180.5,
                p999_ms: 950.0,
                max_ms: 1900.0,
            }),
            uplink: Some(OneWay {
                p50_ms: 3.1,
                p99_ms: 60.2,
                max_ms: 400.0,
            }),
            downlink: Some(OneWay {
                p50_ms: 1.2,
                p99_ms: 20.4,
                max_ms: 150.0,
            }),
            downlink_from: Some("round_trip_split"),
        },
        loss: DirectionLoss {
            downlink_pct: Some(0.5),
            uplink_pct: Some(1.2),
            uplink_from: Some("direction_split"),
            round_trip_pct: Some(1.7),
        },
        outages: Outages {
            count: 4,
            total_s: 9.5,
            bands: vec![
                band("<1s", 1, 0.5),
                band("1-3s", 2, 3.5),
                band("3-10s", 1, 5.5),
                band("10-30s", 0, 0.0),
                band(">30s", 0, 0.0),
            ],
            longest: vec![
                outage(420.0, 5.5, Some(912.0), false),
                outage(120.5, 2.0, Some(240.0), false),
                outage(598.5, 1.5, None, true),
                outage(300.0, 0.5, Some(600.0), false),
            ],
        },
        // 8 s bins over 600 s: each outage's time in the bins it spans.
        timeline: Timeline {
            bin_s: 8.0,
            down_s: (0..75)
                .map(|bin| match bin {
                    15 => 2.0,
                    37 => 0.5,
                    52 => 4.0,
                    53 | 74 => 1.5,
                    _ => 0.0,
                })
                .collect(),
        },
        distance: vec![
            distance(0.0, 300.0, 2.0, 1),
            distance(250.0, 150.0, 0.0, 0),
            distance(500.0, 100.0, 0.5, 1),
            distance(750.0, 40.0, 5.5, 1),
        ],
        availability_under_floor_from_m: Some(750.0),
        failsafes: vec![
            FailsafeReplay {
                trips: 1,
                trip_list: vec![trip(424.0, 2.0, false, false)],
                closest_wait_s: Some(4.0),
                closest_margin_s: Some(1.0),
                closest_at_s: Some(124.0),
                expected_if_independent: Some(1.475e-7),
                ..up("ardupilot-copter", "FS_GCS_TIMEOUT=5s", 5.0, None)
            },
            FailsafeReplay {
                trips: 3,
                long_trips: 1,
                trip_list: vec![
                    trip(121.5, 0.5, false, false),
                    trip(420.5, 5.5, false, true),
                    trip(599.5, 0.5, true, false),
                ],
                expected_if_independent: Some(0.0103),
                ..up(
                    "ardupilot-plane",
                    "FS_SHORT_TIMEOUT=1.5s FS_LONG_TIMEOUT=5s",
                    1.5,
                    Some(5.0),
                )
            },
            FailsafeReplay {
                model: "custom".into(),
                setting: "TIMESYNC@2Hz timeout 3s".into(),
                direction: "down",
                message: "TIMESYNC",
                rate_hz: 2.0,
                timeout_s: 3.0,
                long_timeout_s: None,
                basis: "received",
                inferred: false,
                messages: 1200,
                delivered: 1188,
                trips: 2,
                long_trips: 0,
                trip_list: vec![
                    trip(421.0, 4.5, false, false),
                    trip(599.5, 0.5, true, false),
                ],
                closest_wait_s: Some(2.5),
                closest_margin_s: Some(0.5),
                closest_at_s: Some(122.0),
                expected_if_independent: Some(0.012),
            },
        ],
    }
}

/// A TIMESYNC run with a C2 link report over it (`--report c2`).
pub(crate) fn c2_run(borrowed: &Borrowed) -> Vec<Told<'_>> {
    let mut told = echo_run("timesync", borrowed);
    if let Some(Told::Summary(summary, _)) = told.last_mut() {
        summary.set_c2(c2_report());
    }
    told
}

/// The kinds of run, each with what it writes.
#[derive(Debug, Clone, Copy)]
pub(crate) enum Run {
    Echo(&'static str),
    Sweep(PlanKind),
    Command,
    Passive,
    Log,
    Transfer,
    /// A run whose summary carries a C2 link report.
    C2,
}

pub(crate) const RUNS: [Run; 11] = [
    Run::Echo("ping"),
    Run::Echo("timesync"),
    Run::Sweep(PlanKind::Sweep {
        first_hz: 10.0,
        max_hz: 244.9,
        max_from: MaxFrom::Baud {
            baud: 57_600,
            capacity_hz: 122.45,
        },
        loss_limit: 0.2,
    }),
    Run::Sweep(PlanKind::Sweep {
        first_hz: 1.0,
        max_hz: 100.0,
        max_from: MaxFrom::Given,
        loss_limit: 0.05,
    }),
    Run::Sweep(PlanKind::Sweep {
        first_hz: 5.0,
        max_hz: 1000.0,
        max_from: MaxFrom::Default,
        loss_limit: 0.5,
    }),
    Run::Sweep(PlanKind::Load { rate_hz: 10.0 }),
    Run::Command,
    Run::Passive,
    Run::Log,
    Run::Transfer,
    Run::C2,
];

impl Run {
    pub(crate) fn told(self, borrowed: &Borrowed) -> Vec<Told<'_>> {
        match self {
            Run::Echo(probe) => echo_run(probe, borrowed),
            Run::Sweep(plan) => sweep_run(plan, borrowed),
            Run::Command => command_run(),
            Run::Passive => passive_run(borrowed),
            Run::Log => log_run(borrowed),
            Run::Transfer => transfer_run(),
            Run::C2 => c2_run(borrowed),
        }
    }
}
