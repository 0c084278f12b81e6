//! Why a target we hear well ignores what we send: a command never
//! acknowledged, a download never answered, while its own frames flow.
//! Each hint names what its frames showed, in the order the causes are
//! checked: a signing clock it refuses ours by, another ground station's
//! id it answers, MAVLink 1 only, and else nothing of ours answered at all
//! (a router or filter between). Pure: the driver hands in what was heard
//! ([`Heard::of`]) and what was asked ([`Asked`]).

use std::collections::BTreeMap;
use std::time::{Duration, UNIX_EPOCH};

use super::hint::{Hint, HintCode};
use super::roster::{Addressed, Roster, SignedClock};
use crate::frame::signing::EPOCH_2015_UNIX_S;
use crate::frame::{codec, SysComp, Version};

/// MAVLink 2 signing: a receiver refuses a new stream whose timestamp is
/// more than a minute behind its own (pymavlink's, ArduPilot's and PX4's
/// check), in 10 µs units.
const NEW_STREAM_WINDOW: u64 = 60 * 100_000;

/// What the target's own frames showed: every component of its system
/// when the target names none (compid 0), else that one.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Heard {
    /// The target as text reports name it: "1/1 (quadrotor, px4)".
    pub(crate) who: String,
    pub(crate) frames: u64,
    pub(crate) v1: u64,
    pub(crate) signature: Option<SignedClock>,
    pub(crate) addressed: BTreeMap<u8, Addressed>,
}

impl Heard {
    /// The target's traffic in `roster`; none when nothing of it was heard.
    pub(crate) fn of(roster: &Roster, target: SysComp, ours: SysComp) -> Option<Heard> {
        let mut heard: Option<Heard> = None;
        let of_target = |id: &SysComp| {
            *id != ours
                && id.sysid == target.sysid
                && (target.compid == 0 || id.compid == target.compid)
        };
        for (id, source) in roster.sources().filter(|(id, _)| of_target(id)) {
            let h = heard.get_or_insert_with(|| Heard {
                who: match &source.identity {
                    Some(i) => format!("{id} ({}, {})", i.vehicle, i.autopilot_said()),
                    None => id.to_string(),
                },
                frames: 0,
                v1: 0,
                signature: None,
                addressed: BTreeMap::new(),
            });
            h.frames += source.frames;
            h.v1 += source.v1;
            if let Some(s) = source.signature {
                if h.signature.is_none_or(|c| s.theirs > c.theirs) {
                    h.signature = Some(s);
                }
            }
            for (to, a) in &source.addressed {
                let mine = h.addressed.entry(*to).or_default();
                mine.frames += a.frames;
                for m in &a.msgids {
                    if !mine.msgids.contains(m) {
                        mine.msgids.push(*m);
                    }
                }
            }
        }
        heard
    }
}

/// What we asked of the target and how we sent it.
#[derive(Debug, Clone)]
pub(crate) struct Asked {
    pub(crate) ours: SysComp,
    pub(crate) version: Version,
    /// Our frames are signed (`--signing-key`).
    pub(crate) key: bool,
    /// What went unanswered, in words: "MAV_CMD_REQUEST_MESSAGE (3 sent)".
    pub(crate) what: String,
    /// PING and TIMESYNC requests sent beside it, and how many the target
    /// answered; none when the run sent none.
    pub(crate) echoes: Option<(u64, u64)>,
}

/// A signing timestamp as a UTC time.
fn utc(stamp: u64) -> String {
    let at = UNIX_EPOCH
        + Duration::from_secs(EPOCH_2015_UNIX_S)
        + Duration::from_micros(stamp.saturating_mul(10));
    humantime::format_rfc3339_millis(at).to_string()
}

/// Our signing clock is so far behind the target's that it refuses our
/// frames as too old. The other way round is no cause: a receiver takes
/// a newer stamp and moves its own clock up to it.
fn signing_clock(heard: &Heard, asked: &Asked) -> Option<Hint> {
    let clock = heard.signature.filter(|_| asked.key)?;
    let ahead = clock.theirs.checked_sub(clock.ours)?;
    (ahead > NEW_STREAM_WINDOW).then(|| {
        Hint::new(
            HintCode::SigningClockBehind,
            format!(
                "our signing clock is {:.1} s behind {}'s: its newest signature timestamp is \
                 {}, ours was {} when it came; MAVLink 2 signing refuses a new stream more \
                 than 60 s behind the receiver's clock, so our signed frames are dropped as \
                 too old: set this computer's clock (or the vehicle's) right",
                ahead as f64 / 1e5,
                heard.who,
                utc(clock.theirs),
                utc(clock.ours)
            ),
        )
    })
}

