//! Two links to one vehicle (issue 41): a pymavlink vehicle
//! (`tests/peers/two_link_vehicle.py`) writes the same packed frames to
//! two or three UDP links with seeded per-link drops and delays and
//! counts what it did; mavping listens on every link and its
//! `pair_summary` must count the same, exactly.

use serde_json::Value;

use crate::common::*;
use crate::passive_peers::json_line;

fn count(v: &Value, key: &str) -> u64 {
    v[key].as_u64().unwrap_or_else(|| panic!("no {key} in {v}"))
}

/// Runs the vehicle on `n` links with `faults` (its per-link arguments)
/// and mavping listening on them for `listen_s`; the vehicle's truth and
/// mavping's pair line for source 1/1, every line held to the schema.
fn paired(n: usize, faults: &[&str], listen_s: &str) -> (Value, Value, String) {
    paired_with(n, faults, listen_s, &[])
}

/// [`paired`], mavping given `extra` arguments too.
fn paired_with(
    n: usize,
    faults: &[&str],
    listen_s: &str,
    extra: &[&str],
) -> (Value, Value, String) {
    let ports: Vec<u16> = (0..n).map(|_| free_udp_port()).collect();
    let links: Vec<String> = ports.iter().map(|p| format!("udp:127.0.0.1:{p}")).collect();
    let tos: Vec<String> = ports.iter().map(|p| format!("127.0.0.1:{p}")).collect();
    let mut args: Vec<&str> = Vec::new();
    for to in &tos {
        args.extend(["--to", to.as_str()]);
    }
    args.extend(faults);
    args.extend(["--duration", "4", "--start-after", "1", "--seed", "7"]);
    let vehicle = Peer::start("two_link_vehicle.py", &args);
    let mut mavping_args = vec!["--passive", "-q", "--json", "-w", listen_s];
    mavping_args.extend(extra);
    mavping_args.extend(links.iter().map(String::as_str));
    let (code, out, err) = run_mavping(&mavping_args);
    assert_eq!(code, 0, "{err}");
    let truth = vehicle.finish();
    assert_schema(&json_lines(&out));
    let pair = json_line(&out, "pair_summary");
    assert_eq!(pair["links"].as_array().unwrap().len(), n, "{pair}");
    let source = pair["sources"]
        .as_array()
        .unwrap()
        .iter()
        .find(|s| s["source"] == serde_json::json!({"sysid": 1, "compid": 1}))
        .unwrap_or_else(|| panic!("no 1/1 in {pair}"))
        .clone();
    (truth, source, out)
}

/// Every count the vehicle kept, equal to mavping's: each link's
/// deliveries, the frames it delivered first and only it delivered, its
/// own loss (the drops between its first and last frame: its sequence
/// cannot see the others); the frames lost on every link and the copies.
fn assert_counts(truth: &Value, source: &Value) {
    let frames = count(truth, "frames");
    let lost_everywhere = count(truth, "lost_on_every_link");
    assert_eq!(
        count(source, "distinct_frames"),
        frames - lost_everywhere,
        "{source}"
    );
    let between = count(truth, "lost_on_every_link_between");
    assert_eq!(count(source, "lost_on_every_link"), between, "{source}");
    let links = source["links"].as_array().unwrap();
    let told = truth["links"].as_array().unwrap();
    assert_eq!(links.len(), told.len(), "{source}");
    let mut copies = 0;
    // Each link in the order the vehicle was given them (the tracker's
    // index may be higher: ways first heard from others come before).
    let order: Vec<u64> = links.iter().map(|l| count(l, "link")).collect();
    assert!(order.windows(2).all(|w| w[0] < w[1]), "{source}");
    for (k, (got, t)) in links.iter().zip(told).enumerate() {
        assert_eq!(
            count(got, "frames"),
            count(t, "sent"),
            "link {k}: {got} vs {t}"
        );
        assert_eq!(
            count(got, "first"),
            count(t, "first"),
            "link {k}: {got} vs {t}"
        );
        assert_eq!(
            count(got, "only"),
            count(t, "only"),
            "link {k}: {got} vs {t}"
        );
        assert_eq!(count(got, "only_undecided"), 0, "{got}");
        let between = count(t, "dropped_between");
        assert_eq!(count(got, "lost"), between, "link {k}: {got} vs {t}");
        copies += count(t, "sent") - count(t, "first");
    }
    assert_eq!(count(source, "copies"), copies, "{source}");
}

