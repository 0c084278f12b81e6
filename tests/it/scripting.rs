//! mavping for scripts: JSON events against the committed schema, exact
//! snapshots, every threshold's exit code, and the exports.

use crate::common::*;

/// Loss, duplicates, reordering and late replies, all seeded and in
/// virtual time: every run gives the same bytes.
const FAULTY: &str =
    "sim:?responders=2&loss=5%&dup=3%&reorder=5%&hold=150ms&jitter=4ms&seed=9&clock=virtual";

#[test]
fn every_json_event_matches_the_schema() {
    let (code, out, err) =
        run_mavping(&["--json", "-c", "300", "-i", "0.01", "-W", "100ms", FAULTY]);
    assert_eq!(code, 0, "{err}");
    let validator = schema();
    let events = json_lines(&out);
    for e in &events {
        let errors: Vec<String> = validator.iter_errors(e).map(|e| e.to_string()).collect();
        assert!(errors.is_empty(), "{e}\n{errors:?}");
    }
    let kinds: std::collections::BTreeSet<&str> =
        events.iter().map(|e| e["type"].as_str().unwrap()).collect();
    for kind in [
        "start",
        "responder",
        "reply",
        "lost",
        "late",
        "duplicate",
        "summary",
    ] {
        assert!(
            kinds.contains(kind),
            "no {kind} event in this run: {kinds:?}"
        );
    }
    // The schema is not vacuous: a reply without an RTT is rejected.
    let mut broken = events
        .iter()
        .find(|e| e["type"] == "reply")
        .unwrap()
        .clone();
    broken.as_object_mut().unwrap().remove("rtt_us");
    assert!(!validator.is_valid(&broken));
    // The counts add up in the summary the way the README says.
    for r in summary_of(&out)["responders"].as_array().unwrap() {
        assert_eq!(
            r["sent"].as_u64().unwrap(),
            r["received"].as_u64().unwrap() + r["lost"].as_u64().unwrap()
        );
    }
}

#[test]
fn json_quiet_prints_only_the_summary() {
    let (code, out, _) = run_mavping(&[
        "--json",
        "-q",
        "-c",
        "5",
        "-i",
        "0.01",
        "sim:?clock=virtual",
    ]);
    assert_eq!(code, 0);
    let events = json_lines(&out);
    assert_eq!(events.len(), 1);
    assert_eq!(events[0]["type"], "summary");
    assert_eq!(events[0]["responders"][0]["received"], 5);
    assert_eq!(events[0]["exit_code"], 0);
}

#[test]
fn text_output_snapshot() {
    let (_, out, _) = run_mavping(&["-c", "30", "-i", "0.02", "-W", "100ms", FAULTY]);
    insta::assert_snapshot!("text_faulty_sim", out);
}

#[test]
fn json_output_snapshot() {
    let (_, out, _) = run_mavping(&["--json", "-c", "30", "-i", "0.02", "-W", "100ms", FAULTY]);
    insta::assert_snapshot!("json_faulty_sim", out);
}

/// Each threshold, broken alone, exits 1 and is named in text and JSON;
/// held, exits 0.
#[test]
fn each_threshold_decides_the_exit_code() {
    // 10% loss, p99 ~ 22-23 ms, jitter ~ 1 ms, responders 1/1 and 2/1.
    let sim = "sim:?responders=2&loss=10%&seed=5&clock=virtual";
    let base = ["-c", "100", "-i", "0.01", "-W", "200ms"];
    let cases: [(&[&str], &[&str], &str); 5] = [
        (&["--max-loss", "1%"], &["--max-loss", "50%"], "max-loss"),
        (
            &["--max-rtt", "p99=15ms"],
            &["--max-rtt", "p99=30ms"],
            "max-rtt",
        ),
        (
            &["--max-jitter", "100us"],
            &["--max-jitter", "10ms"],
            "max-jitter",
        ),
        (&["--expect", "3"], &["--expect", "2/1"], "expect"),
        (
            &["--min-responders", "3"],
            &["--min-responders", "2"],
            "min-responders",
        ),
    ];
    for (broken, held, check) in cases {
        let args: Vec<&str> = base.iter().chain(broken).chain([&sim]).copied().collect();
        let (code, out, _) = run_mavping(&args);
        assert_eq!(code, 1, "{broken:?}\n{out}");
        assert!(out.contains(&format!("FAILED {check}: ")), "{out}");
        let json_args: Vec<&str> = ["--json", "-q"].iter().chain(&args).copied().collect();
        let (code, out, _) = run_mavping(&json_args);
        assert_eq!(code, 1);
        let verdict = &summary_of(&out)["verdict"];
        assert_eq!(verdict["ok"], false);
        assert!(
            verdict["failures"]
                .as_array()
                .unwrap()
                .iter()
                .any(|f| f["check"] == check),
            "{verdict}"
        );

        let args: Vec<&str> = base.iter().chain(held).chain([&sim]).copied().collect();
        let (code, out, _) = run_mavping(&args);
        assert_eq!(code, 0, "{held:?}\n{out}");
        assert!(!out.contains("FAILED"), "{out}");
    }
}

#[test]
fn max_loss_names_the_failing_responder_only() {
    // Responder 2/1 is the only one behind a lossy path? The sim applies
    // loss to all; check the per-responder failure lists instead.
    let (code, out, _) = run_mavping(&[
        "--json",
        "-q",
        "-c",
        "200",
        "-i",
        "0.01",
        "--max-loss",
        "8%",
        "sim:?responders=3&loss=8%&seed=11&clock=virtual",
    ]);
    let s = summary_of(&out);
    let over: Vec<u64> = s["responders"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|r| r["loss_ratio"].as_f64().unwrap() > 0.08)
        .map(|r| r["responder"]["sysid"].as_u64().unwrap())
        .collect();
    let named: Vec<u64> = s["responders"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|r| !r["failures"].as_array().unwrap().is_empty())
        .map(|r| r["responder"]["sysid"].as_u64().unwrap())
        .collect();
    assert_eq!(over, named);
    assert_eq!(code, i32::from(!over.is_empty()));
}

