//! `mavping respond [OPTIONS] LINK` into a [`RespondConfig`].

use super::{
    invalid, signing, validate_baud, validate_ids, ConfigError, RespondConfig, MAX_TIMEOUT,
};
use crate::cli::RespondArgs;
use crate::responder::ResponderSettings;
use crate::transport::address::LinkSpec;
use crate::transport::route::Route;
use crate::transport::LinkOptions;

impl TryFrom<&RespondArgs> for RespondConfig {
    type Error = ConfigError;

    fn try_from(cli: &RespondArgs) -> Result<Self, ConfigError> {
        let link: LinkSpec = cli.link.parse()?;
        for (flag, d) in [("--delay", cli.delay), ("--jitter", cli.jitter)] {
            if d > MAX_TIMEOUT {
                return Err(invalid(format!(
                    "{flag} {}: at most 1h",
                    humantime::format_duration(d)
                )));
            }
        }
        Ok(RespondConfig {
            link,
            link_options: LinkOptions {
                baud: validate_baud(cli.baud)?,
                // A responder outlives its pingers: one that is not up yet
                // or restarts must not end it.
                reconnect: true,
                route: Route::default(),
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
            },
            verbose: cli.verbose,
        })
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
        for (args, needle) in [
            ("--drop 150 sim:", "'150' for '--drop <PCT>'"),
            ("--dup x sim:", "'x' for '--dup <PCT>'"),
            ("--sysid 0 sim:", "--sysid 0"),
            ("--delay 2h sim:", "at most 1h"),
            ("bogus:1:2", "accepted forms"),
            ("", "CONNECTION"),
        ] {
            let err = respond(args).unwrap_err();
            assert!(err.contains(needle), "{args}: {err}");
        }
    }
}
