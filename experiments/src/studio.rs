//! The studio's backend ([`rmt_server::studio::Backend`]): the page's parameters are the options
//! of `experiments extract`, parsed by the command line's own parser ([`extract_args::Args`]) and
//! checked by the same [`extract_args::extraction`] (object parameters, settings, memory
//! estimate), so the page refuses what the command line refuses, with the same message. The
//! parameter list the page shows (help texts and defaults) is read from the same parser.
//!
//! Options that name files or change the process (`out`, `gif`, `mesh`, `threads`, ...) are not
//! accepted from the page.
//!
//! Sculpting uses the `edit` workload's terrain (`experiments/manifests/edit.toml`): the box
//! `-4,-1,-4 .. 4,1,4` with cubic cells, `size` cells along x and z and `size / 4` along y, meshed
//! in chunks of `chunk^3` cells ([`crate::edit::world_settings`]).
//!
//! The LOD mode uses the same box with a multiresolution world ([`rmt_terrain::lod`], as the
//! `lod` workload builds it: [`crate::lod::lod_settings`]): `size` finest cells along x and z
//! (`size / 4` along y), chunks of `chunk^3` cells at levels `0..=levels`, split while the viewer
//! is closer than `ratio` chunk edges; plain marching tetrahedra on the body-centred lattice.

use std::sync::Mutex;

use clap::{Args as _, Parser};
use rmt_extract::Extractor;
use rmt_mesh::Mesh;
use rmt_server::studio::{Backend, BackendError, Extracted, LodBuilt, Params};
use rmt_terrain::World;
use serde_json::{json, Map, Value};

use crate::config::{self, Extraction};
use crate::extract_args::{self, Args};
use crate::objects::{ObjectError, ObjectKind};

/// The chunk-tets cache of one studio LOD session (at most four live at once).
const STUDIO_TET_CACHE_BYTES: usize = 256 << 20;

/// `extract` options the page may set (object parameters come from [`ObjectKind::accepted`]).
pub const PAGE_OPTIONS: [&str; 9] = [
    "resolution",
    "bounds",
    "lattice",
    "method",
    "clustering",
    "collapse_threshold",
    "iso",
    "normals",
    "simplify",
];

/// LOD mode's defaults: finest cells along x and z, chunk edge, coarsest level, distance ratio.
pub const LOD_SIZE: usize = 128;
/// See [`LOD_SIZE`].
pub const LOD_CHUNK: usize = 8;
/// See [`LOD_SIZE`].
pub const LOD_LEVELS: usize = 2;
/// See [`LOD_SIZE`].
pub const LOD_RATIO: f64 = 1.5;

/// Object parameters the page may not set (they name files).
const FILE_PARAMETERS: [&str; 1] = ["mesh"];

/// The sculpt world's box (the `edit` workload's): 8 x 2 x 8 world units.
pub const SCULPT_BOUNDS: &str = "-4,-1,-4,4,1,4";
/// Default cells along x and z of the sculpt world (y gets a quarter).
pub const SCULPT_SIZE: usize = 128;
/// Default chunk edge of the sculpt world, in cells.
pub const SCULPT_CHUNK: usize = 16;

/// Choices of the options whose parser is a function (not listed by clap): the lists the
/// parsers accept ([`config::LATTICES`], ...).
fn choices(option: &str) -> Option<Vec<&'static str>> {
    Some(match option {
        "lattice" => config::names(&config::LATTICES, rmt_extract::Lattice::name),
        "method" => config::names(&config::METHODS, config::method_name),
        "clustering" => config::names(&config::CLUSTERINGS, rmt_extract::Clustering::name),
        "normals" => config::names(&config::NORMALS, config::Normals::name),
        _ => return None,
    })
}

#[derive(Parser)]
#[command(name = "extract")]
struct ExtractLine {
    #[command(flatten)]
    args: Args,
}

