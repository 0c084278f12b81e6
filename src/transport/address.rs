//! Connection strings, as pymavlink, MAVProxy and rust-mavlink spell them.

use std::fmt;

use thiserror::Error;

pub(crate) use super::m2r_url::M2rUrl;
use super::sim::SimParams;
use super::tlog::TlogPath;
pub(crate) use super::ws_url::WsUrl;

/// Where to connect, before anything is opened.
#[derive(Debug, Clone, PartialEq)]
pub enum LinkSpec {
    /// Listen on a UDP address; ping every peer heard from.
    UdpIn(HostPort),
    /// Send to a UDP address from an ephemeral port.
    UdpOut(HostPort),
    /// Send to a broadcast address; hear replies from anyone.
    UdpBcast(HostPort),
    /// Connect to a TCP server.
    TcpOut(HostPort),
    /// Listen for TCP clients; each is a path to responders.
    TcpIn(HostPort),
    /// Connect to a WebSocket server (`ws://`, `wss://`; boxed: a URL is
    /// large beside the other forms).
    Ws(Box<WsUrl>),
    /// Listen for WebSocket clients; each is a path to responders.
    WsIn(HostPort),
    /// Connect to a mavlink2rest WebSocket, messages as JSON (`m2r://`,
    /// `m2rs://`).
    M2r(Box<M2rUrl>),
    /// A serial device; `baud` None means "use --baud".
    Serial { path: String, baud: Option<u32> },
    /// The built-in simulated link (boxed: its parameters are many).
    Sim(Box<SimParams>),
    /// A telemetry log, read on its own clock (`-`: standard input).
    Tlog(TlogPath),
}

/// A host (name, IPv4, or IPv6 without brackets) and a port.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct HostPort {
    pub(crate) host: String,
    pub(crate) port: u16,
}

impl fmt::Display for HostPort {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.host.contains(':') {
            write!(f, "[{}]:{}", self.host, self.port)
        } else {
            write!(f, "{}:{}", self.host, self.port)
        }
    }
}

impl LinkSpec {
    /// A serial device that may ignore its baud rate: a USB CDC ACM port
    /// (a flight controller's own USB) or a pseudo-terminal pass data as
    /// fast as they can, whatever the baud rate says.
    pub(crate) fn may_ignore_baud(&self) -> bool {
        self.baud_ignorer().is_some()
    }

    /// What kind of device may ignore the baud rate, as a summary names it.
    pub(crate) fn baud_ignorer(&self) -> Option<&'static str> {
        const KINDS: [(&str, &str); 4] = [
            ("/dev/ttyACM", "a USB CDC port"),
            ("/dev/pts/", "a pty"),
            ("/dev/cu.usbmodem", "a USB CDC port"),
            ("/dev/tty.usbmodem", "a USB CDC port"),
        ];
        match self {
            LinkSpec::Serial { path, .. } => KINDS
                .iter()
                .find(|(prefix, _)| path.starts_with(prefix))
                .map(|&(_, kind)| kind),
            _ => None,
        }
    }

    /// A link on tokio's paused, virtual clock: a simulated link with
    /// `clock=virtual`, or a telemetry log (on the log's own clock).
    pub(crate) fn is_virtual(&self) -> bool {
        matches!(self, LinkSpec::Sim(p) if p.virtual_clock) || self.is_log()
    }

    /// A telemetry log: passive, nothing sent, ends with the log.
    pub(crate) fn is_log(&self) -> bool {
        matches!(self, LinkSpec::Tlog(_))
    }
}

impl fmt::Display for LinkSpec {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            LinkSpec::UdpIn(a) => write!(f, "udpin:{a}"),
            LinkSpec::UdpOut(a) => write!(f, "udpout:{a}"),
            LinkSpec::UdpBcast(a) => write!(f, "udpbcast:{a}"),
            LinkSpec::TcpOut(a) => write!(f, "tcp:{a}"),
            LinkSpec::TcpIn(a) => write!(f, "tcpin:{a}"),
            LinkSpec::Ws(url) => write!(f, "{url}"),
            LinkSpec::WsIn(a) => write!(f, "wsin:{a}"),
            LinkSpec::M2r(url) => write!(f, "{url}"),
            LinkSpec::Serial { path, baud } => match baud {
                Some(b) => write!(f, "serial:{path}:{b}"),
                None => write!(f, "serial:{path}"),
            },
            LinkSpec::Sim(p) => write!(f, "{p}"),
            LinkSpec::Tlog(path) => write!(f, "{path}"),
        }
    }
}

