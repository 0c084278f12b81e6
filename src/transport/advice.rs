//! What to do when a link cannot open because of how it was named: the
//! OS says "Cannot assign requested address" to someone who typed a
//! vehicle's address ping-style (`mavping 10.1.2.3:14550`, which listens),
//! and "Address already in use" to someone listening on the vehicle's own
//! port. The error keeps the OS's words and adds the form that was meant.

use std::io;
use std::net::{Ipv4Addr, SocketAddr};

use super::address::HostPort;

/// `e`, from binding a listening socket of `scheme` (`udp`, `tcpin`) to
/// `local`, with advice where the cause is a mistaken form.
pub(super) fn listening(
    scheme: &str,
    addr: &HostPort,
    local: SocketAddr,
    e: io::Error,
) -> io::Error {
    let (send, bare) = if scheme == "udp" {
        ("udpout", " (and a bare HOST:PORT)")
    } else {
        ("tcp", "")
    };
    let advice = match e.kind() {
        io::ErrorKind::AddrNotAvailable => format!(
            "{} is not an address of this machine: {scheme}:HOST:PORT{bare} listens on one of \
             its own addresses; to send to a system at {addr}, use {send}:{addr}",
            local.ip()
        ),
        io::ErrorKind::AddrInUse => format!(
            "another program (a vehicle, a router, a ground station) is listening on port {}: \
             to send to it, use {send}:{addr}; to listen beside it, choose a port it sends to",
            local.port()
        ),
        _ => return e,
    };
    io::Error::new(e.kind(), format!("{e}; {advice}"))
}

/// Why `target` is not a broadcast address this machine can send to, if it
/// is not: the limited broadcast 255.255.255.255, or the broadcast address
/// of one of this machine's IPv4 networks.
pub(super) fn not_broadcast(target: Ipv4Addr) -> Option<String> {
    if target == Ipv4Addr::BROADCAST {
        return None;
    }
    let ours = interface_broadcasts();
    if ours.contains(&target) {
        return None;
    }
    let listed = if ours.is_empty() {
        "none found".to_string()
    } else {
        ours.iter()
            .map(ToString::to_string)
            .collect::<Vec<_>>()
            .join(", ")
    };
    Some(format!(
        "{target} is not a broadcast address of this machine's networks (theirs: {listed}; or \
         255.255.255.255): to send to one system, use udpout:"
    ))
}

/// The broadcast address of every IPv4 network this machine is on: as
/// the interface gives it, or its address with the host bits set (the
/// loopback has no broadcast flag, yet 127.255.255.255 reaches every
/// socket on it).
#[cfg(unix)]
fn interface_broadcasts() -> Vec<Ipv4Addr> {
    let Ok(addrs) = nix::ifaddrs::getifaddrs() else {
        return Vec::new();
    };
    let v4 = |s: Option<nix::sys::socket::SockaddrStorage>| {
        s.and_then(|s| s.as_sockaddr_in().map(|a| a.ip()))
    };
    let mut found = Vec::new();
    for a in addrs {
        found.extend(v4(a.broadcast));
        if let (Some(ip), Some(mask)) = (v4(a.address), v4(a.netmask)) {
            // A /31 or /32 has no broadcast address.
            if mask.to_bits().leading_ones() < 31 {
                found.push(Ipv4Addr::from_bits(ip.to_bits() | !mask.to_bits()));
            }
        }
    }
    found.sort();
    found.dedup();
    found
}

/// Windows: no getifaddrs; the check then knows the limited broadcast
/// (255.255.255.255) and the loopback's only.
#[cfg(not(unix))]
fn interface_broadcasts() -> Vec<Ipv4Addr> {
    vec![Ipv4Addr::new(127, 255, 255, 255)]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn loopback_broadcasts_and_the_limited_broadcast_are_broadcasts_hosts_are_not() {
        assert_eq!(not_broadcast(Ipv4Addr::BROADCAST), None);
        let host = not_broadcast(Ipv4Addr::LOCALHOST).unwrap();
        assert!(
            host.contains("127.0.0.1 is not a broadcast address"),
            "{host}"
        );
        assert!(host.contains("udpout:"), "{host}");
        assert!(host.contains("127.255.255.255"), "{host}");
        assert_eq!(not_broadcast(Ipv4Addr::new(127, 255, 255, 255)), None);
    }

    #[test]
    fn advice_keeps_the_os_words_and_names_the_form_meant() {
        let addr = HostPort {
            host: "10.1.2.3".into(),
            port: 14550,
        };
        let local: SocketAddr = "10.1.2.3:14550".parse().unwrap();
        let e = io::Error::from(io::ErrorKind::AddrNotAvailable);
        let said = listening("udp", &addr, local, e).to_string();
        assert!(said.contains("use udpout:10.1.2.3:14550"), "{said}");
        let e = io::Error::from(io::ErrorKind::AddrInUse);
        let said = listening("tcpin", &addr, local, e).to_string();
        assert!(said.contains("listening on port 14550"), "{said}");
        assert!(said.contains("use tcp:10.1.2.3:14550"), "{said}");
        let other = io::Error::from(io::ErrorKind::PermissionDenied);
        assert_eq!(
            listening("udp", &addr, local, other).kind(),
            io::ErrorKind::PermissionDenied
        );
    }
}
