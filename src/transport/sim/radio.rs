//! The physics of a simulated SiK-style radio pair (`sim:?baud=N&air=RATE`):
//! what a frame goes through between mavping and a responder, and when it
//! comes out, or where it is dropped.
//!
//! ```text
//! mavping ─UART─▶ ground radio ─air (its TDM window)─▶ remote radio ─UART─▶ responder
//! mavping ◀─UART─ ground radio ◀─air (its TDM window)─ remote radio ◀─UART─ responder
//! ```
//!
//! - Each UART carries 10 bits a byte at the baud rate, each way on its own.
//! - The air carries `air` bits per second; with ECC (SiK's Golay code)
//!   every byte costs two. Time is cut into TDM rounds: the ground radio
//!   may send in the first half of each round, the remote one in the
//!   second, and each only for `duty` of its half. A frame waits for its
//!   radio's window, and a long one continues in the next.
//! - Each radio holds what waits for the air in a transmit buffer of
//!   `buffer` bytes; a frame that does not fit is dropped whole. So a
//!   radio queues before it drops: a large buffer is delay (bufferbloat),
//!   a small one is loss.
//!
//! The capacity that follows, [`capacity_hz`], is what a sweep's knee is
//! tested against. Pure: times are nanoseconds since the link opened.

use std::collections::VecDeque;
use std::time::Duration;

/// What the host's serial driver holds on each side before it drops (a
/// Linux tty buffer).
pub(crate) const UART_BUFFER_BYTES: u64 = 4096;
const BITS_PER_UART_BYTE: u64 = 10;

/// The air side of a simulated radio pair.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct AirParams {
    /// Bits per second over the air.
    pub(crate) air_bps: u32,
    /// Share of its half of each round a radio transmits, 0 < duty <= 1.
    pub(crate) duty: f64,
    /// Error correction: two bytes on the air for every byte of data.
    pub(crate) ecc: bool,
    /// A TDM round: each radio's window is in its half of it.
    pub(crate) tdm_round: Duration,
}

pub(crate) const DEFAULT_TDM_ROUND: Duration = Duration::from_millis(20);

impl AirParams {
    #[cfg(test)]
    /// Bytes of data per second one radio puts on the air when busy.
    pub(crate) fn bytes_per_s_each_way(&self) -> f64 {
        let ecc = if self.ecc { 2.0 } else { 1.0 };
        f64::from(self.air_bps) / 8.0 / ecc * self.duty / 2.0
    }
}

#[cfg(test)]
/// PING exchanges per second a radio pair carries when each request of
/// `request_bytes` draws `responders` replies of `reply_bytes`: the least
/// of what each UART direction and each radio's share of the air allow.
pub(crate) fn capacity_hz(
    baud: u32,
    air: &AirParams,
    request_bytes: u64,
    reply_bytes: u64,
    responders: u64,
) -> f64 {
    let uart = f64::from(baud) / BITS_PER_UART_BYTE as f64;
    let air = air.bytes_per_s_each_way();
    let up = request_bytes as f64;
    let down = (reply_bytes * responders) as f64;
    (uart / up).min(uart / down).min(air / up).min(air / down)
}

/// When a stage may send: its window of each TDM round.
#[derive(Debug, Clone, Copy)]
struct Window {
    round_ns: u64,
    offset_ns: u64,
    len_ns: u64,
}

impl Window {
    /// When `need_ns` of sending that starts at `t` is done, sending only
    /// inside the window.
    fn finish(&self, mut t: u64, mut need_ns: u64) -> u64 {
        loop {
            let pos = (t + self.round_ns - self.offset_ns) % self.round_ns;
            if pos < self.len_ns {
                let room = self.len_ns - pos;
                if need_ns <= room {
                    return t + need_ns;
                }
                need_ns -= room;
                t += room;
            } else {
                t += self.round_ns - pos;
            }
        }
    }
}

/// One first-in first-out hop: a UART, or a radio's transmit buffer and
/// its share of the air.
#[derive(Debug, Clone)]
struct Stage {
    ns_per_byte: f64,
    window: Option<Window>,
    buffer: u64,
    /// When the hop has sent everything it holds.
    free_at: u64,
    /// Frames held, with when each is sent: what the buffer holds.
    held: VecDeque<(u64, u64)>,
    held_bytes: u64,
}

impl Stage {
    fn new(bytes_per_s: f64, window: Option<Window>, buffer: u64) -> Self {
        Stage {
            ns_per_byte: 1e9 / bytes_per_s,
            window,
            buffer,
            free_at: 0,
            held: VecDeque::new(),
            held_bytes: 0,
        }
    }

