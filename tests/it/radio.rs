//! RADIO_STATUS from a radio injecting into the stream (pymavlink, 51/68)
//! beside a PING responder: the figures and counter deltas are exact. And
//! each kind of radio as it sends (tests/peers/radio_peer.py: SiK, mLRS
//! with its HEARTBEAT, ExpressLRS from 255/68 at 100 Hz, an ESP8266
//! bridge from compid 240, RADIO (166)): mavping names the kind and gives
//! back exactly the figures the peer encoded, on that kind's scale.

use crate::common::*;

#[test]
fn radio_figures_and_counter_deltas_are_exact() {
    let port = free_udp_port();
    // rssi,remrssi,txbuf,noise,remnoise,rxerrors,fixed. rssi 255 is
    // unknown; rxerrors wraps 65 530 → 3 (65 530, 65 534, 3, 10: +4 +5 +7).
    let schedule = "200,150,90,40,60,65530,100;\
                    190,140,80,50,60,65534,100;\
                    255,130,255,50,255,3,101;\
                    180,120,20,60,70,10,101";
    let peer = Peer::start(
        "responder.py",
        &[
            &format!("udpout:127.0.0.1:{port}"),
            "--radio-status",
            schedule,
        ],
    );
    let (code, out, err) = run_mavping(&[
        "-c",
        "4",
        "-i",
        "0.1",
        "-W",
        "2s",
        "--json",
        &format!("udpin:127.0.0.1:{port}"),
    ]);
    assert_eq!(code, 0, "{out}\n{err}");
    let lines: Vec<serde_json::Value> = out
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    // One radio event: the first report only.
    let events: Vec<_> = lines.iter().filter(|v| v["type"] == "radio").collect();
    assert_eq!(events.len(), 1, "{out}");
    assert_eq!(events[0]["responder"]["sysid"], 51);
    assert_eq!(events[0]["status"]["rxerrors"], 65530);
    let s = lines.iter().find(|v| v["type"] == "summary").expect(&out);
    let radios = s["radios"].as_array().unwrap();
    assert_eq!(radios.len(), 1, "{s}");
    let r = &radios[0];
    assert_eq!(
        (&r["id"]["sysid"], &r["id"]["compid"]),
        (&51.into(), &68.into())
    );
    assert_eq!(r["reports"], 4);
    let range = |k: &str| {
        let v = &r[k];
        (
            v["min"].as_f64().unwrap(),
            v["mean"].as_f64().unwrap(),
            v["max"].as_f64().unwrap(),
            v["samples"].as_u64().unwrap(),
        )
    };
    assert_eq!(range("rssi"), (180.0, 190.0, 200.0, 3));
    assert_eq!(range("remrssi"), (120.0, 135.0, 150.0, 4));
    assert_eq!(range("noise"), (40.0, 50.0, 60.0, 4));
    assert_eq!(range("remnoise"), (60.0, 190.0 / 3.0, 70.0, 3));
    // 160, 140, 120: the third report has no rssi.
    assert_eq!(range("fade_margin"), (120.0, 140.0, 160.0, 3));
    // 90, 80, 50: the third report has no remnoise.
    assert_eq!(range("remote_fade_margin"), (50.0, 220.0 / 3.0, 90.0, 3));
    assert_eq!(range("txbuf"), (20.0, 190.0 / 3.0, 90.0, 3));
    assert_eq!(r["rxerrors_delta"], 16);
    assert_eq!(r["fixed_delta"], 1);
    let dbm = r["approx_dbm"]["rssi"]["max"].as_f64().unwrap();
    assert!((dbm - (200.0 / 1.9 - 127.0)).abs() < 1e-9, "{r}");
    assert_eq!(r["latest"]["rxerrors"], 10);
    // The radio is no responder and gets no "never answered" hint; the
    // counters grew, so that hint is there.
    let responders = s["responders"].as_array().unwrap();
    assert_eq!(responders.len(), 1, "{s}");
    assert_eq!(responders[0]["responder"]["sysid"], 1);
    assert_eq!(responders[0]["received"], 4);
    let hints: Vec<&str> = s["hints"]
        .as_array()
        .unwrap()
        .iter()
        .map(|h| h["text"].as_str().unwrap())
        .collect();
    assert!(
        !hints.iter().any(|h| h.contains("never answered")),
        "{hints:?}"
    );
    assert!(
        hints.contains(&"radio 51/68: rxerrors grew by 16 during the run: interference or range"),
        "{hints:?}"
    );
    assert_eq!(peer.finish()["radio_status"], 4);
}

