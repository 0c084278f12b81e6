//! Hostile input on real sockets and ptys, with exact counts afterwards:
//! bad CRCs, unknown ids, lying lengths, signed frames without a key,
//! v1/v2 mixed, wrong echoed time_usec, seqs never sent, spoofed ids,
//! frames split and truncated across serial reads, a flood of foreign
//! traffic; and the simulated link's outage and delay spikes.

use std::net::UdpSocket;
use std::process::Stdio;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::Arc;
use std::time::Duration;

use crate::common::*;
use mavping::frame::{encode, Header, Msg, RadioStatus, StreamScanner, Version};
use serde_json::Value;

#[test]
fn hostile_udp_peer_costs_no_reply_and_every_rejection_is_counted() {
    let port = free_udp_port();
    let peer = Peer::start("hostile_peer.py", &["--port", &port.to_string()]);
    let (code, out, err) = run_mavping(&[
        "--json",
        "-q",
        "-c",
        "60",
        "-i",
        "10ms",
        "-W",
        "2s",
        &format!("udpout:127.0.0.1:{port}"),
    ]);
    let truth = peer.finish();
    assert!(code == 0 || code == 1, "{err}");
    let s = summary_of(&out);
    let t = |k: &str| n(&truth, k);
    assert_eq!(t("requests"), 60, "{truth}");
    assert_eq!(n(&s, "requests"), 60);
    assert_eq!(n(&s, "in_flight"), 0);

    // The real responder: every reply counted once, in time, whatever
    // came with it (signed without our key, v1 or v2, behind a lying length).
    let r = responder(&s, "1/1");
    assert_eq!(
        (
            n(r, "sent"),
            n(r, "received"),
            n(r, "lost"),
            n(r, "late"),
            n(r, "duplicate")
        ),
        (60, 60, 0, 0, 0),
        "{r}"
    );
    assert!(t("signed") > 0 && t("v1") > 0 && t("lying") > 0);
    // Wrong echoed time_usec and seqs never sent: stale, never measured.
    assert_eq!(n(r, "stale"), t("wrong_time") + t("unsent_seq"), "{r}");
    assert_eq!(r["rtt_us"]["count"].as_u64().unwrap_or(60), 60);

    // A spoofed id with a forged reply: stale for that id, nothing received.
    let spoofed = responder(&s, "7/1");
    assert_eq!(
        (n(spoofed, "received"), n(spoofed, "stale")),
        (0, t("spoofed")),
        "{spoofed}"
    );

    // The scanner's figures, exactly.
    let f = &s["frames"];
    assert_eq!(n(f, "bad_crc"), t("bad_crc"), "{f} {truth}");
    assert!(t("damaged") > 0, "{truth}");
    assert_eq!(n(f, "damaged"), t("damaged"), "{f} {truth}");
    assert_eq!(n(f, "unknown_id"), t("unknown_id"), "{f} {truth}");
    assert_eq!(n(f, "skipped_bytes"), t("skipped_bytes"), "{f} {truth}");
    assert_eq!(n(f, "truncated"), 0, "{f}");
    assert_eq!(
        n(f, "frames"),
        t("replies") + t("wrong_time") + t("unsent_seq") + t("spoofed"),
        "{f} {truth}"
    );
}

