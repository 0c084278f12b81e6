//! Draws one `--live` frame from the links' [`Screen`]s; pure over its
//! input, so it is tested on ratatui's test backend.
//!
//! It fits the terminal it is given, down to 80×24: a column is as wide as
//! its header or its widest figure, the strip of recent outcomes takes what
//! is left, and when too little is left the least needed columns go first.
//! Headers are short and never cut (units and the strip's marks are in the
//! key line). A link's section shows as many responders as fit and says how
//! many more there are; with several links each section gets a row before
//! any gets a second.

use ratatui::layout::{Alignment, Constraint, Layout, Rect};
use ratatui::style::{Color, Modifier, Style};
use ratatui::text::{Line, Span};
use ratatui::widgets::{Block, Cell, Paragraph, Row, Table};
use ratatui::Frame;

use super::sources::Second;
use super::state::{Cells, Mark, Screen, Strip};
use crate::engine::summary::ProbeName;

const BARS: [char; 8] = ['▁', '▂', '▃', '▄', '▅', '▆', '▇', '█'];
/// The key line: the keys, then what the figures and marks mean.
pub(super) const KEYS: &str =
    "q or Ctrl-C: stop and print the summary · RTT in ms · × lost · ! late";
/// The key line of a passive run.
pub(super) const PASSIVE_KEYS: &str =
    "q or Ctrl-C: stop and print the summary · a bar a second: frames, red: lost";
/// The strip is dropped last, and kept at least this wide.
const STRIP_MIN: u16 = 8;
/// ratatui's default gap between table columns.
const SPACING: u16 = 1;
/// A section's lines besides its rows: two borders and the header.
const SECTION_FRAME: u16 = 3;

/// What a kind of row shows: its figure columns in display order, then
/// the strip. Sections of the same kind are sized alike.
#[derive(PartialEq)]
pub(super) struct Spec {
    pub(crate) headers: &'static [&'static str],
    /// Room for the usual figures, so columns do not shift as the figures
    /// change; wider figures widen them.
    pub(crate) min_widths: &'static [u16],
    /// When the terminal is too narrow, columns go in falling order of
    /// this; 0 is never given up.
    pub(crate) give_up: &'static [u8],
    /// The first this many columns (who) are left-aligned, the figures
    /// after them right-aligned, so their digits line up.
    pub(crate) left: usize,
    pub(crate) strip: &'static str,
    pub(crate) keys: &'static str,
    /// What a row is, to count those beyond the screen.
    pub(crate) rows_are: &'static str,
}

/// A responder's row: who, how much is lost and how long it takes stay.
pub(super) const ECHO: Spec = Spec {
    headers: &[
        "responder",
        "sent",
        "recv",
        "loss%",
        "late",
        "dup",
        "last",
        "p50",
        "p99",
        "jitter",
        "age ms",
    ],
    min_widths: &[9, 5, 5, 5, 4, 3, 5, 5, 5, 6, 6],
    give_up: &[0, 5, 6, 0, 10, 11, 7, 0, 0, 8, 9],
    left: 1,
    strip: "recent",
    keys: KEYS,
    rows_are: "responders",
};

/// A source's row in a passive run: who and how much it loses stay; its
/// identity goes first, then the rarer counts.
pub(super) const PASSIVE: Spec = Spec {
    headers: &[
        "source", "identity", "recv", "lost", "loss%", "dup", "reord", "sil", "fr/s", "age ms",
    ],
    min_widths: &[7, 8, 6, 4, 5, 3, 5, 3, 5, 6],
    give_up: &[0, 9, 5, 0, 0, 8, 7, 6, 4, 3],
    left: 2,
    strip: "per second",
    keys: PASSIVE_KEYS,
    rows_are: "sources",
};

/// The pair report's row: a source's link, what it brings and how late,
/// under the merged stream's (whose strip is the de-duplication window).
pub(crate) const PAIR: Spec = Spec {
    headers: &[
        "source", "link", "frames", "first%", "only", "lost%", "lag p50", "lag p99", "behind",
    ],
    min_widths: &[6, 8, 6, 6, 4, 5, 7, 7, 6],
    give_up: &[0, 0, 4, 3, 0, 0, 2, 0, 1],
    left: 2,
    strip: "",
    keys: PASSIVE_KEYS,
    rows_are: "links",
};

