//! [`Manifest::plan`] in named steps, in the order errors are reported: [`check_options`] (name,
//! repetitions, threads, data paths), [`check_objects`], [`base_configurations`] (the matrix and
//! the explicit list), [`sweep_values`], [`check_seeds`], [`expand`] (objects x lattices x
//! clusterings x sweeps, each configuration checked, and [`plan_seeds`] for a seed study), and
//! [`plan_edits`].

use std::collections::HashSet;
use std::path::{Path, PathBuf};

use rmt_extract::{Clustering, Lattice, Method};

use super::{
    base_id, finish_suffix, safe_name, shading_suffix, Configuration, EditPlan, LodEdit,
    LodEditEntry, LodPlan, Manifest, ManifestError, Matrix, Overrides, Plan, SeedOf, SeedRange,
    Shading,
};
use crate::config::{self, Extraction};
use crate::objects::{self, Bounds, ObjectKind, ObjectSpec, Resolution};
use crate::simplify::Simplify;

/// Builds the errors of one manifest.
struct Invalid<'a>(&'a Path);

impl Invalid<'_> {
    /// The error at `key` (`objects[1] (sphere)`, `configuration as_bi`, ...).
    fn at(&self, key: &str, message: impl Into<String>) -> ManifestError {
        ManifestError::Invalid {
            path: self.0.to_path_buf(),
            key: key.to_string(),
            message: message.into(),
        }
    }
}

/// The run options of a manifest after the command line's overrides.
struct Options {
    repetitions: usize,
    warmup: usize,
    threads: usize,
    collapse_default: f32,
    search: Vec<PathBuf>,
    paper_benchmark: Option<PathBuf>,
}

/// One `[[objects]]` entry, checked.
struct PlannedObject {
    name: String,
    code: String,
    spec: ObjectSpec,
    resolution: Resolution,
    bounds: Bounds,
    elevation_deg: Option<f32>,
}

/// A configuration before sweeps: its object, id, method, lattice, clustering, its own
/// resolution, threshold and isovalue when it sets them, and where the manifest defines it.
struct BaseConfiguration {
    obj: usize,
    id: String,
    method: Method,
    lattice: Lattice,
    clustering: Clustering,
    resolution: Option<Resolution>,
    threshold: Option<f32>,
    iso: Option<f32>,
    shading: Shading,
    simplify: Option<Simplify>,
    vertex_cache: bool,
    key: String,
}

/// The sweep's values (`None`: the configuration's own) and the variables swept.
struct SweepValues {
    resolutions: Vec<Option<Resolution>>,
    thresholds: Vec<Option<f32>>,
    variables: Vec<String>,
}

impl Manifest {
    /// Expands into a checked [`Plan`]. `path` names the manifest in errors; `base` is the folder
    /// relative data paths are searched from (before the workspace root).
    pub fn plan(
        &self,
        path: &Path,
        base: &Path,
        overrides: &Overrides,
    ) -> Result<Plan, ManifestError> {
        let invalid = Invalid(path);
        let options = check_options(self, base, overrides, &invalid)?;
        let objects = check_objects(self, &invalid)?;
        let bases = base_configurations(self, &objects, &invalid)?;
        let sweep = sweep_values(self, &invalid)?;
        check_seeds(self, &objects, &bases, &invalid)?;
        let configurations = expand(self, &options, &objects, &bases, &sweep, &invalid)?;
        let edit = plan_edits(self, &configurations, &invalid)?;
        let lod = plan_lod(self, &configurations, &invalid)?;
        Ok(Plan {
            name: self.name.clone(),
            repetitions: options.repetitions,
            warmup: options.warmup,
            threads: options.threads,
            save_meshes: overrides.save_meshes.unwrap_or(self.save_meshes),
            render_cost: self.render_cost,
            output: self
                .output
                .clone()
                .unwrap_or_else(|| PathBuf::from("results")),
            paper_benchmark: options.paper_benchmark,
            search: options.search,
            sweep_variables: sweep.variables,
            configurations,
            edit,
            lod,
        })
    }
}

