//! The C2 tracker watching a driver's events on their way to the
//! observer: the decided requests it counts for continuity and the uplink.

use std::io;

use super::C2Tracker;
use crate::engine::matcher::MatchEvent;
use crate::engine::observe::{Event, Observer, StartInfo};
use crate::engine::probe::command::CommandEvent;
use crate::engine::summary::Interim;

/// `observer`, with the tracker (if the run has one) seeing each event first.
pub(crate) struct Watching<'a> {
    pub(crate) c2: Option<&'a mut C2Tracker>,
    pub(crate) observer: &'a mut dyn Observer,
}

impl Observer for Watching<'_> {
    fn start(&mut self, info: &StartInfo) -> io::Result<()> {
        self.observer.start(info)
    }

    fn event(&mut self, event: &Event<'_>) -> io::Result<()> {
        if let (Some(c2), Event::Kind(value)) = (self.c2.as_deref_mut(), event) {
            if let Some(matched) = value.get::<MatchEvent>() {
                c2.matched(matched);
            } else if let Some(command) = value.get::<CommandEvent>() {
                c2.command(command);
            }
        }
        self.observer.event(event)
    }

    fn flush(&mut self) -> io::Result<()> {
        self.observer.flush()
    }

    fn interim(&mut self, figures: &Interim) -> io::Result<()> {
        self.observer.interim(figures)
    }
}