#[test]
#[allow(
    clippy::many_single_char_names,
    reason = "a, b: the pty's two ends; s, t, r: summary, truth, responder"
)]
fn hostile_serial_peer_frames_split_and_truncated_across_reads() {
    let mut bridge = Peer::start("pty_bridge.py", &[]);
    let line = bridge.read_line();
    let (a, b) = line.split_once(' ').expect("two pty paths");
    let log = std::env::temp_dir().join(format!("mavping-hostile-{}.bin", std::process::id()));
    let _ = std::fs::remove_file(&log);
    let peer = Peer::start(
        "hostile_peer.py",
        &["--serial", b, "--log", log.to_str().unwrap()],
    );
    let (code, out, err) = run_mavping(&[
        "--json",
        "-q",
        "-c",
        "30",
        "-i",
        "30ms",
        // Short: a reply held back behind a lying length (waiting for the
        // 263 bytes it claims) would come late and count lost.
        "-W",
        "150ms",
        &format!("serial:{a}:57600"),
    ]);
    let truth = peer.finish();
    assert!(code == 0 || code == 1, "{err}");
    let s = summary_of(&out);
    let t = |k: &str| n(&truth, k);
    assert_eq!(t("requests"), 30, "{truth}");
    assert!(t("truncated_sent") > 0 && t("signed") > 0 && t("v1") > 0 && t("lying") > 0);
    let r = responder(&s, "1/1");
    assert_eq!(
        (
            n(r, "sent"),
            n(r, "received"),
            n(r, "lost"),
            n(r, "late"),
            n(r, "duplicate")
        ),
        (30, 30, 0, 0, 0),
        "{r}"
    );
    assert_eq!(n(r, "stale"), t("wrong_time") + t("unsent_seq"), "{r}");
    assert_eq!(n(responder(&s, "7/1"), "stale"), t("spoofed"));
    // Whatever the read splits were, the stream's figures are those of the
    // whole byte stream scanned at once (split-invariance, proved by the
    // property tests), and the junk is all accounted for.
    let bytes = std::fs::read(&log).unwrap();
    let _ = std::fs::remove_file(&log);
    let mut scanner = StreamScanner::new();
    let mut frames = 0u64;
    scanner.push(&bytes, &mut |_| frames += 1);
    let f = &s["frames"];
    assert_eq!(n(f, "frames"), frames, "{f}");
    assert_eq!(
        n(f, "frames"),
        t("replies") + t("wrong_time") + t("unsent_seq") + t("spoofed")
    );
    assert_eq!(n(f, "bad_crc"), scanner.stats.bad_crc, "{f}");
    assert_eq!(n(f, "damaged"), scanner.stats.damaged, "{f}");
    assert!(n(f, "bad_crc") >= t("bad_crc"), "{f} {truth}");
    assert_eq!(n(f, "unknown_id"), scanner.stats.unknown_id, "{f}");
    assert_eq!(n(f, "skipped_bytes"), scanner.stats.skipped_bytes, "{f}");
    drop(bridge);
}

/// Pre-encoded foreign traffic: HEARTBEATs and RADIO_STATUS from 200
/// other systems, their PING requests (targets 0/0) and PING replies to
/// another GCS (9/9), ten frames a datagram.
fn flood_datagrams() -> (Vec<Vec<u8>>, u64) {
    let mut datagrams = Vec::new();
    let mut foreign_replies = 0;
    for d in 0..200u32 {
        let mut data = Vec::new();
        for k in 0..10u32 {
            let sysid = 20 + (d % 200) as u8;
            let header = Header {
                sysid,
                compid: 1,
                seq: k as u8,
            };
            let msg = match k % 4 {
                0 => Msg::Heartbeat {
                    mav_type: 2,
                    autopilot: 3,
                },
                1 => Msg::Ping {
                    time_usec: u64::from(d * 10 + k),
                    seq: d,
                    target_system: 0,
                    target_component: 0,
                },
                2 => {
                    foreign_replies += 1;
                    Msg::Ping {
                        time_usec: u64::from(d),
                        seq: d,
                        target_system: 9,
                        target_component: 9,
                    }
                }
                _ => Msg::RadioStatus(RadioStatus {
                    rssi: 100,
                    remrssi: 100,
                    txbuf: 50,
                    noise: 10,
                    remnoise: 10,
                    rxerrors: 0,
                    fixed: 0,
                }),
            };
            encode(&mut data, Version::V2, header, &msg);
        }
        datagrams.push(data);
    }
    (datagrams, foreign_replies)
}

