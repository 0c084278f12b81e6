//! Issue 26's figures against real peers: pymavlink vehicles
//! (`tests/peers/vehicle.py`, streaming telemetry and answering PING)
//! behind a relay that drops, duplicates and reorders frames in each
//! direction by a seeded plan and counts exactly what it did
//! (`tests/peers/fault_relay.py`), and MAVProxy routing the same stream.
//!
//! What is exact is held exactly: the downlink figures of a probe run and
//! every count of a passive one equal the relay's; the requests' fates add
//! up request by request. What is inferred (the uplink loss) is held to
//! its own standard error, and to its formula applied to the relay's
//! counts.

use std::io::{BufRead, BufReader, Write};
use std::process::{Command, Stdio};
use std::sync::mpsc;
use std::time::Duration;

use serde_json::Value;

use crate::common::*;

/// Faults in both directions: requests and our HEARTBEATs lost and doubled
/// on the way up, each vehicle's frames lost, doubled and swapped on the
/// way down.
pub(crate) const FAULTS: [&str; 12] = [
    "--seed",
    "7",
    "--drop-up",
    "0.1",
    "--dup-up",
    "0.03",
    "--drop-down",
    "0.05",
    "--dup-down",
    "0.03",
    "--reorder-down",
    "0.02",
];

/// A pymavlink vehicle `sysid`/1 listening on a free port.
pub(crate) fn vehicle(sysid: u8, args: &[&str]) -> (Peer, u16) {
    let port = free_udp_port();
    let sysid = sysid.to_string();
    let mut all = vec![format!("udpin:127.0.0.1:{port}"), "--sysid".into(), sysid];
    all.extend(args.iter().map(|a| a.to_string()));
    let all: Vec<&str> = all.iter().map(String::as_str).collect();
    (Peer::start("vehicle.py", &all), port)
}

/// The relay in front of vehicles on `ports`, and the port it listens on
/// for the ground side.
pub(crate) fn relay(ports: &[u16], args: &[&str]) -> (Peer, u16) {
    let mut all: Vec<String> = ports
        .iter()
        .flat_map(|p| ["--vehicle".to_string(), format!("127.0.0.1:{p}")])
        .collect();
    all.extend(args.iter().map(|a| a.to_string()));
    let all: Vec<&str> = all.iter().map(String::as_str).collect();
    let mut peer = Peer::start("fault_relay.py", &all);
    let port = peer.read_line().parse().expect("the relay's port");
    (peer, port)
}

/// A vehicle's ground truth, printed once its stream has ended.
pub(crate) fn truth_when_done(peer: &mut Peer) -> Value {
    loop {
        let line = peer.read_line();
        if line.starts_with('{') {
            return serde_json::from_str(&line).unwrap();
        }
        assert!(!line.is_empty(), "the vehicle ended without its truth");
    }
}

/// The last JSON line of `kind`.
pub(crate) fn json_line(stdout: &str, kind: &str) -> Value {
    let line = stdout
        .lines()
        .rfind(|l| l.contains(&format!("\"type\":\"{kind}\"")))
        .unwrap_or_else(|| panic!("no {kind} line in\n{stdout}"));
    serde_json::from_str(line).unwrap()
}

pub(crate) fn u(v: &Value) -> u64 {
    v.as_u64().unwrap_or_else(|| panic!("not a count: {v}"))
}

/// What the relay says became of one vehicle's PING requests, counted from
/// the first it answered (the prober charges a responder from there).
#[derive(Debug, PartialEq, Eq)]
struct Requests {
    not_charged: u64,
    sent: u64,
    answered: u64,
    /// Every copy lost on the way up.
    lost_up: u64,
    /// Forwarded, and every reply lost on the way down.
    lost_down: u64,
    /// Replies forwarded beyond the first (a request or a reply doubled).
    duplicate: u64,
}

impl Requests {
    fn of(uplink: &Value) -> Self {
        // [seq, copies forwarded, replies forwarded, replies dropped]
        let fates: Vec<[u64; 3]> = uplink["requests"]
            .as_array()
            .unwrap()
            .iter()
            .map(|r| [u(&r[1]), u(&r[2]), u(&r[3])])
            .collect();
        let first = fates.iter().position(|f| f[1] > 0).expect("one answered");
        let charged = &fates[first..];
        let count = |p: &dyn Fn(&[u64; 3]) -> bool| charged.iter().filter(|f| p(f)).count() as u64;
        Requests {
            not_charged: first as u64,
            sent: charged.len() as u64,
            answered: count(&|f| f[1] > 0),
            lost_up: count(&|f| f[0] == 0),
            lost_down: count(&|f| f[0] > 0 && f[1] == 0),
            duplicate: charged.iter().map(|f| f[1].saturating_sub(1)).sum(),
        }
    }
}

