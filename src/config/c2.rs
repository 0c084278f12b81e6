//! `--report c2` and its settings into the engine's [`C2Config`].

use std::time::Duration;

use super::error::ConfigError;
use super::keys::Keys;
use crate::engine::c2::{
    C2Config, FailsafeModel, DEFAULT_DISTANCE_BAND_M, DEFAULT_FLOOR_PCT, DEFAULT_UP_WITHIN,
};
use crate::engine::Nanos;
use crate::units::parse_duration;

/// What the command line says of the C2 report.
pub(crate) struct C2Flags<'a> {
    /// How errors name the settings.
    pub(crate) keys: Keys,
    pub(crate) asked: bool,
    pub(crate) up_within: Duration,
    pub(crate) continuity_within: Option<Duration>,
    pub(crate) distance_band_m: f64,
    pub(crate) failsafes: &'a [String],
    /// `--min-availability`, %: also the distance bands' floor.
    pub(crate) min_availability: Option<f64>,
    /// `--min-continuity`, %.
    pub(crate) min_continuity: Option<f64>,
    /// The reply timeout (`-W`).
    pub(crate) timeout: Duration,
}

fn nanos(d: Duration) -> Nanos {
    Nanos::try_from(d.as_nanos()).unwrap_or(Nanos::MAX)
}

impl C2Flags<'_> {
    /// The report asked for and nothing else said (a `/probe` query's
    /// `report=c2`): every setting at its default.
    pub(crate) fn defaults(keys: Keys, timeout: Duration) -> Self {
        C2Flags {
            keys,
            asked: true,
            up_within: DEFAULT_UP_WITHIN,
            continuity_within: None,
            distance_band_m: DEFAULT_DISTANCE_BAND_M,
            failsafes: &[],
            min_availability: None,
            min_continuity: None,
            timeout,
        }
    }
}

/// The report's settings, when it is asked for (`--report c2`, or a
/// threshold on one of its figures).
pub(crate) fn validate(f: &C2Flags<'_>) -> Result<Option<C2Config>, ConfigError> {
    let wanted = f.asked || f.min_availability.is_some() || f.min_continuity.is_some();
    let name = |key: &str| f.keys.name(key);
    if !wanted {
        let flags = f.keys == Keys::Flags;
        if let Some(setting) = [
            (!f.failsafes.is_empty(), ["--failsafe", "failsafe"]),
            (
                f.continuity_within.is_some(),
                ["--continuity-within", "continuity_within"],
            ),
        ]
        .iter()
        .find_map(|(given, names)| given.then_some(names[usize::from(!flags)]))
        {
            return Err(ConfigError::Needs {
                setting,
                needs: if flags {
                    "--report c2"
                } else {
                    "report = \"c2\""
                },
            });
        }
        return Ok(None);
    }
    if f.up_within.is_zero() || f.up_within > Duration::from_secs(3600) {
        return Err(ConfigError::value(
            name("up_within"),
            humantime::format_duration(f.up_within),
            "expected more than 0 and at most 1h",
        ));
    }
    let continuity = f.continuity_within.unwrap_or(f.timeout);
    if continuity.is_zero() || continuity > f.timeout {
        return Err(ConfigError::value(
            name("continuity_within"),
            humantime::format_duration(continuity),
            "expected more than 0 and at most the reply timeout -W (a later reply is a loss)",
        ));
    }
    if !(f.distance_band_m.is_finite() && f.distance_band_m >= 1.0) {
        return Err(ConfigError::value(
            name("distance_band"),
            f.distance_band_m,
            "expected at least 1 (metres)",
        ));
    }
    let failsafes = f
        .failsafes
        .iter()
        .map(|text| {
            FailsafeModel::parse(text, |v| {
                parse_duration(v)
                    .map(|d| d.as_secs_f64())
                    .map_err(|e| e.to_string())
            })
            .map_err(|e| ConfigError::value(name("failsafe"), text, e.0))
        })
        .collect::<Result<Vec<_>, _>>()?;
    Ok(Some(C2Config {
        up_within: nanos(f.up_within),
        continuity_within: nanos(continuity),
        distance_band_m: f.distance_band_m,
        availability_floor_pct: f.min_availability.unwrap_or(DEFAULT_FLOOR_PCT),
        failsafes,
    }))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn flags(keys: Keys, asked: bool, failsafes: &[String]) -> C2Flags<'_> {
        C2Flags {
            asked,
            failsafes,
            ..C2Flags::defaults(keys, Duration::from_secs(2))
        }
    }

    #[test]
    fn the_reports_settings_without_it_say_what_they_need_in_each_front_ends_words() {
        let px4 = ["px4".to_string()];
        let e = validate(&flags(Keys::Flags, false, &px4)).unwrap_err();
        assert_eq!(e.to_string(), "--failsafe needs --report c2");
        let e = validate(&flags(Keys::File, false, &px4)).unwrap_err();
        assert_eq!(e.to_string(), "failsafe needs report = \"c2\"");
        assert_eq!(validate(&flags(Keys::Flags, false, &[])).unwrap(), None);
    }

    /// A threshold on a figure asks for the report; its floor holds the
    /// distance bands; continuity defaults to the reply timeout.
    #[test]
    fn a_threshold_implies_the_report_and_sets_the_floor() {
        let mut f = flags(Keys::Flags, false, &[]);
        f.min_availability = Some(99.5);
        let c = validate(&f).unwrap().unwrap();
        assert_eq!(c.availability_floor_pct, 99.5);
        assert_eq!(c.continuity_within, 2_000_000_000);
        assert!(c.failsafes.is_empty());
        f.continuity_within = Some(Duration::from_secs(3));
        let e = validate(&f).unwrap_err().to_string();
        assert!(e.starts_with("--continuity-within 3s: "), "{e}");
    }

    #[test]
    fn a_bad_model_is_named_with_its_setting() {
        let bad = ["custom:rate=1".to_string()];
        let e = validate(&flags(Keys::File, true, &bad))
            .unwrap_err()
            .to_string();
        assert_eq!(
            e,
            "failsafe custom:rate=1: failsafe custom: give its timeout (timeout=DURATION)"
        );
    }
}
