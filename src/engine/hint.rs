//! A hint: what the summary suggests, with a stable code scripts can
//! branch on, and the sentence a person reads. Every hint names what was
//! observed; none is a guess.

use serde::Serialize;

/// The stable, machine-readable kinds of hint (listed in the JSON schema).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Serialize)]
#[serde(rename_all = "snake_case")]
pub(crate) enum HintCode {
    /// A listening link heard no MAVLink system before it gave up.
    NoPeerHeard,
    /// Nothing at all came back on the link.
    NothingHeard,
    /// Bytes came, but no valid MAVLink frame.
    NotMavlink,
    /// Our ids are QGroundControl's, which MAVSDK ground stations ignore.
    OurIdsAreQgcs,
    /// A system's frames are signed and we have no key.
    SignedNoKey,
    /// Frames signed with another key than ours were refused.
    SignedOtherKey,
    /// Unsigned frames were refused (`--require-signed`) and none came signed.
    UnsignedRefused,
    /// Our signing clock is more than a minute behind the target's newest
    /// signature timestamp: it refuses our signed frames as too old.
    SigningClockBehind,
    /// A system speaks MAVLink 1 only; our requests are MAVLink 2.
    Mavlink1Only,
    /// An ArduPilot vehicle never answered PING: it answers only TIMESYNC.
    TimesyncOnly,
    /// A vehicle accepts only its ground station's system id: an ArduPilot
    /// that never answered (SYSID_ENFORCE), or a target whose frames were
    /// addressed to another system and never to us.
    SysidEnforced,
    /// A system sends but never answered: a router may not forward our
    /// requests, or it ignores our ids. For a command or a download: it
    /// answered nothing of ours at all, and none of its frames showed why.
    NeverAnswered,
    /// Only a ground station or router was heard (MAVProxy,
    /// mavlink-router): it forwards, but answers nothing itself, and no
    /// vehicle was heard behind it.
    GroundStationOnly,
    /// Every request was still within its timeout when the run ended.
    TooEarly,
    /// Loss concentrated while the radio's transmit buffer was low.
    RadioOverloaded,
    /// A radio's fade margin fell below a safe level.
    RadioWeakSignal,
    /// A radio's receive errors grew during the run.
    RadioErrors,
    /// The rate was above what the serial link's baud rate carries, and the
    /// run shows it.
    WireOverrun,
    /// Replies came back faster than the baud rate allows: the device
    /// ignores it (USB CDC, a pty).
    BaudNotInEffect,
    /// The device may ignore the baud rate (a pty, USB CDC) and the replies
    /// were too slow to show whether it did: the wire figures are unproven.
    BaudUnverified,
    /// A responder's causal clock-offset bounds do not intersect.
    ClockInconsistent,
    /// The link refused requests: its peer is not reading what we send.
    LinkNotReading,
    /// A system's replies all came after the timeout: the round trip is
    /// longer than `-W` allows.
    RepliesLate,
    /// The only frames heard were our own, sent back (a loopback).
    OwnFramesEchoed,
    /// A command's target was never heard, another system was.
    WrongTarget,
    /// A vehicle's own count of what it lost on the way to it
    /// (LINK_NODE_STATUS) is outside mavping's uplink estimate for it.
    VehicleUplinkDisagrees,
    /// A source's frames arrived ever later, by their own clock stamps,
    /// while it lost next to none: a queue delays what it does not drop.
    QueueBuilding,
    /// A download's opening request was never answered.
    TransferNoAnswer,
    /// A download stopped coming and asking again did not finish it.
    TransferStalled,
    /// The vehicle refused a download (a NAK, a MISSION_ACK error).
    TransferRefused,
    /// A download's list stopped by itself before its end.
    TransferListStopped,
    /// The first passes lost far more than the re-requests.
    TransferLoadLoss,
}

#[derive(Debug, Clone, PartialEq, Serialize)]
pub(crate) struct Hint {
    pub(crate) code: HintCode,
    pub(crate) text: String,
}

impl Hint {
    pub(crate) fn new(code: HintCode, text: impl Into<String>) -> Self {
        Hint {
            code,
            text: text.into(),
        }
    }
}