/// The relay's downlink truth for one source: (frames it numbered from the
/// first forwarded to the last, of them lost where a later frame shows it).
fn downlink(truth: &Value, source: &str) -> (u64, u64) {
    let d = &truth["down"][source];
    let lost = u(&d["dropped"]) - u(&d["dropped_after_last"]);
    (u(&d["last_forwarded_index"]) + 1, lost)
}

#[test]
fn pings_through_a_lossy_relay_are_split_by_direction_as_the_relay_lost_them() {
    let stream = ["--frames", "100000", "--rate", "50"];
    let (_v1, p1) = vehicle(1, &stream);
    let (_v2, p2) = vehicle(2, &stream);
    let (relay, port) = relay(&[p1, p2], &[&FAULTS[..], &["--requests", "400"]].concat());
    let target = format!("udpout:127.0.0.1:{port}");
    let (code, out, err) = run_mavping(&[
        "-c", "400", "-i", "15ms", "-W", "1s", "-q", "--json", &target,
    ]);
    let truth = relay.finish();
    assert_eq!(code, 0, "{out}{err}");
    assert_eq!(truth["requests_seen"], 400, "{truth}");
    // The downlink closed once every copy forwarded was answered: the
    // relay's counts are what mavping can have seen.
    assert_eq!(
        (&truth["closed"], &truth["close_forced"]),
        (&Value::Bool(true), &Value::Bool(false)),
        "{truth}"
    );
    let s = json_line(&out, "summary");
    assert_eq!(s["requests"], 400);
    for (i, sysid) in [(0, 1), (1, 2)] {
        let r = s["responders"]
            .as_array()
            .unwrap()
            .iter()
            .find(|r| r["responder"]["sysid"] == sysid)
            .unwrap_or_else(|| panic!("no {sysid}/1 in {s}"));
        let up = &truth["up"][i];
        let id = format!("{sysid}/1");
        assert_eq!(up["sources"], serde_json::json!([id]), "{up}");
        let want = Requests::of(up);
        // Request by request: sent = answered + lost on the way up + lost
        // on the way down, and mavping's counts are those.
        assert_eq!(want.sent, want.answered + want.lost_up + want.lost_down);
        let got = Requests {
            not_charged: u(&r["not_charged"]),
            sent: u(&r["sent"]),
            answered: u(&r["received"]),
            lost_up: want.lost_up,
            lost_down: u(&r["lost"]) - want.lost_up,
            duplicate: u(&r["duplicate"]),
        };
        assert_eq!(got, want, "{id}: {r}");
        assert!(want.lost_up > 10 && want.lost_down > 3, "{want:?}");
        assert_eq!(r["out_of_order"], up["replies_out_of_order"], "{id}");
        assert_eq!(
            (r["late"].as_u64(), r["stale"].as_u64()),
            (Some(0), Some(0))
        );
        // The downlink, exactly: every frame of its the relay dropped
        // between its first and last forwarded.
        let d = &r["direction"];
        let (frames, lost) = downlink(&truth, &id);
        assert_eq!(
            (u(&d["downlink_frames"]), u(&d["downlink_lost"])),
            (frames, lost),
            "{id}: {d}\n{truth}"
        );
        let replies_dropped = u(&truth["down"][&id]["replies_dropped"]);
        assert!(replies_dropped >= want.lost_down, "{truth}");
        // The uplink, inferred: the formula on the relay's counts...
        let round_trip = (want.lost_up + want.lost_down) as f64 / want.sent as f64;
        assert_eq!(d["round_trip_loss"].as_f64(), Some(round_trip));
        let formula = 1.0 - (1.0 - round_trip) / (1.0 - lost as f64 / frames as f64);
        let (est, se) = (
            d["uplink_loss"].as_f64().unwrap(),
            d["uplink_stderr"].as_f64().unwrap(),
        );
        assert!(
            (est - formula.clamp(0.0, 1.0)).abs() < 1e-12,
            "{est} {formula}"
        );
        // ...and the truth within three of its standard errors (which
        // replies the plan drops depends on how they interleave with the
        // telemetry, so a tighter bound would fail one run in a few).
        let up_truth = want.lost_up as f64 / want.sent as f64;
        assert!(
            (est - up_truth).abs() < 3.0 * se,
            "{id}: up ~{est} ± {se}, truth {up_truth}"
        );
        assert!(se > 0.005 && se < 0.04, "{d}");
        assert_eq!(d["consistent"], true);
    }
}

