//! Basic auth against the web config's bcrypt hashes. bcrypt is slow by
//! design (tens of milliseconds a check): each check runs on a blocking
//! thread, off the thread that serves and probes, and its answer is kept
//! (keyed by a SHA-256 of user, hash and password, as the exporter-toolkit
//! does) so a scrape every few seconds costs one bcrypt, not one each.

use std::cell::RefCell;
use std::collections::HashMap;

use base64::Engine;
use hyper::header::{HeaderMap, AUTHORIZATION};
use sha2::{Digest, Sha256};

use crate::config::WebConfig;

/// Checks remembered at most; then the memory starts again.
const CACHE: usize = 256;

#[derive(Default)]
pub(crate) struct Checker {
    known: RefCell<HashMap<[u8; 32], bool>>,
}

impl Checker {
    /// True when `web` asks for no users, or the request's `Authorization:
    /// Basic` names one with the right password.
    pub(crate) async fn allows(&self, web: &WebConfig, headers: &HeaderMap) -> bool {
        if web.users.is_empty() {
            return true;
        }
        let Some((user, password)) = credentials(headers) else {
            return false;
        };
        // An unknown user costs a bcrypt too, so timing tells no names.
        let (hash, known_user) = match web.users.get(&user) {
            Some(h) => (h.clone(), true),
            None => (
                web.users.values().next().cloned().unwrap_or_default(),
                false,
            ),
        };
        let key: [u8; 32] = Sha256::new()
            .chain_update(user.as_bytes())
            .chain_update([0])
            .chain_update(hash.as_bytes())
            .chain_update([0])
            .chain_update(password.as_bytes())
            .finalize()
            .into();
        if let Some(&ok) = self.known.borrow().get(&key) {
            return ok && known_user;
        }
        let ok = tokio::task::spawn_blocking(move || bcrypt::verify(password, &hash))
            .await
            .is_ok_and(|r| r.unwrap_or(false));
        let mut known = self.known.borrow_mut();
        if known.len() >= CACHE {
            known.clear();
        }
        known.insert(key, ok);
        ok && known_user
    }
}

/// `Authorization: Basic base64(user:password)`.
fn credentials(headers: &HeaderMap) -> Option<(String, String)> {
    let value = headers.get(AUTHORIZATION)?.to_str().ok()?;
    let (scheme, encoded) = value.trim().split_once(' ')?;
    if !scheme.eq_ignore_ascii_case("basic") {
        return None;
    }
    let decoded = base64::engine::general_purpose::STANDARD
        .decode(encoded.trim())
        .ok()?;
    let text = String::from_utf8(decoded).ok()?;
    let (user, password) = text.split_once(':')?;
    Some((user.to_string(), password.to_string()))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn web(user: &str, password: &str) -> WebConfig {
        WebConfig {
            users: [(user.to_string(), bcrypt::hash(password, 4).unwrap())].into(),
            ..WebConfig::default()
        }
    }

    fn basic(user_password: &str) -> HeaderMap {
        let mut h = HeaderMap::new();
        let encoded = base64::engine::general_purpose::STANDARD.encode(user_password);
        h.insert(AUTHORIZATION, format!("Basic {encoded}").parse().unwrap());
        h
    }

    #[tokio::test]
    async fn only_the_right_user_and_password_pass() {
        let checker = Checker::default();
        let w = web("prometheus", "s3cret");
        assert!(
            checker
                .allows(&WebConfig::default(), &HeaderMap::new())
                .await
        );
        assert!(!checker.allows(&w, &HeaderMap::new()).await);
        assert!(checker.allows(&w, &basic("prometheus:s3cret")).await);
        // Twice: the remembered answer is the same.
        assert!(checker.allows(&w, &basic("prometheus:s3cret")).await);
        assert!(!checker.allows(&w, &basic("prometheus:wrong")).await);
        // The right password under another name.
        assert!(!checker.allows(&w, &basic("grafana:s3cret")).await);
        assert!(!checker.allows(&w, &basic("prometheus")).await);
        let mut bearer = HeaderMap::new();
        bearer.insert(AUTHORIZATION, "Bearer s3cret".parse().unwrap());
        assert!(!checker.allows(&w, &bearer).await);
    }
}
