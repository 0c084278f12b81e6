//! Shared by the integration tests: real peers (pymavlink processes),
//! free loopback ports, running mavping, and parsing its summaries.

pub mod frame_oracle;
pub mod http;
pub mod json;
pub mod render;
pub mod serve;
pub mod silent;
pub mod tmux;

pub use http::*;
pub use json::*;
pub use render::Rendered;
pub use serve::Server;
pub use silent::SilentPeer;
pub use tmux::Tmux;

use std::io::{BufRead, BufReader, Read};
use std::net::UdpSocket;
use std::path::PathBuf;
use std::process::{Child, ChildStdout, Command, Stdio};
use std::time::{Duration, Instant};

/// The Python that has pymavlink: $MAVPING_PYTHON (set by scripts/test.sh)
/// or .venv/bin/python. A missing peer fails the test loudly: interop
/// tests never skip.
pub fn python() -> PathBuf {
    let path = std::env::var_os("MAVPING_PYTHON").map_or_else(
        || PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(".venv/bin/python"),
        PathBuf::from,
    );
    let ok = Command::new(&path)
        .args(["-c", "import pymavlink, serial"])
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|s| s.success());
    assert!(
        ok,
        "pymavlink or pyserial is not available at {} — run `bash scripts/test.sh` (it creates .venv with both)",
        path.display()
    );
    path
}

pub fn peer_script(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/peers")
        .join(name)
}

/// A free UDP port on 127.0.0.1 (bound then released).
pub fn free_udp_port() -> u16 {
    UdpSocket::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port()
}

/// A free TCP port on 127.0.0.1.
pub fn free_tcp_port() -> u16 {
    std::net::TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port()
}

/// `mavping respond`, started and ready (its first line says so).
pub struct Respond {
    pub child: Child,
    stdout: BufReader<std::process::ChildStdout>,
}

impl Respond {
    pub fn start(args: &[&str]) -> Respond {
        let mut child = mavping()
            .arg("respond")
            .args(args)
            .stdout(Stdio::piped())
            .stderr(Stdio::inherit())
            .spawn()
            .unwrap();
        let mut stdout = BufReader::new(child.stdout.take().unwrap());
        let mut line = String::new();
        stdout.read_line(&mut line).unwrap();
        assert!(line.starts_with("mavping respond: "), "{line:?}");
        Respond { child, stdout }
    }

    /// SIGTERM; returns its exit code and its counts: requests, ping,
    /// timesync, command, retransmissions, replies sent, dropped, duplicated.
    pub fn finish(self) -> (i32, Vec<u64>) {
        let (code, rest) = self.finish_text();
        let line = rest
            .lines()
            .find(|l| l.starts_with("respond "))
            .unwrap_or_else(|| panic!("no counts line: {rest}"));
        let counts = line
            .split_once(": ")
            .unwrap()
            .1
            .split(|c: char| !c.is_ascii_digit())
            .filter(|s| !s.is_empty())
            .map(|s| s.parse().unwrap())
            .collect();
        (code, counts)
    }
}

impl Respond {
    /// SIGTERM; returns its exit code and what it printed after its first
    /// line.
    pub fn finish_text(mut self) -> (i32, String) {
        signal(self.child.id(), "TERM");
        let mut rest = String::new();
        self.stdout.read_to_string(&mut rest).unwrap();
        let code = self.child.wait().unwrap().code().unwrap_or(-1);
        (code, rest)
    }
}

