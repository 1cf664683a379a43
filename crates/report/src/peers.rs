//! Against what game developers use: RMT beside marching cubes and surface nets (as they come and
//! simplified by meshoptimizer to RMT's triangle count), plain MT and edge collapse, per object:
//! time, triangles, triangle quality, fidelity, rendering cost and defects.
//!
//! The inputs are a run of `experiments/manifests/peers.toml` (kept in a report as
//! `data/peers/`) and, optionally, of `peers-seeds.toml` (`data/peers-seeds/`, its `seeds.csv`:
//! the same methods over 200 asteroids, for 95% intervals).
//!
//! ```text
//!   peers run summary.csv ──► PeerRow per configuration ──► table `peers` (a block per object)
//!                                                      ├──► figure peers_occupancy (occupancy
//!                                                      │    against screen size, a line per method)
//!                                                      ├──► figure peers_time_triangles (time
//!                                                      │    against triangles, quality as marker)
//!                                                      └──► the README's paragraph (in words)
//!   peers-seeds seeds.csv  ──► table `peers_seeds` (mean [95% CI] per method)
//! ```
//!
//! Rules: rows with the vertex-cache order are not rows of their own; they give the "ACMR after
//! reordering" of their method (the ACMR that meshoptimizer's reordering reaches on any mesh is
//! also measured without them, as `acmr_16_optimized`). Time is `t_pipeline_s`: extraction plus
//! the finish steps, so a simplified peer pays for its simplification.

use std::path::Path;

use crate::csv_file::CsvFile;
use crate::data::RunInfo;
use crate::error::Result;
use crate::format::{count, fixed, sig};
use crate::output::{Block, TextTable};
use crate::plot::{palette, Axis, LegendEntry, Marker, Panel, Series, Swatch, XyChart};

/// The screen sizes of the occupancy columns, near to far (pixels across the bounding sphere).
pub const SIZES: [u32; 4] = [1080, 540, 270, 135];

/// The method families, in the order tables and legends list them.
pub const FAMILIES: [&str; 9] = [
    "RMT",
    "RMT unchecked",
    "plain MT",
    "edge collapse",
    "plain MT + meshopt",
    "marching cubes",
    "marching cubes + meshopt",
    "surface nets",
    "surface nets + meshopt",
];

/// One configuration of the peers run (without the vertex-cache order).
#[derive(Clone, Debug, PartialEq)]
pub struct PeerRow {
    /// Configuration id.
    pub id: String,
    /// Object name.
    pub object: String,
    /// One of [`FAMILIES`].
    pub family: &'static str,
    /// `mt`, `mc` or `surface-nets`.
    pub method: String,
    /// The clustering mode.
    pub clustering: String,
    /// The readable method: family, lattice and border rule.
    pub label: String,
    /// `bcdl` or `simple`.
    pub lattice: String,
    /// The simplification's name (`none`, `meshopt:rmt`, `meshopt-locked:rmt`).
    pub simplify: String,
    /// Extraction plus finish steps, mean seconds.
    pub time_s: f64,
    /// Output triangles.
    pub triangles: f64,
    /// Radius ratio: mean and 95th percentile.
    pub ar: (f64, f64),
    /// Mean vertex distance to the true surface in grid spacings.
    pub fidelity_h: Option<f64>,
    /// Quad occupancy at [`SIZES`].
    pub occupancy: [Option<f64>; 4],
    /// Share of front-facing triangles below one pixel at 1080 and 135 px.
    pub below_pixel: (Option<f64>, Option<f64>),
    /// ACMR at cache size 16 as extracted, and after meshoptimizer's reordering.
    pub acmr: (Option<f64>, Option<f64>),
    /// Interior boundary edges (holes) and non-manifold edges.
    pub defects: (f64, f64),
    /// meshoptimizer's reported error, grid spacings (simplified rows).
    pub simplify_error_h: Option<f64>,
}

impl PeerRow {
    /// Whether this is RMT proper: checked integrated clustering on the body-centred lattice.
    pub fn is_rmt_bcdl(&self) -> bool {
        self.family == "RMT" && self.lattice == "bcdl"
    }
}

