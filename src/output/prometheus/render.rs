//! The exposition text: each family once, its `HELP` and `TYPE` lines,
//! then a series per link and responder (or radio); families with no
//! series are left out. What a run, `mavping serve`'s `/metrics` and one
//! `/probe` show differs only in which families are written.

use std::fmt::Write as _;

use super::c2::write_c2;
use super::exposition::{Exposition, Family, Figure, SeriesFigure};
use super::link_node::write_link_nodes;
use super::passive::{write_directions, write_sources};
use super::radio_series::RadioSeries;
use super::series::{Series, BUCKETS_S};
use super::transfer::write_transfers;
use super::Metrics;
use crate::engine::radio::{Field, UNKNOWN};

/// What a [`Metrics`] stands for, which decides how its counts are typed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Scope {
    /// A run or a continuous link: counters that only grow (`_total`).
    Run,
    /// One `/probe`: that probe's counts (as gauges) and histogram, under
    /// names of their own, so `rate()` is never applied to figures that
    /// start afresh each scrape.
    Probe,
}

/// A per-responder count: a counter in a run; a gauge of one probe under
/// the name of its own beside its value (see [`Scope`]).
type Count = Figure<(&'static str, fn(&Series) -> u64)>;

const COUNTS: [Count; 5] = [
    Figure::counter(
        "mavping_sent_total",
        "Requests in the responder's window whose fate is decided (received + lost).",
        ("mavping_probe_sent", |s| s.counts.sent),
    ),
    Figure::counter(
        "mavping_received_total",
        "Replies received within the timeout.",
        ("mavping_probe_received", |s| s.counts.received),
    ),
    Figure::counter(
        "mavping_lost_total",
        "Requests not answered within the timeout.",
        ("mavping_probe_lost", |s| s.counts.lost),
    ),
    Figure::counter(
        "mavping_late_total",
        "First replies after the timeout (each also counted lost).",
        ("mavping_probe_late", |s| s.counts.late),
    ),
    Figure::counter(
        "mavping_duplicate_total",
        "Second and later replies to the same request.",
        ("mavping_probe_duplicate", |s| s.counts.duplicate),
    ),
];

/// Only `/probe` has it: a run's loss ratio is the counters' arithmetic.
const PROBE_LOSS_RATIO: [SeriesFigure<Series>; 1] = [Figure::gauge(
    "mavping_probe_loss_ratio",
    "Lost over sent in this probe (0 to 1).",
    Series::loss_ratio,
)];

/// The RTT histogram, under a run's name or a probe's.
fn rtt_histogram(scope: Scope) -> Family {
    let name = match scope {
        Scope::Run => "mavping_rtt_seconds",
        Scope::Probe => "mavping_probe_rtt_seconds",
    };
    Family::histogram(name, "Round-trip time of replies within the timeout.")
}

const GAUGES: [SeriesFigure<Series>; 5] = [
    Figure::gauge(
        "mavping_last_rtt_seconds",
        "Round-trip time of the latest reply within the timeout.",
        |s| s.last_rtt_s,
    ),
    Figure::gauge(
        "mavping_rtt_p50_seconds",
        "Median round-trip time (HDR histogram; at the end of a run or probe).",
        |s| Some(s.rtt?.p50_us / 1e6),
    ),
    Figure::gauge(
        "mavping_rtt_p99_seconds",
        "99th percentile round-trip time (HDR histogram; at the end of a run or probe).",
        |s| Some(s.rtt?.p99_us / 1e6),
    ),
    Figure::gauge(
        "mavping_clock_offset_seconds",
        "Responder's clock minus ours at its latest reply (TIMESYNC probe; updated at most once a second).",
        |s| s.clock_offset_s,
    ),
    Figure::gauge(
        "mavping_responder_via_timesync",
        "--probe auto: 1 when the responder is measured by TIMESYNC (it does not answer PING), 0 by PING.",
        |s| s.via_timesync.map(f64::from),
    ),
];

/// A radio's kind, in a label of its own.
const RADIO_INFO: Family = Family::gauge(
    "mavping_radio_info",
    "1 for each radio, its kind (sik, mlrs, elrs, esp, unknown) in a label: from what it sends, or --radio-type.",
);

const RADIO: [SeriesFigure<RadioSeries>; 14] = [
    Figure::gauge(
        "mavping_radio_rssi",
        "Local signal strength, raw RADIO_STATUS units (255, unknown, left out).",
        |r| known(r.latest.rssi),
    ),
    Figure::gauge(
        "mavping_radio_remote_rssi",
        "Remote signal strength, raw RADIO_STATUS units.",
        |r| known(r.latest.remrssi),
    ),
    Figure::gauge(
        "mavping_radio_noise",
        "Local background noise, raw RADIO_STATUS units.",
        |r| known(r.latest.noise),
    ),
    Figure::gauge(
        "mavping_radio_remote_noise",
        "Remote background noise, raw RADIO_STATUS units.",
        |r| known(r.latest.remnoise),
    ),
    Figure::gauge(
        "mavping_radio_rssi_dbm",
        "Local signal strength in dBm, on a known scale only: SiK raw / 1.9 - 127 (approximate), mLRS -120..-50 dBm as 0..254, an ESP8266 bridge's WiFi RSSI.",
        |r| in_kind_units(r, "rssi_dbm"),
    ),
    Figure::gauge(
        "mavping_radio_remote_rssi_dbm",
        "Remote signal strength in dBm: SiK (approximate), mLRS; ExpressLRS's uplink RSSI (-remrssi).",
        |r| in_kind_units(r, "remrssi_dbm"),
    ),
    Figure::gauge(
        "mavping_radio_noise_dbm",
        "Local noise floor in dBm (SiK radios, approximate; other radios' noise is no noise floor).",
        |r| in_kind_units(r, "noise_dbm"),
    ),
    Figure::gauge(
        "mavping_radio_remote_noise_dbm",
        "Remote noise floor in dBm (SiK radios, approximate).",
        |r| in_kind_units(r, "remnoise_dbm"),
    ),
    Figure::gauge(
        "mavping_radio_snr_db",
        "Signal-to-noise ratio in dB: mLRS (10 - noise), ExpressLRS (noise).",
        |r| in_kind_units(r, "snr_db"),
    ),
    Figure::gauge(
        "mavping_radio_link_quality_percent",
        "ExpressLRS's uplink link quality, percent (rssi / 2.55).",
        |r| in_kind_units(r, "link_quality_pct"),
    ),
    Figure::gauge(
        "mavping_radio_vehicle_lost_percent",
        "An ESP8266 WiFi bridge's share of the vehicle's (serial) messages lost, percent (its remnoise).",
        |r| in_kind_units(r, "vehicle_lost_pct"),
    ),
    Figure::gauge(
        "mavping_radio_txbuf_percent",
        "Free space in the radio's transmit buffer, percent.",
        |r| known(r.latest.txbuf),
    ),
    Figure::counter(
        "mavping_radio_rxerrors_total",
        "Receive errors the radio counted since mavping first heard it (its 16-bit counter's wraps and restarts followed; not an ESP8266 bridge's, whose rxerrors is a percentage).",
        |r| (!r.kind.rxerrors_is_gcs_lost_pct()).then_some(r.rxerrors.grown() as f64),
    ),
    Figure::counter(
        "mavping_radio_fixed_total",
        "Packets the radio's error correction repaired since mavping first heard it.",
        |r| Some(r.fixed.grown() as f64),
    ),
];

fn known(raw: u8) -> Option<f64> {
    (raw != UNKNOWN).then_some(f64::from(raw))
}

/// The latest report's figure `key` (`rssi_dbm`, `snr_db`) where the
/// radio's kind defines one: a scale is never guessed.
fn in_kind_units(r: &RadioSeries, key: &str) -> Option<f64> {
    Field::ALL.into_iter().find_map(|f| {
        let m = r.kind.meaning(f).filter(|m| m.key == key)?;
        (m.convert)(f.of(&r.latest))
    })
}

/// A link's requests, whoever answered them (a run's and a continuous
/// link's; a `/probe` has `mavping_probe_requests`)...
const REQUESTS: Family = Family::counter(
    "mavping_requests_total",
    "Requests the link put on the wire, answered or not (a continuous link's across its reopenings).",
);

/// ...and who answers them: with requests going out, 0 says nobody hears.
const RESPONDERS: Family = Family::gauge(
    "mavping_responders",
    "Systems that answered the link's requests (in time or late) since it was last opened.",
);

/// Each link's requests and responders, by link and probe.
fn write_senders(out: &mut Exposition, links: &[&Metrics]) {
    let senders = || {
        links
            .iter()
            .filter(|m| m.sends())
            .map(|m| (m.probe_labels(), *m))
    };
    out.family(&REQUESTS, senders().map(|(l, m)| (l, m.requests())));
    out.family(&RESPONDERS, senders().map(|(l, m)| (l, m.answering())));
}

/// Every link's per-responder and radio families, each family once with
/// a series per link and responder told apart by their labels.
fn write_links(out: &mut Exposition, links: &[&Metrics], scope: Scope) {
    if scope == Scope::Run {
        write_senders(out, links);
    }
    let series = || {
        links
            .iter()
            .flat_map(|m| m.responders.iter().map(move |(id, s)| (m.labels(*id), s)))
    };
    for Figure { family, value } in &COUNTS {
        let (probe, count) = value;
        let family = match scope {
            Scope::Run => *family,
            Scope::Probe => Family::gauge(probe, family.help),
        };
        out.family(&family, series().map(|(l, s)| (l, count(s))));
    }
    if scope == Scope::Probe {
        out.figures(&PROBE_LOSS_RATIO, series);
    }
    let histogram = rtt_histogram(scope);
    if series().next().is_some() {
        out.header(&histogram);
    }
    let name = |part| format!("{}_{part}", histogram.name);
    for (labels, s) in series() {
        let mut cumulative = 0;
        for (i, count) in s.buckets.iter().enumerate() {
            cumulative += count;
            let le = BUCKETS_S.get(i).map_or("+Inf".into(), f64::to_string);
            let bucket = format!("{labels},le=\"{le}\"");
            out.sample(&name("bucket"), &bucket, cumulative);
        }
        out.sample(&name("sum"), &labels, s.rtt_sum_s);
        out.sample(&name("count"), &labels, s.counts.received);
    }
    out.figures(&GAUGES, series);
    let radios = || {
        links
            .iter()
            .flat_map(|m| m.radios.iter().map(move |(id, r)| (m.radio_labels(*id), r)))
    };
    let kind = |l, r: &RadioSeries| (format!("{l},kind=\"{}\"", r.kind.key()), 1);
    out.family(&RADIO_INFO, radios().map(|(l, r)| kind(l, r)));
    out.figures(&RADIO, radios);
    write_link_nodes(out, links);
    write_directions(out, links);
    write_sources(out, links);
    write_transfers(out, links, scope == Scope::Probe);
    write_c2(out, links);
}

/// A link's state, as a run has it...
const RUN_LINK_UP: Family = Family::gauge(
    "mavping_link_up",
    "1 while the link is open, 0 after it failed (a run's other links go on).",
);

/// ...and as `mavping serve` has it.
const SERVE_LINK_UP: Family = Family::gauge(
    "mavping_link_up",
    "1 while the continuous link is open, 0 while it is down and being retried.",
);

const LINK_RESTARTS: Family = Family::counter(
    "mavping_link_restarts_total",
    "Times the continuous link was reopened after it broke or could not be opened.",
);

/// The exposition of one or several links of a run (`--prometheus`).
pub(crate) fn render(links: &[&Metrics]) -> String {
    let mut out = Exposition::default();
    write_link_states(&mut out, links, &RUN_LINK_UP, None);
    write_links(&mut out, links, Scope::Run);
    out.0
}

/// Each link's state: whether it is up, and (`mavping serve`'s
/// continuous links) how often it was reopened.
fn write_link_states(
    out: &mut Exposition,
    links: &[&Metrics],
    up: &Family,
    restarts: Option<&Family>,
) {
    let states = || {
        links
            .iter()
            .filter_map(|m| Some((m.link_labels(), m.state?)))
    };
    out.family(up, states().map(|(l, s)| (l, u8::from(s.up))));
    if let Some(restarts) = restarts {
        out.family(restarts, states().map(|(l, s)| (l, s.restarts)));
    }
}

/// What `mavping serve` says about itself at `/metrics`.
#[derive(Debug, Default, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Health {
    /// `/probe` requests that ran a probe...
    pub(crate) probes: u64,
    /// ...of which failed (`mavping_probe_success` 0).
    pub(crate) probes_failed: u64,
    /// `/probe` requests refused (400: bad or forbidden; 503: too many).
    pub(crate) probes_refused: u64,
    pub(crate) probes_running: u64,
    /// Links open now: continuous links up and probes' links.
    pub(crate) open_links: u64,
    pub(crate) reloads: u64,
    pub(crate) reloads_failed: u64,
    pub(crate) last_reload_ok: bool,
}

