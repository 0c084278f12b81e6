//! What a serial link can carry: frame sizes, requests per second at a
//! baud rate (PING or TIMESYNC exchanges, each its own sizes), and the
//! serialisation floor under every RTT. Pure arithmetic.
//!
//! A pty or a USB adapter may ignore the baud rate, but the radio behind
//! a real port cannot: these figures are what the radio's UART delivers.

use serde::Serialize;

use super::SessionConfig;
use crate::frame::Version;

/// Start bit, 8 data bits, stop bit.
pub(crate) const BITS_PER_BYTE: u64 = 10;
/// PING's payload: time_usec u64, seq u32, target system and component.
const PING_PAYLOAD: u64 = 14;
const V1_OVERHEAD: u64 = 6 + 2;
const V2_OVERHEAD: u64 = 10 + 2;
/// A MAVLink 2 signature (link id, timestamp, signature).
pub(crate) const SIGNATURE: u64 = 13;
/// TIMESYNC's payload: tc1 and ts1 (i64 each); MAVLink 2 adds the
/// target system and component as extensions.
const TIMESYNC_PAYLOAD: u64 = 16;
const TIMESYNC_TARGETS: u64 = 2;

/// The request and reply a probe's exchange is made of.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Exchange {
    Ping,
    /// Our request names `target` (0/0: any).
    Timesync {
        target: crate::frame::SysComp,
    },
}

impl Exchange {
    /// The message, as the text names it ("PINGs/s").
    pub(crate) fn message(self) -> &'static str {
        match self {
            Exchange::Ping => "PING",
            Exchange::Timesync { .. } => "TIMESYNC",
        }
    }

    /// Bytes of a request (with sequence numbers up to `max_seq`) and of
    /// a reply, unsigned.
    pub(crate) fn bytes(self, version: Version, max_seq: u32) -> (u64, u64) {
        match self {
            Exchange::Ping => (request_bytes(version, max_seq), reply_bytes(version, false)),
            Exchange::Timesync { target } => timesync_bytes(version, target),
        }
    }
}

/// A TIMESYNC request and reply. MAVLink 2 trims trailing zero bytes: a
/// request to 0/0 ends at ts1 (our clock in ns, never zero in its high
/// byte on a wall clock); a reply is counted with its targets set, as
/// PX4 and `mavping respond` send it (ArduPilot's 0/0 is 2 bytes less).
fn timesync_bytes(version: Version, target: crate::frame::SysComp) -> (u64, u64) {
    match version {
        Version::V1 => (
            V1_OVERHEAD + TIMESYNC_PAYLOAD,
            V1_OVERHEAD + TIMESYNC_PAYLOAD,
        ),
        Version::V2 => {
            let targets = match (target.sysid, target.compid) {
                (_, c) if c != 0 => 2,
                (s, _) if s != 0 => 1,
                _ => 0,
            };
            (
                V2_OVERHEAD + TIMESYNC_PAYLOAD + targets,
                V2_OVERHEAD + TIMESYNC_PAYLOAD + TIMESYNC_TARGETS,
            )
        }
    }
}

/// Bytes of a PING reply: its targets are set, so nothing is trimmed.
pub(crate) fn reply_bytes(version: Version, signed: bool) -> u64 {
    let base = match version {
        Version::V1 => V1_OVERHEAD + PING_PAYLOAD,
        Version::V2 => V2_OVERHEAD + PING_PAYLOAD,
    };
    base + if signed { SIGNATURE } else { 0 }
}

/// Bytes of our PING request with sequence numbers up to `max_seq`.
/// MAVLink 2 trims trailing zero bytes of the payload: the targets (0/0)
/// and the seq's unused high bytes go. time_usec is never zero.
pub(crate) fn request_bytes(version: Version, max_seq: u32) -> u64 {
    match version {
        Version::V1 => V1_OVERHEAD + PING_PAYLOAD,
        Version::V2 => {
            let seq_bytes = 4 - u64::from(max_seq.leading_zeros() / 8);
            V2_OVERHEAD + 8 + seq_bytes
        }
    }
}