/// The family of a configuration, by its method, clustering and simplification.
pub fn family(method: &str, clustering: &str, simplify: &str) -> Option<&'static str> {
    let simplified = simplify != "none" && !simplify.is_empty();
    Some(match (method, clustering, simplified) {
        ("mt", "integrated", false) => "RMT",
        ("mt", "integrated-unchecked", false) => "RMT unchecked",
        ("mt", "none", false) => "plain MT",
        ("mt", "postprocessed", false) => "edge collapse",
        ("mt", "none", true) => "plain MT + meshopt",
        ("mc", _, false) => "marching cubes",
        ("mc", _, true) => "marching cubes + meshopt",
        ("surface-nets", _, false) => "surface nets",
        ("surface-nets", _, true) => "surface nets + meshopt",
        _ => return None,
    })
}

fn lattice_word(method: &str, lattice: &str) -> &'static str {
    match (method, lattice) {
        ("mt", "bcdl") => "body-centred",
        ("mt", _) => "simple cubic",
        _ => "",
    }
}

/// The readable label of a row.
fn label(family: &str, method: &str, lattice: &str, simplify: &str) -> String {
    let mut text = family.to_string();
    let lattice = lattice_word(method, lattice);
    if !lattice.is_empty() {
        text += &format!(", {lattice}");
    }
    if simplify.starts_with("meshopt-locked") {
        text += ", borders locked";
    }
    text
}

/// What a configuration and its vertex-cache twin share: everything but the reordering.
fn twin_key(object: &str, method: &str, lattice: &str, clustering: &str, simplify: &str) -> String {
    format!("{object}|{method}|{lattice}|{clustering}|{simplify}")
}

/// Reads the peers run's `summary.csv` into rows (vertex-cache rows folded into their method's
/// ACMR), in file order.
pub fn read_peers(folder: &Path) -> Result<Vec<PeerRow>> {
    let file = CsvFile::read(&folder.join(crate::data::SUMMARY_CSV))?;
    let text = |r: usize, name: &str| -> String {
        file.text(r, name).map(str::to_string).unwrap_or_default()
    };
    let mut rows: Vec<PeerRow> = Vec::new();
    let mut reordered: Vec<(String, f64)> = Vec::new();
    for r in 0..file.rows.len() {
        let method = text(r, "method");
        let clustering = text(r, "clustering");
        let simplify = text(r, "simplify");
        let lattice = text(r, "lattice");
        let Some(fam) = family(&method, &clustering, &simplify) else {
            continue;
        };
        let key = twin_key(
            &text(r, "object"),
            &method,
            &lattice,
            &clustering,
            &simplify,
        );
        let opt = |name: &str| -> Result<Option<f64>> {
            if file.has(name) {
                file.optional(r, name)
            } else {
                Ok(None)
            }
        };
        if text(r, "vertex_cache") == "true" {
            if let Some(acmr) = opt("acmr_16")? {
                reordered.push((key, acmr));
            }
            continue;
        }
        let time_s = match opt("t_pipeline_s_mean")? {
            Some(t) => t,
            None => file.required(r, "t_total_s_mean")?,
        };
        let mut occupancy = [None; 4];
        for (o, size) in occupancy.iter_mut().zip(SIZES) {
            *o = opt(&format!("quad_occupancy_{size}"))?;
        }
        rows.push(PeerRow {
            id: text(r, "id"),
            object: text(r, "object"),
            family: fam,
            label: label(fam, &method, &lattice, &simplify),
            method: method.clone(),
            clustering: clustering.clone(),
            lattice: lattice.clone(),
            simplify: simplify.clone(),
            time_s,
            triangles: file.required(r, "triangles")?,
            ar: (file.required(r, "ar_mean")?, file.required(r, "ar_p95")?),
            fidelity_h: opt("fidelity_mean_h")?,
            occupancy,
            below_pixel: (opt("tris_below_pixel_1080")?, opt("tris_below_pixel_135")?),
            acmr: (opt("acmr_16")?, opt("acmr_16_optimized")?),
            defects: (
                file.required(r, "boundary_edges_interior")?,
                file.required(r, "non_manifold_edges")?,
            ),
            simplify_error_h: opt("simplify_error_h")?,
        });
    }
    // A vertex-cache twin's ACMR replaces the estimate from `acmr_16_optimized`.
    for row in &mut rows {
        let key = twin_key(
            &row.object,
            &row.method,
            &row.lattice,
            &row.clustering,
            &row.simplify,
        );
        if let Some((_, acmr)) = reordered.iter().find(|(k, _)| *k == key) {
            row.acmr.1 = Some(*acmr);
        }
    }
    Ok(rows)
}

/// The objects of `rows`, in first-appearance order.
fn objects(rows: &[PeerRow]) -> Vec<String> {
    let mut out: Vec<String> = Vec::new();
    for r in rows {
        if !out.contains(&r.object) {
            out.push(r.object.clone());
        }
    }
    out
}

