//! `--signing-key`, `--signing-key-file` (or a module's
//! `signing_key_file`): the key, and the policy it makes.

use super::error::ConfigError;
use crate::cli::SigningArgs;
use crate::frame::signing::{SecretKey, SigningConfig};

/// The signing key from `--signing-key` (or its env var) or the file
/// `--signing-key-file` names; `None` when neither is given.
fn signing_key(args: &SigningArgs) -> Result<Option<SecretKey>, ConfigError> {
    let text = match (&args.signing_key, &args.signing_key_file) {
        (Some(_), Some(_)) => {
            return Err(ConfigError::GiveOne {
                first: "--signing-key (or MAVPING_SIGNING_KEY)",
                second: "--signing-key-file",
            })
        }
        (Some(key), None) => key.trim().to_string(),
        (None, Some(path)) => std::fs::read_to_string(path)
            .map_err(|source| ConfigError::Unreadable {
                what: format!("--signing-key-file {}", path.display()),
                source,
            })?
            .trim()
            .to_string(),
        (None, None) => return Ok(None),
    };
    let from = match &args.signing_key_file {
        Some(path) if args.signing_key.is_none() => {
            format!("--signing-key-file {}", path.display())
        }
        _ => "--signing-key".to_string(),
    };
    SecretKey::parse(&text)
        .map(Some)
        .map_err(|e| ConfigError::SigningKey {
            from,
            source: Box::new(e),
        })
}

/// The signing policy: a key signs what we send and checks what comes.
pub(super) fn signing(
    args: &SigningArgs,
    require_signed: bool,
) -> Result<Option<SigningConfig>, ConfigError> {
    Ok(signing_key(args)?.map(|key| SigningConfig {
        key,
        link_id: args.signing_link_id,
        require_signed,
    }))
}