/// The server's own figures (counts below 2^53, exact as `f64`).
const HEALTH: [SeriesFigure<Health>; 8] = [
    Figure::counter(
        "mavping_exporter_probes_total",
        "/probe requests that ran a probe.",
        |h| Some(h.probes as f64),
    ),
    Figure::counter(
        "mavping_exporter_probes_failed_total",
        "Probes that ran and failed (mavping_probe_success 0).",
        |h| Some(h.probes_failed as f64),
    ),
    Figure::counter(
        "mavping_exporter_probes_refused_total",
        "/probe requests refused: bad or forbidden (400) or too many at once (503).",
        |h| Some(h.probes_refused as f64),
    ),
    Figure::gauge(
        "mavping_exporter_probes_running",
        "Probes running now.",
        |h| Some(h.probes_running as f64),
    ),
    Figure::gauge(
        "mavping_exporter_open_links",
        "Links open now: continuous links that are up and the links of running probes.",
        |h| Some(h.open_links as f64),
    ),
    Figure::counter(
        "mavping_exporter_config_reloads_total",
        "Configuration reloads asked for (SIGHUP, POST /-/reload).",
        |h| Some(h.reloads as f64),
    ),
    Figure::counter(
        "mavping_exporter_config_reloads_failed_total",
        "Reloads refused because the new configuration was invalid (the old one stays).",
        |h| Some(h.reloads_failed as f64),
    ),
    Figure::gauge(
        "mavping_exporter_config_last_reload_successful",
        "1 when the configuration in use is the one last read from the file.",
        |h| Some(f64::from(u8::from(h.last_reload_ok))),
    ),
];

