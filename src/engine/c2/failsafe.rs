//! Failsafe models and their replay: a message at a rate, checked
//! against a timeout, as an autopilot checks its ground station's
//! HEARTBEATs (ArduPilot's GCS failsafe, PX4's data link loss), played
//! against the deliveries the link made.
//!
//! The rule: the failsafe trips when the time since the last delivery
//! (or since the start) exceeds the timeout, at that last delivery plus
//! the timeout, and clears at the next delivery. Autopilots check at
//! their loop rate (10-400 Hz); the replay checks continuously, so a
//! trip by less than a loop period may be one an autopilot would miss.

use std::fmt;

use super::report::{FailsafeReplay, Trip};
use crate::engine::Nanos;

/// Trips listed in the report (all are counted).
pub(crate) const LISTED_TRIPS: usize = 10;

const SECOND: f64 = 1e9;

/// Who checks whose messages.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Direction {
    /// The vehicle checks the ground station's (every autopilot preset).
    Up,
    /// The ground station checks the vehicle's.
    Down,
}

impl Direction {
    fn as_str(self) -> &'static str {
        match self {
            Direction::Up => "up",
            Direction::Down => "down",
        }
    }
}

/// The message a failsafe watches.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Watched {
    Heartbeat,
    Timesync,
    /// Any message (PX4 counts any telemetry from the link as alive).
    Any,
}

impl Watched {
    pub(crate) fn as_str(self) -> &'static str {
        match self {
            Watched::Heartbeat => "HEARTBEAT",
            Watched::Timesync => "TIMESYNC",
            Watched::Any => "any",
        }
    }
}

/// A failsafe rule, a preset's or the user's.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct FailsafeModel {
    /// The preset's name, or `custom`.
    pub(crate) name: String,
    /// The autopilot's parameters that set it, with their values.
    pub(crate) setting: String,
    pub(crate) direction: Direction,
    pub(crate) message: Watched,
    pub(crate) rate_hz: f64,
    pub(crate) timeout: Nanos,
    /// A second, longer stage (ArduPlane's FS_LONG_TIMEOUT).
    pub(crate) long_timeout: Option<Nanos>,
}

/// The presets: name, the autopilot's parameters, timeout, long timeout.
/// The defaults are the ones the autopilots document: ArduCopter 4.x
/// FS_GCS_TIMEOUT 5 s; ArduPlane FS_SHORT_TIMEOUT 1.5 s and
/// FS_LONG_TIMEOUT 5 s (with FS_GCS_ENABL set); Rover FS_TIMEOUT 1.5 s
/// (with FS_GCS_ENABLE set); PX4 COM_DL_LOSS_T 10 s. Each watches the
/// ground station's HEARTBEAT, sent at 1 Hz by every ground station.
pub(crate) const PRESETS: [(&str, &str, f64, Option<f64>); 4] = [
    ("ardupilot-copter", "FS_GCS_TIMEOUT", 5.0, None),
    (
        "ardupilot-plane",
        "FS_SHORT_TIMEOUT/FS_LONG_TIMEOUT",
        1.5,
        Some(5.0),
    ),
    ("ardupilot-rover", "FS_TIMEOUT", 1.5, None),
    ("px4", "COM_DL_LOSS_T", 10.0, None),
];

/// A setting out of range, or a name no preset has.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct ModelError(pub(crate) String);

impl fmt::Display for ModelError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

fn ns(seconds: f64) -> Nanos {
    (seconds * SECOND).round() as Nanos
}

fn secs(ns: Nanos) -> f64 {
    ns as f64 / SECOND
}

/// Shows a duration as the autopilots' parameters take it: seconds.
fn show(seconds: f64) -> String {
    format!("{}s", (seconds * 1000.0).round() / 1000.0)
}

impl FailsafeModel {
    /// The preset called `name`, at its defaults.
    pub(crate) fn preset(name: &str) -> Option<FailsafeModel> {
        let (name, params, timeout, long) = PRESETS.iter().find(|p| p.0 == name)?;
        let mut model = FailsafeModel {
            name: (*name).to_string(),
            setting: String::new(),
            direction: Direction::Up,
            message: Watched::Heartbeat,
            rate_hz: 1.0,
            timeout: ns(*timeout),
            long_timeout: long.map(ns),
        };
        model.setting = model.describe(params);
        Some(model)
    }

