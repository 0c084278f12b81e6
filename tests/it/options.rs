//! Out-of-range and malformed options: one clear error line on stderr,
//! nothing on stdout, exit 2, and never a panic.

use crate::common::*;

fn rejects(args: &[&str], needle: &str) {
    let (code, out, err) = run_mavping(args);
    assert_eq!(code, 2, "{args:?}: {err}");
    assert!(out.is_empty(), "{args:?}: {out}");
    assert_eq!(err.lines().count(), 1, "{args:?}: {err}");
    assert!(err.starts_with("mavping: "), "{args:?}: {err}");
    assert!(err.contains(needle), "{args:?}: {err} (wanted {needle:?})");
    assert!(!err.contains("panicked"), "{args:?}: {err}");
}

#[test]
fn rates_counts_and_durations_out_of_range() {
    for (args, needle) in [
        (&["--rate", "0", "sim:"][..], "--rate 0"),
        (&["--rate", "-5", "sim:"], "--rate -5"),
        (&["--rate", "nan", "sim:"], "--rate NaN"),
        (&["--rate", "inf", "sim:"], "--rate inf"),
        (&["--rate", "1e-30", "sim:"], "at least one request a day"),
        (&["--rate", "fast", "sim:"], "fast"),
        (&["-c", "0", "sim:"], "--count 0"),
        (&["-c", "-1", "sim:"], "'-1'"),
        (&["-c", "1e3", "sim:"], "1e3"),
        (&["-i", "0", "sim:"], "at least 1us"),
        (&["-i", "-1", "sim:"], "'-1' is not a duration"),
        (&["-i", "1e30", "sim:"], "1e30"),
        (&["-i", "2d", "sim:"], "at most 1 day"),
        (&["-i", "nan", "sim:"], "nan"),
        (&["-w", "99999999999h", "sim:"], "at most 365 days"),
        (&["-w", "1e30s", "sim:"], "1e30s"),
        (&["-W", "0", "sim:"], "--timeout"),
        (&["-W", "2h", "sim:"], "at most 1h"),
        (&["--max-jitter", "1e30", "sim:"], "1e30"),
        (&["--max-loss", "-1", "sim:"], "-1"),
        (&["--max-loss", "nan", "sim:"], "nan"),
    ] {
        rejects(args, needle);
    }
}

#[test]
fn ids_out_of_range() {
    for (args, needle) in [
        (&["--sysid", "0", "sim:"][..], "--sysid 0"),
        (&["--sysid", "256", "sim:"], "256"),
        (&["--sysid", "-1", "sim:"], "-1"),
        (&["--compid", "0", "sim:"], "--compid 0"),
        (&["--compid", "256", "sim:"], "256"),
        (&["--expect", "1/300", "sim:"], "SYSID"),
        (
            &["--probe", "timesync", "--target", "300", "sim:"],
            "SYS/COMP",
        ),
        (&["respond", "--sysid", "0", "sim:"], "--sysid 0"),
        (&["respond", "--sysid", "-3", "sim:"], "-3"),
        (&["respond", "--compid", "999", "sim:"], "999"),
        // A radio kind mavping does not know: named, never guessed.
        (&["--radio-type", "rfd", "sim:"], "'rfd'"),
    ] {
        rejects(args, needle);
    }
}

#[test]
fn bad_sim_parameters() {
    for (link, needle) in [
        ("sim:?responders=0", "responders=0"),
        ("sim:?responders=1001", "responders=1001"),
        ("sim:?responders=-1", "responders=-1"),
        ("sim:?sysid=0", "sysid=0"),
        ("sim:?sysid=256", "sysid=256"),
        ("sim:?compid=0", "compid=0"),
        ("sim:?delay=1e30s", "delay=1e30s"),
        ("sim:?delay=-1ms", "delay=-1ms"),
        ("sim:?jitter=99999999999h", "at most 1h"),
        ("sim:?loss=nan", "loss=nan"),
        ("sim:?loss=-1", "loss=-1"),
        ("sim:?dup=101", "dup=101"),
        ("sim:?seed=-1", "seed=-1"),
        ("sim:?drift=nan", "drift=nan"),
        ("sim:?drift=1e30", "drift=1e30"),
        ("sim:?offset=1e30s", "offset=1e30s"),
        ("sim:?baud=0", "baud=0"),
        ("sim:?hold=1e30", "hold=1e30"),
        ("sim:?foo=1", "unknown key 'foo'"),
        ("sim:?loss", "not key=value"),
        ("sim:?clock=fast", "clock=fast"),
        ("sim:?outage=1e30s", "outage=1e30s"),
        ("sim:?outage=1s", "START+LENGTH"),
        ("sim:?spike=200%", "spike=200%"),
        ("sim:?spike_delay=2h", "at most 1h"),
        ("sim:?loss=5%&loss=6%", "loss= is given twice"),
    ] {
        rejects(&[link], needle);
    }
}

/// Two simulated vehicles that differ only in their ids, or in answering
/// PING, are two links (they were refused as "the same link").
#[test]
fn sim_links_that_differ_in_ids_or_ping_run_side_by_side() {
    let list = std::env::temp_dir().join(format!("mavping-sim-ids-{}.txt", std::process::id()));
    std::fs::write(
        &list,
        "sim:?sysid=7&clock=virtual\nsim:?sysid=8&clock=virtual\nsim:?ping=off&clock=virtual&loss=100%\n",
    )
    .unwrap();
    let (code, out, err) = run_mavping(&["-c", "3", "-q", "-f", list.to_str().unwrap()]);
    let _ = std::fs::remove_file(&list);
    assert_eq!(code, 1, "the one that loses everything fails: {out}{err}");
    for (name, responder) in [("sysid=7", "7/1"), ("sysid=8", "8/1")] {
        let section = out
            .split("--- ")
            .find(|s| s.contains(name))
            .unwrap_or_else(|| panic!("no summary of {name}: {out}"));
        let counts = text_counts(section, responder).unwrap_or_else(|| panic!("{section}"));
        assert_eq!((counts.received, counts.lost), (3, 0), "{section}");
    }
    let silent = out.split("--- ").find(|s| s.contains("ping=off")).unwrap();
    assert!(silent.contains("no replies"), "{silent}");
}

/// Flags from the environment take the usual spellings of yes and no.
#[test]
fn boolean_environment_variables_take_one_zero_yes_and_no() {
    for (value, on) in [
        ("1", true),
        ("yes", true),
        ("on", true),
        ("0", false),
        ("no", false),
    ] {
        let out = mavping()
            .args(["-c", "1", "-q", "sim:?clock=virtual"])
            .env("MAVPING_LIVE", value)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(0), "MAVPING_LIVE={value}: {err}");
        // Not a terminal: --live falls back to text and says so.
        assert_eq!(
            err.contains("--live needs a terminal"),
            on,
            "{value}: {err}"
        );
    }
    rejects_env("MAVPING_RECONNECT", "maybe", "maybe");
}

fn rejects_env(name: &str, value: &str, needle: &str) {
    let out = mavping()
        .args(["-c", "1", "sim:?clock=virtual"])
        .env(name, value)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{name}={value}: {err}");
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(err.contains(needle), "{err}");
}
