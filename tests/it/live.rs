//! `--live` in a real terminal (a tmux pane of a set size), as a user sees
//! it: at 80×24 every column header is whole and every row fits inside its
//! borders, with one link or several; a wider terminal shows more of the
//! recent outcomes; responders beyond the screen are counted; a passive
//! run has a row per source, its identity and its seconds; `q` leaves the
//! view and prints the summary.

use std::process::Command;

use assert_cmd::cargo::cargo_bin;

use crate::common::Tmux;

/// What a kind of run's view shows: its column headers, in order, as the
/// header line must show them, and its key line.
struct Kind {
    headers: &'static [&'static str],
    keys: &'static str,
}

const ECHO: Kind = Kind {
    headers: &[
        "responder",
        "sent",
        "recv",
        "loss%",
        "late",
        "dup",
        "last",
        "p50",
        "p99",
        "jitter",
        "age",
        "ms",
        "recent",
    ],
    keys: "q or Ctrl-C: stop and print the summary · RTT in ms · × lost · ! late",
};

const PASSIVE: Kind = Kind {
    headers: &[
        "source", "identity", "recv", "lost", "loss%", "dup", "reord", "sil", "fr/s", "age", "ms",
        "per", "second",
    ],
    keys: "q or Ctrl-C: stop and print the summary · a bar a second: frames, red: lost",
};

/// Runs `mavping --live ARGS` in a `width` x `height` pane; the shell
/// prints the exit code when it ends.
fn live(name: &str, args: &str, width: u16, height: u16) -> Tmux {
    let command = format!(
        "{} --live -i 0.02 -W 300ms {args}; echo exit=$?",
        cargo_bin("mavping").display()
    );
    Tmux::start(name, &command, width, height)
}

/// A responder's row: `│1/1   ... strip│`.
fn is_row(line: &str) -> bool {
    line.strip_prefix('│')
        .and_then(|l| l.split_whitespace().next())
        .is_some_and(|id| {
            id.split('/').count() == 2 && id.split('/').all(|n| n.parse::<u16>().is_ok())
        })
}

fn rows(screen: &str) -> Vec<&str> {
    screen.lines().filter(|l| is_row(l)).collect()
}

/// The strip of recent outcomes at the end of a row.
fn strip(row: &str) -> &str {
    let last = row.split_whitespace().last().unwrap_or_default();
    last.trim_end_matches('│')
}

/// Everything a screen of `width` x `height` must hold to fit: no line
/// wider than the terminal or beyond its height, every header line with
/// every header whole and in order, every row closed by its right border,
/// and the key line whole at the bottom. Returns the number of sections.
fn assert_fits(screen: &str, width: usize, height: usize) -> usize {
    assert_fits_as(&ECHO, screen, width, height)
}

fn assert_fits_as(kind: &Kind, screen: &str, width: usize, height: usize) -> usize {
    let lines: Vec<&str> = screen.lines().collect();
    assert!(lines.len() <= height, "{} lines:\n{screen}", lines.len());
    for l in &lines {
        assert!(l.chars().count() <= width, "wider than {width}: {l:?}");
    }
    let first = format!("│{}", kind.headers[0]);
    let headers: Vec<&&str> = lines.iter().filter(|l| l.starts_with(&first)).collect();
    assert!(!headers.is_empty(), "no header line:\n{screen}");
    for h in &headers {
        let words: Vec<&str> = h.trim_matches('│').split_whitespace().collect();
        assert_eq!(words, kind.headers, "a header is cut or missing:\n{screen}");
        assert!(h.ends_with('│'), "{h:?}");
    }
    for r in rows(screen) {
        assert!(r.ends_with('│'), "a row overflows: {r:?}");
        assert_eq!(r.chars().count(), width, "{r:?}");
    }
    let keys = lines.iter().rev().find(|l| !l.trim().is_empty());
    assert_eq!(keys, Some(&kind.keys), "{screen}");
    headers.len()
}

/// Presses `q` and checks the view is left for the text summary of the
/// links named `links...`.
fn quit(tmux: &Tmux, links: &[&str]) {
    quit_as(&ECHO, tmux, links);
}