/// Accepted forms, listed in every parse error.
pub(crate) const ACCEPTED_FORMS: &str = "udpin:HOST:PORT, udp:HOST:PORT, HOST:PORT, udpout:HOST:PORT, \
udpbcast:ADDR:PORT, tcp:HOST:PORT, tcpout:HOST:PORT, tcpin:HOST:PORT, ws://[USER:PASSWORD@]HOST[:PORT][/PATH], \
wss://..., wsin:HOST:PORT, m2r://HOST[:PORT][/PATH] (mavlink2rest's JSON; m2rs:// with TLS), \
serial:DEVICE[:BAUD], \
/dev/DEVICE, COMn[:BAUD], sim:[?key=value&...], tlog:FILE or FILE.tlog (a telemetry log; tlog:- reads standard \
input) (IPv6 hosts in brackets: udpout:[::1]:14550)";

#[derive(Debug, Error, PartialEq)]
#[error("bad connection string '{input}': {reason}; accepted forms: {ACCEPTED_FORMS}")]
pub struct AddressError {
    pub(crate) input: String,
    pub(crate) reason: String,
}

fn error(input: &str, reason: impl Into<String>) -> AddressError {
    AddressError {
        input: input.to_string(),
        reason: reason.into(),
    }
}

fn host_port(input: &str, rest: &str) -> Result<HostPort, AddressError> {
    let (host, port) = if let Some(bracketed) = rest.strip_prefix('[') {
        let (host, after) = bracketed
            .split_once(']')
            .ok_or_else(|| error(input, "missing ']' after IPv6 address"))?;
        let port = after
            .strip_prefix(':')
            .ok_or_else(|| error(input, "missing ':PORT' after IPv6 address"))?;
        (host, port)
    } else {
        let (host, port) = rest
            .rsplit_once(':')
            .ok_or_else(|| error(input, "missing ':PORT'"))?;
        if host.contains(':') {
            return Err(error(
                input,
                "IPv6 addresses need brackets, e.g. [::1]:14550",
            ));
        }
        (host, port)
    };
    if host.is_empty() {
        return Err(error(input, "missing host"));
    }
    let port: u16 = port
        .parse()
        .map_err(|_| error(input, format!("'{port}' is not a port number (0-65535)")))?;
    Ok(HostPort {
        host: host.to_string(),
        port,
    })
}

/// The address of a peer to send to: port 0 names no peer.
fn reachable(input: &str, rest: &str) -> Result<HostPort, AddressError> {
    let hp = host_port(input, rest)?;
    if hp.port == 0 {
        return Err(error(
            input,
            "port 0 names no peer: give the port the system listens on",
        ));
    }
    Ok(hp)
}

fn serial(input: &str, rest: &str) -> Result<LinkSpec, AddressError> {
    if rest.is_empty() {
        return Err(error(input, "missing serial device"));
    }
    // The baud is the part after the last ':' when it is all digits; device
    // paths themselves do not end in ":digits".
    match rest.rsplit_once(':') {
        Some((path, baud)) if !baud.is_empty() && baud.bytes().all(|b| b.is_ascii_digit()) => {
            let baud: u32 = baud
                .parse()
                .ok()
                .filter(|&b| b > 0)
                .ok_or_else(|| error(input, format!("'{baud}' is not a baud rate")))?;
            Ok(LinkSpec::Serial {
                path: path.to_string(),
                baud: Some(baud),
            })
        }
        // `/dev/ttyS0:abc`: a mistyped baud, not a device named so (device
        // names with colons, as /dev/serial/by-path's, end in `-port0`).
        Some((path, baud))
            if (path.starts_with("/dev/") || is_windows_port(path))
                && !baud.is_empty()
                && baud.bytes().all(|b| b.is_ascii_alphanumeric()) =>
        {
            Err(error(
                input,
                format!("'{baud}' is not a baud rate (e.g. serial:{path}:57600)"),
            ))
        }
        _ => Ok(LinkSpec::Serial {
            path: rest.to_string(),
            baud: None,
        }),
    }
}

