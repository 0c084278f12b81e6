//! How to open a link beyond its connection string ([`LinkOptions`]:
//! baud, reconnecting, the IP route) and the address family of `-4`/`-6`:
//! what the configuration settles and [`Link::open`](super::Link::open)
//! reads, apart from the links themselves.

use super::{route, serial};

/// An IP address family, for `-4` and `-6`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Family {
    V4,
    V6,
}

/// How to open a link, beyond its connection string.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct LinkOptions {
    /// Baud rate of a serial port whose connection string names none.
    pub(crate) baud: u32,
    /// Reopen a tcp client or serial link that breaks, instead of ending;
    /// on `udpout:` an ICMP "port unreachable" does not end the link.
    pub(crate) reconnect: bool,
    /// With `reconnect`: a tcp client whose peer is not up yet ("connection
    /// refused") starts down and keeps trying, as after a loss (`mavping
    /// respond`, which may start before the pinger it answers).
    pub(crate) wait_for_peer: bool,
    /// Address family, local address and interface of IP links.
    pub(crate) route: route::Route,
    /// Whom `wss://` trusts (`--cacert`, else the system's roots).
    pub(crate) trust: super::ws::Trust,
}

impl Default for LinkOptions {
    fn default() -> Self {
        LinkOptions {
            baud: serial::DEFAULT_BAUD,
            reconnect: false,
            wait_for_peer: false,
            route: route::Route::default(),
            trust: super::ws::Trust::default(),
        }
    }
}
