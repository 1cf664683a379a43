//! Level of detail (issue 40): the level map of a `lod` run seen from above, with the viewer's
//! path, and the triangles per level.
//!
//! The input is a run folder of the `lod` workload (`experiments run` of a manifest with
//! `workload = "lod"`, kept in a report as `data/lod/`):
//!
//! ```text
//!   run.json, manifest.toml, configurations.csv   provenance and the manifest as run
//!   summary.csv     one row per configuration (schema::LOD_SUMMARY): world, re-mesh times, checks
//!   lod.csv         one row per viewer step (schema::LOD_STEPS): the viewer's position
//!   lod_levels.csv  chunks and triangles per step and level (schema::LOD_LEVELS)
//!   lod_map.csv     the last step's level map, one row per chunk with its box (schema::LOD_MAP)
//!        │
//!        └──► figures lod_top_view (a horizontal section of the level map at the viewer's
//!             height, levels coloured, the viewer's path drawn) and lod_triangles (bars per
//!             level), tables lod_levels and lod_summary, and the README's section
//! ```
//!
//! A run with several configurations shows its first one (the section says which).

use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, VPos};

use crate::csv_file::CsvFile;
use crate::data::{RunInfo, CONFIGURATIONS_CSV, MANIFEST_TOML, RUN_JSON, SUMMARY_CSV};
use crate::error::{io_error, ReportError, Result};
use crate::format;
use crate::output::{Block, TextTable};
use crate::plot::{
    draw_header, e, header_height, header_width, label, palette, Axis, Bar, DrawResult, Figure,
    LegendEntry, Marker, RowChart, RowLine, Swatch, INK, MARGIN, SMALL_SIZE, TICK_SIZE,
};
use rmt_runfolder::layout::{LOD_CSV, LOD_LEVELS_CSV, LOD_MAP_CSV};

/// The files of a `lod` run the report reads (and copies into `data/lod/`), in order.
pub const LOD_FILES: [&str; 7] = [
    RUN_JSON,
    MANIFEST_TOML,
    CONFIGURATIONS_CSV,
    SUMMARY_CSV,
    LOD_CSV,
    LOD_LEVELS_CSV,
    LOD_MAP_CSV,
];

/// The measures of the triangles' shape on a flight's checked steps, as `summary.csv` names
/// them (`rmt_runfolder::schema::LOD_SUMMARY`), with their captions.
const LOD_QUALITY: [(&str, &str); 5] = [
    (
        "ar_mean",
        "radius ratio R / 2r of the checked steps' triangles, mean (1 is equilateral)",
    ),
    ("ar_median", "radius ratio, median (the largest step's)"),
    ("ar_p99", "radius ratio, p99 (the largest step's)"),
    ("ar_max", "radius ratio, max"),
    (
        "zero_area_triangles",
        "zero-area triangles, most at a step (not in the ratios)",
    ),
];

/// Whether `folder` holds a `lod` run with the files of the report's section.
pub fn is_lod(folder: &Path) -> bool {
    LOD_FILES.iter().all(|f| folder.join(f).is_file())
}

/// The files of [`LOD_FILES`] in `folder`, read into memory.
pub fn lod_files(folder: &Path) -> Result<Vec<(&'static str, Vec<u8>)>> {
    LOD_FILES
        .iter()
        .map(|name| {
            let path = folder.join(name);
            if !path.is_file() {
                return Err(ReportError::MissingFile {
                    path,
                    hint: "a file of the lod workload's run folder (experiments run of a \
                           manifest with workload = \"lod\")"
                        .into(),
                });
            }
            Ok((*name, std::fs::read(&path).map_err(io_error(&path))?))
        })
        .collect()
}

/// One level at the map's step and over the flight.
#[derive(Clone, Debug, PartialEq)]
pub struct LevelRow {
    /// Level (0 finest).
    pub level: u8,
    /// Chunks of the level at the map's step.
    pub chunks: u64,
    /// Their triangles.
    pub triangles: u64,
    /// Mean triangles of the level over every step of the flight.
    pub mean_triangles: f64,
}

/// One chunk of the map, its box in world coordinates.
#[derive(Clone, Debug, PartialEq)]
pub struct MapRow {
    /// Level (0 finest).
    pub level: u8,
    /// Near corner.
    pub min: [f64; 3],
    /// Far corner.
    pub max: [f64; 3],
}

