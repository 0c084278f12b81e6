//! A vehicle heard on several paths (`paths=`), as a radio and an LTE
//! modem both forwarding to one ground port: each frame a responder
//! sends, once through the link's own faults, is copied onto every path,
//! the same bytes on each. A path loses its copy by its own seeded draw
//! (`path_loss=`) or while its outage is on (`path_outage=`), and delays
//! it by its own `path_delay=` on top of what the link gave it; mavping
//! gets each copy with the path's index as its
//! [`PathId`](crate::transport::link::PathId). Without `paths=` the one
//! path is 0 and nothing is drawn, so the link is as it was.

use std::time::Duration;

use rand::rngs::SmallRng;
use rand::{Rng, SeedableRng};
use tokio::time::Instant;

use super::deliveries::Copies;
use super::link::SimLink;
use super::params::{PathParams, SimParams};

/// Seeds each path's draws beside `seed=` and the responders' own, with
/// the path's index: a path's plan is the same whatever the others'.
const PATH_SEED: u64 = 0x9a75_5eed_0000_0041;

/// One path and its own draws.
pub(super) struct SimPath {
    params: PathParams,
    rng: SmallRng,
}

impl SimPath {
    /// The link's paths, none without `paths=`.
    pub(super) fn all(params: &SimParams) -> Vec<SimPath> {
        (0u64..)
            .zip(&params.paths)
            .map(|(k, path)| SimPath {
                params: *path,
                rng: SmallRng::seed_from_u64((params.seed ^ PATH_SEED).wrapping_add(k)),
            })
            .collect()
    }

    /// Whether its outage is on for a frame the responder sends `since`
    /// the link opened.
    fn out(&self, since: Duration) -> bool {
        self.params
            .outage
            .is_some_and(|(start, length)| since.checked_sub(start).is_some_and(|t| t < length))
    }

    /// Whether its draw loses a copy. Drawn even in the outage, so an
    /// outage leaves the rest of the plan where it was.
    fn draws_loss(&mut self) -> bool {
        self.params.loss > 0.0 && self.rng.gen::<f64>() < self.params.loss
    }
}

impl SimLink {
    /// The link's copies of a frame responder `i` sent at `sent`, spread
    /// onto the paths: one copy on each path that does not lose it, later
    /// by its delay (none left when every path lost every copy). A path
    /// that loses every copy of the frame counts it lost to its outage
    /// when that is on, else to its draw.
    pub(super) fn on_paths(&mut self, i: usize, sent: Instant, link: &Copies) -> Copies {
        if self.paths.is_empty() {
            return *link;
        }
        let since = sent.saturating_duration_since(self.started);
        let mut spread = link.emptied();
        let mut carried = 0u8;
        for copy in link.as_slice() {
            for (k, path) in (0..).zip(self.paths.iter_mut()) {
                let drawn = path.draws_loss();
                if !drawn && !path.out(since) {
                    spread.push(copy.at + path.params.delay, copy.payload, k);
                    carried |= 1 << k;
                }
            }
        }
        let counts = &mut self.responders[i].paths;
        for (k, (path, counts)) in self.paths.iter().zip(counts.iter_mut()).enumerate() {
            if carried & (1 << k) == 0 {
                if path.out(since) {
                    counts.outage += 1;
                } else {
                    counts.drawn += 1;
                }
            }
        }
        spread
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn paths(query: &str) -> Vec<SimPath> {
        SimPath::all(&SimParams::parse(query).unwrap())
    }

    #[test]
    fn an_outage_is_on_from_its_start_for_its_length() {
        let [path] = &paths("?paths=1&path_outage=30s+5s")[..] else {
            panic!("one path");
        };
        let s = Duration::from_millis;
        for (since, out) in [
            (s(0), false),
            (s(29_999), false),
            (s(30_000), true),
            (s(34_999), true),
            (s(35_000), false),
        ] {
            assert_eq!(path.out(since), out, "{since:?}");
        }
        assert!(paths("?paths=2").iter().all(|p| !p.out(s(30_000))));
    }

    #[test]
    fn each_path_draws_its_own_share_from_its_own_seed() {
        let draws =
            |p: &mut SimPath| -> Vec<bool> { (0..100_000).map(|_| p.draws_loss()).collect() };
        let mut two = paths("?paths=2&path_loss=10%,2%&seed=4");
        let mut three = paths("?paths=3&path_loss=10%,50%,0%&seed=4");
        let first = draws(&mut two[0]);
        let lost = first.iter().filter(|&&l| l).count();
        assert!((9_500..10_500).contains(&lost), "{lost}");
        let second = draws(&mut two[1]).iter().filter(|&&l| l).count();
        assert!((1_800..2_200).contains(&second), "{second}");
        // The same seed and index: the same plan, whatever the others.
        assert_eq!(draws(&mut three[0]), first);
        // No loss set: never lost.
        assert!(draws(&mut three[2]).iter().all(|&l| !l));
        let mut other_seed = paths("?paths=1&path_loss=10%&seed=5");
        assert_ne!(draws(&mut other_seed[0]), first);
    }
}
