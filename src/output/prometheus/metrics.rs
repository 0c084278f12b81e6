//! One link's metrics: what its sessions' events add up to, per
//! responder, radio, node and source, and the link's own state.

use std::collections::BTreeMap;
use std::io;

use super::radio_series::RadioSeries;
use super::series::{Outcome, Series, Split};
use super::sources::{self, SourceSeries};
use crate::engine::c2::C2Report;
use crate::engine::clock_offset::ClockSummary;
use crate::engine::kind::KindValue;
use crate::engine::link_node::{LinkNodeReport, LinkNodes};
use crate::engine::matcher::MatchEvent;
use crate::engine::observe::{RadioHeard, StartInfo};
use crate::engine::probe::command::CommandEvent;
use crate::engine::probe::passive::SourcesNow;
use crate::engine::probe::transfer::AttemptFigures;
use crate::engine::radio::MAX_RADIOS;
use crate::engine::summary::passive::PassiveSummary;
use crate::engine::summary::{CommandSummary, EchoSummary, ProbeName};
use crate::engine::Nanos;
use crate::frame::SysComp;
use crate::output::Reporter;
use crate::verdict::Verdict;

/// One link's metrics.
#[derive(Debug, Default)]
pub(crate) struct Metrics {
    pub(super) link: String,
    /// `None` before a session starts (an unopened link's metrics).
    pub(super) probe: Option<ProbeName>,
    pub(super) responders: BTreeMap<SysComp, Series>,
    /// Each radio heard.
    pub(super) radios: BTreeMap<SysComp, RadioSeries>,
    /// Each node heard by its LINK_NODE_STATUS.
    pub(super) link_nodes: LinkNodes,
    /// Each source's packet sequence (a passive run's figures; an echo
    /// run's responders' downlink).
    pub(super) sources: sources::Sources,
    /// Open now, and (a continuous link of `mavping serve`) how often it
    /// was reopened after breaking; `None` before a session starts.
    pub(super) state: Option<LinkState>,
    /// Requests the link put on the wire, whoever answered them: in the
    /// sessions before (a continuous link reopened)...
    pub(super) earlier_requests: u64,
    /// ...and in this one so far.
    pub(super) session_requests: u64,
    /// A download run's downloads.
    pub(super) transfer: Option<super::transfer::TransferSeries>,
    /// The C2 link report of the latest run that made one.
    pub(super) c2: Option<Box<C2Report>>,
}

#[derive(Debug, Default, Clone, Copy)]
pub(super) struct LinkState {
    pub(super) up: bool,
    pub(super) restarts: u64,
}

impl Metrics {
    /// A continuous link's metrics, named `link` before its first session
    /// (so a link that never opens still shows `mavping_link_up 0`).
    pub(crate) fn continuous(link: &str, probe: ProbeName) -> Self {
        Metrics {
            probe: Some(probe),
            ..Metrics::unopened(link)
        }
    }

    /// A run's link that could not be opened: down from the start.
    pub(crate) fn unopened(link: &str) -> Self {
        Metrics {
            link: link.to_string(),
            state: Some(LinkState::default()),
            ..Metrics::default()
        }
    }

    /// A link opened (`true`) or broke (`false`).
    pub(crate) fn set_up(&mut self, up: bool) {
        self.state.get_or_insert_default().up = up;
    }

    /// Whether a continuous link is open now.
    pub(crate) fn is_up(&self) -> bool {
        self.state.is_some_and(|s| s.up)
    }

    /// A continuous link is being reopened after it broke.
    pub(crate) fn restarted(&mut self) {
        self.state.get_or_insert_default().restarts += 1;
    }

    /// Whether the link sends requests (a passive one does not); `None`
    /// before a session starts.
    pub(super) fn sends(&self) -> bool {
        self.probe.is_some_and(|p| p != ProbeName::Passive)
    }

    /// Requests the link put on the wire, its earlier sessions' included.
    pub(super) fn requests(&self) -> u64 {
        self.earlier_requests + self.session_requests
    }

    /// Responders that answered in the link's current session.
    pub(super) fn answering(&self) -> usize {
        self.responders.values().filter(|s| s.answering).count()
    }

    /// What an event told of a responder's requests, if anything.
    fn record(&mut self, told: Option<(SysComp, Outcome)>) {
        let Some((id, outcome)) = told else {
            return;
        };
        let auto = self.probe == Some(ProbeName::Auto);
        let s = self.responders.entry(id).or_default();
        s.record(outcome);
        // PING until its clock says TIMESYNC (told with its first reply,
        // in the same report).
        if auto && matches!(outcome, Outcome::Received(_)) && s.via_timesync.is_none() {
            s.via_timesync = Some(0);
        }
    }

