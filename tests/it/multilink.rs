//! Several links side by side: two pymavlink responders on two UDP ports
//! with different reply delays and one behind a pty serial link, in one
//! run; the simulated links for exact, reproducible output.

use std::time::Duration;

use crate::common::*;
use serde_json::Value;

const SIMS: [&str; 2] = ["sim:?clock=virtual", "sim:?delay=50ms&clock=virtual"];

/// Each link's summary object, by its link.
fn summary_for(out: &str, link: &str) -> Value {
    json_lines(out)
        .into_iter()
        .find(|v| v["type"] == "summary" && v["link"] == link)
        .unwrap_or_else(|| panic!("no summary for {link} in\n{out}"))
}

/// The ids of the responders in a summary, and the first one's object.
fn responders(summary: &Value) -> (Vec<String>, Value) {
    let all = summary["responders"].as_array().unwrap();
    let ids = all
        .iter()
        .map(|r| format!("{}/{}", r["responder"]["sysid"], r["responder"]["compid"]))
        .collect();
    (ids, all.first().cloned().unwrap_or(Value::Null))
}

/// The text summary section of one link (from its header on).
fn text_section<'a>(out: &'a str, link: &str) -> &'a str {
    let header = format!("--- {link} mavping statistics ---");
    let start = out
        .find(&header)
        .unwrap_or_else(|| panic!("no summary for {link} in\n{out}"));
    let rest = &out[start..];
    let end = rest[header.len()..]
        .find("\n--- ")
        .map_or(rest.len(), |i| i + header.len() + 1);
    &rest[..end]
}

#[test]
fn each_link_has_its_own_figures() {
    let (pa, pb) = (free_udp_port(), free_udp_port());
    let fast = Peer::start(
        "responder.py",
        &[&format!("udpin:127.0.0.1:{pa}"), "--sysid", "1"],
    );
    let slow = Peer::start(
        "responder.py",
        &[
            &format!("udpin:127.0.0.1:{pb}"),
            "--sysid",
            "2",
            "--delay-ms",
            "80",
            "--drop",
            "3",
        ],
    );
    let (_bridge, a, b) = pty_bridge(&[]);
    let serial = Peer::start("responder.py", &[&b, "--baud", "57600", "--sysid", "3"]);
    let links = [
        format!("udpout:127.0.0.1:{pa}"),
        format!("udpout:127.0.0.1:{pb}"),
        format!("serial:{a}:57600"),
    ];
    let (code, out, err) = run_mavping(&[
        "-c", "10", "-i", "0.1", "-W", "1s", "--json", &links[0], &links[1], &links[2],
    ]);
    assert_eq!(code, 0, "{out}\n{err}");
    // Every object names its link, and each link saw only its responder.
    for v in json_lines(&out) {
        assert!(links.iter().any(|l| v["link"] == l.as_str()), "{v}");
        if let Some(r) = v.get("responder").filter(|_| v["type"] == "reply") {
            let expected = links.iter().position(|l| v["link"] == l.as_str()).unwrap() + 1;
            assert_eq!(r["sysid"], expected, "{v}");
        }
    }
    let mut figures = Vec::new();
    for (link, id, received, lost) in [
        (&links[0], "1/1", 10, 0),
        (&links[1], "2/1", 9, 1),
        (&links[2], "3/1", 10, 0),
    ] {
        let s = summary_for(&out, link);
        assert_eq!(s["requests"], 10, "{s}");
        assert!(s["link_error"].is_null(), "{s}");
        let (ids, r) = responders(&s);
        assert_eq!(ids, [id], "{link}: {s}");
        assert_eq!(
            (&r["sent"], &r["received"], &r["lost"], &r["duplicate"]),
            (
                &Value::from(10),
                &Value::from(received),
                &Value::from(lost),
                &Value::from(0)
            ),
            "{link}: {r}"
        );
        figures.push((
            r["rtt_us"]["min"].as_f64().unwrap(),
            r["rtt_us"]["max"].as_f64().unwrap(),
        ));
    }
    // The slow responder holds each reply 80 ms; the fast one does not.
    assert!(figures[1].0 >= 80_000.0, "{figures:?}");
    assert!(figures[0].0 < figures[1].0, "{figures:?}");
    assert_eq!(fast.finish()["replies"], 10);
    assert_eq!(slow.finish()["replies"], 9);
    assert_eq!(serial.finish()["replies"], 10);
}

