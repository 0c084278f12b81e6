//! The C2 report's running figures over one session: fed every frame
//! the session admits and every decided request, finished into a
//! [`C2Report`] against the run's summary.

use super::config::C2Config;
use super::failsafe::{Direction, FailsafeModel, Replay, Watched, PRESETS};
use super::outages::Availability;
use super::position::Whereabouts;
use super::report::{C2Report, C2Rule, Continuity, Percentiles};
use super::summary_figures;
use super::uplink::{Paced, ProbedUplink};
use crate::engine::matcher::MatchEvent;
use crate::engine::probe::command::CommandEvent;
use crate::engine::probe::passive::ground::GroundIds;
use crate::engine::probe::passive::round_trips::RoundTrips;
use crate::engine::radio::is_radio_ids;
use crate::engine::stats::RttStats;
use crate::engine::summary::{EchoSummary, LinkSummary};
use crate::engine::Nanos;
use crate::frame::{Frame, Msg, SysComp, AUTOPILOT_ARDUPILOT};

/// MAV_AUTOPILOT_PX4.
const AUTOPILOT_PX4: u8 = 12;

/// Round trips completed within the continuity time.
#[derive(Clone)]
struct Tally {
    within_t: Nanos,
    within: u64,
    answered: u64,
    unanswered: u64,
    rtt: RttStats,
}

impl Tally {
    fn answered(&mut self, rtt: Nanos) {
        self.answered += 1;
        self.within += u64::from(rtt <= self.within_t);
        self.rtt.record(rtt);
    }

    fn continuity(&self, from: &'static str) -> Option<Continuity> {
        let transactions = self.answered + self.unanswered;
        (transactions > 0).then(|| Continuity {
            within: self.within,
            transactions,
            pct: 100.0 * self.within as f64 / transactions as f64,
            from,
        })
    }

    fn percentiles(&self) -> Option<Percentiles> {
        let s = self.rtt.summary()?;
        Some(Percentiles {
            count: self.rtt.count(),
            p50_ms: self.rtt.quantile_us(0.5) / 1e3,
            p99_ms: self.rtt.quantile_us(0.99) / 1e3,
            p999_ms: self.rtt.quantile_us(0.999) / 1e3,
            max_ms: s.max_us / 1e3,
        })
    }
}

/// One failsafe model, played every way its deliveries could be known;
/// the report keeps the best known at the end.
#[derive(Debug, Clone)]
struct Played {
    /// Down: the vehicle's messages as received. Up: the ground
    /// station's recorded messages (a log's), delivered while the
    /// downlink was up.
    recorded: Replay,
    /// Up: messages at the model's rate, delivered while the downlink
    /// was up.
    paced: Paced,
}

/// The C2 report's figures so far.
#[derive(Clone)]
pub(crate) struct C2Tracker {
    cfg: C2Config,
    ours: SysComp,
    ground: GroundIds,
    whereabouts: Whereabouts,
    availability: Availability,
    tally: Tally,
    /// A log's requests and replies, for continuity.
    logged: Option<RoundTrips>,
    probed: ProbedUplink,
    played: Vec<Played>,
    /// The vehicle's MAV_TYPE and autopilot, for the presets.
    vehicle: Option<(u8, u8)>,
    /// Commands decided: continuity is theirs.
    commands: bool,
    /// The sequence number of our first request.
    first_seq: u32,
}

/// The models a run plays: those asked for, else every preset (the one
/// matching the vehicle is kept at the end).
fn models(cfg: &C2Config) -> Vec<FailsafeModel> {
    if cfg.failsafes.is_empty() {
        PRESETS
            .iter()
            .filter_map(|p| FailsafeModel::preset(p.0))
            .collect()
    } else {
        cfg.failsafes.clone()
    }
}