/// As [`quit`]; returns what the terminal shows then.
fn quit_as(kind: &Kind, tmux: &Tmux, links: &[&str]) -> String {
    tmux.send_keys("q");
    let screen = tmux.wait_for("exit=", |s| s.contains("exit="));
    assert!(screen.contains("exit=0"), "{screen}");
    for link in links {
        let summary = screen.lines().any(|l| {
            l.starts_with(&format!("--- {link}"))
                && l.trim_end().ends_with(" mavping statistics ---")
        });
        assert!(summary, "no summary of {link}:\n{screen}");
    }
    assert!(
        !screen.contains(kind.keys),
        "the view was not left:\n{screen}"
    );
    screen
}

#[test]
fn one_link_fits_80x24_and_a_wider_terminal_shows_more() {
    let link = "sim:?responders=2&loss=20%&delay=2ms&seed=5";
    // The figure columns take 69 characters (and 2 the borders); the strip
    // of recent outcomes has the rest: 9 of 80, 49 of 120.
    for (width, height, full) in [(80u16, 24u16, 9usize), (120, 40, 49)] {
        let tmux = live(&format!("one-{width}"), &format!("'{link}'"), width, height);
        // Both rows, a loss shown, and enough outcomes to fill the strip.
        let screen = tmux.wait_for_screen("two full rows with a loss", |s| {
            let rows = rows(s);
            rows.len() == 2
                && rows.iter().any(|r| r.contains('×'))
                && rows.iter().all(|r| strip(r).chars().count() >= full)
        });
        assert_eq!(assert_fits(&screen, width.into(), height.into()), 1);
        for text in ["mavping · auto · ", "┌ sim:?responders=2&"] {
            assert!(screen.contains(text), "{text:?} not on screen:\n{screen}");
        }
        quit(&tmux, &["sim:?responders=2&"]);
    }
}

/// A responder's `age ms` follows a growing downlink queue: with
/// TIMESYNC its replies carry its clock, and the sim's queue grows to
/// 600 ms over 6 s. The cell (the one before the strip) passes 300 ms
/// while the run goes on; before the queue it read near 0.
#[test]
fn a_responders_age_follows_a_growing_queue() {
    let link = "sim:?delay=5ms&jitter=0ms&queue_down=600ms@6s";
    let tmux = live("age", &format!("--probe timesync '{link}'"), 120, 40);
    let age_of = |s: &str| -> Option<f64> {
        let row = rows(s).first().copied()?;
        let cells: Vec<&str> = row.split_whitespace().collect();
        cells.get(cells.len().checked_sub(2)?)?.parse().ok()
    };
    let early = tmux.wait_for_screen("an age", |s| age_of(s).is_some());
    assert!(age_of(&early).unwrap() < 150.0, "{early}");
    let queued = tmux.wait_for_screen("an age past 300 ms", |s| {
        age_of(s).is_some_and(|a| a > 300.0)
    });
    assert_fits(&queued, 120, 40);
    quit(&tmux, &["sim:?responders=1&delay=5ms&"]);
}

#[test]
fn several_links_fit_80x24() {
    let links = [
        "sim:?responders=3&loss=20%&seed=5",
        "sim:?delay=30ms&loss=10%&seed=2",
        "sim:?responders=2&delay=5ms",
    ];
    let args = links.map(|l| format!("'{l}'")).join(" ");
    let tmux = live("several", &args, 80, 24);
    let screen = tmux.wait_for_screen("six rows", |s| rows(s).len() == 6);
    assert_eq!(assert_fits(&screen, 80, 24), 3, "{screen}");
    assert!(
        screen.starts_with("mavping · 3 links · auto · "),
        "{screen}"
    );
    for link in links {
        let title = format!("┌ {link} ─");
        assert!(
            screen.contains(&title),
            "{title:?} not on screen:\n{screen}"
        );
    }
    quit(
        &tmux,
        &[
            "sim:?responders=3&",
            "sim:?delay=30ms&",
            "sim:?responders=2&",
        ],
    );
}

