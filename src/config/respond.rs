//! `mavping respond [OPTIONS] LINK` into a [`RespondConfig`].

use super::error::ConfigError;
use super::measure::validate_links;
use super::signing::signing;
use super::values::{validate_baud, validate_ids, MAX_TIMEOUT};
use crate::answering::ftp::MAX_FILE_SIZE;
use crate::answering::mission::MAX_ITEMS;
use crate::answering::params::MAX_PARAMS;
use crate::answering::transfers::ServeSpec;
use crate::cli::RespondArgs;
use crate::responder::ResponderSettings;
use crate::transport::address::LinkSpec;
use crate::transport::route::Route;
use crate::transport::LinkOptions;

/// `mavping respond`, validated.
#[derive(Debug, Clone)]
pub(crate) struct RespondConfig {
    /// Every link it answers on, one identity on all.
    pub(crate) links: Vec<LinkSpec>,
    pub(crate) link_options: LinkOptions,
    pub(crate) settings: ResponderSettings,
    pub(crate) verbose: u8,
}

impl TryFrom<&RespondArgs> for RespondConfig {
    type Error = ConfigError;

    fn try_from(cli: &RespondArgs) -> Result<Self, ConfigError> {
        let links = cli
            .links
            .iter()
            .map(|l| l.parse::<LinkSpec>())
            .collect::<Result<Vec<_>, _>>()?;
        if let Some(log) = links.iter().find(|l| l.is_log()) {
            return Err(ConfigError::value(
                "mavping respond",
                log,
                "a telemetry log is only read; answer on a live link",
            ));
        }
        validate_links(&cli.links, &links)?;
        for (flag, d) in [("--delay", cli.delay), ("--jitter", cli.jitter)] {
            if d > MAX_TIMEOUT {
                return Err(ConfigError::value(
                    flag,
                    humantime::format_duration(d),
                    "at most 1h",
                ));
            }
        }
        crate::telemetry::check_distinct(&cli.stream)
            .map_err(|e| ConfigError::rejected("--stream", e))?;
        if cli.stream_drop > 0.0 && cli.stream.is_empty() {
            return Err(ConfigError::Needs {
                setting: "--stream-drop",
                needs: "--stream MSG@HZ: nothing is streamed",
            });
        }
        Ok(RespondConfig {
            links,
            link_options: LinkOptions {
                baud: validate_baud(cli.baud)?,
                // A responder outlives its pingers: one that is not up yet
                // or restarts must not end it.
                reconnect: true,
                // Nor one whose tcp listener is not up yet.
                wait_for_peer: true,
                route: Route::default(),
                trust: crate::transport::ws::Trust::default(),
            },
            settings: ResponderSettings {
                id: validate_ids(cli.sysid, cli.compid)?,
                delay: cli.delay,
                jitter: cli.jitter,
                drop: cli.drop,
                dup: cli.dup,
                seed: cli.seed,
                answer_ping: !cli.no_ping,
                // A responder with a key answers only signed requests.
                signing: signing(&cli.signing, true)?,
                streams: cli.stream.clone(),
                stream_drop: cli.stream_drop,
                serve: serve_spec(cli)?,
                transfer_rate: transfer_rate(cli.transfer_rate)?,
            },
            verbose: cli.verbose,
        })
    }
}

/// `--params`, `--mission` and `--file-size`, each in its range.
fn serve_spec(cli: &RespondArgs) -> Result<ServeSpec, ConfigError> {
    let within = |flag: &str, value: i64, max: u32, what: &str| {
        u32::try_from(value)
            .ok()
            .filter(|v| *v <= max)
            .ok_or_else(|| {
                ConfigError::value(flag, value, format!("expected {what} from 0 to {max}"))
            })
    };
    Ok(ServeSpec {
        params: within("--params", cli.params, u32::from(MAX_PARAMS), "parameters")? as u16,
        mission: within(
            "--mission",
            cli.mission,
            u32::from(MAX_ITEMS),
            "mission items",
        )? as u16,
        file_size: within("--file-size", cli.file_size, MAX_FILE_SIZE, "bytes")?,
    })
}

/// Frames a second: above 0, at most a million (a frame a microsecond).
fn transfer_rate(hz: f64) -> Result<f64, ConfigError> {
    if hz.is_finite() && hz > 0.0 && hz <= 1e6 {
        Ok(hz)
    } else {
        Err(ConfigError::value(
            "--transfer-rate",
            hz,
            "expected frames a second above 0, at most 1000000",
        ))
    }
}

#[cfg(test)]
mod tests {
    use clap::Parser;

    use std::time::Duration;

    use super::*;
    use crate::cli::Cli;
    use crate::frame::SysComp;

    fn respond(args: &str) -> Result<RespondConfig, String> {
        let cli = Cli::try_parse_from(
            ["mavping", "respond"]
                .into_iter()
                .chain(args.split_whitespace()),
        )
        .map_err(|e| e.to_string())?;
        let Some(crate::cli::Mode::Respond(r)) = &cli.mode else {
            return Err("not respond".into());
        };
        RespondConfig::try_from(r).map_err(|e| e.to_string())
    }

