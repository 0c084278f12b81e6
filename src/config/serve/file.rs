//! The `mavping serve` TOML file as written, and its tables into modules
//! and continuous links. One table type serves both, so each key is parsed
//! once; keys that belong to the other kind are refused by name.

use crate::engine::c2::{C2Config, DEFAULT_DISTANCE_BAND_M, DEFAULT_UP_WITHIN};
use crate::engine::radio::RadioType;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::Duration;

use clap::ValueEnum;
use serde::Deserialize;

use super::limits::{
    validate_count, validate_probe_interval, validate_timeout, MAX_PROBE_TIMEOUT,
    MIN_PROBE_INTERVAL,
};
use super::session::{refuse_virtual, session, Common};
use super::settings::{ContinuousLink, Module};
use crate::cli::{parse_expected, parse_rtt_limit, ProbeKind, SigningArgs};
use crate::config::c2::C2Flags;
use crate::config::error::ConfigError;
use crate::config::keys::Keys;
use crate::config::link::LinkConfig;
use crate::config::probe::{probe_of, Probe, ProbeChoice};
use crate::config::signing::signing;
use crate::config::values::{validate_baud, validate_ids, MAX_TIMEOUT};
use crate::frame::{SysComp, Version};
use crate::transport::address::LinkSpec;
use crate::transport::route::Route;
use crate::transport::{serial, LinkOptions};
use crate::units::{parse_duration, parse_percent};
use crate::verdict::Thresholds;

/// The probes a module or a `/probe` request may name.
pub(super) const PROBES: &str = "auto, ping, timesync or command";

/// The shortest silence threshold a passive link takes, as `--gap`.
const MIN_GAP: Duration = Duration::from_millis(10);

/// A duration in the file: `"250ms"`, `"2s"`, or a number of seconds.
#[derive(Debug, Clone, Deserialize)]
#[serde(untagged)]
enum FileDuration {
    Text(String),
    Seconds(f64),
}

impl FileDuration {
    fn get(&self, key: &str) -> Result<Duration, ConfigError> {
        match self {
            FileDuration::Text(t) => parse_duration(t),
            FileDuration::Seconds(s) => parse_duration(&s.to_string()),
        }
        .map_err(|e| ConfigError::rejected(key, e))
    }
}

/// The file as written. One table type for modules and links, so each key
/// is parsed once; keys that belong to the other kind are refused by name.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct File {
    pub(super) listen: Option<String>,
    pub(super) max_concurrent: Option<usize>,
    #[serde(default)]
    pub(super) allow: Vec<String>,
    #[serde(default)]
    pub(super) module: BTreeMap<String, Table>,
    #[serde(default)]
    pub(super) link: Vec<Table>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct Table {
    // [[link]] only
    link: Option<String>,
    name: Option<String>,
    rate: Option<f64>,
    passive: Option<bool>,
    gap: Option<FileDuration>,
    // [module.NAME] only
    count: Option<u64>,
    max_loss: Option<String>,
    #[serde(default)]
    max_rtt: Vec<String>,
    max_jitter: Option<FileDuration>,
    #[serde(default)]
    expect: Vec<String>,
    min_responders: Option<usize>,
    // both
    probe: Option<String>,
    interval: Option<FileDuration>,
    timeout: Option<FileDuration>,
    target: Option<String>,
    command: Option<String>,
    path: Option<String>,
    retry_interval: Option<FileDuration>,
    retries: Option<u8>,
    sysid: Option<u8>,
    compid: Option<u8>,
    mavlink: Option<u8>,
    heartbeat: Option<bool>,
    signing_key_file: Option<PathBuf>,
    signing_link_id: Option<u8>,
    require_signed: Option<bool>,
    baud: Option<u32>,
    radio_type: Option<String>,
    // The C2 link report (both; its thresholds module only)
    report: Option<String>,
    up_within: Option<FileDuration>,
    continuity_within: Option<FileDuration>,
    distance_band: Option<f64>,
    #[serde(default)]
    failsafe: Vec<String>,
    min_availability: Option<String>,
    min_continuity: Option<String>,
}

