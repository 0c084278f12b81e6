//! MAVLink 2 message signing: pure, synchronous, no clock inside.
//!
//! A signed frame has incompat flag 0x01 and 13 more bytes after its CRC:
//! a link id, a 48-bit timestamp (10 µs units since 2015-01-01 00:00:00
//! UTC, little endian) and the first 6 bytes of
//! `sha256(secret_key + header + payload + crc + link_id + timestamp)`,
//! where the header starts with the 0xFD start byte. The same layout as
//! pymavlink, MAVProxy, ArduPilot and PX4.
//!
//! - [`SecretKey`]: the 32-byte secret, from hex or a passphrase.
//! - [`Signer`]: signs our outgoing frames with a monotonic timestamp.
//! - [`Gate`]: decides which received frames the rest of mavping may see
//!   (signature checked, replays refused) and counts what it refused.

use std::collections::HashMap;
use std::time::Duration;

use sha2::{Digest, Sha256};
use thiserror::Error;

use super::scanner::{IFLAG_SIGNED, STX_V2};
use super::SysComp;

/// Link id, timestamp and the 6-byte signature.
pub(crate) const SIGNATURE_LEN: usize = 13;
const TAG_LEN: usize = 6;
const V2_HEADER: usize = 10;
/// Seconds from the Unix epoch to 2015-01-01 00:00:00 UTC.
pub(crate) const EPOCH_2015_UNIX_S: u64 = 1_420_070_400;
/// pymavlink's rule for a stream seen for the first time: its timestamp may
/// be at most one minute behind the newest timestamp accepted so far.
const NEW_STREAM_WINDOW: u64 = 60 * 100_000;
/// Streams (sysid, compid, link id) whose last timestamp is remembered.
pub(crate) const MAX_STREAMS: usize = 1024;

/// The 32-byte signing secret. Its `Debug` never shows the key.
#[derive(Clone, Copy, PartialEq, Eq)]
pub(crate) struct SecretKey([u8; 32]);

impl std::fmt::Debug for SecretKey {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("SecretKey(<redacted>)")
    }
}

#[derive(Debug, Error, PartialEq, Eq)]
pub(crate) enum KeyError {
    #[error("the signing key is empty")]
    Empty,
}

impl SecretKey {
    #[cfg(test)]
    pub(crate) const fn from_bytes(bytes: [u8; 32]) -> Self {
        SecretKey(bytes)
    }

    /// 64 hex characters are the key itself; anything else is a passphrase
    /// hashed with SHA-256, as MAVProxy's `signing setup` does.
    pub(crate) fn parse(text: &str) -> Result<Self, KeyError> {
        if text.is_empty() {
            return Err(KeyError::Empty);
        }
        if text.len() == 64 && text.bytes().all(|b| b.is_ascii_hexdigit()) {
            let mut key = [0u8; 32];
            for (i, byte) in key.iter_mut().enumerate() {
                *byte = u8::from_str_radix(&text[2 * i..2 * i + 2], 16).expect("hex checked");
            }
            return Ok(SecretKey(key));
        }
        Ok(SecretKey(Sha256::digest(text.as_bytes()).into()))
    }

    /// The first 6 bytes of sha256(key + `signed`), where `signed` is the
    /// frame from its start byte up to and including the timestamp.
    fn tag(&self, signed: &[u8]) -> [u8; TAG_LEN] {
        let mut h = Sha256::new();
        h.update(self.0);
        h.update(signed);
        let digest = h.finalize();
        let mut tag = [0u8; TAG_LEN];
        tag.copy_from_slice(&digest[..TAG_LEN]);
        tag
    }
}

/// A signing timestamp (10 µs units since 2015-01-01) for a wall-clock
/// time given as the time since the Unix epoch.
pub(crate) fn timestamp_at(since_unix_epoch: Duration) -> u64 {
    let since_2015 = since_unix_epoch.saturating_sub(Duration::from_secs(EPOCH_2015_UNIX_S));
    (since_2015.as_micros() / 10) as u64 & 0xFFFF_FFFF_FFFF
}