/// Checks the run name and the run options (with the command line's overrides), and resolves
/// the dissertation's table.
fn check_options(
    m: &Manifest,
    base: &Path,
    overrides: &Overrides,
    invalid: &Invalid,
) -> Result<Options, ManifestError> {
    if !safe_name(&m.name) {
        return Err(invalid.at(
            "name",
            format!(
                "`{}` must be non-empty letters, digits, '-', '_' or '.'",
                m.name
            ),
        ));
    }
    let repetitions = overrides.repetitions.unwrap_or(m.repetitions);
    if repetitions == 0 {
        return Err(invalid.at("repetitions", "must be at least 1"));
    }
    let warmup = overrides.warmup.unwrap_or(m.warmup);
    let threads = overrides
        .threads
        .or(m.threads)
        .unwrap_or_else(config::default_threads);
    if !(1..=1024).contains(&threads) {
        return Err(invalid.at("threads", format!("must be 1 to 1024, got {threads}")));
    }
    let collapse_default = m
        .collapse_threshold
        .unwrap_or_else(config::default_collapse_threshold);
    let search = vec![base.to_path_buf()];
    let paper_benchmark = match &m.paper_benchmark {
        Some(p) => Some(
            objects::resolve_data_path(p, &search)
                .map_err(|e| invalid.at("paper_benchmark", e.to_string()))?,
        ),
        None => None,
    };
    Ok(Options {
        repetitions,
        warmup,
        threads,
        collapse_default,
        search,
        paper_benchmark,
    })
}

/// Checks every `[[objects]]` entry: unique safe names, a kind, parameters the kind takes (the
/// manifest's seed for seeded kinds that set none), a safe id code.
fn check_objects(m: &Manifest, invalid: &Invalid) -> Result<Vec<PlannedObject>, ManifestError> {
    if m.objects.is_empty() {
        return Err(invalid.at("objects", "the manifest defines no [[objects]]"));
    }
    let mut objs: Vec<PlannedObject> = Vec::new();
    for (i, o) in m.objects.iter().enumerate() {
        let key = format!("objects[{i}] ({})", o.name);
        if !safe_name(&o.name) {
            return Err(invalid.at(&key, "name must be letters, digits, '-', '_' or '.'"));
        }
        if objs.iter().any(|x| x.name == o.name) {
            return Err(invalid.at(&key, format!("object name `{}` is used twice", o.name)));
        }
        let kind = match o.kind {
            Some(k) => k,
            None => o.name.parse::<ObjectKind>().map_err(|e| {
                invalid.at(&key, format!("{e}; set `kind` when the name is not a kind"))
            })?,
        };
        let mut params = o.params();
        if kind.accepted().contains(&"seed") && params.seed.is_none() {
            params.seed = m.seed;
        }
        let spec = ObjectSpec::new(kind, params).map_err(|e| invalid.at(&key, e.to_string()))?;
        let code = o.code.clone().unwrap_or_else(|| kind.code().to_string());
        if !safe_name(&code) {
            return Err(invalid.at(&key, format!("code `{code}` must be letters or digits")));
        }
        if let Some(e) = o.elevation_deg {
            if !(-89.0..=89.0).contains(&e) {
                return Err(invalid.at(
                    &key,
                    format!("elevation_deg must be -89 to 89 degrees, got {e}"),
                ));
            }
        }
        objs.push(PlannedObject {
            name: o.name.clone(),
            code,
            spec,
            resolution: o.resolution.map(|c| c.0).unwrap_or(Resolution::Cube(50)),
            bounds: o.bounds.unwrap_or_default(),
            elevation_deg: o.elevation_deg,
        });
    }
    Ok(objs)
}

/// The index of the object named `name` (`key` says where the manifest names it).
fn find_object(
    objs: &[PlannedObject],
    name: &str,
    key: &str,
    invalid: &Invalid,
) -> Result<usize, ManifestError> {
    objs.iter().position(|o| o.name == name).ok_or_else(|| {
        let names: Vec<&str> = objs.iter().map(|o| o.name.as_str()).collect();
        invalid.at(
            key,
            format!("no object named `{name}` (defined: {})", names.join(", ")),
        )
    })
}

