//! `mavping compare [OPTIONS] A.json B.json` into a [`CompareConfig`].

use std::path::PathBuf;

use super::error::ConfigError;
use crate::cli::CompareArgs;
use crate::compare::{Options, SourceFilter};

/// `mavping compare`, validated.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct CompareConfig {
    pub(crate) a: PathBuf,
    pub(crate) b: PathBuf,
    pub(crate) json: bool,
    pub(crate) options: Options,
    pub(crate) fail_if_worse: bool,
}

impl TryFrom<&CompareArgs> for CompareConfig {
    type Error = ConfigError;

    fn try_from(cli: &CompareArgs) -> Result<Self, ConfigError> {
        let source = cli.source.as_deref().map(parse_source).transpose()?;
        if let Some(m) = cli.band_m {
            if !(m.is_finite() && m > 0.0) {
                return Err(ConfigError::value(
                    "--band-m",
                    m,
                    "expected a width above 0 m",
                ));
            }
        }
        Ok(CompareConfig {
            a: cli.a.clone(),
            b: cli.b.clone(),
            json: cli.json,
            options: Options {
                source,
                band_m: cli.band_m,
            },
            fail_if_worse: cli.fail_if_worse,
        })
    }
}

/// `1/1`, or `1` for every component of system 1.
fn parse_source(text: &str) -> Result<SourceFilter, ConfigError> {
    let bad = || {
        ConfigError::value(
            "--source",
            text,
            "expected SYSID/COMPID or SYSID, ids 0-255 (e.g. 1/1)",
        )
    };
    let (sys, comp) = match text.split_once('/') {
        Some((sys, comp)) => (sys, Some(comp)),
        None => (text, None),
    };
    let sysid = sys.trim().parse::<u8>().map_err(|_| bad())?;
    let compid = comp
        .map(|c| c.trim().parse::<u8>().map_err(|_| bad()))
        .transpose()?;
    Ok(SourceFilter { sysid, compid })
}

#[cfg(test)]
mod tests {
    use clap::Parser;

    use super::*;
    use crate::cli::{Cli, Mode};

    fn config(args: &[&str]) -> Result<CompareConfig, ConfigError> {
        let mut argv = vec!["mavping", "compare"];
        argv.extend_from_slice(args);
        let cli = Cli::try_parse_from(argv).unwrap();
        match &cli.mode {
            Some(Mode::Compare(args)) => CompareConfig::try_from(args),
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn the_files_and_options_are_taken() {
        let c = config(&[
            "--json",
            "--source",
            "1/190",
            "--band-m",
            "25",
            "--fail-if-worse",
            "a.json",
            "b.json",
        ])
        .unwrap();
        assert_eq!(c.a, PathBuf::from("a.json"));
        assert_eq!(c.b, PathBuf::from("b.json"));
        assert!(c.json && c.fail_if_worse);
        assert_eq!(
            c.options.source,
            Some(SourceFilter {
                sysid: 1,
                compid: Some(190)
            })
        );
        assert_eq!(c.options.band_m, Some(25.0));
        let c = config(&["--source", "7", "a", "b"]).unwrap();
        assert_eq!(
            c.options.source,
            Some(SourceFilter {
                sysid: 7,
                compid: None
            })
        );
        assert_eq!(config(&["a", "b"]).unwrap().options, Options::default());
    }

    #[test]
    fn bad_values_are_refused_in_one_line() {
        for (args, message) in [
            (
                ["--source", "1/300"],
                "--source 1/300: expected SYSID/COMPID or SYSID, ids 0-255 (e.g. 1/1)",
            ),
            (
                ["--source", "x"],
                "--source x: expected SYSID/COMPID or SYSID, ids 0-255 (e.g. 1/1)",
            ),
            (["--band-m", "0"], "--band-m 0: expected a width above 0 m"),
            (
                ["--band-m", "-5"],
                "--band-m -5: expected a width above 0 m",
            ),
        ] {
            let mut all = args.to_vec();
            all.extend(["a", "b"]);
            assert_eq!(config(&all).unwrap_err().to_string(), message);
        }
    }
}