#[test]
fn responders_beyond_the_screen_are_counted_at_80x24() {
    let tmux = live(
        "many",
        "'sim:?responders=40&delay=2ms' 'sim:?delay=30ms'",
        80,
        24,
    );
    // The first link shows the responders that fit and counts the rest
    // (once all 40 answered); the second keeps its section and its row.
    let more = |s: &str| format!("└ {} more responders ─", 40 + 1 - rows(s).len());
    let screen = tmux.wait_for_screen("40 responders counted", |s| s.contains(&more(s)));
    assert_eq!(assert_fits(&screen, 80, 24), 2, "{screen}");
    assert!(rows(&screen).len() > 10, "{screen}");
    assert!(screen.contains("┌ sim:?delay=30ms ─"), "{screen}");
    // 40 responders' summaries scroll the first link's off the history.
    quit(&tmux, &["sim:?delay=30ms"]);
}

/// A row's words: `1/1 quadrotor px4 546 54 9.0 ...`.
fn words(row: &str) -> Vec<&str> {
    row.trim_matches('│').split_whitespace().collect()
}

#[test]
fn a_passive_run_has_a_row_per_source_with_its_seconds_at_80x24() {
    let link = "sim:?responders=2&stream=ATTITUDE@50&loss_down=10%&seed=5";
    let command = format!(
        "{} --live --passive '{link}'; echo exit=$?",
        cargo_bin("mavping").display()
    );
    let tmux = Tmux::start("passive", &command, 80, 24);
    // Both vehicles, each named by its HEARTBEAT, each having lost frames,
    // with three seconds in their strips: told once a second, not per frame.
    let screen = tmux.wait_for_screen("two sources with losses and 3 s", |s| {
        let rows = rows(s);
        rows.len() == 2
            && rows.iter().all(|r| {
                let w = words(r);
                w.len() == 12 && w[4] != "0" && w[11].chars().count() >= 3
            })
    });
    assert_eq!(assert_fits_as(&PASSIVE, &screen, 80, 24), 1);
    assert!(screen.starts_with("mavping · passive · "), "{screen}");
    assert!(screen.contains("┌ sim:?responders=2&"), "{screen}");
    let shown: Vec<(String, u64)> = rows(&screen)
        .iter()
        .map(|r| {
            let w = words(r);
            assert_eq!(w[1..3], ["quadrotor", "px4"], "{r}");
            // 51 frames a second (50 ATTITUDE and a HEARTBEAT), less 10%.
            let rate: f64 = w[9].parse().unwrap();
            assert!((38.0..=56.0).contains(&rate), "{r}");
            // Its newest ATTITUDE's age above its baseline: the sim's 2 ms
            // of jitter and whole-ms stamps.
            let age: f64 = w[10].parse().unwrap();
            assert!((0.0..=5.0).contains(&age), "{r}");
            (w[0].to_string(), w[3].parse().unwrap())
        })
        .collect();
    assert_eq!(shown[0].0, "1/1");
    assert_eq!(shown[1].0, "2/1");
    let after = quit_as(&PASSIVE, &tmux, &["sim:?responders=2&"]);
    // The summary has at least what the view showed, as the run went on.
    for (id, received) in shown {
        let row = after
            .lines()
            .find(|l| l.starts_with(&format!("{id} ")))
            .unwrap_or_else(|| panic!("no {id} in the summary:\n{after}"));
        let summary_received: u64 = row.split_whitespace().nth(3).unwrap().parse().unwrap();
        assert!(summary_received >= received, "{row}\n{after}");
    }
}

#[test]
fn live_falls_back_to_text_when_stdout_is_not_a_terminal() {
    let out = Command::new(cargo_bin("mavping"))
        .args(["--live", "-c", "3", "sim:?clock=virtual"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0));
    assert_eq!(
        String::from_utf8_lossy(&out.stderr),
        "mavping: --live needs a terminal; printing text\n"
    );
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(stdout.contains("reply from 1/1: seq=2"), "{stdout}");
    assert!(stdout.contains("mavping statistics"), "{stdout}");
}

