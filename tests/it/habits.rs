//! What ping, fping and irtt users reach for: -D, -f, -Q and SIGQUIT,
//! --bind, -I, -O; each against `mavping respond` or a real socket.

use std::io::Write;
use std::net::{TcpListener, UdpSocket};
use std::process::Stdio;
use std::time::{Duration, SystemTime, UNIX_EPOCH};

use crate::common::*;

fn respond() -> (Respond, String) {
    let port = free_udp_port();
    let link = format!("udpin:127.0.0.1:{port}");
    (Respond::start(&[&link]), format!("udpout:127.0.0.1:{port}"))
}

fn unix_now() -> f64 {
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .unwrap()
        .as_secs_f64()
}

#[test]
fn dash_d_stamps_every_reply_line_with_unix_time() {
    let (_respond, link) = respond();
    let before = unix_now();
    let (code, out, err) = run_mavping(&["-D", "-c", "3", "-i", "100ms", &link]);
    let after = unix_now();
    assert_eq!(code, 0, "{out}\n{err}");
    let stamps: Vec<f64> = out
        .lines()
        .filter(|l| l.contains("reply from"))
        .map(|l| {
            let stamp = l
                .strip_prefix('[')
                .and_then(|l| l.split_once("] "))
                .unwrap()
                .0;
            let (secs, micros) = stamp.split_once('.').unwrap();
            assert_eq!(micros.len(), 6, "{l}");
            format!("{secs}.{micros}").parse().unwrap()
        })
        .collect();
    assert_eq!(stamps.len(), 3, "{out}");
    assert!(stamps.windows(2).all(|w| w[0] <= w[1]), "{stamps:?}");
    assert!(
        before - 0.1 <= stamps[0] && stamps[2] <= after + 0.1,
        "{stamps:?}"
    );
}

#[test]
fn dash_f_reads_links_from_a_file_and_from_stdin() {
    let (_a, link_a) = respond();
    let (_b, link_b) = respond();
    let file = std::env::temp_dir().join(format!("mavping-links-{}.txt", std::process::id()));
    std::fs::write(
        &file,
        format!("# the radio and the VPN\n{link_a}   # first\n\n"),
    )
    .unwrap();
    let (code, out, err) = run_mavping(&[
        "-q",
        "-c",
        "2",
        "-i",
        "50ms",
        "-f",
        file.to_str().unwrap(),
        &link_b,
    ]);
    std::fs::remove_file(&file).unwrap();
    assert_eq!(code, 0, "{out}\n{err}");
    // Command-line links first, then the file's.
    let headers: Vec<&str> = out.lines().filter(|l| l.starts_with("--- ")).collect();
    assert_eq!(
        headers,
        [
            format!("--- {link_b} mavping statistics ---"),
            format!("--- {link_a} mavping statistics ---")
        ]
    );
    // `-` is standard input.
    let mut child = mavping()
        .args(["-q", "-c", "2", "-i", "50ms", "-f", "-"])
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    writeln!(child.stdin.take().unwrap(), "{link_a}\n# nothing else").unwrap();
    let (code, out, err) = wait_output(child, Duration::from_secs(30));
    assert_eq!(code, 0, "{out}\n{err}");
    let c = text_counts(&out, "1/1").expect(&out);
    assert_eq!((c.sent, c.received), (2, 2), "{out}");
    // A bad line names its line.
    let file = std::env::temp_dir().join(format!("mavping-bad-{}.txt", std::process::id()));
    std::fs::write(&file, "sim:\nudpout:nowhere\n").unwrap();
    let (code, _, err) = run_mavping(&["-f", file.to_str().unwrap()]);
    std::fs::remove_file(&file).unwrap();
    assert_eq!(code, 2);
    assert!(
        err.contains(", line 2: bad connection string 'udpout:nowhere'"),
        "{err}"
    );
}

