//! `--probe params`, `mission` and `ftp` against a pymavlink vehicle that
//! plans its faults and counts them (`tests/peers/transfer_vehicle.py`):
//! what the first pass missed, what asking again brought and how each
//! download ended, held to the vehicle's own truth; the outputs that read
//! them; bad input.

use serde_json::Value;

use crate::common::*;

/// A transfer_vehicle.py on a free port, with `args`.
fn vehicle(args: &[&str]) -> (Peer, String) {
    let port = free_udp_port().to_string();
    let mut all = vec![port.as_str()];
    all.extend_from_slice(args);
    let peer = Peer::start("transfer_vehicle.py", &all);
    (peer, format!("udpout:127.0.0.1:{port}"))
}

/// A download run's JSON: its exit code, its lines (each held to the
/// schema) and its summary.
fn download(link: &str, args: &[&str]) -> (i32, Vec<Value>, Value) {
    let mut all = vec!["--json", "-W", "500ms", "-i", "100ms", link];
    all.extend_from_slice(args);
    let (code, out, err) = run_mavping(&all);
    let lines = json_lines(&out);
    assert_schema(&lines);
    let summary = lines
        .iter()
        .find(|l| l["type"] == "transfer_summary")
        .unwrap_or_else(|| panic!("no transfer_summary: {out}\n{err}"))
        .clone();
    (code, lines, summary)
}

fn count(v: &Value) -> u64 {
    v.as_u64().unwrap_or_else(|| panic!("not a count: {v}"))
}

#[test]
fn what_the_list_missed_is_what_the_vehicle_dropped_and_every_read_brings_one() {
    let (peer, link) = vehicle(&["--params", "400", "--drop-list", "0.1", "--seed", "7"]);
    let (code, lines, s) = download(&link, &["--probe", "params", "-c", "2"]);
    let truth = peer.finish();
    assert_eq!(code, 0, "{s}");
    let dropped = truth["list_dropped"].as_array().unwrap().len() as u64;
    assert!(dropped > 40, "{truth}");
    // Over both downloads: the list's dropped frames are the first passes'
    // missing parameters, each read once by index and answered.
    assert_eq!(count(&s["missing_first_pass"]), dropped, "{s}");
    assert_eq!(count(&s["re_requests"]), dropped);
    assert_eq!(count(&truth["reads"]), dropped);
    assert_eq!((count(&s["attempts"]), count(&s["complete"])), (2, 2));
    let ended: Vec<&Value> = lines.iter().filter(|l| l["type"] == "transfer").collect();
    assert_eq!(ended.len(), 2);
    for d in ended {
        assert_eq!(d["ending"], "complete");
        assert_eq!((count(&d["total"]), count(&d["received"])), (400, 400));
        assert_eq!(d["re_requests_answered"], d["re_requests"]);
        assert!(d["time_to_95_ms"].as_f64() <= d["time_to_100_ms"].as_f64());
    }
    let t = &s["time_to_complete"];
    assert!(t["min_ms"].as_f64() <= t["max_ms"].as_f64(), "{t}");
    // The TIMESYNC probes beside the downloads were answered.
    assert!(count(&s["latency"]["received"]) > 0, "{s}");
}

#[test]
fn dropped_reads_are_asked_again_until_answered() {
    let (peer, link) = vehicle(&[
        "--params",
        "200",
        "--drop-list",
        "0.2",
        "--drop-reads",
        "0.3",
        "--seed",
        "3",
    ]);
    let (code, _, s) = download(&link, &["--probe", "params", "--retries", "9"]);
    let truth = peer.finish();
    assert_eq!(code, 0, "{s}");
    let last = &s["last"];
    let missing = truth["list_dropped"].as_array().unwrap().len() as u64;
    assert_eq!(count(&last["missing_first_pass"]), missing);
    // Every read the vehicle took is one mavping sent (loopback loses
    // none); those it dropped were sent again.
    assert_eq!(count(&last["re_requests"]), count(&truth["reads"]));
    assert_eq!(
        count(&truth["reads"]) - count(&truth["reads_dropped"]),
        missing
    );
    assert_eq!(count(&last["re_requests_answered"]), missing);
}

#[test]
fn a_list_that_stops_by_itself_is_named_where_it_stopped() {
    let (peer, link) = vehicle(&["--params", "300", "--stop-list-after", "212"]);
    let (code, _, s) = download(&link, &["--probe", "params"]);
    peer.finish();
    assert_eq!(code, 0, "the reads fetch the rest: {s}");
    let last = &s["last"];
    assert_eq!(count(&last["stopped_after"]), 212);
    assert_eq!(count(&last["first_pass"]), 213);
    assert_eq!(count(&last["re_requests_answered"]), 87);
    let hint = &s["hints"][0];
    assert_eq!(hint["code"], "transfer_list_stopped", "{s}");
    assert!(
        hint["text"].as_str().unwrap().contains("after index 212"),
        "{hint}"
    );
}

