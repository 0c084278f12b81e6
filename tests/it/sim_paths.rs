//! A simulated vehicle heard on several paths (`sim:?paths=`, issue 41):
//! each path loses by its own seeded draw and outage and adds its own
//! delay, the sim logs what each path did (`-v`), and mavping's
//! `pair_summary` must count the same, exactly; the lag behind the first
//! copy is the planned difference of the paths' delays.

use serde_json::Value;

use crate::common::*;
use crate::passive_peers::json_line;

fn count(v: &Value, key: &str) -> u64 {
    v[key].as_u64().unwrap_or_else(|| panic!("no {key} in {v}"))
}

fn ms(v: &Value, key: &str) -> f64 {
    v[key].as_f64().unwrap_or_else(|| panic!("no {key} in {v}"))
}

/// A passive `--json -v` run of `link` for 20 s of its virtual clock:
/// the pair line's figures for 1/1, its link names, and `-v`'s stderr.
fn paired(link: &str) -> (Value, Vec<String>, String) {
    let (code, out, err) = run_mavping(&["--passive", "--json", "-v", "-w", "20", link]);
    assert_eq!(code, 0, "{err}");
    assert_schema(&json_lines(&out));
    let pair = json_line(&out, "pair_summary");
    let names = pair["links"]
        .as_array()
        .unwrap()
        .iter()
        .map(|n| n.as_str().unwrap().to_string())
        .collect();
    let source = pair["sources"]
        .as_array()
        .unwrap()
        .iter()
        .find(|s| s["source"] == serde_json::json!({"sysid": 1, "compid": 1}))
        .unwrap_or_else(|| panic!("no 1/1 in {pair}"))
        .clone();
    (source, names, err)
}

/// Path `k`'s figure `key` of the sim's truth.
fn path(err: &str, k: usize, key: &str) -> u64 {
    sim_truth(err, &format!("path {k} 1/1"), key)
}

/// Every count the sim kept for its `paths` paths, equal to mavping's:
/// each path's frames, the ones it delivered first and only it
/// delivered, its loss as its own sequence finds it, its duplicates; the
/// frames lost on every path and the copies.
fn assert_counts(source: &Value, err: &str, paths: usize) {
    let delivered = sim_truth(err, "1/1", "down_delivered");
    assert_eq!(count(source, "distinct_frames"), delivered, "{source}");
    assert_eq!(
        count(source, "lost_on_every_link"),
        sim_truth(err, "paths 1/1", "missing_on_every_path"),
        "{source}"
    );
    let links = source["links"].as_array().unwrap();
    assert_eq!(links.len(), paths, "{source}");
    let mut copies = 0;
    for (k, got) in links.iter().enumerate() {
        assert_eq!(count(got, "link"), k as u64, "{got}");
        let frames = path(err, k, "delivered") + path(err, k, "duplicates");
        assert_eq!(count(got, "frames"), frames, "path {k}: {got}");
        for (key, truth) in [
            ("first", "first"),
            ("only", "only"),
            ("lost", "missing"),
            ("duplicates", "duplicates"),
        ] {
            assert_eq!(
                count(got, key),
                path(err, k, truth),
                "path {k} {key}: {got}"
            );
        }
        assert_eq!(count(got, "only_undecided"), 0, "{got}");
        copies += path(err, k, "delivered");
    }
    assert_eq!(count(source, "copies"), copies - delivered, "{source}");
}

