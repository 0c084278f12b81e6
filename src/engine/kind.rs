//! How the engine carries what only one kind of run has (an echo probe's
//! matches, a command's acknowledgements, a sweep's steps, a log's
//! timeline, each kind's plan, figures so far and summary) without
//! naming the kinds. Each kind owns its types; the engine hands them on
//! as [`KindValue`]s and a reader takes the ones it shows by their type.
//! A new kind adds its folder and its report, not arms in shared enums.

use std::any::Any;
use std::fmt::Debug;

/// A value of one kind's own type, carried without naming it. Each type
/// says it is one (`impl KindValue for ...`), and one that is written
/// whole as it serialises (the command probe's events are their JSON
/// lines) says so, so a format can write a kind it has no code for.
pub trait KindValue: Any + Debug {
    /// The value as it is written whole, if it is.
    fn serialized(&self) -> Option<&dyn erased_serde::Serialize> {
        None
    }
}

impl dyn KindValue {
    /// The value, if it is a `T`.
    pub fn get<T: KindValue>(&self) -> Option<&T> {
        (self as &dyn Any).downcast_ref()
    }
}
