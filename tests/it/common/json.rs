//! Reading mavping's `--json` output in tests.

use serde_json::Value;

/// Every non-empty line of `out`, parsed.
pub fn json_lines(out: &str) -> Vec<Value> {
    out.lines()
        .filter(|l| !l.trim().is_empty())
        .map(|l| serde_json::from_str(l).unwrap_or_else(|e| panic!("not JSON: {l}: {e}")))
        .collect()
}

/// The published schema of the events.
pub fn schema() -> jsonschema::Validator {
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/schema/mavping-events.schema.json"
    ))
    .unwrap();
    jsonschema::validator_for(&serde_json::from_str(&text).unwrap()).unwrap()
}

/// Fails unless every event is valid against the schema.
pub fn assert_schema(events: &[Value]) {
    let validator = schema();
    for e in events {
        let errors: Vec<String> = validator.iter_errors(e).map(|e| e.to_string()).collect();
        assert!(errors.is_empty(), "{e}\n{errors:?}");
    }
}

/// The (first) summary object of a run.
pub fn summary_of(out: &str) -> Value {
    json_lines(out)
        .into_iter()
        .find(|v| v["type"] == "summary")
        .unwrap_or_else(|| panic!("no summary line in\n{out}"))
}

/// The summary object of a run, every event checked against the schema.
pub fn checked_summary(out: &str) -> Value {
    assert_schema(&json_lines(out));
    summary_of(out)
}

/// The responder `SYS/COMP` of a summary.
pub fn responder<'a>(summary: &'a Value, id: &str) -> &'a Value {
    summary["responders"]
        .as_array()
        .unwrap()
        .iter()
        .find(|r| {
            let ids = &r["responder"];
            format!("{}/{}", ids["sysid"], ids["compid"]) == id
        })
        .unwrap_or_else(|| panic!("no responder {id} in {summary}"))
}

/// A count that must be there.
pub fn n(v: &Value, key: &str) -> u64 {
    v[key].as_u64().unwrap_or_else(|| panic!("{key} in {v}"))
}
