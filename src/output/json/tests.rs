//! One of every kind of line the JSON reporter writes, made of what runs
//! of every kind tell it: each line is checked against the published
//! schema, and all of them, as written through the reporter's `Observer`
//! and `Reporter` interface, are pinned byte for byte by a snapshot.

use std::collections::BTreeSet;
use std::time::SystemTime;

use serde_json::Value;

use super::lines::{Line, Lines};
use super::JsonReporter;
use crate::engine::matcher::MatchEvent;
use crate::engine::probe::command::CommandEvent;
use crate::engine::probe::passive::flight::FlightEvent;
use crate::engine::summary::passive::PassiveSummary;
use crate::engine::summary::{CommandSummary, EchoSummary, LinkSummary};
use crate::engine::sweep_report::StepFigures;
use crate::output::runs::*;
use crate::output::{Event, Reporter, WallClock};
use crate::verdict::Verdict;

impl Lines {
    /// The summary line the reporter writes.
    fn summary<'a>(&'a self, summary: &'a LinkSummary, verdict: &'a Verdict) -> Line<'a> {
        if let Some(s) = summary.get::<EchoSummary>() {
            Line::Summary(Box::new(super::echo::Summary::of(
                s,
                verdict,
                self.link_or(&s.link),
            )))
        } else if let Some(s) = summary.get::<CommandSummary>() {
            Line::CommandSummary(Box::new(super::command::Summary::of(
                s,
                verdict,
                self.link_or(&s.link),
            )))
        } else {
            let s = summary
                .get::<PassiveSummary>()
                .expect("a summary of a known kind");
            Line::PassiveSummary(Box::new(super::passive::Summary::of(
                s,
                verdict,
                self.link_or(&s.link),
                self,
            )))
        }
    }

    /// The line the reporter writes for `event`, if any (the reporter's
    /// own path is pinned by the snapshot of every line).
    fn event<'a>(&self, event: &Event<'a>) -> Option<Line<'a>> {
        if let Some(e) = event.kind::<MatchEvent>() {
            return Some(self.match_line(e));
        } else if let Some(e) = event.kind::<CommandEvent>() {
            return super::command::line(e);
        } else if let Some(step) = event.kind::<StepFigures>() {
            return Some(Line::Step(self.step(step)));
        } else if let Some(e) = event.kind::<FlightEvent>() {
            return Some(self.flight_event(e));
        }
        match *event {
            Event::Heard { id, identity } => Some(self.heard_line(id, identity)),
            Event::Radio(ref radio) => self.radio_line(radio),
            Event::WaitingForPeer => Some(Self::waiting_line()),
            _ => None,
        }
    }
}

fn reporter(quiet: bool, link: Option<&str>) -> JsonReporter<Vec<u8>> {
    JsonReporter::new(
        Vec::new(),
        quiet,
        WallClock {
            start: SystemTime::UNIX_EPOCH,
        },
    )
    .with_link(link.map(String::from))
}

/// Tells `out` as a run would.
fn tell(out: &mut JsonReporter<Vec<u8>>, told: &Told<'_>) {
    match told {
        Told::Start(info) => out.start(info),
        Told::Event(event) => out.tell(event),
        Told::Interim(figures) => out.interim(figures),
        Told::Summary(summary, verdict) => out.summary(summary, verdict),
    }
    .unwrap()
}

/// Every run kind, quiet and not, alone and as one of several links.
fn every_line() -> String {
    let borrowed = Borrowed::new();
    let mut text = String::new();
    for (quiet, link) in [(false, None), (false, Some("the link")), (true, None)] {
        for run in RUNS {
            let mut out = reporter(quiet, link);
            for told in run.told(&borrowed) {
                tell(&mut out, &told);
            }
            text.push_str(&String::from_utf8(out.out).unwrap());
        }
    }
    text
}

fn schema() -> (jsonschema::Validator, Value) {
    let text = include_str!("../../../schema/mavping-events.schema.json");
    let schema: Value = serde_json::from_str(text).unwrap();
    (jsonschema::validator_for(&schema).unwrap(), schema)
}

fn assert_valid(validator: &jsonschema::Validator, line: &Value) {
    let errors: Vec<String> = validator.iter_errors(line).map(|e| e.to_string()).collect();
    assert!(errors.is_empty(), "{line}\n{errors:#?}");
}

/// The `type`s the schema's `oneOf` tells apart.
fn schema_types(schema: &Value) -> BTreeSet<String> {
    let mut types = BTreeSet::new();
    for choice in schema["oneOf"].as_array().unwrap() {
        let name = choice["$ref"].as_str().unwrap();
        let def = &schema["$defs"][name.strip_prefix("#/$defs/").unwrap()];
        let r#type = &def["properties"]["type"];
        match (&r#type["const"], &r#type["enum"]) {
            (Value::String(one), _) => {
                types.insert(one.clone());
            }
            (_, Value::Array(some)) => types.extend(
                some.iter()
                    .map(|t| t.as_str().expect("a type is a string").to_string()),
            ),
            _ => panic!("{name} names no type: {def}"),
        }
    }
    types
}

/// Which kinds of line were written. `record` has no wildcard and
/// `missing` reads every field: a new kind of [`Line`] does not compile
/// until it has a field here, and fails the test until a run writes one.
#[derive(Default)]
struct Seen {
    start: bool,
    waiting: bool,
    responder: bool,
    reply: bool,
    lost: bool,
    late: bool,
    duplicate: bool,
    stale: bool,
    radio: bool,
    interim: bool,
    passive_interim: bool,
    step: bool,
    summary: bool,
    ack: bool,
    command_failed: bool,
    skipped: bool,
    late_ack: bool,
    duplicate_ack: bool,
    command_summary: bool,
    passive_summary: bool,
    flight_window: bool,
    flight_silence: bool,
    flight_burst: bool,
}

