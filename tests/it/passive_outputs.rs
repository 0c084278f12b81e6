//! A passive run's outputs beside its summary: `-Q` and SIGQUIT interim
//! figures, and `--samples` rows, held against the summary and against the
//! simulated link's own count of what it did to each source's frames.
//! (`--live` is in `live.rs`, `--plot` in `views.rs`.)

use std::collections::BTreeMap;
use std::time::Duration;

use serde_json::Value;

use crate::common::*;

/// Two vehicles at 56 frames a second (ATTITUDE, GLOBAL_POSITION_INT and
/// HEARTBEAT), 5% of their frames lost on the way down, 2% doubled, 2%
/// arriving after a later one.
const FAULTY: &str = "sim:?clock=virtual&responders=2&stream=ATTITUDE@50,GLOBAL_POSITION_INT@5\
                      &loss_down=5%&dup_down=2%&reorder_down=2%&seed=3";

/// The figures of source `id` (`SYS/COMP`) in a line's `sources`.
fn source<'a>(line: &'a Value, id: &str) -> &'a Value {
    line["sources"]
        .as_array()
        .unwrap()
        .iter()
        .find(|s| format!("{}/{}", s["source"]["sysid"], s["source"]["compid"]) == id)
        .unwrap_or_else(|| panic!("no {id} in {line}"))
}

fn count(s: &Value, key: &str) -> i64 {
    s["counts"][key].as_i64().unwrap()
}

/// What the simulated link did to `id`'s frames, as the counts say it.
fn assert_truth(err: &str, id: &str, received: i64, lost: i64, duplicate: i64, reordered: i64) {
    let truth = |k| sim_truth(err, id, k) as i64;
    assert_eq!(lost, truth("down_dropped"), "{id}: {err}");
    assert_eq!(duplicate, truth("down_duplicates_arrived"), "{id}");
    assert_eq!(reordered, truth("down_reordered"), "{id}");
    assert_eq!(
        received,
        truth("down_delivered") + truth("down_duplicates_arrived"),
        "{id}"
    );
}

/// `--samples` rows by their columns' names.
fn rows(csv: &str) -> Vec<BTreeMap<String, String>> {
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().expect("a header").split(',').collect();
    lines
        .map(|l| {
            // Only the link, the last column, may be quoted.
            let fields: Vec<&str> = l.splitn(header.len(), ',').collect();
            assert_eq!(fields.len(), header.len(), "{l}");
            header
                .iter()
                .zip(fields)
                .map(|(h, f)| {
                    let f = match f.strip_prefix('"').and_then(|f| f.strip_suffix('"')) {
                        Some(quoted) => quoted.replace("\"\"", "\""),
                        None => f.to_string(),
                    };
                    (h.to_string(), f)
                })
                .collect()
        })
        .collect()
}

fn field(row: &BTreeMap<String, String>, key: &str) -> i64 {
    row[key]
        .parse()
        .unwrap_or_else(|_| panic!("{key} in {row:?}"))
}

/// The sums of a source's rows up to `t_s` (inclusive), by column.
fn sums(rows: &[BTreeMap<String, String>], id: &str, t_s: f64) -> BTreeMap<&'static str, i64> {
    let mine: Vec<_> = rows
        .iter()
        .filter(|r| format!("{}/{}", r["sysid"], r["compid"]) == id)
        .filter(|r| r["t_s"].parse::<f64>().unwrap() <= t_s + 1e-9)
        .collect();
    ["received", "lost", "duplicate", "reordered", "bytes"]
        .into_iter()
        .map(|k| (k, mine.iter().map(|r| field(r, k)).sum()))
        .collect()
}

