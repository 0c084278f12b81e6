//! `--json`: newline-delimited JSON, one object per event. The schema is
//! `schema/mavping-events.schema.json`; bump [`SCHEMA_VERSION`] on any
//! change that could break a consumer. Echo probes' objects are built in
//! [`echo`], the command probe's in [`command`].

mod command;
mod echo;
mod sweep;
#[cfg(test)]
mod tests;

use std::io::{self, Write};

use serde_json::{json, Value};

use super::{Event, Observer, Reporter, RunKind, StartInfo, WallClock};
use crate::engine::summary::{Interim, LinkSummary};
use crate::engine::Nanos;
use crate::frame::SysComp;
use crate::verdict::Verdict;

pub const SCHEMA_VERSION: u32 = 2;

pub struct JsonReporter<W: Write> {
    out: W,
    /// Only the summary object (`--json -q`).
    quiet: bool,
    wall: WallClock,
    /// With several links, every object names its link.
    link: Option<String>,
    /// The run is a command probe's: only its own events are written.
    command: bool,
}

impl<W: Write> JsonReporter<W> {
    pub fn new(out: W, quiet: bool, wall: WallClock) -> Self {
        JsonReporter {
            out,
            quiet,
            wall,
            link: None,
            command: false,
        }
    }

    /// Adds `"link": LINK` to every event (the start and summary objects
    /// always carry it), for runs over several links.
    pub fn with_link(mut self, link: Option<String>) -> Self {
        self.link = link;
        self
    }

    fn emit(&mut self, mut value: Value) -> io::Result<()> {
        if let (Some(link), Value::Object(m)) = (&self.link, &mut value) {
            m.insert("link".into(), link.clone().into());
        }
        serde_json::to_writer(&mut self.out, &value)?;
        self.out.write_all(b"\n")
    }

    /// The `start` event: what the run is about to do.
    fn start_object(&self, info: &StartInfo) -> serde_json::Map<String, Value> {
        let Value::Object(m) = json!({
            "type": "start",
            "schema_version": SCHEMA_VERSION,
            "mavping_version": env!("CARGO_PKG_VERSION"),
            "time": self.wall.rfc3339(0),
            "link": info.link,
            "probe": info.probe,
            "ours": info.ours,
            "interval_s": info.interval.as_secs_f64(),
            "rate_hz": 1.0 / info.interval.as_secs_f64(),
            "timeout_s": info.timeout.as_secs_f64(),
            "count": info.count,
        }) else {
            unreachable!("json! of an object literal is an object")
        };
        m
    }

    /// Fields every timed event carries: session seconds and wall time.
    fn stamped(&self, kind: &str, t: Nanos, responder: SysComp) -> serde_json::Map<String, Value> {
        let mut m = serde_json::Map::new();
        m.insert("type".into(), kind.into());
        m.insert("t_s".into(), json!(t as f64 / 1e9));
        m.insert("time".into(), self.wall.rfc3339(t).into());
        m.insert("responder".into(), json!(responder));
        m
    }
}

fn us(ns: Nanos) -> f64 {
    ns as f64 / 1e3
}

impl<W: Write> Observer for JsonReporter<W> {
    fn start(&mut self, info: &StartInfo) -> io::Result<()> {
        self.command = matches!(info.run, RunKind::Command(_));
        if self.quiet {
            return Ok(());
        }
        let mut value = self.start_object(info);
        if let Some(spec) = info.run.command() {
            value.insert("command".into(), command::spec(spec));
        }
        if let Some(plan) = info.run.steps() {
            value.insert("sweep".into(), sweep::plan(plan));
        }
        self.emit(Value::Object(value))
    }

    fn event(&mut self, event: &Event<'_>) -> io::Result<()> {
        if self.quiet {
            return Ok(());
        }
        let value = match event {
            Event::Command(e) => command::event(e),
            // A command run writes its commands' fate only.
            _ if self.command => None,
            _ => self.echo_event(event),
        };
        match value {
            Some(value) => self.emit(value),
            None => Ok(()),
        }
    }

    fn flush(&mut self) -> io::Result<()> {
        self.out.flush()
    }

    /// Written in quiet mode too: that is what `-Q` is for.
    fn interim(&mut self, figures: &Interim) -> io::Result<()> {
        let value = self.interim_object(figures);
        self.emit(value)?;
        self.out.flush()
    }
}

impl<W: Write> Reporter for JsonReporter<W> {
    fn summary(&mut self, summary: &LinkSummary, verdict: &Verdict) -> io::Result<()> {
        let value = match summary {
            LinkSummary::Echo(s) => echo::summary(s, verdict),
            LinkSummary::Command(s) => command::summary(s, verdict)?,
        };
        self.emit(value)?;
        self.out.flush()
    }
}
