//! The end of one link's run, whichever probe ran it ([`LinkSummary`]):
//! the one value the run hands the reports, dispatching to the echo,
//! command or passive summary.

use super::command::CommandSummary;
use super::echo::EchoSummary;
use super::passive;

/// The end of one link's run, by probe kind.
#[derive(Debug, Clone)]
pub enum LinkSummary {
    /// PING or TIMESYNC.
    Echo(Box<EchoSummary>),
    /// COMMAND_LONG until acknowledged.
    Command(Box<CommandSummary>),
    /// `--passive`: no probes, the sources' own sequence numbers.
    Passive(Box<passive::PassiveSummary>),
}

impl LinkSummary {
    pub(crate) fn link(&self) -> &str {
        match self {
            LinkSummary::Echo(s) => &s.link,
            LinkSummary::Command(s) => &s.link,
            LinkSummary::Passive(s) => &s.link,
        }
    }

    pub(crate) fn link_error(&self) -> Option<&str> {
        match self {
            LinkSummary::Echo(s) => s.link_error.as_deref(),
            LinkSummary::Command(s) => s.link_error.as_deref(),
            LinkSummary::Passive(s) => s.link_error.as_deref(),
        }
    }

    /// Requests put on the wire (commands, re-sends not counted), and
    /// those still within their timeout at the end: what every kind of
    /// run counts alike. A passive run sends none.
    pub(crate) fn requests(&self) -> (u64, u64) {
        match self {
            LinkSummary::Echo(s) => (s.requests, s.in_flight),
            LinkSummary::Command(s) => (s.commands(), s.in_flight),
            LinkSummary::Passive(_) => (0, 0),
        }
    }
}
