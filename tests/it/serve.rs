//! `mavping serve` as Prometheus and an operator use it: `/probe` against a
//! pymavlink responder with known drops, bad and forbidden requests, probes
//! that fail, continuous links that break and come back, reloads on SIGHUP,
//! bounded concurrency and the scrape's timeout (hostile clients:
//! endpoints.rs).

use std::path::PathBuf;
use std::time::{Duration, Instant};

use crate::common::{
    assert_promtool_clean, free_udp_port, sample, Peer, Response, Server, SilentPeer,
};

/// Generous bound for something that normally takes a second or two;
/// reaching it fails the test instead of hanging it.
const PATIENCE: Duration = Duration::from_secs(30);

/// Scrapes `/metrics` until `done` holds for it.
fn metrics_until(server: &Server, what: &str, done: impl Fn(&str) -> bool) -> String {
    let start = Instant::now();
    loop {
        let r = server.get("/metrics");
        assert_eq!(r.status, 200, "{}", r.body);
        if done(&r.body) {
            return r.body;
        }
        assert!(
            start.elapsed() < PATIENCE,
            "{what} not seen within {PATIENCE:?}:\n{}\nstderr:\n{}",
            r.body,
            server.stderr()
        );
        std::thread::sleep(Duration::from_millis(100));
    }
}

/// A query string value, percent-encoded.
fn enc(value: &str) -> String {
    form_urlencoded::byte_serialize(value.as_bytes()).collect()
}

/// A config file in the temp directory, removed when dropped.
pub(crate) struct TempFile(PathBuf);

impl TempFile {
    pub(crate) fn new(name: &str, text: &str) -> Self {
        let path = std::env::temp_dir().join(format!("mavping-{}-{name}", std::process::id()));
        std::fs::write(&path, text).unwrap();
        TempFile(path)
    }

    fn write(&self, text: &str) {
        std::fs::write(&self.0, text).unwrap();
    }

    pub(crate) fn path(&self) -> &str {
        self.0.to_str().unwrap()
    }
}

impl Drop for TempFile {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.0);
    }
}

#[test]
fn a_probe_counts_exactly_what_the_responder_dropped() {
    let port = free_udp_port();
    let responder = Peer::start(
        "responder.py",
        &[
            &format!("udpin:127.0.0.1:{port}"),
            "--drop",
            "1,4",
            "--dup",
            "6",
        ],
    );
    let server = Server::start(&["--allow", "udpout:127.0.0.1:*"]);
    let target = format!("udpout:127.0.0.1:{port}");
    let path = format!(
        "/probe?target={}&count=10&interval=20ms&timeout=500ms",
        enc(&target)
    );
    let r1 = server.get(&path);
    let r2 = server.get(&path);
    let truth = responder.finish();
    for r in [&r1, &r2] {
        assert_eq!(r.status, 200, "{}", r.body);
        assert!(
            r.head
                .to_ascii_lowercase()
                .contains("content-type: text/plain; version=0.0.4"),
            "{}",
            r.head
        );
        let b = &r.body;
        let one = [("link", target.as_str()), ("sysid", "1"), ("compid", "1")];
        let v = |name| sample(b, name, &one).unwrap_or_else(|| panic!("no {name} in\n{b}"));
        assert_eq!(sample(b, "mavping_probe_success", &[]), Some(1.0), "{b}");
        assert_eq!(sample(b, "mavping_probe_requests", &[]), Some(10.0));
        assert_eq!(sample(b, "mavping_probe_in_flight", &[]), Some(0.0));
        // Each probe is a session of its own: sequences 0-9, the same two
        // dropped and one duplicated each time.
        assert_eq!(v("mavping_probe_sent"), 10.0);
        assert_eq!(v("mavping_probe_received"), 8.0);
        assert_eq!(v("mavping_probe_lost"), 2.0);
        assert_eq!(v("mavping_probe_duplicate"), 1.0);
        assert_eq!(v("mavping_probe_late"), 0.0);
        assert_eq!(v("mavping_probe_loss_ratio"), 0.2);
        assert_eq!(v("mavping_probe_rtt_seconds_count"), 8.0);
        let p50 = v("mavping_rtt_p50_seconds");
        let p99 = v("mavping_rtt_p99_seconds");
        assert!(0.0 < p50 && p50 <= p99 && p99 < 0.5, "{p50} {p99}");
        let duration = sample(b, "mavping_probe_duration_seconds", &[]).unwrap();
        assert!(duration > 0.18 && duration < 9.5, "{duration}");
        assert!(sample(b, "mavping_probe_failure", &[]).is_none());
        // A probe's figures never pose as counters.
        assert!(!b.contains("_total"), "{b}");
        assert_promtool_clean(b);
    }
    assert_eq!(truth["ping_requests"], 20, "{truth}");
    assert_eq!(truth["dropped"], 4, "{truth}");
    assert_eq!(truth["duplicated"], 2, "{truth}");
    let m = server.get("/metrics").body;
    assert_eq!(sample(&m, "mavping_exporter_probes_total", &[]), Some(2.0));
    assert_eq!(
        sample(&m, "mavping_exporter_probes_failed_total", &[]),
        Some(0.0)
    );
    assert_eq!(
        sample(&m, "mavping_exporter_probes_running", &[]),
        Some(0.0)
    );
    assert_eq!(sample(&m, "mavping_exporter_open_links", &[]), Some(0.0));
    assert_promtool_clean(&m);
}

