//! Why requests went unanswered, from what the link showed. Each hint
//! names what was observed (nothing at all, bytes but no frame, signed
//! frames without a key, a vehicle's HEARTBEAT, MAVLink 1 only...), most
//! likely cause first; none is a guess. Pure: the session hands in what it
//! saw.

use std::time::Duration;

use super::hint::{Hint, HintCode};
use super::ignored::{echo_silence, Asked};
use super::radio;
use super::roster::{Roster, Source};
use super::summary::ProbeName;
use super::summary::ResponderSummary;
use crate::frame::signing::SigningCounts;
use crate::frame::{mav_type, ScanStats, SysComp, Version};
use crate::transport::LinkKind;

/// QGroundControl's and Mission Planner's ids, which MAVSDK ground
/// stations drop on receipt (`MavsdkImpl::receive_message`).
pub(crate) const QGC_IDS: SysComp = SysComp::new(255, 190);

/// What a run saw, for its diagnosis.
pub(crate) struct Observed<'a> {
    pub(crate) link: &'a str,
    pub(crate) kind: LinkKind,
    pub(crate) probe: ProbeName,
    pub(crate) ours: SysComp,
    pub(crate) version: Version,
    /// A signing key was given.
    pub(crate) key: bool,
    /// What the signing gate accepted and refused.
    pub(crate) signing: SigningCounts,
    pub(crate) frames: ScanStats,
    /// ICMP "port unreachable" reports the link shrugged off (`udpout:`
    /// with `--reconnect`).
    pub(crate) unreachable: u64,
    pub(crate) roster: &'a Roster,
    pub(crate) responders: &'a [ResponderSummary],
    /// Radios heard by their RADIO_STATUS: no answer is expected of them.
    pub(crate) radios: &'a [SysComp],
    pub(crate) requests: u64,
    /// Requests still within their timeout when the run ended.
    pub(crate) undecided: u64,
    /// How long a request waits for its reply (`-W`).
    pub(crate) timeout: Duration,
    /// A listening link gave up after this long without a peer.
    pub(crate) no_peer_within: Option<Duration>,
    /// The link failed: its error says what happened.
    pub(crate) link_failed: bool,
}

/// Seconds as a person writes them: "2.5 s", "20 s".
pub(crate) fn seconds(d: Duration) -> String {
    let s = format!("{:.3}", d.as_secs_f64());
    let s = s.trim_end_matches('0').trim_end_matches('.');
    format!("{s} s")
}

fn nothing_heard(o: &Observed<'_>) -> Hint {
    let refusals;
    let advice = match o.kind {
        LinkKind::Connecting if o.unreachable > 0 => {
            refusals = format!(
                "no reply, no HEARTBEAT, and {} ICMP \"port unreachable\" in return: nothing \
                 listens on that port; a vehicle, SITL or router that sends to this port needs a \
                 listening link (udp:HOST:PORT)",
                o.unreachable
            );
            &refusals
        }
        LinkKind::Connecting => {
            "no reply, no HEARTBEAT, not even a refusal: check the address and port; a vehicle, \
             SITL or router that sends to this port needs a listening link (udp:HOST:PORT)"
        }
        LinkKind::Listening => {
            "a vehicle, SITL or router must send to this address; one that only listens needs \
             udpout:HOST:PORT"
        }
        LinkKind::Broadcast => "no system on this segment answered or sent anything",
        LinkKind::Serial => {
            "check the wiring, that the device speaks MAVLink, and that nothing else holds the port"
        }
        LinkKind::Simulated => "the simulated link delivered nothing",
        LinkKind::Log => "the log held no frame",
    };
    Hint::new(
        HintCode::NothingHeard,
        format!("nothing heard on {} at all: {advice}", o.link),
    )
}

fn not_mavlink(o: &Observed<'_>) -> Hint {
    let f = &o.frames;
    let baud = if o.kind == LinkKind::Serial {
        "a wrong baud rate, "
    } else {
        ""
    };
    Hint::new(
        HintCode::NotMavlink,
        format!(
            "{} bytes heard on {} but no valid MAVLink frame ({} failed their CRC, {} of them \
             whole frames): {baud}not MAVLink, or a dialect whose messages have other CRCs",
            f.skipped_bytes,
            o.link,
            f.bad_crc + f.damaged,
            f.damaged
        ),
    )
}