/// The configurations before sweeps: the matrix's, then the explicit list's.
fn base_configurations(
    m: &Manifest,
    objs: &[PlannedObject],
    invalid: &Invalid,
) -> Result<Vec<BaseConfiguration>, ManifestError> {
    let mut bases = Vec::new();
    for (i, matrix) in m.matrix.iter().enumerate() {
        let key = if m.matrix.len() == 1 {
            "matrix".to_string()
        } else {
            format!("matrix[{i}]")
        };
        bases.extend(matrix_configurations(matrix, objs, &key, invalid)?);
    }
    for (i, c) in m.configurations.iter().enumerate() {
        let key = format!("configurations[{i}]");
        let obj = find_object(objs, &c.object, &key, invalid)?;
        let method = c.method.unwrap_or(Method::Mt);
        let lattice = match method {
            Method::Mc | Method::SurfaceNets => Lattice::Simple,
            Method::Mt => c.lattice.unwrap_or(Lattice::BodyCentred),
        };
        let clustering = c.clustering.unwrap_or(Clustering::None);
        let shading = c.shading.unwrap_or_default();
        let simplify = c.simplify.and_then(|s| s.0);
        let vertex_cache = c.vertex_cache.unwrap_or(false);
        let id = match &c.id {
            Some(id) => id.clone(),
            None => {
                base_id(&objs[obj].code, method, lattice, clustering)
                    + &finish_suffix(simplify.as_ref(), vertex_cache)
                    + shading_suffix(shading)
            }
        };
        bases.push(BaseConfiguration {
            obj,
            id,
            method,
            lattice,
            clustering,
            resolution: c.resolution.map(|r| r.0),
            threshold: c.collapse_threshold,
            iso: c.iso,
            shading,
            simplify,
            vertex_cache,
            key,
        });
    }
    if bases.is_empty() {
        return Err(invalid.at(
            "configurations",
            "no configurations: add a [matrix] or [[configurations]]",
        ));
    }
    Ok(bases)
}

/// The matrix's configurations: objects x methods x lattices x clusterings (marching cubes
/// gives one per object), every list non-empty.
fn matrix_configurations(
    matrix: &Matrix,
    objs: &[PlannedObject],
    at: &str,
    invalid: &Invalid,
) -> Result<Vec<BaseConfiguration>, ManifestError> {
    let names: Vec<String> = match &matrix.objects {
        Some(list) => list.clone(),
        None => objs.iter().map(|o| o.name.clone()).collect(),
    };
    for (key, empty) in [
        ("objects", names.is_empty()),
        ("methods", matrix.methods.is_empty()),
        ("lattices", matrix.lattices.is_empty()),
        ("clustering", matrix.clustering.is_empty()),
        ("shading", matrix.shading.is_empty()),
        ("simplify", matrix.simplify.is_empty()),
        ("vertex_cache", matrix.vertex_cache.is_empty()),
    ] {
        if empty {
            return Err(invalid.at(&format!("{at}.{key}"), "the list is empty"));
        }
    }
    // Finish steps, crossed: every simplification with every vertex-cache setting.
    let finishes: Vec<(Option<Simplify>, bool)> = matrix
        .simplify
        .iter()
        .flat_map(|s| matrix.vertex_cache.iter().map(move |&v| (s.0, v)))
        .collect();
    let mut bases = Vec::new();
    for name in &names {
        let obj = find_object(objs, name, &format!("{at}.objects"), invalid)?;
        for &method in &matrix.methods {
            // Marching cubes and surface nets have no lattice choice and no clustering: one
            // configuration.
            let combos: Vec<(Lattice, Clustering)> = match method {
                Method::Mc | Method::SurfaceNets => vec![(Lattice::Simple, Clustering::None)],
                Method::Mt => matrix
                    .lattices
                    .iter()
                    .flat_map(|&l| matrix.clustering.iter().map(move |&c| (l, c)))
                    .collect(),
            };
            for (lattice, clustering) in combos {
                for &(simplify, vertex_cache) in &finishes {
                    for &shading in &matrix.shading {
                        bases.push(BaseConfiguration {
                            obj,
                            id: base_id(&objs[obj].code, method, lattice, clustering)
                                + &finish_suffix(simplify.as_ref(), vertex_cache)
                                + shading_suffix(shading),
                            method,
                            lattice,
                            clustering,
                            resolution: None,
                            threshold: None,
                            iso: None,
                            shading,
                            simplify,
                            vertex_cache,
                            key: at.into(),
                        });
                    }
                }
            }
        }
    }
    Ok(bases)
}

