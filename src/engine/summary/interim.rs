//! The figures of a run so far (`-Q`, SIGQUIT): a snapshot the reporters
//! print mid-run, of the kind's own type ([`Interim`]), apart from the
//! summaries it borrows its parts from.

use super::echo::ResponderSummary;
use super::passive;
use crate::engine::kind::KindValue;
use crate::engine::roster::Identity;
use crate::frame::SysComp;

/// The figures of a run so far, of whichever kind has them.
#[derive(Debug)]
pub struct Interim(Box<dyn KindValue>);

impl Interim {
    pub(crate) fn new(figures: impl KindValue) -> Self {
        Interim(Box::new(figures))
    }

    /// The figures, if their kind's are a `T`.
    pub fn get<T: KindValue>(&self) -> Option<&T> {
        self.0.get()
    }
}

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
