//! Charts as PNG and SVG with plotters: mean preference factors with interval bars, the overall
//! weights as a heat map, and Bradley-Terry strengths per comparison group.
//!
//! Text is set in the bundled DejaVu Sans (registered once through plotters' `ab_glyph` feature),
//! so nothing depends on system fonts. Charts are laid out in pixels: label columns are measured
//! with the font before drawing, so labels are never clipped, and every bar is labelled directly,
//! so no legend covers data.

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use plotters::style::FontStyle;

use crate::analysis::{Analysis, Interval, StrengthScope};
use crate::error::{AnalysisError, Result};
use rmt_runfolder::write_atomic;

/// DejaVu Sans (Bitstream Vera licence, see `assets/DejaVuSans-LICENSE.txt`).
static FONT: &[u8] = include_bytes!("../assets/DejaVuSans.ttf");
const FAMILY: &str = "sans-serif";

/// Registers the bundled font for plotters' text (idempotent).
pub fn register_bundled_font() -> Result<()> {
    static REGISTERED: OnceLock<bool> = OnceLock::new();
    let ok = *REGISTERED
        .get_or_init(|| plotters::style::register_font(FAMILY, FontStyle::Normal, FONT).is_ok());
    if ok {
        Ok(())
    } else {
        Err(AnalysisError::Chart {
            path: PathBuf::from("assets/DejaVuSans.ttf"),
            message: "the bundled font could not be loaded".into(),
        })
    }
}

/// Colour-blind-friendly categorical colours (Okabe-Ito), by level index.
const PALETTE: [RGBColor; 7] = [
    RGBColor(0, 114, 178),
    RGBColor(230, 159, 0),
    RGBColor(0, 158, 115),
    RGBColor(204, 121, 167),
    RGBColor(86, 180, 233),
    RGBColor(213, 94, 0),
    RGBColor(240, 228, 66),
];
const INK: RGBColor = RGBColor(30, 30, 30);
const GRID: RGBColor = RGBColor(225, 225, 225);

type DrawResult = std::result::Result<(), String>;

/// A chart that can be drawn on any plotters backend.
trait Chart {
    /// Pixel size.
    fn size(&self) -> (u32, u32);
    /// Draws on `root`, which has [`Chart::size`].
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult;
}

fn font(size: f64) -> TextStyle<'static> {
    TextStyle::from((FAMILY, size).into_font()).color(&INK)
}

fn e<E: std::fmt::Display>(error: E) -> String {
    error.to_string()
}

/// Width in pixels of `text` in `style` (measured with the bundled font).
fn text_width(text: &str, size: f64) -> u32 {
    let style = (FAMILY, size).into_font();
    style
        .box_size(text)
        .map(|(w, _)| w)
        .unwrap_or(text.len() as u32 * size as u32)
}

/// One line of a horizontal dot or bar chart: a heading or a labelled value.
enum Line {
    Heading(String),
    Value {
        label: String,
        value: f64,
        interval: Interval,
        colour: usize,
    },
}

/// Horizontal bars (or dots) with interval whiskers, one labelled line each, under headings.
struct IntervalChart {
    title: String,
    axis: String,
    lines: Vec<Line>,
    x_range: (f64, f64),
    bars: bool,
    /// Draw a reference line at x = 0.
    zero_line: bool,
}

const LINE_HEIGHT: i32 = 25;
const LABEL_SIZE: f64 = 15.0;
const TITLE_HEIGHT: i32 = 44;
const AXIS_HEIGHT: i32 = 56;
const PLOT_WIDTH: i32 = 560;
const MARGIN: i32 = 16;

impl IntervalChart {
    fn label_width(&self) -> i32 {
        self.lines
            .iter()
            .map(|line| match line {
                Line::Heading(_) => 0,
                Line::Value { label, .. } => text_width(label, LABEL_SIZE) as i32,
            })
            .max()
            .unwrap_or(0)
            + 12
    }

    fn value_width(&self) -> i32 {
        text_width("-0.000", 12.0) as i32 + 8
    }

    fn heading_width(&self) -> i32 {
        self.lines
            .iter()
            .map(|line| match line {
                Line::Heading(text) => text_width(text, LABEL_SIZE) as i32,
                Line::Value { .. } => 0,
            })
            .max()
            .unwrap_or(0)
    }
}

