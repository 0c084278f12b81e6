//! `--samples FILE.csv`: one row per reply or loss, written as the run goes.
//! The one output whose size grows with the run, by the user's choice; the
//! process itself keeps nothing.

use std::io::{self, Write};

use super::{Event, Observer, Reporter, StartInfo};
use crate::engine::matcher::MatchEvent;
use crate::engine::radio::{self, RadioReport};
use crate::engine::summary::LinkSummary;
use crate::verdict::Verdict;

/// The radio columns come last, so readers of the first six keep working.
/// They hold the latest RADIO_STATUS (any radio) when the row was written,
/// so loss can be plotted against RSSI; empty before one or when unknown.
pub const HEADER: &str = "sysid,compid,seq,sent_s,rtt_us,status,rssi,remrssi,txbuf,noise,remnoise";

/// With several links, one file holds them all and each row ends with its
/// link's connection string.
pub const LINK_COLUMN: &str = ",link";

pub struct SampleLog<W: Write> {
    out: W,
    radio: Option<RadioReport>,
    /// `,LINK` (CSV-quoted when needed) after each row, with several links.
    link: Option<String>,
    header: bool,
}

impl<W: Write> SampleLog<W> {
    pub fn new(out: W) -> Self {
        SampleLog {
            out,
            radio: None,
            link: None,
            header: true,
        }
    }

    /// Rows end with a `link` column; only the first link's log writes
    /// the header (`header`), as they share one file.
    pub fn for_link(mut self, link: &str, header: bool) -> Self {
        self.link = Some(format!(",{}", csv_field(link)));
        self.header = header;
        self
    }
}

/// A CSV field, quoted when it holds a comma, a quote or a line break.
fn csv_field(s: &str) -> String {
    if s.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

fn radio_columns(r: Option<RadioReport>) -> String {
    let Some(r) = r else {
        return ",,,,".into();
    };
    [r.rssi, r.remrssi, r.txbuf, r.noise, r.remnoise]
        .map(|v| {
            if v == radio::UNKNOWN {
                String::new()
            } else {
                v.to_string()
            }
        })
        .join(",")
}

fn secs(ns: u64) -> String {
    format!("{:.6}", ns as f64 / 1e9)
}

fn us(ns: u64) -> String {
    format!("{:.3}", ns as f64 / 1e3)
}

impl<W: Write> Observer for SampleLog<W> {
    fn start(&mut self, _: &StartInfo) -> io::Result<()> {
        match (self.header, &self.link) {
            (false, _) => Ok(()),
            (true, None) => writeln!(self.out, "{HEADER}"),
            (true, Some(_)) => writeln!(self.out, "{HEADER}{LINK_COLUMN}"),
        }
    }

    fn event(&mut self, event: &Event<'_>) -> io::Result<()> {
        if let Event::Radio { report, .. } = *event {
            self.radio = Some(report);
        }
        let Event::Match(e) = event else {
            return Ok(());
        };
        let (who, seq, sent, rtt, status) = match *e {
            MatchEvent::Reply {
                responder,
                seq,
                rtt,
                sent_at,
                ..
            } => (responder, seq, sent_at, us(rtt), "ok"),
            MatchEvent::Late {
                responder,
                seq,
                rtt,
                sent_at,
                ..
            } => (responder, seq, sent_at, us(rtt), "late"),
            MatchEvent::Duplicate {
                responder,
                seq,
                rtt,
                sent_at,
                ..
            } => (responder, seq, sent_at, us(rtt), "duplicate"),
            MatchEvent::Lost {
                responder,
                seq,
                sent_at,
                ..
            } => (responder, seq, sent_at, String::new(), "lost"),
            MatchEvent::Stale { .. } => return Ok(()),
        };
        writeln!(
            self.out,
            "{},{},{seq},{},{rtt},{status},{}{}",
            who.sysid,
            who.compid,
            secs(sent),
            radio_columns(self.radio),
            self.link.as_deref().unwrap_or("")
        )
    }

    fn flush(&mut self) -> io::Result<()> {
        self.out.flush()
    }
}

impl<W: Write> Reporter for SampleLog<W> {
    fn summary(&mut self, _: &LinkSummary, _: &Verdict) -> io::Result<()> {
        self.out.flush()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::engine::observe::RunKind;
    use crate::engine::summary::ProbeName;
    use crate::frame::SysComp;

    #[test]
    fn rows_carry_the_latest_radio_figures() {
        let mut log = SampleLog::new(Vec::new());
        let lost = |seq| {
            Event::Match(MatchEvent::Lost {
                responder: SysComp::new(1, 1),
                seq,
                sent_at: 0,
                at: 1,
            })
        };
        log.event(&lost(0)).unwrap();
        log.event(&Event::Radio {
            id: SysComp::new(51, 68),
            at: 1,
            report: RadioReport {
                rssi: 200,
                remrssi: radio::UNKNOWN,
                txbuf: 15,
                noise: 40,
                remnoise: 60,
                rxerrors: 0,
                fixed: 0,
            },
            first: true,
        })
        .unwrap();
        log.event(&lost(1)).unwrap();
        let out = String::from_utf8(log.out).unwrap();
        assert_eq!(
            out,
            "1,1,0,0.000000,,lost,,,,,\n1,1,1,0.000000,,lost,200,,15,40,60\n"
        );
    }

    #[test]
    fn rows_of_several_links_name_their_link() {
        let info = StartInfo {
            link: "sim:?a=1,2".into(),
            probe: ProbeName::Ping,
            ours: SysComp::new(255, 190),
            interval: std::time::Duration::from_secs(1),
            timeout: std::time::Duration::from_secs(1),
            count: None,
            run: RunKind::Echo,
        };
        let lost = Event::Match(MatchEvent::Lost {
            responder: SysComp::new(1, 1),
            seq: 3,
            sent_at: 0,
            at: 1,
        });
        let mut first = SampleLog::new(Vec::new()).for_link("sim:?a=1,2", true);
        first.start(&info).unwrap();
        first.event(&lost).unwrap();
        let mut second = SampleLog::new(Vec::new()).for_link("sim:", false);
        second.start(&info).unwrap();
        second.event(&lost).unwrap();
        assert_eq!(
            String::from_utf8(first.out).unwrap(),
            format!("{HEADER},link\n1,1,3,0.000000,,lost,,,,,,\"sim:?a=1,2\"\n")
        );
        assert_eq!(
            String::from_utf8(second.out).unwrap(),
            "1,1,3,0.000000,,lost,,,,,,sim:\n"
        );
    }
}
