//! `mavping respond` serving the transfers a ground station makes at
//! connect, to MAVProxy itself: `param fetch` (through `--drop` too: it
//! re-requests what was lost), `ftp get` of /mavping.bin byte for byte,
//! `wp list`; and what MAVProxy cannot ask (a read by name, an item past
//! the end, a second FTP session) from a pymavlink client. Each count
//! is held against what the other end saw: MAVProxy's telemetry log
//! holds every frame it sent and received.

use std::collections::HashMap;
use std::io::{BufRead, BufReader, Write};
use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::sync::mpsc;
use std::time::Duration;

use crate::common::*;
use crate::tlog::Scratch;

/// Long enough for any of these transfers on a loaded machine: a guard
/// against a hang, not a measurement.
const PATIENCE: Duration = Duration::from_secs(120);

/// MAVProxy with its console on pipes, its master `mavping respond`.
struct Console {
    child: Child,
    lines: mpsc::Receiver<String>,
    seen: Vec<String>,
}

impl Console {
    /// `mavping respond`'s HEARTBEAT is a companion computer's, which
    /// MAVProxy does not take for a vehicle: the target is named.
    fn start(port: u16, dir: &Path) -> Console {
        let mut child = Command::new(venv_program("mavproxy.py"))
            .args([
                &format!("--master=udpout:127.0.0.1:{port}"),
                "--target-system=1",
                "--target-component=1",
                "--nowait",
            ])
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
        Console {
            child,
            lines,
            seen: Vec::new(),
        }
    }

    fn type_line(&mut self, command: &str) {
        let stdin = self.child.stdin.as_mut().unwrap();
        writeln!(stdin, "{command}").unwrap();
        stdin.flush().unwrap();
    }

    /// The first line from now on that contains `text`.
    fn wait_for(&mut self, text: &str) -> String {
        loop {
            match self.lines.recv_timeout(PATIENCE) {
                Ok(line) => {
                    self.seen.push(line.clone());
                    if line.contains(text) {
                        return line;
                    }
                }
                Err(e) => panic!(
                    "MAVProxy never printed {text:?} ({e}):\n{}",
                    self.seen.join("\n")
                ),
            }
        }
    }