#[test]
fn bad_requests_get_one_line_and_failed_probes_a_reason() {
    let server = Server::start(&[
        "--allow",
        "udpout:127.0.0.1:*",
        "--allow",
        "/dev/mavping-test-missing*",
    ]);
    for (query, needle) in [
        (
            format!("target={}&module=fast", enc("udpout:127.0.0.1:9")),
            "unknown module 'fast'; known: default",
        ),
        (
            format!("target={}", enc("udpout:10.9.8.7:14550")),
            "target udpout:10.9.8.7:14550 is not allowed: it matches no allow pattern",
        ),
        (
            format!("target={}", enc("udpout:nowhere")),
            "bad connection string 'udpout:nowhere'",
        ),
        (String::new(), "missing target"),
        (
            format!("target={}&count=-1", enc("udpout:127.0.0.1:9")),
            "count '-1'",
        ),
        (
            format!("target={}&probe=echo", enc("udpout:127.0.0.1:9")),
            "probe 'echo'",
        ),
    ] {
        let r = server.get(&format!("/probe?{query}"));
        assert_eq!(r.status, 400, "{query}: {}", r.body);
        assert!(r.body.contains(needle), "{query}: {}", r.body);
        assert_eq!(r.body.lines().count(), 1, "{}", r.body);
    }
    // Probes that run and fail are answered with why.
    let closed = format!("udpout:127.0.0.1:{}", free_udp_port());
    for (target, reason) in [
        (closed.as_str(), "link_failed"),
        ("/dev/mavping-test-missing0", "open_failed"),
    ] {
        let r = server.get(&format!("/probe?target={}&count=3", enc(target)));
        assert_eq!(r.status, 200, "{target}: {}", r.body);
        assert_eq!(
            sample(&r.body, "mavping_probe_success", &[]),
            Some(0.0),
            "{}",
            r.body
        );
        assert_eq!(
            sample(&r.body, "mavping_probe_failure", &[("reason", reason)]),
            Some(1.0),
            "{}",
            r.body
        );
        // The error itself, for whoever reads the answer.
        assert!(r.body.starts_with("# mavping: "), "{}", r.body);
        assert_promtool_clean(&r.body);
    }
    assert_eq!(server.get("/nothing").status, 404);
    let m = server.get("/metrics").body;
    assert_eq!(
        sample(&m, "mavping_exporter_probes_refused_total", &[]),
        Some(6.0)
    );
    assert_eq!(sample(&m, "mavping_exporter_probes_total", &[]), Some(2.0));
    assert_eq!(
        sample(&m, "mavping_exporter_probes_failed_total", &[]),
        Some(2.0)
    );

    // With nothing allowed, every target is refused, with how to allow one.
    let closed_door = Server::start(&[]);
    let r = closed_door.get("/probe?target=sim%3A");
    assert_eq!(r.status, 400);
    assert!(
        r.body
            .contains("no target is; start mavping serve with --allow PATTERN"),
        "{}",
        r.body
    );
}

