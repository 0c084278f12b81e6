//! The continuous links of `mavping serve`: each measured all the time by
//! the one run path, into metrics `/metrics` shows. A link that cannot be
//! opened or breaks shows `mavping_link_up 0` and is reopened with
//! backoff. A reload keeps the links that did not change running, and the
//! history of those it restarts under the same name and probe.

use std::sync::Arc;
use std::time::{Duration, Instant};

use tokio::sync::Notify;

use crate::engine::session::Controls;
use tokio::task::JoinHandle;

use crate::config::ContinuousLink;
use crate::output::prometheus::{Metrics, SharedMetrics};
use crate::output::WallClock;
use crate::run::one_link::measure;
use crate::stderr;
use crate::transport::Link;

/// The first wait before reopening a link, doubled at each failure in a row.
const FIRST_BACKOFF: Duration = Duration::from_secs(1);
const MAX_BACKOFF: Duration = Duration::from_secs(60);
/// A link that ran this long before breaking starts its backoff afresh.
const STEADY: Duration = Duration::from_secs(60);

/// One running continuous link.
struct Running {
    config: ContinuousLink,
    metrics: SharedMetrics,
    stop: Arc<Notify>,
    task: JoinHandle<()>,
}

/// Every continuous link, in configuration order.
#[derive(Default)]
pub(super) struct Links {
    running: Vec<Running>,
}

impl Links {
    /// Runs exactly `wanted`: links that did not change go on untouched,
    /// changed ones are restarted (keeping their history when their name
    /// and probe stay), new ones start, the others stop.
    pub(super) fn reconcile(&mut self, wanted: &[ContinuousLink]) {
        let mut old = std::mem::take(&mut self.running);
        for config in wanted {
            let same_name = old
                .iter()
                .position(|r| r.config.link.name == config.link.name);
            let running = match same_name.map(|i| old.remove(i)) {
                Some(r) if r.config == *config => r,
                Some(r) => {
                    r.stop.notify_one();
                    let metrics = if r.config.probe.name() == config.probe.name() {
                        r.metrics
                    } else {
                        fresh(config)
                    };
                    start(config.clone(), metrics, Some(r.task))
                }
                None => start(config.clone(), fresh(config), None),
            };
            self.running.push(running);
        }
        for gone in old {
            gone.stop.notify_one();
        }
    }

    /// Every link's metrics, in configuration order.
    pub(super) fn metrics(&self) -> Vec<SharedMetrics> {
        self.running.iter().map(|r| r.metrics.clone()).collect()
    }
}

fn fresh(config: &ContinuousLink) -> SharedMetrics {
    SharedMetrics::new(Metrics::continuous(&config.link.name, config.probe.name()))
}

/// Starts measuring `config` once `previous` (its former self) has let go
/// of the link.
fn start(
    config: ContinuousLink,
    metrics: SharedMetrics,
    previous: Option<JoinHandle<()>>,
) -> Running {
    let controls = Controls::default();
    let stop = controls.stop.clone();
    let task = tokio::task::spawn_local({
        let (config, metrics) = (config.clone(), metrics.clone());
        async move {
            if let Some(previous) = previous {
                let _ = previous.await;
            }
            keep_measuring(&config, &metrics, &controls).await;
        }
    });
    Running {
        config,
        metrics,
        stop,
        task,
    }
}

/// Opens and measures the link until stopped, reopening it with backoff
/// whenever it cannot be opened or breaks.
async fn keep_measuring(config: &ContinuousLink, metrics: &SharedMetrics, controls: &Controls) {
    let stop = &*controls.stop;
    let name = &config.link.name;
    let wall = WallClock::starting(false);
    let mut backoff = FIRST_BACKOFF;
    loop {
        let opened = tokio::select! {
            opened = Link::open(&config.link.spec, &config.options) => opened,
            () = stop.notified() => return,
        };
        let error = match opened {
            Ok(link) => {
                metrics.update(|m| m.set_up(true));
                let started = Instant::now();
                let mut observer = metrics.clone();
                let outcome = measure(
                    &config.link,
                    link,
                    &config.probe,
                    wall,
                    &mut observer,
                    controls,
                )
                .await;
                metrics.update(|m| m.set_up(false));
                // Without an error, the session ended because it was stopped.
                let Some(e) = outcome.summary.link_error() else {
                    return;
                };
                if started.elapsed() > STEADY {
                    backoff = FIRST_BACKOFF;
                }
                e.to_string()
            }
            Err(e) => e.to_string(),
        };
        stderr::warning(&format_args!(
            "link {name}: {error}; retrying in {}",
            humantime::format_duration(backoff)
        ));
        tokio::select! {
            () = tokio::time::sleep(backoff) => {}
            () = stop.notified() => return,
        }
        metrics.update(Metrics::restarted);
        backoff = (backoff * 2).min(MAX_BACKOFF);
    }
}
