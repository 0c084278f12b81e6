//! WebSocket links: `ws://` and `wss://` connect to a server as a client
//! (pymavlink's `wsserver:`, BlueOS's mavlink-server, Mission Planner's
//! `/websocket/raw`); `wsin:HOST:PORT` listens and pings every client that
//! connects, as `tcpin:` does. MAVLink frames travel in binary messages,
//! one message holding one or more whole frames.
//!
//! The WebSocket protocol is the `tungstenite` crate's; the sockets, TLS
//! (rustls, the system's roots or `--cacert`) and the messages' frames are
//! ours. A WebSocket runs over TCP: it delays what a datagram link would
//! drop, which is what a latency test of that path is for.

use std::future::{poll_fn, Future};
use std::net::SocketAddr;
use std::pin::Pin;
use std::sync::Arc;
use std::task::Poll;
use std::time::Duration;

use futures_util::{SinkExt, Stream};
use rustls_pki_types::{CertificateDer, ServerName};
use tokio::io::{AsyncRead, AsyncWrite};
use tokio::net::{TcpListener, TcpStream};
use tokio::time::Instant;
use tokio_tungstenite::tungstenite::client::IntoClientRequest;
use tokio_tungstenite::tungstenite::http::HeaderValue;
use tokio_tungstenite::tungstenite::protocol::{CloseFrame, WebSocketConfig};
use tokio_tungstenite::tungstenite::{Error as WsError, Message};
use tokio_tungstenite::WebSocketStream;

use super::address::HostPort;
use super::link::push_datagram;
use super::route::{resolve, Route};
use super::ws_url::WsUrl;
use super::{Inbound, LinkError, LinkKind, PathId, Transport};
use crate::frame::ScanStats;

/// A client that does not take our message for this long is given up: a
/// WebSocket's TCP would otherwise hold the run.
pub(crate) const WRITE_STALL: Duration = Duration::from_secs(1);
/// Clients beyond this are refused (`wsin:`): memory stays bounded.
const MAX_CLIENTS: usize = 64;
/// A client's handshake must be done within this.
const HANDSHAKE_LIMIT: Duration = Duration::from_secs(5);

/// The largest message (and frame) taken: MAVLink frames are at most 280
/// bytes and a message holds a few; the protocol's 64 MiB default would
/// let one peer hold that much of our memory.
const MAX_MESSAGE: usize = 64 * 1024;

/// The WebSocket settings of every binary link: messages bounded.
fn bounded() -> WebSocketConfig {
    WebSocketConfig::default()
        .max_message_size(Some(MAX_MESSAGE))
        .max_frame_size(Some(MAX_MESSAGE))
}

/// What a WebSocket runs over: TCP, or TLS over TCP.
pub(crate) trait Io: AsyncRead + AsyncWrite + Unpin + Send {}
impl<T: AsyncRead + AsyncWrite + Unpin + Send> Io for T {}

pub(crate) type Socket = WebSocketStream<Box<dyn Io>>;

/// A client link that talks to one server in WebSocket messages: what
/// `ws://` (binary frames) and `m2r://` (JSON texts) share. Each says how
/// a message it sends is made and how one it reads becomes frames; the
/// writing and the reading are done once, here.
#[allow(async_fn_in_trait)] // used with concrete types only
pub(crate) trait MessageLink {
    fn socket(&mut self) -> &mut Socket;
    /// The link as reports name it.
    fn name(&self) -> &str;
    /// Why the WebSocket ended, kept to be told after the frames that
    /// came before it.
    fn gone(&mut self) -> &mut Option<String>;
    /// A message's frames into `out`; why the peer is gone, if it is.
    fn take(&mut self, msg: Result<Message, WsError>, out: &mut Vec<Inbound>) -> Option<String>;

