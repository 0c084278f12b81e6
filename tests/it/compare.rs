//! `mavping compare A.json B.json`: runs saved by mavping itself against
//! truth the test controls (`sim:` runs with seeded loss and delay, logs
//! written by `tests/peers/tlog_writer.py` with losses planned window by
//! window along a route), compared: the counts are the runs' own, the
//! intervals hold the planned differences, the distance bands the planned
//! losses; bad input is refused in one line with exit 2, and a closed
//! pipe does not turn a failed comparison into a success.

use std::path::{Path, PathBuf};
use std::process::Stdio;
use std::time::Duration;

use serde_json::{json, Value};

use crate::common::*;
use crate::tlog::{tlog, write_log, Scratch};

/// Saves `mavping -v --json ARGS LINK` in `path`; its stderr (the sim's
/// truth).
fn save(path: &Path, args: &[&str], link: &str) -> String {
    let mut all = vec!["-v", "--json"];
    all.extend_from_slice(args);
    all.push(link);
    let (code, out, err) = run_mavping(&all);
    assert_eq!(code, 0, "{err}");
    assert_schema(&json_lines(&out));
    std::fs::write(path, &out).unwrap();
    err
}

/// `mavping compare --json ARGS`: exit code, the compare line (checked
/// against the schema), stderr.
fn compare_json(args: &[&str]) -> (i32, Value, String) {
    let mut all = vec!["compare", "--json"];
    all.extend_from_slice(args);
    let (code, out, err) = run_mavping(&all);
    let lines = json_lines(&out);
    assert_schema(&lines);
    assert_eq!(lines.len(), 1, "{out}{err}");
    (code, lines.into_iter().next().unwrap(), err)
}

fn path_str(p: &Path) -> &str {
    p.to_str().unwrap()
}

fn f(v: &Value, key: &str) -> f64 {
    v[key].as_f64().unwrap_or_else(|| panic!("{key} in {v}"))
}

/// A: 2 % of exchanges lost, 20 ms each way; B: 6 %, 35 ms; both with
/// 0-4 ms of jitter each way, so the true median RTT is 30 ms longer in
/// B and the true loss 4 points higher.
fn sim_link(delay_ms: u64, loss_pct: u64, seed: u64) -> String {
    format!("sim:?delay={delay_ms}ms&jitter=4ms&loss={loss_pct}%&seed={seed}&clock=virtual")
}

/// Twenty pairs of runs, each pair's seeds its own: each comparison's
/// counts are the runs' own and the sim's truth, its difference theirs;
/// the 95 % intervals hold the planned 4 points and 30 ms in at least 17
/// of the 20 (a 95 % interval misses one time in twenty: 16 or fewer
/// would happen 1.6 % of the time with exact intervals; the seeds are
/// fixed, so the outcome is too).
#[test]
fn two_sim_runs_compare_against_their_planned_loss_and_delay() {
    let dir = Scratch::new("compare-sim");
    let (a, b) = (dir.path("a.json"), dir.path("b.json"));
    let (mut loss_held, mut rtt_held) = (0, 0);
    for k in 0..20u64 {
        let args = ["-c", "1000", "-i", "10ms"];
        let truth_a = save(&a, &args, &sim_link(20, 2, 2 * k + 1));
        let truth_b = save(&b, &args, &sim_link(35, 6, 2 * k + 2));
        let (code, report, err) = compare_json(&[path_str(&a), path_str(&b)]);
        assert_eq!(code, 0, "{err}");
        assert!(err.is_empty(), "{err}");
        let links = report["links"].as_array().unwrap();
        assert_eq!(links.len(), 1, "{report}");
        assert_eq!(links[0]["paired_by"], "only_summary");
        let rows = links[0]["rows"].as_array().unwrap();
        assert_eq!(rows.len(), 1, "{report}");
        let row = &rows[0];
        assert_eq!(row["role"], "responder");
        assert_eq!(row["a_id"], json!({"sysid": 1, "compid": 1}));
        let loss = &row["loss"];
        for (side, path, truth) in [("a", &a, &truth_a), ("b", &b, &truth_b)] {
            let summary = summary_of(&std::fs::read_to_string(path).unwrap());
            let r = responder(&summary, "1/1");
            assert_eq!(loss[side]["lost"], r["lost"], "{side}: {loss}");
            assert_eq!(loss[side]["of"], r["sent"], "{side}: {loss}");
            // Requests lost before the responder's first reply are not
            // charged to it (the run cannot tell it was there yet).
            let before = sim_truth(truth, "1/1", "dropped_before_first");
            assert_eq!(n(r, "not_charged"), before);
            let dropped = sim_truth(truth, "1/1", "dropped");
            assert_eq!(n(&loss[side], "lost"), dropped - before, "{side}: {loss}");
            assert_eq!(n(&loss[side], "of"), 1000 - before, "{side}: {loss}");
        }
        let pct = |side: &str| 100.0 * n(&loss[side], "lost") as f64 / n(&loss[side], "of") as f64;
        let d = f(loss, "difference_pp");
        assert!((d - (pct("b") - pct("a"))).abs() < 1e-9, "{loss}");
        let (low, high) = (f(loss, "low_pp"), f(loss, "high_pp"));
        assert!(low < d && d < high, "{loss}");
        loss_held += u32::from(low <= 4.0 && 4.0 <= high);
        let expected = match (low > 0.0, high < 0.0) {
            (true, _) => "b_higher",
            (_, true) => "b_lower",
            _ => "no_clear_difference",
        };
        assert_eq!(loss["finding"], expected);
        assert_eq!(report["b_loses_more"], expected == "b_higher");
        let rtt = &row["rtt_p50"];
        let shift = f(rtt, "shift_us");
        assert!((shift - 30_000.0).abs() < 1_000.0, "{rtt}");
        assert!(
            f(rtt, "low_us") < shift && shift < f(rtt, "high_us"),
            "{rtt}"
        );
        rtt_held += u32::from(f(rtt, "low_us") <= 30_000.0 && 30_000.0 <= f(rtt, "high_us"));
        assert_eq!(rtt["finding"], "b_higher");
        // The same files, the same report, to the last bit.
        let (_, again, _) = compare_json(&[path_str(&a), path_str(&b)]);
        assert_eq!(again, report);
    }
    assert!(
        loss_held >= 17,
        "the loss interval held 4 points {loss_held} times of 20"
    );
    assert!(
        rtt_held >= 17,
        "the RTT interval held 30 ms {rtt_held} times of 20"
    );
}

