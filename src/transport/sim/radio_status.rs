//! The near radio's RADIO_STATUS, once a second: RSSI from the simulated
//! loss, the buffer's free share, the drops so far.

use std::time::Duration;

use tokio::time::Instant;

use super::deliveries::Payload;
use super::link::SimLink;
use crate::frame::{self, Header, Msg, RadioStatus, SysComp, Version};

pub(crate) const RADIO_ID: SysComp = SysComp::new(51, 68);
impl SimLink {
    /// RADIO_STATUS once a second: RSSI falls with the simulated loss,
    /// txbuf is the buffer's free share, rxerrors the drops so far.
    pub(super) fn queue_radio_status(&mut self, now: Instant) {
        while self.params.radio && self.next_radio <= now {
            let sent = self.next_radio;
            self.next_radio += Duration::from_secs(1);
            let rssi = (200.0 - 300.0 * self.params.loss).clamp(0.0, 254.0) as u8;
            let at = self.ns(sent);
            let txbuf = match self.pair.as_mut() {
                Some(pair) => pair.ground_free_percent(at),
                None => {
                    let buffer = self.params.buffer;
                    let free = buffer.saturating_sub(self.backlog_bytes(sent));
                    (free * 100 / buffer) as u8
                }
            };
            let dropped = self.responders.iter().map(|r| r.truth.dropped).sum::<u64>();
            self.radio_seq = self.radio_seq.wrapping_add(1);
            let header = Header {
                sysid: RADIO_ID.sysid,
                compid: RADIO_ID.compid,
                seq: self.radio_seq,
            };
            let mut bytes = Vec::new();
            frame::encode(
                &mut bytes,
                Version::V2,
                header,
                &Msg::RadioStatus(RadioStatus {
                    rssi,
                    remrssi: rssi,
                    txbuf,
                    noise: 40,
                    remnoise: 40,
                    // Since-boot counters wrap at 65 535, as a radio's do.
                    rxerrors: dropped as u16,
                    fixed: 0,
                }),
            );
            // The radio is the near end: no link delay.
            // The near radio's own frame: on its path (0), once.
            self.enqueue(sent, bytes, Payload::Plain, 0, None);
        }
    }
}
