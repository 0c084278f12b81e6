//! The pair report of a run (issue 41): every link's received frames go
//! to one [`PairTracker`] on one clock as the links run, and its report
//! follows the links' summaries. A tracker's "link" is one way frames
//! came: a link of the command line, or one path of a link that tells
//! several apart (a MAVProxy telemetry log's link numbers, a simulated
//! vehicle's paths). The run's links share one thread, so one tracker
//! behind a `RefCell` serves them all.

use std::cell::RefCell;
use std::collections::BTreeMap;
use std::io::{self, Write};
use std::rc::Rc;

use tokio::time::Instant;

use crate::cli::Format;
use crate::config::{LinkConfig, Probe};
use crate::engine::pair::matrix::Matrix;
use crate::engine::pair::merge::{TimeMerge, DEFAULT_CAP, DEFAULT_HOLD};
use crate::engine::pair::{Heard, PairConfig, PairSummary, PairTracker, MAX_LINKS};
use crate::engine::Nanos;
use crate::frame::{self, Msg};
use crate::output::live::LiveView;
use crate::output::pair as report;
use crate::output::prometheus;
use crate::transport::recording::Watch;
use crate::transport::tlog::writer::SENT;
use crate::transport::{Inbound, LinkSpec, PathId};

/// One way frames came: a link's place on the command line and a path.
type Way = (usize, PathId);

/// The trackers and what their links are.
struct Shared {
    /// TIMESYNC requests out on each link, replies heard on each.
    matrix: Matrix,
    /// The same of PING requests, for a vehicle that answers them.
    ping_matrix: Matrix,
    /// The same from each telemetry log (by its place) whose logger sent
    /// TIMESYNC requests, as MAVProxy's `ping` does: its links are its
    /// paths, each request's out-link in its `ts1`'s low four bits.
    log_matrices: BTreeMap<usize, Matrix>,
    /// The timeout of a request, for the logs' matrices.
    timeout: Nanos,
    /// Every way apart: a link's paths too.
    by_way: PairTracker,
    /// `by_way`'s links, in the order first heard.
    ways: Vec<Way>,
    /// The links of the command line, their paths together: for when a
    /// link's paths turn out not to be ways (a telemetry log whose stamps'
    /// low bits are a clock's, not MAVProxy's link numbers; known only
    /// once the whole log is read), and a simulated link's paths drawn as
    /// one. Kept only where a link's paths may be several.
    by_link: Option<PairTracker>,
    /// Each link's frames until they leave in the order they came (by
    /// place; with their way).
    merge: TimeMerge<(usize, Heard)>,
}

impl Shared {
    /// Matches the frames that may leave the merge, in the order they
    /// came; all of them when `all` (nothing more will come).
    fn take(&mut self, all: bool) {
        loop {
            let next = if all {
                self.merge.pop_any()
            } else {
                self.merge.pop_ready()
            };
            let Some((place, at, (way, heard))) = next else {
                return;
            };
            self.by_way.on_heard(way, heard, at);
            if let Some(by_link) = &mut self.by_link {
                by_link.on_heard(place, heard, at);
            }
        }
    }

    /// The report so far with a link's paths together: `by_link`'s, or
    /// `by_way`'s for the links with one way each (its ways by place).
    fn by_link(&self, at: Nanos) -> PairSummary {
        if let Some(by_link) = &self.by_link {
            return by_link.summary(at);
        }
        let mut summary = self.by_way.summary(at);
        let place = |way: usize| {
            let (place, _) = self.ways[way];
            let alone = self.ways.iter().filter(|w| w.0 == place).count() == 1;
            alone.then_some(place)
        };
        for source in &mut summary.sources {
            source
                .links
                .retain_mut(|l| place(l.link).map(|p| l.link = p).is_some());
        }
        summary
    }

