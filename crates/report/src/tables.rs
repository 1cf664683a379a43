//! The benchmark tables: the summary per configuration in the dissertation's columns, our numbers
//! beside the dissertation's, and the growth of time with resolution.

use crate::data::{lattice_name, Configuration, PaperRow, Run};
use crate::format::{self, count, fixed, percent, readable, sig};
use crate::output::{Block, TextTable};
use crate::scaling::ScalingFit;

/// The dissertation's columns (`data/paper/benchmark.csv`), in its order.
pub const PAPER_COLUMNS: [&str; 25] = [
    "id",
    "rx",
    "ry",
    "rz",
    "lattice",
    "clustering",
    "n_tetrahedra",
    "n_vertices",
    "n_triangles",
    "n_discarded",
    "t_total_s",
    "t_sampling_s",
    "t_vertex_s",
    "t_geometry_s",
    "f_sampling",
    "f_vertex",
    "f_geometry",
    "b_lattice",
    "b_edges",
    "b_vertices",
    "b_indices",
    "f_tetrahedra",
    "f_discard",
    "ar_mean",
    "ar_sd",
];

/// Our columns after the dissertation's.
pub const EXTRA_COLUMNS: [&str; 15] = [
    "object",
    "method",
    "repetitions",
    "t_total_sd_s",
    "t_normals_s",
    "f_normals",
    "triangle_reduction",
    "ar_median",
    "ar_p95",
    "fidelity_mean_h",
    "fidelity_max_h",
    "closed_manifold",
    "euler",
    "f_points_sampled",
    "f_blocks_skipped",
];

/// Share of the total time spent in `stage`, percent.
fn stage_percent(c: &Configuration, stage: &str) -> f64 {
    let total = c.mean_time("total");
    if total > 0.0 {
        100.0 * c.mean_time(stage) / total
    } else {
        f64::NAN
    }
}

fn opt(v: Option<f64>, f: impl Fn(f64) -> String) -> String {
    v.map(f).unwrap_or_default()
}

fn resolution(c: &Configuration) -> String {
    let [x, y, z] = c.resolution;
    if x == y && y == z {
        format!("{x}³")
    } else {
        format!("{x}×{y}×{z}")
    }
}