#[test]
fn dash_q_prints_interim_summaries_in_quiet_mode() {
    let (_respond, link) = respond();
    let (code, out, err) = run_mavping(&["-Q", "300ms", "-c", "10", "-i", "100ms", &link]);
    assert_eq!(code, 0, "{out}\n{err}");
    let interim: Vec<&str> = out.lines().filter(|l| l.starts_with("[0.")).collect();
    assert!(interim.len() >= 2, "{out}");
    assert!(
        interim
            .iter()
            .all(|l| l.contains("] 1/1: ") && l.contains(" sent, ")),
        "{out}"
    );
    assert!(!out.contains("reply from"), "quiet: {out}");
    let c = text_counts(&out, "1/1").expect(&out);
    assert_eq!((c.sent, c.received), (10, 10), "{out}");
    // JSON: interim events, valid against the schema.
    let (code, out, err) =
        run_mavping(&["--json", "-Q", "300ms", "-c", "10", "-i", "100ms", &link]);
    assert_eq!(code, 0, "{out}\n{err}");
    let events = json_lines(&out);
    assert_schema(&events);
    let interim: Vec<_> = events.iter().filter(|e| e["type"] == "interim").collect();
    assert!(interim.len() >= 2, "{out}");
    let first = &interim[0]["responders"][0];
    assert_eq!(
        n(first, "sent"),
        n(first, "received") + n(first, "lost"),
        "{first}"
    );
}

#[test]
fn sigquit_prints_an_interim_summary_and_the_run_goes_on() {
    let (_respond, link) = respond();
    let run = start_mavping(&["-c", "20", "-i", "50ms", &link]);
    std::thread::sleep(Duration::from_millis(500));
    signal(run.child.id(), "QUIT");
    let (code, out, err) = run.wait(Duration::from_secs(30));
    assert_eq!(code, 0, "{out}\n{err}");
    let interim: Vec<&str> = out
        .lines()
        .filter(|l| l.starts_with('[') && l.contains("] 1/1: "))
        .collect();
    assert_eq!(interim.len(), 1, "{out}");
    let c = text_counts(&out, "1/1").expect(&out);
    assert_eq!((c.sent, c.received), (20, 20), "the run went on: {out}");
}

#[test]
fn signals_reach_a_fast_schedule_that_sleeps_on_its_own_clock() {
    // At 2,000/s on UDP the session sleeps between sends outside the
    // runtime (clock_nanosleep): SIGQUIT and Ctrl-C must still be heard.
    let (_respond, link) = respond();
    let run = start_mavping(&["--rate", "2000", &link]);
    std::thread::sleep(Duration::from_millis(500));
    signal(run.child.id(), "QUIT");
    std::thread::sleep(Duration::from_millis(300));
    signal(run.child.id(), "INT");
    let (code, out, err) = run.wait(Duration::from_secs(30));
    assert_eq!(code, 0, "{out}\n{err}");
    let interim = out
        .lines()
        .filter(|l| l.starts_with('[') && l.contains("] 1/1: "))
        .count();
    assert_eq!(interim, 1, "{out}");
    let c = text_counts(&out, "1/1").expect(&out);
    assert!(c.received > 100, "{out}");
    assert_eq!(c.sent, c.received + c.lost, "{out}");
}

#[test]
fn bind_sends_from_the_local_address_given() {
    let server = UdpSocket::bind("127.0.0.1:0").unwrap();
    server
        .set_read_timeout(Some(Duration::from_secs(10)))
        .unwrap();
    let to = server.local_addr().unwrap();
    let from_port = free_udp_port();
    let (code, out, err) = run_mavping(&[
        "-c",
        "1",
        "-W",
        "200ms",
        "--bind",
        &format!("127.0.0.1:{from_port}"),
        &format!("udpout:{to}"),
    ]);
    assert_eq!(code, 1, "nothing answers: {out}\n{err}");
    let mut buf = [0u8; 512];
    let (_, from) = server.recv_from(&mut buf).unwrap();
    assert_eq!(from.port(), from_port);
    // TCP too.
    let listener = TcpListener::bind("127.0.0.1:0").unwrap();
    let to = listener.local_addr().unwrap();
    let from_port = free_tcp_port();
    let run = start_mavping(&[
        "-c",
        "1",
        "-W",
        "200ms",
        "--bind",
        &format!("127.0.0.1:{from_port}"),
        &format!("tcp:{to}"),
    ]);
    let (_stream, from) = listener.accept().unwrap();
    assert_eq!(from.port(), from_port);
    drop(run);
    // A listening link names its own address.
    let (code, _, err) = run_mavping(&["--bind", "127.0.0.1", "udpin:127.0.0.1:0"]);
    assert_eq!(code, 2);
    assert!(
        err.contains("--bind 127.0.0.1: only links that send first"),
        "{err}"
    );
}

