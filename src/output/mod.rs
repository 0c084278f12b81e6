//! Reports: the engine hands events and the summary to one [`Reporter`];
//! each output format is one implementation.

pub mod text;

use std::io;
use std::time::Duration;

use crate::config::CommandSpec;
use crate::engine::commands::CommandEvent;
use crate::engine::matcher::MatchEvent;
use crate::engine::roster::Identity;
use crate::engine::summary::{CommandSummary, Summary};
use crate::frame::SysComp;

/// What a run is doing, printed first.
#[derive(Debug, Clone)]
pub struct StartInfo {
    pub link: String,
    pub probe: &'static str,
    pub ours: SysComp,
    pub interval: Duration,
    pub timeout: Duration,
    pub count: Option<u64>,
}

#[derive(Debug, Clone, Copy)]
pub enum Event<'a> {
    Match(MatchEvent),
    /// A system's first HEARTBEAT.
    Heard {
        id: SysComp,
        identity: &'a Identity,
    },
    /// Nothing to send to yet (udpin before a peer is heard).
    WaitingForPeer,
}

/// An output format. Write errors end the run quietly (a closed pipe,
/// as in `mavping ... | head -1`, is not a failure).
pub trait Reporter {
    fn start(&mut self, info: &StartInfo) -> io::Result<()>;
    fn event(&mut self, event: &Event<'_>) -> io::Result<()>;
    fn summary(&mut self, summary: &Summary) -> io::Result<()>;
}

/// An output format for `--probe command`, whose events and summary differ
/// from the echo probes'.
pub trait CommandReporter {
    fn command_start(&mut self, info: &StartInfo, spec: &CommandSpec) -> io::Result<()>;
    fn command_event(&mut self, event: &CommandEvent) -> io::Result<()>;
    fn command_summary(&mut self, summary: &CommandSummary) -> io::Result<()>;
}