/// A `lod` run read for the report: its first configuration.
#[derive(Clone, Debug)]
pub struct LodRun {
    /// `run.json`.
    pub info: RunInfo,
    /// The configuration shown.
    pub id: String,
    /// Configurations in the run.
    pub configurations: usize,
    /// `summary.csv`'s row of the configuration, by column.
    pub summary: Vec<(String, String)>,
    /// The viewer at every step, world coordinates.
    pub path: Vec<[f64; 3]>,
    /// The step the map is of (the last).
    pub step: u64,
    /// Levels `0..=levels`.
    pub levels: Vec<LevelRow>,
    /// The map's chunks.
    pub map: Vec<MapRow>,
    /// The finest cell edge, world units.
    pub cell: f64,
}

fn need(csv: &CsvFile, row: usize, name: &str) -> Result<f64> {
    csv.number(row, name)?
        .ok_or_else(|| ReportError::EmptyCell {
            path: csv.path.clone(),
            line: row + 2,
            column: name.to_string(),
        })
}

fn input_error(path: &Path, message: impl Into<String>) -> ReportError {
    ReportError::Input {
        path: path.to_path_buf(),
        message: message.into(),
    }
}

/// Reads the `lod` run in `folder` (see the [module documentation](self)).
pub fn read_lod(folder: &Path) -> Result<LodRun> {
    let info = RunInfo::read(&folder.join(RUN_JSON))?;
    let summary = CsvFile::read(&folder.join(SUMMARY_CSV))?;
    if summary.rows.is_empty() {
        return Err(input_error(&summary.path, "no configuration"));
    }
    let id = summary.text(0, "id")?.to_string();
    let row: Vec<(String, String)> = summary
        .header
        .iter()
        .cloned()
        .zip(summary.rows[0].iter().cloned())
        .collect();
    let levels_max = need(&summary, 0, "levels")?;
    let chunk = need(&summary, 0, "chunk")?;
    if !(0.0..=12.0).contains(&levels_max) || chunk < 1.0 {
        return Err(input_error(
            &summary.path,
            format!("levels {levels_max} and chunk {chunk} are not a lod world's"),
        ));
    }
    let levels_max = levels_max as u8;

    let steps = CsvFile::read(&folder.join(LOD_CSV))?;
    let mut path = Vec::new();
    for r in 0..steps.rows.len() {
        if steps.text(r, "id")? == id {
            path.push([
                need(&steps, r, "viewer_x")?,
                need(&steps, r, "viewer_y")?,
                need(&steps, r, "viewer_z")?,
            ]);
        }
    }
    if path.is_empty() {
        return Err(input_error(&steps.path, format!("no step of {id}")));
    }

    let per_level = CsvFile::read(&folder.join(LOD_LEVELS_CSV))?;
    let mut levels: Vec<LevelRow> = (0..=levels_max)
        .map(|level| LevelRow {
            level,
            chunks: 0,
            triangles: 0,
            mean_triangles: 0.0,
        })
        .collect();
    let last = (path.len() - 1) as f64;
    let mut steps_seen = 0usize;
    for r in 0..per_level.rows.len() {
        if per_level.text(r, "id")? != id {
            continue;
        }
        let level = need(&per_level, r, "level")?;
        let slot = levels
            .iter_mut()
            .find(|l| f64::from(l.level) == level)
            .ok_or_else(|| {
                input_error(
                    &per_level.path,
                    format!("line {}: level {level} outside 0..={levels_max}", r + 2),
                )
            })?;
        let triangles = need(&per_level, r, "triangles")?;
        slot.mean_triangles += triangles;
        if level == 0.0 {
            steps_seen += 1;
        }
        if need(&per_level, r, "step")? == last {
            slot.chunks = need(&per_level, r, "chunks")? as u64;
            slot.triangles = triangles as u64;
        }
    }
    if steps_seen != path.len() {
        return Err(input_error(
            &per_level.path,
            format!(
                "{steps_seen} steps of {id} at level 0, lod.csv has {}",
                path.len()
            ),
        ));
    }
    for l in &mut levels {
        l.mean_triangles /= path.len() as f64;
    }

    let map_csv = CsvFile::read(&folder.join(LOD_MAP_CSV))?;
    let mut map = Vec::new();
    let mut step = None;
    for r in 0..map_csv.rows.len() {
        if map_csv.text(r, "id")? != id {
            continue;
        }
        step = Some(need(&map_csv, r, "step")? as u64);
        let corner = |names: [&str; 3]| -> Result<[f64; 3]> {
            Ok([
                need(&map_csv, r, names[0])?,
                need(&map_csv, r, names[1])?,
                need(&map_csv, r, names[2])?,
            ])
        };
        map.push(MapRow {
            level: need(&map_csv, r, "level")? as u8,
            min: corner(["x_min", "y_min", "z_min"])?,
            max: corner(["x_max", "y_max", "z_max"])?,
        });
    }
    let step = step.ok_or_else(|| input_error(&map_csv.path, format!("no chunk of {id}")))?;
    let first = &map[0];
    let cell = (first.max[0] - first.min[0]) / (chunk * f64::from(1u32 << first.level.min(12)));
    Ok(LodRun {
        info,
        id,
        configurations: summary.rows.len(),
        summary: row,
        path,
        step,
        levels,
        map,
        cell,
    })
}