/// Draws every link's section under one title line, with the keys below.
/// The pair report's section (`pair`), when there is one, goes last.
pub(super) fn render(frame: &mut Frame<'_>, screens: &[Screen], pair: Option<&Screen>) {
    let [head, body, foot] = Layout::vertical([
        Constraint::Length(1),
        Constraint::Min(0),
        Constraint::Length(1),
    ])
    .areas(frame.area());
    frame.render_widget(
        Paragraph::new(title(screens)).style(Style::new().add_modifier(Modifier::BOLD)),
        head,
    );
    let sections: Vec<&Screen> = screens.iter().chain(pair).collect();
    let needs: Vec<u16> = sections
        .iter()
        .map(|s| SECTION_FRAME + s.rows.len().max(1) as u16)
        .collect();
    let heights = section_heights(body.height, &needs);
    let areas = Layout::vertical(heights.iter().map(|&h| Constraint::Length(h))).split(body);
    for (&screen, area) in sections.iter().zip(areas.iter()) {
        if area.height < SECTION_FRAME {
            continue;
        }
        // One set of columns for every section of a kind, so they line up.
        let kind = screen.kind;
        let alike = sections
            .iter()
            .filter(|s| s.kind == kind)
            .flat_map(|s| s.rows.iter().map(|r| &r.cells));
        let widths = widths(kind, alike);
        let columns = fit(&widths, kind.give_up, body.width.saturating_sub(2));
        section(frame, *area, screen, &columns);
    }
    let keys = screens.first().map_or(KEYS, |s| s.kind.keys);
    frame.render_widget(
        Paragraph::new(keys).style(Style::new().fg(Color::DarkGray)),
        foot,
    );
}

/// Each column as wide as its header, its minimum or its widest figure.
fn widths<'a>(kind: &Spec, rows: impl Iterator<Item = &'a Cells> + Clone) -> Vec<u16> {
    (0..kind.headers.len())
        .map(|c| {
            rows.clone()
                .map(|row| width(&row[c].0))
                .chain([width(kind.headers[c]), kind.min_widths[c]])
                .max()
                .unwrap_or(0)
        })
        .collect()
}

/// `mavping · ping · 4.4 s`, with the number of links when there are several.
fn title(screens: &[Screen]) -> String {
    let now = screens.iter().map(|s| s.now).max().unwrap_or(0);
    let probe = screens
        .first()
        .and_then(|s| s.probe)
        .map_or("", ProbeName::as_str);
    let links = match screens.len() {
        1 => String::new(),
        n => format!("{n} links · "),
    };
    format!("mavping · {links}{probe} · {:.1} s", now as f64 / 1e9)
}

/// Each section's height out of `available` lines: all it needs when that
/// fits; otherwise each a frame and one row in turn, then one more row each
/// in turn, so no link is pushed off the screen by another's responders.
fn section_heights(available: u16, needs: &[u16]) -> Vec<u16> {
    let mut left = available;
    let mut heights: Vec<u16> = needs
        .iter()
        .map(|&need| {
            let h = need.min(SECTION_FRAME + 1).min(left);
            left -= h;
            h
        })
        .collect();
    while left > 0 && heights.iter().zip(needs).any(|(h, n)| h < n) {
        for (h, &need) in heights.iter_mut().zip(needs) {
            if *h < need && left > 0 {
                *h += 1;
                left -= 1;
            }
        }
    }
    heights
}