/// The benchmark summary: one row per configuration, the dissertation's columns then ours.
pub fn benchmark_summary(run: &Run) -> TextTable {
    let cs = &run.configurations;
    let mut csv_header: Vec<String> = PAPER_COLUMNS.iter().map(|s| s.to_string()).collect();
    csv_header.extend(EXTRA_COLUMNS.iter().map(|s| s.to_string()));
    let mut csv_rows = Vec::with_capacity(cs.len());
    for c in cs {
        let t = |stage: &str| sig(c.mean_time(stage), 6);
        let p = |stage: &str| fixed(stage_percent(c, stage), 2);
        let [rx, ry, rz] = c.resolution;
        let mut row = vec![
            c.id.clone(),
            rx.to_string(),
            ry.to_string(),
            rz.to_string(),
            c.lattice.clone(),
            c.clustering.clone(),
            fixed(c.tetrahedra_processed, 0),
            fixed(c.vertices, 0),
            fixed(c.triangles, 0),
            fixed(c.discarded, 0),
            t("total"),
            t("sampling"),
            t("vertex"),
            t("geometry"),
            p("sampling"),
            p("vertex"),
            p("geometry"),
            fixed(c.bytes[0], 0),
            fixed(c.bytes[1], 0),
            fixed(c.bytes[2], 0),
            fixed(c.bytes[3], 0),
            opt(c.tetrahedra_share, |s| fixed(100.0 * s, 2)),
            opt(c.discard_share, |s| fixed(100.0 * s, 2)),
            sig(c.ar_mean, 6),
            sig(c.ar_sd, 6),
        ];
        row.extend([
            c.object.clone(),
            c.method.clone(),
            c.repetitions.to_string(),
            opt(c.time("total").and_then(|t| t.sd), |v| sig(v, 6)),
            t("normals"),
            p("normals"),
            opt(c.triangle_reduction, |v| sig(v, 6)),
            sig(c.ar_median, 6),
            sig(c.ar_p95, 6),
            opt(c.fidelity_mean_h, |v| sig(v, 6)),
            opt(c.fidelity_max_h, |v| sig(v, 6)),
            c.closed_manifold.to_string(),
            fixed(c.euler, 0),
            opt(c.points_sampled_share, |s| fixed(100.0 * s, 2)),
            opt(c.blocks_skipped_share, |s| fixed(100.0 * s, 2)),
        ]);
        csv_rows.push(row);
    }

    let max_total = cs.iter().map(|c| c.mean_time("total")).fold(0.0, f64::max);
    let (scale, unit) = format::time_unit(max_total);
    let counts = Block {
        caption: Some("Counts and quality".into()),
        header: [
            "configuration",
            "cells",
            "lattice",
            "clustering",
            "tetrahedra with a crossing",
            "vertices",
            "triangles",
            "discarded",
            "triangle reduction",
            "mean aspect ratio",
            "aspect ratio sd",
            "mean distance to surface (h)",
            "closed, manifold",
        ]
        .map(String::from)
        .to_vec(),
        rows: cs
            .iter()
            .map(|c| {
                vec![
                    c.id.clone(),
                    resolution(c),
                    if c.is_marching_cubes() {
                        "(cubes)".into()
                    } else {
                        lattice_name(&c.lattice)
                    },
                    if c.is_marching_cubes() {
                        "marching cubes".into()
                    } else {
                        c.clustering.clone()
                    },
                    count(c.tetrahedra_processed),
                    count(c.vertices),
                    count(c.triangles),
                    count(c.discarded),
                    opt(c.triangle_reduction, percent),
                    sig(c.ar_mean, 3),
                    sig(c.ar_sd, 3),
                    opt(c.fidelity_mean_h, |v| sig(v, 3)),
                    if c.closed_manifold { "yes" } else { "no" }.into(),
                ]
            })
            .collect(),
    };
    let time = |c: &Configuration, stage: &str| readable(c.mean_time(stage) * scale);
    let times = Block {
        caption: Some(format!(
            "Time per extraction ({unit}, mean of the repetitions)"
        )),
        header: [
            "configuration",
            "repetitions",
            "total",
            "sd",
            "sampling",
            "vertex pass",
            "geometry pass",
            "normals",
            "sampling share",
            "vertex share",
            "geometry share",
        ]
        .map(String::from)
        .to_vec(),
        rows: cs
            .iter()
            .map(|c| {
                vec![
                    c.id.clone(),
                    c.repetitions.to_string(),
                    time(c, "total"),
                    opt(c.time("total").and_then(|t| t.sd), |v| readable(v * scale)),
                    time(c, "sampling"),
                    time(c, "vertex"),
                    time(c, "geometry"),
                    time(c, "normals"),
                    percent(stage_percent(c, "sampling") / 100.0),
                    percent(stage_percent(c, "vertex") / 100.0),
                    percent(stage_percent(c, "geometry") / 100.0),
                ]
            })
            .collect(),
    };
    let memory = Block {
        caption: Some("Memory and work".into()),
        header: [
            "configuration",
            "lattice samples",
            "edge data",
            "vertex buffer",
            "index buffer",
            "tetrahedra processed",
            "triangles discarded",
            "points sampled",
            "blocks skipped",
        ]
        .map(String::from)
        .to_vec(),
        rows: cs
            .iter()
            .map(|c| {
                vec![
                    c.id.clone(),
                    format::bytes(c.bytes[0]),
                    format::bytes(c.bytes[1]),
                    format::bytes(c.bytes[2]),
                    format::bytes(c.bytes[3]),
                    opt(c.tetrahedra_share, percent),
                    opt(c.discard_share, percent),
                    opt(c.points_sampled_share, percent),
                    opt(c.blocks_skipped_share, percent),
                ]
            })
            .collect(),
    };
    TextTable {
        name: "benchmark_summary".into(),
        title: "Benchmark summary per configuration".into(),
        notes: vec![
            format!(
                "Run `{}` ({} configurations). Counts and quality come from the mesh of the last \
                 repetition (every repetition gives the same mesh); times are means over the \
                 timed repetitions. Aspect ratio is the radius ratio R / (2r), 1 for an \
                 equilateral triangle; the distance to the surface is the mean distance of the \
                 vertices to the true surface in grid spacings h (objects whose distance is \
                 known). Triangle reduction is relative to the same object, lattice and \
                 resolution without clustering.",
                run.info.run_id,
                cs.len()
            ),
            "The CSV has the dissertation's columns (`data/paper/benchmark.csv`: times in \
             seconds, `f_*` in percent, bytes) followed by ours."
                .into(),
            "Points sampled: the share of the lattice points at which the field was evaluated; \
             blocks skipped: the share of the sampling blocks (4 cells per axis, tested 8 at a \
             time first) whose value range excluded the isovalue, so that only the sign of their points was stored \
             (blank for runs made before sparse sampling)."
                .into(),
        ],
        csv_header,
        csv_rows,
        blocks: vec![counts, times, memory],
    }
}

