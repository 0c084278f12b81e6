//! mavping over real UDP sockets against pymavlink responders.

use crate::common::*;

#[test]
fn udpin_pings_every_peer_and_counts_each_exactly() {
    let port = free_udp_port();
    let target = format!("udpout:127.0.0.1:{port}");
    // A answers in MAVLink 1 and drops seqs 0, 2 and 5; its window starts
    // at seq 1, its first answer. B (MAVLink 2) ignores 0 and 1, then
    // answers everything, twice for seqs 3 and 5.
    let a = Peer::start(
        "responder.py",
        &[&target, "--sysid", "1", "--mavlink1", "--drop", "0,2,5"],
    );
    let b = Peer::start(
        "responder.py",
        &[&target, "--sysid", "2", "--drop", "0,1", "--dup", "3,5"],
    );
    let (code, out, err) = run_mavping(&[
        "-c",
        "10",
        "-i",
        "0.2",
        "-W",
        "500ms",
        &format!("udpin:127.0.0.1:{port}"),
    ]);
    assert_eq!(code, 0, "{out}\n{err}");
    let ca = text_counts(&out, "1/1").expect(&out);
    let cb = text_counts(&out, "2/1").expect(&out);
    assert_eq!(
        (ca.sent, ca.received, ca.lost, ca.duplicate),
        (9, 7, 2, 0),
        "{out}"
    );
    assert_eq!(
        (cb.sent, cb.received, cb.lost, cb.duplicate),
        (8, 8, 0, 2),
        "{out}"
    );
    let (ta, tb) = (a.finish(), b.finish());
    assert_eq!(ta["replies"], 7);
    assert_eq!(tb["duplicated"], 2);
    // Both announced themselves as PX4 quadrotors.
    assert!(out.contains("1/1 (quadrotor, px4)"), "{out}");
}

#[test]
fn udpout_to_pymavlink_udpin_survives_junk_and_bad_crc() {
    let port = free_udp_port();
    let peer = Peer::start(
        "responder.py",
        &[
            &format!("udpin:127.0.0.1:{port}"),
            "--junk-before",
            "1,2,3",
            "--bad-crc",
            "4",
        ],
    );
    let (code, out, err) = run_mavping(&[
        "-c",
        "8",
        "-i",
        "0.1",
        "-W",
        "500ms",
        &format!("udpout:127.0.0.1:{port}"),
    ]);
    assert_eq!(code, 0, "{out}\n{err}");
    let c = text_counts(&out, "1/1").expect(&out);
    // Junk datagrams cost no reply; the corrupted reply to seq 4 (a
    // datagram of its own: a damaged frame, never a reply) is lost.
    assert_eq!((c.sent, c.received, c.lost), (8, 7, 1), "{out}");
    assert!(out.contains("0 bad CRC, 1 damaged frames"), "{out}");
    let truth = peer.finish();
    assert_eq!(truth["junk"], 3);
    assert_eq!(truth["replies"], 7);
}

#[test]
fn a_system_that_never_answers_ping_gets_the_timesync_hint() {
    let port = free_udp_port();
    let _ardupilot = Peer::start(
        "responder.py",
        &[
            &format!("udpin:127.0.0.1:{port}"),
            "--no-ping",
            "--autopilot",
            "3",
        ],
    );
    let (code, out, err) = run_mavping(&[
        "--probe",
        "ping",
        "-c",
        "3",
        "-i",
        "0.1",
        "-W",
        "300ms",
        &format!("udpout:127.0.0.1:{port}"),
    ]);
    assert_eq!(code, 1, "no reply at all must exit 1\n{out}\n{err}");
    assert!(
        out.contains(
            "hint: 1/1 (quadrotor, ardupilotmega) sends HEARTBEAT but never answered PING"
        ) && out.contains("--probe timesync"),
        "{out}"
    );
}
