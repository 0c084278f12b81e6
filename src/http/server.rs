//! The server: hyper's HTTP/1.1 (parsing, framing, `HEAD`, error statuses) with the
//! limits that keep a scrape answerable whatever other clients do.
//!
//! - A request head must arrive within [`Limits::header_read_timeout`] and
//!   fit in [`Limits::max_header_bytes`]; hyper answers 431 to a larger
//!   head (a 1 MB header, a request line that never ends) and closes.
//! - One request a connection (no keep-alive), so a connection is either
//!   waiting for its head or serving: at [`Limits::max_connections`], a new
//!   client evicts the oldest connection still waiting for its head. Idle
//!   connections, however many, never lock a scraper out.
//! - Only `GET` and `HEAD` reach the handler, and `POST` to the paths
//!   [`Limits::posts`] names; no request body is read.
//! - With a web config ([`WebConfig`], `--web.config.file`): TLS first (a
//!   handshake within the header timeout; a plain-HTTP client gets nothing),
//!   then basic auth (401, the handler never called), then the config's
//!   extra headers on every response. The config is read at each accept, so
//!   a reload applies to the next connection.
//!
//! Everything runs on the current thread's `LocalSet`, so handlers may run
//! sessions, which are not `Send`.

use std::cell::{Cell, RefCell};
use std::collections::VecDeque;
use std::convert::Infallible;
use std::future::Future;
use std::io;
use std::pin::Pin;
use std::rc::Rc;
use std::time::Duration;

use bytes::Bytes;
use http_body_util::Full;
use hyper::header::{HeaderValue, ALLOW, CONTENT_TYPE, WWW_AUTHENTICATE};
use hyper::{Method, Request, Response, StatusCode};
use hyper_util::rt::{TokioIo, TokioTimer};
use tokio::net::TcpListener;
use tokio::sync::oneshot;

use super::basic_auth::Checker;
use crate::config::WebConfig;

pub(crate) use hyper::http::request::Parts as Head;

/// The web config now in force; a reload swaps it.
pub(crate) type SharedWeb = Rc<RefCell<Rc<WebConfig>>>;

/// How much a client may ask of the server.
#[derive(Debug, Clone, Copy)]
pub struct Limits {
    /// Connections open at once; beyond it the oldest idle one is closed.
    pub(crate) max_connections: usize,
    /// Time to send a whole request head.
    pub(crate) header_read_timeout: Duration,
    /// Largest request head (hyper's floor is 8 KiB).
    pub(crate) max_header_bytes: usize,
    /// Longest a connection lives, serving included: a client that never
    /// reads its response does not hold a slot for ever.
    pub(crate) max_connection_time: Duration,
    /// Paths a `POST` may reach the handler at (`/-/reload`).
    pub(crate) posts: &'static [&'static str],
}

impl Default for Limits {
    fn default() -> Self {
        Limits {
            max_connections: 512,
            header_read_timeout: Duration::from_secs(10),
            max_header_bytes: 16 * 1024,
            max_connection_time: Duration::from_secs(15 * 60),
            posts: &[],
        }
    }
}

/// Content type of the Prometheus text format.
pub(crate) const PROMETHEUS_TEXT: &str = "text/plain; version=0.0.4; charset=utf-8";

/// A handler's answer.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Reply {
    pub(crate) status: StatusCode,
    pub(crate) content_type: &'static str,
    pub(crate) body: String,
}

impl Reply {
    /// Plain text (errors, pointers).
    pub(crate) fn text(status: StatusCode, body: impl Into<String>) -> Self {
        Reply {
            status,
            content_type: "text/plain; charset=utf-8",
            body: body.into(),
        }
    }

    /// An exposition in the Prometheus text format.
    pub(crate) fn metrics(body: String) -> Self {
        Reply {
            status: StatusCode::OK,
            content_type: PROMETHEUS_TEXT,
            body,
        }
    }
}

/// What a handler returns: its reply, later.
pub(crate) type Replying = Pin<Box<dyn Future<Output = Reply>>>;

/// Open connections in accept order, each waiting for its head or serving.
#[derive(Default)]
struct Connections {
    open: VecDeque<Open>,
    next_id: u64,
}

struct Open {
    id: u64,
    waiting: Rc<Cell<bool>>,
    evict: Option<oneshot::Sender<()>>,
}

impl Connections {
    /// Makes room for one more below `max`: closes the oldest connection
    /// still waiting for its request head. False when every one is serving.
    fn make_room(&mut self, max: usize) -> bool {
        if self.open.len() < max {
            return true;
        }
        let Some(i) = self.open.iter().position(|c| c.waiting.get()) else {
            return false;
        };
        if let Some(mut idle) = self.open.remove(i) {
            if let Some(evict) = idle.evict.take() {
                let _ = evict.send(());
            }
        }
        true
    }

