//! `--web.config.file`: the exporter-toolkit's YAML (the format every
//! Prometheus exporter reads) into what the HTTP server enforces: a TLS
//! configuration (rustls on ring), basic-auth users with bcrypt hashes, and
//! headers added to every response. Certificates and keys are read here, so
//! a bad file or a key that does not match its certificate is refused at
//! the start or at a reload, never at a client's handshake.

use std::collections::BTreeMap;
use std::fmt;
use std::path::{Path, PathBuf};
use std::str::FromStr;
use std::sync::Arc;

use hyper::header::{HeaderName, HeaderValue};
use rustls::server::WebPkiClientVerifier;
use rustls::RootCertStore;
use rustls_pki_types::pem::PemObject;
use rustls_pki_types::{CertificateDer, PrivateKeyDer};
use serde::Deserialize;

use super::super::{invalid, ConfigError};

/// The headers the exporter-toolkit lets a web config set; the others
/// (Content-Type, Content-Length...) are the server's to say.
const HEADERS: [&str; 5] = [
    "Content-Security-Policy",
    "X-Frame-Options",
    "X-Content-Type-Options",
    "X-XSS-Protection",
    "Strict-Transport-Security",
];

/// The file as written.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct File {
    tls_server_config: Option<TlsFile>,
    http_server_config: Option<HttpFile>,
    #[serde(default)]
    basic_auth_users: BTreeMap<String, String>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields, rename = "a map of cert_file, key_file...")]
struct TlsFile {
    cert_file: Option<PathBuf>,
    key_file: Option<PathBuf>,
    client_auth_type: Option<String>,
    client_ca_file: Option<PathBuf>,
    min_version: Option<String>,
    max_version: Option<String>,
    #[serde(default)]
    cipher_suites: Vec<String>,
    #[serde(default)]
    curve_preferences: Vec<String>,
    // Go's knob; rustls always prefers its own order.
    #[allow(dead_code)]
    prefer_server_cipher_suites: Option<bool>,
    #[serde(default)]
    client_allowed_sans: Vec<String>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields, rename = "a map of headers, http2")]
struct HttpFile {
    // HTTP/2 is Go's default; mavping serves HTTP/1.1, which Prometheus
    // speaks as well.
    #[allow(dead_code)]
    http2: Option<bool>,
    #[serde(default)]
    headers: BTreeMap<String, String>,
}

/// Which client certificates the server asks for (the exporter-toolkit's
/// names; those that accept unverified certificates are not offered).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum ClientAuth {
    NoClientCert,
    VerifyClientCertIfGiven,
    RequireAndVerifyClientCert,
}

impl fmt::Display for ClientAuth {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            ClientAuth::NoClientCert => "NoClientCert",
            ClientAuth::VerifyClientCertIfGiven => "VerifyClientCertIfGiven",
            ClientAuth::RequireAndVerifyClientCert => "RequireAndVerifyClientCert",
        })
    }
}

/// What the HTTP server enforces; the default is plain HTTP, open to all.
#[derive(Clone, Default)]
pub(crate) struct WebConfig {
    pub(crate) tls: Option<Arc<rustls::ServerConfig>>,
    pub(crate) client_auth: Option<ClientAuth>,
    /// User name to bcrypt hash.
    pub(crate) users: BTreeMap<String, String>,
    pub(crate) headers: Vec<(HeaderName, HeaderValue)>,
}

impl fmt::Debug for WebConfig {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.describe())
    }
}

