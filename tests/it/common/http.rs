//! Talking HTTP to mavping's exporters and to Prometheus in tests: a plain
//! HTTP/1.1 GET over a socket, an exposition parser that keeps label
//! values whole (connection strings hold `=`, `&` and `,`), and promtool.

use std::collections::BTreeMap;
use std::io::{BufRead, BufReader, Read, Write};
use std::net::TcpStream;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

/// An HTTP response.
#[derive(Debug)]
pub struct Response {
    pub status: u16,
    pub head: String,
    pub body: String,
}

/// `GET path` on `host` ("127.0.0.1:PORT") with extra header lines.
pub fn http_get(host: &str, path: &str, headers: &[(&str, &str)]) -> Response {
    let mut s = TcpStream::connect(host).unwrap_or_else(|e| panic!("connect to {host}: {e}"));
    s.set_read_timeout(Some(Duration::from_secs(60))).unwrap();
    let mut request = format!("GET {path} HTTP/1.1\r\nHost: {host}\r\nConnection: close\r\n");
    for (k, v) in headers {
        request.push_str(&format!("{k}: {v}\r\n"));
    }
    request.push_str("\r\n");
    s.write_all(request.as_bytes()).unwrap();
    let mut response = String::new();
    s.read_to_string(&mut response).unwrap();
    let (head, body) = response
        .split_once("\r\n\r\n")
        .unwrap_or_else(|| panic!("not an HTTP response: {response:?}"));
    let status = head
        .split(' ')
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or_else(|| panic!("no status in {head:?}"));
    Response {
        status,
        head: head.to_string(),
        body: body.to_string(),
    }
}

/// One sample of an exposition.
#[derive(Debug, Clone, PartialEq)]
pub struct Sample {
    pub name: String,
    pub labels: BTreeMap<String, String>,
    pub value: f64,
}

/// Every sample of a Prometheus text exposition (comments skipped).
pub fn samples(text: &str) -> Vec<Sample> {
    text.lines()
        .filter(|l| !l.is_empty() && !l.starts_with('#'))
        .map(|line| {
            let (series, value) = line.rsplit_once(' ').expect("NAME VALUE");
            let value: f64 = match value {
                "+Inf" => f64::INFINITY,
                v => v.parse().unwrap_or_else(|_| panic!("value in {line}")),
            };
            let (name, labels) = match series.split_once('{') {
                Some((name, rest)) => (name, parse_labels(rest.strip_suffix('}').unwrap())),
                None => (series, BTreeMap::new()),
            };
            Sample {
                name: name.to_string(),
                labels,
                value,
            }
        })
        .collect()
}

fn parse_labels(mut text: &str) -> BTreeMap<String, String> {
    let mut labels = BTreeMap::new();
    while !text.is_empty() {
        let (key, rest) = text.split_once("=\"").expect("key=\"value\"");
        let mut value = String::new();
        let mut chars = rest.char_indices();
        let end = loop {
            match chars.next().expect("closing quote") {
                (_, '\\') => match chars.next().unwrap().1 {
                    'n' => value.push('\n'),
                    c => value.push(c),
                },
                (i, '"') => break i,
                (_, c) => value.push(c),
            }
        };
        labels.insert(key.to_string(), value);
        text = rest[end + 1..].trim_start_matches(',');
    }
    labels
}

/// The value of the one sample named `name` whose labels include `labels`.
pub fn sample(text: &str, name: &str, labels: &[(&str, &str)]) -> Option<f64> {
    let found: Vec<Sample> = samples(text)
        .into_iter()
        .filter(|s| {
            s.name == name
                && labels
                    .iter()
                    .all(|(k, v)| s.labels.get(*k).map(String::as_str) == Some(*v))
        })
        .collect();
    assert!(found.len() <= 1, "{name}{labels:?} is ambiguous: {found:?}");
    found.first().map(|s| s.value)
}

/// A program of Debian's prometheus package (`prometheus`, `promtool`),
/// which scripts/test.sh installs; missing, the test fails saying so.
pub fn prometheus_tool(name: &str) -> Command {
    let found = Command::new(name)
        .arg("--version")
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|s| s.success());
    assert!(
        found,
        "{name} is missing — run `bash scripts/test.sh` (it installs Debian's prometheus package)"
    );
    Command::new(name)
}

pub fn promtool() -> Command {
    prometheus_tool("promtool")
}

/// `promtool check metrics` finds nothing to say about `text`.
pub fn assert_promtool_clean(text: &str) {
    let mut check = promtool()
        .args(["check", "metrics"])
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    check
        .stdin
        .take()
        .unwrap()
        .write_all(text.as_bytes())
        .unwrap();
    let out = check.wait_with_output().unwrap();
    assert!(
        out.status.success() && out.stdout.is_empty() && out.stderr.is_empty(),
        "promtool check metrics: {}{}\n{text}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
}

#[test]
fn label_values_stay_whole() {
    let text = "# HELP x y\nm{link=\"sim:?a=1&b=2,c\",q=\"\\\"\\\\\"} 3\nn 1.5\n";
    let all = samples(text);
    assert_eq!(all.len(), 2);
    assert_eq!(all[0].labels["link"], "sim:?a=1&b=2,c");
    assert_eq!(all[0].labels["q"], "\"\\");
    assert_eq!(sample(text, "n", &[]), Some(1.5));
    assert_eq!(sample(text, "m", &[("link", "sim:?a=1&b=2,c")]), Some(3.0));
    assert_eq!(sample(text, "m", &[("link", "sim:")]), None);
}

/// A `mavping -q --prometheus 127.0.0.1:0 ARGS...` run, killed when the
/// test ends; `host` is the address it announced.
pub struct Exporting {
    pub child: Child,
    pub host: String,
}

impl Exporting {
    pub fn start(args: &[&str]) -> Exporting {
        let mut child = super::mavping()
            .args(["-q", "--prometheus", "127.0.0.1:0"])
            .args(args)
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        let mut line = String::new();
        BufReader::new(child.stderr.take().unwrap())
            .read_line(&mut line)
            .unwrap();
        let host = line
            .trim()
            .strip_prefix("mavping: serving metrics at http://")
            .and_then(|l| l.strip_suffix("/metrics"))
            .unwrap_or_else(|| panic!("no address announced: {line:?}"))
            .to_string();
        Exporting { child, host }
    }

    /// Scrapes `/metrics` until `ready` holds of the exposition (20 s at
    /// most, then the test fails showing the last one).
    pub fn scrape_until(&self, what: &str, ready: impl Fn(&str) -> bool) -> String {
        let start = Instant::now();
        loop {
            let body = http_get(&self.host, "/metrics", &[]).body;
            if ready(&body) {
                return body;
            }
            assert!(
                start.elapsed() < Duration::from_secs(20),
                "not {what}:\n{body}"
            );
            std::thread::sleep(Duration::from_millis(50));
        }
    }

    /// Still measuring (a run with no count ends only on a signal).
    pub fn running(&mut self) -> bool {
        self.child.try_wait().unwrap().is_none()
    }
}

impl Drop for Exporting {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}
