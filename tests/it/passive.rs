//! `--passive`: no probes, each source's frames counted from its packet
//! sequence numbers, held exactly against links whose faults we control:
//! the simulated link's per-direction truth, and a pymavlink vehicle
//! that numbers frames it never sends, sends some twice, swaps pairs and
//! goes silent for longer than the 8-bit sequence can span.

use serde_json::Value;

use crate::common::*;

/// The `passive_summary` line of a `--json` run.
fn summary(stdout: &str) -> Value {
    let line = stdout
        .lines()
        .find(|l| l.contains("\"passive_summary\""))
        .unwrap_or_else(|| panic!("no passive_summary in\n{stdout}"));
    serde_json::from_str(line).unwrap()
}

/// The summary's figures for `sysid/compid`.
fn source(s: &Value, sysid: u64, compid: u64) -> &Value {
    s["sources"]
        .as_array()
        .unwrap()
        .iter()
        .find(|r| r["source"]["sysid"] == sysid && r["source"]["compid"] == compid)
        .unwrap_or_else(|| panic!("no {sysid}/{compid} in {s}"))
}

fn count(v: &Value, key: &str) -> u64 {
    v["counts"][key].as_u64().unwrap()
}

#[test]
fn sim_losses_duplicates_and_reorders_per_source_equal_the_links_truth() {
    let link = "sim:?clock=virtual&responders=2&stream=ATTITUDE@50,GLOBAL_POSITION_INT@5\
                &loss_down=5%&dup_down=2%&reorder_down=2%&seed=3";
    let (code, out, err) = run_mavping(&["--passive", "-w", "10", "--json", "-v", link]);
    assert_eq!(code, 0, "{out}{err}");
    let s = summary(&out);
    assert_eq!(s["probe"], "passive");
    for (sysid, id) in [(1, "1/1"), (2, "2/1")] {
        let r = source(&s, sysid, 1);
        let truth = |k| sim_truth(&err, id, k);
        // 561 frames each: the sequence wraps twice.
        assert!(truth("down_sent") > 512, "{err}");
        assert!(truth("down_dropped") > 10, "{err}");
        assert_eq!(count(r, "lost"), truth("down_dropped"), "{id}: {r}");
        assert_eq!(
            count(r, "duplicate"),
            truth("down_duplicates_arrived"),
            "{id}: {r}"
        );
        assert_eq!(count(r, "reordered"), truth("down_reordered"), "{id}: {r}");
        assert_eq!(
            count(r, "received"),
            truth("down_delivered") + truth("down_duplicates_arrived"),
            "{id}: {r}"
        );
        // pymavlink's figure counts each duplicate and reorder as ~255 lost.
        assert!(r["pymav"]["loss"].as_u64().unwrap() > 255 * count(r, "duplicate"));
    }
}

#[test]
fn a_silence_longer_than_the_sequence_counts_its_gap_and_estimates_its_wraps() {
    // 8 s without a frame at 50/s: 400 frames, which a wrapping 8-bit
    // counter aliases to 144. The sequence proves those 144; the rate
    // says 256 more are likely, said apart and not counted.
    let link = "sim:?clock=virtual&heartbeat=off&stream=ATTITUDE@50&outage=2s+8s&seed=4";
    let (code, out, err) = run_mavping(&["--passive", "-w", "12", "--json", "-v", link]);
    assert_eq!(code, 0, "{out}{err}");
    let s = summary(&out);
    let r = source(&s, 1, 1);
    let dropped = sim_truth(&err, "1/1", "down_dropped");
    assert!((395..=405).contains(&dropped), "{err}");
    let proven = dropped % 256;
    assert_eq!(count(r, "lost"), proven, "{r}");
    assert_eq!(r["silence_count"], 1, "{r}");
    let silence = &r["silences"][0];
    assert_eq!(silence["seq_lost"].as_u64(), Some(proven), "{r}");
    assert_eq!(silence["restart"], false, "{r}");
    // Estimates from the source's rate: within a frame of the truth.
    let estimated = silence["frames_estimated"].as_u64().unwrap();
    assert!(estimated.abs_diff(dropped) <= 1, "{dropped}: {r}");
    let likely = silence["lost_estimated"].as_u64().unwrap();
    assert!(likely.abs_diff(dropped) <= 1, "{dropped}: {r}");
    // Only the wraps are "estimated": the proven gap is in `lost` alone.
    assert_eq!(likely % 256, proven, "{r}");
    assert_eq!(
        r["silence_frames_estimated"].as_u64(),
        Some(likely - proven)
    );
    let ms = silence["length_ns"].as_u64().unwrap() / 1_000_000;
    assert!((7_990..=8_050).contains(&ms), "{r}");
    // pymavlink's figure is the alias too.
    assert_eq!(r["pymav"]["loss"].as_u64(), Some(proven), "{r}");
    let (_, text, _) = run_mavping(&["--passive", "-w", "12", link]);
    assert!(
        text.contains(&format!(
            "{proven} frames lost by the sequence, ~{likely} likely at its rate \
             (its 8-bit counter wrapped in it, as the rate says: the {} more are not counted)",
            likely - proven
        )),
        "{text}"
    );
}