#[test]
fn flood_of_foreign_traffic_leaves_the_responders_counts_exact() {
    use std::io::{BufRead, BufReader, Read};

    let port = free_udp_port();
    // mavping listens; `mavping respond` and the flood both send to it.
    let mut ping = mavping()
        .args([
            "--json",
            // PING to everyone: the flood's systems would draw TIMESYNC
            // under auto, which respond answers too (its own counts).
            "--probe",
            "ping",
            "-c",
            "300",
            "-i",
            "5ms",
            "-W",
            "3s",
            "--expect",
            "1/1",
            &format!("udpin:127.0.0.1:{port}"),
        ])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut respond = mavping()
        .args(["respond", &format!("udpout:127.0.0.1:{port}")])
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let stop = Arc::new(AtomicBool::new(false));
    let sent = Arc::new(AtomicU64::new(0));
    let start_flood = || {
        let (stop, sent) = (stop.clone(), sent.clone());
        std::thread::spawn(move || {
            let (datagrams, _) = flood_datagrams();
            let sock = UdpSocket::bind("127.0.0.1:0").unwrap();
            // ~50,000 messages/s: 5,000 datagrams of 10 a second, in bursts
            // of 50 datagrams every 10 ms.
            let mut i = 0;
            while !stop.load(Ordering::Relaxed) {
                for _ in 0..50 {
                    let _ = sock.send_to(&datagrams[i % datagrams.len()], ("127.0.0.1", port));
                    i += 1;
                }
                sent.fetch_add(500, Ordering::Relaxed);
                std::thread::sleep(Duration::from_millis(10));
            }
        })
    };
    // The flood starts once mavping has its responder (so a slow start of
    // `mavping respond` on a busy machine cannot leave it unheard), and
    // runs through the rest of the 300 requests.
    let mut flood = None;
    let mut lines = BufReader::new(ping.stdout.take().unwrap());
    let (mut out, mut line) = (String::new(), String::new());
    while lines.read_line(&mut line).unwrap() > 0 {
        if flood.is_none() && line.contains(r#""type":"reply""#) {
            flood = Some(start_flood());
        }
        out.push_str(&line);
        line.clear();
    }
    let mut err = String::new();
    ping.stderr
        .take()
        .unwrap()
        .read_to_string(&mut err)
        .unwrap();
    let code = ping.wait().unwrap().code().unwrap_or(-1);
    stop.store(true, Ordering::Relaxed);
    flood.expect("a reply came").join().unwrap();
    signal(respond.id(), "TERM");
    let mut rest = String::new();
    respond
        .stdout
        .take()
        .unwrap()
        .read_to_string(&mut rest)
        .unwrap();
    let _ = respond.wait();
    let s = summary_of(&out);
    let replies_sent: u64 = rest
        .split(" replies sent")
        .next()
        .and_then(|x| x.rsplit(", ").next())
        .and_then(|x| x.parse().ok())
        .unwrap_or_else(|| panic!("respond said: {rest}"));
    let r = responder(&s, "1/1");
    assert_eq!(code, 0, "{err}\n{r}");
    // Every reply the responder sent was counted once; none lost or stale.
    assert_eq!(
        n(r, "received") + n(r, "late") + n(r, "duplicate"),
        replies_sent,
        "{r}"
    );
    assert_eq!(
        (n(r, "lost"), n(r, "stale"), n(r, "duplicate")),
        (0, 0, 0),
        "{r}"
    );
    assert_eq!(n(r, "sent"), n(r, "received"), "{r}");
    // The flood was heard and set aside: foreign replies counted, no
    // responder made of it, nothing rejected by the scanner.
    assert!(n(&s, "foreign_replies") > 1_000, "{}", s["foreign_replies"]);
    assert!(sent.load(Ordering::Relaxed) > 10_000);
    assert_eq!(
        s["responders"].as_array().unwrap().len(),
        1,
        "{}",
        s["responders"]
    );
    let f = &s["frames"];
    assert_eq!((n(f, "bad_crc"), n(f, "skipped_bytes")), (0, 0), "{f}");
}

#[test]
fn sim_outage_and_delay_spikes_are_counted_exactly() {
    // 10 ms interval, no jitter, virtual clock: the outage from 300 ms for
    // 200 ms loses requests 30..49 exactly; every reply hit by a 1 s spike
    // (past the 100 ms timeout) is lost and then late.
    let (code, out, err) = run_mavping(&[
        "--json",
        "-q",
        "-c",
        "100",
        "-i",
        "10ms",
        "-W",
        "100ms",
        "-v",
        "sim:?jitter=0ms&outage=300ms+200ms&spike=10%&spike_delay=1s&seed=4&clock=virtual",
    ]);
    let s = summary_of(&out);
    let r = responder(&s, "1/1");
    let field = |k: &str| sim_truth(&err, "1/1", k);
    assert_eq!(field("outage"), 20, "{err}");
    let spiked = field("spiked");
    assert!(spiked > 0, "{err}");
    // A spiked first reply opens the window too (late), so nothing before
    // the outage goes uncharged.
    assert_eq!(field("dropped_before_first"), 0, "{err}");
    assert_eq!(n(r, "lost"), 20 + spiked, "{r}");
    assert_eq!(n(r, "received"), field("delivered"), "{r}");
    assert_eq!(n(r, "sent"), 100, "{r}");
    // The spikes near the end come after the run: late is what arrived.
    assert_eq!(n(r, "late"), field("spiked_arrived"), "{r}");
    assert!(n(r, "late") <= spiked, "{r}");
    assert_eq!(code, 0, "{err}");
}

