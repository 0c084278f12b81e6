//! `--stream`: telemetry sent unasked at its rate, as a vehicle does,
//! numbered with the same packet sequence as every other frame, some
//! numbered and then dropped by `--stream-drop`.

use rand::Rng;

use super::counts::StreamCount;
use super::respond_loop::Responder;
use crate::telemetry::{Schedule, StreamKind};
use crate::transport::{LinkError, Transport};

/// Most frames one stream sends back to back before the loop reads the
/// link again.
const MAX_BURST: usize = 64;
/// Seeds the streams' phases and `--stream-drop` beside `--seed`, so
/// streaming leaves the replies' draws as they were.
pub(super) const STREAM_SEED: u64 = 0x7e1e_3e7e_5eed_0002;

/// One `--stream`: its timetable and counts.
pub(super) struct Stream {
    pub(super) kind: StreamKind,
    pub(super) schedule: Schedule,
    pub(super) count: StreamCount,
}

impl Responder {
    /// Sends every streamed frame due at `now` (at most a burst per
    /// stream), each numbered, some dropped by `--stream-drop` instead.
    pub(super) async fn stream_due<T: Transport>(
        &mut self,
        link: &mut T,
        now: u64,
    ) -> Result<(), LinkError> {
        for s in &mut self.streams {
            for _ in 0..MAX_BURST {
                let due = s.schedule.due_ns();
                if due > now {
                    break;
                }
                s.schedule.advance();
                let msg = s.kind.msg((due / 1_000_000) as u32, self.heartbeat.msg());
                let frame = self.sender.frame(&msg);
                let drop = self.settings.stream_drop;
                if drop > 0.0 && self.stream_rng.gen::<f64>() < drop {
                    s.count.dropped += 1;
                    continue;
                }
                link.send(frame).await?;
                s.count.sent += 1;
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use std::time::Duration;

    use tokio::sync::Notify;
    use tokio::time::Instant;

    use super::*;
    use crate::frame::{self, ids, ScanStats, SysComp};
    use crate::responder::respond_loop::run;
    use crate::responder::settings::ResponderSettings;
    use crate::transport::{Inbound, LinkKind, PathId};

    /// A link that keeps what is sent to it and hears nothing.
    #[derive(Default)]
    struct Capture {
        sent: Vec<frame::Frame>,
    }

    impl Transport for Capture {
        async fn send(&mut self, bytes: &[u8]) -> Result<Instant, LinkError> {
            let mut stats = ScanStats::default();
            frame::scan_datagram(bytes, &mut stats, &mut |raw| {
                self.sent.push(frame::decode(raw));
            });
            Ok(Instant::now())
        }

        async fn send_to(&mut self, _: PathId, bytes: &[u8]) -> Result<Instant, LinkError> {
            self.send(bytes).await
        }

        async fn recv(&mut self, _: &mut Vec<Inbound>) -> Result<(), LinkError> {
            std::future::pending().await
        }

        fn scan_stats(&self) -> ScanStats {
            ScanStats::default()
        }

        fn kind(&self) -> LinkKind {
            LinkKind::Connecting
        }

        fn keep_raw(&mut self) {}
    }

    #[tokio::test(start_paused = true)]
    async fn streams_go_at_their_rates_numbered_with_everything_else() {
        let settings = ResponderSettings {
            id: SysComp::new(1, 1),
            delay: Duration::ZERO,
            jitter: Duration::ZERO,
            drop: 0.0,
            dup: 0.0,
            seed: 1,
            answer_ping: true,
            signing: None,
            streams: crate::telemetry::parse_list("ATTITUDE@50,HEARTBEAT@2").unwrap(),
            stream_drop: 0.1,
            serve: crate::answering::transfers::ServeSpec {
                params: 0,
                mission: 0,
                file_size: 0,
            },
            transfer_rate: 1000.0,
        };
        let mut link = Capture::default();
        let stop = Notify::new();
        let ((counts, error), ()) = tokio::join!(run(&settings, &mut link, &stop), async {
            tokio::time::sleep(Duration::from_millis(9_999)).await;
            stop.notify_one();
        });
        assert!(error.is_none());
        let [attitude, heartbeat] = counts.streamed[..] else {
            panic!("two streams: {counts:?}")
        };
        // 10 s: 500 ATTITUDE from a random phase, 20 HEARTBEAT from the
        // start (and no 1 Hz one beside them), a tenth of both dropped.
        assert!(
            (499..=500).contains(&(attitude.sent + attitude.dropped)),
            "{counts:?}"
        );
        assert_eq!(heartbeat.sent + heartbeat.dropped, 20, "{counts:?}");
        let dropped = attitude.dropped + heartbeat.dropped;
        assert!((30..75).contains(&dropped), "{counts:?}");
        let of = |msgid| link.sent.iter().filter(|f| f.msgid == msgid).count() as u64;
        assert_eq!(of(30), attitude.sent);
        assert_eq!(of(ids::HEARTBEAT), heartbeat.sent);
        // One sequence from 0: every gap is a dropped frame, the rest were
        // dropped after the last frame sent.
        let mut next = 0u64;
        let mut missing = 0;
        for f in &link.sent {
            let gap = u64::from(f.packet_seq.wrapping_sub(next as u8));
            missing += gap;
            next += gap + 1;
        }
        let numbered = attitude.sent + attitude.dropped + heartbeat.sent + heartbeat.dropped;
        assert!(numbered - next < 5 && missing + (numbered - next) == dropped);
        let line = counts.to_string();
        assert!(
            line.ends_with(&format!(
                "; {} frames streamed ({} ATTITUDE, {} HEARTBEAT), {dropped} dropped by \
                 --stream-drop",
                attitude.sent + heartbeat.sent,
                attitude.sent,
                heartbeat.sent
            )),
            "{line}"
        );
    }
}
