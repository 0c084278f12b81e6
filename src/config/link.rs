//! One link of a run, as the command line and the server both give it.

use rustls_pki_types::pem::PemObject;
use rustls_pki_types::CertificateDer;

use super::error::ConfigError;
use crate::engine::SessionConfig;
use crate::transport::address::LinkSpec;
use crate::transport::ws::Trust;
use crate::verdict::Thresholds;

/// One link of a run.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct LinkConfig {
    pub(crate) spec: LinkSpec,
    /// The connection string as typed: with several links, reply lines,
    /// error lines and exports are labelled with it.
    pub(crate) name: String,
    /// Its session; `link_name` is the form reports head the run with
    /// (the link's full form alone, or the name beside others).
    pub(crate) session: SessionConfig,
    /// Every link's thresholds, and the responders `--expect` wants here.
    pub(crate) thresholds: Thresholds,
}

/// Whom `wss://` links trust: the PEM certificates of `--cacert`, or (none
/// given) the system's roots, read when a link opens.
pub(super) fn trust(cacert: Option<&std::path::Path>) -> Result<Trust, ConfigError> {
    let Some(path) = cacert else {
        return Ok(Trust::default());
    };
    let what = || format!("--cacert {}", path.display());
    let certs = CertificateDer::pem_file_iter(path)
        .and_then(|certs| certs.collect::<Result<Vec<_>, _>>())
        .map_err(|e| match e {
            rustls_pki_types::pem::Error::Io(source) => ConfigError::Unreadable {
                what: what(),
                source,
            },
            other => ConfigError::value("--cacert", path.display(), format!("not PEM: {other}")),
        })?;
    if certs.is_empty() {
        return Err(ConfigError::value(
            "--cacert",
            path.display(),
            "no CERTIFICATE in it (a PEM file of the CA that signed the server's certificate)",
        ));
    }
    Ok(Trust {
        cacert: Some(std::sync::Arc::new(certs)),
    })
}
