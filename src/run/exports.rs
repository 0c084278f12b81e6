//! What a run writes besides its report: `--samples`, `--plot`, `--hgrm`,
//! the `--tlog` recording, the `--prometheus` endpoint and
//! `--prometheus-textfile`. Each is opened (files created) before
//! the first request, so a bad path or a port in use fails before anything
//! is sent and a long run's result is never lost to one; the plot and the
//! histograms are written once every link has ended.

use std::fs::File;
use std::io::{self, BufWriter, Write};
use std::net::SocketAddr;
use std::path::{Path, PathBuf};

use thiserror::Error;

use crate::config::Config;
use crate::engine::pair::PairSummary;
use crate::engine::session::Measurement;
use crate::engine::Nanos;
use crate::output::hgrm;
use crate::output::plot::{Plot, PlotError};
use crate::output::prometheus::{Metrics, PrometheusExporter};
use crate::output::samples::SampleLog;
use crate::output::textfile::Textfile;
use crate::output::{Reporter, Shared};
use crate::stderr;
use crate::transport::recording::{Recording, Tap};

pub(super) struct Exports {
    samples: Option<Shared<BufWriter<File>>>,
    plot: Option<(Plot, BufWriter<File>, PathBuf)>,
    prometheus: Option<PrometheusExporter>,
    hgrm: Option<(BufWriter<File>, PathBuf)>,
    tlog: Option<Recording>,
    /// The metrics the textfile gets at the end, gathered as for `/metrics`.
    textfile: Option<(Textfile, PrometheusExporter)>,
    /// Several links: sample rows name their link.
    several: bool,
}

/// An export that could not be opened or written, and which file or
/// address it was.
#[derive(Debug, Error)]
pub(super) enum ExportError {
    /// `what` is the option (`--samples`, `--plot`, `--hgrm`).
    #[error("cannot write {what} {}: {source}", path.display())]
    Create {
        what: &'static str,
        path: PathBuf,
        source: io::Error,
    },
    #[error("--prometheus {addr}: {source}")]
    Prometheus { addr: SocketAddr, source: io::Error },
    #[error("cannot write --plot {}: {source}", path.display())]
    PlotDrawn { path: PathBuf, source: PlotError },
    #[error("cannot write --plot {}: {source}", path.display())]
    PlotWritten { path: PathBuf, source: io::Error },
    #[error("cannot write --hgrm {}: {source}", path.display())]
    Hgrm { path: PathBuf, source: io::Error },
    #[error("cannot write --prometheus-textfile {}: {source}", path.display())]
    Textfile { path: PathBuf, source: io::Error },
    /// A write of the recording failed during the run or at its end.
    #[error("cannot write --tlog {}: {source}", path.display())]
    Tlog { path: PathBuf, source: io::Error },
}

fn create(path: &Path, what: &'static str) -> Result<BufWriter<File>, ExportError> {
    File::create(path)
        .map(BufWriter::new)
        .map_err(|source| ExportError::Create {
            what,
            path: path.to_path_buf(),
            source,
        })
}

impl Exports {
    /// Opens every export the configuration asks for, in a fixed order.
    pub(super) fn open(config: &Config) -> Result<Self, ExportError> {
        let out = &config.output;
        let samples = out
            .samples
            .as_deref()
            .map(|p| create(p, "--samples").map(Shared::new))
            .transpose()?;
        let prometheus = match out.prometheus {
            None => None,
            Some(addr) => {
                let (exporter, bound) = std::net::TcpListener::bind(addr)
                    .and_then(PrometheusExporter::serve)
                    .map_err(|source| ExportError::Prometheus { addr, source })?;
                // Says the port when 0 was asked for; scripts and tests read it.
                stderr::error(&format_args!("serving metrics at http://{bound}/metrics"));
                Some(exporter)
            }
        };
        let plot = out
            .plot
            .as_deref()
            .map(|p| create(p, "--plot").map(|f| (Plot::default(), f, p.to_path_buf())))
            .transpose()?;
        let hgrm = out
            .hgrm
            .as_deref()
            .map(|p| create(p, "--hgrm").map(|f| (f, p.to_path_buf())))
            .transpose()?;
        let tlog = out
            .tlog
            .as_deref()
            .map(|path| {
                Recording::create(path).map_err(|source| ExportError::Create {
                    what: "--tlog",
                    path: path.to_path_buf(),
                    source,
                })
            })
            .transpose()?;
        let textfile = out
            .prometheus_textfile
            .as_deref()
            .map(|path| {
                Textfile::create(path)
                    .map(|t| (t, PrometheusExporter::default()))
                    .map_err(|source| ExportError::Create {
                        what: "--prometheus-textfile",
                        path: path.to_path_buf(),
                        source,
                    })
            })
            .transpose()?;
        Ok(Exports {
            samples,
            plot,
            prometheus,
            hgrm,
            tlog,
            textfile,
            several: config.links.len() > 1,
        })
    }

