//! The server's settings: the command line and, when given, the TOML file
//! (read again at each reload) into a [`ServeConfig`], its modules and its
//! continuous links.

use std::collections::BTreeMap;
use std::net::SocketAddr;
use std::path::{Path, PathBuf};
use std::time::Duration;

use super::allow::Pattern;
use super::file::{continuous_link, default_module, file_error, within, File, Table};
use super::limits::{
    DEFAULT_LISTEN, DEFAULT_MAX_CONCURRENT, DEFAULT_MODULE, MAX_CONCURRENT, MAX_LINKS,
};
use super::web::WebConfig;
use crate::cli::{ProbeKind, ServeArgs};
use crate::config::error::ConfigError;
use crate::config::link::LinkConfig;
use crate::config::probe::Probe;
use crate::config::values::validate_listen;
use crate::engine::radio::RadioType;
use crate::frame::signing::SigningConfig;
use crate::frame::{SysComp, Version};
use crate::transport::LinkOptions;
use crate::verdict::Thresholds;

/// `mavping serve`, validated.
#[derive(Debug)]
pub struct ServeConfig {
    pub(crate) listen: SocketAddr,
    /// Reread on SIGHUP.
    pub(crate) file: Option<PathBuf>,
    pub settings: ServeSettings,
    /// `--web.config.file`, reread on reload with the configuration.
    pub(crate) web_file: Option<PathBuf>,
    pub(crate) web: WebConfig,
    /// `--web.enable-lifecycle`: `POST /-/reload` reloads.
    pub(crate) lifecycle: bool,
    /// `--config.check`: validate, say what was found, and exit.
    pub(crate) check: bool,
    pub(crate) verbose: u8,
    /// The command line, whose `--allow` and `--link` a reload keeps.
    args: ServeArgs,
}

impl ServeConfig {
    /// The settings as they are now: the file read again, beside the
    /// command line's. The address stays what it was at the start.
    pub(crate) fn reload(&self) -> Result<(ServeSettings, WebConfig), ConfigError> {
        let (settings, _) = ServeSettings::load(&self.args, self.file.as_deref())?;
        Ok((settings, WebConfig::load(self.web_file.as_deref())?))
    }

    /// What `--config.check` prints: one line on what was found.
    pub(crate) fn describe(&self) -> String {
        let s = &self.settings;
        let plural =
            |n: usize, one: &str, many: &str| format!("{n} {}", if n == 1 { one } else { many });
        format!(
            "configuration OK: {}, {}, {}, max_concurrent {}; web: {}",
            plural(s.allow.len(), "allowed pattern", "allowed patterns"),
            plural(s.modules.len(), "module", "modules"),
            plural(s.links.len(), "continuous link", "continuous links"),
            s.max_concurrent,
            self.web.describe()
        )
    }
}

/// What a reload may change (everything but the address).
#[derive(Debug, Clone, PartialEq)]
pub struct ServeSettings {
    pub(crate) allow: Vec<Pattern>,
    pub(crate) modules: BTreeMap<String, Module>,
    pub(crate) links: Vec<ContinuousLink>,
    pub(crate) max_concurrent: usize,
}

/// How a `/probe` measures, unless its request says otherwise.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Module {
    pub(crate) kind: ProbeKind,
    pub(crate) target: Option<String>,
    pub(crate) command: String,
    pub(crate) retry_interval: Duration,
    pub(crate) retries: u8,
    /// The file a download module reads over FTP.
    pub(crate) path: String,
    pub(crate) count: u64,
    pub(crate) interval: Duration,
    pub(crate) timeout: Duration,
    pub(crate) thresholds: Thresholds,
    pub(crate) ours: SysComp,
    pub(crate) version: Version,
    pub(crate) heartbeat: bool,
    pub(crate) signing: Option<SigningConfig>,
    pub(crate) baud: u32,
    /// How radios are read (`radio_type`, as `--radio-type`).
    pub(crate) radio_type: RadioType,
    /// `report = "c2"`: each /probe run's C2 link report.
    pub(crate) c2: Option<crate::engine::c2::C2Config>,
}

/// A link probed all the time, shown at `/metrics` as `link="NAME"`.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct ContinuousLink {
    pub(crate) link: LinkConfig,
    pub(crate) probe: Probe,
    pub(crate) options: LinkOptions,
}