fn opt_fixed(v: Option<f64>, decimals: usize) -> String {
    v.filter(|v| v.is_finite())
        .map(|v| fixed(v, decimals))
        .unwrap_or_default()
}

fn opt_sig(v: Option<f64>) -> String {
    v.filter(|v| v.is_finite())
        .map(|v| sig(v, 6))
        .unwrap_or_default()
}

/// The table `peers`: a block per object, a row per method.
pub fn peers_table(info: &RunInfo, rows: &[PeerRow]) -> TextTable {
    let csv_header: Vec<String> = [
        "object",
        "id",
        "method",
        "time_s",
        "triangles",
        "ar_mean",
        "ar_p95",
        "fidelity_mean_h",
        "quad_occupancy_1080",
        "quad_occupancy_540",
        "quad_occupancy_270",
        "quad_occupancy_135",
        "tris_below_pixel_1080",
        "tris_below_pixel_135",
        "acmr_16",
        "acmr_16_reordered",
        "holes",
        "non_manifold_edges",
        "simplify_error_h",
    ]
    .map(String::from)
    .to_vec();
    let mut csv_rows = Vec::new();
    let mut blocks = Vec::new();
    for object in objects(rows) {
        let mut block_rows = Vec::new();
        for r in rows.iter().filter(|r| r.object == object) {
            csv_rows.push(vec![
                r.object.clone(),
                r.id.clone(),
                r.label.clone(),
                sig(r.time_s, 6),
                sig(r.triangles, 12),
                sig(r.ar.0, 6),
                sig(r.ar.1, 6),
                opt_sig(r.fidelity_h),
                opt_sig(r.occupancy[0]),
                opt_sig(r.occupancy[1]),
                opt_sig(r.occupancy[2]),
                opt_sig(r.occupancy[3]),
                opt_sig(r.below_pixel.0),
                opt_sig(r.below_pixel.1),
                opt_sig(r.acmr.0),
                opt_sig(r.acmr.1),
                sig(r.defects.0, 12),
                sig(r.defects.1, 12),
                opt_sig(r.simplify_error_h),
            ]);
            let defects = if r.defects == (0.0, 0.0) {
                "none".to_string()
            } else {
                format!(
                    "{} holes, {} non-manifold",
                    count(r.defects.0),
                    count(r.defects.1)
                )
            };
            block_rows.push(vec![
                r.label.clone(),
                format!("{} ms", fixed(r.time_s * 1e3, 2)),
                count(r.triangles),
                format!("{} / {}", number(r.ar.0, 2), number(r.ar.1, 2)),
                opt_fixed(r.fidelity_h, 3),
                r.occupancy
                    .iter()
                    .map(|o| opt_fixed(*o, 2))
                    .collect::<Vec<_>>()
                    .join(" / "),
                format!("{} → {}", opt_fixed(r.acmr.0, 2), opt_fixed(r.acmr.1, 2)),
                defects,
            ]);
        }
        blocks.push(Block {
            caption: Some(object.clone()),
            header: [
                "method",
                "time",
                "triangles",
                "radius ratio mean / p95",
                "fidelity (h)",
                "quad occupancy 1080 / 540 / 270 / 135 px",
                "ACMR → reordered",
                "defects",
            ]
            .map(String::from)
            .to_vec(),
            rows: block_rows,
        });
    }
    TextTable {
        name: "peers".into(),
        title: "Against what game developers use".into(),
        notes: vec![format!(
            "From run `{}` on {}. Time is extraction plus the finish steps (meshoptimizer's \
             simplifier for the `+ meshopt` rows, to RMT's triangle count on the same object: \
             RMT on the body-centred lattice), mean over the timed repetitions on one thread. \
             Radius ratio: 1 is equilateral. Fidelity: mean vertex distance to the true surface \
             in grid spacings h. Quad occupancy: covered pixels over 4 x the 2x2 quads the \
             triangles launch after a depth pre-pass, over 8 turntable views, with the object's \
             bounding sphere 1080 to 135 pixels across (1 is the best a GPU can do). ACMR: \
             vertices transformed per triangle with a 16-entry cache, as extracted and after \
             meshoptimizer's vertex-cache order. Holes are boundary edges off the sampled box: \
             surface nets' open borders lie half a cell inside the box, and meshoptimizer with \
             free borders moves a mesh's open border off the box, so both count here (the \
             border-locked rows keep it on the box).",
            info.run_id,
            info.machine()
        )],
        csv_header,
        csv_rows,
        blocks,
    }
}

