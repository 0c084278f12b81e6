//! The vehicle's own view of the link in text: a line per node that sent
//! LINK_NODE_STATUS, with what its counters grew by during the run, and in
//! a probe run mavping's uplink estimate beside it.

use std::io::{self, Write};

use crate::engine::link_node::{LinkNodeSummary, DISAGREE_SIGMAS};

/// 2103 → "2,103".
fn grouped(n: u64) -> String {
    let digits = n.to_string();
    let mut out = String::with_capacity(digits.len() + digits.len() / 3);
    for (i, c) in digits.chars().enumerate() {
        if i > 0 && (digits.len() - i).is_multiple_of(3) {
            out.push(',');
        }
        out.push(c);
    }
    out
}

/// Always two decimals: the vehicle's counts and the estimate are compared
/// digit for digit.
fn percent_2dp(ratio: f64) -> String {
    format!("{:.2}%", ratio * 100.0)
}

/// `vehicle 1/1 says (LINK_NODE_STATUS, 42 reports): received 2,103, lost
/// 12 (0.57%), parse errors +0, overflows rx +0 tx +0`, and the estimate
/// beside it.
pub(super) fn write_link_nodes(out: &mut impl Write, nodes: &[LinkNodeSummary]) -> io::Result<()> {
    for n in nodes {
        let reports = if n.reports == 1 {
            "1 report".to_string()
        } else {
            format!("{} reports", grouped(n.reports))
        };
        write!(out, "vehicle {} says (LINK_NODE_STATUS, {reports}): ", n.id)?;
        match n.uplink_loss {
            Some(loss) => write!(
                out,
                "received {}, lost {} ({})",
                grouped(n.received_delta),
                grouped(n.lost_delta),
                percent_2dp(loss)
            )?,
            None if n.reports == 1 => write!(out, "one report, no count to grow")?,
            None => write!(out, "received +0, lost +0")?,
        }
        write!(
            out,
            ", parse errors +{}, overflows rx +{} tx +{}",
            grouped(n.rx_parse_err_delta),
            grouped(n.rx_overflows_delta),
            grouped(n.tx_overflows_delta)
        )?;
        match n.reboots {
            0 => writeln!(out)?,
            1 => writeln!(out, "; it rebooted once")?,
            k => writeln!(out, "; it rebooted {k} times")?,
        }
        if let Some(c) = &n.compared {
            let (estimate, stderr) = (percent_2dp(c.estimate), percent_2dp(c.estimate_stderr));
            let (verdict, beyond) = if c.agrees {
                ("agrees", String::new())
            } else {
                (
                    "DISAGREES",
                    format!(", more than {DISAGREE_SIGMAS}: see the hint"),
                )
            };
            writeln!(
                out,
                "  beside mavping's up ~{estimate} ± {stderr} for {}: {verdict} ({:.1} standard \
                 errors apart{beyond})",
                c.responder, c.sigmas
            )?;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::engine::link_node::{LinkNodeReport, LinkNodes, UplinkComparison};
    use crate::frame::SysComp;

    #[test]
    fn counts_are_grouped_by_thousands() {
        assert_eq!(grouped(0), "0");
        assert_eq!(grouped(999), "999");
        assert_eq!(grouped(2_103), "2,103");
        assert_eq!(grouped(1_234_567), "1,234,567");
    }

    #[test]
    fn a_line_per_node_and_the_estimate_beside_it() {
        let mut nodes = LinkNodes::default();
        let id = SysComp::new(1, 1);
        let report = |t, received, lost, parse| LinkNodeReport {
            timestamp: t,
            messages_received: received,
            messages_lost: lost,
            rx_parse_err: parse,
            ..LinkNodeReport::default()
        };
        nodes.record(id, report(1_000, 100, 3, 0), 0);
        nodes.record(id, report(43_000, 2_203, 15, 2), 1);
        nodes.record(SysComp::new(2, 1), report(1_000, 7, 0, 0), 1);
        let mut summaries = nodes.summaries();
        summaries[0].compared = Some(UplinkComparison {
            responder: id,
            estimate: 0.097,
            estimate_stderr: 0.013,
            vehicle: 0.0057,
            vehicle_stderr: 0.0016,
            sigmas: 7.0,
            agrees: false,
        });
        let mut out = Vec::new();
        write_link_nodes(&mut out, &summaries).unwrap();
        assert_eq!(
            String::from_utf8(out).unwrap(),
            "vehicle 1/1 says (LINK_NODE_STATUS, 2 reports): received 2,103, lost 12 (0.57%), \
             parse errors +2, overflows rx +0 tx +0\n\
             \x20 beside mavping's up ~9.70% ± 1.30% for 1/1: DISAGREES (7.0 standard errors \
             apart, more than 3: see the hint)\n\
             vehicle 2/1 says (LINK_NODE_STATUS, 1 report): one report, no count to grow, \
             parse errors +0, overflows rx +0 tx +0\n"
        );
    }
}
