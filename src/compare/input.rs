//! A saved run: the JSON lines `mavping --json` wrote, read back into the
//! few figures a comparison needs. Lines of types it does not use are
//! passed over; anything that is not mavping's JSON is refused.

use std::collections::BTreeMap;
use std::io::{BufRead, Read};

use serde::Deserialize;
use serde_json::Value;
use thiserror::Error;

use super::bootstrap::Bucket;
use crate::frame::SysComp;

/// The `schema_version` this build writes and reads.
pub(crate) const SCHEMA_VERSION: u64 = 2;

/// The longest line read. A summary of many sources is tens of KiB; a
/// file that is no JSON lines at all (a log, an image) must not be read
/// whole in search of a newline.
pub(crate) const MAX_LINE: u64 = 16 << 20;

/// Why a file cannot be compared: one line, naming the file.
#[derive(Debug, Error, PartialEq)]
pub(crate) enum InputError {
    #[error("{file}: empty; expected the JSON lines of `mavping --json ... > FILE`")]
    Empty { file: String },
    #[error(
        "{file} line {line}: not a line of `mavping --json` (save a run with `mavping --json ... > \
         FILE`, a telemetry log with `mavping --json LOG.tlog > FILE`)"
    )]
    NotJson { file: String, line: usize },
    #[error("{file} line {line}: schema_version {found}; this mavping reads {SCHEMA_VERSION}")]
    Version {
        file: String,
        line: usize,
        found: String,
    },
    #[error("{file} line {line}: a {kind} line without the figures compare needs: {problem}")]
    Malformed {
        file: String,
        line: usize,
        kind: &'static str,
        problem: String,
    },
    #[error("{file} line {line}: longer than {MAX_LINE} bytes, not a line of `mavping --json`")]
    LineTooLong { file: String, line: usize },
    #[error("{file}: cannot read it: {message}")]
    Read { file: String, message: String },
    #[error(
        "{file}: no summary or passive_summary line (a run cut short, or a --probe command run, \
         which compare does not read)"
    )]
    NoSummary { file: String },
}

/// One file: each link's summary, in the order written.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct RunFile {
    pub(crate) name: String,
    pub(crate) runs: Vec<LinkRun>,
}

/// One link's run.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct LinkRun {
    pub(crate) link: String,
    pub(crate) figures: Figures,
    /// The frames' ages by their own clock stamps, per source.
    pub(crate) ages: Vec<Age>,
}

/// What kind of run, with its own figures.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Figures {
    /// An echo probe (`summary`): each responder's requests and RTTs.
    Probe(Vec<Responder>),
    /// `passive_summary`: each source's sequence counts; a telemetry log
    /// also has its flight windows.
    Passive(Passive),
}

/// A responder of a probe run.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Responder {
    pub(crate) id: SysComp,
    /// Requests whose fate is decided, and those of them lost.
    pub(crate) sent: u64,
    pub(crate) lost: u64,
    /// The exact median RTT, µs; `None` with no reply.
    pub(crate) p50_us: Option<f64>,
    pub(crate) histogram: Vec<Bucket>,
}

/// A passive run or a telemetry log.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Passive {
    pub(crate) sources: Vec<Source>,
    /// Every source but the radio and the ground station's own frames.
    pub(crate) totals: Counts,
    /// `Some` on a telemetry log: its flight windows (the `flight_window`
    /// lines), in order.
    pub(crate) windows: Option<Vec<Window>>,
}

/// A source of a passive run.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Source {
    pub(crate) id: SysComp,
    /// The radio's own RADIO_STATUS frames.
    pub(crate) radio: bool,
    /// In a log, the ground station's frames as it sent them.
    pub(crate) ground: bool,
    pub(crate) counts: Counts,
}

/// Frames a sequence accounts for and those of them lost.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub(crate) struct Counts {
    pub(crate) lost: u64,
    pub(crate) numbered: u64,
}

/// A source's frame age headline, ms.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Age {
    pub(crate) id: SysComp,
    pub(crate) p50_ms: f64,
    pub(crate) p99_ms: f64,
}

/// A log's flight window: frames and where the vehicle was.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Window {
    /// Distinct frames received (duplicates left out).
    pub(crate) received: u64,
    /// What the sequence's lost count grew by in it: negative when late
    /// frames filled earlier gaps.
    pub(crate) lost: i64,
    /// At the window's last position; `None` with no position.
    pub(crate) distance_m: Option<f64>,
}