/// The wall clock's signing timestamp now.
pub(crate) fn timestamp_now() -> u64 {
    timestamp_at(
        std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .unwrap_or_default(),
    )
}

/// The signature's timestamp of one whole frame whose header says it is
/// signed (10 µs units since 2015-01-01), unchecked: a clock reading for
/// the frame's age, not a verdict on the signature.
pub(crate) fn signature_timestamp(raw: &[u8]) -> Option<u64> {
    let block = raw.len().checked_sub(SIGNATURE_LEN).map(|at| &raw[at..])?;
    (raw.len() >= V2_HEADER + SIGNATURE_LEN && raw[0] == STX_V2).then(|| {
        u64::from_le_bytes([
            block[1], block[2], block[3], block[4], block[5], block[6], 0, 0,
        ])
    })
}

/// The whole bytes of a received signed MAVLink 2 frame, kept so its
/// signature can be checked once a key is known.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct SignedBytes(Box<[u8]>);

impl SignedBytes {
    /// `Some` when `raw` (one whole, CRC-checked frame) is signed.
    pub(crate) fn of(raw: &[u8]) -> Option<Self> {
        let signed = raw.len() >= V2_HEADER + SIGNATURE_LEN
            && raw[0] == STX_V2
            && raw[2] & IFLAG_SIGNED != 0;
        signed.then(|| SignedBytes(raw.into()))
    }

    fn block(&self) -> &[u8] {
        &self.0[self.0.len() - SIGNATURE_LEN..]
    }

    pub(crate) fn link_id(&self) -> u8 {
        self.block()[0]
    }

    pub(crate) fn timestamp(&self) -> u64 {
        let b = self.block();
        u64::from_le_bytes([b[1], b[2], b[3], b[4], b[5], b[6], 0, 0])
    }

    /// Whether `key` made this signature.
    pub(crate) fn verify(&self, key: &SecretKey) -> bool {
        let (signed, tag) = self.0.split_at(self.0.len() - TAG_LEN);
        key.tag(signed) == tag
    }
}

/// Signs our outgoing frames. The timestamp never goes backwards and never
/// repeats: each frame gets max(now, last + 1).
#[derive(Debug, Clone)]
pub(crate) struct Signer {
    key: SecretKey,
    link_id: u8,
    last: u64,
}

impl Signer {
    pub(crate) fn new(key: SecretKey, link_id: u8) -> Self {
        Signer {
            key,
            link_id,
            last: 0,
        }
    }

    /// Turns the unsigned MAVLink 2 frame at the end of `buf` (starting at
    /// `start`) into a signed one: sets the flag, recomputes the CRC (the
    /// flag is under it) and appends the signature. `now` is a signing
    /// timestamp, e.g. from [`timestamp_now`]. Returns the timestamp used.
    pub(crate) fn sign(&mut self, buf: &mut Vec<u8>, start: usize, now: u64) -> u64 {
        let frame = &mut buf[start..];
        assert!(
            frame[0] == STX_V2 && frame[2] & IFLAG_SIGNED == 0,
            "only unsigned MAVLink 2 frames can be signed"
        );
        frame[2] |= IFLAG_SIGNED;
        let crc_at = V2_HEADER + usize::from(frame[1]);
        let msgid = u32::from_le_bytes([frame[7], frame[8], frame[9], 0]);
        let extra = super::scanner::extra_crc(msgid).expect("we only encode known messages");
        let crc = mavlink::calculate_crc(&frame[1..crc_at], extra);
        frame[crc_at..crc_at + 2].copy_from_slice(&crc.to_le_bytes());

        let timestamp = now.max(self.last + 1) & 0xFFFF_FFFF_FFFF;
        self.last = timestamp;
        buf.push(self.link_id);
        buf.extend_from_slice(&timestamp.to_le_bytes()[..6]);
        let tag = self.key.tag(&buf[start..]);
        buf.extend_from_slice(&tag);
        timestamp
    }
}