#[test]
fn text_output_has_the_radio_block_and_annotated_replies() {
    let port = free_udp_port();
    let _peer = Peer::start(
        "responder.py",
        &[
            &format!("udpout:127.0.0.1:{port}"),
            "--radio-status",
            "200,150,90,40,60,7,0;200,150,90,40,60,9,0",
        ],
    );
    let (code, out, err) = run_mavping(&[
        "-c",
        "2",
        "-i",
        "0.1",
        "-W",
        "2s",
        &format!("udpin:127.0.0.1:{port}"),
    ]);
    assert_eq!(code, 0, "{out}\n{err}");
    assert!(
        out.contains("heard radio 51/68: rssi=200 remrssi=150 txbuf=90%, noise=40 remnoise=60"),
        "{out}"
    );
    // The first reply after a report carries it (how often later ones do
    // is the text reporter's unit test, with explicit times).
    assert!(
        out.lines().any(|l| l.contains("seq=0 time=")
            && l.ends_with("[radio 51/68 rssi=200 remrssi=150 txbuf=90%]")),
        "{out}"
    );
    // The block names the radio's kind and why (the counts moved under it).
    assert!(
        out.contains(
            "radio 51/68: SiK (compid 68 and no HEARTBEAT from 51/68)\n  \
             2 reports, rxerrors +2, fixed +0 during the run"
        ),
        "{out}"
    );
    assert!(
        out.contains("  rssi               min/mean/max = 200/200.0/200"),
        "{out}"
    );
    assert!(out.contains("(approximate, SiK scale)"), "{out}");
}

/// `sim:?baud=`: wire time and a bounded radio buffer, on the virtual clock.
fn sim_run(interval: &str) -> serde_json::Value {
    let (code, out, err) = run_mavping(&[
        "-c",
        "200",
        "-i",
        interval,
        "-W",
        "2s",
        "--json",
        "-q",
        "sim:?baud=57600&delay=0&jitter=0&heartbeat=off&clock=virtual&radio=on",
    ]);
    assert!(code == 0 || code == 1, "{out}\n{err}");
    let mut s: serde_json::Value = serde_json::from_str(out.trim()).unwrap();
    s["stderr"] = err.into();
    s
}

