//! The vehicle's own uplink figure (LINK_NODE_STATUS, `engine::link_node`)
//! beside mavping's estimate for the same system (the round trip split by
//! the responder's sequence, [`Direction`]): [`compare_uplink`] says when
//! the two disagree. Here, not in `link_node`, so that the vehicle's
//! counters name no summary of a probe run.

use crate::engine::hint::{Hint, HintCode};
use crate::engine::link_node::{LinkNodeSummary, UplinkComparison, DISAGREE_SIGMAS};
use crate::engine::summary::{Direction, ResponderSummary};
use crate::frame::SysComp;

/// The binomial standard error of `p` over `n`, never under 1/n (with
/// nothing lost of n, 3/n is the usual 95 % bound: the rule of three).
fn stderr(p: f64, n: u64) -> f64 {
    let n = n.max(1) as f64;
    (p * (1.0 - p) / n).sqrt().max(1.0 / n)
}

/// mavping's uplink estimate for a responder and its standard error: the
/// direction split's when it holds; 0 when nothing was lost at all.
fn estimate(r: &ResponderSummary) -> Option<(f64, f64)> {
    let requests = r.counts.sent;
    match r.direction {
        Some(Direction {
            uplink_loss: Some(up),
            uplink_stderr: Some(se),
            consistent: true,
            ..
        }) => Some((up, se.max(1.0 / requests.max(1) as f64))),
        None if requests > 0 && r.counts.lost == 0 => Some((0.0, stderr(0.0, requests))),
        // No split, or one that does not hold: nothing to compare with.
        _ => None,
    }
}

/// The responder a node speaks for: the one with its ids, else the one
/// responder of its system.
fn responder_of(id: SysComp, responders: &[ResponderSummary]) -> Option<&ResponderSummary> {
    responders.iter().find(|r| r.id == id).or_else(|| {
        let mut same = responders.iter().filter(|r| r.id.sysid == id.sysid);
        match (same.next(), same.next()) {
            (Some(r), None) => Some(r),
            _ => None,
        }
    })
}

/// Puts each node's uplink figure beside mavping's estimate for its
/// system, and a hint for each that disagrees.
pub(crate) fn compare_uplink(
    nodes: &mut [LinkNodeSummary],
    responders: &[ResponderSummary],
) -> Vec<Hint> {
    let mut hints = Vec::new();
    for node in nodes {
        let Some(vehicle) = node.uplink_loss else {
            continue;
        };
        let Some(r) = responder_of(node.id, responders) else {
            continue;
        };
        let Some((est, est_se)) = estimate(r) else {
            continue;
        };
        let vehicle_se = stderr(vehicle, node.seen());
        let sigmas = (vehicle - est).abs() / est_se.hypot(vehicle_se);
        let c = UplinkComparison {
            responder: r.id,
            estimate: est,
            estimate_stderr: est_se,
            vehicle,
            vehicle_stderr: vehicle_se,
            sigmas,
            agrees: sigmas <= DISAGREE_SIGMAS,
        };
        node.compared = Some(c);
        if !c.agrees {
            hints.push(disagreement(node.id, &c));
        }
    }
    hints
}

fn percent(ratio: f64) -> String {
    format!("{:.2}%", ratio * 100.0)
}

