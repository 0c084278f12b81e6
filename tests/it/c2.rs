//! The C2 link report (`--report c2`, issue 44) against truth the tests
//! control: `sim:` outages of known lengths (the sim's `outage=` windows),
//! a pymavlink vehicle behind a relay that cuts the link on a schedule
//! (`fault_relay.py --cut`, which says when it forwarded every frame), and
//! the shared real logs, whose figures `tests/peers/c2_truth.py` computes
//! from its own walk of the records with pymavlink's dialect. The failsafe
//! replays are held against a direct simulation of the rule written here
//! (or in c2_truth.py), not mavping's.

use std::path::Path;

use serde_json::{json, Value};

use crate::common::*;
use crate::field_logs::shared_tlog;
use crate::passive_peers::{relay, vehicle};
use crate::tlog::{write_log, Scratch};

/// The duration bands and their lower bounds, s.
const BANDS: [(&str, f64); 5] = [
    ("<1s", 0.0),
    ("1-3s", 1.0),
    ("3-10s", 3.0),
    ("10-30s", 10.0),
    (">30s", 30.0),
];

fn f(v: &Value, key: &str) -> f64 {
    v[key]
        .as_f64()
        .unwrap_or_else(|| panic!("no number {key} in {v}"))
}

fn u(v: &Value, key: &str) -> u64 {
    v[key]
        .as_u64()
        .unwrap_or_else(|| panic!("no count {key} in {v}"))
}

fn list<'a>(v: &'a Value, key: &str) -> &'a Vec<Value> {
    v[key]
        .as_array()
        .unwrap_or_else(|| panic!("no list {key} in {v}"))
}

fn band_of(duration: f64) -> &'static str {
    BANDS
        .iter()
        .rev()
        .find(|(_, lo)| duration >= *lo)
        .unwrap()
        .0
}

/// A run with `--json --report c2 ARGS`: its exit code, the `c2_report`
/// line (every line checked against the schema), and stderr.
fn c2_run(args: &[&str]) -> (i32, Value, String) {
    let mut all = vec!["--json", "--report", "c2"];
    all.extend_from_slice(args);
    let (code, out, err) = run_mavping(&all);
    let lines = json_lines(&out);
    assert_schema(&lines);
    let at = lines
        .iter()
        .position(|l| l["type"] == "c2_report")
        .unwrap_or_else(|| panic!("no c2_report line (exit {code}):\n{out}\n{err}"));
    // The report comes just before its link's summary.
    let next = &lines.get(at + 1).map(|l| l["type"].clone());
    assert!(
        matches!(next.as_ref().and_then(|t| t.as_str()), Some(t) if t.ends_with("summary")),
        "{out}"
    );
    (code, lines[at].clone(), err)
}

/// The failsafe replays of a report, by position.
fn replays(report: &Value) -> &Vec<Value> {
    list(report, "failsafes")
}

// ---------------------------------------------------------------------
// The direct simulation of the rules, on delivery and frame times (s).

/// A failsafe trip: when, for how long, still on at the end.
#[derive(Debug, Clone, Copy)]
struct Trip {
    at: f64,
    lasted: f64,
    open: bool,
}

/// The failsafe rule: tripped when the time since the last delivery (or
/// time 0) exceeds `timeout`, at that delivery plus the timeout, until
/// the next delivery or `end`.
fn failsafe_trips(deliveries: &[f64], end: f64, timeout: f64) -> Vec<Trip> {
    let mut trips = Vec::new();
    let mut last = 0.0;
    for &d in deliveries {
        if d - last > timeout {
            trips.push(Trip {
                at: last + timeout,
                lasted: d - last - timeout,
                open: false,
            });
        }
        last = d;
    }
    if end - last > timeout {
        trips.push(Trip {
            at: last + timeout,
            lasted: end - last - timeout,
            open: true,
        });
    }
    trips
}

/// The up-within rule on a vehicle's frame times: (start, duration) of
/// each outage, the last one open if the frames stopped before `end`.
fn outages_of(frames: &[f64], end: f64, up_within: f64) -> Vec<(f64, f64)> {
    let mut out = Vec::new();
    let mut last = 0.0;
    for &t in frames.iter().chain([end].iter()) {
        if t - last > up_within {
            out.push((last + up_within, t - last - up_within));
        }
        last = t;
    }
    out
}

/// The report's trips (all listed: fewer than its list holds) against
/// the simulation's, each time within `tol` s.
fn assert_trips(replay: &Value, expected: &[Trip], tol: f64) {
    assert_eq!(
        u(replay, "trips"),
        expected.len() as u64,
        "{replay}\n{expected:?}"
    );
    let listed = list(replay, "trip_list");
    assert_eq!(listed.len(), expected.len(), "{replay}");
    for (t, e) in listed.iter().zip(expected) {
        assert!((f(t, "at_s") - e.at).abs() <= tol, "{t} vs {e:?}");
        assert!((f(t, "lasted_s") - e.lasted).abs() <= tol, "{t} vs {e:?}");
        assert_eq!(t["open"], e.open, "{t} vs {e:?}");
    }
}

// ---------------------------------------------------------------------
// The shared real logs, against c2_truth.py.

/// `c2_truth.py LOG ARGS`.
fn log_truth(path: &Path, args: &[&str]) -> Value {
    let name = path.display();
    let out = std::process::Command::new(python())
        .arg(peer_script("c2_truth.py"))
        .arg(path)
        .args(args)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "c2_truth.py {name}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).unwrap()
}