/// `mavping serve`'s `/metrics`: its health, then its continuous links.
pub(crate) fn render_serve(links: &[&Metrics], health: &Health) -> String {
    let mut out = Exposition::default();
    out.figures(&HEALTH, || std::iter::once((String::new(), health)));
    write_link_states(&mut out, links, &SERVE_LINK_UP, Some(&LINK_RESTARTS));
    write_links(&mut out, links, Scope::Run);
    out.0
}

/// How one `/probe` ended.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct ProbeResult {
    pub(crate) success: bool,
    pub(crate) duration_s: f64,
    /// Why it failed: `open_failed`, `link_failed`, or a broken check
    /// (`no_reply`, `max_loss`, ...), each once.
    pub(crate) reasons: Vec<&'static str>,
    /// Requests put on the wire, and those still undecided when the
    /// probe's time was up.
    pub(crate) requests: u64,
    pub(crate) in_flight: u64,
    /// The error, for a person reading the exposition (a comment line).
    pub(crate) message: Option<String>,
}

/// What one `/probe` says of itself.
const PROBE_SUCCESS: Family = Family::gauge(
    "mavping_probe_success",
    "1 when a responder answered and every threshold of the module held.",
);
const PROBE_FAILURE: Family = Family::gauge(
    "mavping_probe_failure",
    "1 for each reason the probe failed (open_failed, link_failed, nothing_heard, no_reply, max_loss, ...).",
);
const PROBE_DURATION: Family = Family::gauge(
    "mavping_probe_duration_seconds",
    "How long the probe took, opening the link included.",
);
const PROBE_REQUESTS: Family = Family::gauge(
    "mavping_probe_requests",
    "Requests the probe put on the wire.",
);
const PROBE_IN_FLIGHT: Family = Family::gauge(
    "mavping_probe_in_flight",
    "Requests still undecided when the probe's time was up (counted neither received nor lost).",
);