/// A stable colour per family.
fn colour(family: &str) -> plotters::style::RGBColor {
    match family {
        "RMT" => palette::BLUE,
        "RMT unchecked" => palette::GREEN,
        "plain MT" => palette::DARK_GREY,
        "edge collapse" => palette::ORANGE,
        "plain MT + meshopt" => palette::PURPLE,
        "marching cubes" => palette::VERMILLION,
        "marching cubes + meshopt" => palette::YELLOW,
        "surface nets" => palette::SKY,
        _ => palette::GREY,
    }
}

/// The rows a figure shows: one per family and object (body-centred for MT families, free
/// borders for simplified peers), so that lines stay readable.
fn figure_rows(rows: &[PeerRow]) -> Vec<&PeerRow> {
    rows.iter()
        .filter(|r| {
            let mt = matches!(
                r.family,
                "RMT" | "RMT unchecked" | "plain MT" | "edge collapse" | "plain MT + meshopt"
            );
            (!mt || r.lattice == "bcdl") && !r.simplify.starts_with("meshopt-locked")
        })
        .collect()
}

fn family_legend(shown: &[&PeerRow], marker: Option<Marker>) -> Vec<LegendEntry> {
    FAMILIES
        .iter()
        .filter(|f| shown.iter().any(|r| r.family == **f))
        .map(|f| {
            let swatch = match marker {
                Some(m) => Swatch::Marker(m, colour(f)),
                None => Swatch::Line {
                    colour: colour(f),
                    dashed: false,
                    marker: Some(Marker::Circle),
                },
            };
            LegendEntry::new(swatch, *f)
        })
        .collect()
}

/// Quad occupancy against screen size, a panel per object and a line per method.
pub fn occupancy_figure(info: &RunInfo, rows: &[PeerRow]) -> Option<XyChart> {
    let shown = figure_rows(rows);
    let mut panels = Vec::new();
    for object in objects(rows) {
        let series: Vec<Series> = shown
            .iter()
            .filter(|r| r.object == object && r.occupancy.iter().all(Option::is_some))
            .map(|r| Series {
                colour: colour(r.family),
                marker: Some(Marker::Circle),
                line: true,
                dashed: r.family.contains("meshopt"),
                points: SIZES
                    .iter()
                    .zip(r.occupancy)
                    .map(|(&s, o)| (f64::from(s), o.unwrap_or(f64::NAN)))
                    .collect(),
            })
            .collect();
        if series.is_empty() {
            continue;
        }
        let ys: Vec<f64> = series
            .iter()
            .flat_map(|s| s.points.iter().map(|p| p.1))
            .collect();
        panels.push(Panel {
            title: object,
            x: Axis::log(&SIZES.map(f64::from)),
            y: Axis::linear(&ys, false),
            x_ticks: SIZES.map(f64::from).to_vec(),
            series,
        });
    }
    if panels.is_empty() {
        return None;
    }
    Some(XyChart {
        title: "Quad occupancy against screen size".into(),
        subtitle: vec![
            format!("Run {} ({}); {}.", info.run_id, info.name, info.machine()),
            "Covered pixels over 4 x quads launched, 8 views; the bounding sphere 1080 (near) \
             to 135 (far) pixels across. Higher is less wasted shading; dashed: simplified by \
             meshoptimizer to RMT's count."
                .into(),
        ],
        x_label: "bounding sphere on screen (pixels)".into(),
        y_label: "quad occupancy".into(),
        columns: 3,
        plot_size: (330, 260),
        panels,
        legend: family_legend(&shown, None),
    })
}

/// The marker of a radius-ratio mean: circle up to 1.3, square up to 2, triangle above.
pub fn quality_marker(ar_mean: f64) -> Marker {
    if ar_mean <= 1.3 {
        Marker::Circle
    } else if ar_mean <= 2.0 {
        Marker::Square
    } else {
        Marker::Triangle
    }
}

