//! JSON objects of the command probe.

use std::io;

use serde_json::{json, Value};

use super::{us, SCHEMA_VERSION};
use crate::engine::summary::CommandSummary;
use crate::engine::{observe::CommandEvent, CommandSpec};
use crate::frame::codec;
use crate::verdict::Verdict;

/// The `command` member of the start object: what is sent, and how.
pub(super) fn spec(spec: &CommandSpec) -> Value {
    json!({
        "id": spec.command,
        "name": codec::command_name(spec.command),
        "target": spec.target,
        "params": spec.params,
        "retry_interval_s": spec.retry_interval.as_secs_f64(),
        "retries": spec.retries,
    })
}

/// The object of a command event, if it has one.
pub(super) fn event(event: &CommandEvent) -> Option<Value> {
    use CommandEvent as E;
    let value = match *event {
        // Each transmission is in the summary's attempt counts.
        E::Send { .. } => return None,
        E::Acked {
            n,
            target,
            from,
            command,
            result,
            attempts,
            time_to_ack,
        } => json!({
            "type": "ack", "n": n, "target": target, "from": from, "command": command,
            "result": result, "result_name": codec::result_name(result),
            "attempts": attempts, "time_to_ack_us": us(time_to_ack),
        }),
        E::Failed {
            n,
            target,
            command,
            attempts,
        } => json!({
            "type": "command_failed", "n": n, "target": target, "command": command,
            "attempts": attempts,
        }),
        E::Skipped {
            target,
            command,
            at,
            ..
        } => json!({
            "type": "skipped", "t_s": at as f64 / 1e9, "target": target, "command": command,
        }),
        E::LateAck {
            from,
            command,
            result,
        } => json!({"type": "late_ack", "from": from, "command": command, "result": result}),
        E::DuplicateAck {
            from,
            command,
            result,
        } => {
            json!({"type": "duplicate_ack", "from": from, "command": command, "result": result})
        }
    };
    Some(value)
}

/// The `command_summary` object.
pub(super) fn summary(summary: &CommandSummary, verdict: &Verdict) -> io::Result<Value> {
    let mut value = serde_json::to_value(summary)?;
    if let Value::Object(m) = &mut value {
        m.insert("type".into(), "command_summary".into());
        m.insert("schema_version".into(), SCHEMA_VERSION.into());
        m.insert("exit_code".into(), verdict.exit_code.into());
    }
    Ok(value)
}