    /// Writes one message; a server that takes nothing for
    /// [`WRITE_STALL`] ends the link.
    async fn send_message(&mut self, msg: Message) -> Result<(), LinkError> {
        match tokio::time::timeout(WRITE_STALL, self.socket().send(msg)).await {
            Ok(Ok(())) => Ok(()),
            Ok(Err(e)) => Err(LinkError::Closed(format!(
                "{}: {}",
                self.name(),
                broken(&e)
            ))),
            Err(_) => Err(LinkError::Closed(format!(
                "{}: the server took nothing for {} s: it stopped reading",
                self.name(),
                WRITE_STALL.as_secs()
            ))),
        }
    }

    /// Reads what has come. Cancel-safe: polling the stream keeps its
    /// state in the link. The frames of the messages before an end are
    /// handed over first; the end is told by the next call.
    async fn recv_messages(&mut self, out: &mut Vec<Inbound>) -> Result<(), LinkError> {
        if let Some(why) = self.gone().take() {
            return Err(LinkError::Closed(format!("{}: {why}", self.name())));
        }
        let before = out.len();
        let why = poll_fn(|cx| loop {
            let why = match Pin::new(self.socket()).poll_next(cx) {
                Poll::Ready(Some(msg)) => match self.take(msg, out) {
                    None => continue,
                    Some(why) => why,
                },
                Poll::Ready(None) => "the connection ended".into(),
                Poll::Pending if out.len() > before => return Poll::Ready(None),
                Poll::Pending => return Poll::Pending,
            };
            return Poll::Ready(Some(why));
        })
        .await;
        match why {
            Some(why) if out.len() > before => {
                *self.gone() = Some(why);
                Ok(())
            }
            Some(why) => Err(LinkError::Closed(format!("{}: {why}", self.name()))),
            None => Ok(()),
        }
    }
}

/// Trust for `wss://`: the certificates `--cacert` named, or the system's.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub(crate) struct Trust {
    pub(crate) cacert: Option<Arc<Vec<CertificateDer<'static>>>>,
}

/// `ws://` or `wss://`: one server.
pub(crate) struct WsClient {
    name: String,
    ws: Socket,
    /// Why the WebSocket ended, told after the frames that came before.
    gone: Option<String>,
    stats: ScanStats,
    keep_raw: bool,
}

impl WsClient {
    pub(crate) async fn connect(
        url: &WsUrl,
        route: &Route,
        trust: &Trust,
    ) -> Result<Self, LinkError> {
        let name = url.to_string();
        let ws = open(url, &name, route, trust, Some(bounded())).await?;
        Ok(WsClient {
            name,
            ws,
            gone: None,
            stats: ScanStats::default(),
            keep_raw: false,
        })
    }
}

/// A WebSocket to the server `url` names, open (TCP, TLS for `wss`, the
/// handshake), errors told as the link `name`; `config` None for
/// tungstenite's limits. Shared with `m2r://`, which speaks JSON over it.
pub(crate) async fn open(
    url: &WsUrl,
    name: &str,
    route: &Route,
    trust: &Trust,
    config: Option<WebSocketConfig>,
) -> Result<Socket, LinkError> {
    let refused = |why: String| LinkError::Closed(format!("cannot open {name}: {why}"));
    let peer = resolve(&url.addr, route.family).await?;
    let socket = route.tcp(peer)?;
    let tcp = socket
        .connect(peer)
        .await
        .map_err(|e| LinkError::io(format!("cannot connect to {name}"), e))?;
    // A PING is a few dozen bytes: Nagle would hold it back.
    let _ = tcp.set_nodelay(true);
    let stream: Box<dyn Io> = if url.tls {
        Box::new(tls(url, trust, tcp).await.map_err(refused)?)
    } else {
        Box::new(tcp)
    };
    let request = request(url).map_err(refused)?;
    let (ws, _) = tokio_tungstenite::client_async_with_config(request, stream, config)
        .await
        .map_err(|e| refused(handshake_refused(e)))?;
    tracing::info!(link = %name, "WebSocket open");
    Ok(ws)
}