#[test]
fn continuous_links_come_back_and_reloads_keep_their_history() {
    let port = free_udp_port();
    let link = format!("udpout:127.0.0.1:{port}");
    let config = |extra: &str| {
        format!(
            "[[link]]\nlink = \"{link}\"\nname = \"radio\"\ninterval = \"50ms\"\ntimeout = \"300ms\"\n{extra}"
        )
    };
    let file = TempFile::new("serve-reload.toml", &config(""));
    let server = Server::start(&["--config", file.path()]);
    let radio = [("link", "radio")];
    // Nobody answers yet: ICMP port unreachable breaks the link, which is
    // shown down and retried.
    metrics_until(&server, "the link down and retried", |m| {
        sample(m, "mavping_link_up", &radio) == Some(0.0)
            && sample(m, "mavping_link_restarts_total", &radio).unwrap_or(0.0) >= 1.0
    });
    assert!(server
        .stderr()
        .contains("link radio: nothing listening at 127.0.0.1:"));
    let responder = Peer::start("responder.py", &[&format!("udpin:127.0.0.1:{port}")]);
    let one = [("link", "radio"), ("sysid", "1"), ("compid", "1")];
    let m = metrics_until(&server, "replies on the reopened link", |m| {
        sample(m, "mavping_link_up", &radio) == Some(1.0)
            && sample(m, "mavping_received_total", &one).unwrap_or(0.0) >= 5.0
    });
    let restarts = sample(&m, "mavping_link_restarts_total", &radio).unwrap();
    let before = sample(&m, "mavping_sent_total", &one).unwrap();

    // A reload that adds a link leaves this one running: its counters go
    // on from where they were, and it is not restarted.
    file.write(&config(
        "[[link]]\nlink = \"sim:\"\nname = \"sim\"\ninterval = \"50ms\"\n",
    ));
    server.signal("HUP");
    let m = metrics_until(&server, "the new link", |m| {
        sample(m, "mavping_received_total", &[("link", "sim")]).unwrap_or(0.0) > 0.0
    });
    assert!(sample(&m, "mavping_sent_total", &one).unwrap() >= before);
    assert_eq!(
        sample(&m, "mavping_link_restarts_total", &radio),
        Some(restarts)
    );
    assert_eq!(
        sample(&m, "mavping_exporter_config_reloads_total", &[]),
        Some(1.0)
    );

    // An invalid file is refused; everything goes on as it was.
    file.write("[[link]]\nlink = \"nowhere\"\n");
    server.signal("HUP");
    let m = metrics_until(&server, "the refused reload", |m| {
        sample(m, "mavping_exporter_config_reloads_failed_total", &[]) == Some(1.0)
    });
    assert_eq!(
        sample(&m, "mavping_exporter_config_last_reload_successful", &[]),
        Some(0.0)
    );
    // The stderr line is written before the count grows, and read by a
    // thread of the test's: wait for it.
    let start = std::time::Instant::now();
    while !server
        .stderr()
        .contains("reload refused, the old configuration stays:")
    {
        assert!(
            start.elapsed() < Duration::from_secs(30),
            "{}",
            server.stderr()
        );
        std::thread::sleep(Duration::from_millis(50));
    }
    let kept = sample(&m, "mavping_sent_total", &one).unwrap();

    // A changed link is restarted under its name, history kept; a link
    // taken out of the file goes.
    file.write(&config("").replace("50ms", "20ms"));
    server.signal("HUP");
    let m = metrics_until(&server, "the sim link gone", |m| {
        sample(m, "mavping_link_up", &[("link", "sim")]).is_none()
            && sample(m, "mavping_exporter_config_last_reload_successful", &[]) == Some(1.0)
    });
    assert!(sample(&m, "mavping_sent_total", &one).unwrap() >= kept);
    let m = metrics_until(&server, "the changed link measuring again", |m| {
        sample(m, "mavping_sent_total", &one).unwrap() > kept + 20.0
    });
    let (sent, received, lost) = (
        sample(&m, "mavping_sent_total", &one).unwrap(),
        sample(&m, "mavping_received_total", &one).unwrap(),
        sample(&m, "mavping_lost_total", &one).unwrap(),
    );
    assert_eq!(sent, received + lost, "{m}");
    assert_promtool_clean(&m);
    drop(responder);
    assert_eq!(server.stop(), Some(0));
}

