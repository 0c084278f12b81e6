//! `--report c2` and its settings into the engine's [`C2Config`].

use std::time::Duration;

use super::error::ConfigError;
use super::keys::Keys;
use crate::engine::c2::{C2Config, FailsafeModel, DEFAULT_FLOOR_PCT};
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

/// The report's settings, when it is asked for (`--report c2`, or a
/// threshold on one of its figures).
pub(crate) fn validate(f: &C2Flags<'_>) -> Result<Option<C2Config>, ConfigError> {
    let wanted = f.asked || f.min_availability.is_some() || f.min_continuity.is_some();
    let name = |key: &str| f.keys.name(key);
    if !wanted {
        if let Some(setting) = [
            (!f.failsafes.is_empty(), "failsafe"),
            (f.continuity_within.is_some(), "continuity_within"),
        ]
        .iter()
        .find_map(|(given, key)| given.then_some(*key))
        {
            return Err(ConfigError::value(
                name(setting),
                "",
                format!("needs {} c2", name("report")),
            ));
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