fn ms(v: &Value, key: &str) -> f64 {
    v[key].as_f64().unwrap_or_else(|| panic!("no {key} in {v}"))
}

/// Two links, one losing 10 % at 20 ms, the other 20 % at 100 ms: exact
/// counts, the slower link's lag 80 ms within 5 ms, the faster never
/// behind, and the de-duplication window that catches the copies.
#[test]
fn two_links_are_counted_as_the_vehicle_sent_them() {
    let faults = [
        "--drop",
        "10",
        "--delay-ms",
        "20",
        "--drop",
        "20",
        "--delay-ms",
        "100",
    ];
    let (truth, source, out) = paired(2, &faults, "7");
    assert!(count(&truth, "lost_on_every_link_between") > 0, "{truth}");
    assert_counts(&truth, &source);
    // The lags within 5 ms of the vehicle's, as its copies were really
    // sent (80 ms apart by plan; later when the machine is busy).
    for (got, t) in source["links"]
        .as_array()
        .unwrap()
        .iter()
        .zip(truth["links"].as_array().unwrap())
    {
        for key in ["lag_p50_ms", "lag_max_ms"] {
            assert!(
                (ms(got, key) - ms(t, key)).abs() < 5.0,
                "{key}: {got} vs {t}"
            );
        }
    }
    let slow = &source["links"][1];
    assert!((ms(slow, "lag_p50_ms") - 80.0).abs() < 5.0, "{slow}");
    // The window that catches the copies is the slow link's worst lag.
    let window = ms(&source, "dedup_window_p999_ms");
    assert!(
        (window - ms(&truth["links"][1], "lag_max_ms")).abs() < 5.0,
        "{source}"
    );
    // Every frame the fast link lost and the slow one delivered came
    // behind a newer one: the map jumps back even behind de-duplication.
    assert_eq!(count(slow, "stale_first"), count(slow, "first"), "{slow}");
    let fast = &source["links"][0];
    assert_eq!(count(fast, "stale"), 0, "{fast}");
    // Each link's own summary is there too, before the pair's line.
    let passive = out.matches("\"type\":\"passive_summary\"").count();
    assert_eq!(passive, 2, "{out}");
}

/// Three links, one with jitter that reorders its copies: still exact.
#[test]
fn three_links_with_a_reordering_one_are_counted_exactly() {
    let faults = [
        "--drop",
        "30",
        "--delay-ms",
        "0",
        "--jitter-ms",
        "0",
        "--drop",
        "40",
        "--delay-ms",
        "30",
        "--jitter-ms",
        "40",
        "--drop",
        "20",
        "--delay-ms",
        "300",
        "--jitter-ms",
        "0",
    ];
    let (truth, source, _) = paired(3, &faults, "7");
    assert!(
        truth["links"][1]["reordered"].as_u64().unwrap() > 0,
        "{truth}"
    );
    assert_counts(&truth, &source);
}