fn our_ids_are_qgcs(observed: &str) -> Hint {
    Hint::new(
        HintCode::OurIdsAreQgcs,
        format!(
            "{observed}our ids {QGC_IDS} are QGroundControl's: MAVSDK-based ground stations \
             (mavsdk_server) ignore every frame from them; try --sysid 250"
        ),
    )
}

/// What one silent system's traffic says about its silence, if anything.
fn silent_system(o: &Observed<'_>, id: SysComp, source: &Source) -> Option<Hint> {
    if source.signed > 0 && !o.key {
        return Some(Hint::new(
            HintCode::SignedNoKey,
            format!("frames from {id} are signed and we have no key: pass --signing-key"),
        ));
    }
    let identity = source.identity.as_ref()?;
    let who = format!("{id} ({}, {})", identity.vehicle, identity.autopilot_said());
    // Auto asked an ArduPilot by TIMESYNC alone, anyone else by both.
    let probe = match o.probe {
        ProbeName::Auto if identity.is_ardupilot() => "TIMESYNC".to_string(),
        ProbeName::Auto => "PING or TIMESYNC".to_string(),
        p => p.as_str().to_uppercase(),
    };
    if identity.mav_type == mav_type::GCS {
        if o.ours == QGC_IDS {
            return Some(our_ids_are_qgcs(&format!("{who} never answered: ")));
        }
        let vehicles = o
            .roster
            .iter()
            .any(|(other, i)| *other != o.ours && i.is_vehicle_like());
        if vehicles {
            return None;
        }
        let timesync = if matches!(o.probe, ProbeName::Timesync | ProbeName::Auto) {
            " (MAVProxy answers TIMESYNC with `module load system_time` and \
             --target-system set to our system id)"
        } else {
            ""
        };
        return Some(Hint::new(
            HintCode::GroundStationOnly,
            format!(
                "{who} is a ground station or router: it forwards requests but does not \
                 answer {probe} itself{timesync}, and no vehicle was heard behind it"
            ),
        ));
    }
    if !identity.is_vehicle_like() {
        return None;
    }
    // What its frames show first: a signing clock ahead of ours, frames
    // addressed to another ground station's id.
    let asked = Asked {
        ours: o.ours,
        version: o.version,
        key: o.key,
        what: format!("our {probe} requests"),
        echoes: None,
    };
    if let Some(hint) = echo_silence(o.roster, id, &asked) {
        return Some(hint);
    }
    if source.v1 == source.frames && o.version == Version::V2 {
        return Some(Hint::new(
            HintCode::Mavlink1Only,
            format!("{who} sends MAVLink 1 only and our requests are MAVLink 2: try --mavlink 1"),
        ));
    }
    if identity.is_ardupilot() {
        if o.probe == ProbeName::Ping {
            return Some(Hint::new(
                HintCode::TimesyncOnly,
                format!(
                    "{who} sends HEARTBEAT but never answered PING; ArduPilot answers only \
                     TIMESYNC: try --probe timesync"
                ),
            ));
        }
        if o.ours.sysid != 255 {
            return Some(Hint::new(
                HintCode::SysidEnforced,
                format!(
                    "{who} sends HEARTBEAT but never answered {probe}: with SYSID_ENFORCE=1 \
                     ArduPilot accepts only its ground station's system id (SYSID_MYGCS, \
                     usually 255): try --sysid 255"
                ),
            ));
        }
    }
    Some(Hint::new(
        HintCode::NeverAnswered,
        format!(
            "{who} sends HEARTBEAT but never answered {probe}: a router may not forward our \
             requests to it, or it ignores our ids {}: try --sysid or --compid",
            o.ours
        ),
    ))
}

