//! One `/probe?target=...`: the request checked against the configuration
//! (a 400 with one line when it is bad or forbidden), then the target
//! opened and measured by the one run path within the time the scrape
//! allows, judged by the module's thresholds, and answered with that
//! probe's metrics. A probe that fails is an answer too:
//! `mavping_probe_success 0` and `mavping_probe_failure{reason=...}`.
//!
//! With `debug=true` the answer is the probe's own log instead, as the
//! blackbox exporter gives it: what was asked, each request and reply as
//! `mavping` prints them, the summary, why it failed, and the metrics a
//! scrape would have had. For a person at a browser, not for Prometheus.

use std::time::{Duration, Instant};

use crate::engine::session::Controls;
use hyper::header::HeaderMap;
use hyper::StatusCode;
use thiserror::Error;

use super::server::Server;
use crate::engine::hint::HintCode;
use crate::engine::summary::{EchoSummary, LinkSummary};
use crate::http::Reply;
use crate::output::prometheus::{render_probe, ProbeResult, SharedMetrics};
use crate::output::text::TextReporter;
use crate::output::{Fanout, Reporter, Shared, WallClock};
use crate::run::one_link::measure;
use crate::transport::Link;
use crate::verdict::{self, Check};

/// Prometheus's own default scrape timeout, for a request that names none.
const DEFAULT_SCRAPE_TIMEOUT_S: f64 = 10.0;
/// The longest a probe may run whatever the scrape says.
const MAX_SCRAPE_TIMEOUT_S: f64 = 300.0;
/// Left of the scrape's timeout for the answer to reach Prometheus.
const MARGIN_S: f64 = 0.5;

/// How long a probe may take: the scrape's timeout
/// (`X-Prometheus-Scrape-Timeout-Seconds`) less a margin (at most a
/// quarter of it).
pub(super) fn budget(headers: &HeaderMap) -> Duration {
    let timeout = headers
        .get("x-prometheus-scrape-timeout-seconds")
        .and_then(|v| v.to_str().ok())
        .and_then(|v| v.trim().parse::<f64>().ok())
        .filter(|t| t.is_finite() && *t > 0.0)
        .unwrap_or(DEFAULT_SCRAPE_TIMEOUT_S)
        .min(MAX_SCRAPE_TIMEOUT_S);
    Duration::from_secs_f64(timeout - MARGIN_S.min(timeout / 4.0))
}

/// Keeps the health counters right however the probe ends, the client
/// hanging up (which drops the probe) included.
struct Running<'a> {
    server: &'a Server,
    link_open: bool,
}

impl Drop for Running<'_> {
    fn drop(&mut self) {
        self.server.health(|h| {
            h.probes_running -= 1;
            if self.link_open {
                h.open_links -= 1;
            }
        });
    }
}

/// A `debug=` that is neither true nor false.
#[derive(Debug, Error)]
#[error("debug '{0}': expected true or false")]
struct BadDebugFlag(String);

/// `debug=true` taken out of the query (the rest is the probe's).
fn debug_flag(query: &str) -> (String, Result<bool, BadDebugFlag>) {
    let mut rest = form_urlencoded::Serializer::new(String::new());
    let mut debug = Ok(false);
    for (key, value) in form_urlencoded::parse(query.as_bytes()) {
        if key == "debug" {
            debug = match &*value {
                "true" | "1" => Ok(true),
                "false" | "0" | "" => Ok(false),
                other => Err(BadDebugFlag(other.to_string())),
            };
        } else {
            rest.append_pair(&key, &value);
        }
    }
    (rest.finish(), debug)
}

/// Answers one `/probe` request.
pub(super) async fn answer(server: &Server, query: &str, headers: &HeaderMap) -> Reply {
    let started = Instant::now();
    let settings = server.settings();
    let (query, debug) = debug_flag(query);
    let debug = match debug {
        Ok(debug) => debug,
        Err(line) => {
            server.health(|h| h.probes_refused += 1);
            return Reply::text(StatusCode::BAD_REQUEST, format!("{line}\n"));
        }
    };
    let query = query.as_str();
    let plan = match settings.plan(query) {
        Ok(plan) => plan,
        Err(line) => {
            server.health(|h| h.probes_refused += 1);
            return Reply::text(StatusCode::BAD_REQUEST, format!("{line}\n"));
        }
    };
    let Ok(_slot) = server.slots().try_acquire_owned() else {
        server.health(|h| h.probes_refused += 1);
        return Reply::text(
            StatusCode::SERVICE_UNAVAILABLE,
            format!(
                "too many probes at once: max_concurrent is {}; try again\n",
                settings.max_concurrent
            ),
        );
    };
    server.health(|h| {
        h.probes += 1;
        h.probes_running += 1;
    });
    let mut running = Running {
        server,
        link_open: false,
    };
    let budget = budget(headers);
    let metrics = SharedMetrics::default();
    let log = Shared::new(Vec::new());
    let result = match tokio::time::timeout(budget, Link::open(&plan.link.spec, &plan.options))
        .await
    {
        Err(_) => failed(
            started,
            "open_failed",
            format!(
                "opening {} took longer than the scrape allows ({})",
                plan.link.name,
                humantime::format_duration(budget)
            ),
        ),
        Ok(Err(e)) => failed(started, "open_failed", e.to_string()),
        Ok(Ok(link)) => {
            running.link_open = true;
            server.health(|h| h.open_links += 1);
            let mut config = plan.link.clone();
            // The session stops when the scrape's time is up, whatever is
            // still in flight.
            config.session.deadline = Some(budget.saturating_sub(started.elapsed()));
            let wall = WallClock::starting(false);
            let never = Controls::default();
            let mut observers: Vec<Box<dyn Reporter>> = vec![Box::new(metrics.clone())];
            if debug {
                observers.push(Box::new(TextReporter::new(log.clone(), false)));
            }
            let mut observer = Fanout::new(observers);
            let outcome = measure(&config, link, &plan.probe, wall, &mut observer, &never).await;
            let verdict = verdict::judge_link(&outcome.summary, &plan.link.thresholds);
            let _ = observer.summary(&outcome.summary, &verdict);
            judged(started, &outcome.summary, &verdict)
        }
    };
    drop(running);
    if !result.success {
        server.health(|h| h.probes_failed += 1);
    }
    let exposition = render_probe(&metrics.get(), &result);
    if debug {
        let log = String::from_utf8_lossy(&log.0.borrow()).into_owned();
        return Reply::text(
            StatusCode::OK,
            debug_text(&plan, budget, &log, &result, &exposition),
        );
    }
    Reply::metrics(exposition)
}