impl Chart for IntervalChart {
    fn size(&self) -> (u32, u32) {
        let body = self.label_width() + PLOT_WIDTH + self.value_width();
        let width = body
            .max(self.heading_width())
            .max(text_width(&self.title, 18.0) as i32);
        let height = TITLE_HEIGHT + self.lines.len() as i32 * LINE_HEIGHT + AXIS_HEIGHT;
        ((width + 2 * MARGIN) as u32, (height + MARGIN) as u32)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult {
        root.fill(&WHITE).map_err(e)?;
        let left = MARGIN + self.label_width();
        let right = left + PLOT_WIDTH;
        let top = TITLE_HEIGHT;
        let bottom = top + self.lines.len() as i32 * LINE_HEIGHT;
        let (x0, x1) = self.x_range;
        let px = |x: f64| left + ((x - x0) / (x1 - x0) * PLOT_WIDTH as f64).round() as i32;
        root.draw(&Text::new(self.title.clone(), (MARGIN, 12), font(18.0)))
            .map_err(e)?;

        // Grid and axis ticks.
        for tick in ticks(x0, x1) {
            let x = px(tick);
            root.draw(&PathElement::new(vec![(x, top), (x, bottom)], GRID))
                .map_err(e)?;
            root.draw(&PathElement::new(vec![(x, bottom), (x, bottom + 5)], INK))
                .map_err(e)?;
            root.draw(&Text::new(
                format_tick(tick),
                (x, bottom + 8),
                font(12.0).pos(Pos::new(HPos::Center, VPos::Top)),
            ))
            .map_err(e)?;
        }
        root.draw(&PathElement::new(
            vec![(left, bottom), (right, bottom)],
            INK,
        ))
        .map_err(e)?;
        root.draw(&Text::new(
            self.axis.clone(),
            ((left + right) / 2, bottom + 30),
            font(13.0).pos(Pos::new(HPos::Center, VPos::Top)),
        ))
        .map_err(e)?;
        if self.zero_line && x0 < 0.0 && x1 > 0.0 {
            root.draw(&PathElement::new(
                vec![(px(0.0), top), (px(0.0), bottom)],
                INK,
            ))
            .map_err(e)?;
        }

        for (k, line) in self.lines.iter().enumerate() {
            let y = top + k as i32 * LINE_HEIGHT + LINE_HEIGHT / 2;
            match line {
                Line::Heading(text) => {
                    // Headings may reach into the plot: clear the grid behind them.
                    clear_behind(root, text, LABEL_SIZE, (MARGIN, y))?;
                    root.draw(&Text::new(
                        text.clone(),
                        (MARGIN, y),
                        font(LABEL_SIZE).pos(Pos::new(HPos::Left, VPos::Center)),
                    ))
                    .map_err(e)?;
                }
                Line::Value {
                    label,
                    value,
                    interval,
                    colour,
                } => {
                    let colour = PALETTE[colour % PALETTE.len()];
                    root.draw(&Text::new(
                        label.clone(),
                        (left - 8, y),
                        font(LABEL_SIZE).pos(Pos::new(HPos::Right, VPos::Center)),
                    ))
                    .map_err(e)?;
                    if !value.is_finite() {
                        continue;
                    }
                    let clamp = |x: f64| x.clamp(x0, x1);
                    if self.bars {
                        root.draw(&Rectangle::new(
                            [(px(clamp(0.0)), y - 8), (px(clamp(*value)), y + 8)],
                            colour.mix(0.85).filled(),
                        ))
                        .map_err(e)?;
                    } else {
                        root.draw(&Circle::new((px(clamp(*value)), y), 5, colour.filled()))
                            .map_err(e)?;
                    }
                    let mut end = px(clamp(*value));
                    if let Some((lo, hi)) = interval {
                        let (a, b) = (px(clamp(*lo)), px(clamp(*hi)));
                        let whisker = ShapeStyle::from(&INK).stroke_width(2);
                        root.draw(&PathElement::new(vec![(a, y), (b, y)], whisker))
                            .map_err(e)?;
                        for x in [a, b] {
                            root.draw(&PathElement::new(vec![(x, y - 5), (x, y + 5)], whisker))
                                .map_err(e)?;
                        }
                        end = end.max(b);
                    }
                    let value_text = format!("{value:.3}");
                    clear_behind(root, &value_text, 12.0, (end.min(right) + 6, y))?;
                    root.draw(&Text::new(
                        value_text,
                        (end.min(right) + 6, y),
                        font(12.0).pos(Pos::new(HPos::Left, VPos::Center)),
                    ))
                    .map_err(e)?;
                }
            }
        }
        Ok(())
    }
}

/// Paints white behind left-aligned, vertically centred text at `at`, so grid and reference
/// lines never run through a label.
fn clear_behind<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    text: &str,
    size: f64,
    at: (i32, i32),
) -> DrawResult {
    let width = text_width(text, size) as i32;
    let half = (size * 0.65) as i32;
    root.draw(&Rectangle::new(
        [(at.0 - 3, at.1 - half), (at.0 + width + 3, at.1 + half)],
        WHITE.filled(),
    ))
    .map_err(e)
}