#[test]
fn sim_baud_queues_and_loses_where_the_arithmetic_says() {
    // 57600 baud = 5760 bytes/s; request 21 B + reply 26 B = 47 B per
    // exchange: 8.1597 ms of wire each, at most 122.55 exchanges/s.
    let floor_ms = 47.0 / 5760.0 * 1e3;

    // Our own HEARTBEAT (21 B, once a second) shares the wire too.
    let heartbeat_ms = 21.0 / 5760.0 * 1e3;

    // 100/s: the wire keeps up; an RTT is the wire time alone, or that
    // plus a HEARTBEAT ahead of it in the queue.
    let below = sim_run("0.01");
    assert!(!below["stderr"].as_str().unwrap().contains("warning"));
    let r = &below["responders"][0];
    assert_eq!(
        (r["received"].as_u64(), r["lost"].as_u64()),
        (Some(200), Some(0)),
        "{below}"
    );
    let p50_ms = r["rtt_us"]["p50"].as_f64().unwrap() / 1e3;
    assert!((p50_ms - floor_ms).abs() < 0.001, "{p50_ms} vs {floor_ms}");
    let max_ms = r["rtt_us"]["max"].as_f64().unwrap() / 1e3;
    assert!(max_ms <= floor_ms + heartbeat_ms + 0.001, "{max_ms}");
    assert_eq!(below["wire"]["request_bytes"], 21);
    assert_eq!(below["wire"]["reply_bytes"], 26);

    // 200/s: each request adds 47 - 28.8 = 18.2 B to the backlog, so the
    // 1024 B buffer fills after 1024 / 18.2 = 56 requests and drops from
    // then on; the RTT climbs with the queue meanwhile. Delivered: what the
    // wire carries while sending (122.55/s over the 0.995 s between the
    // first and last request) plus what the full buffer still held
    // (1024 / 47 = 21.8): 143.7.
    let above = sim_run("0.005");
    assert!(
        above["stderr"]
            .as_str()
            .unwrap()
            .contains("at 57600 baud this link carries at most ~122 PINGs/s each way; 200/s"),
        "{above}"
    );
    let r = &above["responders"][0];
    let received = r["received"].as_u64().unwrap();
    assert!((143..=145).contains(&received), "{above}");
    assert_eq!(r["lost"].as_u64().unwrap(), 200 - received);
    let rtt = &r["rtt_us"];
    // The first exchange queues behind our first HEARTBEAT only.
    let min_ms = rtt["min"].as_f64().unwrap() / 1e3;
    assert!(min_ms <= floor_ms + heartbeat_ms + 0.001, "{above}");
    // A full buffer's worth of queueing on top of the wire time.
    let max_ms = rtt["max"].as_f64().unwrap() / 1e3;
    let full_ms = 1024.0 / 5760.0 * 1e3;
    assert!(
        max_ms > full_ms && max_ms < full_ms + 2.0 * floor_ms,
        "{max_ms}"
    );
    // The simulated radio counts the drops and shows its buffer filling.
    let radio = &above["radios"][0];
    assert_eq!(radio["rxerrors_delta"].as_u64().unwrap(), 200 - received);
    assert_eq!(radio["txbuf"]["min"].as_f64(), Some(0.0), "{radio}");
    let hints = above["hints"].to_string();
    assert!(
        hints.contains("200/s will queue and then lose: this run did"),
        "{hints}"
    );
}

/// `mavping --passive -q` over udpout to a radio_peer of `kind` sending
/// `count` reports: the summary (JSON with `--json`) and the peer's truth.
fn radio_run(kind: &str, count: usize, extra: &[&str]) -> (String, serde_json::Value) {
    let mut args = vec!["-q"];
    args.extend_from_slice(extra);
    run_radio(kind, count, &[], &args)
}

/// `mavping --passive ARGS` over udpout to a radio_peer of `kind` (with
/// `peer_args`) sending `count` reports: its output and the peer's truth.
fn run_radio(
    kind: &str,
    count: usize,
    peer_args: &[&str],
    args: &[&str],
) -> (String, serde_json::Value) {
    let port = free_udp_port();
    let count = count.to_string();
    let listen = format!("udpin:127.0.0.1:{port}");
    let mut peer = vec![listen.as_str(), "--kind", kind, "--count", &count];
    peer.extend_from_slice(peer_args);
    let peer = Peer::start("radio_peer.py", &peer);
    let link = format!("udpout:127.0.0.1:{port}");
    let mut all = vec!["--passive", "-w", "3.5s"];
    all.extend_from_slice(args);
    all.push(&link);
    let (code, out, err) = run_mavping(&all);
    assert!(code == 0 || code == 1, "{out}\n{err}");
    (out, peer.finish())
}

/// The one radio of a `--json` run's summary, and the peer's truth.
fn radio_summary(
    kind: &str,
    count: usize,
    extra: &[&str],
) -> (serde_json::Value, serde_json::Value) {
    let mut args = vec!["--json"];
    args.extend_from_slice(extra);
    let (out, truth) = radio_run(kind, count, &args);
    let s: serde_json::Value = serde_json::from_str(out.trim()).expect(&out);
    let radios = s["radios"].as_array().expect(&out);
    assert_eq!(radios.len(), 1, "{out}");
    (radios[0].clone(), truth)
}