    /// The reporters of the `index`-th link, named `name`.
    pub(super) fn reporters(&self, index: usize, name: &str) -> Vec<Box<dyn Reporter>> {
        let mut reporters: Vec<Box<dyn Reporter>> = Vec::new();
        if let Some(file) = &self.samples {
            let log = SampleLog::new(file.clone());
            reporters.push(Box::new(if self.several {
                log.for_link(name, index == 0)
            } else {
                log
            }));
        }
        if let Some(p) = &self.prometheus {
            reporters.push(Box::new(p.link(index)));
        }
        if let Some((_, p)) = &self.textfile {
            reporters.push(Box::new(p.link(index)));
        }
        if let Some((plot, _, _)) = &self.plot {
            reporters.push(Box::new(plot.link()));
        }
        reporters
    }

    /// Whether an exporter shows the run's own figures (the pair report).
    pub(super) fn exports_metrics(&self) -> bool {
        self.prometheus.is_some() || self.textfile.is_some()
    }

    /// Whether the run is drawn (`--plot`).
    pub(super) fn plots(&self) -> bool {
        self.plot.is_some()
    }

    /// The pair report so far, by link, at `at`, for the plot.
    pub(super) fn pair_by_link(&self, at: Nanos, summary: &PairSummary) {
        if let Some((plot, _, _)) = &self.plot {
            plot.on_pair(at, summary);
        }
    }

    /// The run's own figures, as exposition text, for every exporter.
    pub(super) fn run_figures(&self, text: &str) {
        for p in self
            .prometheus
            .iter()
            .chain(self.textfile.iter().map(|(_, p)| p))
        {
            p.set_run_figures(text.to_string());
        }
    }

    /// What the `index`-th link records through (`--tlog`).
    pub(super) fn tap(&self, index: usize) -> Option<Tap> {
        self.tlog.as_ref().map(|r| r.tap(index))
    }

    /// A link that could not be opened, given the `index` after every
    /// opened one's: the exporter shows it down.
    pub(super) fn unopened(&self, index: usize, name: &str) {
        for p in self
            .prometheus
            .iter()
            .chain(self.textfile.iter().map(|(_, p)| p))
        {
            p.link(index).update(|m| *m = Metrics::unopened(name));
        }
    }

    /// Flushes the recording, writes the plot and the histograms of every
    /// link; an error says which file could not be written. A recording
    /// that failed does not keep the plot and histograms from being
    /// written: its error is told after theirs.
    pub(super) fn finish<'a>(
        self,
        outcomes: impl IntoIterator<Item = &'a Measurement>,
    ) -> Result<(), ExportError> {
        let recorded = self.tlog.as_ref().map(|r| {
            r.finish().map_err(|source| ExportError::Tlog {
                path: r.path().to_path_buf(),
                source,
            })
        });
        if let Some((plot, mut file, path)) = self.plot {
            let svg = match plot.svg() {
                Ok(svg) => svg,
                Err(source) => return Err(ExportError::PlotDrawn { path, source }),
            };
            file.write_all(svg.as_bytes())
                .and_then(|()| file.flush())
                .map_err(|source| ExportError::PlotWritten { path, source })?;
        }
        if let Some((file, path)) = self.hgrm {
            write_hgrm(file, outcomes).map_err(|source| ExportError::Hgrm { path, source })?;
        }
        if let Some((textfile, metrics)) = self.textfile {
            let path = textfile.path().to_path_buf();
            textfile
                .commit(&with_end_time(metrics.render_now()))
                .map_err(|source| ExportError::Textfile { path, source })?;
        }
        recorded.transpose().map(|_| ())
    }
}

/// The textfile's metrics and when the run ended: a timer that stopped
/// running mavping leaves a file that only this says is old.
fn with_end_time(mut text: String) -> String {
    let now = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0.0, |d| d.as_secs_f64());
    text.push_str(
        "# HELP mavping_textfile_run_end_timestamp_seconds When the run that wrote this file ended (Unix time).\n\
         # TYPE mavping_textfile_run_end_timestamp_seconds gauge\n",
    );
    text.push_str(&format!(
        "mavping_textfile_run_end_timestamp_seconds {now:.3}\n"
    ));
    text
}

/// Every link's responders, one section each, in one file.
fn write_hgrm<'a>(
    mut out: BufWriter<File>,
    outcomes: impl IntoIterator<Item = &'a Measurement>,
) -> io::Result<()> {
    for outcome in outcomes {
        // One 8-byte-count copy at a time, not all of them at once.
        for (id, rtt) in &outcome.histograms {
            hgrm::write_section(&mut out, outcome.summary.link(), *id, &rtt.histogram())?;
        }
    }
    out.flush()
}