/// Why replies may be missing when the signing gate refused frames.
fn signing(c: &SigningCounts) -> Vec<Hint> {
    let mut hints = Vec::new();
    if c.rejected_bad_signature > 0 {
        hints.push(Hint::new(
            HintCode::SignedOtherKey,
            format!(
                "{} frames were signed with another key: are both ends using the same signing key?",
                c.rejected_bad_signature
            ),
        ));
    }
    if c.rejected_unsigned > 0 && c.signed == 0 {
        hints.push(Hint::new(
            HintCode::UnsignedRefused,
            format!(
                "{} unsigned frames were refused (--require-signed) and none came signed: \
                 is signing set up on the other end?",
                c.rejected_unsigned
            ),
        ));
    }
    hints
}

fn too_early(o: &Observed<'_>) -> Hint {
    Hint::new(
        HintCode::TooEarly,
        format!(
            "{} still within {} {} timeout when the run ended: too early to tell why nothing \
             has answered (run longer, or -W shorter)",
            match o.requests {
                1 => "the one request was".to_string(),
                n => format!("all {n} requests were"),
            },
            if o.requests == 1 { "its" } else { "their" },
            seconds(o.timeout)
        ),
    )
}

/// A system that answered, but never within the timeout.
fn replies_late(o: &Observed<'_>, r: &ResponderSummary) -> Option<Hint> {
    (r.counts.received == 0 && r.counts.late > 0).then(|| {
        Hint::new(
            HintCode::RepliesLate,
            format!(
                "{}: all {} of its replies came after the {} timeout (counted lost): its round \
                 trip is longer than that; raise -W",
                r.id,
                r.counts.late,
                seconds(o.timeout)
            ),
        )
    })
}

/// Our own frames came back and no other system's: a loopback, not a peer.
fn own_frames_echoed(o: &Observed<'_>) -> Option<Hint> {
    let mut sources = o.roster.sources();
    let (_, own) = sources.find(|(id, _)| **id == o.ours)?;
    let others = o.roster.sources().any(|(id, _)| *id != o.ours);
    let answered = o.responders.iter().any(|r| r.counts.received > 0);
    (!others && !answered).then(|| {
        Hint::new(
            HintCode::OwnFramesEchoed,
            format!(
                "the only frames heard on {} were our own ({} from {}) sent back: a loopback \
                 (a peer that echoes what it gets, a serial adapter with TX wired to RX) and \
                 no other system; check the address or the wiring",
                o.link, own.frames, o.ours
            ),
        )
    })
}

/// Why a command run's targets never acknowledged, from what the link
/// heard: nothing at all or no MAVLink, or other systems than the target.
pub(crate) fn command_hints(o: &Observed<'_>, unacknowledged: &[SysComp]) -> Vec<Hint> {
    let f = &o.frames;
    if unacknowledged.is_empty() || o.no_peer_within.is_some() || o.link_failed {
        return Vec::new();
    }
    if f.frames == 0 {
        let junk = f.skipped_bytes + f.bad_crc + f.damaged + f.truncated > 0;
        return vec![if junk {
            not_mavlink(o)
        } else {
            nothing_heard(o)
        }];
    }
    let heard: Vec<(&SysComp, &crate::engine::roster::Identity)> = o
        .roster
        .iter()
        .filter(|(id, i)| **id != o.ours && i.is_vehicle_like())
        .collect();
    let mut hints: Vec<Hint> = own_frames_echoed(o).into_iter().collect();
    for target in unacknowledged {
        if o.roster.get(*target).is_some() || heard.is_empty() {
            continue;
        }
        let said = |(id, i): &(&SysComp, &crate::engine::roster::Identity)| {
            format!("{id} ({}, {})", i.vehicle, i.autopilot_said())
        };
        let text = match heard.as_slice() {
            [one] => format!(
                "no HEARTBEAT from {target}, the command's target, but {} was heard: try \
                 --target {}",
                said(one),
                one.0
            ),
            many => format!(
                "no HEARTBEAT from {target}, the command's target, but {} were heard: name one \
                 with --target",
                many.iter().map(said).collect::<Vec<_>>().join(", ")
            ),
        };
        hints.push(Hint::new(HintCode::WrongTarget, text));
    }
    hints
}

