//! BASELINE, not mavping: the two ends of `scripts/bench.sh`'s passive
//! rows, measured in the same run as mavping.
//!
//! `stream_floor send HOST:PORT[,HOST:PORT...] RATE SECONDS`: a vehicle's
//! telemetry at RATE frames/s, one ATTITUDE frame (MAVLink 2, 1/1, its
//! packet sequence counting up) a datagram, in batches of one `sendmmsg`
//! every 0.5 ms on an absolute schedule (`clock_nanosleep`). With several
//! destinations, a vehicle on several links: each batch's same bytes go to
//! every one, from a socket of its own, so a listener on all of them can
//! match every frame's copies. Prints `{"sent": N}`, N frames to each.
//!
//! `stream_floor read PORT SECONDS`: the least a listener can do with the
//! same stream: `recvmmsg` into 64 buffers (a 4 MiB receive buffer, as
//! mavping asks for) and count the datagrams, no parsing; it ends 0.5 s
//! after the stream stops, or SECONDS after it started. Prints
//! `{"received": N, "cpu_s": S}` (its own CPU time).
//!
//! Linux only (its system calls are the point): elsewhere it says so.

fn main() {
    #[cfg(target_os = "linux")]
    linux::main();
    #[cfg(not(target_os = "linux"))]
    {
        eprintln!("stream_floor: Linux only (recvmmsg, sendmmsg, clock_nanosleep)");
        std::process::exit(2);
    }
}

#[cfg(target_os = "linux")]
mod linux {

    use std::io::{IoSlice, IoSliceMut};
    use std::net::UdpSocket;
    use std::os::fd::AsRawFd;
    use std::time::{Duration, Instant};

    use mavping::frame::{self, Header, Msg, Version};
    use nix::sys::resource::{getrusage, UsageWho};
    use nix::sys::socket::{self as nixsock, MsgFlags, MultiHeaders, SockaddrStorage};
    use nix::sys::time::TimeSpec;
    use nix::time::{clock_gettime, clock_nanosleep, ClockId, ClockNanosleepFlags};

    /// Frames a batch when the rate allows: one wake-up every 0.5 ms.
    const BATCH_S: f64 = 0.0005;
    const MAX_BATCH: usize = 256;

    fn cpu_s() -> f64 {
        let usage = getrusage(UsageWho::RUSAGE_SELF).expect("getrusage");
        let (u, s) = (usage.user_time(), usage.system_time());
        u.tv_sec() as f64 + s.tv_sec() as f64 + (u.tv_usec() + s.tv_usec()) as f64 / 1e6
    }

    /// A frame of the stream: its packet sequence number, and the sender's
    /// clock (ms since the stream began) as a vehicle stamps ATTITUDE, so
    /// a listener that reads ages has real stamps to read.
    fn frame(seq: u8, time_boot_ms: u32) -> Vec<u8> {
        let mut bytes = Vec::new();
        let header = Header {
            sysid: 1,
            compid: 1,
            seq,
        };
        frame::encode(
            &mut bytes,
            Version::V2,
            header,
            &Msg::Attitude { time_boot_ms },
        );
        bytes
    }