#[test]
fn interim_figures_follow_the_run_to_the_summary_and_the_truth() {
    let dir = std::env::temp_dir().join(format!("mavping-passive-q-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let csv = dir.join("samples.csv");
    // 10 s: the run ends on a frame that arrived, so the sequence has seen
    // every drop (the link counts a drop when the frame is sent; one among
    // the last frames would be seen only with the frame after it).
    let (code, out, err) = run_mavping(&[
        "--passive",
        "-w",
        "10",
        "--json",
        "-Q",
        "2s",
        "-v",
        "--samples",
        csv.to_str().unwrap(),
        FAULTY,
    ]);
    assert_eq!(code, 0, "{out}{err}");
    let samples = rows(&std::fs::read_to_string(&csv).unwrap());
    std::fs::remove_dir_all(&dir).unwrap();
    let events = json_lines(&out);
    assert_schema(&events);
    let interims: Vec<&Value> = events
        .iter()
        .filter(|e| e["type"] == "passive_interim")
        .collect();
    // Every 2 s of the 10, quiet otherwise: nothing but the interims and
    // the summary.
    let times: Vec<f64> = interims
        .iter()
        .map(|i| i["t_s"].as_f64().unwrap())
        .collect();
    assert_eq!(times, [2.0, 4.0, 6.0, 8.0]);
    let summary = events
        .iter()
        .find(|e| e["type"] == "passive_summary")
        .unwrap();
    assert_eq!(events.len(), interims.len() + 1, "{out}");
    for id in ["1/1", "2/1"] {
        let mut last = 0;
        for interim in &interims {
            let s = source(interim, id);
            let t = interim["t_s"].as_f64().unwrap();
            // The figures so far grow with the run, at the stream's rate
            // less what the link lost...
            let received = count(s, "received");
            assert!(received > last, "{id} at {t} s: {s}");
            last = received;
            let rate = received as f64 / t;
            assert!((50.0..=58.0).contains(&rate), "{id} at {t} s: {s}");
            // ...and are what the samples add up to at the same time.
            let sums = sums(&samples, id, t);
            for key in ["received", "lost", "duplicate", "reordered"] {
                assert_eq!(sums[key], count(s, key), "{id} {key} at {t} s");
            }
            assert_eq!(sums["bytes"], s["bytes"].as_i64().unwrap(), "{id}");
        }
        let end = source(summary, id);
        assert!(count(end, "received") > last, "{id}: {end}");
        // The loss so far tends to the run's: 5% of the frames sent.
        let so_far = source(interims.last().unwrap(), id)["loss_pct"]
            .as_f64()
            .unwrap();
        let final_pct = end["loss_pct"].as_f64().unwrap();
        assert!((so_far - final_pct).abs() < 1.5, "{so_far} {final_pct}");
        assert!((2.0..=8.0).contains(&final_pct), "{end}");
        assert_truth(
            &err,
            id,
            count(end, "received"),
            count(end, "lost"),
            count(end, "duplicate"),
            count(end, "reordered"),
        );
    }

    // In text: a line per source at each interim, in quiet mode too.
    let (code, text, err) = run_mavping(&["--passive", "-w", "5", "-q", "-Q", "2s", FAULTY]);
    assert_eq!(code, 0, "{text}{err}");
    let lines: Vec<&str> = text.lines().filter(|l| l.starts_with('[')).collect();
    assert_eq!(lines.len(), 4, "{text}");
    for (line, (t, id)) in lines.iter().zip([
        ("2.0", "1/1"),
        ("2.0", "2/1"),
        ("4.0", "1/1"),
        ("4.0", "2/1"),
    ]) {
        let head = format!("[{t} s] {id}: ");
        assert!(line.starts_with(&head), "{line}");
        for part in [
            " received, ",
            " lost (",
            " duplicate, ",
            " reordered, ",
            " frames/s",
        ] {
            assert!(line.contains(part), "{part} not in {line}");
        }
    }
}

#[test]
fn sigquit_prints_the_figures_so_far_and_the_run_goes_on() {
    // A real clock: 3 s of listening, SIGQUIT after about one.
    let link = "sim:?responders=2&stream=ATTITUDE@50&loss_down=5%&seed=8";
    let run = start_mavping(&["--passive", "-w", "3", "-v", link]);
    std::thread::sleep(Duration::from_millis(1_200));
    signal(run.child.id(), "QUIT");
    let (code, out, err) = run.wait(Duration::from_secs(30));
    assert_eq!(code, 0, "{out}\n{err}");
    for id in ["1/1", "2/1"] {
        let interim: Vec<&str> = out
            .lines()
            .filter(|l| l.starts_with('[') && l.contains(&format!("] {id}: ")))
            .collect();
        assert_eq!(interim.len(), 1, "{out}");
        let so_far: u64 = interim[0]
            .split(": ")
            .nth(1)
            .and_then(|rest| rest.split(' ').next())
            .and_then(|n| n.parse().ok())
            .unwrap_or_else(|| panic!("{}", interim[0]));
        let row = out
            .lines()
            .find(|l| l.starts_with(&format!("{id} ")))
            .unwrap_or_else(|| panic!("no {id} row in\n{out}"));
        let received: u64 = row.split_whitespace().nth(3).unwrap().parse().unwrap();
        // About a second of 51 frames by then, and the run went on to 3 s.
        assert!((25..=110).contains(&so_far), "{}", interim[0]);
        assert!(received > so_far + 50, "{row}\n{out}");
        // The link's drops, but for any among the last frames it sent: on
        // a real clock the run may end before the frame after them came.
        let lost: i64 = row.split_whitespace().nth(4).unwrap().parse().unwrap();
        let dropped = sim_truth(&err, id, "down_dropped") as i64;
        assert!(
            (0..=2).contains(&(dropped - lost)),
            "{lost} of {dropped}: {err}"
        );
    }
}

#[test]
fn samples_add_up_to_the_summary_and_the_truth_on_each_link() {
    let dir = std::env::temp_dir().join(format!("mavping-passive-csv-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let csv = dir.join("samples.csv");
    // A vehicle of its own ids, so the link's truth (`-v`) names it apart.
    let other = "sim:?clock=virtual&sysid=7&stream=GLOBAL_POSITION_INT@20&loss_down=10%&seed=9";
    // 12.5 s: twelve whole seconds and the last half (and, as above, the
    // runs end on frames that arrived).
    let (code, out, err) = run_mavping(&[
        "--passive",
        "-w",
        "12.5s",
        "--json",
        "-v",
        "--samples",
        csv.to_str().unwrap(),
        FAULTY,
        other,
    ]);
    assert_eq!(code, 0, "{out}{err}");
    let text = std::fs::read_to_string(&csv).unwrap();
    std::fs::remove_dir_all(&dir).unwrap();
    assert_eq!(
        text.lines().next(),
        Some("t_s,window_s,sysid,compid,received,lost,duplicate,reordered,bytes,frames_per_s,link")
    );
    let all = rows(&text);
    let summaries: Vec<Value> = json_lines(&out)
        .into_iter()
        .filter(|e| e["type"] == "passive_summary")
        .collect();
    assert_eq!(summaries.len(), 2, "{out}");
    for summary in &summaries {
        let link = summary["link"].as_str().unwrap();
        let mine: Vec<_> = all.iter().filter(|r| r["link"] == link).cloned().collect();
        // A row per source per second, and one per source for the last half.
        let sources = summary["sources"].as_array().unwrap().len();
        assert_eq!(mine.len(), 13 * sources, "{link}: {text}");
        let last = mine.last().unwrap();
        assert_eq!(
            (last["t_s"].as_str(), last["window_s"].as_str()),
            ("12.500000", "0.500000")
        );
        for s in summary["sources"].as_array().unwrap() {
            let id = format!("{}/{}", s["source"]["sysid"], s["source"]["compid"]);
            let sums = sums(&mine, &id, 12.5);
            for key in ["received", "lost", "duplicate", "reordered"] {
                assert_eq!(sums[key], count(s, key), "{link} {id} {key}");
            }
            assert_eq!(sums["bytes"], s["bytes"].as_i64().unwrap(), "{link} {id}");
            // Each second's rate is its frames over its length.
            for r in mine
                .iter()
                .filter(|r| Some(field(r, "sysid")) == s["source"]["sysid"].as_i64())
            {
                let rate: f64 = r["frames_per_s"].parse().unwrap();
                let window: f64 = r["window_s"].parse().unwrap();
                let frames = field(r, "received") as f64;
                assert!((rate * window - frames).abs() < 1e-6, "{r:?}");
            }
        }
        let totals = &summary["totals"]["counts"];
        let lost: i64 = summary["sources"]
            .as_array()
            .unwrap()
            .iter()
            .map(|s| {
                sums(
                    &mine,
                    &format!("{}/{}", s["source"]["sysid"], s["source"]["compid"]),
                    12.5,
                )["lost"]
            })
            .sum();
        assert_eq!(lost, totals["lost"].as_i64().unwrap(), "{link}");
    }
    // Every source, against what its link did to its frames.
    for (summary, id) in [(0, "1/1"), (0, "2/1"), (1, "7/1")] {
        let link = summaries[summary]["link"].as_str().unwrap();
        let mine: Vec<_> = all.iter().filter(|r| r["link"] == link).cloned().collect();
        let s = sums(&mine, id, 12.5);
        assert_truth(
            &err,
            id,
            s["received"],
            s["lost"],
            s["duplicate"],
            s["reordered"],
        );
    }
}