/// How a compared metric is shown.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum MetricKind {
    Count,
    Share,
    Plain,
    Time,
    Bytes,
}

/// Display name, kind and block of a `paper_comparison.csv` metric.
fn metric_info(metric: &str) -> (&str, MetricKind, usize) {
    match metric {
        "vertices" => ("vertices", MetricKind::Count, 0),
        "triangles" => ("triangles", MetricKind::Count, 0),
        "discarded" => ("discarded triangles", MetricKind::Count, 0),
        "tetrahedra_processed" => ("tetrahedra with a crossing", MetricKind::Count, 0),
        "triangle_reduction" => ("triangle reduction", MetricKind::Share, 1),
        "discard_share" => ("discarded share", MetricKind::Share, 1),
        "ar_mean" => ("mean aspect ratio", MetricKind::Plain, 1),
        "ar_sd" => ("aspect ratio sd", MetricKind::Plain, 1),
        "t_total_s_mean" => ("total time", MetricKind::Time, 2),
        "t_sampling_s_mean" => ("sampling", MetricKind::Time, 2),
        "t_vertex_s_mean" => ("vertex pass", MetricKind::Time, 2),
        "t_geometry_s_mean" => ("geometry pass", MetricKind::Time, 2),
        "bytes_lattice" => ("lattice samples", MetricKind::Bytes, 3),
        "bytes_edges" => ("edge data", MetricKind::Bytes, 3),
        "bytes_vertices" => ("vertex buffer", MetricKind::Bytes, 3),
        "bytes_indices" => ("index buffer", MetricKind::Bytes, 3),
        other => (other, MetricKind::Plain, 4),
    }
}

const METRIC_BLOCKS: [&str; 5] = [
    "Counts",
    "Reduction and triangle quality",
    "Times (ms)",
    "Memory",
    "Other",
];

fn show(kind: MetricKind, v: Option<f64>) -> String {
    let Some(v) = v else {
        return "–".into();
    };
    match kind {
        MetricKind::Count => count(v),
        MetricKind::Share => percent(v),
        MetricKind::Plain => sig(v, 3),
        MetricKind::Time => readable(v * 1e3),
        MetricKind::Bytes => format::bytes(v),
    }
}

/// Metrics in order of first appearance.
fn metrics(rows: &[PaperRow]) -> Vec<String> {
    let mut out: Vec<String> = Vec::new();
    for r in rows {
        if !out.contains(&r.metric) {
            out.push(r.metric.clone());
        }
    }
    out
}

