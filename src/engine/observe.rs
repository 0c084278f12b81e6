//! What a session tells the world while it runs: the engine's own
//! interface. Reports, exporters and tests implement [`Observer`]; the
//! engine names none of them.

use std::io;
use std::sync::Arc;
use std::time::Duration;

use super::clock_offset::ClockSummary;
use super::kind::KindValue;
use super::link_node::LinkNodeReport;
use super::radio::{Judgement, RadioReport};
use super::roster::Identity;
use super::summary::{Interim, ProbeName};
use super::Nanos;
use crate::frame::SysComp;

/// What a run is doing, told first.
#[derive(Debug, Clone)]
pub struct StartInfo {
    pub link: String,
    pub probe: ProbeName,
    pub ours: SysComp,
    pub interval: Duration,
    /// The reply timeout (the retry interval for commands).
    pub timeout: Duration,
    pub count: Option<u64>,
    /// What only this kind of run has, planned before it starts (the
    /// steps of a sweep, the command sent, what a passive run listens to);
    /// `None` for an echo probe at one rate.
    pub plan: Option<Arc<dyn KindValue + Send + Sync>>,
}

impl StartInfo {
    /// The plan, if this run's is a `T`.
    pub fn plan<T: KindValue>(&self) -> Option<&T> {
        let plan: &dyn KindValue = self.plan.as_deref()?;
        plan.get()
    }
}

#[derive(Debug, Clone, Copy)]
pub enum Event<'a> {
    /// What only one kind of run tells, by its own type: an echo probe's
    /// replies and losses, a command's sends and acknowledgements, a step
    /// of a sweep ended, every source's sequence figures so far (once a
    /// second), a telemetry log's timeline.
    Kind(&'a dyn KindValue),
    /// A system's first HEARTBEAT.
    Heard { id: SysComp, identity: &'a Identity },
    /// A RADIO_STATUS (or RADIO) counted.
    Radio(RadioHeard<'a>),
    /// A LINK_NODE_STATUS: a node's own count of the link; `first` for
    /// each node's first report.
    LinkNode {
        id: SysComp,
        at: Nanos,
        report: LinkNodeReport,
        first: bool,
    },
    /// A TIMESYNC responder's clock offset so far: at its first reply,
    /// then at most once a second.
    Clock {
        id: SysComp,
        at: Nanos,
        clock: ClockSummary,
    },
    /// Nothing to send to yet (udpin before a peer is heard).
    WaitingForPeer,
    /// Requests put on the wire so far in this session (PINGs, TIMESYNCs,
    /// commands; re-sends not counted), whoever answers them: told when
    /// the figure changed, at most once a second while the run sends, and
    /// once at its end. A link nobody answers shows in nothing else.
    Progress { at: Nanos, requests: u64 },
    /// The link failed; the session ends (told before its summary, so an
    /// exporter shows it while a run's other links go on).
    LinkFailed { at: Nanos, error: &'a str },
}

impl<'a> Event<'a> {
    /// A kind's own event.
    pub fn of(value: &'a dyn KindValue) -> Self {
        Event::Kind(value)
    }

    /// The kind's own event, if this is one and a `T`.
    pub fn kind<T: KindValue>(&self) -> Option<&'a T> {
        match *self {
            Event::Kind(value) => value.get(),
            _ => None,
        }
    }
}

/// A RADIO_STATUS (or RADIO) counted: `first` for each radio's first
/// report, `kind_changed` when the evidence changed what it is (a
/// HEARTBEAT can tell it without a report: the latest one then).
#[derive(Debug, Clone, Copy)]
pub struct RadioHeard<'a> {
    pub(crate) id: SysComp,
    pub(crate) at: Nanos,
    pub(crate) report: RadioReport,
    /// What the radio is and why, as things stand.
    pub(crate) judgement: &'a Judgement,
    pub(crate) first: bool,
    pub(crate) kind_changed: bool,
}

/// What became of a run's output. The reader's choice to stop reading (a
/// closed pipe, as in `mavping ... | head -1`) is not a failure: the run
/// goes on to its end and its code. Any other write error (a full disk,
/// an I/O error) is: the figures did not reach where they were sent.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub(crate) enum OutputFate {
    #[default]
    Written,
    Closed,
    Failed(String),
}

