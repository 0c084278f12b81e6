//! The process's file descriptor limit, raised for a server.

/// Each link, probe and client costs a file descriptor: take as many as
/// the system allows (as Go programs do), so a fleet is not cut short by a
/// default soft limit of 1024. Best effort.
pub(super) fn raise_descriptor_limit() {
    #[cfg(unix)]
    {
        use nix::sys::resource::{getrlimit, setrlimit, Resource};
        if let Ok((soft, hard)) = getrlimit(Resource::RLIMIT_NOFILE) {
            if soft < hard {
                let _ = setrlimit(Resource::RLIMIT_NOFILE, hard, hard);
            }
        }
    }
}
