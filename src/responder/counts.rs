//! The ground truth printed on exit ([`RespondCounts`]): requests
//! answered, replies sent, dropped and duplicated, and each stream's
//! frames, to hold a pinger's figures against.

use serde::Serialize;

use crate::answering::transfers::ServedCounts;
use crate::answering::ResponderCounts;
use crate::frame::signing::SigningCounts;

/// What one `--stream` sent.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub(crate) struct StreamCount {
    pub(crate) message: &'static str,
    /// Frames written to the link.
    pub(crate) sent: u64,
    /// Frames numbered but dropped by `--stream-drop`.
    pub(crate) dropped: u64,
}

/// Ground truth printed on exit, to hold a pinger's figures against.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize)]
pub(crate) struct RespondCounts {
    pub(crate) requests: ResponderCounts,
    pub(crate) replies_sent: u64,
    pub(crate) dropped: u64,
    pub(crate) duplicated: u64,
    /// Replies dropped because too many were held by `--delay`.
    pub(crate) overflow: u64,
    /// With a signing key: frames accepted and refused by signature.
    pub(crate) signing: Option<SigningCounts>,
    /// With `--stream`: each stream's frames, in the order given.
    pub(crate) streamed: Vec<StreamCount>,
    /// The transfers served: requests, frames sent and dropped by kind.
    pub(crate) served: ServedCounts,
}

impl std::fmt::Display for RespondCounts {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let r = &self.requests;
        write!(
            f,
            "{} requests ({} ping, {} timesync, {} command, {} command retransmissions), \
             {} replies sent, {} dropped, {} duplicated",
            r.requests(),
            r.ping_requests,
            r.timesync_requests,
            r.commands,
            r.retransmissions,
            self.replies_sent,
            self.dropped,
            self.duplicated
        )?;
        if self.overflow > 0 {
            write!(f, ", {} dropped (too many held)", self.overflow)?;
        }
        if !self.streamed.is_empty() {
            let each: Vec<String> = self
                .streamed
                .iter()
                .map(|s| format!("{} {}", s.sent, s.message))
                .collect();
            write!(
                f,
                "; {} frames streamed ({}), {} dropped by --stream-drop",
                self.streamed.iter().map(|s| s.sent).sum::<u64>(),
                each.join(", "),
                self.streamed.iter().map(|s| s.dropped).sum::<u64>()
            )?;
        }
        let served = &self.served;
        if served.requests.total() > 0 {
            write!(f, "; {served}")?;
        }
        if let Some(signing) = &self.signing {
            write!(f, "; signing: {signing}")?;
        }
        Ok(())
    }
}