#[test]
fn excess_probes_are_turned_away_and_probes_end_within_the_scrape_timeout() {
    let server = Server::start(&["--allow", "sim:**", "--max-concurrent", "1"]);
    let addr = server.addr.clone();
    // Ten seconds of requests, but the scrape allows three.
    let long = std::thread::spawn(move || {
        crate::common::http_get(
            &addr,
            "/probe?target=sim%3A&count=100&interval=100ms",
            &[("X-Prometheus-Scrape-Timeout-Seconds", "3")],
        )
    });
    metrics_until(&server, "the running probe", |m| {
        sample(m, "mavping_exporter_probes_running", &[]) == Some(1.0)
    });
    let r = server.get("/probe?target=sim%3A");
    assert_eq!(r.status, 503, "{}", r.body);
    assert_eq!(
        r.body,
        "too many probes at once: max_concurrent is 1; try again\n"
    );
    let Response { status, body, .. } = long.join().unwrap();
    assert_eq!(status, 200, "{body}");
    let duration = sample(&body, "mavping_probe_duration_seconds", &[]).unwrap();
    assert!(
        duration < 3.0,
        "the probe outlived the scrape: {duration} s"
    );
    let requests = sample(&body, "mavping_probe_requests", &[]).unwrap();
    assert!((1.0..100.0).contains(&requests), "{requests}");
    assert_eq!(sample(&body, "mavping_probe_success", &[]), Some(1.0));
    // The slot is free again.
    let r = server.get("/probe?target=sim%3A&count=2&interval=10ms");
    assert_eq!(r.status, 200, "{}", r.body);
}

#[test]
fn bad_command_lines_and_a_port_in_use_exit_2_with_one_line() {
    let taken = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    let addr = taken.local_addr().unwrap().to_string();
    for (args, needle) in [
        (
            vec!["serve", "--allow", "*"],
            "--allow: allow pattern '*': start it with a link kind",
        ),
        (
            vec!["serve", "--link", "nowhere"],
            "--link: bad connection string 'nowhere'",
        ),
        (
            vec!["serve", "--listen", "localhost:9465"],
            "--listen localhost:9465: expected ADDR:PORT",
        ),
        (
            vec!["serve", "--max-concurrent", "0"],
            "max_concurrent 0: expected 1 to 1024",
        ),
        (
            vec!["serve", "--config", "/nonexistent/serve.toml"],
            "--config /nonexistent/serve.toml: cannot read it",
        ),
        (vec!["serve", "--listen", &addr], "Address already in use"),
    ] {
        let (code, out, err) = crate::common::run_mavping(&args);
        assert_eq!(code, 2, "{args:?}: {err}");
        assert!(out.is_empty(), "{out}");
        assert_eq!(err.lines().count(), 1, "{err}");
        assert!(
            err.starts_with("mavping: ") && err.contains(needle),
            "{args:?}: {err}"
        );
    }
}

