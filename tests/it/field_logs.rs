//! `tlog:FILE` on logs shaped like the real ground stations' in
//! shared/tlogs, written with their truth by `tests/peers/field_tlog.py`:
//! QGroundControl's batches a second apart with whole-ms stamps (as
//! vtol.tlog), losses next to the pauses, outages long enough to wrap the
//! 8-bit counter and a delayed burst, a reboot, the ground station's own
//! frames logged in part and a second counter under its id, damaged and
//! unknown-id frames, two programs under one id, MAVProxy's link bits, a
//! SiK radio.
//!
//! Asserted here is what mavping gets right today and must keep: each
//! source's `received` is the frames written whole (a good CRC and a
//! known id), which is also pymavlink's count (the writer's own reading
//! with pymavlink, and `mavloss.py` with MAVLINK20=1), and the log's time
//! span. What the new sequence rules must count (loss across batch
//! pauses, silences, restarts, damaged frames, ground-station frames,
//! second counters) is listed at the end of each test as `// lead:`
//! comments: which truth field each figure should equal.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;

use serde_json::Value;

use crate::common::*;
use crate::tlog::{mavloss_env, read, tlog, Scratch};

/// A log written by field_tlog.py, its truth, and mavping's summary of it.
struct Field {
    path: PathBuf,
    truth: Value,
    summary: Value,
}

impl Field {
    /// `field_tlog.py LOG --truth JSON ARGS`, then `mavping --json -q
    /// tlog:LOG`.
    fn write_and_read(dir: &Scratch, name: &str, args: &[&str]) -> Field {
        let path = dir.path(&format!("{name}.tlog"));
        let truth_path = dir.path(&format!("{name}.json"));
        let out = Command::new(python())
            .arg(peer_script("field_tlog.py"))
            .arg(&path)
            .arg("--truth")
            .arg(&truth_path)
            .args(args)
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "field_tlog.py {args:?}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        let truth: Value =
            serde_json::from_str(&std::fs::read_to_string(&truth_path).unwrap()).unwrap();
        // The writer read its log back with pymavlink: every source's good
        // frames, the radio's, the damaged ones as BAD_DATA and the
        // unknown ids as UNKNOWN_60045, as it wrote them.
        assert_eq!(
            truth["pymavlink_agrees"], true,
            "{name}: pymavlink reads {}",
            truth["pymavlink"]
        );
        let (code, summary, err) = read(&["-q"], &tlog(&path));
        assert_eq!(code, 0, "{name}: {err}");
        Field {
            path,
            truth,
            summary,
        }
    }

    /// The truth of source "S/C".
    fn truth(&self, id: &str) -> &Value {
        let t = &self.truth["sources"][id];
        assert!(t.is_object(), "no {id} in the truth");
        t
    }

    fn truth_u64(&self, id: &str, key: &str) -> u64 {
        self.truth(id)[key]
            .as_u64()
            .unwrap_or_else(|| panic!("{id}: no {key} in the truth"))
    }

    /// mavping's figures for source "S/C".
    fn source(&self, id: &str) -> &Value {
        self.summary["sources"]
            .as_array()
            .unwrap()
            .iter()
            .find(|s| sc(s) == id)
            .unwrap_or_else(|| panic!("no {id} in {}", self.summary["sources"]))
    }

    fn received(&self, id: &str) -> u64 {
        self.count(id, "received")
    }

    /// One of mavping's sequence counts for source "S/C".
    fn count(&self, id: &str, key: &str) -> u64 {
        self.source(id)["counts"][key].as_u64().unwrap()
    }

    /// mavping's silences of source "S/C" that ended before the log did.
    fn silences(&self, id: &str) -> Vec<&Value> {
        self.source(id)["silences"]
            .as_array()
            .unwrap()
            .iter()
            .filter(|s| s["ongoing"] == false)
            .collect()
    }
}

fn sc(s: &Value) -> String {
    format!("{}/{}", s["source"]["sysid"], s["source"]["compid"])
}

