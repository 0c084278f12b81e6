//! The command probe: COMMAND_LONG sent until acknowledged. [`tracker`]
//! is the pure bookkeeping (what is pending, re-sent, failed); [`driver`]
//! joins it to the session.

pub(crate) mod driver;
mod event;
pub(crate) mod tracker;

pub(crate) use event::CommandEvent;