/// Time against triangles, a panel per object and a point per method, quality as the marker.
pub fn time_figure(info: &RunInfo, rows: &[PeerRow]) -> Option<XyChart> {
    let shown = figure_rows(rows);
    let mut panels = Vec::new();
    for object in objects(rows) {
        let members: Vec<&&PeerRow> = shown.iter().filter(|r| r.object == object).collect();
        if members.is_empty() {
            continue;
        }
        let xs: Vec<f64> = members.iter().map(|r| r.triangles).collect();
        let ys: Vec<f64> = members.iter().map(|r| r.time_s * 1e3).collect();
        panels.push(Panel {
            title: object,
            x: Axis::auto(&xs, 30.0),
            y: Axis::auto(&ys, 30.0),
            x_ticks: Vec::new(),
            series: members
                .iter()
                .map(|r| Series {
                    colour: colour(r.family),
                    marker: Some(quality_marker(r.ar.0)),
                    line: false,
                    dashed: false,
                    points: vec![(r.triangles, r.time_s * 1e3)],
                })
                .collect(),
        });
    }
    if panels.is_empty() {
        return None;
    }
    let mut legend = family_legend(&shown, Some(Marker::Circle));
    legend.extend([
        LegendEntry::new(
            Swatch::Marker(Marker::Circle, palette::DARK_GREY),
            "radius ratio mean <= 1.3",
        ),
        LegendEntry::new(Swatch::Marker(Marker::Square, palette::DARK_GREY), "1.3-2"),
        LegendEntry::new(Swatch::Marker(Marker::Triangle, palette::DARK_GREY), "> 2"),
    ]);
    Some(XyChart {
        title: "Time against triangles, quality as the marker".into(),
        subtitle: vec![
            format!("Run {} ({}); {}.", info.run_id, info.name, info.machine()),
            "Extraction plus finish steps on one thread; down and to the left is cheaper and \
             smaller, a circle is well-shaped."
                .into(),
        ],
        x_label: "output triangles".into(),
        y_label: "time (ms)".into(),
        columns: 3,
        plot_size: (330, 260),
        panels,
        legend,
    })
}

/// The metrics of `peers_seeds`: column stem in `seeds.csv`, heading, decimals.
const SEED_COLUMNS: [(&str, &str, usize); 7] = [
    ("t_pipeline_s_mean", "time (ms)", 2),
    ("triangles", "triangles", 0),
    ("ar_mean", "radius ratio mean", 3),
    ("ar_p95", "radius ratio p95", 3),
    ("quad_occupancy_1080", "occupancy 1080 px", 3),
    ("quad_occupancy_135", "occupancy 135 px", 3),
    ("non_manifold_edges", "non-manifold edges", 1),
];

/// The table `peers_seeds`: every method of the seed study, mean and 95% interval over its
/// seeds; None when `seeds.csv` lacks the columns.
pub fn seeds_table(run_id: &str, seeds: &CsvFile) -> Result<Option<TextTable>> {
    if !seeds.has("quad_occupancy_1080_mean") {
        return Ok(None);
    }
    let mut csv_header: Vec<String> = ["id", "method", "seeds"].map(String::from).to_vec();
    for (stem, _, _) in SEED_COLUMNS {
        for stat in ["mean", "ci_low", "ci_high"] {
            csv_header.push(format!("{stem}_{stat}"));
        }
    }
    let mut csv_rows = Vec::new();
    let mut rows = Vec::new();
    for r in 0..seeds.rows.len() {
        let text = |name: &str| seeds.text(r, name).map(str::to_string);
        let (method, clustering, simplify, lattice) = (
            text("method")?,
            text("clustering")?,
            if seeds.has("simplify") {
                text("simplify")?
            } else {
                "none".into()
            },
            text("lattice")?,
        );
        let Some(fam) = family(&method, &clustering, &simplify) else {
            continue;
        };
        let name = label(fam, &method, &lattice, &simplify);
        let n = seeds.required(r, "seeds")?;
        let mut csv = vec![text("id")?, name.clone(), sig(n, 12)];
        let mut cells = vec![name, count(n)];
        for (stem, _, decimals) in SEED_COLUMNS {
            let scale = if stem.starts_with("t_") { 1e3 } else { 1.0 };
            let get = |stat: &str| seeds.optional(r, &format!("{stem}_{stat}"));
            let (mean, lo, hi) = (get("mean")?, get("ci_low")?, get("ci_high")?);
            csv.extend([mean, lo, hi].map(opt_sig));
            cells.push(match (mean, lo, hi) {
                (Some(m), Some(l), Some(h)) => format!(
                    "{} [{}, {}]",
                    fixed(m * scale, decimals),
                    fixed(l * scale, decimals),
                    fixed(h * scale, decimals)
                ),
                (Some(m), _, _) => fixed(m * scale, decimals),
                _ => String::new(),
            });
        }
        csv_rows.push(csv);
        rows.push(cells);
    }
    let mut header = vec!["method".to_string(), "seeds".to_string()];
    header.extend(SEED_COLUMNS.iter().map(|(_, h, _)| h.to_string()));
    Ok(Some(TextTable {
        name: "peers_seeds".into(),
        title: "Against what game developers use, across asteroids".into(),
        notes: vec![format!(
            "From run `{run_id}`: every method over {} asteroids (noise seeds), mean and 95% \
             confidence interval of the mean (Student's t) over the seeds.",
            seeds
                .rows
                .first()
                .and_then(|_| seeds.optional(0, "seeds").ok().flatten())
                .map(count)
                .unwrap_or_default()
        )],
        csv_header,
        csv_rows,
        blocks: vec![Block {
            caption: None,
            header,
            rows,
        }],
    }))
}