impl Drop for Respond {
    // A failing test must not leave a responder running (it would hold the
    // test runner's output pipe open).
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// A program from .venv that scripts/test.sh installs (`mavproxy.py`, the
/// `mavsdk_server` binary of the mavsdk-grpc wheel). A missing one fails
/// the test loudly.
pub fn venv_program(name: &str) -> PathBuf {
    let python = python();
    let path = if name == "mavsdk_server" {
        let site = Command::new(&python)
            .args([
                "-c",
                "import sysconfig; print(sysconfig.get_paths()['purelib'])",
            ])
            .output()
            .expect("python runs");
        PathBuf::from(String::from_utf8_lossy(&site.stdout).trim())
            .join("mavsdk_grpc/bin/mavsdk_server")
    } else {
        python.with_file_name(name)
    };
    assert!(
        path.exists(),
        "{name} is not installed at {} — run `bash scripts/test.sh`",
        path.display()
    );
    path
}

/// A third-party program run for a test; killed when dropped.
pub struct Program(Child);

/// A program started by the caller, stopped by [`Program::terminate`]
/// or killed when dropped.
impl From<Child> for Program {
    fn from(child: Child) -> Self {
        Program(child)
    }
}

impl Program {
    /// Starts `program` with `args` in `dir`, its output discarded, and
    /// waits until a socket of it is bound to UDP `port` on 127.0.0.1 (its
    /// link is open). Watched in /proc/net/udp: binding the port to try it
    /// could race the program for it.
    pub fn start_on_udp(
        program: &std::path::Path,
        args: &[&str],
        dir: &std::path::Path,
        port: u16,
    ) -> Program {
        let child = Command::new(program)
            .args(args)
            .current_dir(dir)
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .unwrap_or_else(|e| panic!("cannot start {}: {e}", program.display()));
        let mut program_handle = Program(child);
        let local = format!("0100007F:{port:04X} ");
        let started = Instant::now();
        loop {
            let table = std::fs::read_to_string("/proc/net/udp").unwrap_or_default();
            if table.lines().any(|l| l.contains(&local)) {
                return program_handle;
            }
            if let Ok(Some(status)) = program_handle.0.try_wait() {
                panic!("{} exited: {status}", program.display());
            }
            assert!(
                started.elapsed() < Duration::from_secs(30),
                "{} did not open udp port {port}",
                program.display()
            );
            std::thread::sleep(Duration::from_millis(20));
        }
    }
}

impl Program {
    /// Stops it with SIGTERM, so it flushes what it writes (MAVProxy its
    /// log), and waits for it: killed after 10 s.
    pub fn terminate(mut self) {
        signal(self.0.id(), "TERM");
        let started = Instant::now();
        while started.elapsed() < Duration::from_secs(10) {
            if let Ok(Some(_)) = self.0.try_wait() {
                return;
            }
            std::thread::sleep(Duration::from_millis(20));
        }
    }
}

impl Drop for Program {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

/// A pty pair joined by `tests/peers/pty_bridge.py` (with `args`): the
/// bridge and the two device paths.
pub fn pty_bridge(args: &[&str]) -> (Peer, String, String) {
    let mut bridge = Peer::start("pty_bridge.py", args);
    let line = bridge.read_line();
    let (a, b) = line.split_once(' ').expect("two pty paths");
    (bridge, a.to_string(), b.to_string())
}

/// A running peer process; killed when dropped.
pub struct Peer {
    child: Child,
    stdout: BufReader<ChildStdout>,
}

impl Peer {
    /// Starts `tests/peers/<script>` with pymavlink and waits for "ready".
    pub fn start(script: &str, args: &[&str]) -> Peer {
        let mut child = Command::new(python())
            .arg("-u")
            .arg(peer_script(script))
            .args(args)
            .stdout(Stdio::piped())
            .stderr(Stdio::inherit())
            .spawn()
            .expect("start peer");
        let mut stdout = BufReader::new(child.stdout.take().unwrap());
        let mut line = String::new();
        stdout.read_line(&mut line).unwrap();
        assert_eq!(
            line.trim(),
            "ready",
            "peer {script} did not start: {line:?}"
        );
        Peer { child, stdout }
    }

    /// The next line the peer prints (after "ready").
    pub fn read_line(&mut self) -> String {
        let mut line = String::new();
        self.stdout.read_line(&mut line).unwrap();
        line.trim().to_string()
    }

    /// Stops the peer with SIGTERM and returns its ground-truth JSON line.
    pub fn finish(mut self) -> serde_json::Value {
        signal(self.child.id(), "TERM");
        // pymavlink itself may print notices (e.g. "EOF on TCP socket").
        let mut line = String::new();
        while self.stdout.read_line(&mut line).unwrap() > 0 && !line.starts_with('{') {
            line.clear();
        }
        let _ = self.child.wait();
        serde_json::from_str(&line).unwrap_or_else(|e| panic!("peer truth {line:?}: {e}"))
    }

