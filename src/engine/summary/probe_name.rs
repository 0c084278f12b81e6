//! The name a probe goes by in every report ([`ProbeName`]): the one
//! vocabulary the echo, command and passive summaries, the interim
//! figures and the probes themselves share, so it sits apart from each.

use std::fmt;

use serde::Serialize;

/// Which probe a session runs, by the name reports give it (`PING` in
/// text, `"probe": "ping"` in JSON, `probe="ping"` in Prometheus labels).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum ProbeName {
    Ping,
    Timesync,
    /// PING, and TIMESYNC for responders that do not answer PING.
    Auto,
    Command,
    /// No probes: the sequence numbers of what the link carries.
    Passive,
    /// Downloads: every parameter, the mission, a file over FTP.
    Params,
    Mission,
    Ftp,
}

impl ProbeName {
    pub(crate) fn as_str(self) -> &'static str {
        match self {
            ProbeName::Ping => "ping",
            ProbeName::Timesync => "timesync",
            ProbeName::Auto => "auto",
            ProbeName::Command => "command",
            ProbeName::Passive => "passive",
            ProbeName::Params => "params",
            ProbeName::Mission => "mission",
            ProbeName::Ftp => "ftp",
        }
    }
}

impl fmt::Display for ProbeName {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}