/// The `[sweep]` lists (each non-empty when given).
fn sweep_values(m: &Manifest, invalid: &Invalid) -> Result<SweepValues, ManifestError> {
    let sweep = m.sweep.clone().unwrap_or_default();
    let mut variables = Vec::new();
    let resolutions: Vec<Option<Resolution>> = match &sweep.resolution {
        Some(list) if list.is_empty() => {
            return Err(invalid.at("sweep.resolution", "the list is empty"))
        }
        Some(list) => {
            variables.push("resolution".to_string());
            list.iter().map(|c| Some(c.0)).collect()
        }
        None => vec![None],
    };
    let thresholds: Vec<Option<f32>> = match &sweep.collapse_threshold {
        Some(list) if list.is_empty() => {
            return Err(invalid.at("sweep.collapse_threshold", "the list is empty"))
        }
        Some(list) => {
            variables.push("collapse_threshold".to_string());
            list.iter().map(|&t| Some(t)).collect()
        }
        None => vec![None],
    };
    Ok(SweepValues {
        resolutions,
        thresholds,
        variables,
    })
}

/// Checks a seed study's range and that some configuration uses a seeded object.
fn check_seeds(
    m: &Manifest,
    objs: &[PlannedObject],
    bases: &[BaseConfiguration],
    invalid: &Invalid,
) -> Result<(), ManifestError> {
    let Some(range) = m.seeds else {
        return Ok(());
    };
    if !(1..=100_000).contains(&range.count) {
        return Err(invalid.at(
            "seeds.count",
            format!("must be 1 to 100000, got {}", range.count),
        ));
    }
    if range.from.checked_add(range.count - 1).is_none() {
        return Err(invalid.at(
            "seeds",
            format!(
                "seeds {} .. {} + {} leave the 32-bit range",
                range.from, range.from, range.count
            ),
        ));
    }
    if !bases
        .iter()
        .any(|b| objs[b.obj].spec.kind.accepted().contains(&"seed"))
    {
        return Err(invalid.at(
            "seeds",
            "no configuration uses a seeded object (asteroid, terrain, caves, random)",
        ));
    }
    Ok(())
}

