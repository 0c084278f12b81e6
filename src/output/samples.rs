//! `--samples FILE.csv`: one row per reply or loss, written as the run goes.
//! The one output whose size grows with the run, by the user's choice; the
//! process itself keeps nothing.

use std::io::{self, Write};

use super::{Event, Reporter, StartInfo};
use crate::engine::matcher::MatchEvent;
use crate::engine::summary::Summary;
use crate::verdict::Verdict;

pub const HEADER: &str = "sysid,compid,seq,sent_s,rtt_us,status";

pub struct SampleLog<W: Write> {
    out: W,
}

impl<W: Write> SampleLog<W> {
    pub fn new(out: W) -> Self {
        SampleLog { out }
    }
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
            "{},{},{seq},{},{rtt},{status}",
            who.sysid,
            who.compid,
            secs(sent)
        )
    }

    fn summary(&mut self, _: &Summary, _: &Verdict) -> io::Result<()> {
        self.out.flush()
    }

    fn flush(&mut self) -> io::Result<()> {
        self.out.flush()
    }
}