/// A Windows serial port named as Windows names it: `COM3`, `com12`, or
/// the device path `\\.\COM12` (what ports above COM9 need in some
/// programs), with an optional `:BAUD`. On every system, so a
/// configuration file means the same wherever it is read.
fn is_windows_port(input: &str) -> bool {
    let name = input.split_once(':').map_or(input, |(name, _)| name);
    let name = name.strip_prefix(r"\\.\").unwrap_or(name);
    strip_prefix_ignoring_case(name, "COM")
        .is_some_and(|n| !n.is_empty() && n.len() <= 3 && n.bytes().all(|b| b.is_ascii_digit()))
}

/// `input` less `prefix`, if it starts with it in any case.
fn strip_prefix_ignoring_case<'a>(input: &'a str, prefix: &str) -> Option<&'a str> {
    input
        .get(..prefix.len())
        .filter(|p| p.eq_ignore_ascii_case(prefix))
        .map(|_| &input[prefix.len()..])
}

impl std::str::FromStr for LinkSpec {
    type Err = AddressError;

    fn from_str(input: &str) -> Result<Self, Self::Err> {
        let input = input.trim();
        if input.is_empty() {
            return Err(error(input, "empty"));
        }
        if input == "sim" || input.starts_with("sim:") {
            let query = input.strip_prefix("sim").unwrap_or_default();
            let query = query.strip_prefix(':').unwrap_or(query);
            return SimParams::parse(query)
                .map(|p| LinkSpec::Sim(Box::new(p)))
                .map_err(|reason| error(input, reason.to_string()));
        }
        if let Some(path) = strip_prefix_ignoring_case(input, "tlog:") {
            if path.is_empty() {
                return Err(error(
                    input,
                    "missing file: tlog:FILE, or tlog:- for standard input",
                ));
            }
            return Ok(LinkSpec::Tlog(TlogPath(path.to_string())));
        }
        // A path naming a log (no serial device is called *.tlog).
        if !input.contains(':') && input.to_ascii_lowercase().ends_with(".tlog") {
            return Ok(LinkSpec::Tlog(TlogPath(input.to_string())));
        }
        if input.starts_with('/') || is_windows_port(input) {
            return serial(input, input);
        }
        if let Some((scheme, rest)) = input.split_once(':') {
            // MAVSDK's forms (`udpin://0.0.0.0:14540`, `udp://:14540`,
            // `tcp://HOST:PORT`, `serial:///dev/ttyUSB0:57600`) mean what
            // ours without the slashes mean; an empty host listens on all.
            let (rest, mavsdk) = match rest.strip_prefix("//") {
                Some(rest) => (rest, true),
                None => (rest, false),
            };
            let listening = |rest: &str| match rest.strip_prefix(':') {
                Some(port) if mavsdk => host_port(input, &format!("0.0.0.0:{port}")),
                _ => host_port(input, rest),
            };
            let spec = match scheme.to_ascii_lowercase().as_str() {
                "udpin" | "udp" => Some(LinkSpec::UdpIn(listening(rest)?)),
                "udpout" => Some(LinkSpec::UdpOut(reachable(input, rest)?)),
                "udpbcast" => Some(LinkSpec::UdpBcast(reachable(input, rest)?)),
                "tcp" | "tcpout" => Some(LinkSpec::TcpOut(reachable(input, rest)?)),
                "tcpin" => Some(LinkSpec::TcpIn(listening(rest)?)),
                "ws" | "wss" if mavsdk => Some(LinkSpec::Ws(Box::new(
                    WsUrl::parse(scheme.eq_ignore_ascii_case("wss"), rest)
                        .map_err(|reason| error(input, reason))?,
                ))),
                "wsin" => Some(LinkSpec::WsIn(listening(rest)?)),
                "m2r" | "m2rs" if mavsdk => Some(LinkSpec::M2r(Box::new(
                    M2rUrl::parse(scheme.eq_ignore_ascii_case("m2rs"), rest)
                        .map_err(|reason| error(input, reason))?,
                ))),
                "serial" => Some(serial(input, rest)?),
                _ => None,
            };
            if let Some(spec) = spec {
                return Ok(spec);
            }
        }
        // A bare HOST:PORT listens, as in pymavlink and MAVProxy.
        match host_port(input, input) {
            Ok(hp) if !hp.host.contains('/') => Ok(LinkSpec::UdpIn(hp)),
            _ => Err(error(input, "unknown form")),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn usb_cdc_and_ptys_may_ignore_the_baud_rate() {
        let spec = |s: &str| s.parse::<LinkSpec>().unwrap();
        assert!(spec("/dev/ttyACM0").may_ignore_baud());
        assert!(spec("serial:/dev/pts/4:57600").may_ignore_baud());
        assert!(!spec("/dev/ttyUSB0").may_ignore_baud());
        assert!(!spec("serial:/dev/ttyAMA0:57600").may_ignore_baud());
        assert!(!spec("udpout:127.0.0.1:14550").may_ignore_baud());
        assert_eq!(spec("/dev/pts/3").baud_ignorer(), Some("a pty"));
        assert_eq!(spec("/dev/ttyACM0").baud_ignorer(), Some("a USB CDC port"));
    }

    fn hp(host: &str, port: u16) -> HostPort {
        HostPort {
            host: host.into(),
            port,
        }
    }

    #[test]
    fn accepted_forms_parse() {
        let table: Vec<(&str, LinkSpec)> = vec![
            ("udpin:0.0.0.0:14550", LinkSpec::UdpIn(hp("0.0.0.0", 14550))),
            (
                "udp:127.0.0.1:14550",
                LinkSpec::UdpIn(hp("127.0.0.1", 14550)),
            ),
            ("127.0.0.1:14550", LinkSpec::UdpIn(hp("127.0.0.1", 14550))),
            ("localhost:14550", LinkSpec::UdpIn(hp("localhost", 14550))),
            (
                "udpout:127.0.0.1:14550",
                LinkSpec::UdpOut(hp("127.0.0.1", 14550)),
            ),
            ("udpout:[::1]:14550", LinkSpec::UdpOut(hp("::1", 14550))),
            ("UDPOUT:[::1]:1", LinkSpec::UdpOut(hp("::1", 1))),
            (
                "udpbcast:127.255.255.255:14550",
                LinkSpec::UdpBcast(hp("127.255.255.255", 14550)),
            ),
            (
                "tcp:127.0.0.1:5760",
                LinkSpec::TcpOut(hp("127.0.0.1", 5760)),
            ),
            (
                "tcpout:127.0.0.1:5760",
                LinkSpec::TcpOut(hp("127.0.0.1", 5760)),
            ),
            ("tcpin:[::]:5760", LinkSpec::TcpIn(hp("::", 5760))),
            (
                "serial:/dev/ttyUSB0:57600",
                LinkSpec::Serial {
                    path: "/dev/ttyUSB0".into(),
                    baud: Some(57600),
                },
            ),
            (
                "/dev/ttyACM0",
                LinkSpec::Serial {
                    path: "/dev/ttyACM0".into(),
                    baud: None,
                },
            ),
            (
                "serial:/dev/pts/3",
                LinkSpec::Serial {
                    path: "/dev/pts/3".into(),
                    baud: None,
                },
            ),
            (
                "tlog:flight.tlog",
                LinkSpec::Tlog(TlogPath("flight.tlog".into())),
            ),
            ("TLOG:-", LinkSpec::Tlog(TlogPath("-".into()))),
            ("tlog:/tmp/a:b", LinkSpec::Tlog(TlogPath("/tmp/a:b".into()))),
            (
                "/logs/2026-12-01.TLOG",
                LinkSpec::Tlog(TlogPath("/logs/2026-12-01.TLOG".into())),
            ),
            (
                "flight.tlog",
                LinkSpec::Tlog(TlogPath("flight.tlog".into())),
            ),
            (
                "serial:/dev/odd.tlog",
                LinkSpec::Serial {
                    path: "/dev/odd.tlog".into(),
                    baud: None,
                },
            ),
        ];
        for (input, expected) in table {
            assert_eq!(input.parse::<LinkSpec>(), Ok(expected), "{input}");
        }
    }

    #[test]
    fn bad_forms_name_the_accepted_ones() {
        for input in [
            "",
            "udpout:127.0.0.1",
            "udpout:127.0.0.1:99999",
            "udpout::14550",
            "udpout:::1:14550",
            "udpout:[::1:14550",
            "carrier-pigeon:1:2",
            "14550",
            "serial:",
            "serial:/dev/ttyUSB0:0",
            "serial:/dev/ttyS0:abc",
            "/dev/ttyS0:fast",
            "udpout:127.0.0.1:0",
            "udpbcast:255.255.255.255:0",
            "tcp:localhost:0",
            "udpout://127.0.0.1:0",
            "sim:?bogus=1",
            "tlog:",
        ] {
            let err = input.parse::<LinkSpec>().unwrap_err().to_string();
            assert!(
                err.contains("accepted forms: udpin:HOST:PORT"),
                "{input}: {err}"
            );
        }
    }

    #[test]
    fn mavsdk_forms_mean_what_ours_do() {
        let same = [
            ("udp://:14540", "udpin:0.0.0.0:14540"),
            ("udpin://0.0.0.0:14540", "udpin:0.0.0.0:14540"),
            ("udp://127.0.0.1:14550", "udpin:127.0.0.1:14550"),
            ("udpout://192.168.1.12:14550", "udpout:192.168.1.12:14550"),
            ("tcp://127.0.0.1:5760", "tcp:127.0.0.1:5760"),
            ("tcpout://127.0.0.1:5760", "tcp:127.0.0.1:5760"),
            ("tcpin://:5760", "tcpin:0.0.0.0:5760"),
            ("serial:///dev/ttyUSB0:57600", "serial:/dev/ttyUSB0:57600"),
            (
                "/dev/serial/by-path/pci-0000:00:14.0-usb-0:2:1.0-port0",
                "serial:/dev/serial/by-path/pci-0000:00:14.0-usb-0:2:1.0-port0",
            ),
        ];
        for (theirs, ours) in same {
            assert_eq!(theirs.parse::<LinkSpec>(), ours.parse(), "{theirs}");
        }
        let err = "serial:/dev/ttyS0:abc".parse::<LinkSpec>().unwrap_err();
        assert!(err.reason.contains("'abc' is not a baud rate"), "{err}");
        let err = "udpout:127.0.0.1:0".parse::<LinkSpec>().unwrap_err();
        assert!(err.reason.contains("port 0 names no peer"), "{err}");
    }

    #[test]
    fn windows_and_macos_serial_names_parse_on_every_system() {
        let serial = |path: &str, baud: Option<u32>| LinkSpec::Serial {
            path: path.into(),
            baud,
        };
        for (input, expected) in [
            ("COM3", serial("COM3", None)),
            ("com3", serial("com3", None)),
            ("COM3:57600", serial("COM3", Some(57600))),
            ("serial:COM3:57600", serial("COM3", Some(57600))),
            ("serial:COM12", serial("COM12", None)),
            (r"\\.\COM12:115200", serial(r"\\.\COM12", Some(115200))),
            (
                "serial:/dev/cu.usbserial-1410:57600",
                serial("/dev/cu.usbserial-1410", Some(57600)),
            ),
            (
                "/dev/tty.usbserial-A10K",
                serial("/dev/tty.usbserial-A10K", None),
            ),
            (
                "/dev/cu.usbmodem14101",
                serial("/dev/cu.usbmodem14101", None),
            ),
        ] {
            assert_eq!(input.parse::<LinkSpec>(), Ok(expected), "{input}");
        }
        // A host whose name starts with COM is still a host.
        assert_eq!(
            "computer:14550".parse::<LinkSpec>(),
            Ok(LinkSpec::UdpIn(hp("computer", 14550)))
        );
        assert_eq!(
            "COM1X:14550".parse::<LinkSpec>(),
            Ok(LinkSpec::UdpIn(hp("COM1X", 14550)))
        );
        for bad in ["COM3:fast", "COM3:0", "serial:COM3:0"] {
            let err = bad.parse::<LinkSpec>().unwrap_err();
            assert!(err.reason.contains("baud rate"), "{bad}: {err}");
        }
        assert!("/dev/cu.usbmodem14101"
            .parse::<LinkSpec>()
            .unwrap()
            .may_ignore_baud());
        assert!(!"COM3".parse::<LinkSpec>().unwrap().may_ignore_baud());
    }

    #[test]
    fn display_round_trips() {
        for input in [
            "udpout:[::1]:14550",
            "tcpin:0.0.0.0:5760",
            "serial:/dev/ttyUSB0:57600",
            "serial:COM3:57600",
            "tlog:-",
            "m2r://127.0.0.1:8088/v1/ws/mavlink",
            "m2rs://blueos.example.com:443/mavlink2rest/v1/ws/mavlink",
        ] {
            assert_eq!(input.parse::<LinkSpec>().unwrap().to_string(), input);
        }
    }

    #[test]
    fn mavlink2rest_urls_are_m2r_and_need_their_slashes() {
        let spec = "M2R://blueos.local".parse::<LinkSpec>().unwrap();
        assert!(matches!(spec, LinkSpec::M2r(_)), "{spec:?}");
        assert_eq!(spec.to_string(), "m2r://blueos.local:8088/v1/ws/mavlink");
        let err = "m2r:127.0.0.1:8088".parse::<LinkSpec>().unwrap_err();
        assert_eq!(err.reason, "unknown form");
        let err = "m2r://127.0.0.1:99999/".parse::<LinkSpec>().unwrap_err();
        assert!(err.reason.contains("not a port"), "{err}");
    }
}
