//! `--samples FILE.csv`: one row per reply or loss, written as the run goes;
//! in a passive run, one row per source per second of what its sequence
//! said in that second. The one output whose size grows with the run, by
//! the user's choice; the process itself keeps nothing but the last
//! figures of each source.

use std::io::{self, Write};

use super::windows::{Window, Windows};
use super::{Reporter, StartInfo};
use crate::engine::matcher::MatchEvent;
use crate::engine::observe::RadioHeard;
use crate::engine::probe::passive::PassivePlan;
use crate::engine::probe::passive::SourcesNow;
use crate::engine::radio::{self, RadioReport};
use crate::engine::summary::passive::{PassiveSummary, TableSummary};
use crate::engine::summary::LinkSummary;
use crate::verdict::Verdict;

/// The radio columns come last, so readers of the first six keep working.
/// They hold the latest RADIO_STATUS (any radio) when the row was written,
/// so loss can be plotted against RSSI; empty before one or when unknown.
pub(crate) const HEADER: &str =
    "sysid,compid,seq,sent_s,rtt_us,status,rssi,remrssi,txbuf,noise,remnoise";

/// A passive run's rows: per source and window (from the previous row's
/// time, or the start, to `t_s`, session seconds), what its sequence said
/// in it. The columns add up to the summary's figures; `lost` is negative
/// in a window whose late frames filled more of earlier windows' gaps than
/// it skipped (they count as reordered). The radio (51/68) has rows too,
/// as it is outside the summary's totals.
pub(crate) const PASSIVE_HEADER: &str =
    "t_s,window_s,sysid,compid,received,lost,duplicate,reordered,bytes,frames_per_s";

/// With several links, one file holds them all and each row ends with its
/// link's connection string.
pub(crate) const LINK_COLUMN: &str = ",link";

pub(crate) struct SampleLog<W: Write> {
    out: W,
    radio: Option<RadioReport>,
    /// `,LINK` (CSV-quoted when needed) after each row, with several links.
    link: Option<String>,
    header: bool,
    /// A passive run's sources, window by window (set at its start).
    windows: Option<Windows>,
}

impl<W: Write> SampleLog<W> {
    #[cfg(test)]
    pub(crate) fn into_inner(self) -> W {
        self.out
    }

    pub(crate) fn new(out: W) -> Self {
        SampleLog {
            out,
            radio: None,
            link: None,
            header: true,
            windows: None,
        }
    }

    /// Rows end with a `link` column; only the first link's log writes
    /// the header (`header`), as they share one file.
    pub(crate) fn for_link(mut self, link: &str, header: bool) -> Self {
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
    let known = |v: u8| (v != radio::UNKNOWN).then(|| v.to_string());
    [r.rssi, r.remrssi, r.txbuf, r.noise, r.remnoise]
        .map(|v| known(v).unwrap_or_default())
        .join(",")
}

fn secs(ns: u64) -> String {
    format!("{:.6}", ns as f64 / 1e9)
}

fn us(ns: u64) -> String {
    format!("{:.3}", ns as f64 / 1e3)
}

impl<W: Write> SampleLog<W> {
    /// A passive run's row of one window.
    fn window(&mut self, w: &Window) -> io::Result<()> {
        writeln!(
            self.out,
            "{},{},{},{},{},{},{},{},{},{}{}",
            secs(w.end),
            secs(w.end - w.start),
            w.source.sysid,
            w.source.compid,
            w.received,
            w.lost,
            w.duplicate,
            w.reordered,
            w.bytes,
            w.frames_per_s()
                .map_or_else(String::new, |r| format!("{r:.3}")),
            self.link.as_deref().unwrap_or("")
        )
    }

