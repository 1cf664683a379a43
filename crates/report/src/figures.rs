//! The benchmark figures, built from a run's configurations: triangle counts, pass times, the
//! share of time per stage, aspect ratio, triangle count against fidelity, and time against
//! resolution. Colour always means the method variant (clustering mode, or marching cubes) and
//! marker shape the lattice.

use std::path::{Path, PathBuf};

use crate::data::{Configuration, PaperRow, Run};
use crate::error::Result;
use crate::format::{self, count, readable, sig};
use crate::plot::{
    palette, write_figure, Axis, Bar, LegendEntry, Marker, Panel, RowChart, RowLine, Segment,
    Series, Swatch, XyChart,
};
use crate::scaling::ScalingFit;

/// A figure of either kind, ready to write.
#[derive(Clone, Debug, PartialEq)]
pub enum AnyFigure {
    /// Rows of bars, dots or stacks.
    Rows(RowChart),
    /// X-y panels.
    Xy(XyChart),
    /// The level map of a `lod` run from above.
    TopView(crate::lod::TopView),
}

impl AnyFigure {
    /// Writes `dir/name.png` and `dir/name.svg`.
    pub fn write(&self, dir: &Path, name: &str) -> Result<Vec<PathBuf>> {
        match self {
            AnyFigure::Rows(chart) => write_figure(chart, dir, name),
            AnyFigure::Xy(chart) => write_figure(chart, dir, name),
            AnyFigure::TopView(view) => write_figure(view, dir, name),
        }
    }
}

/// Method variants in legend order.
const VARIANTS: [&str; 6] = [
    "none",
    "integrated",
    "integrated-unchecked",
    "postprocessed",
    "meshopt",
    "marching cubes",
];

/// The legend text of a method variant.
pub fn variant_label(variant: &str) -> String {
    match variant {
        "none" => "MT, no clustering".into(),
        "integrated" => "MT, integrated clustering (RMT)".into(),
        "integrated-unchecked" => "MT, integrated, unchecked".into(),
        "postprocessed" => "MT, post-processed (edge collapse)".into(),
        "meshopt" => "MT, meshopt simplifier".into(),
        other => other.to_string(),
    }
}

/// Legend entries for the variants that occur in `configurations`, in a fixed order.
fn variant_legend<'a>(
    configurations: impl Iterator<Item = &'a Configuration> + Clone,
    marker: Option<Marker>,
) -> Vec<LegendEntry> {
    let present: Vec<String> = configurations.map(Configuration::variant).collect();
    let mut order: Vec<String> = VARIANTS
        .iter()
        .map(|v| v.to_string())
        .filter(|v| present.contains(v))
        .collect();
    for v in &present {
        if !order.contains(v) {
            order.push(v.clone());
        }
    }
    order
        .iter()
        .map(|v| {
            let colour = palette::variant(v);
            let swatch = match marker {
                Some(m) => Swatch::Marker(m, colour),
                None => Swatch::Bar(colour),
            };
            LegendEntry::new(swatch, variant_label(v))
        })
        .collect()
}

/// Marker of a configuration's lattice (marching cubes: diamond).
pub fn lattice_marker(c: &Configuration) -> Marker {
    if c.is_marching_cubes() {
        Marker::Diamond
    } else if c.lattice == "simple" {
        Marker::Square
    } else {
        Marker::Circle
    }
}

/// `BCDL, integrated (ss_bi)`.
fn row_label(c: &Configuration) -> String {
    format!("{} ({})", c.description(), c.id)
}

/// `sphere, 50³ cells` (the resolution when all of the object's configurations share it).
fn heading(object: &str, members: &[&Configuration]) -> String {
    let first = members[0].resolution;
    if members.iter().all(|c| c.resolution == first) {
        let [x, y, z] = first;
        if x == y && y == z {
            format!("{object}, {x}³ cells")
        } else {
            format!("{object}, {x} × {y} × {z} cells")
        }
    } else {
        object.to_string()
    }
}

/// Rows of a row chart: a heading per object, then one line per configuration.
fn rows(run: &Run, line: impl Fn(&Configuration) -> RowLine) -> Vec<RowLine> {
    let mut lines = Vec::new();
    for (object, members) in run.by_object() {
        lines.push(RowLine::Heading(heading(&object, &members)));
        lines.extend(members.iter().map(|c| line(c)));
    }
    lines
}