impl Table {
    /// Keys set here that only the other kind of table takes.
    pub(super) fn misplaced(&self, module: bool) -> Option<&'static str> {
        let link_only = [
            ("link", self.link.is_some()),
            ("name", self.name.is_some()),
            ("rate", self.rate.is_some()),
            ("passive", self.passive.is_some()),
            ("gap", self.gap.is_some()),
        ];
        let module_only = [
            ("count", self.count.is_some()),
            ("max_loss", self.max_loss.is_some()),
            ("max_rtt", !self.max_rtt.is_empty()),
            ("max_jitter", self.max_jitter.is_some()),
            ("expect", !self.expect.is_empty()),
            ("min_responders", self.min_responders.is_some()),
            ("min_availability", self.min_availability.is_some()),
            ("min_continuity", self.min_continuity.is_some()),
        ];
        let wrong: &[(&str, bool)] = if module { &link_only } else { &module_only };
        wrong.iter().find(|(_, set)| *set).map(|(k, _)| *k)
    }

    pub(super) fn common(&self, default_timeout: Duration) -> Result<Common, ConfigError> {
        let kind = match &self.probe {
            None => ProbeKind::Ping,
            Some(p) => ProbeKind::from_str(p, true).map_err(|_| ConfigError::Unknown {
                setting: "probe",
                value: p.clone(),
                expected: PROBES,
            })?,
        };
        let retry_interval = match &self.retry_interval {
            Some(d) => d.get("retry_interval")?,
            None => Duration::from_millis(100),
        };
        let timeout = match &self.timeout {
            Some(d) => validate_timeout("timeout", d.get("timeout")?, MAX_TIMEOUT)?,
            None => default_timeout,
        };
        let probe = probe_of(
            Keys::File,
            &ProbeChoice {
                kind,
                target: self.target.as_deref(),
                command: self.command.as_deref().unwrap_or("REQUEST_MESSAGE,0"),
                retry_interval,
                retries: self.retries.unwrap_or(3),
                timeout,
                path: self.path(),
            },
        )?;
        let version = match self.mavlink.unwrap_or(2) {
            1 => Version::V1,
            2 => Version::V2,
            v => return Err(ConfigError::value("mavlink", v, "expected 1 or 2")),
        };
        let signing = match &self.signing_key_file {
            None if self.require_signed.is_some() => {
                return Err(ConfigError::Needs {
                    setting: "require_signed",
                    needs: "signing_key_file",
                })
            }
            None => None,
            Some(path) => signing(
                &SigningArgs {
                    signing_key: None,
                    signing_key_file: Some(path.clone()),
                    signing_link_id: self.signing_link_id.unwrap_or(0),
                },
                self.require_signed.unwrap_or(false),
            )?,
        };
        if signing.is_some() && version == Version::V1 {
            return Err(ConfigError::SignedMavlink1 {
                mavlink: "mavlink",
                hint: "",
            });
        }
        Ok(Common {
            probe,
            kind,
            ours: validate_ids(
                self.sysid.unwrap_or(SysComp::OURS.sysid),
                self.compid.unwrap_or(SysComp::OURS.compid),
            )?,
            version,
            heartbeat: self.heartbeat.unwrap_or(true),
            signing,
            baud: validate_baud(self.baud.unwrap_or(serial::DEFAULT_BAUD))?,
            radio_type: radio_type(self.radio_type.as_deref())?,
            c2: self.c2(timeout)?,
            timeout,
            retry_interval,
        })
    }

    /// A module's or link's C2 report (`report = "c2"`), its thresholds
    /// a module's.
    fn c2(&self, timeout: Duration) -> Result<Option<C2Config>, ConfigError> {
        let asked = match self.report.as_deref() {
            None => false,
            Some("c2") => true,
            Some(other) => {
                return Err(ConfigError::Unknown {
                    setting: "report",
                    value: other.to_string(),
                    expected: "c2",
                })
            }
        };
        crate::config::c2::validate(&C2Flags {
            keys: Keys::File,
            asked,
            up_within: match &self.up_within {
                Some(d) => d.get("up_within")?,
                None => DEFAULT_UP_WITHIN,
            },
            continuity_within: self
                .continuity_within
                .as_ref()
                .map(|d| d.get("continuity_within"))
                .transpose()?,
            distance_band_m: self.distance_band.unwrap_or(DEFAULT_DISTANCE_BAND_M),
            failsafes: &self.failsafe,
            min_availability: Self::percent("min_availability", self.min_availability.as_deref())?,
            min_continuity: Self::percent("min_continuity", self.min_continuity.as_deref())?,
            timeout,
        })
    }

    /// A percentage key, as a percentage.
    fn percent(key: &str, value: Option<&str>) -> Result<Option<f64>, ConfigError> {
        value
            .map(|p| {
                parse_percent(p)
                    .map(|r| r * 100.0)
                    .map_err(|e| ConfigError::rejected(key, e))
            })
            .transpose()
    }

    pub(super) fn module(&self) -> Result<Module, ConfigError> {
        let c = self.common(Duration::from_secs(1))?;
        // A download module makes one download a scrape unless told more.
        let downloads = matches!(c.probe, Probe::Transfer(_));
        let count = self.count.unwrap_or(if downloads { 1 } else { 10 });
        validate_count(count)?;
        let interval = match &self.interval {
            Some(d) => validate_probe_interval("interval", d.get("interval")?)?,
            None => Duration::from_millis(100),
        };
        if c.timeout > MAX_PROBE_TIMEOUT {
            return Err(ConfigError::value(
                "timeout",
                humantime::format_duration(c.timeout),
                "a probe's timeout is at most 1m",
            ));
        }
        let thresholds = Thresholds {
            max_loss: self
                .max_loss
                .as_deref()
                .map(|p| parse_percent(p).map_err(|e| ConfigError::rejected("max_loss", e)))
                .transpose()?,
            max_rtt: self
                .max_rtt
                .iter()
                .map(|r| {
                    parse_rtt_limit(r).map_err(|e| ConfigError::rejected(format!("max_rtt {r}"), e))
                })
                .collect::<Result<_, _>>()?,
            max_jitter: self
                .max_jitter
                .as_ref()
                .map(|d| d.get("max_jitter"))
                .transpose()?,
            // Ages are a listening run's; /probe runs are short probes.
            max_age: None,
            max_transfer_time: None,
            min_availability: Self::percent("min_availability", self.min_availability.as_deref())?,
            min_continuity: Self::percent("min_continuity", self.min_continuity.as_deref())?,
            expect: self
                .expect
                .iter()
                .map(|e| parse_expected(e).map_err(|m| ConfigError::rejected("expect", m)))
                .collect::<Result<_, _>>()?,
            min_responders: match self.min_responders {
                Some(0) => {
                    return Err(ConfigError::value(
                        "min_responders",
                        0,
                        "expected at least 1",
                    ))
                }
                n => n,
            },
        };
        Ok(Module {
            kind: c.kind,
            target: self.target.clone(),
            command: self
                .command
                .clone()
                .unwrap_or_else(|| "REQUEST_MESSAGE,0".into()),
            retry_interval: c.retry_interval,
            retries: self.retries.unwrap_or(3),
            path: self.path().to_string(),
            count,
            interval,
            timeout: c.timeout,
            thresholds,
            ours: c.ours,
            version: c.version,
            heartbeat: c.heartbeat,
            signing: c.signing,
            baud: c.baud,
            radio_type: c.radio_type,
            c2: c.c2,
        })
    }

    /// The file an FTP download reads: ArduPilot's parameters unless named.
    fn path(&self) -> &str {
        self.path.as_deref().unwrap_or("@PARAM/param.pck")
    }

    /// A key that says how to probe, set in a table that sends no probes.
    fn probing_key(&self) -> Option<&'static str> {
        [
            ("probe", self.probe.is_some()),
            ("rate", self.rate.is_some()),
            ("interval", self.interval.is_some()),
            ("timeout", self.timeout.is_some()),
            ("target", self.target.is_some()),
            ("command", self.command.is_some()),
            ("path", self.path.is_some()),
            ("retry_interval", self.retry_interval.is_some()),
            ("retries", self.retries.is_some()),
        ]
        .into_iter()
        .find(|(_, set)| *set)
        .map(|(k, _)| k)
    }

    /// `passive = true`: the link's own traffic, no probes (`--passive`),
    /// with `gap` as `--gap`; `None` for a probed link.
    fn passive_probe(&self) -> Result<Option<Probe>, ConfigError> {
        let gap = self.gap.as_ref().map(|g| g.get("gap")).transpose()?;
        if self.passive != Some(true) {
            return match gap {
                Some(_) => Err(ConfigError::Needs {
                    setting: "gap",
                    needs: "passive = true",
                }),
                None => Ok(None),
            };
        }
        if let Some(key) = self.probing_key() {
            return Err(ConfigError::Other(format!(
                "passive = true sends no probes: drop {key}, or drop passive to probe the link"
            )));
        }
        if gap.is_some_and(|g| g < MIN_GAP) {
            return Err(ConfigError::Expected {
                setting: "gap",
                expected: "at least 10ms",
            });
        }
        Ok(Some(Probe::Passive { gap }))
    }

    pub(super) fn continuous(&self) -> Result<ContinuousLink, ConfigError> {
        let Some(given) = &self.link else {
            return Err(ConfigError::Needs {
                setting: "a [[link]]",
                needs: "link = \"CONNECTION\", e.g. link = \"udpout:10.0.0.2:14550\"",
            });
        };
        let mut c = self.common(Duration::from_secs(2))?;
        if let Some(passive) = self.passive_probe()? {
            c.probe = passive;
            return continuous_link(given, self.name.as_deref(), Duration::from_secs(1), c);
        }
        let interval = match (self.rate, &self.interval) {
            (Some(_), Some(_)) => {
                return Err(ConfigError::GiveOne {
                    first: "rate",
                    second: "interval",
                })
            }
            (Some(rate), None) => {
                if !rate.is_finite() || !(1.0 / 86_400.0..=1000.0).contains(&rate) {
                    return Err(ConfigError::value(
                        "rate",
                        rate,
                        "expected at least one request a day and at most 1000 a second",
                    ));
                }
                Duration::from_secs_f64(1.0 / rate)
            }
            (None, Some(d)) => {
                let d = d.get("interval")?;
                if d < MIN_PROBE_INTERVAL || d > Duration::from_secs(86_400) {
                    return Err(ConfigError::value(
                        "interval",
                        humantime::format_duration(d),
                        "expected 1ms to 1 day",
                    ));
                }
                d
            }
            (None, None) => Duration::from_secs(1),
        };
        continuous_link(given, self.name.as_deref(), interval, c)
    }
}