/// The handshake's request, with basic authentication from the URL.
fn request(
    url: &WsUrl,
) -> Result<tokio_tungstenite::tungstenite::handshake::client::Request, String> {
    use base64::Engine;
    let mut request = url
        .request_uri()
        .into_client_request()
        .map_err(|e| format!("not a WebSocket URL: {e}"))?;
    if let Some((user, password)) = &url.auth {
        let token = base64::engine::general_purpose::STANDARD.encode(format!("{user}:{password}"));
        let value = HeaderValue::from_str(&format!("Basic {token}")).map_err(|e| e.to_string())?;
        request.headers_mut().insert("Authorization", value);
    }
    Ok(request)
}

/// TLS over `tcp`, the server's certificate verified against `trust` and
/// the URL's host.
async fn tls(
    url: &WsUrl,
    trust: &Trust,
    tcp: TcpStream,
) -> Result<tokio_rustls::client::TlsStream<TcpStream>, String> {
    let mut roots = rustls::RootCertStore::empty();
    match &trust.cacert {
        Some(certs) => {
            for cert in certs.iter() {
                roots
                    .add(cert.clone())
                    .map_err(|e| format!("--cacert: {e}"))?;
            }
        }
        None => {
            for cert in rustls_native_certs::load_native_certs().certs {
                // One bad certificate in the system's store spoils no other.
                let _ = roots.add(cert);
            }
            if roots.is_empty() {
                return Err(
                    "no CA certificates on this system; name the server's CA with --cacert FILE"
                        .into(),
                );
            }
        }
    }
    let provider = Arc::new(rustls::crypto::ring::default_provider());
    let config = rustls::ClientConfig::builder_with_provider(provider)
        .with_safe_default_protocol_versions()
        .map_err(|e| e.to_string())?
        .with_root_certificates(roots)
        .with_no_client_auth();
    let server = ServerName::try_from(url.addr.host.clone())
        .map_err(|e| format!("'{}' cannot name a TLS server: {e}", url.addr.host))?;
    tokio_rustls::TlsConnector::from(Arc::new(config))
        .connect(server, tcp)
        .await
        .map_err(
            |e| match e.get_ref().and_then(|e| e.downcast_ref::<rustls::Error>()) {
                Some(rustls::Error::InvalidCertificate(why)) => format!(
                    "TLS: the server's certificate does not verify: {}",
                    certificate_words(why)
                ),
                _ => format!("TLS: {e}"),
            },
        )
}

/// Why a certificate was refused, in words, with what to do.
fn certificate_words(why: &rustls::CertificateError) -> String {
    use rustls::CertificateError as C;
    match why {
        C::UnknownIssuer => {
            "signed by a CA this machine does not trust (--cacert FILE names one to trust)".into()
        }
        C::NotValidForName | C::NotValidForNameContext { .. } => {
            "it is not for this host name (connect by a name the certificate lists)".into()
        }
        C::Expired | C::ExpiredContext { .. } => "it has expired".into(),
        C::NotValidYet | C::NotValidYetContext { .. } => {
            "it is not valid yet (check the clocks)".into()
        }
        other => format!("{other:?} (--cacert FILE names a CA to trust)"),
    }
}

/// Why a handshake failed, in a line.
fn handshake_refused(e: WsError) -> String {
    match e {
        WsError::Http(response) => {
            let status = response.status();
            let hint = match status.as_u16() {
                401 | 403 => ": the server wants credentials (ws://USER:PASSWORD@HOST/...)",
                404 => ": no WebSocket at that path",
                _ => "",
            };
            format!("the server refused the WebSocket handshake with HTTP {status}{hint}")
        }
        WsError::Protocol(p) => format!(
            "the server did not answer as a WebSocket server does ({p}): is it one, at that path?"
        ),
        other => format!("WebSocket handshake: {other}"),
    }
}

/// Why a WebSocket that was open broke, in words.
pub(crate) fn broken(e: &WsError) -> String {
    use tokio_tungstenite::tungstenite::error::ProtocolError;
    match e {
        WsError::Protocol(ProtocolError::ResetWithoutClosingHandshake) => {
            "the connection ended without a WebSocket close: the server died or dropped it".into()
        }
        WsError::ConnectionClosed | WsError::AlreadyClosed => "the WebSocket is closed".into(),
        other => other.to_string(),
    }
}

