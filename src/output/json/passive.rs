//! `--passive` as JSON: the `passive_interim` line (`-Q`, SIGQUIT) and the
//! `passive_summary` line, with every source's sequence figures (ours and
//! pymavlink's), silences and rates.

use serde::Serialize;

use super::lines::{Lines, SCHEMA_VERSION};
use super::round_trips::RoundTrips;
use super::units::seconds;
use crate::engine::age::SourceAge;
use crate::engine::answers::AnswerSummary;
use crate::engine::hint::Hint;
use crate::engine::link_node::LinkNodeSummary;
use crate::engine::radio::RadioSummary;
use crate::engine::roster::Identity;
use crate::engine::summary::passive::{
    LinkTotals, PassiveSummary, PerLink, SourceSummary, TableSummary, Untracked,
};
use crate::engine::summary::PassiveInterim;
use crate::frame::signing::SigningSummary;
use crate::frame::{ScanStats, SysComp};
use crate::transport::tlog::LogFacts;
use crate::transport::RxClock;
use crate::verdict::Verdict;

/// One source, with its identity when it sent a HEARTBEAT.
#[derive(Serialize)]
pub(super) struct Source<'a> {
    #[serde(flatten)]
    figures: &'a SourceSummary,
    identity: Option<&'a Identity>,
}

/// Every source of `table`, each with its identity if it sent a HEARTBEAT.
fn sources<'a>(table: &'a TableSummary, identities: &'a [(SysComp, Identity)]) -> Vec<Source<'a>> {
    table
        .sources
        .iter()
        .map(|r| Source {
            figures: r,
            identity: identities
                .iter()
                .find(|(id, _)| *id == r.source)
                .map(|(_, i)| i),
        })
        .collect()
}

/// `passive_interim`: every source's figures so far, as the summary gives
/// them.
#[derive(Serialize)]
pub(super) struct Interim<'a> {
    r#type: &'static str,
    t_s: f64,
    time: String,
    totals: &'a LinkTotals,
    sources: Vec<Source<'a>>,
    untracked: Untracked,
    /// Each source's age above its baseline so far.
    #[serde(skip_serializing_if = "<[_]>::is_empty")]
    age: &'a [SourceAge],
}

impl Lines {
    /// The `passive_interim` line.
    pub(super) fn passive_interim<'a>(&self, figures: &'a PassiveInterim) -> Interim<'a> {
        Interim {
            r#type: "passive_interim",
            t_s: seconds(figures.at),
            time: self.wall.rfc3339(figures.at),
            totals: &figures.table.totals,
            sources: sources(&figures.table, &figures.identities),
            untracked: figures.table.untracked,
            age: &figures.ages,
        }
    }
}

/// One MAVProxy link's table.
#[derive(Serialize)]
pub(super) struct Link<'a> {
    link: u8,
    totals: &'a LinkTotals,
    sources: Vec<Source<'a>>,
    untracked: Untracked,
}

/// A log's figures per MAVProxy link.
#[derive(Serialize)]
pub(super) struct Links<'a> {
    links: Vec<Link<'a>>,
    unlinked: &'a [SysComp],
}

impl<'a> Links<'a> {
    fn of(s: &'a PassiveSummary, per: &'a PerLink) -> Self {
        Links {
            links: per
                .links
                .iter()
                .map(|l| Link {
                    link: l.link,
                    totals: &l.table.totals,
                    sources: sources(&l.table, &s.identities),
                    untracked: l.table.untracked,
                })
                .collect(),
            unlinked: &per.unlinked,
        }
    }
}

#[derive(Serialize)]
pub(super) struct Summary<'a> {
    r#type: &'static str,
    schema_version: u32,
    link: &'a str,
    probe: &'static str,
    ours: SysComp,
    heartbeat: bool,
    duration_s: f64,
    interrupted: bool,
    link_error: Option<&'a str>,
    rx_clock: RxClock,
    frames: ScanStats,
    totals: &'a LinkTotals,
    sources: Vec<Source<'a>>,
    untracked: Untracked,
    own_frames: u64,
    radios: &'a [RadioSummary],
    link_node: &'a [LinkNodeSummary],
    signing: SigningSummary,
    #[serde(skip_serializing_if = "AnswerSummary::is_none")]
    answered: AnswerSummary,
    /// Each source's frames' age above its baseline, from their stamps.
    #[serde(skip_serializing_if = "<[_]>::is_empty")]
    age: &'a [SourceAge],
    #[serde(skip_serializing_if = "<[_]>::is_empty")]
    hints: &'a [Hint],
    /// A telemetry log's records and stamps.
    #[serde(skip_serializing_if = "Option::is_none")]
    log: Option<&'a LogFacts>,
    /// A telemetry log's figures per MAVProxy link.
    #[serde(skip_serializing_if = "Option::is_none")]
    per_link: Option<Links<'a>>,
    /// A telemetry log's requests matched to replies by their stamps.
    #[serde(skip_serializing_if = "Option::is_none")]
    round_trips: Option<RoundTrips<'a>>,
    /// A telemetry log's timeline: its windows' summary, silences, bursts.
    #[serde(skip_serializing_if = "Option::is_none")]
    flight: Option<super::flight::Summary<'a>>,
    verdict: &'a Verdict,
    exit_code: u8,
}

impl<'a> Summary<'a> {
    pub(super) fn of(
        s: &'a PassiveSummary,
        verdict: &'a Verdict,
        link: &'a str,
        lines: &Lines,
    ) -> Self {
        Summary {
            r#type: "passive_summary",
            schema_version: SCHEMA_VERSION,
            link,
            probe: "passive",
            ours: s.ours,
            heartbeat: s.heartbeat,
            duration_s: s.duration_s,
            interrupted: s.interrupted,
            link_error: s.link_error.as_deref(),
            rx_clock: s.rx_clock,
            frames: s.frames,
            totals: &s.table.totals,
            sources: sources(&s.table, &s.identities),
            untracked: s.table.untracked,
            own_frames: s.own_frames,
            radios: &s.radios,
            link_node: &s.link_node,
            signing: s.signing,
            answered: s.answered,
            age: &s.age,
            hints: &s.hints,
            log: s.log.as_ref(),
            per_link: s.per_link.as_ref().map(|p| Links::of(s, p)),
            round_trips: s
                .round_trips
                .as_ref()
                .map(|rt| RoundTrips::of(rt, s.log.as_ref())),
            flight: s.flight.as_ref().map(|f| lines.flight_summary(f)),
            verdict,
            exit_code: verdict.exit_code(),
        }
    }
}
