//! `--tlog FILE` records a live run: every frame received and sent, read
//! back by pymavlink's `mavlogdump.py` frame for frame and by mavping's
//! own `tlog:` reader, against what the run's JSON and the peers' own
//! counts say.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Duration;

use serde_json::Value;

use crate::common::*;

/// A directory of the test's own, removed when it ends.
struct Dir(PathBuf);

impl Dir {
    fn new(name: &str) -> Dir {
        let dir = std::env::temp_dir().join(format!("mavping-rec-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        Dir(dir)
    }

    fn path(&self, file: &str) -> PathBuf {
        self.0.join(file)
    }
}

impl Drop for Dir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// One record of the file as its bytes say, read here without mavping or
/// pymavlink.
#[derive(Debug)]
struct Record {
    stamp: u64,
    sysid: u8,
    compid: u8,
    seq: u8,
    msgid: u32,
}

fn records(path: &Path) -> Vec<Record> {
    let data = std::fs::read(path).unwrap();
    let mut out = Vec::new();
    let mut i = 0;
    while i < data.len() {
        let stamp = u64::from_be_bytes(data[i..i + 8].try_into().unwrap());
        let f = &data[i + 8..];
        let (len, sysid, compid, seq, msgid) = match f[0] {
            0xFE => (8 + usize::from(f[1]), f[3], f[4], f[2], u32::from(f[5])),
            0xFD => {
                let signed = if f[2] & 1 != 0 { 13 } else { 0 };
                let msgid = u32::from_le_bytes([f[7], f[8], f[9], 0]);
                (12 + usize::from(f[1]) + signed, f[5], f[6], f[4], msgid)
            }
            other => panic!("record at {i}: no frame (0x{other:02x})"),
        };
        assert!(8 + len <= data.len() - i, "record at {i} cut short");
        out.push(Record {
            stamp,
            sysid,
            compid,
            seq,
            msgid,
        });
        i += 8 + len;
    }
    out
}

/// One frame as `mavlogdump.py --show-source --show-seq` prints it.
#[derive(Debug, Clone, PartialEq)]
struct Dumped {
    kind: String,
    sysid: u8,
    compid: u8,
    seq: u8,
    /// The message's own fields, as printed.
    fields: BTreeMap<String, String>,
}

/// Every frame pymavlink reads in the log, in order; only those on `link`
/// (the stamps' two lowest bits, pymavlink's `_link`) when given.
fn mavlogdump(path: &Path, link: Option<u8>) -> Vec<Dumped> {
    let mut cmd = Command::new(python());
    cmd.arg(venv_program("mavlogdump.py"))
        .args(["--show-source", "--show-seq"]);
    if let Some(link) = link {
        cmd.args(["--link", &link.to_string()]);
    }
    let out = cmd.arg(path).output().expect("mavlogdump.py runs");
    assert!(out.status.success(), "{out:?}");
    let text = String::from_utf8(out.stdout).unwrap();
    text.lines().map(dumped).collect()
}

/// `2026-12-02 01:45:49.89: PING {time_usec : 1, seq : 0, ...} srcSystem=250 srcComponent=190 seq=1`
fn dumped(line: &str) -> Dumped {
    let (_, rest) = line.split_once(": ").expect(line);
    let (kind, rest) = rest.split_once(" {").expect(line);
    let (inside, tail) = rest.rsplit_once("} ").expect(line);
    let fields = inside
        .split(", ")
        .filter_map(|kv| kv.split_once(" : "))
        .map(|(k, v)| (k.to_string(), v.to_string()))
        .collect();
    let meta: BTreeMap<&str, u8> = tail
        .split_whitespace()
        .map(|kv| {
            let (k, v) = kv.split_once('=').expect(line);
            (k, v.parse().expect(line))
        })
        .collect();
    Dumped {
        kind: kind.to_string(),
        sysid: meta["srcSystem"],
        compid: meta["srcComponent"],
        seq: meta["seq"],
        fields,
    }
}

fn u(v: &Value) -> u64 {
    v.as_u64().unwrap_or_else(|| panic!("not a count: {v}"))
}

/// The last JSON line of `kind`, every line checked against the schema.
fn json_of(stdout: &str, kind: &str) -> Value {
    let lines = json_lines(stdout);
    assert_schema(&lines);
    lines
        .into_iter()
        .rfind(|l| l["type"] == kind)
        .unwrap_or_else(|| panic!("no {kind} line in\n{stdout}"))
}

/// The packet sequence numbers step by one (mod 256) from the first.
fn assert_consecutive(frames: &[&Dumped], who: &str) {
    for pair in frames.windows(2) {
        assert_eq!(
            pair[1].seq,
            pair[0].seq.wrapping_add(1),
            "{who}: a frame is missing between {:?} and {:?}",
            pair[0],
            pair[1]
        );
    }
}

/// mavping reading the recording back, as it is (our own ids, 250/190,
/// are a source in a log): the passive summary.
fn read_back(path: &Path) -> Value {
    let (code, out, err) = run_mavping(&["--json", "-q", &format!("tlog:{}", path.display())]);
    assert_eq!(code, 0, "{out}{err}");
    json_of(&out, "passive_summary")
}

fn source<'a>(sources: &'a Value, id: &str) -> &'a Value {
    sources
        .as_array()
        .unwrap()
        .iter()
        .find(|s| format!("{}/{}", s["source"]["sysid"], s["source"]["compid"]) == id)
        .unwrap_or_else(|| panic!("no {id} in {sources}"))
}

