//! One link's session, whatever the probe: the piece every run path
//! shares (`mavping LINK...` and each link and probe of `mavping serve`).

use std::rc::Rc;

use crate::config::{LinkConfig, Probe};
use crate::engine::observe::Observer;
use crate::engine::probe::auto::AutoProbe;
use crate::engine::probe::command::driver as command;
use crate::engine::probe::echo;
use crate::engine::probe::passive::driver::{self as passive, PassiveDriver};
use crate::engine::probe::ping::PingProbe;
use crate::engine::probe::timesync::TimesyncProbe;
use crate::engine::probe::transfer::driver as transfer;
use crate::engine::probe::EchoProbe;
use crate::engine::session::{self, Controls, Measurement};
use crate::engine::summary::passive::PassiveSummary;
use crate::engine::{sweep, SessionConfig};
use crate::output::WallClock;
use crate::transport::recording::{Recorded, Tap, Watch};
use crate::transport::sim::SimLink;
use crate::transport::{Link, LinkSpec};

/// An echo probe's run, in steps when `--sweep` or `--load` asks.
async fn echo_or_steps<P: EchoProbe>(
    session: &SessionConfig,
    link: &mut Recorded<Link>,
    probe: P,
    observer: &mut dyn Observer,
    controls: &Controls,
) -> Measurement {
    match &session.sweep {
        Some(steps) => sweep::driver::run(session, steps, link, probe, observer, controls).await,
        None => echo::run(session, link, probe, observer, controls).await,
    }
}

/// Runs `probe` on the opened `link` until the session ends; its outcome.
pub(super) async fn measure(
    config: &LinkConfig,
    link: Link,
    probe: &Probe,
    wall: WallClock,
    observer: &mut dyn Observer,
    controls: &Controls,
) -> Measurement {
    measure_recorded(
        config,
        link,
        Taps::default(),
        probe,
        wall,
        observer,
        controls,
    )
    .await
}

/// What a run taps of one link besides its session.
#[derive(Default)]
pub(super) struct Taps {
    /// Its way into the `--tlog` recording.
    pub(super) tlog: Option<Tap>,
    /// What the run watches of its frames across its links.
    pub(super) watch: Option<Rc<dyn Watch>>,
    /// Its number among several links, put in its TIMESYNC tokens' low
    /// four bits as MAVProxy's `ping` puts its out-link there.
    pub(super) out_link: Option<u8>,
}

