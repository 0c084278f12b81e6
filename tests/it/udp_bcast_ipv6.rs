//! udpbcast on loopback (127.255.255.255 is looped back to every socket
//! bound to the port on 0.0.0.0) and IPv6 over ::1, against pymavlink.

use crate::common::*;

#[test]
fn udpbcast_hears_every_responder_on_the_segment() {
    let port = free_udp_port();
    // pymavlink's udpin sets SO_REUSEADDR, so both bind the same port and
    // both receive each broadcast; nothing leaves the loopback interface.
    let listen = format!("udpin:0.0.0.0:{port}");
    let a = Peer::start("responder.py", &[&listen, "--sysid", "1", "--drop", "3"]);
    let b = Peer::start("responder.py", &[&listen, "--sysid", "2", "--dup", "4"]);
    let (code, out, err) = run_mavping(&[
        "-c",
        "8",
        "-i",
        "0.05",
        "-W",
        "300ms",
        &format!("udpbcast:127.255.255.255:{port}"),
    ]);
    assert_eq!(code, 0, "{out}\n{err}");
    let ca = text_counts(&out, "1/1").expect(&out);
    let cb = text_counts(&out, "2/1").expect(&out);
    assert_eq!(
        (ca.sent, ca.received, ca.lost, ca.duplicate),
        (8, 7, 1, 0),
        "{out}"
    );
    assert_eq!(
        (cb.sent, cb.received, cb.lost, cb.duplicate),
        (8, 8, 0, 1),
        "{out}"
    );
    assert_eq!(a.finish()["ping_requests"], 8);
    assert_eq!(b.finish()["duplicated"], 1);
}

#[test]
fn udpout_over_ipv6_loopback() {
    let port = std::net::UdpSocket::bind("[::1]:0")
        .expect("::1 is configured on lo")
        .local_addr()
        .unwrap()
        .port();
    let responder = Peer::start(
        "responder.py",
        &[&format!("udpin:[::1]:{port}"), "--drop", "3"],
    );
    let (code, out, err) = run_mavping(&[
        "-c",
        "6",
        "-i",
        "0.05",
        "-W",
        "300ms",
        &format!("udpout:[::1]:{port}"),
    ]);
    assert_eq!(code, 0, "{out}\n{err}");
    assert!(
        out.starts_with(&format!("MAVPING udpout:[::1]:{port}")),
        "{out}"
    );
    let c = text_counts(&out, "1/1").expect(&out);
    assert_eq!((c.sent, c.received, c.lost), (6, 5, 1), "{out}");
    assert_eq!(responder.finish()["replies"], 5);
}

#[test]
fn udpbcast_rejects_ipv6() {
    let (code, _, err) = run_mavping(&["-c", "1", "udpbcast:[::1]:14550"]);
    assert_eq!(code, 2);
    assert!(err.contains("IPv6 has no broadcast"), "{err}");
}
