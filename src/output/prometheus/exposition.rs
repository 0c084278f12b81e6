//! The Prometheus text format, written: a family (its name, `HELP` and
//! `TYPE`), its samples, and the label sets of a link's series. Every
//! exposition mavping serves is written through [`Exposition`].

use std::fmt::{Display, Write as _};

use super::Metrics;
use crate::engine::summary::ProbeName;
use crate::frame::SysComp;

impl Metrics {
    /// The link's own series: its state.
    pub(super) fn link_labels(&self) -> String {
        format!("link=\"{}\"", escape(&self.link))
    }

    /// What the link measures with: its requests and who answers them.
    pub(super) fn probe_labels(&self) -> String {
        let probe = self.probe.map_or("", ProbeName::as_str);
        format!("{},probe=\"{probe}\"", self.link_labels())
    }

    /// A responder's series.
    pub(super) fn labels(&self, id: SysComp) -> String {
        with_id(self.probe_labels(), id)
    }

    /// A radio's, a node's or a source's series: not the probe's.
    pub(super) fn radio_labels(&self, id: SysComp) -> String {
        with_id(self.link_labels(), id)
    }
}

fn with_id(labels: String, id: SysComp) -> String {
    format!("{labels},sysid=\"{}\",compid=\"{}\"", id.sysid, id.compid)
}

/// A metric family: its name, its `HELP` text and its type (the word
/// its `TYPE` line says).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) struct Family {
    pub(super) name: &'static str,
    pub(super) help: &'static str,
    kind: &'static str,
}

impl Family {
    pub(super) const fn gauge(name: &'static str, help: &'static str) -> Self {
        Family::of("gauge", name, help)
    }

    pub(super) const fn counter(name: &'static str, help: &'static str) -> Self {
        Family::of("counter", name, help)
    }

    pub(super) const fn histogram(name: &'static str, help: &'static str) -> Self {
        Family::of("histogram", name, help)
    }

    const fn of(kind: &'static str, name: &'static str, help: &'static str) -> Self {
        Family { name, help, kind }
    }
}

/// A family and how to read its value (of a series, a radio, the server).
pub(super) struct Figure<V> {
    pub(super) family: Family,
    pub(super) value: V,
}

impl<V> Figure<V> {
    pub(super) const fn gauge(name: &'static str, help: &'static str, value: V) -> Self {
        Figure {
            family: Family::gauge(name, help),
            value,
        }
    }

    pub(super) const fn counter(name: &'static str, help: &'static str, value: V) -> Self {
        Figure {
            family: Family::counter(name, help),
            value,
        }
    }
}

/// A figure of each series of a kind (`T`), left out where the series
/// has none.
pub(super) type SeriesFigure<T> = Figure<fn(&T) -> Option<f64>>;

/// Text being written in the exposition format: a family's `HELP` and
/// `TYPE` lines, then its samples.
#[derive(Default)]
pub(super) struct Exposition(pub(super) String);

impl Exposition {
    pub(super) fn header(&mut self, family: &Family) {
        let Family { name, help, kind } = family;
        let _ = writeln!(self.0, "# HELP {name} {help}\n# TYPE {name} {kind}");
    }

    pub(super) fn sample(&mut self, name: &str, labels: &str, value: impl Display) {
        let _ = if labels.is_empty() {
            writeln!(self.0, "{name} {value}")
        } else {
            writeln!(self.0, "{name}{{{labels}}} {value}")
        };
    }

    /// A family with its samples; nothing at all when it has none.
    pub(super) fn family<V: Display>(
        &mut self,
        family: &Family,
        samples: impl IntoIterator<Item = (String, V)>,
    ) {
        let mut samples = samples.into_iter().peekable();
        if samples.peek().is_none() {
            return;
        }
        self.header(family);
        for (labels, value) in samples {
            self.sample(family.name, &labels, value);
        }
    }

    /// Each figure of `table` as a family, with a sample for each of
    /// `items` that has the figure: the shape of every per-series table.
    pub(super) fn figures<'a, T: 'a, I>(&mut self, table: &[SeriesFigure<T>], items: impl Fn() -> I)
    where
        I: Iterator<Item = (String, &'a T)>,
    {
        for Figure { family, value } in table {
            self.family(family, items().filter_map(|(l, x)| Some((l, value(x)?))));
        }
    }
}

/// Label values escape backslash, double quote and newline.
pub(super) fn escape(value: &str) -> String {
    value
        .replace('\\', "\\\\")
        .replace('"', "\\\"")
        .replace('\n', "\\n")
}