    #[cfg(test)]
    /// The exposition of this link alone, as `--prometheus` serves it.
    pub(crate) fn render(&self) -> String {
        super::render::render(&[self])
    }
}

/// The link's session, as its events tell it: each figure where the
/// exposition reads it.
impl Reporter for Metrics {
    fn start(&mut self, info: &StartInfo) -> io::Result<()> {
        self.link = info.link.clone();
        self.probe = Some(info.probe);
        self.set_up(true);
        // A continuous link's new session: its sequences start afresh,
        // its counters go on.
        self.sources.values_mut().for_each(SourceSeries::carry);
        self.earlier_requests += std::mem::take(&mut self.session_requests);
        for s in self.responders.values_mut() {
            s.split = Split::Live;
            s.answering = false;
        }
        Ok(())
    }

    fn matched(&mut self, e: &MatchEvent) -> io::Result<()> {
        self.record(Outcome::of_match(e));
        Ok(())
    }

    fn command(&mut self, e: &CommandEvent) -> io::Result<()> {
        self.record(Outcome::of_command(e));
        Ok(())
    }

    /// A RADIO_STATUS: its figures replace the radio's last ones.
    fn radio(&mut self, radio: &RadioHeard<'_>) -> io::Result<()> {
        let (id, kind) = (radio.id, radio.judgement.kind);
        if self.radios.len() < MAX_RADIOS || self.radios.contains_key(&id) {
            self.radios
                .entry(id)
                .or_insert_with(|| RadioSeries::new(kind))
                .record(radio.report, kind);
        }
        Ok(())
    }

    fn link_node(
        &mut self,
        id: SysComp,
        at: Nanos,
        report: &LinkNodeReport,
        _: bool,
    ) -> io::Result<()> {
        self.link_nodes.record(id, *report, at);
        Ok(())
    }

    /// A TIMESYNC responder's clock offset so far, carried from the run's
    /// start to `at` along the measured drift (none until it is measured).
    fn clock(&mut self, id: SysComp, at: Nanos, clock: &ClockSummary) -> io::Result<()> {
        let auto = self.probe == Some(ProbeName::Auto);
        if let Some(s) = self.responders.get_mut(&id) {
            // Only TIMESYNC replies give a clock.
            if auto {
                s.via_timesync = Some(1);
            }
            let drift_ns = clock.drift_ppm.unwrap_or(0.0) * 1e-6 * at as f64;
            s.clock_offset_s = Some((clock.offset_ns as f64 + drift_ns) / 1e9);
        }
        Ok(())
    }

    fn link_failed(&mut self, _: Nanos, _: &str) -> io::Result<()> {
        self.set_up(false);
        Ok(())
    }

    /// The table of sources, as told while the session goes on.
    fn sources(&mut self, now: &SourcesNow) -> io::Result<()> {
        sources::update(&mut self.sources, &now.table, false);
        sources::update_ages(&mut self.sources, now);
        Ok(())
    }

    fn progress(&mut self, _: Nanos, requests: u64) -> io::Result<()> {
        self.session_requests = requests;
        Ok(())
    }

    /// The figures known only at the end (percentiles from the HDR
    /// histogram), so a last scrape or a `/probe` has them.
    fn echo_summary(&mut self, summary: &EchoSummary, _: &Verdict) -> io::Result<()> {
        self.session_requests = summary.requests;
        for r in &summary.responders {
            let s = self.responders.entry(r.id).or_default();
            // The live figure, when there is one, is the later.
            let at_end = r.clock.as_ref().map(|c| c.offset_ns as f64 / 1e9);
            s.clock_offset_s = s.clock_offset_s.or(at_end);
            s.rtt = r.rtt.or(s.rtt);
            s.split = Split::AtEnd(r.direction);
            let timesync = r.probe.map(|p| u8::from(p == ProbeName::Timesync));
            s.via_timesync = timesync.or(s.via_timesync);
        }
        Ok(())
    }

    /// The table of sources as the session's summary has it.
    fn passive_summary(&mut self, summary: &PassiveSummary, _: &Verdict) -> io::Result<()> {
        sources::update(&mut self.sources, &summary.table, true);
        Ok(())
    }

    fn command_summary(&mut self, summary: &CommandSummary, _: &Verdict) -> io::Result<()> {
        self.session_requests = summary.commands();
        Ok(())
    }

    fn c2_report(&mut self, _: &str, report: &C2Report) -> io::Result<()> {
        self.c2 = Some(Box::new(report.clone()));
        Ok(())
    }