/// Different vehicles on two links are no pair: no pair line.
#[test]
fn links_to_different_vehicles_make_no_pair_line() {
    let (code, out, err) = run_mavping(&[
        "--passive",
        "-q",
        "--json",
        "-w",
        "2",
        "sim:?clock=virtual&stream=ATTITUDE@20",
        "sim:?clock=virtual&stream=ATTITUDE@20&sysid=2",
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(!out.contains("pair_summary"), "{out}");
}

/// After the flight: a MAVProxy log (written by pymavlink with MAVProxy's
/// link numbers in its stamps' low bits) of a vehicle on links 0 and 1,
/// each losing frames of its own beside two both lost, link 1 300 µs
/// behind. The pair report reads the log's links as ways: the frames only
/// one link delivered are the other's drops, exactly.
#[test]
fn a_mavproxy_logs_links_make_the_pair_report() {
    use crate::tlog::{mavproxy_plan, tlog, write_log, Scratch};
    let dir = Scratch::new("pair-links");
    let path = dir.path("links.tlog");
    let t = write_log(&path, &mavproxy_plan());
    let (code, out, err) = run_mavping(&["--json", "-q", &tlog(&path)]);
    assert_eq!(code, 0, "{err}");
    assert_schema(&json_lines(&out));
    let pair = json_line(&out, "pair_summary");
    let source = &pair["sources"][0];
    assert_eq!(
        source["source"],
        serde_json::json!({"sysid": 1, "compid": 1})
    );
    let truth = &t["sources"]["1/1"];
    let both = truth["dropped"].as_u64().unwrap();
    assert_eq!(count(source, "lost_on_every_link"), both, "{source}");
    let link = |n: u64| {
        let name = format!("{} path {n}", tlog(&path));
        let k = pair["links"]
            .as_array()
            .unwrap()
            .iter()
            .position(|l| *l == name.as_str())
            .unwrap_or_else(|| panic!("no {name} in {pair}"));
        source["links"]
            .as_array()
            .unwrap()
            .iter()
            .find(|l| count(l, "link") == k as u64)
            .unwrap()
            .clone()
    };
    let (zero, one) = (link(0), link(1));
    let dropped = |n: &str| truth["links"][n]["dropped"].as_u64().unwrap();
    assert_eq!(
        count(&zero, "frames"),
        truth["links"]["0"]["written"].as_u64().unwrap()
    );
    assert_eq!(
        count(&one, "frames"),
        truth["links"]["1"]["written"].as_u64().unwrap()
    );
    assert_eq!(count(&zero, "only"), dropped("1"), "{zero}");
    assert_eq!(count(&one, "only"), dropped("0"), "{one}");
    assert!((ms(&one, "lag_p50_ms") - 0.3).abs() < 0.01, "{one}");
    // MAVProxy's own frames (link 3) came one way; the ground station's
    // it forwarded, stamped with a clock, fell on links 1 and 3 by their
    // stamps' bits, no frame on both: split, not copied.
    assert_eq!(pair["sources"].as_array().unwrap().len(), 1, "{pair}");
    let ids = |v: &Value| v.as_array().unwrap().len();
    assert_eq!(ids(&pair["single_link_sources"]), 1, "{pair}");
    assert_eq!(
        pair["uncopied_sources"],
        serde_json::json!([{"sysid": 255, "compid": 190}])
    );
}

/// A real log whose stamps' low bits are a clock's, not MAVProxy's link
/// numbers (flight_logs.tlog: they spread over 0 to 3, and splitting by
/// them leaves each part 75 % lost): no ways, no pair report.
#[test]
fn a_log_without_link_numbers_makes_no_pair_report() {
    let path = crate::field_logs::shared_tlog("flight_logs.tlog");
    let (code, out, err) = run_mavping(&["--json", "-q", path.to_str().unwrap()]);
    assert_eq!(code, 0, "{err}");
    assert!(!out.contains("pair_summary"), "{out}");
}

/// A real MAVProxy session with two masters, the pymavlink vehicle
/// sending the same frames to both with its own drops and delays, logging
/// into its own tlog with its link numbers: read back, the pair report
/// counts what the vehicle sent on each link, exactly.
#[test]
fn a_mavproxy_session_on_two_links_is_read_back_as_a_pair() {
    let mavproxy = venv_program("mavproxy.py");
    let dir = crate::tlog::Scratch::new("pair-mavproxy");
    let (one, two) = (free_udp_port(), free_udp_port());
    let masters = [
        format!("--master=udpin:127.0.0.1:{one}"),
        format!("--master=udpin:127.0.0.1:{two}"),
    ];
    let log = dir.path("two.tlog");
    let logfile = format!("--logfile={}", log.display());
    let session = Program::start_on_udp(
        &mavproxy,
        // Flushed on every frame, so that the log shows what MAVProxy has
        // read so far.
        &[
            &masters[0],
            &masters[1],
            "--non-interactive",
            "--cmd=set flushlogs 1",
            &logfile,
        ],
        log.parent().unwrap(),
        two,
    );
    let vehicle = std::process::Command::new(python())
        .arg(peer_script("two_link_vehicle.py"))
        .args([
            "--to",
            &format!("127.0.0.1:{one}"),
            "--to",
            &format!("127.0.0.1:{two}"),
        ])
        .args([
            "--drop",
            "10",
            "--delay-ms",
            "20",
            "--drop",
            "20",
            "--delay-ms",
            "100",
        ])
        .args(["--duration", "4", "--start-after", "0.5", "--seed", "7"])
        .output()
        .unwrap();
    assert!(vehicle.status.success(), "{vehicle:?}");
    let stdout = String::from_utf8(vehicle.stdout).unwrap();
    let truth: Value = serde_json::from_str(stdout.lines().last().unwrap()).unwrap();
    let sent: u64 = truth["links"]
        .as_array()
        .unwrap()
        .iter()
        .map(|l| count(l, "sent"))
        .sum();
    wait_until_logged(&log, sent);
    session.terminate();
    let (code, out, err) = run_mavping(&["--json", "-q", log.to_str().unwrap()]);
    assert_eq!(code, 0, "{err}");
    let pair = json_line(&out, "pair_summary");
    let source = &pair["sources"][0];
    assert_eq!(
        source["source"],
        serde_json::json!({"sysid": 1, "compid": 1})
    );
    // MAVProxy's link 0 is the first master, link 1 the second (its own
    // HEARTBEAT is on 3).
    let name = |k: usize| {
        let link = count(&source["links"][k], "link") as usize;
        pair["links"][link].as_str().unwrap().to_string()
    };
    assert!(
        name(0).ends_with("path 0") && name(1).ends_with("path 1"),
        "{pair}"
    );
    assert_counts(&truth, source);
    let slow = &source["links"][1];
    assert!((ms(slow, "lag_p50_ms") - 80.0).abs() < 5.0, "{slow}");
}

/// Waits (at most 30 s) until the tlog at `path` holds `frames` frames
/// from the vehicle (1/1), as pymavlink reads it: MAVProxy, slow on a
/// busy machine, has logged every copy it was sent.
fn wait_until_logged(path: &std::path::Path, frames: u64) {
    let script = r"
import sys
from pymavlink import mavutil
log = mavutil.mavlink_connection(sys.argv[1])
n = 0
while True:
    m = log.recv_match()
    if m is None:
        break
    n += (m.get_srcSystem(), m.get_srcComponent()) == (1, 1)
print(n)
";
    let started = std::time::Instant::now();
    loop {
        let out = std::process::Command::new(python())
            .args(["-c", script])
            .arg(path)
            .output()
            .unwrap();
        let logged: u64 = String::from_utf8_lossy(&out.stdout)
            .trim()
            .parse()
            .unwrap_or(0);
        if logged >= frames || started.elapsed().as_secs() >= 30 {
            return;
        }
        std::thread::sleep(std::time::Duration::from_millis(250));
    }
}

/// The pair report as metrics: each link's part and the merged stream's,
/// the same figures as the JSON line, and promtool finds nothing to say.
#[test]
fn the_pair_report_is_exported_as_metrics() {
    let dir = crate::tlog::Scratch::new("pair-metrics");
    let prom = dir.path("pair.prom");
    let faults = [
        "--drop",
        "10",
        "--delay-ms",
        "20",
        "--drop",
        "20",
        "--delay-ms",
        "60",
    ];
    let extra = ["--prometheus-textfile", prom.to_str().unwrap()];
    let (_, source, out) = paired_with(2, &faults, "7", &extra);
    let text = std::fs::read_to_string(&prom).unwrap();
    crate::common::http::assert_promtool_clean(&text);
    let samples = crate::common::http::samples(&text);
    let value = |name: &str, link: Option<&str>| {
        samples
            .iter()
            .find(|s| {
                s.name == name
                    && s.labels.get("sysid").map(String::as_str) == Some("1")
                    && s.labels.get("link").map(String::as_str) == link
            })
            .unwrap_or_else(|| panic!("no {name} {link:?} in {text}"))
            .value
    };
    let pair = json_line(&out, "pair_summary");
    let names = pair["links"].as_array().unwrap();
    for l in source["links"].as_array().unwrap() {
        let name = names[count(l, "link") as usize].as_str().unwrap();
        for (metric, key) in [
            ("mavping_pair_frames_total", "frames"),
            ("mavping_pair_first_frames_total", "first"),
            ("mavping_pair_only_frames_total", "only"),
            ("mavping_pair_lost_total", "lost"),
            ("mavping_pair_stale_frames_total", "stale"),
        ] {
            assert_eq!(
                value(metric, Some(name)),
                count(l, key) as f64,
                "{metric} {name}"
            );
        }
        let lag = value("mavping_pair_lag_p50_seconds", Some(name));
        assert!((lag * 1e3 - ms(l, "lag_p50_ms")).abs() < 1e-6, "{name}");
    }
    assert_eq!(
        value("mavping_pair_distinct_frames_total", None),
        count(&source, "distinct_frames") as f64
    );
    assert_eq!(
        value("mavping_pair_lost_on_every_link_total", None),
        count(&source, "lost_on_every_link") as f64
    );
}

/// The matrix: TIMESYNC requests out on each of two links to a vehicle
/// that routes every reply to both (`two_link_responder.py`, with its own
/// drops each way): each cell (out on A, back on B) counts the replies
/// the vehicle sent on B to requests that came on A, exactly, and the
/// slow link's replies come back later.
#[test]
fn the_matrix_counts_each_links_replies_to_each_links_requests() {
    let (listen, responder) = two_link_responder(&MATRIX_FAULTS);
    let links: Vec<String> = listen.iter().map(|l| format!("udpout:{l}")).collect();
    let dir = crate::tlog::Scratch::new("pair-matrix");
    let recording = dir.path("matrix.tlog");
    let (code, out, err) = run_mavping(&[
        "--probe",
        "timesync",
        "-c",
        "100",
        "-i",
        "0.02",
        "-W",
        "1s",
        "--json",
        "-q",
        "--tlog",
        recording.to_str().unwrap(),
        &links[0],
        &links[1],
    ]);
    let truth = responder.finish();
    assert!(code <= 1, "{err}");
    assert_schema(&json_lines(&out));
    let matrix = json_line(&out, "link_matrix");
    assert_eq!(
        matrix["requests"],
        serde_json::json!([100, 100]),
        "{matrix}"
    );
    let cell = |a: usize, b: usize| {
        matrix["cells"]
            .as_array()
            .unwrap()
            .iter()
            .find(|c| count(c, "out") == a as u64 && count(c, "back") == b as u64)
            .unwrap_or_else(|| panic!("no cell {a} -> {b} in {matrix}"))
            .clone()
    };
    for a in 0..2 {
        let received = count(&truth["links"][a], "requests_received");
        assert_eq!(received, 100, "{truth}");
        // Each request carries its out-link in its low bits, as
        // MAVProxy's `ping` does.
        assert_eq!(
            truth["links"][a]["ts1_low_bits"],
            serde_json::json!({a.to_string(): 100}),
            "{truth}"
        );
        for b in 0..2 {
            let told = count(&truth["cells"][a][b], "replies");
            assert_eq!(
                count(&cell(a, b), "replies"),
                told,
                "{a} -> {b}: {matrix} vs {truth}"
            );
            assert_eq!(count(&cell(a, b), "duplicates"), 0);
        }
    }
    // Link 1's copies leave the vehicle 40 ms after link 0's.
    for a in 0..2 {
        let (fast, slow) = (ms(&cell(a, 0), "rtt_p50_ms"), ms(&cell(a, 1), "rtt_p50_ms"));
        assert!((slow - fast - 40.0).abs() < 10.0, "{a}: {fast} vs {slow}");
    }
    // The recording, read back, is MAVProxy's log of the same: our sends
    // on its own link 3, the replies on the links they came on, and each
    // request's out-link in its token. The same cells.
    let (code, out, err) = run_mavping(&["--json", "-q", recording.to_str().unwrap()]);
    assert_eq!(code, 0, "{err}");
    let read = json_line(&out, "link_matrix");
    assert_eq!(read["requests"], matrix["requests"], "{read}");
    assert_eq!(read["cells"].as_array().unwrap().len(), 4, "{read}");
    for (got, live) in read["cells"]
        .as_array()
        .unwrap()
        .iter()
        .zip(matrix["cells"].as_array().unwrap())
    {
        for key in ["out", "back", "replies", "duplicates"] {
            assert_eq!(got[key], live[key], "{read} vs {matrix}");
        }
    }
}

/// The first link's requests lose 10 % on the way up, the second link's
/// replies 20 % on the way down, 40 ms later.
const MATRIX_FAULTS: [&str; 14] = [
    "--drop-up",
    "10",
    "--drop-up",
    "0",
    "--drop-down",
    "0",
    "--drop-down",
    "20",
    "--delay-ms",
    "0",
    "--delay-ms",
    "40",
    "--seed",
    "3",
];

/// `two_link_responder.py` listening on two free UDP ports with `faults`:
/// its two HOST:PORT and the peer.
fn two_link_responder(faults: &[&str]) -> ([String; 2], Peer) {
    let listen = [
        format!("127.0.0.1:{}", free_udp_port()),
        format!("127.0.0.1:{}", free_udp_port()),
    ];
    let mut args = vec![
        "--listen",
        listen[0].as_str(),
        "--listen",
        listen[1].as_str(),
    ];
    args.extend(faults);
    let responder = Peer::start("two_link_responder.py", &args);
    (listen, responder)
}

/// Two logs of one flight, one per ground station, read together: each
/// lost frames of its own, the second's logger received every frame
/// 30 ms later. The logs are laid on one clock by their stamps, so the
/// pair report counts each log's part, the second's lag, and its frames
/// behind newer ones, exactly.
#[test]
fn two_logs_of_one_flight_are_read_as_a_pair() {
    use crate::tlog::{tlog, write_log, Scratch};
    let dir = Scratch::new("pair-two-logs");
    let drops = [vec![5u64, 6, 7, 100, 700, 701, 1200], vec![7, 8, 300, 700]];
    let paths = [dir.path("a.tlog"), dir.path("b.tlog")];
    for (k, (path, drop)) in paths.iter().zip(&drops).enumerate() {
        let plan = serde_json::json!({
            "start_us": 1_764_500_000_000_000u64 + 30_000 * k as u64,
            "stamps": "us",
            "sources": [{"sysid": 1, "compid": 1, "rate": 50, "frames": 1500, "drop": drop}],
        });
        write_log(path, &plan);
    }
    let links: Vec<String> = paths.iter().map(|p| tlog(p)).collect();
    let (code, out, err) = run_mavping(&["--json", "-q", &links[0], &links[1]]);
    assert_eq!(code, 0, "{err}");
    assert_schema(&json_lines(&out));
    let source = &json_line(&out, "pair_summary")["sources"][0];
    let (a, b) = (&drops[0], &drops[1]);
    let both = a.iter().filter(|n| b.contains(n)).count() as u64;
    assert_eq!(count(source, "lost_on_every_link"), both, "{source}");
    assert_eq!(count(source, "distinct_frames"), 1500 - both, "{source}");
    let (one, two) = (&source["links"][0], &source["links"][1]);
    assert_eq!(count(one, "frames"), 1500 - a.len() as u64);
    assert_eq!(count(two, "frames"), 1500 - b.len() as u64);
    let only =
        |mine: &[u64], theirs: &[u64]| theirs.iter().filter(|n| !mine.contains(n)).count() as u64;
    assert_eq!(count(one, "only"), only(a, b), "{one}");
    assert_eq!(count(two, "only"), only(b, a), "{two}");
    assert_eq!(count(one, "first"), 1500 - a.len() as u64, "{one}");
    assert_eq!(count(two, "first"), only(b, a), "{two}");
    assert!((ms(two, "lag_p50_ms") - 30.0).abs() < 0.01, "{two}");
    // A frame every 20 ms, the second log's 30 ms late: its frame n came
    // after the first log's n + 1, when that one was not lost. The logs
    // are read a page at a time each, not in time order.
    let behind = (0..1499)
        .filter(|n| !b.contains(n) && !a.contains(&(n + 1)))
        .count() as u64;
    assert_eq!(count(two, "stale"), behind, "{two}");
    assert_eq!(count(one, "stale"), 0, "{one}");
}

/// `--plot` of a run on two links: the lag chart, and each link's first
/// share and lag p50 in the legend, as the pair report has them.
#[test]
fn the_plot_draws_each_links_lag() {
    let dir = crate::tlog::Scratch::new("pair-plot");
    let svg = dir.path("pair.svg");
    let faults = [
        "--drop",
        "10",
        "--delay-ms",
        "20",
        "--drop",
        "20",
        "--delay-ms",
        "100",
    ];
    let extra = ["--plot", svg.to_str().unwrap()];
    let (_, source, _) = paired_with(2, &faults, "7", &extra);
    let svg = std::fs::read_to_string(&svg).unwrap();
    assert!(
        svg.contains("lag behind the first copy, by link"),
        "no lag chart"
    );
    for link in source["links"].as_array().unwrap() {
        for key in ["first_pct", "lag_p50_ms"] {
            let figure = format!("\n{:.1}\n", ms(link, key));
            assert!(svg.contains(&figure), "{key} {figure:?} of {link} missing");
        }
    }
}

/// MAVProxy's own `ping` (repeated), on two masters to the two-link
/// responder, logged into its tlog: mavping reads the matrix back from
/// the log (the requests MAVProxy logged on its own link 3, each one's
/// out-link in its `ts1`'s low bits; the replies on the links they came
/// back on), every cell the count of MAVProxy's own "ping response ...
/// in-link=B out-link=A" lines and of the responder's replies.
#[test]
fn a_mavproxy_ping_session_is_read_back_as_its_matrix() {
    let (listen, responder) = two_link_responder(&MATRIX_FAULTS);
    let dir = crate::tlog::Scratch::new("pair-mavproxy-ping");
    let log = dir.path("ping.tlog");
    let printed = dir.path("mavproxy.out");
    let mavproxy = std::process::Command::new(venv_program("mavproxy.py"))
        .args([
            &format!("--master=udpout:{}", listen[0]),
            &format!("--master=udpout:{}", listen[1]),
            "--non-interactive",
            "--cmd=set flushlogs 1; repeat add 0.2 ping",
            &format!("--logfile={}", log.display()),
        ])
        .current_dir(log.parent().unwrap())
        .stdin(std::process::Stdio::null())
        .stdout(std::fs::File::create(&printed).unwrap())
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    let session = Program::from(mavproxy);
    let responses = || {
        let text = std::fs::read_to_string(&printed).unwrap_or_default();
        let mut cells = std::collections::BTreeMap::new();
        for line in text.lines().filter(|l| l.starts_with("ping response")) {
            let link = |key: &str| -> u64 {
                let at = line.find(key).unwrap() + key.len();
                line[at..=at].parse().unwrap()
            };
            *cells
                .entry((link("out-link="), link("in-link=")))
                .or_insert(0u64) += 1;
        }
        cells
    };
    let started = std::time::Instant::now();
    while responses().values().sum::<u64>() < 60 {
        assert!(
            started.elapsed().as_secs() < 60,
            "MAVProxy printed {:?}",
            responses()
        );
        std::thread::sleep(std::time::Duration::from_millis(200));
    }
    // No reply after the responder stops: MAVProxy logs what it printed.
    let truth = responder.finish();
    std::thread::sleep(std::time::Duration::from_secs(1));
    session.terminate();
    let (code, out, err) = run_mavping(&["--json", "-q", log.to_str().unwrap()]);
    assert_eq!(code, 0, "{err}");
    assert_schema(&json_lines(&out));
    let matrix = json_line(&out, "link_matrix");
    let name = |k: usize| format!("{} path {k}", log.display());
    assert_eq!(matrix["links"][0], name(0), "{matrix}");
    let printed = responses();
    for a in 0..2 {
        let requests = matrix["requests"][a].as_u64().unwrap();
        assert!(
            requests >= count(&truth["links"][a], "requests_received"),
            "{matrix} vs {truth}"
        );
        for b in 0..2 {
            let cell = matrix["cells"]
                .as_array()
                .unwrap()
                .iter()
                .find(|c| count(c, "out") == a as u64 && count(c, "back") == b as u64)
                .unwrap_or_else(|| panic!("no cell {a} -> {b} in {matrix}"));
            let replies = count(cell, "replies");
            assert_eq!(
                replies,
                printed[&(a as u64, b as u64)],
                "{a} -> {b}: {printed:?}"
            );
            assert_eq!(replies, count(&truth["cells"][a][b], "replies"), "{truth}");
        }
    }
}

/// The same matrix of PING, for a vehicle that answers PING and routes
/// its replies to every link: each cell the responder's own count.
#[test]
fn the_ping_matrix_counts_each_links_replies_to_each_links_requests() {
    let (listen, responder) = two_link_responder(&[
        "--ping",
        "--drop-up",
        "0",
        "--drop-up",
        "15",
        "--drop-down",
        "25",
        "--drop-down",
        "0",
        "--delay-ms",
        "30",
        "--delay-ms",
        "0",
        "--seed",
        "5",
    ]);
    let links: Vec<String> = listen.iter().map(|l| format!("udpout:{l}")).collect();
    let (code, out, err) = run_mavping(&[
        "--probe", "ping", "-c", "80", "-i", "0.02", "-W", "1s", "--json", "-q", &links[0],
        &links[1],
    ]);
    let truth = responder.finish();
    assert!(code <= 1, "{err}");
    assert_schema(&json_lines(&out));
    let matrix = json_line(&out, "link_matrix");
    assert_eq!(matrix["message"], "PING", "{matrix}");
    assert_eq!(matrix["requests"], serde_json::json!([80, 80]), "{matrix}");
    let cells = matrix["cells"].as_array().unwrap();
    assert_eq!(cells.len(), 4, "{matrix}");
    for cell in cells {
        let (a, b) = (count(cell, "out") as usize, count(cell, "back") as usize);
        let told = count(&truth["cells"][a][b], "replies");
        assert_eq!(
            count(cell, "replies"),
            told,
            "{a} -> {b}: {matrix} vs {truth}"
        );
    }
    assert!(
        !out.contains("\"message\":\"TIMESYNC\""),
        "no TIMESYNC was sent: {out}"
    );
}
