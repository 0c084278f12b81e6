//! `mavping respond` on several links (issue 41): one identity, one packet
//! sequence, as a vehicle with two links. What goes to every peer goes
//! out on every link, the same bytes; an answer only on its request's
//! link. Held to the responder's own count of what each link carried.

use std::process::Stdio;
use std::time::{Duration, Instant};

use serde_json::Value;

use crate::common::*;
use crate::passive_peers::json_line;

/// What `respond` says one link carried: frames received, sent, and sent
/// to one peer only.
#[derive(Debug, PartialEq, Eq)]
struct Carried {
    received: u64,
    sent: u64,
    to_one: u64,
}

/// The responder's lines for `link` ("  on LINK: ...").
fn carried(out: &str, link: &str) -> Carried {
    let line = out
        .lines()
        .find_map(|l| l.strip_prefix(&format!("  on {link}: ")))
        .unwrap_or_else(|| panic!("no line for {link} in\n{out}"));
    let n: Vec<u64> = line
        .split(|c: char| !c.is_ascii_digit())
        .filter(|s| !s.is_empty())
        .map(|s| s.parse().unwrap())
        .collect();
    Carried {
        received: n[0],
        sent: n[1],
        to_one: n[2],
    }
}

/// Waits (at most 10 s) until something listens on UDP `port`.
fn wait_bound(port: u16) {
    let local = format!("0100007F:{port:04X} ");
    let started = Instant::now();
    while !std::fs::read_to_string("/proc/net/udp")
        .unwrap_or_default()
        .lines()
        .any(|l| l.contains(&local))
    {
        assert!(
            started.elapsed() < Duration::from_secs(10),
            "nothing on {port}"
        );
        std::thread::sleep(Duration::from_millis(20));
    }
}

fn count(v: &Value, key: &str) -> u64 {
    v[key].as_u64().unwrap_or_else(|| panic!("no {key} in {v}"))
}

/// The responder streams to two links while mavping listens on both: the
/// pair report finds every frame sent to every peer on both links, once
/// each, and only the frames the responder sent one peer (its greetings)
/// on one link.
#[test]
fn one_identity_on_two_links_sends_the_same_frames_on_both() {
    let (a, b) = (free_udp_port(), free_udp_port());
    let listen = [
        format!("udpin:127.0.0.1:{a}"),
        format!("udpin:127.0.0.1:{b}"),
    ];
    let listener = mavping()
        .args([
            "--passive",
            "--json",
            "-q",
            "-w",
            "4",
            &listen[0],
            &listen[1],
        ])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    wait_bound(a);
    wait_bound(b);
    let out = [
        format!("udpout:127.0.0.1:{a}"),
        format!("udpout:127.0.0.1:{b}"),
    ];
    let responder = Respond::start(&["--stream", "ATTITUDE@50", &out[0], &out[1]]);
    std::thread::sleep(Duration::from_secs(2));
    let (code, said) = responder.finish_text();
    assert_eq!(code, 0, "{said}");
    let (code, stdout, err) = wait_output(listener, Duration::from_secs(30));
    assert_eq!(code, 0, "{err}");
    assert_schema(&json_lines(&stdout));
    let pair = json_line(&stdout, "pair_summary");
    let source = &pair["sources"][0];
    assert_eq!(
        source["source"],
        serde_json::json!({"sysid": 1, "compid": 1})
    );
    let told = [carried(&said, &out[0]), carried(&said, &out[1])];
    // Sent to every peer: the same frames on both links.
    let every = told[0].sent - told[0].to_one;
    assert_eq!(told[1].sent - told[1].to_one, every, "{said}");
    assert!(every > 90, "{said}");
    for (k, t) in told.iter().enumerate() {
        let link = &source["links"][k];
        assert_eq!(count(link, "frames"), t.sent, "link {k}: {link}");
        assert_eq!(count(link, "only"), t.to_one, "link {k}: {link}");
        // The other link's greeting numbers are the gaps in its own.
        assert_eq!(count(link, "lost"), told[1 - k].to_one, "link {k}: {link}");
    }
    assert_eq!(
        count(source, "distinct_frames"),
        every + told[0].to_one + told[1].to_one,
        "{source}"
    );
    assert_eq!(count(source, "copies"), every, "{source}");
    assert_eq!(count(source, "lost_on_every_link"), 0, "{source}");
}

/// mavping probes the responder over two links: every reply comes back on
/// its request's link and no other (no link sees a reply it did not ask
/// for), and the responder wrote each link its answers and one greeting.
#[test]
fn answers_go_back_on_the_link_their_request_came_on() {
    let (a, b) = (free_udp_port(), free_udp_port());
    let listen = [
        format!("udpin:127.0.0.1:{a}"),
        format!("udpin:127.0.0.1:{b}"),
    ];
    let responder = Respond::start(&[&listen[0], &listen[1]]);
    let out = [
        format!("udpout:127.0.0.1:{a}"),
        format!("udpout:127.0.0.1:{b}"),
    ];
    let (code, stdout, err) =
        run_mavping(&["-c", "50", "-i", "0.02", "--json", "-q", &out[0], &out[1]]);
    assert_eq!(code, 0, "{err}");
    let summaries: Vec<Value> = json_lines(&stdout)
        .into_iter()
        .filter(|v| v["type"] == "summary")
        .collect();
    assert_eq!(summaries.len(), 2, "{stdout}");
    for s in &summaries {
        for key in ["foreign_replies", "wrong_path_replies", "untracked_replies"] {
            assert_eq!(count(s, key), 0, "{key}: {s}");
        }
        let r = &s["responders"][0];
        assert_eq!((count(r, "sent"), count(r, "received")), (50, 50), "{r}");
        // A reply to the other link's request: a token it never sent.
        assert_eq!((count(r, "duplicate"), count(r, "stale")), (0, 0), "{r}");
    }
    let (code, said) = responder.finish_text();
    assert_eq!(code, 0, "{said}");
    assert!(
        said.contains("respond 1/1: 100 requests (100 ping"),
        "{said}"
    );
    for link in &listen {
        assert_eq!(carried(&said, link).to_one, 51, "{said}");
    }
}

/// A link that cannot be opened (its port taken) ends the responder at
/// once with one line, exit 2: one identity on every link or none.
#[test]
fn a_link_that_cannot_open_ends_the_responder() {
    let taken = std::net::UdpSocket::bind("127.0.0.1:0").unwrap();
    let busy = format!("udpin:127.0.0.1:{}", taken.local_addr().unwrap().port());
    let free = format!("udpin:127.0.0.1:{}", free_udp_port());
    let (code, out, err) = run_mavping(&["respond", &free, &busy]);
    assert_eq!(code, 2, "{out}{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(err.contains(&busy[6..]), "{err}");
    assert!(out.is_empty(), "{out}");
}
