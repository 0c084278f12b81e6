//! WebSocket links against real peers: pymavlink's own `wsserver:` and
//! `ws:` client (wsproto), socat's `OPENSSL-LISTEN` as the TLS terminator
//! in front of it for `wss://`, `mavping respond` on `wsin:`, and a
//! wsproto server that refuses, closes and sends text on request
//! (`tests/peers/ws_peer.py`). Exact counts; each failure one line and
//! exit 2.

use std::net::TcpStream;
use std::process::{Child, Command, Stdio};
use std::time::Duration;

use serde_json::Value;

use crate::common::*;
use crate::serve_secure::Pki;

/// A pymavlink responder serving WebSocket on a free port, with `args`.
fn wsserver(args: &[&str]) -> (Peer, u16) {
    let port = free_tcp_port();
    let conn = format!("wsserver:127.0.0.1:{port}");
    let mut all = vec![conn.as_str()];
    all.extend_from_slice(args);
    (Peer::start("responder.py", &all), port)
}

/// The responder's counts in a JSON run's summary.
fn counts(out: &str) -> Value {
    let summary = checked_summary(out);
    responder(&summary, "1/1").clone()
}

fn n(v: &Value, key: &str) -> u64 {
    v[key].as_u64().unwrap_or_else(|| panic!("{key} in {v}"))
}

#[test]
fn pymavlinks_wsserver_is_pinged_over_ws_with_exact_counts() {
    let (peer, port) = wsserver(&["--drop", "3,7", "--dup", "5"]);
    let link = format!("ws://127.0.0.1:{port}/");
    let (code, out, err) = run_mavping(&["-c", "10", "-i", "50ms", "-W", "500ms", "--json", &link]);
    let truth = peer.finish();
    assert_eq!(code, 0, "{out}{err}");
    let r = counts(&out);
    assert_eq!(n(&truth, "ping_requests"), 10);
    assert_eq!(
        (n(&r, "sent"), n(&r, "received")),
        (10, n(&truth, "replies"))
    );
    assert_eq!(n(&r, "lost"), n(&truth, "dropped"));
    assert_eq!(n(&r, "duplicate"), n(&truth, "duplicated"));
}

/// socat terminating TLS on a free port in front of `to`, with the
/// server certificate of `pki`; killed when dropped.
struct Terminator(Child, u16);

impl Terminator {
    fn start(pki: &Pki, to: u16) -> Terminator {
        let port = free_tcp_port();
        let mut child = Command::new("socat")
            .arg(format!(
                "OPENSSL-LISTEN:{port},reuseaddr,fork,verify=0,cert={},key={}",
                pki.path("server.pem"),
                pki.path("server.key")
            ))
            .arg(format!("TCP:127.0.0.1:{to}"))
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .expect("socat (scripts/test.sh installs it)");
        // Listening once a connection is taken.
        for _ in 0..100 {
            if TcpStream::connect(("127.0.0.1", port)).is_ok() {
                return Terminator(child, port);
            }
            std::thread::sleep(Duration::from_millis(50));
        }
        let _ = child.kill();
        let _ = child.wait();
        panic!("socat never listened on {port}");
    }
}