/// The `extract` parser's description of `option` (its id, e.g. `collapse_threshold`).
fn describe(command: &clap::Command, option: &str) -> Value {
    let arg = command.get_arguments().find(|a| a.get_id() == option);
    let help = arg
        .and_then(|a| a.get_help())
        .map(|h| h.to_string())
        .unwrap_or_default();
    let default = arg
        .and_then(|a| a.get_default_values().first())
        .map(|d| d.to_string_lossy().into_owned());
    let mut v = json!({ "name": option, "help": help, "default": default });
    if let (Some(c), Value::Object(m)) = (choices(option), &mut v) {
        m.insert("choices".into(), json!(c));
    }
    v
}

/// The studio's budget for one extraction, in sample slots of cubic cells
/// ([`extraction_work`]): about 300^3 cells, a few seconds on two cores. Past it the page gets a
/// 400 (the command line has no such budget, only the memory estimate).
pub const WORK_BUDGET: u64 = 64 << 20;

/// The work of an extraction for the studio's budget: its sample slots (the memory estimate's)
/// times the ratio of its longest cell edge to its shortest. Flat cells are what makes an
/// extraction slow for its size: at `resolution=100000,1,1` nearly every cell is crossed (2
/// million triangles from 1.5 million slots) and integrated clustering takes about 14 s, where a
/// 64^3 cube takes 0.07 s.
pub fn extraction_work(settings: &rmt_extract::ExtractSettings) -> f64 {
    let slots = crate::config::estimated_bytes(settings) / crate::config::BYTES_PER_SAMPLE_ESTIMATE;
    let h = settings.grid.spacing();
    let aspect = f64::from(h.max_element()) / f64::from(h.min_element());
    slots as f64
        * if aspect.is_finite() {
            aspect.max(1.0)
        } else {
            f64::INFINITY
        }
}

/// Refuses an extraction over [`WORK_BUDGET`], with what to change.
pub fn check_budget(e: &Extraction) -> Result<(), String> {
    let settings = e.settings(1);
    let work = extraction_work(&settings);
    // A box so large that its cells' size is not finite is the extraction's to refuse (its
    // field is not finite there), with that message.
    if work <= WORK_BUDGET as f64 || !settings.grid.spacing().is_finite() {
        return Ok(());
    }
    let h = settings.grid.spacing();
    Err(format!(
        "resolution {:?} is over the studio's budget for one extraction: {work:.3e} units of \
         work (sample slots times the cells' longest / shortest edge, {:.3e}), at most {:.3e}; \
         lower the resolution or make the cells closer to cubes (the command line has no such \
         budget)",
        e.resolution.cells(),
        f64::from(h.max_element()) / f64::from(h.min_element()),
        WORK_BUDGET as f64
    ))
}

/// The studio backend of the `experiments` binary.
pub struct StudioBackend {
    threads: usize,
    /// Extractors with their buffers, one taken per running extraction (extractions run side
    /// by side; the studio decides how many).
    extractors: Mutex<Vec<Extractor>>,
}

impl StudioBackend {
    /// Extractions on `threads` worker threads.
    pub fn new(threads: usize) -> Self {
        Self {
            threads: threads.max(1),
            extractors: Mutex::new(Vec::new()),
        }
    }

    /// Parses the page's parameters as `experiments extract` options (with `extra` options
    /// first) and checks them like the command line: the extraction and its thread count.
    pub fn parse(&self, params: &Params, extra: &[String]) -> Result<Extraction, String> {
        let command = Args::augment_args(clap::Command::new("extract"));
        let mut line = vec!["extract".to_string()];
        line.extend(extra.iter().cloned());
        for (key, value) in params {
            let id = key.replace('-', "_");
            let allowed = PAGE_OPTIONS.contains(&id.as_str())
                || id == "object"
                || all_object_parameters().contains(&id.as_str());
            if !allowed {
                return Err(
                    if command.get_arguments().any(|a| a.get_id() == id.as_str()) {
                        format!("`{key}` cannot be set from the studio")
                    } else {
                        format!("unknown parameter `{key}`")
                    },
                );
            }
            line.push(format!("--{}={value}", id.replace('_', "-")));
        }
        let parsed = ExtractLine::try_parse_from(&line).map_err(|e| clap_message(&e))?;
        let (e, _) = extract_args::extraction(&Args {
            threads: Some(self.threads),
            ..parsed.args
        })
        .map_err(|e| format!("{e:#}"))?;
        Ok(e)
    }