fn repetitions_text(run: &Run) -> String {
    let reps: Vec<u64> = run.configurations.iter().map(|c| c.repetitions).collect();
    let min = reps.iter().copied().min().unwrap_or(0);
    let max = reps.iter().copied().max().unwrap_or(0);
    if min == max {
        format!("{min} repetitions")
    } else {
        format!("{min}–{max} repetitions")
    }
}

fn source_line(run: &Run) -> String {
    format!(
        "Run {} ({} manifest), {}; {}.",
        run.info.run_id,
        run.info.name,
        repetitions_text(run),
        run.info.cpu_model.as_deref().unwrap_or("unknown CPU")
    )
}

/// The dissertation's value of `metric` for configuration `id`.
fn theirs(paper: Option<&Vec<PaperRow>>, id: &str, metric: &str) -> Option<f64> {
    paper?
        .iter()
        .find(|r| r.id == id && r.metric == metric)
        .and_then(|r| r.theirs)
}

/// Output triangles per configuration, with the dissertation's count as a tick.
pub fn triangles(run: &Run) -> RowChart {
    let paper = run.paper.as_ref();
    let mut values: Vec<f64> = run.configurations.iter().map(|c| c.triangles).collect();
    values.extend(
        run.configurations
            .iter()
            .filter_map(|c| theirs(paper, &c.id, "triangles")),
    );
    let has_reference = run
        .configurations
        .iter()
        .any(|c| theirs(paper, &c.id, "triangles").is_some());
    let axis = Axis::auto(&values, 30.0);
    let mut legend = variant_legend(run.configurations.iter(), None);
    if has_reference {
        legend.push(LegendEntry::new(
            Swatch::Marker(Marker::Tick, crate::plot::INK),
            "the dissertation's count",
        ));
    }
    RowChart {
        title: "Triangle count per configuration".into(),
        subtitle: vec![source_line(run)],
        axis_label: format!(
            "output triangles{}",
            if axis.log { " (log scale)" } else { "" }
        ),
        axis,
        percent_axis: false,
        dots: false,
        lines: rows(run, |c| RowLine::Bars {
            label: row_label(c),
            bars: vec![Bar {
                value: c.triangles,
                colour: palette::variant(&c.variant()),
                interval: None,
                reference: theirs(paper, &c.id, "triangles").map(|t| (t, Marker::Tick)),
                text: count(c.triangles),
            }],
        }),
        legend,
    }
}

/// Mean vertex and geometry pass time per configuration, with ±1 sd whiskers.
pub fn pass_times(run: &Run) -> RowChart {
    let stat = |c: &Configuration, stage: &str| c.time(stage).copied();
    let mut values = Vec::new();
    for c in &run.configurations {
        for stage in ["vertex", "geometry"] {
            if let Some(t) = stat(c, stage) {
                values.push(t.mean);
                if let Some(sd) = t.sd {
                    values.push(t.mean + sd);
                }
            }
        }
    }
    let max = values.iter().copied().fold(0.0, f64::max);
    let (scale, unit) = format::time_unit(max);
    let scaled: Vec<f64> = values.iter().map(|v| v * scale).collect();
    let axis = Axis::auto(&scaled, 50.0);
    let bar = |c: &Configuration, stage: &str, colour| {
        let t = stat(c, stage);
        Bar {
            value: t.map_or(f64::NAN, |t| t.mean * scale),
            colour,
            interval: t.and_then(|t| {
                t.sd.map(|sd| {
                    let lo = (t.mean - sd).max(0.0) * scale;
                    // A log axis cannot show 0: such whiskers start at the axis.
                    (lo, (t.mean + sd) * scale)
                })
            }),
            reference: None,
            text: t.map_or(String::new(), |t| readable(t.mean * scale)),
        }
    };
    RowChart {
        title: "Vertex and geometry pass time per configuration".into(),
        subtitle: vec![source_line(run)],
        axis_label: format!(
            "mean time per extraction ({unit}{})",
            if axis.log { ", log scale" } else { "" }
        ),
        axis,
        percent_axis: false,
        dots: false,
        lines: rows(run, |c| RowLine::Bars {
            label: row_label(c),
            bars: vec![
                bar(c, "vertex", palette::BLUE),
                bar(c, "geometry", palette::ORANGE),
            ],
        }),
        legend: vec![
            LegendEntry::new(Swatch::Bar(palette::BLUE), "vertex pass"),
            LegendEntry::new(
                Swatch::Bar(palette::ORANGE),
                "geometry pass (post-processing included)",
            ),
            LegendEntry::new(Swatch::Whisker, "mean ± 1 standard deviation"),
        ],
    }
}