    /// Sends all of `iovs` on `fd`: a later destination gets every frame
    /// the first one took, or the links would differ by more than the
    /// kernel's drops.
    fn send_all(fd: i32, headers: &mut MultiHeaders<SockaddrStorage>, iovs: &[[IoSlice<'_>; 1]]) {
        let addrs = vec![None; iovs.len()];
        let mut done = 0;
        while done < iovs.len() {
            match nixsock::sendmmsg(
                fd,
                headers,
                &iovs[done..],
                &addrs[done..],
                [],
                MsgFlags::empty(),
            ) {
                Ok(sent) => done += sent.count(),
                Err(e) => panic!("sendmmsg: {e}"),
            }
        }
    }

    fn send(to: &str, rate: f64, seconds: f64) {
        let sockets: Vec<UdpSocket> = to
            .split(',')
            .map(|dest| {
                let socket = UdpSocket::bind("127.0.0.1:0").unwrap();
                socket.connect(dest).unwrap();
                socket
            })
            .collect();
        let fd = sockets[0].as_raw_fd();
        let batch = ((rate * BATCH_S).round() as usize).clamp(1, MAX_BATCH);
        let every = Duration::from_secs_f64(batch as f64 / rate);
        let total = (rate * seconds) as u64;
        let mut headers = MultiHeaders::<SockaddrStorage>::preallocate(batch, None);
        let start = clock_gettime(ClockId::CLOCK_MONOTONIC).unwrap();
        let mut sent: u64 = 0;
        let mut n: u32 = 0;
        while sent < total {
            n += 1;
            let due = start + TimeSpec::from_duration(every * n);
            let _ = clock_nanosleep(
                ClockId::CLOCK_MONOTONIC,
                ClockNanosleepFlags::TIMER_ABSTIME,
                &due,
            );
            let count = batch.min((total - sent) as usize);
            let ms = (every * n).as_millis() as u32;
            let frames: Vec<Vec<u8>> = (0..count)
                .map(|k| frame(((sent + k as u64) % 256) as u8, ms))
                .collect();
            let iovs: Vec<[IoSlice<'_>; 1]> = frames.iter().map(|f| [IoSlice::new(f)]).collect();
            let addrs = vec![None; count];
            let done =
                match nixsock::sendmmsg(fd, &mut headers, &iovs, &addrs, [], MsgFlags::empty()) {
                    Ok(done) => done.count(),
                    Err(e) => panic!("sendmmsg: {e}"),
                };
            for socket in &sockets[1..] {
                send_all(socket.as_raw_fd(), &mut headers, &iovs[..done]);
            }
            sent += done as u64;
        }
        println!("{{\"sent\": {sent}}}");
    }

    fn read(port: u16, seconds: f64) {
        let socket = UdpSocket::bind(("127.0.0.1", port)).unwrap();
        let size = 4 << 20;
        let _ = nixsock::setsockopt(&socket, nixsock::sockopt::RcvBuf, &size);
        // Ends 0.5 s after the stream stops (or `seconds` after it starts).
        socket
            .set_read_timeout(Some(Duration::from_millis(500)))
            .unwrap();
        let fd = socket.as_raw_fd();
        let mut slots = vec![[0u8; 512]; 64];
        let mut headers = MultiHeaders::<SockaddrStorage>::preallocate(64, None);
        let before = cpu_s();
        let mut end = None;
        let mut received: u64 = 0;
        while end.is_none_or(|end| Instant::now() < end) {
            let mut chunks = slots.iter_mut();
            let mut iovs: [[IoSliceMut<'_>; 1]; 64] =
                std::array::from_fn(|_| [IoSliceMut::new(&mut chunks.next().unwrap()[..])]);
            match nixsock::recvmmsg(
                fd,
                &mut headers,
                iovs.iter_mut(),
                MsgFlags::MSG_WAITFORONE,
                None,
            ) {
                Ok(read) => received += read.count() as u64,
                Err(_) if received > 0 => break,
                Err(_) => {}
            }
            if received > 0 && end.is_none() {
                end = Some(Instant::now() + Duration::from_secs_f64(seconds));
            }
        }
        println!(
            "{{\"received\": {received}, \"cpu_s\": {:.6}}}",
            cpu_s() - before
        );
    }

    pub fn main() {
        let args: Vec<String> = std::env::args().skip(1).collect();
        let num = |i: usize| -> f64 { args[i].parse().expect("a number") };
        match args.first().map(String::as_str) {
            Some("send") if args.len() == 4 => send(&args[1], num(2), num(3)),
            Some("read") if args.len() == 3 => read(num(1) as u16, num(2)),
            _ => {
                eprintln!(
                "usage: stream_floor send HOST:PORT[,HOST:PORT...] RATE SECONDS | stream_floor read PORT SECONDS"
            );
                std::process::exit(2);
            }
        }
    }
}
