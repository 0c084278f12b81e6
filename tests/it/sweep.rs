//! `--sweep` and `--load`: the knee measured on links whose capacity is
//! known from their parameters (simulated radios, a pty relay that paces
//! bytes at a baud rate), bufferbloat where the buffer is deep, the load's
//! effect on the RTT, Ctrl-C, the plot, and the JSON against the schema.

use std::io::{BufRead, BufReader};
use std::process::Stdio;
use std::time::{Duration, Instant};

use serde_json::Value;

use crate::common::*;

/// A sweep on `link` (`--json -q` and `args`): every event checked against
/// the schema; the summary's `sweep`.
fn sweep(link: &str, args: &[&str]) -> Value {
    let mut all = vec!["--sweep", "--json"];
    all.extend_from_slice(args);
    all.push(link);
    let (code, out, err) = run_mavping(&all);
    assert_eq!(code, 0, "{link}\n{out}\n{err}");
    let summary = checked_summary(&out);
    summary["sweep"].clone()
}

fn f(v: &Value, key: &str) -> f64 {
    v[key]
        .as_f64()
        .unwrap_or_else(|| panic!("{key} missing in {v}"))
}

/// The knee, within ±15 % of `capacity`, on a simulated radio.
fn assert_knee(link: &str, capacity: f64) -> Value {
    // Steps of 2 s: enough for a queue past the capacity to show, and
    // less work than the default 5 s.
    let s = sweep(
        &format!("sim:?{link}&clock=virtual&radio=on"),
        &["-q", "--step", "2s"],
    );
    let knee = f(&s["knee"], "rate_hz");
    assert!(
        (knee - capacity).abs() <= 0.15 * capacity,
        "{link}: knee {knee}/s, capacity {capacity:.1}/s\n{s:#}"
    );
    // The step above it failed: the knee is an edge, not the top tried.
    let above = f(&s["knee"], "failed_above_hz");
    assert!(above > knee && above <= 1.3 * capacity, "{s:#}");
    // Its bytes per second are what it carried both ways (a request of
    // 22 B out, a reply of 26 B in, and our and the responder's heartbeats).
    let bytes = f(&s["knee"], "bytes_per_s");
    assert!(
        (bytes / (knee * 48.0) - 1.0).abs() < 0.1,
        "{link}: {bytes} B/s at {knee}/s"
    );
    s
}

#[test]
fn the_knee_of_simulated_radios_is_their_capacity_from_the_parameters() {
    // Each radio sends in its half of every TDM round, so the reply
    // direction carries air / 8 / 2 bytes a second and a PING exchange
    // ends there: 26 bytes a reply.
    // 64 kbit/s: 4000 B/s each way, 153.8 replies/s (the 57600 baud UART
    // would carry 5760 / 26 = 221/s).
    let s = assert_knee("baud=57600&air=64k", 4000.0 / 26.0);
    // The baud rate alone says otherwise: a sweep measures what it cannot.
    assert!((f(&s, "baud_capacity_hz") - 115.2).abs() < 0.1, "{s:#}");
    // 128 kbit/s behind 115200 baud: 8000 B/s each way, 307.7/s.
    assert_knee("baud=115200&air=128k", 8000.0 / 26.0);
    // A small buffer (200 B, under 8 replies) drops where a deep one
    // queues: the same capacity, and no bufferbloat.
    let small = assert_knee("baud=57600&air=64k&buffer=200", 4000.0 / 26.0);
    assert_eq!(small["queueing"]["bufferbloat"], false, "{small:#}");
    // ECC: two bytes on the air for each: 2000 B/s each way, 76.9/s.
    assert_knee("baud=57600&air=64k&ecc=on", 2000.0 / 26.0);
    // No air rate: one half-duplex wire at the baud rate, request and
    // reply sharing it: 5760 / (22 + 26) = 120/s.
    assert_knee("baud=57600", 5760.0 / 48.0);
}