/// Colour of a stage in the stacked shares.
fn stage_colour(stage: &str) -> plotters::style::RGBColor {
    match stage {
        "sampling" => palette::SKY,
        "vertex" => palette::BLUE,
        "geometry" => palette::ORANGE,
        "normals" => palette::GREEN,
        "allocation" => palette::PURPLE,
        _ => palette::YELLOW,
    }
}

/// Stages of the run (every time column but the total), in column order.
pub fn stages(run: &Run) -> Vec<String> {
    let mut stages: Vec<String> = Vec::new();
    for c in &run.configurations {
        for (s, _) in &c.times {
            if s != "total" && !stages.contains(s) {
                stages.push(s.clone());
            }
        }
    }
    stages
}

/// The shares of the total time of each stage of `c`, plus the unaccounted rest; scaled down
/// when the stages add up to more than the total.
pub fn stage_shares_of(c: &Configuration, stages: &[String]) -> Vec<(String, f64)> {
    let total = c.mean_time("total");
    let mut shares: Vec<(String, f64)> = stages
        .iter()
        .map(|s| {
            let share = if total > 0.0 {
                (c.mean_time(s) / total).max(0.0)
            } else {
                0.0
            };
            (s.clone(), share)
        })
        .collect();
    let sum: f64 = shares.iter().map(|s| s.1).sum();
    if sum > 1.0 {
        shares.iter_mut().for_each(|s| s.1 /= sum);
    }
    shares.push(("other".into(), (1.0 - sum).max(0.0)));
    shares
}

/// Share of the total time per stage, one stacked bar per configuration.
pub fn stage_shares(run: &Run) -> RowChart {
    let stages = stages(run);
    let mut legend: Vec<LegendEntry> = stages
        .iter()
        .map(|s| {
            let text = match s.as_str() {
                "vertex" | "geometry" => format!("{s} pass"),
                other => other.to_string(),
            };
            LegendEntry::new(Swatch::Bar(stage_colour(s)), text)
        })
        .collect();
    legend.push(LegendEntry::new(
        Swatch::Bar(palette::GREY),
        "not in a stage",
    ));
    RowChart {
        title: "Share of the extraction time per stage".into(),
        subtitle: vec![
            source_line(run),
            "Mean stage time over mean total time; shares of 6% and more are printed.".into(),
        ],
        axis_label: "share of the total time".into(),
        axis: Axis {
            lo: 0.0,
            hi: 1.0,
            log: false,
        },
        percent_axis: true,
        dots: false,
        lines: rows(run, |c| RowLine::Stack {
            label: row_label(c),
            segments: stage_shares_of(c, &stages)
                .into_iter()
                .map(|(s, share)| Segment {
                    value: share,
                    colour: if s == "other" {
                        palette::GREY
                    } else {
                        stage_colour(&s)
                    },
                    text: if share >= 0.06 {
                        format!("{}%", format::fixed(share * 100.0, 0))
                    } else {
                        String::new()
                    },
                })
                .collect(),
        }),
        legend,
    }
}

/// Mean aspect ratio per configuration, whiskers ±1 sd over the triangles, median as a diamond.
pub fn aspect_ratio(run: &Run) -> RowChart {
    let spread = |c: &Configuration| ((c.ar_mean - c.ar_sd).max(1.0), c.ar_mean + c.ar_sd);
    let mut values = Vec::new();
    for c in &run.configurations {
        let (lo, hi) = spread(c);
        values.extend([c.ar_mean, c.ar_median, lo, hi]);
    }
    let mut axis = Axis::auto(&values, 30.0);
    if !axis.log {
        // The radius ratio is at least 1: start the axis there.
        axis = Axis::linear(&values, false);
        axis.lo = 1.0;
    }
    let mut legend = variant_legend(run.configurations.iter(), Some(Marker::Circle));
    legend.push(LegendEntry::new(
        Swatch::Whisker,
        "mean ± 1 sd over the triangles (from 1)",
    ));
    legend.push(LegendEntry::new(
        Swatch::Marker(Marker::OpenDiamond, crate::plot::INK),
        "median",
    ));
    RowChart {
        title: "Triangle aspect ratio per configuration".into(),
        subtitle: vec![
            source_line(run),
            "Radius ratio R / (2r) of each triangle: 1 is equilateral, slivers grow without bound."
                .into(),
        ],
        axis_label: format!("radius ratio{}", if axis.log { " (log scale)" } else { "" }),
        axis,
        percent_axis: false,
        dots: true,
        lines: rows(run, |c| RowLine::Bars {
            label: row_label(c),
            bars: vec![Bar {
                value: c.ar_mean,
                colour: palette::variant(&c.variant()),
                interval: Some(spread(c)),
                reference: Some((c.ar_median, Marker::OpenDiamond)),
                text: sig(c.ar_mean, 3),
            }],
        }),
        legend,
    }
}

