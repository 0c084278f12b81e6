//! Where a link's sockets go: the address family host names resolve to
//! (`-4`, `-6`), the local address outgoing links send from (`--bind`) and
//! the network interface every socket is tied to (`-I`, SO_BINDTODEVICE),
//! for a ground station with a radio, LTE and Wi-Fi at once, where the
//! route is the question.

use std::io;
use std::net::SocketAddr;

use socket2::{Domain, Protocol, Socket, Type};
use tokio::net::{TcpSocket, UdpSocket};

use super::address::HostPort;
use super::{Family, LinkError};

/// The route options a link is opened with.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub(crate) struct Route {
    pub(crate) family: Option<Family>,
    /// Outgoing links send from here (`--bind ADDR[:PORT]`).
    pub(crate) bind: Option<SocketAddr>,
    /// Every socket is tied to this interface (`-I IFACE`).
    pub(crate) interface: Option<String>,
}

/// The first address `addr` resolves to, of the family asked for.
pub(crate) async fn resolve(
    addr: &HostPort,
    family: Option<Family>,
) -> Result<SocketAddr, LinkError> {
    let mut addrs = tokio::net::lookup_host((addr.host.as_str(), addr.port))
        .await
        .map_err(|e| LinkError::io(format!("cannot resolve {addr}"), e))?;
    let wanted = |a: &SocketAddr| match family {
        None => true,
        Some(Family::V4) => a.is_ipv4(),
        Some(Family::V6) => a.is_ipv6(),
    };
    addrs.find(wanted).ok_or_else(|| {
        let why = match family {
            None => "no address found",
            Some(Family::V4) => "no IPv4 address (-4)",
            Some(Family::V6) => "no IPv6 address (-6)",
        };
        LinkError::io(
            format!("cannot resolve {addr}"),
            io::Error::new(io::ErrorKind::NotFound, why),
        )
    })
}

/// `-I` on the portable path, in one line.
pub(crate) fn interface_needs_linux(iface: &str) -> String {
    format!(
        "-I {iface}: tying a socket to a network interface needs Linux (SO_BINDTODEVICE); \
         this build has the portable path only: choose the route by address (--bind ADDR, udpin:ADDR:PORT)"
    )
}

impl Route {
    /// The local address an outgoing link towards `peer` sends from:
    /// `--bind`, else any address of the peer's family.
    pub(crate) fn local_for(&self, peer: SocketAddr) -> Result<SocketAddr, LinkError> {
        match self.bind {
            Some(bind) if bind.is_ipv4() != peer.is_ipv4() => Err(LinkError::Closed(format!(
                "--bind {bind} and {peer} are of different address families"
            ))),
            Some(bind) => Ok(bind),
            None if peer.is_ipv6() => Ok("[::]:0".parse().expect("valid literal")),
            None => Ok("0.0.0.0:0".parse().expect("valid literal")),
        }
    }

    /// What SO_BINDTODEVICE's failures mean, in one line. Before Linux 5.7
    /// it needs CAP_NET_RAW.
    #[cfg(not(mavping_portable))]
    fn interface_error(&self, e: io::Error) -> LinkError {
        let iface = self.interface.as_deref().unwrap_or_default();
        match e.raw_os_error() {
            Some(eperm) if eperm == nix::errno::Errno::EPERM as i32 => LinkError::Closed(format!(
                "-I {iface}: tying a socket to an interface needs CAP_NET_RAW (run as root, \
                     or: sudo setcap cap_net_raw+ep $(which mavping))"
            )),
            Some(nodev) if nodev == nix::errno::Errno::ENODEV as i32 => {
                LinkError::Closed(format!("-I {iface}: no such network interface"))
            }
            _ => LinkError::io(format!("-I {iface}"), e),
        }
    }

    #[cfg(not(mavping_portable))]
    fn tie(&self, socket: &Socket) -> Result<(), LinkError> {
        if let Some(iface) = &self.interface {
            socket
                .bind_device(Some(iface.as_bytes()))
                .map_err(|e| self.interface_error(e))?;
        }
        Ok(())
    }

    /// The portable path cannot tie a socket to an interface; the options
    /// refuse `-I` before any link opens (config), so this is a backstop.
    #[cfg(mavping_portable)]
    fn tie(&self, _socket: &Socket) -> Result<(), LinkError> {
        match &self.interface {
            Some(iface) => Err(LinkError::Closed(interface_needs_linux(iface))),
            None => Ok(()),
        }
    }

    /// A UDP socket bound to `local`, tied to the interface if one is set.
    pub(crate) fn udp(&self, local: SocketAddr, what: &str) -> Result<UdpSocket, LinkError> {
        let domain = Domain::for_address(local);
        let socket = Socket::new(domain, Type::DGRAM, Some(Protocol::UDP))
            .map_err(|e| LinkError::io("cannot open a udp socket", e))?;
        self.tie(&socket)?;
        socket
            .bind(&local.into())
            .map_err(|e| LinkError::io(what.to_string(), e))?;
        socket
            .set_nonblocking(true)
            .map_err(|e| LinkError::io("cannot open a udp socket", e))?;
        UdpSocket::from_std(socket.into()).map_err(|e| LinkError::io("cannot open a udp socket", e))
    }

    /// A TCP socket for `addr`'s family, tied to the interface if one is set.
    pub(crate) fn tcp(&self, addr: SocketAddr) -> Result<TcpSocket, LinkError> {
        let domain = Domain::for_address(addr);
        let socket = Socket::new(domain, Type::STREAM, Some(Protocol::TCP))
            .map_err(|e| LinkError::io("cannot open a tcp socket", e))?;
        self.tie(&socket)?;
        socket
            .set_nonblocking(true)
            .map_err(|e| LinkError::io("cannot open a tcp socket", e))?;
        Ok(TcpSocket::from_std_stream(socket.into()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bind_must_match_the_peers_family() {
        let route = Route {
            bind: Some("127.0.0.1:0".parse().unwrap()),
            ..Route::default()
        };
        assert!(route.local_for("[::1]:14550".parse().unwrap()).is_err());
        assert_eq!(
            route.local_for("127.0.0.1:14550".parse().unwrap()).unwrap(),
            "127.0.0.1:0".parse().unwrap()
        );
        let any = Route::default();
        assert_eq!(
            any.local_for("[::1]:1".parse().unwrap()).unwrap(),
            "[::]:0".parse().unwrap()
        );
    }

    #[cfg(not(mavping_portable))]
    #[test]
    fn interface_errors_say_what_is_needed() {
        let route = Route {
            interface: Some("wlan0".into()),
            ..Route::default()
        };
        let eperm = io::Error::from_raw_os_error(nix::errno::Errno::EPERM as i32);
        assert!(route
            .interface_error(eperm)
            .to_string()
            .starts_with("-I wlan0: tying a socket to an interface needs CAP_NET_RAW"));
        let enodev = io::Error::from_raw_os_error(nix::errno::Errno::ENODEV as i32);
        assert_eq!(
            route.interface_error(enodev).to_string(),
            "-I wlan0: no such network interface"
        );
    }
}