#[test]
fn a_pymavlink_vehicle_is_counted_exactly_over_udp() {
    let port = free_udp_port();
    let vehicle = Peer::start(
        "vehicle.py",
        &[
            &format!("udpin:127.0.0.1:{port}"),
            "--frames",
            "600",
            "--rate",
            "100",
            "--drop",
            "10,11,12,200",
            "--dup",
            "50,300",
            "--swap",
            "100,400",
            "--silence",
            "450:300",
        ],
    );
    let target = format!("udpout:127.0.0.1:{port}");
    let (code, out, err) = run_mavping(&["--passive", "-w", "14", "--json", &target]);
    let truth = vehicle.finish();
    assert_eq!(code, 0, "{out}{err}");
    let s = summary(&out);
    let r = source(&s, 1, 1);
    assert_eq!(truth["dropped"], 4, "{truth}");
    assert_eq!(truth["silenced"], 300, "{truth}");
    // The drops, and the silence's 300 numbers as the sequence proves
    // them: 300 modulo 256.
    assert_eq!(count(r, "lost"), 4 + 300 % 256, "{r}");
    assert_eq!(count(r, "duplicate"), 2, "{r}");
    assert_eq!(count(r, "reordered"), 2, "{r}");
    assert_eq!(count(r, "received"), truth["sent"].as_u64().unwrap(), "{r}");
    // The silence it was told to keep, and the one after its last frame,
    // still on when the run ended.
    assert_eq!(r["silence_count"], 2, "{r}");
    let (kept, after) = (&r["silences"][0], &r["silences"][1]);
    assert_eq!(
        (&kept["ongoing"], &after["ongoing"]),
        (&Value::Bool(false), &Value::Bool(true))
    );
    assert_eq!(kept["seq_lost"].as_u64(), Some(300 % 256), "{r}");
    let estimated = kept["frames_estimated"].as_u64().unwrap();
    assert!((270..=330).contains(&estimated), "{r}");
    // At its rate the silence likely held one more wrap: the 256 beyond
    // the proven 44 are said, not counted.
    let likely = kept["lost_estimated"].as_u64().unwrap();
    assert!((270..=330).contains(&likely), "{r}");
    assert_eq!(likely % 256, 300 % 256, "{r}");
    // Only the wraps are estimated; the silence still on at the end has
    // no gap yet, so it adds nothing.
    assert_eq!(
        r["silence_frames_estimated"].as_u64(),
        Some(likely - 300 % 256),
        "{r}"
    );
    // pymavlink's arithmetic on the same frames: each duplicate 255, each
    // swap 256, the drops as they are, the silence modulo 256.
    assert_eq!(
        r["pymav"]["loss"].as_u64(),
        Some(4 + 2 * 255 + 2 * 256 + 300 % 256),
        "{r}"
    );
    let identity = &r["identity"];
    assert_eq!(identity["autopilot_name"], "ardupilotmega", "{r}");
}

#[test]
fn nothing_heard_is_exit_1_and_a_count_is_refused() {
    let (code, out, _) = run_mavping(&["--passive", "-w", "2", "sim:?clock=virtual&heartbeat=off"]);
    assert_eq!(code, 1, "{out}");
    assert!(out.contains("FAILED heard: nothing heard"), "{out}");
    let (code, _, err) = run_mavping(&["--passive", "-c", "3", "sim:"]);
    assert_eq!(code, 2);
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(
        err.contains("'--passive' cannot be used with '--count"),
        "{err}"
    );
    // --max-loss holds for the sources' sequence loss.
    let lossy = "sim:?clock=virtual&stream=ATTITUDE@50&loss_down=20%&seed=5";
    let (code, out, _) = run_mavping(&["--passive", "-w", "5", "--max-loss", "5%", lossy]);
    assert_eq!(code, 1, "{out}");
    assert!(out.contains("FAILED max-loss: 1/1: sequence loss"), "{out}");
}

#[test]
fn a_probe_run_splits_its_loss_by_direction_as_the_link_lost_it() {
    // Requests lost on the way up, frames on the way down, in a vehicle
    // that streams telemetry beside its replies.
    let link = "sim:?clock=virtual&stream=ATTITUDE@50&loss_up=10%&loss_down=5%&seed=7";
    let (code, out, err) = run_mavping(&["-c", "1000", "-i", "20ms", "-q", "--json", "-v", link]);
    assert_eq!(code, 0, "{out}{err}");
    let line = out
        .lines()
        .find(|l| l.contains("\"type\":\"summary\""))
        .unwrap();
    let s: Value = serde_json::from_str(line).unwrap();
    let d = &s["responders"][0]["direction"];
    let truth = |k| sim_truth(&err, "1/1", k);
    // The downlink is counted exactly: every frame it numbered and lost.
    assert_eq!(
        d["downlink_lost"].as_u64(),
        Some(truth("down_dropped")),
        "{d}\n{err}"
    );
    let sent = truth("down_sent");
    let frames = d["downlink_frames"].as_u64().unwrap();
    assert!(frames <= sent && sent - frames <= 2, "{sent} {d}");
    // The uplink is inferred: within three standard errors of the truth.
    let up_truth = truth("up_requests_dropped") as f64 / 1000.0;
    let (up, e) = (
        d["uplink_loss"].as_f64().unwrap(),
        d["uplink_stderr"].as_f64().unwrap(),
    );
    assert!(
        (up - up_truth).abs() < 3.0 * e,
        "up {up} ± {e} vs {up_truth}"
    );
    assert!(e > 0.005 && e < 0.03, "{d}");
    assert_eq!(d["consistent"], true);
    // A clean link has nothing to split.
    let (_, clean, _) = run_mavping(&[
        "-c",
        "20",
        "-i",
        "20ms",
        "-q",
        "--json",
        "sim:?clock=virtual",
    ]);
    assert!(!clean.contains("\"direction\""), "{clean}");
}