/// A failsafe asked of mavping, and the same asked of c2_truth.py.
struct Model {
    mavping: &'static str,
    truth: &'static str,
}

const DOWN_HEARTBEAT: [Model; 3] = [
    Model {
        mavping: "custom:message=heartbeat,timeout=1.5s,direction=down",
        truth: "direction=down,message=heartbeat,timeout=1.5",
    },
    Model {
        mavping: "custom:message=heartbeat,timeout=1s,direction=down",
        truth: "direction=down,message=heartbeat,timeout=1",
    },
    Model {
        mavping: "custom:message=heartbeat,timeout=3s,long-timeout=4s,direction=down",
        truth: "direction=down,message=heartbeat,timeout=3,long-timeout=4",
    },
];

/// The ground station's own HEARTBEATs, delivered while the link was up
/// (a log with none: 1 Hz from time 0).
const UP_HEARTBEAT: [Model; 2] = [
    Model {
        mavping: "ardupilot-plane",
        truth: "direction=up,message=heartbeat,timeout=1.5,long-timeout=5,rate=1",
    },
    Model {
        mavping: "custom:message=heartbeat,timeout=3s,direction=up",
        truth: "direction=up,message=heartbeat,timeout=3,rate=1",
    },
];

/// mavping's report of `name` with `--up-within up_within` and `models`,
/// and c2_truth.py's.
fn log_reports(name: &str, up_within: &str, models: &[&Model]) -> (Value, Value) {
    path_reports(&shared_tlog(name), up_within, models)
}

fn path_reports(path: &Path, up_within: &str, models: &[&Model]) -> (Value, Value) {
    let truths: Vec<&str> = models.iter().map(|m| m.truth).collect();
    reports_as(path, &["--up-within", up_within], models, &truths)
}

/// mavping's report with `models` asked for, and c2_truth.py's with
/// `truths` (none asked for: mavping plays the preset of the vehicle's
/// autopilot).
fn reports_as(path: &Path, rule: &[&str], models: &[&Model], truths: &[&str]) -> (Value, Value) {
    let name = path.display();
    let log = format!("tlog:{name}");
    // The rule's options (--up-within, --distance-band) are both's.
    let mut args = vec!["-q"];
    args.extend_from_slice(rule);
    let mut truth_args = rule.to_vec();
    for m in models {
        args.extend(["--failsafe", m.mavping]);
    }
    for t in truths {
        truth_args.extend(["--failsafe", *t]);
    }
    args.push(&log);
    let (code, report, err) = c2_run(&args);
    assert_eq!(code, 0, "{name}: {err}");
    (report, log_truth(path, &truth_args))
}

/// Seconds equal to the millisecond (MAVProxy's stamps lose their two low
/// bits in mavping's reading: microseconds apart).
fn assert_s(what: &str, got: f64, want: f64) {
    assert!(
        (got - want).abs() < 1e-3,
        "{what}: mavping {got} truth {want}"
    );
}

/// Every figure of the report the truth has, exactly (times to the ms).
fn assert_log_report(name: &str, r: &Value, t: &Value) {
    assert_s("duration_s", f(r, "duration_s"), f(t, "duration_s"));
    assert_eq!(u(r, "frames"), u(t, "frames"), "{name} frames");
    assert_s("down_s", f(r, "down_s"), f(t, "down_s"));
    let duration = f(t, "duration_s");
    let availability = f(r, "availability_pct");
    assert!(
        (availability - f(t, "availability_pct")).abs() < 0.1 / duration,
        "{name}: availability {availability} truth {}",
        t["availability_pct"]
    );
    let (ro, to) = (&r["outages"], &t["outages"]);
    assert_eq!(u(ro, "count"), u(to, "count"), "{name}: {ro}\n{to}");
    for (rb, tb) in list(ro, "bands").iter().zip(list(to, "bands")) {
        assert_eq!(rb["band"], tb["band"]);
        assert_eq!(u(rb, "count"), u(tb, "count"), "{name} {rb} {tb}");
        assert_s("band total_s", f(rb, "total_s"), f(tb, "total_s"));
    }
    // mavping lists the longest, longest first: each is the truth's
    // outage that began then, and they are the truth's longest.
    let mut all: Vec<&Value> = list(to, "list").iter().collect();
    all.sort_by(|a, b| f(b, "duration_s").total_cmp(&f(a, "duration_s")));
    let longest = list(ro, "longest");
    assert!(
        !longest.is_empty() || all.is_empty(),
        "{name}: none listed of {all:?}"
    );
    for (k, o) in longest.iter().enumerate() {
        assert_s("longest", f(o, "duration_s"), f(all[k], "duration_s"));
        let same = all
            .iter()
            .find(|a| (f(a, "start_s") - f(o, "start_s")).abs() < 1e-3)
            .unwrap_or_else(|| panic!("{name}: no outage of the truth at {o}"));
        assert_s("duration_s", f(o, "duration_s"), f(same, "duration_s"));
        assert_s("silence_s", f(o, "silence_s"), f(same, "silence_s"));
        assert_eq!(o["open"], same["open"], "{name} {o}");
        match (o["distance_m"].as_f64(), same["distance_m"].as_f64()) {
            (Some(a), Some(b)) => assert!((a - b).abs() < 0.01, "{name} {o} {same}"),
            (a, b) => assert_eq!(a, b, "{name} {o} {same}"),
        }
    }
    assert_distance_bands(name, r, t);
    assert_timeline(name, r, list(to, "list"), duration);
    assert_eq!(replays(r).len(), list(t, "failsafes").len(), "{name}");
    for (rf, tf) in replays(r).iter().zip(list(t, "failsafes")) {
        assert_replay(name, rf, tf);
    }
}

