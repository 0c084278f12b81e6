//! The vehicle's own view of the link: LINK_NODE_STATUS (message 8), which
//! PX4 sends at 1 Hz on most links. Per node (the sender's ids): its first
//! and last report, and how much each since-boot counter grew between
//! them: the messages it received, lost (by their packet sequence) and
//! sent on that link, its parse errors and buffer overflows. Its uplink
//! loss is lost / (received + lost) of that growth: what the vehicle saw
//! of everything sent to it on that link, ours and anyone else's.
//!
//! In a probe run the vehicle's figure is held against mavping's own
//! uplink estimate (`probe::uplink_check`).
//!
//! Pure: the session feeds reports with their times; nothing here reads a
//! clock. Memory is bounded by [`MAX_NODES`].

use std::collections::BTreeMap;

use serde::Serialize;

use super::Nanos;
use crate::frame::SysComp;

/// One LINK_NODE_STATUS as received: the frame's own struct, under the
/// name the engine and the reports know it by.
pub(crate) use crate::frame::LinkNodeStatus as LinkNodeReport;

/// A spoofing flood cannot grow memory beyond this many nodes.
pub(crate) const MAX_NODES: usize = 16;
/// The vehicle's figure and mavping's estimate disagree when they are
/// more than this many (combined) standard errors apart.
pub(crate) const DISAGREE_SIGMAS: f64 = 3.0;

/// The widths of the since-boot counters: LINK_NODE_STATUS has 32-bit
/// message counts and 16-bit error counts.
pub(crate) trait Width: Copy + Ord + Into<u64> {
    /// A fall from at or above this is a wrap (the top sixteenth of the
    /// range); from below, the node counting again from 0.
    const WRAP_ZONE: Self;
    fn wrapping_sub(self, other: Self) -> Self;
}

impl Width for u16 {
    const WRAP_ZONE: u16 = 0xF000;
    fn wrapping_sub(self, other: u16) -> u16 {
        u16::wrapping_sub(self, other)
    }
}

impl Width for u32 {
    const WRAP_ZONE: u32 = 0xF000_0000;
    fn wrapping_sub(self, other: u32) -> u32 {
        u32::wrapping_sub(self, other)
    }
}

/// A since-boot counter: what it grew by since it was first seen. Each
/// step is taken modulo its width, so a wrap (2^32 − 6 → 5) counts as 11;
/// but after a reboot (the report's own boot clock fell, or the counter
/// fell from well below the top) the node counts from 0 again, and the
/// step is the new value. As `radio::SinceBootCounter`, for either width.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct SinceBoot<T> {
    last: Option<T>,
    grown: u64,
}

impl<T: Width> SinceBoot<T> {
    /// The counter reads `v`; `rebooted`: the node restarted since the
    /// last reading, whatever the counter shows.
    pub(crate) fn record(&mut self, v: T, rebooted: bool) {
        if let Some(last) = self.last {
            let restarted = rebooted || (v < last && last < T::WRAP_ZONE);
            self.grown += if restarted {
                v.into()
            } else {
                v.wrapping_sub(last).into()
            };
        }
        self.last = Some(v);
    }

    pub(crate) fn grown(&self) -> u64 {
        self.grown
    }
}

/// Every counter of one node, followed across wraps and reboots.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct NodeCounters {
    /// The boot clock of the last report (ms): a fall is a reboot.
    last_timestamp: Option<u64>,
    pub(crate) reboots: u64,
    pub(crate) received: SinceBoot<u32>,
    pub(crate) lost: SinceBoot<u32>,
    pub(crate) sent: SinceBoot<u32>,
    pub(crate) rx_parse_err: SinceBoot<u16>,
    pub(crate) rx_overflows: SinceBoot<u16>,
    pub(crate) tx_overflows: SinceBoot<u16>,
}

impl NodeCounters {
    pub(crate) fn record(&mut self, r: &LinkNodeReport) {
        let rebooted = self.last_timestamp.is_some_and(|t| r.timestamp < t);
        self.reboots += u64::from(rebooted);
        self.last_timestamp = Some(r.timestamp);
        self.received.record(r.messages_received, rebooted);
        self.lost.record(r.messages_lost, rebooted);
        self.sent.record(r.messages_sent, rebooted);
        self.rx_parse_err.record(r.rx_parse_err, rebooted);
        self.rx_overflows.record(r.rx_overflows, rebooted);
        self.tx_overflows.record(r.tx_overflows, rebooted);
    }

