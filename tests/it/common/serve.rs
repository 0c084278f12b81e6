//! A `mavping serve` running in the background for a test.

use std::io::{BufRead, BufReader};
use std::process::{Child, Command, Stdio};
use std::sync::{Arc, Mutex};

use super::http::{http_get, Response};
use super::{mavping, signal};

/// A running `mavping serve`, killed when dropped. Its stderr is collected
/// as it comes (a full pipe would stall it).
pub struct Server {
    child: Child,
    /// "127.0.0.1:PORT"
    pub addr: String,
    stderr: Arc<Mutex<String>>,
}

impl Server {
    /// Starts `mavping serve ARGS` on a free loopback port (unless ARGS
    /// name one) and waits until it serves.
    pub fn start(args: &[&str]) -> Server {
        Server::start_as(mavping(), args)
    }

    /// As [`Server::start`], `serve ARGS` given to `command` (another
    /// binary, or mavping under setpriv).
    pub fn start_as(mut command: Command, args: &[&str]) -> Server {
        command.arg("serve");
        if !args.contains(&"--listen") {
            command.args(["--listen", "127.0.0.1:0"]);
        }
        let mut child = command
            .args(args)
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        let mut stderr = BufReader::new(child.stderr.take().unwrap());
        let mut line = String::new();
        stderr.read_line(&mut line).unwrap();
        // "...at http://ADDR/", or "at https://ADDR/ (TLS, ...)" with a web
        // config.
        let addr = line
            .trim()
            .strip_prefix("mavping: serving /probe and /metrics at ")
            .and_then(|l| l.strip_prefix("http://").or(l.strip_prefix("https://")))
            .and_then(|l| l.split_once('/').map(|(addr, _)| addr))
            .unwrap_or_else(|| panic!("mavping serve did not start: {line:?}"))
            .to_string();
        let collected = Arc::new(Mutex::new(String::new()));
        let sink = collected.clone();
        std::thread::spawn(move || {
            for line in stderr.lines().map_while(Result::ok) {
                let mut all = sink.lock().unwrap();
                all.push_str(&line);
                all.push('\n');
            }
        });
        Server {
            child,
            addr,
            stderr: collected,
        }
    }

    pub fn get(&self, path: &str) -> Response {
        http_get(&self.addr, path, &[])
    }

    /// What it printed on stderr after its first line, so far.
    pub fn stderr(&self) -> String {
        self.stderr.lock().unwrap().clone()
    }

    pub fn pid(&self) -> u32 {
        self.child.id()
    }

    pub fn signal(&self, name: &str) {
        signal(self.child.id(), name);
    }

    /// Stops it with SIGTERM; its exit code.
    pub fn stop(mut self) -> Option<i32> {
        self.signal("TERM");
        self.child.wait().unwrap().code()
    }
}

impl Drop for Server {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}
