//! Thresholds: pure judgement of a finished link. The code it leads to
//! comes from [`crate::exit`], the one exit policy.

use std::fmt;
use std::time::Duration;

use serde::Serialize;
use thiserror::Error;

use crate::engine::age::SourceAge;
use crate::engine::c2::C2Report;
use crate::engine::probe::transfer::TransferSummary;
use crate::engine::stats::RttSummary;
use crate::engine::summary::passive::PassiveSummary;
use crate::engine::summary::{CommandSummary, EchoSummary, LinkSummary, ResponderSummary};
use crate::exit::{self, LinkEnd};
use crate::frame::SysComp;

/// Which RTT figure a `--max-rtt` limit applies to.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum RttFigure {
    Mean,
    Max,
    P50,
    P90,
    P99,
    P999,
}

impl RttFigure {
    pub(crate) const NAMES: &'static str = "p50, p90, p99, p99.9, mean, max";

    fn of(self, rtt: &RttSummary) -> f64 {
        match self {
            RttFigure::Mean => rtt.mean_us,
            RttFigure::Max => rtt.max_us,
            RttFigure::P50 => rtt.p50_us,
            RttFigure::P90 => rtt.p90_us,
            RttFigure::P99 => rtt.p99_us,
            RttFigure::P999 => rtt.p999_us,
        }
    }
}

/// Not one of [`RttFigure::NAMES`]; the text given is quoted.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
#[error("'{0}' is not an RTT figure; use one of {names}", names = RttFigure::NAMES)]
pub(crate) struct UnknownRttFigure(String);

impl std::str::FromStr for RttFigure {
    type Err = UnknownRttFigure;
    fn from_str(s: &str) -> Result<Self, UnknownRttFigure> {
        match s {
            "mean" => Ok(RttFigure::Mean),
            "max" => Ok(RttFigure::Max),
            "p50" => Ok(RttFigure::P50),
            "p90" => Ok(RttFigure::P90),
            "p99" => Ok(RttFigure::P99),
            "p99.9" | "p999" => Ok(RttFigure::P999),
            _ => Err(UnknownRttFigure(s.to_string())),
        }
    }
}

impl fmt::Display for RttFigure {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            RttFigure::Mean => "mean",
            RttFigure::Max => "max",
            RttFigure::P50 => "p50",
            RttFigure::P90 => "p90",
            RttFigure::P99 => "p99",
            RttFigure::P999 => "p99.9",
        })
    }
}

/// `--max-rtt [FIGURE=]DURATION`
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct RttLimit {
    pub(crate) figure: RttFigure,
    pub(crate) limit: Duration,
}

/// `--expect SYSID[/COMPID]`
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Expected {
    pub(crate) sysid: u8,
    pub(crate) compid: Option<u8>,
}

impl Expected {
    fn matches(&self, id: SysComp) -> bool {
        id.sysid == self.sysid && self.compid.is_none_or(|c| c == id.compid)
    }
}

impl fmt::Display for Expected {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.compid {
            Some(c) => write!(f, "{}/{c}", self.sysid),
            None => write!(f, "{}", self.sysid),
        }
    }
}

#[derive(Debug, Clone, Default, PartialEq)]
pub(crate) struct Thresholds {
    /// Largest allowed loss ratio (0..=1) per responder.
    pub(crate) max_loss: Option<f64>,
    pub(crate) max_rtt: Vec<RttLimit>,
    pub(crate) max_jitter: Option<Duration>,
    /// Largest allowed p99 age above the baseline of a source's frames
    /// (`--max-age`).
    pub(crate) max_age: Option<Duration>,
    /// Longest allowed time for a download to complete
    /// (`--max-transfer-time`).
    pub(crate) max_transfer_time: Option<Duration>,
    /// Least allowed C2 availability and continuity, % (`--min-availability`,
    /// `--min-continuity`).
    pub(crate) min_availability: Option<f64>,
    pub(crate) min_continuity: Option<f64>,
    pub(crate) expect: Vec<Expected>,
    pub(crate) min_responders: Option<usize>,
}