/// The rule for spoofed ids: on a link with several peers (udpin, tcpin,
/// udpbcast) a responder's ids are believed only from the peer it first
/// answered from in time. A second peer that sees our requests and answers
/// them as 1/1 (even for the requests the real 1/1 dropped) is counted in
/// `wrong_path_replies` and never measured.
#[test]
fn spoofed_ids_from_another_peer_are_rejected_not_measured() {
    use mavping::frame::{decode, scan_datagram, ScanStats, SysComp};
    use std::io::{BufRead, BufReader, Read};

    let port = free_udp_port();
    let mut ping = mavping()
        .args([
            "--json",
            "-c",
            "80",
            "-i",
            "10ms",
            "-W",
            "2s",
            "--expect",
            "1/1",
            &format!("udpin:127.0.0.1:{port}"),
        ])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut respond = mavping()
        .args([
            "respond",
            "--drop",
            "20",
            "--seed",
            "3",
            &format!("udpout:127.0.0.1:{port}"),
        ])
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let armed = Arc::new(AtomicBool::new(false));
    let stop = Arc::new(AtomicBool::new(false));
    let forged = Arc::new(AtomicU64::new(0));
    let spoofer = {
        let (armed, stop, forged) = (armed.clone(), stop.clone(), forged.clone());
        std::thread::spawn(move || {
            let sock = UdpSocket::bind("127.0.0.1:0").unwrap();
            sock.set_read_timeout(Some(Duration::from_millis(50)))
                .unwrap();
            let mut hello = Vec::new();
            let header = Header {
                sysid: 66,
                compid: 1,
                seq: 0,
            };
            encode(
                &mut hello,
                Version::V2,
                header,
                &Msg::Heartbeat {
                    mav_type: 6,
                    autopilot: 8,
                },
            );

            let mut buf = [0u8; 2048];
            let mut heard = false;
            while !stop.load(Ordering::Relaxed) {
                // Once armed (mavping has heard the real responder, so its
                // schedule runs), say hello like a real system until
                // mavping has heard us and sends requests.
                if !heard && armed.load(Ordering::Relaxed) {
                    let _ = sock.send_to(&hello, ("127.0.0.1", port));
                }
                let Ok(len) = sock.recv(&mut buf) else {
                    continue;
                };
                heard = true;
                let mut requests = Vec::new();
                scan_datagram(&buf[..len], &mut ScanStats::default(), &mut |raw| {
                    requests.push(decode(raw))
                });
                for f in requests {
                    let Msg::Ping {
                        time_usec,
                        seq,
                        target_system: 0,
                        target_component: 0,
                    } = f.msg
                    else {
                        continue;
                    };
                    if !armed.load(Ordering::Relaxed) {
                        continue;
                    }
                    let SysComp { sysid, compid } = f.source;
                    let mut reply = Vec::new();
                    let header = Header {
                        sysid: 1,
                        compid: 1,
                        seq: 0,
                    };
                    let msg = Msg::Ping {
                        time_usec,
                        seq,
                        target_system: sysid,
                        target_component: compid,
                    };
                    encode(&mut reply, Version::V2, header, &msg);
                    sock.send_to(&reply, ("127.0.0.1", port)).unwrap();
                    forged.fetch_add(1, Ordering::Relaxed);
                }
            }
        })
    };
    // Arm the spoofer once mavping has accepted a reply from the real 1/1.
    let mut lines = BufReader::new(ping.stdout.take().unwrap());
    let mut out = String::new();
    let mut line = String::new();
    while lines.read_line(&mut line).unwrap() > 0 {
        if !armed.load(Ordering::Relaxed) && line.contains(r#""type":"reply""#) {
            armed.store(true, Ordering::Relaxed);
        }
        out.push_str(&line);
        line.clear();
    }
    let mut err = String::new();
    ping.stderr
        .take()
        .unwrap()
        .read_to_string(&mut err)
        .unwrap();
    let code = ping.wait().unwrap().code();
    stop.store(true, Ordering::Relaxed);
    spoofer.join().unwrap();
    signal(respond.id(), "TERM");
    let mut rest = String::new();
    respond
        .stdout
        .take()
        .unwrap()
        .read_to_string(&mut rest)
        .unwrap();
    let _ = respond.wait();
    let replies_sent: u64 = rest
        .split(" replies sent")
        .next()
        .and_then(|x| x.rsplit(", ").next())
        .and_then(|x| x.parse().ok())
        .unwrap_or_else(|| panic!("respond said: {rest}"));
    let s = summary_of(&out);
    let r = responder(&s, "1/1");
    assert_eq!(code, Some(0), "{err}");
    assert!(
        forged.load(Ordering::Relaxed) > 30,
        "{}",
        forged.load(Ordering::Relaxed)
    );
    assert_eq!(
        n(&s, "wrong_path_replies"),
        forged.load(Ordering::Relaxed),
        "{s}"
    );
    // Only the real responder's replies count for 1/1: the requests it
    // dropped stay lost although the spoofer answered them.
    assert_eq!(
        n(r, "received") + n(r, "late") + n(r, "duplicate"),
        replies_sent,
        "{r}"
    );
    assert_eq!(n(r, "duplicate"), 0, "{r}");
    assert!(n(r, "lost") > 0, "{r}");
    assert_eq!(n(r, "sent"), n(r, "received") + n(r, "lost"), "{r}");
}

