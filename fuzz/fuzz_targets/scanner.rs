//! The byte-stream frame scanner fed arbitrary bytes in arbitrary read
//! splits. Invariants:
//! - no panic, and the carried tail is at most one maximal frame;
//! - the same frames, stats and tail whatever the split;
//! - every byte is accounted for: good frames + skipped + unknown-id and
//!   damaged frames + the carried tail = all bytes fed;
//! - the stream's frames are a prefix of the frames the datagram scan
//!   (which knows where the data ends) finds in the same bytes, unless the
//!   datagram scan kept a good frame whose payload holds another good frame
//!   (a stream lets the inner one win), and the datagram scan accounts for
//!   every byte with nothing left over;
//! - every good frame that overlaps no other good frame (by the oracle the
//!   property tests use) is delivered by the datagram scan, and nothing
//!   else (issue 21).
#![no_main]

use libfuzzer_sys::fuzz_target;
use mavping::frame::scanner::{MAX_FRAME_LEN, MAX_PENDING};
use mavping::frame::{decode, scan_datagram, ScanStats, StreamScanner};

#[path = "../../tests/it/common/frame_oracle.rs"]
mod frame_oracle;

/// Smallest frame the scanner can take as an unknown id or a damaged frame
/// (v1, no payload).
const MIN_FRAME: u64 = 8;

fn stream(data: &[u8], splits: &[u8]) -> (Vec<Vec<u8>>, ScanStats, usize) {
    let mut scanner = StreamScanner::new();
    let mut frames = Vec::new();
    let mut rest = data;
    let mut i = 0;
    while !rest.is_empty() {
        // Read sizes from the split bytes (0 means "one byte"); 0xFF adds an empty
        // read first, which is legal and must change nothing.
        let size = if splits.is_empty() {
            rest.len()
        } else {
            let s = splits[i % splits.len()] as usize;
            i += 1;
            if s == 0xFF {
                // An empty read, then one byte (so the loop always ends).
                scanner.push(&[], &mut |f| frames.push(f.to_vec()));
            }
            (s % 0xFF + 1).min(rest.len())
        };
        let (now, later) = rest.split_at(size);
        scanner.push(now, &mut |f| frames.push(f.to_vec()));
        assert!(scanner.pending_bytes() <= MAX_PENDING);
        rest = later;
    }
    (frames, scanner.stats, scanner.pending_bytes())
}

fn check_accounting(frames: &[Vec<u8>], stats: &ScanStats, pending: usize, total: usize) {
    let frame_bytes: u64 = frames.iter().map(|f| f.len() as u64).sum();
    assert_eq!(stats.frames, frames.len() as u64);
    let accounted = frame_bytes + stats.skipped_bytes + pending as u64;
    assert!(
        accounted <= total as u64,
        "{stats:?} pending {pending} total {total}"
    );
    // Unknown-id and damaged frames are taken whole, neither delivered as
    // good nor skipped.
    let unchecked_bytes = total as u64 - accounted;
    let unchecked = stats.unknown_id + stats.damaged;
    assert!(unchecked_bytes >= unchecked * MIN_FRAME, "{stats:?}");
    assert!(
        unchecked_bytes <= unchecked * MAX_FRAME_LEN as u64,
        "{stats:?}"
    );
}

fuzz_target!(|input: &[u8]| {
    // First byte: how many split bytes follow; then the split bytes; then data.
    let Some((&n, rest)) = input.split_first() else {
        return;
    };
    let n = usize::from(n % 32).min(rest.len());
    let (splits, data) = rest.split_at(n);

    let (whole, whole_stats, whole_tail) = stream(data, &[]);
    let (split, split_stats, split_tail) = stream(data, splits);
    assert_eq!(whole, split);
    assert_eq!(whole_stats, split_stats);
    assert_eq!(whole_tail, split_tail);
    if data.len() <= 600 {
        let (bytewise, bytewise_stats, bytewise_tail) = stream(data, &[0]);
        assert_eq!(whole, bytewise);
        assert_eq!(whole_stats, bytewise_stats);
        assert_eq!(whole_tail, bytewise_tail);
    }
    check_accounting(&whole, &whole_stats, whole_tail, data.len());
    for f in &whole {
        let frame = decode(f);
        assert_eq!(frame.version == mavping::frame::Version::V1, f[0] == 0xFE);
    }

    let mut dgram_stats = ScanStats::default();
    let mut dgram = Vec::new();
    let mut at = Vec::new();
    let base = data.as_ptr() as usize;
    scan_datagram(data, &mut dgram_stats, &mut |f| {
        dgram.push(f.to_vec());
        let start = f.as_ptr() as usize - base;
        at.push(start..start + f.len());
    });
    check_accounting(&dgram, &dgram_stats, 0, data.len());
    let holds_a_good_frame = |f: &Vec<u8>| {
        let mut inside = false;
        scan_datagram(&f[1..], &mut ScanStats::default(), &mut |_| inside = true);
        inside
    };
    if !dgram.iter().any(holds_a_good_frame) {
        assert!(dgram.len() >= whole.len());
        assert_eq!(&dgram[..whole.len()], &whole[..]);
    }

    let good = frame_oracle::good_frames(data);
    for f in frame_oracle::isolated(&good) {
        assert!(at.contains(&f), "good frame {f:?} not delivered");
    }
    for f in &at {
        assert!(good.contains(f), "{f:?} is not a good frame");
    }
});