/// Per MAVProxy link in the read-back: link number to the sources on it
/// and how many frames each.
fn per_link(summary: &Value) -> BTreeMap<u64, BTreeMap<String, u64>> {
    summary["per_link"]["links"]
        .as_array()
        .unwrap_or_else(|| panic!("no per_link: {summary}"))
        .iter()
        .map(|l| {
            let sources = l["sources"]
                .as_array()
                .unwrap()
                .iter()
                .map(|s| {
                    (
                        format!("{}/{}", s["source"]["sysid"], s["source"]["compid"]),
                        u(&s["counts"]["received"]),
                    )
                })
                .collect();
            (u(&l["link"]), sources)
        })
        .collect()
}

/// The stamps never go back, and their two lowest bits are 3 exactly on
/// what mavping sent (as 250/190), `link(sysid)` on the rest.
fn assert_stamps(records: &[Record], link: impl Fn(u8) -> u64) {
    for pair in records.windows(2) {
        assert!(
            pair[1].stamp & !3 >= pair[0].stamp & !3,
            "stamps go back: {pair:?}"
        );
    }
    for r in records {
        let want = if (r.sysid, r.compid) == (250, 190) {
            3
        } else {
            link(r.sysid)
        };
        assert_eq!(r.stamp & 3, want, "{r:?}");
    }
}

