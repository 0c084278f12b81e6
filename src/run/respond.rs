//! `mavping respond`: open the links, say so, answer until stopped, then
//! print the ground truth.

use std::io::{self, Write};

use crate::config::RespondConfig;
use crate::engine::session::Controls;
use crate::exit::Ending;
use crate::responder::{self, RespondCounts, ResponderSettings};
use crate::stderr;
use crate::transport::several::{Several, Traffic};
use crate::transport::{Link, LinkError};

pub(super) async fn run(config: &RespondConfig, controls: Controls) -> Ending {
    let mut links = Vec::with_capacity(config.links.len());
    for spec in &config.links {
        match Link::open(spec, &config.link_options).await {
            Ok(link) => links.push(link),
            // One identity on every link or none: a vehicle half served
            // would measure as a link that fails.
            Err(e) => {
                stderr::error(&e);
                return Ending::LinkFailed;
            }
        }
    }
    let settings = &config.settings;
    let names: Vec<String> = config.links.iter().map(ToString::to_string).collect();
    let mut out = io::stdout().lock();
    // Printed once the links are open: a test (or a person) knows from it
    // that requests will be heard.
    let _ = writeln!(
        out,
        "{}",
        responder::describe(settings, &names.join(" and "))
    );
    let _ = out.flush();
    let stop = &controls.stop;
    if let [_] = links.as_slice() {
        // One link as it is: nothing between the responder and it.
        let mut link = links.pop().expect("one link");
        let (counts, error) = responder::run(settings, &mut link, stop).await;
        return finish(&mut out, settings, &counts, &[], error);
    }
    let mut several = Several::new(links);
    let (counts, error) = responder::run(settings, &mut several, stop).await;
    let traffic: Vec<(&String, Traffic)> = names
        .iter()
        .zip(several.traffic().iter().copied())
        .collect();
    finish(&mut out, settings, &counts, &traffic, error)
}

/// Prints the counts, and what each of several links carried (frames
/// written to every peer count once).
fn finish(
    out: &mut impl Write,
    settings: &ResponderSettings,
    counts: &RespondCounts,
    traffic: &[(&String, Traffic)],
    error: Option<LinkError>,
) -> Ending {
    let _ = writeln!(out, "respond {}: {counts}", settings.id);
    for (name, t) in traffic {
        let _ = writeln!(
            out,
            "  on {name}: {} frames received, {} frames sent ({} to one peer only: answers, greetings)",
            t.received, t.sent, t.to_one
        );
    }
    let _ = out.flush();
    match error {
        Some(e) => {
            stderr::error(&e);
            Ending::LinkFailed
        }
        None => Ending::Done,
    }
}
