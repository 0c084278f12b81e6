//! What `--live` shows of one link, kept from its session's events:
//! [`LiveState`], a row per responder (its counts, RTT figures and recent
//! outcomes) or, in a passive run, per source; and the [`Screen`] one
//! frame is drawn from.

use std::collections::{BTreeMap, VecDeque};
use std::io;

use super::sources::{heard_as, Second, Sources, AGE_SHOWN_MS};
use super::view::{figure, Spec, ECHO, PASSIVE};
use crate::engine::matcher::{Counts, MatchEvent};
use crate::engine::probe::passive::PassivePlan;
use crate::engine::probe::passive::SourcesNow;
use crate::engine::roster::Identity;
use crate::engine::stats::RttStats;
use crate::engine::summary::passive::percent;
use crate::engine::summary::ProbeName;
use crate::engine::Nanos;
use crate::frame::SysComp;
use crate::output::prometheus::Outcome;
use crate::output::{Reporter, StartInfo};

/// Outcomes kept per responder for the strip: more than a wide terminal shows.
pub(crate) const RECENT: usize = 240;

/// One request's outcome for one responder, as the strip shows it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Mark {
    Rtt(Nanos),
    Lost,
    Late,
}

#[derive(Clone, Default)]
struct Track {
    /// Counted as the exporter counts them.
    counts: Counts,
    rtt: RttStats,
    recent: VecDeque<Mark>,
    heard_as: Option<String>,
    /// Its newest stamped frame's age above its baseline (ms), from the
    /// table an echo run tells for its direction split.
    age_ms: Option<f64>,
}

impl Track {
    fn record(&mut self, outcome: Outcome) {
        outcome.count(&mut self.counts);
        let mark = match outcome {
            Outcome::Received(rtt) => {
                self.rtt.record(rtt);
                Mark::Rtt(rtt)
            }
            Outcome::Lost => Mark::Lost,
            Outcome::Late => Mark::Late,
            Outcome::Duplicate => return,
        };
        if self.recent.len() == RECENT {
            self.recent.pop_front();
        }
        self.recent.push_back(mark);
    }
}

/// What the view shows, updated from events; bounded per responder.
#[derive(Clone, Default)]
pub(crate) struct LiveState {
    link: String,
    /// `None` before the session starts.
    probe: Option<ProbeName>,
    /// Session time of the latest event.
    now: Nanos,
    waiting: bool,
    /// The link failed (to open, or during the run): why, as its error
    /// line says, shown in its section while the others go on.
    failed: Option<String>,
    tracks: BTreeMap<SysComp, Track>,
    /// A passive run's sources (`None` in a probe run, whose table is told
    /// for its direction split only).
    sources: Option<Sources>,
}

/// The state follows the link's session: it takes what the view shows.
impl Reporter for LiveState {
    fn start(&mut self, info: &StartInfo) -> io::Result<()> {
        self.link = info.link.clone();
        self.probe = Some(info.probe);
        if info.plan::<PassivePlan>().is_some() {
            self.sources = Some(Sources::default());
        }
        Ok(())
    }

    fn waiting_for_peer(&mut self) -> io::Result<()> {
        self.waiting = true;
        Ok(())
    }

    fn heard(&mut self, id: SysComp, identity: &Identity) -> io::Result<()> {
        match self.sources.as_mut() {
            Some(sources) => sources.heard(id, identity),
            None => self.tracks.entry(id).or_default().heard_as = Some(heard_as(identity)),
        }
        Ok(())
    }

    /// A passive run's table; an echo run's gives its responders' ages.
    fn sources(&mut self, now: &SourcesNow) -> io::Result<()> {
        match self.sources.as_mut() {
            Some(sources) => {
                sources.table(now);
                self.now = self.now.max(now.at);
                self.waiting = false;
            }
            None => {
                for (id, age) in &now.ages {
                    if let Some(t) = self.tracks.get_mut(id) {
                        t.age_ms = Some(age.age_ms);
                    }
                }
            }
        }
        Ok(())
    }

    fn link_failed(&mut self, _: Nanos, error: &str) -> io::Result<()> {
        self.failed = Some(error.to_string());
        Ok(())
    }

    fn matched(&mut self, e: &MatchEvent) -> io::Result<()> {
        self.waiting = false;
        if let Some((id, outcome)) = Outcome::of_match(e) {
            self.now = self.now.max(e.at());
            self.tracks.entry(id).or_default().record(outcome);
        }
        Ok(())
    }
}

impl LiveState {
    /// A link that could not be opened: its section says why.
    pub(super) fn unopened(link: &str, error: &str) -> Self {
        LiveState {
            link: link.to_string(),
            failed: Some(error.to_string()),
            ..LiveState::default()
        }
    }

