//! Which log a `tlog:` connection string names ([`TlogPath`]): a file or
//! standard input. The address parser builds it before any link opens.

use std::fmt;

/// Which log: a file, or standard input (`-`).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct TlogPath(pub String);

impl TlogPath {
    pub(crate) fn is_stdin(&self) -> bool {
        self.0 == "-"
    }
}

impl fmt::Display for TlogPath {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "tlog:{}", self.0)
    }
}
