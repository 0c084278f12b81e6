//! What the exposition's tests share: a run's start, and a line to find.
#![cfg(test)]

use std::time::Duration;

use crate::engine::summary::ProbeName;
use crate::frame::SysComp;
use crate::output::StartInfo;

/// A PING run's start on `link`.
pub(super) fn test_start(link: &str) -> StartInfo {
    StartInfo {
        link: link.into(),
        probe: ProbeName::Ping,
        ours: SysComp::new(255, 190),
        interval: Duration::from_secs(1),
        timeout: Duration::from_secs(2),
        count: None,
        plan: None,
    }
}

/// Fails unless `text` has `line` as one of its lines.
pub(super) fn has(text: &str, line: &str) {
    assert!(text.lines().any(|x| x == line), "{line} not in\n{text}");
}
