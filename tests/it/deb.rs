//! The Debian package, installed for real: scripts/deb.sh packs this
//! test's own mavping (release packages are packed the same way by
//! scripts/dist.sh from the static binaries), `dpkg -i` installs it, the
//! files, man pages, conffile and the service's unit are checked where
//! Debian puts them, `mavping serve` runs with the installed configuration
//! as an unprivileged user, and `dpkg --purge` leaves nothing behind.
//!
//! It needs root, dpkg, systemd-analyze and man (scripts/test.sh installs
//! what is missing) and fails, never skips, without them. Nothing else in
//! the suite runs /usr/bin/mavping (they all run the cargo-built binary),
//! so the package being there for a few seconds disturbs no other test; a
//! lock on the machine keeps two suites (two checkouts) from installing at
//! once.

use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Child, ChildStdin, Command, Output, Stdio};
use std::time::Duration;

use crate::common::*;

const UNIT: &str = "/usr/lib/systemd/system/mavping-serve.service";
const CONFIG: &str = "/etc/mavping/serve.toml";
const WEB_CONFIG: &str = "/etc/mavping/web.yml";

/// Every file the package installs, directories left out.
const FILES: &[&str] = &[
    "/etc/mavping/serve.toml",
    "/etc/mavping/web.yml",
    "/usr/bin/mavping",
    "/usr/lib/systemd/system/mavping-serve.service",
    "/usr/share/bash-completion/completions/mavping",
    "/usr/share/doc/mavping/README.md",
    "/usr/share/doc/mavping/changelog.Debian.gz",
    "/usr/share/doc/mavping/changelog.gz",
    "/usr/share/doc/mavping/copyright",
    "/usr/share/doc/mavping/examples/mavping-dashboard.json",
    "/usr/share/doc/mavping/examples/mavping-serve.toml",
    "/usr/share/doc/mavping/examples/mavping.rules.test.yml",
    "/usr/share/doc/mavping/examples/mavping.rules.yml",
    "/usr/share/doc/mavping/examples/prometheus.yml",
    "/usr/share/doc/mavping/service.md",
    "/usr/share/fish/vendor_completions.d/mavping.fish",
    "/usr/share/man/man1/mavping-compare.1.gz",
    "/usr/share/man/man1/mavping-respond.1.gz",
    "/usr/share/man/man1/mavping.1.gz",
    "/usr/share/zsh/vendor-completions/_mavping",
];

/// The version the test packs: a leftover of a killed run is recognised
/// by it, and anything else installed is somebody's real package.
fn test_version() -> String {
    format!("{}~itest", env!("CARGO_PKG_VERSION"))
}

fn run(program: &str, args: &[&str]) -> Output {
    Command::new(program)
        .args(args)
        .output()
        .unwrap_or_else(|e| panic!("{program} is missing ({e}) — run `bash scripts/test.sh`"))
}

fn stdout(out: &Output) -> String {
    String::from_utf8_lossy(&out.stdout).into_owned()
}

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// Fails loudly unless this machine can install a package and check a unit.
fn require_tools() {
    let uid = stdout(&run("id", &["-u"]));
    assert_eq!(
        uid.trim(),
        "0",
        "the Debian package test installs with dpkg: run the suite as root"
    );
    for (program, package) in [
        ("dpkg", "dpkg"),
        ("dpkg-deb", "dpkg"),
        ("systemd-analyze", "systemd"),
        ("systemctl", "systemd"),
        ("man", "man-db"),
        ("setpriv", "util-linux"),
        ("flock", "util-linux"),
    ] {
        let found = Command::new("sh")
            .args(["-c", &format!("command -v {program}")])
            .stdout(Stdio::null())
            .status()
            .is_ok_and(|s| s.success());
        assert!(
            found,
            "{program} is missing (Debian's {package} package) — run `bash scripts/test.sh`"
        );
    }
}

/// An exclusive lock on the machine, held by a `flock` child while its
/// stdin is open: released when dropped, or when this process dies.
struct MachineLock {
    child: Child,
    stdin: Option<ChildStdin>,
}

