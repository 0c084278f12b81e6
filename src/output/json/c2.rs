//! The `c2_report` line: the C2 link report over a link's run, written
//! whole as the engine's [`C2Report`] serialises, after its `type` and
//! link, as the line before the run's summary.

use serde::Serialize;

use crate::engine::c2::C2Report;

#[derive(Serialize)]
pub(super) struct Report<'a> {
    r#type: &'static str,
    link: &'a str,
    #[serde(flatten)]
    report: &'a C2Report,
}

impl<'a> Report<'a> {
    pub(super) fn of(link: &'a str, report: &'a C2Report) -> Self {
        Report {
            r#type: "c2_report",
            link,
            report,
        }
    }
}
