//! Connection strings typed the way other tools take them, and the
//! mistakes they invite: each ends in one line that names the form meant
//! (exit 2), or works as its author meant it.

use std::net::UdpSocket;

use crate::common::*;

fn fails_saying(args: &[&str], needles: &[&str]) {
    let (code, out, err) = run_mavping(args);
    assert_eq!(code, 2, "{args:?}: {out}{err}");
    assert_eq!(err.lines().count(), 1, "{args:?}: {err}");
    for needle in needles {
        assert!(err.contains(needle), "{args:?}: {err} (wanted {needle:?})");
    }
}

/// `mavping 198.51.100.7:14550` typed ping-style: that listens, on an
/// address this machine does not have.
#[test]
fn a_vehicles_address_typed_ping_style_says_udpout_sends() {
    fails_saying(
        &["-c", "1", "198.51.100.7:14550"],
        &[
            "Cannot assign requested address",
            "198.51.100.7 is not an address of this machine",
            "use udpout:198.51.100.7:14550",
        ],
    );
    fails_saying(
        &["-c", "1", "tcpin:198.51.100.7:5760"],
        &["use tcp:198.51.100.7:5760"],
    );
}

/// Listening on the port a vehicle (here: a bound socket) listens on.
#[test]
fn listening_on_a_port_in_use_says_how_to_send_to_it() {
    let vehicle = UdpSocket::bind("127.0.0.1:0").unwrap();
    let port = vehicle.local_addr().unwrap().port();
    fails_saying(
        &["-c", "1", &format!("udp:127.0.0.1:{port}")],
        &[
            "Address already in use",
            &format!("listening on port {port}"),
            &format!("use udpout:127.0.0.1:{port}"),
        ],
    );
}

/// MAVSDK's strings mean what MAVSDK means: a real exchange with `mavping
/// respond` through `udpout://` and `udp://:PORT`.
#[test]
fn mavsdk_style_strings_measure_as_ours() {
    let port = free_udp_port();
    let respond = Respond::start(&[&format!("udpin:127.0.0.1:{port}")]);
    let link = format!("udpout://127.0.0.1:{port}");
    let (code, out, err) = run_mavping(&["-c", "3", "-i", "50ms", &link]);
    assert_eq!(code, 0, "{out}{err}");
    let counts = text_counts(&out, "1/1").unwrap_or_else(|| panic!("{out}"));
    assert_eq!((counts.sent, counts.received, counts.lost), (3, 3, 0));
    let (_, responded) = respond.finish();
    assert_eq!(responded[1], 3, "PINGs the responder answered");

    // `udp://:PORT` listens on every address, as MAVSDK's does.
    let port = free_udp_port();
    let listen = start_mavping(&["-c", "3", "-i", "50ms", &format!("udp://:{port}")]);
    let respond = Respond::start(&[&format!("udpout:127.0.0.1:{port}")]);
    let (code, out, err) = listen.wait(std::time::Duration::from_secs(20));
    assert_eq!(code, 0, "{out}{err}");
    assert!(
        out.starts_with(&format!("MAVPING udpin:0.0.0.0:{port}")),
        "{out}"
    );
    // respond says it is no autopilot (MAV_AUTOPILOT_INVALID), not "invalid".
    assert!(
        out.contains("heard 1/1: onboard_controller, no autopilot"),
        "{out}"
    );
    let counts = text_counts(&out, "1/1").unwrap_or_else(|| panic!("{out}"));
    assert_eq!((counts.received, counts.lost), (3, 0), "{out}");
    drop(respond);
}

#[test]
fn a_peer_at_port_zero_a_unicast_broadcast_and_a_mistyped_baud_are_refused() {
    fails_saying(
        &["-c", "1", "udpout:127.0.0.1:0"],
        &["port 0 names no peer"],
    );
    fails_saying(&["-c", "1", "tcp:127.0.0.1:0"], &["port 0 names no peer"]);
    fails_saying(
        &["-c", "1", "udpbcast:127.0.0.1:14550"],
        &[
            "127.0.0.1 is not a broadcast address",
            "127.255.255.255",
            "use udpout:",
        ],
    );
    fails_saying(
        &["-c", "1", "serial:/dev/ttyS0:abc"],
        &["'abc' is not a baud rate (e.g. serial:/dev/ttyS0:57600)"],
    );
}

/// A file or /dev/null named as a serial device: libc's "Not a
/// typewriter" said as what it means.
#[test]
fn a_file_that_is_no_serial_device_is_named_so() {
    let file = std::env::temp_dir().join(format!("mavping-not-a-tty-{}", std::process::id()));
    std::fs::write(&file, b"not a tty").unwrap();
    for device in ["/dev/null", file.to_str().unwrap()] {
        fails_saying(
            &["-c", "1", &format!("serial:{device}:57600")],
            &[&format!("{device} is not a serial device"), "pty"],
        );
    }
    let _ = std::fs::remove_file(&file);
}