impl MachineLock {
    fn take() -> MachineLock {
        let mut child = Command::new("flock")
            .args([
                "/tmp/mavping-deb-test.lock",
                "-c",
                "echo locked; exec cat >/dev/null",
            ])
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .spawn()
            .expect("flock");
        let mut line = String::new();
        BufReader::new(child.stdout.take().unwrap())
            .read_line(&mut line)
            .unwrap();
        assert_eq!(line.trim(), "locked", "flock did not take the lock");
        let stdin = child.stdin.take();
        MachineLock { child, stdin }
    }
}

impl Drop for MachineLock {
    fn drop(&mut self) {
        drop(self.stdin.take());
        let _ = self.child.wait();
    }
}

/// dpkg with ARGS, waiting while another dpkg or apt holds its lock.
fn dpkg(args: &[&str]) -> Output {
    for _ in 0..120 {
        let out = run("dpkg", args);
        if out.status.success() || !stderr(&out).contains("lock") {
            return out;
        }
        std::thread::sleep(Duration::from_millis(500));
    }
    panic!("dpkg {args:?}: its lock stayed taken for a minute");
}

/// "VERSION STATUS" of the installed mavping package, if dpkg knows one.
fn installed() -> Option<String> {
    let out = run(
        "dpkg-query",
        &[
            "-W",
            "--showformat=${Version} ${db:Status-Status}",
            "mavping",
        ],
    );
    out.status.success().then(|| stdout(&out))
}

fn purge() -> Output {
    dpkg(&["--purge", "mavping"])
}

/// Purges the package when dropped, whether the test passed or not.
struct Installed;

impl Drop for Installed {
    fn drop(&mut self) {
        if installed().is_some() {
            let out = purge();
            assert!(out.status.success(), "dpkg --purge: {}", stderr(&out));
        }
    }
}

/// Installs the package built from this test's binary; a leftover of a
/// killed run is purged first, anyone else's mavping is left alone.
fn install(deb: &Path) -> Installed {
    match installed() {
        Some(found) if found.starts_with(&test_version()) => drop(Installed),
        Some(found) if !found.ends_with("not-installed") => panic!(
            "a mavping package is installed here ({found}): the test would replace it; \
             `dpkg --purge mavping` first, or run the suite on another machine"
        ),
        _ => {}
    }
    let out = dpkg(&["-i", deb.to_str().unwrap()]);
    assert!(out.status.success(), "dpkg -i: {}", stderr(&out));
    Installed
}

/// scripts/deb.sh on this test's mavping; the path of the .deb.
fn build_deb(out: &Path) -> PathBuf {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    // Uncompressed: xz takes minutes on a debug binary of 100 MB.
    let built = Command::new("bash")
        .arg(root.join("scripts/deb.sh"))
        .args(["--binary", env!("CARGO_BIN_EXE_mavping"), "--arch"])
        .arg(debian_arch())
        .args([
            "--version",
            &test_version(),
            "--compression",
            "none",
            "--out",
        ])
        .arg(out)
        .output()
        .unwrap();
    assert!(built.status.success(), "deb.sh: {}", stderr(&built));
    let deb = PathBuf::from(stdout(&built).trim());
    assert_eq!(
        deb,
        out.join(format!("mavping_{}_{}.deb", test_version(), debian_arch()))
    );
    deb
}

fn debian_arch() -> &'static str {
    match std::env::consts::ARCH {
        "x86_64" => "amd64",
        "aarch64" => "arm64",
        "arm" => "armhf",
        other => panic!("no Debian package for {other}"),
    }
}

