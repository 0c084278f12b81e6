//! How the responder behaves ([`ResponderSettings`], validated by the
//! configuration) and the line that says so when it starts.

use std::time::Duration;

use crate::answering::transfers::ServeSpec;
use crate::frame::signing::SigningConfig;
use crate::frame::SysComp;
use crate::telemetry::StreamSpec;

/// How the responder behaves, already validated.
#[derive(Debug, Clone)]
pub(crate) struct ResponderSettings {
    pub(crate) id: SysComp,
    /// Every reply is held this long, plus up to `jitter`.
    pub(crate) delay: Duration,
    pub(crate) jitter: Duration,
    /// Shares of replies dropped and duplicated, 0..=1.
    pub(crate) drop: f64,
    pub(crate) dup: f64,
    pub(crate) seed: u64,
    pub(crate) answer_ping: bool,
    /// With a key: replies signed, requests checked (all must be signed).
    pub(crate) signing: Option<SigningConfig>,
    /// Telemetry sent to every peer unasked; a HEARTBEAT stream sets the
    /// rate of our HEARTBEAT (1 Hz without).
    pub(crate) streams: Vec<StreamSpec>,
    /// Share of streamed frames numbered, then not sent: the gap a lost
    /// frame leaves in our sequence numbers.
    pub(crate) stream_drop: f64,
    /// The parameters, mission and file served (`--params`, `--mission`,
    /// `--file-size`), and the most transfer frames sent a second.
    pub(crate) serve: ServeSpec,
    pub(crate) transfer_rate: f64,
}

/// Who we are, for the first line.
pub(crate) fn describe(settings: &ResponderSettings, link_name: &str) -> String {
    let SysComp { sysid, compid } = settings.id;
    let what = if settings.answer_ping {
        "PING, TIMESYNC and COMMAND_LONG"
    } else {
        "TIMESYNC and COMMAND_LONG (not PING)"
    };
    let signed = if settings.signing.is_some() {
        " (signed requests only)"
    } else {
        ""
    };
    let streaming = if settings.streams.is_empty() {
        String::new()
    } else {
        let streams: Vec<String> = settings.streams.iter().map(ToString::to_string).collect();
        format!(", streaming {}", streams.join(", "))
    };
    format!(
        "mavping respond: {sysid}/{compid} on {link_name}, answering {what}{signed}{streaming}; \
         serving {}",
        serving(settings)
    )
}

/// What the transfers serve, and how fast.
fn serving(settings: &ResponderSettings) -> String {
    let ServeSpec {
        params,
        mission,
        file_size,
    } = settings.serve;
    format!(
        "{params} parameters, a {mission}-item mission and {} ({file_size} bytes) by FTP, \
         at up to {} frames/s",
        crate::answering::ftp::SERVED_PATH,
        settings.transfer_rate
    )
}
