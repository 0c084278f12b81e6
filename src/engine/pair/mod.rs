//! Two links to one vehicle (issue 41): the same source heard on two
//! links or more, each frame identified on every link that delivered it,
//! and the pair measured: which link delivered what first, what only one
//! link delivered, how far each lags behind the first copy, what is left
//! lost after de-duplication, and the de-duplication period that would
//! have caught the copies.
//!
//! Pure and synchronous, as the rest of the engine's parts: each frame
//! comes with its link's index and its arrival on one session clock
//! shared by every link ([`Nanos`]), so lags are exact. Memory is fixed:
//! a 256-slot ring of recent frames per source, sources capped
//! ([`PairConfig::max_sources`]; frames of others are counted in
//! `untracked_frames`), a histogram per link a source lags on.
//!
//! **Which frames are the same.** Each source has one merged sequence
//! line: the 8-bit packet sequence unwrapped around the newest number any
//! link delivered (the head). A good frame's place on it is the number
//! nearest the head with its 8 bits. A frame is the **copy** of one heard
//! before when both have the same source, the same place on the line,
//! the same message id and the same CRC (as on the wire: it covers the
//! header and the payload), and the first was heard at most
//! [`PairConfig::window`] before. So a frame is a copy only while the
//! source's newest number has moved less than half the sequence (128)
//! past it: the HEARTBEAT that recurs with the same sequence number and
//! the same bytes 256 frames later lands 256 further on the line and is a
//! new frame, not a copy. The cost: a link lagging 128 of the source's
//! frames or more behind another cannot be paired (its frames read as
//! other numbers). Besides new frames and copies:
//! - the same frame again on a link that delivered it is a **duplicate**
//!   on that link;
//! - the same frame after the window is **late beyond the window**, and
//!   another frame under a number in use within it a **conflict** (a
//!   second sender under the same ids, a restart): neither is a new frame
//!   nor a copy;
//! - a **damaged** frame ([`Msg::Damaged`](crate::frame::Msg::Damaged))
//!   is counted on its link, and its number arrived (it is not lost, on
//!   its link or the pair's, as the passive table counts it), but its
//!   bytes cannot say which frame it was: never new, first or a copy.
//!
//! **What is counted.** Per source and link: frames delivered, those it
//! delivered first (and their share of the distinct frames), those
//! **only** it delivered (no other link within the window: decided when
//! the window closes, the ones still open said apart), its lag behind the
//! first copy over the frames another link delivered too (0 where it was
//! first), frames that came behind a newer number another link had
//! delivered (**stale**: the vehicle jumps back on a map fed by both),
//! and its loss counted on its own sequence alone ([`seq`]). For the
//! merged stream: distinct frames, the numbers no link delivered (the
//! loss after de-duplication, the same count as lost on every link), and
//! the lag of every later copy, whose 99.9th percentile is the
//! de-duplication period that would have caught 999 copies in 1000.
//!
//! A source heard on one link only has nothing to pair: it is listed
//! apart ([`SingleLinkSource`]) with its link and frames.

mod delivered;
mod lag;
pub(crate) mod matrix;
pub(crate) mod merge;
mod recent;
mod seq;
mod side;
mod source;
mod summary;
#[cfg(test)]
mod tests;

use std::collections::HashMap;

pub(crate) use summary::{LinkPair, PairSummary, SingleLinkSource, SourcePair};

use source::SourceState;

use crate::engine::Nanos;
use crate::frame::{Frame, Msg, SysComp};

/// The most links a tracker tells apart (a frame's links are bits of a
/// `u64`).
pub(crate) const MAX_LINKS: usize = 64;
/// Sources tracked unless told otherwise, as the passive table's cap.
pub(crate) const DEFAULT_MAX_SOURCES: usize = 32;
/// How long after its first copy a frame may still be copied: past the
/// seconds a cellular link falls behind a radio. For a source sending 26
/// frames a second or more the sequence rule (128 numbers) ends it sooner.
pub(crate) const DEFAULT_WINDOW: Nanos = 5_000_000_000;

/// What the tracker reads of a frame: who sent it, under which number,
/// and what tells it from another frame under that number.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Heard {
    pub(crate) source: SysComp,
    pub(crate) seq: u8,
    pub(crate) msgid: u32,
    pub(crate) crc: u16,
    /// Its CRC failed: its number came, not which frame it was.
    pub(crate) damaged: bool,
}