/// Every base configuration for every sweep value (ids get `_r<cells>`, `_t<threshold>`), each
/// checked, ids unique; in a seed study, configurations of seeded objects once per seed.
fn expand(
    m: &Manifest,
    options: &Options,
    objs: &[PlannedObject],
    bases: &[BaseConfiguration],
    sweep: &SweepValues,
    invalid: &Invalid,
) -> Result<Vec<Configuration>, ManifestError> {
    let mut configurations = Vec::new();
    let mut ids = HashSet::new();
    for b in bases {
        let o = &objs[b.obj];
        for r in &sweep.resolutions {
            for t in &sweep.thresholds {
                let mut id = b.id.clone();
                if let Some(r) = r {
                    id += &format!("_r{}", r.label());
                }
                if let Some(t) = t {
                    id += &format!("_t{t}");
                }
                if !safe_name(&id) {
                    return Err(invalid.at(
                        &b.key,
                        format!("id `{id}` must be letters, digits, '-', '_' or '.'"),
                    ));
                }
                if !ids.insert(id.clone()) {
                    return Err(
                        invalid.at(&b.key, format!("configuration id `{id}` is used twice"))
                    );
                }
                let extraction = Extraction {
                    object: o.spec.clone(),
                    bounds: o.bounds,
                    resolution: r.or(b.resolution).unwrap_or(o.resolution),
                    method: b.method,
                    lattice: b.lattice,
                    clustering: b.clustering,
                    collapse_threshold: t.or(b.threshold).unwrap_or(options.collapse_default),
                    iso: b.iso.or(m.iso).unwrap_or(0.0),
                    normals: m.normals.unwrap_or_default(),
                    simplify: b.simplify,
                    vertex_cache: b.vertex_cache,
                };
                // A multiresolution world never samples the whole grid at its finest level:
                // its shape is checked by `plan_lod` instead of the dense extraction's limits.
                if m.workload.as_deref() != Some("lod") {
                    extraction
                        .check(options.threads)
                        .map_err(|e| invalid.at(&format!("configuration {id}"), e))?;
                }
                let configuration = Configuration {
                    id,
                    object: o.name.clone(),
                    extraction,
                    seed_of: None,
                    shading: b.shading,
                    elevation_deg: o.elevation_deg,
                };
                let seeded = o.spec.kind.accepted().contains(&"seed");
                match m.seeds {
                    Some(range) if seeded => {
                        plan_seeds(configuration, range, &mut ids, &mut configurations).map_err(
                            |sid| {
                                invalid
                                    .at(&b.key, format!("configuration id `{sid}` is used twice"))
                            },
                        )?
                    }
                    _ => configurations.push(configuration),
                }
            }
        }
    }
    Ok(configurations)
}

/// A seed study's configurations of `c` (a configuration of a seeded object): one per seed of
/// `range`, id `<id>_s<seed>`, pushed to `out`. Fails with the id when it is taken.
fn plan_seeds(
    c: Configuration,
    range: SeedRange,
    ids: &mut HashSet<String>,
    out: &mut Vec<Configuration>,
) -> Result<(), String> {
    for seed in range.from..=range.from + (range.count - 1) {
        let mut e = c.extraction.clone();
        e.object.params.seed = Some(seed);
        let sid = format!("{}_s{seed}", c.id);
        if !ids.insert(sid.clone()) {
            return Err(sid);
        }
        out.push(Configuration {
            id: sid,
            object: c.object.clone(),
            extraction: e,
            seed_of: Some(SeedOf {
                base_id: c.id.clone(),
                seed,
            }),
            shading: c.shading,
            elevation_deg: c.elevation_deg,
        });
    }
    Ok(())
}

/// The `edit` workload of `workload = "edit"` (its `[edit]` table checked, defaults filled in;
/// meshopt refused), or None for repeated extractions.
fn plan_edits(
    m: &Manifest,
    configurations: &[Configuration],
    invalid: &Invalid,
) -> Result<Option<EditPlan>, ManifestError> {
    match (m.workload.as_deref(), &m.edit) {
        (None | Some("extract") | Some("lod"), None) => Ok(None),
        (Some("lod"), Some(_)) => Err(invalid.at(
            "edit",
            "an [edit] table needs `workload = \"edit\"`, not \"lod\"",
        )),
        (None | Some("extract"), Some(_)) => {
            Err(invalid.at("edit", "an [edit] table needs `workload = \"edit\"`"))
        }
        (Some("edit"), entry) => {
            let e = entry.clone().unwrap_or_default();
            let plan = EditPlan {
                chunk: e.chunk.unwrap_or(32),
                strokes: e.strokes.unwrap_or(200),
                warmup: e.warmup.unwrap_or(20),
                seed: e.seed.unwrap_or(1),
                radius: e.radius.unwrap_or(4.0),
            };
            if !(1..=4096).contains(&plan.chunk) {
                return Err(invalid.at(
                    "edit.chunk",
                    format!("must be 1 to 4096 cells, got {}", plan.chunk),
                ));
            }
            if plan.strokes == 0 {
                return Err(invalid.at("edit.strokes", "must be at least 1"));
            }
            if !(plan.radius.is_finite() && plan.radius > 0.0) {
                return Err(invalid.at(
                    "edit.radius",
                    format!("must be finite and > 0 (cells), got {}", plan.radius),
                ));
            }
            if let Some(c) = configurations
                .iter()
                .find(|c| c.extraction.simplify.is_some() || c.extraction.vertex_cache)
            {
                return Err(invalid.at(
                    &format!("configuration {}", c.id),
                    "the edit workload cannot simplify or reorder after extraction (the finish \
                     steps work on one whole mesh, not on chunks)",
                ));
            }
            if let Some(c) = configurations.iter().find(|c| {
                c.extraction.method == Method::Mt && c.extraction.clustering == Clustering::Meshopt
            }) {
                return Err(invalid.at(
                    &format!("configuration {}", c.id),
                    "the edit workload cannot use meshopt (a global simplifier: chunks \
                     cannot reproduce it)",
                ));
            }
            Ok(Some(plan))
        }
        (Some(other), _) => Err(invalid.at(
            "workload",
            format!("unknown workload `{other}` (expected `extract`, `edit` or `lod`)"),
        )),
    }
}

