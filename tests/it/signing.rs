//! MAVLink 2 signing against pymavlink's own signing code, both ways, and
//! mavping against `mavping respond`: forged, unsigned and replayed frames
//! are refused, counted exactly and never measured.

use crate::common::*;

use std::process::Stdio;
use std::time::Duration;

use serde_json::Value;

const HEX_KEY: &str = "8f1e6c2a9b3d4e5f60718293a4b5c6d7e8f90112233445566778899aabbccddee";

fn run_with_env(args: &[&str], env: &[(&str, &str)]) -> (i32, String, String) {
    let mut cmd = mavping();
    cmd.args(args).stdout(Stdio::piped()).stderr(Stdio::piped());
    for (k, v) in env {
        cmd.env(k, v);
    }
    wait_output(cmd.spawn().unwrap(), Duration::from_secs(60))
}

fn key_file(name: &str, content: &str) -> std::path::PathBuf {
    let path =
        std::env::temp_dir().join(format!("mavping-signing-{name}-{}.key", std::process::id()));
    std::fs::write(&path, content).unwrap();
    path
}

#[test]
fn pymavlink_signs_and_mavping_requiring_signatures_measures_every_reply() {
    let port = free_udp_port();
    let peer = Peer::start(
        "signed_peer.py",
        &[&format!("udpin:127.0.0.1:{port}"), "--key", HEX_KEY],
    );
    // The key from the environment, not the command line.
    let (code, out, err) = run_with_env(
        &[
            "--json",
            "-q",
            "-c",
            "10",
            "-i",
            "0.05",
            "-W",
            "500ms",
            "--require-signed",
            &format!("udpout:127.0.0.1:{port}"),
        ],
        &[("MAVPING_SIGNING_KEY", HEX_KEY)],
    );
    assert_eq!(code, 0, "{out}\n{err}");
    let s = checked_summary(&out);
    let r = responder(&s, "1/1");
    assert_eq!(
        (&r["sent"], &r["received"], &r["lost"]),
        (&10.into(), &10.into(), &0.into()),
        "{s}"
    );
    let signing = &s["signing"];
    assert_eq!(signing["required"], true);
    assert_eq!(signing["signed"], 10, "{signing}");
    for refused in [
        "unsigned",
        "rejected_unsigned",
        "rejected_bad_signature",
        "rejected_replay",
    ] {
        assert_eq!(signing[refused], 0, "{refused}: {signing}");
    }
    let truth = peer.finish();
    // pymavlink verified all our frames: 10 PINGs and our HEARTBEAT.
    assert_eq!(truth["ping_requests"], 10, "{truth}");
    assert_eq!(truth["replies"], 10, "{truth}");
    assert_eq!(truth["rejected_frames"], 0, "{truth}");
}

#[test]
fn mavping_signs_and_pymavlink_answers_only_what_it_verified() {
    let port = free_udp_port();
    let target = format!("udpout:127.0.0.1:{port}");
    // A passphrase on both sides: pymavlink gets sha256 of it, as MAVProxy.
    let peer = Peer::start(
        "signed_peer.py",
        &[&format!("udpin:127.0.0.1:{port}"), "--key", "open sesame"],
    );
    let file = key_file("passphrase", "open sesame\n");
    let signed = run_mavping(&[
        "-c",
        "5",
        "-i",
        "0.05",
        "-W",
        "500ms",
        "--signing-key-file",
        file.to_str().unwrap(),
        "--signing-link-id",
        "4",
        &target,
    ]);
    std::fs::remove_file(&file).unwrap();
    let (code, out, err) = signed;
    assert_eq!(code, 0, "{out}\n{err}");
    let c = text_counts(&out, "1/1").expect(&out);
    assert_eq!((c.sent, c.received, c.lost), (5, 5, 0), "{out}");
    assert!(
        out.contains(
            "signing (link id 4, unsigned accepted): 5 signed and 0 unsigned frames accepted; \
             rejected 0 unsigned, 0 with a bad signature, 0 replayed"
        ),
        "{out}"
    );
    // Unsigned and wrongly signed requests get no answer at all.
    for extra in [&[][..], &["--signing-key", "guess"][..]] {
        let mut args = vec!["-c", "3", "-i", "0.05", "-W", "300ms", "--no-heartbeat"];
        args.extend_from_slice(extra);
        args.push(&target);
        let (code, out, err) = run_mavping(&args);
        assert_eq!(code, 1, "{extra:?}: {out}\n{err}");
        assert!(out.contains("no replies"), "{out}");
    }
    let truth = peer.finish();
    assert_eq!(truth["ping_requests"], 5, "{truth}");
    assert_eq!(truth["rejected_pings"], 6, "{truth}");
    assert_eq!(truth["rejected_frames"], 6, "{truth}");
}

