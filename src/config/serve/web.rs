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

use thiserror::Error;

use crate::config::error::ConfigError;

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
        let what = || format!("--web.config.file {}", path.display());
        let fail = |e: WebError| ConfigError::rejected(what(), e);
        let text = std::fs::read_to_string(path).map_err(|source| ConfigError::Unreadable {
            what: what(),
            source,
        })?;
        let file: File = if text.trim().is_empty() {
            File::default()
        } else {
            serde_norway::from_str(&text).map_err(|e| ConfigError::Syntax {
                place: what(),
                message: one_line(&e.to_string()),
            })?
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

/// What is wrong inside the web config (its name is put before it).
#[derive(Debug, Error)]
pub(crate) enum WebError {
    #[error("tls_server_config needs both cert_file and key_file")]
    CertAndKey,
    /// Go's TLS knobs that rustls does not have.
    #[error(
        "{0} is not supported: mavping's TLS (rustls) offers only its own modern suites and groups; remove it"
    )]
    GoOnly(&'static str),
    #[error("client_auth_type {0} needs client_ca_file")]
    NoClientCa(ClientAuth),
    #[error(
        "client_auth_type {0} accepts certificates nobody verified: use RequireAndVerifyClientCert (or VerifyClientCertIfGiven) with client_ca_file"
    )]
    Unverified(String),
    #[error(
        "client_auth_type '{0}': expected NoClientCert, VerifyClientCertIfGiven or RequireAndVerifyClientCert"
    )]
    ClientAuthType(String),
    #[error("{key} {version}: mavping speaks TLS 1.2 and 1.3 only (use TLS12 or TLS13)")]
    OldTls { key: &'static str, version: String },
    #[error("{key} '{version}': expected TLS12 or TLS13")]
    TlsVersion { key: &'static str, version: String },
    #[error("min_version is above max_version")]
    VersionsCrossed,
    /// A PEM file (`cert_file`, `key_file`, `client_ca_file`) that cannot
    /// be read or holds no such thing.
    #[error("{key} {}: {source}", .path.display())]
    Pem {
        key: &'static str,
        path: PathBuf,
        source: rustls_pki_types::pem::Error,
    },
    #[error("{key} {}: no PEM certificate in it", .path.display())]
    NoCertificate { key: &'static str, path: PathBuf },
    #[error("client_ca_file {}: {source}", .path.display())]
    ClientCa {
        path: PathBuf,
        source: rustls::Error,
    },
    /// The protocol versions asked of rustls.
    #[error(transparent)]
    Versions(rustls::Error),
    #[error(transparent)]
    Verifier(#[from] rustls::server::VerifierBuilderError),
    #[error(
        "cert_file {} and key_file {}: {}",
        .cert.display(),
        .key.display(),
        why_not_a_pair(.source)
    )]
    NotAPair {
        cert: PathBuf,
        key: PathBuf,
        source: rustls::Error,
    },
    #[error("basic_auth_users: user '{0}' has a ':', which basic auth cannot carry")]
    UserWithColon(String),
    #[error(
        "basic_auth_users.{0}: not a bcrypt hash (make one with `htpasswd -nBC 10 \"\" | tr -d ':\\n'`)"
    )]
    NotBcrypt(String),
    #[error(
        "http_server_config.headers: {0} cannot be set; allowed: {allowed}",
        allowed = HEADERS.join(", ")
    )]
    Header(String),
    #[error("http_server_config.headers.{0}: not a valid header value")]
    HeaderValue(String),
}

/// Why rustls refused a certificate and key, in the user's words when it
/// is the common mistake.
fn why_not_a_pair(e: &rustls::Error) -> String {
    match e {
        rustls::Error::InconsistentKeys(_) => "the key is not the certificate's".to_string(),
        e => e.to_string(),
    }
}

