//! A small plotting kit on plotters, laid out in pixels: row charts (horizontal bars, dots with
//! whiskers, stacked shares) and x-y panels (points, lines, dashed fits), each with its legend in
//! a strip under the title, so no legend covers data.
//!
//! Text is set in the DejaVu Sans that `rmt-analysis` bundles and registers through plotters'
//! `ab_glyph` feature ([`rmt_analysis::charts::register_bundled_font`]); label columns are
//! measured with that font before anything is drawn, so labels are never clipped. Every figure is
//! written as PNG and SVG; the same figure always gives the same bytes.

use std::path::{Path, PathBuf};

use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use crate::error::{io_error, ReportError, Result};
use crate::format;
use rmt_runfolder::write_atomic;

/// The font family registered by `rmt-analysis`.
const FAMILY: &str = "sans-serif";
/// Text colour.
pub const INK: RGBColor = RGBColor(30, 30, 30);
/// Grid lines.
const GRID: RGBColor = RGBColor(228, 228, 228);
/// Minor grid lines of log axes.
const GRID_MINOR: RGBColor = RGBColor(243, 243, 243);
/// Outer margin, pixels.
pub(crate) const MARGIN: i32 = 16;
/// Title size.
const TITLE_SIZE: f64 = 20.0;
/// Subtitle, axis titles and legend size.
pub(crate) const SMALL_SIZE: f64 = 14.0;
/// Row labels and headings.
const LABEL_SIZE: f64 = 14.0;
/// Tick labels and value labels.
pub(crate) const TICK_SIZE: f64 = 12.0;

pub(crate) type DrawResult = std::result::Result<(), String>;

pub(crate) fn e<E: std::fmt::Display>(error: E) -> String {
    error.to_string()
}

/// The style of text of `size` pixels.
fn font(size: f64) -> TextStyle<'static> {
    TextStyle::from((FAMILY, size).into_font()).color(&INK)
}

/// Width in pixels of `text` at `size`, measured with the bundled font.
pub fn text_width(text: &str, size: f64) -> i32 {
    (FAMILY, size)
        .into_font()
        .box_size(text)
        .map(|(w, _)| w as i32)
        .unwrap_or((text.chars().count() as f64 * size * 0.6) as i32)
}

/// Draws `text` at `at` with the given anchor.
pub(crate) fn label<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    text: &str,
    at: (i32, i32),
    size: f64,
    h: HPos,
    v: VPos,
) -> DrawResult {
    root.draw(&Text::new(
        text.to_string(),
        at,
        font(size).pos(Pos::new(h, v)),
    ))
    .map_err(e)
}

/// Paints white behind left-aligned, vertically centred text at `at`, so grid lines never run
/// through it.
fn clear_behind<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    text: &str,
    size: f64,
    at: (i32, i32),
) -> DrawResult {
    let width = text_width(text, size);
    let half = (size * 0.65) as i32;
    root.draw(&Rectangle::new(
        [(at.0 - 2, at.1 - half), (at.0 + width + 2, at.1 + half)],
        WHITE.filled(),
    ))
    .map_err(e)
}

/// A value axis: linear or logarithmic (base 10) between `lo` and `hi`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Axis {
    /// Lower end.
    pub lo: f64,
    /// Upper end.
    pub hi: f64,
    /// Logarithmic.
    pub log: bool,
}

/// One tick of an axis.
#[derive(Clone, Debug, PartialEq)]
pub struct Tick {
    /// Where.
    pub value: f64,
    /// Its label, if labelled.
    pub label: Option<String>,
    /// A major tick (full grid line) or a minor one.
    pub major: bool,
}

impl Axis {
    /// A linear axis with round ends covering `values` (and 0 when `include_zero`).
    pub fn linear(values: &[f64], include_zero: bool) -> Axis {
        let finite: Vec<f64> = values.iter().copied().filter(|v| v.is_finite()).collect();
        let mut lo = finite.iter().copied().fold(f64::INFINITY, f64::min);
        let mut hi = finite.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        if finite.is_empty() {
            (lo, hi) = (0.0, 1.0);
        }
        if include_zero {
            lo = lo.min(0.0);
            hi = hi.max(0.0);
        }
        if hi - lo <= f64::EPSILON * hi.abs().max(1.0) {
            let pad = if hi == 0.0 { 1.0 } else { hi.abs() * 0.1 };
            lo -= if include_zero && lo == 0.0 { 0.0 } else { pad };
            hi += pad;
        }
        let step = linear_step(lo, hi);
        Axis {
            lo: (lo / step).floor() * step,
            hi: (hi / step).ceil() * step,
            log: false,
        }
    }

    /// A logarithmic axis from the round value (1, 2 or 5 times a power of ten) at or below the
    /// smallest positive value to the one at or above the largest.
    pub fn log(values: &[f64]) -> Axis {
        let positive: Vec<f64> = values
            .iter()
            .copied()
            .filter(|v| v.is_finite() && *v > 0.0)
            .collect();
        if positive.is_empty() {
            return Axis {
                lo: 1.0,
                hi: 10.0,
                log: true,
            };
        }
        let min = positive.iter().copied().fold(f64::INFINITY, f64::min);
        let max = positive.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let lo = round_125(min, false);
        let mut hi = round_125(max, true);
        if hi <= lo {
            hi = round_125(lo * 1.5, true);
        }
        Axis { lo, hi, log: true }
    }