/// [`measure`], recording what the link receives and sends (`--tlog`) and
/// telling what it receives to the run's watch, when there are.
pub(super) async fn measure_recorded(
    config: &LinkConfig,
    link: Link,
    taps: Taps,
    probe: &Probe,
    wall: WallClock,
    observer: &mut dyn Observer,
    controls: &Controls,
) -> Measurement {
    let out_link = taps.out_link;
    let mut link = Recorded::new(link, taps.tlog).watched(taps.watch);
    let session = &config.session;
    let mut outcome = match probe {
        Probe::Command(spec) => command::run(session, spec, &mut link, observer, controls).await,
        Probe::Transfer(spec) => {
            let wall_clock = !matches!(config.spec, LinkSpec::Sim(_));
            let timeout = session.timeout.as_nanos() as u64;
            let beside = AutoProbe::new(wall.micros_since_epoch(), wall_clock, timeout);
            transfer::run(session, spec, &mut link, beside, observer, controls).await
        }
        // A log: a table per MAVProxy link too, and what the log held.
        Probe::Passive { gap } if matches!(link.inner(), Link::Tlog(_)) => {
            let driver = PassiveDriver::for_log(session, *gap);
            session::run(session, &mut link, driver, observer, controls).await
        }
        Probe::Passive { gap } => passive::run(session, *gap, &mut link, observer, controls).await,
        Probe::Timesync { target } => {
            // The simulated link has no wall clock: its responders count
            // from its start, and so do we there (reproducible output).
            let wall_clock = !matches!(config.spec, LinkSpec::Sim(_));
            let mut probe = TimesyncProbe::new(*target, wall_clock);
            if let Some(out) = out_link {
                probe = probe.with_out_link(out);
            }
            echo_or_steps(session, &mut link, probe, observer, controls).await
        }
        Probe::Auto => {
            let wall_clock = !matches!(config.spec, LinkSpec::Sim(_));
            let timeout = session.timeout.as_nanos() as u64;
            let probe = AutoProbe::new(wall.micros_since_epoch(), wall_clock, timeout);
            echo_or_steps(session, &mut link, probe, observer, controls).await
        }
        Probe::Ping => {
            let mut probe = PingProbe::new(wall.micros_since_epoch());
            if let Some(out) = out_link {
                probe = probe.with_out_link(out);
            }
            echo_or_steps(session, &mut link, probe, observer, controls).await
        }
    };
    if let (Link::Tlog(log), Some(s)) = (link.inner(), outcome.summary.get_mut::<PassiveSummary>())
    {
        s.log = log.facts();
        let first_us = s.log.as_ref().map(|f| f.stamps.first_us);
        if let (Some(us), Some(c2)) = (first_us, outcome.summary.c2_mut()) {
            c2.date(std::time::SystemTime::UNIX_EPOCH + std::time::Duration::from_micros(us));
        }
    }
    // The simulated link's ground truth, for soak scripts (`-v`).
    if let Link::Sim(sim) = link.inner() {
        log_sim_truth(&config.name, sim);
    }
    outcome
}

/// The simulated link's ground truth, logged with `-v`: each responder's,
/// each path's (`paths=`) and the queues'.
fn log_sim_truth(name: &str, sim: &SimLink) {
    for (id, t) in sim.truth() {
        tracing::info!(
            link = %name,
            "sim truth {id}: answered={} dropped={} dropped_before_first={} delivered={} \
             duplicated={} duplicates_arrived={} outage={} spiked={} spiked_arrived={} \
             down_sent={} down_dropped={} down_duplicated={} down_duplicates_arrived={} \
             down_delivered={} down_reordered={} up_sent={} up_dropped={} \
             up_requests_dropped={} up_duplicated={} up_requests_duplicated={}",
            t.answered,
            t.dropped,
            t.dropped_before_first,
            t.delivered,
            t.duplicated,
            t.duplicates_arrived,
            t.outage,
            t.spiked,
            t.spiked_arrived,
            t.down.sent,
            t.down.dropped,
            t.down.duplicated,
            t.down.duplicates_arrived,
            t.down.delivered,
            t.down.reordered,
            t.up.sent,
            t.up.dropped,
            t.up.requests_dropped,
            t.up.duplicated,
            t.up.requests_duplicated
        );
        if t.served.requests.total() > 0 {
            tracing::info!(link = %name, "sim truth {id} {}", t.served);
        }
    }
    let queues = sim.queue_truth();
    if !queues.up.is_zero() || !queues.down.is_zero() {
        tracing::info!(
            link = %name,
            "sim truth queues: up_max_ms={:.3} down_max_ms={:.3}",
            queues.up.as_secs_f64() * 1e3,
            queues.down.as_secs_f64() * 1e3
        );
    }
    for (id, t) in sim.path_truth() {
        for (k, p) in t.paths.iter().enumerate() {
            tracing::info!(
                link = %name,
                "sim truth path {k} {id}: sent={} dropped={} drawn={} outage={} \
                 missing={} delivered={} first={} only={} duplicates={}",
                p.sent,
                p.dropped,
                p.drawn,
                p.outage,
                p.missing,
                p.delivered,
                p.first,
                p.only,
                p.duplicates
            );
        }
        tracing::info!(
            link = %name,
            "sim truth paths {id}: lost_on_every_path={} missing_on_every_path={}",
            t.lost_on_every_path,
            t.missing_on_every_path
        );
    }
}
