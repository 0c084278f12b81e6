//! The end of one link's run, whichever kind ran it ([`LinkSummary`]):
//! the one value the run hands the reports. Each kind's summary is its
//! own type ([`KindSummary`]); what every kind answers alike is asked
//! here, the rest read by type.

use std::any::Any;
use std::fmt::Debug;

use crate::engine::c2::C2Report;
use crate::engine::capacity::WireBudget;

/// What every kind of run's summary answers alike.
pub trait KindSummary: Any + Debug + Send + Sync {
    /// The link's name.
    fn link(&self) -> &str;
    /// Why the link failed, if it did.
    fn link_error(&self) -> Option<&str>;
    /// Requests put on the wire (commands, re-sends not counted), and
    /// those still within their timeout at the end. A kind that sends
    /// nothing has none.
    fn requests(&self) -> (u64, u64) {
        (0, 0)
    }
    /// The serial link's wire budget, judged against the finished figures
    /// by a kind whose figures it explains.
    fn apply_wire(&mut self, _budget: WireBudget) {}
    /// The summary as it is written whole, and the name it goes by there
    /// (the command probe's: its JSON `command_summary` line's figures),
    /// so a format can write a kind it has no code for.
    fn serialized(&self) -> Option<(&'static str, &dyn erased_serde::Serialize)> {
        None
    }
}

/// The end of one link's run, of whichever kind, and the C2 link report
/// over it when one was asked for (`--report c2`): any kind's run has one.
#[derive(Debug)]
pub struct LinkSummary(Box<dyn KindSummary>, Option<Box<C2Report>>);

impl LinkSummary {
    pub(crate) fn new(summary: impl KindSummary) -> Self {
        LinkSummary(Box::new(summary), None)
    }

    /// The C2 link report, if the run made one.
    pub(crate) fn c2(&self) -> Option<&C2Report> {
        self.1.as_deref()
    }

    pub(crate) fn c2_mut(&mut self) -> Option<&mut C2Report> {
        self.1.as_deref_mut()
    }

    pub(crate) fn set_c2(&mut self, report: C2Report) {
        self.1 = Some(Box::new(report));
    }

    /// The summary, if its kind's is a `T`.
    pub fn get<T: KindSummary>(&self) -> Option<&T> {
        (&*self.0 as &dyn Any).downcast_ref()
    }

    pub(crate) fn get_mut<T: KindSummary>(&mut self) -> Option<&mut T> {
        (&mut *self.0 as &mut dyn Any).downcast_mut()
    }

    /// The summary as every kind's is.
    pub(crate) fn kind(&self) -> &dyn KindSummary {
        &*self.0
    }

    pub(crate) fn link(&self) -> &str {
        self.0.link()
    }

    pub(crate) fn link_error(&self) -> Option<&str> {
        self.0.link_error()
    }

    /// See [`KindSummary::requests`].
    pub(crate) fn requests(&self) -> (u64, u64) {
        self.0.requests()
    }

    /// See [`KindSummary::apply_wire`].
    pub(crate) fn apply_wire(&mut self, budget: WireBudget) {
        self.0.apply_wire(budget);
    }
}
