//! A real terminal for `--live`: a private tmux server per test.

use std::process::Command;
use std::time::{Duration, Instant};

/// How long a screen may take to show what a test waits for.
const PATIENCE: Duration = Duration::from_secs(30);

/// A tmux server of its own running one command in a window of a given
/// size; killed when dropped.
pub struct Tmux {
    socket: String,
}

impl Tmux {
    /// Runs `command` (a shell line) in a `width` x `height` window that
    /// stays open after the command exits.
    pub fn start(name: &str, command: &str, width: u16, height: u16) -> Tmux {
        let t = Tmux {
            socket: format!("mavping-{name}-{}", std::process::id()),
        };
        let (w, h) = (width.to_string(), height.to_string());
        // The shell stays a while after the command: tmux drops output it
        // has not read yet when a pane's process exits (seen with a long
        // summary on a loaded machine), and the window is dropped with the
        // server at the end of the test anyway.
        let command = format!("{command}; sleep 60");
        t.run(&[
            "new-session",
            "-d",
            "-s",
            "live",
            "-x",
            &w,
            "-y",
            &h,
            &command,
        ]);
        t.run(&["set-option", "-t", "live", "remain-on-exit", "on"]);
        t
    }

    fn run(&self, args: &[&str]) -> String {
        let out = Command::new("tmux")
            .args(["-L", &self.socket])
            .args(args)
            .output()
            .unwrap_or_else(|e| panic!("tmux is missing ({e}) — run `bash scripts/test.sh`"));
        assert!(out.status.success(), "tmux {args:?}: {out:?}");
        String::from_utf8_lossy(&out.stdout).into_owned()
    }

    /// Types `keys` into the window.
    pub fn send_keys(&self, keys: &str) {
        self.run(&["send-keys", "-t", "live", keys]);
    }

    /// The screen (and 200 lines of history) once `found` holds, lines
    /// the terminal wrapped joined again.
    pub fn wait_for(&self, what: &str, found: impl Fn(&str) -> bool) -> String {
        self.wait(&["-J", "-S", "-200"], what, found)
    }

    /// The screen alone, line for line as the terminal shows it, once
    /// `found` holds.
    pub fn wait_for_screen(&self, what: &str, found: impl Fn(&str) -> bool) -> String {
        self.wait(&[], what, found)
    }

    fn wait(&self, history: &[&str], what: &str, found: impl Fn(&str) -> bool) -> String {
        let start = Instant::now();
        loop {
            let mut capture = vec!["capture-pane", "-p", "-t", "live"];
            capture.extend_from_slice(history);
            let screen = self.run(&capture);
            if found(&screen) {
                return screen;
            }
            assert!(
                start.elapsed() < PATIENCE,
                "{what:?} not on screen:\n{screen}"
            );
            std::thread::sleep(Duration::from_millis(50));
        }
    }
}

impl Drop for Tmux {
    fn drop(&mut self) {
        let _ = Command::new("tmux")
            .args(["-L", &self.socket, "kill-server"])
            .output();
    }
}
