//! What the C2 report takes from the run's own summary: the delay each
//! way (the round trip's split by the responder's stamps) and the loss
//! each way (the vehicle's sequence numbers down; up, its own
//! LINK_NODE_STATUS counts where it sends them, else the direction split).

use super::report::{DirectionLoss, Latency, OneWay};
use crate::engine::age::{SourceAge, MAX_DRIFT_PPM};
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
        downlink_from: None,
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
            latency.downlink_from = Some("round_trip_split");
        }
        frame_age(&echo.age, &mut latency);
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
        frame_age(&passive.age, &mut latency);
        node_uplink(&passive.link_node, &mut loss);
    }
    (latency, loss)
}

/// Where no round trip was split, the downlink's delay above its least
/// from the vehicle's own clock stamps: the source with the most aged
/// frames (the ground station's are not among a run's ages). A baseline
/// whose drift sits at the limit is a clock that runs at another rate
/// (a sped-up simulation): its ages mean nothing, and none is given.
fn frame_age(ages: &[SourceAge], latency: &mut Latency) {
    if latency.downlink.is_some() {
        return;
    }
    let vehicle = ages
        .iter()
        .filter(|a| !is_radio_ids(a.source))
        .max_by_key(|a| a.headline.samples)
        .filter(|a| {
            !a.headline
                .drift_ppm
                .is_some_and(|d| d.abs() >= MAX_DRIFT_PPM * 0.999)
        });
    if let Some(a) = vehicle {
        latency.downlink = Some(OneWay {
            p50_ms: a.headline.p50_ms,
            p99_ms: a.headline.p99_ms,
            max_ms: a.headline.max_ms,
        });
        latency.downlink_from = Some("frame_age");
    }
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
