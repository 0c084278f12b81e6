//! One of every line the JSON reporter writes, told through its
//! `Observer` and `Reporter` interface as a run would: each line is checked
//! against the published schema, and all of them are pinned byte for byte
//! by a snapshot.

use std::time::{Duration, SystemTime};

use serde_json::Value;

use super::JsonReporter;
use crate::engine::clock_offset::ClockSummary;
use crate::engine::hint::{Hint, HintCode};
use crate::engine::load::{Load, LoadKind, LoadSpec};
use crate::engine::matcher::{Counts, MatchEvent};
use crate::engine::observe::CommandEvent;
use crate::engine::radio::{RadioReport, Radios, UNKNOWN};
use crate::engine::roster::Identity;
use crate::engine::stats::RttStats;
use crate::engine::summary::{
    AckResult, CommandSummary, CommandTargetSummary, Interim, LinkSummary, ResponderSummary,
    ScheduleSummary, Summary,
};
use crate::engine::sweep::step::{Phase, StepFigures, StepRadio};
use crate::engine::sweep::verdict::{self as sweep_verdict, Ending, SweepSummary};
use crate::engine::sweep::{MaxFrom, PlanKind, SweepConfig};
use crate::engine::{capacity, CommandSpec};
use crate::frame::{ScanStats, SysComp, Version};
use crate::output::{Event, Observer, Reporter, StartInfo, WallClock};
use crate::verdict::{self, Thresholds};

const ONE: SysComp = SysComp {
    sysid: 1,
    compid: 1,
};
const TWO: SysComp = SysComp {
    sysid: 2,
    compid: 1,
};
const RADIO: SysComp = SysComp {
    sysid: 51,
    compid: 68,
};

fn reporter(quiet: bool, link: Option<&str>) -> JsonReporter<Vec<u8>> {
    JsonReporter::new(
        Vec::new(),
        quiet,
        WallClock {
            start: SystemTime::UNIX_EPOCH,
        },
    )
    .with_link(link.map(String::from))
}

fn start(probe: &'static str) -> StartInfo {
    StartInfo {
        link: "sim:?seed=1".into(),
        probe,
        ours: SysComp::new(250, 190),
        interval: Duration::from_millis(100),
        timeout: Duration::from_secs(2),
        count: Some(10),
        command: None,
        sweep: None,
    }
}

fn identity() -> Identity {
    Identity {
        mav_type: 2,
        autopilot: 12,
        vehicle: "quadrotor".into(),
        autopilot_name: "px4".into(),
        first_heard: 12_000_000,
    }
}

fn radio_report(rssi: u8) -> RadioReport {
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

fn clock(bounds: bool) -> ClockSummary {
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

fn responder(id: SysComp, answered: bool) -> ResponderSummary {
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
        clock: None,
    }
}

fn radios() -> Vec<crate::engine::radio::RadioSummary> {
    let mut radios = Radios::default();
    radios.record(RADIO, radio_report(120), 1_000_000_000);
    radios.record(RADIO, radio_report(110), 2_000_000_000);
    radios.record(SysComp::new(52, 100), radio_report(UNKNOWN), 2_000_000_000);
    radios.summaries()
}

fn echo_summary(probe: &'static str) -> Summary {
    let mut first = responder(ONE, true);
    if probe == "timesync" {
        first.clock = Some(clock(true));
    }
    let mut second = responder(TWO, false);
    if probe == "timesync" {
        second.clock = Some(clock(false));
    }
    Summary {
        probe,
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
        }),
        rx_clock: "simulated arrival times",
        radios: radios(),
        wire: Some(capacity::budget(57_600, Version::V2, 99, 2)),
        ..Summary::empty("sim:?seed=1", 8)
    }
}

fn thresholds() -> Thresholds {
    Thresholds {
        max_loss: Some(0.01),
        ..Thresholds::default()
    }
}

/// A PING (or TIMESYNC) run: every echo event, figures so far, the summary.
fn echo_run(out: &mut JsonReporter<Vec<u8>>, probe: &'static str) {
    out.start(&start(probe)).unwrap();
    let identity = identity();
    let reply = |seq, at, out_of_order| {
        Event::Match(MatchEvent::Reply {
            responder: ONE,
            seq,
            rtt: 10_123_456,
            sent_at: at - 10_123_456,
            at,
            out_of_order,
            first_from_responder: seq == 0,
        })
    };
    for event in [
        Event::WaitingForPeer,
        Event::Heard {
            id: ONE,
            identity: &identity,
        },
        reply(0, 110_123_456, false),
        reply(2, 310_000_001, true),
        Event::Match(MatchEvent::Lost {
            responder: ONE,
            seq: 1,
            sent_at: 200_000_000,
            at: 2_200_000_000,
        }),
        Event::Match(MatchEvent::Late {
            responder: ONE,
            seq: 1,
            rtt: 2_500_000_001,
            sent_at: 200_000_000,
            at: 2_700_000_001,
        }),
        Event::Match(MatchEvent::Duplicate {
            responder: ONE,
            seq: 2,
            rtt: 12_000_000,
            sent_at: 300_000_000,
            at: 312_000_000,
        }),
        Event::Match(MatchEvent::Stale {
            responder: TWO,
            at: 400_000_000,
        }),
        Event::Radio {
            id: RADIO,
            at: 1_000_000_000,
            report: radio_report(120),
            first: true,
        },
        // Not written: only each radio's first report is.
        Event::Radio {
            id: RADIO,
            at: 2_000_000_000,
            report: radio_report(110),
            first: false,
        },
        // Not written: the summary has the clock and the link's error.
        Event::Clock {
            id: ONE,
            at: 2_000_000_000,
            clock: clock(true),
        },
        Event::LinkFailed {
            at: 2_900_000_000,
            error: "the link broke",
        },
    ] {
        out.event(&event).unwrap();
    }
    out.interim(&Interim {
        at: 2_500_000_000,
        requests: 8,
        responders: vec![responder(ONE, true), responder(TWO, false)],
    })
    .unwrap();
    let summary = echo_summary(probe);
    let verdict = verdict::judge(&summary, &thresholds());
    out.summary(&LinkSummary::Echo(Box::new(summary)), &verdict)
        .unwrap();
}

