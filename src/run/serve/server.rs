//! The server's state, shared by the HTTP handlers and the reload: the
//! settings, the probe slots, the health counters and the continuous links;
//! and what answers each request.

use std::cell::RefCell;
use std::rc::Rc;
use std::sync::Arc;

use hyper::StatusCode;
use tokio::sync::Semaphore;

use super::links::Links;
use super::probe;
use crate::config::{ConfigError, ServeSettings, WebConfig};
use crate::http::{Head, Reply, Replying, SharedWeb};
use crate::output::prometheus::{borrow_all, render_serve, Health, Metrics};
use crate::stderr;

/// What the handlers and the reload share.
pub(super) struct Server {
    settings: RefCell<Rc<ServeSettings>>,
    /// `max_concurrent` probe slots; a reload that changes the number
    /// starts a new set (running probes keep theirs).
    slots: RefCell<Arc<Semaphore>>,
    health: RefCell<Health>,
    links: RefCell<Links>,
    /// The web config the HTTP server enforces; a reload swaps it.
    pub(super) web: SharedWeb,
    /// Rereads both files (the configuration, the web config).
    reload: Box<dyn Fn() -> Reloaded>,
    /// `--web.enable-lifecycle`.
    pub(super) lifecycle: bool,
}

type Reloaded = Result<(ServeSettings, WebConfig), ConfigError>;

impl Server {
    pub(super) fn new(
        settings: ServeSettings,
        web: WebConfig,
        reload: Box<dyn Fn() -> Reloaded>,
    ) -> Self {
        let server = Server {
            web: Rc::new(RefCell::new(Rc::new(web))),
            reload,
            lifecycle: false,
            slots: RefCell::new(Arc::new(Semaphore::new(settings.max_concurrent))),
            settings: RefCell::new(Rc::new(settings)),
            health: RefCell::new(Health {
                last_reload_ok: true,
                ..Health::default()
            }),
            links: RefCell::default(),
        };
        server
            .links
            .borrow_mut()
            .reconcile(&server.settings().links);
        server
    }

    pub(super) fn settings(&self) -> Rc<ServeSettings> {
        self.settings.borrow().clone()
    }

    pub(super) fn slots(&self) -> Arc<Semaphore> {
        self.slots.borrow().clone()
    }

    pub(super) fn health(&self, f: impl FnOnce(&mut Health)) {
        f(&mut self.health.borrow_mut());
    }

    /// Rereads the files and takes what they say, or keeps the old ones and
    /// says why (also the answer to `POST /-/reload`).
    pub(super) fn reload(&self) -> Result<(), ConfigError> {
        self.health(|h| h.reloads += 1);
        let (settings, web) = match (self.reload)() {
            Ok(both) => both,
            Err(e) => {
                // Said before it is counted: whoever sees the count can
                // find the reason.
                stderr::error(&format_args!(
                    "reload refused, the old configuration stays: {e}"
                ));
                self.health(|h| {
                    h.reloads_failed += 1;
                    h.last_reload_ok = false;
                });
                return Err(e);
            }
        };
        *self.web.borrow_mut() = Rc::new(web);
        if settings.max_concurrent != self.settings().max_concurrent {
            *self.slots.borrow_mut() = Arc::new(Semaphore::new(settings.max_concurrent));
        }
        self.links.borrow_mut().reconcile(&settings.links);
        *self.settings.borrow_mut() = Rc::new(settings);
        self.health(|h| h.last_reload_ok = true);
        stderr::error(&"configuration reloaded");
        Ok(())
    }

    /// `/-/reload`, as Prometheus answers it: POST only, and only with the
    /// lifecycle API enabled.
    fn reload_request(&self, head: &Head) -> Reply {
        if head.method != hyper::Method::POST {
            return Reply::text(
                StatusCode::METHOD_NOT_ALLOWED,
                "Only POST requests allowed\n",
            );
        }
        if !self.lifecycle {
            return Reply::text(
                StatusCode::FORBIDDEN,
                "Lifecycle API is not enabled (--web.enable-lifecycle)\n",
            );
        }
        match self.reload() {
            Ok(()) => Reply::text(StatusCode::OK, "configuration reloaded\n"),
            Err(e) => Reply::text(
                StatusCode::INTERNAL_SERVER_ERROR,
                format!("failed to reload config: {e}\n"),
            ),
        }
    }

    /// `/metrics`: the exporter's health and every continuous link.
    fn metrics(&self) -> Reply {
        let links = self.links.borrow().metrics();
        let all = borrow_all(&links);
        let refs: Vec<&Metrics> = all.iter().map(|m| &**m).collect();
        let mut health = *self.health.borrow();
        health.open_links += refs.iter().filter(|m| m.is_up()).count() as u64;
        Reply::metrics(render_serve(&refs, &health))
    }

    async fn handle(self: Rc<Self>, head: Head) -> Reply {
        match head.uri.path() {
            "/probe" => probe::answer(&self, head.uri.query().unwrap_or(""), &head.headers).await,
            "/metrics" => self.metrics(),
            "/-/reload" => self.reload_request(&head),
            "/" => Reply::text(
                StatusCode::OK,
                "mavping serve: /probe?target=LINK[&module=NAME] probes a link; /metrics shows \
                 the continuous links and the exporter's health\n",
            ),
            _ => Reply::text(StatusCode::NOT_FOUND, "not found: try /probe or /metrics\n"),
        }
    }
}

/// What answers each request: `/probe`, `/metrics`, `/`.
pub(super) fn handler(server: &Rc<Server>) -> impl Fn(Head) -> Replying + 'static {
    let server = server.clone();
    move |head: Head| -> Replying { Box::pin(server.clone().handle(head)) }
}

/// The handler of a server with `settings` that is not listening anywhere
/// (its continuous links do run, on the current `LocalSet`): the HTTP
/// fuzz target's way in.
pub fn handler_for(settings: ServeSettings) -> impl Fn(Head) -> Replying + 'static {
    let kept = settings.clone();
    let reload = Box::new(move || Ok((kept.clone(), WebConfig::default())));
    handler(&Rc::new(Server::new(
        settings,
        WebConfig::default(),
        reload,
    )))
}