/// `--fail-if-worse` fails when B loses more, not when it loses less, and
/// not without the option.
#[test]
fn fail_if_worse_fails_only_when_b_loses_more() {
    let dir = Scratch::new("compare-worse");
    let (good, bad) = (dir.path("good.json"), dir.path("bad.json"));
    let args = ["-c", "2000", "-i", "10ms", "-q"];
    save(&good, &args, &sim_link(20, 1, 5));
    save(&bad, &args, &sim_link(20, 10, 6));
    let (g, b) = (path_str(&good), path_str(&bad));
    let (code, report, _) = compare_json(&["--fail-if-worse", g, b]);
    assert_eq!((code, &report["exit_code"]), (1, &json!(1)), "{report}");
    assert_eq!(report["b_loses_more"], true);
    let (code, report, _) = compare_json(&[g, b]);
    assert_eq!((code, &report["exit_code"]), (0, &json!(0)), "{report}");
    let (code, report, _) = compare_json(&["--fail-if-worse", b, g]);
    assert_eq!((code, &report["exit_code"]), (0, &json!(0)), "{report}");
    assert_eq!(report["links"][0]["rows"][0]["loss"]["finding"], "b_lower");
    // The text says so too, and exits the same.
    let (code, out, err) = run_mavping(&["compare", "--fail-if-worse", g, b]);
    assert_eq!(code, 1, "{err}");
    assert!(out.contains("B loses more"), "{out}");
}

