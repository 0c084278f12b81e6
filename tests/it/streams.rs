//! Vehicles that stream telemetry: `mavping respond --stream` on a real
//! socket sends what it says it sent, each frame numbered with the same
//! counter as its HEARTBEATs; the simulated link's per-direction faults
//! are what the pinger counts and what its `-v` truth line says.

use std::net::UdpSocket;
use std::time::{Duration, Instant};

use mavlink::dialects::ardupilotmega::MavMessage;
use mavlink::MAVLinkV2MessageRaw;

use crate::common::*;

const ATTITUDE: u32 = 30;
const HEARTBEAT: u32 = 0;

/// One MAVLink 2 frame a datagram holds, CRC checked by the `mavlink`
/// crate: its sender, sequence number and message id.
fn frame_of(datagram: &[u8]) -> (u8, u8, u8, u32) {
    assert_eq!(datagram.first(), Some(&0xfd), "MAVLink 2: {datagram:?}");
    let mut raw = MAVLinkV2MessageRaw::new();
    raw.as_mut_slice()[..datagram.len()].copy_from_slice(datagram);
    assert!(raw.has_valid_crc::<MavMessage>(), "{datagram:?}");
    (
        raw.system_id() as u8,
        raw.component_id(),
        raw.sequence(),
        raw.message_id(),
    )
}

#[test]
fn respond_streams_what_it_says_numbered_with_its_heartbeats() {
    let socket = UdpSocket::bind("127.0.0.1:0").unwrap();
    socket
        .set_read_timeout(Some(Duration::from_millis(300)))
        .unwrap();
    let port = socket.local_addr().unwrap().port();
    let respond = Respond::start(&[
        "--stream",
        "ATTITUDE@50",
        "--stream-drop",
        "10",
        "--seed",
        "7",
        &format!("udpout:127.0.0.1:{port}"),
    ]);
    let started = Instant::now();
    let mut frames = Vec::new();
    let mut buf = [0u8; 512];
    let read = |frames: &mut Vec<_>, buf: &mut [u8], until: Option<Instant>| loop {
        if until.is_some_and(|t| Instant::now() >= t) {
            return;
        }
        match socket.recv(buf) {
            Ok(n) => frames.push(frame_of(&buf[..n])),
            Err(_) if until.is_none() => return,
            Err(e) => panic!("{e}"),
        }
    };
    read(
        &mut frames,
        &mut buf,
        Some(started + Duration::from_secs(4)),
    );
    let elapsed = started.elapsed().as_secs_f64();
    let (code, counts) = respond.finish();
    // What it wrote before it stopped is waiting in the socket.
    read(&mut frames, &mut buf, None);
    assert_eq!(code, 0);
    // "N requests (...), 0 replies sent, 0 dropped, 0 duplicated; S frames
    // streamed (S ATTITUDE), D dropped by --stream-drop"
    let [requests, .., streamed, attitude, dropped] = counts[..] else {
        panic!("{counts:?}")
    };
    assert_eq!((requests, streamed), (0, attitude), "{counts:?}");
    let of = |msgid| frames.iter().filter(|f| f.3 == msgid).count() as u64;
    assert_eq!(
        of(ATTITUDE),
        attitude,
        "every frame it says it streamed arrived"
    );
    assert!(of(HEARTBEAT) >= 4, "{frames:?}");
    assert_eq!(of(ATTITUDE) + of(HEARTBEAT), frames.len() as u64);
    assert!(frames.iter().all(|f| (f.0, f.1) == (1, 1)));
    // 50 a second, a tenth of them numbered but not sent.
    let numbered = attitude + dropped;
    assert!(
        (45.0 * elapsed..52.0 * elapsed + 5.0).contains(&(numbered as f64)),
        "{numbered} in {elapsed} s"
    );
    assert!((5..50).contains(&dropped), "{counts:?}");
    // One sequence for the HEARTBEATs and the telemetry, from 0: every gap
    // is a dropped frame, and the others were dropped after the last one
    // that was sent.
    let mut next = 0u64;
    let mut gaps = 0;
    for &(_, _, seq, _) in &frames {
        let gap = u64::from(seq.wrapping_sub(next as u8));
        gaps += gap;
        next += gap + 1;
    }
    assert!(
        gaps <= dropped && dropped - gaps < 4,
        "{gaps} gaps, {dropped} dropped"
    );
}

#[test]
fn sim_per_direction_faults_are_what_the_pinger_counts_and_the_truth_line_says() {
    let (code, out, err) = run_mavping(&[
        "-c",
        "200",
        "-i",
        "20ms",
        "-v",
        "sim:?responders=2&stream=ATTITUDE@50,GLOBAL_POSITION_INT@5&loss_down=10%&dup_down=5%\
         &reorder_down=5%&loss_up=10%&seed=2&clock=virtual",
    ]);
    assert_eq!(code, 0, "{err}");
    for id in ["1/1", "2/1"] {
        let truth = |k| sim_truth(&err, id, k);
        let c = text_counts(&out, id).unwrap_or_else(|| panic!("{out}"));
        assert_eq!(truth("answered"), 200);
        // Requests lost on the way up and replies lost on the way down are
        // both lost exchanges for the pinger.
        assert!(truth("up_requests_dropped") > 5, "{err}");
        assert!(truth("dropped") > truth("up_requests_dropped"), "{err}");
        assert_eq!(c.received, truth("delivered"), "{id}: {out}");
        assert_eq!(
            c.lost,
            truth("dropped") - truth("dropped_before_first"),
            "{id}: {out}"
        );
        assert_eq!(c.duplicate, truth("duplicates_arrived"), "{id}: {out}");
        // Telemetry, HEARTBEATs and replies: 4 s and the last replies' wait
        // of 56 frames a second, and the replies; about a tenth lost, a
        // twentieth doubled and held.
        let sent = truth("down_sent");
        assert!((400..700).contains(&sent), "{err}");
        let in_flight = sent - truth("down_dropped") - truth("down_delivered");
        assert!(in_flight < 10, "{err}");
        assert!(truth("down_dropped") * 20 > sent && truth("down_dropped") * 5 < sent);
        assert!(truth("down_reordered") > 0 && truth("down_duplicates_arrived") > 0);
        let copies_on_the_way = truth("down_duplicated") - truth("down_duplicates_arrived");
        assert!(copies_on_the_way < 3, "{err}");
        // Our PINGs and HEARTBEATs, each responder losing its own.
        assert!(truth("up_sent") >= 200 && truth("up_dropped") >= truth("up_requests_dropped"));
    }
}
