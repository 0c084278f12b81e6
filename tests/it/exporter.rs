//! `--prometheus` beyond the counts: each radio's latest RADIO_STATUS (dBm
//! and error counters that only grow), a link-up gauge per link, and a
//! TIMESYNC clock offset that follows the run instead of waiting for its
//! end. Scraped over HTTP from real pymavlink peers, checked by promtool.

use crate::common::{assert_promtool_clean, free_tcp_port, sample, Exporting, Peer};

#[test]
fn radios_and_link_state_are_exported_as_a_run_goes_on() {
    let (radio_port, gone_port, closed_port) = (free_tcp_port(), free_tcp_port(), free_tcp_port());
    // rxerrors wrap (65 530 → 5) and fixed grows by 2; the last report
    // (rssi 190, remrssi 171) stays.
    let schedule = "100,120,90,40,255,65500,7;150,140,80,41,255,65530,7;\
                    190,171,70,42,255,5,9;190,171,70,42,255,20,9";
    let radio_link = format!("tcpin:127.0.0.1:{radio_port}");
    let gone_link = format!("tcpin:127.0.0.1:{gone_port}");
    let _radio = Peer::start("responder.py", &[&radio_link, "--radio-status", schedule]);
    let mut gone = Peer::start("responder.py", &[&gone_link, "--sysid", "2"]);
    let (a, b) = (
        format!("tcp:127.0.0.1:{radio_port}"),
        format!("tcp:127.0.0.1:{gone_port}"),
    );
    // Nothing listens on the third: it is never opened.
    let never = format!("tcp:127.0.0.1:{closed_port}");
    let mut run = Exporting::start(&["-i", "0.05", "-W", "500ms", &a, &b, &never]);

    let radio = [("link", a.as_str()), ("sysid", "51"), ("compid", "68")];
    let body = run.scrape_until("four radio reports and both links answering", |m| {
        sample(m, "mavping_radio_rxerrors_total", &radio) == Some(56.0)
            && sample(m, "mavping_received_total", &[("link", &b)]).is_some_and(|v| v > 0.0)
    });
    assert_promtool_clean(&body);
    assert!(body.contains("# TYPE mavping_radio_rxerrors_total counter"));
    // 30 + 11 through the wrap + 15; 7 → 9.
    assert_eq!(
        sample(&body, "mavping_radio_fixed_total", &radio),
        Some(2.0)
    );
    assert_eq!(sample(&body, "mavping_radio_rssi", &radio), Some(190.0));
    let dbm = |name| sample(&body, name, &radio).unwrap();
    assert!((dbm("mavping_radio_rssi_dbm") - (190.0 / 1.9 - 127.0)).abs() < 1e-9);
    assert!((dbm("mavping_radio_remote_rssi_dbm") - (171.0 / 1.9 - 127.0)).abs() < 1e-9);
    assert!((dbm("mavping_radio_noise_dbm") - (42.0 / 1.9 - 127.0)).abs() < 1e-9);
    // 255 is "unknown": no remote noise at all.
    assert_eq!(
        sample(&body, "mavping_radio_remote_noise_dbm", &radio),
        None
    );
    for link in [&a, &b] {
        assert_eq!(
            sample(&body, "mavping_link_up", &[("link", link)]),
            Some(1.0)
        );
    }

    // The second link's peer goes away: that link is down, the first
    // goes on measuring.
    gone.kill();
    let body = run.scrape_until("the second link down", |m| {
        sample(m, "mavping_link_up", &[("link", &b)]) == Some(0.0)
    });
    assert_eq!(sample(&body, "mavping_link_up", &[("link", &a)]), Some(1.0));
    let sent = sample(&body, "mavping_sent_total", &[("link", &a)]).unwrap();
    run.scrape_until("the first link still measuring", |m| {
        sample(m, "mavping_sent_total", &[("link", &a)]).is_some_and(|v| v > sent + 5.0)
    });
    assert!(run.running());
}

#[test]
fn the_clock_offset_is_exported_while_the_run_goes_on() {
    let port = free_tcp_port();
    let listen = format!("tcpin:127.0.0.1:{port}");
    // A TIMESYNC clock 2.5 s ahead of the wall clock.
    let peer = Peer::start(
        "ardupilot_like.py",
        &[&listen, "--clock", "unix", "--offset-s", "2.5"],
    );
    let link = format!("tcp:127.0.0.1:{port}");
    let mut run = Exporting::start(&["--probe", "timesync", "-i", "0.05", &link]);
    let offset = |m: &str| sample(m, "mavping_clock_offset_seconds", &[("link", &link)]);
    let body = run.scrape_until("a clock offset", |m| offset(m).is_some());
    let first = offset(&body).unwrap();
    assert!((first - 2.5).abs() < 0.05, "offset {first} s, truth 2.5 s");
    assert!(run.running(), "the offset came only with the end");
    // Updated again while the run goes on: the value is re-estimated from
    // later replies (it moves by nanoseconds, so compare the text).
    let later = run.scrape_until("a later estimate", |m| {
        offset(m).is_some_and(|v| v.to_bits() != first.to_bits())
    });
    assert!((offset(&later).unwrap() - 2.5).abs() < 0.05, "{later}");
    assert!(run.running());
    assert_promtool_clean(&later);
    drop(peer);
}
