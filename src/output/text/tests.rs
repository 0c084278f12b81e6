//! Every run of every kind as text, quiet and not, byte for byte: the
//! snapshot was taken before the text's writers were shared, so that
//! sharing them cannot change a line unseen (same-output.sh runs no
//! per-link log, no LINK_NODE_STATUS and no signing).

use super::TextReporter;
use crate::output::runs::{Borrowed, Told, RUNS};
use crate::output::Reporter;

fn every_run() -> String {
    let borrowed = Borrowed::new();
    let mut all = String::new();
    for run in RUNS {
        for quiet in [false, true] {
            let mut out = TextReporter::new(Vec::new(), quiet);
            for told in run.told(&borrowed) {
                match &told {
                    Told::Start(info) => out.start(info),
                    Told::Event(event) => out.tell(event),
                    Told::Interim(figures) => out.interim(figures),
                    Told::Summary(summary, verdict) => out.summary(summary, verdict),
                }
                .unwrap();
            }
            all += &format!("=== {run:?}, quiet {quiet}\n");
            all += &String::from_utf8(out.into_inner()).unwrap();
        }
    }
    all
}

#[test]
fn every_run_byte_for_byte() {
    insta::assert_snapshot!(every_run());
}
