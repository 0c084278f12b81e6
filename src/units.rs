//! The value parsers every layer shares (options, `sim:` keys, `respond`
//! emulation): one for durations, one for percentages. They say what is
//! wrong with the value; callers add which option or key it was.

use std::time::Duration;

use thiserror::Error;

/// The longest duration any option takes: anything longer is a typo, and
/// would overflow the clock arithmetic (`Instant + Duration`) that
/// schedules it.
pub const MAX_DURATION: Duration = Duration::from_secs(365 * 86_400);

/// What is wrong with a duration; the text given is quoted.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
pub enum DurationError {
    /// A number, but not of zero or more seconds (negative, not finite).
    #[error("'{0}' is not a duration of zero or more seconds")]
    NotZeroOrMore(String),
    /// Neither a number nor a duration humantime reads.
    #[error("'{text}': {reason} (e.g. 250ms, 2s, 1m)")]
    Unreadable { text: String, reason: String },
    /// Longer than the option allows (`limit` as said to the user).
    #[error("'{text}': at most {limit}")]
    TooLong { text: String, limit: String },
}

/// What is wrong with a percentage; the text given is quoted.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
#[error("'{0}' is not a percentage from 0 to 100")]
pub struct PercentError(pub String);

/// "250ms", "2s", "1m30s", or a plain number of seconds ("0.2"), at most a
/// year.
pub fn parse_duration(s: &str) -> Result<Duration, DurationError> {
    parse_duration_up_to(s, MAX_DURATION)
}

/// As [`parse_duration`], at most `max`.
pub fn parse_duration_up_to(s: &str, max: Duration) -> Result<Duration, DurationError> {
    let d = match s.parse::<f64>() {
        Ok(secs) => Duration::try_from_secs_f64(secs)
            .map_err(|_| DurationError::NotZeroOrMore(s.to_string()))?,
        Err(_) => humantime::parse_duration(s).map_err(|e| DurationError::Unreadable {
            text: s.to_string(),
            reason: e.to_string(),
        })?,
    };
    if d > max {
        // humantime counts a year as 365.25 days: say what the limit is.
        let limit = if max == MAX_DURATION {
            "365 days".to_string()
        } else {
            humantime::format_duration(max).to_string()
        };
        return Err(DurationError::TooLong {
            text: s.to_string(),
            limit,
        });
    }
    Ok(d)
}

/// "5%", "0.5%" or "5" (all percent), 0 to 100, as a ratio 0..=1.
pub fn parse_percent(s: &str) -> Result<f64, PercentError> {
    let number = s.strip_suffix('%').unwrap_or(s);
    match number.parse::<f64>() {
        Ok(p) if (0.0..=100.0).contains(&p) => Ok(p / 100.0),
        _ => Err(PercentError(s.to_string())),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn durations() {
        assert_eq!(parse_duration("0.2"), Ok(Duration::from_millis(200)));
        assert_eq!(parse_duration("1m30s"), Ok(Duration::from_secs(90)));
        assert_eq!(
            parse_duration("-1").unwrap_err().to_string(),
            "'-1' is not a duration of zero or more seconds"
        );
        assert!(parse_duration("soon")
            .unwrap_err()
            .to_string()
            .starts_with("'soon': "));
        assert!(parse_duration("soon")
            .unwrap_err()
            .to_string()
            .ends_with(" (e.g. 250ms, 2s, 1m)"));
        assert_eq!(
            parse_duration("400d").unwrap_err().to_string(),
            "'400d': at most 365 days"
        );
        assert_eq!(
            parse_duration_up_to("2h", Duration::from_secs(3600))
                .unwrap_err()
                .to_string(),
            "'2h': at most 1h"
        );
    }

    #[test]
    fn percentages() {
        assert_eq!(parse_percent("5%"), Ok(0.05));
        assert_eq!(parse_percent("100"), Ok(1.0));
        assert_eq!(parse_percent("0.5"), Ok(0.005));
        for bad in ["101", "-1%", "x", "NaN"] {
            assert_eq!(
                parse_percent(bad).unwrap_err().to_string(),
                format!("'{bad}' is not a percentage from 0 to 100")
            );
        }
    }
}