    /// Logarithmic when the positive values span more than `ratio` (and none is 0 or
    /// negative), linear from 0 otherwise.
    pub fn auto(values: &[f64], ratio: f64) -> Axis {
        let finite: Vec<f64> = values.iter().copied().filter(|v| v.is_finite()).collect();
        let min = finite.iter().copied().fold(f64::INFINITY, f64::min);
        let max = finite.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        if !finite.is_empty() && min > 0.0 && max / min > ratio {
            Axis::log(&finite)
        } else {
            Axis::linear(&finite, true)
        }
    }

    /// Position of `v` along the axis, 0 at `lo` and 1 at `hi` (not clamped).
    pub fn fraction(&self, v: f64) -> f64 {
        if self.log {
            let v = v.max(self.lo * 1e-3);
            (v.log10() - self.lo.log10()) / (self.hi.log10() - self.lo.log10())
        } else {
            (v - self.lo) / (self.hi - self.lo)
        }
    }

    /// Pixel position of `v` between pixels `a` (at `lo`) and `b` (at `hi`), clamped to them.
    pub fn pixel(&self, v: f64, a: i32, b: i32) -> i32 {
        let t = self.fraction(v).clamp(0.0, 1.0);
        a + ((b - a) as f64 * t).round() as i32
    }

    /// Ticks: round steps on linear axes; decades (labelled) and 2..9 (labelled at 2 and 5
    /// when the axis spans at most two decades) on log axes.
    pub fn ticks(&self) -> Vec<Tick> {
        if !self.log {
            let step = linear_step(self.lo, self.hi);
            let mut ticks = Vec::new();
            let first = (self.lo / step - 1e-9).ceil() as i64;
            let last = (self.hi / step + 1e-9).floor() as i64;
            for k in first..=last {
                let value = k as f64 * step;
                ticks.push(Tick {
                    value,
                    label: Some(tick_label(value, step)),
                    major: true,
                });
            }
            return ticks;
        }
        // Decades are major and labelled; 2 and 5 are labelled too unless the axis spans more
        // than two and a half decades; an end is labelled when it is at least 2.5x from every
        // other label, so that labels never run into each other.
        let span = (self.hi / self.lo).log10();
        let first = self.lo.log10().floor() as i32;
        let last = self.hi.log10().ceil() as i32;
        let mut ticks = Vec::new();
        let mut ends = Vec::new();
        for d in first..=last {
            let base = 10f64.powi(d);
            for m in 1..=9 {
                let value = base * m as f64;
                let inside = value >= self.lo * (1.0 - 1e-9) && value <= self.hi * (1.0 + 1e-9);
                if !inside {
                    continue;
                }
                let is_end =
                    (value / self.lo - 1.0).abs() < 1e-9 || (value / self.hi - 1.0).abs() < 1e-9;
                let labelled = m == 1 || (span <= 2.5 && (m == 2 || m == 5));
                if is_end && !labelled {
                    ends.push((ticks.len(), base));
                }
                ticks.push(Tick {
                    value,
                    label: labelled.then(|| tick_label(value, base)),
                    major: m == 1,
                });
            }
        }
        for (i, base) in ends {
            let value = ticks[i].value;
            let room = ticks
                .iter()
                .filter(|t| t.label.is_some())
                .all(|t| (t.value / value).max(value / t.value) >= 2.5);
            if room {
                ticks[i].label = Some(tick_label(value, base));
            }
        }
        ticks
    }
}

/// The round value (1, 2 or 5 times a power of ten) at or below `v` (`up`: at or above).
fn round_125(v: f64, up: bool) -> f64 {
    let base = 10f64.powf(v.log10().floor());
    let steps = [1.0, 2.0, 5.0, 10.0];
    let tolerance = 1e-9;
    if up {
        steps
            .iter()
            .map(|m| m * base)
            .find(|c| *c >= v * (1.0 - tolerance))
            .unwrap_or(10.0 * base)
    } else {
        steps
            .iter()
            .rev()
            .map(|m| m * base)
            .find(|c| *c <= v * (1.0 + tolerance))
            .unwrap_or(base)
    }
}

/// A round step giving about six intervals over [lo, hi].
fn linear_step(lo: f64, hi: f64) -> f64 {
    let span = (hi - lo).abs();
    if !span.is_finite() || span == 0.0 {
        return 1.0;
    }
    let raw = span / 6.0;
    let magnitude = 10f64.powf(raw.log10().floor());
    [1.0, 2.0, 2.5, 5.0, 10.0]
        .iter()
        .map(|m| m * magnitude)
        .find(|s| span / s <= 7.0)
        .unwrap_or(10.0 * magnitude)
}

/// A tick label: thousands separators from 1000 up, otherwise as many decimals as the step needs.
fn tick_label(value: f64, step: f64) -> String {
    if value.abs() >= 1000.0 && step >= 1.0 {
        return format::count(value);
    }
    let decimals = if step >= 1.0 {
        0
    } else {
        (-step.log10().floor()) as usize + 1
    };
    let text = format::fixed(value, decimals);
    if text.contains('.') {
        let t = text.trim_end_matches('0').trim_end_matches('.');
        t.to_string()
    } else {
        text
    }
}

/// Point markers (colour-blind safe: shape carries meaning as well as colour).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Marker {
    /// Filled circle.
    Circle,
    /// Filled square.
    Square,
    /// Filled triangle, point up.
    Triangle,
    /// Filled diamond.
    Diamond,
    /// Diamond outline.
    OpenDiamond,
    /// A short vertical bar across the row (a reference value).
    Tick,
}