/// `v` with `decimals`, or in powers of ten from 10,000 up (`6.1e13`: degenerate triangles give
/// radius ratios that no fixed format reads well).
fn number(v: f64, decimals: usize) -> String {
    if v.abs() >= 1e4 {
        let e = v.abs().log10().floor();
        format!("{}e{}", fixed(v / 10f64.powf(e), 1), e as i64)
    } else {
        fixed(v, decimals)
    }
}

/// `a-b` (or `a` when both print the same) of finite `values` with `decimals`; None when empty.
fn range_text(values: &[f64], decimals: usize) -> Option<String> {
    let finite: Vec<f64> = values.iter().copied().filter(|v| v.is_finite()).collect();
    if finite.is_empty() {
        return None;
    }
    let lo = finite.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = finite.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let (a, b) = (number(lo, decimals), number(hi, decimals));
    Some(if a == b { a } else { format!("{a}-{b}") })
}

/// The row of `family` on `object` the README compares: body-centred for MT families, free
/// borders for simplified peers.
fn pick<'a>(rows: &'a [PeerRow], object: &str, family: &str) -> Option<&'a PeerRow> {
    figure_rows(rows)
        .into_iter()
        .find(|r| r.object == object && r.family == family)
}

/// The peers compared with RMT at an equal budget.
const BUDGET_PEERS: [&str; 3] = [
    "marching cubes + meshopt",
    "surface nets + meshopt",
    "plain MT + meshopt",
];

