//! Ctrl-C and SIGTERM: the first stops the run (it still reports, as ping
//! does); a second one means "leave now". SIGHUP asks `mavping serve` to
//! reread its configuration.

use std::sync::Arc;

use tokio::sync::Notify;

/// Raises `stop` at the first Ctrl-C or SIGTERM; resolves at the second.
/// Raced against the run, so the run is dropped (and the terminal given
/// back) when it wins.
pub async fn stop_then_leave(stop: Arc<Notify>) {
    #[cfg(unix)]
    let mut term = tokio::signal::unix::signal(tokio::signal::unix::SignalKind::terminate()).ok();
    for round in 0..2 {
        #[cfg(unix)]
        let terminated = async {
            match term.as_mut() {
                Some(t) => {
                    t.recv().await;
                }
                None => std::future::pending().await,
            }
        };
        #[cfg(not(unix))]
        let terminated = std::future::pending::<()>();
        tokio::select! {
            r = tokio::signal::ctrl_c() => if r.is_err() {
                // No signal handling here: never leave on our own.
                return std::future::pending().await;
            },
            _ = terminated => {}
        }
        if round == 0 {
            stop.notify_one();
        }
    }
}

/// Each SIGHUP, as it comes (none where the system has no such signal,
/// or its handler could not be set).
pub struct Hangups {
    #[cfg(unix)]
    signal: Option<tokio::signal::unix::Signal>,
}

impl Hangups {
    pub fn new() -> Self {
        Hangups {
            #[cfg(unix)]
            signal: tokio::signal::unix::signal(tokio::signal::unix::SignalKind::hangup()).ok(),
        }
    }

    /// Resolves at the next SIGHUP.
    pub async fn next(&mut self) {
        #[cfg(unix)]
        if let Some(s) = self.signal.as_mut() {
            if s.recv().await.is_some() {
                return;
            }
        }
        std::future::pending().await
    }
}
