//! `m2r://[USER:PASSWORD@]HOST[:PORT][/PATH]` and `m2rs://...`: a
//! mavlink2rest WebSocket, whose messages are JSON texts. A WebSocket URL
//! ([`WsUrl`]) with mavlink2rest's defaults: port 8088 (its `--server`;
//! `m2rs://` 443, TLS being a proxy's) and path `/v1/ws/mavlink`.

use std::fmt;

use super::ws_url::WsUrl;

/// mavlink2rest's own port.
const PORT: u16 = 8088;
/// mavlink2rest's WebSocket of every message.
const PATH: &str = "/v1/ws/mavlink";

/// A mavlink2rest WebSocket to connect to.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct M2rUrl(pub(crate) WsUrl);

impl M2rUrl {
    /// `rest` is what follows `m2r://` or `m2rs://`.
    pub(crate) fn parse(tls: bool, rest: &str) -> Result<M2rUrl, String> {
        let at = rest.find(['/', '?']).unwrap_or(rest.len());
        let (authority, path) = rest.split_at(at);
        let path = match path {
            "" | "/" => PATH.to_string(),
            query if query.starts_with('?') => format!("{PATH}{query}"),
            path => path.to_string(),
        };
        let hostport = authority.rsplit_once('@').map_or(authority, |(_, hp)| hp);
        let has_port = match hostport.rsplit_once(']') {
            Some((_, after)) => !after.is_empty(),
            None => hostport.contains(':'),
        };
        let authority = if has_port || tls || hostport.is_empty() {
            authority.to_string()
        } else {
            format!("{authority}:{PORT}")
        };
        WsUrl::parse(tls, &format!("{authority}{path}"))
            .map(M2rUrl)
            .map_err(|e| e.replace("ws://", "m2r://"))
    }
}

impl fmt::Display for M2rUrl {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        // The WebSocket URL as shown (password hidden), its scheme ours:
        // `ws://` becomes `m2r://`, `wss://` `m2rs://`.
        let shown = self.0.to_string();
        let rest = shown.strip_prefix("ws").unwrap_or(&shown);
        write!(f, "m2r{rest}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn shown(tls: bool, rest: &str) -> (String, String) {
        let url = M2rUrl::parse(tls, rest).unwrap_or_else(|e| panic!("{rest}: {e}"));
        (url.to_string(), url.0.request_uri())
    }

    #[test]
    fn mavlink2rest_s_port_and_path_are_the_defaults() {
        for (tls, rest, name, uri) in [
            (
                false,
                "127.0.0.1",
                "m2r://127.0.0.1:8088/v1/ws/mavlink",
                "ws://127.0.0.1:8088/v1/ws/mavlink",
            ),
            (
                false,
                "blueos.local:80/mavlink2rest/v1/ws/mavlink",
                "m2r://blueos.local:80/mavlink2rest/v1/ws/mavlink",
                "ws://blueos.local:80/mavlink2rest/v1/ws/mavlink",
            ),
            (
                false,
                "[::1]?filter=PING|TIMESYNC",
                "m2r://[::1]:8088/v1/ws/mavlink?filter=PING|TIMESYNC",
                "ws://[::1]:8088/v1/ws/mavlink?filter=PING|TIMESYNC",
            ),
            (
                false,
                "pilot:s%40cret@10.0.0.2/",
                "m2r://pilot:***@10.0.0.2:8088/v1/ws/mavlink",
                "ws://10.0.0.2:8088/v1/ws/mavlink",
            ),
            (
                true,
                "blueos.example.com/mavlink2rest/v1/ws/mavlink",
                "m2rs://blueos.example.com:443/mavlink2rest/v1/ws/mavlink",
                "wss://blueos.example.com:443/mavlink2rest/v1/ws/mavlink",
            ),
        ] {
            assert_eq!(shown(tls, rest), (name.to_string(), uri.to_string()));
        }
    }

    #[test]
    fn what_is_not_a_url_says_why() {
        for (rest, says) in [
            ("127.0.0.1:0/", "not a port"),
            ("127.0.0.1:x", "not a port"),
            ("", "missing host (e.g. m2r://"),
            ("/v1/ws/mavlink", "missing host"),
            ("[::1", "missing ']'"),
        ] {
            let e = M2rUrl::parse(false, rest).unwrap_err();
            assert!(e.contains(says), "{rest}: {e}");
        }
    }
}