    fn add(&mut self) -> (u64, Rc<Cell<bool>>, oneshot::Receiver<()>) {
        let id = self.next_id;
        self.next_id += 1;
        let waiting = Rc::new(Cell::new(true));
        let (evict, evicted) = oneshot::channel();
        self.open.push_back(Open {
            id,
            waiting: waiting.clone(),
            evict: Some(evict),
        });
        (id, waiting, evicted)
    }

    fn remove(&mut self, id: u64) {
        if let Some(i) = self.open.iter().position(|c| c.id == id) {
            self.open.remove(i);
        }
    }
}

/// Serves `listener` on the current `LocalSet` until the runtime ends,
/// answering each `GET`/`HEAD` with `handler`, in plain HTTP open to all.
pub(crate) fn serve<H>(listener: TcpListener, limits: Limits, handler: H)
where
    H: Fn(Head) -> Replying + 'static,
{
    serve_with(listener, limits, SharedWeb::default(), handler);
}

/// [`serve`] under the web config `web` holds at each accept.
pub(crate) fn serve_with<H>(listener: TcpListener, limits: Limits, web: SharedWeb, handler: H)
where
    H: Fn(Head) -> Replying + 'static,
{
    let handler = Rc::new(handler);
    let checker = Rc::new(Checker::default());
    let connections = Rc::new(RefCell::new(Connections::default()));
    tokio::task::spawn_local(async move {
        loop {
            let stream = match listener.accept().await {
                Ok((stream, _)) => stream,
                // Out of file descriptors, or a client gone before accept:
                // it concerns one client; pause so a full table is no spin.
                Err(e) => {
                    tracing::debug!("accept: {e}");
                    tokio::time::sleep(Duration::from_millis(50)).await;
                    continue;
                }
            };
            if !connections.borrow_mut().make_room(limits.max_connections) {
                // Every slot is serving a request: this client waits its turn
                // by reconnecting, rather than pushing another out.
                continue;
            }
            let (id, waiting, evicted) = connections.borrow_mut().add();
            let web = web.borrow().clone();
            let guard = Guard {
                web: web.clone(),
                checker: checker.clone(),
            };
            let task = secured(stream, web, limits, waiting, guard, handler.clone());
            let connections = connections.clone();
            tokio::task::spawn_local(async move {
                tokio::select! {
                    () = task => {}
                    _ = evicted => {}
                    () = tokio::time::sleep(limits.max_connection_time) => {}
                }
                connections.borrow_mut().remove(id);
            });
        }
    });
}

/// Serves one connection of any byte stream (a socket; the fuzz target's
/// in-memory pipe) as the server serves each client: a request head
/// within the limits, the handler's reply, then close.
pub async fn serve_one<S, H>(stream: S, limits: Limits, handler: H)
where
    S: tokio::io::AsyncRead + tokio::io::AsyncWrite + Unpin + 'static,
    H: Fn(Head) -> Replying + 'static,
{
    let waiting = Rc::new(Cell::new(true));
    let guard = Guard {
        web: Rc::default(),
        checker: Rc::default(),
    };
    connection(
        TokioIo::new(stream),
        limits,
        waiting,
        guard,
        Rc::new(handler),
    )
    .await;
}

/// What a connection enforces: the web config taken at its accept.
struct Guard {
    web: Rc<WebConfig>,
    checker: Rc<Checker>,
}

/// The TLS handshake when the web config asks for TLS (within the header
/// timeout, so a silent client holds nothing), then the connection.
async fn secured<H>(
    stream: tokio::net::TcpStream,
    web: Rc<WebConfig>,
    limits: Limits,
    waiting: Rc<Cell<bool>>,
    guard: Guard,
    handler: Rc<H>,
) where
    H: Fn(Head) -> Replying + 'static,
{
    let Some(tls) = web.tls.clone() else {
        return connection(TokioIo::new(stream), limits, waiting, guard, handler).await;
    };
    let acceptor = tokio_rustls::TlsAcceptor::from(tls);
    let handshake = async {
        let mut stream = stream;
        if !starts_tls(&stream).await {
            // As Go's servers say it: plain HTTP to this port is a mistake
            // worth a readable answer (Prometheus shows the status).
            let _ = tokio::io::AsyncWriteExt::write_all(&mut stream, PLAIN_TO_TLS).await;
            let _ = tokio::io::AsyncWriteExt::shutdown(&mut stream).await;
            // Read what the client sent before closing: unread bytes would
            // make the close a reset, which can beat the answer to it.
            let mut sink = [0u8; 4096];
            let drain = async {
                let mut left: usize = 64 * 1024;
                while left > 0 {
                    match tokio::io::AsyncReadExt::read(&mut stream, &mut sink).await {
                        Ok(0) | Err(_) => break,
                        Ok(n) => left = left.saturating_sub(n),
                    }
                }
            };
            let _ = tokio::time::timeout(Duration::from_secs(1), drain).await;
            return Err(io::Error::other("plain HTTP to the TLS port"));
        }
        acceptor.accept(stream).await
    };
    match tokio::time::timeout(limits.header_read_timeout, handshake).await {
        Ok(Ok(stream)) => connection(TokioIo::new(stream), limits, waiting, guard, handler).await,
        // Plain HTTP, no or a bad client certificate, a stalled handshake.
        Ok(Err(e)) => tracing::debug!("tls handshake: {e}"),
        Err(_) => tracing::debug!("tls handshake: timed out"),
    }
}