/// Two passive runs of a vehicle streaming ATTITUDE at 50 Hz beside its
/// radio, losing 2 % and 6 % of its frames on the way down: each source's
/// counts are the sim's truth (frames lost of those that arrived or were
/// lost), the radio a row of its own, the vehicle's loss higher in B.
#[test]
fn two_passive_runs_compare_each_source_against_the_sims_truth() {
    let dir = Scratch::new("compare-passive");
    let (a, b) = (dir.path("a.json"), dir.path("b.json"));
    let link = |loss: u64, seed: u64| {
        format!("sim:?stream=ATTITUDE@50&radio=on&loss_down={loss}%&seed={seed}&clock=virtual")
    };
    let args = ["--passive", "-w", "60s", "-q"];
    let truth_a = save(&a, &args, &link(2, 3));
    let truth_b = save(&b, &args, &link(6, 4));
    let (code, report, err) = compare_json(&[path_str(&a), path_str(&b)]);
    assert_eq!(code, 0, "{err}");
    let link = &report["links"][0];
    assert_eq!(
        (&link["a_kind"], &link["b_kind"]),
        (&json!("passive"), &json!("passive"))
    );
    let rows = link["rows"].as_array().unwrap();
    let roles: Vec<&str> = rows.iter().map(|r| r["role"].as_str().unwrap()).collect();
    assert_eq!(roles, ["source", "radio"], "{report}");
    let loss = &rows[0]["loss"];
    for (side, path, truth) in [("a", &a, &truth_a), ("b", &b, &truth_b)] {
        let summary = json_lines(&std::fs::read_to_string(path).unwrap())
            .into_iter()
            .find(|l| l["type"] == "passive_summary")
            .unwrap();
        let counts = &summary["sources"][0]["counts"];
        assert_eq!(
            summary["sources"][0]["source"],
            json!({"sysid": 1, "compid": 1})
        );
        let (lost, of) = (n(&loss[side], "lost"), n(&loss[side], "of"));
        assert_eq!(lost, n(counts, "lost"), "{side}: {counts}");
        // Every frame that arrived, once, and every gap proven.
        let delivered = sim_truth(truth, "1/1", "down_delivered");
        assert_eq!(of, delivered + lost, "{side}: {loss}");
        // Frames lost after the last that arrived leave no gap.
        let dropped = sim_truth(truth, "1/1", "down_dropped");
        assert!(lost <= dropped, "{side}: {lost} of {dropped}");
        if side == "a" {
            assert_eq!(lost, dropped, "seed 3 loses none of its last frames");
        }
    }
    assert_eq!(loss["finding"], "b_higher", "{loss}");
    // The radio loses nothing in either.
    assert_eq!(rows[1]["loss"]["finding"], "no_clear_difference");
    assert_eq!(rows[1]["loss"]["a"]["lost"], 0);
    assert!(rows[0]["rtt_p50"].is_null() && !rows[0]["age"].is_null());
    assert!(!link["totals"].is_null());
    assert_eq!(report["b_loses_more"], true);
}

/// A route north at `north_mps` for `seconds`, 50 frames a second (its
/// position every tenth), the windows' losses planned: `per_window[k]`
/// frames of window k (10 s), none of them a position.
fn route_plan(north_mps: f64, seconds: u64, per_window: &[u64]) -> Value {
    let drops: Vec<u64> = per_window
        .iter()
        .enumerate()
        .flat_map(|(k, &lost)| (0..lost).map(move |i| k as u64 * 500 + 101 + 2 * i))
        .collect();
    json!({
        "start_us": 1_764_500_000_000_000u64,
        "window_us": 10_000_000,
        "sources": [
            {"sysid": 1, "compid": 1, "rate": 50, "frames": 50 * seconds, "drop": drops,
             "position": {"every": 10, "lat0": 47.0, "lon0": 8.0, "alt0_m": 500.0,
                          "north_mps": north_mps, "climb_mps": 0.0}}
        ]
    })
}

/// Per band of `width` m (by the truth's distance of each window): windows,
/// frames lost and numbered.
fn truth_bands(truth: &Value, width: f64) -> std::collections::BTreeMap<u64, (u64, u64, u64)> {
    let mut bands = std::collections::BTreeMap::new();
    for w in truth["sources"]["1/1"]["windows"]
        .as_object()
        .unwrap()
        .values()
    {
        let band = (f(w, "distance_m") / width).floor() as u64;
        let (numbered, written) = (n(w, "numbered"), n(w, "written"));
        let entry = bands.entry(band).or_insert((0, 0, 0));
        entry.0 += 1;
        entry.1 += numbered - written;
        entry.2 += numbered;
    }
    bands
}