impl Heard {
    pub(crate) fn of(frame: &Frame) -> Self {
        Heard {
            source: frame.source,
            seq: frame.packet_seq,
            msgid: frame.msgid,
            crc: frame.crc,
            damaged: frame.msg == Msg::Damaged,
        }
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct PairConfig {
    /// How long after a frame's first copy another is still its copy.
    pub(crate) window: Nanos,
    /// Sources tracked; frames of others are counted, not matched.
    pub(crate) max_sources: usize,
}

impl Default for PairConfig {
    fn default() -> Self {
        PairConfig {
            window: DEFAULT_WINDOW,
            max_sources: DEFAULT_MAX_SOURCES,
        }
    }
}

/// The pair report's bookkeeping over every link of a run.
#[derive(Debug, Clone)]
pub(crate) struct PairTracker {
    links: usize,
    config: PairConfig,
    sources: HashMap<SysComp, SourceState>,
    untracked_frames: u64,
}

impl PairTracker {
    /// A tracker of `links` links (indices `0..links`, at most
    /// [`MAX_LINKS`]; frames of others are counted, not matched).
    pub(crate) fn new(links: usize, config: PairConfig) -> Self {
        PairTracker {
            links: links.min(MAX_LINKS),
            config,
            sources: HashMap::new(),
            untracked_frames: 0,
        }
    }

    /// Takes `frame`, delivered by link `link` at `at` on the clock every
    /// link shares.
    #[cfg(test)]
    pub(crate) fn on_frame(&mut self, link: usize, frame: &Frame, at: Nanos) {
        self.on_heard(link, Heard::of(frame), at);
    }

    /// [`PairTracker::on_frame`] of what the tracker reads of a frame.
    pub(crate) fn on_heard(&mut self, link: usize, frame: Heard, at: Nanos) {
        let Ok(index) = u8::try_from(link) else {
            self.untracked_frames += 1;
            return;
        };
        if link >= self.links {
            self.untracked_frames += 1;
            return;
        }
        let room = self.sources.len() < self.config.max_sources;
        let state = match self.sources.entry(frame.source) {
            std::collections::hash_map::Entry::Occupied(e) => e.into_mut(),
            std::collections::hash_map::Entry::Vacant(e) if room => {
                e.insert(SourceState::new(self.links))
            }
            std::collections::hash_map::Entry::Vacant(_) => {
                self.untracked_frames += 1;
                return;
            }
        };
        state.on_frame(index, &frame, at, self.config.window);
    }

    /// The figures at `at`: the sources heard on two links or more, and
    /// those heard on one. Cheap enough for a live view once a second (a
    /// pass over each source's ring and histograms, nothing per frame).
    pub(crate) fn summary(&self, at: Nanos) -> PairSummary {
        let mut ids: Vec<SysComp> = self.sources.keys().copied().collect();
        ids.sort_unstable();
        let mut sources = Vec::new();
        let mut single_link_sources = Vec::new();
        let mut uncopied_sources = Vec::new();
        let mut conflicting_sources = Vec::new();
        for id in ids {
            let state = &self.sources[&id];
            // No frame on two links, even after the window: split, not copied.
            let uncopied = state.copies == 0 && state.late == 0;
            // As many numbers taken by another frame as copies: two senders.
            let conflicting = state.conflicts > 0 && state.conflicts >= state.copies;
            if state.links_heard() >= 2 && uncopied {
                uncopied_sources.push(id);
            } else if state.links_heard() >= 2 && conflicting {
                conflicting_sources.push(id);
            } else if state.links_heard() >= 2 {
                sources.push(SourcePair::new(id, state, at, self.config.window));
            } else if let Some(single) = SingleLinkSource::of(id, state) {
                single_link_sources.push(single);
            }
        }
        PairSummary {
            window_ms: summary::ms(self.config.window),
            sources,
            single_link_sources,
            uncopied_sources,
            conflicting_sources,
            untracked_frames: self.untracked_frames,
        }
    }

    /// Bytes held, for the tests of the memory bound: the map's capacity
    /// and each source's ring, links and histograms.
    #[cfg(test)]
    fn bytes(&self) -> usize {
        let per_entry = std::mem::size_of::<(SysComp, SourceState)>();
        self.sources.capacity() * per_entry
            + self.sources.values().map(SourceState::bytes).sum::<usize>()
    }
}