impl WebConfig {
    /// Reads and checks `path` (`--web.config.file`), or the open default.
    pub(crate) fn load(path: Option<&Path>) -> Result<Self, ConfigError> {
        let Some(path) = path else {
            return Ok(WebConfig::default());
        };
        let fail = |e: String| invalid(format!("--web.config.file {}: {e}", path.display()));
        let text =
            std::fs::read_to_string(path).map_err(|e| fail(format!("cannot read it: {e}")))?;
        let file: File = if text.trim().is_empty() {
            File::default()
        } else {
            serde_norway::from_str(&text).map_err(|e| fail(one_line(&e.to_string())))?
        };
        // Relative paths are the file's, as the exporter-toolkit reads them.
        let dir = path.parent().unwrap_or(Path::new("."));
        let (tls, client_auth) = match &file.tls_server_config {
            None => (None, None),
            Some(t) => {
                let (config, auth) = tls(t, dir).map_err(fail)?;
                (Some(Arc::new(config)), Some(auth))
            }
        };
        let users = users(&file.basic_auth_users).map_err(fail)?;
        let headers = headers(file.http_server_config.as_ref()).map_err(fail)?;
        Ok(WebConfig {
            tls,
            client_auth,
            users,
            headers,
        })
    }

    /// One line on what is enforced (`--config.check`, the start line).
    pub(crate) fn describe(&self) -> String {
        let mut parts = vec![match self.client_auth {
            None => "plain HTTP".to_string(),
            Some(ClientAuth::NoClientCert) => "TLS".to_string(),
            Some(auth) => format!("TLS, client certificates {auth}"),
        }];
        parts.push(match self.users.len() {
            0 => "no basic auth".to_string(),
            1 => "1 basic-auth user".to_string(),
            n => format!("{n} basic-auth users"),
        });
        match self.headers.len() {
            0 => {}
            1 => parts.push("1 extra header".to_string()),
            n => parts.push(format!("{n} extra headers")),
        }
        parts.join(", ")
    }

    pub(crate) fn scheme(&self) -> &'static str {
        if self.tls.is_some() {
            "https"
        } else {
            "http"
        }
    }
}

/// serde_norway's messages may span lines (a snippet of the file): the
/// first says what and where.
fn one_line(message: &str) -> String {
    message.lines().next().unwrap_or(message).to_string()
}

fn tls(t: &TlsFile, dir: &Path) -> Result<(rustls::ServerConfig, ClientAuth), String> {
    let (Some(cert_file), Some(key_file)) = (&t.cert_file, &t.key_file) else {
        return Err("tls_server_config needs both cert_file and key_file".into());
    };
    for (key, given) in [
        ("cipher_suites", &t.cipher_suites),
        ("curve_preferences", &t.curve_preferences),
        ("client_allowed_sans", &t.client_allowed_sans),
    ] {
        if !given.is_empty() {
            return Err(format!(
                "{key} is not supported: mavping's TLS (rustls) offers only its own modern suites and groups; remove it"
            ));
        }
    }
    let versions = versions(t.min_version.as_deref(), t.max_version.as_deref())?;
    let auth = client_auth(t)?;
    if auth != ClientAuth::NoClientCert && t.client_ca_file.is_none() {
        return Err(format!("client_auth_type {auth} needs client_ca_file"));
    }
    let chain = certificates(&dir.join(cert_file), "cert_file")?;
    let key = PrivateKeyDer::from_pem_file(dir.join(key_file))
        .map_err(|e| format!("key_file {}: {e}", key_file.display()))?;
    let provider = Arc::new(rustls::crypto::ring::default_provider());
    let builder = rustls::ServerConfig::builder_with_provider(provider.clone())
        .with_protocol_versions(&versions)
        .map_err(|e| e.to_string())?;
    let builder = match (auth, &t.client_ca_file) {
        // (A verifying type without a CA was refused above.)
        (ClientAuth::NoClientCert, _) | (_, None) => builder.with_no_client_auth(),
        (_, Some(ca)) => {
            let mut roots = RootCertStore::empty();
            for cert in certificates(&dir.join(ca), "client_ca_file")? {
                roots
                    .add(cert)
                    .map_err(|e| format!("client_ca_file {}: {e}", ca.display()))?;
            }
            let verifier = WebPkiClientVerifier::builder_with_provider(Arc::new(roots), provider);
            let verifier = if auth == ClientAuth::VerifyClientCertIfGiven {
                verifier.allow_unauthenticated()
            } else {
                verifier
            };
            builder.with_client_cert_verifier(verifier.build().map_err(|e| e.to_string())?)
        }
    };
    let config = builder.with_single_cert(chain, key).map_err(|e| {
        let why = match e {
            rustls::Error::InconsistentKeys(_) => "the key is not the certificate's".to_string(),
            e => e.to_string(),
        };
        format!(
            "cert_file {} and key_file {}: {why}",
            cert_file.display(),
            key_file.display()
        )
    })?;
    Ok((config, auth))
}

