//! The frames of one source heard lately, one slot per sequence number:
//! what a frame heard on a link is to the ones heard before it.

use crate::engine::Nanos;

/// Slots: one per value of the 8-bit sequence. A frame's place on the
/// line picks its slot, so the frame 256 numbers later takes the slot
/// over: memory is fixed whatever the source sends.
const SLOTS: usize = 256;

/// What identifies a frame within its source, besides its number.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub(super) struct Key {
    pub(super) msgid: u32,
    pub(super) crc: u16,
}

/// A frame as first heard, and the links that delivered it since.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub(super) struct Entry {
    /// Its place on the source's line; 0 for a slot never used.
    line: u64,
    key: Key,
    pub(super) first_at: Nanos,
    pub(super) first_link: u8,
    /// Bit `n`: link `n` delivered it within the window.
    pub(super) links: u64,
}

impl Entry {
    /// Whether the frame may still be joined by a copy at `at`.
    fn open(&self, at: Nanos, window: Nanos) -> bool {
        at.saturating_sub(self.first_at) <= window
    }
}

/// What a frame is, against the frames heard before it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Seen {
    /// Nothing heard under its number within the window: a new frame.
    New,
    /// The copy of a frame another link delivered first; `before` is the
    /// entry as it was until this copy joined it.
    Copy { before: Entry },
    /// A frame this link had delivered already.
    Again,
    /// The same frame, after the window closed: not a copy.
    Late,
    /// Another frame under the same number within the window (a second
    /// sender under the same ids, or a restart): neither new nor a copy.
    Conflict,
}

#[derive(Debug, Clone)]
pub(super) struct Recent {
    slots: Box<[Entry]>,
}

impl Default for Recent {
    fn default() -> Self {
        Recent {
            slots: vec![Entry::default(); SLOTS].into_boxed_slice(),
        }
    }
}

impl Recent {
    /// Takes the frame at `line` with `key` that `link` delivered at `at`,
    /// and says what it is.
    pub(super) fn see(&mut self, line: u64, key: Key, link: u8, at: Nanos, window: Nanos) -> Seen {
        let entry = &mut self.slots[slot(line)];
        let same_number = entry.line == line;
        if same_number && entry.open(at, window) {
            if entry.key != key {
                return Seen::Conflict;
            }
            if entry.links & (1 << link) != 0 {
                return Seen::Again;
            }
            let before = *entry;
            entry.links |= 1 << link;
            // Links are read in turns (a log's batches, a socket's): a copy
            // taken later may have come earlier, and then it is the first.
            if at < entry.first_at {
                entry.first_at = at;
                entry.first_link = link;
            }
            return Seen::Copy { before };
        }
        if same_number && entry.key == key {
            return Seen::Late;
        }
        *entry = Entry {
            line,
            key,
            first_at: at,
            first_link: link,
            links: 1 << link,
        };
        Seen::New
    }

    /// The frames only one link has delivered that a copy may still join
    /// at `at`: those within the window and within half the sequence of
    /// `head`, the source's newest number.
    pub(super) fn undecided(
        &self,
        at: Nanos,
        window: Nanos,
        head: u64,
    ) -> impl Iterator<Item = u8> + '_ {
        self.slots
            .iter()
            .filter(move |e| {
                e.line != 0
                    && e.links.is_power_of_two()
                    && e.open(at, window)
                    && head.saturating_sub(e.line) < (SLOTS / 2) as u64
            })
            .map(|e| e.first_link)
    }

    /// Bytes held, for the tests of the memory bound.
    #[cfg(test)]
    pub(super) fn bytes(&self) -> usize {
        std::mem::size_of_val(&*self.slots)
    }
}

fn slot(line: u64) -> usize {
    (line % SLOTS as u64) as usize
}
