//! What the C2 report takes from the run's own summary: the delay each
//! way (the round trip's split by the responder's stamps) and the loss
//! each way (the vehicle's sequence numbers down; up, its own
//! LINK_NODE_STATUS counts where it sends them, else the direction split).

use super::report::{DirectionLoss, Latency, OneWay};
use crate::engine::link_node::LinkNodeSummary;
use crate::engine::radio::is_radio_ids;
use crate::engine::summary::passive::PassiveSummary;
use crate::engine::summary::{EchoSummary, LinkSummary};

/// The one-way delays (no round trip: the tracker has it) and the loss.
pub(crate) fn of(summary: &LinkSummary) -> (Latency, DirectionLoss) {
    let mut latency = Latency {
        round_trip: None,
        uplink: None,
        downlink: None,
    };
    let mut loss = DirectionLoss {
        downlink_pct: None,
        uplink_pct: None,
        uplink_from: None,
        round_trip_pct: None,
    };
    if let Some(echo) = summary.get::<EchoSummary>() {
        let first = echo.responders.first();
        if let Some(split) = first.and_then(|r| r.split.as_ref()) {
            latency.uplink = Some(OneWay {
                p50_ms: split.uplink_p50_ms,
                p99_ms: split.uplink_p99_ms,
                max_ms: split.uplink_max_ms,
            });
            latency.downlink = Some(OneWay {
                p50_ms: split.downlink_p50_ms,
                p99_ms: split.downlink_p99_ms,
                max_ms: split.downlink_max_ms,
            });
        }
        if let Some(d) = first.and_then(|r| r.direction.as_ref()) {
            loss.round_trip_pct = Some(100.0 * d.round_trip_loss);
            loss.downlink_pct = Some(100.0 * d.downlink_loss);
            if d.consistent {
                loss.uplink_pct = d.uplink_loss.map(|u| 100.0 * u.max(0.0));
                loss.uplink_from = loss.uplink_pct.map(|_| "direction_split");
            }
        } else if let Some(r) = first {
            loss.round_trip_pct = Some(100.0 * r.loss_ratio);
        }
        node_uplink(&echo.link_node, &mut loss);
    } else if let Some(passive) = summary.get::<PassiveSummary>() {
        let (lost, numbered) = passive
            .table
            .sources
            .iter()
            .filter(|s| !s.ground && !s.radio && !is_radio_ids(s.source))
            .fold((0, 0), |(l, n), s| {
                (l + s.counts.lost, n + s.counts.numbered())
            });
        loss.downlink_pct = (numbered > 0).then(|| 100.0 * lost as f64 / numbered as f64);
        node_uplink(&passive.link_node, &mut loss);
    }
    (latency, loss)
}

/// The vehicle's own count of what reached it, over the guess.
fn node_uplink(nodes: &[LinkNodeSummary], loss: &mut DirectionLoss) {
    let node = nodes
        .iter()
        .find(|n| !is_radio_ids(n.id) && n.uplink_loss.is_some());
    if let Some(up) = node.and_then(|n| n.uplink_loss) {
        loss.uplink_pct = Some(100.0 * up);
        loss.uplink_from = Some("link_node_status");
    }
}