fn draw_marker<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    marker: Marker,
    (x, y): (i32, i32),
    r: i32,
    colour: RGBColor,
) -> DrawResult {
    let outline = ShapeStyle::from(&WHITE).stroke_width(1);
    match marker {
        Marker::Circle => {
            root.draw(&Circle::new((x, y), r, colour.filled()))
                .map_err(e)?;
            root.draw(&Circle::new((x, y), r, outline)).map_err(e)
        }
        Marker::Square => {
            let s = r - 1;
            root.draw(&Rectangle::new(
                [(x - s, y - s), (x + s, y + s)],
                colour.filled(),
            ))
            .map_err(e)
        }
        Marker::Triangle => root
            .draw(&Polygon::new(
                vec![(x, y - r - 1), (x + r + 1, y + r), (x - r - 1, y + r)],
                colour.filled(),
            ))
            .map_err(e),
        Marker::Diamond => root
            .draw(&Polygon::new(
                vec![
                    (x, y - r - 1),
                    (x + r + 1, y),
                    (x, y + r + 1),
                    (x - r - 1, y),
                ],
                colour.filled(),
            ))
            .map_err(e),
        Marker::OpenDiamond => {
            let style = ShapeStyle::from(&colour).stroke_width(2);
            root.draw(&PathElement::new(
                vec![(x, y - r), (x + r, y), (x, y + r), (x - r, y), (x, y - r)],
                style,
            ))
            .map_err(e)
        }
        Marker::Tick => {
            let style = ShapeStyle::from(&colour).stroke_width(3);
            root.draw(&PathElement::new(vec![(x, y - r), (x, y + r)], style))
                .map_err(e)
        }
    }
}

/// A polyline, solid or dashed.
fn draw_line<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    points: &[(i32, i32)],
    colour: RGBColor,
    width: u32,
    dashed: bool,
) -> DrawResult {
    let style = ShapeStyle::from(&colour).stroke_width(width);
    if !dashed {
        return root
            .draw(&PathElement::new(points.to_vec(), style))
            .map_err(e);
    }
    const DASH: f64 = 9.0;
    const GAP: f64 = 6.0;
    let mut phase = 0.0;
    for pair in points.windows(2) {
        let (a, b) = (pair[0], pair[1]);
        let (dx, dy) = ((b.0 - a.0) as f64, (b.1 - a.1) as f64);
        let length = (dx * dx + dy * dy).sqrt();
        let mut t = 0.0;
        while t < length {
            let in_dash = phase < DASH;
            let left = if in_dash {
                DASH - phase
            } else {
                DASH + GAP - phase
            };
            let step = left.min(length - t);
            if in_dash {
                let p = |s: f64| {
                    (
                        a.0 + (dx * s / length).round() as i32,
                        a.1 + (dy * s / length).round() as i32,
                    )
                };
                root.draw(&PathElement::new(vec![p(t), p(t + step)], style))
                    .map_err(e)?;
            }
            t += step;
            phase = (phase + step) % (DASH + GAP);
        }
    }
    Ok(())
}

/// What a legend entry shows.
#[derive(Clone, Debug, PartialEq)]
pub enum Swatch {
    /// A filled box (bars, stacked segments).
    Bar(RGBColor),
    /// A marker.
    Marker(Marker, RGBColor),
    /// A line, optionally dashed, optionally with a marker.
    Line {
        /// Its colour.
        colour: RGBColor,
        /// Dashed.
        dashed: bool,
        /// Marker on it.
        marker: Option<Marker>,
    },
    /// An interval whisker.
    Whisker,
}

/// One legend entry.
#[derive(Clone, Debug, PartialEq)]
pub struct LegendEntry {
    /// The sample.
    pub swatch: Swatch,
    /// What it means.
    pub label: String,
}

impl LegendEntry {
    /// An entry.
    pub fn new(swatch: Swatch, label: impl Into<String>) -> Self {
        Self {
            swatch,
            label: label.into(),
        }
    }
}

const LEGEND_SWATCH: i32 = 26;
const LEGEND_ROW: i32 = 22;
const LEGEND_GAP: i32 = 22;

/// Entries per legend line when wrapped into `width` pixels.
fn legend_lines(entries: &[LegendEntry], width: i32) -> Vec<Vec<usize>> {
    let mut lines: Vec<Vec<usize>> = Vec::new();
    let mut used = 0;
    for (i, entry) in entries.iter().enumerate() {
        let w = LEGEND_SWATCH + 6 + text_width(&entry.label, SMALL_SIZE);
        match lines.last_mut() {
            Some(line) if used + LEGEND_GAP + w <= width => {
                line.push(i);
                used += LEGEND_GAP + w;
            }
            _ => {
                lines.push(vec![i]);
                used = w;
            }
        }
    }
    lines
}

fn legend_height(entries: &[LegendEntry], width: i32) -> i32 {
    if entries.is_empty() {
        0
    } else {
        legend_lines(entries, width).len() as i32 * LEGEND_ROW + 8
    }
}