/// A close from the peer, in words.
pub(crate) fn closed(frame: Option<CloseFrame>) -> String {
    match frame {
        Some(f) if !f.reason.is_empty() => format!("closed by the peer ({}: {})", f.code, f.reason),
        Some(f) => format!("closed by the peer ({})", f.code),
        None => "closed by the peer".into(),
    }
}

/// What became of one message read.
enum Read {
    Frames,
    Nothing,
    Gone(String),
}

/// A message's frames into `out`, or why the peer is gone.
fn take(
    msg: Result<Message, WsError>,
    path: PathId,
    keep_raw: bool,
    stats: &mut ScanStats,
    out: &mut Vec<Inbound>,
) -> Read {
    match msg {
        Ok(Message::Binary(data)) => {
            push_datagram(&data, Instant::now(), path, keep_raw, stats, out);
            Read::Frames
        }
        Ok(Message::Text(text)) => Read::Gone(format!(
            "it sent a text message where MAVLink's binary frames were expected ({} bytes: {}); \
             a mavlink2rest JSON endpoint is m2r://",
            text.len(),
            // One line, whatever the text's own (mavlink2rest's are pretty).
            text.split_whitespace()
                .collect::<Vec<_>>()
                .join(" ")
                .chars()
                .take(40)
                .collect::<String>()
        )),
        Ok(Message::Close(frame)) => Read::Gone(closed(frame)),
        // Pings are answered by the protocol itself.
        Ok(Message::Ping(_) | Message::Pong(_) | Message::Frame(_)) => Read::Nothing,
        Err(e) => Read::Gone(broken(&e)),
    }
}

impl MessageLink for WsClient {
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
        match take(msg, 0, self.keep_raw, &mut self.stats, out) {
            Read::Frames | Read::Nothing => None,
            Read::Gone(why) => Some(why),
        }
    }
}

