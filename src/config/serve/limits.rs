//! A server's defaults and what it takes at most, with the checks that
//! hold a module or a `/probe` request to them.

use std::time::Duration;

use crate::config::error::ConfigError;

/// `mavping serve` listens here unless told otherwise: this machine only.
pub(super) const DEFAULT_LISTEN: &str = "127.0.0.1:9465";
/// Probes at once unless told otherwise.
pub(super) const DEFAULT_MAX_CONCURRENT: usize = 16;
pub(super) const MAX_CONCURRENT: usize = 1024;
/// The module `/probe` uses when none is named, unless the file defines one.
pub(super) const DEFAULT_MODULE: &str = "default";
/// Bounds on what a `/probe` request may ask: a remote caller must not
/// turn the exporter into a flood or tie it up for long.
pub(super) const MAX_PROBE_COUNT: u64 = 10_000;
pub(super) const MIN_PROBE_INTERVAL: Duration = Duration::from_millis(1);
pub(super) const MAX_PROBE_INTERVAL: Duration = Duration::from_secs(60);
pub(super) const MAX_PROBE_TIMEOUT: Duration = Duration::from_secs(60);
/// Most continuous links one server runs.
pub(super) const MAX_LINKS: usize = 10_000;

pub(super) fn validate_count(count: u64) -> Result<u64, ConfigError> {
    if count == 0 || count > MAX_PROBE_COUNT {
        return Err(ConfigError::value(
            "count",
            count,
            format!("expected 1 to {MAX_PROBE_COUNT}"),
        ));
    }
    Ok(count)
}

pub(super) fn validate_probe_interval(key: &str, d: Duration) -> Result<Duration, ConfigError> {
    if d < MIN_PROBE_INTERVAL || d > MAX_PROBE_INTERVAL {
        return Err(ConfigError::value(
            key,
            humantime::format_duration(d),
            "a probe's interval is 1ms to 1m",
        ));
    }
    Ok(d)
}

pub(super) fn validate_timeout(
    key: &str,
    d: Duration,
    max: Duration,
) -> Result<Duration, ConfigError> {
    if d.is_zero() || d > max {
        return Err(ConfigError::value(
            key,
            humantime::format_duration(d),
            format!(
                "expected more than 0 and at most {}",
                humantime::format_duration(max)
            ),
        ));
    }
    Ok(d)
}
