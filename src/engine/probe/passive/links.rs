//! Whether a telemetry log's stamps carry MAVProxy link numbers, and the
//! figures per link when they do. Pure: the tables in, a verdict out.
//!
//! MAVProxy stamps `(usec & ~3) | link` (3: what it sent itself); other
//! tools write a clock's microseconds (QGroundControl whole
//! milliseconds, pymavlink `usec & ~3`). The bits alone cannot tell a link
//! number from a clock's last bits; the frames can. Per source:
//! - **on one value only**: its stamps do not vary as a clock's would.
//!   With at least [`EVIDENCE_FRAMES`] frames on a value other than 0
//!   that is evidence of links (a clock's bits would put them all there
//!   one time in 4^15);
//! - **on several**: the bits are links for it if splitting its frames by
//!   them leaves sequences with less disorder (lost + duplicate +
//!   reordered + resyncs) than the merged one has: a vehicle heard on two
//!   links duplicates every frame merged and none split, while a clock's
//!   bits scatter a clean sequence (about 3 frames in 4 missing from each
//!   part). If the split is no cleaner, the source is *unlinked* (MAVProxy
//!   logs what its outputs send with a plain stamp), evidence of nothing.
//!
//! The stamps carry links when at least one source is evidence; each
//! source that is not unlinked is then in the table of every link it was
//! heard on. No evidence (all bits 0, or a clock's): no per-link figures.

use crate::engine::summary::passive::{
    LinkTable, LinkTotals, PerLink, SeqCounts, SourceSummary, TableSummary,
};
use crate::frame::SysComp;

/// Frames on one non-zero link value that make a source evidence.
pub(crate) const EVIDENCE_FRAMES: u64 = 16;

fn disorder(c: &SeqCounts) -> u64 {
    c.lost + c.duplicate + c.reordered + c.resyncs
}

/// The sources only MAVProxy's link 3 carried: what it sent itself.
pub(crate) fn sent_by_mavproxy(per: &PerLink) -> Vec<SysComp> {
    let on = |link: u8| {
        per.links
            .iter()
            .filter(move |t| t.link == link)
            .flat_map(|t| t.table.sources.iter().map(|s| s.source))
    };
    on(3)
        .filter(|s| !(0..3).any(|link| on(link).any(|o| o == *s)))
        .collect()
}

/// The figures per link, from the table of all frames (`merged`) and one
/// table per value of the stamps' low bits (`paths[link]`), when the
/// stamps carry links; see the module's rules.
pub(crate) fn per_link(merged: &TableSummary, paths: &[TableSummary]) -> Option<PerLink> {
    let mut evidence = false;
    let mut unlinked = Vec::new();
    for m in &merged.sources {
        let parts: Vec<(usize, &SourceSummary)> = paths
            .iter()
            .enumerate()
            .filter_map(|(p, t)| {
                t.sources
                    .iter()
                    .find(|s| s.source == m.source)
                    .map(|s| (p, s))
            })
            .collect();
        match parts.as_slice() {
            [] => {}
            [(link, s)] => evidence |= *link != 0 && s.counts.received >= EVIDENCE_FRAMES,
            _ => {
                let split: u64 = parts.iter().map(|(_, s)| disorder(&s.counts)).sum();
                if split < disorder(&m.counts) {
                    evidence = true;
                } else {
                    unlinked.push(m.source);
                }
            }
        }
    }
    if !evidence {
        return None;
    }
    let links = paths
        .iter()
        .enumerate()
        .filter_map(|(link, t)| {
            let sources: Vec<SourceSummary> = t
                .sources
                .iter()
                .filter(|s| !unlinked.contains(&s.source))
                .cloned()
                .collect();
            (!sources.is_empty()).then(|| LinkTable {
                link: link as u8,
                table: TableSummary {
                    totals: LinkTotals::of(&sources),
                    sources,
                    untracked: t.untracked,
                },
            })
        })
        .collect();
    Some(PerLink { links, unlinked })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::engine::probe::passive::tracker::SourceTable;
    use crate::engine::Nanos;
    use crate::frame::SysComp;

    const VEHICLE: SysComp = SysComp::new(1, 1);
    const PROXY: SysComp = SysComp::new(255, 230);
    const GCS: SysComp = SysComp::new(255, 190);

    /// Tables (merged, per link value) of frames given as (source, seq,
    /// link value), 20 ms apart.
    fn tables(frames: &[(SysComp, u8, usize)]) -> (TableSummary, Vec<TableSummary>) {
        let mut merged = SourceTable::new(None, 32);
        let mut paths: Vec<SourceTable> = (0..4).map(|_| SourceTable::new(None, 32)).collect();
        for (i, &(source, seq, link)) in frames.iter().enumerate() {
            let at = i as Nanos * 20_000_000;
            merged.on_frame(source, seq, 30, 36, at);
            paths[link].on_frame(source, seq, 30, 36, at);
        }
        let end = frames.len() as Nanos * 20_000_000;
        (
            merged.summary(end),
            paths.iter().map(|t| t.summary(end)).collect(),
        )
    }

    #[test]
    fn a_vehicle_on_two_links_and_mavproxys_own_frames_are_links() {
        let mut frames = Vec::new();
        for seq in 0..100u8 {
            frames.push((VEHICLE, seq, 0));
            // Link 1 loses every tenth frame.
            if seq % 10 != 5 {
                frames.push((VEHICLE, seq, 1));
            }
            if seq % 5 == 0 {
                frames.push((PROXY, seq / 5, 3));
            }
        }
        let (merged, paths) = tables(&frames);
        assert!(merged.sources[0].counts.duplicate > 80);
        let per = per_link(&merged, &paths).expect("links");
        assert!(per.unlinked.is_empty());
        let links: Vec<u8> = per.links.iter().map(|l| l.link).collect();
        assert_eq!(links, [0, 1, 3]);
        let link1 = &per.links[1].table.sources[0];
        assert_eq!((link1.counts.lost, link1.counts.duplicate), (10, 0));
        assert_eq!(per.links[2].table.sources[0].source, PROXY);
    }

    #[test]
    fn a_clocks_low_bits_are_no_link_numbers() {
        // The bits of a microsecond clock: anything, frame by frame.
        let mut x: u32 = 12345;
        let frames: Vec<(SysComp, u8, usize)> = (0..400u32)
            .map(|seq| {
                x = x.wrapping_mul(1_103_515_245).wrapping_add(12345);
                (VEHICLE, seq as u8, (x >> 16) as usize % 4)
            })
            .collect();
        let (merged, paths) = tables(&frames);
        assert_eq!(per_link(&merged, &paths), None);
    }

    #[test]
    fn all_bits_zero_is_no_evidence() {
        let frames: Vec<(SysComp, u8, usize)> = (0..100).map(|s| (VEHICLE, s, 0)).collect();
        let (merged, paths) = tables(&frames);
        assert_eq!(per_link(&merged, &paths), None);
    }

    #[test]
    fn forwarded_frames_with_plain_stamps_are_unlinked() {
        let mut frames = Vec::new();
        for seq in 0..100u8 {
            frames.push((VEHICLE, seq, 0));
            frames.push((PROXY, seq, 3));
            frames.push((GCS, seq, usize::from(seq.wrapping_mul(7) % 4)));
        }
        let (merged, paths) = tables(&frames);
        let per = per_link(&merged, &paths).expect("links");
        assert_eq!(per.unlinked, [GCS]);
        assert!(per
            .links
            .iter()
            .all(|l| l.table.sources.iter().all(|s| s.source != GCS)));
        assert_eq!(per.links[0].table.totals.counts.received, 100);
    }
}