const PLAIN_TO_TLS: &[u8] = b"HTTP/1.0 400 Bad Request\r\nContent-Type: text/plain; charset=utf-8\r\nConnection: close\r\n\r\nClient sent an HTTP request to an HTTPS server.\n";

/// Whether the client's first byte opens a TLS handshake record (22).
async fn starts_tls(stream: &tokio::net::TcpStream) -> bool {
    let mut first = [0u8; 1];
    matches!(stream.peek(&mut first).await, Ok(1) if first[0] == 0x16)
}

/// One connection: a request head, the handler's reply, then close.
async fn connection<S, H>(
    stream: TokioIo<S>,
    limits: Limits,
    waiting: Rc<Cell<bool>>,
    guard: Guard,
    handler: Rc<H>,
) where
    S: tokio::io::AsyncRead + tokio::io::AsyncWrite + Unpin + 'static,
    H: Fn(Head) -> Replying + 'static,
{
    let guard = Rc::new(guard);
    let service = hyper::service::service_fn(move |request: Request<hyper::body::Incoming>| {
        waiting.set(false);
        let (head, _body) = request.into_parts();
        let (guard, handler) = (guard.clone(), handler.clone());
        async move {
            let reply = if guard.checker.allows(&guard.web, &head.headers).await {
                let allowed = match head.method {
                    Method::GET | Method::HEAD => true,
                    Method::POST => limits.posts.contains(&head.uri.path()),
                    _ => false,
                };
                if allowed {
                    handler(head).await
                } else {
                    Reply::text(StatusCode::METHOD_NOT_ALLOWED, "only GET\n")
                }
            } else {
                Reply::text(StatusCode::UNAUTHORIZED, "Unauthorized\n")
            };
            Ok::<_, Infallible>(response(reply, &guard.web))
        }
    });
    let mut http = hyper::server::conn::http1::Builder::new();
    http.timer(TokioTimer::new())
        .header_read_timeout(limits.header_read_timeout)
        .max_buf_size(limits.max_header_bytes.max(8192))
        .keep_alive(false);
    if let Err(e) = http.serve_connection(stream, service).await {
        tracing::debug!("http connection: {e}");
    }
}

fn response(reply: Reply, web: &WebConfig) -> Response<Full<Bytes>> {
    let mut response = Response::new(Full::new(Bytes::from(reply.body)));
    *response.status_mut() = reply.status;
    let headers = response.headers_mut();
    headers.insert(CONTENT_TYPE, HeaderValue::from_static(reply.content_type));
    if reply.status == StatusCode::METHOD_NOT_ALLOWED {
        headers.insert(ALLOW, HeaderValue::from_static("GET, HEAD"));
    }
    if reply.status == StatusCode::UNAUTHORIZED {
        headers.insert(WWW_AUTHENTICATE, HeaderValue::from_static("Basic"));
    }
    for (name, value) in &web.headers {
        headers.insert(name.clone(), value.clone());
    }
    response
}

/// A bound std listener, handed to the runtime (non-blocking).
pub(crate) fn listener(std: std::net::TcpListener) -> io::Result<TcpListener> {
    std.set_nonblocking(true)?;
    TcpListener::from_std(std)
}

#[cfg(test)]
mod tests {
    use std::io::{Read, Write};

    use super::*;

    #[test]
    fn the_oldest_waiting_connection_makes_room() {
        let mut c = Connections::default();
        let (a, a_waiting, mut a_evicted) = c.add();
        let (_, _, mut b_evicted) = c.add();
        assert!(c.make_room(3), "below the limit");
        // a is serving: b, the oldest still waiting, goes.
        a_waiting.set(false);
        assert!(c.make_room(2));
        assert!(b_evicted.try_recv().is_ok());
        assert!(a_evicted.try_recv().is_err());
        assert_eq!(c.open.len(), 1);
        // Only a serving connection left: no room at its expense.
        assert!(!c.make_room(1));
        c.remove(a);
        assert!(c.make_room(1));
    }

