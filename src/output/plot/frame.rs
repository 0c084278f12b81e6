//! What every picture `--plot` draws shares: its width (the legend's
//! labels and the title decide it), the title across the top, and the
//! legend table below the charts (a row per line: its colour and marker,
//! its label, its figures); and [`PlotError`], when the drawing fails.

use std::collections::BTreeMap;

use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use thiserror::Error;

use super::style::Look;

/// The SVG could not be drawn: the drawing library's message.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
#[error("{0}")]
pub(crate) struct PlotError(pub(super) String);

pub(super) type DrawResult = Result<(), Box<dyn std::error::Error>>;

/// The narrowest picture; a long title or legend label widens it.
const WIDTH: u32 = 1000;
pub(super) const MARGIN: u32 = 14;
pub(super) const FONT: &str = "sans-serif";
const TITLE_SIZE: f64 = 24.0;

/// Height of the title band.
const TITLE_H: u32 = 44;
/// Height of a legend row.
const ROW_H: u32 = 26;

pub(super) type Area<'a> = DrawingArea<SVGBackend<'a>, Shift>;

pub(super) fn title_font(size: f64) -> FontDesc<'static> {
    (FONT, size).into_font()
}

pub(super) fn legend_font() -> FontDesc<'static> {
    (FONT, 17).into_font()
}

/// The width `text` takes. plotters can only estimate it for SVG (the
/// viewer picks the font), and its estimate runs short for DejaVu Sans,
/// the usual sans-serif on Linux: a fifth is added.
pub(super) fn text_width(text: &str, font: FontDesc<'_>) -> u32 {
    font.box_size(text).map_or(0, |(w, _)| w * 6 / 5)
}

/// One line of a picture (a responder, a source, a link's sweep), in
/// drawing order: its legend label, its look, and what it draws.
pub(super) struct Entry<'a, T> {
    pub(super) label: String,
    pub(super) look: Look,
    pub(super) track: &'a T,
}

/// An entry per track, each with the next look.
pub(super) fn entries<K: Copy, T>(
    tracks: &BTreeMap<K, T>,
    label: impl Fn(K, &T) -> String,
) -> Vec<Entry<'_, T>> {
    let each = tracks.iter().enumerate();
    each.map(|(n, (&key, track))| Entry {
        label: label(key, track),
        look: Look::nth(n),
        track,
    })
    .collect()
}

/// The legend under the charts: the first column's head (over the labels)
/// and the figures' heads, how wide a figure's column is, a row per line,
/// and what stands in place of the rows when there are none.
pub(super) struct Legend<'a> {
    pub(super) heads: (&'a str, &'a [&'a str]),
    pub(super) number_w: i32,
    pub(super) rows: Vec<LegendRow<'a>>,
    pub(super) empty: &'a str,
}

/// An SVG document: white, `title` across the top, charts `heights` high
/// one under the other (`charts` draws them), and `legend` below them,
/// so nothing is ever drawn under it.
pub(super) fn page(
    title: &str,
    legend: &Legend<'_>,
    heights: &[u32],
    charts: impl FnOnce(&[Area<'_>]) -> DrawResult,
) -> Result<String, PlotError> {
    let (first, columns) = legend.heads;
    let labels = legend.rows.iter().map(|r| r.label).chain([first]);
    let label_w = labels.map(|l| text_width(l, legend_font())).max();
    // The legend's figures after the labels, and wider when a label is
    // long.
    let numbers_x = 70 + label_w.unwrap_or(0) as i32 + 20;
    let width = WIDTH.max((numbers_x + columns.len() as i32 * legend.number_w + 30) as u32);
    // A long title (a simulated link with every parameter) gets a smaller
    // font, down to three fifths, before the picture gets wider.
    let wide = f64::from(text_width(title, title_font(TITLE_SIZE)).max(1));
    let fitting = TITLE_SIZE * f64::from(width - 2 * MARGIN) / wide;
    let title_size = fitting.clamp(TITLE_SIZE * 0.6, TITLE_SIZE);
    let width = width.max(text_width(title, title_font(title_size)) + 2 * MARGIN);
    let rows = legend.rows.len().max(1) as u32;
    let height = TITLE_H + heights.iter().sum::<u32>() + ROW_H * (rows + 1) + 20;
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (width, height)).into_drawing_area();
        let drawn = (|| -> DrawResult {
            root.fill(&WHITE)?;
            let (head, mut rest) = root.split_vertically(TITLE_H);
            head.draw(&Text::new(
                title,
                (MARGIN as i32, TITLE_H as i32 / 2),
                title_font(title_size)
                    .into_text_style(&root)
                    .pos(Pos::new(HPos::Left, VPos::Center)),
            ))?;
            let mut areas = Vec::new();
            for &h in heights {
                let (chart, below) = rest.split_vertically(h);
                areas.push(chart);
                rest = below;
            }
            charts(&areas)?;
            legend_table(&rest, numbers_x, legend)?;
            root.present()?;
            Ok(())
        })();
        drawn.map_err(|e| PlotError(e.to_string()))?;
    }
    Ok(svg)
}

/// One row of the legend.
pub(super) struct LegendRow<'a> {
    pub(crate) look: Look,
    pub(crate) label: &'a str,
    /// Its figures, in the columns' order; `-` where unknown.
    pub(crate) cells: Vec<Option<String>>,
}

