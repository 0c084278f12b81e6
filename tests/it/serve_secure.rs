//! `mavping serve --web.config.file` as operators deploy exporters: TLS
//! with certificates the test makes (openssl), client certificates, bcrypt
//! basic auth, reload over HTTP and on SIGHUP, `--config.check`,
//! `debug=true`; scraped by the real Prometheus server and by curl. A
//! refused request must probe nothing: the targets count what reached them.

use std::path::PathBuf;
use std::process::Command;
use std::time::{Duration, Instant};

use crate::common::{free_udp_port, promtool, run_mavping, sample, Peer, Server, SilentPeer};
use crate::prometheus_server::{Prometheus, PATIENCE};

/// A CA, a server certificate for localhost and 127.0.0.1, a client
/// certificate from the same CA and one from a CA the server does not
/// know, made with the openssl command in a directory of their own.
pub(crate) struct Pki {
    dir: PathBuf,
}

impl Pki {
    pub(crate) fn make(name: &str) -> Pki {
        let dir = std::env::temp_dir().join(format!("mavping-pki-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let pki = Pki { dir };
        pki.ca("ca");
        pki.ca("other-ca");
        pki.signed("server", "ca", "localhost", "serverAuth", true);
        pki.signed("client", "ca", "prometheus", "clientAuth", false);
        pki.signed("stranger", "other-ca", "prometheus", "clientAuth", false);
        pki
    }

    fn openssl(&self, args: &[&str]) {
        let out = Command::new("openssl")
            .current_dir(&self.dir)
            .args(args)
            .output()
            .expect("openssl (scripts/test.sh installs it)");
        assert!(out.status.success(), "openssl {args:?}: {out:?}");
    }

    fn ca(&self, name: &str) {
        let (key, pem) = (format!("{name}.key"), format!("{name}.pem"));
        self.openssl(&[
            "req",
            "-x509",
            "-newkey",
            "ec",
            "-pkeyopt",
            "ec_paramgen_curve:P-256",
            "-nodes",
            "-days",
            "2",
            "-subj",
            &format!("/CN={name}"),
            "-keyout",
            &key,
            "-out",
            &pem,
        ]);
    }

    fn signed(&self, name: &str, ca: &str, cn: &str, usage: &str, san: bool) {
        let ext = format!("{name}.ext");
        let mut text = format!("extendedKeyUsage={usage}\n");
        if san {
            text.push_str("subjectAltName=DNS:localhost,IP:127.0.0.1\n");
        }
        std::fs::write(self.dir.join(&ext), text).unwrap();
        let (key, csr, pem) = (
            format!("{name}.key"),
            format!("{name}.csr"),
            format!("{name}.pem"),
        );
        self.openssl(&[
            "req",
            "-newkey",
            "ec",
            "-pkeyopt",
            "ec_paramgen_curve:P-256",
            "-nodes",
            "-subj",
            &format!("/CN={cn}"),
            "-keyout",
            &key,
            "-out",
            &csr,
        ]);
        self.openssl(&[
            "x509",
            "-req",
            "-in",
            &csr,
            "-CA",
            &format!("{ca}.pem"),
            "-CAkey",
            &format!("{ca}.key"),
            "-CAcreateserial",
            "-days",
            "2",
            "-extfile",
            &ext,
            "-out",
            &pem,
        ]);
    }

    pub(crate) fn path(&self, file: &str) -> String {
        self.dir.join(file).display().to_string()
    }

    /// Writes the web config `yaml` as `name` here; its path.
    fn write(&self, name: &str, yaml: &str) -> String {
        std::fs::write(self.dir.join(name), yaml).unwrap();
        self.path(name)
    }
}

impl Drop for Pki {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.dir);
    }
}

/// What curl got: its exit code, the HTTP status (0 when none), the body.
struct Curled {
    code: i32,
    status: u16,
    body: String,
}

fn curl(args: &[&str]) -> Curled {
    let out = Command::new("curl")
        .args(["-sS", "--max-time", "20", "-w", "\n%{http_code}"])
        .args(args)
        .output()
        .expect("curl (scripts/test.sh installs it)");
    let text = String::from_utf8_lossy(&out.stdout).into_owned();
    let (body, status) = text.rsplit_once('\n').unwrap_or(("", &text));
    Curled {
        code: out.status.code().unwrap_or(-1),
        status: status.trim().parse().unwrap_or(0),
        body: body.to_string(),
    }
}

/// A bcrypt hash of `password` at htpasswd's usual cost.
fn hash(password: &str) -> String {
    bcrypt::hash(password, 10).unwrap()
}