/// A serial link's budget for one request and its replies.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct WireBudget {
    pub(crate) baud: u32,
    /// The request's message, as the text names it ("PINGs/s"); the
    /// start line names the probe in JSON.
    #[serde(skip)]
    pub(crate) message: &'static str,
    pub(crate) request_bytes: u64,
    pub(crate) reply_bytes: u64,
    /// Replies each request is expected to draw.
    pub(crate) replies: u64,
    /// Request and replies share the radio's air time (SiK is half duplex),
    /// so the bound is the baud's bytes over all of them.
    pub(crate) max_rate_hz: f64,
    /// Request plus one reply at the baud: the part of every RTT the wire
    /// itself costs, before any radio or autopilot processing.
    pub(crate) floor_us: f64,
    /// The device may pass data faster than the baud (a pty, USB CDC):
    /// then the figures are a bound the run may not be under, and the
    /// summary says whether the replies could tell.
    #[serde(skip)]
    pub(crate) ignorer: Option<&'static str>,
    pub(crate) may_ignore_baud: bool,
}

#[cfg(test)]
/// A PING exchange's budget.
pub(crate) fn budget(baud: u32, version: Version, max_seq: u32, replies: u64) -> WireBudget {
    exchange_budget(Exchange::Ping, baud, version, max_seq, replies)
}

pub(crate) fn exchange_budget(
    exchange: Exchange,
    baud: u32,
    version: Version,
    max_seq: u32,
    replies: u64,
) -> WireBudget {
    let (request, reply) = exchange.bytes(version, max_seq);
    sized(exchange.message(), baud, request, reply, replies)
}

fn sized(message: &'static str, baud: u32, request: u64, reply: u64, replies: u64) -> WireBudget {
    let bytes_per_s = u64::from(baud) as f64 / BITS_PER_BYTE as f64;
    WireBudget {
        baud,
        message,
        request_bytes: request,
        reply_bytes: reply,
        replies: 0,
        max_rate_hz: 0.0,
        floor_us: (request + reply) as f64 / bytes_per_s * 1e6,
        ignorer: None,
        may_ignore_baud: false,
    }
    .with_replies(replies)
}

/// The budget of `exchange` at `baud`, where each request draws
/// `replies` (one on a real link unless the run shows more: the warning is
/// a floor). Which links have a baud rate is the configuration's business.
pub(crate) fn for_baud(
    baud: u32,
    replies: u64,
    session: &SessionConfig,
    exchange: Exchange,
) -> WireBudget {
    // The largest seq of the run sets the request's length; an endless run
    // is assumed to reach full width.
    let max_seq = session
        .count
        .and_then(|c| u32::try_from(c.saturating_sub(1)).ok())
        .and_then(|c| session.first_seq.checked_add(c))
        .unwrap_or(u32::MAX);
    let b = exchange_budget(exchange, baud, session.version, max_seq, replies);
    // Signed, our request and (from a peer that signs) each reply carry a
    // 13-byte signature more.
    match session.signing {
        Some(_) => sized(
            b.message,
            baud,
            b.request_bytes + SIGNATURE,
            b.reply_bytes + SIGNATURE,
            replies,
        ),
        None => b,
    }
}

impl WireBudget {
    /// The same link with `replies` replies per request.
    pub(crate) fn with_replies(self, replies: u64) -> WireBudget {
        let replies = replies.max(1);
        let bytes_per_s = u64::from(self.baud) as f64 / BITS_PER_BYTE as f64;
        WireBudget {
            replies,
            max_rate_hz: bytes_per_s / (self.request_bytes + replies * self.reply_bytes) as f64,
            ..self
        }
    }

    /// The one-line warning before a run whose rate the link cannot carry.
    pub(crate) fn warning(&self, rate_hz: f64) -> Option<String> {
        (rate_hz > self.max_rate_hz).then(|| {
            format!(
                "at {} baud this link carries at most ~{:.0} {}s/s each way; {}/s will queue and then lose",
                self.baud,
                self.max_rate_hz.floor(),
                self.message,
                trim(rate_hz)
            )
        })
    }
}

