//! What a transfer probe downloads and its policy: whom it asks, how long
//! it waits for an answer before asking again, and how often.

use std::time::Duration;

use serde::Serialize;

use crate::engine::summary::ProbeName;
use crate::frame::SysComp;

/// Which download.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case", tag = "kind")]
pub(crate) enum TransferKind {
    /// Every parameter: PARAM_REQUEST_LIST, then PARAM_REQUEST_READ for
    /// each one the list missed.
    Params,
    /// The mission (MAV_MISSION_TYPE 0): its count, then each item.
    Mission,
    /// A file over MAVLink FTP, read-only.
    Ftp { path: String },
}

impl TransferKind {
    /// The name reports give the probe.
    pub(crate) fn probe_name(&self) -> ProbeName {
        match self {
            TransferKind::Params => ProbeName::Params,
            TransferKind::Mission => ProbeName::Mission,
            TransferKind::Ftp { .. } => ProbeName::Ftp,
        }
    }

    /// What the transfer counts its progress in.
    pub(crate) fn unit(&self) -> &'static str {
        match self {
            TransferKind::Params => "parameters",
            TransferKind::Mission => "items",
            TransferKind::Ftp { .. } => "bytes",
        }
    }
}

/// A transfer probe's plan (`StartInfo::plan`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub(crate) struct TransferSpec {
    #[serde(flatten)]
    pub(crate) kind: TransferKind,
    /// The system (and component, or 0 for the first that answers) asked.
    pub(crate) target: SysComp,
    /// How long a request waits for its answer (and the list for its next
    /// parameter) before it is asked again.
    #[serde(rename = "timeout_ms", serialize_with = "as_ms")]
    pub(crate) timeout: Duration,
    /// Re-sends of one request before the transfer gives it up.
    pub(crate) retries: u8,
    /// Requests for missing pieces in flight at once.
    pub(crate) window: u8,
}

impl crate::engine::kind::KindValue for TransferSpec {
    fn serialized(&self) -> Option<&dyn erased_serde::Serialize> {
        Some(self)
    }
}

#[allow(clippy::trivially_copy_pass_by_ref)] // serde lends the field
fn as_ms<S: serde::Serializer>(d: &Duration, s: S) -> Result<S::Ok, S::Error> {
    s.serialize_u64(d.as_millis() as u64)
}
