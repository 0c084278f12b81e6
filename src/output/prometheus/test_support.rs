//! What the exposition's tests share: a run's start, and a line to find.
#![cfg(test)]

use std::time::Duration;

use super::Metrics;
use crate::engine::clock_offset::ClockSummary;
use crate::engine::matcher::MatchEvent;
use crate::engine::observe::RadioHeard;
use crate::engine::probe::command::CommandEvent;
use crate::engine::probe::passive::SourcesNow;
use crate::engine::radio::{Judgement, RadioKind, RadioReport, RadioType};
use crate::engine::summary::passive::TableSummary;
use crate::engine::summary::{EchoSummary, ProbeName};
use crate::engine::Nanos;
use crate::frame::SysComp;
use crate::output::{Reporter, StartInfo};
use crate::verdict::Verdict;

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

/// The tests feed a link's events one kind at a time, as its session
/// tells them through [`Reporter`].
impl Metrics {
    pub(super) fn on_start(&mut self, info: &StartInfo) {
        self.start(info).expect("metrics take every start");
    }

    pub(super) fn on_event(&mut self, e: &MatchEvent) {
        self.matched(e).expect("metrics take every event");
    }

    pub(super) fn on_command(&mut self, e: &CommandEvent) {
        self.command(e).expect("metrics take every event");
    }

    /// A RADIO_STATUS from a radio judged of `kind`.
    pub(super) fn on_radio(&mut self, id: SysComp, report: RadioReport, kind: RadioKind) {
        let judgement = Judgement {
            kind,
            radio_type: RadioType::Auto,
            evidence: vec![],
        };
        let heard = RadioHeard {
            id,
            at: 0,
            report,
            judgement: &judgement,
            first: false,
            kind_changed: false,
        };
        self.radio(&heard).expect("metrics take every event");
    }

    pub(super) fn on_clock(&mut self, id: SysComp, at: Nanos, clock: &ClockSummary) {
        self.clock(id, at, clock).expect("metrics take every event");
    }

    pub(super) fn on_summary(&mut self, summary: &EchoSummary) {
        let verdict = Verdict {
            end: crate::exit::LinkEnd {
                link_failed: false,
                checks_held: true,
            },
            failures: vec![],
        };
        self.echo_summary(summary, &verdict)
            .expect("metrics take every summary");
    }

    /// The table of sources, as told while the session goes on (`ended`
    /// false) or in its summary.
    pub(super) fn on_sources(&mut self, table: &TableSummary, ended: bool) {
        if ended {
            super::sources::update(&mut self.sources, table, true);
        } else {
            let now = SourcesNow {
                at: 0,
                table: table.clone(),
                ages: Vec::new(),
                age_counts: Vec::new(),
                age_max: Vec::new(),
            };
            self.sources(&now).expect("metrics take every event");
        }
    }
}