/// What mavping gets right today, on any of these logs: each source's
/// `received` is its frames written with a good CRC and a known id (no
/// source more, none less); pymavlink counts the same (`mavloss.py`); the
/// records and the span are the log's.
fn assert_received_and_span(f: &Field) {
    let sources = f.truth["sources"].as_object().unwrap();
    let with_frames: Vec<&String> = sources
        .iter()
        .filter(|(_, s)| s["good"].as_u64().unwrap() > 0)
        .map(|(id, _)| id)
        .collect();
    for id in &with_frames {
        // A frame of an id the dialect does not know took its number
        // from its source's counter: received too.
        let unknown = f.truth(id)["unknown_id_total"].as_u64().unwrap_or(0);
        assert_eq!(
            f.received(id),
            f.truth_u64(id, "good") + unknown,
            "{id}: received (mavping) vs good + unknown ids (truth): {}",
            f.source(id)
        );
        assert_eq!(
            f.source(id)["radio"],
            *id == "51/68",
            "{id}: {}",
            f.source(id)
        );
    }
    let listed: Vec<String> = f.summary["sources"]
        .as_array()
        .unwrap()
        .iter()
        .map(sc)
        .collect();
    assert_eq!(
        listed.len(),
        with_frames.len(),
        "mavping lists {listed:?}, the truth {with_frames:?}"
    );
    // pymavlink's own tool, MAVLink 2 on: the same frames per source (the
    // radio left out, by design).
    let loss = mavloss_env(&f.path, &[("MAVLINK20", "1")]);
    let packets: BTreeMap<String, u64> = loss
        .sources
        .iter()
        .map(|((sys, comp), (count, _))| (format!("{sys}/{comp}"), *count))
        .collect();
    let expect: BTreeMap<String, u64> = with_frames
        .iter()
        .filter(|id| **id != "51/68")
        .map(|id| ((*id).clone(), f.truth_u64(id, "good")))
        .collect();
    assert_eq!(packets, expect, "mavloss.py (left), the truth (right)");
    assert_eq!(loss.total.0, expect.values().sum::<u64>());
    // Every good frame is a record; the stamps are the log's (link bits
    // cleared), its span the session's length (to the clock's next ms).
    let t = &f.truth;
    let log = &f.summary["log"];
    assert_eq!(log["records"]["records"], t["totals"]["good"], "{log}");
    assert_eq!(log["stamps"]["first_us"], t["first_us"], "{log}");
    assert_eq!(log["stamps"]["latest_us"], t["last_us"], "{log}");
    assert_eq!(log["stamps"]["whole_ms"], t["stamps"]["whole_ms"], "{log}");
    // Damaged and unknown-id records are records too (on link 0 here).
    let mut low_bits = t["stamps"]["low_bits"].clone();
    let extra = t["totals"]["damaged"].as_u64().unwrap_or(0)
        + t["totals"]["unknown_id"].as_u64().unwrap_or(0);
    low_bits[0] = (low_bits[0].as_u64().unwrap() + extra).into();
    assert_eq!(log["stamps"]["low_bits"], low_bits, "{log}");
    assert_eq!(
        log["records"]["damaged"],
        t["totals"]["damaged"].as_u64().unwrap_or(0)
    );
    let span = t["span_s"].as_f64().unwrap();
    let duration = f.summary["duration_s"].as_f64().unwrap();
    assert!(
        (span - 1e-6..span + 0.002).contains(&duration),
        "duration {duration} s, the log's span {span} s"
    );
    assert_eq!(log["complete"], true);
    assert_eq!(f.summary["rx_clock"], "the log's time stamps");
}

/// `field_tlog.py --shape`: a log's stamps (equal ones, pauses, batches).
fn shape(path: &Path) -> Value {
    let out = Command::new(python())
        .arg(peer_script("field_tlog.py"))
        .arg("--shape")
        .arg(path)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).unwrap()
}

/// A real log in shared/tlogs (beside the repository, as CI lays it).
pub(crate) fn shared_tlog(name: &str) -> PathBuf {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../shared/tlogs")
        .join(name);
    assert!(path.exists(), "{} is not there", path.display());
    path
}

