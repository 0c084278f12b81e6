//! A kind's events and summary in words, as they serialise, for a kind
//! with no text of its own: an event is a line of its figures, the
//! summary its figures one to a line. What the text shows of a new kind
//! until it is given lines of its own (`output/reporter.rs`).

use std::io::{self, Write};

use serde_json::{Map, Value};

/// `type: key=value ...`, or `None` for a value that is not an object.
pub(super) fn event_line(value: &dyn erased_serde::Serialize) -> Option<String> {
    let Value::Object(mut fields) = serde_json::to_value(value).ok()? else {
        return None;
    };
    // shift_remove: the figures keep their order (remove would swap).
    let kind = match fields.shift_remove("type") {
        Some(Value::String(kind)) => kind,
        _ => "event".to_string(),
    };
    let figures: Vec<String> = fields.iter().map(|(k, v)| format!("{k}={v}")).collect();
    Some(format!("{kind}: {}", figures.join(" ")))
}

/// Each figure on a line of its own, `key: value`, nested ones by their
/// path (`targets[0].acknowledged: 2`).
pub(super) fn write_figures(
    out: &mut impl Write,
    figures: &dyn erased_serde::Serialize,
) -> io::Result<()> {
    match serde_json::to_value(figures)? {
        Value::Object(fields) => write_object(out, "", &fields),
        other => writeln!(out, "{other}"),
    }
}

fn write_object(out: &mut impl Write, path: &str, fields: &Map<String, Value>) -> io::Result<()> {
    for (key, value) in fields {
        let path = if path.is_empty() {
            key.clone()
        } else {
            format!("{path}.{key}")
        };
        write_value(out, &path, value)?;
    }
    Ok(())
}

fn write_value(out: &mut impl Write, path: &str, value: &Value) -> io::Result<()> {
    match value {
        Value::Object(fields) => write_object(out, path, fields),
        Value::Array(items) if items.iter().any(|v| v.is_object() || v.is_array()) => {
            for (i, item) in items.iter().enumerate() {
                write_value(out, &format!("{path}[{i}]"), item)?;
            }
            Ok(())
        }
        Value::Array(items) => {
            let items: Vec<String> = items.iter().map(Value::to_string).collect();
            writeln!(out, "{path}: {}", items.join(", "))
        }
        Value::String(text) => writeln!(out, "{path}: {text}"),
        scalar => writeln!(out, "{path}: {scalar}"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(serde::Serialize)]
    #[serde(tag = "type", rename = "novel")]
    struct Event {
        n: u64,
        from: [u8; 2],
    }

    #[derive(serde::Serialize)]
    struct Target {
        id: u8,
        acknowledged: u64,
    }

    #[derive(serde::Serialize)]
    struct Summary {
        seen: u64,
        name: &'static str,
        rates: Vec<f64>,
        targets: Vec<Target>,
        none: Option<u8>,
    }

    #[test]
    fn an_event_is_a_line_of_its_figures_and_a_summary_a_figure_a_line() {
        let event = Event { n: 7, from: [1, 1] };
        assert_eq!(event_line(&event).unwrap(), "novel: n=7 from=[1,1]");
        let summary = Summary {
            seen: 3,
            name: "x",
            rates: vec![1.5, 2.0],
            targets: vec![Target {
                id: 1,
                acknowledged: 2,
            }],
            none: None,
        };
        let mut out = Vec::new();
        write_figures(&mut out, &summary).unwrap();
        assert_eq!(
            String::from_utf8(out).unwrap(),
            "seen: 3\nname: x\nrates: 1.5, 2.0\ntargets[0].id: 1\ntargets[0].acknowledged: 2\n\
             none: null\n"
        );
    }
}