/// `(lost, frames)` from a text summary's `direction:` line for `id`.
fn text_direction(out: &str, id: &str) -> (u64, u64) {
    let block = out
        .split_once(&format!("\n{id} ("))
        .unwrap_or_else(|| panic!("no {id} in {out}"))
        .1;
    let line = block
        .lines()
        .find(|l| l.trim_start().starts_with("direction: round trip"))
        .unwrap_or_else(|| panic!("no direction line for {id}: {out}"));
    let inside = line.split_once(" (").unwrap().1;
    let mut words = inside.split_whitespace();
    let lost = words.next().unwrap().parse().unwrap();
    assert_eq!(words.next(), Some("of"));
    (lost, words.next().unwrap().parse().unwrap())
}

#[test]
fn the_text_direction_line_says_the_relays_counts() {
    let (_v, p) = vehicle(1, &["--frames", "100000", "--rate", "50"]);
    let (relay, port) = relay(&[p], &[&FAULTS[..], &["--requests", "300"]].concat());
    let target = format!("udpout:127.0.0.1:{port}");
    let (code, out, err) = run_mavping(&["-c", "300", "-i", "15ms", "-W", "1s", "-q", &target]);
    let truth = relay.finish();
    assert_eq!(code, 0, "{out}{err}");
    assert_eq!(truth["close_forced"], false, "{truth}");
    let want = Requests::of(&truth["up"][0]);
    let c = text_counts(&out, "1/1").expect(&out);
    assert_eq!(
        (c.sent, c.received, c.lost, c.duplicate),
        (
            want.sent,
            want.answered,
            want.lost_up + want.lost_down,
            want.duplicate
        ),
        "{out}"
    );
    let (frames, lost) = downlink(&truth, "1/1");
    assert_eq!(text_direction(&out, "1/1"), (lost, frames), "{out}");
}

/// The passive summary's figures for `id`, as the relay's truth names
/// them.
fn passive_counts(s: &Value, id: &str) -> [u64; 5] {
    let r = s["sources"]
        .as_array()
        .unwrap()
        .iter()
        .find(|r| format!("{}/{}", r["source"]["sysid"], r["source"]["compid"]) == id)
        .unwrap_or_else(|| panic!("no {id} in {s}"));
    let c = &r["counts"];
    [
        u(&c["received"]),
        u(&c["lost"]),
        u(&c["duplicate"]),
        u(&c["reordered"]),
        u(&c["resyncs"]),
    ]
}

/// What the relay did to `id`'s frames, in the order of [`passive_counts`].
fn relay_counts(truth: &Value, id: &str) -> [u64; 5] {
    let d = &truth["down"][id];
    let (_, lost) = downlink(truth, id);
    [
        u(&d["forwarded"]),
        lost,
        u(&d["duplicated"]),
        u(&d["reordered"]),
        0,
    ]
}

/// Waits for every vehicle's stream to end, then stops `run` with Ctrl-C
/// (its summary is the normal one): what the vehicles sent, and mavping's
/// (exit code, stdout, stderr).
fn stop_after(run: Running, vehicles: &mut [&mut Peer]) -> (Vec<Value>, (i32, String, String)) {
    let truths = vehicles.iter_mut().map(|v| truth_when_done(v)).collect();
    // The last frames are through the relay (and MAVProxy) in well under
    // this.
    std::thread::sleep(Duration::from_millis(500));
    signal(run.child.id(), "INT");
    (truths, run.wait(Duration::from_secs(20)))
}

#[test]
fn a_passive_count_through_the_relay_equals_its_truth_per_source() {
    let (mut v1, p1) = vehicle(1, &["--frames", "500", "--rate", "100"]);
    let (mut v2, p2) = vehicle(2, &["--frames", "400", "--rate", "80"]);
    let (relay, port) = relay(&[p1, p2], &FAULTS);
    let target = format!("udpout:127.0.0.1:{port}");
    let run = start_mavping(&["--passive", "--json", &target]);
    let (sent, (code, out, err)) = stop_after(run, &mut [&mut v1, &mut v2]);
    let truth = relay.finish();
    assert_eq!(code, 0, "{out}{err}");
    let s = json_line(&out, "passive_summary");
    for (id, vehicle) in [("1/1", &sent[0]), ("2/1", &sent[1])] {
        // The relay had every frame the vehicle sent.
        assert_eq!(truth["down"][id]["frames"], vehicle["sent"], "{truth}");
        let want = relay_counts(&truth, id);
        assert!(want[1] > 5 && want[2] > 3 && want[3] > 2, "{id}: {want:?}");
        assert_eq!(passive_counts(&s, id), want, "{id}\n{truth}");
    }
}

/// MAVProxy's `link` line: (packets, lost, loss % as printed).
fn mavproxy_link(line: &str) -> (u64, u64, String) {
    let inside = line.split_once(" (").expect(line).1;
    let field = |unit: &str| {
        inside
            .split(", ")
            .find(|p| p.ends_with(unit))
            .unwrap_or_else(|| panic!("no '{unit}' in {line}"))
            .split_whitespace()
            .next()
            .unwrap()
            .to_string()
    };
    (
        field("packets").parse().unwrap(),
        field("lost").parse().unwrap(),
        field("% loss").trim_end_matches('%').to_string(),
    )
}