/// A link that cannot be opened shows in the view, among those that run,
/// with the reason its error line gives (it was hidden until the view
/// closed); the run ends with exit 2 for it.
#[test]
fn a_link_that_failed_to_open_is_shown_in_the_view() {
    let missing = format!("/dev/mavping-missing-{}", std::process::id());
    let sim = "sim:?delay=5ms";
    let tmux = live(
        "unopened",
        &format!("'{sim}' serial:{missing}:57600"),
        100,
        24,
    );
    let screen = tmux.wait_for_screen("a row and the failed link", |s| {
        rows(s).len() == 1 && s.contains(": failed: cannot open serial:")
    });
    // The title gives the error; the error names the link.
    assert!(
        screen.contains(&format!(
            ": failed: cannot open serial:{missing}:57600: No such file or directory"
        )),
        "{screen}"
    );
    tmux.send_keys("q");
    let screen = tmux.wait_for("exit=", |s| s.contains("exit="));
    assert!(screen.contains("exit=2"), "{screen}");
    assert!(
        screen
            .lines()
            .any(|l| l.starts_with("--- sim:?delay=5ms") && l.ends_with("mavping statistics ---")),
        "{screen}"
    );
}

/// A vehicle heard on two links (`two_link_vehicle.py`: the second link
/// 80 ms behind the first): the view gains the pair report's section,
/// the merged stream's row over a row per link with its lag, and `q`
/// leaves it for the summaries and the pair report.
#[test]
fn a_source_on_two_links_gets_the_pair_section() {
    let ports = [
        crate::common::free_udp_port(),
        crate::common::free_udp_port(),
    ];
    let links: Vec<String> = ports
        .iter()
        .map(|p| format!("udpin:127.0.0.1:{p}"))
        .collect();
    let command = format!(
        "{} --live --passive {} {}; echo exit=$?",
        cargo_bin("mavping").display(),
        links[0],
        links[1]
    );
    let tmux = Tmux::start("pair", &command, 120, 30);
    tmux.wait_for_screen("the view", |s| s.starts_with("mavping · 2 links"));
    let tos: Vec<String> = ports.iter().map(|p| format!("127.0.0.1:{p}")).collect();
    let mut vehicle = crate::common::Peer::start(
        "two_link_vehicle.py",
        &[
            "--to",
            &tos[0],
            "--to",
            &tos[1],
            "--drop",
            "10",
            "--delay-ms",
            "20",
            "--drop",
            "20",
            "--delay-ms",
            "100",
            "--duration",
            "60",
            "--start-after",
            "0.2",
            "--seed",
            "7",
        ],
    );
    // A pair row: `│       udpin:...  frames first% only lost% p50 p99 behind │`.
    let row = |screen: &str, link: &str| -> Option<Vec<f64>> {
        let line = screen
            .lines()
            .find(|l| l.starts_with("│ ") && l.contains(link))?;
        let w = words(line);
        (w.len() == 8).then(|| w[1..].iter().map(|n| n.parse().unwrap()).collect())
    };
    let screen = tmux.wait_for_screen("the pair section with 100 frames", |s| {
        s.contains("┌ the same sources on several links · lag in ms")
            && row(s, &links[1]).is_some_and(|r| r[0] >= 100.0)
    });
    for line in screen.lines() {
        assert!(line.chars().count() <= 120, "{line:?}");
    }
    let merged = screen
        .lines()
        .find(|l| l.starts_with("│1/1") && l.contains(" merged "))
        .unwrap_or_else(|| panic!("no merged row:\n{screen}"));
    assert!(merged.contains("de-dup window"), "{merged}");
    let (fast, slow) = (
        row(&screen, &links[0]).unwrap(),
        row(&screen, &links[1]).unwrap(),
    );
    // lag p50: the first link's copies come first; the second's 80 ms later.
    assert!(fast[4] < 5.0, "{screen}");
    assert!((slow[4] - 80.0).abs() < 10.0, "{screen}");
    let after = quit_as(&PASSIVE, &tmux, &[&links[0], &links[1]]);
    assert!(
        after.contains("--- the same sources on several links"),
        "{after}"
    );
    vehicle.kill();
}