/// Message ids as names: "COMMAND_ACK, TIMESYNC".
fn names(msgids: &[u32]) -> String {
    msgids
        .iter()
        .map(|&m| codec::message_name(m).map_or_else(|| format!("message {m}"), str::to_string))
        .collect::<Vec<_>>()
        .join(", ")
}

/// The target addresses other systems and never us: it answers another
/// ground station's id.
fn other_gcs(heard: &Heard, asked: &Asked) -> Option<Hint> {
    let ours = asked.ours.sysid;
    if heard.addressed.contains_key(&ours) {
        return None;
    }
    let mut others: Vec<(&u8, &Addressed)> = heard.addressed.iter().collect();
    // The most addressed first; of equals, the lower id.
    others.sort_by(|a, b| b.1.frames.cmp(&a.1.frames).then(a.0.cmp(b.0)));
    let (&first, _) = *others.first()?;
    let list = others
        .iter()
        .map(|(to, a)| format!("{} to system {to} ({})", a.frames, names(&a.msgids)))
        .collect::<Vec<_>>()
        .join(", ");
    Some(Hint::new(
        HintCode::SysidEnforced,
        format!(
            "{} addressed its frames to another ground station and none to us ({ours}): \
             {list}; a vehicle answers the ground station id it is set to (ArduPilot's \
             SYSID_MYGCS with SYSID_ENFORCE): try --sysid {first}",
            heard.who
        ),
    ))
}

fn mavlink1_only(heard: &Heard, asked: &Asked) -> Option<Hint> {
    // Signed frames are MAVLink 2 whatever --mavlink says.
    let ours_v2 = asked.version == Version::V2 || asked.key;
    (heard.frames > 0 && heard.v1 == heard.frames && ours_v2).then(|| {
        let advice = if asked.key {
            "a MAVLink 1 system cannot read signed frames: drop --signing-key and use \
             --mavlink 1"
        } else {
            "try --mavlink 1"
        };
        Hint::new(
            HintCode::Mavlink1Only,
            format!(
                "{} sent MAVLink 1 only ({} frames) and our requests are MAVLink 2, which it \
                 may not read: {advice}",
                heard.who, heard.frames
            ),
        )
    })
}

/// Nothing of ours was answered and nothing it sent was addressed to us,
/// while its own frames came.
fn nothing_of_ours(heard: &Heard, asked: &Asked) -> Option<Hint> {
    if heard.addressed.contains_key(&asked.ours.sysid) {
        return None;
    }
    let echoes = match asked.echoes {
        Some((_, answered)) if answered > 0 => return None,
        Some((sent, _)) => format!(", nor any of our {sent} PING and TIMESYNC requests"),
        None => String::new(),
    };
    Some(Hint::new(
        HintCode::NeverAnswered,
        format!(
            "{} is heard ({} frames) but answered nothing of ours: not {}{echoes}, and none \
             of its frames was addressed to us ({}): a router or filter between may drop what \
             we send, or the vehicle ignores it",
            heard.who, heard.frames, asked.what, asked.ours
        ),
    ))
}

/// Why a target heard well ignores us, in the order the causes are
/// checked; when none of its frames shows a cause, that nothing of ours
/// was answered at all.
pub(crate) fn ignored(heard: &Heard, asked: &Asked) -> Vec<Hint> {
    let causes: Vec<Hint> = [
        signing_clock(heard, asked),
        other_gcs(heard, asked),
        mavlink1_only(heard, asked),
    ]
    .into_iter()
    .flatten()
    .collect();
    if causes.is_empty() {
        return nothing_of_ours(heard, asked).into_iter().collect();
    }
    causes
}

/// What the frames of `target`, silent to an echo probe, show of why:
/// its signing clock ahead of ours, or another ground station's id it
/// answers; none when they show neither (the echo diagnosis has its own
/// hints for the rest).
pub(crate) fn echo_silence(roster: &Roster, target: SysComp, asked: &Asked) -> Option<Hint> {
    let heard = Heard::of(roster, target, asked.ours)?;
    signing_clock(&heard, asked).or_else(|| other_gcs(&heard, asked))
}