/// One `/probe`'s answer: its result, then its link's figures.
pub(crate) fn render_probe(metrics: &Metrics, result: &ProbeResult) -> String {
    let mut out = Exposition::default();
    if let Some(message) = &result.message {
        // A comment: ignored by Prometheus, read by whoever curls.
        let _ = writeln!(out.0, "# mavping: {}", message.replace('\n', " "));
    }
    let one = |v: f64| [(String::new(), v)];
    out.family(&PROBE_SUCCESS, one(f64::from(u8::from(result.success))));
    let reasons = result
        .reasons
        .iter()
        .map(|r| (format!("reason=\"{r}\""), 1));
    out.family(&PROBE_FAILURE, reasons);
    out.family(&PROBE_DURATION, one(result.duration_s));
    out.family(&PROBE_REQUESTS, one(result.requests as f64));
    out.family(&PROBE_IN_FLIGHT, one(result.in_flight as f64));
    write_links(&mut out, &[metrics], Scope::Probe);
    out.0
}

#[cfg(test)]
mod tests {
    use super::super::test_support::{has, test_start as info};
    use super::*;
    use crate::engine::matcher::MatchEvent;
    use crate::engine::observe::Observer;
    use crate::engine::radio::{RadioKind, RadioReport};
    use crate::engine::summary::ProbeName;
    use crate::frame::SysComp;
    use crate::output::{Event, StartInfo};

