//! Default deny: `/probe` opens only targets an allow pattern admits. In a
//! pattern, `*` stands for one part of an address (no `.`, `:` or `/`: a
//! port, an octet, a device or host name) and `**` for anything, so
//! `udpout:10.0.0.*:14550` cannot be stretched to
//! `udpout:10.0.0.5.evil.example:14550`.

use crate::config::error::ConfigError;
use crate::transport::address::LinkSpec;

/// An allow pattern, in the canonical form targets are compared in.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Pattern(String);

/// Link kinds as patterns may spell them, and their canonical form.
const KINDS: [(&str, &str); 10] = [
    ("udpin:", "udpin:"),
    ("udp:", "udpin:"),
    ("udpout:", "udpout:"),
    ("udpbcast:", "udpbcast:"),
    ("tcpout:", "tcp:"),
    ("tcp:", "tcp:"),
    ("tcpin:", "tcpin:"),
    ("serial:", "serial:"),
    ("/", "serial:/"),
    ("sim:", "sim:"),
];

impl Pattern {
    pub fn parse(text: &str) -> Result<Self, ConfigError> {
        let text = text.trim();
        let Some((given, canonical)) = KINDS.iter().find(|(k, _)| text.starts_with(k)) else {
            return Err(ConfigError::value(
                "allow pattern",
                format!("'{text}'"),
                "start it with a link kind (udpout:, udpin:, udpbcast:, tcp:, tcpin:, serial:, \
                 /dev/..., sim:), e.g. 'udpout:127.0.0.1:*'",
            ));
        };
        let mut pattern = format!("{canonical}{}", &text[given.len()..]);
        if pattern.starts_with("serial:") {
            pattern = without_baud(&pattern).to_string();
        }
        if pattern.len() <= canonical.len() {
            return Err(ConfigError::value(
                "allow pattern",
                format!("'{text}'"),
                format!("it names no address; '{canonical}**' allows every one"),
            ));
        }
        Ok(Pattern(pattern))
    }

    /// Whether the target (in its canonical form) is admitted.
    pub fn admits(&self, target: &LinkSpec) -> bool {
        glob(self.0.as_bytes(), canonical(target).as_bytes())
    }
}