    /// The figures to draw, computed while the state is locked so the
    /// drawing itself runs without the lock.
    pub(crate) fn screen(&self) -> Screen {
        let (kind, rows) = match &self.sources {
            Some(sources) => (&PASSIVE, sources.rows()),
            None => (&ECHO, self.echo_rows()),
        };
        let status = match (&self.failed, &self.sources) {
            (Some(error), _) => format!(": failed: {error}"),
            (None, None) if self.waiting => ": waiting for a peer".to_string(),
            (None, Some(_)) if rows.is_empty() => ": nothing heard yet".to_string(),
            _ => String::new(),
        };
        Screen {
            link: self.link.clone(),
            probe: self.probe,
            now: self.now,
            status,
            kind,
            rows,
        }
    }

    /// A responder's row: its figures, then its recent outcomes, or what
    /// was heard from it if it never answered.
    fn echo_rows(&self) -> Vec<RowView> {
        let ms = |v: Option<f64>| (figure(v, 2), false);
        self.tracks
            .iter()
            .map(|(id, t)| {
                let (c, s) = (&t.counts, t.rtt.summary());
                let loss = percent(c.lost, c.sent).unwrap_or(0.0);
                RowView {
                    cells: vec![
                        (id.to_string(), false),
                        (c.sent.to_string(), false),
                        (c.received.to_string(), false),
                        (format!("{loss:.1}"), c.lost > 0),
                        (c.late.to_string(), c.late > 0),
                        (c.duplicate.to_string(), false),
                        ms(t.rtt.last().map(|ns| ns as f64 / 1e6)),
                        ms(s.map(|s| s.p50_us / 1e3)),
                        ms(s.map(|s| s.p99_us / 1e3)),
                        ms(s.map(|s| s.jitter_us / 1e3)),
                        (
                            figure(t.age_ms, 0),
                            t.age_ms.is_some_and(|a| a >= AGE_SHOWN_MS),
                        ),
                    ],
                    strip: match (&t.heard_as, c.received) {
                        (Some(heard), 0) => Strip::Heard(heard.clone()),
                        _ => Strip::Marks(t.recent.iter().copied().collect()),
                    },
                    quiet: false,
                }
            })
            .collect()
    }
}

/// A row's figures, each with whether it is bad news.
pub(crate) type Cells = Vec<(String, bool)>;

/// One row of a section: a responder's, or in a passive run a source's.
pub(crate) struct RowView {
    /// In the order of its kind's headers.
    pub(crate) cells: Cells,
    pub(crate) strip: Strip,
    /// The radio's own row is not the link's: shown, but dimmed.
    pub(crate) quiet: bool,
}

/// What a row's strip shows.
pub(crate) enum Strip {
    /// A responder's recent outcomes.
    Marks(Vec<Mark>),
    /// What a responder that never answered was heard as.
    Heard(String),
    /// A source's recent seconds.
    Seconds(Vec<Second>),
    /// Words: the pair report's merged figures.
    Note(String),
}

/// Everything one frame shows.
pub(crate) struct Screen {
    pub(crate) link: String,
    pub(crate) probe: Option<ProbeName>,
    /// Session time of the latest event.
    pub(crate) now: Nanos,
    /// After the link in its section's title: why it failed, or that it
    /// waits.
    pub(crate) status: String,
    /// Its rows' kind, whose columns they fill.
    pub(super) kind: &'static Spec,
    pub(crate) rows: Vec<RowView>,
}

#[cfg(test)]
mod tests {
    use crate::engine::probe::passive::{PassivePlan, SourcesNow};
    use crate::output::runs::kind;
    use std::time::Duration;

    use ratatui::backend::TestBackend;
    use ratatui::style::Color;
    use ratatui::Terminal;

    use super::super::view;
    use super::*;
    use crate::output::Event;

    impl LiveState {
        fn on_start(&mut self, info: &StartInfo) {
            self.start(info).expect("the state takes every start");
        }

        fn on_event(&mut self, event: &Event<'_>) {
            self.tell(event).expect("the state takes every event");
        }
    }

