//! The committed completions and man pages match the current CLI, the man
//! pages render, and completion offers connection strings, serial devices
//! and no hidden option. Regenerate with `bash scripts/gen-completions.sh`.

use std::path::{Path, PathBuf};
use std::process::Command;

use crate::common::*;

fn committed(file: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("completions")
        .join(file)
}

#[test]
fn committed_completions_and_man_pages_are_current() {
    for (kind, file) in [
        ("complete-bash", "mavping.bash"),
        ("complete-zsh", "_mavping"),
        ("complete-fish", "mavping.fish"),
        ("complete-powershell", "_mavping.ps1"),
        ("complete-elvish", "mavping.elv"),
        ("man", "mavping.1"),
        ("man-respond", "mavping-respond.1"),
        ("man-compare", "mavping-compare.1"),
    ] {
        let (code, fresh, err) = run_mavping(&["--generate", kind]);
        assert_eq!(code, 0, "{err}");
        let committed = std::fs::read_to_string(committed(file)).unwrap_or_default();
        assert!(
            committed == fresh,
            "completions/{file} is out of date: run `bash scripts/gen-completions.sh` and commit"
        );
    }
}

/// A page as `man -l` renders it, 100 columns wide, no pager, with runs
/// of spaces (justification) made one.
fn man(file: &str) -> String {
    let out = Command::new("man")
        .arg("-l")
        .arg(committed(file))
        .env("MANWIDTH", "100")
        .env("MANPAGER", "cat")
        .env("PAGER", "cat")
        .output()
        .unwrap_or_else(|e| panic!("man is missing ({e}) — run `bash scripts/test.sh`"));
    assert!(out.status.success(), "{out:?}");
    String::from_utf8_lossy(&out.stdout)
        .lines()
        .map(|l| l.split_whitespace().collect::<Vec<_>>().join(" "))
        .collect::<Vec<_>>()
        .join("\n")
}

#[test]
fn man_pages_render_with_synopsis_examples_and_exit_status() {
    let page = man("mavping.1");
    for text in [
        "SYNOPSIS",
        "mavping [--sysid ID] [--compid ID]",
        "[-c|--count COUNT]",
        "CONNECTION...",
        "EXAMPLES",
        "mavping udp:127.0.0.1:14550",
        "CONNECTION STRINGS",
        "EXIT STATUS",
        "SEE ALSO",
        "mavping-respond(1)",
    ] {
        assert!(page.contains(text), "{text:?} not in mavping(1):\n{page}");
    }
    assert!(!page.contains("--first-seq"), "a hidden option in the page");
    let page = man("mavping-respond.1");
    for text in [
        "mavping respond [--sysid ID]",
        "EXAMPLES",
        "mavping respond udpin:0.0.0.0:14550",
        "EXIT STATUS",
        "mavping(1)",
    ] {
        assert!(
            page.contains(text),
            "{text:?} not in mavping-respond(1):\n{page}"
        );
    }
    let page = man("mavping-compare.1");
    for text in [
        "mavping compare [--json] [--source SYSID[/COMPID]]",
        "A.json B.json",
        "EXAMPLES",
        "mavping compare monday.json tuesday.json",
        "EXIT STATUS",
        "mavping(1)",
    ] {
        assert!(
            page.contains(text),
            "{text:?} not in mavping-compare(1):\n{page}"
        );
    }
}

/// What bash completes for the words `line`, through the committed
/// completion script and the mavping under test.
fn bash_completes(line: &[&str]) -> Vec<String> {
    let bin_dir = Path::new(env!("CARGO_BIN_EXE_mavping")).parent().unwrap();
    let words = line.join(" ");
    let script = format!(
        "source {script}\n\
         COMP_WORDS=({words}); COMP_CWORD={cword}; COMP_TYPE=9\n\
         _clap_complete_mavping mavping \"${{COMP_WORDS[COMP_CWORD]}}\" \"${{COMP_WORDS[COMP_CWORD-1]}}\"\n\
         printf '%s\\n' \"${{COMPREPLY[@]}}\"",
        script = committed("mavping.bash").display(),
        cword = line.len() - 1,
    );
    let path = format!(
        "{}:{}",
        bin_dir.display(),
        std::env::var("PATH").unwrap_or_default()
    );
    let out = Command::new("bash")
        .args(["-c", &script])
        .env("PATH", path)
        .output()
        .expect("bash runs");
    String::from_utf8_lossy(&out.stdout)
        .lines()
        .filter(|l| !l.is_empty())
        .map(str::to_string)
        .collect()
}

#[test]
fn bash_completes_connection_strings_and_serial_devices_not_hidden_options() {
    let schemes = bash_completes(&["mavping", "udp"]);
    assert_eq!(schemes, ["udp:", "udpin:", "udpout:", "udpbcast:"]);
    // A real pty: its device completes after serial: and as a bare path.
    let (_bridge, a, _b) = pty_bridge(&[]);
    let (dir, name) = a.rsplit_once('/').unwrap();
    let partial = format!("serial:{dir}/{}", &name[..name.len() - 1]);
    assert!(
        bash_completes(&["mavping", &partial]).contains(&format!("serial:{a}")),
        "{partial}"
    );
    let devices = bash_completes(&["mavping", "/dev/"]);
    assert!(devices.iter().any(|d| d == "/dev/pts/"), "{devices:?}");
    assert!(devices.iter().all(|d| !d.contains("null")), "{devices:?}");
    let options = bash_completes(&["mavping", "--"]);
    assert!(options.contains(&"--count".to_string()), "{options:?}");
    for hidden in ["--first-seq", "--generate"] {
        assert!(
            !options.contains(&hidden.to_string()),
            "{hidden} offered: {options:?}"
        );
    }
}