/// Our numbers beside the dissertation's: one cell `ours / theirs (ratio×)` per metric, in
/// blocks of related metrics.
pub fn paper_comparison(run: &Run, rows: &[PaperRow]) -> TextTable {
    let csv_rows = rows
        .iter()
        .map(|r| {
            let cell = |v: Option<f64>| opt(v, |v| sig(v, 6));
            vec![
                r.id.clone(),
                r.metric.clone(),
                cell(r.ours),
                cell(r.theirs),
                cell(r.ratio),
            ]
        })
        .collect();
    let mut ids: Vec<String> = Vec::new();
    for r in rows {
        if !ids.contains(&r.id) {
            ids.push(r.id.clone());
        }
    }
    let all = metrics(rows);
    let mut blocks = Vec::new();
    for (b, caption) in METRIC_BLOCKS.iter().enumerate() {
        let members: Vec<&String> = all.iter().filter(|m| metric_info(m).2 == b).collect();
        if members.is_empty() {
            continue;
        }
        let mut header = vec!["configuration".to_string()];
        header.extend(members.iter().map(|m| metric_info(m).0.to_string()));
        let table_rows = ids
            .iter()
            .map(|id| {
                let mut row = vec![id.clone()];
                for m in &members {
                    let kind = metric_info(m).1;
                    let cell = rows
                        .iter()
                        .find(|r| &r.id == id && &r.metric == *m)
                        .map(|r| {
                            let ratio = r
                                .ratio
                                .map(|x| format!(" ({})", ratio_text(x)))
                                .unwrap_or_default();
                            format!("{} / {}{ratio}", show(kind, r.ours), show(kind, r.theirs))
                        })
                        .unwrap_or_default();
                    row.push(cell);
                }
                row
            })
            .collect();
        blocks.push(Block {
            caption: Some(caption.to_string()),
            header,
            rows: table_rows,
        });
    }
    TextTable {
        name: "paper_comparison".into(),
        title: "Our numbers beside the dissertation's".into(),
        notes: vec![format!(
            "Each cell: ours / the dissertation's (ours ÷ theirs). Ours from run `{}` on {}; \
             theirs from `data/paper/benchmark.csv` (another machine, another implementation: \
             times compare orders of magnitude, not hardware).",
            run.info.run_id,
            run.info.machine()
        )],
        csv_header: ["id", "metric", "ours", "dissertation", "ratio"]
            .map(String::from)
            .to_vec(),
        csv_rows,
        blocks,
    }
}

/// A ratio as `1.02×`, `246×` from 100 up, or with two significant digits below 0.1
/// (`0.0031×`).
pub fn ratio_text(v: f64) -> String {
    if v.abs() >= 99.5 {
        format!("{}×", fixed(v, 0))
    } else if v.abs() >= 0.095 || v == 0.0 {
        format!("{}×", fixed(v, 2))
    } else {
        format!("{}×", sig(v, 2))
    }
}

/// Median of finite values; `None` for none.
pub fn median(values: &[f64]) -> Option<f64> {
    if values.is_empty() {
        return None;
    }
    let mut v = values.to_vec();
    v.sort_by(f64::total_cmp);
    let n = v.len();
    Some(if n % 2 == 1 {
        v[n / 2]
    } else {
        (v[n / 2 - 1] + v[n / 2]) / 2.0
    })
}

/// Ratio ours / theirs per metric over all configurations: count, median, min, max.
pub fn paper_ratios(rows: &[PaperRow]) -> TextTable {
    let mut csv_rows = Vec::new();
    let mut md_rows = Vec::new();
    for m in metrics(rows) {
        let ratios: Vec<f64> = rows
            .iter()
            .filter(|r| r.metric == m)
            .filter_map(|r| r.ratio)
            .filter(|r| r.is_finite())
            .collect();
        let min = ratios.iter().copied().fold(f64::INFINITY, f64::min);
        let max = ratios.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let med = median(&ratios);
        csv_rows.push(vec![
            m.clone(),
            ratios.len().to_string(),
            opt(med, |v| sig(v, 6)),
            opt((!ratios.is_empty()).then_some(min), |v| sig(v, 6)),
            opt((!ratios.is_empty()).then_some(max), |v| sig(v, 6)),
        ]);
        let show = ratio_text;
        md_rows.push(vec![
            metric_info(&m).0.to_string(),
            ratios.len().to_string(),
            opt(med, show),
            opt((!ratios.is_empty()).then_some(min), show),
            opt((!ratios.is_empty()).then_some(max), show),
        ]);
    }
    TextTable {
        name: "paper_ratios".into(),
        title: "Ours ÷ the dissertation's, over the configurations".into(),
        notes: vec![
            "Configurations with a ratio (the dissertation's value present and not zero); \
             1.00× means the same number."
                .into(),
        ],
        csv_header: [
            "metric",
            "configurations",
            "median_ratio",
            "min_ratio",
            "max_ratio",
        ]
        .map(String::from)
        .to_vec(),
        csv_rows,
        blocks: vec![Block {
            caption: None,
            header: ["metric", "configurations", "median", "min", "max"]
                .map(String::from)
                .to_vec(),
            rows: md_rows,
        }],
    }
}