    /// The tracker's index of `way`, given one when first heard (none
    /// beyond the tracker's links: their frames are counted untracked).
    fn index(&mut self, way: Way) -> usize {
        match self.ways.iter().position(|&w| w == way) {
            Some(k) => k,
            None if self.ways.len() < MAX_LINKS => {
                self.ways.push(way);
                self.ways.len() - 1
            }
            None => MAX_LINKS,
        }
    }
}

/// The run's tracker and the clock its links share.
pub(super) struct Pairs {
    shared: Rc<RefCell<Shared>>,
    origin: Instant,
    /// Several links: requests may go out on one and come back on
    /// another (one link's requests come back on it: nothing to match).
    several: bool,
    /// Our PING requests carry their link in `time_usec` (`--probe ping`):
    /// only then are they told apart across links.
    ping: bool,
}

/// One link's way into the tracker.
struct LinkWatch {
    shared: Rc<RefCell<Shared>>,
    place: usize,
    origin: Instant,
    /// Added to its frames' times: a log's start after the first log's.
    shift: Nanos,
    /// A telemetry log: what its logger sent is among its frames.
    log: bool,
    /// Whether our requests and their replies are matched across links.
    matrix: bool,
    /// Whether our PING requests are too.
    ping: bool,
}

/// The path MAVProxy (and mavping's `--tlog`) logs its own frames on.
const LOGGER_PATH: PathId = SENT as PathId;

impl LinkWatch {
    /// A TIMESYNC in a log: the logger's request (on its own path; its
    /// out-link in the low four bits of `ts1`, as MAVProxy's `ping` puts
    /// it), or a reply heard on one of the log's links.
    fn logged_timesync(&self, shared: &mut Shared, path: PathId, tc1: i64, ts1: i64, at: Nanos) {
        let timeout = shared.timeout;
        let matrix = shared
            .log_matrices
            .entry(self.place)
            .or_insert_with(|| Matrix::new(timeout));
        match (path == LOGGER_PATH, tc1 == 0) {
            (true, true) => matrix.on_request((ts1 & 0xF) as usize, ts1 as u64, at),
            (false, false) => matrix.on_reply(path as usize, ts1 as u64, at),
            // Its answers to the vehicle's requests, and those requests.
            _ => {}
        }
    }
}

/// Nanoseconds from `origin` to `at` (0 before it).
fn since(origin: Instant, at: Instant) -> Nanos {
    at.saturating_duration_since(origin).as_nanos() as Nanos
}

impl Watch for LinkWatch {
    fn received(&self, inbound: &[Inbound]) {
        let mut shared = self.shared.borrow_mut();
        for i in inbound {
            let at = since(self.origin, i.at) + self.shift;
            let way = shared.index((self.place, i.path));
            shared
                .merge
                .push(self.place, at, (way, Heard::of(&i.frame)));
            match i.frame.msg {
                Msg::Timesync { tc1, ts1, .. } if self.log => {
                    self.logged_timesync(&mut shared, i.path, tc1, ts1, at);
                }
                Msg::Timesync { tc1, ts1, .. } if self.matrix && tc1 != 0 => {
                    shared.matrix.on_reply(self.place, ts1 as u64, at);
                }
                // A reply names the requester; a request names no one.
                Msg::Ping {
                    time_usec,
                    seq,
                    target_system,
                    target_component,
                } if self.ping && (target_system, target_component) != (0, 0) => {
                    let key = ping_key(time_usec, seq);
                    shared.ping_matrix.on_reply(self.place, key, at);
                }
                _ => {}
            }
        }
        shared.take(false);
    }

    fn sent(&self, at: Instant, frame: &[u8]) {
        // Our TIMESYNC and PING requests only: decoding every frame we
        // send would cost the runs for nothing.
        if !self.matrix || frame.len() < 10 || !is_request(frame) {
            return;
        }
        let at = since(self.origin, at);
        let mut shared = self.shared.borrow_mut();
        match frame::decode(frame).msg {
            Msg::Timesync { tc1: 0, ts1, .. } => {
                shared.matrix.on_request(self.place, ts1 as u64, at);
            }
            Msg::Ping {
                time_usec,
                seq,
                target_system: 0,
                target_component: 0,
            } if self.ping => {
                let key = ping_key(time_usec, seq);
                shared.ping_matrix.on_request(self.place, key, at);
            }
            _ => {}
        }
    }
}