    /// Builds the field of `e` and extracts it (reusing an extractor's buffers): the mesh and
    /// the measurement `experiments extract --json` prints, plus a `studio` object with what the
    /// page shows. Errors the request caused (an object parameter out of range, a field that is
    /// not finite over the box, ...) are [`BackendError::Invalid`], as the command line refuses
    /// them; the others are [`BackendError::Failed`].
    pub fn run(&self, e: &Extraction) -> Result<(Mesh, Value), BackendError> {
        let settings = e.settings(self.threads);
        let field = e
            .object
            .build_for_spacing(
                &e.bounds,
                Some(e.settings(1).grid.spacing().max_element()),
                &[],
            )
            .map_err(|err| {
                let message = format!("building object {}: {err}", e.object.kind);
                match err {
                    // The data files the server reads: not the request's fault.
                    ObjectError::MissingMesh { .. } | ObjectError::MeshIo(_) => {
                        BackendError::Failed(message)
                    }
                    _ => BackendError::Invalid(message),
                }
            })?;
        let mut mesh = Mesh::default();
        let mut extractor = self
            .extractors
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .pop()
            .unwrap_or_default();
        let stats = extractor.extract(field.as_ref(), &settings, &mut mesh);
        self.extractors
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .push(extractor);
        let mut stats = stats.map_err(|err| {
            let message = format!("extracting {}: {err}", e.object.kind);
            match err {
                rmt_extract::ExtractError::ThreadPool { .. } => BackendError::Failed(message),
                _ => BackendError::Invalid(message),
            }
        })?;
        // The finish steps (a simplification to a budget), as `extract` runs them; no
        // rendering cost (it would take longer than most extractions).
        let finish = crate::finish::Finisher::new(e, field.as_ref(), self.threads)
            .run(&mut mesh, &mut stats)
            .map_err(|err| BackendError::Failed(format!("{err:#}")))?;
        let measured = crate::measured::measure(
            &mesh,
            &stats,
            &finish,
            Some(field.as_ref()),
            &settings,
            None,
        )
        .map_err(|err| BackendError::Failed(format!("{err:#}")))?;
        let m = &measured.measurement;
        let mut out: Map<String, Value> = config::config_json(e, self.threads);
        out.extend(
            measured
                .json()
                .map_err(|e| BackendError::Failed(e.to_string()))?,
        );
        let (s, v, q) = (&m.stats, &m.validation, &m.quality);
        let ms = |t: f64| t * 1e3;
        out.insert(
            "studio".into(),
            json!({
                "triangles": mesh.triangle_count(),
                "vertices": mesh.vertex_count(),
                "stage_ms": {
                    "total": ms(s.t_total_s),
                    "sampling": ms(s.t_sampling_s),
                    "vertex": ms(s.t_vertex_s),
                    "geometry": ms(s.t_geometry_s),
                    "normals": ms(s.t_normals_s),
                    "simplify": ms(measured.finish.t_simplify_s),
                },
                "ar_mean": q.ar_mean,
                "ar_p95": q.ar_p95,
                "fidelity_mean_h": m.fidelity_mean_h,
                "fidelity_max_h": m.fidelity_max_h,
                "closed": v.boundary_edges_interior == 0,
                "manifold": v.non_manifold_edges == 0 && v.non_manifold_vertices == 0,
                "euler": v.euler,
                "components": v.components,
            }),
        );
        Ok((mesh, Value::Object(out)))
    }
}

