//! Links: every transport hands the engine whole, CRC-checked frames with a
//! receive timestamp, and sends a frame to every peer it knows.
//!
//! Our own transports, not the `mavlink` crate's connections: those answer
//! only the last UDP peer, take one TCP client, drop v1 frames by default
//! and hide CRC errors — each fatal to a ping tool.

pub(crate) mod address;
mod advice;
mod any_link;
mod link;
mod m2r;
mod m2r_url;
#[cfg(not(mavping_portable))]
mod mmsg;
mod options;
mod out_queue;
pub(crate) mod outbox;
pub(crate) mod recording;
pub(crate) mod route;
pub(crate) mod rx_time;
pub(crate) mod serial;
pub(crate) mod several;
pub mod sim;
#[cfg(mavping_portable)]
mod single;
pub(crate) mod stream;
pub(crate) mod tcp;
pub(crate) mod tlog;
pub mod udp;
pub(crate) mod ws;
mod ws_url;

pub use address::LinkSpec;
pub(crate) use any_link::Link;
pub(crate) use link::push_datagram;
pub(crate) use link::{Inbound, LinkError, LinkKind, PathId, RxClock, Transport};
pub(crate) use options::{Family, LinkOptions};
pub(crate) use outbox::{Outbox, To};