impl std::fmt::Display for Pattern {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

/// A serial device is allowed whatever its baud: the device is what matters.
fn without_baud(serial: &str) -> &str {
    match serial.rsplit_once(':') {
        Some((device, baud))
            if device.len() > "serial".len()
                && !baud.is_empty()
                && baud.bytes().all(|b| b.is_ascii_digit() || b == b'*') =>
        {
            device
        }
        _ => serial,
    }
}

/// The form a target is matched in: how mavping prints it, serial
/// devices without their baud.
fn canonical(target: &LinkSpec) -> String {
    match target {
        LinkSpec::Serial { path, .. } => format!("serial:{path}"),
        other => other.to_string(),
    }
}

/// `*` matches a run of characters other than `.`, `:` and `/`; `**`
/// any run at all; everything else itself. One pass over the pattern,
/// keeping which prefixes of the text the pattern so far can match: time
/// pattern × text, where trying each split of each star in turn grows
/// with the text's length to the power of the stars (a pattern of 16 stars
/// took longer than the fuzzer's 10 s on a 60-byte target).
fn glob(pattern: &[u8], text: &[u8]) -> bool {
    // matched[j]: the pattern so far matches text[..j].
    let mut matched = vec![false; text.len() + 1];
    matched[0] = true;
    let mut i = 0;
    while i < pattern.len() {
        match pattern[i..] {
            [b'*', b'*', ..] => {
                for j in 1..=text.len() {
                    matched[j] |= matched[j - 1];
                }
                i += 2;
            }
            [b'*', ..] => {
                for j in 1..=text.len() {
                    let in_part = !matches!(text[j - 1], b'.' | b':' | b'/');
                    matched[j] |= matched[j - 1] && in_part;
                }
                i += 1;
            }
            [c, ..] => {
                for j in (1..=text.len()).rev() {
                    matched[j] = matched[j - 1] && text[j - 1] == c;
                }
                matched[0] = false;
                i += 1;
            }
            [] => unreachable!("i < pattern.len()"),
        }
    }
    matched[text.len()]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spec(s: &str) -> LinkSpec {
        s.parse().unwrap()
    }

    #[test]
    fn patterns_stand_for_parts_of_an_address() {
        let p = |s| Pattern::parse(s).unwrap();
        assert!(p("udpout:127.0.0.1:*").admits(&spec("udpout:127.0.0.1:14550")));
        assert!(!p("udpout:127.0.0.1:*").admits(&spec("udpout:127.0.0.2:14550")));
        assert!(!p("udpout:127.0.0.1:*").admits(&spec("udpin:127.0.0.1:14550")));
        assert!(p("udpout:10.0.0.*:14550").admits(&spec("udpout:10.0.0.7:14550")));
        // A host name cannot stand in for the last octet.
        assert!(!p("udpout:10.0.0.*:14550").admits(&spec("udpout:10.0.0.5.evil.example:14550")));
        assert!(p("udpout:**").admits(&spec("udpout:gcs.example:14550")));
        // Kinds are compared in their canonical form.
        assert!(p("udp:0.0.0.0:*").admits(&spec("udpin:0.0.0.0:14550")));
        assert!(p("tcpout:127.0.0.1:5760").admits(&spec("tcp:127.0.0.1:5760")));
        // Serial devices, whatever the baud.
        assert!(p("/dev/ttyUSB*").admits(&spec("serial:/dev/ttyUSB0:57600")));
        assert!(p("serial:/dev/ttyUSB*:57600").admits(&spec("/dev/ttyUSB1")));
        assert!(!p("/dev/ttyUSB*").admits(&spec("/dev/ttyS0")));
        assert!(!p("/dev/tty*").admits(&spec("/dev/pts/3")));
        assert!(p("sim:**").admits(&spec("sim:?loss=0.5%")));
        assert!(p("udpout:[::1]:*").admits(&spec("udpout:[::1]:14550")));
        for bad in ["127.0.0.1:*", "*", "udpout:", "sim:"] {
            assert!(Pattern::parse(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn stars_match_as_a_backtracking_glob_would() {
        // The old recursive form, for texts short enough for it.
        fn slow(pattern: &[u8], text: &[u8]) -> bool {
            match pattern {
                [] => text.is_empty(),
                [b'*', b'*', rest @ ..] => (0..=text.len()).any(|i| slow(rest, &text[i..])),
                [b'*', rest @ ..] => {
                    let part = text
                        .iter()
                        .position(|b| matches!(b, b'.' | b':' | b'/'))
                        .unwrap_or(text.len());
                    (0..=part).any(|i| slow(rest, &text[i..]))
                }
                [c, rest @ ..] => text.first() == Some(c) && slow(rest, &text[1..]),
            }
        }
        let patterns = [
            "a*b", "**b", "*.*", "a**", "*", "**", "*:**:*", "a*.*b", "***", "****.*",
        ];
        let texts = [
            "", "ab", "a.b", "axxb", "a:b.c", "b", "a..b", ":.", "aab.b", "x.y:z",
        ];
        for p in patterns {
            for t in texts {
                let (p, t) = (p.as_bytes(), t.as_bytes());
                assert_eq!(glob(p, t), slow(p, t), "{p:?} {t:?}");
            }
        }
    }

    #[test]
    fn many_stars_take_no_longer_than_a_few() {
        // Found by the parse fuzz target: 16 stars against a long target
        // took longer than 10 s when each star tried every split.
        let pattern = format!("tcp:{}x", "*".repeat(40));
        let target = format!("tcp:{}:1", "a".repeat(4000));
        assert!(!glob(pattern.as_bytes(), target.as_bytes()));
    }
}