fn draw_legend<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    entries: &[LegendEntry],
    (x0, y0): (i32, i32),
    width: i32,
) -> DrawResult {
    for (row, line) in legend_lines(entries, width).iter().enumerate() {
        let y = y0 + row as i32 * LEGEND_ROW + LEGEND_ROW / 2;
        let mut x = x0;
        for &i in line {
            let entry = &entries[i];
            let mid = x + LEGEND_SWATCH / 2;
            match &entry.swatch {
                Swatch::Bar(colour) => {
                    root.draw(&Rectangle::new(
                        [(x + 3, y - 6), (x + LEGEND_SWATCH - 3, y + 6)],
                        colour.filled(),
                    ))
                    .map_err(e)?;
                }
                Swatch::Marker(marker, colour) => draw_marker(root, *marker, (mid, y), 5, *colour)?,
                Swatch::Line {
                    colour,
                    dashed,
                    marker,
                } => {
                    draw_line(root, &[(x, y), (x + LEGEND_SWATCH, y)], *colour, 2, *dashed)?;
                    if let Some(m) = marker {
                        draw_marker(root, *m, (mid, y), 4, *colour)?;
                    }
                }
                Swatch::Whisker => {
                    let style = ShapeStyle::from(&INK).stroke_width(2);
                    let (a, b) = (x + 3, x + LEGEND_SWATCH - 3);
                    root.draw(&PathElement::new(vec![(a, y), (b, y)], style))
                        .map_err(e)?;
                    for px in [a, b] {
                        root.draw(&PathElement::new(vec![(px, y - 5), (px, y + 5)], style))
                            .map_err(e)?;
                    }
                }
            }
            x += LEGEND_SWATCH + 6;
            label(
                root,
                &entry.label,
                (x, y),
                SMALL_SIZE,
                HPos::Left,
                VPos::Center,
            )?;
            x += text_width(&entry.label, SMALL_SIZE) + LEGEND_GAP;
        }
    }
    Ok(())
}

/// A figure that can be drawn on any plotters backend.
pub trait Figure {
    /// Pixel size.
    fn size(&self) -> (u32, u32);
    /// Draws on `root`, which has [`Figure::size`].
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult;
}

/// Title, wrapped subtitle lines and legend at the top of a figure; returns the y below them.
pub(crate) fn draw_header<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    title: &str,
    subtitle: &[String],
    legend: &[LegendEntry],
    width: i32,
) -> std::result::Result<i32, String> {
    root.fill(&WHITE).map_err(e)?;
    label(root, title, (MARGIN, 12), TITLE_SIZE, HPos::Left, VPos::Top)?;
    let mut y = 12 + TITLE_SIZE as i32 + 10;
    for line in subtitle {
        label(root, line, (MARGIN, y), SMALL_SIZE, HPos::Left, VPos::Top)?;
        y += SMALL_SIZE as i32 + 6;
    }
    y += 4;
    draw_legend(root, legend, (MARGIN, y), width - 2 * MARGIN)?;
    Ok(y + legend_height(legend, width - 2 * MARGIN))
}

pub(crate) fn header_height(subtitle: &[String], legend: &[LegendEntry], width: i32) -> i32 {
    12 + TITLE_SIZE as i32
        + 10
        + subtitle.len() as i32 * (SMALL_SIZE as i32 + 6)
        + 4
        + legend_height(legend, width - 2 * MARGIN)
}

/// The width a header needs: the title and subtitle lines.
pub(crate) fn header_width(title: &str, subtitle: &[String]) -> i32 {
    subtitle
        .iter()
        .map(|s| text_width(s, SMALL_SIZE))
        .chain([text_width(title, TITLE_SIZE)])
        .max()
        .unwrap_or(0)
        + 2 * MARGIN
}

/// One bar (or dot) of a row.
#[derive(Clone, Debug, PartialEq)]
pub struct Bar {
    /// Its value.
    pub value: f64,
    /// Its colour.
    pub colour: RGBColor,
    /// A whisker from lo to hi.
    pub interval: Option<(f64, f64)>,
    /// A reference value drawn as a marker in ink (the dissertation's value, a median).
    pub reference: Option<(f64, Marker)>,
    /// The value as printed after the bar.
    pub text: String,
}

/// One segment of a stacked bar.
#[derive(Clone, Debug, PartialEq)]
pub struct Segment {
    /// Its length on the axis.
    pub value: f64,
    /// Its colour.
    pub colour: RGBColor,
    /// Printed inside when it fits.
    pub text: String,
}

/// A line of a row chart.
#[derive(Clone, Debug, PartialEq)]
pub enum RowLine {
    /// A group heading (an object).
    Heading(String),
    /// A labelled row of one or more bars, one above the other.
    Bars {
        /// Row label.
        label: String,
        /// Its bars.
        bars: Vec<Bar>,
    },
    /// A labelled stacked bar.
    Stack {
        /// Row label.
        label: String,
        /// Its segments, left to right.
        segments: Vec<Segment>,
    },
}

/// Horizontal bars, dots with whiskers or stacked bars, one labelled row per configuration
/// under group headings, with a value axis at the bottom.
#[derive(Clone, Debug, PartialEq)]
pub struct RowChart {
    /// Title.
    pub title: String,
    /// Lines under the title (what is shown, units, source).
    pub subtitle: Vec<String>,
    /// Axis title with units.
    pub axis_label: String,
    /// The value axis.
    pub axis: Axis,
    /// Tick labels as percentages (for shares in 0..1).
    pub percent_axis: bool,
    /// Dots instead of bars.
    pub dots: bool,
    /// The rows.
    pub lines: Vec<RowLine>,
    /// Legend entries.
    pub legend: Vec<LegendEntry>,
}

const PLOT_WIDTH: i32 = 600;
const BAR_HEIGHT: i32 = 14;
const ROW_PAD: i32 = 10;
const HEADING_HEIGHT: i32 = 26;
const AXIS_HEIGHT: i32 = 58;