impl C2Tracker {
    /// `log`: the session reads a telemetry log.
    pub(crate) fn new(
        cfg: &C2Config,
        ours: SysComp,
        timeout: Nanos,
        first_seq: u32,
        log: bool,
    ) -> Self {
        let models = models(cfg);
        let paced_up = |m: &FailsafeModel| Paced::new(Replay::new(m.clone()));
        C2Tracker {
            ours,
            ground: GroundIds::default(),
            whereabouts: Whereabouts::default(),
            availability: Availability::new(cfg.up_within, cfg.distance_band_m),
            tally: Tally {
                within_t: cfg.continuity_within,
                within: 0,
                answered: 0,
                unanswered: 0,
                rtt: RttStats::new(),
            },
            logged: log.then(|| RoundTrips::new(timeout)),
            probed: ProbedUplink::new(timeout, models.iter().map(paced_up).collect()),
            played: models
                .iter()
                .map(|m| Played {
                    recorded: Replay::new(m.clone()),
                    paced: paced_up(m),
                })
                .collect(),
            vehicle: None,
            commands: false,
            first_seq,
            cfg: cfg.clone(),
        }
    }

    /// A frame the session admitted, at `at`.
    pub(crate) fn frame(&mut self, frame: &Frame, at: Nanos) {
        if matches!(frame.msg, Msg::Damaged) || frame.source == self.ours {
            return;
        }
        let ground = self.ground.sees(frame);
        if let Some(rt) = &mut self.logged {
            if let Some((requester, rtt)) = rt.on_frame(frame, at) {
                if self.ground.sees_id(requester) {
                    self.tally.answered(rtt);
                }
            }
        }
        if ground {
            self.ground_frame(frame, at);
        } else if !is_radio_ids(frame.source) {
            self.vehicle_frame(frame, at);
        }
    }

    /// The ground station's own frame in a log: a message its vehicle's
    /// failsafe watches, delivered if the downlink was up then.
    fn ground_frame(&mut self, frame: &Frame, at: Nanos) {
        let up = self.availability.up_at(at);
        for p in &mut self.played {
            let m = &p.recorded.model;
            if m.direction == Direction::Up && watches(m.message, &frame.msg) {
                p.recorded.message(at, up);
            }
        }
    }

    fn vehicle_frame(&mut self, frame: &Frame, at: Nanos) {
        // The failsafe's paced messages up to now, by the downlink as it
        // was before this frame.
        let availability = &self.availability;
        for p in &mut self.played {
            let m = &p.recorded.model;
            match m.direction {
                Direction::Up => p.paced.send_until(at, |t| availability.up_at(t)),
                Direction::Down if watches(m.message, &frame.msg) => {
                    p.recorded.message(at, true);
                }
                Direction::Down => {}
            }
        }
        self.availability.frame(at, self.whereabouts.distance_m());
        match &frame.msg {
            Msg::Fix(f) => self.whereabouts.fix(frame.source, f),
            Msg::Heartbeat {
                mav_type,
                autopilot,
            } if self.vehicle.is_none() && *autopilot != crate::frame::AUTOPILOT_INVALID => {
                self.vehicle = Some((*mav_type, *autopilot));
            }
            _ => {}
        }
    }

    /// A request of ours decided.
    pub(crate) fn matched(&mut self, event: &MatchEvent) {
        match *event {
            MatchEvent::Reply {
                rtt,
                sent_at,
                at,
                seq,
                first_from_responder,
                ..
            } => {
                // A first answer to a later request than the first: those
                // before it were answered by nobody.
                if first_from_responder && seq > self.first_seq && self.probed.outcomes() == 0 {
                    self.probed.unanswered_from_start();
                }
                self.tally.answered(rtt);
                self.probed.decided(sent_at, true, at);
            }
            MatchEvent::Lost { sent_at, at, .. } => {
                self.tally.unanswered += 1;
                self.probed.decided(sent_at, false, at);
            }
            // Counted lost already, but the request got through.
            MatchEvent::Late { sent_at, at, .. } => self.probed.decided(sent_at, true, at),
            MatchEvent::Duplicate { .. } | MatchEvent::Stale { .. } => {}
        }
    }