#[test]
fn the_debian_package_installs_a_hardened_disabled_service_and_purges_clean() {
    require_tools();
    let _lock = MachineLock::take();
    let out = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("deb-{}", std::process::id()));
    let deb = build_deb(&out);
    let _installed = install(&deb);
    std::fs::remove_dir_all(&out).unwrap();

    assert_files_installed();
    assert_unit_verified_and_scored();
    assert_serve_runs_unprivileged_with_the_installed_config();

    let purged = purge();
    assert!(purged.status.success(), "dpkg --purge: {}", stderr(&purged));
    let left = installed();
    assert!(
        left.as_deref().is_none_or(|s| s.ends_with("not-installed")),
        "dpkg still knows mavping after the purge: {left:?}"
    );
    for file in FILES
        .iter()
        .chain(&["/etc/mavping", "/usr/share/doc/mavping"])
    {
        assert!(!Path::new(file).exists(), "{file} is left after the purge");
    }
}

/// `dpkg -L`, the binary, the man pages, completions and the conffile.
fn assert_files_installed() {
    let listed = stdout(&dpkg(&["-L", "mavping"]));
    let mut files: Vec<&str> = listed.lines().filter(|p| Path::new(p).is_file()).collect();
    files.sort_unstable();
    assert_eq!(files, FILES, "dpkg -L mavping:\n{listed}");

    let version = run("/usr/bin/mavping", &["--version"]);
    assert!(version.status.success(), "{version:?}");
    assert_eq!(
        stdout(&version).trim(),
        format!("mavping {}", env!("CARGO_PKG_VERSION"))
    );
    for (page, path) in [
        ("mavping", "/usr/share/man/man1/mavping.1.gz"),
        (
            "mavping-respond",
            "/usr/share/man/man1/mavping-respond.1.gz",
        ),
        (
            "mavping-compare",
            "/usr/share/man/man1/mavping-compare.1.gz",
        ),
    ] {
        let found = run("man", &["-w", page]);
        assert_eq!(stdout(&found).trim(), path, "man -w {page}: {found:?}");
    }
    let committed = Path::new(env!("CARGO_MANIFEST_DIR")).join("completions");
    for (file, installed) in [
        (
            "mavping.bash",
            "/usr/share/bash-completion/completions/mavping",
        ),
        ("_mavping", "/usr/share/zsh/vendor-completions/_mavping"),
        (
            "mavping.fish",
            "/usr/share/fish/vendor_completions.d/mavping.fish",
        ),
    ] {
        assert_eq!(
            std::fs::read(installed).unwrap(),
            std::fs::read(committed.join(file)).unwrap(),
            "{installed}"
        );
    }
    let conffiles = stdout(&run(
        "dpkg-query",
        &["-W", "--showformat=${Conffiles}", "mavping"],
    ));
    let listed: Vec<&str> = conffiles
        .lines()
        .filter_map(|l| l.split_whitespace().next())
        .collect();
    assert_eq!(listed, [CONFIG, WEB_CONFIG], "conffiles: {conffiles:?}");
}

/// `systemd-analyze verify` is silent about our unit, `security --offline`
/// says OK or better with each hardening line counted, and nothing enabled
/// it.
fn assert_unit_verified_and_scored() {
    let verify = run("systemd-analyze", &["verify", UNIT]);
    let said = stderr(&verify);
    // verify loads every unit on the machine, and prints what it finds in
    // other packages' files too (Debian's irtt.service: "Special user
    // nobody configured"); those lines start with the other file's path.
    let ours: Vec<&str> = said
        .lines()
        .filter(|line| !about_another_unit(line))
        .filter(|line| !line.trim().is_empty())
        .collect();
    assert!(
        verify.status.success() && ours.is_empty(),
        "systemd-analyze verify {UNIT}: {verify:?}"
    );
    let security = run("systemd-analyze", &["security", "--offline=yes", UNIT]);
    let report = stdout(&security);
    assert!(security.status.success(), "{security:?}");
    let (exposure, level) = overall_exposure(&report);
    assert!(
        ["PERFECT", "SAFE", "OK"].contains(&level.as_str()) && exposure < 5.0,
        "exposure {exposure} {level}, not OK or better:\n{report}"
    );
    for setting in [
        "User=/DynamicUser=",
        "NoNewPrivileges=",
        "ProtectSystem=",
        "ProtectHome=",
        "PrivateTmp=",
        "CapabilityBoundingSet=~CAP_SYS_ADMIN",
        "RestrictAddressFamilies=~AF_UNIX",
        "RestrictAddressFamilies=~AF_PACKET",
        "SystemCallFilter=~@privileged",
        "MemoryDenyWriteExecute=",
        "RestrictNamespaces=~user",
        "ProtectClock=",
        "ProtectKernelModules=",
    ] {
        assert!(
            report
                .lines()
                .filter_map(|l| l.strip_prefix('✓'))
                .any(|l| l.trim_start().starts_with(setting)),
            "{setting} is not counted as set:\n{report}"
        );
    }
    let enabled = run("systemctl", &["is-enabled", "mavping-serve.service"]);
    assert_eq!(stdout(&enabled).trim(), "disabled", "{enabled:?}");
}