impl Seen {
    /// Notes a line; returns the `type` it must have.
    fn record(&mut self, line: &Line<'_>) -> &'static str {
        let (seen, r#type) = match line {
            Line::Start(_) => (&mut self.start, "start"),
            Line::Waiting(_) => (&mut self.waiting, "waiting"),
            Line::Responder(_) => (&mut self.responder, "responder"),
            Line::Reply(_) => (&mut self.reply, "reply"),
            Line::Lost(_) => (&mut self.lost, "lost"),
            Line::Late(_) => (&mut self.late, "late"),
            Line::Duplicate(_) => (&mut self.duplicate, "duplicate"),
            Line::Stale(_) => (&mut self.stale, "stale"),
            Line::Radio(_) => (&mut self.radio, "radio"),
            Line::Interim(_) => (&mut self.interim, "interim"),
            Line::PassiveInterim(_) => (&mut self.passive_interim, "passive_interim"),
            Line::Step(_) => (&mut self.step, "step"),
            Line::Summary(_) => (&mut self.summary, "summary"),
            Line::Ack(_) => (&mut self.ack, "ack"),
            Line::CommandFailed(_) => (&mut self.command_failed, "command_failed"),
            Line::Skipped(_) => (&mut self.skipped, "skipped"),
            Line::LateAck(_) => (&mut self.late_ack, "late_ack"),
            Line::DuplicateAck(_) => (&mut self.duplicate_ack, "duplicate_ack"),
            Line::CommandSummary(_) => (&mut self.command_summary, "command_summary"),
            Line::PassiveSummary(_) => (&mut self.passive_summary, "passive_summary"),
            Line::FlightWindow(_) => (&mut self.flight_window, "flight_window"),
            Line::FlightSilence(_) => (&mut self.flight_silence, "flight_silence"),
            Line::FlightBurst(_) => (&mut self.flight_burst, "flight_burst"),
        };
        *seen = true;
        r#type
    }

    /// The kinds no run wrote.
    fn missing(&self) -> Vec<&'static str> {
        let Seen {
            start,
            waiting,
            responder,
            reply,
            lost,
            late,
            duplicate,
            stale,
            radio,
            interim,
            passive_interim,
            step,
            summary,
            ack,
            command_failed,
            skipped,
            late_ack,
            duplicate_ack,
            command_summary,
            passive_summary,
            flight_window,
            flight_silence,
            flight_burst,
        } = *self;
        [
            (start, "start"),
            (waiting, "waiting"),
            (responder, "responder"),
            (reply, "reply"),
            (lost, "lost"),
            (late, "late"),
            (duplicate, "duplicate"),
            (stale, "stale"),
            (radio, "radio"),
            (interim, "interim"),
            (passive_interim, "passive_interim"),
            (step, "step"),
            (summary, "summary"),
            (ack, "ack"),
            (command_failed, "command_failed"),
            (skipped, "skipped"),
            (late_ack, "late_ack"),
            (duplicate_ack, "duplicate_ack"),
            (command_summary, "command_summary"),
            (passive_summary, "passive_summary"),
            (flight_window, "flight_window"),
            (flight_silence, "flight_silence"),
            (flight_burst, "flight_burst"),
        ]
        .into_iter()
        .filter(|&(seen, _)| !seen)
        .map(|(_, r#type)| r#type)
        .collect()
    }
}

/// Every kind of [`Line`] the reporter makes of the runs, alone and as one
/// of several links: each is written with the `type` its kind says, the
/// schema accepts it, and the schema tells apart no kind the reporter
/// cannot write.
#[test]
fn the_schema_accepts_every_kind_of_line() {
    let (validator, schema) = schema();
    let borrowed = Borrowed::new();
    let mut seen = Seen::default();
    let mut written = BTreeSet::new();
    for link in [None, Some("the link")] {
        for run in RUNS {
            let mut lines = reporter(false, link).lines;
            for told in run.told(&borrowed) {
                let line = match &told {
                    Told::Start(info) => {
                        lines.starts(info);
                        Some(lines.start(info))
                    }
                    Told::Event(event) => lines.event(event),
                    Told::Interim(figures) => lines.interim(figures),
                    Told::Summary(summary, verdict) => Some(lines.summary(summary, verdict)),
                };
                let Some(line) = line else { continue };
                let r#type = seen.record(&line);
                let mut bytes = Vec::new();
                lines.write(&mut bytes, &line).unwrap();
                let value: Value = serde_json::from_slice(&bytes).unwrap();
                assert_eq!(value["type"], r#type, "{value}");
                if let Some(link) = link {
                    assert_eq!(value["link"], link, "{value}");
                }
                assert_valid(&validator, &value);
                written.insert(r#type.to_string());
            }
        }
    }
    assert_eq!(seen.missing(), Vec::<&str>::new(), "no run wrote these");
    assert_eq!(schema_types(&schema), written);
}

/// What the runs write through the reporter's `Observer` and `Reporter`
/// interface, quiet or not, the schema accepts.
#[test]
fn the_schema_accepts_what_runs_write() {
    let (validator, _) = schema();
    for line in every_line().lines() {
        assert_valid(&validator, &serde_json::from_str(line).unwrap());
    }
}

#[test]
fn every_line_byte_for_byte() {
    insta::assert_snapshot!(every_line());
}
