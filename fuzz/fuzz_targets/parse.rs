//! The text parsers a user or a scraper reaches: connection strings (the
//! `sim:` query among them), durations, percentages and `mavping serve`'s
//! allow patterns matched against targets. Invariants:
//! - no panic, and an answer in bounded time (libFuzzer's -timeout);
//! - what a connection string parses to prints as a connection string
//!   that parses again, and printing that is stable (reports name links by
//!   their printed form, and `mavping serve` compares targets in it);
//!   links other than `sim:` parse back to the same value;
//! - a duration that parses is at most the limit it was parsed against,
//!   and humantime's form of it parses back to exactly it;
//! - a percentage is a ratio in 0..=1.
//!
//! Input: lines. Every line is tried as each kind of value; the first line
//! is also tried as an allow pattern against every other line as a target.
#![no_main]

use std::time::Duration;

use libfuzzer_sys::fuzz_target;
use mavping::config::Pattern;
use mavping::transport::LinkSpec;
use mavping::units::{parse_duration, parse_duration_up_to, parse_percent, MAX_DURATION};

fn link(text: &str) -> Option<LinkSpec> {
    let spec: LinkSpec = text.parse().ok()?;
    let printed = spec.to_string();
    let again: LinkSpec = printed
        .parse()
        .unwrap_or_else(|e| panic!("{text:?} printed as {printed:?}, which does not parse: {e}"));
    assert_eq!(again.to_string(), printed, "{text:?}");
    if !matches!(spec, LinkSpec::Sim(_)) {
        assert_eq!(again, spec, "{text:?}");
    }
    Some(spec)
}

fn duration(text: &str) {
    if let Ok(d) = parse_duration(text) {
        assert!(d <= MAX_DURATION, "{text:?}: {d:?}");
        let printed = humantime::format_duration(d).to_string();
        assert_eq!(parse_duration(&printed), Ok(d), "{text:?} -> {printed:?}");
    }
    let limit = Duration::from_secs(3600);
    if let Ok(d) = parse_duration_up_to(text, limit) {
        assert!(d <= limit, "{text:?}: {d:?}");
    }
}

fn percent(text: &str) {
    if let Ok(p) = parse_percent(text) {
        assert!((0.0..=1.0).contains(&p), "{text:?}: {p}");
    }
}

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let mut lines = text.lines();
    let first = lines.next().unwrap_or_default();
    let pattern = Pattern::parse(first).ok();
    for line in std::iter::once(first).chain(lines) {
        duration(line);
        percent(line);
        if let (Some(target), Some(pattern)) = (link(line), &pattern) {
            pattern.admits(&target);
        }
    }
});