impl ServeSettings {
    /// The settings from the command line and, when given, the file (read
    /// again at each reload); also the file's `listen`.
    pub(crate) fn load(
        args: &ServeArgs,
        path: Option<&Path>,
    ) -> Result<(Self, Option<String>), ConfigError> {
        let file = match path {
            None => File::default(),
            Some(path) => {
                let text =
                    std::fs::read_to_string(path).map_err(|source| ConfigError::Unreadable {
                        what: format!("--config {}", path.display()),
                        source,
                    })?;
                toml::from_str(&text).map_err(|e| file_error(path, &text, &e))?
            }
        };
        let path = path.unwrap_or(Path::new("--config"));
        let mut allow = Vec::new();
        for p in &args.allow {
            allow.push(Pattern::parse(p).map_err(|e| e.within("--allow"))?);
        }
        for p in &file.allow {
            allow.push(Pattern::parse(p).map_err(|e| within(path, "allow", e))?);
        }
        let mut modules = BTreeMap::new();
        modules.insert(DEFAULT_MODULE.to_string(), default_module());
        for (name, table) in &file.module {
            let section = format!("[module.{name}]");
            if let Some(key) = table.misplaced(true) {
                let e = ConfigError::Misplaced {
                    key,
                    table: "a [[link]], not a module",
                };
                return Err(within(path, &section, e));
            }
            let module = table.module().map_err(|e| within(path, &section, e))?;
            modules.insert(name.clone(), module);
        }
        let mut links = Vec::new();
        for given in &args.links {
            let c = Table::default().common(Duration::from_secs(2))?;
            links.push(
                continuous_link(given, None, Duration::from_secs(1), c)
                    .map_err(|e| e.within("--link"))?,
            );
        }
        for (i, table) in file.link.iter().enumerate() {
            let section = format!("[[link]] #{}", i + 1);
            if let Some(key) = table.misplaced(false) {
                let e = ConfigError::Misplaced {
                    key,
                    table: "a [module.NAME]: a continuous link has no end to judge (alert in \
                            Prometheus instead)",
                };
                return Err(within(path, &section, e));
            }
            links.push(table.continuous().map_err(|e| within(path, &section, e))?);
        }
        if links.len() > MAX_LINKS {
            return Err(ConfigError::TooManyLinks {
                links: links.len(),
                max: MAX_LINKS,
            });
        }
        for (i, l) in links.iter().enumerate() {
            if links[..i].iter().any(|o| o.link.name == l.link.name) {
                return Err(ConfigError::SameName {
                    name: l.link.name.clone(),
                });
            }
        }
        let max_concurrent = args
            .max_concurrent
            .or(file.max_concurrent)
            .unwrap_or(DEFAULT_MAX_CONCURRENT);
        if max_concurrent == 0 || max_concurrent > MAX_CONCURRENT {
            return Err(ConfigError::value(
                "max_concurrent",
                max_concurrent,
                format!("expected 1 to {MAX_CONCURRENT}"),
            ));
        }
        Ok((
            ServeSettings {
                allow,
                modules,
                links,
                max_concurrent,
            },
            file.listen,
        ))
    }
}

impl TryFrom<&ServeArgs> for ServeConfig {
    type Error = ConfigError;

    fn try_from(args: &ServeArgs) -> Result<Self, ConfigError> {
        let (settings, file_listen) = ServeSettings::load(args, args.config.as_deref())?;
        let listen = match (&args.listen, file_listen) {
            (Some(l), _) => validate_listen("--listen", l)?,
            (None, Some(l)) => validate_listen("listen", &l).map_err(|e| {
                within(
                    args.config.as_deref().unwrap_or(Path::new("--config")),
                    "listen",
                    e,
                )
            })?,
            (None, None) => DEFAULT_LISTEN.parse().expect("a valid address"),
        };
        Ok(ServeConfig {
            listen,
            file: args.config.clone(),
            settings,
            web: WebConfig::load(args.web_config_file.as_deref())?,
            web_file: args.web_config_file.clone(),
            lifecycle: args.enable_lifecycle,
            check: args.config_check,
            verbose: args.verbose,
            args: args.clone(),
        })
    }
}