/// Time against resolution per method, with the fitted growth exponent.
pub fn scaling_table(run: &Run, fits: &[ScalingFit]) -> TextTable {
    let mut resolutions: Vec<u64> = fits
        .iter()
        .flat_map(|f| f.points.iter().map(|p| p.0.round() as u64))
        .collect();
    resolutions.sort_unstable();
    resolutions.dedup();
    let times: Vec<f64> = fits
        .iter()
        .flat_map(|f| f.points.iter().map(|p| p.1))
        .collect();
    let (scale, unit) = format::time_unit_median(&times);
    let mut header = vec!["method".to_string()];
    header.extend(resolutions.iter().map(|n| format!("{n}³")));
    header.extend(["exponent b", "R²"].map(String::from));
    let rows = fits
        .iter()
        .map(|f| {
            let mut row = vec![f.label.clone()];
            for n in &resolutions {
                row.push(
                    f.points
                        .iter()
                        .find(|p| p.0.round() as u64 == *n)
                        .map(|p| readable(p.1 * scale))
                        .unwrap_or_default(),
                );
            }
            row.push(opt(f.exponent, |b| fixed(b, 2)));
            row.push(opt(f.r_squared, |r| fixed(r, 3)));
            row
        })
        .collect();
    let csv_rows = fits
        .iter()
        .map(|f| {
            let first = f.points.first().copied();
            let last = f.points.last().copied();
            vec![
                f.label.clone(),
                f.object.clone(),
                f.method.clone(),
                f.lattice.clone(),
                f.clustering.clone(),
                f.points.len().to_string(),
                opt(first.map(|p| p.0), |v| sig(v, 6)),
                opt(last.map(|p| p.0), |v| sig(v, 6)),
                opt(first.map(|p| p.1), |v| sig(v, 6)),
                opt(last.map(|p| p.1), |v| sig(v, 6)),
                opt(f.exponent, |v| sig(v, 6)),
                opt(f.r_squared, |v| sig(v, 6)),
            ]
        })
        .collect();
    TextTable {
        name: "scaling".into(),
        title: "Time against resolution".into(),
        notes: vec![format!(
            "Mean total time per extraction ({unit}) at N³ cells, run `{}` on {}. The exponent b \
             is the least-squares slope of log t against log N over all resolutions (t ∝ N^b; \
             b = 3 is linear in the number of cells).",
            run.info.run_id,
            run.info.machine()
        )],
        csv_header: [
            "series",
            "object",
            "method",
            "lattice",
            "clustering",
            "points",
            "n_min",
            "n_max",
            "t_total_s_at_n_min",
            "t_total_s_at_n_max",
            "exponent",
            "r_squared",
        ]
        .map(String::from)
        .to_vec(),
        csv_rows,
        blocks: vec![Block {
            caption: None,
            header,
            rows,
        }],
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ratios_keep_two_significant_digits_when_small() {
        assert_eq!(ratio_text(1.0), "1.00×");
        assert_eq!(ratio_text(0.0031), "0.0031×");
        assert_eq!(ratio_text(245.87), "246×");
        assert_eq!(ratio_text(0.0), "0.00×");
    }

    #[test]
    fn medians_of_odd_and_even_counts() {
        assert_eq!(median(&[3.0, 1.0, 2.0]), Some(2.0));
        assert_eq!(median(&[4.0, 1.0, 3.0, 2.0]), Some(2.5));
        assert_eq!(median(&[]), None);
    }
}
