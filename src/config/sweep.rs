//! `--sweep`, `--load` and their options into each link's [`SweepConfig`]:
//! which rates, how long a step, how far (by default twice what a serial
//! link's baud rate carries: a sweep floods the link on purpose).

use std::time::Duration;

use super::error::ConfigError;
use super::probe::ECHO_PROBES;
use super::values::MAX_RATE;
use crate::cli::{PingArgs, ProbeKind};
use crate::engine::sweep::{MaxFrom, PlanKind, SweepConfig};
use crate::engine::SessionConfig;

/// The highest rate a sweep offers on a link without a baud rate, unless
/// `--sweep-max` says otherwise.
pub(super) const DEFAULT_SWEEP_MAX_HZ: f64 = 1000.0;
/// The first step of a sweep when neither `--rate` nor `-i` is given.
const DEFAULT_FIRST_HZ: f64 = 2.0;
/// The rate of a `--load` run without `--sweep`, `--rate` or `-i`.
const DEFAULT_LOAD_RATE_HZ: f64 = 10.0;
const DEFAULT_STEP: Duration = Duration::from_secs(5);
const DEFAULT_LOSS_LIMIT: f64 = 0.2;
const MIN_STEP: Duration = Duration::from_millis(100);
const MAX_STEP: Duration = Duration::from_secs(3600);
/// With the default maximum, a sweep offers up to this many times what the
/// baud rate carries.
const BAUD_HEADROOM: f64 = 2.0;

/// Whether the run goes in steps.
pub(super) fn wanted(cli: &PingArgs) -> bool {
    cli.sweep || !cli.load.is_empty()
}

/// The options that only a run in steps takes, and those it cannot take.
pub(super) fn validate_flags(cli: &PingArgs) -> Result<(), ConfigError> {
    if !cli.sweep {
        for (set, flag) in [
            (cli.sweep_max.is_some(), "--sweep-max"),
            (cli.sweep_loss.is_some(), "--sweep-loss"),
        ] {
            if set {
                return Err(ConfigError::Needs {
                    setting: flag,
                    needs: "--sweep",
                });
            }
        }
        if cli.step.is_some() && cli.load.is_empty() {
            return Err(ConfigError::Needs {
                setting: "--step",
                needs: "--sweep or --load",
            });
        }
    }
    if !wanted(cli) {
        return Ok(());
    }
    let what = if cli.sweep { "--sweep" } else { "--load" };
    if matches!(
        cli.probe,
        ProbeKind::Command | ProbeKind::Params | ProbeKind::Mission | ProbeKind::Ftp
    ) {
        return Err(ConfigError::WorksWith {
            setting: what,
            with: ECHO_PROBES,
        });
    }
    if cli.count.is_some() {
        return Err(ConfigError::Other(format!(
            "{what} runs in steps of --step each; -c does not apply"
        )));
    }
    if cli.sweep {
        let thresholds =
            cli.max_loss.is_some() || !cli.max_rtt.is_empty() || cli.max_jitter.is_some();
        if thresholds {
            return Err(ConfigError::Other(
                "--sweep loses on purpose past the knee: --max-loss, --max-rtt and --max-jitter \
                 judge a whole run, not a sweep"
                    .into(),
            ));
        }
    }
    if let Some(step) = cli.step {
        if !(MIN_STEP..=MAX_STEP).contains(&step) {
            return Err(ConfigError::value(
                "--step",
                humantime::format_duration(step),
                "expected 100ms to 1h",
            ));
        }
    }
    if cli.sweep_loss.is_some_and(|l| l <= 0.0) {
        return Err(ConfigError::value(
            "--sweep-loss",
            0,
            "expected more than 0%",
        ));
    }
    Ok(())
}

/// The rate of the first step (a sweep) or of both steps (`--load`),
/// when `--rate` and `-i` leave it to us.
pub(super) fn default_rate(cli: &PingArgs) -> Option<f64> {
    match (cli.rate, cli.interval) {
        (None, None) if cli.sweep => Some(DEFAULT_FIRST_HZ),
        (None, None) if !cli.load.is_empty() => Some(DEFAULT_LOAD_RATE_HZ),
        _ => None,
    }
}

/// The highest rate a sweep of `session` may offer, and why.
pub(super) fn sweep_max(cli: &PingArgs, session: &SessionConfig) -> (f64, MaxFrom) {
    if let Some(max) = cli.sweep_max {
        return (max, MaxFrom::Given);
    }
    match session.wire {
        Some(w) => (
            (BAUD_HEADROOM * w.max_rate_hz).round(),
            MaxFrom::Baud {
                baud: w.baud,
                capacity_hz: w.max_rate_hz,
            },
        ),
        None => (DEFAULT_SWEEP_MAX_HZ, MaxFrom::Default),
    }
}

/// A link's steps; `None` when the run does not go in steps.
pub(super) fn for_link(
    cli: &PingArgs,
    session: &SessionConfig,
) -> Result<Option<SweepConfig>, ConfigError> {
    if !wanted(cli) {
        return Ok(None);
    }
    let first_hz = 1.0 / session.interval.as_secs_f64();
    let plan = if cli.sweep {
        let (max_hz, max_from) = sweep_max(cli, session);
        if !max_hz.is_finite() || max_hz <= first_hz || max_hz > MAX_RATE {
            return Err(ConfigError::value(
                "--sweep-max",
                max_hz,
                format!(
                    "expected more than the first step's {first_hz}/s and at most {MAX_RATE} \
                     requests per second"
                ),
            ));
        }
        PlanKind::Sweep {
            first_hz,
            max_hz,
            max_from,
            loss_limit: cli.sweep_loss.unwrap_or(DEFAULT_LOSS_LIMIT),
        }
    } else {
        PlanKind::Load { rate_hz: first_hz }
    };
    let signed = session.signing.is_some();
    Ok(Some(SweepConfig {
        plan,
        step: cli.step.unwrap_or(DEFAULT_STEP),
        load: cli.load.clone(),
        load_bytes_per_s: cli
            .load
            .iter()
            .map(|l| l.bytes_per_s(session.version, signed))
            .fold(0.0, |a, b| a + b),
    }))
}

/// The fastest rate a link's steps offer: what the pending table is
/// sized for.
pub(super) fn fastest_hz(sweep: &SweepConfig) -> f64 {
    match sweep.plan {
        PlanKind::Sweep { max_hz, .. } => max_hz,
        PlanKind::Load { rate_hz } => rate_hz,
    }
}
