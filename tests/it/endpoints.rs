//! Nothing a client does wedges mavping's HTTP endpoints, `mavping serve`
//! and `mavping --prometheus` alike (one server, src/output/http.rs): 2,000
//! idle connections held open while a scrape is answered within a second,
//! a 1 MB header and a request line that never ends (431), a method other
//! than GET (405), and a client that stops in the middle of its request
//! head, closed by the server's header timeout (10 s), as are the idle ones.

use std::io::{BufRead, BufReader, Read, Write};
use std::net::TcpStream;
use std::process::{Child, Stdio};
use std::time::{Duration, Instant};

use crate::common::{http_get, mavping, samples, Server};

/// The server's time limit for a request head (`Limits::default()`).
const HEADER_TIMEOUT: Duration = Duration::from_secs(10);
/// A guard against a hang, not a measure of speed.
const SCRAPE_WITHIN: Duration = Duration::from_secs(1);

/// Lets this test process hold a few thousand sockets.
fn raise_descriptor_limit() {
    use nix::sys::resource::{getrlimit, setrlimit, Resource};
    let (soft, hard) = getrlimit(Resource::RLIMIT_NOFILE).unwrap();
    if soft < 4096 {
        setrlimit(Resource::RLIMIT_NOFILE, hard.min(8192), hard).unwrap();
    }
}

/// Sends `bytes` (the server may close before reading them all) and reads
/// the answer to its end.
fn send(addr: &str, bytes: &[u8]) -> String {
    let mut s = TcpStream::connect(addr).unwrap();
    s.set_read_timeout(Some(HEADER_TIMEOUT * 3)).unwrap();
    let _ = s.write_all(bytes);
    let mut out = Vec::new();
    let _ = s.read_to_end(&mut out);
    String::from_utf8_lossy(&out).into_owned()
}

/// True once the server has closed `s` (end of stream or a reset), false
/// when its read timeout passes first.
fn closed_by_server(s: &mut TcpStream) -> bool {
    let mut buf = [0u8; 512];
    loop {
        match s.read(&mut buf) {
            Ok(0) => return true,
            // An answer (such as a 408) before the close.
            Ok(_) => {}
            Err(e)
                if matches!(
                    e.kind(),
                    std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut
                ) =>
            {
                return false
            }
            Err(_) => return true,
        }
    }
}

/// Everything a hostile or careless client may do, against the server at
/// `addr`; `metric` is a family its `/metrics` always shows.
fn no_client_wedges(addr: &str, metric: &str) {
    raise_descriptor_limit();
    let mut idle: Vec<TcpStream> = (0..2000)
        .map(|_| TcpStream::connect(addr).expect("connect"))
        .collect();
    // One that stops in the middle of its request head.
    let mut stalled = TcpStream::connect(addr).unwrap();
    stalled.write_all(b"GET /metrics HT").unwrap();
    let stalled_at = Instant::now();

    let started = Instant::now();
    let r = http_get(addr, "/metrics", &[]);
    let took = started.elapsed();
    assert_eq!(r.status, 200, "{}", r.body);
    assert!(
        samples(&r.body).iter().any(|s| s.name == metric),
        "{}",
        r.body
    );
    assert!(
        took < SCRAPE_WITHIN,
        "a scrape behind 2,000 idle connections took {took:?}"
    );

    let mut huge = b"GET /metrics HTTP/1.1\r\nX-Junk: ".to_vec();
    huge.extend(std::iter::repeat_n(b'x', 1 << 20));
    huge.extend_from_slice(b"\r\n\r\n");
    let answer = send(addr, &huge);
    assert!(answer.starts_with("HTTP/1.1 431"), "{answer:.200}");
    let answer = send(addr, &[b'G'; 200_000]);
    assert!(answer.starts_with("HTTP/1.1 431"), "{answer:.200}");
    let answer = send(addr, b"POST /metrics HTTP/1.1\r\nContent-Length: 0\r\n\r\n");
    assert!(answer.starts_with("HTTP/1.1 405"), "{answer:.200}");

    // The header timeout closes the stalled client and every idle one
    // still open (the oldest were closed to make room for newer ones).
    stalled.set_read_timeout(Some(HEADER_TIMEOUT * 3)).unwrap();
    assert!(closed_by_server(&mut stalled), "the stalled client is open");
    let after = stalled_at.elapsed();
    assert!(
        after
            >= HEADER_TIMEOUT
                .checked_sub(Duration::from_millis(500))
                .unwrap(),
        "closed after {after:?}, before the header timeout"
    );
    for (i, s) in idle.iter_mut().enumerate() {
        s.set_read_timeout(Some(HEADER_TIMEOUT)).unwrap();
        assert!(closed_by_server(s), "idle connection {i} is still open");
    }
    drop(idle);
    assert_eq!(http_get(addr, "/metrics", &[]).status, 200);
}

#[test]
fn no_client_wedges_mavping_serve() {
    let server = Server::start(&["--link", "sim:"]);
    no_client_wedges(&server.addr, "mavping_link_up");
    assert_eq!(server.stop(), Some(0));
}

/// Kills the run when the test ends, whatever happens.
struct Running(Child);

impl Drop for Running {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

#[test]
fn no_client_wedges_mavping_prometheus() {
    let mut child = mavping()
        .args(["-q", "--prometheus", "127.0.0.1:0", "sim:"])
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut stderr = BufReader::new(child.stderr.take().unwrap());
    let _running = Running(child);
    let mut line = String::new();
    stderr.read_line(&mut line).unwrap();
    let addr = line
        .trim()
        .strip_prefix("mavping: serving metrics at http://")
        .and_then(|l| l.strip_suffix("/metrics"))
        .unwrap_or_else(|| panic!("no address announced: {line:?}"))
        .to_string();
    no_client_wedges(&addr, "mavping_link_up");
}
