//! A link whose peer stops reading: a pty nobody reads, a TCP peer that
//! accepts and never reads. Writes that cannot complete must never block
//! the run: `-w` and Ctrl-C end it with a summary, requests the link
//! refused are counted as not sent (never as lost), and the schedule line
//! says what the link took.

use std::io::Read;
use std::net::TcpListener;
use std::time::Duration;

use crate::common::*;

#[test]
fn a_pty_nobody_reads_ends_on_the_deadline_with_what_it_took() {
    let mut pty = Peer::start("stuck_pty.py", &[]);
    let device = format!("serial:{}:57600", pty.read_line());
    // 2000/s for 3 s: far more than the pty's buffer holds.
    let (code, out, err) = run_mavping(&["--json", "-i", "0.0005", "-w", "3", &device]);
    assert_eq!(code, 1, "no reply is a failed check, not a hang: {err}");
    let s = checked_summary(&out);
    let schedule = &s["schedule"];
    let not_sent = schedule["not_sent"].as_u64().unwrap();
    let sent = s["requests"].as_u64().unwrap();
    assert!(not_sent > 0, "{schedule}");
    assert!(sent > 0, "the pty took what its buffer holds: {s}");
    assert!(
        schedule["achieved_rate_hz"].as_f64().unwrap()
            < schedule["requested_rate_hz"].as_f64().unwrap(),
        "{schedule}"
    );
    let codes: Vec<&str> = s["hints"]
        .as_array()
        .unwrap()
        .iter()
        .map(|h| h["code"].as_str().unwrap())
        .collect();
    assert_eq!(codes.first(), Some(&"link_not_reading"), "{codes:?}");

    // The same in text: the schedule line tells the truth.
    let (code, out, _) = run_mavping(&["-q", "-i", "0.0005", "-w", "2", &device]);
    assert_eq!(code, 1);
    let line = out
        .lines()
        .find(|l| l.starts_with("schedule:"))
        .expect(&out);
    assert!(
        line.contains("requests not sent: it is not reading"),
        "{line}"
    );
    pty.kill();
}

#[test]
fn one_ctrl_c_ends_a_stalled_serial_run_with_its_summary() {
    let mut pty = Peer::start("stuck_pty.py", &[]);
    let device = format!("serial:{}:57600", pty.read_line());
    let run = start_mavping(&["-i", "0.0005", &device]);
    std::thread::sleep(Duration::from_millis(1500));
    signal(run.child.id(), "INT");
    let (code, out, err) = run.wait(Duration::from_secs(20));
    assert_eq!(code, 1, "one Ctrl-C is a normal end, not 130: {err}");
    assert!(out.contains("mavping statistics"), "{out}");
    assert!(out.contains("not sent"), "{out}");
    pty.kill();
}

#[test]
fn a_tcp_peer_that_stops_reading_cannot_hold_the_run() {
    let listener = TcpListener::bind("127.0.0.1:0").unwrap();
    let port = listener.local_addr().unwrap().port();
    // Accepts, then never reads, holding the connection open.
    let holder = std::thread::spawn(move || {
        let (mut conn, _) = listener.accept().unwrap();
        std::thread::sleep(Duration::from_secs(8));
        let mut sink = Vec::new();
        let _ = conn.read_to_end(&mut sink);
    });
    let link = format!("tcp:127.0.0.1:{port}");
    let run = start_mavping(&["--json", "-i", "0.0001", &link]);
    std::thread::sleep(Duration::from_secs(2));
    signal(run.child.id(), "INT");
    let (code, out, err) = run.wait(Duration::from_secs(20));
    assert_eq!(code, 1, "{err}");
    let s = checked_summary(&out);
    assert!(s["interrupted"].as_bool().unwrap(), "{s}");
    assert!(s["requests"].as_u64().unwrap() > 0, "{s}");
    holder.join().unwrap();
}
