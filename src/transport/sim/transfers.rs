//! The transfers a simulated responder serves, through the same
//! answering code as `mavping respond`: a transfer request is taken when
//! it reaches the responder, and what it draws goes out frame by frame at
//! `transfer_rate=`, no faster than the responder's side of the wire
//! takes it (as ArduPilot sends parameters only while its serial port has
//! room), each frame numbered and carried as telemetry is: through the
//! wire or the radios, the outage, the per-direction faults and the
//! paths, plus `loss=` on each (a transfer's frames are the legs of its
//! exchange). A radio whose air is slower than its serial port still
//! fills and drops, as a SiK radio without flow control does. Their
//! draws are the responders' own (as telemetry's), so a transfer leaves
//! the faults a seed gives the probes' exchanges where they were.

use std::time::Duration;

use tokio::time::Instant;

use super::link::SimLink;
use super::outgoing::Sends;
use crate::frame::{self, Frame};

impl SimLink {
    /// A transfer request mavping sent at `now`, through the uplink by
    /// `sent_done`, heard by responder `i` at each of `heard` past its
    /// arrival (none when lost on the way): taken when it arrives.
    pub(super) fn transfer_heard(
        &mut self,
        i: usize,
        request: &Frame,
        heard: [Option<Duration>; 2],
        now: Instant,
        sent_done: Instant,
    ) {
        if heard[0].is_none() || self.in_outage(now) {
            return;
        }
        let up = self.vehicle_one_way() + self.queued_up(now);
        for extra in heard.into_iter().flatten() {
            let at = self.ns(sent_done + up + extra);
            self.schedule(at, i, Sends::TransferRequest(Box::new(*request)));
        }
    }

    /// Responder `i` has `request` at `at`: what it draws is queued, and
    /// its first frame goes at once unless frames are going already.
    pub(super) fn take_transfer_request(&mut self, i: usize, request: &Frame, at: Instant) {
        let clock_ns = self.clock_ns(at).max(0) as u64;
        let r = &mut self.responders[i];
        let version = request.version;
        r.transfers.request(request, version, clock_ns);
        if !r.serving && r.transfers.pending() {
            r.serving = true;
            self.send_transfer(i, at);
        }
    }

    /// Responder `i` sends its next transfer frame at `at`, and schedules
    /// the one after: `1 / transfer_rate` later, or once its side of the
    /// wire has sent this one.
    pub(super) fn send_transfer(&mut self, i: usize, at: Instant) {
        let Some((version, msg, kind)) = self.responders[i].transfers.next() else {
            self.responders[i].serving = false;
            return;
        };
        let sent = if self.vehicle_chance(self.params.loss) {
            // Not sent, so not numbered, as a lost exchange's reply.
            false
        } else {
            let (header, index) = self.responders[i].header();
            let mut bytes = Vec::new();
            frame::encode(&mut bytes, version, header, &msg);
            let down = self.downlink(at, Duration::ZERO, bytes.len());
            match down.filter(|_| !self.in_outage(at)) {
                Some(done) => {
                    let arrives = done + self.queued_down(done) + self.vehicle_one_way();
                    let before = self.responders[i].truth.down.dropped;
                    self.send_down(i, index, bytes, at, arrives);
                    self.responders[i].truth.down.dropped == before
                }
                None => {
                    self.responders[i].truth.down.dropped += 1;
                    false
                }
            }
        };
        let r = &mut self.responders[i];
        r.transfers.counts.frame(kind, sent);
        if !r.transfers.pending() {
            r.serving = false;
            return;
        }
        let paced = at + Duration::from_secs_f64(1.0 / self.params.transfer_rate);
        let next = paced.max(self.responder_free_at(at));
        let ns = self.ns(next);
        self.schedule(ns, i, Sends::Transfer);
    }
}

#[cfg(test)]
mod tests {
    use std::collections::HashSet;

    use tokio::time::sleep_until;

    use super::*;
    use crate::frame::transfer::{ParamValue, Target};
    use crate::frame::{Header, Msg, SysComp, Transfer, Version};
    use crate::transport::link::{Inbound, Transport};
    use crate::transport::sim::SimParams;