/// The report's timeline is the truth's outages cut into its bins: the
/// narrowest power of two seconds that 120 of cover the run.
fn assert_timeline(name: &str, r: &Value, outages: &[Value], duration: f64) {
    let mut width = 1.0;
    while width * 120.0 < duration {
        width *= 2.0;
    }
    let bins = (duration / width).ceil() as usize;
    let mut want = vec![0.0; bins];
    for o in outages {
        let (start, end) = (f(o, "start_s"), f(o, "start_s") + f(o, "duration_s"));
        for (k, bin) in want.iter_mut().enumerate() {
            let (from, to) = (k as f64 * width, (k + 1) as f64 * width);
            *bin += (end.min(to) - start.max(from)).max(0.0);
        }
    }
    let t = &r["timeline"];
    assert_eq!(f(t, "bin_s"), width, "{name}: {t}");
    let got = list(t, "down_s");
    assert_eq!(got.len(), bins, "{name}: {t}");
    for (k, (g, w)) in got.iter().zip(&want).enumerate() {
        assert!(
            (g.as_f64().unwrap() - w).abs() < 1e-3,
            "{name} bin {k}: {g} vs {w}"
        );
    }
}

fn assert_distance_bands(name: &str, r: &Value, t: &Value) {
    let (rd, td) = (list(r, "distance"), list(t, "distance"));
    assert_eq!(rd.len(), td.len(), "{name}: {rd:?}\n{td:?}");
    for (a, b) in rd.iter().zip(td) {
        assert_eq!(f(a, "from_m"), f(b, "from_m"), "{name} {a} {b}");
        assert_s("observed_s", f(a, "observed_s"), f(b, "observed_s"));
        assert_s("band down_s", f(a, "down_s"), f(b, "down_s"));
        assert_eq!(u(a, "outages"), u(b, "outages"), "{name} {a} {b}");
    }
}

/// One replay against the truth's direct simulation of the rule.
fn assert_replay(name: &str, r: &Value, t: &Value) {
    let what = format!("{name} {}:\n{r}\n{t}", r["setting"]);
    assert_eq!(r["direction"], t["direction"], "{what}");
    assert_eq!(r["basis"], t["basis"], "{what}");
    assert_eq!(r["inferred"], t["direction"] == "up", "{what}");
    assert_s("timeout_s", f(r, "timeout_s"), f(t, "timeout_s"));
    for key in ["messages", "delivered", "trips", "long_trips"] {
        assert_eq!(u(r, key), u(t, key), "{key}: {what}");
    }
    let listed = list(r, "trip_list");
    assert!(!listed.is_empty() || u(t, "trips") == 0, "{what}");
    for (a, b) in listed.iter().zip(list(t, "trip_list")) {
        assert_s("trip at_s", f(a, "at_s"), f(b, "at_s"));
        assert_s("trip lasted_s", f(a, "lasted_s"), f(b, "lasted_s"));
        assert_eq!((&a["open"], &a["long"]), (&b["open"], &b["long"]), "{what}");
    }
    for key in ["closest_wait_s", "closest_margin_s", "closest_at_s"] {
        match (r[key].as_f64(), t[key].as_f64()) {
            (Some(a), Some(b)) => assert_s(key, a, b),
            (a, b) => assert_eq!(a, b, "{key}: {what}"),
        }
    }
}

#[test]
fn vtol_outages_at_2s_and_1s_are_the_logs_silences_exactly() {
    let down: Vec<&Model> = DOWN_HEARTBEAT.iter().collect();
    let (r, t) = log_reports("vtol.tlog", "2s", &down);
    // The README's figures, by c2_truth.py's walk: ten pauses of 2 s or
    // more, the 4.2 s and 2.2 s silences among them.
    let silences: Vec<f64> = list(&t["outages"], "list")
        .iter()
        .map(|o| f(o, "silence_s"))
        .collect();
    assert_eq!(silences.len(), 10, "{silences:?}");
    assert!(
        silences.iter().any(|s| (4.2..4.3).contains(s)),
        "{silences:?}"
    );
    assert!(
        silences.iter().any(|s| (2.15..2.25).contains(s)),
        "{silences:?}"
    );
    assert_log_report("vtol 2s", &r, &t);
    // A rule of 1 s finds the batch pauses a little over it too. No
    // failsafe asked for: the ArduPlane's own (its HEARTBEAT says so).
    let plane = UP_HEARTBEAT[0].truth;
    let (r, t) = reports_as(
        &shared_tlog("vtol.tlog"),
        &["--up-within", "1s"],
        &[],
        &[plane],
    );
    assert_eq!(replays(&r)[0]["model"], "ardupilot-plane");
    assert!(u(&t["outages"], "count") > 100, "{}", t["outages"]);
    assert_log_report("vtol 1s", &r, &t);
}

#[test]
fn vtol_up_failsafes_play_the_link_at_1_hz_and_its_distance_bands_of_100_m() {
    // No ground station's frame in the log: the up models are played at
    // their rate against the downlink (inferred).
    let up: Vec<&Model> = UP_HEARTBEAT.iter().collect();
    let truths: Vec<&str> = up.iter().map(|m| m.truth).collect();
    // In bands of 100 m: the flight reaches about 250 m from home.
    let rule = ["--up-within", "2s", "--distance-band", "100"];
    let (r, t) = reports_as(&shared_tlog("vtol.tlog"), &rule, &up, &truths);
    assert!(list(&t, "failsafes")
        .iter()
        .all(|f| f["basis"] == "downlink"));
    assert!(list(&t, "distance").len() >= 3, "{t}");
    assert_log_report("vtol up", &r, &t);
}

