//! The end-of-run figures, built from the matcher and the roster. Every
//! report format renders these structures: one per kind of run ([`echo`],
//! [`command`], [`passive`]), the interim figures of a run so far
//! ([`interim`]), and [`LinkSummary`], which holds whichever a link's run
//! ended with.

mod command;
mod direction;
mod echo;
mod interim;
mod link;
pub(crate) mod passive;
mod probe_name;

pub use command::CommandSummary;
pub(crate) use command::{AckResult, CommandTargetSummary};
pub(crate) use direction::Direction;
pub use echo::EchoInterim;
pub(crate) use echo::{responder_summaries, ScheduleSummary, HISTOGRAM_ROWS};
pub use echo::{EchoSummary, ResponderSummary};
pub use interim::Interim;
pub use link::{KindSummary, LinkSummary};
pub use passive::PassiveInterim;
pub use probe_name::ProbeName;
