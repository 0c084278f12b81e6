//! `mavping compare`: reads the two files, compares them
//! ([`crate::compare`]) and writes the report on stdout.

use std::io::{self, Write};
use std::path::Path;

use thiserror::Error;

use crate::compare::{self, CompareError, InputError, Report, RunFile};
use crate::config::CompareConfig;
use crate::exit::{self, Ending};
use crate::stderr;

/// Why nothing was compared: one line on stderr, exit 2.
#[derive(Debug, Error)]
enum Refused {
    #[error("{file}: cannot read it: {source}")]
    Unreadable { file: String, source: io::Error },
    #[error(transparent)]
    Input(#[from] InputError),
    #[error(transparent)]
    Compare(#[from] CompareError),
}

fn read(path: &Path) -> Result<RunFile, Refused> {
    let file = path.display().to_string();
    let opened = std::fs::File::open(path).map_err(|source| Refused::Unreadable {
        file: file.clone(),
        source,
    })?;
    Ok(compare::parse(&file, io::BufReader::new(opened))?)
}

fn report(config: &CompareConfig) -> Result<Report, Refused> {
    let a = read(&config.a)?;
    let b = read(&config.b)?;
    Ok(compare::compare(&a, &b, &config.options)?)
}

pub(super) fn run(config: &CompareConfig) -> Ending {
    let report = match report(config) {
        Ok(report) => report,
        Err(e) => {
            stderr::error(&e);
            return Ending::Refused;
        }
    };
    let worse = config.fail_if_worse && report.b_loses_more;
    let code = if worse { exit::FAILED } else { exit::OK };
    let mut out = io::stdout().lock();
    let written = if config.json {
        compare::write_json(&mut out, &report, code)
    } else {
        compare::write_text(&mut out, &report)
    };
    // A closed stdout is the reader's choice (`mavping compare ... | head`).
    let output_failed = match written.and_then(|()| out.flush()) {
        Err(e) if e.kind() != io::ErrorKind::BrokenPipe => {
            stderr::error(&format_args!("cannot write the output: {e}"));
            true
        }
        _ => false,
    };
    Ending::Compared {
        worse,
        output_failed,
    }
}