/// Round tick positions covering [lo, hi].
fn ticks(lo: f64, hi: f64) -> Vec<f64> {
    let span = hi - lo;
    if span.is_nan() || span <= 0.0 {
        return vec![lo];
    }
    let raw = span / 6.0;
    let magnitude = 10f64.powf(raw.log10().floor());
    let step = [1.0, 2.0, 2.5, 5.0, 10.0]
        .iter()
        .map(|m| m * magnitude)
        .find(|s| span / s <= 7.0)
        .unwrap_or(10.0 * magnitude);
    let mut t = (lo / step).ceil() * step;
    let mut out = Vec::new();
    while t <= hi + step * 1e-9 {
        out.push(if t.abs() < step * 1e-9 { 0.0 } else { t });
        t += step;
    }
    out
}

fn format_tick(t: f64) -> String {
    let text = format!("{t:.2}");
    let text = text.trim_end_matches('0').trim_end_matches('.').to_string();
    if text == "-0" {
        "0".into()
    } else {
        text
    }
}

/// The overall weights as a heat map with the value and interval in every cell.
struct HeatMap {
    title: String,
    column_title: String,
    row_title: String,
    columns: Vec<String>,
    rows: Vec<String>,
    values: Vec<Vec<f64>>,
    intervals: Vec<Vec<Interval>>,
}

const CELL_W: i32 = 170;
const CELL_H: i32 = 64;

impl HeatMap {
    fn row_label_width(&self) -> i32 {
        self.rows
            .iter()
            .map(|r| text_width(r, LABEL_SIZE))
            .chain([text_width(&self.row_title, 13.0)])
            .max()
            .unwrap_or(0) as i32
            + 16
    }
}