    /// A download as it ends.
    fn other_event(&mut self, value: &dyn KindValue) -> io::Result<()> {
        if let Some(a) = value.get::<AttemptFigures>() {
            self.transfer.get_or_insert_default().add(a);
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::super::test_support::test_start;
    use super::*;
    use crate::output::{Event, Reporter};

    #[test]
    fn counters_and_histogram_follow_the_events() {
        let mut m = Metrics::default();
        m.on_start(&test_start("udpout:\"a\\b\""));
        let r = SysComp::new(1, 1);
        let reply = |seq, rtt| MatchEvent::Reply {
            responder: r,
            seq,
            rtt,
            sent_at: 0,
            at: rtt,
            out_of_order: false,
            first_from_responder: seq == 0,
        };
        m.on_event(&reply(0, 800_000));
        m.on_event(&reply(1, 30_000_000));
        m.on_event(&MatchEvent::Lost {
            responder: r,
            seq: 2,
            sent_at: 0,
            at: 0,
        });
        m.on_event(&MatchEvent::Late {
            responder: r,
            seq: 2,
            rtt: 20_000_000_000,
            sent_at: 0,
            at: 0,
        });
        m.on_event(&MatchEvent::Duplicate {
            responder: r,
            seq: 1,
            rtt: 1,
            sent_at: 0,
            at: 0,
        });
        let text = m.render();
        let l = r#"link="udpout:\"a\\b\"",probe="ping",sysid="1",compid="1""#;
        for line in [
            format!("mavping_sent_total{{{l}}} 3"),
            format!("mavping_received_total{{{l}}} 2"),
            format!("mavping_lost_total{{{l}}} 1"),
            format!("mavping_late_total{{{l}}} 1"),
            format!("mavping_duplicate_total{{{l}}} 1"),
            format!("mavping_rtt_seconds_bucket{{{l},le=\"0.0005\"}} 0"),
            format!("mavping_rtt_seconds_bucket{{{l},le=\"0.001\"}} 1"),
            format!("mavping_rtt_seconds_bucket{{{l},le=\"0.025\"}} 1"),
            format!("mavping_rtt_seconds_bucket{{{l},le=\"0.05\"}} 2"),
            format!("mavping_rtt_seconds_bucket{{{l},le=\"+Inf\"}} 2"),
            format!("mavping_rtt_seconds_count{{{l}}} 2"),
            format!("mavping_last_rtt_seconds{{{l}}} 0.03"),
        ] {
            assert!(text.lines().any(|x| x == line), "{line} not in\n{text}");
        }
        let sum: f64 = text
            .lines()
            .find_map(|x| x.strip_prefix(&format!("mavping_rtt_seconds_sum{{{l}}} ")))
            .unwrap()
            .parse()
            .unwrap();
        assert!((sum - 0.0308).abs() < 1e-12, "{sum}");
        assert!(!text.contains("mavping_clock_offset_seconds{"));
    }

    /// A continuous link's requests go on across its sessions; who answers
    /// is its current session's.
    #[test]
    fn requests_add_up_across_sessions_and_responders_are_the_sessions() {
        let mut m = Metrics::continuous("udpout:h:1", ProbeName::Ping);
        let link = r#"link="udpout:h:1",probe="ping""#;
        let has = |m: &Metrics, line: String| {
            let text = m.render();
            assert!(text.lines().any(|x| x == line), "{line} not in\n{text}");
        };
        has(&m, format!("mavping_requests_total{{{link}}} 0"));
        has(&m, format!("mavping_responders{{{link}}} 0"));
        let _ = m.start(&test_start("udpout:h:1"));
        let _ = m.tell(&Event::Progress { at: 0, requests: 3 });
        m.on_event(&MatchEvent::Reply {
            responder: SysComp::new(1, 1),
            seq: 0,
            rtt: 1,
            sent_at: 0,
            at: 1,
            out_of_order: false,
            first_from_responder: true,
        });
        has(&m, format!("mavping_requests_total{{{link}}} 3"));
        has(&m, format!("mavping_responders{{{link}}} 1"));
        // Reopened: nobody has answered the new session yet.
        let _ = m.start(&test_start("udpout:h:1"));
        let _ = m.tell(&Event::Progress { at: 0, requests: 2 });
        has(&m, format!("mavping_requests_total{{{link}}} 5"));
        has(&m, format!("mavping_responders{{{link}}} 0"));
        // A passive link sends nothing: neither family.
        let passive = Metrics::continuous("udpin:0.0.0.0:1", ProbeName::Passive);
        assert!(!passive.render().contains("mavping_requests_total"));
    }
}