/// Lattice legend entries (grey markers) for the lattices present.
fn lattice_legend(configurations: &[&Configuration]) -> Vec<LegendEntry> {
    let mut entries = Vec::new();
    for (marker, text) in [
        (Marker::Circle, "BCDL lattice"),
        (Marker::Square, "simple cubic lattice"),
        (Marker::Diamond, "cubes (marching cubes)"),
    ] {
        if configurations.iter().any(|c| lattice_marker(c) == marker) {
            entries.push(LegendEntry::new(
                Swatch::Marker(marker, palette::DARK_GREY),
                text,
            ));
        }
    }
    entries
}

/// Triangle count against mean distance to the true surface, one panel per object that knows its
/// distance; `None` when no configuration has a fidelity value.
pub fn fidelity(run: &Run) -> Option<XyChart> {
    let mut panels = Vec::new();
    let mut shown: Vec<&Configuration> = Vec::new();
    for (object, members) in run.by_object() {
        let measured: Vec<&Configuration> = members
            .into_iter()
            .filter(|c| c.fidelity_mean_h.is_some_and(f64::is_finite))
            .collect();
        if measured.is_empty() {
            continue;
        }
        let xs: Vec<f64> = measured.iter().map(|c| c.triangles).collect();
        let ys: Vec<f64> = measured.iter().filter_map(|c| c.fidelity_mean_h).collect();
        panels.push(Panel {
            title: heading(&object, &measured),
            x: Axis::auto(&xs, 30.0),
            y: Axis::auto(&ys, 30.0),
            x_ticks: Vec::new(),
            series: measured
                .iter()
                .map(|c| Series {
                    colour: palette::variant(&c.variant()),
                    marker: Some(lattice_marker(c)),
                    line: false,
                    dashed: false,
                    points: vec![(c.triangles, c.fidelity_mean_h.unwrap_or(f64::NAN))],
                })
                .collect(),
        });
        shown.extend(measured);
    }
    if panels.is_empty() {
        return None;
    }
    let mut legend = variant_legend(shown.iter().copied(), Some(Marker::Circle));
    legend.extend(lattice_legend(&shown));
    Some(XyChart {
        title: "Triangle count against fidelity".into(),
        subtitle: vec![
            source_line(run),
            "One point per configuration: fewer triangles to the left, closer to the true \
             surface further down."
                .into(),
        ],
        x_label: "output triangles".into(),
        y_label: "mean vertex distance to the surface in grid spacings h".into(),
        columns: 3,
        plot_size: (330, 260),
        panels,
        legend,
    })
}