impl Chart for HeatMap {
    fn size(&self) -> (u32, u32) {
        let grid = self.row_label_width() + self.columns.len() as i32 * CELL_W;
        let width = grid.max(text_width(&self.title, 18.0) as i32);
        let height = TITLE_HEIGHT + 50 + self.rows.len() as i32 * CELL_H;
        ((width + 2 * MARGIN) as u32, (height + MARGIN) as u32)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult {
        root.fill(&WHITE).map_err(e)?;
        root.draw(&Text::new(self.title.clone(), (MARGIN, 12), font(18.0)))
            .map_err(e)?;
        let left = MARGIN + self.row_label_width();
        let top = TITLE_HEIGHT + 50;
        let finite: Vec<f64> = self
            .values
            .iter()
            .flatten()
            .copied()
            .filter(|v| v.is_finite())
            .collect();
        let lo = finite.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = finite.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        root.draw(&Text::new(
            self.column_title.clone(),
            (
                left + self.columns.len() as i32 * CELL_W / 2,
                TITLE_HEIGHT + 4,
            ),
            font(13.0).pos(Pos::new(HPos::Center, VPos::Top)),
        ))
        .map_err(e)?;
        root.draw(&Text::new(
            self.row_title.clone(),
            (left - 8, top - 8),
            font(13.0).pos(Pos::new(HPos::Right, VPos::Bottom)),
        ))
        .map_err(e)?;
        for (c, column) in self.columns.iter().enumerate() {
            root.draw(&Text::new(
                column.clone(),
                (left + c as i32 * CELL_W + CELL_W / 2, top - 8),
                font(LABEL_SIZE).pos(Pos::new(HPos::Center, VPos::Bottom)),
            ))
            .map_err(e)?;
        }
        for (r, row) in self.rows.iter().enumerate() {
            let y = top + r as i32 * CELL_H;
            root.draw(&Text::new(
                row.clone(),
                (left - 8, y + CELL_H / 2),
                font(LABEL_SIZE).pos(Pos::new(HPos::Right, VPos::Center)),
            ))
            .map_err(e)?;
            for c in 0..self.columns.len() {
                let x = left + c as i32 * CELL_W;
                let value = self.values[r][c];
                // White (lowest weight) to deep blue (highest).
                let t = if hi > lo && value.is_finite() {
                    (value - lo) / (hi - lo)
                } else {
                    0.5
                };
                let fill = if value.is_finite() {
                    RGBColor(
                        (247.0 - t * (247.0 - 8.0)) as u8,
                        (251.0 - t * (251.0 - 69.0)) as u8,
                        (255.0 - t * (255.0 - 148.0)) as u8,
                    )
                } else {
                    RGBColor(240, 240, 240)
                };
                root.draw(&Rectangle::new(
                    [(x, y), (x + CELL_W, y + CELL_H)],
                    fill.filled(),
                ))
                .map_err(e)?;
                root.draw(&Rectangle::new(
                    [(x, y), (x + CELL_W, y + CELL_H)],
                    WHITE.stroke_width(2),
                ))
                .map_err(e)?;
                let ink = if t > 0.55 && value.is_finite() {
                    WHITE
                } else {
                    INK
                };
                let main = if value.is_finite() {
                    format!("{value:.3}")
                } else {
                    "–".into()
                };
                root.draw(&Text::new(
                    main,
                    (x + CELL_W / 2, y + CELL_H / 2 - 9),
                    font(17.0)
                        .color(&ink)
                        .pos(Pos::new(HPos::Center, VPos::Center)),
                ))
                .map_err(e)?;
                if let Some((a, b)) = self.intervals[r][c] {
                    root.draw(&Text::new(
                        format!("[{a:.3}, {b:.3}]"),
                        (x + CELL_W / 2, y + CELL_H / 2 + 13),
                        font(12.0)
                            .color(&ink)
                            .pos(Pos::new(HPos::Center, VPos::Center)),
                    ))
                    .map_err(e)?;
                }
            }
        }
        Ok(())
    }
}

fn factors_chart(analysis: &Analysis) -> IntervalChart {
    let mut lines = Vec::new();
    for row in &analysis.factors {
        lines.push(Line::Heading(row.label.clone()));
        // Colour by the level's position among all levels of the varied variable, so a level
        // keeps its colour in every row.
        let mut all_levels: Vec<&str> = Vec::new();
        if let Some(v) = analysis
            .design
            .variables
            .iter()
            .position(|n| *n == row.varied)
        {
            for values in &analysis.design.configuration_values {
                if !all_levels.contains(&values[v].as_str()) {
                    all_levels.push(&values[v]);
                }
            }
        }
        for level in &row.levels {
            lines.push(Line::Value {
                label: level.level.clone(),
                value: level.factor,
                interval: level.interval,
                colour: all_levels
                    .iter()
                    .position(|l| *l == level.level)
                    .unwrap_or(0),
            });
        }
    }
    let mean_over = analysis
        .design
        .mean_over
        .map(|m| format!(", mean over {}", analysis.design.variables[m]))
        .unwrap_or_default();
    IntervalChart {
        title: format!(
            "Mean preference factors ({} participants, {} responses{mean_over})",
            analysis.basis.participants, analysis.basis.responses
        ),
        axis: "preference factor (votes / responses in group; bars: 95% bootstrap interval)".into(),
        lines,
        x_range: (0.0, 1.0),
        bars: true,
        zero_line: false,
    }
}

fn strengths_chart(analysis: &Analysis) -> IntervalChart {
    let mut lines = Vec::new();
    let mut lo: f64 = -1.0;
    let mut hi: f64 = 1.0;
    for fit in analysis
        .strengths
        .iter()
        .filter(|f| f.scope == StrengthScope::Group)
    {
        lines.push(Line::Heading(format!(
            "{} (v = {:.2}{})",
            fit.label,
            fit.tie_parameter,
            if fit.prior_used { ", prior" } else { "" }
        )));
        for (k, item) in fit.items.iter().enumerate() {
            for x in [
                Some(item.log_strength),
                item.interval.map(|i| i.0),
                item.interval.map(|i| i.1),
            ]
            .into_iter()
            .flatten()
            .filter(|x| x.is_finite())
            {
                lo = lo.min(x);
                hi = hi.max(x);
            }
            lines.push(Line::Value {
                label: item.item.clone(),
                value: item.log_strength,
                interval: item.interval,
                colour: k,
            });
        }
    }
    let pad = 0.05 * (hi - lo);
    IntervalChart {
        title: format!(
            "Bradley-Terry-Davidson log-strengths per comparison group ({} participants)",
            analysis.participants.len()
        ),
        axis: "centred log-strength (whiskers: 95% bootstrap interval)".into(),
        lines,
        x_range: ((lo - pad).floor(), (hi + pad).ceil()),
        bars: false,
        zero_line: true,
    }
}

fn weights_chart(analysis: &Analysis) -> HeatMap {
    let w = &analysis.weights;
    HeatMap {
        title: format!(
            "Overall preference weights ({} participants, {} responses)",
            analysis.basis.participants, analysis.basis.responses
        ),
        column_title: w.column_variable.clone(),
        row_title: w.row_variables.join(", "),
        columns: w.columns.clone(),
        rows: w
            .rows
            .iter()
            .map(|r| {
                if r.is_empty() {
                    "all".to_string()
                } else {
                    r.clone()
                }
            })
            .collect(),
        values: w.values.clone(),
        intervals: w.intervals.clone(),
    }
}

/// Renders `chart` to `dir/name.png` and `dir/name.svg` (each written atomically).
fn write_chart<C: Chart>(chart: &C, dir: &Path, name: &str) -> Result<Vec<PathBuf>> {
    let size = chart.size();
    let png = dir.join(format!("{name}.png"));
    let svg = dir.join(format!("{name}.svg"));
    let chart_error = |path: &Path| {
        let path = path.to_path_buf();
        move |message: String| AnalysisError::Chart { path, message }
    };

    // PNG: the bitmap backend encodes by file extension, so draw into a pixel buffer and let
    // the backend save a temporary ".png" that is then renamed over the target.
    let temporary = dir.join(format!(".{name}.tmp.png"));
    {
        let root = BitMapBackend::new(&temporary, size).into_drawing_area();
        chart.draw(&root).map_err(chart_error(&png))?;
        root.present()
            .map_err(|e| chart_error(&png)(e.to_string()))?;
    }
    std::fs::rename(&temporary, &png).map_err(crate::error::io_error(&png))?;

    let mut text = String::new();
    {
        let root = SVGBackend::with_string(&mut text, size).into_drawing_area();
        chart.draw(&root).map_err(chart_error(&svg))?;
        root.present()
            .map_err(|e| chart_error(&svg)(e.to_string()))?;
    }
    write_atomic(&svg, text.as_bytes())?;
    Ok(vec![png, svg])
}

/// Draws all charts into `dir`; returns the files written.
pub fn write_charts(analysis: &Analysis, dir: &Path) -> Result<Vec<PathBuf>> {
    register_bundled_font()?;
    let mut written = Vec::new();
    if !analysis.factors.is_empty() {
        written.extend(write_chart(
            &factors_chart(analysis),
            dir,
            "preference_factors",
        )?);
        written.extend(write_chart(
            &weights_chart(analysis),
            dir,
            "preference_weights",
        )?);
        written.extend(write_chart(
            &strengths_chart(analysis),
            dir,
            "bradley_terry",
        )?);
    }
    Ok(written)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ticks_are_round_and_cover_the_range() {
        let labels: Vec<String> = ticks(0.0, 1.0).into_iter().map(format_tick).collect();
        assert_eq!(labels, ["0", "0.2", "0.4", "0.6", "0.8", "1"]);
        let t = ticks(-3.0, 2.0);
        assert_eq!(t.first(), Some(&-3.0));
        assert_eq!(t.last(), Some(&2.0));
        assert!(t.contains(&0.0));
        assert_eq!(format_tick(0.6000000000000001), "0.6");
        assert_eq!(format_tick(-0.0), "0");
    }

    #[test]
    fn the_bundled_font_measures_text() {
        register_bundled_font().unwrap();
        let short = text_width("ab", 14.0);
        let long = text_width("abcdefgh", 14.0);
        assert!(short > 0 && long > 3 * short, "{short} {long}");
    }
}