/// What a run was judged by: an option (`--max-loss`, ...) or what every
/// run needs (a reply, an acknowledgement). Reports show it as the option's
/// name (`max-loss`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub(crate) enum Check {
    /// Something answered at all.
    Reply,
    /// A command was acknowledged.
    Ack,
    /// A passive run heard some source.
    Heard,
    MaxLoss,
    MaxRtt,
    MaxJitter,
    MaxAge,
    Expect,
    MinResponders,
    /// Every download completed.
    Transfer,
    MaxTransferTime,
    MinAvailability,
    MinContinuity,
}

impl Check {
    pub(crate) fn as_str(self) -> &'static str {
        match self {
            Check::Reply => "reply",
            Check::Ack => "ack",
            Check::Heard => "heard",
            Check::MaxLoss => "max-loss",
            Check::MaxRtt => "max-rtt",
            Check::MaxJitter => "max-jitter",
            Check::MaxAge => "max-age",
            Check::Expect => "expect",
            Check::MinResponders => "min-responders",
            Check::Transfer => "transfer",
            Check::MaxTransferTime => "max-transfer-time",
            Check::MinAvailability => "min-availability",
            Check::MinContinuity => "min-continuity",
        }
    }
}

impl fmt::Display for Check {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

#[derive(Debug, Clone, PartialEq, Serialize)]
pub(crate) struct Failure {
    /// The responder it concerns, when it concerns one.
    pub(crate) responder: Option<SysComp>,
    /// The check that was broken.
    pub(crate) check: Check,
    pub(crate) message: String,
}

/// A link's judgement: how it ended, for the exit policy, and the checks
/// that failed. Reports show the code the policy gives it
/// (`{"ok", "exit_code", "failures"}` in JSON).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Verdict {
    pub(crate) end: LinkEnd,
    pub(crate) failures: Vec<Failure>,
}

impl Verdict {
    /// The link's own exit code.
    pub(crate) fn exit_code(&self) -> u8 {
        exit::of_link(self.end)
    }

    pub(crate) fn ok(&self) -> bool {
        self.exit_code() == exit::OK
    }
}

impl Serialize for Verdict {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeStruct;
        let mut s = serializer.serialize_struct("Verdict", 3)?;
        s.serialize_field("ok", &self.ok())?;
        s.serialize_field("exit_code", &self.exit_code())?;
        s.serialize_field("failures", &self.failures)?;
        s.end()
    }
}

fn ms(us: f64) -> String {
    format!("{:.3} ms", us / 1e3)
}

fn judge_responder(r: &ResponderSummary, t: &Thresholds, out: &mut Vec<Failure>) {
    let mut fail = |check, message: String| {
        out.push(Failure {
            responder: Some(r.id),
            check,
            message: format!("{}: {message}", r.id),
        })
    };
    if let Some(max) = t.max_loss {
        if r.loss_ratio > max {
            fail(
                Check::MaxLoss,
                format!(
                    "loss {:.2}% is above --max-loss {:.2}%",
                    r.loss_ratio * 100.0,
                    max * 100.0
                ),
            );
        }
    }
    let Some(rtt) = &r.rtt else {
        return;
    };
    for limit in &t.max_rtt {
        let value = limit.figure.of(rtt);
        let max_us = limit.limit.as_secs_f64() * 1e6;
        if value > max_us {
            fail(
                Check::MaxRtt,
                format!(
                    "rtt {} {} is above --max-rtt {}={}",
                    limit.figure,
                    ms(value),
                    limit.figure,
                    ms(max_us)
                ),
            );
        }
    }
    if let Some(max) = t.max_jitter {
        let max_us = max.as_secs_f64() * 1e6;
        if rtt.jitter_us > max_us {
            fail(
                Check::MaxJitter,
                format!(
                    "jitter {} is above --max-jitter {}",
                    ms(rtt.jitter_us),
                    ms(max_us)
                ),
            );
        }
    }
}