    /// The parameters with this model's values: `FS_GCS_TIMEOUT=5s`.
    fn describe(&self, params: &str) -> String {
        let mut values = vec![show(secs(self.timeout))];
        values.extend(self.long_timeout.map(|l| show(secs(l))));
        params
            .split('/')
            .zip(values)
            .map(|(p, v)| format!("{p}={v}"))
            .collect::<Vec<_>>()
            .join(" ")
    }

    /// `NAME[:KEY=VALUE,...]`: a preset with settings changed, or
    /// `custom:` with its own (message, rate, timeout, long-timeout,
    /// direction). `parse_duration` reads a duration as the rest of the
    /// command line does.
    pub(crate) fn parse(
        text: &str,
        parse_duration: impl Fn(&str) -> Result<f64, String>,
    ) -> Result<FailsafeModel, ModelError> {
        let (name, settings) = text.split_once(':').unwrap_or((text, ""));
        let mut model = if name == "custom" {
            FailsafeModel {
                name: "custom".into(),
                setting: String::new(),
                direction: Direction::Up,
                message: Watched::Heartbeat,
                rate_hz: 1.0,
                timeout: 0,
                long_timeout: None,
            }
        } else {
            FailsafeModel::preset(name).ok_or_else(|| {
                let names: Vec<_> = PRESETS.iter().map(|p| p.0).collect();
                ModelError(format!(
                    "no failsafe preset {name:?}: {} or custom:message=...,rate=...,timeout=...",
                    names.join(", ")
                ))
            })?
        };
        for pair in settings.split(',').filter(|s| !s.is_empty()) {
            let (key, value) = pair
                .split_once('=')
                .ok_or_else(|| ModelError(format!("{pair:?} is not KEY=VALUE")))?;
            model.set(key, value, &parse_duration)?;
        }
        model.check()?;
        if let Some((_, params, ..)) = PRESETS.iter().find(|p| p.0 == model.name) {
            model.setting = model.describe(params);
        } else {
            model.setting = format!(
                "{}@{}Hz timeout={}{}",
                model.message.as_str(),
                model.rate_hz,
                show(secs(model.timeout)),
                model
                    .long_timeout
                    .map(|l| format!(" long-timeout={}", show(secs(l))))
                    .unwrap_or_default()
            );
        }
        Ok(model)
    }

    fn set(
        &mut self,
        key: &str,
        value: &str,
        parse_duration: &impl Fn(&str) -> Result<f64, String>,
    ) -> Result<(), ModelError> {
        let duration =
            |v: &str| parse_duration(v).map_err(|e| ModelError(format!("failsafe {key}: {e}")));
        match key {
            "timeout" => self.timeout = ns(duration(value)?),
            "long-timeout" => self.long_timeout = Some(ns(duration(value)?)),
            "rate" => {
                let hz = value.trim_end_matches("hz").trim_end_matches("Hz");
                self.rate_hz = hz
                    .parse::<f64>()
                    .ok()
                    .filter(|r| r.is_finite() && *r > 0.0 && *r <= 1000.0)
                    .ok_or_else(|| {
                        ModelError(format!("failsafe rate {value:?}: a rate in Hz, 0 to 1000"))
                    })?;
            }
            "message" => {
                self.message = match value.to_ascii_lowercase().as_str() {
                    "heartbeat" => Watched::Heartbeat,
                    "timesync" => Watched::Timesync,
                    "any" => Watched::Any,
                    _ => {
                        return Err(ModelError(format!(
                            "failsafe message {value:?}: heartbeat, timesync or any"
                        )))
                    }
                }
            }
            "direction" => {
                self.direction = match value {
                    "up" => Direction::Up,
                    "down" => Direction::Down,
                    _ => {
                        return Err(ModelError(format!(
                            "failsafe direction {value:?}: up or down"
                        )))
                    }
                }
            }
            _ => {
                return Err(ModelError(format!(
                    "no failsafe setting {key:?}: message, rate, timeout, long-timeout, direction"
                )))
            }
        }
        Ok(())
    }

