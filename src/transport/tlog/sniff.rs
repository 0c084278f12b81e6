//! Naming what a file that holds no record is instead (a raw capture
//! without stamps, text): guesses from the log's first bytes, for the
//! error that refuses it, apart from the reading of records.

use crate::frame::{self, ScanStats};

/// How much of the log's start is kept, to say what a file that holds no
/// record is instead.
pub(super) const SNIFF_LEN: usize = 4096;

/// Whether the bytes hold MAVLink frames as a stream would (no stamps).
pub(super) fn holds_frames(bytes: &[u8]) -> bool {
    let mut stats = ScanStats::default();
    frame::scan_datagram(bytes, &mut stats, &mut |_| {});
    stats.frames >= 2
}

/// Whether the bytes read as text (printable ASCII or UTF-8, whitespace).
pub(super) fn is_text(bytes: &[u8]) -> bool {
    // A chunk may end inside a character.
    let text = match std::str::from_utf8(bytes) {
        Ok(t) => t,
        Err(e) => std::str::from_utf8(&bytes[..e.valid_up_to()]).unwrap_or(""),
    };
    text.len() + 4 >= bytes.len()
        && text
            .chars()
            .all(|c| !c.is_control() || c.is_ascii_whitespace())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn what_a_file_without_records_is_gets_a_name() {
        assert!(is_text(b"hello\nworld\t!"));
        assert!(!is_text(b"\x89PNG\r\n\x1a\n\0\0\0\rIHDR"));
        assert!(!holds_frames(b"hello"));
    }
}