/// A PING exchange's key: its `time_usec` (a µs clock, below 2^56 for
/// two millennia) and `seq`, both echoed by the reply.
fn ping_key(time_usec: u64, seq: u32) -> u64 {
    time_usec.wrapping_shl(8) ^ u64::from(seq & 0xFF)
}

/// Whether `raw` is a TIMESYNC or PING frame by its header's message id
/// (MAVLink 1: one byte at 5; 2: three at 7).
fn is_request(raw: &[u8]) -> bool {
    const TIMESYNC: u32 = 111;
    const PING: u32 = 4;
    let id = match raw[0] {
        0xFE => u32::from(raw[5]),
        0xFD => u32::from_le_bytes([raw[7], raw[8], raw[9], 0]),
        _ => return false,
    };
    id == TIMESYNC || id == PING
}

impl Pairs {
    /// A tracker for a run over `links`, when frames of one source can
    /// come more than one way: several links, or a link whose paths are
    /// told apart (a telemetry log's MAVProxy link numbers, the simulated
    /// link). One link of another kind has nothing to pair, and pays
    /// nothing per frame.
    pub(super) fn of(links: &[LinkConfig], probe: &Probe) -> Option<Self> {
        let timeout = links
            .iter()
            .map(|l| l.session.timeout.as_nanos() as Nanos)
            .max()
            .unwrap_or(0);
        let paths = links
            .iter()
            .any(|l| matches!(l.spec, LinkSpec::Tlog(_) | LinkSpec::Sim(_)));
        let ways = links.len() > 1 || paths;
        ways.then(|| Pairs {
            shared: Rc::new(RefCell::new(Shared {
                matrix: Matrix::new(timeout),
                ping_matrix: Matrix::new(timeout),
                log_matrices: BTreeMap::new(),
                timeout,
                by_way: PairTracker::new(MAX_LINKS, PairConfig::default()),
                ways: Vec::new(),
                by_link: paths.then(|| PairTracker::new(links.len(), PairConfig::default())),
                merge: TimeMerge::new(links.len(), DEFAULT_HOLD, DEFAULT_CAP),
            })),
            origin: Instant::now(),
            several: links.len() > 1,
            ping: matches!(probe, Probe::Ping),
        })
    }

    /// What the link at `place` on the command line tells the tracker by,
    /// its frames' times shifted by `shift` (a log that began later than
    /// the run's first); `log` when it is a telemetry log.
    pub(super) fn watch(
        &self,
        place: usize,
        shift: std::time::Duration,
        log: bool,
    ) -> Rc<dyn Watch> {
        Rc::new(LinkWatch {
            shared: self.shared.clone(),
            place,
            origin: self.origin,
            shift: shift.as_nanos() as Nanos,
            log,
            matrix: self.several,
            ping: self.several && self.ping,
        })
    }

    /// The report so far as exposition text (`--prometheus`), every way
    /// apart (a log's are known to be links only at its end).
    pub(super) fn metrics(&self, names: &[&str]) -> String {
        let shared = self.shared.borrow();
        let summary = shared.by_way.summary(since(self.origin, Instant::now()));
        let ways = way_names(&shared.ways, names);
        let ways: Vec<&str> = ways.iter().map(String::as_str).collect();
        prometheus::render_pair(&summary, &ways)
    }

    /// The report so far, a link's paths together, and when.
    pub(super) fn by_link_now(&self) -> (Nanos, PairSummary) {
        let now = since(self.origin, Instant::now());
        (now, self.shared.borrow().by_link(now))
    }

    /// Matches every frame still held: the links have ended.
    pub(super) fn finish(&self) {
        self.shared.borrow_mut().take(true);
    }