#[test]
fn a_ping_run_against_pymavlink_is_recorded_frame_for_frame() {
    let dir = Dir::new("ping");
    let file = dir.path("run.tlog");
    let port = free_udp_port();
    // Drops the requests numbered 3 and 7, answers 5 twice.
    let peer = Peer::start(
        "responder.py",
        &[
            &format!("udpin:127.0.0.1:{port}"),
            "--drop",
            "3,7",
            "--dup",
            "5",
        ],
    );
    let (code, out, err) = run_mavping(&[
        "-c",
        "30",
        "-i",
        "0.05",
        "-W",
        "500ms",
        "--json",
        "--tlog",
        file.to_str().unwrap(),
        &format!("udpout:127.0.0.1:{port}"),
    ]);
    let truth = peer.finish();
    assert_eq!(code, 0, "{out}{err}");
    let summary = json_of(&out, "summary");
    let r = &summary["responders"][0];
    assert_eq!((u(&r["sent"]), u(&r["received"])), (30, 28), "{r}");
    assert_eq!(u(&r["duplicate"]), 1, "{r}");

    let all = mavlogdump(&file, None);
    let raw = records(&file);
    assert_eq!(all.len(), raw.len(), "pymavlink read every record");
    assert_stamps(&raw, |_| 0);
    for (d, r) in all.iter().zip(&raw) {
        assert_eq!((d.sysid, d.compid, d.seq), (r.sysid, r.compid, r.seq));
    }
    let ours: Vec<&Dumped> = all.iter().filter(|d| d.sysid == 250).collect();
    let theirs: Vec<&Dumped> = all.iter().filter(|d| d.sysid == 1).collect();
    assert_eq!(ours.len() + theirs.len(), all.len(), "no one else");
    // Every frame we sent, from our first: numbered 0, 1, 2, ...
    assert_eq!(ours[0].seq, 0);
    assert_consecutive(&ours, "sent");
    // Every frame the peer sent once we were there, its numbers unbroken.
    assert_consecutive(&theirs, "received");
    // pymavlink takes the stamps' link bits as MAVProxy's: 3 ours, 0 its.
    assert_eq!(
        mavlogdump(&file, Some(3)),
        ours.into_iter().cloned().collect::<Vec<_>>()
    );
    assert_eq!(
        mavlogdump(&file, Some(0)),
        theirs.iter().copied().cloned().collect::<Vec<_>>()
    );

    // The requests, in order, as the run and the peer counted them.
    let pings = |from: u8, target: &str| -> Vec<u32> {
        all.iter()
            .filter(|d| d.kind == "PING" && d.sysid == from && d.fields["target_system"] == target)
            .map(|d| d.fields["seq"].parse().unwrap())
            .collect()
    };
    let requests = pings(250, "0");
    assert_eq!(requests, (0..30).collect::<Vec<_>>());
    assert_eq!(u(&truth["ping_requests"]), 30, "{truth}");
    // The replies: all but 3 and 7, 5 twice.
    let mut replies = pings(1, "250");
    assert_eq!(
        replies.len() as u64,
        u(&truth["replies"]) + u(&truth["duplicated"])
    );
    replies.sort_unstable();
    let mut want: Vec<u32> = (0..30).filter(|s| ![3, 7].contains(s)).collect();
    want.push(5);
    want.sort_unstable();
    assert_eq!(replies, want);
    // Each reply after its request in the file.
    for (i, d) in all.iter().enumerate() {
        if d.kind == "PING" && d.sysid == 1 {
            let seq = &d.fields["seq"];
            let asked = all[..i]
                .iter()
                .any(|e| e.kind == "PING" && e.sysid == 250 && &e.fields["seq"] == seq);
            assert!(asked, "reply {seq} before its request");
        }
    }

    // mavping reads it back: every frame, per link as MAVProxy's.
    let back = read_back(&file);
    let heard = |id: &str| u(&source(&back["sources"], id)["counts"]["received"]);
    let (n_ours, n_theirs) = (
        raw.iter().filter(|r| r.sysid == 250).count() as u64,
        theirs.len() as u64,
    );
    assert_eq!(
        (heard("250/190"), heard("1/1")),
        (n_ours, n_theirs),
        "{back}"
    );
    assert_eq!(u(&source(&back["sources"], "1/1")["counts"]["lost"]), 0);
    assert_eq!(
        u(&back["log"]["records"]["records"]),
        raw.len() as u64,
        "{back}"
    );
    assert_eq!(
        back["log"]["stamps"]["low_bits"],
        serde_json::json!([n_theirs, 0, 0, n_ours])
    );
    let links = per_link(&back);
    assert_eq!(links[&0], BTreeMap::from([("1/1".to_string(), n_theirs)]));
    assert_eq!(links[&3], BTreeMap::from([("250/190".to_string(), n_ours)]));
}

#[test]
fn a_passive_run_against_a_pymavlink_vehicle_is_recorded_and_read_back_alike() {
    let dir = Dir::new("passive");
    let file = dir.path("passive.tlog");
    let port = free_udp_port();
    let mut vehicle = Peer::start(
        "vehicle.py",
        &[
            &format!("udpin:127.0.0.1:{port}"),
            "--frames",
            "300",
            "--rate",
            "100",
            "--drop",
            "10,20,21",
            "--dup",
            "40",
            "--swap",
            "50",
        ],
    );
    let run = start_mavping(&[
        "--passive",
        "--json",
        "--tlog",
        file.to_str().unwrap(),
        &format!("udpout:127.0.0.1:{port}"),
    ]);
    let truth = crate::passive_peers::truth_when_done(&mut vehicle);
    std::thread::sleep(Duration::from_millis(300));
    // Ctrl-C: the recording is flushed whole.
    signal(run.child.id(), "INT");
    let (code, out, err) = run.wait(Duration::from_secs(20));
    drop(vehicle);
    assert_eq!(code, 0, "{out}{err}");
    let live = json_of(&out, "passive_summary");
    let live_v = source(&live["sources"], "1/1");
    assert_eq!(
        u(&live_v["counts"]["received"]),
        u(&truth["sent"]),
        "{truth}"
    );
    assert_eq!(u(&live_v["counts"]["lost"]), 3, "{live_v}");

    let raw = records(&file);
    assert_stamps(&raw, |_| 0);
    let all = mavlogdump(&file, None);
    assert_eq!(all.len(), raw.len());
    let theirs = all.iter().filter(|d| d.sysid == 1).count() as u64;
    assert_eq!(theirs, u(&truth["sent"]), "every frame the vehicle sent");
    let ours: Vec<&Dumped> = all.iter().filter(|d| d.sysid == 250).collect();
    assert!(
        ours.iter().all(|d| d.kind == "HEARTBEAT"),
        "passive: ours only"
    );
    assert_eq!(ours[0].seq, 0);
    assert_consecutive(&ours, "sent");

    // Read back, the vehicle's figures are the live run's, every one.
    let back = read_back(&file);
    let back_v = source(&back["sources"], "1/1");
    for key in ["received", "lost", "duplicate", "reordered", "resyncs"] {
        assert_eq!(
            back_v["counts"][key], live_v["counts"][key],
            "{key}: {back_v}"
        );
    }
    assert_eq!(
        u(&source(&back["sources"], "250/190")["counts"]["received"]),
        ours.len() as u64
    );
}