#[cfg(not(mavping_portable))]
#[test]
fn dash_i_ties_the_link_to_an_interface_and_says_what_it_needs() {
    let (_respond, link) = respond();
    let (code, out, err) = run_mavping(&["-I", "lo", "-q", "-c", "2", "-i", "50ms", &link]);
    assert_eq!(code, 0, "{out}\n{err}");
    let c = text_counts(&out, "1/1").expect(&out);
    assert_eq!((c.sent, c.received), (2, 2), "{out}");
    let (code, _, err) = run_mavping(&["-I", "nosuch0", "-c", "1", &link]);
    assert_eq!(code, 2);
    assert_eq!(err.trim(), "mavping: -I nosuch0: no such network interface");
    // Unprivileged: since Linux 5.7 a socket not yet bound may be tied
    // to an interface without CAP_NET_RAW (older kernels refuse, and the
    // error says what is needed: a unit test in transport/route.rs).
    let as_root =
        std::os::unix::fs::MetadataExt::uid(&std::fs::metadata("/proc/self").unwrap()) == 0;
    let mut cmd = if as_root {
        let mut c = std::process::Command::new("setpriv");
        c.args(["--reuid=65534", "--regid=65534", "--clear-groups"])
            .arg(env!("CARGO_BIN_EXE_mavping"));
        c
    } else {
        mavping()
    };
    let child = cmd
        .args(["-I", "lo", "-q", "-c", "1", &link])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("setpriv (util-linux) runs mavping as nobody");
    let (code, out, err) = wait_output(child, Duration::from_secs(30));
    assert_eq!(code, 0, "{out}\n{err}");
}

/// The portable path (Windows, macOS, `--features portable`) cannot tie a
/// socket to an interface: one line, exit 2, before any link opens.
#[cfg(mavping_portable)]
#[test]
fn dash_i_is_refused_in_one_line_on_the_portable_path() {
    let (code, out, err) = run_mavping(&["-I", "lo", "-c", "1", "udpout:127.0.0.1:14550"]);
    assert_eq!(code, 2, "{out}\n{err}");
    assert_eq!(
        err.trim(),
        "mavping: -I lo: tying a socket to a network interface needs Linux (SO_BINDTODEVICE); \
         this build has the portable path only: choose the route by address (--bind ADDR, \
         udpin:ADDR:PORT)"
    );
    assert!(out.is_empty(), "{out}");
}

#[test]
fn dash_o_is_accepted_for_ping_users() {
    let (code, out, err) = run_mavping(&["-O", "-c", "1", "sim:?clock=virtual"]);
    assert_eq!(code, 0, "{out}\n{err}");
}

#[test]
fn mavping_log_takes_target_level_lists_and_falls_back_on_nonsense() {
    let port = UdpSocket::bind("127.0.0.1:0").unwrap();
    let link = format!("udpout:{}", port.local_addr().unwrap());
    let run = |spec: &str| {
        let child = mavping()
            .env("MAVPING_LOG", spec)
            .args(["-c", "1", "-W", "100ms", &link])
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        let (code, out, err) = wait_output(child, Duration::from_secs(60));
        assert_eq!(code, 1, "MAVPING_LOG={spec}\n{out}\n{err}");
        err
    };
    // The UDP link logs the receive buffer it was granted at info.
    let granted = "udp receive buffer granted";
    assert!(run("mavping::transport::udp=info").contains(granted));
    assert!(run("warn,mavping::transport=debug").contains(granted));
    assert!(!run("mavping::transport::udp=warn").contains(granted));
    // Not a list: the default (warnings only), as with no MAVPING_LOG.
    assert!(!run("=[nonsense").contains(granted));
}