    /// The rows of the windows ending at `at`; an empty last window (the
    /// run ended on a telling) writes none.
    fn windows(&mut self, at: u64, table: &TableSummary, last: bool) -> io::Result<()> {
        let Some(windows) = self.windows.as_mut() else {
            return Ok(());
        };
        let rows = windows.next(at, table);
        if last && rows.iter().all(Window::is_empty) {
            return Ok(());
        }
        rows.iter().try_for_each(|w| self.window(w))
    }
}

impl<W: Write> Reporter for SampleLog<W> {
    fn start(&mut self, info: &StartInfo) -> io::Result<()> {
        let passive = info.plan::<PassivePlan>().is_some();
        self.windows = passive.then(Windows::default);
        let header = if passive { PASSIVE_HEADER } else { HEADER };
        match (self.header, &self.link) {
            (false, _) => Ok(()),
            (true, None) => writeln!(self.out, "{header}"),
            (true, Some(_)) => writeln!(self.out, "{header}{LINK_COLUMN}"),
        }
    }

    /// The latest radio's figures go on each row.
    fn radio(&mut self, radio: &RadioHeard<'_>) -> io::Result<()> {
        self.radio = Some(radio.report);
        Ok(())
    }

    fn sources(&mut self, now: &SourcesNow) -> io::Result<()> {
        self.windows(now.at, &now.table, false)
    }