/// What the gate decided about one received frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum SignatureCheck {
    /// Signed with our key, timestamp newer than its stream's last one.
    Signed,
    /// Not signed, and unsigned frames are allowed.
    Unsigned,
    /// Signed, but we have no key to check it with.
    SignedUnchecked,
    RejectedUnsigned,
    RejectedBadSignature,
    RejectedReplay,
}

impl SignatureCheck {
    pub(crate) fn accepted(self) -> bool {
        matches!(
            self,
            SignatureCheck::Signed | SignatureCheck::Unsigned | SignatureCheck::SignedUnchecked
        )
    }
}

/// Frames the gate let through and refused, exact.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize)]
pub(crate) struct SigningCounts {
    /// Accepted: correctly signed, not replayed.
    pub(crate) signed: u64,
    /// Accepted without a check: signed, but we have no key.
    pub(crate) signed_unchecked: u64,
    /// Accepted unsigned (no `--require-signed`; or a radio's RADIO_STATUS).
    pub(crate) unsigned: u64,
    /// Refused: not signed while signatures are required.
    pub(crate) rejected_unsigned: u64,
    /// Refused: signed, but not with our key (or altered on the way).
    pub(crate) rejected_bad_signature: u64,
    /// Refused: correctly signed, but its timestamp was not newer than the
    /// last one accepted on its stream (or too old for a new stream).
    pub(crate) rejected_replay: u64,
}

impl SigningCounts {
    fn record(&mut self, v: SignatureCheck) {
        match v {
            SignatureCheck::Signed => self.signed += 1,
            SignatureCheck::SignedUnchecked => self.signed_unchecked += 1,
            SignatureCheck::Unsigned => self.unsigned += 1,
            SignatureCheck::RejectedUnsigned => self.rejected_unsigned += 1,
            SignatureCheck::RejectedBadSignature => self.rejected_bad_signature += 1,
            SignatureCheck::RejectedReplay => self.rejected_replay += 1,
        }
    }
}

impl std::fmt::Display for SigningCounts {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if self.signed_unchecked > 0 {
            write!(
                f,
                "{} signed frames accepted unchecked; ",
                self.signed_unchecked
            )?;
        }
        write!(
            f,
            "{} signed and {} unsigned frames accepted; rejected {} unsigned, \
             {} with a bad signature, {} replayed",
            self.signed,
            self.unsigned,
            self.rejected_unsigned,
            self.rejected_bad_signature,
            self.rejected_replay
        )
    }
}

/// Signing in a run's summary: what the gate checked with a key, or,
/// without one, the signed frames it let through unchecked.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub(crate) struct SigningSummary {
    /// A key was given: our frames are signed, signatures checked.
    pub(crate) key: bool,
    /// `--require-signed`
    pub(crate) required: bool,
    /// Our outgoing link id (with a key).
    pub(crate) link_id: Option<u8>,
    #[serde(flatten)]
    pub(crate) counts: SigningCounts,
}

/// The last timestamp accepted per stream (sysid, compid, link id), for at
/// most [`MAX_STREAMS`] streams: constant memory whatever arrives.
///
/// When full, the stream with the oldest timestamp is forgotten and its
/// timestamp becomes a floor that every new stream must beat, so a
/// forgotten stream's frames cannot be replayed either.
#[derive(Debug, Default)]
struct ReplayTable {
    last: HashMap<(u8, u8, u8), u64>,
    newest: u64,
    floor: Option<u64>,
}

