//! Issue 21: each PING reply hidden among mutated copies of itself (bit
//! flips, cuts, junk prefixes rich in start bytes, lying lengths, random
//! bytes, a lone 0xFD), sent by a seeded pymavlink peer
//! (tests/peers/mutant_peer.py) over UDP (a datagram each), TCP and a pty
//! (one byte stream). Every true reply is received, nothing is lost, and
//! every whole copy the peer sent is counted as a duplicate, seq by seq.
//!
//! `scripts/mutation-soak.sh` runs these with many seeds and exchanges:
//! MAVPING_MUTANT_SEED, MAVPING_MUTANT_EXCHANGES and
//! MAVPING_MUTANT_INTERVAL set them; each test prints one `mutants:` line
//! of figures.

use std::collections::BTreeMap;
use std::time::Instant;

use crate::common::*;

fn env_or(name: &str, default: &str) -> String {
    std::env::var(name).unwrap_or_else(|_| default.to_string())
}

/// Runs mavping against the peer for `exchanges` requests and checks every
/// count against the peer's ground truth.
fn replies_among_mutants(transport: &str, default_exchanges: u64) {
    let seed = env_or("MAVPING_MUTANT_SEED", "21");
    let exchanges = env_or("MAVPING_MUTANT_EXCHANGES", &default_exchanges.to_string());
    let interval = env_or("MAVPING_MUTANT_INTERVAL", "2ms");
    // The pty bridge lives until mavping is done.
    let mut bridge = None;
    let (option, endpoint, link) = match transport {
        "udp" => {
            let port = free_udp_port().to_string();
            ("--port", port.clone(), format!("udpout:127.0.0.1:{port}"))
        }
        "tcp" => {
            let port = free_tcp_port().to_string();
            ("--tcp", port.clone(), format!("tcp:127.0.0.1:{port}"))
        }
        _ => {
            let (b, ours, theirs) = pty_bridge(&[]);
            bridge = Some(b);
            ("--serial", theirs, format!("serial:{ours}:57600"))
        }
    };
    let args = ["--seed", &seed, "--count", &exchanges, option, &endpoint];
    let peer = Peer::start("mutant_peer.py", &args);
    let started = Instant::now();
    let (code, out, err) = run_mavping(&["--json", "-c", &exchanges, "-i", &interval, &link]);
    let wall = started.elapsed();
    let truth = peer.finish();
    drop(bridge);
    assert_eq!(code, 0, "{err}");

    let t = |k: &str| n(&truth, k);
    let exchanges: u64 = exchanges.parse().unwrap();
    assert_eq!(
        (t("requests"), t("replies")),
        (exchanges, exchanges),
        "{truth}"
    );
    // The test is only as good as its mutants: each kind was sent, and
    // some copies were whole.
    for (kind, sent) in truth["kinds"].as_object().unwrap() {
        assert!(sent.as_u64().unwrap() > 0, "no {kind} mutant: {truth}");
    }
    assert!(t("intact") > 0, "{truth}");

    // Seq by seq: the reply and every whole copy, counted once each.
    let events = json_lines(&out);
    let mut counted: BTreeMap<u64, u64> = BTreeMap::new();
    for e in &events {
        if matches!(e["type"].as_str(), Some("reply" | "late" | "duplicate")) {
            assert_eq!(e["responder"], serde_json::json!({"sysid": 1, "compid": 1}));
            *counted.entry(n(e, "seq")).or_default() += 1;
        }
    }
    let copies = |seq: u64| truth["copies"][seq.to_string()].as_u64().unwrap_or(0);
    let wrong: Vec<String> = counted
        .iter()
        .filter(|&(&seq, &got)| got != 1 + copies(seq))
        .map(|(seq, got)| format!("seq {seq}: {got} counted, {} sent", 1 + copies(*seq)))
        .collect();
    // Whole copies on the wire (replies included) not counted, and counts
    // with no copy behind them.
    let sent = exchanges + t("intact");
    let counted_total: u64 = counted.values().sum();
    println!(
        "mutants: {transport} seed={seed} exchanges={exchanges} mutants={} intact={} \
         missed={} extra={} redrawn={} bytes={} wall_s={:.1}",
        t("mutants"),
        t("intact"),
        sent.saturating_sub(counted_total),
        counted_total.saturating_sub(sent),
        t("redrawn"),
        t("bytes"),
        wall.as_secs_f64(),
    );
    assert!(wrong.is_empty(), "{}", wrong.join("\n"));
    assert_eq!(counted.len() as u64, exchanges, "a seq never answered");

    let s = summary_of(&out);
    let r = responder(&s, "1/1");
    let counts = ["sent", "received", "lost", "late", "duplicate", "stale"].map(|k| n(r, k));
    assert_eq!(
        counts,
        [exchanges, exchanges, 0, 0, t("intact"), 0],
        "sent, received, lost, late, duplicate, stale: {r}"
    );
    assert_eq!(n(&s, "in_flight"), 0);
    assert_eq!(n(&s, "foreign_replies"), 0);
    // Nothing but the reply and its whole copies passed as a frame.
    assert_eq!(
        n(&s["frames"], "frames"),
        exchanges + t("intact"),
        "{}",
        s["frames"]
    );
}

#[test]
fn udp_replies_among_mutated_copies_are_all_counted() {
    replies_among_mutants("udp", 1500);
}

#[test]
fn tcp_replies_among_mutated_copies_are_all_counted() {
    replies_among_mutants("tcp", 500);
}

#[test]
fn pty_replies_among_mutated_copies_are_all_counted() {
    replies_among_mutants("pty", 500);
}