#[test]
fn flight_logs_and_the_ardusub_gps_log_have_no_outage_at_2s() {
    let models: Vec<&Model> = DOWN_HEARTBEAT.iter().chain(&UP_HEARTBEAT).collect();
    for name in ["flight_logs.tlog", "qgc_ardusub_gps_2023-05-04.tlog"] {
        let (r, t) = log_reports(name, "2s", &models);
        // Their longest silences (1.0 s: the SITL's reboot; 0.351 s).
        assert!(f(&t, "longest_silence_s") < 1.1, "{name}: {t}");
        assert_eq!(u(&t["outages"], "count"), 0, "{name}");
        assert_eq!(f(&r, "availability_pct"), 100.0, "{name}");
        assert_log_report(name, &r, &t);
    }
}

#[test]
fn qgc_logs_outages_are_where_the_vehicle_was_not_heard() {
    let models: Vec<&Model> = DOWN_HEARTBEAT.iter().chain(&UP_HEARTBEAT).collect();
    // ArduSub: its longest silence between the vehicle's frames is 0.415
    // s, but its last 3.3 s hold only the ground station's frames (and a
    // DISTANCE_SENSOR whose CRC fails): an open outage at the end.
    let (r, t) = log_reports("qgc_ardusub_2023-04-18.tlog", "2s", &models);
    assert_s("longest silence", f(&t, "longest_silence_s"), 0.415);
    let o = list(&t["outages"], "list");
    assert!(o.len() == 1 && o[0]["open"] == true, "{o:?}");
    assert_log_report("qgc_ardusub", &r, &t);
    // PX4 on the bench: only the ground station's HEARTBEATs for its
    // first 15.7 s; its up failsafes lose the heartbeats sent then.
    let (r, t) = log_reports("qgc_px4_bench_2019-11-20.tlog", "2s", &models);
    assert!(f(&t, "first_vehicle_s") > 15.0, "{t}");
    assert_eq!(u(&t["outages"], "count"), 1);
    let up = &list(&t, "failsafes")[DOWN_HEARTBEAT.len()];
    assert!(u(up, "delivered") < u(up, "messages"), "{up}");
    assert_log_report("qgc_px4_bench", &r, &t);
}

/// A flight written by pymavlink (tlog_writer.py): ATTITUDE at 50 Hz and
/// a HEARTBEAT each second, the vehicle flying north at 20 m/s (a
/// position every tenth frame), silent for 150 frames after frame 500
/// (10 s, 200 m out), 250 after frame 1500 (30 s, 600 m) and 60 after frame
/// 2600 (1.22 s: under the rule); its SiK radio reporting each second all
/// along (not the vehicle: it must not fill the silences).
#[test]
fn a_written_flight_has_its_silences_as_outages_in_their_distance_bands() {
    let dir = Scratch::new("c2-flight");
    let path = dir.path("flight.tlog");
    let (rate, silences) = (50.0, [(500.0, 150.0), (1500.0, 250.0)]);
    write_log(
        &path,
        &json!({
            "start_us": 1_764_500_000_000_000u64,
            "sources": [
                {"sysid": 1, "compid": 1, "rate": 50, "frames": 3500,
                 "silence": [[500, 150], [1500, 250], [2600, 60]],
                 "position": {"every": 10, "lat0": 47.0, "lon0": 8.0, "alt0_m": 500.0,
                              "north_mps": 20.0, "climb_mps": 0.0, "message": "global"}},
                {"sysid": 51, "compid": 68, "rate": 1, "frames": 70, "phase_us": 500_000,
                 "radio": {"rxerrors0": 0, "rxerrors_step": 1}}
            ]
        }),
    );
    let models: Vec<&Model> = DOWN_HEARTBEAT.iter().chain(&UP_HEARTBEAT).collect();
    let (r, t) = path_reports(&path, "2s", &models);
    assert_log_report("flight", &r, &t);
    // By hand: frame n at n/50 s; a silence of k frames after frame n is a
    // gap of (k + 1)/50 s, an outage of that less 2 s from n/50 + 2 s, at
    // 20 m/s x n/50 s (the last position written, a little before).
    let longest = list(&r["outages"], "longest");
    assert_eq!(longest.len(), 2, "{longest:?}");
    let mut down = 0.0;
    for (n, k) in silences {
        let duration = (k + 1.0) / rate - 2.0;
        down += duration;
        let o = longest
            .iter()
            .find(|o| (f(o, "start_s") - (n / rate + 2.0)).abs() < 1e-6)
            .unwrap_or_else(|| panic!("no outage after frame {n}: {longest:?}"));
        assert!((f(o, "duration_s") - duration).abs() < 1e-6, "{o}");
        let d = f(o, "distance_m");
        assert!(d <= 20.0 * n / rate && d > 20.0 * (n / rate - 0.5), "{o}");
    }
    assert!((f(&r, "down_s") - down).abs() < 1e-6, "{r}");
    // 0-500 m holds the first outage, 500-1000 m the second, 1000-1500 m
    // none; the floor (99 %) is first missed from 0 m.
    let bands = list(&r, "distance");
    let downs: Vec<f64> = bands.iter().map(|b| f(b, "down_s")).collect();
    assert_eq!(bands.len(), 3, "{bands:?}");
    assert!((downs[0] - 151.0 / rate + 2.0).abs() < 1e-6, "{bands:?}");
    assert!((downs[1] - 251.0 / rate + 2.0).abs() < 1e-6, "{bands:?}");
    assert_eq!(downs[2], 0.0);
    assert_eq!(f(&r, "availability_under_floor_from_m"), 0.0);
}