#[test]
fn a_passive_link_counts_each_source_across_reopenings() {
    let port = free_udp_port();
    let vehicle = |args: &[&str]| {
        let listen = format!("udpin:127.0.0.1:{port}");
        let mut all = vec![listen.as_str(), "--frames", "200", "--rate", "100"];
        all.extend(args);
        Peer::start("vehicle.py", &all)
    };
    // The first vehicle numbers 200 frames and does not send two of them.
    let mut first = vehicle(&["--drop", "30,31"]);
    let file = TempFile::new(
        "serve-passive.toml",
        &format!(
            "[[link]]\nlink = \"udpout:127.0.0.1:{port}\"\nname = \"vehicle\"\npassive = true\n"
        ),
    );
    let server = Server::start(&["--config", file.path()]);
    let link = [("link", "vehicle")];
    let one = [("link", "vehicle"), ("sysid", "1"), ("compid", "1")];
    let value = |m: &str, name: &str| sample(m, name, &one);
    let truth: serde_json::Value = serde_json::from_str(&first.read_line()).unwrap();
    let sent_first = truth["sent"].as_f64().unwrap();
    let m = metrics_until(&server, "the first vehicle counted and silent", |m| {
        value(m, "mavping_source_received_total") == Some(sent_first)
            && value(m, "mavping_source_silent") == Some(1.0)
    });
    assert_promtool_clean(&m);
    assert_eq!(value(&m, "mavping_source_lost_total"), Some(2.0));
    // Nothing is probed on a passive link.
    assert!(!m.contains("mavping_sent_total"), "{m}");

    // It goes away: our HEARTBEAT meets ICMP port unreachable, the link
    // breaks and is reopened; a second vehicle (its sequence from 0 again)
    // loses one frame and doubles one.
    first.kill();
    metrics_until(&server, "the link reopened", |m| {
        sample(m, "mavping_link_restarts_total", &link).unwrap_or(0.0) >= 1.0
    });
    let mut second = vehicle(&["--drop", "50", "--dup", "70"]);
    let truth: serde_json::Value = serde_json::from_str(&second.read_line()).unwrap();
    let sent = sent_first + truth["sent"].as_f64().unwrap();
    let m = metrics_until(&server, "both vehicles counted", |m| {
        value(m, "mavping_source_received_total") == Some(sent)
            && value(m, "mavping_source_silent") == Some(1.0)
    });
    assert_promtool_clean(&m);
    // The counters go on across the two sessions of the link.
    assert_eq!(value(&m, "mavping_source_lost_total"), Some(3.0));
    assert_eq!(value(&m, "mavping_source_duplicate_total"), Some(1.0));
    assert_eq!(value(&m, "mavping_source_reordered_total"), Some(0.0));
    // Each vehicle's silence after its last frame.
    assert_eq!(value(&m, "mavping_source_silences_total"), Some(2.0));
    assert_eq!(value(&m, "mavping_source_lost_pending"), Some(0.0));
    assert_eq!(
        value(&m, "mavping_source_loss_ratio"),
        Some(3.0 / (sent - 1.0 + 3.0))
    );
    assert_eq!(sample(&m, "mavping_link_up", &link), Some(1.0));
    assert_eq!(server.stop(), Some(0));
}

#[test]
fn a_probe_splits_its_loss_by_direction() {
    let server = Server::start(&["--allow", "sim:**"]);
    let target = enc("sim:?stream=ATTITUDE@50&loss_up=10%&loss_down=5%&seed=7");
    let r = server.get(&format!("/probe?target={target}&count=200&interval=10ms"));
    assert_eq!(r.status, 200, "{}", r.body);
    assert_promtool_clean(&r.body);
    let m = &r.body;
    let one = [("sysid", "1"), ("compid", "1")];
    let dir = |d: &str| {
        sample(
            m,
            "mavping_direction_loss_ratio",
            &[one.as_slice(), &[("direction", d)]].concat(),
        )
        .unwrap_or_else(|| panic!("no {d} in\n{m}"))
    };
    // The probe's own counts give the round trip; up is the summary's
    // formula on it and the responder's downlink.
    let lost = sample(m, "mavping_probe_lost", &one).unwrap();
    let sent = sample(m, "mavping_probe_sent", &one).unwrap();
    assert_eq!(dir("round_trip"), lost / sent);
    let (down, up) = (dir("down"), dir("up"));
    assert!(down > 0.0 && down < 0.15, "{down}");
    assert!((up - (1.0 - (1.0 - lost / sent) / (1.0 - down))).abs() < 1e-12);
    assert_eq!(
        sample(m, "mavping_direction_split_consistent", &one),
        Some(1.0)
    );
}

#[test]
fn serve_probes_as_the_command_line_does_so_mavsdk_answers() {
    // MAVSDK drops frames from 255/190 (QGroundControl's ids); serve used
    // them, so /probe of a default mavsdk_server failed with no hint, and
    // a continuous link to it showed only that it was up.
    let port = free_udp_port();
    let _mavsdk = crate::common::Program::start_on_udp(
        &crate::common::venv_program("mavsdk_server"),
        &["-p", "0", &format!("udpin://127.0.0.1:{port}")],
        &std::env::temp_dir(),
        port,
    );
    let target = format!("udpout:127.0.0.1:{port}");
    let server = Server::start(&["--allow", "udpout:127.0.0.1:*", "--link", &target]);
    let r = server.get(&format!(
        "/probe?target={}&count=4&interval=100ms&timeout=500ms",
        enc(&target)
    ));
    assert_eq!(r.status, 200, "{}", r.body);
    let b = &r.body;
    let mavsdk = [("sysid", "245"), ("compid", "190")];
    assert_eq!(sample(b, "mavping_probe_success", &[]), Some(1.0), "{b}");
    assert_eq!(
        sample(b, "mavping_probe_received", &mavsdk),
        Some(4.0),
        "{b}"
    );
    // The continuous link hears it answer too.
    let m = metrics_until(&server, "replies from 245/190", |m| {
        sample(
            m,
            "mavping_received_total",
            &[("link", &target), ("sysid", "245")],
        )
        .is_some_and(|v| v > 0.0)
    });
    assert_promtool_clean(&m);
}

