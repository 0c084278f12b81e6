//! The signing line of a summary: what the signing gate let through and
//! what it refused.

use std::io::{self, Write};

use crate::frame::signing::SigningSummary;

/// One line: what the signing gate let through and what it refused
/// (refused frames were never measured); without a key, only when signed
/// frames came (their signatures could not be checked).
pub(super) fn write_signing(out: &mut impl Write, s: &SigningSummary) -> io::Result<()> {
    match s.link_id {
        Some(link_id) => writeln!(
            out,
            "signing (link id {link_id}, {}): {}",
            if s.required {
                "signatures required"
            } else {
                "unsigned accepted"
            },
            s.counts
        ),
        None if s.counts.signed_unchecked > 0 => writeln!(
            out,
            "signing (no key): {} signed frames accepted unchecked, {} unsigned",
            s.counts.signed_unchecked, s.counts.unsigned
        ),
        None => Ok(()),
    }
}