    /// The report so far in the live view, every way apart.
    pub(super) fn show(&self, names: &[&str], view: &LiveView) {
        let shared = self.shared.borrow();
        let now = since(self.origin, Instant::now());
        let summary = shared.by_way.summary(now);
        let ways = way_names(&shared.ways, names);
        let ways: Vec<&str> = ways.iter().map(String::as_str).collect();
        view.show_pair(&summary, &ways, now);
    }

    /// Writes the report in `format` when a source was heard two ways or
    /// more (`names`: the links by place; `paths_are_ways`: whether each
    /// link's paths are ways of their own), and the matrix when requests
    /// went out on two links or more and came back; flushes.
    pub(super) fn write(
        &self,
        format: Format,
        names: &[&str],
        paths_are_ways: &[bool],
        out: &mut impl Write,
    ) -> io::Result<()> {
        self.finish();
        let shared = self.shared.borrow();
        let by_way = paths_are_ways.iter().all(|&w| w);
        let (tracker, ways) = match &shared.by_link {
            Some(by_link) if !by_way => {
                let links = names.iter().map(|n| n.to_string()).collect();
                (by_link, links)
            }
            _ => (&shared.by_way, way_names(&shared.ways, names)),
        };
        // The links have ended: no copy can come, every window is closed.
        let summary = tracker.summary(Nanos::MAX);
        let ways: Vec<&str> = ways.iter().map(String::as_str).collect();
        if !summary.sources.is_empty() {
            match format {
                Format::Json => report::write_json(out, &summary, &ways)?,
                Format::Text => report::write_text(out, &summary, &ways)?,
            }
        }
        write_matrix(format, "TIMESYNC", &shared.matrix, names, out)?;
        write_matrix(format, "PING", &shared.ping_matrix, names, out)?;
        // A log's, when its paths are MAVProxy's links.
        for (&place, matrix) in &shared.log_matrices {
            if !paths_are_ways.get(place).copied().unwrap_or(false) {
                continue;
            }
            let name = names.get(place).copied().unwrap_or("?");
            let paths: Vec<String> = (0..MAX_LINKS).map(|k| format!("{name} path {k}")).collect();
            let paths: Vec<&str> = paths.iter().map(String::as_str).collect();
            write_matrix(format, "TIMESYNC", matrix, &paths, out)?;
        }
        out.flush()
    }
}

/// Writes `matrix` in `format`, its links named by `names`, when requests
/// went out on two links or more and a reply came back on another.
fn write_matrix(
    format: Format,
    message: &str,
    matrix: &Matrix,
    names: &[&str],
    out: &mut impl Write,
) -> io::Result<()> {
    let matrix = matrix.summary();
    // A reply heard on another link than its request's: else each
    // link's summary has said it all.
    if matrix.requests.len() < 2 || matrix.cells.iter().all(|c| c.out == c.back) {
        return Ok(());
    }
    match format {
        Format::Json => report::write_matrix_json(out, message, &matrix, names),
        Format::Text => report::write_matrix_text(out, message, &matrix, names),
    }
}

/// Each way's name: its link's, with its path when that link came more
/// than one way (`flight.tlog path 1`).
fn way_names(ways: &[Way], names: &[&str]) -> Vec<String> {
    ways.iter()
        .map(|&(place, path)| {
            let name = names.get(place).copied().unwrap_or("?");
            if ways.iter().filter(|w| w.0 == place).count() > 1 {
                format!("{name} path {path}")
            } else {
                name.to_string()
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ways_are_named_by_their_link_and_path_only_when_it_has_several() {
        let ways = [(0, 0), (1, 0), (0, 1)];
        assert_eq!(
            way_names(&ways, &["flight.tlog", "udp:0.0.0.0:14550"]),
            [
                "flight.tlog path 0",
                "udp:0.0.0.0:14550",
                "flight.tlog path 1"
            ]
        );
    }
}