/// The blackbox exporter's debug page, for mavping's probe.
fn debug_text(
    plan: &crate::config::ProbePlan,
    budget: Duration,
    log: &str,
    result: &ProbeResult,
    exposition: &str,
) -> String {
    let s = &plan.link.session;
    let mut out = format!(
        "Probe of {} with module {}: {} {} requests, every {}, each answered within {}; the \
         scrape allows {}\n\n",
        plan.link.name,
        plan.module,
        s.count.unwrap_or(0),
        plan.probe.name(),
        humantime::format_duration(s.interval),
        humantime::format_duration(s.timeout),
        humantime::format_duration(budget),
    );
    out.push_str("Logs for the probe:\n");
    if log.is_empty() {
        out.push_str("(nothing measured: the link did not open)\n");
    } else {
        out.push_str(log);
    }
    out.push_str(&format!(
        "\nResult: {}",
        if result.success { "success" } else { "failure" }
    ));
    if !result.reasons.is_empty() {
        out.push_str(&format!(" ({})", result.reasons.join(", ")));
    }
    if let Some(m) = &result.message {
        out.push_str(&format!(": {m}"));
    }
    out.push_str("\n\n\nMetrics that would have been returned:\n");
    out.push_str(exposition);
    out
}

fn failed(started: Instant, reason: &'static str, message: String) -> ProbeResult {
    ProbeResult {
        success: false,
        duration_s: started.elapsed().as_secs_f64(),
        reasons: vec![reason],
        requests: 0,
        in_flight: 0,
        message: Some(message),
    }
}

/// A measured probe's result: success is the verdict's; each broken check
/// is a reason.
fn judged(started: Instant, summary: &LinkSummary, verdict: &verdict::Verdict) -> ProbeResult {
    let mut reasons = Vec::new();
    if summary.link_error().is_some() {
        reasons.push("link_failed");
    }
    let no_peer = no_peer_heard(summary);
    if no_peer.is_some() {
        reasons.push("nothing_heard");
    }
    for f in &verdict.failures {
        let reason = match f.check {
            Check::Reply => "no_reply",
            Check::Heard => "nothing_heard",
            Check::Ack => "no_ack",
            Check::MaxLoss => "max_loss",
            Check::MaxRtt => "max_rtt",
            Check::MaxJitter => "max_jitter",
            Check::MaxAge => "max_age",
            Check::Expect => "expect",
            Check::MinResponders => "min_responders",
            Check::Transfer => "transfer_incomplete",
            Check::MaxTransferTime => "max_transfer_time",
            Check::MinAvailability => "min_availability",
            Check::MinContinuity => "min_continuity",
        };
        if !reasons.contains(&reason) {
            reasons.push(reason);
        }
    }
    let (requests, in_flight) = summary.requests();
    let message = summary
        .link_error()
        .or(no_peer)
        .map(str::to_string)
        .or_else(|| verdict.failures.first().map(|f| f.message.clone()));
    ProbeResult {
        success: verdict.ok(),
        duration_s: started.elapsed().as_secs_f64(),
        reasons,
        requests,
        in_flight,
        message,
    }
}

/// What a listening link that heard no peer within its count's time says
/// ("no MAVLink system heard on udpin:... in 1.1 s").
fn no_peer_heard(summary: &LinkSummary) -> Option<&str> {
    summary
        .get::<EchoSummary>()?
        .hints
        .iter()
        .find(|h| h.code == HintCode::NoPeerHeard)
        .map(|h| h.text.as_str())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_budget_follows_the_scrape_timeout() {
        let mut h = HeaderMap::new();
        assert_eq!(budget(&h), Duration::from_millis(9_500));
        for (header, ms) in [
            ("10", 9_500),
            ("2.000000", 1_500),
            ("1", 750),
            ("0.2", 150),
            ("1e9", 299_500),
            ("-1", 9_500),
            ("soon", 9_500),
        ] {
            h.insert(
                "x-prometheus-scrape-timeout-seconds",
                header.parse().unwrap(),
            );
            assert_eq!(budget(&h), Duration::from_millis(ms), "{header}");
        }
    }
}