/// The `lod` workload of `workload = "lod"` (its `[lod]` table checked, defaults filled in), or
/// None for the other workloads.
fn plan_lod(
    m: &Manifest,
    configurations: &[Configuration],
    invalid: &Invalid,
) -> Result<Option<LodPlan>, ManifestError> {
    if m.workload.as_deref() != Some("lod") {
        return match &m.lod {
            Some(_) => Err(invalid.at("lod", "a [lod] table needs `workload = \"lod\"`")),
            None => Ok(None),
        };
    }
    let e = m.lod.clone().unwrap_or_default();
    let plan = LodPlan {
        levels: e.levels.unwrap_or(4),
        chunk: e.chunk.unwrap_or(16),
        ratio: e.ratio.unwrap_or(2.0),
        steps: e.steps.unwrap_or(200),
        path: e.path,
        validate_every: e.validate_every.unwrap_or(1),
        validate_max_chunks: e.validate_max_chunks.unwrap_or(4096),
        finest_exact_chunks: e.finest_exact_chunks.unwrap_or(4096),
        tet_cache_mb: e.tet_cache_mb.unwrap_or(1024),
        morph: e.morph.unwrap_or(0.0),
        edits: Vec::new(),
    };
    if !(plan.morph == 0.0 || (plan.morph > 0.0 && plan.morph <= 1.0)) {
        return Err(invalid.at(
            "lod.morph",
            format!("must be 0 (no morph) or in (0, 1], got {}", plan.morph),
        ));
    }
    if plan.morph > 0.0 && plan.ratio <= 0.0 {
        return Err(invalid.at(
            "lod.morph",
            "a morph needs a distance rule: set lod.ratio > 0",
        ));
    }
    if plan.tet_cache_mb > 1 << 20 {
        return Err(invalid.at(
            "lod.tet_cache_mb",
            format!("must be at most 1048576 (1 TiB), got {}", plan.tet_cache_mb),
        ));
    }
    if plan.levels > 12 {
        return Err(invalid.at(
            "lod.levels",
            format!("must be 0 to 12, got {}", plan.levels),
        ));
    }
    if !(2..=256).contains(&plan.chunk) {
        return Err(invalid.at(
            "lod.chunk",
            format!("must be 2 to 256 cells, got {}", plan.chunk),
        ));
    }
    if !(plan.ratio.is_finite() && plan.ratio >= 0.0) {
        return Err(invalid.at(
            "lod.ratio",
            format!("must be finite and >= 0, got {}", plan.ratio),
        ));
    }
    if plan.steps == 0 || plan.steps > 1_000_000 {
        return Err(invalid.at(
            "lod.steps",
            format!("must be 1 to 1000000, got {}", plan.steps),
        ));
    }
    if let Some(path) = &plan.path {
        if path.len() < 2 {
            return Err(invalid.at("lod.path", "needs at least two waypoints"));
        }
        if let Some(p) = path.iter().find(|p| !p.iter().all(|c| c.is_finite())) {
            return Err(invalid.at("lod.path", format!("waypoint {p:?} is not finite")));
        }
    }
    let edits = e.edits.unwrap_or_default();
    let edits = edits
        .iter()
        .enumerate()
        .map(|(i, entry)| lod_edit(i, entry, plan.steps, configurations, invalid))
        .collect::<Result<Vec<_>, _>>()?;
    let plan = LodPlan { edits, ..plan };
    for c in configurations {
        let e = &c.extraction;
        if e.method != Method::Mt || e.lattice != Lattice::BodyCentred {
            return Err(invalid.at(
                &format!("configuration {}", c.id),
                "the lod workload meshes nested body-centred lattices: method mt, lattice bcdl",
            ));
        }
        if !matches!(e.clustering, Clustering::None | Clustering::Integrated) {
            return Err(invalid.at(
                &format!("configuration {}", c.id),
                "the lod workload clusters with the exact check (integrated) or not at all \
                 (none)",
            ));
        }
        if e.simplify.is_some() || e.vertex_cache {
            return Err(invalid.at(
                &format!("configuration {}", c.id),
                "the lod workload cannot simplify or reorder after extraction",
            ));
        }
        let side = u64::from(plan.chunk) << plan.levels;
        if let Some(r) = e
            .resolution
            .cells()
            .into_iter()
            .find(|&r| !(r as u64).is_multiple_of(side))
        {
            return Err(invalid.at(
                &format!("configuration {}", c.id),
                format!(
                    "resolution {r} is not a multiple of chunk x 2^levels = {side} (the \
                     coarsest chunks tile the world)"
                ),
            ));
        }
    }
    Ok(Some(plan))
}

