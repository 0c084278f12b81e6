//! Per-packet costs of mavping's hot path, each beside a baseline measured
//! in the same run:
//! - frame scanning: mavping's scanner vs the `mavlink` crate's own reader
//!   on the same bytes (the crate mavping would otherwise use), and on
//!   hostile bytes (each reply among mutated copies of itself, as the
//!   mutation test sends them) as a stream and as datagrams;
//! - matching and statistics per reply, the work done for every PING;
//! - the per-source sequence accounting of every received frame (passive
//!   runs, and the downlink figure of every echo run).
//!
//! Run: `cargo bench --bench core` (or `bash scripts/bench.sh` for the
//! end-to-end comparison with irtt and pymavlink).

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use mavping::engine::matcher::{Lookup, Matcher};
use mavping::engine::probe::passive::tracker::{SourceTable, DEFAULT_MAX_SOURCES};
use mavping::engine::stats::RttStats;
use mavping::frame::{self, Header, Msg, ScanStats, StreamScanner, SysComp, Version};

/// 1,000 PING replies, as a responder sends them, in one byte stream.
fn ping_stream(count: u32) -> Vec<u8> {
    let mut bytes = Vec::new();
    for seq in 0..count {
        frame::encode(
            &mut bytes,
            Version::V2,
            Header {
                sysid: 1,
                compid: 1,
                seq: seq as u8,
            },
            &Msg::Ping {
                time_usec: 1_700_000_000_000_000 + u64::from(seq),
                seq,
                target_system: 255,
                target_component: 190,
            },
        );
    }
    bytes
}

fn frames(c: &mut Criterion) {
    const N: u32 = 1000;
    let stream = ping_stream(N);
    let one = ping_stream(1);
    let mut g = c.benchmark_group("parse");
    g.throughput(Throughput::Elements(u64::from(N)));
    g.bench_function("mavping StreamScanner + decode (1000 frames)", |b| {
        b.iter(|| {
            let mut scanner = StreamScanner::new();
            let mut n = 0u32;
            scanner.push(black_box(&stream), &mut |raw| {
                black_box(frame::decode(raw));
                n += 1;
            });
            assert_eq!(n, N);
        })
    });
    g.bench_function("baseline: mavlink crate MavlinkReader (1000 frames)", |b| {
        b.iter(|| {
            let mut reader = mavlink::MavlinkReader::new(black_box(&stream[..]));
            for _ in 0..N {
                let msg = reader
                    .read_any_message::<mavlink::dialects::ardupilotmega::MavMessage>()
                    .unwrap();
                black_box(msg);
            }
        })
    });
    g.finish();
    let mut g = c.benchmark_group("datagram");
    g.throughput(Throughput::Elements(1));
    g.bench_function("mavping scan_datagram + decode (1 frame)", |b| {
        let mut stats = ScanStats::default();
        b.iter(|| {
            frame::scan_datagram(black_box(&one), &mut stats, &mut |raw| {
                black_box(frame::decode(raw));
            })
        })
    });
    g.bench_function("encode one PING request", |b| {
        let mut out = Vec::with_capacity(64);
        b.iter(|| {
            out.clear();
            frame::encode(
                &mut out,
                Version::V2,
                Header {
                    sysid: 255,
                    compid: 190,
                    seq: 0,
                },
                black_box(&Msg::Ping {
                    time_usec: 1,
                    seq: 2,
                    target_system: 0,
                    target_component: 0,
                }),
            );
            black_box(&out);
        })
    });
    g.finish();
}

/// Each of 1,000 replies with 8 mutated copies of itself (cut short, a
/// junk prefix rich in start bytes, bit flips, a random length byte,
/// random bytes), seeded: one datagram per piece.
fn mutated_pieces() -> Vec<Vec<u8>> {
    let mut state = 0x9E37_79B9_7F4A_7C15u64;
    let mut next = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        state
    };
    let mut pieces = Vec::new();
    for reply in ping_stream(1000).chunks(26) {
        pieces.push(reply.to_vec());
        for k in 0..8 {
            let mut copy = reply.to_vec();
            match k % 5 {
                0 => copy.truncate(1 + next() as usize % (reply.len() - 1)),
                1 => {
                    let junk = 1 + next() as usize % 20;
                    let stx = [0xFD, 0xFE, next() as u8];
                    copy = (0..junk).map(|_| stx[next() as usize % 3]).collect();
                    copy.extend_from_slice(reply);
                }
                2 => copy[next() as usize % reply.len()] ^= 1 << (next() % 8),
                3 => copy[1] = next() as u8,
                _ => copy = (0..=next() % 300).map(|_| next() as u8).collect(),
            }
            pieces.push(copy);
        }
    }
    pieces
}