    /// A command of ours acknowledged (from its first transmission: the
    /// transaction's time) or given up.
    pub(crate) fn command(&mut self, event: &CommandEvent) {
        match *event {
            CommandEvent::Acked { time_to_ack, .. } => {
                self.commands = true;
                self.tally.answered(time_to_ack);
            }
            CommandEvent::Failed { .. } => {
                self.commands = true;
                self.tally.unanswered += 1;
            }
            _ => {}
        }
    }

    /// The report at `end`, with the figures the run's summary has (dated
    /// apart: [`C2Report::date`]).
    pub(crate) fn finish(mut self, end: Nanos, summary: &LinkSummary) -> C2Report {
        // Requests nobody answered that no responder's count holds (it
        // counts from its first answer; none for one never heard) are
        // failed transactions all the same.
        let decided = summary
            .get::<EchoSummary>()
            .map_or(0, |e| e.requests.saturating_sub(e.in_flight));
        let counted = self.tally.answered + self.tally.unanswered;
        if !self.commands && decided > counted {
            self.tally.unanswered += decided - counted;
            if self.probed.outcomes() == 0 {
                self.probed.unanswered_from_start();
            }
        }
        let probed = self.probed.outcomes() > 0 || (decided > 0 && !self.commands);
        let logged_from = self.logged.as_mut().map(|rt| {
            let s = rt.summary(end);
            let ground = self.ground;
            s.pairs
                .iter()
                .filter(|p| ground.sees_id(p.requester))
                .map(|p| p.counts.unanswered)
                .sum::<u64>()
        });
        if let Some(unanswered) = logged_from.filter(|_| !probed && !self.commands) {
            self.tally.unanswered += unanswered;
        }
        let availability = &self.availability;
        let mut played = std::mem::take(&mut self.played);
        for p in &mut played {
            p.paced
                .send_until(end.saturating_add(1), |t| availability.up_at(t));
        }
        let (latency_split, loss) = summary_figures::of(summary);
        let by_probes =
            std::mem::replace(&mut self.probed, ProbedUplink::new(0, Vec::new())).finish(end);
        let failsafes = self.replays(played, by_probes, end, probed, &loss);
        let frames = self.availability.frames();
        let distance = self.whereabouts.distance_m();
        let (down, outages, timeline, bands) = self.availability.finish(end, distance);
        let floor = self.cfg.availability_floor_pct;
        let duration_s = end as f64 / 1e9;
        C2Report {
            started_utc: None,
            rule: C2Rule {
                up_within_s: self.cfg.up_within as f64 / 1e9,
                continuity_within_s: self.cfg.continuity_within as f64 / 1e9,
                distance_band_m: self.cfg.distance_band_m,
                availability_floor_pct: floor,
            },
            duration_s,
            down_s: down as f64 / 1e9,
            availability_pct: (frames > 0 && end > 0)
                .then(|| 100.0 * (1.0 - down as f64 / end as f64)),
            frames,
            continuity: self.tally.continuity(match (probed, self.commands) {
                (true, _) => "probes",
                (_, true) => "commands",
                _ => "log",
            }),
            latency: super::report::Latency {
                round_trip: self.tally.percentiles(),
                ..latency_split
            },
            loss,
            outages,
            timeline,
            availability_under_floor_from_m: bands
                .iter()
                .find(|b| b.availability_pct < floor)
                .map(|b| b.from_m),
            distance: bands,
            failsafes,
        }
    }