#[test]
fn forged_unsigned_and_replayed_replies_are_refused_counted_and_never_measured() {
    let port = free_udp_port();
    let target = format!("udpout:127.0.0.1:{port}");
    let peer = Peer::start(
        "signed_peer.py",
        &[
            &format!("udpin:127.0.0.1:{port}"),
            "--key",
            HEX_KEY,
            "--forge",
            "1,4",
            "--unsigned",
            "2",
            "--replay",
            "3,5,6",
        ],
    );
    let run = |require: bool| {
        let mut args = vec![
            "--json",
            "-c",
            "8",
            "-i",
            "0.05",
            "-W",
            "500ms",
            "--signing-key",
            HEX_KEY,
        ];
        if require {
            args.push("--require-signed");
        }
        args.push(&target);
        let (code, out, err) = run_mavping(&args);
        assert_eq!(code, 0, "{out}\n{err}");
        checked_summary(&out)
    };

    // Required: the forged (1, 4) and unsigned (2) replies are lost; the
    // replayed copies of 3, 5 and 6 are not duplicates.
    let s = run(true);
    let r = responder(&s, "1/1");
    let counts = |r: &Value| {
        ["sent", "received", "lost", "duplicate", "late"].map(|k| r[k].as_u64().unwrap())
    };
    assert_eq!(counts(r), [8, 5, 3, 0, 0], "{s}");
    let signing = |s: &Value| {
        [
            "signed",
            "unsigned",
            "rejected_unsigned",
            "rejected_bad_signature",
            "rejected_replay",
        ]
        .map(|k| s["signing"][k].as_u64().unwrap())
    };
    assert_eq!(signing(&s), [5, 0, 1, 2, 3], "{s}");

    // Without --require-signed the unsigned reply is measured; forged and
    // replayed frames are still refused.
    let s = run(false);
    assert_eq!(counts(responder(&s, "1/1")), [8, 6, 2, 0, 0], "{s}");
    assert_eq!(signing(&s), [5, 1, 0, 2, 3], "{s}");
    assert_eq!(s["signing"]["required"], false);

    let truth = peer.finish();
    assert_eq!(
        ["ping_requests", "replies", "forged", "unsigned", "replayed"]
            .map(|k| truth[k].as_u64().unwrap()),
        [16, 10, 4, 2, 6],
        "{truth}"
    );
}

#[test]
fn text_summary_reports_refused_frames() {
    let port = free_udp_port();
    let peer = Peer::start(
        "signed_peer.py",
        &[
            &format!("udpin:127.0.0.1:{port}"),
            "--key",
            HEX_KEY,
            "--forge",
            "0",
            "--replay",
            "1",
        ],
    );
    let (code, out, err) = run_mavping(&[
        "-c",
        "3",
        "-i",
        "0.05",
        "-W",
        "500ms",
        "--signing-key",
        HEX_KEY,
        "--require-signed",
        &format!("udpout:127.0.0.1:{port}"),
    ]);
    assert_eq!(code, 0, "{out}\n{err}");
    let c = text_counts(&out, "1/1").expect(&out);
    // The forged reply to seq 0 opened no window: 2 sent from seq 1 on.
    assert_eq!((c.received, c.duplicate), (2, 0), "{out}");
    assert!(
        out.contains(
            "signing (link id 0, signatures required): 2 signed and 0 unsigned frames accepted; \
             rejected 0 unsigned, 1 with a bad signature, 1 replayed"
        ),
        "{out}"
    );
    assert!(
        out.contains("hint: 1 frames were signed with another key"),
        "{out}"
    );
    drop(peer);
}