impl LodRun {
    /// A column of the summary row (empty when absent).
    pub fn value(&self, name: &str) -> &str {
        self.summary
            .iter()
            .find(|(k, _)| k == name)
            .map_or("", |(_, v)| v.as_str())
    }

    /// The viewer at the map's step.
    pub fn viewer(&self) -> [f64; 3] {
        self.path[self.path.len() - 1]
    }

    /// The world's box: the union of the map's chunks.
    pub fn bounds(&self) -> ([f64; 3], [f64; 3]) {
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for c in &self.map {
            for i in 0..3 {
                lo[i] = lo[i].min(c.min[i]);
                hi[i] = hi[i].max(c.max[i]);
            }
        }
        (lo, hi)
    }

    /// The chunks a horizontal plane at height `y` cuts (the top chunks where `y` is the
    /// world's top).
    pub fn section(&self, y: f64) -> Vec<&MapRow> {
        let top = self.bounds().1[1];
        self.map
            .iter()
            .filter(|c| c.min[1] <= y && (y < c.max[1] || (y == top && c.max[1] == top)))
            .collect()
    }

    /// One sentence naming the world: manifest, object, cells, chunks, levels, steps.
    pub fn world_sentence(&self) -> String {
        format!(
            "the `{}` manifest's run (`{}`): {} of {} x {} x {} finest cells (cell edge {}), \
             chunks of {}^3 cells at levels 0 (finest) to {}, split while the viewer is closer \
             than {} chunk edges, a viewer flown in {} steps",
            self.info.name,
            self.info.run_id,
            self.value("object"),
            self.value("rx"),
            self.value("ry"),
            self.value("rz"),
            format::sig(self.cell, 3),
            self.value("chunk"),
            self.value("levels"),
            self.value("ratio"),
            self.value("steps")
        )
    }
}

/// The colour of level `l` in the top view and the bars (finest darkest).
pub fn level_colour(level: u8) -> RGBColor {
    // The studio's "colour by level" uses the same colours.
    const COLOURS: [RGBColor; 7] = [
        palette::BLUE,
        palette::ORANGE,
        palette::GREEN,
        palette::PURPLE,
        palette::SKY,
        palette::VERMILLION,
        palette::YELLOW,
    ];
    COLOURS[usize::from(level) % COLOURS.len()]
}

fn level_label(run: &LodRun, level: u8) -> String {
    format!(
        "level {level} (cell {})",
        format::sig(run.cell * f64::from(1u32 << level.min(12)), 3)
    )
}

/// The level map from above: a horizontal section at the viewer's height, every chunk it cuts
/// filled with its level's colour, the viewer's path over it.
#[derive(Clone, Debug, PartialEq)]
pub struct TopView {
    /// Title.
    pub title: String,
    /// Lines under the title.
    pub subtitle: Vec<String>,
    /// Level colours.
    pub legend: Vec<LegendEntry>,
    /// x range (world).
    pub x: (f64, f64),
    /// z range (world).
    pub z: (f64, f64),
    /// Rectangles in x-z with their colour.
    pub cells: Vec<([f64; 2], [f64; 2], RGBColor)>,
    /// The viewer's path in x-z.
    pub path: Vec<[f64; 2]>,
}