#[test]
fn qgroundcontrol_batches_a_second_apart_as_in_vtol_tlog() {
    // vtol.tlog's shape: ArduPlane in MAVLink 1 at 115 frames/s, logged by
    // QGroundControl in batches about 1.05 s apart; ten losses, six of
    // them right next to a pause (the last frame before pause 5, the two
    // first after pause 9, the three last before pause 14).
    let dir = Scratch::new("field-batched");
    let f = Field::write_and_read(
        &dir,
        "batched",
        &[
            "--batched",
            "--mavlink1",
            "--duration",
            "90",
            "--lose",
            "100,200-202,<p5,>p9:2,<p14:3",
        ],
    );
    assert_received_and_span(&f);
    let t = &f.truth;
    assert_eq!(f.truth_u64("1/1", "lost"), 10);
    assert_eq!(
        f.truth("1/1")["lost_near_pauses"].as_array().unwrap().len(),
        6
    );
    // No number goes missing across a pause but the frames lost there:
    // those planned next to pauses 5, 9 and 14 (and any other loss that
    // falls on one).
    let missing = t["batches"]["missing_across_pauses"]["1/1"]
        .as_array()
        .unwrap();
    for planned in [[5, 1], [9, 2], [14, 3]] {
        assert!(missing.contains(&serde_json::json!(planned)), "{missing:?}");
    }
    let across: u64 = missing.iter().map(|m| m[1].as_u64().unwrap()).sum();
    assert!(across <= f.truth_u64("1/1", "lost"), "{missing:?}");
    // The synthetic log looks like the real one.
    let ours = shape(&f.path);
    let real = shape(&shared_tlog("vtol.tlog"));
    let near = |key: &str, i: usize, within: f64| {
        let (a, b) = (
            ours[key][i].as_f64().unwrap(),
            real[key][i].as_f64().unwrap(),
        );
        assert!(
            (a - b).abs() <= within * b,
            "{key}[{i}]: {a} here, {b} in vtol.tlog\nours {ours}\nreal {real}"
        );
    };
    let share = |v: &Value| v["equal_consecutive_share"].as_f64().unwrap();
    assert!(
        (share(&ours) - share(&real)).abs() < 0.05,
        "ours {ours}\nreal {real}"
    );
    // Pauses' p10 and median within 5 %; frames per batch within 15 %.
    near("pause_s_p10_p50_p90_max", 0, 0.05);
    near("pause_s_p10_p50_p90_max", 1, 0.05);
    near("frames_per_batch_p10_p50_p90", 1, 0.15);
    assert_eq!(ours["whole_ms"], true);
    let summary = &f.summary;
    assert_eq!(summary["log"]["stamps"]["whole_ms"], true);
    // The batch pauses hide no number; the losses next to them count as
    // any other, exactly.
    assert_eq!(f.count("1/1", "lost"), f.truth_u64("1/1", "lost"));
    assert_eq!(f.count("1/1", "resyncs"), 0);
    assert_eq!(summary["totals"]["counts"]["lost"], t["totals"]["lost"]);
    assert_eq!(f.source("1/1")["pymav"]["loss"], 10);
    // A pause of ~1.05 s every second is the logger's routine, not a
    // silence: at most the first pauses, before a second of its rhythm is
    // in, are told, and as delayed (nothing missing across them).
    let routine = f.source("1/1")["routine_pause_ns"].as_u64().unwrap();
    assert!((800_000_000..1_200_000_000).contains(&routine), "{routine}");
    let silences = f.silences("1/1");
    assert!(silences.len() <= 2, "{silences:?}");
    for s in silences {
        assert!(s["lost_estimated"].is_null(), "{s}");
        assert!(s["start"].as_u64().unwrap() < 4_000_000_000, "{s}");
    }
}

