//! The async runtime a run goes on ([`block_on`]): one thread, paused for
//! a virtual clock, raced against the signals.

use std::future::Future;

use super::signals;
use crate::engine::session::Controls;
use crate::exit::Ending;
use crate::stderr;

/// Runs `run` on a current-thread runtime (paused for a virtual clock)
/// against the signals: the first Ctrl-C stops it, a second abandons it.
pub(super) fn block_on<F, R>(paused: bool, run: F) -> Ending
where
    F: FnOnce(Controls) -> R,
    R: Future<Output = Ending>,
{
    let mut builder = tokio::runtime::Builder::new_current_thread();
    builder.enable_all();
    if paused {
        builder.start_paused(true);
    }
    let runtime = match builder.build() {
        Ok(rt) => rt,
        Err(e) => {
            stderr::error(&format_args!("cannot start the async runtime: {e}"));
            return Ending::Refused;
        }
    };
    let controls = Controls::default();
    let run = run(controls.clone());
    // A LocalSet: the HTTP server's handlers run sessions, which stay on
    // this one thread.
    let ending = tokio::task::LocalSet::new().block_on(&runtime, async move {
        tokio::select! {
            biased;
            () = signals::watch(controls) => Ending::InterruptedTwice,
            ending = run => ending,
        }
    });
    // A read of standard input may still be blocked on the blocking pool
    // (a telemetry log on a pipe that went quiet): do not wait for it.
    runtime.shutdown_background();
    ending
}
