//! `mavping serve` started: the address bound, the server built and
//! answering until Ctrl-C or SIGTERM, rereading its files on SIGHUP; or,
//! with `--config.check`, only what was found said.

use std::rc::Rc;

use super::descriptors;
use super::server::{handler, Server};
use crate::config::ServeConfig;
use crate::engine::session::Controls;
use crate::exit::Ending;
use crate::http::{self, Limits};
use crate::run::signals::Hangups;
use crate::stderr;

/// `--config.check`: both files were read and checked on the way here.
pub(crate) fn check(config: &ServeConfig) -> Ending {
    println!("{}", config.describe());
    Ending::Done
}

/// Serves until Ctrl-C or SIGTERM.
pub(crate) async fn run(config: Rc<ServeConfig>, controls: Controls) -> Ending {
    let stop = controls.stop;
    descriptors::raise_descriptor_limit();
    let listener = match std::net::TcpListener::bind(config.listen).and_then(http::listener) {
        Ok(l) => l,
        Err(e) => {
            stderr::error(&format_args!("--listen {}: {e}", config.listen));
            return Ending::Refused;
        }
    };
    let addr = match listener.local_addr() {
        Ok(a) => a,
        Err(e) => {
            stderr::error(&format_args!("--listen {}: {e}", config.listen));
            return Ending::Refused;
        }
    };
    let rereads = config.clone();
    let reload = Box::new(move || rereads.reload());
    let mut server = Server::new(config.settings.clone(), config.web.clone(), reload);
    server.lifecycle = config.lifecycle;
    let server = Rc::new(server);
    let limits = Limits {
        posts: &["/-/reload"],
        ..Limits::default()
    };
    http::serve_with(listener, limits, server.web.clone(), handler(&server));
    // Says the port when 0 was asked for; scripts and tests read it.
    let enforced = match config.web_file {
        Some(_) => format!(" ({})", config.web.describe()),
        None => String::new(),
    };
    stderr::error(&format_args!(
        "serving /probe and /metrics at {}://{addr}/{enforced}",
        config.web.scheme(),
    ));
    let mut hangups = Hangups::new();
    loop {
        tokio::select! {
            () = stop.notified() => return Ending::Done,
            () = hangups.next() => { let _ = server.reload(); }
        }
    }
}