/// Two flights of one vehicle: A at 10 m/s for 60 s losing 1 % in each
/// window; B at 20 m/s for 30 s losing 2 %, 10 % and 20 % as it goes out.
/// Each band's counts are the logs' truth; the bands B reached, B's
/// loss higher where planned so.
#[test]
fn two_logs_compare_loss_by_distance_as_planned() {
    let dir = Scratch::new("compare-logs");
    let (la, lb) = (dir.path("a.tlog"), dir.path("b.tlog"));
    let ta = write_log(&la, &route_plan(10.0, 60, &[5, 5, 5, 5, 5, 5]));
    let tb = write_log(&lb, &route_plan(20.0, 30, &[10, 50, 100]));
    let (a, b) = (dir.path("a.json"), dir.path("b.json"));
    save(&a, &[], &tlog(&la));
    save(&b, &[], &tlog(&lb));
    let (code, report, err) = compare_json(&[path_str(&a), path_str(&b)]);
    assert_eq!(code, 0, "{err}");
    let link = &report["links"][0];
    assert_eq!(
        (&link["a_kind"], &link["b_kind"]),
        (&json!("log"), &json!("log"))
    );
    // The whole flights: 30 of 3000 and 160 of 1500.
    let row = &link["rows"][0];
    assert_eq!(
        row["loss"]["a"],
        json!({"lost": 30, "of": 3000, "pct": 1.0})
    );
    let b_pct = 100.0 * 160.0 / 1500.0;
    assert_eq!(
        row["loss"]["b"],
        json!({"lost": 160, "of": 1500, "pct": b_pct})
    );
    assert_eq!(row["loss"]["finding"], "b_higher");
    // The farthest window, near 596 m: bands of 100 m.
    let bands = &link["bands"];
    assert_eq!(bands["width_m"], 100.0, "{bands}");
    assert_eq!((n(bands, "a_windows"), n(bands, "b_windows")), (6, 3));
    let (want_a, want_b) = (truth_bands(&ta, 100.0), truth_bands(&tb, 100.0));
    let got = bands["bands"].as_array().unwrap();
    let reached: Vec<u64> = got
        .iter()
        .map(|g| (f(g, "from_m") / 100.0) as u64)
        .collect();
    assert_eq!(reached, [0, 1, 2, 3, 4, 5], "{bands}");
    assert_eq!(want_b.keys().copied().collect::<Vec<_>>(), [1, 3, 5]);
    for g in got {
        let band = (f(g, "from_m") / 100.0) as u64;
        for (side, want) in [("a", &want_a), ("b", &want_b)] {
            let (windows, lost, of) = want.get(&band).copied().unwrap_or_default();
            assert_eq!(n(g, &format!("{side}_windows")), windows, "{g}");
            assert_eq!(n(&g["loss"][side], "lost"), lost, "band {band}: {g}");
            assert_eq!(n(&g["loss"][side], "of"), of, "band {band}: {g}");
        }
        // A loses 5 of 500 in each; B 10, 50 and 100 of 500 in its three.
        let finding = match band {
            1 => "no_clear_difference",
            3 | 5 => "b_higher",
            _ => "no_data",
        };
        assert_eq!(g["loss"]["finding"], finding, "band {band}: {g}");
    }
    // Bands of 200 m on request: A's windows two to a band.
    let (_, report, _) = compare_json(&["--band-m", "200", path_str(&a), path_str(&b)]);
    let bands = &report["links"][0]["bands"];
    let windows: Vec<(u64, u64)> = bands["bands"]
        .as_array()
        .unwrap()
        .iter()
        .map(|g| (n(g, "a_windows"), n(g, "b_windows")))
        .collect();
    assert_eq!(windows, [(2, 1), (2, 1), (2, 1)], "{bands}");
    // The text names the bands B never reached.
    let (_, out, _) = run_mavping(&["compare", path_str(&a), path_str(&b)]);
    assert_eq!(out.matches("B was never this far").count(), 3, "{out}");
}

/// `mavping compare ARGS`, expecting a refusal: exit 2 and one line on
/// stderr, no panic; the line.
fn refused(args: &[&str]) -> String {
    let mut all = vec!["compare"];
    all.extend_from_slice(args);
    let (code, out, err) = run_mavping(&all);
    assert_eq!(code, 2, "{args:?}: {out}{err}");
    assert!(out.is_empty(), "{args:?}: {out}");
    assert_eq!(err.trim_end().lines().count(), 1, "{args:?}: {err}");
    assert!(!err.contains("panicked"), "{err}");
    err
}