    /// Bytes held at `at`: taken in, not yet sent.
    fn backlog(&mut self, at: u64) -> u64 {
        while let Some(&(done, bytes)) = self.held.front() {
            if done > at {
                break;
            }
            self.held.pop_front();
            self.held_bytes -= bytes;
        }
        self.held_bytes
    }

    /// A frame of `bytes` arriving at `at`: when its last byte is sent, or
    /// `None` when the buffer cannot take it.
    fn pass(&mut self, at: u64, bytes: u64) -> Option<u64> {
        if self.backlog(at) + bytes > self.buffer {
            return None;
        }
        let start = at.max(self.free_at);
        let need = (bytes as f64 * self.ns_per_byte).round() as u64;
        let done = match self.window {
            Some(w) => w.finish(start, need),
            None => start + need,
        };
        self.free_at = done;
        self.held.push_back((done, bytes));
        self.held_bytes += bytes;
        Some(done)
    }
}

/// Where a frame was dropped.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Dropped {
    /// A host or radio serial buffer was full.
    Uart,
    /// A radio's transmit buffer was full.
    Radio,
}

/// Both radios and the four UART directions around them.
#[derive(Debug, Clone)]
pub(crate) struct RadioPair {
    ground_uart_in: Stage,
    ground: Stage,
    remote_uart_out: Stage,
    remote_uart_in: Stage,
    remote: Stage,
    ground_uart_out: Stage,
    buffer: u64,
}

impl RadioPair {
    pub(crate) fn new(baud: u32, air: &AirParams, buffer: u64) -> Self {
        let uart = f64::from(baud) / BITS_PER_UART_BYTE as f64;
        let round_ns = air.tdm_round.as_nanos().max(2) as u64;
        let len_ns = ((round_ns / 2) as f64 * air.duty).round().max(1.0) as u64;
        // Inside its window a radio sends at the full air rate.
        let on_air = f64::from(air.air_bps) / 8.0 / if air.ecc { 2.0 } else { 1.0 };
        let window = |offset_ns| {
            Some(Window {
                round_ns,
                offset_ns,
                len_ns,
            })
        };
        RadioPair {
            ground_uart_in: Stage::new(uart, None, UART_BUFFER_BYTES),
            ground: Stage::new(on_air, window(0), buffer),
            remote_uart_out: Stage::new(uart, None, UART_BUFFER_BYTES),
            remote_uart_in: Stage::new(uart, None, UART_BUFFER_BYTES),
            remote: Stage::new(on_air, window(round_ns / 2), buffer),
            ground_uart_out: Stage::new(uart, None, UART_BUFFER_BYTES),
            buffer,
        }
    }

    /// A frame mavping writes at `at`: when the responder has read it.
    pub(crate) fn uplink(&mut self, at: u64, bytes: u64) -> Result<u64, Dropped> {
        let t = self.ground_uart_in.pass(at, bytes).ok_or(Dropped::Uart)?;
        let t = self.ground.pass(t, bytes).ok_or(Dropped::Radio)?;
        self.remote_uart_out.pass(t, bytes).ok_or(Dropped::Uart)
    }

    /// A frame a responder writes at `at`: when mavping can read it.
    pub(crate) fn downlink(&mut self, at: u64, bytes: u64) -> Result<u64, Dropped> {
        let t = self.remote_uart_in.pass(at, bytes).ok_or(Dropped::Uart)?;
        let t = self.remote.pass(t, bytes).ok_or(Dropped::Radio)?;
        self.ground_uart_out.pass(t, bytes).ok_or(Dropped::Uart)
    }

    /// When the remote radio's UART has taken everything written to it:
    /// what a responder that waits for room in its serial port (as
    /// ArduPilot streams parameters) paces itself by.
    pub(crate) fn remote_uart_free_ns(&self) -> u64 {
        self.remote_uart_in.free_at
    }