impl Transport for WsClient {
    async fn send(&mut self, frame: &[u8]) -> Result<Instant, LinkError> {
        let sent = Instant::now();
        self.send_message(Message::Binary(frame.to_vec().into()))
            .await
            .map(|()| sent)
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

type Handshake =
    Pin<Box<dyn Future<Output = Result<WebSocketStream<Box<dyn Io>>, WsError>> + Send>>;

struct Client {
    path: PathId,
    peer: SocketAddr,
    ws: Socket,
}

/// `wsin:HOST:PORT`: a listening socket, the handshakes under way and the
/// clients that finished theirs.
pub(crate) struct WsServer {
    listener: TcpListener,
    handshakes: Vec<(SocketAddr, Instant, Handshake)>,
    clients: Vec<Client>,
    next_path: PathId,
    stats: ScanStats,
    keep_raw: bool,
}

impl WsServer {
    pub(crate) async fn listen(addr: &HostPort, route: &Route) -> Result<Self, LinkError> {
        let listener = super::tcp::listener("wsin", "ws", addr, route).await?;
        Ok(WsServer {
            listener,
            handshakes: Vec::new(),
            clients: Vec::new(),
            next_path: 0,
            stats: ScanStats::default(),
            keep_raw: false,
        })
    }

    fn accept(&mut self, stream: TcpStream, peer: SocketAddr) {
        if self.clients.len() + self.handshakes.len() >= MAX_CLIENTS {
            tracing::warn!(%peer, "too many WebSocket clients; refused");
            return;
        }
        let _ = stream.set_nodelay(true);
        let stream: Box<dyn Io> = Box::new(stream);
        self.handshakes.push((
            peer,
            Instant::now(),
            Box::pin(tokio_tungstenite::accept_async_with_config(
                stream,
                Some(bounded()),
            )),
        ));
    }

    /// Handshakes done become clients; failed or slow ones are dropped.
    fn poll_handshakes(&mut self, cx: &mut std::task::Context<'_>) -> bool {
        let mut progress = false;
        let mut i = 0;
        while i < self.handshakes.len() {
            let (peer, started, handshake) = &mut self.handshakes[i];
            match handshake.as_mut().poll(cx) {
                Poll::Ready(Ok(ws)) => {
                    tracing::info!(peer = %*peer, "WebSocket client connected");
                    self.clients.push(Client {
                        path: self.next_path,
                        peer: *peer,
                        ws,
                    });
                    // Paths are never reused: an answer for a departed
                    // client cannot reach a newcomer.
                    self.next_path = self.next_path.wrapping_add(1);
                    drop(self.handshakes.swap_remove(i));
                    progress = true;
                }
                Poll::Ready(Err(e)) => {
                    tracing::info!(peer = %*peer, error = %e, "WebSocket handshake failed");
                    drop(self.handshakes.swap_remove(i));
                }
                Poll::Pending if started.elapsed() > HANDSHAKE_LIMIT => {
                    drop(self.handshakes.swap_remove(i));
                }
                Poll::Pending => i += 1,
            }
        }
        progress
    }

    async fn write_to(&mut self, index: usize, frame: &[u8]) -> bool {
        let msg = Message::Binary(frame.to_vec().into());
        let ws = &mut self.clients[index].ws;
        matches!(
            tokio::time::timeout(WRITE_STALL, ws.send(msg)).await,
            Ok(Ok(()))
        )
    }

    /// A client leaving is not a link failure: the others go on.
    fn remove(&mut self, index: usize, why: &str) {
        let client = self.clients.swap_remove(index);
        tracing::info!(peer = %client.peer, why, "WebSocket client left");
    }
}

impl Transport for WsServer {
    async fn send(&mut self, frame: &[u8]) -> Result<Instant, LinkError> {
        let sent = Instant::now();
        let mut i = 0;
        while i < self.clients.len() {
            if self.write_to(i, frame).await {
                i += 1;
            } else {
                self.remove(i, "write failed");
            }
        }
        Ok(sent)
    }

    async fn send_to(&mut self, path: PathId, frame: &[u8]) -> Result<Instant, LinkError> {
        let sent = Instant::now();
        if let Some(i) = self.clients.iter().position(|c| c.path == path) {
            if !self.write_to(i, frame).await {
                self.remove(i, "write failed");
            }
        }
        Ok(sent)
    }

    // Cancel-safe: it only polls, and keeps no state outside `self`.
    // Returns after any message or new client, so the session sees peers.
    async fn recv(&mut self, out: &mut Vec<Inbound>) -> Result<(), LinkError> {
        poll_fn(|cx| {
            let mut progress = false;
            while let Poll::Ready(accepted) = self.listener.poll_accept(cx) {
                match accepted {
                    Ok((stream, peer)) => self.accept(stream, peer),
                    Err(e) => {
                        tracing::warn!(error = %e, "accept failed");
                        break;
                    }
                }
            }
            progress |= self.poll_handshakes(cx);
            let mut i = 0;
            while i < self.clients.len() {
                let client = &mut self.clients[i];
                let mut gone = None;
                while let Poll::Ready(msg) = Pin::new(&mut client.ws).poll_next(cx) {
                    let Some(msg) = msg else {
                        gone = Some("the connection ended".to_string());
                        break;
                    };
                    match take(msg, client.path, self.keep_raw, &mut self.stats, out) {
                        Read::Frames => progress = true,
                        Read::Nothing => {}
                        Read::Gone(why) => {
                            gone = Some(why);
                            break;
                        }
                    }
                }
                match gone {
                    Some(why) => self.remove(i, &why),
                    None => i += 1,
                }
            }
            if progress {
                Poll::Ready(Ok(()))
            } else {
                Poll::Pending
            }
        })
        .await
    }

    fn has_peers(&self) -> bool {
        !self.clients.is_empty()
    }

    fn scan_stats(&self) -> ScanStats {
        self.stats
    }

    fn kind(&self) -> LinkKind {
        LinkKind::Listening
    }

    fn keep_raw(&mut self) {
        self.keep_raw = true;
    }
}
