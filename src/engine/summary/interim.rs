//! The figures of a run so far (`-Q`, SIGQUIT): a snapshot the reporters
//! print mid-run, of the kind's own type ([`Interim`]; the echo probes'
//! `EchoInterim` beside their summary, a passive run's `PassiveInterim`
//! beside its).

use crate::engine::kind::KindValue;

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
