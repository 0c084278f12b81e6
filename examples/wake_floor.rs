//! BASELINE, not mavping: the least CPU a pinger that wakes once per send
//! can cost on this machine, measured in the same run as mavping by
//! `scripts/bench.sh`. Each send: `clock_nanosleep(TIMER_ABSTIME)` to its
//! due time, one `recvmmsg` of what came back (with kernel timestamps),
//! one `sendmmsg` of a 21-byte datagram to an echo thread on loopback. No
//! parsing, matching, statistics or output.
//!
//! `cargo run --release --example wake_floor -- RATE SECONDS` prints the
//! sender thread's CPU time per send in µs (one JSON line).
//!
//! Linux only (its system calls are the point): elsewhere it says so.

fn main() {
    #[cfg(target_os = "linux")]
    linux::main();
    #[cfg(not(target_os = "linux"))]
    {
        eprintln!("wake_floor: Linux only (recvmmsg, sendmmsg, clock_nanosleep)");
        std::process::exit(2);
    }
}

#[cfg(target_os = "linux")]
mod linux {

    use std::io::{IoSlice, IoSliceMut};
    use std::net::UdpSocket;
    use std::os::fd::AsRawFd;
    use std::time::Duration;

    use nix::sys::resource::{getrusage, UsageWho};
    use nix::sys::socket::{
        self as nixsock, ControlMessage, MsgFlags, MultiHeaders, SockaddrStorage,
    };
    use nix::sys::time::TimeSpec;
    use nix::time::{clock_gettime, clock_nanosleep, ClockId, ClockNanosleepFlags};

    fn cpu_s() -> f64 {
        let usage = getrusage(UsageWho::RUSAGE_THREAD).expect("getrusage");
        let (u, s) = (usage.user_time(), usage.system_time());
        u.tv_sec() as f64 + s.tv_sec() as f64 + (u.tv_usec() + s.tv_usec()) as f64 / 1e6
    }

    pub fn main() {
        let args: Vec<f64> = std::env::args()
            .skip(1)
            .map(|a| a.parse().expect("RATE SECONDS"))
            .collect();
        let (rate, seconds) = (args[0], args[1]);
        let _ = nix::sys::prctl::set_timerslack(1_000);
        let echo = UdpSocket::bind("127.0.0.1:0").unwrap();
        let to = echo.local_addr().unwrap();
        std::thread::spawn(move || {
            let mut buf = [0u8; 2048];
            while let Ok((n, from)) = echo.recv_from(&mut buf) {
                let _ = echo.send_to(&buf[..n], from);
            }
        });
        let socket = UdpSocket::bind("127.0.0.1:0").unwrap();
        socket.connect(to).unwrap();
        nixsock::setsockopt(&socket, nixsock::sockopt::ReceiveTimestampns, &true).unwrap();
        let fd = socket.as_raw_fd();
        let interval = Duration::from_secs_f64(1.0 / rate);
        let sends = (rate * seconds) as u32;
        let frame = [0xFDu8; 21];
        let mut slots = vec![[0u8; 2048]; 16];
        let mut send_headers = MultiHeaders::<SockaddrStorage>::preallocate(1, None);
        let start = clock_gettime(ClockId::CLOCK_MONOTONIC).unwrap();
        let before = cpu_s();
        let mut replies = 0;
        for n in 1..=sends {
            let due = start + TimeSpec::from_duration(interval * n);
            let _ = clock_nanosleep(
                ClockId::CLOCK_MONOTONIC,
                ClockNanosleepFlags::TIMER_ABSTIME,
                &due,
            );
            let mut headers =
                MultiHeaders::<SockaddrStorage>::preallocate(16, Some(nix::cmsg_space!(TimeSpec)));
            let mut chunks = slots.iter_mut();
            let mut iovs: [[IoSliceMut<'_>; 1]; 16] =
                std::array::from_fn(|_| [IoSliceMut::new(&mut chunks.next().unwrap()[..])]);
            if let Ok(read) = nixsock::recvmmsg(
                fd,
                &mut headers,
                iovs.iter_mut(),
                MsgFlags::MSG_DONTWAIT,
                None,
            ) {
                replies += read.count();
            }
            let iov = [[IoSlice::new(&frame)]];
            let none: [ControlMessage<'_>; 0] = [];
            let _ = nixsock::sendmmsg(fd, &mut send_headers, &iov, [None], none, MsgFlags::empty());
        }
        let cpu = cpu_s() - before;
        println!(
            "{{\"sends\": {sends}, \"replies\": {replies}, \"cpu_per_send_us\": {:.2}}}",
            cpu / f64::from(sends) * 1e6
        );
    }
}
