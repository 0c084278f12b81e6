//! Damaged frames are not lost frames (issue 38): a frame whose CRC fails
//! with its header whole arrived, so its number is not lost, and it is
//! counted per source as damaged, by message id.
//!
//! Against truth the test does not take from mavping: a real
//! QGroundControl log whose 1,949 DISTANCE_SENSOR frames fail their CRC
//! (pymavlink issue 807), counted frame by frame with pymavlink's dialect
//! (`tests/peers/tlog_crc_census.py`); and a pymavlink sender that breaks
//! the CRC of every k-th frame it sends and says which
//! (`tests/peers/damaging_sender.py`).

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Duration;

use serde_json::Value;

use crate::common::*;

/// A log in `../shared/tlogs/`; missing, the test fails: the figures below
/// are about that file and no other.
fn shared_log(name: &str) -> PathBuf {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../shared/tlogs")
        .join(name);
    assert!(
        path.is_file(),
        "{} is missing: the damaged-frame tests read the real log there",
        path.display()
    );
    path
}

/// pymavlink's walk over the log's records: figures per source.
fn census(log: &Path) -> Value {
    let out = Command::new(python())
        .arg(peer_script("tlog_crc_census.py"))
        .arg(log)
        .output()
        .expect("run tlog_crc_census.py");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("census JSON")
}

/// The `passive_summary` line of a run's output.
fn passive_summary(out: &str) -> Value {
    let line = out
        .lines()
        .rfind(|l| l.contains("\"type\":\"passive_summary\""))
        .unwrap_or_else(|| panic!("no passive_summary in\n{out}"));
    serde_json::from_str(line).unwrap()
}

/// The summary's figures for source `id` ("1/194").
fn source<'a>(s: &'a Value, id: &str) -> &'a Value {
    s["sources"]
        .as_array()
        .unwrap()
        .iter()
        .find(|r| format!("{}/{}", r["source"]["sysid"], r["source"]["compid"]) == id)
        .unwrap_or_else(|| panic!("no source {id} in {s}"))
}

/// A source's damaged frames by id, as the census gives them.
fn damaged_ids(r: &Value) -> Vec<(u64, u64)> {
    let mut ids: Vec<(u64, u64)> = r["damaged_ids"]
        .as_array()
        .unwrap()
        .iter()
        .map(|m| (n(m, "id"), n(m, "count")))
        .collect();
    ids.sort_unstable();
    ids
}

fn census_ids(c: &Value) -> Vec<(u64, u64)> {
    let mut ids: Vec<(u64, u64)> = c["damaged_ids"]
        .as_object()
        .unwrap()
        .iter()
        .map(|(id, count)| (id.parse().unwrap(), count.as_u64().unwrap()))
        .collect();
    ids.sort_unstable();
    ids
}

#[test]
fn the_ardusub_log_counts_its_distance_sensor_frames_damaged_not_lost() {
    let log = shared_log("qgc_ardusub_2023-04-18.tlog");
    let truth = census(&log);
    let (code, out, err) = run_mavping(&["--json", "-q", log.to_str().unwrap()]);
    assert!(code == 0 || code == 1, "{err}");
    let s = passive_summary(&out);
    assert_eq!(truth["junk_bytes"], 0, "every record lines up: {truth}");

    // 1/194: the companion computer's DISTANCE_SENSOR, all 132, all damaged.
    let want = &truth["sources"]["1/194"];
    assert!(n(want, "damaged") > 1_000, "{want}");
    let ids = census_ids(want);
    assert_eq!(ids, [(132, n(want, "damaged"))], "{want}");
    let got = source(&s, "1/194");
    assert_eq!(
        (n(&got["counts"], "received"), n(&got["counts"], "damaged")),
        (n(want, "good"), n(want, "damaged")),
        "{got}"
    );
    assert_eq!(damaged_ids(got), ids);
    // Counted with its damaged frames, the sequence loses only what it
    // lost: a few, where pymavlink's figure calls 61 % lost.
    assert_eq!(n(&got["counts"], "lost"), n(want, "lost"), "{got}");
    assert!(n(want, "lost") * 100 < n(want, "damaged"), "{want}");
    assert!(n(&got["pymav"], "loss") >= n(want, "damaged"), "{got}");

    // Every source: damaged frames by id as pymavlink's dialect finds them,
    // received as its good ones (the log has no id this build lacks).
    for (id, want) in truth["sources"].as_object().unwrap() {
        let got = source(&s, id);
        assert_eq!(n(want, "unknown"), 0, "{id}: {want}");
        assert_eq!(
            (n(&got["counts"], "received"), n(&got["counts"], "damaged")),
            (n(want, "good"), n(want, "damaged")),
            "{id}: {got}"
        );
        assert_eq!(damaged_ids(got), census_ids(want), "{id}");
    }
    // 1/100, the camera: its 8 damaged frames fill its sequence whole.
    let camera = &truth["sources"]["1/100"];
    assert_eq!(n(&source(&s, "1/100")["counts"], "lost"), n(camera, "lost"));

    // The scanner's and the log's figures: damaged, not junk.
    let damaged: u64 = truth["sources"]
        .as_object()
        .unwrap()
        .values()
        .map(|c| n(c, "damaged"))
        .sum();
    assert_eq!(n(&s["frames"], "damaged"), damaged, "{}", s["frames"]);
    assert_eq!(n(&s["frames"], "bad_crc"), 0);
    let records = &s["log"]["records"];
    assert_eq!(
        (
            n(records, "damaged"),
            n(records, "junk_bytes"),
            n(records, "bad_crc")
        ),
        (damaged, 0, 0),
        "{records}"
    );
    assert_eq!(
        n(records, "records") + n(records, "damaged") + n(records, "unknown_id"),
        n(&truth, "records")
    );
    assert_schema(&json_lines(&out));

    // The text summary says it per source, by name.
    let (_, text, _) = run_mavping(&[log.to_str().unwrap()]);
    let line = format!(
        "damaged: 1/194 {} frames whose CRC failed (DISTANCE_SENSOR ×{})",
        n(want, "damaged"),
        n(want, "damaged")
    );
    assert!(text.contains(&line), "{line}\n{text}");
    assert!(
        text.contains(&format!(
            "log: {damaged} records whose frame failed its CRC"
        )),
        "{text}"
    );
}