/// One link: its rows as a table, titled with the link.
fn section(frame: &mut Frame<'_>, area: Rect, screen: &Screen, columns: &Columns) {
    let kind = screen.kind;
    let inner = area.width.saturating_sub(2);
    let shown = &columns.shown;

    let slots = usize::from(area.height.saturating_sub(SECTION_FRAME));
    let hidden = screen.rows.len().saturating_sub(slots);
    let status = screen.status.as_str();
    let link = ellipsis(
        &screen.link,
        usize::from(inner.saturating_sub(4 + width(status))),
    );
    let mut block = Block::bordered().title(format!(" {link}{status} "));
    if hidden > 0 {
        block = block.title_bottom(format!(" {hidden} more {} ", kind.rows_are));
    }

    let alarm = Style::new().fg(Color::Red).add_modifier(Modifier::BOLD);
    let dimmed = Style::new().fg(Color::DarkGray);
    let rows = screen.rows.iter().take(slots).map(|r| {
        let mut row: Vec<Cell<'_>> = shown
            .iter()
            .map(|&c| {
                let (text, bad) = &r.cells[c];
                let style = if *bad { alarm } else { Style::new() };
                Cell::from(aligned(kind, c, text.clone())).style(style)
            })
            .collect();
        let width = usize::from(columns.strip);
        row.push(Cell::from(match &r.strip {
            Strip::Marks(marks) => strip(marks, width),
            Strip::Heard(heard) => no_reply(heard, width).into(),
            Strip::Seconds(recent) => seconds(recent, width),
            Strip::Note(note) => ellipsis(note, width).into(),
        }));
        Row::new(row).style(if r.quiet { dimmed } else { Style::new() })
    });
    let header = Row::new(
        shown
            .iter()
            .map(|&c| Cell::from(aligned(kind, c, kind.headers[c].to_string())))
            .chain([Cell::from(kind.strip)]),
    )
    .style(Style::new().add_modifier(Modifier::UNDERLINED));
    let constraints = shown
        .iter()
        .map(|&c| Constraint::Length(columns.widths[c]))
        .chain([Constraint::Length(columns.strip)]);
    let table = Table::new(rows, constraints)
        .header(header)
        .column_spacing(SPACING)
        .block(block);
    frame.render_widget(table, area);
}

/// Figures (every column after who) right-aligned, so their digits line
/// up.
fn aligned(kind: &Spec, column: usize, text: String) -> Line<'static> {
    let line = Line::from(text);
    if column < kind.left {
        line
    } else {
        line.alignment(Alignment::Right)
    }
}

/// `v` to `places` decimals, `-` when there is none yet.
pub(super) fn figure(v: Option<f64>, places: usize) -> String {
    v.map_or_else(|| "-".into(), |v| format!("{v:.places$}"))
}

fn width(text: &str) -> u16 {
    text.chars().count().try_into().unwrap_or(u16::MAX)
}

/// The columns a table shows.
#[derive(Debug, PartialEq)]
struct Columns {
    /// Indices into the kind's headers, in display order.
    shown: Vec<usize>,
    /// Of every figure column, shown or not.
    widths: Vec<u16>,
    strip: u16,
}

/// Which figure columns are shown in `inner` columns, and the strip's
/// width: columns are given up (in falling order of `give_up`) until the
/// strip has [`STRIP_MIN`].
fn fit(widths: &[u16], give_up: &[u8], inner: u16) -> Columns {
    // Each column is followed by a gap: the last one's is the strip's.
    let strip =
        |shown: &[usize]| inner.saturating_sub(shown.iter().map(|&c| widths[c] + SPACING).sum());
    let mut shown: Vec<usize> = (0..widths.len()).collect();
    while strip(&shown) < STRIP_MIN {
        let next = (0..shown.len())
            .filter(|&i| give_up[shown[i]] > 0)
            .max_by_key(|&i| give_up[shown[i]]);
        let Some(i) = next else { break };
        shown.remove(i);
    }
    Columns {
        strip: strip(&shown),
        shown,
        widths: widths.to_vec(),
    }
}

/// `text`, cut to `max` characters with an ellipsis when longer.
fn ellipsis(text: &str, max: usize) -> String {
    if text.chars().count() <= max {
        return text.to_string();
    }
    let kept: String = text.chars().take(max.saturating_sub(1)).collect();
    format!("{kept}…")
}

/// What a responder that never answered was heard as, in place of its
/// strip.
fn no_reply(heard: &str, width: usize) -> String {
    let long = format!("heard ({heard}), no reply");
    if long.chars().count() <= width {
        long
    } else {
        "heard, no reply".to_string()
    }
}

/// The recent outcomes, newest on the right, scaled between the lowest and
/// highest RTT shown: `×` lost (red), `!` late (yellow).
pub(super) fn strip(recent: &[Mark], width: usize) -> Line<'static> {
    let shown = newest(recent, width);
    let rtts = shown.iter().filter_map(|m| match m {
        Mark::Rtt(ns) => Some(*ns),
        _ => None,
    });
    let lo = rtts.clone().min().unwrap_or(0);
    let hi = rtts.max().unwrap_or(0);
    let spans: Vec<Span<'static>> = shown
        .iter()
        .map(|m| match *m {
            Mark::Rtt(ns) if hi > lo => bar((ns - lo) as f64 / (hi - lo) as f64, Color::Green),
            Mark::Rtt(_) => bar(0.0, Color::Green),
            Mark::Lost => Span::styled(
                "×",
                Style::new().fg(Color::Red).add_modifier(Modifier::BOLD),
            ),
            Mark::Late => Span::styled("!", Style::new().fg(Color::Yellow)),
        })
        .collect();
    Line::from(spans)
}

