//! The command line: exit codes, errors, signals, reproducible output.

use std::net::UdpSocket;
use std::process::Stdio;
use std::time::Duration;

use crate::common::*;

#[test]
fn help_and_version_exit_zero() {
    let (code, out, _) = run_mavping(&["--help"]);
    assert_eq!(code, 0);
    assert!(
        out.contains("Usage: mavping") && out.contains("CONNECTION"),
        "{out}"
    );
    assert!(out.contains("--count"));
    let (code, out, _) = run_mavping(&["--version"]);
    assert_eq!(code, 0);
    assert!(out.starts_with("mavping "));
}

#[test]
fn bad_connection_strings_exit_2_with_one_line() {
    for bad in [
        "udpout:127.0.0.1",
        "bogus:1:2",
        "udpout:[::1:5",
        "sim:?loss=200%",
        "14550",
    ] {
        let (code, out, err) = run_mavping(&[bad]);
        assert_eq!(code, 2, "{bad}");
        assert!(out.is_empty(), "{bad}: {out}");
        assert_eq!(err.lines().count(), 1, "{bad}: {err}");
        assert!(err.starts_with("mavping: bad connection string"), "{err}");
        assert!(err.contains("accepted forms"), "{err}");
    }
}

#[test]
fn usage_errors_exit_2() {
    for args in [
        &["--sysid", "0", "sim:"][..],
        &["-c", "0", "sim:"],
        &["--rate", "0", "sim:"],
        &[],
    ] {
        let (code, _, err) = run_mavping(args);
        assert_eq!(code, 2, "{args:?}: {err}");
        assert!(!err.contains("panicked"), "{err}");
    }
}

#[test]
fn port_in_use_exits_2_with_the_os_reason() {
    let taken = UdpSocket::bind("127.0.0.1:0").unwrap();
    let port = taken.local_addr().unwrap().port();
    let (code, _, err) = run_mavping(&[&format!("udpin:127.0.0.1:{port}")]);
    assert_eq!(code, 2);
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(
        err.contains("cannot listen on udp 127.0.0.1") && err.contains("in use"),
        "{err}"
    );
}

#[test]
fn unknown_host_exits_2() {
    let (code, _, err) = run_mavping(&["udpout:no-such-host.invalid:14550"]);
    assert_eq!(code, 2);
    assert!(
        err.contains("cannot resolve no-such-host.invalid:14550"),
        "{err}"
    );
}

#[test]
fn silent_peer_exits_1_and_counts_nothing() {
    let silent = UdpSocket::bind("127.0.0.1:0").unwrap();
    let port = silent.local_addr().unwrap().port();
    let (code, out, _) = run_mavping(&[
        "-c",
        "2",
        "-i",
        "0.05",
        "-W",
        "200ms",
        &format!("udpout:127.0.0.1:{port}"),
    ]);
    assert_eq!(code, 1, "{out}");
    assert!(
        out.contains("2 requests sent") && out.contains("no replies"),
        "{out}"
    );
}

#[test]
fn closed_udp_port_is_a_link_failure_with_summary() {
    let port = free_udp_port();
    let (code, out, err) =
        run_mavping(&["-c", "5", "-i", "0.05", &format!("udpout:127.0.0.1:{port}")]);
    assert_eq!(code, 2, "{out}\n{err}");
    assert_eq!(
        err.trim(),
        format!(
            "mavping: nothing listening at 127.0.0.1:{port} (ICMP port unreachable); if the \
             vehicle sends to this port, listen: udp:127.0.0.1:{port}"
        )
    );
    assert!(
        out.contains("mavping statistics"),
        "summary still printed: {out}"
    );
}

#[test]
fn sim_runs_exit_0_and_total_loss_exits_1() {
    let (code, out, _) = run_mavping(&["-c", "3", "-i", "0.01", "-q", "sim:?clock=virtual"]);
    assert_eq!(code, 0, "{out}");
    assert_eq!(text_counts(&out, "1/1").unwrap().received, 3);
    let (code, out, _) = run_mavping(&["-c", "3", "-i", "0.01", "sim:?clock=virtual&loss=100%"]);
    assert_eq!(code, 1, "{out}");
}

#[test]
fn seeded_virtual_sim_output_is_exactly_reproducible() {
    let args = [
        "-c",
        "200",
        "-i",
        "0.01",
        "-W",
        "100ms",
        "sim:?responders=2&loss=5%&dup=2%&reorder=3%&hold=15ms&jitter=4ms&seed=42&clock=virtual",
    ];
    let (code1, first, _) = run_mavping(&args);
    let (code2, second, _) = run_mavping(&args);
    assert_eq!((code1, code2), (0, 0));
    assert_eq!(first, second);
    let c = text_counts(&first, "2/1").unwrap();
    assert_eq!(c.sent, c.received + c.lost);
    assert!(
        c.duplicate > 0 && c.lost > 0 && c.out_of_order > 0,
        "{first}"
    );
}

