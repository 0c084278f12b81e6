//! The value parsers every layer shares (options, `sim:` keys, `respond`
//! emulation): one for durations, one for percentages. They say what is
//! wrong with the value; callers add which option or key it was.

use std::time::Duration;

/// The longest duration any option takes: anything longer is a typo, and
/// would overflow the clock arithmetic (`Instant + Duration`) that
/// schedules it.
pub const MAX_DURATION: Duration = Duration::from_secs(365 * 86_400);

/// "250ms", "2s", "1m30s", or a plain number of seconds ("0.2"), at most a
/// year.
pub fn parse_duration(s: &str) -> Result<Duration, String> {
    parse_duration_up_to(s, MAX_DURATION)
}

/// As [`parse_duration`], at most `max`.
pub fn parse_duration_up_to(s: &str, max: Duration) -> Result<Duration, String> {
    let d = match s.parse::<f64>() {
        Ok(secs) => Duration::try_from_secs_f64(secs)
            .map_err(|_| format!("'{s}' is not a duration of zero or more seconds"))?,
        Err(_) => {
            humantime::parse_duration(s).map_err(|e| format!("'{s}': {e} (e.g. 250ms, 2s, 1m)"))?
        }
    };
    if d > max {
        // humantime counts a year as 365.25 days: say what the limit is.
        let limit = if max == MAX_DURATION {
            "365 days".to_string()
        } else {
            humantime::format_duration(max).to_string()
        };
        return Err(format!("'{s}': at most {limit}"));
    }
    Ok(d)
}

/// "5%", "0.5%" or "5" (all percent), 0 to 100, as a ratio 0..=1.
pub fn parse_percent(s: &str) -> Result<f64, String> {
    let number = s.strip_suffix('%').unwrap_or(s);
    match number.parse::<f64>() {
        Ok(p) if (0.0..=100.0).contains(&p) => Ok(p / 100.0),
        _ => Err(format!("'{s}' is not a percentage from 0 to 100")),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn durations() {
        assert_eq!(parse_duration("0.2"), Ok(Duration::from_millis(200)));
        assert_eq!(parse_duration("1m30s"), Ok(Duration::from_secs(90)));
        assert!(parse_duration("-1").unwrap_err().contains("zero or more"));
        assert!(parse_duration("soon").unwrap_err().contains("e.g. 250ms"));
        assert!(parse_duration("400d")
            .unwrap_err()
            .contains("at most 365 days"));
    }

    #[test]
    fn percentages() {
        assert_eq!(parse_percent("5%"), Ok(0.05));
        assert_eq!(parse_percent("100"), Ok(1.0));
        assert_eq!(parse_percent("0.5"), Ok(0.005));
        for bad in ["101", "-1%", "x", "NaN"] {
            assert!(
                parse_percent(bad).unwrap_err().contains("percentage"),
                "{bad}"
            );
        }
    }
}