/// A `/probe` names its target: every request to it counts, the first
/// ones too. The responder drops 0, 1, 2 and 7 of each probe's ten: with a
/// long timeout its first answer (to 3) comes while 0-2 are undecided,
/// with a short one after 0 and 1 were decided; either way the probe
/// charges all four, as the responder's own count says.
#[test]
fn a_probe_charges_the_requests_dropped_before_the_first_answer() {
    let port = free_udp_port();
    let responder = Peer::start(
        "responder.py",
        &[&format!("udpin:127.0.0.1:{port}"), "--drop", "0,1,2,7"],
    );
    let server = Server::start(&["--allow", "udpout:127.0.0.1:*"]);
    let target = format!("udpout:127.0.0.1:{port}");
    let answers: Vec<Response> = ["interval=20ms&timeout=500ms", "interval=30ms&timeout=50ms"]
        .iter()
        .map(|timing| server.get(&format!("/probe?target={}&count=10&{timing}", enc(&target))))
        .collect();
    let truth = responder.finish();
    assert_eq!(truth["ping_requests"], 20, "{truth}");
    assert_eq!(truth["dropped"], 8, "{truth}");
    assert_eq!(truth["replies"], 12, "{truth}");
    for r in &answers {
        assert_eq!(r.status, 200, "{}", r.body);
        let b = &r.body;
        let one = [("link", target.as_str()), ("sysid", "1"), ("compid", "1")];
        let v = |name| sample(b, name, &one).unwrap_or_else(|| panic!("no {name} in\n{b}"));
        assert_eq!(sample(b, "mavping_probe_requests", &[]), Some(10.0), "{b}");
        assert_eq!(v("mavping_probe_sent"), 10.0, "{b}");
        assert_eq!(v("mavping_probe_received"), 6.0, "{b}");
        assert_eq!(v("mavping_probe_lost"), 4.0, "{b}");
        assert_eq!(v("mavping_probe_loss_ratio"), 0.4, "{b}");
        assert_eq!(sample(b, "mavping_probe_success", &[]), Some(1.0), "{b}");
        assert_promtool_clean(b);
    }
}

/// The case: 20 probes of 10 against `mavping respond` dropping
/// 12 % at random. Every request of every probe counts, so the probes'
/// losses add up to exactly what the responder dropped (the first
/// requests' included: before, each probe excused those).
#[test]
fn twenty_probes_lose_exactly_what_mavping_respond_dropped() {
    let port = free_udp_port();
    let respond = crate::common::Respond::start(&[
        "--drop",
        "12%",
        "--seed",
        "3",
        &format!("udpin:127.0.0.1:{port}"),
    ]);
    let server = Server::start(&["--allow", "udpout:127.0.0.1:*"]);
    let target = format!("udpout:127.0.0.1:{port}");
    let one = [("link", target.as_str()), ("sysid", "1"), ("compid", "1")];
    let (mut sent, mut lost) = (0.0, 0.0);
    for _ in 0..20 {
        let r = server.get(&format!(
            "/probe?target={}&interval=20ms&timeout=300ms",
            enc(&target)
        ));
        assert_eq!(r.status, 200, "{}", r.body);
        sent += sample(&r.body, "mavping_probe_sent", &one).unwrap();
        lost += sample(&r.body, "mavping_probe_lost", &one).unwrap();
    }
    let (code, counts) = respond.finish();
    assert_eq!(code, 0);
    // requests, ping, timesync, command, retransmissions, replies, dropped
    assert_eq!(counts[1], 200, "{counts:?}");
    assert!(counts[6] > 0, "{counts:?}");
    assert_eq!((sent, lost), (200.0, counts[6] as f64), "{counts:?}");
}