#[derive(Deserialize)]
struct Ids {
    sysid: u8,
    compid: u8,
}

impl From<Ids> for SysComp {
    fn from(ids: Ids) -> Self {
        SysComp::new(ids.sysid, ids.compid)
    }
}

#[derive(Deserialize)]
struct ProbeLine {
    link: String,
    responders: Vec<ResponderLine>,
    #[serde(default)]
    age: Vec<AgeLine>,
}

#[derive(Deserialize)]
struct ResponderLine {
    responder: Ids,
    sent: u64,
    lost: u64,
    rtt_us: Option<RttLine>,
    histogram: Vec<BucketLine>,
}

#[derive(Deserialize)]
struct RttLine {
    p50: f64,
}

#[derive(Deserialize)]
struct BucketLine {
    low_us: f64,
    high_us: f64,
    count: u64,
}

#[derive(Deserialize)]
struct PassiveLine {
    link: String,
    totals: TotalsLine,
    sources: Vec<SourceLine>,
    #[serde(default)]
    age: Vec<AgeLine>,
    #[serde(default)]
    flight: Option<Value>,
}

#[derive(Deserialize)]
struct TotalsLine {
    counts: SeqLine,
}

#[derive(Deserialize)]
struct SourceLine {
    source: Ids,
    radio: bool,
    ground: bool,
    counts: SeqLine,
}

#[derive(Deserialize)]
struct SeqLine {
    received: u64,
    damaged: u64,
    lost: u64,
    duplicate: u64,
}

impl From<SeqLine> for Counts {
    /// As the passive summary's `loss_pct`: each number received once,
    /// damaged, or lost.
    fn from(c: SeqLine) -> Self {
        Counts {
            lost: c.lost,
            numbered: c
                .received
                .saturating_add(c.damaged)
                .saturating_sub(c.duplicate)
                .saturating_add(c.lost),
        }
    }
}

#[derive(Deserialize)]
struct AgeLine {
    source: Ids,
    headline: HeadlineLine,
}

#[derive(Deserialize)]
struct HeadlineLine {
    p50_ms: f64,
    p99_ms: f64,
}

#[derive(Deserialize)]
struct WindowLine {
    received: u64,
    duplicate: u64,
    lost: i64,
    range: Option<RangeLine>,
}

#[derive(Deserialize)]
struct RangeLine {
    distance_m: f64,
}

impl From<AgeLine> for Age {
    fn from(a: AgeLine) -> Self {
        Age {
            id: a.source.into(),
            p50_ms: a.headline.p50_ms,
            p99_ms: a.headline.p99_ms,
        }
    }
}

impl From<WindowLine> for Window {
    fn from(w: WindowLine) -> Self {
        Window {
            received: w.received.saturating_sub(w.duplicate),
            lost: w.lost,
            distance_m: w.range.map(|r| r.distance_m),
        }
    }
}

/// Reads one file's text (`name` is how errors and the report call it),
/// a line at a time: memory holds one line and the figures kept, however
/// many reply or interim lines the run wrote.
pub(crate) fn parse(name: &str, mut reader: impl BufRead) -> Result<RunFile, InputError> {
    let file = || name.to_string();
    let mut runs = Vec::new();
    // Flight windows come before their summary; with several links each
    // names its link.
    let mut windows: BTreeMap<Option<String>, Vec<Window>> = BTreeMap::new();
    let mut any = false;
    let mut raw = Vec::new();
    for line in 1.. {
        raw.clear();
        let read = (&mut reader)
            .take(MAX_LINE + 1)
            .read_until(b'\n', &mut raw)
            .map_err(|e| InputError::Read {
                file: file(),
                message: e.to_string(),
            })?;
        if read == 0 {
            break;
        }
        if raw.len() as u64 > MAX_LINE {
            return Err(InputError::LineTooLong { file: file(), line });
        }
        if raw.iter().all(u8::is_ascii_whitespace) {
            continue;
        }
        any = true;
        let value: Value = match serde_json::from_slice(&raw) {
            Ok(v @ Value::Object(_)) => v,
            _ => return Err(InputError::NotJson { file: file(), line }),
        };
        let Some(kind) = value.get("type").and_then(Value::as_str) else {
            return Err(InputError::NotJson { file: file(), line });
        };
        if let Some(version) = value.get("schema_version") {
            if version.as_u64() != Some(SCHEMA_VERSION) {
                return Err(InputError::Version {
                    file: file(),
                    line,
                    found: version.to_string(),
                });
            }
        }
        let malformed = |kind: &'static str, e: serde_json::Error| InputError::Malformed {
            file: file(),
            line,
            kind,
            problem: e.to_string(),
        };
        match kind {
            "summary" | "passive_summary" if value.get("schema_version").is_none() => {
                return Err(InputError::Version {
                    file: file(),
                    line,
                    found: "missing".into(),
                });
            }
            "summary" => {
                let s: ProbeLine =
                    serde_json::from_value(value).map_err(|e| malformed("summary", e))?;
                runs.push(probe_run(s));
            }
            "passive_summary" => {
                let s: PassiveLine =
                    serde_json::from_value(value).map_err(|e| malformed("passive_summary", e))?;
                let told = windows
                    .remove(&Some(s.link.clone()))
                    .or_else(|| windows.remove(&None));
                runs.push(passive_run(s, told));
            }
            "flight_window" => {
                let link = value.get("link").and_then(Value::as_str).map(String::from);
                let w: WindowLine =
                    serde_json::from_value(value).map_err(|e| malformed("flight_window", e))?;
                windows.entry(link).or_default().push(w.into());
            }
            _ => {}
        }
    }
    if !any {
        return Err(InputError::Empty { file: file() });
    }
    if runs.is_empty() {
        return Err(InputError::NoSummary { file: file() });
    }
    Ok(RunFile { name: file(), runs })
}