    fn matched(&mut self, e: &MatchEvent) -> io::Result<()> {
        let status = match e {
            MatchEvent::Reply { .. } => "ok",
            MatchEvent::Late { .. } => "late",
            MatchEvent::Duplicate { .. } => "duplicate",
            MatchEvent::Lost { .. } => "lost",
            MatchEvent::Stale { .. } => return Ok(()),
        };
        let (Some(seq), Some(sent)) = (e.seq(), e.sent_at()) else {
            return Ok(());
        };
        let who = e.responder();
        let rtt = e.rtt().map(us).unwrap_or_default();
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

    /// A passive run's last, partial, window comes from its summary.
    fn summary(&mut self, summary: &LinkSummary, _: &Verdict) -> io::Result<()> {
        if let Some(s) = summary.get::<PassiveSummary>() {
            let end = (s.duration_s * 1e9) as u64;
            self.windows(end, &s.table, true)?;
        }
        self.out.flush()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::engine::observe::Event;
    use crate::engine::probe::passive::{PassivePlan, SourcesNow};
    use crate::engine::summary::ProbeName;
    use crate::frame::SysComp;
    use crate::output::runs::kind;

    #[test]
    fn rows_carry_the_latest_radio_figures() {
        let mut log = SampleLog::new(Vec::new());
        let lost = |seq| {
            kind(MatchEvent::Lost {
                responder: SysComp::new(1, 1),
                seq,
                sent_at: 0,
                at: 1,
            })
        };
        log.tell(&lost(0)).unwrap();
        let sik = radio::Judgement {
            kind: radio::RadioKind::Sik,
            radio_type: radio::RadioType::Auto,
            evidence: vec![],
        };
        log.tell(&Event::Radio(RadioHeard {
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
            judgement: &sik,
            first: true,
            kind_changed: false,
        }))
        .unwrap();
        log.tell(&lost(1)).unwrap();
        let out = String::from_utf8(log.out).unwrap();
        assert_eq!(
            out,
            "1,1,0,0.000000,,lost,,,,,\n1,1,1,0.000000,,lost,200,,15,40,60\n"
        );
    }

    fn passive_start() -> StartInfo {
        StartInfo {
            link: "sim:".into(),
            probe: ProbeName::Passive,
            ours: SysComp::new(250, 190),
            interval: std::time::Duration::from_secs(1),
            timeout: std::time::Duration::from_secs(1),
            count: None,
            plan: Some(std::sync::Arc::new(PassivePlan {
                heartbeat: true,
                log: false,
            })),
        }
    }

    fn passive_summary(duration_s: f64, table: TableSummary) -> LinkSummary {
        use crate::engine::summary::passive::PassiveSummary;
        LinkSummary::new(PassiveSummary {
            link: "sim:".into(),
            ours: SysComp::new(250, 190),
            heartbeat: true,
            duration_s,
            table,
            identities: vec![],
            own_frames: 0,
            radios: vec![],
            frames: crate::frame::ScanStats::default(),
            rx_clock: crate::transport::RxClock::Simulated,
            interrupted: false,
            link_error: None,
            signing: crate::frame::signing::Gate::new(None).summary(),
            answered: crate::engine::answers::AnswerSummary::default(),
            age: Vec::new(),
            hints: Vec::new(),
            link_node: vec![],
            log: None,
            per_link: None,
            round_trips: None,
            flight: None,
        })
    }

    fn judged(summary: &LinkSummary) -> Verdict {
        crate::verdict::judge_link(summary, &crate::verdict::Thresholds::default())
    }

    #[test]
    fn a_passive_run_has_a_row_per_source_per_second_and_the_last_part() {
        use crate::engine::probe::passive::tracker::SourceTable;
        let ms = 1_000_000;
        let (a, b) = (SysComp::new(1, 1), SysComp::new(2, 1));
        let mut table = SourceTable::new(None, 32);
        let mut log = SampleLog::new(Vec::new()).for_link("sim:", true);
        log.start(&passive_start()).unwrap();
        // 1/1 skips 2, which comes in the next second; 2/1 starts then.
        for (seq, at) in [(0, 100), (1, 200), (3, 300)] {
            table.on_frame(a, seq, 30, 40, at * ms);
        }
        let first = table.summary(1_000 * ms);
        log.tell(&kind(SourcesNow {
            at: 1_000 * ms,
            table: first.clone(),
            ages: Vec::new(),
            age_counts: Vec::new(),
            age_max: Vec::new(),
        }))
        .unwrap();
        table.on_frame(a, 2, 30, 40, 1_100 * ms);
        table.on_frame(b, 0, 0, 21, 1_200 * ms);
        table.on_frame(b, 0, 0, 21, 1_300 * ms);
        table.on_frame(b, 1, 0, 21, 1_400 * ms);
        let end = passive_summary(1.5, table.summary(1_500 * ms));
        log.summary(&end, &judged(&end)).unwrap();
        assert_eq!(
            String::from_utf8(log.out).unwrap(),
            format!(
                "{PASSIVE_HEADER},link\n\
                 1.000000,1.000000,1,1,3,1,0,0,120,3.000,sim:\n\
                 1.500000,0.500000,1,1,1,-1,0,1,40,2.000,sim:\n\
                 1.500000,0.500000,2,1,3,0,1,0,63,6.000,sim:\n"
            )
        );
    }

    #[test]
    fn a_passive_run_that_ends_on_a_second_adds_no_empty_rows() {
        use crate::engine::probe::passive::tracker::SourceTable;
        let mut table = SourceTable::new(None, 32);
        table.on_frame(SysComp::new(1, 1), 0, 30, 40, 500_000_000);
        let at_one = table.summary(1_000_000_000);
        let mut log = SampleLog::new(Vec::new());
        log.start(&passive_start()).unwrap();
        // An echo run's table (told for its direction split) is not sampled.
        let mut echo = SampleLog::new(Vec::new());
        echo.start(&StartInfo {
            plan: None,
            ..passive_start()
        })
        .unwrap();
        for l in [&mut log, &mut echo] {
            l.tell(&kind(SourcesNow {
                at: 1_000_000_000,
                table: at_one.clone(),
                ages: Vec::new(),
                age_counts: Vec::new(),
                age_max: Vec::new(),
            }))
            .unwrap();
        }
        let end = passive_summary(1.0, at_one.clone());
        log.summary(&end, &judged(&end)).unwrap();
        assert_eq!(
            String::from_utf8(log.out).unwrap(),
            format!("{PASSIVE_HEADER}\n1.000000,1.000000,1,1,1,0,0,0,40,1.000\n")
        );
        assert_eq!(String::from_utf8(echo.out).unwrap(), format!("{HEADER}\n"));
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
            plan: None,
        };
        let lost = kind(MatchEvent::Lost {
            responder: SysComp::new(1, 1),
            seq: 3,
            sent_at: 0,
            at: 1,
        });
        let mut first = SampleLog::new(Vec::new()).for_link("sim:?a=1,2", true);
        first.start(&info).unwrap();
        first.tell(&lost).unwrap();
        let mut second = SampleLog::new(Vec::new()).for_link("sim:", false);
        second.start(&info).unwrap();
        second.tell(&lost).unwrap();
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