    fn request(t: Transfer) -> Vec<u8> {
        let mut bytes = Vec::new();
        let header = Header {
            sysid: 250,
            compid: 190,
            seq: 0,
        };
        frame::encode(&mut bytes, Version::V2, header, &Msg::Transfer(t));
        bytes
    }

    const US: Target = Target {
        system: 1,
        component: 1,
    };

    /// Sends a PARAM_REQUEST_LIST and reads the link for `run` of its
    /// paused clock: each PARAM_VALUE that arrived, and when after the
    /// request.
    async fn list(query: &str, run: Duration) -> (SimLink, Vec<(Duration, ParamValue)>) {
        let mut link = SimLink::new(SimParams::parse(query).unwrap());
        let start = Instant::now();
        link.send(&request(Transfer::ParamRequestList { target: US }))
            .await
            .unwrap();
        let mut out: Vec<Inbound> = Vec::new();
        let end = start + run;
        loop {
            tokio::select! {
                r = link.recv(&mut out) => r.unwrap(),
                () = sleep_until(end) => break,
            }
        }
        let values = out
            .iter()
            .filter_map(|i| match i.frame.msg {
                Msg::Transfer(Transfer::ParamValue(p)) => Some((i.at - start, p)),
                _ => None,
            })
            .collect();
        (link, values)
    }

    fn param_value_bytes() -> u64 {
        let mut bytes = Vec::new();
        let p = crate::answering::params::ParamSet { count: 500 };
        let header = Header {
            sysid: 1,
            compid: 1,
            seq: 0,
        };
        let msg = Msg::Transfer(Transfer::ParamValue(p.get(3).unwrap()));
        frame::encode(&mut bytes, Version::V2, header, &msg);
        bytes.len() as u64
    }

    #[tokio::test(start_paused = true)]
    async fn a_list_goes_at_the_transfer_rate_on_a_fast_link() {
        let (link, values) = list(
            "?params=300&transfer_rate=200&jitter=0&heartbeat=off",
            Duration::from_secs(3),
        )
        .await;
        let indices: Vec<u16> = values.iter().map(|(_, p)| p.index).collect();
        assert_eq!(indices, (0..300).collect::<Vec<u16>>());
        // The request arrives 10 ms on, the frames go 5 ms apart, each
        // arrives 10 ms after it went.
        for (k, (at, _)) in values.iter().enumerate() {
            assert_eq!(*at, Duration::from_millis(20 + 5 * k as u64), "{k}");
        }
        let (_, t) = link.truth()[0];
        assert_eq!(t.served.requests.param_lists, 1);
        assert_eq!(
            (t.served.sent.param_value, t.served.dropped.param_value),
            (300, 0)
        );
        assert_eq!((t.down.sent, t.down.delivered), (300, 300));
    }

    #[tokio::test(start_paused = true)]
    async fn at_57600_baud_a_list_takes_the_wire_time_of_its_frames() {
        let (link, values) = list(
            "?baud=57600&params=500&jitter=0&heartbeat=off",
            Duration::from_secs(10),
        )
        .await;
        assert_eq!(values.len(), 500);
        // Each PARAM_VALUE is 37 bytes: 6.42 ms of a 57600-baud wire, so
        // 155 a second whatever transfer_rate= (1000) asks, none dropped.
        let bytes = param_value_bytes();
        assert_eq!(bytes, 37);
        let wire = Duration::from_nanos(bytes * 10 * 1_000_000_000 / 57_600);
        let last = values[499].0;
        let predicted = wire * 500;
        assert!(
            last > predicted && last < predicted + Duration::from_millis(40),
            "{last:?} for {predicted:?}"
        );
        let (_, t) = link.truth()[0];
        assert_eq!((t.served.sent.param_value, t.down.dropped), (500, 0));
    }

    #[tokio::test(start_paused = true)]
    async fn a_radio_slower_on_the_air_than_its_port_drops_and_the_truth_counts_it() {
        // 64 kbit/s of air, half of each round each way: 4000 B/s, less
        // than the 5760 B/s the serial port takes.
        let (link, values) = list(
            "?baud=57600&air=64k&params=1000&jitter=0&heartbeat=off",
            Duration::from_secs(20),
        )
        .await;
        let (_, t) = link.truth()[0];
        let s = t.served;
        assert_eq!(s.sent.param_value + s.dropped.param_value, 1000);
        assert_eq!(values.len() as u64, s.sent.param_value);
        assert!(s.dropped.param_value > 100, "{s:?}");
        assert_eq!(t.down.dropped, s.dropped.param_value);
        let distinct: HashSet<u16> = values.iter().map(|(_, p)| p.index).collect();
        assert_eq!(distinct.len(), values.len());
    }