fn probe_run(s: ProbeLine) -> LinkRun {
    let responders = s
        .responders
        .into_iter()
        .map(|r| Responder {
            id: r.responder.into(),
            sent: r.sent,
            lost: r.lost,
            p50_us: r.rtt_us.map(|rtt| rtt.p50),
            histogram: r
                .histogram
                .into_iter()
                .map(|b| Bucket {
                    low: b.low_us,
                    high: b.high_us,
                    count: b.count,
                })
                .collect(),
        })
        .collect();
    LinkRun {
        link: s.link,
        figures: Figures::Probe(responders),
        ages: s.age.into_iter().map(Age::from).collect(),
    }
}

/// A telemetry log's summary has a `flight` section; its windows were
/// written before it (none with `-q`).
fn passive_run(s: PassiveLine, windows: Option<Vec<Window>>) -> LinkRun {
    let sources = s
        .sources
        .into_iter()
        .map(|src| Source {
            id: src.source.into(),
            radio: src.radio,
            ground: src.ground,
            counts: src.counts.into(),
        })
        .collect();
    let is_log = s.flight.is_some_and(|f| !f.is_null());
    LinkRun {
        link: s.link,
        figures: Figures::Passive(Passive {
            sources,
            totals: s.totals.counts.into(),
            windows: is_log.then(|| windows.unwrap_or_default()),
        }),
        ages: s.age.into_iter().map(Age::from).collect(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const PROBE: &str = r#"{"type":"start","schema_version":2,"link":"sim:"}
{"type":"reply","t_s":0.02,"responder":{"sysid":1,"compid":1},"seq":0,"rtt_us":21503.9}
{"type":"summary","schema_version":2,"link":"sim:","responders":[{"responder":{"sysid":1,"compid":1},"sent":500,"received":491,"lost":9,"rtt_us":{"p50":21967.0},"histogram":[{"low_us":20103.0,"high_us":20581.0,"count":27}]}],"age":[{"source":{"sysid":1,"compid":1},"headline":{"p50_ms":1.5,"p99_ms":4.0}}]}
"#;

    #[test]
    fn a_probe_summary_gives_each_responder_and_its_ages() {
        let f = parse("a.json", PROBE.as_bytes()).unwrap();
        assert_eq!(f.runs.len(), 1);
        let run = &f.runs[0];
        assert_eq!(run.link, "sim:");
        let Figures::Probe(rs) = &run.figures else {
            panic!("{run:?}")
        };
        assert_eq!(
            (rs[0].id, rs[0].sent, rs[0].lost),
            (SysComp::new(1, 1), 500, 9)
        );
        assert_eq!(rs[0].p50_us, Some(21967.0));
        assert_eq!(rs[0].histogram[0].count, 27);
        assert_eq!(run.ages[0].p99_ms, 4.0);
    }

    #[test]
    fn a_log_keeps_its_windows_and_counts_as_its_loss_pct_does() {
        let text = r#"{"type":"flight_window","index":0,"received":100,"duplicate":2,"lost":5,"loss_pct":4.9,"radio":null,"range":{"ground_m":1.0,"distance_m":12.5,"alt_m":3.0}}
{"type":"flight_window","index":1,"received":50,"duplicate":0,"lost":-1,"loss_pct":0.0,"radio":null,"range":null}
{"type":"passive_summary","schema_version":2,"link":"tlog:x.tlog","totals":{"counts":{"received":150,"damaged":1,"lost":4,"duplicate":2,"reordered":0,"resyncs":0}},"sources":[{"source":{"sysid":1,"compid":1},"radio":false,"ground":false,"counts":{"received":150,"damaged":1,"lost":4,"duplicate":2}}],"flight":{"window_s":10.0}}"#;
        let f = parse("log.json", text.as_bytes()).unwrap();
        let Figures::Passive(p) = &f.runs[0].figures else {
            panic!()
        };
        assert_eq!(
            p.totals,
            Counts {
                lost: 4,
                numbered: 153
            }
        );
        let w = p.windows.as_ref().unwrap();
        assert_eq!(w.len(), 2);
        assert_eq!(
            (w[0].received, w[0].lost, w[0].distance_m),
            (98, 5, Some(12.5))
        );
        assert_eq!(w[1].distance_m, None);
    }

    #[test]
    fn windows_go_to_their_own_link() {
        let text = r#"{"type":"flight_window","link":"b","received":7,"duplicate":0,"lost":0,"range":null}
{"type":"passive_summary","schema_version":2,"link":"a","totals":{"counts":{"received":0,"damaged":0,"lost":0,"duplicate":0}},"sources":[],"flight":{}}
{"type":"passive_summary","schema_version":2,"link":"b","totals":{"counts":{"received":7,"damaged":0,"lost":0,"duplicate":0}},"sources":[],"flight":{}}"#;
        let f = parse("two.json", text.as_bytes()).unwrap();
        let windows = |i: usize| match &f.runs[i].figures {
            Figures::Passive(p) => p.windows.clone().unwrap().len(),
            Figures::Probe(_) => panic!(),
        };
        assert_eq!((windows(0), windows(1)), (0, 1));
    }

    #[test]
    fn what_is_not_a_saved_run_is_refused_with_its_reason() {
        let err = |text: &[u8]| parse("x", text).unwrap_err();
        assert_eq!(err(b""), InputError::Empty { file: "x".into() });
        assert_eq!(err(b"\n  \n"), InputError::Empty { file: "x".into() });
        assert_eq!(
            err(b"\xfe\x00\x00\x01garbage"),
            InputError::NotJson {
                file: "x".into(),
                line: 1
            }
        );
        assert_eq!(
            err(b"{\"type\":\"start\",\"schema_version\":2}\n[1,2]\n"),
            InputError::NotJson {
                file: "x".into(),
                line: 2
            }
        );
        assert_eq!(
            err(b"{\"no_type\":1}"),
            InputError::NotJson {
                file: "x".into(),
                line: 1
            }
        );
        assert!(matches!(
            err(b"{\"type\":\"summary\",\"schema_version\":3,\"link\":\"a\"}"),
            InputError::Version { line: 1, ref found, .. } if found == "3"
        ));
        assert!(matches!(
            err(b"{\"type\":\"summary\",\"link\":\"a\",\"responders\":[]}"),
            InputError::Version { .. }
        ));
        assert!(matches!(
            err(b"{\"type\":\"summary\",\"schema_version\":2,\"link\":\"a\"}"),
            InputError::Malformed {
                kind: "summary",
                ..
            }
        ));
        assert_eq!(
            err(b"{\"type\":\"start\",\"schema_version\":2}\n"),
            InputError::NoSummary { file: "x".into() }
        );
        let message = err(b"garbage").to_string();
        assert!(!message.contains('\n'), "{message}");
    }

    /// A stream with no newline (a binary file, `/dev/zero`) is refused
    /// after `MAX_LINE` bytes, not read on until memory runs out.
    #[test]
    fn a_line_without_end_is_refused_at_its_limit() {
        let endless = std::io::BufReader::new(std::io::repeat(b'x'));
        assert_eq!(
            parse("zero", endless).unwrap_err(),
            InputError::LineTooLong {
                file: "zero".into(),
                line: 1
            }
        );
        // Lines up to the limit are read, however many.
        let many = "{\"type\":\"reply\"}\n".repeat(10_000);
        assert_eq!(
            parse("many", many.as_bytes()).unwrap_err(),
            InputError::NoSummary {
                file: "many".into()
            }
        );
    }
}