impl OutputFate {
    /// Notes the outcome of a write; a failure outranks a closed pipe.
    pub(crate) fn note(&mut self, written: &io::Result<()>) {
        let Err(e) = written else {
            return;
        };
        let fate = if e.kind() == io::ErrorKind::BrokenPipe {
            OutputFate::Closed
        } else {
            OutputFate::Failed(e.to_string())
        };
        self.merge(fate);
    }

    /// The worse of the two.
    pub(crate) fn merge(&mut self, other: OutputFate) {
        let rank = |f: &OutputFate| match f {
            OutputFate::Written => 0,
            OutputFate::Closed => 1,
            OutputFate::Failed(_) => 2,
        };
        if rank(&other) > rank(self) {
            *self = other;
        }
    }
}

/// Follows a session. A write error is told back and the run goes on: an
/// output that failed is not written to again (see [`OutputFate`]).
pub trait Observer {
    fn start(&mut self, info: &StartInfo) -> io::Result<()>;
    fn event(&mut self, event: &Event<'_>) -> io::Result<()>;
    /// Pushes buffered output to the reader (called before the session
    /// blocks, and every 50 ms while it is busy).
    fn flush(&mut self) -> io::Result<()> {
        Ok(())
    }
    /// The figures so far (`-Q`, SIGQUIT); the run goes on.
    fn interim(&mut self, _figures: &Interim) -> io::Result<()> {
        Ok(())
    }
}

/// Tells `observer` each event in order. After a write error the rest are
/// still taken (their side effects happen) but not written; the first
/// error is returned.
pub(crate) fn tell_each<'a>(
    observer: &mut dyn Observer,
    events: impl Iterator<Item = Event<'a>>,
) -> io::Result<()> {
    tell_as(observer, events, |event| *event)
}

/// Tells `observer` each of a kind's own events in order, as
/// [`tell_each`] does.
pub(crate) fn tell_kind<T: KindValue>(
    observer: &mut dyn Observer,
    events: impl Iterator<Item = T>,
) -> io::Result<()> {
    tell_as(observer, events, |event| Event::Kind(event))
}

fn tell_as<T>(
    observer: &mut dyn Observer,
    events: impl Iterator<Item = T>,
    as_event: impl Fn(&T) -> Event<'_>,
) -> io::Result<()> {
    let mut result = Ok(());
    for event in events {
        if result.is_ok() {
            result = observer.event(&as_event(&event));
        }
    }
    result
}

/// Follows nothing: for runs whose outcome is all that matters.
pub struct Unobserved;

impl Observer for Unobserved {
    fn start(&mut self, _: &StartInfo) -> io::Result<()> {
        Ok(())
    }
    fn event(&mut self, _: &Event<'_>) -> io::Result<()> {
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_full_disk_outranks_a_closed_pipe_whatever_the_order() {
        let pipe = Err(io::Error::from(io::ErrorKind::BrokenPipe));
        let full = Err(io::Error::from(io::ErrorKind::StorageFull));
        let mut fate = OutputFate::default();
        fate.note(&Ok(()));
        assert_eq!(fate, OutputFate::Written);
        fate.note(&pipe);
        assert_eq!(fate, OutputFate::Closed);
        fate.note(&full);
        assert!(matches!(fate, OutputFate::Failed(_)));
        fate.note(&pipe);
        assert!(matches!(fate, OutputFate::Failed(_)));
    }

    #[test]
    fn probe_names_serialise_as_reports_show_them() {
        for probe in [ProbeName::Ping, ProbeName::Timesync, ProbeName::Command] {
            assert_eq!(serde_json::to_value(probe).unwrap(), probe.as_str());
            assert_eq!(probe.to_string(), probe.as_str());
        }
        assert_eq!(ProbeName::Timesync.as_str(), "timesync");
    }
}