#[test]
fn outages_that_wrap_the_counter_and_a_burst_after_a_pause() {
    // 115 frames/s: a 4.2 s outage holds 483 numbers (227 mod 256), a
    // 2.2 s one 253; then a 2.2 s pause after which the frames come in a
    // burst, none missing. The radio reports through all of it.
    let dir = Scratch::new("field-outages");
    let f = Field::write_and_read(
        &dir,
        "outages",
        &[
            "--batched",
            "--radio",
            "--silence",
            "12:4.2,30:2.2",
            "--delayed",
            "45:2.2",
            "--lose",
            "300,301,2500,>p20",
        ],
    );
    assert_received_and_span(&f);
    let outages = f.truth["outages"].as_array().unwrap();
    let one = |k: usize| &outages[k]["counters"]["1/1"];
    assert_eq!(one(0)["numbered"], 483);
    assert_eq!(one(0)["numbered_mod_256"], 227);
    assert_eq!(one(1)["numbered"], 253);
    assert_eq!(outages[2]["kind"], "delayed");
    assert_eq!(one(2)["any_missing"], false);
    assert_eq!(one(2)["apparent_gap_mod_256"], 0);
    // The radio went on: every report it numbered is in the log.
    assert_eq!(f.truth_u64("51/68", "lost"), 0);
    assert_eq!(f.received("51/68"), f.truth_u64("51/68", "sent"));
    // What the sequence proves across each outage is counted (its gap,
    // modulo 256), never less; the rest the rate suggests is apart.
    let gap = |k: usize| one(k)["apparent_gap_mod_256"].as_u64().unwrap();
    assert_eq!(
        f.count("1/1", "lost"),
        f.truth_u64("1/1", "lost") + gap(0) + gap(1)
    );
    // The outages and the delayed pause are silences (besides, at most,
    // the first batch pauses before their rhythm is known, told as
    // delayed).
    let long: Vec<&Value> = f
        .silences("1/1")
        .into_iter()
        .filter(|s| s["length_ns"].as_u64().unwrap() > 2_000_000_000)
        .collect();
    assert_eq!(long.len(), 3, "{long:?}");
    for (k, s) in long.iter().enumerate() {
        assert_eq!(s["restart"], false, "{s}");
        assert_eq!(s["seq_lost"].as_u64(), Some(gap(k)), "{s}");
    }
    // The 4.2 s outage wrapped the counter: the rate says how often,
    // within a few frames of the numbers it held.
    let numbered = one(0)["numbered"].as_u64().unwrap();
    let likely = long[0]["lost_estimated"].as_u64().unwrap();
    assert!(likely.abs_diff(numbered) <= numbered / 50, "{}", long[0]);
    // The 2.2 s one did not (253 < 256): its gap alone, no wrap likelier.
    assert!(
        long[1]["lost_estimated"].is_null() || long[1]["lost_estimated"] == long[1]["seq_lost"],
        "{}",
        long[1]
    );
    // The pause after which the frames came in a burst: delayed, not lost.
    assert!(long[2]["lost_estimated"].is_null(), "{}", long[2]);
    // The radio reported through the outages: no loss, no silence.
    assert_eq!(f.count("51/68", "lost"), 0);
    assert!(f.silences("51/68").is_empty());
}

#[test]
fn a_reboot_starts_the_counter_again_at_zero() {
    // As ArduPilot's SITL in flight_logs.tlog: a second of nothing, then
    // STATUSTEXT, PARAM_VALUE... numbered from 0.
    let dir = Scratch::new("field-reboot");
    let f = Field::write_and_read(
        &dir,
        "reboot",
        &["--reboot", "25", "--radio", "--lose", "50,51"],
    );
    assert_received_and_span(&f);
    let reboot = &f.truth["reboots"][0];
    assert_eq!(reboot["first_seq_after"], 0);
    assert_eq!(reboot["first_msgs_after"][0], "STATUSTEXT");
    assert_eq!(reboot["numbered_while_off"], 0);
    // The restart loses nothing: only the planned losses count.
    assert_eq!(f.count("1/1", "lost"), f.truth_u64("1/1", "lost"));
    let restarts: Vec<&Value> = f
        .silences("1/1")
        .into_iter()
        .filter(|s| s["restart"] == true)
        .collect();
    assert_eq!(restarts.len(), 1, "{:?}", f.silences("1/1"));
    assert!(restarts[0]["seq_lost"].is_null());
    let length = restarts[0]["length_ns"].as_f64().unwrap() / 1e9;
    let pause = reboot["log_pause_s"].as_f64().unwrap();
    assert!(
        (length - pause).abs() < 0.1,
        "{length} s, the log's {pause} s"
    );
}

