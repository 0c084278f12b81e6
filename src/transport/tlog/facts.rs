//! What a log held and how far it was read ([`LogFacts`]): what the run
//! puts in the passive summary, apart from the link that gathers it.

use serde::Serialize;

use super::records::RecordStats;
use super::stamps::StampFacts;

/// What a log held and how far it was read, for the summary.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub(crate) struct LogFacts {
    pub(crate) records: RecordStats,
    pub(crate) stamps: StampFacts,
    /// The run read the log to its end (not stopped by `-w` or Ctrl-C).
    pub(crate) complete: bool,
}
