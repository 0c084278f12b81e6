//! LINK_NODE_STATUS as metrics: each node's own counts of the link (what
//! it received, lost and sent, its parse errors and overflows) as counters
//! that only grow since mavping first heard it, its loss ratio and rates
//! as gauges. The node's own counters are since its boot and wrap; the
//! engine's table of nodes ([`LinkNodes`]) follows them, and bounds how
//! many nodes a link keeps.
//!
//! [`LinkNodes`]: crate::engine::link_node::LinkNodes

use super::exposition::{Exposition, Figure, SeriesFigure};
use super::Metrics;
use crate::engine::link_node::LinkNodeSummary;

const NODE: [SeriesFigure<LinkNodeSummary>; 10] = [
    Figure::counter(
        "mavping_link_node_reports_total",
        "LINK_NODE_STATUS reports received from the node.",
        |n| Some(n.reports as f64),
    ),
    Figure::counter(
        "mavping_link_node_received_total",
        "Messages the node says it received on its link since mavping first heard it (every sender's, ours included; its 32-bit counter's wraps and reboots followed).",
        |n| Some(n.received_delta as f64),
    ),
    Figure::counter(
        "mavping_link_node_lost_total",
        "Messages the node says it lost on its way to it (by their packet sequence) since mavping first heard it.",
        |n| Some(n.lost_delta as f64),
    ),
    Figure::counter(
        "mavping_link_node_sent_total",
        "Messages the node says it sent on its link since mavping first heard it.",
        |n| Some(n.sent_delta as f64),
    ),
    Figure::counter(
        "mavping_link_node_rx_parse_errors_total",
        "Bytes the node could not parse since mavping first heard it.",
        |n| Some(n.rx_parse_err_delta as f64),
    ),
    Figure::counter(
        "mavping_link_node_rx_overflows_total",
        "The node's receive buffer overflows since mavping first heard it.",
        |n| Some(n.rx_overflows_delta as f64),
    ),
    Figure::counter(
        "mavping_link_node_tx_overflows_total",
        "The node's transmit buffer overflows since mavping first heard it.",
        |n| Some(n.tx_overflows_delta as f64),
    ),
    Figure::gauge(
        "mavping_link_node_loss_ratio",
        "What the node lost of its link since mavping first heard it: lost / (received + lost), 0 to 1 (the vehicle's own view of the uplink).",
        |n| n.uplink_loss,
    ),
    Figure::gauge(
        "mavping_link_node_rx_rate_bytes_per_second",
        "The node's receive rate on its link, as its latest report says.",
        |n| Some(f64::from(n.last.rx_rate)),
    ),
    Figure::gauge(
        "mavping_link_node_tx_rate_bytes_per_second",
        "The node's transmit rate on its link, as its latest report says.",
        |n| Some(f64::from(n.last.tx_rate)),
    ),
];

/// Every link's nodes, each family once: the figures the engine's table
/// of nodes sums up for a run's end, as they are now.
pub(super) fn write_link_nodes(out: &mut Exposition, links: &[&Metrics]) {
    let nodes: Vec<_> = links
        .iter()
        .flat_map(|m| {
            let summaries = m.link_nodes.summaries().into_iter();
            summaries.map(|n| (m.radio_labels(n.id), n))
        })
        .collect();
    out.figures(&NODE, || nodes.iter().map(|(l, n)| (l.clone(), n)));
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::engine::link_node::LinkNodeReport;
    use crate::frame::SysComp;

    fn report(t: u64, received: u32, lost: u32) -> LinkNodeReport {
        LinkNodeReport {
            timestamp: t,
            messages_received: received,
            messages_lost: lost,
            rx_rate: 640,
            tx_rate: 12_000,
            ..LinkNodeReport::default()
        }
    }

    #[test]
    fn counters_only_grow_through_a_wrap_and_a_reboot() {
        let mut m = Metrics {
            link: "udpout:127.0.0.1:14550".into(),
            ..Metrics::default()
        };
        let id = SysComp::new(1, 1);
        // 100 through the wrap, then a reboot (its clock went back): 40
        // more counted from 0.
        for (t, received, lost) in [(5_000, u32::MAX - 49, 7), (6_000, 50, 9), (300, 40, 0)] {
            m.link_nodes.record(id, report(t, received, lost), 0);
        }
        let text = m.render();
        let l = r#"link="udpout:127.0.0.1:14550",sysid="1",compid="1""#;
        for line in [
            format!("mavping_link_node_reports_total{{{l}}} 3"),
            format!("mavping_link_node_received_total{{{l}}} 140"),
            format!("mavping_link_node_lost_total{{{l}}} 2"),
            format!("mavping_link_node_loss_ratio{{{l}}} {}", 2.0 / 142.0),
            format!("mavping_link_node_rx_rate_bytes_per_second{{{l}}} 640"),
            "# TYPE mavping_link_node_received_total counter".to_string(),
        ] {
            assert!(text.lines().any(|t| t == line), "{line}\n{text}");
        }
    }
}