#[test]
fn the_ground_stations_own_frames_logged_in_part_and_its_second_counter() {
    // QGroundControl's 255/190, as in qgc_ardusub_2023-04-18.tlog:
    // HEARTBEAT and MANUAL_CONTROL numbered by one counter, about every
    // 13th number spent on a frame it never logged; REQUEST_DATA_STREAM
    // every 0.5 s numbered 1..7 again and again by a small counter of its
    // own (35 frames).
    let dir = Scratch::new("field-gcs");
    let f = Field::write_and_read(
        &dir,
        "gcs",
        &[
            "--batched",
            "--gcs",
            "--gcs-second-counter",
            "--radio",
            "--lose",
            "400,401",
        ],
    );
    assert_received_and_span(&f);
    let gcs = f.truth("255/190");
    let a = &gcs["counters"]["255/190:A"];
    let b = &gcs["counters"]["255/190:B"];
    assert!(a["not_logged"].as_u64().unwrap() > 50, "{a}");
    assert_eq!(b["not_logged"], 0);
    assert_eq!(b["good"], 35);
    assert_eq!(b["cycle"], serde_json::json!([1, 7]));
    assert_eq!(
        f.received("255/190"),
        a["good"].as_u64().unwrap() + b["good"].as_u64().unwrap()
    );
    // The ground station's own frames are apart: out of the link's
    // totals, which are the vehicle's alone.
    assert_eq!(f.source("255/190")["ground"], true);
    assert_eq!(f.source("1/1")["ground"], false);
    let totals = &f.summary["totals"];
    assert_eq!(totals["ground_received"], f.truth("255/190")["good"]);
    assert_eq!(totals["counts"]["received"], f.truth("1/1")["good"]);
    assert_eq!(totals["counts"]["lost"], 2);
    assert_eq!(f.count("1/1", "lost"), f.truth_u64("1/1", "lost"));
    // Its REQUEST_DATA_STREAM counter, read on its own: all but at most
    // the first frame (heard before a second counter was evident, or on
    // the main counter's very next number), none lost.
    let second = &f.source("255/190")["second_counter"];
    let got = second["counts"]["received"].as_u64().unwrap();
    let b_good = b["good"].as_u64().unwrap();
    assert!((b_good - 2..=b_good + 2).contains(&got), "{second}");
    assert_eq!(second["msg_ids"][0]["id"], 66, "{second}");
    // The main counter's gaps are the numbers it spent on frames it did
    // not log (and the second counter's frames it took), not link loss.
    let not_logged = a["not_logged"].as_u64().unwrap();
    let main_lost = f.count("255/190", "lost") - second["counts"]["lost"].as_u64().unwrap();
    assert!(
        main_lost.abs_diff(not_logged) <= 3,
        "{main_lost} vs {not_logged} not logged: {}",
        f.source("255/190")
    );
    assert_eq!(f.count("255/190", "duplicate"), 0);
    assert_eq!(f.count("255/190", "reordered"), 0);
}

#[test]
fn damaged_frames_and_unknown_ids_are_not_received_and_not_lost() {
    // As the BlueOS/ArduSub log (qgc_ardusub_2023-04-18.tlog): 60 % of a
    // companion's DISTANCE_SENSOR frames with a broken CRC, some of the
    // vehicle's ATTITUDE too; frames of id 60045, unknown to the dialect,
    // each taking a number of its source's sequence.
    let dir = Scratch::new("field-damage");
    let f = Field::write_and_read(
        &dir,
        "damage",
        &[
            "--batched",
            "--damage",
            "1/194:DISTANCE_SENSOR:0.6",
            "--damage",
            "1/1:ATTITUDE:0.1",
            "--unknown",
            "1/1:20",
            "--unknown",
            "1/194:5",
            "--gcs",
        ],
    );
    assert_received_and_span(&f);
    assert!(f.truth_u64("1/194", "damaged_total") > 300);
    assert_eq!(
        f.truth("1/194")["damaged"]["132"],
        f.truth("1/194")["damaged_total"]
    );
    assert_eq!(f.truth_u64("1/1", "unknown_id_total"), 20);
    assert_eq!(f.truth_u64("1/1", "lost"), 0);
    // Damaged frames arrived: counted apart, by id, filling their
    // numbers; an unknown id's frame is received. Nothing is lost.
    for (id, msg) in [("1/194", 132), ("1/1", 30)] {
        assert_eq!(f.count(id, "damaged"), f.truth_u64(id, "damaged_total"));
        assert_eq!(
            f.source(id)["damaged_ids"],
            serde_json::json!([{"id": msg, "count": f.truth_u64(id, "damaged_total")}]),
            "{id}"
        );
        assert_eq!(f.count(id, "lost"), f.truth_u64(id, "lost"), "{id}");
    }
    assert_eq!(f.count("1/194", "lost"), 0);
}

