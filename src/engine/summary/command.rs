//! The end of a `--probe command` run: per target, commands sent,
//! acknowledged and failed, the attempts each took, the time to an ACK
//! and the MAV_RESULTs; a shape of its own, unlike the echo summary.

use serde::Serialize;

use crate::engine::answers::AnswerSummary;
use crate::engine::hint::Hint;
use crate::engine::link_node::LinkNodeSummary;
use crate::engine::roster::Identity;
use crate::engine::stats::{Bucket, RttSummary};
use crate::frame::signing::SigningSummary;
use crate::frame::{ScanStats, SysComp};

/// `--probe command`: one target's figures.
#[derive(Debug, Clone, Serialize)]
pub(crate) struct CommandTargetSummary {
    pub(crate) id: SysComp,
    pub(crate) commands: u64,
    pub(crate) acknowledged: u64,
    pub(crate) failed: u64,
    pub(crate) skipped: u64,
    pub(crate) late_acks: u64,
    pub(crate) duplicate_acks: u64,
    /// `attempts[k - 1]`: commands acknowledged after k transmissions.
    pub(crate) attempts: Vec<u64>,
    #[serde(serialize_with = "crate::engine::stats::with_units")]
    pub(crate) time_to_ack: Option<RttSummary>,
    pub(crate) histogram: Vec<Bucket>,
    pub(crate) results: Vec<AckResult>,
    pub(crate) identity: Option<Identity>,
}

/// How many acknowledged commands got one MAV_RESULT.
#[derive(Debug, Clone, Serialize)]
pub(crate) struct AckResult {
    pub(crate) result: u8,
    pub(crate) name: String,
    pub(crate) count: u64,
}

/// The end of a `--probe command` run. Serialised as the JSON
/// `command_summary` line's figures, which the line follows with the link
/// as named (so the run's own is skipped here).
#[derive(Debug, Clone, Serialize)]
pub struct CommandSummary {
    #[serde(skip)]
    pub(crate) link: String,
    pub(crate) ours: SysComp,
    pub(crate) command: u16,
    pub(crate) command_name: String,
    pub(crate) duration_s: f64,
    /// Commands still pending when the run ended: neither acknowledged
    /// nor failed.
    pub(crate) in_flight: u64,
    pub(crate) targets: Vec<CommandTargetSummary>,
    /// Why targets never acknowledged, from what the link heard.
    pub(crate) hints: Vec<Hint>,
    /// ACKs addressed to us for commands we never sent that system.
    pub(crate) unmatched_acks: u64,
    pub(crate) frames: ScanStats,
    pub(crate) interrupted: bool,
    pub(crate) link_error: Option<String>,
    /// What the signing gate accepted and refused, or, without a key, what
    /// came signed unchecked.
    pub(crate) signing: SigningSummary,
    /// The vehicle's TIMESYNC and PING requests answered.
    #[serde(skip_serializing_if = "AnswerSummary::is_none")]
    pub(crate) answered: AnswerSummary,
    /// Nodes heard by their LINK_NODE_STATUS (the vehicle's own view of
    /// the link).
    pub(crate) link_node: Vec<LinkNodeSummary>,
}

impl CommandSummary {
    /// Commands put on the wire, every target's (re-sends not counted).
    pub(crate) fn commands(&self) -> u64 {
        self.targets.iter().map(|t| t.commands).sum()
    }

    pub(crate) fn any_ack(&self) -> bool {
        self.targets.iter().any(|t| t.acknowledged > 0)
    }
}

impl super::KindSummary for CommandSummary {
    fn link(&self) -> &str {
        &self.link
    }
    fn link_error(&self) -> Option<&str> {
        self.link_error.as_deref()
    }
    fn requests(&self) -> (u64, u64) {
        (self.commands(), self.in_flight)
    }
    fn serialized(&self) -> Option<(&'static str, &dyn erased_serde::Serialize)> {
        Some(("command_summary", self))
    }
}