impl RowChart {
    fn line_height(line: &RowLine) -> i32 {
        match line {
            RowLine::Heading(_) => HEADING_HEIGHT,
            RowLine::Bars { bars, .. } => bars.len().max(1) as i32 * BAR_HEIGHT + ROW_PAD,
            RowLine::Stack { .. } => BAR_HEIGHT + 4 + ROW_PAD,
        }
    }

    fn label_width(&self) -> i32 {
        self.lines
            .iter()
            .map(|line| match line {
                RowLine::Heading(_) => 0,
                RowLine::Bars { label, .. } | RowLine::Stack { label, .. } => {
                    text_width(label, LABEL_SIZE)
                }
            })
            .max()
            .unwrap_or(0)
            + 14
    }

    fn value_width(&self) -> i32 {
        self.lines
            .iter()
            .flat_map(|line| match line {
                RowLine::Bars { bars, .. } => bars
                    .iter()
                    .map(|b| text_width(&b.text, TICK_SIZE))
                    .collect::<Vec<_>>(),
                _ => Vec::new(),
            })
            .max()
            .unwrap_or(0)
            + 16
    }

    fn body_width(&self) -> i32 {
        let headings = self
            .lines
            .iter()
            .map(|line| match line {
                RowLine::Heading(text) => text_width(text, LABEL_SIZE) + 4,
                _ => 0,
            })
            .max()
            .unwrap_or(0);
        (self.label_width() + PLOT_WIDTH + self.value_width()).max(headings) + 2 * MARGIN
    }

    fn width(&self) -> i32 {
        self.body_width()
            .max(header_width(&self.title, &self.subtitle))
    }

    fn tick_text(&self, tick: &Tick) -> Option<String> {
        if self.percent_axis {
            Some(format!("{}%", format::fixed(tick.value * 100.0, 0)))
        } else {
            tick.label.clone()
        }
    }
}

impl Figure for RowChart {
    fn size(&self) -> (u32, u32) {
        let width = self.width();
        let rows: i32 = self.lines.iter().map(Self::line_height).sum();
        let height = header_height(&self.subtitle, &self.legend, width) + 8 + rows + AXIS_HEIGHT;
        (width as u32, (height + MARGIN) as u32)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult {
        let width = self.width();
        let top = draw_header(root, &self.title, &self.subtitle, &self.legend, width)? + 8;
        let left = MARGIN + self.label_width();
        let right = left + PLOT_WIDTH;
        let rows: i32 = self.lines.iter().map(Self::line_height).sum();
        let bottom = top + rows;
        let px = |v: f64| self.axis.pixel(v, left, right);

        // Grid, ticks and the axis.
        for tick in self.axis.ticks() {
            let x = px(tick.value);
            let colour = if tick.major { GRID } else { GRID_MINOR };
            root.draw(&PathElement::new(vec![(x, top), (x, bottom)], colour))
                .map_err(e)?;
            if let Some(text) = self.tick_text(&tick) {
                root.draw(&PathElement::new(vec![(x, bottom), (x, bottom + 5)], INK))
                    .map_err(e)?;
                label(
                    root,
                    &text,
                    (x, bottom + 8),
                    TICK_SIZE,
                    HPos::Center,
                    VPos::Top,
                )?;
            }
        }
        root.draw(&PathElement::new(
            vec![(left, bottom), (right, bottom)],
            INK,
        ))
        .map_err(e)?;
        label(
            root,
            &self.axis_label,
            ((left + right) / 2, bottom + 30),
            SMALL_SIZE,
            HPos::Center,
            VPos::Top,
        )?;

        let mut y = top;
        for line in &self.lines {
            let height = Self::line_height(line);
            match line {
                RowLine::Heading(text) => {
                    let at = (MARGIN, y + height / 2 + 2);
                    clear_behind(root, text, LABEL_SIZE, at)?;
                    label(root, text, at, LABEL_SIZE, HPos::Left, VPos::Center)?;
                }
                RowLine::Bars { label: text, bars } => {
                    label(
                        root,
                        text,
                        (left - 8, y + height / 2),
                        LABEL_SIZE,
                        HPos::Right,
                        VPos::Center,
                    )?;
                    for (k, bar) in bars.iter().enumerate() {
                        let cy = y + ROW_PAD / 2 + k as i32 * BAR_HEIGHT + BAR_HEIGHT / 2;
                        self.draw_bar(root, bar, cy, (left, right))?;
                    }
                }
                RowLine::Stack {
                    label: text,
                    segments,
                } => {
                    let cy = y + height / 2;
                    label(
                        root,
                        text,
                        (left - 8, cy),
                        LABEL_SIZE,
                        HPos::Right,
                        VPos::Center,
                    )?;
                    let mut start = 0.0;
                    for segment in segments {
                        let end = start + segment.value;
                        let (a, b) = (px(start), px(end));
                        if b > a {
                            root.draw(&Rectangle::new(
                                [(a, cy - BAR_HEIGHT / 2 - 2), (b, cy + BAR_HEIGHT / 2 + 2)],
                                segment.colour.filled(),
                            ))
                            .map_err(e)?;
                            let w = text_width(&segment.text, TICK_SIZE);
                            if !segment.text.is_empty() && w + 6 <= b - a {
                                let RGBColor(r, g, bl) = segment.colour;
                                let luminance =
                                    0.299 * r as f64 + 0.587 * g as f64 + 0.114 * bl as f64;
                                let ink = if luminance < 140.0 { WHITE } else { INK };
                                root.draw(&Text::new(
                                    segment.text.clone(),
                                    ((a + b) / 2, cy),
                                    font(TICK_SIZE)
                                        .color(&ink)
                                        .pos(Pos::new(HPos::Center, VPos::Center)),
                                ))
                                .map_err(e)?;
                            }
                        }
                        start = end;
                    }
                }
            }
            y += height;
        }
        Ok(())
    }
}

impl RowChart {
    fn draw_bar<DB: DrawingBackend>(
        &self,
        root: &DrawingArea<DB, Shift>,
        bar: &Bar,
        cy: i32,
        (left, right): (i32, i32),
    ) -> DrawResult {
        let px = |v: f64| self.axis.pixel(v, left, right);
        if !bar.value.is_finite() {
            return Ok(());
        }
        let mut end = px(bar.value);
        if self.dots {
            // Whisker first, so the dot sits on top.
            if let Some((lo, hi)) = bar.interval {
                draw_whisker(root, (px(lo), px(hi)), cy, bar.colour)?;
                end = end.max(px(hi));
            }
            draw_marker(root, Marker::Circle, (px(bar.value), cy), 5, bar.colour)?;
        } else {
            let base = if self.axis.log { self.axis.lo } else { 0.0 };
            root.draw(&Rectangle::new(
                [
                    (px(base), cy - BAR_HEIGHT / 2 + 1),
                    (end, cy + BAR_HEIGHT / 2 - 1),
                ],
                bar.colour.filled(),
            ))
            .map_err(e)?;
            if let Some((lo, hi)) = bar.interval {
                draw_whisker(root, (px(lo), px(hi)), cy, INK)?;
                end = end.max(px(hi));
            }
        }
        // The value goes right after the bar, unless the reference marker would sit under it.
        let text_end = end + 6 + text_width(&bar.text, TICK_SIZE) + 6;
        if let Some((value, marker)) = bar.reference {
            if value.is_finite() {
                let x = px(value);
                draw_marker(root, marker, (x, cy), BAR_HEIGHT / 2 - 1, INK)?;
                if x + 4 >= end && x - 4 <= text_end {
                    end = x + 4;
                }
            }
        }
        let at = (end + 6, cy);
        clear_behind(root, &bar.text, TICK_SIZE, at)?;
        label(root, &bar.text, at, TICK_SIZE, HPos::Left, VPos::Center)
    }
}

fn draw_whisker<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    (a, b): (i32, i32),
    cy: i32,
    colour: RGBColor,
) -> DrawResult {
    let style = ShapeStyle::from(&colour).stroke_width(2);
    root.draw(&PathElement::new(vec![(a, cy), (b, cy)], style))
        .map_err(e)?;
    for x in [a, b] {
        root.draw(&PathElement::new(vec![(x, cy - 4), (x, cy + 4)], style))
            .map_err(e)?;
    }
    Ok(())
}

