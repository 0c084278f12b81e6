//! The figures of a run so far (`-Q`, SIGQUIT), by the kind of run that
//! has them: a snapshot the reporters print mid-run, apart from the
//! summaries it borrows its parts from.

use super::echo::ResponderSummary;
use super::passive;
use crate::engine::roster::Identity;
use crate::frame::SysComp;

/// The figures of a run so far (`-Q`, SIGQUIT), by the kind of run that
/// has them.
#[derive(Debug, Clone)]
pub enum Interim {
    /// An echo probe's (PING, TIMESYNC, and a sweep's steps).
    Echo(EchoInterim),
    /// A `--passive` run's.
    Passive(PassiveInterim),
}

impl Interim {}

/// An echo run so far: each responder's counts of decided requests and
/// its RTT figures.
#[derive(Debug, Clone)]
pub struct EchoInterim {
    /// Session time, ns.
    pub(crate) at: crate::engine::Nanos,
    pub(crate) requests: u64,
    pub(crate) responders: Vec<ResponderSummary>,
}

/// A passive run so far: every source's sequence figures (cumulative), as
/// the summary will give them.
#[derive(Debug, Clone)]
pub struct PassiveInterim {
    /// Session time, ns.
    pub(crate) at: crate::engine::Nanos,
    pub(crate) table: passive::TableSummary,
    /// What each source said it is, from its HEARTBEAT.
    pub(crate) identities: Vec<(SysComp, Identity)>,
}