#[test]
fn bad_input_is_refused_in_one_line() {
    let dir = Scratch::new("compare-bad");
    let good = dir.path("good.json");
    save(
        &good,
        &["-c", "50", "-i", "10ms", "-q"],
        &sim_link(20, 2, 1),
    );
    let g = path_str(&good);
    let write = |name: &str, bytes: &[u8]| -> PathBuf {
        let p = dir.path(name);
        std::fs::write(&p, bytes).unwrap();
        p
    };
    let missing = dir.path("missing.json");
    let err = refused(&[g, path_str(&missing)]);
    assert!(err.contains("missing.json: cannot read it"), "{err}");
    let err = refused(&[path_str(&dir.0), g]);
    assert!(err.contains("cannot read it"), "{err}");
    let empty = write("empty.json", b"");
    assert!(refused(&[g, path_str(&empty)]).contains("empty.json: empty"));
    let text = write("notes.txt", b"radio A was better\n");
    let err = refused(&[path_str(&text), g]);
    assert!(
        err.contains("notes.txt line 1: not a line of `mavping --json`"),
        "{err}"
    );
    // A telemetry log itself, not the JSON saved from it.
    let log = dir.path("flight.tlog");
    write_log(&log, &route_plan(10.0, 10, &[1]));
    let err = refused(&[g, path_str(&log)]);
    assert!(err.contains("flight.tlog line 1: not a line of"), "{err}");
    // JSON of another kind: a compare report, an interval's lines only.
    let (_, out, _) = run_mavping(&["compare", "--json", g, g]);
    let report = write("report.json", out.as_bytes());
    let err = refused(&[path_str(&report), g]);
    assert!(
        err.contains("report.json: no summary or passive_summary line"),
        "{err}"
    );
    let other = write(
        "other.json",
        b"{\"type\":\"summary\",\"schema_version\":1}\n",
    );
    assert!(refused(&[g, path_str(&other)]).contains("schema_version 1"));
    let old = write("old.json", b"{\"type\":\"summary\",\"schema_version\":2}\n");
    assert!(refused(&[g, path_str(&old)]).contains("a summary line without the figures"));
    // Two runs with nothing in common: other responders, and a probe run
    // against a passive one.
    let other_ids = dir.path("ids.json");
    let ids_link = "sim:?responders=2&sysid=7&clock=virtual";
    save(&other_ids, &["-c", "20", "-i", "10ms", "-q"], ids_link);
    let twice = dir.path("twice.json");
    save(
        &twice,
        &["-c", "20", "-i", "10ms", "-q"],
        "sim:?responders=2&clock=virtual",
    );
    let err = refused(&[path_str(&twice), path_str(&other_ids)]);
    assert!(err.contains("no responder or source is in both"), "{err}");
    let passive = dir.path("passive.json");
    save(&passive, &[], &tlog(&log));
    let err = refused(&[g, path_str(&passive)]);
    assert!(err.contains("not the same measure"), "{err}");
    // Options: bad values and a missing file name.
    assert!(refused(&["--band-m", "0", g, g]).contains("--band-m 0"));
    let (code, _, err) = run_mavping(&["compare", g]);
    assert_eq!(code, 2, "{err}");
}

/// `mavping compare` with stdout a pipe whose reader is gone: the report
/// meets a closed pipe and the exit code stays the comparison's.
fn compare_into_closed_pipe(args: &[&str]) -> i32 {
    let (reader, writer) = std::io::pipe().unwrap();
    drop(reader);
    let child = mavping()
        .arg("compare")
        .args(args)
        .stdout(writer)
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let (code, _, err) = wait_output(child, Duration::from_secs(60));
    assert!(err.is_empty(), "{err}");
    code
}

#[test]
fn a_closed_pipe_keeps_the_comparisons_exit_code_and_a_full_disk_fails() {
    let dir = Scratch::new("compare-pipe");
    let (good, bad) = (dir.path("good.json"), dir.path("bad.json"));
    let args = ["-c", "2000", "-i", "10ms", "-q"];
    save(&good, &args, &sim_link(20, 1, 5));
    save(&bad, &args, &sim_link(20, 10, 6));
    let (g, b) = (path_str(&good), path_str(&bad));
    for json in [&[][..], &["--json"][..]] {
        let with = |rest: &[&'static str]| -> Vec<&str> {
            json.iter().copied().chain(rest.iter().copied()).collect()
        };
        let worse = [with(&["--fail-if-worse"]), vec![g, b]].concat();
        assert_eq!(compare_into_closed_pipe(&worse), 1, "{worse:?}");
        let better = [with(&["--fail-if-worse"]), vec![b, g]].concat();
        assert_eq!(compare_into_closed_pipe(&better), 0, "{better:?}");
        // A full disk is no reader's choice: the report was not written.
        let full = std::fs::File::create("/dev/full").unwrap();
        let child = mavping()
            .arg("compare")
            .args(&better)
            .stdout(full)
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        let (code, _, err) = wait_output(child, Duration::from_secs(60));
        assert_eq!(code, 2, "{err}");
        assert!(err.contains("cannot write the output"), "{err}");
    }
}
