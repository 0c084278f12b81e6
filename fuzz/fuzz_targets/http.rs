//! Arbitrary bytes as one client connection to mavping's HTTP server
//! (src/output/http.rs, with its limits), answered by the real handlers:
//! `mavping serve`'s (`/probe` queries planned against an allow list whose
//! only targets are serial devices that do not exist, so a probe that
//! passes every check fails to open at once; `/metrics`) or
//! `--prometheus`'s (`/metrics` of a link with a few replies).
//! Invariants: no panic, an answer in bounded time, and the bytes sent
//! back are nothing or exactly one well-formed HTTP/1.x response whose
//! body is as long as its content-length says (or empty, for HEAD).
//!
//! Input: the first byte picks the server (even: serve, odd:
//! --prometheus); the rest is what the client sends before it closes its
//! side.
#![no_main]

use std::cell::RefCell;
use std::time::Duration;

use clap::Parser;
use libfuzzer_sys::fuzz_target;
use mavping::cli::{Cli, Mode};
use mavping::config::ServeConfig;
use mavping::engine::matcher::MatchEvent;
use mavping::engine::observe::{Event, Observer, StartInfo};
use mavping::engine::summary::ProbeName;
use mavping::frame::SysComp;
use mavping::http::{serve_one, Limits};
use mavping::output::prometheus::PrometheusExporter;
use tokio::io::{AsyncReadExt, AsyncWriteExt};

thread_local! {
    static RUNTIME: RefCell<tokio::runtime::Runtime> = RefCell::new(
        tokio::runtime::Builder::new_current_thread()
            .enable_all()
            .build()
            .expect("a runtime"),
    );
}

fn serve_settings() -> mavping::config::ServeSettings {
    let cli = Cli::try_parse_from(["mavping", "serve", "--allow", "/dev/mavping-fuzz-*"])
        .expect("serve arguments");
    let Some(Mode::Serve(args)) = cli.mode else {
        panic!("not serve");
    };
    ServeConfig::try_from(&args).expect("serve config").settings
}

fn exporter() -> PrometheusExporter {
    let exporter = PrometheusExporter::default();
    let mut link = exporter.link(0);
    let _ = link.start(&StartInfo {
        link: "udpout:127.0.0.1:14550".into(),
        probe: ProbeName::Ping,
        ours: SysComp::new(250, 190),
        interval: Duration::from_millis(100),
        timeout: Duration::from_secs(1),
        count: None,
        plan: None,
    });
    for seq in 0..3u32 {
        let _ = link.event(&Event::of(&MatchEvent::Reply {
            responder: SysComp::new(1, 1),
            seq,
            rtt: 1_000_000 * u64::from(seq + 1),
            sent_at: 0,
            at: 1_000_000 * u64::from(seq + 1),
            out_of_order: false,
            first_from_responder: seq == 0,
        }));
    }
    exporter
}

/// Checks what the server sent back.
fn check(out: &[u8]) {
    if out.is_empty() {
        return;
    }
    let mut headers = [httparse::EMPTY_HEADER; 32];
    let mut response = httparse::Response::new(&mut headers);
    let head_len = match response.parse(out) {
        Ok(httparse::Status::Complete(n)) => n,
        other => panic!(
            "not one whole response head: {other:?}: {:?}",
            String::from_utf8_lossy(&out[..out.len().min(300)])
        ),
    };
    // HTTP/1.1, or 1.0 in answer to a 1.0 request (hyper answers in the
    // client's version).
    assert!(matches!(response.version, Some(0 | 1)), "{:?}", response.version);
    let code = response.code.expect("a status");
    assert!((100..600).contains(&code), "{code}");
    let length = response
        .headers
        .iter()
        .find(|h| h.name.eq_ignore_ascii_case("content-length"))
        .map(|h| {
            std::str::from_utf8(h.value)
                .expect("ascii")
                .parse::<usize>()
                .expect("a length")
        });
    let body = out.len() - head_len;
    match length {
        Some(n) => assert!(body == n || body == 0, "content-length {n}, body {body}"),
        None => assert_eq!(body, 0, "a body without a length"),
    }
}

fuzz_target!(|data: &[u8]| {
    let Some((&pick, request)) = data.split_first() else {
        return;
    };
    let request = request.to_vec();
    let out = RUNTIME.with(|rt| {
        let rt = rt.borrow();
        let local = tokio::task::LocalSet::new();
        local.block_on(&rt, async move {
            let (mut client, server) = tokio::io::duplex(64 * 1024);
            let limits = Limits::default();
            let serving = if pick % 2 == 0 {
                let handler = mavping::run::serve_handler(serve_settings());
                tokio::task::spawn_local(serve_one(server, limits, handler))
            } else {
                let exporter = exporter();
                tokio::task::spawn_local(serve_one(server, limits, exporter.handler()))
            };
            let (mut reader, mut writer) = tokio::io::split(&mut client);
            let send = async {
                // The server may close before reading it all.
                let _ = writer.write_all(&request).await;
                let _ = writer.shutdown().await;
            };
            let mut out = Vec::new();
            let receive = reader.read_to_end(&mut out);
            let (_, received) = tokio::join!(send, receive);
            received.expect("read");
            serving.await.expect("served");
            out
        })
    });
    check(&out);
});