    /// Two links with every kind of figure: responders with replies,
    /// losses and a clock, a SiK radio and another maker's.
    fn rich_links() -> (Metrics, Metrics) {
        let mut a = Metrics::continuous("sim:?seed=1", ProbeName::Timesync);
        a.on_start(&StartInfo {
            probe: ProbeName::Timesync,
            ..info("sim:?seed=1")
        });
        let mut b = Metrics::default();
        b.on_start(&info("udpout:\"x\\y\"\n"));
        for m in [&mut a, &mut b] {
            let _ = m.event(&Event::Progress { at: 0, requests: 4 });
            for (seq, rtt) in [
                (0, 400_000),
                (1, 3_000_000),
                (2, 700_000_000),
                (3, 20_000_000_000),
            ] {
                m.on_event(&MatchEvent::Reply {
                    responder: SysComp::new(1, 1),
                    seq,
                    rtt,
                    sent_at: 0,
                    at: rtt,
                    out_of_order: false,
                    first_from_responder: seq == 0,
                });
            }
            m.on_event(&MatchEvent::Lost {
                responder: SysComp::new(2, 1),
                seq: 0,
                sent_at: 0,
                at: 0,
            });
            m.on_event(&MatchEvent::Late {
                responder: SysComp::new(2, 1),
                seq: 0,
                rtt: 5,
                sent_at: 0,
                at: 0,
            });
            m.on_event(&MatchEvent::Duplicate {
                responder: SysComp::new(1, 1),
                seq: 1,
                rtt: 5,
                sent_at: 0,
                at: 0,
            });
            m.on_radio(SysComp::new(51, 68), radio(120, 80), RadioKind::Sik);
            m.on_radio(SysComp::new(3, 100), radio(UNKNOWN, 70), RadioKind::Unknown);
            m.on_radio(
                SysComp::new(52, 68),
                RadioReport {
                    remnoise: 60,
                    ..radio(110, 95)
                },
                RadioKind::Sik,
            );
        }
        a.on_clock(
            SysComp::new(1, 1),
            10_000_000_000,
            &crate::engine::clock_offset::ClockSummary {
                offset_ns: -2_000_000_000,
                uncertainty_ns: 500,
                bounds_ns: None,
                bounds_drift_limit_ppm: 200,
                spread_ns: 0.0,
                drift_ppm: Some(50.0),
                drift_stderr_ppm: None,
                samples: 1,
            },
        );
        // The end of b's run: percentiles of the HDR histogram, and the
        // clock where no live estimate came.
        let mut rtt = crate::engine::stats::RttStats::new();
        rtt.record(3_000_000);
        rtt.record(700_000_000);
        let responder = crate::engine::summary::ResponderSummary {
            id: SysComp::new(1, 1),
            counts: crate::engine::matcher::Counts::default(),
            loss_ratio: 0.0,
            rtt: rtt.summary(),
            histogram: vec![],
            identity: None,
            probe: None,
            clock: Some(crate::engine::clock_offset::ClockSummary {
                offset_ns: 1_500_000,
                uncertainty_ns: 500,
                bounds_ns: None,
                bounds_drift_limit_ppm: 200,
                spread_ns: 0.0,
                drift_ppm: None,
                drift_stderr_ppm: None,
                samples: 1,
            }),
            direction: None,
            split: None,
        };
        b.on_summary(&crate::engine::summary::EchoSummary {
            responders: vec![responder],
            ..crate::engine::summary::EchoSummary::empty("b", 4)
        });
        b.set_up(false);
        (a, b)
    }

    /// Every family of the three expositions, byte for byte.
    #[test]
    fn every_family_byte_for_byte() {
        let (a, b) = rich_links();
        let health = Health {
            probes: 7,
            probes_failed: 2,
            probes_refused: 1,
            probes_running: 1,
            open_links: 2,
            reloads: 1,
            reloads_failed: 1,
            last_reload_ok: true,
        };
        let result = ProbeResult {
            success: false,
            duration_s: 1.25,
            reasons: vec!["link_failed", "max_loss"],
            requests: 5,
            in_flight: 1,
            message: Some("the link broke".into()),
        };
        insta::assert_snapshot!("run", render(&[&a, &b]));
        insta::assert_snapshot!("serve", render_serve(&[&a, &b], &health));
        insta::assert_snapshot!("probe", render_probe(&b, &result));
    }