impl ReplayTable {
    fn admit(&mut self, stream: (u8, u8, u8), timestamp: u64) -> bool {
        match self.last.get_mut(&stream) {
            Some(last) => {
                if timestamp <= *last {
                    return false;
                }
                *last = timestamp;
            }
            None => {
                if timestamp + NEW_STREAM_WINDOW < self.newest
                    || self.floor.is_some_and(|floor| timestamp <= floor)
                {
                    return false;
                }
                if self.last.len() >= MAX_STREAMS {
                    let (&oldest, &at) = self
                        .last
                        .iter()
                        .min_by_key(|(_, &t)| t)
                        .expect("table is full");
                    self.last.remove(&oldest);
                    self.floor = Some(self.floor.map_or(at, |f| f.max(at)));
                }
                self.last.insert(stream, timestamp);
            }
        }
        self.newest = self.newest.max(timestamp);
        true
    }
}

/// Signing, as configured: our frames are signed with `key` on `link_id`;
/// received frames' signatures are checked, and `require_signed` also
/// refuses unsigned ones.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SigningConfig {
    pub(crate) key: SecretKey,
    pub(crate) link_id: u8,
    pub(crate) require_signed: bool,
}

impl SigningConfig {
    pub(crate) fn signer(&self) -> Signer {
        Signer::new(self.key, self.link_id)
    }
}

/// Checks every received frame against a [`SigningConfig`] before anything else
/// looks at it, and counts what it refused. Without a key it checks
/// nothing and counts what came signed.
#[derive(Debug)]
pub(crate) struct Gate {
    policy: Option<SigningConfig>,
    replay: ReplayTable,
    counts: SigningCounts,
}

impl Gate {
    pub(crate) fn new(policy: Option<SigningConfig>) -> Self {
        Gate {
            policy,
            replay: ReplayTable::default(),
            counts: SigningCounts::default(),
        }
    }

    /// Judges one frame from `source` (its header ids); `signed` is its
    /// bytes when it carries a signature. `radio_status` frames may come
    /// unsigned even when signatures are required: a SiK radio injects
    /// them and cannot sign (ArduPilot accepts them the same way).
    pub(crate) fn judge(
        &mut self,
        source: SysComp,
        signed: Option<&SignedBytes>,
        radio_status: bool,
    ) -> SignatureCheck {
        let Some(policy) = &self.policy else {
            let check = match signed {
                None => SignatureCheck::Unsigned,
                Some(_) => SignatureCheck::SignedUnchecked,
            };
            self.counts.record(check);
            return check;
        };
        let check = match signed {
            None if policy.require_signed && !radio_status => SignatureCheck::RejectedUnsigned,
            None => SignatureCheck::Unsigned,
            Some(s) if !s.verify(&policy.key) => SignatureCheck::RejectedBadSignature,
            Some(s) => {
                let stream = (source.sysid, source.compid, s.link_id());
                if self.replay.admit(stream, s.timestamp()) {
                    SignatureCheck::Signed
                } else {
                    SignatureCheck::RejectedReplay
                }
            }
        };
        self.counts.record(check);
        check
    }

    pub(crate) fn counts(&self) -> SigningCounts {
        self.counts
    }

