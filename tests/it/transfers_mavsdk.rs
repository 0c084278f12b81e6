//! The download probes against MAVSDK's own C++ servers (the `mavsdk`
//! package, 4.1.0: its parameter, mission and FTP servers driven from
//! Python, `tests/peers/mavsdk_vehicle.py`), directly and through a relay
//! that drops a known share of one downlink message
//! (`fault_relay.py --down-ids`), which counts what it dropped.

use serde_json::Value;

use crate::common::*;

/// MAVSDK's vehicle serving `params`, `mission` items and a file of
/// `file_size` bytes; its facts line (port, path, sizes).
fn mavsdk(params: u32, mission: u32, file_size: u32) -> (Peer, Value) {
    let args = [
        "--port".to_string(),
        "0".into(),
        "--params".into(),
        params.to_string(),
        "--mission".into(),
        mission.to_string(),
        "--file-size".into(),
        file_size.to_string(),
    ];
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    let mut vehicle = Peer::start("mavsdk_vehicle.py", &args);
    let facts: Value = serde_json::from_str(&vehicle.read_line()).expect("the vehicle's facts");
    (vehicle, facts)
}

/// A relay in front of `port` dropping `share` of message `id` downlink,
/// by a seeded plan; the link to give mavping.
fn relay(port: u64, id: &str, share: &str, seed: &str) -> (Peer, String) {
    let vehicle = format!("127.0.0.1:{port}");
    let mut relay = Peer::start(
        "fault_relay.py",
        &[
            "--vehicle",
            &vehicle,
            "--seed",
            seed,
            "--drop-down",
            share,
            "--down-ids",
            id,
        ],
    );
    let port = relay.read_line();
    (relay, format!("udpout:127.0.0.1:{port}"))
}

/// A download run: its exit code and summary (lines held to the schema).
fn download(link: &str, args: &[&str]) -> (i32, Value) {
    let mut all = vec!["--json", "-W", "200ms", link];
    all.extend_from_slice(args);
    let (code, out, err) = run_mavping(&all);
    let lines = json_lines(&out);
    assert_schema(&lines);
    let summary = lines
        .into_iter()
        .find(|l| l["type"] == "transfer_summary")
        .unwrap_or_else(|| panic!("no transfer_summary: {out}\n{err}"));
    (code, summary)
}

fn count(v: &Value) -> u64 {
    v.as_u64().unwrap_or_else(|| panic!("not a count: {v}"))
}

#[test]
fn mavsdk_serves_every_download_whole() {
    let (vehicle, facts) = mavsdk(1000, 50, 100_000);
    let link = format!("udpout:127.0.0.1:{}", facts["port"]);
    let path = facts["ftp_path"].as_str().unwrap();
    let (p, params) = download(&link, &["--probe", "params"]);
    let (m, mission) = download(&link, &["--probe", "mission"]);
    let (f, file) = download(&link, &["--probe", "ftp", "--path", path]);
    let truth = vehicle.finish();
    assert_eq!((p, m, f), (0, 0, 0));
    let whole = |s: &Value, n: u64| {
        let last = &s["last"];
        assert_eq!(last["ending"], "complete", "{s}");
        assert_eq!((count(&last["total"]), count(&last["received"])), (n, n));
    };
    whole(&params, count(&truth["params"]));
    whole(&mission, count(&truth["mission_accepted"]));
    whole(&file, count(&truth["file_size"]));
    // Loopback loses nothing: every parameter on the list's one pass.
    assert_eq!(count(&params["missing_first_pass"]), 0);
    // MAVSDK answers PING (not TIMESYNC): the round trips beside.
    assert!(count(&params["latency"]["received"]) > 0, "{params}");
}

#[test]
fn through_a_relay_the_first_pass_misses_exactly_the_parameters_it_dropped() {
    let (vehicle, facts) = mavsdk(1000, 0, 0);
    let (relay, link) = relay(facts["port"].as_u64().unwrap(), "22", "0.1", "7");
    let (code, s) = download(&link, &["--probe", "params", "--retries", "9"]);
    let relayed = relay.finish();
    vehicle.finish();
    assert_eq!(code, 0, "{s}");
    let down = &relayed["down"]["1/1"];
    assert_eq!(relayed["kernel_dropped"]["ground"], 0, "{relayed}");
    // MAVSDK sends the list once in index order: the n-th PARAM_VALUE
    // through the relay is index n.
    let first_pass_drops = down["dropped_nth_by_msgid"]["22"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|n| count(n) < 1000)
        .count() as u64;
    assert!(first_pass_drops > 50, "{down}");
    let last = &s["last"];
    assert_eq!(count(&last["missing_first_pass"]), first_pass_drops, "{s}");
    assert_eq!(count(&last["received"]), 1000);
    // Every read is answered once: the relay carried the list and one
    // PARAM_VALUE per read, and dropped the first pass's and the reads'.
    let reads = count(&last["re_requests"]);
    assert_eq!(count(&down["frames_by_msgid"]["22"]), 1000 + reads);
    let unanswered = reads - count(&last["re_requests_answered"]);
    assert_eq!(
        count(&down["dropped_by_msgid"]["22"]),
        first_pass_drops + unanswered
    );
}

#[test]
fn through_a_relay_each_mission_item_dropped_is_asked_again_once() {
    let (vehicle, facts) = mavsdk(0, 60, 0);
    let (relay, link) = relay(facts["port"].as_u64().unwrap(), "73", "0.1", "5");
    let (code, s) = download(&link, &["--probe", "mission", "--retries", "4"]);
    let relayed = relay.finish();
    vehicle.finish();
    assert_eq!(code, 0, "{s}");
    let down = &relayed["down"]["1/1"];
    let dropped = count(&down["dropped_by_msgid"]["73"]);
    assert!(dropped > 2, "{down}");
    let last = &s["last"];
    assert_eq!(count(&last["received"]), 60);
    assert_eq!(count(&last["re_requests"]), dropped, "{s}\n{down}");
    // One MISSION_ITEM_INT per request: the list request and our ACK
    // aside, mavping's requests are the items the relay carried.
    assert_eq!(
        count(&down["frames_by_msgid"]["73"]),
        count(&last["requests"]) - 2
    );
}

#[test]
fn through_a_relay_dropping_ftp_packets_the_file_still_comes_whole() {
    let (vehicle, facts) = mavsdk(0, 0, 120_000);
    let path = facts["ftp_path"].as_str().unwrap().to_string();
    let (relay, link) = relay(facts["port"].as_u64().unwrap(), "110", "0.05", "3");
    let (code, s) = download(
        &link,
        &["--probe", "ftp", "--path", &path, "--retries", "9"],
    );
    let relayed = relay.finish();
    vehicle.finish();
    assert_eq!(code, 0, "{s}");
    let down = &relayed["down"]["1/1"];
    assert!(count(&down["dropped_by_msgid"]["110"]) > 5, "{down}");
    let last = &s["last"];
    assert_eq!(count(&last["received"]), 120_000);
    assert!(count(&last["missing_first_pass"]) > 0, "{s}");
    assert!(count(&last["re_requests_answered"]) > 0);
}
