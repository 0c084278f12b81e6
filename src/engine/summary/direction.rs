//! Round-trip loss split into uplink and downlink ([`Direction`]): a
//! formula of its own, used by the echo summary at the end of a run and
//! by Prometheus while a run goes on.

use serde::Serialize;

use super::passive;

/// Round-trip loss split by direction. The downlink loss is the sequence
/// loss of every frame the responder sent us (replies, telemetry,
/// HEARTBEATs); a request survives both ways with (1 − up)(1 − down), so
/// up = 1 − (1 − round trip) / (1 − down). Its standard error is the
/// binomial errors of both ratios carried through that formula.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub(crate) struct Direction {
    pub(crate) round_trip_loss: f64,
    /// Of the round trip's loss, the share whose replies came back after
    /// the timeout: lost to neither direction (a queue), so left out of
    /// the split.
    pub(crate) late_share: f64,
    /// Frames of the responder's the sequence counted, and of them lost.
    pub(crate) downlink_frames: u64,
    pub(crate) downlink_lost: u64,
    pub(crate) downlink_loss: f64,
    /// `None` when every downlink frame was lost.
    pub(crate) uplink_loss: Option<f64>,
    pub(crate) uplink_stderr: Option<f64>,
    /// False when the downlink alone loses more than the round trip, by
    /// more than two standard errors: the responder's sequence does not
    /// number just what it sends us on this link (a router re-sequencing,
    /// or merging links), so the split would be wrong.
    pub(crate) consistent: bool,
}

impl Direction {
    /// The split for a responder with `round_trip` loss over `requests`,
    /// whose own frames' sequence counted `seq`: every front end's one
    /// way in (the summary at the end, Prometheus while a run goes on).
    /// `late` of the requests were answered after the timeout: counted
    /// in the round trip's loss, but not lost on the way.
    pub(crate) fn of_sequence(
        round_trip: f64,
        requests: u64,
        late: u64,
        seq: &passive::SeqCounts,
    ) -> Option<Self> {
        let late_share = (late as f64 / requests.max(1) as f64).min(round_trip);
        let mut d = Direction::split(round_trip - late_share, requests, seq.numbered(), seq.lost)?;
        d.round_trip_loss = round_trip;
        d.late_share = late_share;
        Some(d)
    }

    /// The split for a responder `round_trip` of whose `requests` were
    /// lost, whose sequence counted `frames` and `lost` of them.
    pub(crate) fn split(round_trip: f64, requests: u64, frames: u64, lost: u64) -> Option<Self> {
        if requests == 0 || frames == 0 || (round_trip == 0.0 && lost == 0) {
            return None;
        }
        let down = lost as f64 / frames as f64;
        let se = |p: f64, n: u64| (p * (1.0 - p) / n as f64).sqrt();
        let (se_rt, se_down) = (se(round_trip, requests), se(down, frames));
        let kept = 1.0 - down;
        let (uplink, stderr) = if kept > 0.0 {
            let up = 1.0 - (1.0 - round_trip) / kept;
            let stderr = ((se_rt / kept).powi(2)
                + ((1.0 - round_trip) * se_down / kept.powi(2)).powi(2))
            .sqrt();
            (Some(up), Some(stderr))
        } else {
            (None, None)
        };
        let consistent = match (uplink, stderr) {
            (Some(up), Some(e)) => up >= -2.0 * e.max(1e-9),
            _ => true,
        };
        Some(Direction {
            round_trip_loss: round_trip,
            late_share: 0.0,
            downlink_frames: frames,
            downlink_lost: lost,
            downlink_loss: down,
            uplink_loss: uplink.map(|u| u.clamp(0.0, 1.0)),
            uplink_stderr: stderr,
            consistent,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn direction_splits_the_round_trip_and_says_when_it_cannot() {
        // 10% up and 5% down: 1 - 0.9 * 0.95 = 14.5% round trip.
        let d = Direction::split(0.145, 10_000, 20_000, 1_000).unwrap();
        assert!((d.downlink_loss - 0.05).abs() < 1e-12);
        assert!((d.uplink_loss.unwrap() - 0.10).abs() < 1e-9, "{d:?}");
        let e = d.uplink_stderr.unwrap();
        assert!(e > 0.002 && e < 0.006, "{e}");
        assert!(d.consistent);
        // Nothing lost either way: nothing to split.
        assert_eq!(Direction::split(0.0, 100, 300, 0), None);
        assert_eq!(Direction::split(0.1, 0, 300, 0), None);
        // The downlink loses far more than the round trip: no split.
        let d = Direction::split(0.01, 1_000, 2_000, 400).unwrap();
        assert!(!d.consistent, "{d:?}");
        // Every frame of its lost: no uplink figure.
        let d = Direction::split(1.0, 10, 5, 5).unwrap();
        assert_eq!((d.uplink_loss, d.consistent), (None, true));
    }

    /// Replies that came after the timeout were lost to neither
    /// direction: a queue's late replies are no uplink loss.
    #[test]
    fn late_replies_are_left_out_of_the_split() {
        let seq = passive::SeqCounts {
            received: 1_000,
            ..passive::SeqCounts::default()
        };
        // 24 % counted lost, 22 % of them late, nothing lost down.
        let d = Direction::of_sequence(0.24, 1_000, 220, &seq).unwrap();
        assert!((d.late_share - 0.22).abs() < 1e-12, "{d:?}");
        assert!((d.uplink_loss.unwrap() - 0.02).abs() < 1e-9, "{d:?}");
        assert!((d.round_trip_loss - 0.24).abs() < 1e-12);
        // All of it late and nothing lost down: nothing to split.
        assert_eq!(Direction::of_sequence(0.2, 1_000, 200, &seq), None);
    }
}
