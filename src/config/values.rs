//! Values every front end checks alike (the command line, `respond` and
//! the serve file): addresses to listen on, the baud rate, our ids, and
//! the bounds on rates and timeouts.

use std::net::SocketAddr;
use std::time::Duration;

use super::error::ConfigError;
use crate::frame::SysComp;

/// `--prometheus`, `--listen`: a numeric address, so nothing is resolved
/// behind the user's back (and `localhost` cannot silently mean IPv6 only).
pub(super) fn validate_listen(flag: &str, arg: &str) -> Result<SocketAddr, ConfigError> {
    arg.parse().map_err(|_| {
        ConfigError::value(
            flag,
            arg,
            "expected ADDR:PORT, e.g. 127.0.0.1:9090, 0.0.0.0:9090 or [::1]:9090",
        )
    })
}

/// The highest request rate (requests per second).
pub(super) const MAX_RATE: f64 = 1_000_000.0;

/// Longest reply timeout, retry interval or emulated delay.
pub(super) const MAX_TIMEOUT: Duration = Duration::from_secs(3600);

pub(super) fn validate_baud(baud: u32) -> Result<u32, ConfigError> {
    if baud == 0 {
        return Err(ConfigError::value(
            "--baud",
            0,
            "expected a baud rate such as 57600 or 115200",
        ));
    }
    Ok(baud)
}

pub(super) fn validate_ids(sysid: u8, compid: u8) -> Result<SysComp, ConfigError> {
    if sysid == 0 {
        return Err(ConfigError::value(
            "--sysid",
            0,
            "0 means 'broadcast'; use 1-255 (ground stations use 250-255)",
        ));
    }
    if compid == 0 {
        return Err(ConfigError::value(
            "--compid",
            0,
            "0 means 'all components'; use 1-255 (190 is a GCS)",
        ));
    }
    Ok(SysComp::new(sysid, compid))
}