/// Whom `--expect` and `--min-responders` count: responders that answered
/// a probe, or sources a passive run heard.
#[derive(Clone, Copy)]
enum Who {
    Responders,
    Sources,
}

/// `--expect` and `--min-responders` over the ids that answered (or were
/// heard).
fn judge_who(ids: &[SysComp], t: &Thresholds, who: Who, out: &mut Vec<Failure>) {
    for e in &t.expect {
        if !ids.iter().any(|&id| e.matches(id)) {
            out.push(Failure {
                responder: e.compid.map(|c| SysComp::new(e.sysid, c)),
                check: Check::Expect,
                message: match who {
                    Who::Responders => format!("expected responder {e} did not answer"),
                    Who::Sources => format!("expected source {e} was not heard"),
                },
            });
        }
    }
    if let Some(min) = t.min_responders.filter(|&min| ids.len() < min) {
        out.push(Failure {
            responder: None,
            check: Check::MinResponders,
            message: match who {
                Who::Responders => {
                    format!(
                        "{} responders answered, --min-responders is {min}",
                        ids.len()
                    )
                }
                Who::Sources => format!("{} sources heard, --min-responders is {min}", ids.len()),
            },
        });
    }
}

/// Judges a finished run. A link failure is exit 2 whatever else held.
pub(crate) fn judge(summary: &EchoSummary, t: &Thresholds) -> Verdict {
    let mut failures = Vec::new();
    let answering: Vec<&ResponderSummary> = summary
        .responders
        .iter()
        .filter(|r| r.counts.received > 0)
        .collect();
    if !summary.any_reply() {
        failures.push(Failure {
            responder: None,
            check: Check::Reply,
            message: "no reply at all".into(),
        });
    }
    for r in &answering {
        judge_responder(r, t, &mut failures);
    }
    judge_ages(&summary.age, t, &mut failures);
    let ids: Vec<SysComp> = answering.iter().map(|r| r.id).collect();
    judge_who(&ids, t, Who::Responders, &mut failures);
    verdict(summary.link_error.is_some(), failures)
}

/// Judges a command run: something must have been acknowledged.
pub(crate) fn judge_command(summary: &CommandSummary) -> Verdict {
    let mut failures = Vec::new();
    if !summary.any_ack() {
        failures.push(Failure {
            responder: None,
            check: Check::Ack,
            message: "no command acknowledged".into(),
        });
    }
    verdict(summary.link_error.is_some(), failures)
}

/// Judges a download run: every download must complete, each within
/// `--max-transfer-time` when given.
pub(crate) fn judge_transfer(summary: &TransferSummary, t: &Thresholds) -> Verdict {
    let mut failures = Vec::new();
    if summary.attempts == 0 || summary.failed() > 0 {
        let why = summary
            .first_failed
            .as_ref()
            .or(summary.last.as_ref())
            .map(|a| match &a.reason {
                Some(reason) => format!(" ({reason})"),
                None => String::new(),
            })
            .unwrap_or_default();
        failures.push(Failure {
            responder: summary.last.as_ref().and_then(|a| a.responder),
            check: Check::Transfer,
            message: format!(
                "{} of {} downloads did not complete{why}",
                summary.failed(),
                summary.attempts
            ),
        });
    }
    let slowest = summary.time_to_complete.map(|t| t.max_ms);
    if let (Some(max), Some(slowest)) = (t.max_transfer_time, slowest) {
        if slowest > max.as_secs_f64() * 1e3 {
            failures.push(Failure {
                responder: summary.last.as_ref().and_then(|a| a.responder),
                check: Check::MaxTransferTime,
                message: format!(
                    "the slowest download took {slowest:.0} ms, above --max-transfer-time {}",
                    humantime::format_duration(max)
                ),
            });
        }
    }
    verdict(summary.link_error.is_some(), failures)
}

