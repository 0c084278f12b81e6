//! Signals: the first Ctrl-C or SIGTERM stops the run (it still reports,
//! as ping does); a second one means "leave now". SIGQUIT (Ctrl-\) asks for
//! an interim summary and the run goes on, as with Linux `ping`. SIGHUP
//! asks `mavping serve` to reread its configuration. Windows has Ctrl-C
//! (and Ctrl-Break, closing the console) only: no SIGQUIT, no SIGHUP.

use std::future::pending;

#[cfg(unix)]
use tokio::signal::unix::{signal, SignalKind};

use crate::engine::session::Controls;

/// Raises `controls.stop` at the first Ctrl-C or SIGTERM and
/// `controls.interim` at every SIGQUIT; resolves at the second Ctrl-C or
/// SIGTERM. Raced against the run, so the run is dropped (and the terminal
/// given back) when it wins.
#[cfg(unix)]
pub(super) async fn watch(controls: Controls) {
    let (Ok(mut int), Ok(mut term)) = (
        signal(SignalKind::interrupt()),
        signal(SignalKind::terminate()),
    ) else {
        // No signal handling here: never leave on our own.
        return pending().await;
    };
    let mut quit = signal(SignalKind::quit()).ok();
    let mut stops = 0;
    loop {
        let quit_now = async {
            match quit.as_mut() {
                Some(q) => q.recv().await,
                None => pending().await,
            }
        };
        tokio::select! {
            _ = int.recv() => stops += 1,
            _ = term.recv() => stops += 1,
            _ = quit_now => {
                controls.interim.notify_one();
                continue;
            }
        }
        if stops == 1 {
            controls.stop.notify_one();
        } else {
            return;
        }
    }
}

/// Windows: the first Ctrl-C (or Ctrl-Break) stops the run, a second
/// leaves; there is no interim-summary signal.
#[cfg(not(unix))]
pub(crate) async fn watch(controls: Controls) {
    use tokio::signal::windows::{ctrl_break, ctrl_c};
    let (Ok(mut int), Ok(mut brk)) = (ctrl_c(), ctrl_break()) else {
        return pending().await;
    };
    let mut stops = 0;
    loop {
        tokio::select! {
            _ = int.recv() => stops += 1,
            _ = brk.recv() => stops += 1,
        }
        if stops == 1 {
            controls.stop.notify_one();
        } else {
            return;
        }
    }
}

/// Each SIGHUP, as it comes (none where the system has no such signal,
/// or its handler could not be set).
pub(super) struct Hangups {
    #[cfg(unix)]
    signal: Option<tokio::signal::unix::Signal>,
}

impl Hangups {
    pub(super) fn new() -> Self {
        Hangups {
            #[cfg(unix)]
            signal: tokio::signal::unix::signal(tokio::signal::unix::SignalKind::hangup()).ok(),
        }
    }

    /// Resolves at the next SIGHUP.
    pub(super) async fn next(&mut self) {
        #[cfg(unix)]
        if let Some(s) = self.signal.as_mut() {
            if s.recv().await.is_some() {
                return;
            }
        }
        std::future::pending().await
    }
}
