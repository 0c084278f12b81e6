//! The vehicle's own view of the link (LINK_NODE_STATUS) against truth the
//! tests control: a pymavlink vehicle (`tests/peers/vehicle.py
//! --link-node-status`) that counts what reaches it by our frames' packet
//! sequence and says so at 1 Hz, behind `tests/peers/fault_relay.py`, which
//! drops a known share of the uplink and counts it; and a telemetry log
//! written by pymavlink with LINK_NODE_STATUS frames whose counters wrap
//! and restart (`tests/peers/tlog_writer.py`'s `link_node`).
//!
//! Exact: mavping's first and last report are reports the vehicle sent,
//! field for field, and the growth is theirs; the vehicle's own count is
//! the relay's. Inferred: mavping's uplink estimate agrees with the
//! vehicle's count within their errors, and disagrees when the vehicle's
//! count contradicts the relay.

use serde_json::Value;

use crate::common::json::{assert_schema, json_lines};
use crate::common::*;
use crate::passive_peers::{json_line, relay, u, vehicle, FAULTS};

/// A vehicle saying `mode` in its LINK_NODE_STATUS behind the lossy relay,
/// probed with 400 PINGs by mavping with `args`: mavping's output, the
/// relay's truth and the vehicle's.
fn probe_through_relay(mode: &str, args: &[&str]) -> (String, Value, Value) {
    let stream = [
        "--frames",
        "100000",
        "--rate",
        "50",
        "--link-node-status",
        mode,
    ];
    let (v, port) = vehicle(1, &stream);
    let (relay, relay_port) = relay(&[port], &[&FAULTS[..], &["--requests", "400"]].concat());
    let target = format!("udpout:127.0.0.1:{relay_port}");
    let mut all = vec!["-c", "400", "-i", "15ms", "-W", "1s", "-q"];
    all.extend(args);
    all.push(&target);
    let (code, out, err) = run_mavping(&all);
    let relay_truth = relay.finish();
    let vehicle_truth = v.finish();
    assert_eq!(code, 0, "{out}{err}");
    assert_eq!(relay_truth["close_forced"], false, "{relay_truth}");
    (out, relay_truth, vehicle_truth)
}

/// The report the vehicle sent with the same boot clock as `report`.
fn sent_as<'a>(vehicle: &'a Value, report: &Value) -> &'a Value {
    vehicle["link_node"]["reports"]
        .as_array()
        .unwrap()
        .iter()
        .find(|r| r["timestamp"] == report["timestamp"])
        .unwrap_or_else(|| panic!("{report} is no report the vehicle sent: {vehicle}"))
}

/// mavping's figures for node 1/1 are those of two reports the vehicle
/// sent, and its own count of the link is the relay's.
fn check_exact(node: &Value, relay: &Value, vehicle: &Value) {
    assert_eq!(node["id"], serde_json::json!({"sysid": 1, "compid": 1}));
    let (first, last) = (&node["first"], &node["last"]);
    assert_eq!(first, sent_as(vehicle, first), "{node}");
    assert_eq!(last, sent_as(vehicle, last), "{node}");
    let grown = |k: &str| u(&last[k]) - u(&first[k]);
    assert_eq!(u(&node["received_delta"]), grown("messages_received"));
    assert_eq!(u(&node["lost_delta"]), grown("messages_lost"));
    assert_eq!(u(&node["sent_delta"]), grown("messages_sent"));
    let sent = vehicle["link_node"]["reports"].as_array().unwrap().len() as u64;
    let reports = u(&node["reports"]);
    assert!(reports >= 4 && reports <= sent, "{reports} of {sent}");
    assert_eq!(node["reboots"], 0);
    // The vehicle's own count is the relay's: every copy it forwarded
    // was received, every frame it dropped before its last forwarded one
    // was a gap in our sequence.
    let up = &relay["up"][0];
    let lv = &vehicle["link_node"];
    assert_eq!(
        u(&lv["received"]),
        u(&up["frames"]) - u(&up["dropped"]) + u(&up["duplicated"]),
        "{up}\n{lv}"
    );
    assert_eq!(
        u(&lv["lost"]),
        u(&up["dropped"]) - u(&up["dropped_after_last"]),
        "{up}\n{lv}"
    );
    assert!(u(&up["dropped"]) > 20, "{up}");
}

