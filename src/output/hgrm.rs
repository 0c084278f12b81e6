//! `--hgrm FILE`: the HdrHistogram percentile distribution format, as
//! HdrHistogram's `outputPercentileDistribution` prints it (values in ms,
//! 5 ticks per half distance), one section per responder. The standard
//! HdrHistogram plotter reads it.

use std::io::{self, Write};

use hdrhistogram::Histogram;

use crate::frame::SysComp;

/// Histograms record µs; the file shows ms, as HdrHistogram users expect.
const SCALE: f64 = 1000.0;
const TICKS_PER_HALF_DISTANCE: u32 = 5;

/// HdrHistogram's sub-bucket count for a precision: the smallest power of
/// two that holds 2 x 10^sigfig (2048 for 3 significant digits).
fn sub_bucket_count(sigfig: u8) -> u64 {
    (2 * 10u64.pow(u32::from(sigfig))).next_power_of_two()
}

pub(crate) fn write_section(
    out: &mut impl Write,
    link: &str,
    responder: SysComp,
    hist: &Histogram<u64>,
) -> io::Result<()> {
    writeln!(
        out,
        "# mavping {link} responder {responder}: RTT in milliseconds"
    )?;
    writeln!(
        out,
        "{:>12} {:>14} {:>10} {:>14}\n",
        "Value", "Percentile", "TotalCount", "1/(1-Percentile)"
    )?;
    let mut total = 0u64;
    for v in hist.iter_quantiles(TICKS_PER_HALF_DISTANCE) {
        total += v.count_since_last_iteration();
        let value = v.value_iterated_to() as f64 / SCALE;
        let q = v.quantile_iterated_to();
        write!(out, "{value:12.3} {q:2.12} {total:10}")?;
        // The last line, at 100 %, has no 1/(1-Percentile).
        if q < 1.0 {
            write!(out, " {:14.2}", 1.0 / (1.0 - q))?;
        }
        writeln!(out)?;
    }
    writeln!(
        out,
        "#[Mean    = {:12.3}, StdDeviation   = {:12.3}]",
        hist.mean() / SCALE,
        hist.stdev() / SCALE
    )?;
    writeln!(
        out,
        "#[Max     = {:12.3}, Total count    = {:12}]",
        hist.max() as f64 / SCALE,
        hist.len()
    )?;
    writeln!(
        out,
        "#[Buckets = {:12}, SubBuckets     = {:12}]",
        hist.buckets(),
        sub_bucket_count(hist.sigfig())
    )?;
    writeln!(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn percentile_lines_parse_back_to_the_histogram() {
        let mut h = Histogram::<u64>::new(3).unwrap();
        for v in 1..=1000u64 {
            h.record(v * 10).unwrap();
        }
        let mut out = Vec::new();
        write_section(&mut out, "sim:", SysComp::new(1, 1), &h).unwrap();
        let text = String::from_utf8(out).unwrap();
        let rows: Vec<(f64, f64, u64)> = text
            .lines()
            .filter(|l| !l.starts_with('#') && !l.trim().is_empty() && !l.contains("Value"))
            .map(|l| {
                let f: Vec<&str> = l.split_whitespace().collect();
                (
                    f[0].parse().unwrap(),
                    f[1].parse().unwrap(),
                    f[2].parse().unwrap(),
                )
            })
            .collect();
        let last = rows.last().unwrap();
        assert_eq!(last.1, 1.0);
        assert_eq!(last.2, 1000);
        let p50 = rows.iter().find(|r| r.1 >= 0.5).unwrap().0;
        assert_eq!(p50, h.value_at_quantile(0.5) as f64 / 1000.0);
        assert!(text.contains("#[Max     =       10.007"), "{text}");
    }
}