#[test]
fn two_programs_numbering_frames_under_one_id() {
    // 1/191: counters A and B take turns, 20 frames/s, a few losses in
    // each.
    let dir = Scratch::new("field-two");
    let f = Field::write_and_read(&dir, "two", &["--batched", "--two-counters", "1/191"]);
    assert_received_and_span(&f);
    let two = f.truth("1/191");
    let counter = |c: &str, k: &str| two["counters"][c][k].as_u64().unwrap();
    assert_eq!(
        f.received("1/191"),
        counter("1/191:A", "good") + counter("1/191:B", "good")
    );
    assert!(counter("1/191:A", "lost") > 0 && counter("1/191:B", "lost") > 0);
    // Each counter is read on its own: its own losses, none made up.
    assert_eq!(f.count("1/191", "lost"), f.truth_u64("1/191", "lost"));
    assert_eq!(f.count("1/191", "duplicate"), 0);
    assert_eq!(f.count("1/191", "reordered"), 0);
    let second = &f.source("1/191")["second_counter"];
    let got = second["counts"]["received"].as_u64().unwrap();
    let which = ["1/191:A", "1/191:B"]
        .into_iter()
        .find(|c| counter(c, "good") == got)
        .unwrap_or_else(|| panic!("{second} is neither counter: {two}"));
    assert_eq!(
        second["counts"]["lost"].as_u64(),
        Some(counter(which, "lost"))
    );
}

#[test]
fn mavproxy_link_bits_tell_what_the_ground_station_sent() {
    // MAVProxy's stamps: (usec & ~3) | link, 3 for its own frames.
    let dir = Scratch::new("field-mavproxy");
    let f = Field::write_and_read(
        &dir,
        "mavproxy",
        &[
            "--mavproxy-links",
            "--gcs",
            "255/0",
            "--radio",
            "--lose",
            "50,51,300",
        ],
    );
    assert_received_and_span(&f);
    let links = f.summary["per_link"]["links"]
        .as_array()
        .unwrap_or_else(|| panic!("no per_link: {}", f.summary));
    let on = |n: u64| -> BTreeMap<String, u64> {
        links
            .iter()
            .find(|l| l["link"] == n)
            .unwrap_or_else(|| panic!("no link {n}: {links:?}"))["sources"]
            .as_array()
            .unwrap()
            .iter()
            .map(|s| (sc(s), s["counts"]["received"].as_u64().unwrap()))
            .collect()
    };
    let good = |id: &str| f.truth_u64(id, "good");
    assert_eq!(
        on(0),
        BTreeMap::from([
            ("1/1".to_string(), good("1/1")),
            ("51/68".to_string(), good("51/68"))
        ])
    );
    assert_eq!(
        on(3),
        BTreeMap::from([("255/0".to_string(), good("255/0"))])
    );
    // What only link 3 carried is what MAVProxy sent: the ground
    // station's, out of the link's totals.
    assert_eq!(f.source("255/0")["ground"], true);
    assert_eq!(f.source("1/1")["ground"], false);
    assert_eq!(f.count("1/1", "lost"), f.truth_u64("1/1", "lost"));
    assert_eq!(
        f.summary["totals"]["ground_received"],
        f.truth("255/0")["good"]
    );
}

#[test]
fn everything_at_once() {
    // Every scenario in one log: the figures above must not disturb each
    // other.
    let dir = Scratch::new("field-all");
    let f = Field::write_and_read(
        &dir,
        "all",
        &[
            "--batched",
            "--radio",
            "--gcs",
            "--gcs-second-counter",
            "--two-counters",
            "1/191",
            "--damage",
            "1/194:DISTANCE_SENSOR:0.5",
            "--unknown",
            "1/1:10",
            "--silence",
            "10:4.2,28:2.2",
            "--delayed",
            "40:2.2",
            "--reboot",
            "50",
            "--lose",
            "100,<p3,>p7:2,1/194@40",
            "--duration",
            "70",
        ],
    );
    assert_received_and_span(&f);
    // lead: each figure of the tests above, on this log's truth.
}