    #[test]
    fn respond_signing() {
        let r = respond("--signing-key pass --signing-link-id 3 udpin:0.0.0.0:14550").unwrap();
        let s = r.settings.signing.unwrap();
        assert_eq!((s.link_id, s.require_signed), (3, true));
        assert!(respond("udpin:0.0.0.0:14550")
            .unwrap()
            .settings
            .signing
            .is_none());
    }

    #[test]
    fn respond_on_several_links() {
        let r = respond("udpin:0.0.0.0:14550 udpin:0.0.0.0:14551").unwrap();
        assert_eq!(r.links.len(), 2);
        let twice = respond("udpin:0.0.0.0:14550 udpin:0.0.0.0:14550").unwrap_err();
        assert!(twice.contains("names the same link"), "{twice}");
        let mixed = respond("sim:?clock=virtual udpin:0.0.0.0:14550").unwrap_err();
        assert!(mixed.contains("virtual"), "{mixed}");
        assert!(respond("").is_err());
    }

    #[test]
    fn respond_streams() {
        let r = respond(
            "--stream ATTITUDE@50,GLOBAL_POSITION_INT@5 --stream HEARTBEAT@2 --stream-drop 10 sim:",
        )
        .unwrap();
        let streams: Vec<String> = r.settings.streams.iter().map(ToString::to_string).collect();
        assert_eq!(
            streams,
            ["ATTITUDE@50", "GLOBAL_POSITION_INT@5", "HEARTBEAT@2"]
        );
        assert!((r.settings.stream_drop - 0.1).abs() < 1e-12);
        let r = respond("sim:").unwrap();
        assert!(r.settings.streams.is_empty() && r.settings.stream_drop == 0.0);
    }

    #[test]
    fn respond_lines() {
        let r = respond("udpin:0.0.0.0:14550").unwrap();
        assert_eq!(r.settings.id, SysComp::new(1, 1));
        assert!(r.settings.answer_ping);
        assert_eq!((r.settings.drop, r.settings.dup), (0.0, 0.0));
        let r = respond(
            "--sysid 7 --compid 2 --delay 5ms --jitter 1ms --drop 10% --dup 2.5 --seed 9 --no-ping sim:",
        )
        .unwrap();
        assert_eq!(r.settings.id, SysComp::new(7, 2));
        assert_eq!(
            (r.settings.delay, r.settings.jitter),
            (Duration::from_millis(5), Duration::from_millis(1))
        );
        assert!((r.settings.drop - 0.1).abs() < 1e-12 && (r.settings.dup - 0.025).abs() < 1e-12);
        assert!(!r.settings.answer_ping);
        let r = respond("--params 0 --mission 3 --file-size 7 --transfer-rate 50 sim:").unwrap();
        let s = r.settings.serve;
        assert_eq!((s.params, s.mission, s.file_size), (0, 3, 7));
        assert_eq!(r.settings.transfer_rate, 50.0);
        let s = respond("sim:").unwrap().settings;
        assert_eq!(
            (
                s.serve.params,
                s.serve.mission,
                s.serve.file_size,
                s.transfer_rate
            ),
            (500, 20, 65536, 1000.0)
        );
        for (args, needle) in [
            ("--drop 150 sim:", "'150' for '--drop <PCT>'"),
            ("--dup x sim:", "'x' for '--dup <PCT>'"),
            ("--sysid 0 sim:", "--sysid 0"),
            ("--delay 2h sim:", "at most 1h"),
            ("bogus:1:2", "accepted forms"),
            (
                "--stream ATTITUDE@0 sim:",
                "invalid value 'ATTITUDE@0' for '--stream <MSG@HZ>': 'ATTITUDE@0': the rate must \
                 be a number above 0",
            ),
            (
                "--stream RAW_IMU@10 sim:",
                "'RAW_IMU@10': unknown message RAW_IMU; expected MSG@HZ",
            ),
            (
                "--stream ATTITUDE@5 --stream ATTITUDE@6 sim:",
                "--stream: ATTITUDE is streamed twice",
            ),
            ("--stream-drop 10 sim:", "--stream-drop needs --stream"),
            (
                "--params 10001 sim:",
                "--params 10001: expected parameters from 0 to 10000",
            ),
            (
                "--mission -1 sim:",
                "--mission -1: expected mission items from 0 to 10000",
            ),
            (
                "--file-size 1073741825 sim:",
                "expected bytes from 0 to 1073741824",
            ),
            ("--file-size x sim:", "'x' for '--file-size <BYTES>'"),
            ("--transfer-rate 0 sim:", "expected frames a second above 0"),
            (
                "--transfer-rate inf sim:",
                "expected frames a second above 0",
            ),
            (
                "--stream ATTITUDE@5 --stream-drop 200 sim:",
                "'200' for '--stream-drop <PCT>'",
            ),
            ("", "CONNECTION"),
        ] {
            let err = respond(args).unwrap_err();
            assert!(err.contains(needle), "{args}: {err}");
        }
    }
}
