//! Writers the text formats share: one output for several links, and a
//! prefix on each line naming the link.

use std::io;

/// One writer shared by the reports of several links run side by side on
/// one thread (one tokio task joins them, so a `RefCell` suffices). A line
/// is written by one `writeln!` without an await in between, so lines of
/// different links never interleave.
pub(crate) struct Shared<W: io::Write>(pub std::rc::Rc<std::cell::RefCell<W>>);

impl<W: io::Write> Shared<W> {
    pub(crate) fn new(out: W) -> Self {
        Shared(std::rc::Rc::new(std::cell::RefCell::new(out)))
    }
}

impl<W: io::Write> Clone for Shared<W> {
    fn clone(&self) -> Self {
        Shared(self.0.clone())
    }
}

impl<W: io::Write> io::Write for Shared<W> {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        self.0.borrow_mut().write(buf)
    }
    fn write_all(&mut self, buf: &[u8]) -> io::Result<()> {
        self.0.borrow_mut().write_all(buf)
    }
    fn flush(&mut self) -> io::Result<()> {
        self.0.borrow_mut().flush()
    }
}

/// Starts every line with a fixed prefix (`[LINK] `), so per-reply lines
/// of several links can be told apart; without one, writes through.
pub(crate) struct Prefixed<W: io::Write> {
    out: W,
    prefix: Option<String>,
    at_line_start: bool,
}

impl<W: io::Write> Prefixed<W> {
    pub(crate) fn new(out: W, prefix: Option<String>) -> Self {
        Prefixed {
            out,
            prefix,
            at_line_start: true,
        }
    }
}

impl<W: io::Write> Prefixed<W> {
    /// The writer itself, bypassing the prefix.
    pub(crate) fn inner(&mut self) -> &mut W {
        &mut self.out
    }

    pub(crate) fn into_inner(self) -> W {
        self.out
    }
}

impl<W: io::Write> io::Write for Prefixed<W> {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        let Some(prefix) = &self.prefix else {
            return self.out.write(buf);
        };
        let mut rest = buf;
        while !rest.is_empty() {
            if self.at_line_start {
                self.out.write_all(prefix.as_bytes())?;
                self.at_line_start = false;
            }
            let end = rest
                .iter()
                .position(|&b| b == b'\n')
                .map_or(rest.len(), |i| i + 1);
            self.out.write_all(&rest[..end])?;
            self.at_line_start = rest[end - 1] == b'\n';
            rest = &rest[end..];
        }
        Ok(buf.len())
    }
    fn flush(&mut self) -> io::Result<()> {
        self.out.flush()
    }
}

#[cfg(test)]
mod tests {
    use std::io::Write;

    use super::*;

    #[test]
    fn prefixed_lines_share_one_writer() {
        let shared = Shared::new(Vec::new());
        let mut a = Prefixed::new(shared.clone(), Some("[a] ".into()));
        let mut b = Prefixed::new(shared.clone(), Some("[b] ".into()));
        let mut plain = Prefixed::new(shared.clone(), None);
        write!(a, "one").unwrap();
        writeln!(a, " line\ntwo").unwrap();
        writeln!(b, "three").unwrap();
        writeln!(plain, "four").unwrap();
        a.write_all(b"").unwrap();
        let out = String::from_utf8(shared.0.borrow().clone()).unwrap();
        assert_eq!(out, "[a] one line\n[a] two\n[b] three\nfour\n");
    }
}