#[test]
fn mission_items_lost_on_their_first_request_are_asked_again() {
    let (peer, link) = vehicle(&["--mission", "40", "--drop-items", "0.25", "--seed", "5"]);
    let (code, _, s) = download(&link, &["--probe", "mission"]);
    let truth = peer.finish();
    assert_eq!(code, 0, "{s}");
    let last = &s["last"];
    let dropped = count(&truth["items_dropped"]);
    assert!(dropped > 3, "{truth}");
    assert_eq!((count(&last["total"]), count(&last["received"])), (40, 40));
    assert_eq!(count(&last["missing_first_pass"]), dropped);
    assert_eq!(count(&last["re_requests"]), dropped);
    // The list request, every item request, our closing ACK.
    assert_eq!(
        count(&last["requests"]),
        1 + count(&truth["items_requested"]) + 1
    );
    assert_eq!(count(&truth["mission_acks"]), 1);
}

#[test]
fn a_file_read_in_bursts_misses_what_the_vehicle_dropped_and_reads_it_back() {
    let (peer, link) = vehicle(&[
        "--file-size",
        "30000",
        "--drop-burst",
        "0.1",
        "--seed",
        "11",
    ]);
    let (code, _, s) = download(
        &link,
        &["--probe", "ftp", "--path", "/vehicle.bin", "-c", "2"],
    );
    let truth = peer.finish();
    assert_eq!(code, 0, "{s}");
    assert_eq!(count(&s["complete"]), 2);
    assert_eq!(
        count(&s["missing_first_pass"]),
        count(&truth["burst_bytes_dropped"]),
        "{s}\n{truth}"
    );
    assert_eq!(count(&s["last"]["received"]), 30000);
    // Each download closed its session.
    assert_eq!(count(&truth["terminated"]), 2);
}

#[test]
fn a_path_the_vehicle_has_not_is_refused_with_its_error_and_exit_1() {
    let (peer, link) = vehicle(&[]);
    let (code, _, s) = download(&link, &["--probe", "ftp", "--path", "/no/such"]);
    peer.finish();
    assert_eq!(code, 1);
    assert_eq!(s["last"]["ending"], "refused");
    assert_eq!(s["last"]["reason"], "NAK FileNotFound for /no/such");
    assert_eq!(s["hints"][0]["code"], "transfer_refused");
    assert_eq!(s["verdict"]["failures"][0]["check"], "transfer");
}

#[test]
fn a_vehicle_that_never_answers_ends_in_no_answer_with_what_it_got() {
    let (peer, link) = vehicle(&["--ignore", "params"]);
    let (code, _, s) = download(&link, &["--probe", "params", "--retries", "1"]);
    peer.finish();
    assert_eq!(code, 1);
    let last = &s["last"];
    assert_eq!(last["ending"], "no_answer");
    assert_eq!(count(&last["requests"]), 2);
    // Its HEARTBEATs and TIMESYNC answers came: heard, yet silent.
    let hint = &s["hints"][0];
    assert_eq!(hint["code"], "transfer_no_answer");
    assert!(
        hint["text"].as_str().unwrap().contains("is heard"),
        "{hint}"
    );
}

#[test]
fn max_transfer_time_fails_a_download_slower_than_it() {
    let (peer, link) = vehicle(&["--params", "100"]);
    let (code, _, s) = download(&link, &["--probe", "params", "--max-transfer-time", "1us"]);
    peer.finish();
    assert_eq!(code, 1, "{s}");
    assert_eq!(s["complete"], 1);
    assert_eq!(s["verdict"]["failures"][0]["check"], "max-transfer-time");
}

#[test]
fn text_prometheus_and_the_plot_show_the_downloads() {
    let (peer, link) = vehicle(&["--params", "150", "--drop-list", "0.1", "--seed", "2"]);
    let scratch = crate::tlog::Scratch::new("transfers");
    let prom = scratch.path("m.prom");
    let plot = scratch.path("p.svg");
    let (code, out, err) = run_mavping(&[
        &link,
        "--probe",
        "params",
        "-W",
        "500ms",
        "--prometheus-textfile",
        prom.to_str().unwrap(),
        "--plot",
        plot.to_str().unwrap(),
    ]);
    let truth = peer.finish();
    assert_eq!(code, 0, "{out}{err}");
    let missing = truth["list_dropped"].as_array().unwrap().len();
    let line = out
        .lines()
        .find(|l| l.starts_with("download 1 from 1/1: complete, 150 parameters"))
        .unwrap_or_else(|| panic!("{out}"));
    assert!(
        line.contains(&format!("({missing} missing), {missing} re-requests")),
        "{line}"
    );
    let text = std::fs::read_to_string(&prom).unwrap();
    let labels = [("probe", "params"), ("ending", "complete")];
    assert_eq!(
        sample(&text, "mavping_transfer_downloads_total", &labels),
        Some(1.0)
    );
    assert_eq!(
        sample(&text, "mavping_transfer_last_missing_first_pass", &[]),
        Some(missing as f64)
    );
    assert_promtool_clean(&text);
    let svg = std::fs::read_to_string(&plot).unwrap();
    assert!(svg.contains("progress of each download"), "{svg}");
}