fn port_of(addr: &str) -> &str {
    addr.rsplit_once(':').unwrap().1
}

fn wait_for(what: &str, mut done: impl FnMut() -> bool) {
    let start = Instant::now();
    while !done() {
        assert!(start.elapsed() < PATIENCE, "{what}");
        std::thread::sleep(Duration::from_millis(200));
    }
}

#[test]
fn a_real_prometheus_scrapes_probes_over_tls_with_basic_auth_and_a_wrong_password_probes_nothing() {
    let pki = Pki::make("prometheus");
    let web = pki.write(
        "web.yml",
        &format!(
            "tls_server_config:\n  cert_file: server.pem\n  key_file: server.key\n\
             basic_auth_users:\n  prometheus: {}\n",
            hash("right horse battery")
        ),
    );
    // The scrape with the password answers 10 requests a probe; the two
    // refused scrapes (a wrong password, plain HTTP) aim at sockets that
    // count every PING that reaches them.
    let good_port = free_udp_port();
    let responder = Peer::start("responder.py", &[&format!("udpin:127.0.0.1:{good_port}")]);
    let mut wrong_target = SilentPeer::bind();
    let mut plain_target = SilentPeer::bind();
    let config = pki.write(
        "serve.toml",
        "allow = [\"udpout:127.0.0.1:*\"]\n[module.fleet]\ncount = 10\ninterval = \"20ms\"\ntimeout = \"300ms\"\n",
    );
    let server = Server::start(&["--config", &config, "--web.config.file", &web]);
    let port = port_of(&server.addr).to_string();
    let job = |name: &str, scheme: &str, password: &str, target: String| {
        format!(
            r"
  - job_name: {name}
    scheme: {scheme}
    metrics_path: /probe
    params:
      module: [fleet]
    basic_auth:
      username: prometheus
      password: '{password}'
    tls_config:
      ca_file: {ca}
      server_name: localhost
    static_configs:
      - targets: ['{target}']
    relabel_configs:
      - source_labels: [__address__]
        target_label: __param_target
      - source_labels: [__param_target]
        target_label: instance
      - target_label: __address__
        replacement: localhost:{port}
",
            ca = pki.path("ca.pem")
        )
    };
    let good = format!("udpout:127.0.0.1:{good_port}");
    let prometheus = Prometheus::start(
        "tls",
        &format!(
            "global:\n  scrape_interval: 2s\n  scrape_timeout: 2s\nscrape_configs:{}{}{}",
            job("secure", "https", "right horse battery", good.clone()),
            job(
                "wrong_password",
                "https",
                "wrong horse battery",
                format!("udpout:127.0.0.1:{}", wrong_target.port())
            ),
            job(
                "plain_http",
                "http",
                "right horse battery",
                format!("udpout:127.0.0.1:{}", plain_target.port())
            ),
        ),
    );
    wait_for("prometheus did not start", || prometheus.ready());
    let now = || {
        std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .unwrap()
            .as_secs_f64()
    };
    // Two scrapes of each job.
    let mut at = 0.0;
    wait_for("no two scrapes of each job", || {
        at = now();
        prometheus
            .query("count_over_time(up[5m]) >= 2", Some(at))
            .len()
            == 3
    });
    assert_eq!(prometheus.value(r#"up{job="secure"}"#, at), 1.0);
    assert_eq!(
        prometheus.value(
            &format!(r#"mavping_probe_success{{instance="{good}"}}"#),
            at
        ),
        1.0
    );
    assert_eq!(
        prometheus.value(
            &format!(r#"mavping_probe_loss_ratio{{instance="{good}",sysid="1"}}"#),
            at
        ),
        0.0
    );
    assert_eq!(prometheus.value(r#"up{job="wrong_password"}"#, at), 0.0);
    assert_eq!(prometheus.value(r#"up{job="plain_http"}"#, at), 0.0);
    // Why, as Prometheus's targets page says it.
    // (curl: the answer is chunked.)
    let targets = curl(&[&format!("http://{}/api/v1/targets", prometheus.addr)]);
    let targets: serde_json::Value = serde_json::from_str(&targets.body).unwrap();
    let error_of = |job: &str| -> String {
        targets["data"]["activeTargets"]
            .as_array()
            .unwrap()
            .iter()
            .find(|t| t["labels"]["job"] == job)
            .map(|t| t["lastError"].as_str().unwrap_or("").to_string())
            .unwrap()
    };
    assert!(
        error_of("wrong_password").contains("401"),
        "{}",
        error_of("wrong_password")
    );
    assert!(
        error_of("plain_http").contains("400"),
        "{}",
        error_of("plain_http")
    );

    // Freeze Prometheus, let the last probe end, then the ground truth:
    // nothing reached the refused targets; the good one heard exactly 10
    // requests for each probe the exporter ran.
    crate::common::signal(prometheus.child.id(), "STOP");
    let metrics = || {
        let c = curl(&[
            "--cacert",
            &pki.path("ca.pem"),
            "-u",
            "prometheus:right horse battery",
            &format!("https://localhost:{port}/metrics"),
        ]);
        assert_eq!(c.status, 200, "{}", c.body);
        c.body
    };
    wait_for("a probe never ended", || {
        sample(&metrics(), "mavping_exporter_probes_running", &[]) == Some(0.0)
    });
    let probes = sample(&metrics(), "mavping_exporter_probes_total", &[]).unwrap();
    assert!(probes >= 2.0, "{probes}");
    let truth = responder.finish();
    assert_eq!(
        truth["ping_requests"].as_f64().unwrap(),
        10.0 * probes,
        "{truth}"
    );
    assert_eq!(wrong_target.pings(), 0);
    assert_eq!(plain_target.pings(), 0);
    drop(prometheus);
}

#[test]
fn client_certificates_are_required_and_verified() {
    let pki = Pki::make("client-certs");
    let web = pki.write(
        "web.yml",
        "tls_server_config:\n  cert_file: server.pem\n  key_file: server.key\n  \
         client_auth_type: RequireAndVerifyClientCert\n  client_ca_file: ca.pem\n  \
         min_version: TLS12\nhttp_server_config:\n  headers:\n    \
         Strict-Transport-Security: max-age=31536000\n",
    );
    let mut target = SilentPeer::bind();
    let server = Server::start(&["--allow", "udpout:127.0.0.1:*", "--web.config.file", &web]);
    let port = port_of(&server.addr).to_string();
    let probe = format!(
        "https://localhost:{port}/probe?target=udpout:127.0.0.1:{}&count=2&interval=20ms&timeout=100ms",
        target.port()
    );
    let ca = pki.path("ca.pem");
    // No certificate: the handshake fails, nothing is probed.
    let none = curl(&["--cacert", &ca, &probe]);
    assert_eq!(none.status, 0, "{}", none.body);
    assert_ne!(none.code, 0);
    // A certificate from a CA the server does not trust: the same.
    let stranger = curl(&[
        "--cacert",
        &ca,
        "--cert",
        &pki.path("stranger.pem"),
        "--key",
        &pki.path("stranger.key"),
        &probe,
    ]);
    assert_eq!(stranger.status, 0, "{}", stranger.body);
    assert_eq!(target.pings(), 0);
    // The right one: answered, with the configured header, and probed.
    let good = Command::new("curl")
        .args(["-sS", "-D", "-", "--cacert", &ca, "--cert"])
        .arg(pki.path("client.pem"))
        .arg("--key")
        .arg(pki.path("client.key"))
        .arg(&probe)
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&good.stdout);
    let (head, body) = text.split_once("\r\n\r\n").unwrap();
    assert!(head.starts_with("HTTP/1.1 200 OK\r\n"), "{head}");
    assert!(
        head.contains("strict-transport-security: max-age=31536000"),
        "{head}"
    );
    assert_eq!(
        sample(body, "mavping_probe_requests", &[]),
        Some(2.0),
        "{body}"
    );
    assert_eq!(target.pings(), 2);
}

#[test]
fn reload_over_http_only_with_the_lifecycle_api_and_a_new_password_takes_effect() {
    let pki = Pki::make("reload");
    let web_of = |password: &str| format!("basic_auth_users:\n  ops: {}\n", hash(password));
    let web = pki.write("web.yml", &web_of("first"));
    let config = pki.write("serve.toml", "allow = [\"udpout:127.0.0.1:*\"]\n");
    let base = |server: &Server| format!("http://{}", server.addr);

    // Off: refused as Prometheus refuses it.
    let off = Server::start(&["--config", &config, "--web.config.file", &web]);
    let post = curl(&[
        "-u",
        "ops:first",
        "-X",
        "POST",
        &format!("{}/-/reload", base(&off)),
    ]);
    assert_eq!(post.status, 403, "{}", post.body);
    assert!(
        post.body.contains("--web.enable-lifecycle"),
        "{}",
        post.body
    );
    let get = curl(&["-u", "ops:first", &format!("{}/-/reload", base(&off))]);
    assert_eq!(get.status, 405, "{}", get.body);
    // Without the password the lifecycle API is not even reached.
    let anonymous = curl(&["-X", "POST", &format!("{}/-/reload", base(&off))]);
    assert_eq!(anonymous.status, 401);
    drop(off);

    // On: a module added to the file exists after the POST.
    let on = Server::start(&[
        "--config",
        &config,
        "--web.config.file",
        &web,
        "--web.enable-lifecycle",
    ]);
    let url = |path: &str| format!("{}{path}", base(&on));
    let quick = url("/probe?target=udpout:127.0.0.1:9&module=quick");
    let before = curl(&["-u", "ops:first", &quick]);
    assert_eq!(before.status, 400, "{}", before.body);
    assert!(
        before.body.contains("unknown module 'quick'"),
        "{}",
        before.body
    );
    std::fs::write(
        &config,
        "allow = [\"udpout:127.0.0.1:*\"]\n[module.quick]\ncount = 1\ntimeout = \"100ms\"\n",
    )
    .unwrap();
    let reload = curl(&["-u", "ops:first", "-X", "POST", &url("/-/reload")]);
    assert_eq!(reload.status, 200, "{}", reload.body);
    let after = curl(&["-u", "ops:first", &quick]);
    assert_eq!(after.status, 200, "{}", after.body);
    assert_eq!(sample(&after.body, "mavping_probe_success", &[]), Some(0.0));

    // A bad web config is refused with the old one kept, and said why.
    std::fs::write(&web, "basic_auth_users:\n  ops: first\n").unwrap();
    let bad = curl(&["-u", "ops:first", "-X", "POST", &url("/-/reload")]);
    assert_eq!(bad.status, 500, "{}", bad.body);
    assert!(bad.body.contains("not a bcrypt hash"), "{}", bad.body);
    assert_eq!(curl(&["-u", "ops:first", &url("/metrics")]).status, 200);

    // A new password, on SIGHUP: the old one is refused from then on.
    std::fs::write(&web, web_of("second")).unwrap();
    on.signal("HUP");
    wait_for("no reload on SIGHUP", || {
        on.stderr().matches("configuration reloaded").count() == 2
    });
    assert_eq!(curl(&["-u", "ops:first", &url("/metrics")]).status, 401);
    let second = curl(&["-u", "ops:second", &url("/metrics")]);
    assert_eq!(second.status, 200);
    assert_eq!(
        sample(&second.body, "mavping_exporter_config_reloads_total", &[]),
        Some(3.0),
        "{}",
        second.body
    );
}

#[test]
fn debug_true_shows_why_a_probe_failed() {
    let mut target = SilentPeer::bind();
    let server = Server::start(&["--allow", "udpout:127.0.0.1:*"]);
    let c = curl(&[&format!(
        "http://{}/probe?target=udpout:127.0.0.1:{}&count=3&interval=50ms&timeout=200ms&debug=true",
        server.addr,
        target.port()
    )]);
    assert_eq!(c.status, 200, "{}", c.body);
    let text = c.body;
    assert!(
        text.starts_with(&format!(
            "Probe of udpout:127.0.0.1:{} with module default: 3 ping requests, every 50ms, each answered within 200ms",
            target.port()
        )),
        "{text}"
    );
    assert!(text.contains("\nLogs for the probe:\n"), "{text}");
    assert!(text.contains("3 requests sent"), "{text}");
    assert!(text.contains("\nResult: failure (no_reply"), "{text}");
    assert!(
        text.contains("\nMetrics that would have been returned:\n"),
        "{text}"
    );
    assert!(text.contains("\nmavping_probe_success 0\n"), "{text}");
    assert_eq!(target.pings(), 3);
    // debug=false is the usual exposition.
    let plain = curl(&[&format!(
        "http://{}/probe?target=udpout:127.0.0.1:{}&count=1&timeout=100ms&debug=false",
        server.addr,
        target.port()
    )]);
    assert!(plain.body.starts_with("# "), "{}", plain.body);
    assert_eq!(sample(&plain.body, "mavping_probe_success", &[]), Some(0.0));
}

#[test]
fn config_check_says_what_it_found_or_why_not_on_one_line() {
    let pki = Pki::make("check");
    let config = pki.write(
        "serve.toml",
        "allow = [\"udpout:127.0.0.1:*\", \"tcp:10.0.0.*:5760\"]\n[module.fleet]\ncount = 5\n",
    );
    let web = pki.write(
        "web.yml",
        &format!(
            "tls_server_config:\n  cert_file: server.pem\n  key_file: server.key\n\
             basic_auth_users:\n  prometheus: {}\n",
            hash("x")
        ),
    );
    let (code, out, err) = run_mavping(&[
        "serve",
        "--config",
        &config,
        "--web.config.file",
        &web,
        "--config.check",
    ]);
    assert_eq!(code, 0, "{err}");
    assert_eq!(
        out,
        "configuration OK: 2 allowed patterns, 2 modules, 0 continuous links, max_concurrent 16; \
         web: TLS, 1 basic-auth user\n"
    );
    for (file, text, said) in [
        (
            "bad.toml",
            "allow = [\"udpout:127.0.0.1:*\"]\nmax_concurrent = 0\n",
            "max_concurrent 0",
        ),
        (
            "bad-web.yml",
            "tls_server_config:\n  cert_file: server.pem\n  key_file: client.key\n",
            "the key is not the certificate's",
        ),
        ("bad-yaml.yml", "basic_auth_users: [\n", "--web.config.file"),
    ] {
        let path = pki.write(file, text);
        let option = if file.starts_with("bad.") {
            "--config"
        } else {
            "--web.config.file"
        };
        let (code, out, err) = run_mavping(&["serve", option, &path, "--config.check"]);
        assert_eq!(code, 2, "{file}: {out}{err}");
        assert!(out.is_empty(), "{out}");
        assert_eq!(err.lines().count(), 1, "{file}: {err}");
        assert!(err.contains(said), "{file}: {err}");
    }
    // Not a check: a bad web config stops the server from starting.
    let (code, _, err) = run_mavping(&["serve", "--web.config.file", &pki.path("bad-web.yml")]);
    assert_eq!(code, 2);
    assert_eq!(err.lines().count(), 1, "{err}");
}

#[test]
fn the_textfile_is_never_seen_half_written_and_promtool_accepts_it() {
    let dir = std::env::temp_dir().join(format!("mavping-textfile-it-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("mavping.prom");
    let path = file.to_str().unwrap().to_string();
    // A reader that reads the file as fast as it can while runs rewrite
    // it: every read it makes must be a whole exposition.
    let stop = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
    let reader = {
        let (file, stop) = (file.clone(), stop.clone());
        std::thread::spawn(move || {
            let (mut reads, mut torn) = (0u64, Vec::new());
            while !stop.load(std::sync::atomic::Ordering::Relaxed) {
                if let Ok(text) = std::fs::read_to_string(&file) {
                    reads += 1;
                    if !whole(&text) {
                        torn.push(text);
                    }
                }
            }
            (reads, torn)
        })
    };
    let runs = 10;
    for seed in 1..=runs {
        let link = format!("sim:?loss=20%&seed={seed}&clock=virtual");
        let (code, _, err) = run_mavping(&[
            "-q",
            "-c",
            "50",
            "-i",
            "10ms",
            &link,
            "--prometheus-textfile",
            &path,
        ]);
        assert!(code == 0 || code == 1, "{err}");
        let text = std::fs::read_to_string(&file).unwrap();
        assert!(whole(&text), "{text}");
        // This run's counts, not an older one's.
        assert!(text.contains(&format!("seed={seed}\"")), "{text}");
        let link = [("link", link_name(&text))];
        let link: Vec<(&str, &str)> = link.iter().map(|(k, v)| (*k, v.as_str())).collect();
        assert_eq!(sample(&text, "mavping_requests_total", &link), Some(50.0));
        let decided = sample(&text, "mavping_received_total", &link).unwrap()
            + sample(&text, "mavping_lost_total", &link).unwrap();
        assert_eq!(sample(&text, "mavping_sent_total", &link), Some(decided));
    }
    stop.store(true, std::sync::atomic::Ordering::Relaxed);
    let (reads, torn) = reader.join().unwrap();
    assert!(reads > 0);
    assert!(
        torn.is_empty(),
        "{} of {reads} reads torn: {:?}",
        torn.len(),
        torn.first()
    );
    eprintln!("{reads} reads of the textfile while {runs} runs rewrote it, none torn");
    // Nothing but the file is left in the directory.
    let names: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(names, ["mavping.prom"]);
    let checked = promtool()
        .args(["check", "metrics"])
        .stdin(std::fs::File::open(&file).unwrap())
        .output()
        .unwrap();
    assert!(checked.status.success(), "{checked:?}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A whole exposition ends with the run's end time, which is written last.
fn whole(text: &str) -> bool {
    text.starts_with("# HELP ")
        && text.ends_with('\n')
        && text
            .lines()
            .last()
            .is_some_and(|l| l.starts_with("mavping_textfile_run_end_timestamp_seconds "))
}

fn link_name(text: &str) -> String {
    let line = text
        .lines()
        .find(|l| l.starts_with("mavping_link_up{link=\""))
        .unwrap();
    let rest = line.strip_prefix("mavping_link_up{link=\"").unwrap();
    rest[..rest.find("\"}").unwrap()].to_string()
}
