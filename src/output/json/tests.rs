//! One of every kind of line the JSON reporter writes, made of what runs
//! of every kind tell it: each line is checked against the published
//! schema, and all of them, as written through the reporter's `Observer`
//! and `Reporter` interface, are pinned byte for byte by a snapshot.

use std::collections::BTreeSet;
use std::time::SystemTime;

use serde_json::Value;

use super::JsonReporter;
use crate::output::runs::*;
use crate::output::{Reporter, WallClock};

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

/// Every kind of line the reporter writes of the runs, alone and as one
/// of several links: the schema accepts each, each names the link it was
/// given, and the `type`s written are exactly those the schema tells
/// apart (one the code writes and the schema lacks fails as invalid; one
/// the schema has and no run writes fails here).
#[test]
fn the_schema_accepts_every_kind_of_line() {
    let (validator, schema) = schema();
    let borrowed = Borrowed::new();
    let mut written = BTreeSet::new();
    for link in [None, Some("the link")] {
        for run in RUNS {
            let mut out = reporter(false, link);
            for told in run.told(&borrowed) {
                tell(&mut out, &told);
            }
            for line in String::from_utf8(out.out).unwrap().lines() {
                let value: Value = serde_json::from_str(line).unwrap();
                if let Some(link) = link {
                    assert_eq!(value["link"], link, "{value}");
                }
                assert_valid(&validator, &value);
                written.insert(value["type"].as_str().unwrap().to_string());
            }
        }
    }
    // The pair report is the run's, after its links' lines.
    let mut pair = Vec::new();
    crate::output::pair::write_json(&mut pair, &pair_summary(), &["a", "b"]).unwrap();
    let value: Value = serde_json::from_slice(&pair).unwrap();
    assert_valid(&validator, &value);
    written.insert(value["type"].as_str().unwrap().to_string());
    let mut matrix = crate::engine::pair::matrix::Matrix::new(1_000_000_000);
    matrix.on_request(0, 7, 0);
    matrix.on_reply(1, 7, 30_000_000);
    let mut line = Vec::new();
    crate::output::pair::write_matrix_json(&mut line, "TIMESYNC", &matrix.summary(), &["a", "b"])
        .unwrap();
    let value: Value = serde_json::from_slice(&line).unwrap();
    assert_valid(&validator, &value);
    written.insert(value["type"].as_str().unwrap().to_string());
    // `mavping compare`'s one line, its every optional part filled.
    let value: Value = serde_json::from_slice(&compare_line()).unwrap();
    assert_valid(&validator, &value);
    written.insert(value["type"].as_str().unwrap().to_string());
    assert_eq!(schema_types(&schema), written);
}

/// Two files, each a probe run (RTTs and frame ages), a telemetry log
/// (windows with and without a position) and a live passive run, A with
/// a link more, compared.
fn compare_line() -> Vec<u8> {
    let file = |loss: u64, base: f64, more: &str| {
        format!(
            r#"{{"type":"summary","schema_version":2,"link":"sim:","responders":[{{"responder":{{"sysid":1,"compid":1}},"sent":500,"lost":{loss},"rtt_us":{{"p50":{p50}}},"histogram":[{{"low_us":{base},"high_us":{high},"count":300}},{{"low_us":{high},"high_us":{top},"count":200}}]}}],"age":[{{"source":{{"sysid":1,"compid":1}},"headline":{{"p50_ms":1.5,"p99_ms":4.0}}}}]}}
{{"type":"flight_window","link":"tlog:f","received":100,"duplicate":0,"lost":{loss},"range":{{"distance_m":12.5}}}}
{{"type":"flight_window","link":"tlog:f","received":100,"duplicate":0,"lost":0,"range":null}}
{{"type":"passive_summary","schema_version":2,"link":"tlog:f","totals":{{"counts":{{"received":200,"damaged":0,"lost":{loss},"duplicate":0}}}},"sources":[{{"source":{{"sysid":1,"compid":1}},"radio":false,"ground":false,"counts":{{"received":200,"damaged":0,"lost":{loss},"duplicate":0}}}},{{"source":{{"sysid":51,"compid":68}},"radio":true,"ground":false,"counts":{{"received":20,"damaged":0,"lost":0,"duplicate":0}}}}],"flight":{{}}}}
{{"type":"passive_summary","schema_version":2,"link":"udp:14550","totals":{{"counts":{{"received":90,"damaged":0,"lost":{loss},"duplicate":0}}}},"sources":[{{"source":{{"sysid":1,"compid":1}},"radio":false,"ground":false,"counts":{{"received":90,"damaged":0,"lost":{loss},"duplicate":0}}}}]}}
{more}"#,
            p50 = base + 500.0,
            high = base + 600.0,
            top = base + 1000.0,
        )
    };
    let a = file(
        5,
        20_000.0,
        r#"{"type":"summary","schema_version":2,"link":"udp:9","responders":[]}"#,
    );
    let b = file(40, 30_000.0, "");
    let parse = |name: &str, text: &str| crate::compare::parse(name, text.as_bytes()).unwrap();
    let report = crate::compare::compare(
        &parse("a.json", &a),
        &parse("b.json", &b),
        &crate::compare::Options::default(),
    )
    .unwrap();
    assert_eq!(report.links.len(), 3);
    let mut line = Vec::new();
    crate::compare::write_json(&mut line, &report, 0).unwrap();
    line
}

/// One source on two links, the second losing every third frame the
/// first delivered and 30 ms behind it; a second source on one link.
fn pair_summary() -> crate::engine::pair::PairSummary {
    use crate::engine::pair::{PairConfig, PairTracker};
    use crate::frame::{test_frame, Msg, SysComp};
    let mut tracker = PairTracker::new(2, PairConfig::default());
    for k in 0..40u8 {
        let mut frame = test_frame(SysComp::new(1, 1), Msg::Other);
        frame.packet_seq = k;
        let at = u64::from(k) * 20_000_000;
        tracker.on_frame(0, &frame, at);
        if k % 3 != 0 {
            tracker.on_frame(1, &frame, at + 30_000_000);
        }
        tracker.on_frame(1, &test_frame(SysComp::new(2, 1), Msg::Other), at);
    }
    tracker.summary(crate::engine::Nanos::MAX)
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