    #[test]
    fn several_links_are_series_of_one_family() {
        let mut a = Metrics::default();
        a.on_start(&info("sim:"));
        let mut b = Metrics::default();
        b.on_start(&info("udpout:127.0.0.1:1"));
        for m in [&mut a, &mut b] {
            m.on_event(&MatchEvent::Lost {
                responder: SysComp::new(1, 1),
                seq: 0,
                sent_at: 0,
                at: 0,
            });
        }
        let text = render(&[&a, &b]);
        assert_eq!(text.matches("# TYPE mavping_lost_total counter").count(), 1);
        for link in ["sim:", "udpout:127.0.0.1:1"] {
            let line = format!(
                "mavping_lost_total{{link=\"{link}\",probe=\"ping\",sysid=\"1\",compid=\"1\"}} 1"
            );
            assert!(text.lines().any(|x| x == line), "{line} not in\n{text}");
        }
    }

    fn radio(rssi: u8, txbuf: u8) -> RadioReport {
        RadioReport {
            rssi,
            remrssi: 150,
            txbuf,
            noise: 40,
            remnoise: UNKNOWN,
            rxerrors: 3,
            fixed: 1,
        }
    }

    #[test]
    fn radios_show_their_latest_report_and_leave_unknowns_out() {
        let mut m = Metrics::default();
        m.on_start(&info("sim:"));
        let id = SysComp::new(51, 68);
        m.on_radio(id, radio(100, 90), RadioKind::Sik);
        m.on_radio(id, radio(120, 80), RadioKind::Sik);
        let text = render(&[&m]);
        let l = r#"link="sim:",sysid="51",compid="68""#;
        has(&text, &format!("mavping_radio_rssi{{{l}}} 120"));
        has(&text, &format!("mavping_radio_remote_rssi{{{l}}} 150"));
        has(&text, &format!("mavping_radio_txbuf_percent{{{l}}} 80"));
        // A SiK radio's figures in dBm too: 120 / 1.9 - 127.
        has(
            &text,
            &format!("mavping_radio_rssi_dbm{{{l}}} {}", 120.0 / 1.9 - 127.0),
        );
        assert!(!text.contains("mavping_radio_remote_noise"), "{text}");
        // No responder: no responder families at all, not even their HELP.
        assert!(!text.contains("mavping_sent_total"), "{text}");
    }

    #[test]
    fn radio_error_counters_only_grow() {
        let mut m = Metrics::default();
        m.on_start(&info("sim:"));
        let id = SysComp::new(51, 68);
        let with_errors = |rxerrors, fixed| RadioReport {
            rxerrors,
            fixed,
            ..radio(100, 90)
        };
        // Grows 30, wraps (+11), grows 15, then the radio restarts (+4).
        for (rx, fixed) in [(65_500, 7), (65_530, 7), (5, 9), (20, 9), (4, 1)] {
            m.on_radio(id, with_errors(rx, fixed), RadioKind::Sik);
        }
        let text = render(&[&m]);
        let l = r#"link="sim:",sysid="51",compid="68""#;
        has(&text, "# TYPE mavping_radio_rxerrors_total counter");
        has(&text, &format!("mavping_radio_rxerrors_total{{{l}}} 60"));
        has(&text, &format!("mavping_radio_fixed_total{{{l}}} 3"));
    }

    #[test]
    fn only_a_sik_radio_has_dbm() {
        let mut m = Metrics::default();
        m.on_start(&info("sim:"));
        // Another maker's radio: its scale is not known.
        m.on_radio(SysComp::new(1, 100), radio(100, 90), RadioKind::Unknown);
        let text = render(&[&m]);
        assert!(text.contains("mavping_radio_rssi{"), "{text}");
        assert!(!text.contains("_dbm"), "{text}");
    }