/// min/mean/max of what the peer encoded under `key`.
fn encoded(truth: &serde_json::Value, key: &str) -> (f64, f64, f64) {
    let v: Vec<f64> = truth["encoded"]
        .as_array()
        .unwrap()
        .iter()
        .map(|e| e[key].as_f64().unwrap())
        .collect();
    let min = v.iter().copied().fold(f64::INFINITY, f64::min);
    let max = v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    (min, v.iter().sum::<f64>() / v.len() as f64, max)
}

/// The radio is `kind`, counted every report, and its `converted` figures
/// are exactly (to float rounding) what the peer encoded: those keys and
/// no others.
fn converts_exactly(r: &serde_json::Value, truth: &serde_json::Value, kind: &str) {
    assert_eq!(r["kind"], kind, "{r}");
    assert_eq!(r["radio_type"], "auto", "{r}");
    assert_eq!(r["reports"], truth["reports"], "{r}");
    assert_eq!(
        (r["id"]["sysid"].clone(), r["id"]["compid"].clone()),
        (truth["id"][0].clone(), truth["id"][1].clone())
    );
    let converted = r["converted"].as_object().unwrap();
    let mut keys: Vec<&String> = converted.keys().collect();
    keys.sort();
    let mut want: Vec<&String> = truth["encoded"][0].as_object().unwrap().keys().collect();
    want.sort();
    assert_eq!(keys, want, "{r}");
    for key in want {
        let got = &converted[key];
        let (min, mean, max) = encoded(truth, key);
        for (name, w) in [("min", min), ("mean", mean), ("max", max)] {
            let g = got[name].as_f64().unwrap();
            assert!(
                (g - w).abs() < 1e-9,
                "{key} {name}: {g} vs {w} encoded\n{r}"
            );
        }
    }
}

#[test]
fn a_sik_radio_in_dbm_with_fade_margins() {
    let (r, truth) = radio_summary("sik", 5, &[]);
    converts_exactly(&r, &truth, "sik");
    assert_eq!(r["evidence"][0], "compid 68 and no HEARTBEAT from 51/68");
    // Its noise is a noise floor: a fade margin, raw and in dB.
    assert!(
        r["fade_margin"].is_object() && r["approx_dbm"].is_object(),
        "{r}"
    );
    // rxerrors +3 a report, fixed +1: counters.
    assert_eq!(r["rxerrors_delta"], 12);
    assert_eq!(r["fixed_delta"], 4);
}

#[test]
fn mlrs_by_its_heartbeat_on_its_own_scale_without_fade_margin() {
    let (r, truth) = radio_summary("mlrs", 5, &[]);
    converts_exactly(&r, &truth, "mlrs");
    assert_eq!(
        r["evidence"],
        serde_json::json!([
            "HEARTBEAT type GENERIC, autopilot INVALID from 51/68",
            "remnoise always 255",
            "rxerrors and fixed always 0"
        ])
    );
    // Its noise is 10 - SNR, no noise floor: no fade margin anywhere.
    assert!(
        r["fade_margin"].is_null() && r["remote_fade_margin"].is_null(),
        "{r}"
    );
    assert!(r["approx_dbm"].is_null(), "{r}");
}

#[test]
fn mlrs_text_names_the_kind_and_why() {
    let (out, _) = radio_run("mlrs", 3, &[]);
    assert!(
        out.contains(
            "radio 51/68: mLRS (HEARTBEAT type GENERIC, autopilot INVALID from 51/68; \
             remnoise always 255; rxerrors and fixed always 0)\n  3 reports\n"
        ),
        "{out}"
    );
    assert!(
        out.contains("  rssi               -101.0/-82.0/-60.0 dBm (mLRS scale"),
        "{out}"
    );
    assert!(!out.contains("fade margin"), "{out}");
}

#[test]
fn elrs_from_255_68_at_100_hz_in_link_quality_uplink_dbm_and_snr() {
    let (r, truth) = radio_summary("elrs", 100, &[]);
    converts_exactly(&r, &truth, "elrs");
    let evidence: Vec<&str> = r["evidence"]
        .as_array()
        .unwrap()
        .iter()
        .map(|e| e.as_str().unwrap())
        .collect();
    // The rate is the evidence: ~100 reports/s, not a SiK's 1.
    let rate: f64 = evidence[0]
        .trim_start_matches('~')
        .trim_end_matches(" reports/s")
        .parse()
        .unwrap_or_else(|_| panic!("{evidence:?}"));
    assert!(rate >= 20.0, "{evidence:?}");
    assert_eq!(evidence[1], "255/68, an ExpressLRS receiver's default ids");
    assert!(r["fade_margin"].is_null(), "{r}");
}