#[test]
fn killing_one_links_peer_ends_that_link_only() {
    let (pa, pb) = (free_udp_port(), free_udp_port());
    let _steady = Peer::start("responder.py", &[&format!("udpin:127.0.0.1:{pa}")]);
    let mut doomed = Peer::start(
        "responder.py",
        &[&format!("udpin:127.0.0.1:{pb}"), "--sysid", "2"],
    );
    let (_bridge, a, b) = pty_bridge(&[]);
    let _serial = Peer::start("responder.py", &[&b, "--baud", "57600", "--sysid", "3"]);
    let links = [
        format!("udpout:127.0.0.1:{pa}"),
        format!("udpout:127.0.0.1:{pb}"),
        format!("serial:{a}:57600"),
    ];
    let run = start_mavping(&[
        "-c", "30", "-i", "0.05", "-W", "1s", &links[0], &links[1], &links[2],
    ]);
    // Killed once it has answered a few requests.
    std::thread::sleep(Duration::from_millis(700));
    doomed.kill();
    let (code, out, err) = run.wait(Duration::from_secs(30));
    assert_eq!(code, 2, "a failed link makes the run exit 2\n{out}\n{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(
        err.starts_with(&format!(
            "mavping: {}: nothing listening at 127.0.0.1:{pb} (ICMP port unreachable)",
            links[1]
        )),
        "{err}"
    );
    // The others went on to the end, with exact counts.
    for (link, id) in [(&links[0], "1/1"), (&links[2], "3/1")] {
        let section = text_section(&out, link);
        assert!(section.starts_with(&format!("--- {link} mavping statistics ---\n30 requests")));
        let c = text_counts(section, id).expect(section);
        assert_eq!((c.sent, c.received, c.lost), (30, 30, 0), "{section}");
    }
    // The failed link still has the summary of what it measured.
    let section = text_section(&out, &links[1]);
    let c = text_counts(section, "2/1").expect(section);
    assert!(
        c.received >= 1 && c.sent == c.received + c.lost,
        "{section}"
    );
    // Reply lines say their link.
    for (i, link) in links.iter().enumerate() {
        let line = format!("[{link}] reply from {}/1: seq=0 ", i + 1);
        assert!(out.contains(&line), "{line} not in\n{out}");
    }
}

#[test]
fn simulated_links_side_by_side_snapshot() {
    let (code, out, err) = run_mavping(&["-c", "4", "-i", "0.1", SIMS[0], SIMS[1]]);
    assert_eq!(code, 0, "{err}");
    insta::assert_snapshot!("two_sim_links", out);
}

#[test]
fn several_links_json_matches_the_schema_and_names_every_link() {
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/schema/mavping-events.schema.json"
    ))
    .unwrap();
    let schema = jsonschema::validator_for(&serde_json::from_str(&text).unwrap()).unwrap();
    let (code, out, err) = run_mavping(&[
        "-c",
        "5",
        "-i",
        "0.1",
        "--json",
        "sim:?loss=20%&seed=3&clock=virtual",
        SIMS[1],
    ]);
    assert_eq!(code, 0, "{err}");
    let lines = json_lines(&out);
    for v in &lines {
        assert!(schema.is_valid(v), "{v}");
        // The run's own lines (the pair report) name every link.
        if v["type"] == "pair_summary" || v["type"] == "link_matrix" {
            assert!(v["links"].is_array(), "{v}");
        } else {
            assert!(v["link"].is_string(), "{v}");
        }
    }
    for link in ["sim:?loss=20%&seed=3&clock=virtual", SIMS[1]] {
        let replies = lines
            .iter()
            .filter(|v| v["type"] == "reply" && v["link"] == link)
            .count() as u64;
        let s = summary_for(&out, link);
        assert_eq!(s["responders"][0]["received"].as_u64(), Some(replies));
    }
    let slow = summary_for(&out, SIMS[1]);
    assert!(slow["responders"][0]["rtt_us"]["min"].as_f64().unwrap() >= 100_000.0);
}