/// A source's recent seconds, newest on the right: a bar per second scaled
/// from none to the most frames shown, red where its sequence lost any,
/// `·` a second without a frame.
pub(super) fn seconds(recent: &[Second], width: usize) -> Line<'static> {
    let shown = newest(recent, width);
    let most = shown.iter().map(|s| s.frames).max().unwrap_or(0).max(1);
    let spans: Vec<Span<'static>> = shown
        .iter()
        .map(|s| {
            if s.frames == 0 {
                return Span::styled("·", Style::new().fg(Color::DarkGray));
            }
            let colour = if s.lost { Color::Red } else { Color::Green };
            bar(s.frames as f64 / most as f64, colour)
        })
        .collect();
    Line::from(spans)
}

/// The last `width` of a strip's marks.
fn newest<T>(recent: &[T], width: usize) -> &[T] {
    &recent[recent.len().saturating_sub(width)..]
}

/// A bar `fraction` of the full height (0 to 1).
fn bar(fraction: f64, colour: Color) -> Span<'static> {
    let level = (fraction * 7.0).round() as usize;
    Span::styled(BARS[level].to_string(), Style::new().fg(colour))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_strip_scales_between_the_lowest_and_highest_rtt_shown() {
        let line = strip(
            &[
                Mark::Rtt(9),
                Mark::Rtt(1),
                Mark::Lost,
                Mark::Rtt(8),
                Mark::Late,
            ],
            4,
        );
        let text: String = line.spans.iter().map(|s| s.content.as_ref()).collect();
        assert_eq!(text, "▁×█!");
    }

    #[test]
    fn columns_are_given_up_least_needed_first() {
        let widths = [9, 4, 4, 5, 4, 3, 5, 5, 5, 6];
        let fit = |widths: &[u16], inner| fit(widths, ECHO.give_up, inner);
        // 80 columns less the borders: everything, and a strip.
        let all = fit(&widths, 78);
        assert_eq!(all.shown, (0..10).collect::<Vec<_>>());
        assert_eq!(all.strip, 78 - 50 - 10);
        // Narrower: dup, then late, go first.
        let narrow = fit(&widths, 60);
        assert_eq!(narrow.shown, [0, 1, 2, 3, 6, 7, 8, 9]);
        assert_eq!(narrow.strip, 9);
        // Far too narrow: only the columns never given up remain.
        assert_eq!(fit(&widths, 20).shown, [0, 3, 7, 8]);
        // A source's identity goes first, then dup, reord and sil.
        let widths = [7, 13, 6, 4, 5, 3, 5, 3, 5];
        let fit = |inner| super::fit(&widths, PASSIVE.give_up, inner).shown;
        assert_eq!(fit(78), (0..9).collect::<Vec<_>>());
        assert_eq!(fit(60), [0, 2, 3, 4, 5, 6, 7, 8]);
        assert_eq!(fit(50), [0, 2, 3, 4, 6, 7, 8]);
        assert_eq!(fit(44), [0, 2, 3, 4, 7, 8]);
        assert_eq!(fit(20), [0, 3, 4]);
    }

    #[test]
    fn sections_each_get_a_row_before_any_gets_two() {
        assert_eq!(section_heights(22, &[5, 4]), [5, 4]);
        assert_eq!(section_heights(10, &[13, 4]), [6, 4]);
        assert_eq!(section_heights(12, &[13, 13, 13]), [4, 4, 4]);
        assert_eq!(section_heights(14, &[13, 13, 13]), [5, 5, 4]);
        assert_eq!(section_heights(6, &[5, 5]), [4, 2]);
    }

    #[test]
    fn long_links_end_in_an_ellipsis() {
        assert_eq!(ellipsis("udp:0.0.0.0:14550", 40), "udp:0.0.0.0:14550");
        assert_eq!(ellipsis("sim:?responders=2&loss=5%", 10), "sim:?resp…");
    }
}
