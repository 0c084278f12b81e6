//! `tlog:FILE`: telemetry logs written by pymavlink (its `mavlogfile`, with
//! faults planned frame by frame: `tests/peers/tlog_writer.py`), recorded by
//! pymavlink's own logger and by MAVProxy from pymavlink vehicles, read by
//! mavping: counts exact against the plan or the vehicles' truth, the
//! pymavlink figure equal to `mavloss.py`'s on the same file, per-link
//! figures from MAVProxy's stamps, standard input, the log's own clock,
//! and files that are not logs.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::Duration;

use serde_json::{json, Value};

use crate::common::*;

/// A scratch directory of one test, removed when dropped.
pub(crate) struct Scratch(pub(crate) PathBuf);

impl Scratch {
    pub(crate) fn new(name: &str) -> Scratch {
        let dir = std::env::temp_dir().join(format!("mavping-tlog-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        Scratch(dir)
    }

    pub(crate) fn path(&self, file: &str) -> PathBuf {
        self.0.join(file)
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// Writes `plan` as a log with pymavlink; its ground truth.
pub(crate) fn write_log(path: &Path, plan: &Value) -> Value {
    let out = Command::new(python())
        .arg(peer_script("tlog_writer.py"))
        .arg(path)
        .arg(plan.to_string())
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "tlog_writer.py: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).unwrap()
}

/// `mavloss.py` on `path`: packets and lost per (sysid, compid), and the
/// total.
pub(crate) struct MavLoss {
    pub(crate) sources: BTreeMap<(u64, u64), (u64, u64)>,
    pub(crate) total: (u64, u64),
}

fn mavloss(path: &Path) -> MavLoss {
    mavloss_env(path, &[])
}

/// `mavloss.py` on `path` with `env` set (MAVLINK20=1: MAVLink 2 from the
/// first frame).
pub(crate) fn mavloss_env(path: &Path, env: &[(&str, &str)]) -> MavLoss {
    let out = Command::new(python())
        .arg(venv_program("mavloss.py"))
        .arg(path)
        .envs(env.iter().copied())
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "mavloss.py: {text}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let numbers = |line: &str| -> Vec<u64> {
        line.split(|c: char| !c.is_ascii_digit())
            .filter(|s| !s.is_empty())
            .map(|s| s.parse().unwrap())
            .collect()
    };
    let mut sources = BTreeMap::new();
    let mut total = None;
    for line in text.lines() {
        if let Some(rest) = line.strip_prefix("Total: ") {
            let n = numbers(rest);
            total = Some((n[0], n[1]));
        } else if line.starts_with("  ")
            && line.trim_start().starts_with(|c: char| c.is_ascii_digit())
        {
            let n = numbers(line);
            sources.insert((n[0], n[1]), (n[2], n[3]));
        }
    }
    MavLoss {
        sources,
        total: total.unwrap_or_else(|| panic!("no total in {text}")),
    }
}

/// mavping `--json` on `link`: exit code, the passive summary (every line
/// checked against the schema), stderr.
pub(crate) fn read(args: &[&str], link: &str) -> (i32, Value, String) {
    let mut all = vec!["--json"];
    all.extend_from_slice(args);
    all.push(link);
    let (code, out, err) = run_mavping(&all);
    let lines = json_lines(&out);
    assert_schema(&lines);
    let summary = lines
        .into_iter()
        .find(|l| l["type"] == "passive_summary")
        .unwrap_or_else(|| panic!("no passive_summary: {out}{err}"));
    (code, summary, err)
}

pub(crate) fn tlog(path: &Path) -> String {
    format!("tlog:{}", path.display())
}

/// A source's figures in a summary (or a link's table).
fn source<'a>(sources: &'a Value, id: &str) -> &'a Value {
    sources
        .as_array()
        .unwrap()
        .iter()
        .find(|s| format!("{}/{}", s["source"]["sysid"], s["source"]["compid"]) == id)
        .unwrap_or_else(|| panic!("no {id} in {sources}"))
}

fn counts(s: &Value, key: &str) -> u64 {
    s["counts"][key].as_u64().unwrap()
}

fn truth(t: &Value, id: &str, key: &str) -> u64 {
    t["sources"][id][key].as_u64().unwrap()
}

/// The pymavlink figure per source and in total is mavloss.py's, exactly.
fn assert_pymavlink_figures(summary: &Value, path: &Path) {
    let loss = mavloss(path);
    let ours: BTreeMap<(u64, u64), (u64, u64)> = summary["sources"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|s| s["radio"] == false)
        .map(|s| {
            let id = (
                s["source"]["sysid"].as_u64().unwrap(),
                s["source"]["compid"].as_u64().unwrap(),
            );
            (
                id,
                (
                    s["pymav"]["count"].as_u64().unwrap(),
                    s["pymav"]["loss"].as_u64().unwrap(),
                ),
            )
        })
        .collect();
    assert_eq!(
        ours, loss.sources,
        "per source: mavping (left), mavloss.py (right)"
    );
    let totals = &summary["totals"]["pymav"];
    assert_eq!(
        (
            totals["count"].as_u64().unwrap(),
            totals["loss"].as_u64().unwrap()
        ),
        loss.total
    );
}

/// 1/1 at 50/s (MAVLink 2): drops (three in a row), duplicates, swapped
/// pairs, a silence of 300 frames (longer than the sequence spans) and one
/// of 20; 2/1 at 10/s in MAVLink 1; 1/154 at 20/s, signed. All wrap the
/// 8-bit sequence.
fn faulty_plan(stamps: &str) -> Value {
    json!({
        "start_us": 1_764_500_000_000_000u64,
        "stamps": stamps,
        "sources": [
            {"sysid": 1, "compid": 1, "rate": 50, "frames": 3000, "phase_us": 0,
             "drop": [10, 11, 12, 500, 2001], "dup": [50, 700], "swap": [100, 900],
             "silence": [[1200, 300], [2500, 20]]},
            {"sysid": 2, "compid": 1, "rate": 10, "frames": 600, "version": 1,
             "phase_us": 3000, "drop": [5, 300], "dup": [77], "swap": [400]},
            {"sysid": 1, "compid": 154, "rate": 20, "frames": 1200, "signed": true,
             "phase_us": 7000, "drop": [30]}
        ]
    })
}

/// The short silence of 1/1 is spanned by its sequence: counted lost.
const SHORT_SILENCE: u64 = 20;
/// The long one is not: the sequence proves 300 modulo 256 of it (counted
/// lost), and the rate says one wrap more is likely (said, not counted).
const LONG_SILENCE: u64 = 300;

fn assert_faulty_plan_counts(summary: &Value, t: &Value) {
    let s = &summary["sources"];
    for id in ["1/1", "2/1", "1/154"] {
        let r = source(s, id);
        assert_eq!(counts(r, "received"), truth(t, id, "written"), "{id}: {r}");
        assert_eq!(
            counts(r, "duplicate"),
            truth(t, id, "duplicated"),
            "{id}: {r}"
        );
        assert_eq!(counts(r, "reordered"), truth(t, id, "swapped"), "{id}: {r}");
        let silenced = if id == "1/1" {
            SHORT_SILENCE + LONG_SILENCE % 256
        } else {
            0
        };
        assert_eq!(
            counts(r, "lost"),
            truth(t, id, "dropped") + silenced,
            "{id}: {r}"
        );
    }
    let one = source(s, "1/1");
    assert_eq!(truth(t, "1/1", "silenced"), SHORT_SILENCE + LONG_SILENCE);
    assert_eq!(one["silence_count"], 1, "{one}");
    let silence = &one["silences"][0];
    assert_eq!(silence["seq_lost"].as_u64(), Some(LONG_SILENCE % 256));
    let estimated = silence["frames_estimated"].as_u64().unwrap();
    assert!(estimated.abs_diff(LONG_SILENCE) <= 1, "{silence}");
    let likely = silence["lost_estimated"].as_u64().unwrap();
    assert!(likely.abs_diff(LONG_SILENCE) <= 1, "{silence}");
    assert_eq!(likely % 256, LONG_SILENCE % 256, "{silence}");
    assert_eq!(
        one["silence_frames_estimated"].as_u64(),
        Some(likely - LONG_SILENCE % 256),
        "{one}"
    );
    // Time 0 is the first record; the log is 60 s long.
    let span = summary["duration_s"].as_f64().unwrap();
    assert!((59.9..60.0).contains(&span), "{span}");
    assert_eq!(summary["log"]["complete"], true);
    assert_eq!(summary["heartbeat"], false);
    assert_eq!(summary["rx_clock"], "the log's time stamps");
}

#[test]
fn a_log_written_by_pymavlink_is_counted_exactly_and_pymavlinks_figure_is_mavloss() {
    let dir = Scratch::new("faulty");
    let path = dir.path("faulty.tlog");
    let t = write_log(&path, &faulty_plan("us"));
    let (code, summary, err) = read(&[], &tlog(&path));
    assert_eq!(code, 0, "{err}");
    assert_faulty_plan_counts(&summary, &t);
    assert_eq!(summary["log"]["records"]["records"], t["records"]);
    assert_eq!(summary["log"]["records"]["junk_bytes"], 0);
    assert_eq!(
        summary["log"]["stamps"]["first_us"],
        1_764_500_000_000_000u64
    );
    assert_eq!(summary["log"]["stamps"]["whole_ms"], false);
    assert_eq!(
        summary["signing"]["signed_unchecked"],
        truth(&t, "1/154", "written")
    );
    assert!(summary.get("per_link").is_none(), "{summary}");
    assert_pymavlink_figures(&summary, &path);
    // pymavlink's figure is far from the truth: each duplicate ~255 lost,
    // each swap 256, the long silence its length modulo 256.
    let one = source(&summary["sources"], "1/1");
    assert!(one["pymav"]["loss"].as_u64().unwrap() > 1000, "{one}");
}

#[test]
fn qgroundcontrol_and_pymavlink_stamps_read_the_same() {
    let dir = Scratch::new("stamps");
    for stamps in ["ms", "pymavlink"] {
        let path = dir.path(&format!("{stamps}.tlog"));
        let t = write_log(&path, &faulty_plan(stamps));
        let (code, summary, err) = read(&[], &tlog(&path));
        assert_eq!(code, 0, "{stamps}: {err}");
        assert_faulty_plan_counts(&summary, &t);
        assert_eq!(summary["log"]["stamps"]["whole_ms"], stamps == "ms");
        let bits = &summary["log"]["stamps"]["low_bits"];
        assert_eq!(bits[0], t["records"], "{stamps}: {bits}");
        assert_pymavlink_figures(&summary, &path);
    }
}

#[test]
fn junk_between_records_is_counted_and_skipped_and_a_cut_last_record_said() {
    let dir = Scratch::new("junk");
    let path = dir.path("junk.tlog");
    let mut plan = faulty_plan("us");
    // Junk without a start byte; with start bytes and a header that claims
    // a frame; eight zero bytes (a stamp of 1970) before a false header.
    plan["junk"] = json!([
        [100, "00112233445566778899"],
        [1500, "fd0900aabbfe01"],
        [3000, "0000000000000000fd1c0000"]
    ]);
    plan["cut"] = json!(7);
    let t = write_log(&path, &plan);
    let (code, summary, err) = read(&[], &tlog(&path));
    assert_eq!(code, 0, "{err}");
    let records = &summary["log"]["records"];
    assert_eq!(records["junk_bytes"], t["junk_bytes"], "{records}");
    assert_eq!(records["junk_stretches"], 3, "{records}");
    let cut_short = t["last_record_len"].as_u64().unwrap() - 7;
    assert_eq!(
        records["truncated_bytes"].as_u64(),
        Some(cut_short),
        "{records}"
    );
    let written = t["records"].as_u64().unwrap();
    assert_eq!(records["records"].as_u64(), Some(written - 1), "{records}");
    assert_eq!(summary["frames"]["truncated"], 1);
    assert_eq!(
        summary["frames"]["skipped_bytes"].as_u64(),
        Some(t["junk_bytes"].as_u64().unwrap() + cut_short)
    );
    // Every record but the cut one is there: the counts are the plan's,
    // less the last frame of the source that wrote it.
    let mut received = 0;
    for s in summary["sources"].as_array().unwrap() {
        received += counts(s, "received");
    }
    assert_eq!(received, written - 1);
    // pymavlink reads what follows junk worse: it loses the two records
    // after a stretch (its parser takes the next stamp for junk), and a
    // stretch that looks like a stamp and a frame header ends its reading.
    let loss = mavloss(&path);
    assert!(
        loss.total.0 < 3000,
        "mavloss.py read {} packets",
        loss.total.0
    );
    let (_, text, _) = run_mavping(&[&tlog(&path)]);
    assert!(
        text.contains(&format!(
            "log: {} bytes of junk between records, in 3 stretches, skipped",
            t["junk_bytes"]
        )),
        "{text}"
    );
    assert!(
        text.contains(&format!(
            "log: its last record is cut short ({cut_short} bytes)"
        )),
        "{text}"
    );
}

#[test]
fn pymavlink_loses_the_two_records_after_junk_mavping_none() {
    let dir = Scratch::new("junk2");
    let path = dir.path("junk2.tlog");
    let plan = json!({
        "start_us": 1_764_500_000_000_000u64,
        "sources": [{"sysid": 1, "compid": 1, "rate": 50, "frames": 1000}],
        "junk": [[100, "00112233445566778899"], [400, "0102030405"]]
    });
    write_log(&path, &plan);
    let (_, summary, _) = read(&[], &tlog(&path));
    let one = source(&summary["sources"], "1/1");
    assert_eq!(
        (counts(one, "received"), counts(one, "lost")),
        (1000, 0),
        "{one}"
    );
    let loss = mavloss(&path);
    assert_eq!(loss.total, (996, 4), "two records lost after each stretch");
}

/// A vehicle on MAVProxy's links 0 and 1, each losing frames of its own
/// beside two both lose; MAVProxy's own frames on link 3; a ground
/// station's frames MAVProxy forwarded with plain stamps.
pub(crate) fn mavproxy_plan() -> Value {
    json!({
        "start_us": 1_764_500_000_000_000u64,
        "stamps": "mavproxy",
        "sources": [
            {"sysid": 1, "compid": 1, "rate": 50, "frames": 3000, "drop": [40, 41],
             "links": {"0": {"drop": [100, 2000]}, "1": {"drop": [7, 8, 9, 1500], "delay_us": 300}}},
            {"sysid": 255, "compid": 230, "rate": 1, "frames": 60, "phase_us": 11,
             "links": {"3": {}}},
            {"sysid": 255, "compid": 190, "rate": 2, "frames": 120, "phase_us": 5, "plain": true}
        ]
    })
}

#[test]
fn mavproxy_link_numbers_give_figures_per_link() {
    let dir = Scratch::new("links");
    let path = dir.path("links.tlog");
    let t = write_log(&path, &mavproxy_plan());
    let (code, summary, err) = read(&[], &tlog(&path));
    assert_eq!(code, 0, "{err}");
    // Merged, the vehicle's second link is duplicates; only what both
    // links lost is lost.
    let merged = source(&summary["sources"], "1/1");
    assert_eq!(counts(merged, "lost"), truth(&t, "1/1", "dropped"));
    let per = &summary["per_link"];
    let link = |n: u64| {
        per["links"]
            .as_array()
            .unwrap()
            .iter()
            .find(|l| l["link"] == n)
            .unwrap_or_else(|| panic!("no link {n}: {per}"))
    };
    for n in [0u64, 1] {
        let r = source(&link(n)["sources"], "1/1");
        let lt = &t["sources"]["1/1"]["links"][n.to_string()];
        assert_eq!(
            counts(r, "received"),
            lt["written"].as_u64().unwrap(),
            "link {n}: {r}"
        );
        assert_eq!(
            counts(r, "lost"),
            lt["dropped"].as_u64().unwrap() + truth(&t, "1/1", "dropped"),
            "link {n}: {r}"
        );
        assert_eq!(counts(r, "duplicate"), 0, "link {n}: {r}");
    }
    let own = source(&link(3)["sources"], "255/230");
    assert_eq!(counts(own, "received"), 60);
    assert_eq!(per["unlinked"], json!([{"sysid": 255, "compid": 190}]));
    assert_eq!(per["links"].as_array().unwrap().len(), 3, "{per}");
    // mavloss.py merges the links, as the main table does.
    assert_pymavlink_figures(&summary, &path);
    let (_, text, _) = run_mavping(&[&tlog(&path)]);
    assert!(text.contains("per MAVProxy link"), "{text}");
    assert!(text.contains("on no link: 255/190"), "{text}");
}

#[test]
fn a_clocks_microseconds_are_no_link_numbers() {
    // Stamps of a clock read as frames arrive: their low bits vary.
    let dir = Scratch::new("nolinks");
    let path = dir.path("us.tlog");
    let mut plan = faulty_plan("us");
    for s in plan["sources"].as_array_mut().unwrap() {
        s["plain"] = json!(true);
    }
    let t = write_log(&path, &plan);
    let (_, summary, _) = read(&[], &tlog(&path));
    let bits = &summary["log"]["stamps"]["low_bits"];
    assert!(
        bits.as_array()
            .unwrap()
            .iter()
            .filter(|b| b.as_u64() > Some(0))
            .count()
            > 1,
        "{bits}"
    );
    assert!(summary.get("per_link").is_none(), "{summary}");
    assert_faulty_plan_counts(&summary, &t);
}

#[test]
fn standard_input_reads_as_the_file_does() {
    let dir = Scratch::new("stdin");
    let path = dir.path("in.tlog");
    write_log(&path, &mavproxy_plan());
    let (_, from_file, _) = read(&[], &tlog(&path));
    let child = Command::new("sh")
        .arg("-c")
        .arg(format!(
            "cat '{}' | '{}' --json tlog:-",
            path.display(),
            env!("CARGO_BIN_EXE_mavping")
        ))
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let (code, out, err) = wait_output(child, Duration::from_secs(60));
    assert_eq!(code, 0, "{err}");
    let mut from_stdin = json_lines(&out)
        .into_iter()
        .find(|l| l["type"] == "passive_summary")
        .unwrap();
    assert_eq!(from_stdin["link"], "tlog:-");
    from_stdin["link"] = from_file["link"].clone();
    assert_eq!(from_stdin, from_file);
}

#[test]
fn a_log_fed_slowly_through_a_pipe_is_read_on_its_own_clock() {
    // The writer sleeps between chunks: the log's clock must wait for its
    // bytes, not run ahead of them (a silence that is not in the log).
    let dir = Scratch::new("slow");
    let path = dir.path("slow.tlog");
    let t = write_log(&path, &faulty_plan("us"));
    let (_, from_file, _) = read(&[], &tlog(&path));
    let feeder = format!(
        "import sys, time\n\
         data = open('{}', 'rb').read()\n\
         for i in range(0, len(data), 4000):\n\
         \x20   sys.stdout.buffer.write(data[i:i + 4000]); sys.stdout.flush(); time.sleep(0.05)\n",
        path.display()
    );
    let child = Command::new("sh")
        .arg("-c")
        .arg(format!(
            "'{}' -c \"$FEED\" | '{}' --json tlog:-",
            python().display(),
            env!("CARGO_BIN_EXE_mavping")
        ))
        .env("FEED", feeder)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let (code, out, err) = wait_output(child, Duration::from_secs(60));
    assert_eq!(code, 0, "{err}");
    let mut slow = json_lines(&out)
        .into_iter()
        .find(|l| l["type"] == "passive_summary")
        .unwrap();
    slow["link"] = from_file["link"].clone();
    assert_eq!(slow, from_file);
    assert_faulty_plan_counts(&slow, &t);
}

#[test]
fn a_deadline_reads_the_logs_first_seconds_exactly() {
    // 1/1 alone at 50/s from time 0: by 10.5 s, frames 0 to 525.
    let dir = Scratch::new("deadline");
    let path = dir.path("d.tlog");
    let plan = json!({
        "start_us": 1_764_500_000_000_000u64,
        "sources": [{"sysid": 1, "compid": 1, "rate": 50, "frames": 3000}]
    });
    write_log(&path, &plan);
    let (code, summary, err) = read(&["-w", "10.5"], &tlog(&path));
    assert_eq!(code, 0, "{err}");
    let one = source(&summary["sources"], "1/1");
    assert_eq!(counts(one, "received"), 526, "{one}");
    assert_eq!(summary["duration_s"], 10.5);
    assert_eq!(summary["log"]["complete"], false);
}

#[test]
fn files_that_are_not_logs_are_refused_in_one_line() {
    let dir = Scratch::new("bad");
    let png = dir.path("image.png");
    std::fs::write(
        &png,
        [&b"\x89PNG\r\n\x1a\n\0\0\0\rIHDR"[..], &[0x42; 300]].concat(),
    )
    .unwrap();
    let text = dir.path("notes.tlog");
    std::fs::write(
        &text,
        "these are my flight notes\nbattery 12.4 V\n".repeat(30),
    )
    .unwrap();
    let empty = dir.path("empty.tlog");
    std::fs::write(&empty, "").unwrap();
    let good = dir.path("one.tlog");
    let plan = json!({
        "start_us": 1_764_500_000_000_000u64,
        "sources": [{"sysid": 1, "compid": 1, "rate": 50, "frames": 1}]
    });
    write_log(&good, &plan);
    let cut = dir.path("cut.tlog");
    let bytes = std::fs::read(&good).unwrap();
    std::fs::write(&cut, &bytes[..bytes.len() - 3]).unwrap();
    let raw = dir.path("raw.tlog");
    // Frames without stamps: the records' frames, back to back.
    let stamped = dir.path("many.tlog");
    let plan = json!({
        "start_us": 1_764_500_000_000_000u64,
        "sources": [{"sysid": 1, "compid": 1, "rate": 50, "frames": 50}]
    });
    write_log(&stamped, &plan);
    let many = std::fs::read(&stamped).unwrap();
    let mut frames = Vec::new();
    let mut at = 0;
    while at < many.len() {
        // MAVLink 2, unsigned: header 10, payload, CRC 2.
        let len = 12 + usize::from(many[at + 9]);
        frames.extend_from_slice(&many[at + 8..at + 8 + len]);
        at += 8 + len;
    }
    std::fs::write(&raw, frames).unwrap();
    let cut_says = format!(
        "not a telemetry log: its {} bytes are one record cut short",
        bytes.len() - 3
    );
    let cases: Vec<(String, &str)> = vec![
        (tlog(&png), "not a telemetry log: no record"),
        (tlog(&text), "not a telemetry log: its"),
        (tlog(&empty), "not a telemetry log: it is empty"),
        (tlog(&cut), &cut_says),
        (tlog(&raw), "hold MAVLink frames without time stamps"),
        (tlog(&dir.0), "it is a directory, not a telemetry log"),
        (tlog(&dir.path("missing.tlog")), "cannot open"),
    ];
    for (link, says) in cases {
        let (code, out, err) = run_mavping(&[&link]);
        assert_eq!(code, 2, "{link}: {out}{err}");
        assert!(out.is_empty(), "{link}: nothing measured: {out}");
        assert_eq!(err.lines().count(), 1, "{link}: {err}");
        assert!(
            err.starts_with(&format!("mavping: {link}")) || err.contains(&link),
            "{err}"
        );
        assert!(err.contains(says), "{link}: {err}");
    }
}

#[test]
fn probes_on_a_log_are_refused_and_passive_is_implied() {
    let dir = Scratch::new("refused");
    let path = dir.path("r.tlog");
    write_log(
        &path,
        &json!({
            "start_us": 1_764_500_000_000_000u64,
            "sources": [{"sysid": 1, "compid": 1, "rate": 50, "frames": 100}]
        }),
    );
    let link = tlog(&path);
    for flags in [
        &["-c", "5"][..],
        &["--probe", "timesync"],
        &["--probe", "command"],
        &["-i", "0.1"],
        &["--sweep"],
    ] {
        let mut args = flags.to_vec();
        args.push(&link);
        let (code, out, err) = run_mavping(&args);
        assert_eq!(code, 2, "{flags:?}: {out}{err}");
        assert_eq!(err.lines().count(), 1, "{flags:?}: {err}");
        assert!(
            err.contains("is a telemetry log, read without probes"),
            "{err}"
        );
    }
    // --passive and --gap are accepted; nothing is sent, and it says so.
    let (code, out, _) = run_mavping(&["--passive", "--gap", "2s", &link]);
    assert_eq!(code, 0, "{out}");
    assert!(
        out.lines().next().unwrap().ends_with(
            "PASSIVE, no probes; a telemetry log, read on its own clock (--passive implied); nothing sent"
        ),
        "{out}"
    );
    let (code, _, err) = run_mavping(&[&link, "sim:"]);
    assert_eq!(code, 2);
    assert!(err.contains("cannot run beside live links"), "{err}");
    let (code, _, err) = run_mavping(&["respond", &link]);
    assert_eq!(code, 2);
    assert!(err.contains("a telemetry log is only read"), "{err}");
}

#[test]
fn pymavlinks_own_logger_records_a_vehicle_counted_exactly() {
    // A pymavlink vehicle over TCP; a pymavlink ground station records
    // every frame it receives with `setup_logfile`.
    let dir = Scratch::new("recorder");
    let path = dir.path("recorded.tlog");
    let port = free_tcp_port();
    let mut vehicle = Peer::start(
        "vehicle.py",
        &[
            &format!("tcpin:127.0.0.1:{port}"),
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
    let recorder = Peer::start(
        "tlog_recorder.py",
        &[&format!("tcp:127.0.0.1:{port}"), path.to_str().unwrap()],
    );
    let truth: Value = serde_json::from_str(&vehicle.read_line()).unwrap();
    std::thread::sleep(Duration::from_millis(300));
    let recorded = recorder.finish();
    let (code, summary, err) = read(&[], &tlog(&path));
    assert_eq!(code, 0, "{err}");
    let one = source(&summary["sources"], "1/1");
    let t = |k: &str| truth[k].as_u64().unwrap();
    assert_eq!(recorded["recorded"].as_u64(), Some(t("sent")));
    assert_eq!(counts(one, "received"), t("sent"), "{one}");
    // The drops, and what the sequence proves of the 300 numbers silenced
    // (more than it spans): 300 modulo 256.
    assert_eq!(t("silenced"), 300);
    assert_eq!(counts(one, "lost"), t("dropped") + 300 % 256, "{one}");
    assert_eq!(counts(one, "duplicate"), t("duplicated"), "{one}");
    assert_eq!(counts(one, "reordered"), t("swapped"), "{one}");
    assert_eq!(one["silence_count"], 1, "{one}");
    assert_eq!(one["silences"][0]["seq_lost"].as_u64(), Some(300 % 256));
    // pymavlink's logger stamps usec & ~3: no link numbers.
    assert!(summary.get("per_link").is_none());
    assert_pymavlink_figures(&summary, &path);
}

#[test]
fn mavproxy_records_a_vehicle_on_two_lossy_links_with_their_numbers() {
    // vehicle.py -> relay -> MAVProxy's masters 0 and 1, each link dropping
    // frames of its own; MAVProxy logs both, stamped with the link.
    let mavproxy = venv_program("mavproxy.py");
    let dir = Scratch::new("mavproxy");
    let (vehicle_port, link0, link1) = (free_udp_port(), free_udp_port(), free_udp_port());
    let mut vehicle = Peer::start(
        "vehicle.py",
        &[
            &format!("udpin:127.0.0.1:{vehicle_port}"),
            "--frames",
            "700",
            "--rate",
            "50",
            "--drop",
            "10,11,12,300",
            "--dup",
            "60",
            "--swap",
            "100,500",
        ],
    );
    let mavproxy = Program::start_on_udp(
        &mavproxy,
        &[
            &format!("--master=udpin:127.0.0.1:{link0}"),
            &format!("--master=udpin:127.0.0.1:{link1}"),
            "--logfile=flight.tlog",
            "--non-interactive",
            "--cmd=set flushlogs 1",
        ],
        &dir.0,
        link1,
    );
    let relay = Peer::start(
        "tlog_relay.py",
        &[
            &vehicle_port.to_string(),
            &link0.to_string(),
            &link1.to_string(),
            "--drop0",
            "200,201,450",
            "--drop1",
            "5,6,7,8,9,400,600",
        ],
    );
    let truth: Value = serde_json::from_str(&vehicle.read_line()).unwrap();
    std::thread::sleep(Duration::from_millis(500));
    let relayed = relay.finish();
    std::thread::sleep(Duration::from_millis(500));
    // Stopped (it flushes its log on every frame), so the log no longer
    // grows while mavping and mavloss.py read it.
    drop(mavproxy);
    let path = dir.path("flight.tlog");
    let (code, summary, err) = read(&[], &tlog(&path));
    assert_eq!(code, 0, "{err}");
    let t = |k: &str| truth[k].as_u64().unwrap();
    let per = &summary["per_link"];
    let link = |n: u64| {
        per["links"]
            .as_array()
            .unwrap()
            .iter()
            .find(|l| l["link"] == n)
            .unwrap_or_else(|| panic!("no link {n}: {per}"))
    };
    for (n, relay_dropped) in [(0u64, 3u64), (1, 7)] {
        let r = source(&link(n)["sources"], "1/1");
        let why = format!("link {n}: {r}\nvehicle: {truth}\nrelay: {relayed}");
        assert_eq!(relayed["dropped"][n as usize], relay_dropped);
        assert_eq!(
            counts(r, "received"),
            relayed["forwarded"][n as usize].as_u64().unwrap(),
            "{why}"
        );
        assert_eq!(counts(r, "lost"), t("dropped") + relay_dropped, "{why}");
        assert_eq!(counts(r, "duplicate"), t("duplicated"), "{why}");
        assert_eq!(counts(r, "reordered"), t("swapped"), "{why}");
    }
    // What MAVProxy sent itself is on link 3.
    let own = link(3)["sources"].as_array().unwrap();
    assert!(own.iter().all(|s| s["source"]["sysid"] == 255), "{own:?}");
    // Merged, the two links are one stream of duplicates, as mavloss.py
    // reads it.
    let merged = source(&summary["sources"], "1/1");
    assert_eq!(
        counts(merged, "received"),
        relayed["forwarded"][0].as_u64().unwrap() + relayed["forwarded"][1].as_u64().unwrap()
    );
    assert_pymavlink_figures(&summary, &path);
}

#[test]
fn interim_figures_come_at_the_logs_own_seconds() {
    // -Q 20s: at 20 s of the log, 1/1 has sent frames 0 to 1000; 4 of them
    // dropped (10-12, 500), 2 doubled (50, 700).
    let dir = Scratch::new("interim");
    let path = dir.path("q.tlog");
    write_log(&path, &faulty_plan("us"));
    let (code, out, err) = run_mavping(&["-Q", "20s", &tlog(&path)]);
    assert_eq!(code, 0, "{err}");
    let times: Vec<&str> = out
        .lines()
        .filter(|l| l.starts_with('['))
        .filter_map(|l| l.split(']').next())
        .collect();
    assert_eq!(
        times,
        ["[20.0 s"; 3]
            .iter()
            .chain(&["[40.0 s"; 3])
            .copied()
            .collect::<Vec<_>>()
    );
    assert!(
        out.contains("[20.0 s] 1/1: 999 received, 4 lost (0.40%), 2 duplicate, 2 reordered"),
        "{out}"
    );
}

/// A flight as pymavlink writes it: a vehicle at 50 Hz moving north at
/// 20 m/s and climbing at 1 m/s, its position every tenth frame
/// (GLOBAL_POSITION_INT or GPS_RAW_INT), losses planned in known windows
/// (25 frames in the second, 100 in the fourth, 75 in the fifth) and an
/// 8 s silence; its radio reporting each second, its rxerrors wrapping.
fn flight_plan(message: &str) -> Value {
    let drops: Vec<u64> = (600..625).chain(1600..1700).chain(2000..2075).collect();
    json!({
        "start_us": 1_764_500_000_000_000u64,
        "window_us": 10_000_000,
        "sources": [
            {"sysid": 1, "compid": 1, "rate": 50, "frames": 3500, "drop": drops,
             "silence": [[2500, 400]],
             "position": {"every": 10, "lat0": 47.0, "lon0": 8.0, "alt0_m": 500.0,
                          "north_mps": 20.0, "climb_mps": 1.0, "message": message}},
            {"sysid": 51, "compid": 68, "rate": 1, "frames": 70, "phase_us": 500_000,
             "radio": {"rxerrors0": 65_500, "rxerrors_step": 7}}
        ]
    })
}

/// mavping `--json` on a log: every line (checked against the schema).
fn json_lines_of(args: &[&str], link: &str) -> Vec<Value> {
    let mut all = vec!["--json"];
    all.extend_from_slice(args);
    all.push(link);
    let (code, out, err) = run_mavping(&all);
    assert_eq!(code, 0, "{err}");
    let lines = json_lines(&out);
    assert_schema(&lines);
    lines
}

#[test]
fn a_flight_is_told_window_by_window_with_its_losses_radio_and_distance() {
    let dir = Scratch::new("flight");
    for message in ["global", "gps"] {
        let path = dir.path(&format!("{message}.tlog"));
        let t = write_log(&path, &flight_plan(message));
        let lines = json_lines_of(&[], &tlog(&path));
        let windows: Vec<&Value> = lines
            .iter()
            .filter(|l| l["type"] == "flight_window")
            .collect();
        // 70 s of log: seven windows, the last ending with the log.
        assert_eq!(windows.len(), 7, "{message}");
        let vehicle = &t["sources"]["1/1"]["windows"];
        let radio = &t["sources"]["51/68"]["windows"];
        let mut last_rxerrors = 65_500u64;
        for (k, w) in windows.iter().enumerate() {
            let truth = &vehicle[k.to_string()];
            assert_eq!(w["index"], k as u64);
            assert_eq!(w["t_s"], 10.0 * k as f64);
            let written = truth["written"].as_u64().unwrap();
            assert_eq!(w["received"].as_u64(), Some(written), "window {k}: {w}");
            // Window 5 holds the silence: its 400 frames are past what the
            // sequence can span, which proves 400 modulo 256 of them, lost
            // in the window where the frame after the silence came.
            let mut lost = truth["numbered"].as_u64().unwrap() - written;
            if k == 5 {
                assert_eq!(lost, 400, "window {k}: {truth}");
                lost %= 256;
            }
            assert_eq!(w["lost"].as_u64(), Some(lost), "window {k}: {w}");
            // Within a metre of the truth (positions are 1e-7 degree).
            let range = &w["range"];
            let near = |key: &str| {
                let got = range[key].as_f64().unwrap();
                let want = truth[key].as_f64().unwrap();
                assert!(
                    (got - want).abs() < 1.0,
                    "window {k} {key}: {got} vs {want}"
                );
            };
            near("ground_m");
            near("distance_m");
            // RADIO_STATUS: rssi 200 less a point a second, so each
            // window's mean; rxerrors' growth through the wrap.
            let r = &radio[k.to_string()];
            let reports = r["reports"].as_u64().unwrap();
            assert_eq!(w["radio"]["reports"].as_u64(), Some(reports), "{w}");
            assert_eq!(w["radio"]["rssi"].as_f64(), Some(195.5 - 10.0 * k as f64));
            let rx = r["rxerrors_last"].as_u64().unwrap();
            let grown = (rx + 65_536 - last_rxerrors) % 65_536;
            assert_eq!(w["radio"]["rxerrors"].as_u64(), Some(grown), "{w}");
            last_rxerrors = rx;
        }
        // Windows 3, 4 and 5 lose 20 %, 15 % and (by the sequence) 59 %:
        // one burst, 30 s to 60 s.
        let bursts: Vec<&Value> = lines
            .iter()
            .filter(|l| l["type"] == "flight_burst")
            .collect();
        assert_eq!(bursts.len(), 1, "{bursts:?}");
        assert_eq!(
            (bursts[0]["t_s"].as_f64(), bursts[0]["end_t_s"].as_f64()),
            (Some(30.0), Some(60.0))
        );
        assert_eq!(bursts[0]["lost"], 100 + 75 + 400 % 256);
        assert_eq!(bursts[0]["time"], "2025-11-30T10:53:50.000000Z");
        // Silences (the radio still talking): the 100 frames dropped in a
        // row, from frame 1599 (31.98 s) to frame 1700 (34 s); the planned
        // one, from frame 2500 (50 s) to frame 2901 (58.02 s).
        let silences: Vec<(f64, f64, &str)> = lines
            .iter()
            .filter(|l| l["type"] == "flight_silence")
            .map(|l| {
                let t = |k: &str| l[k].as_f64().unwrap();
                (t("t_s"), t("end_t_s"), l["end_time"].as_str().unwrap())
            })
            .collect();
        assert_eq!(
            silences,
            [
                (31.98, 34.0, "2025-11-30T10:53:54.000000Z"),
                (50.0, 58.02, "2025-11-30T10:54:18.020000Z")
            ]
        );
        let summary = lines.last().unwrap();
        assert_eq!(summary["type"], "passive_summary");
        let f = &summary["flight"];
        assert_eq!(f["windows"], 7);
        assert_eq!(f["origin"]["kind"], "first_fix");
        assert_eq!(f["farthest"]["index"], 6, "{f}");
        // The silence's window is the worst: 144 proven lost of 244
        // numbers (truly 400 of 500), then the fourth (20 %).
        assert_eq!(f["worst"][0]["index"], 5, "{f}");
        assert_eq!(f["worst"][1]["index"], 3, "{f}");
        // The windows add up to the summary's counts.
        let sum = |key: &str| {
            windows
                .iter()
                .map(|w| w[key].as_i64().unwrap())
                .sum::<i64>()
        };
        let totals = &summary["totals"]["counts"];
        assert_eq!(sum("received"), totals["received"].as_i64().unwrap());
        assert_eq!(sum("lost"), totals["lost"].as_i64().unwrap());
    }
}

/// A vehicle at 10 Hz that goes silent three times while its SiK radio
/// (51/68, 1 Hz) goes on reporting: once with the remote figures cleared
/// to 0 (SiK lost the link: it zeroes them after ~3 s without a packet),
/// once with the signal as before and the noise 30 raw (~16 dB) up, once
/// with nothing wrong with the radio.
fn silent_flight_plan() -> Value {
    json!({
        "start_us": 1_764_500_000_000_000u64,
        "window_us": 10_000_000,
        "sources": [
            // Silent after frames 199 (19.9 s), 599 and 799, for 280, 100
            // and 100 frames: 19.9-48.0 s, 59.9-70.0 s, 79.9-90.0 s.
            {"sysid": 1, "compid": 1, "rate": 10, "frames": 1000,
             "silence": [[199, 280], [599, 100], [799, 100]]},
            {"sysid": 51, "compid": 68, "rate": 1, "frames": 100, "phase_us": 500_000,
             "radio": {
                 "figures": {"rssi": 150, "remrssi": 145, "noise": 40, "remnoise": 38},
                 "spans": [
                     {"from_us": 20_000_000, "to_us": 48_000_000,
                      "rssi": 45, "remrssi": 0, "noise": 40, "remnoise": 0},
                     {"from_us": 60_000_000, "to_us": 70_000_000,
                      "noise": 70, "remnoise": 68}
                 ]
             }}
        ]
    })
}

#[test]
fn a_silence_carries_the_radios_figures_and_what_they_say() {
    let dir = Scratch::new("flight-silence-radio");
    let path = dir.path("silent.tlog");
    let t = write_log(&path, &silent_flight_plan());
    let lines = json_lines_of(&[], &tlog(&path));
    let silences: Vec<&Value> = lines
        .iter()
        .filter(|l| l["type"] == "flight_silence")
        .collect();
    let spans: Vec<(f64, f64)> = silences
        .iter()
        .map(|s| (s["t_s"].as_f64().unwrap(), s["end_t_s"].as_f64().unwrap()))
        .collect();
    assert_eq!(spans, [(19.9, 48.0), (59.9, 70.0), (79.9, 90.0)]);
    // The radio's reports the writer put in each silence, as mavping
    // should give them: min and mean, raw and on SiK's dBm scale.
    let reports = t["sources"]["51/68"]["reports"].as_array().unwrap();
    for (s, (from, to)) in silences.iter().zip(&spans) {
        let during: Vec<&Value> = reports
            .iter()
            .filter(|r| {
                let at = r[0].as_f64().unwrap() / 1e6;
                at > *from && at < *to
            })
            .collect();
        let radio = &s["radio"];
        assert_eq!(radio["id"], json!({"sysid": 51, "compid": 68}));
        assert_eq!(radio["kind"], "sik");
        assert_eq!(radio["reports"].as_u64(), Some(during.len() as u64), "{s}");
        for (key, col) in [("rssi", 1), ("remrssi", 2), ("noise", 3), ("remnoise", 4)] {
            let raw: Vec<f64> = during.iter().map(|r| r[col].as_f64().unwrap()).collect();
            let min = raw.iter().copied().fold(f64::INFINITY, f64::min);
            let mean = raw.iter().sum::<f64>() / raw.len() as f64;
            let f = &radio[key];
            assert_eq!(f["raw_min"].as_f64(), Some(min), "{key}: {s}");
            assert!(
                (f["raw_mean"].as_f64().unwrap() - mean).abs() < 1e-9,
                "{key}: {s}"
            );
            assert_eq!(f["unit"], "dBm");
            let dbm = f["mean"].as_f64().unwrap();
            assert!((dbm - (mean / 1.9 - 127.0)).abs() < 1e-9, "{key}: {s}");
        }
    }
    // 28 reports with the remote figures 0: SiK lost the link.
    assert_eq!(silences[0]["radio"]["reports"], 28);
    assert_eq!(silences[0]["radio"]["remrssi"]["raw_mean"], 0.0);
    assert_eq!(silences[0]["radio"]["diagnosis"], "remote_cleared");
    let text = silences[0]["radio"]["diagnosis_text"].as_str().unwrap();
    assert!(
        text.starts_with(
            "remote RSSI 0 for 28 s: the ground radio heard nothing from the vehicle's"
        ),
        "{text}"
    );
    assert_eq!(silences[1]["radio"]["diagnosis"], "interference");
    assert_eq!(silences[2]["radio"]["diagnosis"], "radio_fine");
    let summary = lines.last().unwrap();
    assert_eq!(summary["flight"]["radio_kind"], "sik");
    assert_eq!(summary["flight"]["silence_count"], 3);
    assert_eq!(
        summary["flight"]["silences"][0]["radio"],
        silences[0]["radio"]
    );
    // The text tells the same under each silence.
    let (code, text, err) = run_mavping(&[&tlog(&path)]);
    assert_eq!(code, 0, "{err}");
    assert!(
        text.contains(
            "  radio 51/68 (SiK), 28 reports, min/mean: rssi -103.3/-103.3 dBm (raw 45/45.0), \
             remote rssi -127.0/-127.0 dBm (raw 0/0.0)"
        ),
        "{text}"
    );
    assert!(
        text.contains("  diagnosis: remote RSSI 0 for 28 s: the ground radio heard nothing"),
        "{text}"
    );
    assert!(
        text.contains("  diagnosis: RSSI held (-48 dBm) and the noise floor up 16 dB (to -90 dBm)"),
        "{text}"
    );
    assert!(
        text.contains("  diagnosis: the radio link's figures stayed good throughout"),
        "{text}"
    );
}

/// A HOME_POSITION before the first fix: distances are from home (the
/// start of the flight), not from the first position 4 m north of it.
#[test]
fn distances_are_from_home_when_the_log_has_one() {
    let dir = Scratch::new("flight-home");
    let path = dir.path("home.tlog");
    let mut plan = flight_plan("global");
    plan["sources"][0]["position"]["home_frame"] = json!(1);
    let t = write_log(&path, &plan);
    assert_eq!(t["sources"]["1/1"]["home"], true);
    let lines = json_lines_of(&[], &tlog(&path));
    let windows: Vec<&Value> = lines
        .iter()
        .filter(|l| l["type"] == "flight_window")
        .collect();
    assert_eq!(windows.len(), 7);
    for (k, w) in windows.iter().enumerate() {
        let truth = &t["sources"]["1/1"]["windows"][k.to_string()];
        let got = w["range"]["distance_m"].as_f64().unwrap();
        let want = truth["distance_m"].as_f64().unwrap();
        assert!((got - want).abs() < 1.0, "window {k}: {got} vs {want}");
    }
    // The last position, at 69.8 s: 1396 m north, 69.8 m up.
    let last = windows[6]["range"]["distance_m"].as_f64().unwrap();
    assert!((last - 1396f64.hypot(69.8)).abs() < 0.1, "{last}");
    let summary = lines.last().unwrap();
    assert_eq!(summary["flight"]["origin"]["kind"], "home");
    assert_eq!(summary["flight"]["origin"]["lat_deg"], 47.0);
}

/// `--plot` on a log: the flight report, drawn from the windows (loss
/// over time, RSSI over time, loss against distance) and rendered.
#[test]
fn the_flight_report_is_drawn_from_the_logs_windows() {
    let dir = Scratch::new("flight-plot");
    let path = dir.path("flight.tlog");
    write_log(&path, &flight_plan("global"));
    let svg_path = dir.path("flight.svg");
    let (code, text, err) = run_mavping(&["--plot", svg_path.to_str().unwrap(), &tlog(&path)]);
    assert_eq!(code, 0, "{err}");
    // The text's summary: the worst window first (the sixth, where the 8 s
    // silence's 400 numbers show as 400 mod 256 = 144 lost beside 100
    // received), then the fourth (20 %), the burst, the planned silence.
    for line in [
        "flight: 7 windows of 10 s; 2 silences",
        "flight worst: 50.0-60.0 s (2025-11-30T10:54:10Z to 10:54:20Z): 100 received, 144 lost (59.02%)",
        "flight worst: 30.0-40.0 s (2025-11-30T10:53:50Z to 10:54:00Z): 400 received, 100 lost (20.00%)",
        "flight burst: 30.0-60.0 s (2025-11-30T10:53:50Z to 10:54:20Z), 30.0 s: 925 received, 319 lost (25.64%)",
        "flight silence: 50.0-58.0 s (2025-11-30T10:54:10Z to 10:54:18Z), 8.0 s",
    ] {
        assert!(text.contains(line), "{line:?} not in\n{text}");
    }
    let svg = std::fs::read_to_string(&svg_path).unwrap();
    for part in [
        "the flight, 7 windows of 10 s, 2 silences, 1 loss burst, farthest 1394 m",
        "sequence loss over time",
        "radio RSSI over time",
        "sequence loss against distance",
        // 344 lost of 3 244 (25 + 100 + 75 dropped, 400 mod 256 across
        // the silence); the worst window 144 of 244.
        "\n10.60\n",
        "\n59.02\n",
    ] {
        assert!(svg.contains(part), "{part:?} is not in the plot");
    }
    // Loss, RSSI and remote RSSI lines; bars of loss by distance.
    assert!(svg.matches("<polyline").count() >= 3, "{svg}");
    let png = Rendered::of(&svg, "flight");
    assert!(png.colours.len() > 30, "{}", png.path.display());
    assert!(
        png.count(0x0072B2) > 200,
        "little blue in {}",
        png.path.display()
    );
    assert!(
        png.dark_in_rows(0..40) > 300,
        "no title in {}",
        png.path.display()
    );
}