/// `/probe` of a listening link nobody sends to gives up as `-c` does
/// (3 requests at 100 ms plus a 200 ms timeout: 0.5 s), not at the
/// scrape's deadline, and says why.
#[test]
fn a_probe_of_a_listening_link_with_no_peer_gives_up_and_says_so() {
    let server = Server::start(&["--allow", "udpin:127.0.0.1:*"]);
    let target = format!("udpin:127.0.0.1:{}", free_udp_port());
    let r = crate::common::http_get(
        &server.addr,
        &format!(
            "/probe?target={}&count=3&interval=100ms&timeout=200ms",
            enc(&target)
        ),
        &[("X-Prometheus-Scrape-Timeout-Seconds", "30")],
    );
    assert_eq!(r.status, 200, "{}", r.body);
    let b = &r.body;
    assert_eq!(
        b.lines().next(),
        Some(format!("# mavping: no MAVLink system heard on {target} in 0.5 s").as_str()),
        "{b}"
    );
    assert_eq!(sample(b, "mavping_probe_success", &[]), Some(0.0), "{b}");
    for reason in ["nothing_heard", "no_reply"] {
        assert_eq!(
            sample(b, "mavping_probe_failure", &[("reason", reason)]),
            Some(1.0),
            "{b}"
        );
    }
    assert_eq!(sample(b, "mavping_probe_requests", &[]), Some(0.0), "{b}");
    // It waited what the count takes, not the 29.5 s the scrape allowed.
    let took = sample(b, "mavping_probe_duration_seconds", &[]).unwrap();
    assert!((0.5..5.0).contains(&took), "{took}");
    assert_promtool_clean(b);
    let m = server.get("/metrics").body;
    assert_eq!(
        sample(&m, "mavping_exporter_probes_failed_total", &[]),
        Some(1.0)
    );
    assert_eq!(sample(&m, "mavping_exporter_open_links", &[]), Some(0.0));
}

/// A continuous link nobody answers shows its requests going out and no
/// responder (the rule MavlinkLinkUnanswered fires on that), beside one a
/// responder answers. Requests go every 2 s, so each is told at once: a
/// scrape between two readings of the peer that found the same count
/// shows exactly that count.
#[test]
fn a_continuous_link_nobody_answers_shows_its_requests_and_no_responder() {
    let mut silent = SilentPeer::bind();
    let port = free_udp_port();
    let responder = Peer::start("responder.py", &[&format!("udpin:127.0.0.1:{port}")]);
    let file = TempFile::new(
        "serve-unanswered.toml",
        &format!(
            "[[link]]\nlink = \"udpout:127.0.0.1:{}\"\nname = \"silent\"\ninterval = \"2s\"\n\
             timeout = \"500ms\"\n\n[[link]]\nlink = \"udpout:127.0.0.1:{port}\"\n\
             name = \"answered\"\ninterval = \"2s\"\ntimeout = \"500ms\"\n",
            silent.port()
        ),
    );
    let server = Server::start(&["--config", file.path()]);
    let quiet = [("link", "silent"), ("probe", "ping")];
    let heard = [("link", "answered"), ("probe", "ping")];
    metrics_until(&server, "three requests on the silent link", |m| {
        sample(m, "mavping_requests_total", &quiet).unwrap_or(0.0) >= 3.0
            && sample(m, "mavping_responders", &heard) == Some(1.0)
    });
    let (m, requests) = loop {
        let before = silent.pings();
        let m = server.get("/metrics").body;
        let after = silent.pings();
        let requests = sample(&m, "mavping_requests_total", &quiet).unwrap();
        assert!(
            before as f64 <= requests && requests <= after as f64,
            "{before} <= {requests} <= {after}"
        );
        if before == after {
            break (m, requests);
        }
    };
    assert!(requests >= 3.0, "{m}");
    assert_eq!(sample(&m, "mavping_responders", &quiet), Some(0.0), "{m}");
    assert_eq!(
        sample(&m, "mavping_link_up", &[("link", "silent")]),
        Some(1.0)
    );
    // Nothing per responder: there is none.
    assert!(!m.contains("mavping_sent_total{link=\"silent\""), "{m}");
    let answered = sample(&m, "mavping_requests_total", &heard).unwrap();
    let one = [("link", "answered"), ("sysid", "1"), ("compid", "1")];
    let received = sample(&m, "mavping_received_total", &one).unwrap();
    assert!(answered >= 2.0 && received >= 1.0, "{m}");
    assert_promtool_clean(&m);
    drop(responder);
    assert_eq!(server.stop(), Some(0));
}