/// A series of an x-y panel.
#[derive(Clone, Debug, PartialEq)]
pub struct Series {
    /// Colour.
    pub colour: RGBColor,
    /// Marker at each point, if any.
    pub marker: Option<Marker>,
    /// Join the points with a line.
    pub line: bool,
    /// Dashed line.
    pub dashed: bool,
    /// The points, in drawing order.
    pub points: Vec<(f64, f64)>,
}

/// One x-y panel with its own axes.
#[derive(Clone, Debug, PartialEq)]
pub struct Panel {
    /// Panel title (an object).
    pub title: String,
    /// Horizontal axis.
    pub x: Axis,
    /// Vertical axis.
    pub y: Axis,
    /// The series, drawn in order.
    pub series: Vec<Series>,
    /// Labelled x positions instead of the axis' own ticks (e.g. the measured resolutions).
    pub x_ticks: Vec<f64>,
}

/// Panels of points and lines side by side (wrapping after `columns`), sharing axis titles and
/// one legend.
#[derive(Clone, Debug, PartialEq)]
pub struct XyChart {
    /// Title.
    pub title: String,
    /// Lines under the title.
    pub subtitle: Vec<String>,
    /// Horizontal axis title with units.
    pub x_label: String,
    /// Vertical axis title with units (printed above each panel's axis).
    pub y_label: String,
    /// The panels.
    pub panels: Vec<Panel>,
    /// Panels per row.
    pub columns: usize,
    /// Plot area of each panel, pixels.
    pub plot_size: (i32, i32),
    /// Legend entries.
    pub legend: Vec<LegendEntry>,
}

const PANEL_GAP: i32 = 28;
const PANEL_TITLE: i32 = 24;
const Y_TITLE: i32 = 22;

impl XyChart {
    fn columns(&self) -> i32 {
        self.columns.clamp(1, self.panels.len().max(1)) as i32
    }

    fn tick_width(&self) -> i32 {
        self.panels
            .iter()
            .flat_map(|p| p.y.ticks())
            .filter_map(|t| t.label)
            .map(|l| text_width(&l, TICK_SIZE))
            .max()
            .unwrap_or(0)
            + 14
    }

    fn panel_width(&self) -> i32 {
        let (w, _) = self.plot_size;
        let y_label = format!("{} (log scale)", self.y_label);
        (self.tick_width() + w).max(text_width(&y_label, SMALL_SIZE))
    }

    fn panel_height(&self) -> i32 {
        PANEL_TITLE + Y_TITLE + self.plot_size.1 + AXIS_HEIGHT
    }