fn trim(v: f64) -> String {
    if v.fract() == 0.0 {
        format!("{v:.0}")
    } else {
        format!("{v:.1}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_sizes_match_the_spec() {
        assert_eq!(reply_bytes(Version::V2, false), 26);
        assert_eq!(reply_bytes(Version::V1, false), 22);
        assert_eq!(reply_bytes(Version::V2, true), 39);
        assert_eq!(request_bytes(Version::V1, 5), 22);
        // Targets and the seq's zero high bytes trimmed.
        assert_eq!(request_bytes(Version::V2, 200), 21);
        assert_eq!(request_bytes(Version::V2, 300), 22);
        assert_eq!(request_bytes(Version::V2, u32::MAX), 24);
    }

    #[test]
    fn signed_frames_cost_13_bytes_each_way() {
        use crate::frame::signing::{SecretKey, SigningConfig};
        use crate::frame::SysComp;
        use std::time::Duration;
        let budget_of = |signing: Option<SigningConfig>| {
            let session = SessionConfig {
                link_name: "serial:/dev/ttyUSB0:57600".into(),
                ours: SysComp::new(255, 190),
                interval: Duration::from_secs(1),
                count: Some(100),
                deadline: None,
                wait: None,
                interim: None,
                timeout: Duration::from_secs(2),
                version: Version::V2,
                heartbeat: true,
                answer: true,
                capacity: 64,
                window: crate::engine::matcher::Window::FirstAnswer,
                first_seq: 0,
                precise_pacing: true,
                signing,
                sweep: None,
                wire: None,
                radio_type: crate::engine::radio::RadioType::Auto,
                c2: None,
            };
            for_baud(57_600, 1, &session, Exchange::Ping)
        };
        let plain = budget_of(None);
        let signed = budget_of(Some(SigningConfig {
            key: SecretKey::parse("k").unwrap(),
            link_id: 0,
            require_signed: false,
        }));
        assert_eq!(
            (signed.request_bytes, signed.reply_bytes),
            (plain.request_bytes + 13, plain.reply_bytes + 13)
        );
        // 5760 bytes/s over 21 + 13 + 26 + 13 bytes: 78.9 PINGs/s.
        assert_eq!(signed.max_rate_hz.floor(), 78.0);
        assert!(signed.floor_us > plain.floor_us);
    }

    #[test]
    fn capacity_at_57600_baud() {
        // 5760 bytes/s over 21 + 26 bytes: 122.55 PINGs/s.
        let b = budget(57_600, Version::V2, 99, 1);
        assert_eq!(b.max_rate_hz.floor(), 122.0);
        // 47 bytes at 5760 bytes/s = 8159.7 µs.
        assert!((b.floor_us - 47.0 / 5760.0 * 1e6).abs() < 1e-6);
        assert!(b.warning(100.0).is_none());
        assert_eq!(
            b.warning(500.0).unwrap(),
            "at 57600 baud this link carries at most ~122 PINGs/s each way; 500/s will queue and then lose"
        );
        // Two responders: 21 + 52 bytes.
        assert_eq!(budget(57_600, Version::V2, 99, 2).max_rate_hz.floor(), 78.0);
    }

    #[test]
    fn a_timesync_exchange_has_its_own_sizes_and_name() {
        use crate::frame::SysComp;
        let any = Exchange::Timesync {
            target: SysComp::new(0, 0),
        };
        let one = Exchange::Timesync {
            target: SysComp::new(1, 1),
        };
        // 12 bytes of MAVLink 2 frame around tc1 and ts1, and the targets
        // when set (a reply's always, as PX4 sends it).
        assert_eq!(any.bytes(Version::V2, 99), (28, 30));
        assert_eq!(one.bytes(Version::V2, 99), (30, 30));
        assert_eq!(any.bytes(Version::V1, 99), (24, 24));
        // 5760 bytes/s over 28 + 30: 99.3 TIMESYNCs/s, not PING's 122.
        let b = exchange_budget(any, 57_600, Version::V2, 99, 1);
        assert_eq!((b.max_rate_hz.floor(), b.message), (99.0, "TIMESYNC"));
        assert_eq!(
            b.warning(500.0).unwrap(),
            "at 57600 baud this link carries at most ~99 TIMESYNCs/s each way; 500/s will queue and then lose"
        );
        assert!((b.floor_us - 58.0 / 5760.0 * 1e6).abs() < 1e-6);
    }
}