    #[tokio::test(start_paused = true)]
    async fn loss_down_loses_frames_in_the_sequence_and_a_read_is_answered() {
        let query = "?params=400&loss_down=10%&seed=3&heartbeat=off&clock=virtual";
        let (mut link, values) = list(query, Duration::from_secs(2)).await;
        let (id, t) = link.truth()[0];
        assert_eq!(id, SysComp::new(1, 1));
        let s = t.served;
        assert_eq!(s.sent.param_value + s.dropped.param_value, 400);
        assert_eq!(values.len() as u64, s.sent.param_value);
        assert!((20..70).contains(&s.dropped.param_value), "{s:?}");
        // Each lost frame was numbered: a gap in the sequence.
        assert_eq!(t.down.sent, 400);
        assert_eq!(t.down.dropped, s.dropped.param_value);
        // A read of a lost one, by name.
        let got: HashSet<u16> = values.iter().map(|(_, p)| p.index).collect();
        let lost = (0..400).find(|i| !got.contains(i)).unwrap();
        let read = Transfer::ParamRequestRead {
            target: US,
            id: crate::frame::transfer::ParamId::new(&format!("MAVPING_{lost:04}")),
            index: -1,
        };
        link.send(&request(read)).await.unwrap();
        let mut out = Vec::new();
        let end = Instant::now() + Duration::from_secs(1);
        loop {
            tokio::select! {
                r = link.recv(&mut out) => r.unwrap(),
                () = sleep_until(end) => break,
            }
        }
        let answered = out.iter().any(
            |i| matches!(i.frame.msg, Msg::Transfer(Transfer::ParamValue(p)) if p.index == lost),
        );
        let t = link.truth()[0].1;
        assert_eq!(t.served.requests.param_reads, 1);
        assert_eq!(
            answered,
            t.served.dropped.param_value == s.dropped.param_value
        );
    }

    /// The PING replies (by seq) that arrived when `pings` PINGs are sent
    /// 100 ms apart, with a parameter list asked for first or not.
    async fn ping_replies(query: &str, with_list: bool) -> Vec<u32> {
        let mut link = SimLink::new(SimParams::parse(query).unwrap());
        if with_list {
            link.send(&request(Transfer::ParamRequestList { target: US }))
                .await
                .unwrap();
        }
        let start = Instant::now();
        let mut out: Vec<Inbound> = Vec::new();
        for seq in 0..50u32 {
            let mut bytes = Vec::new();
            let header = Header {
                sysid: 250,
                compid: 190,
                seq: seq as u8,
            };
            let ping = Msg::Ping {
                time_usec: u64::from(seq) + 1,
                seq,
                target_system: 0,
                target_component: 0,
            };
            frame::encode(&mut bytes, Version::V2, header, &ping);
            link.send(&bytes).await.unwrap();
            let next = start + Duration::from_millis(100 * (u64::from(seq) + 1));
            loop {
                tokio::select! {
                    r = link.recv(&mut out) => r.unwrap(),
                    () = sleep_until(next) => break,
                }
            }
        }
        out.iter()
            .filter_map(|i| match i.frame.msg {
                Msg::Ping { seq, .. } => Some(seq),
                _ => None,
            })
            .collect()
    }

    #[tokio::test(start_paused = true)]
    async fn a_transfer_leaves_the_probes_faults_where_they_were() {
        // The exchanges' faults (loss=, dup=, the jitter) are the link's
        // draws, the transfer's the responder's own. (The per-direction
        // faults are the responder's draws: a transfer moves them, as
        // telemetry does.)
        let query = "?loss=20%&dup=10%&params=200&seed=4&heartbeat=off";
        let alone = ping_replies(query, false).await;
        let beside = ping_replies(query, true).await;
        assert!(alone.len() < 55 && alone.len() > 35, "{alone:?}");
        assert_eq!(alone, beside);
    }
}
