//! Exit codes, as ping and fping use them, and the one policy that picks
//! the code of a run. `main` maps a run's [`Ending`] through [`code`];
//! nothing else chooses a code or calls `exit`.

/// Every expectation held.
pub(crate) const OK: u8 = 0;
/// No reply at all, an expected responder missing, or a threshold broken.
pub(crate) const FAILED: u8 = 1;
/// Usage error, or a link could not be opened or failed.
pub(crate) const ERROR: u8 = 2;
/// A second Ctrl-C (or SIGTERM): the run was abandoned (128 + SIGINT, as
/// shells report a process killed by it).
pub(crate) const INTERRUPTED_TWICE: u8 = 130;

/// How one link's measurement ended, as far as its code cares.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct LinkEnd {
    /// The link could not be opened, or failed during the run.
    pub(crate) link_failed: bool,
    /// Every check held: a reply (or ACK) came, thresholds and `--expect`.
    pub(crate) checks_held: bool,
}

/// How a whole run ended.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Ending {
    /// Nothing to judge went wrong: help, version, `--generate`, a
    /// responder or `mavping serve` stopped by Ctrl-C or SIGTERM.
    Done,
    /// The command line or configuration was refused, or something needed
    /// before the first request (an output file, the runtime, the
    /// metrics port) could not be set up.
    Refused,
    /// Links were measured (one or several, in command-line order).
    Measured {
        links: Vec<LinkEnd>,
        /// The output could not be written (a full disk, an I/O error).
        /// A closed stdout (`mavping ... | head`) is the reader's choice
        /// and changes nothing: the run went on to its end.
        output_failed: bool,
        /// `--plot` or `--hgrm` could not be written at the end.
        exports_failed: bool,
    },
    /// `mavping respond` could not open its link, or lost it.
    LinkFailed,
    /// `mavping compare` compared two runs: a comparison is not a check,
    /// unless `--fail-if-worse` asked for one.
    Compared {
        /// `--fail-if-worse`, and B lost more than A.
        worse: bool,
        /// The report could not be written.
        output_failed: bool,
    },
    /// A second Ctrl-C or SIGTERM left before the run could end.
    InterruptedTwice,
}

/// The code of one link: a failed link is an error whatever else held.
pub(crate) fn of_link(end: LinkEnd) -> u8 {
    if end.link_failed {
        ERROR
    } else if end.checks_held {
        OK
    } else {
        FAILED
    }
}

/// The code of a run: the worst of its links (any error wins, then any
/// failed check); output or an export that could not be written is an
/// error. A closed stdout changes nothing: a failed check stays failed.
pub fn code(ending: &Ending) -> u8 {
    match ending {
        Ending::Done
        | Ending::Compared {
            worse: false,
            output_failed: false,
        } => OK,
        Ending::Refused
        | Ending::LinkFailed
        | Ending::Compared {
            output_failed: true,
            ..
        } => ERROR,
        Ending::Compared {
            worse: true,
            output_failed: false,
        } => FAILED,
        Ending::InterruptedTwice => INTERRUPTED_TWICE,
        Ending::Measured {
            links,
            output_failed,
            exports_failed,
        } => {
            if *exports_failed || *output_failed {
                return ERROR;
            }
            let worst = links
                .iter()
                .map(|&l| of_link(l))
                .fold(OK, |worst, c| match (worst, c) {
                    (ERROR, _) | (_, ERROR) => ERROR,
                    (FAILED, _) | (_, FAILED) => FAILED,
                    _ => OK,
                });
            worst
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const GOOD: LinkEnd = LinkEnd {
        link_failed: false,
        checks_held: true,
    };
    const BAD: LinkEnd = LinkEnd {
        link_failed: false,
        checks_held: false,
    };
    const BROKEN: LinkEnd = LinkEnd {
        link_failed: true,
        checks_held: true,
    };

    fn measured(links: &[LinkEnd], output_failed: bool) -> u8 {
        code(&Ending::Measured {
            links: links.to_vec(),
            output_failed,
            exports_failed: false,
        })
    }

    #[test]
    fn the_worst_link_decides() {
        assert_eq!(measured(&[GOOD, GOOD], false), OK);
        assert_eq!(measured(&[GOOD, BAD], false), FAILED);
        assert_eq!(measured(&[BAD, BROKEN, GOOD], false), ERROR);
        assert_eq!(measured(&[BROKEN], false), ERROR);
    }

    #[test]
    fn output_that_could_not_be_written_is_an_error_even_when_every_check_held() {
        assert_eq!(measured(&[GOOD], true), ERROR);
        assert_eq!(measured(&[BAD], true), ERROR);
    }

    #[test]
    fn an_export_that_failed_is_an_error() {
        let ending = Ending::Measured {
            links: vec![GOOD],
            output_failed: false,
            exports_failed: true,
        };
        assert_eq!(code(&ending), ERROR);
    }

    #[test]
    fn other_endings() {
        assert_eq!(code(&Ending::Done), OK);
        assert_eq!(code(&Ending::Refused), ERROR);
        assert_eq!(code(&Ending::LinkFailed), ERROR);
        assert_eq!(code(&Ending::InterruptedTwice), 130);
    }

    #[test]
    fn a_comparison_fails_only_when_asked_and_b_is_worse() {
        let compared = |worse, output_failed| {
            code(&Ending::Compared {
                worse,
                output_failed,
            })
        };
        assert_eq!(compared(false, false), OK);
        assert_eq!(compared(true, false), FAILED);
        assert_eq!(compared(true, true), ERROR);
        assert_eq!(compared(false, true), ERROR);
    }
}