/// Every object parameter some object accepts, except those naming files.
fn all_object_parameters() -> Vec<&'static str> {
    let mut out: Vec<&'static str> = Vec::new();
    for name in ObjectKind::names() {
        if let Ok(kind) = name.parse::<ObjectKind>() {
            for &p in kind.accepted() {
                if !out.contains(&p) && !FILE_PARAMETERS.contains(&p) {
                    out.push(p);
                }
            }
        }
    }
    out
}

/// A clap error as one line, without the usage and help hints.
fn clap_message(e: &clap::Error) -> String {
    let text = e.to_string();
    let first = text.lines().next().unwrap_or("invalid parameters");
    first.trim_start_matches("error: ").trim().to_string()
}

/// Takes `name` out of `params` and parses it as a positive count within `range`.
fn take_count(
    params: &mut Params,
    name: &str,
    default: usize,
    range: std::ops::RangeInclusive<usize>,
) -> Result<usize, String> {
    let Some(at) = params.iter().position(|(k, _)| k == name) else {
        return Ok(default);
    };
    let (_, v) = params.remove(at);
    let n: usize = v
        .trim()
        .parse()
        .map_err(|_| format!("{name} must be a whole number, got `{v}`"))?;
    if !range.contains(&n) {
        return Err(format!(
            "{name} must be {} to {}, got {n}",
            range.start(),
            range.end()
        ));
    }
    Ok(n)
}

impl Backend for StudioBackend {
    fn schema(&self) -> Value {
        let command = Args::augment_args(clap::Command::new("extract"));
        let objects = |names: &[&str]| -> Vec<Value> {
            names
                .iter()
                .filter_map(|n| n.parse::<ObjectKind>().ok())
                .map(|k| {
                    json!({
                        "name": k.name(),
                        "parameters": k.accepted().iter()
                            .filter(|p| !FILE_PARAMETERS.contains(*p))
                            .map(|p| describe(&command, p))
                            .collect::<Vec<_>>(),
                    })
                })
                .collect()
        };
        let parameters: Vec<Value> = PAGE_OPTIONS.iter().map(|o| describe(&command, o)).collect();
        let default_of = |o: &str| describe(&command, o)["default"].clone();
        let mut defaults = Map::new();
        defaults.insert("object".into(), default_of("object"));
        for o in PAGE_OPTIONS {
            defaults.insert(o.into(), default_of(o));
        }
        let sculpt_parameters: Vec<Value> = [
            json!({"name": "size", "help": "cells along x and z of the 8 x 2 x 8 box (y gets a quarter); a multiple of 4, 16 to 512", "default": SCULPT_SIZE.to_string()}),
            json!({"name": "chunk", "help": "chunk edge in cells (re-meshed as a unit), 4 to 128", "default": SCULPT_CHUNK.to_string()}),
        ]
        .into_iter()
        .chain(
            ["method", "lattice", "clustering", "collapse_threshold", "iso"]
                .iter()
                .map(|o| describe(&command, o)),
        )
        .collect();
        json!({
            "objects": objects(&ObjectKind::names()),
            "parameters": parameters,
            "defaults": defaults,
            "compare_defaults": { "clustering": "none" },
            "threads": self.threads,
            "sculpt": {
                "objects": objects(&["terrain", "caves"]),
                "parameters": sculpt_parameters,
                "defaults": { "object": "terrain", "size": SCULPT_SIZE.to_string(), "chunk": SCULPT_CHUNK.to_string() },
            },
            "lod": {
                "objects": objects(&["terrain", "caves"]),
                "parameters": [
                    {"name": "size", "help": "finest cells along x and z of the 8 x 2 x 8 box (y gets a quarter, which chunk x 2^levels must divide), 16 to 256", "default": LOD_SIZE.to_string()},
                    {"name": "chunk", "help": "chunk edge in cells at every level, 4 to 32", "default": LOD_CHUNK.to_string()},
                    {"name": "levels", "help": "the coarsest level (0 finest; level l has cells of h 2^l), 0 to 4", "default": LOD_LEVELS.to_string()},
                    {"name": "ratio", "help": "a chunk is split while the viewer is closer than ratio x its edge, 0.5 to 4", "default": LOD_RATIO.to_string()},
                    {"name": "clustering", "help": "none, or integrated: RMT's groups merged inside each chunk where the exact check allows it (seams stay plain)", "choices": ["none", "integrated"], "default": "none"},
                ],
                "defaults": { "object": "terrain", "size": LOD_SIZE.to_string(), "chunk": LOD_CHUNK.to_string(), "levels": LOD_LEVELS.to_string(), "ratio": LOD_RATIO.to_string(), "clustering": "none" },
            },
        })
    }