/// Judges a passive run: some source must have been heard, and
/// `--max-loss`, `--expect` and `--min-responders` hold for the sources'
/// sequence loss (the radio's own frames aside).
pub(crate) fn judge_passive(summary: &PassiveSummary, t: &Thresholds) -> Verdict {
    let mut failures = Vec::new();
    let heard: Vec<_> = summary.heard().collect();
    if heard.is_empty() {
        failures.push(Failure {
            responder: None,
            check: Check::Heard,
            message: "nothing heard".into(),
        });
    }
    if let Some(max) = t.max_loss {
        for s in &heard {
            let loss = s.loss_pct.unwrap_or(0.0) / 100.0;
            if loss > max {
                failures.push(Failure {
                    responder: Some(s.source),
                    check: Check::MaxLoss,
                    message: format!(
                        "{}: sequence loss {:.2}% is above --max-loss {:.2}%",
                        s.source,
                        loss * 100.0,
                        max * 100.0
                    ),
                });
            }
        }
    }
    judge_ages(&summary.age, t, &mut failures);
    let ids: Vec<SysComp> = heard.iter().map(|s| s.source).collect();
    judge_who(&ids, t, Who::Sources, &mut failures);
    verdict(summary.link_error.is_some(), failures)
}

/// `--max-age`: each source's p99 age above its baseline, on its headline
/// clock, against the limit.
fn judge_ages(ages: &[SourceAge], t: &Thresholds, failures: &mut Vec<Failure>) {
    let Some(max) = t.max_age else {
        return;
    };
    let limit_ms = max.as_secs_f64() * 1e3;
    let judged = ages.iter().filter(|a| a.headline.clock.keeps_time());
    for a in judged.filter(|a| a.headline.p99_ms > limit_ms) {
        failures.push(Failure {
            responder: Some(a.source),
            check: Check::MaxAge,
            message: format!(
                "{}: p99 age above baseline {:.1} ms is above --max-age {}",
                a.source,
                a.headline.p99_ms,
                humantime::format_duration(max)
            ),
        });
    }
}

/// Judges any link's run; thresholds apply to echo probes and passive runs.
pub(crate) fn judge_link(summary: &LinkSummary, t: &Thresholds) -> Verdict {
    let mut verdict = judge_kind(summary, t);
    if let Some(report) = summary.c2() {
        verdict.failures.extend(judge_c2(report, t));
        verdict.end.checks_held = verdict.failures.is_empty();
    }
    verdict
}

/// `--min-availability` and `--min-continuity` against the C2 report: a
/// figure the run could not measure fails its check.
fn judge_c2(report: &C2Report, t: &Thresholds) -> Vec<Failure> {
    let mut failures = Vec::new();
    if let Some(min) = t.min_availability {
        let message = match report.availability_pct {
            None => Some("no availability: the vehicle was never heard".to_string()),
            Some(a) if a < min => Some(format!(
                "availability {a:.3}% is under --min-availability {min}% ({:.1} s down of {:.1} s)",
                report.down_s, report.duration_s
            )),
            Some(_) => None,
        };
        failures.extend(message.map(|message| Failure {
            responder: None,
            check: Check::MinAvailability,
            message,
        }));
    }
    if let Some(min) = t.min_continuity {
        let message = match &report.continuity {
            None => Some("no continuity: no round trip was decided".to_string()),
            Some(c) if c.pct < min => Some(format!(
                "continuity {:.3}% ({} of {} round trips within {} s) is under --min-continuity {min}%",
                c.pct, c.within, c.transactions, report.rule.continuity_within_s
            )),
            Some(_) => None,
        };
        failures.extend(message.map(|message| Failure {
            responder: None,
            check: Check::MinContinuity,
            message,
        }));
    }
    failures
}

fn judge_kind(summary: &LinkSummary, t: &Thresholds) -> Verdict {
    if let Some(s) = summary.get::<EchoSummary>() {
        judge(s, t)
    } else if let Some(s) = summary.get::<CommandSummary>() {
        judge_command(s)
    } else if let Some(s) = summary.get::<PassiveSummary>() {
        judge_passive(s, t)
    } else if let Some(s) = summary.get::<TransferSummary>() {
        judge_transfer(s, t)
    } else {
        // A kind with no judge here cannot pass: nothing checked it.
        verdict(true, Vec::new())
    }
}