#[test]
fn a_deep_buffer_is_reported_as_bufferbloat() {
    // 16 KiB at 4000 B/s is four seconds of queue before the first drop.
    let s = assert_knee("baud=57600&air=64k&buffer=16384", 4000.0 / 26.0);
    let q = &s["queueing"];
    assert_eq!(q["bufferbloat"], true, "{s:#}");
    // A step beyond the knee lost under 1 % with a p99 many times the
    // first step's: the queue, not loss, took the excess.
    let worst = f(q, "worst_p99_us");
    assert!(worst > 5.0 * f(q, "reference_p99_us"), "{q}");
    let at = f(q, "worst_at_hz");
    let step = s["steps"]
        .as_array()
        .unwrap()
        .iter()
        .find(|st| f(st, "offered_hz") == at)
        .unwrap();
    assert!(f(step, "loss_ratio") < 0.01, "{step}");
    assert_eq!(step["passed"], false);
    // The same link with a small buffer drops instead.
    let shallow = assert_knee("baud=57600&air=64k&buffer=200", 4000.0 / 26.0);
    assert!(shallow["queueing"]["lost_at_hz"].is_number(), "{shallow:#}");
}

#[test]
fn each_step_is_reported_and_the_ramp_stops_past_the_loss_limit() {
    let (code, out, err) = run_mavping(&[
        "--sweep",
        "--json",
        "--step",
        "2s",
        "--sweep-loss",
        "10%",
        "sim:?baud=57600&clock=virtual",
    ]);
    assert_eq!(code, 0, "{out}\n{err}");
    let events = json_lines(&out);
    assert_schema(&events);
    let start = &events[0];
    assert_eq!(start["sweep"]["kind"], "sweep");
    // The default top: twice what 57600 baud carries.
    assert_eq!(start["sweep"]["max_from"]["from"], "baud");
    assert_eq!(f(&start["sweep"], "max_hz"), 230.0);
    assert_eq!(f(&start["sweep"], "loss_limit"), 0.1);
    let steps: Vec<&Value> = events.iter().filter(|e| e["type"] == "step").collect();
    // The schema is not vacuous: a step without its rate, or a summary
    // whose sweep has an unknown ending, is rejected.
    let validator = schema();
    let mut bad = steps[0].clone();
    bad.as_object_mut().unwrap().remove("offered_hz");
    assert!(!validator.is_valid(&bad), "{bad}");
    let summary = events.last().unwrap();
    let mut bad = summary.clone();
    bad["sweep"]["ending"] = "tired".into();
    assert!(!validator.is_valid(&bad));
    let all = summary["sweep"]["steps"].as_array().unwrap();
    // A step event for each step of the summary, in order, the same figures.
    assert_eq!(steps.len(), all.len());
    for (event, step) in steps.iter().zip(all) {
        assert_eq!(event["index"], step["index"]);
        assert_eq!(event["received"], step["received"]);
        assert_eq!(event["rtt_us"], step["rtt_us"]);
    }
    // The ramp climbed 2, 5, 10, ... and stopped at the first step past
    // 10 % loss; the refining steps are below it.
    let ramp: Vec<f64> = all
        .iter()
        .filter(|s| s["phase"] == "ramp")
        .map(|s| f(s, "offered_hz"))
        .collect();
    assert_eq!(&ramp[..4], [2.0, 5.0, 10.0, 20.0]);
    let last = all.iter().rfind(|s| s["phase"] == "ramp").unwrap();
    assert!(f(last, "loss_ratio") > 0.1, "{last}");
    let before: Vec<&Value> = all
        .iter()
        .filter(|s| s["phase"] == "ramp" && s["index"] != last["index"])
        .collect();
    assert!(before.iter().all(|s| f(s, "loss_ratio") <= 0.1));
    assert_eq!(summary["sweep"]["ending"], "loss_limit");
    // Counts add up: every request of every step is received or lost,
    // and the run's totals are the steps' sums.
    let sum = |key: &str| all.iter().map(|s| n(s, key)).sum::<u64>();
    for s in all {
        assert_eq!(n(s, "requests"), n(s, "received") + n(s, "lost"), "{s}");
    }
    assert_eq!(sum("requests"), n(summary, "requests"));
    let r = responder(summary, "1/1");
    assert_eq!(sum("received"), n(r, "received"));
    assert_eq!(sum("lost"), n(r, "lost"));
}