    fn extract(&self, params: &Params) -> Result<Extracted, BackendError> {
        let e = self.parse(params, &[]).map_err(BackendError::Invalid)?;
        check_budget(&e).map_err(BackendError::Invalid)?;
        let (mesh, summary) = self.run(&e)?;
        Ok(Extracted { mesh, summary })
    }

    fn world(&self, params: &Params) -> Result<(World, Value), BackendError> {
        let invalid = BackendError::Invalid;
        let mut params = params.clone();
        let size = take_count(&mut params, "size", SCULPT_SIZE, 16..=512).map_err(invalid)?;
        if size % 4 != 0 {
            return Err(invalid(format!("size must be a multiple of 4, got {size}")));
        }
        let chunk = take_count(&mut params, "chunk", SCULPT_CHUNK, 4..=128).map_err(invalid)?;
        for (k, v) in &params {
            match k.as_str() {
                "resolution" | "bounds" | "normals" => {
                    return Err(invalid(format!(
                        "`{k}` is fixed in sculpt mode (the edit workload's box; set size instead)"
                    )))
                }
                "object" if v != "terrain" && v != "caves" => {
                    return Err(invalid(format!(
                        "sculpt mode takes object terrain or caves, got `{v}`"
                    )))
                }
                _ => {}
            }
        }
        if !params.iter().any(|(k, _)| k == "object") {
            params.insert(0, ("object".into(), "terrain".into()));
        }
        let extra = [
            format!("--resolution={size},{},{size}", size / 4),
            format!("--bounds={SCULPT_BOUNDS}"),
        ];
        let e = self.parse(&params, &extra).map_err(invalid)?;
        let ws = crate::edit::world_settings(&e, chunk, self.threads)
            .map_err(|err| invalid(format!("{err:#}")))?;
        let spacing = e.settings(1).grid.spacing().max_element();
        let field = e
            .object
            .build_for_spacing(&e.bounds, Some(spacing), &[])
            .map_err(|err| invalid(format!("building object {}: {err}", e.object.kind)))?;
        let world = World::new(field.as_ref(), ws).map_err(|err| invalid(err.to_string()))?;
        let [nx, ny, nz] = e.resolution.cells();
        let description = json!({
            "object": e.object.kind.name(),
            "cells": [nx, ny, nz],
            "chunk": chunk,
            "method": crate::config::method_name(e.method),
            "lattice": crate::config::lattice_name(e.method, e.lattice),
            "clustering": e.clustering.name(),
            "label": format!(
                "{} {nx}x{ny}x{nz}, chunks {chunk}^3, {} {} {}",
                e.object.kind.name(),
                crate::config::method_name(e.method),
                crate::config::lattice_name(e.method, e.lattice),
                e.clustering.name()
            ),
        });
        Ok((world, description))
    }

