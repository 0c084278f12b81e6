//! The one form of every line mavping writes on stderr for a person
//! (`mavping: ...`), usable from any layer without reaching up into the
//! run layer.

use std::fmt::Display;
use std::io::{self, Write};

/// An error: `mavping: WHAT`.
pub(crate) fn error(what: &dyn Display) {
    let _ = writeln!(io::stderr(), "mavping: {what}");
}

/// A warning: `mavping: warning: WHAT`.
pub(crate) fn warning(what: &dyn Display) {
    let _ = writeln!(io::stderr(), "mavping: warning: {what}");
}