    /// `exit`, and waits for MAVProxy to end (its log written).
    fn exit(mut self) {
        self.type_line("exit");
        let _ = self.child.stdin.take();
        for _ in 0..200 {
            if let Ok(Some(_)) = self.child.try_wait() {
                return;
            }
            std::thread::sleep(Duration::from_millis(100));
        }
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

impl Drop for Console {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// `mavping respond` with `args` on a free port.
fn respond(args: &[&str]) -> (Respond, u16) {
    let port = free_udp_port();
    let link = format!("udpin:127.0.0.1:{port}");
    let mut all: Vec<&str> = args.to_vec();
    all.push(&link);
    (Respond::start(&all), port)
}

/// The transfers part of respond's counts line: each "N NAME" of its
/// requests, frames sent and frames dropped, by name.
#[derive(Debug)]
struct Served {
    requests: HashMap<String, u64>,
    sent: HashMap<String, u64>,
    dropped: HashMap<String, u64>,
}

fn served(rest: &str) -> Served {
    let line = rest
        .lines()
        .find(|l| l.starts_with("respond "))
        .unwrap_or_else(|| panic!("no counts line: {rest}"));
    let part = line
        .split_once("; transfers: ")
        .unwrap_or_else(|| panic!("no transfers: {line}"))
        .1;
    let list = |after: &str| -> HashMap<String, u64> {
        let inside = part.split_once(after).expect(after).1;
        let inside = inside.split_once(')').unwrap().0;
        inside
            .split(", ")
            .filter(|s| *s != "none")
            .map(|s| {
                let (n, name) = s.split_once(' ').unwrap();
                (name.to_string(), n.parse().unwrap())
            })
            .collect()
    };
    Served {
        requests: list("requests ("),
        sent: list("frames sent ("),
        dropped: list("dropped ("),
    }
}

fn n(map: &HashMap<String, u64>, name: &str) -> u64 {
    map.get(name).copied().unwrap_or(0)
}

/// Parameter `i`'s value as served (src/answering/params.rs).
fn param_value(i: u32) -> f64 {
    let i = i64::from(i);
    match i % 4 {
        0 => i as f64 * 0.25 + 0.5,
        1 => (i * 1000 - 70_000) as f64,
        2 => (i % 2000 - 1000) as f64,
        _ => (i % 256) as f64,
    }
}

/// A `param save` file: name and value of each line.
fn saved_params(path: &Path) -> Vec<(String, f64)> {
    std::fs::read_to_string(path)
        .unwrap()
        .lines()
        .map(|l| {
            let mut it = l.split_whitespace();
            let name = it.next().unwrap().to_string();
            (name, it.next().unwrap().parse().unwrap())
        })
        .collect()
}

/// MAVProxy fetches `params` parameters from a responder run with `args`:
/// once by itself at connect, then again for `param fetch` (typed once
/// the first is complete: typed during MAVProxy's first try by FTP, it
/// can leave its parameter module waiting on that try); what respond
/// counted.
fn param_fetch(args: &[&str], params: u32) -> Served {
    let dir = Scratch::new(&format!("serve-params-{params}"));
    let count = params.to_string();
    let mut all = vec!["--params", &count];
    all.extend_from_slice(args);
    let (responder, port) = respond(&all);
    let mut mavproxy = Console::start(port, &dir.0);
    let received = format!("Received {params} parameters");
    mavproxy.wait_for(&received);
    mavproxy.type_line("param fetch");
    mavproxy.wait_for("Requested parameter list");
    mavproxy.wait_for(&received);
    mavproxy.type_line("param save fetched.parm");
    mavproxy.wait_for(&format!("Saved {params} parameters to fetched.parm"));
    let (code, rest) = responder.finish_text();
    assert_eq!(code, 0, "{rest}");
    mavproxy.exit();
    let saved = saved_params(&dir.path("fetched.parm"));
    let want: Vec<(String, f64)> = (0..params)
        .map(|i| (format!("MAVPING_{i:04}"), param_value(i)))
        .collect();
    assert_eq!(saved, want);
    let served = served(&rest);
    // Two lists, each sent whole: the first was over before the second.
    assert_eq!(n(&served.requests, "PARAM_REQUEST_LIST"), 2, "{served:?}");
    assert!(!rest.contains("lists restarted"), "{rest}");
    served
}

#[test]
fn mavproxy_param_fetch_gets_every_parameter() {
    let s = param_fetch(&[], 777);
    // MAVProxy first asks for @PARAM/param.pck, which is not served, then
    // for the list: sent whole, nothing dropped, nothing to re-request.
    assert_eq!(n(&s.sent, "FTP NAK"), n(&s.requests, "FTP"), "{s:?}");
    assert_eq!(n(&s.sent, "PARAM_VALUE"), 2 * 777, "{s:?}");
    assert_eq!(n(&s.requests, "PARAM_REQUEST_READ"), 0, "{s:?}");
    assert!(s.dropped.is_empty(), "{s:?}");
}

#[test]
fn mavproxy_param_fetch_completes_through_drops_re_requesting_each() {
    let s = param_fetch(&["--drop", "10", "--seed", "7"], 500);
    let sent = n(&s.sent, "PARAM_VALUE");
    let dropped = n(&s.dropped, "PARAM_VALUE");
    assert!(dropped > 20, "{s:?}");
    // Every frame respond took from a list or for a read was sent or
    // dropped: none lost, none made up; every read was for a parameter.
    let reads = n(&s.requests, "PARAM_REQUEST_READ");
    assert_eq!(sent + dropped, 2 * 500 + reads, "{s:?}");
    assert_eq!(n(&s.requests, "of them for no parameter"), 0);
    // MAVProxy re-requested each parameter dropped from a list, and again
    // each whose re-request's answer was dropped: one read per drop.
    assert_eq!(reads, dropped, "{s:?}");
}

/// The file as served: `pattern_byte` of each offset.
fn pattern(size: u32) -> Vec<u8> {
    (0..size)
        .map(|offset| {
            let x = offset.wrapping_mul(2_654_435_761);
            (x >> 24) as u8 ^ (offset >> 8) as u8
        })
        .collect()
}

#[test]
fn mavproxy_ftp_get_writes_the_pattern_byte_for_byte_through_drops() {
    let dir = Scratch::new("serve-ftp");
    // Two bursts of 500 packets and a partial one at the end; a share of
    // the packets dropped, so MAVProxy reads the gaps with ReadFile.
    let size = 150_001u32;
    let (responder, port) = respond(&["--file-size", "150001", "--drop", "3", "--seed", "2"]);
    let mut mavproxy = Console::start(port, &dir.0);
    mavproxy.type_line("ftp get /mavping.bin got.bin");
    mavproxy.wait_for(&format!("Wrote {size} bytes to got.bin"));
    let (code, rest) = responder.finish_text();
    assert_eq!(code, 0, "{rest}");
    mavproxy.exit();
    let got = std::fs::read(dir.path("got.bin")).unwrap();
    assert_eq!(got.len(), size as usize);
    assert!(got == pattern(size), "the file differs from the pattern");
    let s = served(&rest);
    // Packets were dropped, and MAVProxy read each gap again: more data
    // packets than the 628 of the file, a request for each gap.
    let dropped = n(&s.dropped, "FTP ACK");
    assert!(dropped > 5, "{s:?}");
    assert!(
        n(&s.sent, "FTP ACK") > u64::from(size.div_ceil(239)),
        "{s:?}"
    );
    assert!(n(&s.requests, "FTP") > dropped, "{s:?}");
}

#[test]
fn mavproxy_wp_list_gets_every_item() {
    let dir = Scratch::new("serve-mission");
    let (responder, port) = respond(&["--mission", "37"]);
    let mut mavproxy = Console::start(port, &dir.0);
    mavproxy.type_line("wp list");
    mavproxy.wait_for("Requesting 37 waypoints");
    mavproxy.type_line("wp save got.txt");
    mavproxy.wait_for("Saved 37 waypoints to got.txt");
    let (code, rest) = responder.finish_text();
    assert_eq!(code, 0, "{rest}");
    mavproxy.exit();
    let text = std::fs::read_to_string(dir.path("got.txt")).unwrap();
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some("QGC WPL 110"));
    let items: Vec<Vec<String>> = lines
        .map(|l| l.split('\t').map(str::to_string).collect())
        .collect();
    assert_eq!(items.len(), 37);
    for (seq, item) in items.iter().enumerate() {
        assert_eq!(item[0], seq.to_string());
        // The command and frame: home, a takeoff, then waypoints.
        let (command, frame) = match seq {
            0 => ("16", "0"),
            1 => ("22", "3"),
            _ => ("16", "3"),
        };
        assert_eq!(
            (item[3].as_str(), item[2].as_str()),
            (command, frame),
            "{item:?}"
        );
    }
    assert_eq!(items[0][8..11], ["-35.363262", "149.165237", "584.000000"]);
    // The first waypoint is 0.001 degrees north of home.
    assert_eq!(items[2][8..11], ["-35.362262", "149.165237", "50.000000"]);
    let s = served(&rest);
    // MAVProxy's wp module asks for the mission at connect and again for
    // `wp list`, dropping the first download for the second: each list
    // answered, each item request answered with its item, none past the
    // end.
    let lists = n(&s.requests, "MISSION_REQUEST_LIST");
    assert!(lists >= 1, "{s:?}");
    assert_eq!(n(&s.sent, "MISSION_COUNT"), lists);
    let items = n(&s.sent, "MISSION_ITEM_INT") + n(&s.sent, "MISSION_ITEM");
    let requests = n(&s.requests, "MISSION_REQUEST_INT") + n(&s.requests, "MISSION_REQUEST");
    assert_eq!(items, requests, "{s:?}");
    assert!(items >= 37, "{s:?}");
    assert_eq!(n(&s.requests, "of them past the end"), 0, "{s:?}");
    // Each request in its own form: MISSION_REQUEST_INT draws
    // MISSION_ITEM_INT, MAVProxy's MISSION_REQUEST a MISSION_ITEM.
    assert_eq!(
        n(&s.sent, "MISSION_ITEM"),
        n(&s.requests, "MISSION_REQUEST")
    );
}

#[test]
fn a_pymavlink_client_gets_each_answer_as_the_protocols_say() {
    let dir = Scratch::new("serve-client");
    let (responder, port) = respond(&["--file-size", "200000", "--mission", "20"]);
    let file = dir.path("got.bin");
    let out = Command::new(python())
        .arg(peer_script("respond_client.py"))
        .arg(port.to_string())
        .arg(&file)
        .output()
        .expect("python runs");
    let (code, rest) = responder.finish_text();
    assert_eq!(code, 0, "{rest}");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let answers: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let params = &answers["params"];
    // By name (index -1) and by index; an unknown one draws nothing, as on
    // ArduPilot.
    assert_eq!(
        params["by_name"],
        serde_json::json!([["MAVPING_0042", -958.0, 4, 42, 500]])
    );
    assert_eq!(
        params["by_index"],
        serde_json::json!([["MAVPING_0041", -29000.0, 6, 41, 500]])
    );
    assert_eq!(params["unknown_name"], serde_json::json!([]));
    assert_eq!(params["unknown_index"], serde_json::json!([]));
    let m = &answers["mission"];
    assert_eq!(m["count"], serde_json::json!([20]));
    assert_eq!(
        m["item_2"],
        serde_json::json!([[2, 16, 3, -353_622_621, 1_491_652_374, 50.0]])
    );
    // Past the end: MAV_MISSION_INVALID_SEQUENCE; no fence; an upload
    // refused with MAV_MISSION_DENIED.
    assert_eq!(m["past_end"], serde_json::json!([13]));
    assert_eq!(m["fence_count"], serde_json::json!([0]));
    assert_eq!(m["upload"], serde_json::json!([14]));
    let f = &answers["ftp"];
    // NAKs: file not found, no sessions available, end of file, file
    // protected; then invalid session once the session is terminated.
    assert_eq!(f["missing"], serde_json::json!([[129, [10]]]));
    assert_eq!(f["open"], serde_json::json!([[128, [0x40, 0x0d, 3, 0]]]));
    assert_eq!(f["second_session"], serde_json::json!([[129, [5]]]));
    assert_eq!(f["read_past_end"], serde_json::json!([[129, [6]]]));
    assert_eq!(f["write"], serde_json::json!([[129, [9]]]));
    assert_eq!(f["list"], serde_json::json!(["Fmavping.bin\t200000\u{0}"]));
    assert_eq!(f["terminate"], serde_json::json!([[128, []]]));
    assert_eq!(f["after_terminate"], serde_json::json!([[129, [4]]]));
    // Two bursts: 500 packets, `burst_complete` on the last, then the
    // other 337 and the end-of-file NAK.
    assert_eq!(
        f["file"],
        serde_json::json!({"size": 200000, "bytes": 200000, "bursts": 2, "gaps": 0,
                           "blob_hex_head": "009e3cda7817b553"})
    );
    assert!(std::fs::read(&file).unwrap() == pattern(200_000));
    let s = served(&rest);
    let want = |pairs: &[(&str, u64)]| -> HashMap<String, u64> {
        pairs.iter().map(|(k, v)| (k.to_string(), *v)).collect()
    };
    assert_eq!(
        s.requests,
        want(&[
            ("PARAM_REQUEST_READ", 4),
            ("of them for no parameter", 2),
            ("MISSION_REQUEST_LIST", 2),
            ("MISSION_REQUEST_INT", 2),
            ("of them past the end", 1),
            ("MISSION_ACK", 1),
            ("uploads refused", 1),
            ("FTP", 10),
        ])
    );
    // FTP ACKs: the open, the listing, 837 packets of data, the end of
    // the session; NAKs: the six above and the burst's end of file.
    assert_eq!(
        s.sent,
        want(&[
            ("PARAM_VALUE", 2),
            ("MISSION_COUNT", 2),
            ("MISSION_ITEM_INT", 1),
            ("MISSION_ACK", 2),
            ("FTP ACK", 840),
            ("FTP NAK", 6),
        ])
    );
    assert!(s.dropped.is_empty());
}

/// mavping's own download probe against respond: its JSON summary.
fn probe(port: u16, args: &[&str]) -> serde_json::Value {
    let link = format!("udpout:127.0.0.1:{port}");
    let mut all = vec!["--json", "-q", "-W", "300ms", &link];
    all.extend_from_slice(args);
    let (code, out, err) = run_mavping(&all);
    assert_eq!(code, 0, "{out}{err}");
    let summary = json_lines(&out)
        .into_iter()
        .find(|l| l["type"] == "transfer_summary")
        .unwrap_or_else(|| panic!("{out}"));
    assert_schema(std::slice::from_ref(&summary));
    summary
}

#[test]
fn mavpings_probes_download_from_respond_what_it_did_not_drop_and_ask_again_for_the_rest() {
    let (responder, port) = respond(&["--params", "1000", "--drop", "10", "--seed", "7"]);
    let params = probe(port, &["--probe", "params", "--retries", "9"]);
    let mission = probe(port, &["--probe", "mission", "--retries", "9"]);
    let file = probe(
        port,
        &["--probe", "ftp", "--path", "/mavping.bin", "--retries", "9"],
    );
    let (_, rest) = responder.finish_text();
    let s = served(&rest);
    let last = |v: &serde_json::Value, key: &str| v["last"][key].as_u64().unwrap();
    assert_eq!(last(&params, "received"), 1000);
    // Every PARAM_VALUE it dropped is one the list missed or a read's
    // answer; each read it heard is one mavping sent.
    let unanswered = last(&params, "re_requests") - last(&params, "re_requests_answered");
    assert_eq!(
        n(&s.dropped, "PARAM_VALUE"),
        last(&params, "missing_first_pass") + unanswered,
        "{params}\n{s:?}"
    );
    assert_eq!(
        n(&s.requests, "PARAM_REQUEST_READ"),
        last(&params, "re_requests")
    );
    assert_eq!(last(&mission, "received"), 20);
    assert_eq!(
        n(&s.requests, "MISSION_REQUEST_INT"),
        last(&mission, "requests") - 2,
        "the list request and our ACK aside"
    );
    assert_eq!(last(&file, "received"), 65536);
}