/// A module with `report = "c2"`: each `/probe` run gauges its C2 link
/// report, and its `min_availability` is one of the probe's checks. The
/// simulated link is silent from 1 s to 2.5 s of a 3 s probe (30 PINGs
/// at 100 ms): one outage of that silence less the 500 ms rule, in the
/// 1-3 s band; continuity is the PINGs answered within the timeout, as
/// the probe's own counts say; the HEARTBEATs at 1 Hz against a 1.2 s
/// down timeout trip once, in the silence.
#[test]
fn a_c2_module_gauges_the_report_and_checks_its_availability() {
    let config = TempFile::new(
        "c2.toml",
        "allow = [\"sim:*\"]\n\
         [module.c2]\nprobe = \"ping\"\ncount = 30\ninterval = \"100ms\"\ntimeout = \"500ms\"\n\
         report = \"c2\"\nup_within = \"500ms\"\nmin_availability = \"99%\"\n\
         failsafe = [\"custom:message=heartbeat,timeout=1.2s,direction=down\"]\n",
    );
    let server = Server::start(&["--config", config.path()]);
    let target = "sim:?outage=1s+1500ms&seed=4";
    let r = server.get(&format!("/probe?module=c2&target={}", enc(target)));
    assert_eq!(r.status, 200, "{}", r.body);
    let b = &r.body;
    let link = [("link", target)];
    let c2 = |name| sample(b, name, &link).unwrap_or_else(|| panic!("no {name} in\n{b}"));
    let one = [("link", target), ("sysid", "1"), ("compid", "1")];
    let (sent, received) = (
        sample(b, "mavping_probe_sent", &one).unwrap(),
        sample(b, "mavping_probe_received", &one).unwrap(),
    );
    assert!(received < sent, "{b}");
    assert_eq!(c2("mavping_c2_continuity_ratio"), received / sent, "{b}");
    let down = c2("mavping_c2_down_seconds");
    // The silence is the outage's 1.5 s and up to a frame interval
    // (100 ms) either side; the rule takes 0.5 s of it.
    assert!((0.95..=1.25).contains(&down), "{down}\n{b}");
    assert_eq!(c2("mavping_c2_longest_outage_seconds"), down);
    let bands = |band| sample(b, "mavping_c2_outages", &[("link", target), ("band", band)]);
    assert_eq!(bands("1-3s"), Some(1.0), "{b}");
    assert_eq!(bands("<1s"), Some(0.0), "{b}");
    let availability = c2("mavping_c2_availability_ratio");
    assert!(availability < 0.99 && availability > 0.5, "{availability}");
    let trips = sample(
        b,
        "mavping_c2_failsafe_trips",
        &[("link", target), ("model", "custom")],
    );
    assert_eq!(trips, Some(1.0), "{b}");
    assert_eq!(sample(b, "mavping_probe_success", &[]), Some(0.0), "{b}");
    assert_eq!(
        sample(
            b,
            "mavping_probe_failure",
            &[("reason", "min_availability")]
        ),
        Some(1.0),
        "{b}"
    );
    assert_promtool_clean(b);
    // A probe of the default module asks for the report in its query
    // (the defaults: a 2 s rule): the 1.5 s silence is no outage by it.
    let r = server.get(&format!("/probe?target={}&count=20&report=c2", enc(target)));
    assert_eq!(r.status, 200, "{}", r.body);
    let b = &r.body;
    assert_eq!(
        sample(b, "mavping_c2_down_seconds", &link),
        Some(0.0),
        "{b}"
    );
    assert_eq!(sample(b, "mavping_probe_success", &[]), Some(1.0), "{b}");
    let r = server.get(&format!("/probe?target={}&report=pdf", enc(target)));
    assert_eq!(r.status, 400, "{}", r.body);
    assert_eq!(r.body.trim(), "report 'pdf': expected c2", "{}", r.body);
}