/// The README's paragraph: RMT against the simplified peers at an equal budget (quality, time,
/// far occupancy), where RMT loses, and which meshes have defects.
pub fn summary_text(rows: &[PeerRow]) -> Option<String> {
    let objects = objects(rows);
    let rmt: Vec<&PeerRow> = objects
        .iter()
        .filter_map(|o| pick(rows, o, "RMT"))
        .collect();
    if rmt.is_empty() {
        return None;
    }
    let mut parts = vec![format!(
        "At an equal budget (RMT's triangle count on each object), over {} objects RMT's \
         radius-ratio mean is {}",
        rmt.len(),
        range_text(&rmt.iter().map(|r| r.ar.0).collect::<Vec<_>>(), 2).unwrap_or_default()
    )];
    let mut losses = Vec::new();
    for peer in BUDGET_PEERS {
        let pairs: Vec<(&PeerRow, &PeerRow)> = objects
            .iter()
            .filter_map(|o| Some((pick(rows, o, "RMT")?, pick(rows, o, peer)?)))
            .collect();
        if pairs.is_empty() {
            continue;
        }
        let ar: Vec<f64> = pairs.iter().map(|(_, p)| p.ar.0).collect();
        let time: Vec<f64> = pairs.iter().map(|(r, p)| r.time_s / p.time_s).collect();
        parts.push(format!(
            "; {peer}: {} (RMT's time is {} times its time)",
            range_text(&ar, 2).unwrap_or_default(),
            range_text(&time, 2).unwrap_or_default()
        ));
        let slower = pairs.iter().filter(|(r, p)| r.time_s > p.time_s).count();
        if slower > 0 {
            losses.push(format!(
                "it is slower than {peer} on {slower} of {} objects",
                pairs.len()
            ));
        }
        let far_worse = pairs
            .iter()
            .filter(|(r, p)| match (r.occupancy[3], p.occupancy[3]) {
                (Some(a), Some(b)) => a < b,
                _ => false,
            })
            .count();
        if far_worse > 0 {
            losses.push(format!(
                "its quad occupancy at 135 px is below that of {peer} on {far_worse} of {} \
                 objects",
                pairs.len()
            ));
        }
        let worse_order = pairs
            .iter()
            .filter(|(r, p)| match (r.acmr.0, p.acmr.0) {
                (Some(a), Some(b)) => a > b,
                _ => false,
            })
            .count();
        if worse_order > 0 {
            losses.push(format!(
                "its index order as extracted costs more vertex-cache misses (ACMR) than \
                 {peer}'s on {worse_order} of {} objects, until meshoptimizer reorders both",
                pairs.len()
            ));
        }
        let worse_shape = pairs.iter().filter(|(r, p)| r.ar.0 > p.ar.0).count();
        if worse_shape > 0 {
            losses.push(format!(
                "its radius-ratio mean is above that of {peer} on {worse_shape} of {} objects",
                pairs.len()
            ));
        }
    }
    let mut text = parts.concat();
    text.push('.');
    if losses.is_empty() {
        text.push_str(" RMT loses on none of these counts.");
    } else {
        text.push_str(&format!(" Where RMT loses: {}.", losses.join("; ")));
    }
    // Defects, per family: meshes with any, and the non-manifold edges in all.
    let mut defects = Vec::new();
    for family in FAMILIES {
        let members: Vec<&PeerRow> = rows.iter().filter(|r| r.family == family).collect();
        let broken: Vec<&&PeerRow> = members.iter().filter(|r| r.defects != (0.0, 0.0)).collect();
        if !broken.is_empty() {
            defects.push(format!(
                "{family} {} of {} meshes ({} non-manifold edges, {} holes)",
                broken.len(),
                members.len(),
                count(broken.iter().map(|r| r.defects.1).sum()),
                count(broken.iter().map(|r| r.defects.0).sum())
            ));
        }
    }
    let clean: Vec<&str> = FAMILIES
        .iter()
        .copied()
        .filter(|f| {
            rows.iter().any(|r| r.family == *f)
                && rows
                    .iter()
                    .filter(|r| r.family == *f)
                    .all(|r| r.defects == (0.0, 0.0))
        })
        .collect();
    if !clean.is_empty() {
        text.push_str(&format!(
            " Closed and manifold on every object: {}.",
            clean.join(", ")
        ));
    }
    if !defects.is_empty() {
        text.push_str(&format!(" With defects: {}.", defects.join("; ")));
    }
    Some(text)
}

/// The sentence under the occupancy figure: each family's occupancy near and far, over the
/// objects.
pub fn occupancy_sentence(rows: &[PeerRow]) -> String {
    let shown = figure_rows(rows);
    let mut parts = Vec::new();
    for family in FAMILIES {
        let members: Vec<&&PeerRow> = shown.iter().filter(|r| r.family == family).collect();
        let near: Vec<f64> = members.iter().filter_map(|r| r.occupancy[0]).collect();
        let far: Vec<f64> = members.iter().filter_map(|r| r.occupancy[3]).collect();
        if let (Some(n), Some(f)) = (range_text(&near, 2), range_text(&far, 2)) {
            parts.push(format!("{family} {n} at 1080 px and {f} at 135 px"));
        }
    }
    format!(
        "Quad occupancy falls as the object shrinks on screen: triangles approach the size of a \
         2x2 quad and more lanes shade helpers. Over the objects: {}.",
        parts.join("; ")
    )
}