// ---------------------------------------------------------------------
// sim: outages of known lengths.

/// A `sim:` link with `outage=START+LENGTH&outage_every=EVERY`, telemetry
/// at `rate` Hz and its HEARTBEAT at 1 Hz from time 0 (all silenced by the
/// outage, with the replies), a 1 ms delay each way.
struct SimOutages {
    start: f64,
    length: f64,
    every: f64,
    rate: f64,
    run: f64,
    extra: &'static str,
}

impl SimOutages {
    fn link(&self) -> String {
        format!(
            "sim:?clock=virtual&stream=ATTITUDE@{}&delay=1ms&jitter=0ms\
             &outage={}s+{}s&outage_every={}s&seed=5{}",
            self.rate, self.start, self.length, self.every, self.extra
        )
    }

    /// The outage windows that begin and end inside the run.
    fn windows(&self) -> Vec<f64> {
        let mut w = Vec::new();
        let mut s = self.start;
        while s + self.length < self.run {
            w.push(s);
            s += self.every;
        }
        // None still on at the end: that would be an open outage.
        assert!(s >= self.run, "a window across the end");
        w
    }

    /// How far a gap can be from the window's length: a telemetry
    /// interval, and the reply to a request sent just before the window
    /// (2 ms of delay).
    fn tol(&self) -> f64 {
        1.0 / self.rate + 0.005
    }

    fn run(&self, args: &[&str]) -> (i32, Value) {
        let w = format!("{}s", self.run);
        let link = self.link();
        let mut all = vec!["-i", "100ms", "-w", &w, "-q"];
        all.extend_from_slice(args);
        all.push(&link);
        let (code, report, err) = c2_run(&all);
        assert!(code == 0 || code == 1, "{err}");
        (code, report)
    }
}

/// Each window of the sim's outage is one outage of its length less the
/// rule, in its band, at its start plus the rule.
fn assert_sim_outages(sim: &SimOutages, report: &Value, up_within: f64) {
    let windows = sim.windows();
    let tol = sim.tol();
    let expected = sim.length - up_within;
    let o = &report["outages"];
    assert_eq!(u(o, "count"), windows.len() as u64, "{o}");
    let band = band_of(expected);
    // Away from the band's edges, so the band is the truth's.
    assert_eq!(band_of(expected - tol), band);
    assert_eq!(band_of(expected + tol), band);
    for b in list(o, "bands") {
        let n = if b["band"] == band { windows.len() } else { 0 };
        assert_eq!(u(b, "count"), n as u64, "{o}");
    }
    let n = windows.len() as f64;
    let down = f(report, "down_s");
    assert!(
        (down - n * expected).abs() <= n * tol,
        "{down} vs {n} x {expected}"
    );
    let duration = f(report, "duration_s");
    assert!((duration - sim.run).abs() < 0.5, "{duration}");
    let availability = f(report, "availability_pct");
    assert!(
        (availability - 100.0 * (1.0 - down / duration)).abs() < 1e-9,
        "{availability}"
    );
    for l in list(o, "longest") {
        let start = f(l, "start_s") - up_within;
        let w = windows
            .iter()
            .find(|w| (start - *w).abs() <= tol)
            .unwrap_or_else(|| panic!("{l} starts at no window of {windows:?}"));
        assert!((f(l, "duration_s") - expected).abs() <= tol, "{l} at {w}");
        assert_eq!(l["open"], false);
    }
}

#[test]
fn sim_outages_are_counted_in_their_band_at_any_rule() {
    // 4.5 s outages every 20 s for 100 s: 2.5 s each by a 2 s rule (1-3 s),
    // 4 s by 0.5 s (3-10 s); a failsafe of any of the vehicle's frames at
    // 1.5 s trips once in each, and one of its HEARTBEAT (1 Hz from time
    // 0, 1 ms on the way) as the rule simulated on those the outage let
    // through.
    let sim = SimOutages {
        start: 5.0,
        length: 4.5,
        every: 20.0,
        rate: 50.0,
        run: 100.0,
        extra: "",
    };
    let fs = "custom:message=any,timeout=1.5s,direction=down";
    let beat = "custom:message=heartbeat,timeout=1.5s,direction=down";
    for (rule, up_within) in [("2s", 2.0), ("500ms", 0.5)] {
        let (code, report) = sim.run(&["--up-within", rule, "--failsafe", fs, "--failsafe", beat]);
        assert_eq!(code, 0);
        assert_sim_outages(&sim, &report, up_within);
        let trips: Vec<Trip> = sim
            .windows()
            .iter()
            .map(|w| Trip {
                at: w + 1.5,
                lasted: sim.length - 1.5,
                open: false,
            })
            .collect();
        let replay = &replays(&report)[0];
        assert_eq!(replay["basis"], "received");
        assert_trips(replay, &trips, sim.tol());
        let end = f(&report, "duration_s");
        let windows = sim.windows();
        let beats: Vec<f64> = (0..=end as u32)
            .map(f64::from)
            .filter(|t| !windows.iter().any(|w| *t >= *w && *t < w + sim.length))
            .map(|t| t + 0.001)
            .filter(|t| *t <= end)
            .collect();
        let replay = &replays(&report)[1];
        assert_eq!(u(replay, "delivered"), beats.len() as u64, "{replay}");
        assert_trips(replay, &failsafe_trips(&beats, end, 1.5), 1e-6);
    }
}