/// The hints that explain missing replies, most likely first.
pub(crate) fn diagnose(o: &Observed<'_>) -> Vec<Hint> {
    let mut hints = signing(&o.signing);
    if let Some(waited) = o.no_peer_within {
        let mut hint = nothing_heard(o);
        hint.code = HintCode::NoPeerHeard;
        hint.text = format!(
            "no MAVLink system heard on {} in {}",
            o.link,
            seconds(waited)
        );
        hints.push(hint);
        return hints;
    }
    let f = &o.frames;
    if f.frames == 0 && o.link_failed {
        return hints;
    }
    let junk = f.skipped_bytes + f.bad_crc + f.damaged + f.truncated > 0;
    // Answered requests stay undecided until their timeout (a duplicate
    // may follow): too early only while nothing has answered at all.
    let decided = o.requests.saturating_sub(o.undecided);
    let answered_any = o
        .responders
        .iter()
        .any(|r| r.counts.received > 0 || r.counts.late > 0);
    if decided == 0 && o.requests > 0 && !answered_any {
        // Silence proves nothing yet; bytes that are no MAVLink do.
        if f.frames == 0 && junk {
            hints.push(not_mavlink(o));
        }
        hints.push(too_early(o));
        return hints;
    }
    if f.frames == 0 && hints.is_empty() {
        hints.push(if junk {
            not_mavlink(o)
        } else {
            nothing_heard(o)
        });
        if o.ours == QGC_IDS && o.kind != LinkKind::Serial {
            hints.push(our_ids_are_qgcs(""));
        }
        return hints;
    }
    hints.extend(own_frames_echoed(o));
    hints.extend(o.responders.iter().filter_map(|r| replies_late(o, r)));
    let answered = |id: SysComp| {
        o.responders
            .iter()
            .any(|r| r.id == id && (r.counts.received > 0 || r.counts.late > 0))
    };
    let silent: Vec<(&SysComp, &Source)> = o
        .roster
        .sources()
        .filter(|(id, _)| **id != o.ours && !answered(**id))
        // A radio answers no probe: its silence says nothing about the link.
        .filter(|(id, _)| !o.radios.contains(id) && !radio::is_sik_default(**id))
        .collect();
    hints.extend(
        silent
            .into_iter()
            .filter_map(|(&id, source)| silent_system(o, id, source)),
    );
    // The codes are ranked by how directly the evidence explains silence.
    hints.sort_by_key(|h| h.code);
    hints
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::engine::matcher::Counts;

    const ARDUPILOT: (u8, u8) = (2, 3);
    const PX4: (u8, u8) = (2, 12);

    fn observed(roster: &Roster, frames: u64) -> Observed<'_> {
        Observed {
            link: "udpout:127.0.0.1:14550",
            kind: LinkKind::Connecting,
            probe: ProbeName::Ping,
            ours: SysComp::new(250, 190),
            version: Version::V2,
            key: false,
            signing: SigningCounts::default(),
            frames: ScanStats {
                frames,
                ..ScanStats::default()
            },
            unreachable: 0,
            roster,
            responders: &[],
            radios: &[],
            requests: 10,
            undecided: 2,
            timeout: Duration::from_secs(2),
            no_peer_within: None,
            link_failed: false,
        }
    }

    fn codes(hints: &[Hint]) -> Vec<HintCode> {
        hints.iter().map(|h| h.code).collect()
    }

    fn vehicle(
        roster: &mut Roster,
        id: SysComp,
        (mav, autopilot): (u8, u8),
        v: Version,
        signed: bool,
    ) {
        roster.heard(id, mav, autopilot, 0);
        roster.frame(id, v, signed);
    }

    #[test]
    fn nothing_at_all_bytes_but_no_frame_and_qgc_ids() {
        let roster = Roster::default();
        let o = observed(&roster, 0);
        let hints = diagnose(&o);
        assert_eq!(codes(&hints), [HintCode::NothingHeard]);
        assert!(hints[0].text.contains("udp:HOST:PORT"), "{hints:?}");
        assert!(hints[0].text.contains("not even a refusal"), "{hints:?}");
        // With --reconnect the refusals were shrugged off, not unseen.
        let o = Observed {
            unreachable: 3,
            ..observed(&roster, 0)
        };
        let hints = diagnose(&o);
        assert_eq!(codes(&hints), [HintCode::NothingHeard]);
        assert!(
            hints[0]
                .text
                .contains("3 ICMP \"port unreachable\" in return"),
            "{hints:?}"
        );
        assert!(!hints[0].text.contains("not even a refusal"), "{hints:?}");
        let o = Observed {
            ours: QGC_IDS,
            ..observed(&roster, 0)
        };
        assert_eq!(
            codes(&diagnose(&o)),
            [HintCode::NothingHeard, HintCode::OurIdsAreQgcs]
        );
        let o = Observed {
            frames: ScanStats {
                skipped_bytes: 300,
                bad_crc: 4,
                ..ScanStats::default()
            },
            kind: LinkKind::Serial,
            ..observed(&roster, 0)
        };
        let hints = diagnose(&o);
        assert_eq!(codes(&hints), [HintCode::NotMavlink]);
        assert!(hints[0].text.contains("wrong baud rate"), "{hints:?}");
        // A link that failed has its error to say what happened.
        let o = Observed {
            link_failed: true,
            ..observed(&roster, 0)
        };
        assert!(diagnose(&o).is_empty());
    }

    #[test]
    fn a_listening_link_that_gave_up_says_how_long_it_waited() {
        let roster = Roster::default();
        let o = Observed {
            link: "udpin:0.0.0.0:14550",
            kind: LinkKind::Listening,
            no_peer_within: Some(Duration::from_millis(2500)),
            ..observed(&roster, 0)
        };
        let hints = diagnose(&o);
        assert_eq!(codes(&hints), [HintCode::NoPeerHeard]);
        assert_eq!(
            hints[0].text,
            "no MAVLink system heard on udpin:0.0.0.0:14550 in 2.5 s"
        );
    }

    #[test]
    fn each_silent_system_by_what_it_showed() {
        let mut roster = Roster::default();
        vehicle(&mut roster, SysComp::new(8, 1), PX4, Version::V2, true);
        vehicle(&mut roster, SysComp::new(2, 1), PX4, Version::V1, false);
        vehicle(
            &mut roster,
            SysComp::new(3, 1),
            ARDUPILOT,
            Version::V2,
            false,
        );
        vehicle(&mut roster, SysComp::new(4, 1), PX4, Version::V2, false);
        // A ground station and a radio are not expected to answer.
        vehicle(
            &mut roster,
            SysComp::new(245, 190),
            (mav_type::GCS, 8),
            Version::V2,
            false,
        );
        vehicle(&mut roster, SysComp::new(51, 68), PX4, Version::V2, false);
        let hints = diagnose(&observed(&roster, 12));
        assert_eq!(
            codes(&hints),
            [
                HintCode::SignedNoKey,
                HintCode::Mavlink1Only,
                HintCode::TimesyncOnly,
                HintCode::NeverAnswered
            ],
            "{hints:?}"
        );
        assert_eq!(
            hints[0].text,
            "frames from 8/1 are signed and we have no key: pass --signing-key"
        );
        // TIMESYNC unanswered by ArduPilot: its ground-station id check.
        let o = Observed {
            probe: ProbeName::Timesync,
            ..observed(&roster, 12)
        };
        assert!(codes(&diagnose(&o)).contains(&HintCode::SysidEnforced));
    }

    #[test]
    fn a_ground_station_alone_forwards_but_answers_nothing() {
        let mut roster = Roster::default();
        vehicle(
            &mut roster,
            SysComp::new(255, 230),
            (mav_type::GCS, 8),
            Version::V2,
            false,
        );
        let o = Observed {
            probe: ProbeName::Timesync,
            ..observed(&roster, 12)
        };
        let hints = diagnose(&o);
        assert_eq!(codes(&hints), [HintCode::GroundStationOnly]);
        assert!(
            hints[0].text.contains("module load system_time"),
            "{hints:?}"
        );
    }

    #[test]
    fn no_probe_hint_while_every_request_is_in_flight_nor_for_responders() {
        let mut roster = Roster::default();
        vehicle(
            &mut roster,
            SysComp::new(1, 1),
            ARDUPILOT,
            Version::V2,
            false,
        );
        let o = Observed {
            undecided: 10,
            ..observed(&roster, 5)
        };
        assert_eq!(codes(&diagnose(&o)), [HintCode::TooEarly]);
        let responders = [ResponderSummary {
            id: SysComp::new(1, 1),
            counts: Counts {
                sent: 8,
                received: 8,
                ..Counts::default()
            },
            loss_ratio: 0.0,
            rtt: None,
            histogram: vec![],
            identity: None,
            probe: None,
            clock: None,
            direction: None,
            split: None,
        }];
        let o = Observed {
            responders: &responders,
            ..observed(&roster, 5)
        };
        assert!(diagnose(&o).is_empty());
    }

    fn responder(id: SysComp, counts: Counts) -> ResponderSummary {
        ResponderSummary {
            id,
            counts,
            loss_ratio: 1.0,
            rtt: None,
            histogram: vec![],
            identity: None,
            clock: None,
            direction: None,
            split: None,
            probe: None,
        }
    }

    #[test]
    fn too_early_is_said_even_when_nothing_was_heard_and_with_junk_beside_it() {
        let roster = Roster::default();
        let o = Observed {
            undecided: 10,
            ..observed(&roster, 0)
        };
        let hints = diagnose(&o);
        assert_eq!(codes(&hints), [HintCode::TooEarly]);
        assert!(hints[0].text.contains("their 2 s timeout"), "{hints:?}");
        let junk = ScanStats {
            skipped_bytes: 40,
            ..ScanStats::default()
        };
        let o = Observed { frames: junk, ..o };
        assert_eq!(
            codes(&diagnose(&o)),
            [HintCode::NotMavlink, HintCode::TooEarly]
        );
    }

    #[test]
    fn a_responder_whose_replies_all_came_late_is_told_to_raise_the_timeout() {
        let roster = Roster::default();
        let late = Counts {
            sent: 5,
            lost: 5,
            late: 3,
            ..Counts::default()
        };
        let responders = [responder(SysComp::new(1, 1), late)];
        let o = Observed {
            responders: &responders,
            ..observed(&roster, 8)
        };
        let hints = diagnose(&o);
        assert_eq!(codes(&hints), [HintCode::RepliesLate]);
        assert!(hints[0].text.contains("all 3 of its replies"), "{hints:?}");
        // One reply in time: the timeout is not what failed.
        let some = Counts {
            received: 1,
            ..late
        };
        let responders = [responder(SysComp::new(1, 1), some)];
        let o = Observed {
            responders: &responders,
            ..observed(&roster, 8)
        };
        assert!(diagnose(&o).is_empty());
    }

    #[test]
    fn only_our_own_frames_heard_is_a_loopback_and_a_wrong_command_target_is_named() {
        let mut roster = Roster::default();
        let ours = SysComp::new(250, 190);
        roster.heard(ours, 6, 8, 0);
        roster.frame(ours, Version::V2, false);
        let hints = diagnose(&observed(&roster, 12));
        assert_eq!(codes(&hints), [HintCode::OwnFramesEchoed]);
        assert!(
            hints[0].text.contains("our own (1 from 250/190)"),
            "{hints:?}"
        );

        let mut roster = Roster::default();
        vehicle(&mut roster, SysComp::new(7, 1), PX4, Version::V2, false);
        let o = observed(&roster, 12);
        let hints = command_hints(&o, &[SysComp::new(1, 1)]);
        assert_eq!(codes(&hints), [HintCode::WrongTarget]);
        assert!(hints[0].text.contains("try --target 7/1"), "{hints:?}");
        // The target was heard: its silence has other causes.
        assert!(command_hints(&o, &[SysComp::new(7, 1)]).is_empty());
        assert_eq!(
            codes(&command_hints(
                &observed(&Roster::default(), 0),
                &[SysComp::new(1, 1)]
            )),
            [HintCode::NothingHeard]
        );
    }
}
