//! `mavping respond`: open the link, say so, answer until stopped, then
//! print the ground truth.

use crate::config::RespondConfig;
use crate::engine::session::Controls;
use crate::exit::Ending;
use crate::responder;
use crate::stderr;
use crate::transport::Link;
use std::io::{self, Write};

pub(super) async fn run(config: &RespondConfig, controls: Controls) -> Ending {
    let mut link = match Link::open(&config.link, &config.link_options).await {
        Ok(link) => link,
        Err(e) => {
            stderr::error(&e);
            return Ending::LinkFailed;
        }
    };
    let settings = &config.settings;
    let mut out = io::stdout().lock();
    // Printed once the link is open: a test (or a person) knows from it
    // that requests will be heard.
    let _ = writeln!(
        out,
        "{}",
        responder::describe(settings, &config.link.to_string())
    );
    let _ = out.flush();
    let (counts, error) = responder::run(settings, &mut link, &controls.stop).await;
    let _ = writeln!(out, "respond {}: {counts}", settings.id);
    let _ = out.flush();
    match error {
        Some(e) => {
            stderr::error(&e);
            Ending::LinkFailed
        }
        None => Ending::Done,
    }
}
