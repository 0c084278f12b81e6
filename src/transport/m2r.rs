//! `m2r://` and `m2rs://`: mavlink2rest's WebSocket (BlueOS's
//! `/v1/ws/mavlink`, mavlink-server's `/v1/rest/ws`), where every MAVLink
//! message is a JSON text ([`crate::frame::json`]). Each frame mavping
//! sends goes as one text; each text received is made a MAVLink 2 frame
//! again, with the header's ids and sequence, and scanned as a datagram
//! is: everything after this link sees ordinary frames.
//!
//! The JSON costs what it costs: a message is parsed and re-serialised on
//! the way, and mavlink2rest answers each message sent with a text of its
//! own (`Ok(14)`). Texts that are no message are skipped and counted as
//! the scanner counts junk (their bytes in `skipped_bytes`); messages of
//! types this build does not know as `unknown_id`. A binary message of
//! MAVLink frames before any JSON means the URL names a binary endpoint.

use tokio::time::Instant;
use tokio_tungstenite::tungstenite::protocol::WebSocketConfig;
use tokio_tungstenite::tungstenite::{Error as WsError, Message};

use super::link::push_datagram;
use super::m2r_url::M2rUrl;
use super::route::Route;
use super::ws::{self, MessageLink, Socket, Trust};
use super::{Inbound, LinkError, LinkKind, PathId, Transport};
use crate::frame::json::{from_json, to_json, FromJson};
use crate::frame::{scan_datagram, ScanStats};

/// A mavlink2rest message is a few kilobytes at most (pretty-printed, a
/// 253-byte array one number a line): a larger one ends the link rather
/// than the memory.
const MAX_MESSAGE: usize = 64 * 1024;
/// This many messages with none a MAVLink message among them, and the link
/// ends: whatever is at the other end, it is not a mavlink2rest.
const JUNK_LIMIT: u64 = 20;

/// What this link has taken from the JSON, beside the scanner's counts.
#[derive(Debug, Default)]
struct Counts {
    messages: u64,
    unknown: u64,
    junk: u64,
    binary: u64,
    /// mavlink2rest's answers to what we sent (`Ok(14)`).
    acks: u64,
    /// Its refusals (`Could not convert input message.`, `Err(..)`).
    refused: u64,
}

/// `m2r://` or `m2rs://`: one mavlink2rest WebSocket.
pub(crate) struct M2rClient {
    name: String,
    ws: Socket,
    /// Why the WebSocket ended, told after the frames that came before.
    gone: Option<String>,
    stats: ScanStats,
    keep_raw: bool,
    counts: Counts,
}

impl M2rClient {
    pub(crate) async fn connect(
        url: &M2rUrl,
        route: &Route,
        trust: &Trust,
    ) -> Result<Self, LinkError> {
        let name = url.to_string();
        let config = WebSocketConfig::default()
            .max_message_size(Some(MAX_MESSAGE))
            .max_frame_size(Some(MAX_MESSAGE));
        let ws = ws::open(&url.0, &name, route, trust, Some(config)).await?;
        Ok(M2rClient {
            name,
            ws,
            gone: None,
            stats: ScanStats::default(),
            keep_raw: false,
            counts: Counts::default(),
        })
    }

    /// One message read: its frame into `out`; Some(why) when the link
    /// must end.
    fn read(&mut self, msg: Result<Message, WsError>, out: &mut Vec<Inbound>) -> Option<String> {
        match msg {
            Ok(Message::Text(text)) => self.text(text.as_str(), out),
            Ok(Message::Binary(data)) => self.binary(&data),
            Ok(Message::Close(frame)) => Some(ws::closed(frame)),
            Ok(Message::Ping(_) | Message::Pong(_) | Message::Frame(_)) => None,
            Err(WsError::Capacity(e)) => Some(format!(
                "{e}: a mavlink2rest message is a few kilobytes; is this one?"
            )),
            Err(e) => Some(ws::broken(&e)),
        }
    }