/// MAVProxy with its console on pipes: `link` typed on its stdin.
struct Mavproxy {
    child: std::process::Child,
    lines: mpsc::Receiver<String>,
}

impl Mavproxy {
    fn start(master: &str, out: &str, dir: &std::path::Path) -> Self {
        let mut child = Command::new(venv_program("mavproxy.py"))
            .args([format!("--master={master}"), format!("--out={out}")])
            .current_dir(dir)
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .expect("MAVProxy starts");
        let stdout = BufReader::new(child.stdout.take().unwrap());
        let (tx, lines) = mpsc::channel();
        std::thread::spawn(move || {
            for line in stdout.lines().map_while(Result::ok) {
                if tx.send(line).is_err() {
                    return;
                }
            }
        });
        Mavproxy { child, lines }
    }

    /// Types `link` and returns the line it prints for link 1.
    fn link(&mut self) -> String {
        let stdin = self.child.stdin.as_mut().unwrap();
        writeln!(stdin, "link").unwrap();
        stdin.flush().unwrap();
        loop {
            let line = self
                .lines
                .recv_timeout(Duration::from_secs(20))
                .expect("MAVProxy answers `link`");
            // Its prompt may precede the line ("MAV> link 1 OK (...").
            if let Some((_, rest)) = line.split_once("link 1 ") {
                if rest.contains(" packets, ") {
                    return format!("link 1 {rest}");
                }
            }
        }
    }
}

impl Drop for Mavproxy {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

#[test]
fn mavproxy_on_the_same_stream_shows_pymavlinks_figure_and_mavping_the_relays() {
    let dir = std::env::temp_dir().join(format!("mavping-mavproxy-link-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    // Vehicle 1 has a SiK radio beside it (RADIO_STATUS from 51/68).
    let (mut v1, p1) = vehicle(1, &["--frames", "500", "--rate", "100", "--radio-hz", "5"]);
    let (mut v2, p2) = vehicle(2, &["--frames", "400", "--rate", "80"]);
    let (relay, port) = relay(&[p1, p2], &FAULTS);
    // mavping listens where MAVProxy forwards; MAVProxy's master is the
    // relay (its HEARTBEAT, through the relay, starts the vehicles).
    let listen = free_udp_port();
    let run = start_mavping(&["--passive", "--json", &format!("udpin:127.0.0.1:{listen}")]);
    let mut mavproxy = Mavproxy::start(
        &format!("udpout:127.0.0.1:{port}"),
        &format!("udpout:127.0.0.1:{listen}"),
        &dir,
    );
    let (_, (code, out, err)) = stop_after(run, &mut [&mut v1, &mut v2]);
    let line = mavproxy.link();
    drop(mavproxy);
    let truth = relay.finish();
    let _ = std::fs::remove_dir_all(&dir);
    assert_eq!(code, 0, "{out}{err}");
    let s = json_line(&out, "passive_summary");
    // What MAVProxy forwarded is the relay's stream, nothing of its own.
    let ids: Vec<String> = s["sources"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| format!("{}/{}", r["source"]["sysid"], r["source"]["compid"]))
        .collect();
    assert_eq!(ids, ["1/1", "2/1", "51/68"], "{s}");
    // pymavlink's figure, as mavutil.post_message counts it: MAVProxy's
    // `lost` and loss %, to the frame. Its `packets` is its own counter of
    // every message on the link (MasterIn), the radio's included, where
    // mav_count and the loss leave the radio out.
    let totals = &s["totals"];
    let (packets, lost, pct) = mavproxy_link(&line);
    assert_eq!(lost, u(&totals["pymav"]["loss"]), "{line}\n{totals}");
    let pymav_pct = totals["pymav"]["loss_pct"].as_f64().unwrap();
    assert_eq!(pct, format!("{pymav_pct:.1}"), "{line}");
    let radio = u(&totals["radio_received"]);
    assert!(radio > 10, "{totals}");
    assert_eq!(packets, u(&totals["pymav"]["count"]) + radio, "{line}");
    // mavping's own figures are the relay's truth, where pymavlink's (and
    // MAVProxy's) count each duplicate and reorder as ~255 lost.
    let mut relay_lost = 0;
    for id in ["1/1", "2/1"] {
        let want = relay_counts(&truth, id);
        assert_eq!(passive_counts(&s, id), want, "{id}\n{truth}");
        relay_lost += want[1];
    }
    assert_eq!(u(&totals["counts"]["lost"]), relay_lost);
    assert!(lost > 100 * relay_lost, "{lost} vs {relay_lost}");
}
