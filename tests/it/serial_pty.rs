//! mavping on a serial port: a pseudo-terminal "null-modem cable"
//! (tests/peers/pty_bridge.py) with a pymavlink responder on its far end,
//! opened at 57600 baud by both sides, as with a telemetry radio.

use std::path::PathBuf;
use std::time::Duration;

use crate::common::*;

/// A bridge and the device paths of its two ends.
fn scratch_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("mavping-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn skipped_bytes(out: &str) -> u64 {
    out.lines()
        .find_map(|l| l.strip_prefix("link: "))
        .and_then(|l| l.split(", ").find(|p| p.ends_with("bytes skipped")))
        .and_then(|p| p.split_whitespace().next())
        .and_then(|n| n.parse().ok())
        .unwrap_or(0)
}

#[test]
fn junk_between_frames_is_counted_and_skipped_exactly() {
    let (_bridge, a, b) = pty_bridge(&[]);
    let responder = Peer::start(
        "responder.py",
        &[
            &b,
            "--baud",
            "57600",
            "--junk-before",
            "1,3,5",
            "--drop",
            "4",
        ],
    );
    let (code, out, err) = run_mavping(&[
        "-c",
        "8",
        "-i",
        "0.05",
        "-W",
        "300ms",
        &format!("serial:{a}:57600"),
    ]);
    assert_eq!(code, 0, "{out}\n{err}");
    let c = text_counts(&out, "1/1").expect(&out);
    assert_eq!(
        (c.sent, c.received, c.lost, c.duplicate),
        (8, 7, 1, 0),
        "{out}"
    );
    let truth = responder.finish();
    assert_eq!(truth["junk"], 3);
    assert_eq!(truth["replies"], 7);
    let junk = truth["junk_bytes"].as_u64().unwrap();
    assert!(junk >= 3);
    assert_eq!(skipped_bytes(&out), junk, "{out}");
}

#[test]
fn frames_split_across_reads_are_reassembled() {
    // Every 5 bytes from the responder arrive as a read of their own.
    let (bridge, a, b) = pty_bridge(&["--chunk", "5", "--chunk-delay-ms", "2"]);
    let responder = Peer::start("responder.py", &[&b, "--baud", "57600"]);
    // A bare device path takes its baud rate from --baud.
    let (code, out, err) =
        run_mavping(&["-c", "6", "-i", "0.1", "-W", "500ms", "--baud", "57600", &a]);
    assert_eq!(code, 0, "{out}\n{err}");
    let c = text_counts(&out, "1/1").expect(&out);
    assert_eq!((c.sent, c.received, c.lost), (6, 6, 0), "{out}");
    assert_eq!(skipped_bytes(&out), 0, "{out}");
    assert_eq!(responder.finish()["replies"], 6);
    assert!(bridge.finish()["b_to_a"].as_u64().unwrap() > 6 * 26);
}