/// "→ Overall exposure level for mavping-serve.service: 1.3 OK 🙂"
/// A `systemd-analyze verify` line about some other unit file than ours.
fn about_another_unit(line: &str) -> bool {
    let path = line.split(':').next().unwrap_or("");
    path.starts_with('/') && !path.ends_with("/mavping-serve.service")
}

fn overall_exposure(report: &str) -> (f64, String) {
    let line = report
        .lines()
        .find(|l| l.contains("Overall exposure level"))
        .unwrap_or_else(|| panic!("no overall exposure in:\n{report}"));
    let mut words = line.rsplit_once(": ").unwrap().1.split_whitespace();
    let exposure = words.next().and_then(|w| w.parse().ok()).expect(line);
    (exposure, words.next().expect(line).to_string())
}

/// The installed binary and configuration as the unit runs them, as far
/// as this machine (PID 1 is not systemd) allows: user nobody with the
/// dialout group, no capabilities, no new privileges. The shipped file is
/// valid, /metrics answers, /probe denies by default, SIGHUP reloads.
fn assert_serve_runs_unprivileged_with_the_installed_config() {
    let mut command = Command::new("setpriv");
    command.args([
        "--reuid=nobody",
        "--regid=nogroup",
        "--groups=dialout",
        "--no-new-privs",
        "--bounding-set=-all",
        "--inh-caps=-all",
        "/usr/bin/mavping",
    ]);
    let server = Server::start_as(
        command,
        &["--config", CONFIG, "--web.config.file", WEB_CONFIG],
    );
    let status = std::fs::read_to_string(format!("/proc/{}/status", server.pid())).unwrap();
    for line in [
        "Uid:\t65534\t65534\t65534\t65534",
        "NoNewPrivs:\t1",
        "CapEff:\t0000000000000000",
    ] {
        assert!(status.contains(line), "{line:?} not in:\n{status}");
    }
    let metrics = server.get("/metrics");
    assert_eq!(metrics.status, 200, "{metrics:?}");
    let reloads = |text: &str| sample(text, "mavping_exporter_config_reloads_total", &[]);
    assert_eq!(reloads(&metrics.body), Some(0.0), "{}", metrics.body);
    assert_eq!(
        sample(&metrics.body, "mavping_exporter_open_links", &[]),
        Some(0.0)
    );
    let probe = server.get("/probe?target=udpout:127.0.0.1:14550");
    assert_eq!(probe.status, 400, "{probe:?}");
    assert!(probe.body.contains("is not allowed"), "{}", probe.body);

    server.signal("HUP");
    let mut said = String::new();
    for _ in 0..200 {
        said = server.stderr();
        if !said.is_empty() {
            break;
        }
        std::thread::sleep(Duration::from_millis(50));
    }
    assert_eq!(said.trim(), "mavping: configuration reloaded");
    let metrics = server.get("/metrics").body;
    assert_eq!(reloads(&metrics), Some(1.0), "{metrics}");
    assert_eq!(
        sample(
            &metrics,
            "mavping_exporter_config_last_reload_successful",
            &[]
        ),
        Some(1.0)
    );
    assert_eq!(server.stop(), Some(0));
}