    fn lod_world(&self, params: &Params) -> Result<LodBuilt, BackendError> {
        let invalid = BackendError::Invalid;
        let mut params = params.clone();
        let size = take_count(&mut params, "size", LOD_SIZE, 16..=256).map_err(invalid)?;
        let chunk = take_count(&mut params, "chunk", LOD_CHUNK, 4..=32).map_err(invalid)?;
        let levels = take_count(&mut params, "levels", LOD_LEVELS, 0..=4).map_err(invalid)?;
        let ratio = match params.iter().position(|(k, _)| k == "ratio") {
            None => LOD_RATIO,
            Some(at) => {
                let (_, v) = params.remove(at);
                match v.trim().parse::<f64>() {
                    Ok(r) if (0.5..=4.0).contains(&r) => r,
                    _ => {
                        return Err(invalid(format!(
                            "ratio must be a number from 0.5 to 4, got `{v}`"
                        )))
                    }
                }
            }
        };
        let side = chunk << levels;
        if size % 4 != 0 || (size / 4) % side != 0 {
            return Err(invalid(format!(
                "size {size} gives {} cells along y, which chunks of {chunk} cells at {levels} \
                 levels do not tile: size / 4 must be a multiple of chunk x 2^levels = {side}",
                size / 4
            )));
        }
        for (k, v) in &params {
            match k.as_str() {
                "object" if v != "terrain" && v != "caves" => {
                    return Err(invalid(format!(
                        "LOD mode takes object terrain or caves, got `{v}`"
                    )))
                }
                "object" => {}
                "clustering" if v != "none" && v != "integrated" => {
                    return Err(invalid(format!(
                        "LOD mode clusters with integrated or none, got `{v}`"
                    )))
                }
                "clustering" => {}
                other if PAGE_OPTIONS.contains(&other.replace('-', "_").as_str()) => {
                    return Err(invalid(format!(
                        "`{k}` is fixed in LOD mode (marching tetrahedra on the \
                         body-centred lattice over the edit workload's box; set size, chunk, \
                         levels, ratio and clustering instead)"
                    )))
                }
                _ => {}
            }
        }
        if !params.iter().any(|(k, _)| k == "object") {
            params.insert(0, ("object".into(), "terrain".into()));
        }
        let clustering = params
            .iter()
            .find(|(k, _)| k == "clustering")
            .map_or("none", |(_, v)| v.as_str())
            .to_string();
        params.retain(|(k, _)| k != "clustering");
        let extra = [
            format!("--resolution={size},{},{size}", size / 4),
            format!("--bounds={SCULPT_BOUNDS}"),
            "--method=mt".to_string(),
            "--lattice=bcdl".to_string(),
            format!("--clustering={clustering}"),
        ];
        let e = self.parse(&params, &extra).map_err(invalid)?;
        let plan = crate::manifest::LodPlan {
            levels: levels as u8,
            chunk: chunk as u32,
            ratio,
            steps: 0,
            path: None,
            validate_every: 0,
            validate_max_chunks: 0,
            finest_exact_chunks: 0,
            tet_cache_mb: STUDIO_TET_CACHE_BYTES >> 20,
            morph: 0.0,
            edits: Vec::new(),
        };
        let settings = crate::lod::lod_settings(&e, &plan, self.threads)
            .map_err(|err| invalid(format!("{err:#}")))?;
        let spacing = settings.frame.h;
        let field = e
            .object
            .build_for_spacing(&e.bounds, Some(spacing), &[])
            .map_err(|err| invalid(format!("building object {}: {err}", e.object.kind)))?;
        let mut world = rmt_terrain::lod::LodWorld::new(field, settings)
            .map_err(|err| invalid(err.to_string()))?;
        // Up to four sessions live at once: a quarter of the runner's budget each.
        world.set_tet_cache_bytes(plan.tet_cache_mb << 20);
        let (min, max) = (e.bounds.min, e.bounds.max);
        let centre = (min + max) * 0.5;
        // At the top of the box, a quarter of the way in from its near corner.
        let viewer = glam::Vec3::new(
            centre.x + 0.75 * (min.x - centre.x),
            max.y,
            centre.z + 0.75 * (min.z - centre.z),
        );
        let [nx, ny, nz] = e.resolution.cells();
        let description = json!({
            "object": e.object.kind.name(),
            "cells": [nx, ny, nz],
            "chunk": chunk,
            "levels": levels,
            "ratio": ratio,
            "clustering": clustering,
            "h": spacing,
            "bounds": [min.x, min.y, min.z, max.x, max.y, max.z],
            "label": format!(
                "{} {nx}x{ny}x{nz}, chunks {chunk}^3, levels 0-{levels}, ratio {ratio}, \
                 clustering {clustering}",
                e.object.kind.name()
            ),
        });
        Ok(LodBuilt {
            world,
            description,
            viewer,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn params(pairs: &[(&str, &str)]) -> Params {
        pairs
            .iter()
            .map(|(k, v)| (k.to_string(), v.to_string()))
            .collect()
    }

    #[test]
    fn page_parameters_parse_like_the_command_line() {
        let b = StudioBackend::new(1);
        let e = b
            .parse(
                &params(&[
                    ("object", "torus"),
                    ("minor", "0.2"),
                    ("resolution", "12,13,14"),
                    ("iso", "-0.05"),
                    ("bounds", "-1,-1,-1,1,1,1"),
                    ("collapse_threshold", "0.3"),
                ]),
                &[],
            )
            .unwrap();
        assert_eq!(e.resolution.cells(), [12, 13, 14]);
        assert_eq!(e.iso, -0.05);
        assert_eq!(e.collapse_threshold, 0.3);
        assert_eq!(e.object.params.minor, Some(0.2));
    }

    #[test]
    fn the_page_gets_the_command_lines_errors_and_no_file_options() {
        let b = StudioBackend::new(1);
        let err = |p: &[(&str, &str)]| b.parse(&params(p), &[]).unwrap_err();
        assert!(err(&[("object", "teapot")]).contains("teapot"));
        assert!(err(&[("object", "gyroid"), ("radius", "2")]).contains("radius"));
        assert!(err(&[("resolution", "0")]).contains("resolution"));
        assert!(err(&[("lattice", "hex")]).contains("hex"));
        // The same message as `experiments extract --resolution 20000`.
        let cli = extract_args::extraction(
            &ExtractLine::parse_from(["extract", "--resolution=20000"]).args,
        )
        .unwrap_err();
        assert_eq!(err(&[("resolution", "20000")]), format!("{cli:#}"));
        assert!(err(&[("out", "/tmp/x.ply")]).contains("cannot be set"));
        assert!(err(&[("mesh", "/etc/passwd")]).contains("cannot be set"));
        assert!(err(&[("threads", "64")]).contains("cannot be set"));
        assert!(err(&[("colour", "red")]).contains("unknown parameter"));
        assert!(err(&[("iso", "1"), ("iso", "2")]).contains("iso"));
    }

    #[test]
    fn schema_lists_every_extract_option_with_the_command_lines_defaults() {
        let s = StudioBackend::new(1).schema();
        let names: Vec<&str> = s["parameters"]
            .as_array()
            .unwrap()
            .iter()
            .map(|p| p["name"].as_str().unwrap())
            .collect();
        assert_eq!(names, PAGE_OPTIONS);
        assert_eq!(s["defaults"]["resolution"], "50");
        assert_eq!(s["defaults"]["object"], "sphere");
        assert_eq!(
            s["objects"].as_array().unwrap().len(),
            ObjectKind::names().len()
        );
        let bunny = s["objects"]
            .as_array()
            .unwrap()
            .iter()
            .find(|o| o["name"] == "bunny")
            .unwrap();
        assert!(!bunny["parameters"].to_string().contains("\"mesh\""));
    }
}