    /// What a run's summary reports.
    pub(crate) fn summary(&self) -> SigningSummary {
        SigningSummary {
            key: self.policy.is_some(),
            required: self.policy.is_some_and(|p| p.require_signed),
            link_id: self.policy.map(|p| p.link_id),
            counts: self.counts,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frame::{decode, encode, scan_datagram, Header, Msg, ScanStats, Version};

    fn hex(text: &str) -> Vec<u8> {
        (0..text.len())
            .step_by(2)
            .map(|i| u8::from_str_radix(&text[i..i + 2], 16).unwrap())
            .collect()
    }

    fn key() -> SecretKey {
        let mut k = [0u8; 32];
        for (i, b) in k.iter_mut().enumerate() {
            *b = i as u8;
        }
        SecretKey::from_bytes(k)
    }

    const PING: Msg = Msg::Ping {
        time_usec: 1_234_567,
        seq: 42,
        target_system: 255,
        target_component: 190,
    };

    /// pymavlink 2.4.50, key bytes 0..32, link id 7, timestamp 0x0102030405:
    /// `mav.ping_send(1234567, 42, 255, 190)` from 1/1, packet seq 0.
    const PYMAVLINK_PING: &str = "fd0e010000010104000087d61200000000002a000000ffbe\
                                  842507050403020100a0593f3d45c8";

    fn signed_ping(signer: &mut Signer, now: u64) -> Vec<u8> {
        let mut buf = vec![0xAA]; // something before, as in a shared buffer
        let header = Header {
            sysid: 1,
            compid: 1,
            seq: 0,
        };
        encode(&mut buf, Version::V2, header, &PING);
        signer.sign(&mut buf, 1, now);
        buf.remove(0);
        buf
    }

    #[test]
    fn signs_exactly_as_pymavlink_does() {
        let mut signer = Signer::new(key(), 7);
        assert_eq!(signed_ping(&mut signer, 0x0102030405), hex(PYMAVLINK_PING));
    }

    #[test]
    fn verifies_pymavlink_signature_and_reads_its_block() {
        let raw = hex(PYMAVLINK_PING);
        let mut stats = ScanStats::default();
        let mut frames = Vec::new();
        scan_datagram(&raw, &mut stats, &mut |f| {
            frames.push((decode(f), SignedBytes::of(f)))
        });
        let (frame, signed) = frames.pop().expect("the scanner accepts it");
        assert!(frame.signed);
        assert_eq!(frame.msg, PING);
        let signed = signed.expect("signed");
        assert_eq!(signed.link_id(), 7);
        assert_eq!(signed.timestamp(), 0x0102030405);
        assert!(signed.verify(&key()));
        assert!(!signed.verify(&SecretKey::parse("wrong").unwrap()));
        let mut altered = raw.clone();
        altered[raw.len() - 1] ^= 1;
        assert!(!SignedBytes::of(&altered).unwrap().verify(&key()));
    }

    #[test]
    fn unsigned_frames_have_no_signature_bytes() {
        let mut buf = Vec::new();
        let header = Header {
            sysid: 1,
            compid: 1,
            seq: 0,
        };
        encode(&mut buf, Version::V2, header, &PING);
        assert_eq!(SignedBytes::of(&buf), None);
        buf.clear();
        encode(&mut buf, Version::V1, header, &PING);
        assert_eq!(SignedBytes::of(&buf), None);
    }

    #[test]
    fn keys_from_hex_or_passphrase_like_mavproxy() {
        let hex_key = "000102030405060708090a0b0c0d0e0f101112131415161718191A1B1C1D1E1F";
        assert_eq!(SecretKey::parse(hex_key).unwrap(), key());
        // hashlib.sha256(b"correct horse").hexdigest()
        assert_eq!(
            SecretKey::parse("correct horse").unwrap(),
            SecretKey::parse("4104d36f8da2c254349f85836793ebe029e0c957063a34c91c2e9203187b5631")
                .unwrap()
        );
        // 63 hex characters are a passphrase, not a key.
        assert_ne!(
            SecretKey::parse(&hex_key[1..]).unwrap(),
            SecretKey::parse(&hex_key[..63]).unwrap()
        );
        assert_eq!(SecretKey::parse(""), Err(KeyError::Empty));
        assert_eq!(format!("{:?}", key()), "SecretKey(<redacted>)");
    }

    #[test]
    fn timestamps_count_10us_since_2015_and_never_repeat() {
        assert_eq!(timestamp_at(Duration::from_secs(EPOCH_2015_UNIX_S)), 0);
        assert_eq!(
            timestamp_at(Duration::from_secs(EPOCH_2015_UNIX_S + 1)),
            100_000
        );
        assert_eq!(timestamp_at(Duration::from_secs(0)), 0);
        let mut signer = Signer::new(key(), 0);
        let mut buf = Vec::new();
        let mut stamps = Vec::new();
        for now in [500, 500, 499, 1000] {
            buf.clear();
            encode(
                &mut buf,
                Version::V2,
                Header {
                    sysid: 1,
                    compid: 1,
                    seq: 0,
                },
                &PING,
            );
            stamps.push(signer.sign(&mut buf, 0, now));
            assert_eq!(SignedBytes::of(&buf).unwrap().timestamp(), signer.last);
        }
        assert_eq!(stamps, [500, 501, 502, 1000]);
    }

    fn policy(require_signed: bool) -> SigningConfig {
        SigningConfig {
            key: key(),
            link_id: 0,
            require_signed,
        }
    }

    #[test]
    fn gate_accepts_signed_refuses_forged_replayed_and_unsigned_when_required() {
        let mut ours = Signer::new(key(), 1);
        let mut forger = Signer::new(SecretKey::parse("guess").unwrap(), 1);
        let id = SysComp::new(1, 1);
        let first = SignedBytes::of(&signed_ping(&mut ours, 1_000)).unwrap();
        let second = SignedBytes::of(&signed_ping(&mut ours, 1_000)).unwrap();
        let forged = SignedBytes::of(&signed_ping(&mut forger, 5_000)).unwrap();

        let mut gate = Gate::new(Some(policy(true)));
        assert_eq!(gate.judge(id, Some(&first), false), SignatureCheck::Signed);
        assert_eq!(
            gate.judge(id, Some(&first), false),
            SignatureCheck::RejectedReplay
        );
        assert_eq!(gate.judge(id, Some(&second), false), SignatureCheck::Signed);
        assert_eq!(
            gate.judge(id, Some(&first), false),
            SignatureCheck::RejectedReplay
        );
        assert_eq!(
            gate.judge(id, Some(&forged), false),
            SignatureCheck::RejectedBadSignature
        );
        assert_eq!(
            gate.judge(id, None, false),
            SignatureCheck::RejectedUnsigned
        );
        assert_eq!(gate.judge(id, None, true), SignatureCheck::Unsigned);
        // The same bytes from another sender are another stream.
        assert_eq!(
            gate.judge(SysComp::new(2, 1), Some(&first), false),
            SignatureCheck::Signed
        );
        assert_eq!(
            gate.counts(),
            SigningCounts {
                signed: 3,
                unsigned: 1,
                rejected_unsigned: 1,
                rejected_bad_signature: 1,
                rejected_replay: 2,
                ..SigningCounts::default()
            }
        );

        let mut lenient = Gate::new(Some(policy(false)));
        assert_eq!(lenient.judge(id, None, false), SignatureCheck::Unsigned);
        assert_eq!(
            lenient.judge(id, Some(&forged), false),
            SignatureCheck::RejectedBadSignature
        );

        // Without a key nothing is checked, and what came signed is said.
        let mut keyless = Gate::new(None);
        assert_eq!(
            keyless.judge(id, Some(&forged), false),
            SignatureCheck::SignedUnchecked
        );
        assert_eq!(keyless.judge(id, None, false), SignatureCheck::Unsigned);
        let summary = keyless.summary();
        assert!(!summary.key && summary.link_id.is_none());
        assert_eq!(
            (summary.counts.signed_unchecked, summary.counts.unsigned),
            (1, 1)
        );
    }

    #[test]
    fn replay_table_stays_bounded_and_forgotten_streams_cannot_replay() {
        let mut table = ReplayTable::default();
        let n = MAX_STREAMS as u64 * 3;
        for i in 0..n {
            let stream = ((i % 256) as u8, (i / 256) as u8, 0);
            assert!(table.admit(stream, 10_000_000 + i));
            assert!(table.last.len() <= MAX_STREAMS);
        }
        assert_eq!(table.last.len(), MAX_STREAMS);
        // Stream 0/0 was forgotten long ago: its old frame stays refused.
        assert!(!table.admit((0, 0, 0), 10_000_000));
        // A live stream moves on; an old one far behind is refused as new.
        assert!(table.admit((0, 0, 0), 20_000_000));
        assert!(!table.admit((9, 9, 9), 20_000_000 - NEW_STREAM_WINDOW - 1));
    }
}