/// Mean total time against resolution per method (log-log), with the fitted power law dashed;
/// `None` when no series spans two resolutions.
pub fn scaling(run: &Run, fits: &[ScalingFit]) -> Option<XyChart> {
    let fitted: Vec<&ScalingFit> = fits.iter().filter(|f| f.exponent.is_some()).collect();
    if fitted.is_empty() {
        return None;
    }
    let times: Vec<f64> = fitted
        .iter()
        .flat_map(|f| f.points.iter().map(|p| p.1))
        .collect();
    let (scale, unit) = format::time_unit_median(&times);
    let mut objects: Vec<String> = Vec::new();
    for f in &fitted {
        if !objects.contains(&f.object) {
            objects.push(f.object.clone());
        }
    }
    let marker = |f: &ScalingFit| {
        if f.method == "mc" {
            Marker::Diamond
        } else if f.lattice == "simple" {
            Marker::Square
        } else {
            Marker::Circle
        }
    };
    let mut panels = Vec::new();
    for object in &objects {
        let members: Vec<&&ScalingFit> = fitted.iter().filter(|f| &f.object == object).collect();
        let mut xs = Vec::new();
        let mut ys = Vec::new();
        let mut series = Vec::new();
        for f in &members {
            xs.extend(f.points.iter().map(|p| p.0));
            ys.extend(f.points.iter().map(|p| p.1 * scale));
            let colour = palette::variant(&f.variant);
            let n0 = f.points.first().map_or(1.0, |p| p.0);
            let n1 = f.points.last().map_or(1.0, |p| p.0);
            // The fit as a dashed curve, sampled along the measured range.
            let curve: Vec<(f64, f64)> = (0..=16)
                .map(|k| {
                    let n = n0 * (n1 / n0).powf(k as f64 / 16.0);
                    (n, f.predict(n).unwrap_or(f64::NAN) * scale)
                })
                .collect();
            ys.extend(curve.iter().map(|p| p.1));
            series.push(Series {
                colour,
                marker: None,
                line: true,
                dashed: true,
                points: curve,
            });
            series.push(Series {
                colour,
                marker: Some(marker(f)),
                line: false,
                dashed: false,
                points: f.points.iter().map(|p| (p.0, p.1 * scale)).collect(),
            });
        }
        let mut resolutions: Vec<f64> = xs.iter().map(|x| x.round()).collect();
        resolutions.sort_by(f64::total_cmp);
        resolutions.dedup();
        panels.push(Panel {
            title: object.clone(),
            x_ticks: resolutions,
            x: Axis::log(&xs),
            y: Axis::log(&ys),
            series,
        });
    }
    let legend = fitted
        .iter()
        .map(|f| {
            LegendEntry::new(
                Swatch::Line {
                    colour: palette::variant(&f.variant),
                    dashed: true,
                    marker: Some(marker(f)),
                },
                format!(
                    "{}: t ∝ N^{}",
                    f.label,
                    format::fixed(f.exponent.unwrap_or(f64::NAN), 2)
                ),
            )
        })
        .collect();
    Some(XyChart {
        title: "Extraction time against resolution".into(),
        subtitle: vec![
            source_line(run),
            "Markers: measured mean; dashed: least-squares power law t = a N^b (b = 3 is linear \
             in the number of cells)."
                .into(),
        ],
        x_label: "resolution N, cells per axis".into(),
        y_label: format!("mean total time per extraction in {unit}"),
        columns: 2,
        plot_size: (560, 380),
        panels,
        legend,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::data::read_summary;

    fn fixture() -> Run {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/ci");
        Run::read(&dir).unwrap()
    }

    #[test]
    fn stage_shares_add_up_to_the_whole() {
        let run = fixture();
        let stages = stages(&run);
        assert!(stages.iter().any(|s| s == "sampling") && !stages.iter().any(|s| s == "total"));
        for c in &run.configurations {
            let shares = stage_shares_of(c, &stages);
            let sum: f64 = shares.iter().map(|s| s.1).sum();
            assert!((sum - 1.0).abs() < 1e-9, "{}: {sum}", c.id);
            assert!(shares.iter().all(|s| s.1 >= 0.0));
        }
        // Stages that add up to more than the total are scaled down, not drawn past 100%.
        let mut c = run.configurations[0].clone();
        for (_, t) in c.times.iter_mut().filter(|(s, _)| s != "total") {
            t.mean *= 10.0;
        }
        let sum: f64 = stage_shares_of(&c, &stages).iter().map(|s| s.1).sum();
        assert!((sum - 1.0).abs() < 1e-9, "{sum}");
    }

    #[test]
    fn every_configuration_gets_one_row_under_its_object() {
        let run = fixture();
        let chart = triangles(&run);
        let rows = chart
            .lines
            .iter()
            .filter(|l| matches!(l, RowLine::Bars { .. }))
            .count();
        let headings = chart.lines.len() - rows;
        assert_eq!(rows, run.configurations.len());
        assert_eq!(headings, run.objects().len());
        // The dissertation's count is the reference tick where the comparison has it.
        let summary = read_summary(&run.folder.join("summary.csv")).unwrap();
        assert_eq!(summary.len(), rows);
        let with_reference = chart
            .lines
            .iter()
            .filter(|l| matches!(l, RowLine::Bars { bars, .. } if bars[0].reference.is_some()))
            .count();
        let compared = run
            .paper
            .as_ref()
            .unwrap()
            .iter()
            .filter(|r| r.metric == "triangles" && r.theirs.is_some())
            .count();
        assert!(compared > 0);
        assert_eq!(with_reference, compared);
    }

    #[test]
    fn fidelity_panels_only_for_objects_that_know_their_distance() {
        let run = fixture();
        let chart = fidelity(&run).unwrap();
        let titles: Vec<&str> = chart.panels.iter().map(|p| p.title.as_str()).collect();
        for p in &chart.panels {
            assert!(!p.series.is_empty());
        }
        assert!(titles.iter().any(|t| t.starts_with("sphere")));
        assert!(!titles.iter().any(|t| t.starts_with("asteroid")));
    }
}
