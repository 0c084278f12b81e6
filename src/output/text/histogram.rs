//! An RTT histogram in text: a bar per bucket, the longest 40 wide.

use std::io::{self, Write};

use super::format::ms_us;
use crate::engine::stats::Bucket;

pub(super) fn write_histogram(out: &mut impl Write, histogram: &[Bucket]) -> io::Result<()> {
    let most = histogram.iter().map(|b| b.count).max().unwrap_or(0).max(1);
    for b in histogram {
        const WIDTH: u64 = 40;
        let bar = (b.count * WIDTH).div_ceil(most) as usize;
        writeln!(
            out,
            "  {:>9} ms |{:<40}| {}",
            ms_us(b.low_us),
            "#".repeat(bar),
            b.count
        )?;
    }
    Ok(())
}