    fn reply(responder: SysComp, seq: u32, rtt_ms: u64) -> Event<'static> {
        kind(MatchEvent::Reply {
            responder,
            seq,
            rtt: rtt_ms * 1_000_000,
            sent_at: u64::from(seq) * 100_000_000,
            at: u64::from(seq) * 100_000_000 + rtt_ms * 1_000_000,
            out_of_order: false,
            first_from_responder: seq == 0,
        })
    }

    fn lost(responder: SysComp, seq: u32) -> Event<'static> {
        kind(MatchEvent::Lost {
            responder,
            seq,
            sent_at: u64::from(seq) * 100_000_000,
            at: u64::from(seq) * 100_000_000 + 2_000_000_000,
        })
    }

    fn state() -> LiveState {
        let mut s = LiveState::default();
        s.on_start(&start("sim:?responders=2"));
        let (a, b) = (SysComp::new(1, 1), SysComp::new(2, 1));
        for seq in 0..30 {
            s.on_event(&reply(a, seq, 10 + u64::from(seq % 5)));
            if seq % 7 == 3 {
                s.on_event(&lost(b, seq));
            } else {
                s.on_event(&reply(b, seq, 20 + u64::from(seq % 3) * 4));
            }
        }
        s.on_event(&kind(MatchEvent::Late {
            responder: b,
            seq: 3,
            rtt: 2_500_000_000,
            sent_at: 300_000_000,
            at: 2_800_000_000,
        }));
        s
    }

    fn start(link: &str) -> StartInfo {
        StartInfo {
            link: link.into(),
            probe: ProbeName::Ping,
            ours: SysComp::new(255, 190),
            interval: Duration::from_millis(100),
            timeout: Duration::from_secs(2),
            count: None,
            plan: None,
        }
    }

    /// The frame drawn in a `width` x `height` terminal.
    fn frame(width: u16, height: u16, screens: &[Screen]) -> String {
        let mut terminal = Terminal::new(TestBackend::new(width, height)).unwrap();
        terminal.draw(|f| view::render(f, screens, None)).unwrap();
        terminal.backend().to_string()
    }

    #[test]
    fn a_frame_shows_counts_figures_and_losses() {
        let screen = state().screen();
        insta::assert_snapshot!("80_columns", frame(80, 8, std::slice::from_ref(&screen)));
        // A wider terminal shows more of the recent outcomes.
        insta::assert_snapshot!("120_columns", frame(120, 8, &[screen]));
    }

    #[test]
    fn several_links_get_a_section_each() {
        let mut other = LiveState::default();
        other.on_start(&start(
            "udpout:10.8.0.2:14550?a-very-long-name-that-does-not-fit-in-eighty-columns",
        ));
        other.on_event(&Event::WaitingForPeer);
        let screens = [state().screen(), other.screen()];
        insta::assert_snapshot!(frame(80, 11, &screens));
    }

    #[test]
    fn responders_beyond_the_screen_are_counted() {
        let mut many = LiveState::default();
        many.on_start(&start("sim:?responders=12"));
        for sysid in 1..=12 {
            many.on_event(&reply(SysComp::new(sysid, 1), 0, 10));
        }
        let screens = [state().screen(), many.screen()];
        insta::assert_snapshot!(frame(80, 12, &screens));
    }

    /// A passive run of `seconds`: 1/1 (a quadrotor heard by its
    /// HEARTBEAT) at 50 frames a second, losing one in every third
    /// second, with a silent second; 2/1 at 10 a second, once sending a
    /// frame twice; the SiK radio's own reports once a second.
    fn passive(seconds: u64) -> LiveState {
        use crate::engine::probe::passive::tracker::{SourceTable, RADIO_SOURCE};
        let mut s = LiveState::default();
        s.on_start(&StartInfo {
            probe: ProbeName::Passive,
            plan: Some(std::sync::Arc::new(PassivePlan {
                heartbeat: true,
                log: false,
            })),
            ..start("sim:?responders=2&stream=ATTITUDE@50")
        });
        let (a, b) = (SysComp::new(1, 1), SysComp::new(2, 1));
        let identity = crate::engine::roster::Identity {
            mav_type: 2,
            autopilot: 12,
            vehicle: "quadrotor".into(),
            autopilot_name: "px4".into(),
            first_heard: 0,
        };
        s.on_event(&Event::Heard {
            id: a,
            identity: &identity,
        });
        let mut table = SourceTable::new(None, 32);
        let ms = 1_000_000;
        let (mut seq_a, mut seq_b) = (0u8, 0u8);
        for second in 0..seconds {
            let t0 = second * 1_000 * ms;
            for k in 0..50 {
                // Second 7 is silent; one frame lost every third second.
                if second != 7 && !(second % 3 == 2 && k == 25) {
                    table.on_frame(a, seq_a, 30, 40, t0 + k * 20 * ms);
                }
                seq_a = seq_a.wrapping_add(1);
            }
            for k in 0..10 {
                table.on_frame(b, seq_b, 33, 40, t0 + k * 100 * ms);
                if second == 4 && k == 3 {
                    table.on_frame(b, seq_b, 33, 40, t0 + k * 100 * ms + ms);
                }
                seq_b = seq_b.wrapping_add(1);
            }
            table.on_frame(RADIO_SOURCE, second as u8, 109, 38, t0 + 500 * ms);
            let at = t0 + 1_000 * ms;
            s.on_event(&kind(SourcesNow {
                at,
                table: table.summary(at),
                ages: Vec::new(),
                age_counts: Vec::new(),
                age_max: Vec::new(),
            }));
        }
        s
    }

    #[test]
    fn a_passive_frame_shows_each_source_and_its_seconds() {
        // A wider terminal shows more of the recent seconds.
        let screen = passive(60).screen();
        insta::assert_snapshot!(
            "passive_80_columns",
            frame(80, 8, std::slice::from_ref(&screen))
        );
        insta::assert_snapshot!("passive_120_columns", frame(120, 8, &[screen]));
    }

    #[test]
    fn a_second_that_lost_frames_is_red_and_a_silent_one_a_dot() {
        let screen = passive(12).screen();
        let mut terminal = Terminal::new(TestBackend::new(90, 8)).unwrap();
        terminal.draw(|f| view::render(f, &[screen], None)).unwrap();
        let buffer = terminal.backend().buffer();
        // 1/1's row: the strip follows its rate and its age (none: no
        // stamps), newest last.
        let row: Vec<_> = (0..90).map(|x| &buffer[(x, 3)]).collect();
        let symbols: Vec<&str> = row.iter().map(|c| c.symbol()).collect();
        let at = (0..78)
            .find(|&x| symbols[x..x + 12].concat() == "49.0      - ")
            .expect("1/1's rate");
        let strip: Vec<_> = row[at + 12..at + 24].iter().collect();
        let colours: Vec<Color> = strip.iter().map(|c| c.fg).collect();
        let symbols: String = strip.iter().map(|c| c.symbol()).collect();
        assert_eq!(symbols, "███████·████", "{row:?}");
        // Seconds 2, 5 and 11 lost a frame; 8 lost the silent second 7's.
        let red: Vec<usize> = (0..12).filter(|&i| colours[i] == Color::Red).collect();
        assert_eq!(red, [2, 5, 8, 11]);
        assert_eq!(colours[7], Color::DarkGray);
        assert_eq!(colours[0], Color::Green);
    }

    #[test]
    fn a_probe_runs_table_makes_no_source_rows() {
        use crate::engine::probe::passive::tracker::SourceTable;
        let mut s = state();
        let mut table = SourceTable::new(None, 32);
        table.on_frame(SysComp::new(1, 1), 0, 0, 21, 0);
        s.on_event(&kind(SourcesNow {
            at: 1_000_000_000,
            table: table.summary(1_000_000_000),
            ages: Vec::new(),
            age_counts: Vec::new(),
            age_max: Vec::new(),
        }));
        let screen = s.screen();
        assert!(*screen.kind == view::ECHO);
        assert_eq!(screen.rows.len(), 2);
    }

    /// A probe run's table carries its responders' ages: a responder's
    /// row shows its newest, marked past 100 ms; a source that is no
    /// responder gets no row.
    #[test]
    fn a_responders_row_shows_its_frames_age() {
        use crate::engine::age::AgeNow;
        use crate::engine::probe::passive::tracker::SourceTable;
        use crate::frame::{StampClock, StampMeaning};
        let mut s = state();
        let age = |age_ms| AgeNow {
            clock: StampClock::TimesyncNs,
            meaning: StampMeaning::Sent,
            age_ms,
            at: 1_000_000_000,
        };
        s.on_event(&kind(SourcesNow {
            at: 1_000_000_000,
            table: SourceTable::new(None, 32).summary(1_000_000_000),
            ages: vec![
                (SysComp::new(1, 1), age(240.4)),
                (SysComp::new(2, 1), age(3.0)),
                (SysComp::new(9, 9), age(1.0)),
            ],
            age_counts: Vec::new(),
            age_max: Vec::new(),
        }));
        let screen = s.screen();
        let last = |row: &RowView| row.cells.last().cloned().unwrap();
        assert_eq!(last(&screen.rows[0]), ("240".to_string(), true));
        assert_eq!(last(&screen.rows[1]), ("3".to_string(), false));
        assert_eq!(screen.rows.len(), 2);
    }

    #[test]
    fn a_sources_seconds_are_bounded() {
        let s = passive(RECENT as u64 + 60);
        let rows = s.screen().rows;
        assert!(rows
            .iter()
            .all(|r| matches!(&r.strip, Strip::Seconds(s) if s.len() == RECENT)));
        // 2/1's recv.
        let received = 10 * (RECENT as u64 + 60) + 1;
        assert_eq!(rows[1].cells[2].0, received.to_string());
    }

    #[test]
    fn recent_outcomes_are_bounded() {
        let mut s = state();
        let a = SysComp::new(1, 1);
        for seq in 0..10_000 {
            s.on_event(&reply(a, seq, 5));
        }
        let t = &s.tracks[&a];
        assert_eq!(t.recent.len(), RECENT);
        assert_eq!(t.counts.sent, 10_030);
    }
}