    fn width(&self) -> i32 {
        let c = self.columns();
        (2 * MARGIN + c * self.panel_width() + (c - 1) * PANEL_GAP)
            .max(header_width(&self.title, &self.subtitle))
    }

    fn draw_panel<DB: DrawingBackend>(
        &self,
        root: &DrawingArea<DB, Shift>,
        panel: &Panel,
        (x0, y0): (i32, i32),
    ) -> DrawResult {
        let (w, h) = self.plot_size;
        let left = x0 + self.tick_width();
        let right = left + w;
        let top = y0 + PANEL_TITLE + Y_TITLE;
        let bottom = top + h;
        label(
            root,
            &panel.title,
            (left, y0),
            LABEL_SIZE,
            HPos::Left,
            VPos::Top,
        )?;
        let y_label = if panel.y.log {
            format!("{} (log scale)", self.y_label)
        } else {
            self.y_label.clone()
        };
        label(
            root,
            &y_label,
            (x0, y0 + PANEL_TITLE + 2),
            SMALL_SIZE,
            HPos::Left,
            VPos::Top,
        )?;
        let px = |x: f64| panel.x.pixel(x, left, right);
        let py = |y: f64| panel.y.pixel(y, bottom, top);
        let x_ticks = if panel.x_ticks.is_empty() {
            panel.x.ticks()
        } else {
            panel
                .x_ticks
                .iter()
                .map(|&value| Tick {
                    value,
                    label: Some(tick_label(value, 1.0)),
                    major: true,
                })
                .collect()
        };
        for tick in x_ticks {
            let x = px(tick.value);
            let colour = if tick.major { GRID } else { GRID_MINOR };
            root.draw(&PathElement::new(vec![(x, top), (x, bottom)], colour))
                .map_err(e)?;
            if let Some(text) = tick.label {
                root.draw(&PathElement::new(vec![(x, bottom), (x, bottom + 5)], INK))
                    .map_err(e)?;
                label(
                    root,
                    &text,
                    (x, bottom + 8),
                    TICK_SIZE,
                    HPos::Center,
                    VPos::Top,
                )?;
            }
        }
        for tick in panel.y.ticks() {
            let y = py(tick.value);
            let colour = if tick.major { GRID } else { GRID_MINOR };
            root.draw(&PathElement::new(vec![(left, y), (right, y)], colour))
                .map_err(e)?;
            if let Some(text) = tick.label {
                root.draw(&PathElement::new(vec![(left - 5, y), (left, y)], INK))
                    .map_err(e)?;
                label(
                    root,
                    &text,
                    (left - 8, y),
                    TICK_SIZE,
                    HPos::Right,
                    VPos::Center,
                )?;
            }
        }
        root.draw(&PathElement::new(
            vec![(left, top), (left, bottom), (right, bottom)],
            INK,
        ))
        .map_err(e)?;
        let log_note = |axis: &Axis, text: &str| {
            if axis.log {
                format!("{text} (log scale)")
            } else {
                text.to_string()
            }
        };
        label(
            root,
            &log_note(&panel.x, &self.x_label),
            ((left + right) / 2, bottom + 30),
            SMALL_SIZE,
            HPos::Center,
            VPos::Top,
        )?;
        for series in &panel.series {
            let points: Vec<(i32, i32)> = series
                .points
                .iter()
                .filter(|(x, y)| x.is_finite() && y.is_finite())
                .map(|&(x, y)| (px(x), py(y)))
                .collect();
            if series.line && points.len() > 1 {
                draw_line(root, &points, series.colour, 2, series.dashed)?;
            }
            if let Some(marker) = series.marker {
                for &p in &points {
                    draw_marker(root, marker, p, 5, series.colour)?;
                }
            }
        }
        Ok(())
    }
}

impl Figure for XyChart {
    fn size(&self) -> (u32, u32) {
        let width = self.width();
        let rows = (self.panels.len() as i32 + self.columns() - 1) / self.columns();
        let height = header_height(&self.subtitle, &self.legend, width)
            + 8
            + rows * self.panel_height()
            + (rows - 1).max(0) * 12;
        (width as u32, (height + MARGIN) as u32)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult {
        let width = self.width();
        let top = draw_header(root, &self.title, &self.subtitle, &self.legend, width)? + 8;
        let columns = self.columns();
        for (i, panel) in self.panels.iter().enumerate() {
            let (row, column) = (i as i32 / columns, i as i32 % columns);
            let x0 = MARGIN + column * (self.panel_width() + PANEL_GAP);
            let y0 = top + row * (self.panel_height() + 12);
            self.draw_panel(root, panel, (x0, y0))?;
        }
        Ok(())
    }
}

/// Renders `figure` to `dir/name.png` and `dir/name.svg` (each written atomically); returns both
/// paths.
pub fn write_figure<F: Figure>(figure: &F, dir: &Path, name: &str) -> Result<Vec<PathBuf>> {
    rmt_analysis::charts::register_bundled_font()?;
    let size = figure.size();
    let png = dir.join(format!("{name}.png"));
    let svg = dir.join(format!("{name}.svg"));
    let chart_error = |path: &Path, message: String| ReportError::Chart {
        path: path.to_path_buf(),
        message,
    };
    // The bitmap backend picks its encoder by extension: draw to a temporary `.png` and rename.
    let temporary = dir.join(format!(".{name}.tmp.png"));
    {
        let root = BitMapBackend::new(&temporary, size).into_drawing_area();
        figure.draw(&root).map_err(|m| chart_error(&png, m))?;
        root.present()
            .map_err(|m| chart_error(&png, m.to_string()))?;
    }
    std::fs::rename(&temporary, &png).map_err(io_error(&png))?;
    let mut text = String::new();
    {
        let root = SVGBackend::with_string(&mut text, size).into_drawing_area();
        figure.draw(&root).map_err(|m| chart_error(&svg, m))?;
        root.present()
            .map_err(|m| chart_error(&svg, m.to_string()))?;
    }
    write_atomic(&svg, text.as_bytes())?;
    Ok(vec![png, svg])
}

/// Colour-blind-friendly categorical colours (Okabe-Ito).
pub mod palette {
    use plotters::style::RGBColor;