#[test]
fn the_vehicles_count_is_shown_as_it_sent_it_and_agrees_with_the_uplink_estimate() {
    let dir = std::env::temp_dir().join(format!("mavping-link-node-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let prom = dir.join("run.prom");
    let (out, relay, vehicle) = probe_through_relay(
        "honest",
        &[
            "--json",
            "--prometheus-textfile",
            prom.to_str().unwrap(),
            "--report",
            "c2",
        ],
    );
    assert_schema(&json_lines(&out));
    let s = json_line(&out, "summary");
    let nodes = s["link_node"].as_array().unwrap();
    assert_eq!(nodes.len(), 1, "{s}");
    let node = &nodes[0];
    check_exact(node, &relay, &vehicle);
    let (received, lost) = (u(&node["received_delta"]), u(&node["lost_delta"]));
    assert!(lost > 10, "{node}");
    let loss = node["uplink_loss"].as_f64().unwrap();
    assert_eq!(loss, lost as f64 / (received + lost) as f64);
    // Beside mavping's estimate, which is the responder's direction split,
    // and within three combined standard errors of it.
    let c = &node["compared"];
    let d = &s["responders"][0]["direction"];
    assert_eq!(c["estimate"], d["uplink_loss"], "{c}\n{d}");
    assert_eq!(c["vehicle"].as_f64(), Some(loss));
    let combined = c["estimate_stderr"]
        .as_f64()
        .unwrap()
        .hypot(c["vehicle_stderr"].as_f64().unwrap());
    let apart = (loss - d["uplink_loss"].as_f64().unwrap()).abs() / combined;
    assert!((c["sigmas"].as_f64().unwrap() - apart).abs() < 1e-9, "{c}");
    assert_eq!(c["agrees"], true, "{c}");
    // The C2 report's uplink loss is the vehicle's own count, said so;
    // its continuity is the round trips the summary counted.
    let c2 = json_line(&out, "c2_report");
    assert_eq!(c2["loss"]["uplink_from"], "link_node_status", "{c2}");
    assert_eq!(
        c2["loss"]["uplink_pct"].as_f64(),
        Some(100.0 * loss),
        "{c2}"
    );
    let responder = &s["responders"][0];
    assert_eq!(
        c2["continuity"]["transactions"], s["requests"],
        "{c2}\n{responder}"
    );
    assert_eq!(
        c2["continuity"]["within"], responder["received"],
        "{c2}\n{responder}"
    );
    let codes: Vec<&Value> = s["hints"]
        .as_array()
        .unwrap()
        .iter()
        .map(|h| &h["code"])
        .collect();
    assert!(
        !codes.contains(&&Value::from("vehicle_uplink_disagrees")),
        "{s}"
    );
    // Prometheus counts from the first report heard: the same growth.
    let text = std::fs::read_to_string(&prom).unwrap();
    let l = r#"link="udpout:127.0.0.1:"#;
    for (family, value) in [
        ("mavping_link_node_received_total", received),
        ("mavping_link_node_lost_total", lost),
        ("mavping_link_node_reports_total", u(&node["reports"])),
    ] {
        let line = text
            .lines()
            .find(|t| t.starts_with(&format!("{family}{{{l}")))
            .unwrap_or_else(|| panic!("no {family} in\n{text}"));
        assert!(
            line.ends_with(&format!(r#",sysid="1",compid="1"}} {value}"#)),
            "{line}"
        );
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_vehicle_whose_count_contradicts_the_relay_is_said_to_disagree() {
    // It says it lost nothing while the relay drops 10 % of the uplink.
    let (out, relay, vehicle) = probe_through_relay("no-loss", &[]);
    let up = &relay["up"][0];
    assert!(u(&up["dropped"]) > 20, "{up}");
    assert!(u(&vehicle["link_node"]["lost"]) > 20, "{vehicle}");
    let line = out
        .lines()
        .find(|l| l.starts_with("vehicle 1/1 says (LINK_NODE_STATUS, "))
        .unwrap_or_else(|| panic!("no vehicle line in\n{out}"));
    assert!(line.contains(", lost 0 (0.00%), parse errors +0"), "{line}");
    // The received count is the growth between two reports it sent.
    let (_, rest) = line.split_once("received ").expect(line);
    let (grouped, _) = rest.split_once(", lost").expect(line);
    let received: u64 = grouped.replace(',', "").parse().expect(line);
    let sent: Vec<u64> = vehicle["link_node"]["reports"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| u(&r["messages_received"]))
        .collect();
    assert!(
        sent.iter()
            .any(|a| sent.iter().any(|b| b.checked_sub(*a) == Some(received))),
        "{received} is no growth between reports in {sent:?}"
    );
    let beside = out
        .lines()
        .find(|l| l.starts_with("  beside mavping's up ~"))
        .unwrap_or_else(|| panic!("{out}"));
    assert!(beside.contains(" for 1/1: DISAGREES ("), "{beside}");
    let hint = out
        .lines()
        .find(|l| l.starts_with("hint: vehicle 1/1 counts 0.00% of what reached it lost"))
        .unwrap_or_else(|| panic!("no disagreement hint in\n{out}"));
    assert!(
        hint.ends_with("it received requests it did not answer, something between re-numbers our frames, or it counts another link"),
        "{hint}"
    );
}

/// A node's figures in a summary.
fn node<'a>(summary: &'a Value, id: &str) -> &'a Value {
    summary["link_node"]
        .as_array()
        .unwrap()
        .iter()
        .find(|n| format!("{}/{}", n["id"]["sysid"], n["id"]["compid"]) == id)
        .unwrap_or_else(|| panic!("no node {id} in {summary}"))
}

#[test]
fn a_log_of_link_node_status_is_read_across_wraps_a_reboot_and_lost_reports() {
    use crate::tlog::{read, tlog, write_log, Scratch};
    let dir = Scratch::new("link-node");
    let path = dir.path("px4.tlog");
    // 1/1: its received count wraps 2^32 at report 16, its parse errors
    // 2^16 at report 7; reports 5 and 12 are never written. 2/1 reboots at
    // report 9 with every counter in the top sixteenth of its range: only
    // its boot clock going back tells that from a wrap.
    let plan = serde_json::json!({
        "start_us": 1_700_000_000_000_000u64,
        "sources": [
            {"sysid": 1, "compid": 1, "rate": 10, "frames": 300, "drop": [50, 120],
             "link_node": {"every": 10, "received0": 4_294_963_296u64, "received_step": 250,
                           "lost0": 5, "lost_step": 3, "parse0": 65_400, "parse_step": 20}},
            {"sysid": 2, "compid": 1, "rate": 10, "frames": 200, "phase_us": 5_000,
             "link_node": {"every": 10, "received0": 4_294_867_296u64, "received_step": 1000,
                           "lost0": 4_294_967_246u64, "lost_step": 2, "parse0": 65_000,
                           "parse_step": 1, "reboot_at": 9}},
        ],
    });
    let truth = write_log(&path, &plan);
    let (code, s, err) = read(&[], &tlog(&path));
    assert_eq!(code, 0, "{err}");
    for (id, reboots, written) in [("1/1", 0, 28), ("2/1", 1, 20)] {
        let t = &truth["sources"][id]["link_node"];
        let n = node(&s, id);
        assert_eq!(t["written"].as_array().unwrap().len(), written, "{t}");
        assert_eq!(u(&n["reports"]), written as u64, "{id}: {n}");
        assert_eq!(n["reboots"], reboots, "{id}: {n}");
        assert_eq!(t["reboots"], reboots, "{id}: {t}");
        for (ours, theirs) in [
            ("received_delta", "received_grown"),
            ("lost_delta", "lost_grown"),
            ("rx_parse_err_delta", "parse_grown"),
        ] {
            assert_eq!(n[ours], t[theirs], "{id} {ours}: {n}\n{t}");
        }
        let (received, lost) = (u(&n["received_delta"]), u(&n["lost_delta"]));
        assert_eq!(
            n["uplink_loss"].as_f64(),
            Some(lost as f64 / (received + lost) as f64)
        );
        // Passive: nothing to hold it against.
        assert!(n.get("compared").is_none(), "{n}");
    }
    // 1/1's 28 reports span 29 steps of 250: through the wrap.
    assert_eq!(u(&node(&s, "1/1")["received_delta"]), 29 * 250);
    assert_eq!(node(&s, "2/1")["first"]["timestamp"], 3_600_000);
    assert_eq!(node(&s, "2/1")["last"]["timestamp"], 700 + 10 * 1000);
    // The text says the same.
    let (code, out, err) = run_mavping(&["-q", &tlog(&path)]);
    assert_eq!(code, 0, "{err}");
    assert!(
        out.lines().any(|l| l
            == "vehicle 1/1 says (LINK_NODE_STATUS, 28 reports): received 7,250, lost 87 \
                (1.19%), parse errors +580, overflows rx +0 tx +0"),
        "{out}"
    );
    assert!(
        out.lines().any(
            |l| l.starts_with("vehicle 2/1 says (LINK_NODE_STATUS, 20 reports): ")
                && l.ends_with("; it rebooted once")
        ),
        "{out}"
    );
}