#[test]
fn sim_loss_bursts_and_random_loss_leave_only_the_outages() {
    // Outages of 35 s (past 30 s by a 2 s rule: 33 s) and 20% of the
    // vehicle's frames lost at random besides: a gap of 2 s would take
    // 100 losses in a row, so only the outages count, a few frames wider.
    // The near radio's RADIO_STATUS (51/68) goes on through them, once a
    // second: not the vehicle.
    let sim = SimOutages {
        start: 10.0,
        length: 35.0,
        every: 60.0,
        rate: 50.0,
        run: 120.0,
        extra: "&loss_down=20%&radio=on",
    };
    let (code, report) = sim.run(&["--up-within", "2s"]);
    assert_eq!(code, 0);
    let wider = SimOutages {
        rate: sim.rate / 4.0,
        ..sim
    };
    assert_sim_outages(&wider, &report, 2.0);
}

/// The failsafe of the ground station's HEARTBEAT at 1 Hz on a probe run:
/// a message at t is delivered when the last probe sent at or before it
/// was answered. Probes every 100 ms; the outage windows [5.5, 9.5) s and
/// [25.5, 29.5) s lose those sent in them: the messages at 6 to 9 and 26 to
/// 29 are not delivered.
#[test]
fn sim_up_failsafe_replays_the_probes_outcomes() {
    let sim = SimOutages {
        start: 5.5,
        length: 4.0,
        every: 20.0,
        rate: 50.0,
        run: 40.0,
        extra: "",
    };
    let (code, report) = sim.run(&[
        "--failsafe",
        "custom:message=heartbeat,rate=1,timeout=1.5s,direction=up",
        "--failsafe",
        "custom:message=heartbeat,rate=1,timeout=5s,direction=up",
    ]);
    assert_eq!(code, 0);
    let windows = sim.windows();
    let end = f(&report, "duration_s");
    let messages: Vec<f64> = (0..=end.floor() as u32).map(f64::from).collect();
    let delivered: Vec<f64> = messages
        .iter()
        .copied()
        .filter(|t| {
            !windows
                .iter()
                .any(|w| *t >= *w && *t < w + sim.length + 0.1)
        })
        .collect();
    for (k, timeout) in [1.5, 5.0].into_iter().enumerate() {
        let r = &replays(&report)[k];
        assert_eq!(r["basis"], "probes", "{r}");
        assert_eq!(r["inferred"], true, "{r}");
        assert_eq!(u(r, "messages"), messages.len() as u64, "{r}");
        assert_eq!(u(r, "delivered"), delivered.len() as u64, "{r}");
        let trips = failsafe_trips(&delivered, end, timeout);
        assert_trips(r, &trips, 1e-6);
    }
}

/// A run of 10 s at a vehicle never heard (the sim's outage from its
/// start to past the run's end), with a down HEARTBEAT failsafe at 1.5 s
/// and an up one at 5 s: its report (the run exits 1: no reply at all).
fn never_heard() -> Value {
    let (code, r, err) = c2_run(&[
        "-i",
        "100ms",
        "-w",
        "10",
        "-q",
        "--up-within",
        "2s",
        "--failsafe",
        "custom:message=heartbeat,timeout=1.5s,direction=down",
        "--failsafe",
        "custom:message=heartbeat,rate=1,timeout=5s,direction=up",
        "sim:?clock=virtual&outage=0s+1h",
    ]);
    // No reply at all.
    assert_eq!(code, 1, "{err}");
    let end = f(&r, "duration_s");
    assert!((end - 10.0).abs() < 0.01, "{r}");
    r
}

/// Down from the rule's grace on, one open outage; no availability to
/// state; the vehicle's HEARTBEAT failsafe tripped at its timeout for good.
#[test]
fn a_vehicle_never_heard_is_down_from_the_grace_on() {
    let r = never_heard();
    let end = f(&r, "duration_s");
    assert_eq!(u(&r, "frames"), 0);
    assert!(r["availability_pct"].is_null(), "{r}");
    assert!((f(&r, "down_s") - (end - 2.0)).abs() < 1e-9, "{r}");
    let o = &r["outages"];
    assert_eq!(u(o, "count"), 1);
    let only = &list(o, "longest")[0];
    assert_eq!(
        (f(only, "start_s"), only["open"].clone()),
        (2.0, true.into())
    );
    let down = &replays(&r)[0];
    assert_eq!(u(down, "delivered"), 0);
    assert_trips(down, &failsafe_trips(&[], end, 1.5), 1e-9);
}

/// Every one of the 100 round trips failed: continuity is 0 of 100 (the
/// rule: answered within T over answered and unanswered), and the up
/// failsafe's messages, each delivered if the last probe sent at or
/// before it was answered, are none delivered: it trips at 5 s, the
/// probe at time 0 being lost with the first message.
#[test]
fn a_vehicle_never_heard_fails_every_round_trip_and_uplink_message() {
    let r = never_heard();
    let end = f(&r, "duration_s");
    let c = &r["continuity"];
    assert!(c.is_object(), "100 requests unanswered: {r}");
    assert_eq!((u(c, "within"), u(c, "transactions")), (0, 100), "{c}");
    let up = &replays(&r)[1];
    assert_eq!(up["basis"], "probes", "{up}");
    assert_eq!(u(up, "delivered"), 0, "{up}");
    assert_eq!(u(up, "messages"), end.floor() as u64 + 1, "{up}");
    assert_trips(up, &failsafe_trips(&[], end, 5.0), 1e-9);
}