#[test]
fn frames_a_peer_damaged_on_udp_are_counted_damaged_per_source_and_not_lost() {
    let listen = free_udp_port();
    let recording =
        std::env::temp_dir().join(format!("mavping-damaged-{}.tlog", std::process::id()));
    let run = start_mavping(&[
        "--passive",
        "--json",
        "--no-heartbeat",
        "--tlog",
        recording.to_str().unwrap(),
        &format!("udpin:127.0.0.1:{listen}"),
    ]);
    let mut peer = Peer::start(
        "damaging_sender.py",
        &[
            &format!("udpout:127.0.0.1:{listen}"),
            "--source",
            "1:10",
            "--source",
            "2:7",
            // Every HEARTBEAT of 3/1 damaged: no system is heard by them.
            "--source",
            "3:1:heartbeat",
            "--frames",
            "300",
            "--rate",
            "100",
        ],
    );
    let truth: Value = serde_json::from_str(&peer.read_line()).expect("the sender's truth");
    // The last datagrams are through the loopback in well under this.
    std::thread::sleep(Duration::from_millis(300));
    signal(run.child.id(), "INT");
    let (code, out, err) = run.wait(Duration::from_secs(20));
    assert_eq!(code, 0, "{out}{err}");
    let s = passive_summary(&out);
    for id in ["1/1", "2/1"] {
        let want = &truth[id];
        assert!(n(want, "damaged") >= 30, "{truth}");
        let got = source(&s, id);
        let c = &got["counts"];
        assert_eq!(
            (n(c, "received"), n(c, "damaged"), n(c, "lost")),
            (n(want, "good"), n(want, "damaged"), 0),
            "{id}: {got}\n{truth}"
        );
        // ATTITUDE is id 30.
        assert_eq!(damaged_ids(got), [(30, n(want, "damaged"))], "{id}");
    }
    let hb = source(&s, "3/1");
    assert_eq!(n(&truth["3/1"], "good"), 0, "{truth}");
    assert_eq!(
        (n(&hb["counts"], "received"), n(&hb["counts"], "damaged")),
        (0, n(&truth["3/1"], "damaged")),
        "{hb}"
    );
    assert_eq!(damaged_ids(hb), [(0, n(&truth["3/1"], "damaged"))]);
    assert!(
        hb["identity"].is_null(),
        "heard by a damaged HEARTBEAT: {hb}"
    );
    assert!(
        !out.lines()
            .any(|l| l.contains("\"responder\"") && l.contains("\"sysid\":3")),
        "{out}"
    );
    let damaged: u64 = ["1/1", "2/1", "3/1"]
        .iter()
        .map(|id| n(&truth[*id], "damaged"))
        .sum();
    assert_eq!(n(&s["frames"], "damaged"), damaged, "{}", s["frames"]);
    assert_eq!(n(&s["frames"], "bad_crc"), 0, "{}", s["frames"]);
    assert_eq!(n(&s["totals"]["counts"], "damaged"), damaged);
    assert_schema(&json_lines(&out));

    // The recording keeps the damaged frames as they came: read back, they
    // are damaged records, between the good ones.
    let (code, out, err) = run_mavping(&["--json", "-q", recording.to_str().unwrap()]);
    let _ = std::fs::remove_file(&recording);
    assert_eq!(code, 0, "{out}{err}");
    let back = passive_summary(&out);
    assert_eq!(
        n(&back["log"]["records"], "damaged"),
        damaged,
        "{}",
        back["log"]
    );
    assert_eq!(
        n(&back["log"]["records"], "junk_bytes"),
        0,
        "{}",
        back["log"]
    );
    for id in ["1/1", "2/1"] {
        let c = &source(&back, id)["counts"];
        assert_eq!(
            (n(c, "received"), n(c, "damaged"), n(c, "lost")),
            (n(&truth[id], "good"), n(&truth[id], "damaged"), 0),
            "{id}: {c}"
        );
    }
}