#[test]
fn ctrl_c_prints_the_summary_and_exits_normally() {
    let child = mavping()
        .args(["-i", "0.05", "sim:?delay=1ms&jitter=0ms"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    std::thread::sleep(Duration::from_millis(600));
    signal(child.id(), "INT");
    let (code, out, err) = wait_output(child, Duration::from_secs(10));
    assert_eq!(code, 0, "{out}\n{err}");
    let c = text_counts(&out, "1/1").expect(&out);
    assert!(c.received >= 5, "{out}");
    assert_eq!(c.sent, c.received + c.lost);
}

/// A UDP socket that reads everything and answers nothing; joined, it
/// tells how many PINGs (MAVLink 2, message 4) it read.
fn silent_peer(listen_for: Duration) -> (u16, std::thread::JoinHandle<u64>) {
    let socket = UdpSocket::bind("127.0.0.1:0").unwrap();
    let port = socket.local_addr().unwrap().port();
    socket.set_read_timeout(Some(listen_for)).unwrap();
    let counting = std::thread::spawn(move || {
        let mut buf = [0u8; 512];
        let mut pings = 0;
        while let Ok(n) = socket.recv(&mut buf) {
            let msgid = (n >= 10 && buf[0] == 0xFD).then(|| buf[7]);
            pings += u64::from(msgid == Some(4));
        }
        pings
    });
    (port, counting)
}

#[test]
fn a_closed_stdout_stops_the_output_not_the_measurement() {
    use std::io::Read;
    let (port, counting) = silent_peer(Duration::from_secs(3));
    let target = format!("udpout:127.0.0.1:{port}");
    let mut child = mavping()
        .args(["-c", "10", "-i", "0.1", "-W", "0.3", &target])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // Read the first line, then close the pipe, like `| head -1`.
    let mut stdout = child.stdout.take().unwrap();
    let mut first = [0u8; 8];
    stdout.read_exact(&mut first).unwrap();
    drop(stdout);
    let (code, _, err) = wait_output(child, Duration::from_secs(30));
    // Nothing answered: the check failed, pipe or no pipe.
    assert_eq!(code, 1, "{err}");
    assert!(err.is_empty(), "{err}");
    assert_eq!(counting.join().unwrap(), 10, "every request went out");
}

#[test]
fn a_closed_stdout_keeps_a_good_run_good() {
    use std::io::Read;
    let mut child = mavping()
        .args(["-i", "0.01", "-c", "100", "sim:?delay=1ms&jitter=0ms"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut stdout = child.stdout.take().unwrap();
    let mut first = [0u8; 8];
    stdout.read_exact(&mut first).unwrap();
    drop(stdout);
    let (code, _, err) = wait_output(child, Duration::from_secs(30));
    assert_eq!(code, 0, "{err}");
    assert!(err.is_empty(), "{err}");
}

/// Runs `mavping ARGS | head -1` in bash; mavping's exit code.
fn piped_to_head(args: &str) -> String {
    let script = format!(
        "{} {args} | head -1 >/dev/null; echo ${{PIPESTATUS[0]}}",
        env!("CARGO_BIN_EXE_mavping")
    );
    let out = std::process::Command::new("timeout")
        .args(["20", "bash", "-c", &script])
        .output()
        .unwrap();
    String::from_utf8_lossy(&out.stdout).trim().to_string()
}

#[test]
fn an_endless_run_ends_when_its_reader_goes_as_ping_does() {
    // The next line after the first meets the closed pipe and ends the
    // run (no -c, -w or sweep); judged on what it measured until then.
    assert_eq!(piped_to_head("-i 0.05 sim:"), "0");
    assert_eq!(piped_to_head("-i 0.05 --expect 9/1 sim:"), "1");
}

#[test]
fn a_full_disk_is_an_error_whatever_the_measurement() {
    let full = || std::fs::File::create("/dev/full").unwrap();
    let (port, counting) = silent_peer(Duration::from_secs(3));
    let silent = format!("udpout:127.0.0.1:{port}");
    for (args, what) in [
        (vec!["-c", "5", "-i", "0.05", "sim:"], "a good run"),
        (
            vec!["-c", "5", "-i", "0.05", "--json", "sim:"],
            "a good run, JSON",
        ),
        (
            vec![
                "-c",
                "5",
                "-i",
                "0.05",
                "-W",
                "0.2",
                "--max-loss",
                "10",
                &silent,
            ],
            "no reply at all",
        ),
    ] {
        let child = mavping()
            .args(&args)
            .stdout(full())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        let (code, _, err) = wait_output(child, Duration::from_secs(30));
        assert_eq!(code, 2, "{what}: {err}");
        assert_eq!(
            err.trim_end(),
            "mavping: cannot write the output: No space left on device (os error 28)",
            "{what}"
        );
    }
    assert_eq!(
        counting.join().unwrap(),
        5,
        "the silent peer's run went to its count"
    );
}

#[test]
fn probe_and_respond_usage_errors_exit_2_with_one_line() {
    for args in [
        &["--probe", "command", "--command", "FLY_TO_MOON", "sim:"][..],
        &["--probe", "command", "--target", "0/1", "sim:"],
        &["--probe", "timesync", "--target", "1/x", "sim:"],
        &["--target", "1/1", "sim:"],
        &["respond", "--drop", "200", "sim:"],
        &["respond", "--sysid", "0", "sim:"],
        &["respond", "bogus:1:2"],
    ] {
        let (code, out, err) = run_mavping(args);
        assert_eq!(code, 2, "{args:?}: {err}");
        assert!(out.is_empty(), "{args:?}: {out}");
        assert_eq!(err.lines().count(), 1, "{args:?}: {err}");
        assert!(err.starts_with("mavping: "), "{args:?}: {err}");
    }
}

#[test]
fn respond_on_a_port_in_use_exits_2() {
    let taken = UdpSocket::bind("127.0.0.1:0").unwrap();
    let port = taken.local_addr().unwrap().port();
    let (code, _, err) = run_mavping(&["respond", &format!("udpin:127.0.0.1:{port}")]);
    assert_eq!(code, 2);
    assert!(err.contains("in use"), "{err}");
}

/// `mavping respond RESPOND_LINK` started 1.5 s before a pinger on
/// `pinger_link` (5 PINGs, `interval` apart, timeout `wait`): the pinger's
/// 5/5 and what respond printed (its exit code, stdout, stderr).
fn respond_before_its_pinger(
    respond_link: &str,
    pinger_link: &str,
    interval: &str,
    wait: &str,
) -> (i32, String, String) {
    let respond = mavping()
        .args(["respond", respond_link])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // Long enough for HEARTBEATs to hit the closed port and draw ICMP, or
    // for a tcp client to be refused several times.
    std::thread::sleep(Duration::from_millis(1500));
    let (code, out, err) = run_mavping(&["-c", "5", "-i", interval, "-W", wait, pinger_link]);
    signal(respond.id(), "TERM");
    let (respond_code, respond_out, respond_err) = wait_output(respond, Duration::from_secs(10));
    assert_eq!(code, 0, "{out}{err}\nrespond: {respond_out}{respond_err}");
    let counts = text_counts(&out, "1/1").expect("1/1 answered");
    assert_eq!((counts.received, counts.lost), (5, 0), "{out}");
    assert!(respond_out.contains("5 replies sent"), "{respond_out}");
    (respond_code, respond_out, respond_err)
}

/// A responder may start before its pinger: the ICMP "port unreachable"
/// its first HEARTBEATs draw must not end it (this raced in a test).
#[test]
fn respond_udpout_outlives_a_pinger_that_is_not_up_yet() {
    let port = free_udp_port();
    respond_before_its_pinger(
        &format!("udpout:127.0.0.1:{port}"),
        &format!("udpin:127.0.0.1:{port}"),
        "50ms",
        "2s",
    );
}

/// The same on `tcp:`: a responder started before the pinger's listener
/// exists waits for it (respond.md promises so), it does not exit at once.
#[test]
fn respond_tcp_waits_for_a_listener_that_is_not_up_yet() {
    let port = free_tcp_port();
    let (respond_code, _, respond_err) = respond_before_its_pinger(
        &format!("tcp:127.0.0.1:{port}"),
        &format!("tcpin:127.0.0.1:{port}"),
        "100ms",
        "5s",
    );
    assert!(
        respond_err.contains("nothing listening yet"),
        "{respond_err}"
    );
    assert_eq!(respond_code, 0, "{respond_err}");
}

#[test]
fn seeded_virtual_timesync_and_command_runs_are_reproducible() {
    for probe in ["timesync", "command"] {
        let args = [
            "--probe",
            probe,
            "-c",
            "100",
            "-i",
            "20ms",
            "sim:?loss=10%&dup=5%&jitter=4ms&offset=2s&drift=-30&seed=9&clock=virtual",
        ];
        let (code1, first, _) = run_mavping(&args);
        let (code2, second, _) = run_mavping(&args);
        assert_eq!((code1, code2), (0, 0), "{first}");
        assert_eq!(first, second);
    }
}