#[test]
fn min_availability_gates_the_exit_code() {
    let sim = SimOutages {
        start: 5.0,
        length: 4.5,
        every: 20.0,
        rate: 50.0,
        run: 60.0,
        extra: "",
    };
    let (code, report) = sim.run(&["--up-within", "2s"]);
    assert_eq!(code, 0);
    let measured = f(&report, "availability_pct");
    assert!(measured < 99.0, "{measured}");
    let below = format!("{}", measured - 0.5);
    let above = format!("{}", measured + 0.5);
    let (code, _) = sim.run(&["--up-within", "2s", "--min-availability", &below]);
    assert_eq!(code, 0, "at least {below}");
    let (code, again) = sim.run(&["--up-within", "2s", "--min-availability", &above]);
    assert_eq!(code, 1, "at least {above}");
    // The virtual clock's run is the same run.
    assert!((f(&again, "availability_pct") - measured).abs() < 1e-6);
    // The distance bands are held to the floor asked for.
    let floor = f(&again["rule"], "availability_floor_pct");
    assert!((floor - (measured + 0.5)).abs() < 1e-9, "{floor}");
}

#[test]
fn min_continuity_gates_the_exit_code() {
    // Round trips in the outages are lost: continuity is the share
    // answered within --continuity-within (the reply timeout unless given).
    let sim = SimOutages {
        start: 5.0,
        length: 4.5,
        every: 20.0,
        rate: 50.0,
        run: 60.0,
        extra: "",
    };
    let (code, report) = sim.run(&[]);
    assert_eq!(code, 0);
    let c = &report["continuity"];
    let pct = f(c, "pct");
    assert_eq!(c["from"], "probes");
    // Of 600 probes (every 100 ms from 0), the 45 sent in each of the
    // three 4.5 s windows are lost; the others are answered in 2 ms.
    let windows = sim.windows().len() as u64;
    assert_eq!(
        (u(c, "within"), u(c, "transactions")),
        (600 - 45 * windows, 600),
        "{c}"
    );
    assert_eq!(pct, 100.0 * (600 - 45 * windows) as f64 / 600.0);
    // Within 1 ms none is; within 3 ms every answered one.
    for (within, n) in [("1ms", 0), ("3ms", 600 - 45 * windows)] {
        let (_, r) = sim.run(&["--continuity-within", within]);
        let c = &r["continuity"];
        assert_eq!(
            (u(c, "within"), u(c, "transactions")),
            (n, 600),
            "{within}: {c}"
        );
    }
    let (code, _) = sim.run(&["--min-continuity", &format!("{}", pct - 1.0)]);
    assert_eq!(code, 0);
    let (code, _) = sim.run(&["--min-continuity", &format!("{}", pct + 1.0)]);
    assert_eq!(code, 1);
}

// ---------------------------------------------------------------------
// A pymavlink vehicle behind a relay that cuts the link.

/// The relay's truth: when it forwarded each frame down (s after its
/// first frame), and the message ids.
fn forwarded(truth: &Value) -> Vec<(f64, u64)> {
    list(&truth["cut"], "forwarded_down")
        .iter()
        .map(|x| (x[0].as_f64().unwrap(), x[1].as_u64().unwrap()))
        .collect()
}

