//! `--prometheus`: the run's links served at `/metrics` while it goes on
//! ([`PrometheusExporter`]), each link's metrics shared between its
//! session and the scrapes ([`SharedMetrics`]).

use std::cell::{Ref, RefCell};
use std::io;
use std::net::SocketAddr;
use std::rc::Rc;

use hyper::StatusCode;

use super::render::render;
use super::Metrics;
use crate::engine::summary::LinkSummary;
use crate::http::{self, Head, Limits, Reply, Replying};
use crate::output::{Event, Reporter, StartInfo};
use crate::verdict::Verdict;

/// One link's metrics, written by its session and read by scrapes; every
/// part of a run or a server lives on one thread.
#[derive(Debug, Clone, Default)]
pub struct SharedMetrics(Rc<RefCell<Metrics>>);

impl SharedMetrics {
    pub(crate) fn new(metrics: Metrics) -> Self {
        SharedMetrics(Rc::new(RefCell::new(metrics)))
    }

    pub(crate) fn get(&self) -> Ref<'_, Metrics> {
        self.0.borrow()
    }

    pub(crate) fn update(&self, f: impl FnOnce(&mut Metrics)) {
        f(&mut self.0.borrow_mut());
    }
}

impl Reporter for SharedMetrics {
    fn start(&mut self, info: &StartInfo) -> io::Result<()> {
        self.0.borrow_mut().start(info)
    }

    fn tell(&mut self, event: &Event<'_>) -> io::Result<()> {
        self.0.borrow_mut().tell(event)
    }

    fn summary(&mut self, summary: &LinkSummary, verdict: &Verdict) -> io::Result<()> {
        self.0.borrow_mut().summary(summary, verdict)
    }
}

/// Renders several shared links at once.
pub(crate) fn borrow_all(links: &[SharedMetrics]) -> Vec<Ref<'_, Metrics>> {
    links.iter().map(SharedMetrics::get).collect()
}

/// The run's exposition of shared links, each borrowed while it is
/// written, and the run's own families after them.
fn render_shared(links: &[SharedMetrics], run: &str) -> String {
    let all = borrow_all(links);
    let refs: Vec<&Metrics> = all.iter().map(|m| &**m).collect();
    render(&refs) + run
}

/// `--prometheus`: the run's links at `/metrics` while the run goes on.
#[derive(Default)]
pub struct PrometheusExporter {
    links: Rc<RefCell<Vec<SharedMetrics>>>,
    /// The run's figures across its links (the pair report), rendered by
    /// the run as they change.
    run: Rc<RefCell<String>>,
}

impl PrometheusExporter {
    /// Starts serving `listener` on the current `LocalSet`.
    pub(crate) fn serve(listener: std::net::TcpListener) -> io::Result<(Self, SocketAddr)> {
        let listener = http::listener(listener)?;
        let addr = listener.local_addr()?;
        let exporter = PrometheusExporter::default();
        http::serve(listener, Limits::default(), exporter.handler());
        Ok((exporter, addr))
    }

    /// What answers each request: `/metrics` renders every link as it is
    /// now. Also the fuzz target's way in.
    pub fn handler(&self) -> impl Fn(Head) -> Replying + 'static {
        let (links, run) = (self.links.clone(), self.run.clone());
        move |head: Head| -> Replying {
            let reply = match head.uri.path() {
                "/metrics" => Reply::metrics(render_shared(&links.borrow(), &run.borrow())),
                "/" => Reply::text(StatusCode::OK, "mavping: metrics at /metrics\n"),
                _ => Reply::text(StatusCode::NOT_FOUND, "not found\n"),
            };
            Box::pin(std::future::ready(reply))
        }
    }

    /// Every link as it is now, as `/metrics` would show it.
    pub(crate) fn render_now(&self) -> String {
        render_shared(&self.links.borrow(), &self.run.borrow())
    }

    /// The run's own families (exposition text), served after the links'.
    pub(crate) fn set_run_figures(&self, text: String) {
        *self.run.borrow_mut() = text;
    }

    /// The reporter of the `index`-th link, served at the same address.
    pub fn link(&self, index: usize) -> SharedMetrics {
        let mut links = self.links.borrow_mut();
        if links.len() <= index {
            links.resize_with(index + 1, SharedMetrics::default);
        }
        links[index].clone()
    }
}