    /// Lost over what the node saw of the link (received + lost), once it
    /// saw anything.
    pub(crate) fn loss(&self) -> Option<f64> {
        let seen = self.received.grown() + self.lost.grown();
        (seen > 0).then(|| self.lost.grown() as f64 / seen as f64)
    }
}

#[derive(Debug, Clone)]
struct Node {
    reports: u64,
    first_at: Nanos,
    last_at: Nanos,
    first: LinkNodeReport,
    last: LinkNodeReport,
    counters: NodeCounters,
}

/// The end-of-run figures of one node.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub(crate) struct LinkNodeSummary {
    pub(crate) id: SysComp,
    pub(crate) reports: u64,
    /// Session time of its first and last report, s.
    pub(crate) first_t_s: f64,
    pub(crate) last_t_s: f64,
    pub(crate) first: LinkNodeReport,
    pub(crate) last: LinkNodeReport,
    /// Times its boot clock went back between reports.
    pub(crate) reboots: u64,
    /// What each since-boot counter grew by between the first report and
    /// the last (wrap- and reboot-safe).
    pub(crate) received_delta: u64,
    pub(crate) lost_delta: u64,
    pub(crate) sent_delta: u64,
    pub(crate) rx_parse_err_delta: u64,
    pub(crate) rx_overflows_delta: u64,
    pub(crate) tx_overflows_delta: u64,
    /// lost / (received + lost) of the growth: the loss on the way to it,
    /// of everything sent to it on that link. `None` before it counted any.
    pub(crate) uplink_loss: Option<f64>,
    /// A probe run: the figure beside mavping's uplink estimate for the
    /// same system.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(crate) compared: Option<UplinkComparison>,
}

impl LinkNodeSummary {
    /// What the node saw of the link: received + lost.
    pub(crate) fn seen(&self) -> u64 {
        self.received_delta + self.lost_delta
    }
}

/// The vehicle's uplink loss against mavping's estimate for one responder.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub(crate) struct UplinkComparison {
    /// The responder whose requests the estimate is of.
    pub(crate) responder: SysComp,
    /// mavping's uplink loss estimate and its standard error (the
    /// direction split; 0 when no request was lost).
    pub(crate) estimate: f64,
    pub(crate) estimate_stderr: f64,
    /// The vehicle's figure and its own binomial standard error.
    pub(crate) vehicle: f64,
    pub(crate) vehicle_stderr: f64,
    /// |vehicle − estimate| in their combined standard errors.
    pub(crate) sigmas: f64,
    /// Within [`DISAGREE_SIGMAS`].
    pub(crate) agrees: bool,
}

/// All nodes heard, keyed by their MAVLink source.
#[derive(Debug, Default)]
pub(crate) struct LinkNodes {
    nodes: BTreeMap<SysComp, Node>,
}

impl LinkNodes {
    /// Records a report; returns true for a node's first one. Reports
    /// from nodes beyond [`MAX_NODES`] are ignored.
    pub(crate) fn record(&mut self, id: SysComp, r: LinkNodeReport, at: Nanos) -> bool {
        let first = !self.nodes.contains_key(&id);
        if first && self.nodes.len() >= MAX_NODES {
            return false;
        }
        let node = self.nodes.entry(id).or_insert_with(|| Node {
            reports: 0,
            first_at: at,
            last_at: at,
            first: r,
            last: r,
            counters: NodeCounters::default(),
        });
        node.reports += 1;
        node.last_at = at;
        node.last = r;
        node.counters.record(&r);
        first
    }