#[test]
fn a_vehicle_behind_a_cutting_relay_has_its_cuts_as_outages_and_trips() {
    // The vehicle streams ATTITUDE at 50 Hz and HEARTBEAT at 1 Hz for
    // longer than the run, and answers our PINGs; the relay cuts both ways
    // for 3.4 s at 3.05 s, 1.6 s at 10.05 s and 6.5 s at 15.05 s (between
    // our probes, sent every 100 ms from 0).
    let (mut vehicle, vport) = vehicle(1, &["--rate", "50", "--frames", "1500"]);
    let (relay, rport) = relay(&[vport], &["--cut", "3.05+3.4,10.05+1.6,15.05+6.5"]);
    let target = format!("udpout:127.0.0.1:{rport}");
    let (code, report, err) = c2_run(&[
        "-i",
        "100ms",
        "-w",
        "25",
        "-q",
        "--up-within",
        "1s",
        "--failsafe",
        "custom:message=heartbeat,timeout=1.5s,direction=down",
        "--failsafe",
        "custom:message=any,timeout=500ms,direction=down",
        "--failsafe",
        "custom:message=heartbeat,rate=1,timeout=1.5s,direction=up",
        &target,
    ]);
    assert_eq!(code, 0, "{err}");
    let truth = relay.finish();
    vehicle.kill();
    let end = f(&report, "duration_s");
    // What went down before the run ended (the relay's clock starts at
    // our first frame, a moment after the run's).
    let frames: Vec<(f64, u64)> = forwarded(&truth)
        .into_iter()
        .filter(|(t, _)| *t < end - 0.2)
        .collect();
    // 25 s at 50 Hz but 11.5 s of cuts.
    assert!(frames.len() > 500, "{truth}");
    let times: Vec<f64> = frames.iter().map(|x| x.0).collect();
    // Scheduling on a loaded machine: the relay stamps a frame when it
    // sends it, mavping when it reads it.
    let tol = 0.1;
    let expected = outages_of(&times, end, 1.0);
    assert_eq!(expected.len(), 3, "{expected:?}");
    let o = &report["outages"];
    assert_eq!(u(o, "count"), 3, "{o}");
    let mut longest = expected.clone();
    longest.sort_by(|a, b| b.1.total_cmp(&a.1));
    for (l, e) in list(o, "longest").iter().zip(&longest) {
        assert!((f(l, "start_s") - e.0).abs() <= tol, "{l} vs {e:?}");
        assert!((f(l, "duration_s") - e.1).abs() <= tol, "{l} vs {e:?}");
    }
    for b in list(o, "bands") {
        let n = expected
            .iter()
            .filter(|e| b["band"] == band_of(e.1))
            .count();
        assert_eq!(u(b, "count"), n as u64, "{o}\n{expected:?}");
    }
    let down: f64 = expected.iter().map(|e| e.1).sum();
    assert!((f(&report, "down_s") - down).abs() <= 3.0 * tol, "{report}");
    // The HEARTBEAT failsafe, simulated on the HEARTBEATs the relay let
    // through; its waits are about whole seconds, half a second from the
    // timeout.
    let beats: Vec<f64> = frames.iter().filter(|x| x.1 == 0).map(|x| x.0).collect();
    let beat_trips = failsafe_trips(&beats, end, 1.5);
    assert!(beat_trips.len() >= 3, "{beat_trips:?}");
    assert_trips(&replays(&report)[0], &beat_trips, tol);
    let any_trips = failsafe_trips(&times, end, 0.5);
    assert_eq!(any_trips.len(), 3, "{any_trips:?}");
    assert_trips(&replays(&report)[1], &any_trips, tol);
    let cut = &truth["cut"];
    assert!(
        u(cut, "dropped_down") > 0 && u(cut, "dropped_up") > 0,
        "{cut}"
    );
    assert_probed_uplink(&report, &truth, end);
}

/// Continuity and the up failsafe of the cutting relay's run, by what the
/// relay did to each of our probes: those it cut, and those it forwarded
/// with (or without) a reply forwarded back.
fn assert_probed_uplink(report: &Value, truth: &Value, end: f64) {
    let uplink = &list(truth, "up")[0];
    let answered: std::collections::BTreeSet<u64> = list(uplink, "requests")
        .iter()
        .filter(|r| r[2].as_u64().unwrap() > 0)
        .map(|r| r[0].as_u64().unwrap())
        .collect();
    let cut = list(&truth["cut"], "requests_cut").len() as u64;
    let sent = list(uplink, "requests").len() as u64 + cut;
    let c = &report["continuity"];
    assert_eq!(
        (u(c, "within"), u(c, "transactions")),
        (answered.len() as u64, sent),
        "{c}"
    );
    // Probe k (sequence k) is sent at k/10 s; the message at j s is
    // delivered if probe 10j was answered (no cut begins or ends within
    // a probe of a whole second, so probe 10j - 1 would say the same).
    let last = sent - 1;
    let messages: Vec<f64> = (0..=end.floor() as u64).map(|j| j as f64).collect();
    let delivered: Vec<f64> = messages
        .iter()
        .copied()
        .filter(|j| answered.contains(&(10 * *j as u64).min(last)))
        .collect();
    let up = &replays(report)[2];
    assert_eq!(up["basis"], "probes", "{up}");
    assert_eq!(u(up, "messages"), messages.len() as u64, "{up}");
    assert_eq!(u(up, "delivered"), delivered.len() as u64, "{up}");
    let trips = failsafe_trips(&delivered, end, 1.5);
    assert_eq!(trips.len(), 3, "{trips:?}");
    assert_trips(up, &trips, 1e-6);
}

/// How old the telemetry is, where no round trip was split: the report's
/// downlink delay is the run's own age of the vehicle's frames above their
/// quickest (vtol: QGroundControl's batches a second apart), written in the
/// summary beside it; none from a clock that runs at another rate than the
/// logger's (flight_logs, a sped-up SITL: its drift at the 500 ppm limit).
#[test]
fn a_logs_downlink_delay_is_its_vehicles_frame_age_unless_its_clock_runs_apart() {
    for (log, aged) in [("vtol.tlog", true), ("flight_logs.tlog", false)] {
        let path = crate::field_logs::shared_tlog(log);
        let (code, out, err) =
            run_mavping(&["--json", "-q", "--report", "c2", path.to_str().unwrap()]);
        assert_eq!(code, 0, "{err}");
        let lines = json_lines(&out);
        let report = lines.iter().find(|l| l["type"] == "c2_report").unwrap();
        let summary = lines.last().unwrap();
        let age = summary["age"]
            .as_array()
            .unwrap()
            .iter()
            .find(|a| a["source"] == serde_json::json!({"sysid": 1, "compid": 1}))
            .unwrap_or_else(|| panic!("{log}: no age of 1/1 in {summary}"));
        let latency = &report["latency"];
        if aged {
            assert_eq!(latency["downlink_from"], "frame_age", "{latency}");
            for k in ["p50_ms", "p99_ms", "max_ms"] {
                assert_eq!(latency["downlink"][k], age["headline"][k], "{log} {k}");
            }
        } else {
            let drift = age["headline"]["drift_ppm"].as_f64().unwrap();
            assert!(drift.abs() >= 499.5, "{log}: {drift}");
            assert!(latency["downlink"].is_null(), "{log}: {latency}");
        }
    }
}