    fn check(&self) -> Result<(), ModelError> {
        if self.timeout == 0 {
            return Err(ModelError(format!(
                "failsafe {}: give its timeout (timeout=DURATION)",
                self.name
            )));
        }
        if self.long_timeout.is_some_and(|l| l <= self.timeout) {
            return Err(ModelError(format!(
                "failsafe {}: the long timeout must be longer than the timeout",
                self.name
            )));
        }
        Ok(())
    }

    /// Consecutive messages lost before a trip: the gap between two
    /// deliveries, (k + 1) / rate, passes the timeout from k = ⌊T × rate⌋.
    fn losses_to_trip(&self) -> u32 {
        (secs(self.timeout) * self.rate_hz).floor() as u32
    }
}

/// One model played against a sequence of messages, each delivered or not.
#[derive(Debug, Clone)]
pub(crate) struct Replay {
    pub(crate) model: FailsafeModel,
    /// The last delivery, or the start.
    last: Nanos,
    messages: u64,
    delivered: u64,
    trips: u64,
    long_trips: u64,
    listed: Vec<Trip>,
    /// The longest wait that did not trip, and when it ended.
    closest: Option<(Nanos, Nanos)>,
}

impl Replay {
    pub(crate) fn new(model: FailsafeModel) -> Self {
        Replay {
            model,
            last: 0,
            messages: 0,
            delivered: 0,
            trips: 0,
            long_trips: 0,
            listed: Vec::new(),
            closest: None,
        }
    }

    pub(crate) fn messages(&self) -> u64 {
        self.messages
    }

    /// A message sent at `at`, which the link delivered or not.
    pub(crate) fn message(&mut self, at: Nanos, delivered: bool) {
        self.messages += 1;
        if delivered {
            self.delivery(at);
        }
    }

    /// A message delivered at `at`.
    fn delivery(&mut self, at: Nanos) {
        self.delivered += 1;
        let wait = at.saturating_sub(self.last);
        if wait > self.model.timeout {
            self.trip(wait, at, false);
        } else if self.closest.is_none_or(|(w, _)| wait > w) {
            self.closest = Some((wait, at));
        }
        self.last = self.last.max(at);
    }

    fn trip(&mut self, wait: Nanos, until: Nanos, open: bool) {
        let long = self.model.long_timeout.is_some_and(|l| wait > l);
        self.trips += 1;
        self.long_trips += u64::from(long);
        if self.listed.len() < LISTED_TRIPS {
            let at = self.last + self.model.timeout;
            self.listed.push(Trip {
                at_s: secs(at),
                lasted_s: secs(until - at),
                open,
                long,
            });
        }
    }