#[test]
fn the_text_says_what_will_be_sent_then_a_row_per_step_and_the_knee() {
    let (code, out, err) = run_mavping(&[
        "--sweep",
        "--step",
        "1s",
        "sim:?baud=57600&air=64k&clock=virtual&radio=on",
    ]);
    assert_eq!(code, 0, "{out}\n{err}");
    let first = out.lines().next().unwrap();
    assert!(
        first.contains("PING sweep from 2/s up to 230/s (twice the ~115/s that 57600 baud carries; --sweep-max to change), 1s a step, stopping past 20% loss"),
        "{first}"
    );
    let (live, _) = out.split_once("mavping statistics ---").unwrap();
    let rows: Vec<&str> = live
        .lines()
        .filter(|l| {
            l.trim_start()
                .split(' ')
                .next()
                .is_some_and(|w| w.parse::<u32>().is_ok())
        })
        .collect();
    assert!(rows.len() >= 9, "{out}");
    // Per-reply lines give way to the rows; each row has the radio's
    // figures from RADIO_STATUS.
    assert!(!out.contains("reply from"), "{out}");
    assert!(
        rows.iter().all(|r| r.contains("radio 51/68 txbuf min")),
        "{out}"
    );
    let knee = out.lines().find(|l| l.starts_with("knee: ")).expect(&out);
    assert!(
        knee.contains(" PINGs/s (")
            && knee.ends_with("; the baud rate alone says ~115/s (57600 baud)"),
        "{knee}"
    );
    assert!(out.contains("\nqueueing: "), "{out}");
    // Quiet: no rows as it goes, the table in the summary.
    let (_, quiet, _) = run_mavping(&[
        "--sweep",
        "-q",
        "--step",
        "1s",
        "sim:?baud=57600&air=64k&clock=virtual&radio=on",
    ]);
    let header = out.lines().find(|l| l.starts_with("step ")).unwrap();
    let (before, after) = quiet.split_once("mavping statistics ---").unwrap();
    assert!(!before.contains(header), "{quiet}");
    assert!(after.contains(header), "{quiet}");
    assert_eq!(
        after.lines().filter(|l| rows.contains(l)).count(),
        rows.len(),
        "{quiet}"
    );
}

#[test]
fn load_raises_the_p99_of_a_57600_baud_radio_and_the_report_says_by_how_much() {
    let link = "sim:?baud=57600&air=64k&clock=virtual";
    let (code, out, err) = run_mavping(&["--load", "ATTITUDE@50", "--json", link]);
    assert_eq!(code, 0, "{out}\n{err}");
    let events = json_lines(&out);
    assert_schema(&events);
    let summary = events.last().unwrap();
    let s = &summary["sweep"];
    let steps = s["steps"].as_array().unwrap();
    assert_eq!(steps.len(), 2, "{s:#}");
    assert_eq!(
        (&steps[0]["phase"], &steps[0]["load"]),
        (&"baseline".into(), &false.into())
    );
    assert_eq!(
        (&steps[1]["phase"], &steps[1]["load"]),
        (&"loaded".into(), &true.into())
    );
    let e = &s["load_effect"];
    let (unloaded, loaded) = (f(e, "unloaded_p99_us"), f(e, "loaded_p99_us"));
    // 40-byte ATTITUDE frames at 50/s take half the ground radio's share of
    // the air: requests wait behind them.
    assert!(loaded > unloaded + 5_000.0, "{e}");
    assert_eq!(f(e, "p99_rise_us"), loaded - unloaded);
    // The load was sent while the loaded step ran (5 s at 50/s), counted,
    // and went out: the loaded step's bytes per second include it.
    let l = &s["load"][0];
    assert_eq!(l["message"], "ATTITUDE");
    assert_eq!(n(l, "frame_bytes"), 40);
    assert!((245..=255).contains(&n(l, "frames")), "{l}");
    assert_eq!(n(l, "bytes"), 40 * n(l, "frames"));
    assert!(f(&steps[1], "tx_bytes_per_s") > f(&steps[0], "tx_bytes_per_s") + 1800.0);
    // Responders ignored it: every request answered, nothing stale.
    let r = responder(summary, "1/1");
    assert_eq!(n(r, "received"), n(summary, "requests"));
    assert_eq!((n(r, "stale"), n(summary, "foreign_replies")), (0, 0));

    // The text says it in a line.
    let (_, text, _) = run_mavping(&["--load", "ATTITUDE@50", "-q", link]);
    let line = text
        .lines()
        .find(|l| l.starts_with("under load: "))
        .expect(&text);
    let expected = format!(
        "under load: PING p99 at 10/s rose from {:.3} ms to {:.3} ms: +{:.3} ms",
        unloaded / 1e3,
        loaded / 1e3,
        (loaded - unloaded) / 1e3
    );
    assert!(line.starts_with(&expected), "{line}\n{expected}");
    assert!(text.contains("load ATTITUDE@50: "), "{text}");
}