fn tls(t: &TlsFile, dir: &Path) -> Result<(rustls::ServerConfig, ClientAuth), WebError> {
    let (Some(cert_file), Some(key_file)) = (&t.cert_file, &t.key_file) else {
        return Err(WebError::CertAndKey);
    };
    for (key, given) in [
        ("cipher_suites", &t.cipher_suites),
        ("curve_preferences", &t.curve_preferences),
        ("client_allowed_sans", &t.client_allowed_sans),
    ] {
        if !given.is_empty() {
            return Err(WebError::GoOnly(key));
        }
    }
    let versions = versions(t.min_version.as_deref(), t.max_version.as_deref())?;
    let auth = client_auth(t)?;
    if auth != ClientAuth::NoClientCert && t.client_ca_file.is_none() {
        return Err(WebError::NoClientCa(auth));
    }
    let chain = certificates(&dir.join(cert_file), "cert_file")?;
    let key = PrivateKeyDer::from_pem_file(dir.join(key_file)).map_err(|source| WebError::Pem {
        key: "key_file",
        path: key_file.clone(),
        source,
    })?;
    let provider = Arc::new(rustls::crypto::ring::default_provider());
    let builder = rustls::ServerConfig::builder_with_provider(provider.clone())
        .with_protocol_versions(&versions)
        .map_err(WebError::Versions)?;
    let builder = match (auth, &t.client_ca_file) {
        // (A verifying type without a CA was refused above.)
        (ClientAuth::NoClientCert, _) | (_, None) => builder.with_no_client_auth(),
        (_, Some(ca)) => {
            let mut roots = RootCertStore::empty();
            for cert in certificates(&dir.join(ca), "client_ca_file")? {
                roots.add(cert).map_err(|source| WebError::ClientCa {
                    path: ca.clone(),
                    source,
                })?;
            }
            let verifier = WebPkiClientVerifier::builder_with_provider(Arc::new(roots), provider);
            let verifier = if auth == ClientAuth::VerifyClientCertIfGiven {
                verifier.allow_unauthenticated()
            } else {
                verifier
            };
            builder.with_client_cert_verifier(verifier.build()?)
        }
    };
    let config = builder
        .with_single_cert(chain, key)
        .map_err(|source| WebError::NotAPair {
            cert: cert_file.clone(),
            key: key_file.clone(),
            source,
        })?;
    Ok((config, auth))
}

/// Every certificate of a PEM file; none is an error.
fn certificates(path: &Path, key: &'static str) -> Result<Vec<CertificateDer<'static>>, WebError> {
    let pem = |source| WebError::Pem {
        key,
        path: path.to_path_buf(),
        source,
    };
    let chain = CertificateDer::pem_file_iter(path)
        .map_err(pem)?
        .collect::<Result<Vec<_>, _>>()
        .map_err(pem)?;
    if chain.is_empty() {
        return Err(WebError::NoCertificate {
            key,
            path: path.to_path_buf(),
        });
    }
    Ok(chain)
}

/// The exporter-toolkit's default client authentication: none, unless a
/// client CA is given (then required and verified).
fn client_auth(t: &TlsFile) -> Result<ClientAuth, WebError> {
    match t.client_auth_type.as_deref() {
        None | Some("") if t.client_ca_file.is_some() => Ok(ClientAuth::RequireAndVerifyClientCert),
        None | Some("" | "NoClientCert") => Ok(ClientAuth::NoClientCert),
        Some("VerifyClientCertIfGiven") => Ok(ClientAuth::VerifyClientCertIfGiven),
        Some("RequireAndVerifyClientCert") => Ok(ClientAuth::RequireAndVerifyClientCert),
        Some(other @ ("RequestClientCert" | "RequireAnyClientCert")) => {
            Err(WebError::Unverified(other.to_string()))
        }
        Some(other) => Err(WebError::ClientAuthType(other.to_string())),
    }
}

fn versions(
    min: Option<&str>,
    max: Option<&str>,
) -> Result<Vec<&'static rustls::SupportedProtocolVersion>, WebError> {
    let rank = |key: &'static str, v: Option<&str>, default: u8| -> Result<u8, WebError> {
        match v {
            None | Some("") => Ok(default),
            Some("TLS12") => Ok(12),
            Some("TLS13") => Ok(13),
            Some(old @ ("TLS10" | "TLS11")) => Err(WebError::OldTls {
                key,
                version: old.to_string(),
            }),
            Some(other) => Err(WebError::TlsVersion {
                key,
                version: other.to_string(),
            }),
        }
    };
    let (min, max) = (rank("min_version", min, 12)?, rank("max_version", max, 13)?);
    if min > max {
        return Err(WebError::VersionsCrossed);
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
fn users(given: &BTreeMap<String, String>) -> Result<BTreeMap<String, String>, WebError> {
    for (user, hash) in given {
        if user.contains(':') {
            return Err(WebError::UserWithColon(user.clone()));
        }
        bcrypt::HashParts::from_str(hash).map_err(|_| WebError::NotBcrypt(user.clone()))?;
    }
    Ok(given.clone())
}

fn headers(http: Option<&HttpFile>) -> Result<Vec<(HeaderName, HeaderValue)>, WebError> {
    let Some(http) = http else {
        return Ok(Vec::new());
    };
    let mut out = Vec::new();
    for (name, value) in &http.headers {
        if !HEADERS.iter().any(|h| h.eq_ignore_ascii_case(name)) {
            return Err(WebError::Header(name.clone()));
        }
        let value =
            HeaderValue::from_str(value).map_err(|_| WebError::HeaderValue(name.clone()))?;
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