impl Drop for Terminator {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

#[test]
fn wss_through_a_tls_terminator_verifies_the_server_against_cacert() {
    let pki = Pki::make("wss");
    let (peer, port) = wsserver(&["--drop", "2"]);
    let tls = Terminator::start(&pki, port);
    let link = format!("wss://localhost:{}/", tls.1);
    let ca = pki.path("ca.pem");
    let (code, out, err) = run_mavping(&[
        "-c", "6", "-i", "50ms", "-W", "500ms", "--json", "--cacert", &ca, &link,
    ]);
    assert_eq!(code, 0, "{out}{err}");
    let r = counts(&out);
    assert_eq!((n(&r, "received"), n(&r, "lost")), (5, 1));
    // The system's roots do not know our CA: refused, one line, exit 2.
    let (code, out, err) = run_mavping(&["-c", "2", &link]);
    assert_eq!(code, 2, "{out}{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(
        err.contains(
            "the server's certificate does not verify: signed by a CA this machine does not trust"
        ),
        "{err}"
    );
    // Another CA's certificate file is no better.
    let other = pki.path("other-ca.pem");
    let (code, _, err) = run_mavping(&["-c", "2", "--cacert", &other, &link]);
    assert_eq!(code, 2);
    assert!(err.contains("does not verify"), "{err}");
    let truth = peer.finish();
    assert_eq!(n(&truth, "ping_requests"), 6, "{truth}");
}

#[test]
fn a_refused_handshake_is_one_line_and_credentials_from_the_url_pass() {
    let port = free_tcp_port().to_string();
    let peer = Peer::start("ws_peer.py", &[&port, "--auth", "pilot:s3cret"]);
    let bare = format!("ws://127.0.0.1:{port}/");
    let (code, out, err) = run_mavping(&["-c", "2", &bare]);
    assert_eq!(code, 2, "{out}");
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(
        err.contains("HTTP 401 Unauthorized: the server wants credentials"),
        "{err}"
    );
    let with = format!("ws://pilot:s3cret@127.0.0.1:{port}/");
    let (code, out, err) = run_mavping(&["-c", "3", "-i", "50ms", "--json", &with]);
    assert_eq!(code, 0, "{out}{err}");
    assert_eq!(n(&counts(&out), "received"), 3);
    // The password reaches the server, never a report.
    assert!(!out.contains("s3cret") && !err.contains("s3cret"), "{out}");
    assert!(out.contains("ws://pilot:***@127.0.0.1"), "{out}");
    let truth = peer.finish();
    assert_eq!(truth["authorization"][1], "Basic cGlsb3Q6czNjcmV0");
    assert_eq!((n(&truth, "refused"), n(&truth, "accepted")), (1, 1));
}

#[test]
fn a_text_message_or_a_close_ends_the_run_after_counting_what_came() {
    for (arg, says) in [
        (
            "--text-after",
            "text message where MAVLink's binary frames were expected",
        ),
        ("--close-after", "closed by the peer (1001: going away)"),
    ] {
        let port = free_tcp_port().to_string();
        let peer = Peer::start("ws_peer.py", &[&port, arg, "3"]);
        let link = format!("ws://127.0.0.1:{port}/");
        let (code, out, err) =
            run_mavping(&["-c", "8", "-i", "50ms", "-W", "500ms", "--json", &link]);
        let truth = peer.finish();
        assert_eq!(code, 2, "{arg}: {out}{err}");
        assert_eq!(err.lines().count(), 1, "{err}");
        assert!(err.contains(says), "{err}");
        // Every reply sent before it was counted.
        let r = counts(&out);
        assert_eq!(n(&r, "received"), n(&truth, "replies"), "{arg}: {r}");
        assert_eq!(n(&truth, "replies"), 3);
    }
}

#[test]
fn a_server_that_dies_mid_run_is_one_line_and_exit_2() {
    let (mut peer, port) = wsserver(&[]);
    let link = format!("ws://127.0.0.1:{port}/");
    let run = start_mavping(&["-i", "50ms", "--json", &link]);
    std::thread::sleep(Duration::from_millis(600));
    peer.kill();
    let (code, out, err) = run.wait(Duration::from_secs(30));
    assert_eq!(code, 2, "{out}{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(err.contains(&link), "{err}");
    assert!(n(&counts(&out), "received") > 0, "{out}");
}

#[test]
fn respond_on_wsin_answers_over_ws_and_pymavlinks_ws_client_is_pinged_by_wsin() {
    let port = free_tcp_port();
    let listen = format!("wsin:127.0.0.1:{port}");
    let responder = Respond::start(&["--drop", "20", "--seed", "3", &listen]);
    let link = format!("ws://127.0.0.1:{port}/");
    let (code, out, err) = run_mavping(&["-c", "30", "-i", "20ms", "-W", "500ms", "--json", &link]);
    let (_, respond_counts) = responder.finish();
    assert_eq!(code, 0, "{out}{err}");
    let r = counts(&out);
    // respond's counts: requests, ping, timesync, command, retransmissions,
    // replies sent, dropped, duplicated.
    assert_eq!(n(&r, "sent"), respond_counts[1]);
    assert_eq!(n(&r, "lost"), respond_counts[6], "{r} {respond_counts:?}");
    assert!(respond_counts[6] > 0);

    // mavping listens; pymavlink's ws: client connects and answers.
    let port = free_tcp_port();
    let listen = format!("wsin:127.0.0.1:{port}");
    let run = start_mavping(&["-c", "5", "-i", "50ms", "--json", "--wait", "20s", &listen]);
    let client = format!("ws:127.0.0.1:{port}");
    let peer = Peer::start("responder.py", &[&client]);
    let (code, out, err) = run.wait(Duration::from_secs(30));
    let truth = peer.finish();
    assert_eq!(code, 0, "{out}{err}");
    assert_eq!(n(&counts(&out), "received"), 5);
    assert_eq!(n(&truth, "replies"), 5);
}

#[test]
fn bad_websocket_strings_are_one_line_and_exit_2() {
    for (link, says) in [
        ("ws://127.0.0.1:0/", "not a port"),
        ("wss://:443/", "missing host"),
        ("ws://u:%zz@h/", "bad %-escape"),
    ] {
        let (code, _, err) = run_mavping(&["-c", "1", link]);
        assert_eq!(code, 2, "{link}: {err}");
        assert_eq!(err.lines().count(), 1, "{err}");
        assert!(err.contains(says), "{link}: {err}");
    }
    // Nothing listening: refused at once.
    let port = free_tcp_port();
    let (code, _, err) = run_mavping(&["-c", "1", &format!("ws://127.0.0.1:{port}/")]);
    assert_eq!(code, 2, "{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
}

#[test]
fn hop_by_hop_the_same_vehicle_direct_and_over_websocket_in_one_run() {
    let (udp, ws) = (free_udp_port(), free_tcp_port());
    let links = [
        format!("udpin:127.0.0.1:{udp}"),
        format!("wsin:127.0.0.1:{ws}"),
    ];
    let respond = Respond::start(&["--stream", "ATTITUDE@20", &links[0], &links[1]]);
    let direct = format!("udpout:127.0.0.1:{udp}");
    let over_ws = format!("ws://127.0.0.1:{ws}/");
    let (code, out, err) = run_mavping(&[
        "-c", "20", "-i", "50ms", "-W", "500ms", "--json", &direct, &over_ws,
    ]);
    respond.finish();
    assert_eq!(code, 0, "{out}{err}");
    let lines = json_lines(&out);
    assert_schema(&lines);
    // Each link its round trips...
    for link in [&direct, &over_ws] {
        let summary = lines
            .iter()
            .find(|l| l["type"] == "summary" && l["link"] == link.as_str())
            .unwrap_or_else(|| panic!("no summary of {link}: {out}"));
        assert_eq!(n(responder(summary, "1/1"), "received"), 20, "{link}");
    }
    // ...and the same frames heard on both, paired: the WebSocket's lag.
    let pair = lines
        .iter()
        .find(|l| l["type"] == "pair_summary")
        .unwrap_or_else(|| panic!("no pair report: {out}"));
    let text = pair.to_string();
    assert!(text.contains(&over_ws) && text.contains(&direct), "{text}");
}