    /// Each model's replay by the best evidence the run had.
    fn replays(
        &self,
        played: Vec<Played>,
        by_probes: Vec<Replay>,
        end: Nanos,
        probed: bool,
        loss: &super::report::DirectionLoss,
    ) -> Vec<super::report::FailsafeReplay> {
        let vehicle = self.vehicle;
        played
            .into_iter()
            .zip(by_probes)
            .filter(|(p, _)| !self.cfg.failsafes.is_empty() || matches(&p.recorded.model, vehicle))
            .map(|(p, probes)| {
                let m = &p.recorded.model;
                match m.direction {
                    Direction::Down => p.recorded.finish(
                        end,
                        "received",
                        false,
                        loss.downlink_pct.map(|l| l / 100.0),
                    ),
                    Direction::Up => {
                        let up_loss = loss.uplink_pct.map(|l| l / 100.0);
                        if probed {
                            probes.finish(end, "probes", true, up_loss)
                        } else if p.recorded.messages() > 0 {
                            p.recorded.finish(end, "recorded", true, up_loss)
                        } else {
                            p.paced.replay.finish(end, "downlink", true, up_loss)
                        }
                    }
                }
            })
            .collect()
    }
}

/// Whether a preset is the vehicle's autopilot's.
fn matches(model: &FailsafeModel, vehicle: Option<(u8, u8)>) -> bool {
    let Some((mav_type, autopilot)) = vehicle else {
        return false;
    };
    let preset = match autopilot {
        AUTOPILOT_PX4 => "px4",
        AUTOPILOT_ARDUPILOT => match mav_type {
            // Fixed wing and the VTOL types ArduPlane sends.
            1 | 19..=25 => "ardupilot-plane",
            // Ground rover, surface boat.
            10 | 11 => "ardupilot-rover",
            2 | 3 | 4 | 13 | 14 | 15 | 29 | 35 => "ardupilot-copter",
            _ => return false,
        },
        _ => return false,
    };
    model.name == preset
}