#[test]
fn load_frames_reach_a_real_responder_which_ignores_them() {
    // pymavlink answers PINGs only; the load goes to it over UDP beside
    // them and is answered by nothing.
    let port = free_udp_port();
    let peer = Peer::start(
        "responder.py",
        &[&format!("udpin:127.0.0.1:{port}"), "--heartbeat-hz", "1"],
    );
    let (code, out, err) = run_mavping(&[
        "--load",
        "ATTITUDE@50",
        "--load",
        "GLOBAL_POSITION_INT@10",
        "--load",
        "BYTES@2340",
        "--step",
        "1s",
        "--rate",
        "20",
        "--json",
        "-q",
        &format!("udpout:127.0.0.1:{port}"),
    ]);
    assert_eq!(code, 0, "{out}\n{err}");
    let truth = peer.finish();
    let summary = checked_summary(&out);
    let load = summary["sweep"]["load"].as_array().unwrap();
    let frames = |i: usize| n(&load[i], "frames");
    // One loaded second: 50, 10 and 20 frames (2340 B/s of 117-byte
    // filler frames), each give or take one.
    for (i, want) in [(0, 50), (1, 10), (2, 20)] {
        assert!(frames(i).abs_diff(want) <= 1, "{load:?}");
    }
    assert_eq!(n(&load[2], "bytes"), 117 * frames(2));
    assert_eq!(n(&load[2], "frame_bytes"), 117);
    // The responder saw exactly our PINGs as requests and answered each.
    assert_eq!(truth["ping_requests"], summary["requests"], "{truth}");
    let r = responder(&summary, "1/1");
    assert_eq!(n(r, "received"), n(&summary, "requests"));
    assert_eq!(n(r, "stale"), 0);
}

#[test]
fn a_sweep_through_a_paced_pty_finds_the_paced_rate() {
    // The relay carries 19200 baud both ways on one channel: 1920 B/s
    // over a 22-byte request and a 26-byte reply is 40 PINGs/s. Its
    // 384-byte buffer holds about eight exchanges (200 ms): enough for the
    // relay's own scheduling hiccups on a busy machine, and past the
    // capacity it queues and drops within a step. The far end is `mavping
    // respond`, which answers in microseconds even on a loaded machine: the
    // relay, not the responder, must be the link's limit (pymavlink's
    // answers to PING over a pty are in `serial_pty.rs`).
    let mut relay = Peer::start(
        "paced_relay.py",
        &["--baud", "19200", "--latency-ms", "20", "--buffer", "384"],
    );
    let line = relay.read_line();
    let (a, b) = line.split_once(' ').expect("two pty paths");
    let peer = Respond::start(&[&format!("serial:{b}:19200")]);
    let (code, out, err) = run_mavping(&[
        "--sweep",
        "--json",
        "-q",
        "--rate",
        "20",
        "--step",
        "1s",
        "-W",
        "1s",
        &format!("serial:{a}:19200"),
    ]);
    drop(peer);
    assert_eq!(code, 0, "{out}\n{err}");
    let s = &checked_summary(&out)["sweep"];
    let knee = f(&s["knee"], "rate_hz");
    let capacity = 1920.0 / 48.0;
    assert!(
        (knee - capacity).abs() <= 0.15 * capacity,
        "knee {knee}/s on a link carrying {capacity}/s\n{s:#}"
    );
    let truth = relay.finish();
    // The relay dropped what its buffer could not hold: the steps above
    // the knee lost for real.
    assert!(
        truth["dropped_a_to_b"].as_u64().unwrap() + truth["dropped_b_to_a"].as_u64().unwrap() > 0,
        "{truth}"
    );
}