/// Every certificate of a PEM file; none is an error.
fn certificates(path: &Path, key: &str) -> Result<Vec<CertificateDer<'static>>, String> {
    let what = |e: String| format!("{key} {}: {e}", path.display());
    let chain = CertificateDer::pem_file_iter(path)
        .map_err(|e| what(e.to_string()))?
        .collect::<Result<Vec<_>, _>>()
        .map_err(|e| what(e.to_string()))?;
    if chain.is_empty() {
        return Err(what("no PEM certificate in it".into()));
    }
    Ok(chain)
}

/// The exporter-toolkit's default client authentication: none, unless a
/// client CA is given (then required and verified).
fn client_auth(t: &TlsFile) -> Result<ClientAuth, String> {
    match t.client_auth_type.as_deref() {
        None | Some("") if t.client_ca_file.is_some() => Ok(ClientAuth::RequireAndVerifyClientCert),
        None | Some("" | "NoClientCert") => Ok(ClientAuth::NoClientCert),
        Some("VerifyClientCertIfGiven") => Ok(ClientAuth::VerifyClientCertIfGiven),
        Some("RequireAndVerifyClientCert") => Ok(ClientAuth::RequireAndVerifyClientCert),
        Some(other @ ("RequestClientCert" | "RequireAnyClientCert")) => Err(format!(
            "client_auth_type {other} accepts certificates nobody verified: use RequireAndVerifyClientCert (or VerifyClientCertIfGiven) with client_ca_file"
        )),
        Some(other) => Err(format!(
            "client_auth_type '{other}': expected NoClientCert, VerifyClientCertIfGiven or RequireAndVerifyClientCert"
        )),
    }
}

fn versions(
    min: Option<&str>,
    max: Option<&str>,
) -> Result<Vec<&'static rustls::SupportedProtocolVersion>, String> {
    let rank = |key: &str, v: Option<&str>, default: u8| -> Result<u8, String> {
        match v {
            None | Some("") => Ok(default),
            Some("TLS12") => Ok(12),
            Some("TLS13") => Ok(13),
            Some(old @ ("TLS10" | "TLS11")) => Err(format!(
                "{key} {old}: mavping speaks TLS 1.2 and 1.3 only (use TLS12 or TLS13)"
            )),
            Some(other) => Err(format!("{key} '{other}': expected TLS12 or TLS13")),
        }
    };
    let (min, max) = (rank("min_version", min, 12)?, rank("max_version", max, 13)?);
    if min > max {
        return Err("min_version is above max_version".into());
    }
    Ok(
        [(12, &rustls::version::TLS12), (13, &rustls::version::TLS13)]
            .into_iter()
            .filter(|(v, _)| (min..=max).contains(v))
            .map(|(_, p)| p)
            .collect(),
    )
}

/// Each hash must be bcrypt's (`$2y$10$...`): a plain password there would
/// lock its user out, which is better said now.
fn users(given: &BTreeMap<String, String>) -> Result<BTreeMap<String, String>, String> {
    for (user, hash) in given {
        if user.contains(':') {
            return Err(format!(
                "basic_auth_users: user '{user}' has a ':', which basic auth cannot carry"
            ));
        }
        bcrypt::HashParts::from_str(hash).map_err(|_| {
            format!(
                "basic_auth_users.{user}: not a bcrypt hash (make one with `htpasswd -nBC 10 \"\" | tr -d ':\\n'`)"
            )
        })?;
    }
    Ok(given.clone())
}

