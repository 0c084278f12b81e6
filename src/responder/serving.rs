//! The transfers' frames (a parameter list, a file's burst, the replies
//! to re-requests), sent at `--transfer-rate` through the link emulation
//! of the replies: held, dropped or doubled, and counted by kind.

use std::time::Duration;

use tokio::time::Instant;

use super::replies::Fate;
use super::respond_loop::Responder;

/// Transfer frames sent back to back at most before the loop reads the
/// link again: what a late wake-up catches up at once.
const MAX_TRANSFER_BATCH: usize = 64;

impl Responder {
    /// Sends the transfer frames due at `now` at `--transfer-rate` (at
    /// most a batch per wake-up), each through the link emulation.
    pub(super) fn serve_due(&mut self, now: Instant) {
        let interval = Duration::from_secs_f64(1.0 / self.settings.transfer_rate);
        for _ in 0..MAX_TRANSFER_BATCH {
            if self.transfer_next > now {
                return;
            }
            let Some(((path, version), msg, kind)) = self.transfers.next() else {
                return;
            };
            self.transfer_next += interval;
            let fate = self.emit(&msg, version, path, now, false);
            let served = &mut self.transfers.counts;
            served.frame(kind, fate != Fate::Dropped);
            served.duplicated += u64::from(fate == Fate::Doubled);
        }
    }
}

#[cfg(test)]
mod tests {
    use std::time::Duration;

    use tokio::sync::Notify;
    use tokio::time::{sleep_until, Instant};

    use crate::answering::transfers::ServeSpec;
    use crate::frame::transfer::{ParamId, Target};
    use crate::frame::{self, Header, Msg, ScanStats, SysComp, Transfer, Version};
    use crate::responder::respond_loop::run;
    use crate::responder::settings::ResponderSettings;
    use crate::transport::{push_datagram, Inbound, LinkError, LinkKind, PathId, Transport};

    /// A link that hands over `requests` at their times, and keeps what
    /// is sent to it with when.
    struct Scripted {
        start: Instant,
        requests: Vec<(Duration, Transfer)>,
        sent: Vec<(Duration, frame::Frame)>,
    }

    impl Transport for Scripted {
        async fn send(&mut self, bytes: &[u8]) -> Result<Instant, LinkError> {
            let mut stats = ScanStats::default();
            let at = Instant::now() - self.start;
            frame::scan_datagram(bytes, &mut stats, &mut |raw| {
                self.sent.push((at, frame::decode(raw)));
            });
            Ok(Instant::now())
        }

        async fn send_to(&mut self, _: PathId, bytes: &[u8]) -> Result<Instant, LinkError> {
            self.send(bytes).await
        }

        async fn recv(&mut self, out: &mut Vec<Inbound>) -> Result<(), LinkError> {
            if self.requests.is_empty() {
                return std::future::pending().await;
            }
            // Taken once its time has come: a recv cancelled by the
            // loop's other wake-ups loses nothing.
            sleep_until(self.start + self.requests[0].0).await;
            let (_, request) = self.requests.remove(0);
            let mut bytes = Vec::new();
            let header = Header {
                sysid: 255,
                compid: 190,
                seq: 0,
            };
            frame::encode(&mut bytes, Version::V2, header, &Msg::Transfer(request));
            let mut stats = ScanStats::default();
            push_datagram(&bytes, Instant::now(), 0, false, &mut stats, out);
            Ok(())
        }

        fn scan_stats(&self) -> ScanStats {
            ScanStats::default()
        }

        fn kind(&self) -> LinkKind {
            LinkKind::Connecting
        }

        fn keep_raw(&mut self) {}
    }

    fn settings(drop: f64) -> ResponderSettings {
        ResponderSettings {
            id: SysComp::new(1, 1),
            delay: Duration::from_millis(50),
            jitter: Duration::ZERO,
            drop,
            dup: 0.0,
            seed: 3,
            answer_ping: true,
            signing: None,
            streams: Vec::new(),
            stream_drop: 0.0,
            serve: ServeSpec {
                params: 200,
                mission: 0,
                file_size: 0,
            },
            transfer_rate: 100.0,
        }
    }

    const US: Target = Target {
        system: 1,
        component: 1,
    };

    #[tokio::test(start_paused = true)]
    async fn a_list_goes_at_the_rate_through_the_delay_and_drop_of_the_replies() {
        let mut link = Scripted {
            start: Instant::now(),
            requests: vec![
                (
                    Duration::from_secs(1),
                    Transfer::ParamRequestList { target: US },
                ),
                // A re-request in the middle goes before the list's next.
                (
                    Duration::from_millis(1_505),
                    Transfer::ParamRequestRead {
                        target: US,
                        id: ParamId::new("MAVPING_0007"),
                        index: -1,
                    },
                ),
            ],
            sent: Vec::new(),
        };
        let stop = Notify::new();
        let settings = settings(0.1);
        let ((counts, error), ()) = tokio::join!(run(&settings, &mut link, &stop), async {
            tokio::time::sleep(Duration::from_secs(5)).await;
            stop.notify_one();
        });
        assert!(error.is_none());
        let served = counts.served;
        let values: Vec<(Duration, u16)> = link
            .sent
            .iter()
            .filter_map(|(at, f)| match f.msg {
                Msg::Transfer(Transfer::ParamValue(p)) => Some((*at, p.index)),
                _ => None,
            })
            .collect();
        // 201 frames taken at 100 a second from 1 s; a tenth dropped, the
        // rest written 50 ms after they were taken.
        assert_eq!(served.sent.param_value + served.dropped.param_value, 201);
        assert_eq!(values.len() as u64, served.sent.param_value);
        assert!((10..35).contains(&served.dropped.param_value), "{served:?}");
        let first = values[0].0;
        let last = values.last().unwrap().0;
        assert!(
            first >= Duration::from_millis(1_050) && first < Duration::from_millis(1_080),
            "{first:?}"
        );
        // The 201st taken at 3 s (the last written earlier if it was
        // dropped).
        assert!(
            last > Duration::from_millis(2_900) && last < Duration::from_millis(3_052),
            "{last:?}"
        );
        // Never faster than the rate: two frames 10 ms apart at least, but
        // for the read's reply between two of the list's.
        let fast = values
            .windows(2)
            .filter(|w| w[1].0.saturating_sub(w[0].0) < Duration::from_millis(9))
            .count();
        assert!(fast <= 2, "{fast}");
        // The read was answered at once (unless dropped), between the
        // list's 50th and 52nd.
        let read = values
            .iter()
            .position(|&(at, i)| i == 7 && at > first + Duration::from_millis(100));
        if let Some(k) = read {
            assert!((45..=52).contains(&k), "{k}");
        }
        let r = served.requests;
        assert_eq!(
            (r.param_lists, r.param_reads, counts.replies_sent),
            (1, 1, 0)
        );
        let line = counts.to_string();
        assert!(
            line.contains(&format!(
                "; transfers: 2 requests (1 PARAM_REQUEST_LIST, 1 PARAM_REQUEST_READ), {} frames \
                 sent ({} PARAM_VALUE), {} dropped ({} PARAM_VALUE), 0 doubled",
                values.len(),
                values.len(),
                served.dropped.param_value,
                served.dropped.param_value
            )),
            "{line}"
        );
    }
}
