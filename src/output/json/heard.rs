//! What the link hears, whatever the run: the `responder` line of a
//! system's first HEARTBEAT, the `radio` line, the `waiting` line.

use serde::Serialize;

use super::lines::{Lines, Stamp};
use crate::engine::observe::RadioHeard;
use crate::engine::radio::{Judgement, RadioReport};
use crate::engine::roster::Identity;
use crate::frame::SysComp;

/// `waiting`: nothing to send to yet.
#[derive(Serialize)]
pub(super) struct Waiting {
    r#type: &'static str,
    reason: &'static str,
}

/// `responder`: a system's first HEARTBEAT.
#[derive(Serialize)]
pub(super) struct Heard<'a> {
    #[serde(flatten)]
    stamp: Stamp,
    #[serde(flatten)]
    identity: &'a Identity,
}

/// `radio`: a radio's first RADIO_STATUS, and any report after which
/// its kind changed, with what it is and why.
#[derive(Serialize)]
pub(super) struct Radio<'a> {
    #[serde(flatten)]
    stamp: Stamp,
    status: RadioReport,
    #[serde(flatten)]
    judgement: &'a Judgement,
    first: bool,
}

impl Lines {
    pub(super) fn heard_line<'a>(&self, id: SysComp, identity: &'a Identity) -> Heard<'a> {
        Heard {
            stamp: self.stamp("responder", identity.first_heard, id),
            identity,
        }
    }

    pub(super) fn waiting_line() -> Waiting {
        Waiting {
            r#type: "waiting",
            reason: "no peer heard yet",
        }
    }

    /// The first report of each radio, and one whose kind changed; the
    /// summary has the rest.
    pub(super) fn radio_line<'a>(&self, heard: &RadioHeard<'a>) -> Option<Radio<'a>> {
        (heard.first || heard.kind_changed).then(|| Radio {
            stamp: self.stamp("radio", heard.at, heard.id),
            status: heard.report,
            judgement: heard.judgement,
            first: heard.first,
        })
    }
}