fn verdict(link_failed: bool, failures: Vec<Failure>) -> Verdict {
    Verdict {
        end: LinkEnd {
            link_failed,
            checks_held: failures.is_empty(),
        },
        failures,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::engine::matcher::Counts;

    fn responder(
        sysid: u8,
        received: u64,
        lost: u64,
        p99_us: f64,
        jitter_us: f64,
    ) -> ResponderSummary {
        let sent = received + lost;
        ResponderSummary {
            id: SysComp::new(sysid, 1),
            counts: Counts {
                sent,
                received,
                lost,
                ..Counts::default()
            },
            loss_ratio: lost as f64 / sent.max(1) as f64,
            rtt: (received > 0).then_some(RttSummary {
                min_us: 1.0,
                mean_us: p99_us / 2.0,
                max_us: p99_us * 2.0,
                stddev_us: 1.0,
                p50_us: p99_us / 2.0,
                p90_us: p99_us / 1.5,
                p99_us,
                p999_us: p99_us,
                jitter_us,
            }),
            histogram: vec![],
            identity: None,
            probe: None,
            clock: None,
            direction: None,
            split: None,
        }
    }

    fn summary(responders: Vec<ResponderSummary>) -> EchoSummary {
        EchoSummary {
            responders,
            ..EchoSummary::empty("sim:", 10)
        }
    }

    fn checks(v: &Verdict) -> Vec<Check> {
        v.failures.iter().map(|f| f.check).collect()
    }

    #[test]
    fn each_threshold_fails_alone() {
        let s = summary(vec![responder(1, 90, 10, 40_000.0, 3_000.0)]);
        let ok = judge(&s, &Thresholds::default());
        assert_eq!((ok.ok(), ok.exit_code()), (true, 0));
        let table: Vec<(Thresholds, Check)> = vec![
            (
                Thresholds {
                    max_loss: Some(0.05),
                    ..Default::default()
                },
                Check::MaxLoss,
            ),
            (
                Thresholds {
                    max_rtt: vec![RttLimit {
                        figure: RttFigure::P99,
                        limit: Duration::from_millis(30),
                    }],
                    ..Default::default()
                },
                Check::MaxRtt,
            ),
            (
                Thresholds {
                    max_jitter: Some(Duration::from_millis(2)),
                    ..Default::default()
                },
                Check::MaxJitter,
            ),
            (
                Thresholds {
                    expect: vec![Expected {
                        sysid: 2,
                        compid: None,
                    }],
                    ..Default::default()
                },
                Check::Expect,
            ),
            (
                Thresholds {
                    min_responders: Some(2),
                    ..Default::default()
                },
                Check::MinResponders,
            ),
        ];
        for (t, check) in table {
            let v = judge(&s, &t);
            assert_eq!(checks(&v), vec![check]);
            assert_eq!(v.exit_code(), exit::FAILED);
        }
        // The same limits, loose enough, hold.
        let loose = Thresholds {
            max_loss: Some(0.10),
            max_rtt: vec![RttLimit {
                figure: RttFigure::P99,
                limit: Duration::from_millis(40),
            }],
            max_jitter: Some(Duration::from_millis(3)),
            max_age: None,
            max_transfer_time: None,
            min_availability: None,
            min_continuity: None,
            expect: vec![Expected {
                sysid: 1,
                compid: Some(1),
            }],
            min_responders: Some(1),
        };
        assert!(judge(&s, &loose).ok());
    }

    #[test]
    fn checks_are_named_as_their_options() {
        for check in [
            Check::Reply,
            Check::Ack,
            Check::MaxLoss,
            Check::MaxRtt,
            Check::MaxJitter,
            Check::Expect,
            Check::MinResponders,
        ] {
            let serialised = serde_json::to_value(check).unwrap();
            assert_eq!(serialised, check.as_str(), "{check:?}");
            assert_eq!(check.to_string(), check.as_str());
        }
        assert_eq!(Check::MinResponders.as_str(), "min-responders");
    }

    #[test]
    fn no_reply_fails_and_link_error_is_exit_2() {
        let mut s = summary(vec![]);
        assert_eq!(
            checks(&judge(&s, &Thresholds::default())),
            vec![Check::Reply]
        );
        s.responders.push(responder(1, 5, 0, 1.0, 0.0));
        s.link_error = Some("gone".into());
        assert_eq!(judge(&s, &Thresholds::default()).exit_code(), exit::ERROR);
    }

    #[test]
    fn failures_name_the_responder() {
        let s = summary(vec![
            responder(1, 10, 0, 1.0, 0.0),
            responder(7, 5, 5, 1.0, 0.0),
        ]);
        let v = judge(
            &s,
            &Thresholds {
                max_loss: Some(0.1),
                ..Default::default()
            },
        );
        assert_eq!(v.failures.len(), 1);
        assert_eq!(v.failures[0].responder, Some(SysComp::new(7, 1)));
        assert!(
            v.failures[0].message.starts_with("7/1: loss 50.00%"),
            "{}",
            v.failures[0].message
        );
    }

    #[test]
    fn a_passive_run_is_judged_on_the_sources_heard_and_their_sequence_loss() {
        use crate::engine::probe::passive::tracker::{SourceTable, RADIO_SOURCE};
        use crate::engine::summary::passive::PassiveSummary;
        let mut table = SourceTable::new(None, 8);
        // 1/1 loses 1 frame in 10; the radio is no source.
        for (k, seq) in [0u8, 1, 2, 3, 4, 6, 7, 8, 9, 10].into_iter().enumerate() {
            table.on_frame(SysComp::new(1, 1), seq, 0, 21, k as u64 * 10_000_000);
        }
        table.on_frame(RADIO_SOURCE, 0, 109, 38, 0);
        let passive = |table: &SourceTable| PassiveSummary {
            link: "sim:".into(),
            ours: SysComp::new(250, 190),
            heartbeat: true,
            duration_s: 1.0,
            table: table.summary(100_000_000),
            identities: Vec::new(),
            own_frames: 0,
            radios: Vec::new(),
            frames: crate::frame::ScanStats::default(),
            rx_clock: crate::transport::RxClock::UserSpace,
            interrupted: false,
            link_error: None,
            signing: crate::frame::signing::Gate::new(None).summary(),
            answered: crate::engine::answers::AnswerSummary::default(),
            age: Vec::new(),
            hints: Vec::new(),
            link_node: vec![],
            log: None,
            per_link: None,
            round_trips: None,
            flight: None,
        };
        let s = passive(&table);
        assert!(judge_passive(&s, &Thresholds::default()).ok());
        let strict = Thresholds {
            max_loss: Some(0.05),
            expect: vec![Expected {
                sysid: 2,
                compid: None,
            }],
            min_responders: Some(2),
            ..Thresholds::default()
        };
        let v = judge_passive(&s, &strict);
        let checks: Vec<Check> = v.failures.iter().map(|f| f.check).collect();
        assert_eq!(
            checks,
            [Check::MaxLoss, Check::Expect, Check::MinResponders]
        );
        assert_eq!(v.failures[1].message, "expected source 2 was not heard");
        assert_eq!(
            v.failures[2].message,
            "1 sources heard, --min-responders is 2"
        );
        assert_eq!(v.exit_code(), exit::FAILED);
        // Only the radio heard: nothing heard.
        let mut radio_only = SourceTable::new(None, 8);
        radio_only.on_frame(RADIO_SOURCE, 0, 109, 38, 0);
        let v = judge_passive(&passive(&radio_only), &Thresholds::default());
        assert_eq!(v.failures[0].check, Check::Heard);
        assert_eq!(v.exit_code(), exit::FAILED);
    }
}