#[test]
fn closing_the_pty_ends_the_run_with_the_summary_and_exit_2() {
    let (mut bridge, a, b) = pty_bridge(&[]);
    let _responder = Peer::start("responder.py", &[&b, "--baud", "57600"]);
    let run = start_mavping(&["-i", "0.05", "-W", "300ms", &format!("serial:{a}:57600")]);
    std::thread::sleep(Duration::from_millis(700));
    bridge.kill();
    let (code, out, err) = run.wait(Duration::from_secs(10));
    assert_eq!(code, 2, "{out}\n{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(err.contains("hung up"), "{err}");
    let c = text_counts(&out, "1/1").expect(&out);
    assert!(c.received >= 5, "{out}");
    assert_eq!(c.sent, c.received + c.lost, "{out}");
}

#[test]
fn missing_device_exits_2_with_the_os_reason() {
    let (code, out, err) = run_mavping(&["serial:/dev/ttyMAVPING_NONE:57600"]);
    assert_eq!(code, 2, "{out}\n{err}");
    assert!(out.is_empty(), "{out}");
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(
        err.contains("cannot open serial:/dev/ttyMAVPING_NONE:57600")
            && err.contains("No such file or directory"),
        "{err}"
    );
}

#[test]
fn reconnect_reopens_the_device_when_it_comes_back() {
    // The bridge's A end is reached through a symlink, so a new bridge (new
    // pty numbers) reappears under the same name, as a radio replugged.
    let dir = scratch_dir("reconnect");
    let link = dir.join("ttyRADIO");
    let link_s = link.to_str().unwrap();
    let (mut first, _, b) = pty_bridge(&["--link-a", link_s]);
    let mut responder = Peer::start("responder.py", &[&b, "--baud", "57600"]);
    let run = start_mavping(&[
        "--reconnect",
        "-i",
        "0.05",
        "-W",
        "200ms",
        "-w",
        "3s",
        &format!("serial:{link_s}:57600"),
    ]);
    std::thread::sleep(Duration::from_millis(700));
    first.kill();
    responder.kill();
    std::thread::sleep(Duration::from_millis(500));
    let (_second, _, b2) = pty_bridge(&["--link-a", link_s]);
    let _responder2 = Peer::start("responder.py", &[&b2, "--baud", "57600"]);
    let (code, out, err) = run.wait(Duration::from_secs(15));
    let _ = std::fs::remove_dir_all(&dir);
    assert_eq!(code, 0, "{out}\n{err}");
    assert!(err.contains("lost (device hung up"), "{err}");
    assert!(err.contains("reconnected after"), "{err}");
    assert!(out.contains("while reconnecting"), "downtime shown: {out}");
    let c = text_counts(&out, "1/1").expect(&out);
    assert!(c.lost >= 5, "pings sent while down are lost: {out}");
    // Replies to requests sent after the device came back (t > 1.5 s).
    assert!(
        out.lines()
            .any(|l| l.starts_with("reply from 1/1: seq=4")
                || l.starts_with("reply from 1/1: seq=5")),
        "{out}"
    );
}

#[test]
fn a_pty_ignores_the_baud_rate_and_the_summary_says_so() {
    // 57600 baud = 5760 bytes/s: a request (21 B) and its reply (26 B) take
    // 8.16 ms on a real UART, at most ~122 PINGs/s. A pty passes 200/s in
    // well under a millisecond: no warning up front (the device may ignore
    // the baud rate), and afterwards the replies show it does, so no wire
    // floor or capacity is claimed.
    let (_bridge, a, b) = pty_bridge(&[]);
    let _responder = Peer::start("responder.py", &[&b, "--baud", "57600"]);
    let (code, out, err) = run_mavping(&[
        "--json",
        "-q",
        "-c",
        "20",
        "-i",
        "0.005",
        "-W",
        "1s",
        &format!("serial:{a}:57600"),
    ]);
    assert_eq!(code, 0, "{out}\n{err}");
    assert!(!err.contains("warning"), "{err}");
    let s = checked_summary(&out);
    assert_eq!(n(responder(&s, "1/1"), "received"), 20, "{s}");
    assert!(s["wire"].is_null(), "{s}");
    let hints = s["hints"].as_array().unwrap();
    let baud = hints
        .iter()
        .find(|h| h["code"] == "baud_not_in_effect")
        .unwrap_or_else(|| panic!("{s}"));
    let text = baud["text"].as_str().unwrap();
    assert!(
        text.contains("faster than 57600 baud allows (8.160 ms per round trip)"),
        "{text}"
    );
    assert!(!hints.iter().any(|h| h["code"] == "wire_overrun"), "{s}");
}

#[test]
fn a_pty_at_a_high_baud_that_the_replies_cannot_disprove_is_flagged_unproven() {
    // 921600 baud: a PING and its reply take 0.510 ms on a real UART. A pty
    // may ignore that, but here the bridge sends replies in 4-byte pieces
    // 2 ms apart, so every round trip is far above the floor: the replies
    // cannot tell, and the summary must not present the wire figures as
    // measured facts.
    let (_bridge, a, b) = pty_bridge(&["--chunk", "4", "--chunk-delay-ms", "2"]);
    let _responder = Peer::start("responder.py", &[&b, "--baud", "921600"]);
    let link = format!("serial:{a}:921600");
    let (code, out, err) =
        run_mavping(&["--json", "-q", "-c", "5", "-i", "0.1", "-W", "1s", &link]);
    assert_eq!(code, 0, "{out}\n{err}");
    let s = checked_summary(&out);
    assert_eq!(n(responder(&s, "1/1"), "received"), 5, "{s}");
    assert_eq!(s["wire"]["may_ignore_baud"], true, "{s}");
    assert_eq!(s["wire"]["baud"], 921600, "{s}");
    let hints = s["hints"].as_array().unwrap();
    let codes: Vec<&str> = hints.iter().filter_map(|h| h["code"].as_str()).collect();
    assert!(codes.contains(&"baud_unverified"), "{s}");
    assert!(!codes.contains(&"baud_not_in_effect"), "{s}");
    let text = hints
        .iter()
        .find(|h| h["code"] == "baud_unverified")
        .unwrap()["text"]
        .as_str()
        .unwrap();
    assert!(
        text.contains("921600 baud") && text.contains("a pty") && text.contains("0.510 ms"),
        "{text}"
    );
    // The text summary says it on the wire line itself.
    let (code, out, err) = run_mavping(&["-c", "3", "-i", "0.1", "-W", "1s", &link]);
    assert_eq!(code, 0, "{out}\n{err}");
    assert!(
        out.contains("wire (unproven on a pty): 921600 baud carries"),
        "{out}"
    );
}

/// A serial device another program holds exclusively (TIOCEXCL, as
/// mavping and most ground stations open it) is "busy": exit 2 with the
/// OS reason. Root ignores TIOCEXCL, so as root mavping runs as nobody.
#[test]
fn a_device_held_exclusively_exits_2_busy() {
    let holder = "import os, pty, fcntl, termios, sys, time\n\
                  m, s = pty.openpty()\n\
                  name = os.ttyname(s)\n\
                  os.chmod(name, 0o666)\n\
                  fcntl.ioctl(s, termios.TIOCEXCL)\n\
                  print(name, flush=True)\n\
                  sys.stdin.read()\n";
    let mut held = std::process::Command::new(python())
        .args(["-c", holder])
        .stdin(std::process::Stdio::piped())
        .stdout(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let mut device = String::new();
    std::io::BufRead::read_line(
        &mut std::io::BufReader::new(held.stdout.take().unwrap()),
        &mut device,
    )
    .unwrap();
    let link = format!("serial:{}:57600", device.trim());
    let binary = assert_cmd::cargo::cargo_bin("mavping");
    // /proc/self belongs to our effective user.
    let as_root =
        std::os::unix::fs::MetadataExt::uid(&std::fs::metadata("/proc/self").unwrap()) == 0;
    let mut cmd = if as_root {
        let mut c = std::process::Command::new("setpriv");
        c.args(["--reuid=65534", "--regid=65534", "--clear-groups"])
            .arg(&binary);
        c
    } else {
        std::process::Command::new(&binary)
    };
    let child = cmd
        .args(["-c", "1", "-W", "200ms", &link])
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("setpriv (util-linux) runs mavping as nobody");
    let (code, out, err) = wait_output(child, Duration::from_secs(30));
    drop(held.stdin.take());
    let _ = held.wait();
    assert_eq!(code, 2, "{out}{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(err.contains("busy"), "{err}");
}

#[test]
fn a_passive_count_on_a_serial_link_is_exact() {
    // A pymavlink vehicle on the far end of the cable, numbering frames it
    // does not send, sending some twice and swapping pairs; mavping only
    // listens (its HEARTBEAT starts the vehicle, as a radio's GCS does).
    let (_bridge, a, b) = pty_bridge(&[]);
    let mut vehicle = Peer::start(
        "vehicle.py",
        &[
            &b,
            "--baud",
            "57600",
            "--frames",
            "400",
            "--rate",
            "100",
            "--drop",
            "10,11,12,250",
            "--dup",
            "60,300",
            "--swap",
            "100,270,350",
        ],
    );
    let run = start_mavping(&["--passive", "--json", &format!("serial:{a}:57600")]);
    let sent = crate::passive_peers::truth_when_done(&mut vehicle);
    std::thread::sleep(Duration::from_millis(300));
    signal(run.child.id(), "INT");
    let (code, out, err) = run.wait(Duration::from_secs(20));
    assert_eq!(code, 0, "{out}\n{err}");
    let num = |v: &serde_json::Value| v.as_u64().unwrap();
    assert_eq!(
        [
            num(&sent["dropped"]),
            num(&sent["duplicated"]),
            num(&sent["swapped"])
        ],
        [4, 2, 3],
        "{sent}"
    );
    let line = out
        .lines()
        .find(|l| l.contains("\"passive_summary\""))
        .expect(&out);
    let summary: serde_json::Value = serde_json::from_str(line).unwrap();
    let source = &summary["sources"][0];
    assert_eq!(
        [
            num(&source["source"]["sysid"]),
            num(&source["source"]["compid"])
        ],
        [1, 1]
    );
    let counts = &source["counts"];
    assert_eq!(counts["received"], sent["sent"], "{source}");
    assert_eq!(
        [
            num(&counts["lost"]),
            num(&counts["duplicate"]),
            num(&counts["reordered"]),
            num(&counts["resyncs"])
        ],
        [4, 2, 3, 0],
        "{source}"
    );
    // Every byte was a frame: nothing skipped on the wire.
    assert_eq!(summary["frames"]["skipped_bytes"], 0, "{summary}");
    // pymavlink's arithmetic: the drops, 255 a duplicate, 256 a swap.
    assert_eq!(source["pymav"]["loss"], 4 + 2 * 255 + 3 * 256, "{source}");
}