    /// Kills the peer at once (a vanishing responder).
    pub fn kill(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

impl Drop for Peer {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

pub fn signal(pid: u32, name: &str) {
    let status = Command::new("kill")
        .arg(format!("-{name}"))
        .arg(pid.to_string())
        .status()
        .unwrap();
    assert!(status.success());
}

pub fn mavping() -> Command {
    Command::new(env!("CARGO_BIN_EXE_mavping"))
}

/// Runs mavping to completion with a generous guard against hangs.
pub fn run_mavping(args: &[&str]) -> (i32, String, String) {
    let child = mavping()
        .args(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    wait_output(child, Duration::from_secs(60))
}

/// A mavping run in the background whose first line was read: the link
/// is open, so peers that must connect to it can start.
pub struct Running {
    pub child: Child,
    pub first_line: String,
    rest: std::thread::JoinHandle<String>,
}

pub fn start_mavping(args: &[&str]) -> Running {
    let mut child = mavping()
        .args(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut stdout = BufReader::new(child.stdout.take().unwrap());
    let mut first_line = String::new();
    stdout.read_line(&mut first_line).unwrap();
    let rest = std::thread::spawn(move || {
        let mut rest = String::new();
        std::io::Read::read_to_string(&mut stdout, &mut rest).unwrap();
        rest
    });
    Running {
        child,
        first_line,
        rest,
    }
}

impl Running {
    /// Waits for the run to end: (exit code, whole stdout, stderr).
    pub fn wait(self, limit: Duration) -> (i32, String, String) {
        let (code, _, err) = wait_output(self.child, limit);
        let out = self.first_line + &self.rest.join().unwrap();
        (code, out, err)
    }
}

pub fn wait_output(mut child: Child, limit: Duration) -> (i32, String, String) {
    use std::io::Read;
    // Drain both pipes while waiting: a child blocked on a full pipe never exits.
    let drain = |pipe: Option<Box<dyn Read + Send>>| {
        std::thread::spawn(move || {
            let mut text = String::new();
            if let Some(mut p) = pipe {
                let mut bytes = Vec::new();
                let _ = p.read_to_end(&mut bytes);
                text = String::from_utf8_lossy(&bytes).into_owned();
            }
            text
        })
    };
    let out = drain(
        child
            .stdout
            .take()
            .map(|p| Box::new(p) as Box<dyn Read + Send>),
    );
    let err = drain(
        child
            .stderr
            .take()
            .map(|p| Box::new(p) as Box<dyn Read + Send>),
    );
    let start = Instant::now();
    let status = loop {
        if let Some(status) = child.try_wait().unwrap() {
            break status;
        }
        if start.elapsed() > limit {
            let _ = child.kill();
            panic!("mavping did not finish within {limit:?}");
        }
        std::thread::sleep(Duration::from_millis(10));
    };
    (
        status.code().unwrap_or(-1),
        out.join().unwrap(),
        err.join().unwrap(),
    )
}

/// Counts from a text summary line "1/1 (...): 10 sent, 9 received, ...".
#[derive(Debug, Default, PartialEq, Eq)]
pub struct TextCounts {
    pub sent: u64,
    pub received: u64,
    pub lost: u64,
    pub late: u64,
    pub duplicate: u64,
    pub out_of_order: u64,
    pub stale: u64,
}

pub fn text_counts(stdout: &str, responder: &str) -> Option<TextCounts> {
    let summary = stdout.split("mavping statistics ---").nth(1)?;
    let line = summary.lines().find(|l| {
        l.starts_with(&format!("{responder}:")) || l.starts_with(&format!("{responder} "))
    })?;
    let counts = line
        .split("): ")
        .nth(1)
        .or_else(|| line.split(": ").nth(1))?;
    let mut c = TextCounts::default();
    for part in counts.split(", ") {
        let mut words = part.split_whitespace();
        let n: u64 = words.next()?.parse().ok()?;
        match words.next()? {
            "sent" => c.sent = n,
            "received" => c.received = n,
            "lost" => c.lost = n,
            "late" => c.late = n,
            "duplicate" => c.duplicate = n,
            "out" => c.out_of_order = n,
            "stale" => c.stale = n,
            _ => {}
        }
    }
    Some(c)
}

/// One figure of the simulated link's ground truth for `responder`, from
/// the `sim truth 1/1: answered=.. dropped=..` line a `-v` run logs.
pub fn sim_truth(stderr: &str, responder: &str, key: &str) -> u64 {
    let line = stderr
        .lines()
        .find(|l| l.contains(&format!("sim truth {responder}:")))
        .unwrap_or_else(|| panic!("no sim truth for {responder} in {stderr}"));
    line.split_whitespace()
        .find_map(|p| p.strip_prefix(&format!("{key}=")))
        .and_then(|v| v.trim_matches(|c: char| !c.is_ascii_digit()).parse().ok())
        .unwrap_or_else(|| panic!("no {key} in {line}"))
}
