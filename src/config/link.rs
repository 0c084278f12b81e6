//! One link of a run, as the command line and the server both give it.

use crate::engine::SessionConfig;
use crate::transport::address::LinkSpec;
use crate::verdict::Thresholds;

/// One link of a run.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct LinkConfig {
    pub(crate) spec: LinkSpec,
    /// The connection string as typed: with several links, reply lines,
    /// error lines and exports are labelled with it.
    pub(crate) name: String,
    /// Its session; `link_name` is the form reports head the run with
    /// (the link's full form alone, or the name beside others).
    pub(crate) session: SessionConfig,
    /// Every link's thresholds, and the responders `--expect` wants here.
    pub(crate) thresholds: Thresholds,
}