#[test]
fn exports_carry_the_link() {
    let dir = std::env::temp_dir().join(format!("mavping-multilink-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let (csv, hgrm) = (dir.join("s.csv"), dir.join("h.hgrm"));
    let (code, _, err) = run_mavping(&[
        "-c",
        "4",
        "-i",
        "0.1",
        "-q",
        "--samples",
        csv.to_str().unwrap(),
        "--hgrm",
        hgrm.to_str().unwrap(),
        SIMS[0],
        SIMS[1],
    ]);
    assert_eq!(code, 0, "{err}");
    let csv = std::fs::read_to_string(&csv).unwrap();
    let mut lines = csv.lines();
    assert!(lines
        .next()
        .unwrap()
        .ends_with(",status,rssi,remrssi,txbuf,noise,remnoise,link"));
    for link in SIMS {
        let rows = csv
            .lines()
            .filter(|l| l.ends_with(&format!(",ok,,,,,,{link}")));
        assert_eq!(rows.count(), 4, "{link}\n{csv}");
    }
    assert_eq!(csv.lines().count(), 9, "{csv}");
    let hgrm = std::fs::read_to_string(&hgrm).unwrap();
    for link in SIMS {
        assert!(hgrm.contains(link), "{link}\n{hgrm}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn thresholds_and_expect_apply_to_each_link() {
    // Two responders on the first link, one on the second: --expect 2
    // holds on the first and fails on the second.
    let first = "sim:?responders=2&clock=virtual";
    let (code, out, _) = run_mavping(&[
        "-c", "3", "-i", "0.1", "-q", "--expect", "2", first, SIMS[1],
    ]);
    assert_eq!(code, 1, "{out}");
    assert!(!text_section(&out, first).contains("FAILED"), "{out}");
    assert!(
        text_section(&out, SIMS[1]).contains("FAILED expect"),
        "{out}"
    );
    // Scoped to one link, it is checked there only.
    let scoped = format!("{first}=2");
    let (code, out, _) = run_mavping(&["-c", "3", "-q", "--expect", &scoped, first, SIMS[1]]);
    assert_eq!(code, 0, "{out}");
    let scoped = format!("{}=2", SIMS[1]);
    let (code, out, _) = run_mavping(&["-c", "3", "-q", "--expect", &scoped, first, SIMS[1]]);
    assert_eq!(code, 1, "{out}");
    assert!(
        text_section(&out, SIMS[1]).contains("FAILED expect"),
        "{out}"
    );
    let (code, out, _) = run_mavping(&[
        "-c",
        "3",
        "-i",
        "0.1",
        "-q",
        "--max-rtt",
        "80ms",
        SIMS[0],
        SIMS[1],
    ]);
    assert_eq!(code, 1, "{out}");
    assert!(!text_section(&out, SIMS[0]).contains("FAILED"), "{out}");
    assert!(
        text_section(&out, SIMS[1]).contains("FAILED max-rtt"),
        "{out}"
    );
}

#[test]
fn a_link_that_cannot_open_ends_only_itself() {
    let bad = "serial:/dev/ttyMAVPING_NONE:57600";
    let (code, out, err) = run_mavping(&["-c", "3", "-i", "0.05", "-q", bad, "sim:"]);
    assert_eq!(code, 2, "{out}\n{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(err.contains(&format!("cannot open {bad}")), "{err}");
    let c = text_counts(text_section(&out, "sim:"), "1/1").expect(&out);
    assert_eq!((c.sent, c.received), (3, 3), "{out}");
}

#[test]
fn several_links_take_the_plot_and_the_command_probe() {
    let svg = std::env::temp_dir().join(format!("mavping-links-{}.svg", std::process::id()));
    let svg_arg = svg.to_str().unwrap();
    let (code, out, err) = run_mavping(&[
        "-c", "5", "-i", "20ms", "-q", "--plot", svg_arg, SIMS[0], SIMS[1],
    ]);
    assert_eq!(code, 0, "{out}\n{err}");
    let drawn = std::fs::read_to_string(&svg).unwrap();
    std::fs::remove_file(&svg).unwrap();
    for label in [
        "mavping, 2 links",
        &format!("{} 1/1", SIMS[0]),
        &format!("{} 1/1", SIMS[1]),
    ] {
        // SVG text escapes '&'.
        let label = label.replace('&', "&amp;");
        assert!(drawn.contains(&label), "{label} not in the plot");
    }
    // Each link's responder has a colour of its own (Okabe–Ito blue and
    // vermillion), seen in the rendered picture.
    let png = Rendered::of(&drawn, "two-links");
    for rgb in [0x0072B2, 0xD55E00] {
        assert!(png.count(rgb) > 100, "{rgb:06X} in {}", png.path.display());
    }

    let (code, out, err) = run_mavping(&[
        "--probe", "command", "-c", "3", "-i", "200ms", SIMS[0], SIMS[1],
    ]);
    assert_eq!(code, 0, "{out}\n{err}");
    for link in SIMS {
        let section = text_section(&out, link);
        assert!(
            section.contains(": 3 commands, 3 acknowledged, 0 failed"),
            "{link}: {out}"
        );
    }
    assert!(
        out.contains(&format!("[{}] ack from 1/1: cmd=0", SIMS[1])),
        "{out}"
    );
}

#[test]
fn live_view_has_a_section_per_link() {
    let command = format!(
        "{} --live -i 0.02 -W 300ms 'sim:?loss=20%&seed=5' 'sim:?delay=30ms'; echo exit=$?",
        env!("CARGO_BIN_EXE_mavping")
    );
    let tmux = Tmux::start("multilink", &command, 110, 20);
    // A section per link, each with its responder's row; a loss shows on
    // the lossy link.
    let screen = tmux.wait_for("two sections with rows", |screen| {
        let rows: Vec<&str> = screen.lines().filter(|l| l.starts_with("│1/1")).collect();
        rows.len() == 2 && rows[0].contains('×')
    });
    for text in [
        "mavping · 2 links · auto",
        "┌ sim:?loss=20%&seed=5 ─",
        "┌ sim:?delay=30ms ─",
    ] {
        assert!(screen.contains(text), "{text:?} not on screen:\n{screen}");
    }
    tmux.send_keys("q");
    let screen = tmux.wait_for("exit=", |s| s.contains("exit=0"));
    for link in ["sim:?loss=20%&seed=5", "sim:?delay=30ms"] {
        assert!(
            screen.contains(&format!("--- {link} mavping statistics ---")),
            "{screen}"
        );
    }
    assert!(
        !screen.contains("q or Ctrl-C"),
        "the view was not left:\n{screen}"
    );
}

#[test]
fn prometheus_serves_a_series_per_link() {
    let links = ["sim:?loss=20%&seed=4&delay=1ms", "sim:?delay=3ms"];
    let run = Exporting::start(&["-i", "0.01", links[0], links[1]]);
    let series = |link: &str| {
        format!(
            "mavping_received_total{{link=\"{link}\",probe=\"auto\",sysid=\"1\",compid=\"1\"}} "
        )
    };
    // Both links have answered and the lossy one has lost a request.
    let body = run.scrape_until("both links answering, the lossy one losing", |body| {
        let answered = links.iter().all(|l| {
            body.lines()
                .any(|x| x.starts_with(&series(l)) && !x.ends_with(" 0"))
        });
        answered && body.contains(&format!("mavping_lost_total{{link=\"{}\"", links[0]))
    });
    assert_eq!(
        body.matches("# TYPE mavping_received_total counter")
            .count(),
        1,
        "{body}"
    );
    assert_promtool_clean(&body);
}