pub(super) fn continuous_link(
    given: &str,
    name: Option<&str>,
    interval: Duration,
    c: Common,
) -> Result<ContinuousLink, ConfigError> {
    let spec: LinkSpec = given.parse()?;
    refuse_virtual(&spec)?;
    let name = name.unwrap_or(given).trim().to_string();
    if name.is_empty() {
        return Err(ConfigError::value("link", given, "its name is empty"));
    }
    Ok(ContinuousLink {
        link: LinkConfig {
            session: session(&spec, &name, None, interval, c.timeout, &c)?,
            spec,
            name,
            thresholds: Thresholds::default(),
        },
        probe: c.probe,
        options: LinkOptions {
            baud: c.baud,
            // A broken link is reopened by the server, with backoff, so
            // it shows as down meanwhile.
            reconnect: false,
            wait_for_peer: false,
            route: Route::default(),
            trust: crate::transport::ws::Trust::default(),
        },
    })
}

/// The built-in module: ten PINGs, 100 ms apart, 1 s timeout.
pub(super) fn default_module() -> Module {
    Table::default()
        .module()
        .expect("the default module is valid")
}

/// "FILE:LINE: message" from a TOML error, on one line.
pub(super) fn file_error(path: &Path, text: &str, e: &toml::de::Error) -> ConfigError {
    let line = e
        .span()
        .map(|s| text[..s.start.min(text.len())].matches('\n').count() + 1);
    let message = e.message().lines().next().unwrap_or("invalid TOML");
    let place = match line {
        Some(line) => format!("{}:{line}", path.display()),
        None => path.display().to_string(),
    };
    ConfigError::Syntax {
        place,
        message: message.to_string(),
    }
}

/// Names the file and the table an error is about.
pub(super) fn within(path: &Path, table: &str, e: ConfigError) -> ConfigError {
    e.within(format!("{}: {table}", path.display()))
}

/// `radio_type = "..."`: as `--radio-type`.
fn radio_type(value: Option<&str>) -> Result<RadioType, ConfigError> {
    let all = [
        RadioType::Auto,
        RadioType::Sik,
        RadioType::Mlrs,
        RadioType::Elrs,
        RadioType::Esp,
        RadioType::Raw,
    ];
    match value {
        None => Ok(RadioType::Auto),
        Some(v) => all
            .into_iter()
            .find(|t| t.as_str() == v)
            .ok_or_else(|| ConfigError::Unknown {
                setting: "radio_type",
                value: v.to_string(),
                expected: "auto, sik, mlrs, elrs, esp or raw",
            }),
    }
}