#[test]
fn timesync_replies_echoing_a_wrong_ts1_are_stale_not_measured() {
    let port = free_udp_port();
    let peer = Peer::start("hostile_peer.py", &["--port", &port.to_string()]);
    let (code, out, err) = run_mavping(&[
        "--json",
        "-q",
        "--probe",
        "timesync",
        "-c",
        "30",
        "-i",
        "10ms",
        "-W",
        "2s",
        &format!("udpout:127.0.0.1:{port}"),
    ]);
    let truth = peer.finish();
    assert_eq!(code, 0, "{err}");
    let s = summary_of(&out);
    let r = responder(&s, "1/1");
    assert_eq!(n(&truth, "timesync_requests"), 30, "{truth}");
    assert_eq!(
        (
            n(r, "sent"),
            n(r, "received"),
            n(r, "lost"),
            n(r, "duplicate")
        ),
        (30, 30, 0, 0),
        "{r}"
    );
    assert_eq!(n(r, "stale"), n(&truth, "wrong_ts1"), "{r}");
    assert_eq!(n(&truth, "wrong_ts1"), 10);
}

/// The path rule does not lock out a responder that restarts on a new
/// port: once it has been silent for a whole timeout, its ids are believed
/// from the new peer.
#[test]
fn a_responder_restarted_on_a_new_port_is_measured_again() {
    use std::io::{BufRead, BufReader, Read};

    let port = free_udp_port();
    let mut ping = mavping()
        .args([
            "--json",
            "-c",
            "150",
            "-i",
            "20ms",
            "-W",
            "200ms",
            &format!("udpin:127.0.0.1:{port}"),
        ])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let start_respond = || {
        mavping()
            .args(["respond", &format!("udpout:127.0.0.1:{port}")])
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .unwrap()
    };
    let replies_of = |mut child: std::process::Child| -> u64 {
        signal(child.id(), "TERM");
        let mut rest = String::new();
        child
            .stdout
            .take()
            .unwrap()
            .read_to_string(&mut rest)
            .unwrap();
        let _ = child.wait();
        rest.split(" replies sent")
            .next()
            .and_then(|x| x.rsplit(", ").next())
            .and_then(|x| x.parse().ok())
            .unwrap_or_else(|| panic!("respond said: {rest}"))
    };
    let mut first = Some(start_respond());
    let mut second = None;
    let mut first_replies = 0;
    let mut lines = BufReader::new(ping.stdout.take().unwrap());
    let (mut out, mut line) = (String::new(), String::new());
    let (mut replies, mut last_reply_seq) = (0u64, 0u64);
    while lines.read_line(&mut line).unwrap() > 0 {
        let event: Value = serde_json::from_str(&line).unwrap_or(Value::Null);
        match event["type"].as_str() {
            Some("reply") => {
                replies += 1;
                last_reply_seq = event["seq"].as_u64().unwrap();
                // After ten replies the first responder goes away.
                if replies == 10 {
                    first_replies = replies_of(first.take().unwrap());
                }
            }
            // Ten intervals after its last reply, plus the timeout, have
            // passed: it comes back from a new port.
            Some("lost")
                if second.is_none()
                    && first.is_none()
                    && event["seq"].as_u64().unwrap() >= last_reply_seq + 10 =>
            {
                second = Some(start_respond());
            }
            _ => {}
        }
        out.push_str(&line);
        line.clear();
    }
    let mut err = String::new();
    ping.stderr
        .take()
        .unwrap()
        .read_to_string(&mut err)
        .unwrap();
    let _ = ping.wait();
    let second_replies = replies_of(second.expect("the responder came back"));
    let s = summary_of(&out);
    let r = responder(&s, "1/1");
    assert!(second_replies > 10, "{second_replies} {err}");
    assert_eq!(n(&s, "wrong_path_replies"), 0, "{s}");
    assert_eq!(
        n(r, "received") + n(r, "late") + n(r, "duplicate"),
        first_replies + second_replies,
        "{r}"
    );
}