/// Whether `msg` is the message a failsafe watches.
fn watches(watched: Watched, msg: &Msg) -> bool {
    match watched {
        Watched::Any => true,
        Watched::Heartbeat => matches!(msg, Msg::Heartbeat { .. }),
        Watched::Timesync => matches!(msg, Msg::Timesync { .. }),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::engine::summary::EchoSummary;
    use crate::frame::test_frame;

    const S: Nanos = 1_000_000_000;
    const MS: Nanos = 1_000_000;
    const VEHICLE: SysComp = SysComp::new(1, 1);
    const GCS: SysComp = SysComp::new(255, 190);
    const US: SysComp = SysComp::new(250, 190);

    fn config(failsafes: &[&str]) -> C2Config {
        C2Config {
            up_within: 2 * S,
            continuity_within: 500 * MS,
            distance_band_m: 500.0,
            availability_floor_pct: 99.0,
            failsafes: failsafes
                .iter()
                .map(|t| {
                    FailsafeModel::parse(t, |v| {
                        humantime::parse_duration(v)
                            .map(|d| d.as_secs_f64())
                            .map_err(|e| e.to_string())
                    })
                    .unwrap()
                })
                .collect(),
        }
    }

    fn heartbeat(mav_type: u8, autopilot: u8) -> Msg {
        Msg::Heartbeat {
            mav_type,
            autopilot,
        }
    }

    fn summary() -> LinkSummary {
        LinkSummary::new(EchoSummary::empty("test", 0))
    }

    /// A log: the vehicle's HEARTBEATs every 100 ms but for a 6 s hole
    /// from 10 s; the ground station's at 1 Hz, recorded. Against a 2 s
    /// rule, its HEARTBEATs at 13, 14 and 15 s fell while the downlink was
    /// down (up to 12 s, up again at 16 s): ArduCopter's 5 s check waits
    /// 4 s, no trip, 1 s of margin; with a 3 s timeout, one trip at 15 s
    /// lasting 1 s.
    #[test]
    fn a_logs_ground_heartbeats_are_delivered_while_the_downlink_is_up() {
        let mut c2 = C2Tracker::new(
            &config(&["ardupilot-copter", "ardupilot-copter:timeout=3s"]),
            US,
            S,
            0,
            true,
        );
        let mut t = 0;
        while t <= 30 * S {
            if !(t > 10 * S && t < 16 * S) {
                c2.frame(&test_frame(VEHICLE, heartbeat(2, 3)), t);
            }
            if t % S == 0 {
                c2.frame(&test_frame(GCS, heartbeat(6, 8)), t);
            }
            t += 100 * MS;
        }
        let r = c2.finish(30 * S, &summary());
        assert_eq!(r.outages.count, 1);
        assert_eq!(r.down_s, 4.0);
        let (five, three) = (&r.failsafes[0], &r.failsafes[1]);
        assert_eq!((five.basis, five.inferred), ("recorded", true));
        assert_eq!((five.messages, five.delivered), (31, 28));
        assert_eq!((five.trips, five.closest_wait_s), (0, Some(4.0)));
        assert_eq!(three.trips, 1);
        assert_eq!(three.trip_list[0].at_s, 15.0);
        assert_eq!(three.trip_list[0].lasted_s, 1.0);
    }

    /// Our probes every second, those sent at 5-9 s lost: the vehicle's
    /// 5 s check, fed at 1 Hz while the uplink was as the last probe
    /// found it, last hears 4 s and next 10 s: 6 s, a trip at 9 s.
    #[test]
    fn probes_the_vehicle_did_not_answer_leave_the_uplink_down_until_one_it_did() {
        let mut c2 = C2Tracker::new(&config(&["ardupilot-copter"]), US, S, 0, false);
        for k in 0..=20 {
            let sent_at = k * S;
            c2.frame(&test_frame(VEHICLE, heartbeat(2, 3)), sent_at);
            let event = if (5..=9).contains(&k) {
                MatchEvent::Lost {
                    responder: VEHICLE,
                    seq: k as u32,
                    sent_at,
                    at: sent_at + S,
                }
            } else {
                MatchEvent::Reply {
                    responder: VEHICLE,
                    seq: k as u32,
                    rtt: 20 * MS + k * 50 * MS,
                    sent_at,
                    at: sent_at + 20 * MS,
                    out_of_order: false,
                    first_from_responder: k == 0,
                }
            };
            c2.matched(&event);
        }
        let r = c2.finish(20 * S + 500 * MS, &summary());
        let f = &r.failsafes[0];
        assert_eq!((f.basis, f.messages, f.delivered), ("probes", 21, 16));
        assert_eq!(f.trips, 1);
        assert_eq!(f.trip_list[0].at_s, 9.0);
        assert_eq!(f.trip_list[0].lasted_s, 1.0);
        // Continuity within 500 ms: replies of 20 + 50k ms for k ≤ 9.
        let c = r.continuity.unwrap();
        assert_eq!((c.within, c.transactions), (5, 21));
    }

    /// Without --failsafe, the vehicle's autopilot's preset: ArduPlane
    /// (fixed wing), PX4, none for a vehicle that says neither.
    #[test]
    fn the_vehicles_heartbeat_picks_its_preset() {
        for (mav_type, autopilot, want) in [
            (1, 3, Some("ardupilot-plane")),
            (2, 3, Some("ardupilot-copter")),
            (10, 3, Some("ardupilot-rover")),
            (2, 12, Some("px4")),
            (12, 3, None),
            (2, 0, None),
        ] {
            let mut c2 = C2Tracker::new(&config(&[]), US, S, 0, false);
            c2.frame(&test_frame(VEHICLE, heartbeat(mav_type, autopilot)), S);
            let r = c2.finish(2 * S, &summary());
            let got: Vec<_> = r.failsafes.iter().map(|f| f.model.as_str()).collect();
            assert_eq!(
                got,
                want.into_iter().collect::<Vec<_>>(),
                "{mav_type}/{autopilot}"
            );
        }
    }

    /// A down model watches the vehicle's own messages as they came.
    #[test]
    fn a_down_model_replays_the_vehicles_messages_as_received() {
        let mut c2 = C2Tracker::new(
            &config(&["custom:message=heartbeat,timeout=1.5s,direction=down"]),
            US,
            S,
            0,
            false,
        );
        for t in [1, 2, 4, 5, 9] {
            c2.frame(&test_frame(VEHICLE, heartbeat(2, 3)), t * S);
        }
        let r = c2.finish(9 * S, &summary());
        let f = &r.failsafes[0];
        assert_eq!(
            (f.basis, f.inferred, f.delivered, f.trips),
            ("received", false, 5, 2)
        );
        let at: Vec<_> = f.trip_list.iter().map(|t| t.at_s).collect();
        assert_eq!(at, [3.5, 6.5]);
    }

    /// A log's continuity counts the ground station's requests only: the
    /// vehicle's TIMESYNCs nobody answered are no C2 transaction.
    #[test]
    fn a_logs_continuity_counts_the_ground_stations_round_trips() {
        let mut c2 = C2Tracker::new(&config(&[]), US, S, 0, true);
        c2.frame(&test_frame(GCS, heartbeat(6, 8)), 0);
        let ping = |seq, to: SysComp| Msg::Ping {
            time_usec: 7,
            seq,
            target_system: to.sysid,
            target_component: to.compid,
        };
        let timesync = Msg::Timesync {
            tc1: 0,
            ts1: 99,
            target_system: 0,
            target_component: 0,
        };
        c2.frame(&test_frame(GCS, ping(1, SysComp::new(0, 0))), S);
        c2.frame(&test_frame(VEHICLE, ping(1, GCS)), S + 100 * MS);
        c2.frame(&test_frame(GCS, ping(2, SysComp::new(0, 0))), 2 * S);
        c2.frame(&test_frame(VEHICLE, ping(2, GCS)), 2 * S + 700 * MS);
        c2.frame(&test_frame(GCS, ping(3, SysComp::new(0, 0))), 3 * S);
        c2.frame(&test_frame(VEHICLE, timesync), 3 * S);
        let r = c2.finish(10 * S, &summary());
        let c = r.continuity.unwrap();
        assert_eq!((c.within, c.transactions, c.from), (1, 3, "log"));
    }

    /// A command run: acknowledged within the time, after it, never.
    #[test]
    fn a_command_runs_continuity_is_its_acknowledgements() {
        let mut c2 = C2Tracker::new(&config(&[]), US, S, 0, false);
        for (time_to_ack, acked) in [(100 * MS, true), (900 * MS, true), (0, false)] {
            c2.command(&if acked {
                CommandEvent::Acked {
                    n: 1,
                    target: VEHICLE,
                    from: VEHICLE,
                    command: 512,
                    result: 0,
                    attempts: 1,
                    time_to_ack,
                }
            } else {
                CommandEvent::Failed {
                    n: 3,
                    target: VEHICLE,
                    command: 512,
                    attempts: 4,
                }
            });
        }
        let c = c2.finish(5 * S, &summary()).continuity.unwrap();
        assert_eq!((c.within, c.transactions, c.from), (1, 3, "commands"));
    }

    /// The vehicle's first answer is to our fourth request: the three
    /// before it, which the matcher counts for no one, went unanswered,
    /// so the uplink was down from the start; and the summary's requests
    /// make them failed transactions.
    #[test]
    fn requests_before_the_first_answer_are_unanswered() {
        let mut c2 = C2Tracker::new(&config(&["ardupilot-copter:timeout=2s"]), US, S, 0, false);
        for k in 3..=9 {
            c2.matched(&MatchEvent::Reply {
                responder: VEHICLE,
                seq: k as u32,
                rtt: 10 * MS,
                sent_at: k * S,
                at: k * S + 10 * MS,
                out_of_order: false,
                first_from_responder: k == 3,
            });
        }
        let mut echo = EchoSummary::empty("test", 10);
        echo.in_flight = 0;
        let r = c2.finish(10 * S, &LinkSummary::new(echo));
        let f = &r.failsafes[0];
        assert_eq!((f.messages, f.delivered, f.trips), (11, 8, 1));
        assert_eq!(f.trip_list[0].at_s, 2.0);
        let c = r.continuity.unwrap();
        assert_eq!((c.within, c.transactions), (7, 10));
    }
}