    pub(crate) fn summaries(&self) -> Vec<LinkNodeSummary> {
        self.nodes
            .iter()
            .map(|(&id, n)| {
                let c = &n.counters;
                LinkNodeSummary {
                    id,
                    reports: n.reports,
                    first_t_s: n.first_at as f64 / 1e9,
                    last_t_s: n.last_at as f64 / 1e9,
                    first: n.first,
                    last: n.last,
                    reboots: c.reboots,
                    received_delta: c.received.grown(),
                    lost_delta: c.lost.grown(),
                    sent_delta: c.sent.grown(),
                    rx_parse_err_delta: c.rx_parse_err.grown(),
                    rx_overflows_delta: c.rx_overflows.grown(),
                    tx_overflows_delta: c.tx_overflows.grown(),
                    uplink_loss: c.loss(),
                    compared: None,
                }
            })
            .collect()
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    pub(crate) const VEHICLE: SysComp = SysComp {
        sysid: 1,
        compid: 1,
    };

    /// A report at `t_ms` of the vehicle's boot clock.
    pub(crate) fn report(t_ms: u64, received: u32, lost: u32, parse: u16) -> LinkNodeReport {
        LinkNodeReport {
            timestamp: t_ms,
            messages_received: received,
            messages_lost: lost,
            messages_sent: received.wrapping_mul(3),
            rx_parse_err: parse,
            ..LinkNodeReport::default()
        }
    }

    #[test]
    fn a_u32_counter_grows_across_its_wrap() {
        let mut c = SinceBoot::<u32>::default();
        for v in [u32::MAX - 10, u32::MAX - 5, 5, 20] {
            c.record(v, false);
        }
        // 5, then 11 through the wrap (2^32 − 6 → 5), then 15.
        assert_eq!(c.grown(), 31);
    }

    #[test]
    fn a_fall_from_below_the_top_is_a_reboot_in_either_width() {
        let mut c = SinceBoot::<u32>::default();
        for v in [900_000, 1_000_000, 4, 10] {
            c.record(v, false);
        }
        // 100 000, then 4 since the restart, then 6: not 2^32 − 999 996.
        assert_eq!(c.grown(), 100_010);
        let mut c = SinceBoot::<u16>::default();
        for v in [65_530, 3, 100, 7] {
            c.record(v, false);
        }
        // 9 through the wrap, 97, then 7 since the restart.
        assert_eq!(c.grown(), 113);
    }

    #[test]
    fn a_boot_clock_that_falls_is_a_reboot_even_near_the_top() {
        let mut nodes = LinkNodes::default();
        // Near the top of the range a fall alone would read as a wrap:
        // the boot clock (ms) going back says the node restarted.
        nodes.record(VEHICLE, report(50_000, u32::MAX - 100, 10, 65_000), 0);
        nodes.record(VEHICLE, report(51_000, u32::MAX - 50, 12, 65_100), 1);
        nodes.record(VEHICLE, report(900, 30, 1, 2), 2);
        nodes.record(VEHICLE, report(1_900, 80, 1, 2), 3);
        let s = &nodes.summaries()[0];
        assert_eq!(s.reboots, 1);
        // 50, then 30 counted since the reboot, then 50.
        assert_eq!(s.received_delta, 130);
        assert_eq!(s.lost_delta, 3);
        assert_eq!(s.rx_parse_err_delta, 102);
        assert_eq!(s.uplink_loss, Some(3.0 / 133.0));
        assert_eq!((s.first.timestamp, s.last.timestamp), (50_000, 1_900));
        assert_eq!((s.first_t_s, s.last_t_s, s.reports), (0.0, 3e-9, 4));
    }

    #[test]
    fn a_single_report_grows_nothing_and_has_no_loss() {
        let mut nodes = LinkNodes::default();
        assert!(nodes.record(VEHICLE, report(1, 500, 7, 1), 10));
        let s = &nodes.summaries()[0];
        assert_eq!((s.received_delta, s.lost_delta, s.reports), (0, 0, 1));
        assert_eq!(s.uplink_loss, None);
        assert_eq!(s.first, s.last);
    }

    #[test]
    fn nodes_are_bounded() {
        let mut nodes = LinkNodes::default();
        for sysid in 0..=255u8 {
            nodes.record(SysComp::new(sysid, 1), report(1, 1, 0, 0), 0);
        }
        assert_eq!(nodes.summaries().len(), MAX_NODES);
        assert!(!nodes.record(SysComp::new(200, 1), report(2, 2, 0, 0), 1));
    }
}