/// [`ignored`] for `target` by what `roster` heard of it; nothing when
/// nothing of it was heard (other hints say that).
pub(crate) fn ignored_by(roster: &Roster, target: SysComp, asked: &Asked) -> Vec<Hint> {
    Heard::of(roster, target, asked.ours).map_or_else(Vec::new, |h| ignored(&h, asked))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frame::ids;

    const OURS: SysComp = SysComp::new(250, 190);
    const TARGET: SysComp = SysComp::new(1, 1);

    fn asked() -> Asked {
        Asked {
            ours: OURS,
            version: Version::V2,
            key: false,
            what: "MAV_CMD_REQUEST_MESSAGE (4 sent)".into(),
            echoes: None,
        }
    }

    fn roster(v: Version) -> Roster {
        let mut r = Roster::default();
        r.heard(TARGET, 2, 12, 0);
        for _ in 0..5 {
            r.frame(TARGET, v, false);
        }
        r
    }

    fn codes(hints: &[Hint]) -> Vec<HintCode> {
        hints.iter().map(|h| h.code).collect()
    }

    #[test]
    fn a_vehicle_whose_signing_clock_is_over_a_minute_ahead_refuses_ours() {
        let mut r = roster(Version::V2);
        // 3 minutes ahead, in 10 µs units.
        let ours = 37_484_622_000_000;
        r.signature(TARGET, ours + 18_000_000, ours);
        let heard = Heard::of(&r, TARGET, OURS).unwrap();
        let keyed = Asked {
            key: true,
            ..asked()
        };
        let hints = ignored(&heard, &keyed);
        assert_eq!(codes(&hints), [HintCode::SigningClockBehind]);
        assert!(
            hints[0].text.starts_with(
                "our signing clock is 180.0 s behind 1/1 (quadrotor, px4)'s: its newest \
                 signature timestamp is 2026-11-17T12:00:00.000Z, ours was \
                 2026-11-17T11:57:00.000Z"
            ),
            "{hints:?}"
        );
        // Without a key we sign nothing: the clock is no cause.
        assert_eq!(codes(&ignored(&heard, &asked())), [HintCode::NeverAnswered]);
        // A minute ahead is within the window; behind us is no cause.
        for theirs in [ours + NEW_STREAM_WINDOW, ours - 18_000_000] {
            let mut r = roster(Version::V2);
            r.signature(TARGET, theirs, ours);
            let heard = Heard::of(&r, TARGET, OURS).unwrap();
            assert_eq!(codes(&ignored(&heard, &keyed)), [HintCode::NeverAnswered]);
        }
    }

    #[test]
    fn a_vehicle_that_addresses_another_ground_station_names_its_id() {
        let mut r = roster(Version::V2);
        for m in [ids::COMMAND_ACK, ids::COMMAND_ACK, ids::TIMESYNC] {
            r.addressed(TARGET, 255, m);
        }
        r.addressed(TARGET, 254, ids::PING);
        let heard = Heard::of(&r, TARGET, OURS).unwrap();
        let hints = ignored(&heard, &asked());
        assert_eq!(codes(&hints), [HintCode::SysidEnforced]);
        assert!(
            hints[0].text.contains(
                "none to us (250): 3 to system 255 (COMMAND_ACK, TIMESYNC), 1 to system 254 \
                 (PING);"
            ),
            "{hints:?}"
        );
        assert!(hints[0].text.ends_with("try --sysid 255"), "{hints:?}");
        // It addressed us too: it is no ground-station id that keeps it silent.
        r.addressed(TARGET, 250, ids::PING);
        let heard = Heard::of(&r, TARGET, OURS).unwrap();
        assert!(ignored(&heard, &asked()).is_empty());
    }

    #[test]
    fn mavlink1_only_and_nothing_of_ours_answered() {
        let heard = Heard::of(&roster(Version::V1), TARGET, OURS).unwrap();
        let hints = ignored(&heard, &asked());
        assert_eq!(codes(&hints), [HintCode::Mavlink1Only]);
        assert!(hints[0].text.ends_with("try --mavlink 1"), "{hints:?}");
        let v1 = Asked {
            version: Version::V1,
            ..asked()
        };
        assert_eq!(codes(&ignored(&heard, &v1)), [HintCode::NeverAnswered]);

        let heard = Heard::of(&roster(Version::V2), TARGET, OURS).unwrap();
        let with_echoes = Asked {
            echoes: Some((12, 0)),
            ..asked()
        };
        let hints = ignored(&heard, &with_echoes);
        assert_eq!(
            hints[0].text,
            "1/1 (quadrotor, px4) is heard (5 frames) but answered nothing of ours: not \
             MAV_CMD_REQUEST_MESSAGE (4 sent), nor any of our 12 PING and TIMESYNC requests, \
             and none of its frames was addressed to us (250/190): a router or filter between \
             may drop what we send, or the vehicle ignores it"
        );
        // A PING answered: our frames reach it.
        let answered = Asked {
            echoes: Some((12, 3)),
            ..asked()
        };
        assert!(ignored(&heard, &answered).is_empty());
        // Another system, or another component of a named target: not it.
        assert!(Heard::of(&roster(Version::V2), SysComp::new(2, 1), OURS).is_none());
        assert!(Heard::of(&roster(Version::V2), SysComp::new(1, 2), OURS).is_none());
        assert!(Heard::of(&roster(Version::V2), SysComp::new(1, 0), OURS).is_some());
    }
}