#[test]
fn several_links_share_one_log_told_apart_by_the_link_bits() {
    let dir = Dir::new("links");
    let file = dir.path("links.tlog");
    let (pa, pb) = (free_udp_port(), free_udp_port());
    let a = Peer::start(
        "responder.py",
        &[&format!("udpin:127.0.0.1:{pa}"), "--sysid", "1"],
    );
    let b = Peer::start(
        "responder.py",
        &[
            &format!("udpin:127.0.0.1:{pb}"),
            "--sysid",
            "2",
            "--drop",
            "4",
        ],
    );
    let (code, out, err) = run_mavping(&[
        "-c",
        "20",
        "-i",
        "0.05",
        "-W",
        "500ms",
        "--json",
        "--tlog",
        file.to_str().unwrap(),
        &format!("udpout:127.0.0.1:{pa}"),
        &format!("udpout:127.0.0.1:{pb}"),
    ]);
    let (ta, tb) = (a.finish(), b.finish());
    assert_eq!(code, 0, "{out}{err}");
    let raw = records(&file);
    assert_stamps(&raw, |sysid| u64::from(sysid - 1));
    let on = |link: u8| mavlogdump(&file, Some(link));
    let replies = |frames: &[Dumped], from: u8| {
        frames
            .iter()
            .filter(|d| d.kind == "PING" && d.sysid == from)
            .count() as u64
    };
    let (l0, l1, l3) = (on(0), on(1), on(3));
    assert!(l0.iter().all(|d| d.sysid == 1) && l1.iter().all(|d| d.sysid == 2));
    assert_eq!(replies(&l0, 1), u(&ta["replies"]));
    assert_eq!(replies(&l1, 2), u(&tb["replies"]));
    assert_eq!(u(&tb["replies"]), 19);
    // What we sent, on both links: 20 requests each.
    assert_eq!(replies(&l3, 250), 40);
    assert_eq!(l0.len() + l1.len() + l3.len(), raw.len());
    let links = per_link(&read_back(&file));
    assert_eq!(links[&0]["1/1"], l0.len() as u64);
    assert_eq!(links[&1]["2/1"], l1.len() as u64);
    assert_eq!(links[&3]["250/190"], l3.len() as u64);
}

#[test]
fn a_write_error_mid_run_is_an_output_failure_and_the_run_completes() {
    let (code, out, err) = run_mavping(&[
        "-c",
        "5",
        "-i",
        "0.02",
        "--json",
        "--tlog",
        "/dev/full",
        "sim:",
    ]);
    assert_eq!(code, 2, "{out}{err}");
    assert_eq!(
        err.trim_end(),
        "mavping: cannot write --tlog /dev/full: No space left on device (os error 28)"
    );
    let summary = json_of(&out, "summary");
    let r = &summary["responders"][0];
    assert_eq!((u(&r["sent"]), u(&r["received"])), (5, 5), "{r}");
}