fn hostile(c: &mut Criterion) {
    let pieces = mutated_pieces();
    let stream = pieces.concat();
    let mut g = c.benchmark_group("hostile");
    g.throughput(Throughput::Bytes(stream.len() as u64));
    g.bench_function("StreamScanner: 1000 replies among 8000 mutants", |b| {
        b.iter(|| {
            let mut scanner = StreamScanner::new();
            let mut n = 0u32;
            scanner.push(black_box(&stream), &mut |_| n += 1);
            black_box(n);
        })
    });
    g.bench_function("scan_datagram: 1000 replies among 8000 mutants", |b| {
        let mut stats = ScanStats::default();
        b.iter(|| {
            let mut n = 0u32;
            for piece in &pieces {
                frame::scan_datagram(black_box(piece), &mut stats, &mut |_| n += 1);
            }
            black_box(n);
        })
    });
    g.finish();
}

fn matching(c: &mut Criterion) {
    let mut g = c.benchmark_group("engine");
    g.throughput(Throughput::Elements(1));
    // Steady state at 150k PINGs/s with a 1 s timeout: a 512k-slot ring,
    // one send, one reply and one expiry per iteration.
    g.bench_function("matcher: send + reply + expire (1 responder)", |b| {
        let mut m = Matcher::new(1_000_000_000, 1 << 19, 0);
        let who = SysComp::new(1, 1);
        let mut t = 0u64;
        let mut sink = |e| {
            black_box(e);
        };
        b.iter(|| {
            t += 6_667;
            let token = t / 1000;
            let issued = m.on_send(token, t, &mut sink);
            m.on_reply(
                who,
                Lookup::Seq {
                    seq: issued.seq,
                    token,
                },
                t + 50_000,
                &mut sink,
            );
            m.expire(t, &mut sink);
        })
    });
    g.bench_function("stats: record one RTT", |b| {
        let mut s = RttStats::new();
        let mut rtt = 40_000u64;
        b.iter(|| {
            rtt = rtt
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407)
                % 5_000_000;
            s.record(black_box(rtt));
        })
    });
    g.finish();
}

/// The per-frame sequence accounting every passive and echo run does:
/// `SourceTable::on_frame` (the table lookup and the source's tracker).
fn sequences(c: &mut Criterion) {
    let mut g = c.benchmark_group("sequences");
    g.throughput(Throughput::Elements(1));
    // 100,000 frames/s from one source, in order.
    g.bench_function("SourceTable::on_frame: 1 source, in order", |b| {
        let mut table = SourceTable::new(None, DEFAULT_MAX_SOURCES);
        let who = SysComp::new(1, 1);
        let (mut seq, mut at) = (0u8, 0u64);
        b.iter(|| {
            seq = seq.wrapping_add(1);
            at += 10_000;
            table.on_frame(black_box(who), seq, 30, 36, at);
        })
    });
    // 20 sources interleaved, every 16th frame lost and every 64th
    // doubled: the gap, fill and duplicate paths.
    g.bench_function("SourceTable::on_frame: 20 sources, lossy", |b| {
        let mut table = SourceTable::new(None, DEFAULT_MAX_SOURCES);
        let sources: Vec<SysComp> = (1..=20).map(|s| SysComp::new(s, 1)).collect();
        let mut seqs = [0u8; 20];
        let (mut frame, mut at) = (0u64, 0u64);
        b.iter(|| {
            frame += 1;
            at += 10_000;
            let who = (frame % 20) as usize;
            if frame % 16 == 0 {
                seqs[who] = seqs[who].wrapping_add(1);
            }
            if frame % 64 != 0 {
                seqs[who] = seqs[who].wrapping_add(1);
            }
            table.on_frame(black_box(sources[who]), seqs[who], 30, 36, at);
        })
    });
    g.finish();
}

criterion_group!(benches, frames, hostile, matching, sequences);
criterion_main!(benches);