/// A run that ends inside a step (here its deadline) tells that step as
/// a `step` event too, marked cut short: a script that follows the events
/// sees every step the summary lists.
#[test]
fn the_step_a_deadline_cuts_short_is_told_as_an_event() {
    let (code, out, err) = run_mavping(&[
        "--sweep",
        "--json",
        "--step",
        "2s",
        "-w",
        "5",
        "sim:?baud=57600&clock=virtual",
    ]);
    assert_eq!(code, 0, "{out}\n{err}");
    let events = json_lines(&out);
    assert_schema(&events);
    let steps: Vec<&Value> = events.iter().filter(|e| e["type"] == "step").collect();
    let summary = events.last().unwrap();
    let all = summary["sweep"]["steps"].as_array().unwrap();
    assert_eq!(summary["sweep"]["ending"], "deadline", "{summary}");
    assert_eq!(steps.len(), 3, "two whole steps and the one cut at 5 s");
    assert_eq!(steps.len(), all.len());
    for (event, step) in steps.iter().zip(all) {
        assert_eq!(event["index"], step["index"]);
        assert_eq!(event["requests"], step["requests"]);
        assert_eq!(event["complete"], step["complete"]);
    }
    assert_eq!(steps[2]["complete"], false, "{}", steps[2]);
    assert_eq!(steps[1]["complete"], true, "{}", steps[1]);
}

