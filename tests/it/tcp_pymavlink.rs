//! mavping over TCP against pymavlink: as a client of a pymavlink `tcpin:`
//! server, and as a `tcpin:` server with pymavlink clients.

use std::time::Duration;

use crate::common::*;

#[test]
fn tcp_client_counts_a_pymavlink_server_exactly() {
    let port = free_tcp_port();
    let responder = Peer::start(
        "responder.py",
        &[&format!("tcpin:127.0.0.1:{port}"), "--drop", "2,5"],
    );
    let (code, out, err) = run_mavping(&[
        "-c",
        "8",
        "-i",
        "0.05",
        "-W",
        "300ms",
        &format!("tcp:127.0.0.1:{port}"),
    ]);
    assert_eq!(code, 0, "{out}\n{err}");
    let c = text_counts(&out, "1/1").expect(&out);
    assert_eq!(
        (c.sent, c.received, c.lost, c.duplicate),
        (8, 6, 2, 0),
        "{out}"
    );
    let truth = responder.finish();
    assert_eq!(truth["ping_requests"], 8);
    assert_eq!(truth["replies"], 6);
}

#[test]
fn tcpin_pings_every_client_and_counts_each_exactly() {
    let port = free_tcp_port();
    let run = start_mavping(&[
        "-c",
        "60",
        "-i",
        "0.05",
        "-W",
        "300ms",
        &format!("tcpin:127.0.0.1:{port}"),
    ]);
    assert!(
        run.first_line.starts_with("MAVPING tcpin:"),
        "{}",
        run.first_line
    );
    let client = format!("tcp:127.0.0.1:{port}");
    // Both connect within the first requests (Python starts in about a
    // second on a busy machine, 20 requests); the drops come well after.
    let a = Peer::start(
        "responder.py",
        &[&client, "--sysid", "1", "--drop", "40,42"],
    );
    let b = Peer::start(
        "responder.py",
        &[&client, "--sysid", "2", "--drop", "45", "--dup", "47"],
    );
    let (code, out, err) = run.wait(Duration::from_secs(20));
    assert_eq!(code, 0, "{out}\n{err}");
    let (ta, tb) = (a.finish(), b.finish());
    let ca = text_counts(&out, "1/1").expect(&out);
    let cb = text_counts(&out, "2/1").expect(&out);
    // Each responder's window starts at its first answer, so its sent
    // requests are exactly those it answered plus those it dropped.
    assert_eq!(ca.received, ta["replies"].as_u64().unwrap(), "{out}");
    assert_eq!((ca.lost, ca.duplicate), (2, 0), "{out}");
    assert_eq!(ca.sent, ca.received + 2, "{out}");
    assert_eq!(cb.received, tb["replies"].as_u64().unwrap(), "{out}");
    assert_eq!((cb.lost, cb.duplicate), (1, 1), "{out}");
    assert!(ca.received >= 30 && cb.received >= 30, "{out}");
}

#[test]
fn refused_connection_exits_2_with_the_os_reason() {
    let port = free_tcp_port();
    let (code, out, err) = run_mavping(&[&format!("tcpout:127.0.0.1:{port}")]);
    assert_eq!(code, 2, "{out}\n{err}");
    assert!(out.is_empty(), "{out}");
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(
        err.contains(&format!("cannot open tcp:127.0.0.1:{port}"))
            && err.contains("Connection refused"),
        "{err}"
    );
}

#[test]
fn server_going_away_ends_the_run_with_the_summary_and_exit_2() {
    let port = free_tcp_port();
    let mut responder = Peer::start("responder.py", &[&format!("tcpin:127.0.0.1:{port}")]);
    let run = start_mavping(&[
        "-i",
        "0.05",
        "-W",
        "300ms",
        &format!("tcp:127.0.0.1:{port}"),
    ]);
    std::thread::sleep(Duration::from_millis(600));
    responder.kill();
    let (code, out, err) = run.wait(Duration::from_secs(10));
    assert_eq!(code, 2, "{out}\n{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
    // Killed with our requests unread, the server's kernel may answer RST.
    assert!(
        err.contains(&format!("tcp:127.0.0.1:{port}: closed by the peer"))
            || err.contains("Connection reset by peer"),
        "{err}"
    );
    let c = text_counts(&out, "1/1").expect(&out);
    assert!(c.received >= 5, "{out}");
    assert_eq!(c.sent, c.received + c.lost, "{out}");
}

#[test]
fn reconnect_carries_on_when_the_server_comes_back() {
    let port = free_tcp_port();
    let server = format!("tcpin:127.0.0.1:{port}");
    let mut first = Peer::start("responder.py", &[&server]);
    let run = start_mavping(&[
        "--reconnect",
        "-i",
        "0.05",
        "-W",
        "200ms",
        "-w",
        "3s",
        &format!("tcp:127.0.0.1:{port}"),
    ]);
    std::thread::sleep(Duration::from_millis(700));
    first.kill();
    std::thread::sleep(Duration::from_millis(500));
    let second = Peer::start("responder.py", &[&server]);
    let (code, out, err) = run.wait(Duration::from_secs(15));
    assert_eq!(code, 0, "{out}\n{err}");
    assert!(
        err.contains(&format!("mavping: tcp:127.0.0.1:{port} lost ("))
            && err.contains("; reconnecting (attempt 1 in 100ms)"),
        "{err}"
    );
    assert!(err.contains("reconnected after"), "{err}");
    assert!(out.contains("while reconnecting"), "downtime shown: {out}");
    let c = text_counts(&out, "1/1").expect(&out);
    assert!(c.lost >= 5, "pings sent while down are lost: {out}");
    assert_eq!(c.sent, c.received + c.lost, "{out}");
    // The new server answered requests sent after it came back.
    let truth = second.finish();
    assert!(truth["replies"].as_u64().unwrap() >= 10, "{truth}");
}
