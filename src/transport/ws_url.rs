//! `ws://[USER:PASSWORD@]HOST[:PORT][/PATH]` and `wss://...`: where a
//! WebSocket link connects, as a URL says it (pymavlink's `ws:` and
//! `wss:`, mavlink-server's and Mission Planner's endpoints). Shown in
//! reports with the password hidden.

use std::fmt;

use super::address::HostPort;

/// A WebSocket server to connect to.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct WsUrl {
    /// `wss://`: TLS under the WebSocket.
    pub(crate) tls: bool,
    pub(crate) addr: HostPort,
    /// The request's path and query, from its `/`.
    pub(crate) path: String,
    /// Basic authentication from the URL's user part.
    pub(crate) auth: Option<(String, String)>,
}

impl WsUrl {
    /// `rest` is what follows `ws://` or `wss://`; the reason it is not a
    /// URL, if it is not.
    pub(crate) fn parse(tls: bool, rest: &str) -> Result<WsUrl, String> {
        let (authority, path) = match rest.find(['/', '?']) {
            Some(at) => (&rest[..at], &rest[at..]),
            None => (rest, "/"),
        };
        let path = if path.starts_with('?') {
            format!("/{path}")
        } else {
            path.to_string()
        };
        let (auth, hostport) = match authority.rsplit_once('@') {
            Some((user, hostport)) => {
                let (name, password) = user.split_once(':').unwrap_or((user, ""));
                (
                    Some((percent_decoded(name)?, percent_decoded(password)?)),
                    hostport,
                )
            }
            None => (None, authority),
        };
        let default_port = if tls { 443 } else { 80 };
        let (host, port) = split_port(hostport, default_port)?;
        if host.is_empty() {
            return Err("missing host (e.g. ws://127.0.0.1:5777/)".into());
        }
        Ok(WsUrl {
            tls,
            addr: HostPort {
                host: host.to_string(),
                port,
            },
            path,
            auth,
        })
    }

    /// The URL the handshake asks for (with no user part: that goes in a
    /// header).
    pub(crate) fn request_uri(&self) -> String {
        let scheme = if self.tls { "wss" } else { "ws" };
        format!("{scheme}://{}{}", self.addr, self.path)
    }
}

/// `HOST:PORT`, `[V6]:PORT`, or either without the port.
fn split_port(hostport: &str, default: u16) -> Result<(&str, u16), String> {
    let port = |p: &str| {
        p.parse::<u16>()
            .ok()
            .filter(|&p| p > 0)
            .ok_or_else(|| format!("'{p}' is not a port (1-65535)"))
    };
    if let Some(bracketed) = hostport.strip_prefix('[') {
        let (host, after) = bracketed
            .split_once(']')
            .ok_or("missing ']' after IPv6 address")?;
        return match after.strip_prefix(':') {
            Some(p) => Ok((host, port(p)?)),
            None if after.is_empty() => Ok((host, default)),
            None => Err(format!("'{after}' after the IPv6 address")),
        };
    }
    match hostport.rsplit_once(':') {
        Some((host, p)) => Ok((host, port(p)?)),
        None => Ok((hostport, default)),
    }
}

/// A URL's user part with `%XX` escapes decoded (a password with `@`).
fn percent_decoded(text: &str) -> Result<String, String> {
    let bytes = text.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i] == b'%' {
            let hex = text
                .get(i + 1..i + 3)
                .and_then(|h| u8::from_str_radix(h, 16).ok())
                .ok_or_else(|| format!("bad %-escape in '{text}'"))?;
            out.push(hex);
            i += 3;
        } else {
            out.push(bytes[i]);
            i += 1;
        }
    }
    String::from_utf8(out).map_err(|_| format!("'{text}' is not UTF-8 once decoded"))
}

impl fmt::Display for WsUrl {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let scheme = if self.tls { "wss" } else { "ws" };
        let user = match &self.auth {
            // The password never reaches a report.
            Some((name, _)) => format!("{name}:***@"),
            None => String::new(),
        };
        write!(f, "{scheme}://{user}{}{}", self.addr, self.path)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn url(tls: bool, rest: &str) -> WsUrl {
        WsUrl::parse(tls, rest).unwrap_or_else(|e| panic!("{rest}: {e}"))
    }

    #[test]
    fn a_url_names_host_port_path_and_user() {
        let u = url(false, "127.0.0.1:5777/ws/mavlink");
        assert_eq!(
            (u.addr.host.as_str(), u.addr.port, u.path.as_str()),
            ("127.0.0.1", 5777, "/ws/mavlink")
        );
        assert_eq!(u.request_uri(), "ws://127.0.0.1:5777/ws/mavlink");
        let u = url(
            true,
            "pilot:s%40cret@blueos.local/v1/ws/mavlink?filter=PING",
        );
        assert_eq!(u.addr.port, 443);
        assert_eq!(u.path, "/v1/ws/mavlink?filter=PING");
        assert_eq!(u.auth, Some(("pilot".into(), "s@cret".into())));
        assert_eq!(
            u.to_string(),
            "wss://pilot:***@blueos.local:443/v1/ws/mavlink?filter=PING"
        );
        let u = url(false, "[::1]:8080");
        assert_eq!((u.addr.host.as_str(), u.path.as_str()), ("::1", "/"));
        assert_eq!(u.to_string(), "ws://[::1]:8080/");
    }

    #[test]
    fn what_is_not_a_url_says_why() {
        for (rest, says) in [
            ("127.0.0.1:0/", "not a port"),
            ("127.0.0.1:http/", "not a port"),
            (":5777/", "missing host"),
            ("[::1:5777", "missing ']'"),
            ("u:%zz@h/", "bad %-escape"),
        ] {
            let e = WsUrl::parse(false, rest).unwrap_err();
            assert!(e.contains(says), "{rest}: {e}");
        }
    }
}