/// The legend: a header, a rule, and a row per line; its `empty` text
/// in place of the rows when there are none.
fn legend_table(area: &Area<'_>, numbers_x: i32, legend: &Legend<'_>) -> DrawResult {
    let (first, columns) = legend.heads;
    let style =
        |font: FontDesc<'static>, h| font.into_text_style(area).pos(Pos::new(h, VPos::Center));
    let left = style(legend_font(), HPos::Left);
    let right = style(legend_font(), HPos::Right);
    let bold = || legend_font().style(FontStyle::Bold);
    let row_y = |r: usize| ROW_H as i32 * r as i32 + ROW_H as i32 / 2 + 4;
    let column = |j: usize| numbers_x + legend.number_w * (j as i32 + 1);
    let text = |s: &str, at, style| area.draw(&Text::new(s, at, style));
    let path = |ends: [(i32, i32); 2], style| area.draw(&PathElement::new(ends, style));
    text(first, (70, row_y(0)), style(bold(), HPos::Left))?;
    for (j, name) in columns.iter().enumerate() {
        text(name, (column(j), row_y(0)), style(bold(), HPos::Right))?;
    }
    let rule = row_y(0) + ROW_H as i32 / 2;
    path(
        [(MARGIN as i32, rule), (column(columns.len() - 1), rule)],
        BLACK.stroke_width(1),
    )?;
    if legend.rows.is_empty() {
        text(legend.empty, (70, row_y(1)), left)?;
        return Ok(());
    }
    for (r, row) in legend.rows.iter().enumerate() {
        let y = row_y(r + 1);
        path([(18, y), (58, y)], row.look.color.stroke_width(2))?;
        area.draw(&row.look.marker((38, y), 5))?;
        text(row.label, (70, y), left.clone())?;
        for (j, cell) in row.cells.iter().enumerate() {
            let cell = cell.as_deref().unwrap_or("-");
            text(cell, (column(j), y), right.clone())?;
        }
    }
    Ok(())
}

/// A legend row per entry, its figures by `cells`.
pub(super) fn rows<'a, T>(
    entries: &'a [Entry<'_, T>],
    cells: impl Fn(&T) -> Vec<Option<String>>,
) -> Vec<LegendRow<'a>> {
    let row = |e: &'a Entry<'_, T>| LegendRow {
        look: e.look,
        label: &e.label,
        cells: cells(e.track),
    };
    entries.iter().map(row).collect()
}