    /// Share of the ground radio's buffer free at `at`, in percent (its
    /// RADIO_STATUS `txbuf`).
    pub(crate) fn ground_free_percent(&mut self, at: u64) -> u8 {
        let held = self.ground.backlog(at).min(self.buffer);
        ((self.buffer - held) * 100 / self.buffer.max(1)) as u8
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn air(air_bps: u32) -> AirParams {
        AirParams {
            air_bps,
            duty: 1.0,
            ecc: false,
            tdm_round: DEFAULT_TDM_ROUND,
        }
    }

    #[test]
    fn capacity_by_hand() {
        // 64 kbit/s: 8000 B/s, 4000 each way; a reply of 26 B: 153.8/s.
        // The UART (5760 B/s) alone would carry 221/s.
        let c = capacity_hz(57_600, &air(64_000), 22, 26, 1);
        assert!((c - 4000.0 / 26.0).abs() < 1e-9, "{c}");
        // 128 kbit/s at 115200 baud: 8000 B/s each way, 307.7/s.
        let c = capacity_hz(115_200, &air(128_000), 22, 26, 1);
        assert!((c - 8000.0 / 26.0).abs() < 1e-9, "{c}");
        // ECC halves it, and so does a 50 % duty cycle.
        let ecc = AirParams {
            ecc: true,
            ..air(64_000)
        };
        assert!((capacity_hz(57_600, &ecc, 22, 26, 1) - 2000.0 / 26.0).abs() < 1e-9);
        let duty = AirParams {
            duty: 0.5,
            ..air(64_000)
        };
        assert!((capacity_hz(57_600, &duty, 22, 26, 1) - 2000.0 / 26.0).abs() < 1e-9);
        // A fast air behind a slow UART: the UART's 5760 B/s over 26 B.
        let c = capacity_hz(57_600, &air(250_000), 22, 26, 1);
        assert!((c - 5760.0 / 26.0).abs() < 1e-9, "{c}");
        // Two responders double the replies.
        let c = capacity_hz(57_600, &air(64_000), 22, 26, 2);
        assert!((c - 4000.0 / 52.0).abs() < 1e-9, "{c}");
    }

    #[test]
    fn a_window_sends_only_in_its_half() {
        let w = Window {
            round_ns: 100,
            offset_ns: 50,
            len_ns: 50,
        };
        // Before its window: waits for 50, then sends 10.
        assert_eq!(w.finish(0, 10), 60);
        // Inside: at once.
        assert_eq!(w.finish(70, 10), 80);
        // Longer than what is left of the window: goes on in the next.
        assert_eq!(w.finish(90, 30), 170);
        // Nothing to send takes no time inside the window.
        assert_eq!(w.finish(60, 0), 60);
    }

    #[test]
    fn a_full_buffer_queues_then_drops() {
        // 1000 B/s, a 100-byte buffer, no window.
        let mut s = Stage::new(1000.0, None, 100);
        // Five 40-byte frames at once: two fit, then one more once the
        // first is out (at 40 ms).
        let sent: Vec<Option<u64>> = (0..3).map(|_| s.pass(0, 40)).collect();
        assert_eq!(sent, [Some(40_000_000), Some(80_000_000), None]);
        assert_eq!(s.backlog(40_000_000), 40);
        assert_eq!(s.pass(40_000_000, 40), Some(120_000_000));
    }

    #[test]
    fn frames_through_the_pair_take_uart_air_and_uart_time() {
        let mut pair = RadioPair::new(57_600, &air(64_000), 1024);
        // 26 bytes: 4.514 ms on each UART and 3.25 ms on the air (8000 B/s
        // inside the ground radio's window, which is open at 0).
        let done = pair.uplink(0, 26).unwrap();
        let uart = (26.0 * 1e9 / 5760.0_f64).round() as u64;
        assert_eq!(done, uart + 3_250_000 + uart);
        // A reply written at 0 waits for the remote radio's window (10 ms
        // to 20 ms of each 20 ms round).
        assert_eq!(pair.downlink(0, 26).unwrap(), 10_000_000 + 3_250_000 + uart);
        // One that reaches the radio with less than its air time left in
        // the window finishes in the next one (from 30 ms).
        let late = 20_000_000 - 3_000_000 - uart;
        assert_eq!(pair.downlink(late, 26).unwrap(), 30_250_000 + uart);
        // The request sat in the ground radio's buffer until it was on the
        // air: 26 of 1024 bytes, 97 % free; then all of it is.
        assert_eq!(pair.ground_free_percent(uart + 1_000_000), 97);
        assert_eq!(pair.ground_free_percent(done), 100);
    }

    #[test]
    fn a_steady_overload_fills_the_buffer_and_then_drops() {
        // Replies at twice what the remote radio's half of the air takes.
        let mut pair = RadioPair::new(115_200, &air(64_000), 1024);
        let capacity = capacity_hz(115_200, &air(64_000), 22, 26, 1);
        let interval = (1e9 / (2.0 * capacity)) as u64;
        let mut first_drop = None;
        for i in 0..1000u64 {
            if pair.downlink(i * interval, 26).is_err() && first_drop.is_none() {
                first_drop = Some(i);
            }
        }
        // The buffer holds about 39 replies: the excess reaches it after
        // about 80 requests, not before.
        let first = first_drop.expect("an overload drops");
        assert!((60..100).contains(&first), "{first}");
    }
}
