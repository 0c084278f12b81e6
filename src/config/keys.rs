//! The command line's options and the serve file's keys share the rules
//! that check them; errors name each in its own form.

/// How errors name a setting: as a command-line option (`--target`) or as
/// a key of the `mavping serve` configuration file (`target`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Keys {
    Flags,
    File,
}

impl Keys {
    /// `name` is the key's form in the file (`retry_interval` or
    /// `retry-interval`, either); the option's form is derived from it.
    pub(crate) fn name(self, name: &str) -> String {
        match self {
            Keys::Flags => format!("--{}", name.replace('_', "-")),
            Keys::File => name.replace('-', "_"),
        }
    }
}