#[test]
fn an_esp8266_bridge_from_compid_240_reports_losses() {
    let (r, truth) = radio_summary("esp", 5, &[]);
    converts_exactly(&r, &truth, "esp");
    assert!(
        r["evidence"][0].as_str().unwrap().starts_with("compid 240"),
        "{r}"
    );
    assert!(r["fade_margin"].is_null(), "{r}");
}

#[test]
fn radio_166_beside_radio_status_counts_once() {
    let (r, truth) = radio_summary("sik-pairs", 5, &[]);
    // Ten messages, five reports: the means are of five.
    assert_eq!(truth["messages"], 10);
    converts_exactly(&r, &truth, "sik");
    assert_eq!(r["rssi"]["samples"], 5);
    assert!(
        r["evidence"]
            .to_string()
            .contains("RADIO (166) beside each RADIO_STATUS"),
        "{r}"
    );
    // RADIO alone (SiK before 2013, openLRSng) reads the same.
    let (r, truth) = radio_summary("radio-only", 5, &[]);
    converts_exactly(&r, &truth, "sik");
    assert!(
        r["evidence"].to_string().contains("RADIO (166) only"),
        "{r}"
    );
}

#[test]
fn radio_type_overrides_what_the_radio_sends() {
    // An mLRS read as a SiK: SiK's dBm formula on mLRS's bytes, a fade
    // margin from its SNR field; the evidence is the option.
    let (r, truth) = radio_summary("mlrs", 3, &["--radio-type", "sik"]);
    assert_eq!(
        (r["kind"].as_str(), r["radio_type"].as_str()),
        (Some("sik"), Some("sik"))
    );
    assert_eq!(r["evidence"], serde_json::json!(["--radio-type sik"]));
    let raw: Vec<f64> = truth["raw"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x["rssi"].as_f64().unwrap())
        .collect();
    let want = raw.iter().sum::<f64>() / raw.len() as f64 / 1.9 - 127.0;
    let got = r["converted"]["rssi_dbm"]["mean"].as_f64().unwrap();
    assert!((got - want).abs() < 1e-9, "{got} vs {want}");
    assert!(r["fade_margin"].is_object(), "{r}");
    // raw: the figures as sent, nothing converted.
    let (r, _) = radio_summary("sik", 3, &["--radio-type", "raw"]);
    assert_eq!(r["kind"], "unknown");
    assert_eq!(r["converted"], serde_json::json!({}));
    assert!(r["fade_margin"].is_null() && r["rssi"].is_object(), "{r}");
}

/// mLRS's HEARTBEAT after its first report: read as a SiK until it comes,
/// then as mLRS, and the JSON says so as it happens.
#[test]
fn a_late_heartbeat_changes_the_kind_as_the_run_goes() {
    let (out, _) = run_radio("mlrs", 3, &["--late-heartbeat"], &["--json"]);
    let events: Vec<serde_json::Value> = out
        .lines()
        .map(|l| serde_json::from_str::<serde_json::Value>(l).unwrap())
        .filter(|v| v["type"] == "radio")
        .collect();
    let told: Vec<(&str, bool)> = events
        .iter()
        .map(|e| (e["kind"].as_str().unwrap(), e["first"].as_bool().unwrap()))
        .collect();
    assert_eq!(told, [("sik", true), ("mlrs", false)], "{out}");
    assert_eq!(
        events[1]["evidence"][0],
        "HEARTBEAT type GENERIC, autopilot INVALID from 51/68"
    );
    // Every report in the summary, read as mLRS.
    let summary: serde_json::Value = serde_json::from_str(out.lines().last().unwrap()).unwrap();
    assert_eq!(summary["radios"][0]["kind"], "mlrs");
    assert_eq!(summary["radios"][0]["reports"], 3);
}