#[test]
fn hgrm_export_parses_back_into_the_same_percentiles() {
    let dir = std::env::temp_dir().join(format!("mavping-hgrm-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("rtt.hgrm");
    let (code, out, err) = run_mavping(&[
        "--json",
        "-q",
        "-c",
        "2000",
        "-i",
        "0.001",
        "--hgrm",
        path.to_str().unwrap(),
        "sim:?responders=2&jitter=20ms&seed=3&clock=virtual",
    ]);
    assert_eq!(code, 0, "{err}");
    let text = std::fs::read_to_string(&path).unwrap();
    let summary = summary_of(&out);
    let sections: Vec<&str> = text.split("# mavping ").skip(1).collect();
    assert_eq!(sections.len(), 2);
    for (section, r) in sections
        .iter()
        .zip(summary["responders"].as_array().unwrap())
    {
        let rows: Vec<(f64, f64, u64)> = section
            .lines()
            .filter(|l| l.starts_with(' ') && !l.contains("Value"))
            .map(|l| {
                let f: Vec<&str> = l.split_whitespace().collect();
                (
                    f[0].parse().unwrap(),
                    f[1].parse().unwrap(),
                    f[2].parse().unwrap(),
                )
            })
            .collect();
        assert_eq!(rows.last().unwrap().2, r["received"].as_u64().unwrap());
        for (q, key) in [(0.5, "p50"), (0.9, "p90"), (0.99, "p99")] {
            let summary_ms = r["rtt_us"][key].as_f64().unwrap() / 1e3;
            // Rows sit at HdrHistogram's percentile ticks; the figure lies
            // between the rows around it, within one sub-bucket (0.1%).
            let below = rows.iter().rev().find(|row| row.1 <= q).unwrap().0;
            let above = rows.iter().find(|row| row.1 >= q).unwrap().0;
            let slack = summary_ms * 2e-3;
            assert!(
                below - slack <= summary_ms && summary_ms <= above + slack,
                "{key}: {summary_ms} not within [{below}, {above}]"
            );
        }
        assert!(section.contains("#[Max     ="));
    }
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn samples_csv_has_a_row_per_reply_and_loss() {
    let path = std::env::temp_dir().join(format!("mavping-samples-{}.csv", std::process::id()));
    let (code, out, _) = run_mavping(&[
        "--json",
        "-q",
        "-c",
        "500",
        "-i",
        "0.01",
        "-W",
        "100ms",
        "--samples",
        path.to_str().unwrap(),
        FAULTY,
    ]);
    assert_eq!(code, 0);
    let csv = std::fs::read_to_string(&path).unwrap();
    let mut lines = csv.lines();
    assert_eq!(
        lines.next(),
        Some("sysid,compid,seq,sent_s,rtt_us,status,rssi,remrssi,txbuf,noise,remnoise")
    );
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    for r in summary_of(&out)["responders"].as_array().unwrap() {
        let sysid = r["responder"]["sysid"].as_u64().unwrap().to_string();
        let count = |status: &str| {
            rows.iter()
                .filter(|row| row[0] == sysid && row[5] == status)
                .count() as u64
        };
        assert_eq!(count("ok"), r["received"].as_u64().unwrap());
        assert_eq!(count("lost"), r["lost"].as_u64().unwrap());
        assert_eq!(count("late"), r["late"].as_u64().unwrap());
        assert_eq!(count("duplicate"), r["duplicate"].as_u64().unwrap());
    }
    let _ = std::fs::remove_file(path);
}

#[test]
fn unwritable_export_path_exits_2_before_pinging() {
    let (code, out, err) = run_mavping(&["--samples", "/nonexistent-dir/x.csv", "sim:"]);
    assert_eq!(code, 2);
    assert!(out.is_empty());
    assert!(
        err.starts_with("mavping: cannot write --samples /nonexistent-dir/x.csv"),
        "{err}"
    );
}

#[test]
fn timesync_and_command_probe_json_matches_the_schema() {
    let validator = schema();
    for args in [
        &[
            "--json",
            "--probe",
            "timesync",
            "-c",
            "50",
            "-i",
            "0.01",
            "sim:?offset=-2s&drift=50&loss=10%&clock=virtual",
        ][..],
        &[
            "--json",
            "--probe",
            "command",
            "-c",
            "5",
            "-i",
            "0.2",
            "sim:?loss=30%&seed=4&clock=virtual",
        ],
    ] {
        let (code, out, err) = run_mavping(args);
        assert_eq!(code, 0, "{args:?}: {err}");
        let events = json_lines(&out);
        for e in &events {
            let errors: Vec<String> = validator.iter_errors(e).map(|e| e.to_string()).collect();
            assert!(errors.is_empty(), "{e}\n{errors:?}");
        }
        let last = events.last().unwrap();
        assert!(
            last["type"] == "summary" || last["type"] == "command_summary",
            "{last}"
        );
    }
    let (_, out, _) = run_mavping(&[
        "--json",
        "-q",
        "--probe",
        "timesync",
        "-c",
        "50",
        "-i",
        "0.01",
        "sim:?offset=-2s&clock=virtual",
    ]);
    let clock = &summary_of(&out)["responders"][0]["clock"];
    let offset = clock["offset_ns"].as_i64().unwrap();
    assert!((offset + 2_000_000_000).abs() < 1_000_000, "{clock}");
}