fn steps() -> Vec<StepFigures> {
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

fn load() -> Vec<LoadSpec> {
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
fn sweep_run(out: &mut JsonReporter<Vec<u8>>, plan: PlanKind) {
    out.start(&StartInfo {
        count: None,
        sweep: Some(SweepConfig {
            plan,
            step: Duration::from_millis(1500),
            load: load(),
            load_bytes_per_s: 1_234.5,
        }),
        ..start("ping")
    })
    .unwrap();
    let steps = steps();
    for step in &steps {
        out.event(&Event::Step(step)).unwrap();
    }
    let kind = match plan {
        PlanKind::Sweep { .. } => "sweep",
        PlanKind::Load { .. } => "load",
    };
    let summary = Summary {
        sweep: Some(Box::new(SweepSummary {
            kind,
            knee: sweep_verdict::knee(&steps),
            queueing: sweep_verdict::queueing(&steps),
            reference_p99_us: sweep_verdict::reference_p99(&steps),
            load: Load::new(&load(), Version::V2, false).summary(),
            load_effect: sweep_verdict::load_effect(&steps),
            steps,
            ending: Ending::LossLimit,
        })),
        ..echo_summary("ping")
    };
    let verdict = verdict::judge(&summary, &Thresholds::default());
    out.summary(&LinkSummary::Echo(Box::new(summary)), &verdict)
        .unwrap();
}

fn command_summary() -> CommandSummary {
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
        unmatched_acks: 2,
        frames: ScanStats {
            frames: 12,
            ..ScanStats::default()
        },
        interrupted: true,
        link_error: None,
        signing: crate::frame::signing::Gate::new(None).summary(),
    }
}

/// A `--probe command` run: every command event, and its summary.
fn command_run(out: &mut JsonReporter<Vec<u8>>) {
    out.start(&StartInfo {
        command: Some(CommandSpec {
            target: ONE,
            command: 512,
            // f32 params: written as the f64 they widen to.
            params: [0.0, 0.1, 2.5, -3.3, 1e-7, 65_535.0, 7.0],
            retry_interval: Duration::from_millis(100),
            retries: 3,
        }),
        ..start("command")
    })
    .unwrap();
    for event in [
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
    ] {
        out.event(&Event::Command(event)).unwrap();
    }
    // A command run writes its commands' events only.
    out.event(&Event::WaitingForPeer).unwrap();
    let summary = command_summary();
    let verdict = verdict::judge_command(&summary);
    out.summary(&LinkSummary::Command(Box::new(summary)), &verdict)
        .unwrap();
}

/// The kinds of run, each with what it writes.
#[derive(Clone, Copy)]
enum Run {
    Echo(&'static str),
    Sweep(PlanKind),
    Command,
}

const RUNS: [Run; 7] = [
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
];

/// Every run kind, quiet and not, alone and as one of several links.
fn every_line() -> String {
    let mut text = String::new();
    for (quiet, link) in [(false, None), (false, Some("the link")), (true, None)] {
        for run in RUNS {
            let mut out = reporter(quiet, link);
            match run {
                Run::Echo(probe) => echo_run(&mut out, probe),
                Run::Sweep(plan) => sweep_run(&mut out, plan),
                Run::Command => command_run(&mut out),
            }
            text.push_str(&String::from_utf8(out.out).unwrap());
        }
    }
    text
}

fn schema() -> jsonschema::Validator {
    let text = include_str!("../../../schema/mavping-events.schema.json");
    jsonschema::validator_for(&serde_json::from_str(text).unwrap()).unwrap()
}

#[test]
fn the_schema_accepts_every_line() {
    let schema = schema();
    for line in every_line().lines() {
        let value: Value = serde_json::from_str(line).unwrap();
        let errors: Vec<String> = schema.iter_errors(&value).map(|e| e.to_string()).collect();
        assert!(errors.is_empty(), "{line}\n{errors:#?}");
    }
}

#[test]
fn every_line_byte_for_byte() {
    insta::assert_snapshot!(every_line());
}
