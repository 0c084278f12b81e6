//! `--samples FILE.csv`: one row per reply or loss, written as the run goes.
//! The one output whose size grows with the run, by the user's choice; the
//! process itself keeps nothing.

use std::io::{self, Write};

use super::{Event, Reporter, StartInfo};
use crate::engine::matcher::MatchEvent;
use crate::engine::radio::{self, RadioReport};
use crate::engine::summary::Summary;
use crate::verdict::Verdict;

/// The radio columns come last, so readers of the first six keep working.
/// They hold the latest RADIO_STATUS (any radio) when the row was written,
/// so loss can be plotted against RSSI; empty before one or when unknown.
pub const HEADER: &str = "sysid,compid,seq,sent_s,rtt_us,status,rssi,remrssi,txbuf,noise,remnoise";

pub struct SampleLog<W: Write> {
    out: W,
    radio: Option<RadioReport>,
}

impl<W: Write> SampleLog<W> {
    pub fn new(out: W) -> Self {
        SampleLog { out, radio: None }
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

impl<W: Write> Reporter for SampleLog<W> {
    fn start(&mut self, _: &StartInfo) -> io::Result<()> {
        writeln!(self.out, "{HEADER}")
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
            "{},{},{seq},{},{rtt},{status},{}",
            who.sysid,
            who.compid,
            secs(sent),
            radio_columns(self.radio)
        )
    }

    fn summary(&mut self, _: &Summary, _: &Verdict) -> io::Result<()> {
        self.out.flush()
    }

    fn flush(&mut self) -> io::Result<()> {
        self.out.flush()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
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
}