#[test]
fn a_path_that_cannot_be_written_is_refused_before_the_run() {
    let dir = Dir::new("paths");
    let shown = dir.0.display().to_string();
    let missing = dir.path("no/such/dir/x.tlog");
    let missing_shown = missing.display().to_string();
    for (path, why) in [
        (shown.as_str(), "Is a directory (os error 21)"),
        (
            missing_shown.as_str(),
            "No such file or directory (os error 2)",
        ),
    ] {
        let (code, out, err) = run_mavping(&["-c", "3", "--tlog", path, "sim:"]);
        assert_eq!(code, 2, "{out}{err}");
        assert_eq!(out, "", "nothing measured");
        assert_eq!(
            err.trim_end(),
            format!("mavping: cannot write --tlog {path}: {why}")
        );
    }
    // An existing file is replaced, as --samples and --plot replace theirs.
    let old = dir.path("old.tlog");
    std::fs::write(
        &old,
        b"not a log, and longer than the run's records would be.....",
    )
    .unwrap();
    let (code, out, err) = run_mavping(&[
        "-c",
        "2",
        "-i",
        "0.02",
        "--tlog",
        old.to_str().unwrap(),
        "sim:",
    ]);
    assert_eq!(code, 0, "{out}{err}");
    let raw = records(&old);
    assert_eq!(
        raw.iter()
            .filter(|r| r.msgid == 4 && r.sysid == 250)
            .count(),
        2
    );
}

#[test]
fn a_log_as_input_and_more_links_than_the_bits_tell_apart_are_refused() {
    let dir = Dir::new("refused");
    let out_file = dir.path("out.tlog");
    let out_path = out_file.to_str().unwrap();
    let input = dir.path("in.tlog");
    std::fs::write(&input, []).unwrap();
    let input_link = format!("tlog:{}", input.display());
    let (code, out, err) = run_mavping(&["--tlog", out_path, &input_link]);
    assert_eq!((code, out.as_str()), (2, ""), "{err}");
    assert_eq!(
        err.trim_end(),
        format!("mavping: --tlog {out_path}: {input_link} is a telemetry log already; --tlog records live links")
    );
    let links = ["sim:", "sim:?seed=2", "sim:?seed=3", "sim:?seed=4"];
    let mut args = vec!["--tlog", out_path];
    args.extend(links);
    let (code, out, err) = run_mavping(&args);
    assert_eq!((code, out.as_str()), (2, ""), "{err}");
    assert_eq!(
        err.trim_end(),
        format!(
            "mavping: --tlog {out_path}: records at most 3 links in one log (the stamps' link bits), not 4: run sim:?seed=4 separately"
        )
    );
    assert!(!out_file.exists(), "refused before anything was created");
}

#[test]
fn a_fast_run_is_recorded_whole_against_mavping_respond() {
    let dir = Dir::new("fast");
    let file = dir.path("fast.tlog");
    let port = free_udp_port();
    // Drops a seeded 5 % of the requests: lost replies, counted by both.
    let respond = Respond::start(&[
        "--drop",
        "5",
        "--seed",
        "3",
        &format!("udpin:127.0.0.1:{port}"),
    ]);
    // 2,000 requests a second: the session reads what waits while it
    // paces itself (read_waiting), not only when it blocks.
    let (code, out, err) = run_mavping(&[
        "-c",
        "4000",
        "--rate",
        "2000",
        "-W",
        "500ms",
        "--json",
        "-q",
        "--tlog",
        file.to_str().unwrap(),
        &format!("udpout:127.0.0.1:{port}"),
    ]);
    let (rc, counts) = respond.finish();
    assert_eq!(rc, 0);
    assert!(code <= 1, "{out}{err}");
    let summary = json_of(&out, "summary");
    let r = &summary["responders"][0];
    let all = mavlogdump(&file, None);
    let raw = records(&file);
    assert_eq!(all.len(), raw.len());
    assert_stamps(&raw, |_| 0);
    let ours: Vec<&Dumped> = all.iter().filter(|d| d.sysid == 250).collect();
    let theirs: Vec<&Dumped> = all.iter().filter(|d| d.sysid == 1).collect();
    assert_consecutive(&ours, "sent");
    assert_consecutive(&theirs, "received");
    let requests: Vec<u32> = ours
        .iter()
        .filter(|d| d.kind == "PING")
        .map(|d| d.fields["seq"].parse().unwrap())
        .collect();
    assert_eq!(requests, (0..4000).collect::<Vec<_>>());
    let replies = theirs.iter().filter(|d| d.kind == "PING").count() as u64;
    // What the run counted and what respond sent, frame for frame.
    assert_eq!(replies, u(&r["received"]) + u(&r["duplicate"]), "{r}");
    assert_eq!(replies, counts[5], "respond's replies: {counts:?}");
    assert_eq!(counts[6], u(&r["lost"]), "{counts:?} {r}");
    assert!(counts[6] > 100, "the drops happened: {counts:?}");
}