/// Entry `i` of `[lod] edits` checked against the flight's `steps` and every configuration's
/// box, defaults filled in.
fn lod_edit(
    i: usize,
    e: &LodEditEntry,
    steps: usize,
    configurations: &[Configuration],
    invalid: &Invalid,
) -> Result<LodEdit, ManifestError> {
    let key = |field: &str| format!("lod.edits[{i}].{field}");
    let edit = LodEdit {
        step: e.step,
        at: e.at,
        radius: e.radius,
        mode: e.mode,
        strength: e.strength.unwrap_or(1.0),
        frames: e.frames.unwrap_or(1),
    };
    if edit.step > steps {
        return Err(invalid.at(
            &key("step"),
            format!(
                "step {} is after the flight's last step (lod.steps = {steps})",
                edit.step
            ),
        ));
    }
    if !edit.at.iter().all(|c| c.is_finite()) {
        return Err(invalid.at(
            &key("at"),
            format!("the centre must be finite, got {:?}", edit.at),
        ));
    }
    if !(edit.radius.is_finite() && edit.radius > 0.0) {
        return Err(invalid.at(
            &key("radius"),
            format!("must be finite and > 0 (world units), got {}", edit.radius),
        ));
    }
    if !(edit.strength.is_finite() && edit.strength >= 0.0) {
        return Err(invalid.at(
            &key("strength"),
            format!("must be finite and >= 0, got {}", edit.strength),
        ));
    }
    if !(1..=10_000).contains(&edit.frames) {
        return Err(invalid.at(
            &key("frames"),
            format!("must be 1 to 10000, got {}", edit.frames),
        ));
    }
    for c in configurations {
        let b = &c.extraction.bounds;
        let inside = (0..3).all(|a| b.min[a] <= edit.at[a] && edit.at[a] <= b.max[a]);
        if !inside {
            return Err(invalid.at(
                &key("at"),
                format!(
                    "{:?} is outside the box of configuration {}: [{}, {}] x [{}, {}] x [{}, {}]",
                    edit.at, c.id, b.min.x, b.max.x, b.min.y, b.max.y, b.min.z, b.max.z
                ),
            ));
        }
    }
    Ok(edit)
}