    #[test]
    fn each_kind_in_its_own_units() {
        let mut m = Metrics::default();
        m.on_start(&info("sim:"));
        // mLRS: -85 and -90 dBm, SNR 7 dB (noise = 10 - SNR).
        let mlrs = RadioReport {
            rssi: 127,
            remrssi: 109,
            txbuf: 100,
            noise: 3,
            remnoise: UNKNOWN,
            rxerrors: 0,
            fixed: 0,
        };
        m.on_radio(SysComp::new(51, 68), mlrs, RadioKind::Mlrs);
        // ExpressLRS: LQ 98 %, uplink -67 dBm, SNR -3 dB.
        let elrs = RadioReport {
            rssi: 249,
            remrssi: 67,
            txbuf: 90,
            noise: (-3i8) as u8,
            remnoise: 0,
            rxerrors: 0,
            fixed: 0,
        };
        m.on_radio(SysComp::new(255, 68), elrs, RadioKind::Elrs);
        let text = render(&[&m]);
        let l = |s: u8| format!(r#"link="sim:",sysid="{s}",compid="68""#);
        has(
            &text,
            &format!("mavping_radio_info{{{},kind=\"mlrs\"}} 1", l(51)),
        );
        has(&text, &format!("mavping_radio_rssi_dbm{{{}}} -85", l(51)));
        has(
            &text,
            &format!("mavping_radio_remote_rssi_dbm{{{}}} -90", l(51)),
        );
        has(&text, &format!("mavping_radio_snr_db{{{}}} 7", l(51)));
        has(
            &text,
            &format!("mavping_radio_link_quality_percent{{{}}} 98", l(255)),
        );
        has(
            &text,
            &format!("mavping_radio_remote_rssi_dbm{{{}}} -67", l(255)),
        );
        has(&text, &format!("mavping_radio_snr_db{{{}}} -3", l(255)));
        // Neither's noise is a noise floor; ExpressLRS's rssi is no dBm.
        assert!(!text.contains("mavping_radio_noise_dbm"), "{text}");
        assert!(
            !text.contains(&format!("mavping_radio_rssi_dbm{{{}}}", l(255))),
            "{text}"
        );
    }

    #[test]
    fn a_runs_links_are_up_until_they_fail_or_never_open() {
        let mut open = Metrics::default();
        open.on_start(&info("udp:a"));
        let mut failed = Metrics::default();
        failed.on_start(&info("udp:b"));
        failed
            .event(&Event::LinkFailed {
                at: 5,
                error: "gone",
            })
            .unwrap();
        let never = Metrics::unopened("udp:c");
        let text = render(&[&open, &failed, &never]);
        has(&text, r#"mavping_link_up{link="udp:a"} 1"#);
        has(&text, r#"mavping_link_up{link="udp:b"} 0"#);
        has(&text, r#"mavping_link_up{link="udp:c"} 0"#);
        // A serve link's restart counter is not a run's.
        assert!(!text.contains("mavping_link_restarts_total"), "{text}");
    }

    #[test]
    fn the_clock_offset_follows_the_replies() {
        use crate::engine::clock_offset::ClockSummary;
        let mut m = Metrics::default();
        m.on_start(&StartInfo {
            probe: ProbeName::Timesync,
            ..info("sim:")
        });
        let id = SysComp::new(1, 1);
        m.on_event(&MatchEvent::Reply {
            responder: id,
            seq: 0,
            rtt: 1_000,
            sent_at: 0,
            at: 1_000,
            out_of_order: false,
            first_from_responder: true,
        });
        let clock = |drift_ppm| ClockSummary {
            offset_ns: 2_000_000_000,
            uncertainty_ns: 500,
            bounds_ns: None,
            bounds_drift_limit_ppm: 200,
            spread_ns: 0.0,
            drift_ppm,
            drift_stderr_ppm: None,
            samples: 1,
        };
        let offset = |m: &Metrics| {
            render(&[m])
                .lines()
                .find_map(|l| {
                    l.strip_prefix("mavping_clock_offset_seconds{")
                        .and_then(|l| l.split_once("} "))
                        .map(|(_, v)| v.parse::<f64>().unwrap())
                })
                .expect("an offset")
        };
        let at = 10_000_000_000;
        m.event(&Event::Clock {
            id,
            at,
            clock: clock(None),
        })
        .unwrap();
        assert_eq!(offset(&m), 2.0);
        // 50 ppm over 10 s: 0.5 ms later.
        m.event(&Event::Clock {
            id,
            at,
            clock: clock(Some(50.0)),
        })
        .unwrap();
        assert!((offset(&m) - 2.0005).abs() < 1e-12);
    }

    #[test]
    fn a_command_target_counts_as_a_responder() {
        use crate::engine::probe::command::CommandEvent;
        let mut m = Metrics::default();
        m.on_start(&StartInfo {
            probe: ProbeName::Command,
            ..info("sim:")
        });
        let target = SysComp::new(1, 1);
        m.on_command(&CommandEvent::Acked {
            n: 0,
            target,
            from: target,
            command: 512,
            result: 0,
            attempts: 2,
            time_to_ack: 3_000_000,
        });
        m.on_command(&CommandEvent::Failed {
            n: 1,
            target,
            command: 512,
            attempts: 4,
        });
        m.on_command(&CommandEvent::DuplicateAck {
            from: target,
            command: 512,
            result: 0,
        });
        let text = render(&[&m]);
        let l = r#"link="sim:",probe="command",sysid="1",compid="1""#;
        has(&text, &format!("mavping_sent_total{{{l}}} 2"));
        has(&text, &format!("mavping_received_total{{{l}}} 1"));
        has(&text, &format!("mavping_lost_total{{{l}}} 1"));
        has(&text, &format!("mavping_duplicate_total{{{l}}} 1"));
        has(
            &text,
            &format!("mavping_rtt_seconds_bucket{{{l},le=\"0.005\"}} 1"),
        );
    }

    #[test]
    fn a_probe_is_written_as_its_own_figures() {
        let mut m = Metrics::default();
        m.on_start(&info("udpout:127.0.0.1:9"));
        let r = SysComp::new(1, 1);
        for seq in 0..4 {
            m.on_event(&MatchEvent::Reply {
                responder: r,
                seq,
                rtt: 2_000_000,
                sent_at: 0,
                at: 0,
                out_of_order: false,
                first_from_responder: seq == 0,
            });
        }
        m.on_event(&MatchEvent::Lost {
            responder: r,
            seq: 4,
            sent_at: 0,
            at: 0,
        });
        let result = ProbeResult {
            success: false,
            duration_s: 1.5,
            reasons: vec!["max_loss", "max_rtt"],
            requests: 5,
            in_flight: 0,
            message: Some("1/1: loss 20.00% is above --max-loss 5.00%\nsecond line".into()),
        };
        let text = render_probe(&m, &result);
        assert!(
            text.starts_with("# mavping: 1/1: loss 20.00% is above --max-loss 5.00% second line\n"),
            "{text}"
        );
        has(&text, "mavping_probe_success 0");
        has(&text, r#"mavping_probe_failure{reason="max_loss"} 1"#);
        has(&text, r#"mavping_probe_failure{reason="max_rtt"} 1"#);
        has(&text, "mavping_probe_duration_seconds 1.5");
        has(&text, "mavping_probe_requests 5");
        let l = r#"link="udpout:127.0.0.1:9",probe="ping",sysid="1",compid="1""#;
        has(&text, "# TYPE mavping_probe_sent gauge");
        has(&text, &format!("mavping_probe_sent{{{l}}} 5"));
        has(&text, &format!("mavping_probe_lost{{{l}}} 1"));
        has(&text, &format!("mavping_probe_loss_ratio{{{l}}} 0.2"));
        has(&text, &format!("mavping_probe_rtt_seconds_count{{{l}}} 4"));
        assert!(!text.contains("_total"), "{text}");
        assert!(!text.contains("mavping_rtt_seconds"), "{text}");
        // A probe that succeeded names no reason and no message.
        let ok = render_probe(
            &m,
            &ProbeResult {
                success: true,
                reasons: vec![],
                message: None,
                ..result
            },
        );
        assert!(ok.starts_with("# HELP mavping_probe_success"), "{ok}");
        assert!(!ok.contains("mavping_probe_failure"), "{ok}");
    }

    #[test]
    fn the_server_shows_its_health_and_its_links_state() {
        let mut up = Metrics::continuous("radio", ProbeName::Ping);
        up.set_up(true);
        let mut down = Metrics::continuous("gcs \"2\"", ProbeName::Timesync);
        down.restarted();
        down.restarted();
        let health = Health {
            probes: 7,
            probes_failed: 2,
            probes_refused: 1,
            probes_running: 1,
            open_links: 2,
            reloads: 1,
            reloads_failed: 1,
            last_reload_ok: false,
        };
        let text = render_serve(&[&up, &down], &health);
        for line in [
            "mavping_exporter_probes_total 7",
            "mavping_exporter_probes_failed_total 2",
            "mavping_exporter_probes_refused_total 1",
            "mavping_exporter_probes_running 1",
            "mavping_exporter_open_links 2",
            "mavping_exporter_config_reloads_total 1",
            "mavping_exporter_config_reloads_failed_total 1",
            "mavping_exporter_config_last_reload_successful 0",
            r#"mavping_link_up{link="radio"} 1"#,
            r#"mavping_link_up{link="gcs \"2\""} 0"#,
            r#"mavping_link_restarts_total{link="radio"} 0"#,
            r#"mavping_link_restarts_total{link="gcs \"2\""} 2"#,
        ] {
            has(&text, line);
        }
        // A link that has not started has no state to show.
        assert!(!render(&[&Metrics::default()]).contains("mavping_link_up"));
    }
}
