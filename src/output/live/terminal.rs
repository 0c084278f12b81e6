//! The live view's hold on the terminal: a thread that draws the links'
//! states a few times a second and reads the keyboard ([`LiveView`]), and
//! each link's way into it ([`LiveLink`]).

use std::io;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex, MutexGuard};
use std::thread::JoinHandle;
use std::time::Duration;

use crossterm::event::{self, KeyCode, KeyEventKind, KeyModifiers};
use ratatui::Frame;
use tokio::sync::Notify;

use super::pair::pair_screen;
use super::state::{LiveState, Screen};
use super::view;
use crate::engine::pair::PairSummary;
use crate::engine::Nanos;

/// Redraw period: a few times a second is enough to watch a link.
const REFRESH: Duration = Duration::from_millis(200);

pub(super) fn lock<T>(state: &Mutex<T>) -> MutexGuard<'_, T> {
    state.lock().unwrap_or_else(|e| e.into_inner())
}

/// Leaves the alternate screen and raw mode however the UI thread ends.
struct Restore;

impl Drop for Restore {
    fn drop(&mut self) {
        ratatui::restore();
    }
}

/// Draws a frame with `draw` a few times a second until `done`.
fn ui_loop(
    mut terminal: ratatui::DefaultTerminal,
    draw: impl Fn(&mut Frame<'_>),
    done: Arc<AtomicBool>,
    stop: Arc<Notify>,
) -> io::Result<()> {
    let _restore = Restore;
    while !done.load(Ordering::Relaxed) {
        terminal.draw(&draw)?;
        // Raw mode turns Ctrl-C into a key, so it is handled here too.
        if event::poll(REFRESH)? {
            if let event::Event::Key(k) = event::read()? {
                let ctrl_c =
                    k.code == KeyCode::Char('c') && k.modifiers.contains(KeyModifiers::CONTROL);
                if k.kind == KeyEventKind::Press && (k.code == KeyCode::Char('q') || ctrl_c) {
                    stop.notify_one();
                }
            }
        }
    }
    Ok(())
}

/// The live view: one terminal, a section per link (one link fills it).
/// Each link's session feeds its [`LiveLink`]; the caller closes the view
/// once every session ended, then prints the summaries.
pub(crate) struct LiveView {
    states: Arc<Mutex<Vec<LiveState>>>,
    /// The pair report's section, once a source is heard on two links.
    pair: Arc<Mutex<Option<Screen>>>,
    /// Tells the UI thread to end; the thread, until it is joined.
    done: Arc<AtomicBool>,
    thread: Option<JoinHandle<io::Result<()>>>,
}

impl LiveView {
    /// Takes the terminal and starts drawing; `stop` is raised by `q`.
    pub(crate) fn start(stop: Arc<Notify>) -> io::Result<Self> {
        let states: Arc<Mutex<Vec<LiveState>>> = Arc::default();
        let pair: Arc<Mutex<Option<Screen>>> = Arc::default();
        // Also sets a panic hook that restores the terminal first.
        let terminal = ratatui::try_init()?;
        let done = Arc::new(AtomicBool::new(false));
        let (shown, paired, flag) = (states.clone(), pair.clone(), done.clone());
        // The state is locked only while the figures are computed.
        let draw = move |f: &mut Frame<'_>| {
            let screens: Vec<Screen> = lock(&shown).iter().map(LiveState::screen).collect();
            view::render(f, &screens, lock(&paired).as_ref());
        };
        let thread = std::thread::Builder::new()
            .name("live view".into())
            .spawn(move || ui_loop(terminal, draw, flag, stop))
            .inspect_err(|_| ratatui::restore())?;
        Ok(LiveView {
            states,
            pair,
            done,
            thread: Some(thread),
        })
    }

    /// The reporter of the next link, shown below the previous ones.
    pub(crate) fn link(&self) -> LiveLink {
        let mut states = lock(&self.states);
        states.push(LiveState::default());
        LiveLink {
            states: self.states.clone(),
            index: states.len() - 1,
        }
    }

    /// A link that could not be opened: a section that says so, among
    /// the links that run (its error line printed before the view took
    /// the screen is hidden while it shows).
    pub(crate) fn unopened(&self, link: &str, error: &str) {
        lock(&self.states).push(LiveState::unopened(link, error));
    }

    /// The pair report so far, its links named by `ways`, at `now`.
    pub(crate) fn show_pair(&self, summary: &PairSummary, ways: &[&str], now: Nanos) {
        *lock(&self.pair) = pair_screen(summary, ways, now);
    }

    /// Gives the terminal back.
    pub(crate) fn close(&mut self) -> io::Result<()> {
        let Some(thread) = self.thread.take() else {
            return Ok(());
        };
        self.done.store(true, Ordering::Relaxed);
        thread
            .join()
            .unwrap_or_else(|_| Err(io::Error::other("the live view failed")))
    }
}

impl Drop for LiveView {
    /// A run that ends early still gives the terminal back.
    fn drop(&mut self) {
        let _ = self.close();
    }
}

/// One link's part of the [`LiveView`]; its summary is printed as text
/// once the view is closed.
pub(crate) struct LiveLink {
    pub(super) states: Arc<Mutex<Vec<LiveState>>>,
    pub(super) index: usize,
}