/// What the disagreement says, whichever way it goes.
fn disagreement(id: SysComp, c: &UplinkComparison) -> Hint {
    let why = if c.vehicle < c.estimate {
        "our requests are lost where its count does not see them: it received requests it \
         did not answer, something between re-numbers our frames, or it counts another link"
    } else {
        "it counts losses our requests did not suffer: other senders on its link, another \
         link, or a sequence count that charges duplicates and reordering as loss"
    };
    Hint::new(
        HintCode::VehicleUplinkDisagrees,
        format!(
            "vehicle {id} counts {} of what reached it lost (LINK_NODE_STATUS), mavping's up \
             estimate for {} is {} ± {} ({:.1} standard errors apart): {why}",
            percent(c.vehicle),
            c.responder,
            percent(c.estimate),
            percent(c.estimate_stderr),
            c.sigmas
        ),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::engine::link_node::tests::{report, VEHICLE};
    use crate::engine::link_node::LinkNodes;
    use crate::engine::matcher::Counts;

    fn responder(
        id: SysComp,
        sent: u64,
        lost: u64,
        direction: Option<Direction>,
    ) -> ResponderSummary {
        ResponderSummary {
            id,
            counts: Counts {
                sent,
                received: sent - lost,
                lost,
                ..Counts::default()
            },
            loss_ratio: lost as f64 / sent as f64,
            rtt: None,
            histogram: vec![],
            identity: None,
            probe: None,
            clock: None,
            direction,
            split: None,
        }
    }

    /// A node that saw `received` and `lost` of the link.
    fn node(id: SysComp, received: u32, lost: u32) -> LinkNodeSummary {
        let mut nodes = LinkNodes::default();
        nodes.record(id, report(0, 0, 0, 0), 0);
        nodes.record(id, report(1_000, received, lost, 0), 1);
        nodes.summaries().remove(0)
    }

    #[test]
    fn the_vehicles_figure_is_held_against_the_split() {
        // 1000 requests, 145 lost round trip; its downlink lost 100 of
        // 2000: up ~10 % ± ~1.1 %.
        let d = Direction::split(0.145, 1000, 2000, 100);
        let r = responder(VEHICLE, 1000, 145, d);
        let up = d.unwrap().uplink_loss.unwrap();
        // The vehicle counts 110 of 1100 lost (10 %): agrees.
        let mut nodes = vec![node(VEHICLE, 990, 110)];
        assert!(compare_uplink(&mut nodes, std::slice::from_ref(&r)).is_empty());
        let c = nodes[0].compared.unwrap();
        assert!(c.agrees && c.sigmas < 1.0, "{c:?}");
        assert_eq!((c.estimate, c.vehicle, c.responder), (up, 0.1, VEHICLE));
        // It claims none lost: 0 against ~10 %, said.
        let mut nodes = vec![node(VEHICLE, 1100, 0)];
        let hints = compare_uplink(&mut nodes, std::slice::from_ref(&r));
        let c = nodes[0].compared.unwrap();
        assert!(!c.agrees && c.sigmas > 6.0, "{c:?}");
        assert_eq!(hints.len(), 1);
        assert_eq!(hints[0].code, HintCode::VehicleUplinkDisagrees);
        assert!(
            hints[0]
                .text
                .starts_with("vehicle 1/1 counts 0.00% of what reached it lost (LINK_NODE_STATUS), mavping's up estimate for 1/1 is 10.00% ± 1.26% (7.9 standard errors apart)"),
            "{}",
            hints[0].text
        );
        assert!(hints[0]
            .text
            .contains("it received requests it did not answer"));
        // Another component of the same system speaks for it; another
        // system does not.
        let mut nodes = vec![
            node(SysComp::new(1, 191), 1100, 0),
            node(SysComp::new(2, 1), 1100, 0),
        ];
        assert_eq!(compare_uplink(&mut nodes, &[r]).len(), 1);
        assert!(nodes[0].compared.is_some() && nodes[1].compared.is_none());
    }

    #[test]
    fn nothing_lost_is_an_estimate_of_zero_within_the_rule_of_three() {
        // 1000 requests, none lost, no direction split.
        let r = responder(VEHICLE, 1000, 0, None);
        // 2 of 1000 is within 3/1000 ...
        let mut nodes = vec![node(VEHICLE, 998, 2)];
        assert!(compare_uplink(&mut nodes, std::slice::from_ref(&r)).is_empty());
        assert!(nodes[0].compared.unwrap().agrees);
        // ... 50 of 1000 is not: it counts losses we did not suffer.
        let mut nodes = vec![node(VEHICLE, 950, 50)];
        let hints = compare_uplink(&mut nodes, &[r]);
        assert_eq!(hints.len(), 1, "{hints:?}");
        assert!(hints[0]
            .text
            .contains("it counts losses our requests did not suffer"));
    }

    #[test]
    fn no_comparison_without_a_split_or_a_count() {
        // The split does not hold (the downlink loses more than the round
        // trip): nothing to hold the vehicle against.
        let d = Direction::split(0.01, 1000, 1000, 200);
        assert!(!d.unwrap().consistent);
        let mut nodes = vec![node(VEHICLE, 900, 100)];
        assert!(compare_uplink(&mut nodes, &[responder(VEHICLE, 1000, 10, d)]).is_empty());
        assert!(nodes[0].compared.is_none());
        // One report: the node counted nothing yet.
        let mut nodes = LinkNodes::default();
        nodes.record(VEHICLE, report(0, 5, 5, 0), 0);
        let mut nodes = nodes.summaries();
        let r = responder(VEHICLE, 100, 0, None);
        assert!(compare_uplink(&mut nodes, &[r]).is_empty());
        assert!(nodes[0].compared.is_none());
    }
}