    /// Blue.
    pub const BLUE: RGBColor = RGBColor(0, 114, 178);
    /// Orange.
    pub const ORANGE: RGBColor = RGBColor(230, 159, 0);
    /// Bluish green.
    pub const GREEN: RGBColor = RGBColor(0, 158, 115);
    /// Reddish purple.
    pub const PURPLE: RGBColor = RGBColor(204, 121, 167);
    /// Sky blue.
    pub const SKY: RGBColor = RGBColor(86, 180, 233);
    /// Vermillion.
    pub const VERMILLION: RGBColor = RGBColor(213, 94, 0);
    /// Yellow.
    pub const YELLOW: RGBColor = RGBColor(240, 228, 66);
    /// Grey, for "other".
    pub const GREY: RGBColor = RGBColor(170, 170, 170);
    /// Dark grey.
    pub const DARK_GREY: RGBColor = RGBColor(100, 100, 100);

    /// The colour of a method variant (clustering mode, or marching cubes) in every figure.
    pub fn variant(variant: &str) -> RGBColor {
        match variant {
            "none" => DARK_GREY,
            "integrated" => BLUE,
            "integrated-unchecked" => GREEN,
            "postprocessed" => ORANGE,
            "meshopt" => PURPLE,
            "marching cubes" => VERMILLION,
            _ => SKY,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn linear_axes_have_round_ends_and_ticks() {
        let axis = Axis::linear(&[0.3, 7.2], true);
        assert_eq!((axis.lo, axis.hi), (0.0, 8.0));
        let labels: Vec<String> = axis.ticks().into_iter().filter_map(|t| t.label).collect();
        assert_eq!(labels, ["0", "2", "4", "6", "8"]);
        let small = Axis::linear(&[0.0, 0.013], true);
        let labels: Vec<String> = small.ticks().into_iter().filter_map(|t| t.label).collect();
        assert_eq!(labels.last().map(String::as_str), Some("0.014"));
        assert_eq!(labels[1], "0.002");
    }

    #[test]
    fn log_axes_end_on_round_values() {
        let axis = Axis::log(&[27200.0, 101720.0, 3.0]);
        assert_eq!((axis.lo, axis.hi), (2.0, 200000.0));
        let labels: Vec<String> = axis.ticks().into_iter().filter_map(|t| t.label).collect();
        assert_eq!(labels, ["2", "10", "100", "1,000", "10,000", "100,000"]);
        let ends = Axis::log(&[0.3, 40.0]);
        assert_eq!((ends.lo, ends.hi), (0.2, 50.0));
        let labels: Vec<String> = ends.ticks().into_iter().filter_map(|t| t.label).collect();
        assert_eq!(labels, ["0.2", "0.5", "1", "2", "5", "10", "20", "50"]);
        let narrow = Axis::log(&[0.0021, 0.03]);
        assert_eq!((narrow.lo, narrow.hi), (0.002, 0.05));
        let labels: Vec<String> = narrow.ticks().into_iter().filter_map(|t| t.label).collect();
        assert_eq!(labels, ["0.002", "0.005", "0.01", "0.02", "0.05"]);
        let exact = Axis::log(&[10.0, 100.0]);
        assert_eq!((exact.lo, exact.hi), (10.0, 100.0));
    }

    #[test]
    fn auto_axes_go_logarithmic_only_for_wide_positive_ranges() {
        assert!(Axis::auto(&[1.0, 1000.0], 30.0).log);
        assert!(!Axis::auto(&[1.0, 10.0], 30.0).log);
        assert!(!Axis::auto(&[0.0, 1000.0], 30.0).log);
    }

    #[test]
    fn pixels_are_clamped_to_the_axis() {
        let axis = Axis::log(&[1.0, 100.0]);
        assert_eq!((axis.lo, axis.hi), (1.0, 100.0));
        assert_eq!(axis.pixel(10.0, 0, 200), 100);
        assert_eq!(axis.pixel(1e9, 0, 200), 200);
        assert_eq!(axis.pixel(0.0, 0, 200), 0);
    }

    #[test]
    fn legends_wrap_to_the_width() {
        rmt_analysis::charts::register_bundled_font().unwrap();
        let entries: Vec<LegendEntry> = (0..6)
            .map(|i| LegendEntry::new(Swatch::Bar(palette::BLUE), format!("entry number {i}")))
            .collect();
        let lines = legend_lines(&entries, 400);
        assert!(lines.len() > 1);
        assert_eq!(lines.iter().map(Vec::len).sum::<usize>(), 6);
        for line in &lines {
            let used: i32 = line
                .iter()
                .map(|&i| LEGEND_SWATCH + 6 + text_width(&entries[i].label, SMALL_SIZE))
                .sum::<i32>()
                + LEGEND_GAP * (line.len() as i32 - 1);
            assert!(used <= 400 || line.len() == 1);
        }
    }
}