/// Two paths, one losing 10 % at 20 ms, the other 2 % at 100 ms, after
/// the link's own 1 % and its jitter: exact counts, the slower path 80
/// ms behind the faster on every frame both delivered, the faster never
/// behind, and the window that catches the copies 80 ms.
#[test]
fn two_paths_are_counted_as_the_sim_sent_them() {
    let link = "sim:?clock=virtual&stream=ATTITUDE@50,GLOBAL_POSITION_INT@5&loss_down=1%\
                &paths=2&path_loss=10%,2%&path_delay=20ms,100ms&seed=7";
    let (source, names, err) = paired(link);
    assert_eq!(names, [format!("{link} path 0"), format!("{link} path 1")]);
    assert_counts(&source, &err, 2);
    // The draws lose what they were set to, and nothing else does on the
    // paths: no outage.
    for (k, share) in [(0, 0.10), (1, 0.02)] {
        let sent = path(&err, k, "sent");
        assert!(sent > 1000, "{err}");
        let drawn = path(&err, k, "drawn") as f64 / sent as f64;
        assert!((drawn - share).abs() < 0.02, "path {k}: {drawn}");
        assert_eq!(path(&err, k, "outage"), 0);
    }
    assert!(count(&source, "lost_on_every_link") > 0, "{source}");
    let links = source["links"].as_array().unwrap();
    assert!(count(&links[0], "only") > 0 && count(&links[1], "only") > 0);
    for key in ["lag_p50_ms", "lag_p99_ms", "lag_max_ms"] {
        assert_eq!(ms(&links[0], key), 0.0, "{key}: {source}");
        assert_eq!(ms(&links[1], key), 80.0, "{key}: {source}");
    }
    assert_eq!(ms(&source, "dedup_window_p999_ms"), 80.0, "{source}");
    assert_eq!(ms(&source, "copy_lag_max_ms"), 80.0, "{source}");
}

/// The faster path out for a second, nothing else lost: every frame it
/// missed is its loss and the slower path's alone, and the slower path
/// is first for them; no frame is lost on both. The faster path's own
/// "only" are the last frames, whose slower copies were on their way
/// when the run ended.
#[test]
fn an_outage_on_one_path_is_its_loss_and_the_others_only() {
    let link = "sim:?clock=virtual&stream=ATTITUDE@50&paths=2&path_delay=0s,30ms\
                &path_outage=5s+1s,none&seed=3";
    let (source, _, err) = paired(link);
    assert_counts(&source, &err, 2);
    let out = path(&err, 0, "outage");
    // A second of a 51-frame-a-second vehicle (ATTITUDE and HEARTBEAT).
    assert!((50..=52).contains(&out), "{err}");
    assert_eq!((path(&err, 0, "dropped"), path(&err, 0, "drawn")), (out, 0));
    let links = source["links"].as_array().unwrap();
    assert_eq!(count(&links[0], "lost"), out, "{source}");
    assert!(count(&links[0], "only") <= 2, "{source}");
    assert_eq!(
        (count(&links[1], "lost"), count(&links[1], "only")),
        (0, out),
        "{source}"
    );
    assert_eq!(count(&links[1], "first"), out, "{source}");
    assert_eq!(count(&source, "lost_on_every_link"), 0, "{source}");
    assert_eq!(sim_truth(&err, "paths 1/1", "lost_on_every_path"), 0);
}

/// The report in text: each path a way of its own, named by the link and
/// the path.
#[test]
fn the_text_report_names_each_path() {
    let link = "sim:?clock=virtual&stream=ATTITUDE@50&paths=2&path_loss=5%,5%&seed=2";
    let (code, out, err) = run_mavping(&["--passive", "-w", "5", link]);
    assert_eq!(code, 0, "{err}");
    let report = out
        .split("--- the same sources on several links")
        .nth(1)
        .unwrap_or_else(|| panic!("no pair report in {out}"));
    assert!(report.contains(&format!("[{link} path 0] ")), "{report}");
    assert!(report.contains(&format!("[{link} path 1] ")), "{report}");
}

/// A bad path parameter: exit 2 and one line saying what is wrong.
#[test]
fn bad_path_parameters_are_one_line_and_exit_2() {
    for (query, says) in [
        ("paths=5", "paths=5: expected 1 to 4"),
        (
            "paths=2&path_loss=10%",
            "path_loss=10%: 1 given for paths=2",
        ),
        ("path_delay=20ms", "path_delay= needs paths=N"),
        (
            "paths=2&path_delay=20ms,2h",
            "path_delay=20ms,2h: '2h': at most 1h",
        ),
        (
            "paths=2&path_outage=none,5s",
            "path_outage=none,5s: expected none or START+LENGTH",
        ),
        ("paths=2&path_loss=10%,x", "'x' is not a percentage"),
    ] {
        let link = format!("sim:?clock=virtual&{query}");
        let (code, out, err) = run_mavping(&["--passive", "-w", "1", &link]);
        assert_eq!(code, 2, "{query}: {out}{err}");
        assert_eq!(err.lines().count(), 1, "{query}: {err}");
        assert!(err.contains(says), "{query}: {err}");
    }
}