    /// A server on a thread of its own; its address.
    fn start(limits: Limits) -> std::net::SocketAddr {
        let std = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
        let addr = std.local_addr().unwrap();
        std::thread::spawn(move || {
            let rt = tokio::runtime::Builder::new_current_thread()
                .enable_all()
                .build()
                .unwrap();
            let local = tokio::task::LocalSet::new();
            local.block_on(&rt, async move {
                let handler = |head: Head| -> Replying {
                    let path = head.uri.path().to_string();
                    Box::pin(async move { Reply::text(StatusCode::OK, format!("path {path}\n")) })
                };
                serve(listener(std).unwrap(), limits, handler);
                std::future::pending::<()>().await
            });
        });
        addr
    }

    fn exchange(addr: std::net::SocketAddr, request: &[u8]) -> String {
        let mut s = std::net::TcpStream::connect(addr).unwrap();
        s.set_read_timeout(Some(Duration::from_secs(10))).unwrap();
        // The server may close before reading it all (a head too large).
        let _ = s.write_all(request);
        let mut out = Vec::new();
        let _ = s.read_to_end(&mut out);
        String::from_utf8_lossy(&out).into_owned()
    }

    #[test]
    fn answers_get_and_head_and_refuses_the_rest() {
        let addr = start(Limits::default());
        let get = exchange(addr, b"GET /metrics?x=1 HTTP/1.1\r\nHost: a\r\n\r\n");
        assert!(get.starts_with("HTTP/1.1 200 OK\r\n"), "{get}");
        assert!(get.contains("content-length: 14\r\n"), "{get}");
        assert!(get.ends_with("\r\n\r\npath /metrics\n"), "{get}");
        let head = exchange(addr, b"HEAD / HTTP/1.1\r\nHost: a\r\n\r\n");
        assert!(head.starts_with("HTTP/1.1 200 OK\r\n"), "{head}");
        assert!(head.ends_with("\r\n\r\n"), "HEAD has no body: {head}");
        let post = exchange(
            addr,
            b"POST / HTTP/1.1\r\nHost: a\r\nContent-Length: 0\r\n\r\n",
        );
        assert!(post.starts_with("HTTP/1.1 405"), "{post}");
        assert!(post.contains("allow: GET, HEAD\r\n"), "{post}");
        let junk = exchange(addr, b"\x16\x03\x01 hello\r\n\r\n");
        assert!(junk.starts_with("HTTP/1.1 400"), "{junk}");
    }

    #[test]
    fn a_huge_head_is_refused_and_the_server_goes_on() {
        let addr = start(Limits::default());
        let mut big = b"GET / HTTP/1.1\r\nX-Big: ".to_vec();
        big.extend(std::iter::repeat_n(b'a', 1 << 20));
        big.extend_from_slice(b"\r\n\r\n");
        let refused = exchange(addr, &big);
        assert!(refused.starts_with("HTTP/1.1 431"), "{refused:.200}");
        // A request line that never ends.
        let endless = exchange(addr, &[b'A'; 100_000]);
        assert!(endless.starts_with("HTTP/1.1 431"), "{endless:.200}");
        let get = exchange(addr, b"GET /ok HTTP/1.1\r\nHost: a\r\n\r\n");
        assert!(get.ends_with("path /ok\n"), "{get}");
    }

    #[test]
    fn a_silent_client_is_dropped_after_the_header_timeout() {
        let addr = start(Limits {
            header_read_timeout: Duration::from_millis(200),
            ..Limits::default()
        });
        let mut s = std::net::TcpStream::connect(addr).unwrap();
        s.set_read_timeout(Some(Duration::from_secs(10))).unwrap();
        s.write_all(b"GET / HT").unwrap();
        let started = std::time::Instant::now();
        let mut out = Vec::new();
        let _ = s.read_to_end(&mut out);
        assert!(started.elapsed() < Duration::from_secs(5));
    }

    #[test]
    fn idle_connections_beyond_the_limit_do_not_lock_a_client_out() {
        let addr = start(Limits {
            max_connections: 8,
            ..Limits::default()
        });
        let idle: Vec<_> = (0..40)
            .map(|_| std::net::TcpStream::connect(addr).unwrap())
            .collect();
        let get = exchange(addr, b"GET /still HTTP/1.1\r\nHost: a\r\n\r\n");
        assert!(get.ends_with("path /still\n"), "{get}");
        drop(idle);
    }
}