#[test]
fn bad_download_options_are_one_line_and_exit_2() {
    for (args, says) in [
        (&["--probe", "ftp", "--path", " ", "sim:"][..], "--path"),
        (
            &["--probe", "params", "--target", "0", "sim:"][..],
            "one target system",
        ),
        (&["--probe", "mission", "--sweep", "sim:"][..], "--sweep"),
    ] {
        let (code, out, err) = run_mavping(args);
        assert_eq!(code, 2, "{args:?}: {out}{err}");
        assert_eq!(err.lines().count(), 1, "{err}");
        assert!(err.contains(says), "{err}");
    }
}

#[test]
fn a_serve_module_makes_one_download_a_scrape() {
    let (peer, link) = vehicle(&["--params", "250", "--drop-list", "0.08", "--seed", "9"]);
    let config = "allow = [\"udpout:127.0.0.1:*\"]\n\
                  [module.params]\nprobe = \"params\"\ntimeout = \"500ms\"\n";
    let file = crate::serve::TempFile::new("serve-transfers.toml", config);
    let server = crate::common::serve::Server::start(&["--config", file.path()]);
    let r = server.get(&format!("/probe?module=params&target={link}"));
    let truth = peer.finish();
    assert_eq!(r.status, 200, "{}", r.body);
    let labels = [("probe", "params")];
    assert_eq!(sample(&r.body, "mavping_probe_success", &[]), Some(1.0));
    let missing = truth["list_dropped"].as_array().unwrap().len() as f64;
    assert_eq!(
        sample(&r.body, "mavping_transfer_last_missing_first_pass", &labels),
        Some(missing),
        "{}",
        r.body
    );
    assert_eq!(
        sample(&r.body, "mavping_transfer_last_received", &labels),
        Some(250.0)
    );
    let ended = [("probe", "params"), ("ending", "complete")];
    assert_eq!(
        sample(&r.body, "mavping_probe_transfer_downloads", &ended),
        Some(1.0)
    );
    assert_promtool_clean(&r.body);
}

/// The sim's truth line of what it served: "N dropped (N PARAM_VALUE...".
fn dropped_param_values(stderr: &str) -> u64 {
    let line = stderr
        .lines()
        .find(|l| l.contains("sim truth 1/1 transfers:"))
        .unwrap_or_else(|| panic!("no transfers truth: {stderr}"));
    let dropped = line.split(" dropped (").nth(1).unwrap();
    let inside = dropped.split(')').next().unwrap();
    inside
        .split(", ")
        .find_map(|s| s.strip_suffix(" PARAM_VALUE"))
        .map_or(0, |n| n.parse().unwrap())
}

#[test]
fn at_57600_baud_the_list_takes_the_wire_time_its_bytes_need_and_losses_are_the_sims() {
    let (code, out, err) = run_mavping(&[
        "--json",
        "-v",
        "-W",
        "500ms",
        "--probe",
        "params",
        "sim:?params=1000&baud=57600&loss_down=5%&seed=4",
    ]);
    assert_eq!(code, 0, "{out}{err}");
    let lines = json_lines(&out);
    assert_schema(&lines);
    let s = lines
        .iter()
        .find(|l| l["type"] == "transfer_summary")
        .unwrap();
    let last = &s["last"];
    // A PARAM_VALUE is 37 bytes: the list's floor at 5,760 bytes a second.
    let wire_bytes = count(&last["wire_bytes"]);
    assert_eq!(wire_bytes % 37, 0, "{last}");
    let floor = last["wire_floor_ms"].as_f64().unwrap();
    assert!(
        (floor - wire_bytes as f64 * 10.0 / 57.6).abs() < 1e-6,
        "{floor}"
    );
    let took = last["time_to_100_ms"].as_f64().unwrap();
    assert!(took >= floor, "{took} under the wire's floor {floor}");
    // What the sim dropped of the list is what its first pass missed, and
    // no read's answer was lost (each asked once).
    let missing = count(&last["missing_first_pass"]);
    assert!(missing > 20, "{last}");
    assert_eq!(
        dropped_param_values(&err),
        missing + count(&last["re_requests"]) - count(&last["re_requests_answered"])
    );
    assert_eq!(count(&last["received"]), 1000);
}

#[test]
fn an_open_whose_ack_was_lost_resets_the_session_and_reads_the_file() {
    let (peer, link) = vehicle(&["--file-size", "5000", "--lose-open-ack"]);
    let (code, _, s) = download(&link, &["--probe", "ftp", "--path", "/vehicle.bin"]);
    let truth = peer.finish();
    assert_eq!(code, 0, "{s}\n{truth}");
    // Open, open again (refused: the session is held), reset, open.
    assert_eq!(count(&truth["opens"]), 3, "{truth}");
    assert_eq!(count(&truth["opens_refused"]), 1);
    assert_eq!(count(&truth["resets"]), 1);
    assert_eq!(count(&s["last"]["received"]), 5000);
    assert_eq!(count(&s["last"]["re_requests"]), 2);
}