    fn text(&mut self, text: &str, out: &mut Vec<Inbound>) -> Option<String> {
        let json = match from_json(text) {
            FromJson::Frame(raw) => {
                self.counts.messages += 1;
                push_datagram(&raw, Instant::now(), 0, self.keep_raw, &mut self.stats, out);
                return None;
            }
            FromJson::Unknown(name) => {
                self.counts.unknown += 1;
                self.stats.unknown_id += 1;
                if self.counts.unknown == 1 {
                    tracing::warn!(link = %self.name, message_type = %name,
                        "a message of a type this build does not know: skipped (counted as unknown ids)");
                }
                return None;
            }
            FromJson::NotMessage(why) => why,
        };
        // mavlink2rest answers each message sent with its Rust result.
        if text.starts_with("Ok(") {
            self.counts.acks += 1;
            return None;
        }
        if text.starts_with("Err(") || text.starts_with("Could not convert") {
            self.counts.refused += 1;
            if self.counts.refused == 1 {
                tracing::warn!(link = %self.name, answer = %excerpt(text),
                    "the server could not take a message mavping sent");
            }
            return None;
        }
        self.junk(text.len(), || {
            format!("a text that is no message: {json}: {}", excerpt(text))
        })
    }

    fn binary(&mut self, data: &[u8]) -> Option<String> {
        self.counts.binary += 1;
        let mut frames = 0;
        scan_datagram(data, &mut ScanStats::default(), &mut |_| frames += 1);
        if frames > 0 && self.counts.messages == 0 {
            return Some(format!(
                "it sent MAVLink's binary frames ({} bytes) where mavlink2rest's JSON texts were \
                 expected: a binary WebSocket endpoint is ws://",
                data.len()
            ));
        }
        self.junk(data.len(), || {
            format!("a binary message of {} bytes", data.len())
        })
    }

    /// Junk counted (its bytes as the scanner's skipped bytes), told once;
    /// Some(why) when nothing but junk has come.
    fn junk(&mut self, len: usize, what: impl Fn() -> String) -> Option<String> {
        self.counts.junk += 1;
        self.stats.skipped_bytes += len as u64;
        if self.counts.junk == 1 {
            tracing::warn!(link = %self.name, "skipped {}", what());
        }
        (self.counts.messages == 0 && self.counts.junk >= JUNK_LIMIT).then(|| {
            format!(
                "{} messages and no MAVLink message among them (the last: {}): is it a \
                 mavlink2rest WebSocket?",
                self.counts.junk,
                what()
            )
        })
    }
}

/// The start of a text, on one line, for a log line.
fn excerpt(text: &str) -> String {
    let line = text.split_whitespace().collect::<Vec<_>>().join(" ");
    let short: String = line.chars().take(60).collect();
    if short.len() < line.len() {
        format!("{short}...")
    } else {
        short
    }
}

impl Drop for M2rClient {
    fn drop(&mut self) {
        tracing::info!(link = %self.name, counts = ?self.counts, "mavlink2rest JSON");
    }
}

impl MessageLink for M2rClient {
    fn socket(&mut self) -> &mut Socket {
        &mut self.ws
    }

    fn name(&self) -> &str {
        &self.name
    }

    fn gone(&mut self) -> &mut Option<String> {
        &mut self.gone
    }

    fn take(&mut self, msg: Result<Message, WsError>, out: &mut Vec<Inbound>) -> Option<String> {
        self.read(msg, out)
    }
}

impl Transport for M2rClient {
    async fn send(&mut self, frame: &[u8]) -> Result<Instant, LinkError> {
        let sent = Instant::now();
        let mut texts = Vec::new();
        scan_datagram(frame, &mut ScanStats::default(), &mut |raw| {
            texts.extend(to_json(raw))
        });
        for text in texts {
            self.send_message(Message::Text(text.into())).await?;
        }
        Ok(sent)
    }

    async fn send_to(&mut self, _path: PathId, frame: &[u8]) -> Result<Instant, LinkError> {
        self.send(frame).await
    }

    async fn recv(&mut self, out: &mut Vec<Inbound>) -> Result<(), LinkError> {
        self.recv_messages(out).await
    }

    fn scan_stats(&self) -> ScanStats {
        self.stats
    }

    fn kind(&self) -> LinkKind {
        LinkKind::Connecting
    }

    fn keep_raw(&mut self) {
        self.keep_raw = true;
    }
}