fn headers(http: Option<&HttpFile>) -> Result<Vec<(HeaderName, HeaderValue)>, String> {
    let Some(http) = http else {
        return Ok(Vec::new());
    };
    let mut out = Vec::new();
    for (name, value) in &http.headers {
        if !HEADERS.iter().any(|h| h.eq_ignore_ascii_case(name)) {
            return Err(format!(
                "http_server_config.headers: {name} cannot be set; allowed: {}",
                HEADERS.join(", ")
            ));
        }
        let value = HeaderValue::from_str(value)
            .map_err(|_| format!("http_server_config.headers.{name}: not a valid header value"))?;
        out.push((HeaderName::from_str(name).expect("a known name"), value));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn load(yaml: &str) -> Result<WebConfig, String> {
        let dir = std::env::temp_dir().join(format!("mavping-web-unit-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join(format!("{:x}.yml", sha2_of(yaml)));
        std::fs::write(&path, yaml).unwrap();
        WebConfig::load(Some(&path)).map_err(|e| e.to_string())
    }

    fn sha2_of(s: &str) -> u64 {
        use sha2::Digest;
        let d = sha2::Sha256::digest(s.as_bytes());
        u64::from_le_bytes(d[..8].try_into().unwrap())
    }

    #[test]
    fn an_empty_file_is_plain_http_open_to_all() {
        let w = load("").unwrap();
        assert!(w.tls.is_none() && w.users.is_empty() && w.headers.is_empty());
        assert_eq!(w.describe(), "plain HTTP, no basic auth");
    }

    #[test]
    fn users_and_headers_are_read() {
        let hash = bcrypt::hash("secret", 4).unwrap();
        let w = load(&format!(
            "basic_auth_users:\n  prometheus: {hash}\n\
             http_server_config:\n  headers:\n    X-Frame-Options: deny\n"
        ))
        .unwrap();
        assert_eq!(w.users.len(), 1);
        assert_eq!(w.headers[0].0, "x-frame-options");
        assert_eq!(
            w.describe(),
            "plain HTTP, 1 basic-auth user, 1 extra header"
        );
    }

    #[test]
    fn mistakes_are_one_line_each() {
        for (yaml, said) in [
            ("basic_auth_users:\n  a: hunter2\n", "basic_auth_users.a: not a bcrypt hash"),
            ("tls_server_config:\n  cert_file: a.pem\n", "needs both cert_file and key_file"),
            ("tls_config:\n  cert_file: a\n", "unknown field `tls_config`"),
            (
                "http_server_config:\n  headers:\n    Content-Type: x\n",
                "Content-Type cannot be set",
            ),
            (
                "tls_server_config:\n  cert_file: /nonexistent.pem\n  key_file: k\n",
                // Joined to the file's folder: on Windows a rooted path
                // without a drive takes that folder's (seen under Wine).
                if cfg!(windows) {
                    "cert_file C:/nonexistent.pem"
                } else {
                    "cert_file /nonexistent.pem"
                },
            ),
            (
                "tls_server_config:\n  cert_file: a\n  key_file: b\n  min_version: TLS10\n",
                "TLS 1.2 and 1.3 only",
            ),
            (
                "tls_server_config:\n  cert_file: a\n  key_file: b\n  client_auth_type: RequireAndVerifyClientCert\n",
                "needs client_ca_file",
            ),
            (
                "tls_server_config:\n  cert_file: a\n  key_file: b\n  client_auth_type: RequireAnyClientCert\n",
                "nobody verified",
            ),
        ] {
            let e = load(yaml).unwrap_err();
            assert!(e.contains(said), "{yaml}: {e}");
            assert!(!e.contains('\n'), "{e}");
            assert!(e.starts_with("--web.config.file "), "{e}");
        }
    }
}