/// Pixels of the longer side of the map.
const MAP_SIDE: i32 = 520;
/// Room for the tick labels and axis titles left of and under the map.
const AXIS_ROOM: i32 = 56;

impl TopView {
    fn map_size(&self) -> (i32, i32) {
        let (w, d) = (self.x.1 - self.x.0, self.z.1 - self.z.0);
        let scale = f64::from(MAP_SIDE) / w.max(d).max(f64::MIN_POSITIVE);
        (
            ((w * scale).round() as i32).max(40),
            ((d * scale).round() as i32).max(40),
        )
    }

    fn width(&self) -> i32 {
        (AXIS_ROOM + self.map_size().0 + 2 * MARGIN).max(header_width(&self.title, &self.subtitle))
    }
}

impl Figure for TopView {
    fn size(&self) -> (u32, u32) {
        let width = self.width();
        let height =
            header_height(&self.subtitle, &self.legend, width) + 12 + self.map_size().1 + AXIS_ROOM;
        (width as u32, (height + MARGIN) as u32)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult {
        let width = self.width();
        let top = draw_header(root, &self.title, &self.subtitle, &self.legend, width)? + 12;
        let (w, h) = self.map_size();
        let left = MARGIN + AXIS_ROOM;
        let (right, bottom) = (left + w, top + h);
        let x_axis = Axis {
            lo: self.x.0,
            hi: self.x.1,
            log: false,
        };
        let z_axis = Axis {
            lo: self.z.0,
            hi: self.z.1,
            log: false,
        };
        // z grows downwards, as seen from above with x to the right.
        let px = |p: [f64; 2]| {
            (
                x_axis.pixel(p[0], left, right),
                z_axis.pixel(p[1], top, bottom),
            )
        };
        for (lo, hi, colour) in &self.cells {
            let (a, b) = (px(*lo), px(*hi));
            root.draw(&Rectangle::new([a, b], colour.filled()))
                .map_err(e)?;
            root.draw(&Rectangle::new([a, b], ShapeStyle::from(&WHITE)))
                .map_err(e)?;
        }
        root.draw(&Rectangle::new([(left, top), (right, bottom)], INK))
            .map_err(e)?;
        for tick in x_axis.ticks().into_iter().filter(|t| t.major) {
            let x = x_axis.pixel(tick.value, left, right);
            root.draw(&PathElement::new(vec![(x, bottom), (x, bottom + 5)], INK))
                .map_err(e)?;
            if let Some(text) = &tick.label {
                label(
                    root,
                    text,
                    (x, bottom + 8),
                    TICK_SIZE,
                    HPos::Center,
                    VPos::Top,
                )?;
            }
        }
        for tick in z_axis.ticks().into_iter().filter(|t| t.major) {
            let z = z_axis.pixel(tick.value, top, bottom);
            root.draw(&PathElement::new(vec![(left - 5, z), (left, z)], INK))
                .map_err(e)?;
            if let Some(text) = &tick.label {
                label(
                    root,
                    text,
                    (left - 8, z),
                    TICK_SIZE,
                    HPos::Right,
                    VPos::Center,
                )?;
            }
        }
        label(
            root,
            "x",
            ((left + right) / 2, bottom + 28),
            SMALL_SIZE,
            HPos::Center,
            VPos::Top,
        )?;
        label(
            root,
            "z",
            (MARGIN + 4, (top + bottom) / 2),
            SMALL_SIZE,
            HPos::Left,
            VPos::Center,
        )?;
        let points: Vec<(i32, i32)> = self.path.iter().map(|p| px(*p)).collect();
        let line = ShapeStyle::from(&INK).stroke_width(2);
        root.draw(&PathElement::new(points.clone(), line))
            .map_err(e)?;
        for p in &points {
            root.draw(&Circle::new(*p, 3, INK.filled())).map_err(e)?;
        }
        if let Some(&last) = points.last() {
            root.draw(&Circle::new(last, 7, WHITE.filled()))
                .map_err(e)?;
            root.draw(&Circle::new(
                last,
                7,
                ShapeStyle::from(&INK).stroke_width(2),
            ))
            .map_err(e)?;
        }
        Ok(())
    }
}

/// The top view of `run`'s map (see [`TopView`]).
pub fn top_view(run: &LodRun) -> TopView {
    let (lo, hi) = run.bounds();
    let viewer = run.viewer();
    let mut cells: Vec<([f64; 2], [f64; 2], RGBColor)> = run
        .section(viewer[1])
        .into_iter()
        .map(|c| {
            (
                [c.min[0], c.min[2]],
                [c.max[0], c.max[2]],
                level_colour(c.level),
            )
        })
        .collect();
    // Coarse first, so the outlines of fine chunks are drawn last.
    cells.sort_by(|a, b| (b.1[0] - b.0[0]).total_cmp(&(a.1[0] - a.0[0])));
    let legend = run
        .levels
        .iter()
        .map(|l| {
            LegendEntry::new(
                Swatch::Bar(level_colour(l.level)),
                level_label(run, l.level),
            )
        })
        .chain([LegendEntry::new(
            Swatch::Line {
                colour: INK,
                dashed: false,
                marker: Some(Marker::Circle),
            },
            "viewer path (ring: the viewer now)",
        )])
        .collect();
    TopView {
        title: format!("The level map from above, step {}", run.step),
        subtitle: vec![
            format!(
                "{}: {} x {} x {} cells, levels 0-{}, chunks of {}³ cells",
                run.info.name,
                run.value("rx"),
                run.value("ry"),
                run.value("rz"),
                run.value("levels"),
                run.value("chunk")
            ),
            format!(
                "Section at the viewer's height y = {}: the chunks it cuts, by level",
                format::fixed(viewer[1], 3)
            ),
        ],
        legend,
        x: (lo[0], hi[0]),
        z: (lo[2], hi[2]),
        cells,
        path: run.path.iter().map(|p| [p[0], p[2]]).collect(),
    }
}

/// Triangles per level at the map's step, as bars.
pub fn triangles_figure(run: &LodRun) -> RowChart {
    let total: u64 = run.levels.iter().map(|l| l.triangles).sum();
    let values: Vec<f64> = run.levels.iter().map(|l| l.triangles as f64).collect();
    RowChart {
        title: format!("Triangles per level, step {}", run.step),
        subtitle: vec![format!(
            "{}: {} triangles in {} chunks",
            run.info.name,
            format::count(total as f64),
            format::count(run.map.len() as f64)
        )],
        axis_label: "triangles".into(),
        axis: Axis::linear(&values, true),
        percent_axis: false,
        dots: false,
        lines: run
            .levels
            .iter()
            .map(|l| RowLine::Bars {
                label: level_label(run, l.level),
                bars: vec![Bar {
                    value: l.triangles as f64,
                    colour: level_colour(l.level),
                    interval: None,
                    reference: None,
                    text: format!(
                        "{} ({}, {} chunks)",
                        format::count(l.triangles as f64),
                        format::percent(share(l.triangles, total)),
                        format::count(l.chunks as f64)
                    ),
                }],
            })
            .collect(),
        legend: Vec::new(),
    }
}

fn share(part: u64, total: u64) -> f64 {
    if total == 0 {
        0.0
    } else {
        part as f64 / total as f64
    }
}

/// The tables of the section: `lod_levels` (per level) and `lod_summary` (the run's measures).
pub fn lod_tables(run: &LodRun) -> Vec<TextTable> {
    let total: u64 = run.levels.iter().map(|l| l.triangles).sum();
    let mut levels = TextTable {
        name: "lod_levels".into(),
        title: format!("Triangles per level ({})", run.info.name),
        notes: vec![format!(
            "Configuration `{}` at step {} (the last), and the mean over the flight's {} steps \
             (step 0 included). Cell edges in world units.",
            run.id,
            run.step,
            run.path.len()
        )],
        csv_header: [
            "level",
            "cell",
            "chunks",
            "triangles",
            "share",
            "mean_triangles",
        ]
        .map(String::from)
        .to_vec(),
        csv_rows: Vec::new(),
        blocks: vec![Block {
            caption: None,
            header: [
                "level",
                "cell edge",
                "chunks",
                "triangles",
                "share",
                "mean triangles over the flight",
            ]
            .map(String::from)
            .to_vec(),
            rows: Vec::new(),
        }],
    };
    for l in &run.levels {
        let cell = run.cell * f64::from(1u32 << l.level.min(12));
        levels.csv_rows.push(vec![
            l.level.to_string(),
            format!("{cell:.6}"),
            l.chunks.to_string(),
            l.triangles.to_string(),
            format!("{:.4}", share(l.triangles, total)),
            format!("{:.1}", l.mean_triangles),
        ]);
        levels.blocks[0].rows.push(vec![
            l.level.to_string(),
            format::sig(cell, 3),
            format::count(l.chunks as f64),
            format::count(l.triangles as f64),
            format::percent(share(l.triangles, total)),
            format::count(l.mean_triangles.round()),
        ]);
    }
    let mut measures: Vec<(&str, &str)> = vec![
        ("steps", "viewer steps"),
        (
            "remesh_p50_ms",
            "re-mesh after a step, p50 (ms, this machine)",
        ),
        (
            "remesh_p99_ms",
            "re-mesh after a step, p99 (ms, this machine)",
        ),
        ("chunks_remeshed_mean", "chunks re-meshed per step, mean"),
        ("triangles_max", "most triangles in the world"),
        ("validated_steps", "steps checked"),
        ("open_edges", "open edges inside the domain, most at a step"),
        ("non_manifold_edges", "non-manifold edges, most at a step"),
        ("orientation_errors", "misoriented edges, most at a step"),
        ("pop_max_cells", "pop, max (finer cells)"),
        ("pop_mean_cells", "pop, mean (finer cells)"),
        (
            "normal_seam_max_deg",
            "normal difference at level seams, max (degrees)",
        ),
        (
            "triangles_over_finest",
            "triangles over the finest level everywhere",
        ),
    ];
    // A morphed flight (`morph` > 0): its band and the surface's motion per step.
    if run.value("morph").parse::<f64>().is_ok_and(|m| m > 0.0) {
        measures.extend([
            ("morph", "morph band (fraction of ratio x chunk edge)"),
            ("morph_max_cells", "morph per step, max (finer cells)"),
            ("morph_mean_cells", "morph per step, mean (finer cells)"),
        ]);
    }
    // Brush strokes during the flight (`[lod] edits`).
    if run
        .value("edits_applied")
        .parse::<u64>()
        .is_ok_and(|n| n > 0)
    {
        measures.extend([
            ("edits_applied", "brush strokes applied"),
            (
                "edit_chunks_total",
                "chunks that saw a stroke's change, summed over the steps",
            ),
        ]);
    }
    // The triangles' shape on the checked steps (runs that measured it).
    if !run.value("ar_p99").is_empty() {
        measures.extend(LOD_QUALITY);
    }
    let mut summary = TextTable {
        name: "lod_summary".into(),
        title: format!("The flight's measures ({})", run.info.name),
        notes: vec![format!(
            "From `summary.csv` of configuration `{}`; the finest level's triangles are {} \
             (`finest_source`). Times depend on the machine and its load when the run was made (`data/lod/run.json`).",
            run.id,
            if run.value("finest_source") == "exact" {
                "counted"
            } else {
                "estimated"
            }
        )],
        csv_header: ["measure", "column", "value"].map(String::from).to_vec(),
        csv_rows: Vec::new(),
        blocks: vec![Block {
            caption: None,
            header: ["measure", "value"].map(String::from).to_vec(),
            rows: Vec::new(),
        }],
    };
    for (column, what) in measures {
        let value = run.value(column).to_string();
        summary
            .csv_rows
            .push(vec![what.to_string(), column.to_string(), value.clone()]);
        summary.blocks[0].rows.push(vec![what.to_string(), value]);
    }
    vec![levels, summary]
}

/// The README's section: what world it is, the top view, the triangles per level and the
/// measures; `link` gives a table's link.
pub fn readme_section(run: &LodRun, link: impl Fn(&str) -> Option<String>) -> String {
    let mut out = String::from("## Level of detail: the level map from above\n\n");
    out.push_str(&format!(
        "One conforming multiresolution mesh, fine near the viewer and coarse far away (issue \
         40), from {}. This is a small world for CI (`experiments/manifests/{}.toml`), not \
         `lod.toml`'s 4096 x 256 x 4096; its numbers show the construction, not its scale.",
        run.world_sentence(),
        run.info.name
    ));
    if run.configurations > 1 {
        out.push_str(&format!(
            " The run has {} configurations; this section shows the first, `{}`.",
            run.configurations, run.id
        ));
    }
    out.push_str("\n\n");
    let total: u64 = run.levels.iter().map(|l| l.triangles).sum();
    let finest = run.levels.first().map_or(0, |l| l.triangles);
    out.push_str(&format!(
        "### The level map from above\n\nA horizontal section through the level map at the \
         viewer's height after its last step (step {}): every chunk the plane cuts, coloured by \
         level, with the path the viewer flew. The map is 2:1 balanced: no chunk touches one more \
         than one level finer or coarser.\n\n",
        run.step
    ));
    out.push_str(
        "![The level map from above](figures/lod_top_view.png)\n\n[SVG](figures/lod_top_view.svg)\n\n",
    );
    out.push_str(&format!(
        "### Triangles per level\n\nAt step {}, {} of the world's {} triangles are at the \
         finest level ({}).\n\n",
        run.step,
        format::count(finest as f64),
        format::count(total as f64),
        format::percent(share(finest, total))
    ));
    out.push_str(
        "![Triangles per level](figures/lod_triangles.png)\n\n[SVG](figures/lod_triangles.svg)\n\n",
    );
    for name in ["lod_levels", "lod_summary"] {
        if let Some(l) = link(name) {
            out.push_str(&format!("Table: {l}.\n\n"));
        }
    }
    out.push_str(&format!(
        "Regenerate the input: `experiments run experiments/manifests/{}.toml --out DIR`, then \
         `experiments report --lod DIR` (kept as `data/lod/`).\n\n",
        run.info.name
    ));
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run() -> LodRun {
        // A 2 x 1 world of level-1 chunks (edge 1) with the left one split into level 0
        // (edge 0.5): 8 children, 4 per layer.
        let mut map = vec![MapRow {
            level: 1,
            min: [1.0, 0.0, 0.0],
            max: [2.0, 1.0, 1.0],
        }];
        for k in 0..8 {
            let (x, y, z) = (
                f64::from(k & 1) * 0.5,
                f64::from((k >> 1) & 1) * 0.5,
                f64::from((k >> 2) & 1) * 0.5,
            );
            map.push(MapRow {
                level: 0,
                min: [x, y, z],
                max: [x + 0.5, y + 0.5, z + 0.5],
            });
        }
        LodRun {
            info: RunInfo {
                name: "lod-test".into(),
                ..RunInfo::default()
            },
            id: "cs_bu".into(),
            configurations: 1,
            summary: vec![
                ("object".into(), "caves".into()),
                ("chunk".into(), "4".into()),
            ],
            path: vec![[0.1, 0.2, 0.1], [0.4, 0.7, 0.3]],
            step: 1,
            levels: vec![
                LevelRow {
                    level: 0,
                    chunks: 8,
                    triangles: 300,
                    mean_triangles: 250.0,
                },
                LevelRow {
                    level: 1,
                    chunks: 1,
                    triangles: 100,
                    mean_triangles: 120.0,
                },
            ],
            map,
            cell: 0.125,
        }
    }

    #[test]
    fn the_section_cuts_the_chunks_at_the_viewers_height() {
        let r = run();
        // y = 0.7: the upper layer of level-0 chunks and the level-1 chunk.
        let s = r.section(0.7);
        assert_eq!(s.len(), 5);
        assert_eq!(s.iter().filter(|c| c.level == 0).count(), 4);
        assert!(s.iter().all(|c| c.level == 1 || c.min[1] == 0.5));
        // The world's top belongs to the top chunks; a height outside cuts nothing.
        assert_eq!(r.section(1.0).len(), 5);
        assert!(r.section(1.5).is_empty());
        assert_eq!(r.bounds(), ([0.0; 3], [2.0, 1.0, 1.0]));
    }

    #[test]
    fn the_top_view_covers_the_section_and_draws_the_path() {
        let r = run();
        let v = top_view(&r);
        assert_eq!(v.cells.len(), 5);
        // The coarse chunk first, so the fine outlines are drawn over it.
        assert_eq!(v.cells[0].2, level_colour(1));
        let area: f64 = v
            .cells
            .iter()
            .map(|(lo, hi, _)| (hi[0] - lo[0]) * (hi[1] - lo[1]))
            .sum();
        assert!(
            (area - 2.0).abs() < 1e-12,
            "the section covers the world: {area}"
        );
        assert_eq!(v.path, [[0.1, 0.1], [0.4, 0.3]]);
        assert_eq!((v.x, v.z), ((0.0, 2.0), (0.0, 1.0)));
        // Levels plus the path in the legend; the map keeps the world's aspect.
        assert_eq!(v.legend.len(), 3);
        let (w, h) = v.map_size();
        assert_eq!((w, h), (MAP_SIDE, MAP_SIDE / 2));
        assert!(v.subtitle[1].contains("y = 0.700"));
        assert_ne!(level_colour(0), level_colour(1));
    }

    #[test]
    fn tables_and_bars_give_each_level_its_triangles_and_share() {
        let r = run();
        let tables = lod_tables(&r);
        assert_eq!(tables[0].name, "lod_levels");
        assert_eq!(
            tables[0].csv_rows,
            [
                ["0", "0.125000", "8", "300", "0.7500", "250.0"],
                ["1", "0.250000", "1", "100", "0.2500", "120.0"],
            ]
        );
        assert_eq!(tables[1].csv_rows.len(), 13);
        let chart = triangles_figure(&r);
        assert_eq!(chart.lines.len(), 2);
        match &chart.lines[0] {
            RowLine::Bars { label, bars } => {
                assert_eq!(label, "level 0 (cell 0.125)");
                assert_eq!(bars[0].value, 300.0);
                assert!(bars[0].text.contains("75"), "{}", bars[0].text);
            }
            other => panic!("{other:?}"),
        }
        let text = readme_section(&r, |n| Some(format!("[{n}]")));
        assert!(text.starts_with("## Level of detail: the level map from above"));
        assert!(text.contains("300 of the world's 400 triangles"), "{text}");
        assert!(text.contains("[lod_levels]") && text.contains("[lod_summary]"));
        assert!(text.contains("lod-test"));
    }

    /// Strokes and triangle shape join the measures only for runs whose `summary.csv` has
    /// them (older runs, like the committed report's, keep their table).
    #[test]
    fn strokes_and_shape_are_shown_when_the_run_measured_them() {
        let columns = |r: &LodRun| -> Vec<String> {
            lod_tables(r)[1]
                .csv_rows
                .iter()
                .map(|row| row[1].clone())
                .collect()
        };
        let plain = columns(&run());
        assert!(!plain
            .iter()
            .any(|c| c == "edits_applied" || c.starts_with("ar_")));
        let mut r = run();
        r.summary.extend(
            [
                ("edits_applied", "0"),
                ("edit_chunks_total", "0"),
                ("ar_mean", "5.5"),
                ("ar_median", "1.3"),
                ("ar_p99", "31.4"),
                ("ar_max", "1989489"),
                ("zero_area_triangles", "2"),
            ]
            .map(|(k, v)| (k.to_string(), v.to_string())),
        );
        let shaped = columns(&r);
        assert_eq!(shaped.len(), plain.len() + 5);
        assert!(!shaped.iter().any(|c| c == "edits_applied"), "no strokes");
        let rows = &lod_tables(&r)[1].csv_rows;
        let p99 = rows.iter().find(|row| row[1] == "ar_p99").unwrap();
        assert_eq!(p99[2], "31.4");
        r.summary[2].1 = "3".into(); // edits_applied
        let stroked = columns(&r);
        assert_eq!(stroked.len(), plain.len() + 7);
        assert!(stroked.iter().any(|c| c == "edit_chunks_total"));
    }

    #[test]
    fn the_figures_draw() {
        let dir = tempfile::tempdir().unwrap();
        let r = run();
        let files = crate::plot::write_figure(&top_view(&r), dir.path(), "top").unwrap();
        assert_eq!(files.len(), 2);
        let svg = std::fs::read_to_string(dir.path().join("top.svg")).unwrap();
        assert!(svg.contains("<rect") && svg.contains("level 0"));
        crate::plot::write_figure(&triangles_figure(&r), dir.path(), "bars").unwrap();
        assert!(dir.path().join("bars.png").is_file());
    }
}