/// The sentence under the time figure: each family's time relative to plain MT on the same
/// object, and its triangles relative to plain MT's.
pub fn time_sentence(rows: &[PeerRow]) -> String {
    let mut parts = Vec::new();
    for family in FAMILIES {
        let pairs: Vec<(&PeerRow, &PeerRow)> = objects(rows)
            .iter()
            .filter_map(|o| Some((pick(rows, o, "plain MT")?, pick(rows, o, family)?)))
            .collect();
        if family == "plain MT" || pairs.is_empty() {
            continue;
        }
        let time: Vec<f64> = pairs.iter().map(|(b, r)| r.time_s / b.time_s).collect();
        let tris: Vec<f64> = pairs
            .iter()
            .map(|(b, r)| 100.0 * r.triangles / b.triangles)
            .collect();
        parts.push(format!(
            "{family} {} times the time for {}% of the triangles",
            range_text(&time, 2).unwrap_or_default(),
            range_text(&tris, 0).unwrap_or_default()
        ));
    }
    format!(
        "Each point is one method on one object (body-centred lattice for marching tetrahedra, \
         free borders for the simplified peers); down and to the left is cheaper and smaller, \
         the marker gives the shape of the triangles. Against plain body-centred MT on the same \
         object: {}.",
        parts.join("; ")
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn families_and_labels_follow_the_configuration() {
        assert_eq!(family("mt", "integrated", "none"), Some("RMT"));
        assert_eq!(
            family("mt", "none", "meshopt:rmt"),
            Some("plain MT + meshopt")
        );
        assert_eq!(family("mc", "none", ""), Some("marching cubes"));
        assert_eq!(
            family("surface-nets", "none", "meshopt-locked:rmt"),
            Some("surface nets + meshopt")
        );
        assert_eq!(family("mt", "meshopt", "none"), None);
        assert_eq!(
            label(
                "surface nets + meshopt",
                "surface-nets",
                "simple",
                "meshopt-locked:rmt"
            ),
            "surface nets + meshopt, borders locked"
        );
        assert_eq!(label("RMT", "mt", "bcdl", "none"), "RMT, body-centred");
    }

    #[test]
    fn quality_markers_split_at_the_stated_bounds() {
        assert_eq!(quality_marker(1.2), Marker::Circle);
        assert_eq!(quality_marker(1.3), Marker::Circle);
        assert_eq!(quality_marker(1.31), Marker::Square);
        assert_eq!(quality_marker(2.5), Marker::Triangle);
    }

    fn row(object: &str, family: &'static str, time_s: f64, occupancy_135: f64) -> PeerRow {
        PeerRow {
            id: format!("{object}-{family}"),
            object: object.into(),
            family,
            label: family.into(),
            method: "mt".into(),
            clustering: "integrated".into(),
            lattice: if family.contains("MT") || family == "RMT" {
                "bcdl".into()
            } else {
                "simple".into()
            },
            simplify: if family.contains("meshopt") {
                "meshopt:rmt".into()
            } else {
                "none".into()
            },
            time_s,
            triangles: 1000.0,
            ar: (1.2, 1.5),
            fidelity_h: Some(0.1),
            occupancy: [Some(0.9), Some(0.8), Some(0.6), Some(occupancy_135)],
            below_pixel: (Some(0.0), Some(0.1)),
            acmr: (Some(1.0), Some(0.7)),
            defects: (0.0, 0.0),
            simplify_error_h: None,
        }
    }

    #[test]
    fn the_paragraph_says_where_rmt_loses() {
        let rows = vec![
            row("asteroid", "RMT", 0.002, 0.30),
            row("asteroid", "marching cubes + meshopt", 0.001, 0.35),
            row("asteroid", "surface nets + meshopt", 0.004, 0.25),
        ];
        let text = summary_text(&rows).unwrap();
        assert!(
            text.contains("slower than marching cubes + meshopt on 1 of 1 objects"),
            "{text}"
        );
        assert!(!text.contains("slower than surface nets"), "{text}");
        assert!(
            text.contains("below that of marching cubes + meshopt on 1 of 1"),
            "{text}"
        );
        assert!(
            text.contains("(RMT's time is 2.00 times its time)"),
            "{text}"
        );
        assert!(
            text.contains("(RMT's time is 0.50 times its time)"),
            "{text}"
        );
        assert!(
            text.contains("Closed and manifold on every object: RMT"),
            "{text}"
        );
        assert!(summary_text(&[]).is_none());
        assert_eq!(
            range_text(&[1.0, 2.0, f64::NAN], 1).as_deref(),
            Some("1.0-2.0")
        );
        assert_eq!(range_text(&[1.001, 1.002], 2).as_deref(), Some("1.00"));
        assert_eq!(number(61_252_324_390_494.0, 2), "6.1e13");
        assert_eq!(number(9999.5, 1), "9999.5");
    }

    #[test]
    fn the_table_has_a_block_per_object_and_a_csv_row_per_method() {
        let info = RunInfo::default();
        let rows = vec![
            row("asteroid", "RMT", 0.002, 0.30),
            row("sphere", "RMT", 0.002, 0.30),
            row("sphere", "marching cubes", 0.001, 0.35),
        ];
        let t = peers_table(&info, &rows);
        assert_eq!(t.blocks.len(), 2);
        assert_eq!(t.blocks[1].rows.len(), 2);
        assert_eq!(t.csv_rows.len(), 3);
        assert!(t.csv_rows.iter().all(|r| r.len() == t.csv_header.len()));
        assert!(occupancy_figure(&info, &rows).is_some());
        assert_eq!(time_figure(&info, &rows).map(|c| c.panels.len()), Some(2));
    }
}