#[test]
fn mavping_respond_with_a_key_answers_signed_pings_and_ignores_the_rest() {
    let port = free_udp_port();
    let file = key_file("respond", &format!("  {HEX_KEY}  \n"));
    let respond = start_mavping(&[
        "respond",
        "--signing-key-file",
        file.to_str().unwrap(),
        &format!("udpin:127.0.0.1:{port}"),
    ]);
    assert!(
        respond.first_line.contains("(signed requests only)"),
        "{}",
        respond.first_line
    );
    let target = format!("udpout:127.0.0.1:{port}");
    let (code, out, err) = run_mavping(&[
        "--json",
        "-q",
        "-c",
        "5",
        "-i",
        "0.05",
        "-W",
        "500ms",
        "--no-heartbeat",
        "--signing-key-file",
        file.to_str().unwrap(),
        "--require-signed",
        &target,
    ]);
    std::fs::remove_file(&file).unwrap();
    assert_eq!(code, 0, "{out}\n{err}");
    let s = checked_summary(&out);
    let r = responder(&s, "1/1");
    assert_eq!((&r["sent"], &r["received"]), (&5.into(), &5.into()), "{s}");
    // Its replies (and HEARTBEATs) were signed: nothing refused.
    assert!(s["signing"]["signed"].as_u64().unwrap() >= 5, "{s}");
    assert_eq!(s["signing"]["rejected_unsigned"], 0, "{s}");
    assert_eq!(s["signing"]["rejected_bad_signature"], 0, "{s}");

    for extra in [&[][..], &["--signing-key", "guess"][..]] {
        let mut args = vec!["-c", "3", "-i", "0.05", "-W", "300ms", "--no-heartbeat"];
        args.extend_from_slice(extra);
        args.push(&target);
        let (code, out, err) = run_mavping(&args);
        assert_eq!(code, 1, "{extra:?}: {out}\n{err}");
        assert!(out.contains("no replies"), "{out}");
    }

    signal(respond.child.id(), "TERM");
    let (code, out, err) = respond.wait(Duration::from_secs(10));
    assert_eq!(code, 0, "{out}\n{err}");
    let last = out.lines().last().unwrap_or_default();
    assert!(
        last.starts_with("respond 1/1: 5 requests (5 ping,"),
        "{out}"
    );
    assert!(
        last.ends_with(
            "signing: 5 signed and 0 unsigned frames accepted; \
             rejected 3 unsigned, 3 with a bad signature, 0 replayed"
        ),
        "{out}"
    );
}

#[test]
fn a_replayed_signed_request_to_mavping_respond_is_refused() {
    // pymavlink signs five requests, then sends the recorded bytes of
    // three of them again: mavping respond answers each request once.
    let port = free_udp_port();
    let respond = start_mavping(&[
        "respond",
        "--signing-key",
        HEX_KEY,
        &format!("udpin:127.0.0.1:{port}"),
    ]);
    let mut pinger = Peer::start(
        "signed_pinger.py",
        &[
            &format!("udpout:127.0.0.1:{port}"),
            "--key",
            HEX_KEY,
            "--count",
            "5",
            "--replay",
            "1,3,4",
        ],
    );
    let truth: Value = serde_json::from_str(&pinger.read_line()).unwrap();
    assert_eq!(truth["replayed"], 3, "{truth}");
    assert_eq!(
        truth["replies"],
        serde_json::json!({"0": 1, "1": 1, "2": 1, "3": 1, "4": 1}),
        "one signed reply per request, none to a replay: {truth}"
    );
    signal(respond.child.id(), "TERM");
    let (code, out, err) = respond.wait(Duration::from_secs(10));
    assert_eq!(code, 0, "{out}\n{err}");
    let last = out.lines().last().unwrap_or_default();
    assert!(
        last.starts_with("respond 1/1: 5 requests (5 ping,") && last.contains(", 5 replies sent,"),
        "{out}"
    );
    assert!(
        last.ends_with(
            "signing: 5 signed and 0 unsigned frames accepted; \
             rejected 0 unsigned, 0 with a bad signature, 3 replayed"
        ),
        "{out}"
    );
}

#[test]
fn bad_signing_options_are_one_line_errors() {
    for (args, needle) in [
        (
            &["--signing-key-file", "/nonexistent/mavping.key", "sim:"][..],
            "--signing-key-file /nonexistent/mavping.key: cannot read it",
        ),
        (
            &["--require-signed", "sim:"][..],
            "--require-signed needs a signing key",
        ),
        (
            &["--signing-key", "k", "--mavlink", "1", "sim:"][..],
            "signing needs MAVLink 2",
        ),
    ] {
        let (code, out, err) = run_mavping(args);
        assert_eq!(code, 2, "{args:?}: {out}\n{err}");
        assert_eq!(err.trim().lines().count(), 1, "{args:?}: {err}");
        assert!(err.contains(needle), "{args:?}: {err}");
    }
    let empty = key_file("empty", "  \n");
    let (code, _, err) = run_mavping(&["--signing-key-file", empty.to_str().unwrap(), "sim:"]);
    std::fs::remove_file(&empty).unwrap();
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("the signing key is empty"), "{err}");
}
