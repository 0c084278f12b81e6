//! `--live`: a full-screen view of the link, in the spirit of mtr and gping:
//! a row per responder with its counts, RTT figures and a strip of its
//! recent replies, where losses and late replies stand out; in a passive
//! run, a row per source (`sources.rs`) with its sequence figures and a
//! strip of its recent seconds.
//!
//! The measurement never waits on the terminal: `event()` only updates a
//! small state under a mutex, and a separate thread draws it a few times a
//! second and reads the keyboard. When the run ends, the terminal is
//! restored and the normal text summary printed (by the run, as text).
//! The frame itself is drawn by `view.rs`; the pair report's section,
//! when a source is heard on several links, comes from `pair.rs`.
//!
//! This file declares and re-exports, and hands a link's [`Reporter`]
//! calls to its `LiveState` (`state.rs`); the UI thread is in
//! `terminal.rs`.

mod pair;
mod sources;
mod state;
mod terminal;
mod view;

use std::io;

use self::terminal::lock;
use super::{Event, Reporter, StartInfo};
// The run draws through a LiveLink; the tests of every format drive a
// state directly.
#[cfg(test)]
pub(crate) use state::LiveState;
pub(crate) use terminal::{LiveLink, LiveView};

/// Its summary is printed as text once the view is closed.
impl Reporter for LiveLink {
    fn start(&mut self, info: &StartInfo) -> io::Result<()> {
        lock(&self.states)[self.index].start(info)
    }

    fn tell(&mut self, event: &Event<'_>) -> io::Result<()> {
        lock(&self.states)[self.index].tell(event)
    }
}