    /// The replay at `end`: a wait still going past the timeout is a trip
    /// still on. `loss` is the measured loss of the model's direction
    /// (0 to 1), for the trips independent losses would give.
    pub(crate) fn finish(
        mut self,
        end: Nanos,
        basis: &'static str,
        inferred: bool,
        loss: Option<f64>,
    ) -> FailsafeReplay {
        let wait = end.saturating_sub(self.last);
        if wait > self.model.timeout {
            self.trip(wait, end, true);
        }
        let m = &self.model;
        let expected =
            loss.map(|p| secs(end) * m.rate_hz * (1.0 - p) * p.powi(m.losses_to_trip() as i32));
        FailsafeReplay {
            model: m.name.clone(),
            setting: m.setting.clone(),
            direction: m.direction.as_str(),
            message: m.message.as_str(),
            rate_hz: m.rate_hz,
            timeout_s: secs(m.timeout),
            long_timeout_s: m.long_timeout.map(secs),
            basis,
            inferred,
            messages: self.messages,
            delivered: self.delivered,
            trips: self.trips,
            long_trips: self.long_trips,
            trip_list: self.listed,
            closest_wait_s: self.closest.map(|(w, _)| secs(w)),
            closest_margin_s: self.closest.map(|(w, _)| secs(m.timeout) - secs(w)),
            closest_at_s: self.closest.map(|(_, at)| secs(at)),
            expected_if_independent: expected,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const S: Nanos = 1_000_000_000;

    fn parse(text: &str) -> Result<FailsafeModel, ModelError> {
        FailsafeModel::parse(text, |v| {
            humantime::parse_duration(v)
                .map(|d| d.as_secs_f64())
                .map_err(|e| e.to_string())
        })
    }

    #[test]
    fn presets_state_their_parameters_and_defaults() {
        let copter = parse("ardupilot-copter").unwrap();
        assert_eq!(copter.setting, "FS_GCS_TIMEOUT=5s");
        assert_eq!(copter.timeout, 5 * S);
        let plane = parse("ardupilot-plane").unwrap();
        assert_eq!(plane.setting, "FS_SHORT_TIMEOUT=1.5s FS_LONG_TIMEOUT=5s");
        assert_eq!(parse("px4:timeout=3s").unwrap().setting, "COM_DL_LOSS_T=3s");
        let custom = parse("custom:message=timesync,rate=10,timeout=1s,direction=down").unwrap();
        assert_eq!(custom.setting, "TIMESYNC@10Hz timeout=1s");
        assert_eq!(custom.direction, Direction::Down);
    }

    #[test]
    fn bad_models_say_what_is_wrong() {
        for (text, says) in [
            ("ardupilot-sub", "no failsafe preset"),
            ("custom:rate=1", "give its timeout"),
            ("custom:timeout=1s,rate=0", "a rate in Hz"),
            ("px4:timeout", "is not KEY=VALUE"),
            ("px4:colour=red", "no failsafe setting"),
            ("ardupilot-plane:long-timeout=1s", "longer than the timeout"),
            ("custom:timeout=soon", "failsafe timeout"),
        ] {
            let e = parse(text).unwrap_err().0;
            assert!(e.contains(says), "{text}: {e}");
        }
    }

    /// Deliveries at 1 Hz with a 4 s hole and a 7 s hole against 5 s:
    /// one trip, 2 s into the 7 s hole, lasting 2 s; the closest call
    /// the 4 s wait, 1 s of margin.
    #[test]
    fn a_wait_past_the_timeout_trips_once_and_the_longest_other_is_the_closest() {
        let mut r = Replay::new(parse("ardupilot-copter").unwrap());
        let times = [1, 2, 6, 7, 14, 15];
        for t in 1..=15 {
            r.message(t * S, times.contains(&t));
        }
        let f = r.finish(15 * S, "probes", true, None);
        assert_eq!((f.messages, f.delivered, f.trips), (15, 6, 1));
        assert_eq!(f.trip_list[0].at_s, 12.0);
        assert_eq!(f.trip_list[0].lasted_s, 2.0);
        assert_eq!(f.closest_wait_s, Some(4.0));
        assert_eq!(f.closest_margin_s, Some(1.0));
        assert_eq!(f.closest_at_s, Some(6.0));
    }

    #[test]
    fn a_wait_still_going_at_the_end_is_an_open_trip_and_long_past_the_long_timeout() {
        let mut r = Replay::new(parse("ardupilot-plane").unwrap());
        r.message(S, true);
        r.message(3 * S, true); // 2 s: short trip only
        let f = r.finish(10 * S, "received", false, None);
        assert_eq!((f.trips, f.long_trips), (2, 1));
        assert!(!f.trip_list[0].long && f.trip_list[1].long && f.trip_list[1].open);
        assert_eq!(f.trip_list[1].at_s, 4.5);
    }

    /// Exactly the timeout is no trip: it must be exceeded.
    #[test]
    fn a_wait_of_exactly_the_timeout_does_not_trip() {
        let mut r = Replay::new(parse("px4").unwrap());
        r.message(10 * S, true);
        let f = r.finish(20 * S, "received", false, None);
        assert_eq!(f.trips, 0);
        assert_eq!(f.closest_margin_s, Some(0.0));
    }

    /// 1 Hz against 5 s: five losses in a row; at 10 % loss over 1000 s,
    /// 1000 × 0.9 × 0.1^5.
    #[test]
    fn independent_losses_give_the_expected_trips() {
        let r = Replay::new(parse("ardupilot-copter").unwrap());
        let f = r.finish(1000 * S, "probes", true, Some(0.1));
        let e = f.expected_if_independent.unwrap();
        assert!((e - 1000.0 * 0.9 * 1e-5).abs() < 1e-12, "{e}");
    }
}