/// `mavping serve LINE` as clap parses it, for the tests here and below.
#[cfg(test)]
pub(super) fn test_args(line: &str) -> ServeArgs {
    use clap::Parser;
    let cli = crate::cli::Cli::try_parse_from(
        ["mavping", "serve"]
            .into_iter()
            .chain(line.split_whitespace()),
    )
    .unwrap();
    match cli.mode {
        Some(crate::cli::Mode::Serve(a)) => a,
        _ => panic!("not serve"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn args(line: &str) -> ServeArgs {
        test_args(line)
    }

    fn with_file(toml: &str) -> Result<ServeConfig, String> {
        let path = std::env::temp_dir().join(format!(
            "mavping-serve-{}-{}.toml",
            std::process::id(),
            toml.len()
        ));
        std::fs::write(&path, toml).unwrap();
        let mut a = args("");
        a.config = Some(path.clone());
        let c = ServeConfig::try_from(&a).map_err(|e| e.to_string());
        std::fs::remove_file(&path).unwrap();
        c
    }

    #[test]
    fn a_probe_and_a_served_link_carry_the_wire_budget_the_cli_does() {
        // The same link summarises alike behind `serve` and on the command
        // line: the budget is set in the config, not by one front end.
        use clap::Parser;
        let cli = crate::cli::Cli::try_parse_from([
            "mavping",
            "-c",
            "10",
            "-i",
            "0.1",
            "sim:?baud=57600",
        ])
        .unwrap();
        let from_cli = crate::config::Config::try_from(&cli.ping).unwrap().links[0]
            .session
            .wire;
        assert!(from_cli.is_some_and(|w| w.baud == 57600), "{from_cli:?}");
        let c = ServeConfig::try_from(&args("--allow sim:** --link sim:?baud=57600")).unwrap();
        let plan = c
            .settings
            .plan("target=sim:?baud%3D57600&count=10&interval=100ms")
            .unwrap();
        assert_eq!(plan.link.session.wire, from_cli);
        assert_eq!(
            c.settings.links[0].link.session.wire.map(|w| w.baud),
            Some(57600)
        );
        // The command probe's frames vary: it has none.
        let plan = c
            .settings
            .plan("target=sim:?baud%3D57600&probe=command")
            .map(|p| p.link.session.wire);
        assert!(matches!(plan, Ok(None) | Err(_)), "{plan:?}");
    }

    #[test]
    fn radio_type_reaches_a_modules_probes_and_a_links_session() {
        let c = with_file(
            "allow = [\"sim:*\"]\n[module.radio]\nradio_type = \"mlrs\"\n[[link]]\nlink = \"sim:\"\nradio_type = \"elrs\"",
        )
        .unwrap();
        let plan = c.settings.plan("module=radio&target=sim:").unwrap();
        assert_eq!(plan.link.session.radio_type, RadioType::Mlrs);
        let link = &c.settings.links[0].link.session;
        assert_eq!(link.radio_type, RadioType::Elrs);
        let plain = c.settings.plan("target=sim:").unwrap();
        assert_eq!(plain.link.session.radio_type, RadioType::Auto);
    }

    #[test]
    fn the_command_line_alone_needs_no_file() {
        let c = ServeConfig::try_from(&args("")).unwrap();
        assert_eq!(c.listen, "127.0.0.1:9465".parse().unwrap());
        assert!(c.settings.allow.is_empty() && c.settings.links.is_empty());
        assert_eq!(c.settings.max_concurrent, DEFAULT_MAX_CONCURRENT);
        let e = c
            .settings
            .plan("target=udpout:127.0.0.1:14550")
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("no target is; start mavping serve with --allow"),
            "{e}"
        );

        let c = ServeConfig::try_from(&args(
            "--listen [::1]:0 --allow udpout:127.0.0.1:* --link sim: --link udpout:10.0.0.2:14550 --max-concurrent 3",
        ))
        .unwrap();
        assert_eq!(c.listen, "[::1]:0".parse().unwrap());
        assert_eq!(c.settings.max_concurrent, 3);
        let names: Vec<&str> = c
            .settings
            .links
            .iter()
            .map(|l| l.link.name.as_str())
            .collect();
        assert_eq!(names, ["sim:", "udpout:10.0.0.2:14550"]);
        let l = &c.settings.links[1];
        assert_eq!(l.link.session.interval, Duration::from_secs(1));
        assert_eq!(l.link.session.timeout, Duration::from_secs(2));
        assert_eq!(l.link.session.count, None);
        assert_eq!(l.probe, Probe::Ping);

        let p = c
            .settings
            .plan("target=udpout%3A127.0.0.1%3A14550")
            .unwrap();
        assert_eq!(p.module, "default");
        assert_eq!(p.link.name, "udpout:127.0.0.1:14550");
        assert_eq!(p.link.session.count, Some(10));
        assert_eq!(p.link.session.interval, Duration::from_millis(100));
        assert_eq!(p.link.session.timeout, Duration::from_secs(1));
        assert!(!p.link.session.precise_pacing);
        let p = c
            .settings
            .plan("target=udpout:127.0.0.1:9&count=3&interval=20ms&timeout=0.5&probe=timesync")
            .unwrap();
        assert_eq!(p.link.session.count, Some(3));
        assert_eq!(p.link.session.interval, Duration::from_millis(20));
        assert_eq!(p.link.session.timeout, Duration::from_millis(500));
        assert_eq!(
            p.probe,
            Probe::Timesync {
                target: SysComp::new(0, 0)
            }
        );
    }

    #[test]
    fn the_file_sets_modules_links_and_limits() {
        let key = std::env::temp_dir().join(format!("mavping-serve-key-{}", std::process::id()));
        std::fs::write(&key, "secret\n").unwrap();
        let c = with_file(&format!(
            r#"
listen = "127.0.0.1:0"
max_concurrent = 4
allow = ["udpout:127.0.0.1:*", "/dev/ttyUSB*"]

[module.strict]
probe = "timesync"
target = "1/1"
count = 20
interval = "50ms"
timeout = 0.5
max_loss = "5%"
max_rtt = ["p99=50ms", "200ms"]
expect = ["1/1"]
# A literal string: a Windows temp path is full of backslashes.
signing_key_file = '{}'

[module.default]
count = 3

[[link]]
link = "udpout:10.0.0.2:14550"
name = "gcs-1"
rate = 5
probe = "timesync"

[[link]]
link = "sim:?loss=5%"
interval = "200ms"
timeout = "1s"
"#,
            key.display()
        ));
        std::fs::remove_file(&key).unwrap();
        let c = c.unwrap();
        assert_eq!(c.listen, "127.0.0.1:0".parse().unwrap());
        let s = &c.settings;
        assert_eq!(s.max_concurrent, 4);
        assert_eq!(s.allow.len(), 2);
        let strict = &s.modules["strict"];
        assert_eq!((strict.count, strict.kind), (20, ProbeKind::Timesync));
        assert_eq!(strict.timeout, Duration::from_millis(500));
        assert_eq!(strict.thresholds.max_loss, Some(0.05));
        assert_eq!(strict.thresholds.max_rtt.len(), 2);
        assert!(strict.signing.is_some());
        assert_eq!(s.modules["default"].count, 3);
        let p = s.plan("target=udpout:127.0.0.1:5&module=strict").unwrap();
        assert_eq!(
            p.probe,
            Probe::Timesync {
                target: SysComp::new(1, 1)
            }
        );
        assert_eq!(p.link.thresholds.expect.len(), 1);
        assert!(p.link.session.signing.is_some());
        // PING addresses no one, whatever the module's target.
        let p = s
            .plan("target=/dev/ttyUSB0&module=strict&probe=ping")
            .unwrap();
        assert_eq!(p.probe, Probe::Ping);
        assert_eq!(s.links[0].link.name, "gcs-1");
        assert_eq!(s.links[0].link.session.interval, Duration::from_millis(200));
        assert!(matches!(s.links[0].probe, Probe::Timesync { .. }));
        assert_eq!(s.links[1].link.name, "sim:?loss=5%");
        assert_eq!(s.links[1].link.session.timeout, Duration::from_secs(1));
    }

    #[test]
    fn a_continuous_link_can_listen_without_probes() {
        let c = with_file(
            r#"
[[link]]
link = "udp:127.0.0.1:14550"
name = "vehicle"
passive = true
gap = "3s"
heartbeat = false

[[link]]
link = "sim:"
passive = true

[[link]]
link = "sim:?seed=2"
passive = false
rate = 2
"#,
        )
        .unwrap();
        let [vehicle, sim, probed] = &c.settings.links[..] else {
            panic!("three links: {:?}", c.settings.links)
        };
        assert_eq!(
            vehicle.probe,
            Probe::Passive {
                gap: Some(Duration::from_secs(3))
            }
        );
        assert_eq!(vehicle.link.name, "vehicle");
        assert!(!vehicle.link.session.heartbeat);
        assert_eq!(vehicle.link.session.count, None);
        assert_eq!(sim.probe, Probe::Passive { gap: None });
        // Our HEARTBEAT stays on unless turned off, as without --no-heartbeat.
        assert!(sim.link.session.heartbeat);
        assert_eq!(probed.probe, Probe::Ping);
        assert_eq!(probed.link.session.interval, Duration::from_millis(500));
    }

    #[test]
    fn the_example_in_contrib_is_valid() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("contrib/mavping-serve.toml");
        let (s, listen) = ServeSettings::load(&args(""), Some(&path)).unwrap();
        assert_eq!(listen.as_deref(), Some("0.0.0.0:9465"));
        assert_eq!(s.allow.len(), 3);
        assert!(s.modules.contains_key("ardupilot") && s.modules.contains_key("radio"));
        let names: Vec<&str> = s.links.iter().map(|l| l.link.name.as_str()).collect();
        assert_eq!(names, ["sik-radio", "companion", "vehicle-telemetry"]);
        assert!(matches!(s.links[2].probe, Probe::Passive { gap: Some(_) }));
        assert!(s.plan("target=serial:/dev/ttyUSB3&module=radio").is_ok());
        assert!(s
            .plan("target=udpout:10.0.0.9:14550&module=ardupilot")
            .is_ok());
        assert!(s.plan("target=udpout:10.0.1.9:14550").is_err());
    }

    /// The Debian package's /etc/mavping/serve.toml: valid, and safe as
    /// shipped (this machine only, nothing allowed, no link).
    #[test]
    fn the_packaged_config_is_valid_and_opens_nothing() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("packaging/debian/serve.toml");
        let (s, listen) = ServeSettings::load(&args(""), Some(&path)).unwrap();
        assert_eq!(listen.as_deref(), Some(DEFAULT_LISTEN));
        assert!(s.allow.is_empty() && s.links.is_empty());
        assert_eq!(s.modules.keys().collect::<Vec<_>>(), [DEFAULT_MODULE]);
        assert!(s.plan("target=udpout:127.0.0.1:14550").is_err());
    }

    #[test]
    fn bad_files_name_the_place() {
        for (toml, needle) in [
            ("allow = [\n\"udpout:1.2.3.4:*\",\n 7]", ":3: "),
            ("colour = 1", "unknown field `colour`"),
            ("[module.a]\ncount = 0", "[module.a]: count 0"),
            ("[module.a]\nlink = \"sim:\"", "link belongs in a [[link]]"),
            (
                "[[link]]\nlink = \"sim:\"\nmax_loss = \"5%\"",
                "[[link]] #1: max_loss belongs in a [module.NAME]",
            ),
            ("[[link]]\nname = \"x\"", "needs link ="),
            (
                "[[link]]\nlink = \"sim:\"\nrate = 1\ninterval = 1",
                "give one, not both",
            ),
            (
                "[[link]]\nlink = \"sim:\"\n[[link]]\nlink = \"sim:\"",
                "two continuous links are named 'sim:'",
            ),
            ("[module.a]\nprobe = \"echo\"", "probe 'echo'"),
            (
                "[module.a]\ntarget = \"1/1\"",
                "[module.a]: target: PING requests are always broadcast",
            ),
            ("[module.a]\nsysid = 0", "sysid 0"),
            (
                "[module.a]\nradio_type = \"sik2\"",
                "radio_type 'sik2': expected auto, sik, mlrs, elrs, esp or raw",
            ),
            ("[module.a]\ninterval = \"soon\"", "interval: 'soon'"),
            (
                "[module.a]\nsigning_key_file = \"/nonexistent/k\"",
                "cannot read it",
            ),
            ("max_concurrent = 0", "max_concurrent 0"),
            (
                "listen = \"localhost:1\"",
                "listen: listen localhost:1: expected ADDR:PORT",
            ),
            ("allow = [\"*\"]", "start it with a link kind"),
            (
                "[[link]]\nlink = \"sim:\"\npassive = true\nrate = 5",
                "[[link]] #1: passive = true sends no probes: drop rate",
            ),
            (
                "[[link]]\nlink = \"sim:\"\npassive = true\nprobe = \"timesync\"",
                "passive = true sends no probes: drop probe",
            ),
            (
                "[[link]]\nlink = \"sim:\"\npassive = true\ntimeout = \"1s\"",
                "passive = true sends no probes: drop timeout",
            ),
            (
                "[[link]]\nlink = \"sim:\"\ngap = \"2s\"",
                "[[link]] #1: gap needs passive = true",
            ),
            (
                "[[link]]\nlink = \"sim:\"\npassive = true\ngap = \"1ms\"",
                "gap: expected at least 10ms",
            ),
            (
                "[[link]]\nlink = \"sim:\"\npassive = true\ngap = \"soon\"",
                "gap: 'soon'",
            ),
            (
                "[module.a]\npassive = true",
                "[module.a]: passive belongs in a [[link]]",
            ),
        ] {
            let e = with_file(toml).unwrap_err();
            assert!(e.contains(needle), "{toml}: {e}");
            assert!(!e.contains('\n'), "{e}");
        }
        let mut a = args("");
        a.config = Some(PathBuf::from("/nonexistent/serve.toml"));
        let e = ServeConfig::try_from(&a).unwrap_err().to_string();
        assert!(
            e.contains("--config /nonexistent/serve.toml: cannot read it"),
            "{e}"
        );
    }
}