#[test]
fn ctrl_c_stops_a_sweep_at_once_with_the_steps_so_far() {
    // Real time: a step a second, up to 230/s; stopped during the third.
    let mut child = mavping()
        .args(["--sweep", "--step", "1s", "sim:?baud=57600&air=64k"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut stdout = BufReader::new(child.stdout.take().unwrap());
    let mut seen = String::new();
    let mut rows = 0;
    while rows < 2 {
        let mut line = String::new();
        assert!(stdout.read_line(&mut line).unwrap() > 0, "{seen}");
        rows += usize::from(line.trim_start().starts_with(|c: char| c.is_ascii_digit()));
        seen.push_str(&line);
    }
    let stopped = Instant::now();
    signal(child.id(), "INT");
    let mut rest = String::new();
    std::io::Read::read_to_string(&mut stdout, &mut rest).unwrap();
    let code = child.wait().unwrap().code();
    // At once: not after the many steps left to run.
    assert!(stopped.elapsed() < Duration::from_secs(3), "{rest}");
    assert_eq!(code, Some(0), "{seen}{rest}");
    assert!(rest.contains("sweep: 3 steps, interrupted"), "{seen}{rest}");
    assert!(rest.contains("\nknee: 5 PINGs/s"), "{seen}{rest}");
    // The step cut short is shown as a row like the others as the run
    // ends, never judged, and the summary does not repeat a row.
    let (rows, summary) = rest.split_once("mavping statistics ---").unwrap();
    let cut: Vec<&str> = rows
        .lines()
        .filter(|l| l.trim_start().starts_with("3 "))
        .collect();
    assert_eq!(cut.len(), 1, "{rows}");
    assert!(cut[0].ends_with("cut short"), "{rows}");
    assert!(
        !summary.lines().any(|l| l.trim_start().starts_with("3 ")),
        "{summary}"
    );
}

#[test]
fn the_plot_of_a_sweep_draws_rtt_and_loss_against_the_offered_rate() {
    let dir = std::env::temp_dir().join(format!("mavping-sweep-plot-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("sweep.svg");
    let (code, out, err) = run_mavping(&[
        "--sweep",
        "--json",
        "-q",
        "--plot",
        path.to_str().unwrap(),
        "sim:?baud=57600&air=64k&buffer=16384&clock=virtual",
    ]);
    assert_eq!(code, 0, "{out}\n{err}");
    let svg = std::fs::read_to_string(&path).unwrap();
    std::fs::remove_dir_all(&dir).unwrap();
    let s = &checked_summary(&out)["sweep"];
    let knee = f(&s["knee"], "rate_hz");
    let grade = s["queueing"]["grade"].as_str().unwrap();
    let bloat = if s["queueing"]["bufferbloat"] == true {
        ", bufferbloat"
    } else {
        ""
    };
    let queueing = format!("\n{grade}{bloat}\n");
    for text in [
        "mavping sweep sim:",
        "RTT against offered rate",
        "loss against offered rate",
        "offered rate (requests/s, log scale)",
        &format!("knee {knee:.0}/s"),
        &format!("\n{knee:.1}\n"),
        &queueing,
        "queueing",
    ] {
        assert!(svg.contains(text), "{text:?} is not in the plot");
    }
    // A p99 line, a p50 line and a loss line, each with a marker per step.
    let steps = s["steps"].as_array().unwrap().len();
    assert!(svg.matches("<polyline").count() >= 3, "{svg}");
    let png = Rendered::of(&svg, "sweep");
    assert!(png.colours.len() > 30, "{}", png.path.display());
    assert!(steps >= 8, "{s:#}");
    assert!(
        png.count(0x0072B2) > 200,
        "little blue in {}",
        png.path.display()
    );
    assert!(
        png.dark_in_rows(0..40) > 300,
        "no title in {}",
        png.path.display()
    );
}

/// A network namespace of its own whose loopback is a token bucket at
/// 57600 bit/s (`tc qdisc ... tbf`): one queue that both directions share,
/// `limit` bytes deep, like a radio's buffer in front of its air time. The
/// kernel does the pacing, so the knee is measured against a real queue.
struct Bucket {
    name: String,
}

/// 57600 bit/s.
const BUCKET_BYTES_PER_S: f64 = 7200.0;

impl Bucket {
    /// None (and a line saying why) where the namespace or the qdisc
    /// cannot be made: not root, no `ip`, a kernel without tbf.
    fn new(tag: &str, queue: Duration) -> Option<Bucket> {
        let name = format!("mavping-{tag}-{}", std::process::id());
        let ip = |args: &[&str]| {
            std::process::Command::new("ip")
                .args(args)
                .output()
                .map_err(|e| e.to_string())
                .and_then(|o| {
                    o.status
                        .success()
                        .then_some(())
                        .ok_or_else(|| String::from_utf8_lossy(&o.stderr).trim().to_string())
                })
        };
        if let Err(e) = ip(&["netns", "add", &name]) {
            eprintln!("skipped: no network namespace for the token bucket (ip netns add: {e})");
            return None;
        }
        let bucket = Bucket { name };
        let limit = (BUCKET_BYTES_PER_S * queue.as_secs_f64())
            .round()
            .to_string();
        ip(&["-n", &bucket.name, "link", "set", "lo", "up"]).unwrap();
        // A bucket of 200 bytes holds any one frame here (68 at most)
        // and lets no burst past the rate; the queue behind it is `limit`.
        let tbf = [
            "-n",
            &bucket.name,
            "qdisc",
            "add",
            "dev",
            "lo",
            "root",
            "tbf",
            "rate",
            "57600bit",
            "burst",
            "200",
            "limit",
            &limit,
        ];
        let tc = std::process::Command::new("tc").args(tbf).output();
        match tc {
            Ok(o) if o.status.success() => Some(bucket),
            Ok(o) => {
                eprintln!(
                    "skipped: this kernel has no token bucket qdisc (tc qdisc add ... tbf: {})",
                    String::from_utf8_lossy(&o.stderr).trim()
                );
                None
            }
            Err(e) => {
                eprintln!("skipped: no tc to make a token bucket ({e})");
                None
            }
        }
    }

    /// `mavping ARGS` inside the namespace.
    fn mavping(&self) -> std::process::Command {
        let mut c = std::process::Command::new("ip");
        c.args(["netns", "exec", &self.name, env!("CARGO_BIN_EXE_mavping")]);
        c
    }
}

impl Drop for Bucket {
    fn drop(&mut self) {
        let _ = std::process::Command::new("ip")
            .args(["netns", "del", &self.name])
            .status();
    }
}

/// A child process spinning on a core, as another program keeps it busy.
struct BusyLoop(std::process::Child);

impl BusyLoop {
    fn start() -> BusyLoop {
        BusyLoop(
            std::process::Command::new("sh")
                .args(["-c", "while :; do :; done"])
                .spawn()
                .unwrap(),
        )
    }
}

impl Drop for BusyLoop {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

/// A sweep through a token bucket with a `queue` deep queue, beside a
/// busy core, `mavping respond` the far end in the same namespace: the
/// summary's `sweep` (every event checked against the schema).
fn bucket_sweep(tag: &str, queue: Duration) -> Option<Value> {
    let bucket = Bucket::new(tag, queue)?;
    let port = 14_550;
    let mut respond = bucket
        .mavping()
        .args(["respond", &format!("udpin:127.0.0.1:{port}")])
        .stdout(Stdio::piped())
        .stderr(Stdio::inherit())
        .spawn()
        .unwrap();
    let mut ready = String::new();
    BufReader::new(respond.stdout.take().unwrap())
        .read_line(&mut ready)
        .unwrap();
    assert!(ready.starts_with("mavping respond: "), "{ready:?}");
    let busy = BusyLoop::start();
    // Steps of a second from 5/s: a queue past the capacity grows by a
    // tenth of a second per second at a tenth over it.
    let run = bucket
        .mavping()
        .args(["--sweep", "--json", "-q", "--rate", "5", "--step", "1s"])
        .args(["-W", "3s", &format!("udpout:127.0.0.1:{port}")])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let (code, out, err) = wait_output(run, Duration::from_secs(60));
    drop(busy);
    let _ = respond.kill();
    let _ = respond.wait();
    assert_eq!(code, 0, "{out}\n{err}");
    Some(checked_summary(&out)["sweep"].clone())
}

/// The knee through a kernel token bucket beside a busy core is the
/// bucket's capacity (80-110 %: a scheduling hiccup of a few ms is not a
/// queue), and the queueing grade tells a 30 ms queue (B or better, no
/// bufferbloat) from a 2 s one (bufferbloat, D or F).
#[test]
fn the_knee_of_a_kernel_token_bucket_holds_beside_a_busy_core() {
    // On the loopback each frame carries 42 bytes of Ethernet, IP and UDP
    // headers: a 22-byte request and a 26-byte reply are 132 bytes of the
    // 7200 a second: 54.5 PINGs/s (our and the responder's heartbeats take
    // 2 % of it).
    let capacity = BUCKET_BYTES_PER_S / (22.0 + 26.0 + 2.0 * 42.0);
    for (tag, queue) in [
        ("q30ms", Duration::from_millis(30)),
        ("q2s", Duration::from_secs(2)),
    ] {
        let Some(s) = bucket_sweep(tag, queue) else {
            return;
        };
        let knee = f(&s["knee"], "rate_hz");
        assert!(
            (0.8 * capacity..=1.1 * capacity).contains(&knee),
            "{tag}: knee {knee}/s, capacity {capacity:.1}/s\n{s:#}"
        );
        let q = &s["queueing"];
        let grade = q["grade"].as_str().unwrap();
        eprintln!("{tag}: knee {knee}/s of {capacity:.1}/s; queueing {q}");
        if queue < Duration::from_millis(100) {
            assert!(["A+", "A", "B"].contains(&grade), "{tag}: {q}");
            assert_eq!(q["bufferbloat"], false, "{tag}: {q}");
        } else {
            assert!(["D", "F"].contains(&grade), "{tag}: {q}");
            assert_eq!(q["bufferbloat"], true, "{tag}: {q}");
        }
    }
}

/// A TIMESYNC sweep is sized and named by its own frames: a 28-byte
/// request (to 0/0, so its targets are trimmed) and a 30-byte reply share
/// the 5760 bytes a second of 57600 baud: 99.3 TIMESYNCs/s, where PING's
/// smaller frames make 120.
#[test]
fn a_timesync_sweep_counts_timesync_frames_and_says_timesyncs() {
    let link = "sim:?baud=57600&clock=virtual";
    let capacity = 5760.0 / (28.0 + 30.0);
    let s = sweep(link, &["-q", "--step", "2s", "--probe", "timesync"]);
    assert!((f(&s, "baud_capacity_hz") - capacity).abs() < 0.01, "{s:#}");
    let knee = f(&s["knee"], "rate_hz");
    assert!(
        (knee - capacity).abs() <= 0.15 * capacity,
        "knee {knee}/s, capacity {capacity:.1}/s\n{s:#}"
    );
    let (code, text, err) = run_mavping(&["--sweep", "--step", "2s", "--probe", "timesync", link]);
    assert_eq!(code, 0, "{text}\n{err}");
    let first = text.lines().next().unwrap();
    assert!(
        first.contains(
            "TIMESYNC sweep from 2/s up to 199/s (twice the ~99/s that 57600 baud carries"
        ),
        "{first}"
    );
    let line = |start: &str| {
        text.lines()
            .find(|l| l.starts_with(start))
            .unwrap_or_else(|| panic!("no {start:?} in {text}"))
            .to_string()
    };
    let knee_line = line("knee: ");
    assert!(
        knee_line.starts_with(&format!("knee: {knee:.0} TIMESYNCs/s ("))
            && knee_line.ends_with("; the baud rate alone says ~99/s (57600 baud)"),
        "{knee_line}"
    );
    let wire = line("wire: ");
    assert!(
        wire.starts_with("wire: 57600 baud carries ~99 TIMESYNCs/s; ")
            && wire.contains("(request 28 B + reply 30 B)"),
        "{wire}"
    );
    assert!(!text.contains("PINGs/s"), "{text}");
}
