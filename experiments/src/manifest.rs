//! Experiment manifests: a TOML file naming objects and the configurations to extract them with,
//! expanded into a [`Plan`] of uniquely named [`Configuration`]s. Unknown keys are rejected.
//!
//! ```toml
//! name = "paper"            # run name: letters, digits, '-', '_', '.'
//! repetitions = 100         # timed repetitions per configuration (default 100)
//! warmup = 2                # untimed extractions first, same extractor (default 1)
//! threads = 1               # worker threads (default: every core)
//! seed = 7                  # noise seed of objects that do not set their own
//! output = "results"        # parent folder of run folders (default "results")
//! save_meshes = true        # mesh of the last repetition as <run>/meshes/<id>.ply
//! render_cost = true        # quad occupancy, vertex cache, buffer sizes of every mesh (default)
//! paper_benchmark = "data/paper/benchmark.csv"   # compare with the dissertation (optional)
//! collapse_threshold = 0.5  # defaults for every configuration (optional)
//! iso = 0.0
//! normals = "area"          # area | gradient | none
//!
//! [[objects]]
//! name = "sphere"           # used in the `object` column; also the kind unless `kind` is set
//! kind = "sphere"           # sphere | asteroid | gyroid | torus | bunny | terrain | caves
//! code = "ss"               # id prefix (default: the kind's code)
//! resolution = 50           # or [75, 40, 56] (default 50)
//! bounds = [-1, -1, -1, 1, 1, 1]   # default [-1, 1]^3
//! radius = 1.0              # the kind's parameters (see `objects`)
//! elevation_deg = 50        # camera elevation `render` draws it with (default: the render
//!                           # settings', 20 degrees); a terrain chunk seen from above
//!
//! [matrix]                  # objects x methods x lattices x clustering x simplify x
//!                           # vertex_cache x shading; several: [[matrix]] tables, each crossed
//!                           # on its own
//! objects = ["sphere"]      # default: every object, in order
//! methods = ["mt"]          # mt | mc | surface-nets (default mt); mc and surface-nets give one
//!                           # configuration per object (simple lattice, clustering none)
//! lattices = ["bcdl", "simple"]
//! clustering = ["none", "integrated", "postprocessed"]
//! simplify = ["none", { method = "meshopt", target = "rmt" }]   # default ["none"]; target
//!                           # "rmt" | ratio | count, lock_border = true|false (crate::finish)
//! vertex_cache = [false, true]   # meshopt's vertex-cache order after extraction (default [false])
//! shading = ["smooth", "flat"]   # how `render` draws them (default smooth only)
//!
//! [[configurations]]        # and/or an explicit list
//! object = "sphere"
//! lattice = "bcdl"          # default bcdl
//! clustering = "meshopt"    # default none
//! method = "mt"             # default mt
//! id = "my_id"              # default: the naming rule
//! resolution = 64           # overrides the object's (optional)
//! collapse_threshold = 0.3  # optional
//! shading = "flat"          # default smooth
//! simplify = "meshopt:rmt"  # or the table form (default none)
//! vertex_cache = true       # default false
//!
//! [sweep]                   # every configuration for each value (cross product)
//! resolution = [16, 32, 64]
//! collapse_threshold = [0.3, 0.5]
//!
//! seeds = { from = 1, count = 200 }   # seed study: every configuration of a seeded object
//!                           # (asteroid, terrain, caves, random) once per seed, ids
//!                           # `<id>_s<seed>`; `seeds.csv` then gives each configuration's
//!                           # distribution over seeds, `topology.csv` its topology failures
//!
//! workload = "edit"         # instead of repeated extractions: a chunked terrain session
//! [edit]                    # (see `crate::edit`; every key optional)
//! chunk = 32                # chunk edge in cells
//! strokes = 200             # timed brush strokes per configuration
//! warmup = 20               # untimed strokes first
//! seed = 1                  # stroke positions and modes
//! radius = 4.0              # brush radius in cells
//!
//! workload = "lod"          # or: a multiresolution world (`crate::lod`), a viewer flown
//! [lod]                     # along a path, every step re-meshed (every key optional)
//! levels = 4                # coarsest level L (cells of h 2^L); the object's resolution is
//!                           # the finest level's cells, a multiple of chunk 2^L per axis
//! chunk = 16                # chunk edge in cells, at every level
//! ratio = 2.0               # a chunk is split while the viewer is nearer than ratio x its edge
//! steps = 200               # viewer steps after the first meshing
//! path = [[-1, 0.5, -1], [1, 0.5, 1]]   # waypoints (world units), flown at even speed
//! validate_every = 1        # check the surface around the re-meshed chunks every N steps
//!                           # (and the first and last); 0: first and last only
//! validate_max_chunks = 4096   # skip a check whose region has more chunks than this
//! finest_exact_chunks = 4096   # count the finest level's triangles exactly up to this many
//!                           # finest chunks, else estimate them from the world's levels
//! tet_cache_mb = 1024       # keep chunk tetrahedra by surroundings up to this many MiB
//!                           # (rmt_terrain::lod::TetCache; 0 keeps none; meshes unchanged)
//! morph = 0.0               # 0: no morph; in (0, 1]: each level's values blend towards the
//!                           # coarser level's over a band this fraction of `ratio` chunk edges
//!                           # wide (rmt_terrain::lod::Morph): no pop when a chunk changes level
//! edits = [{ step = 3, at = [0.8, 0.0, -0.8], radius = 0.3, mode = "subtract" }]
//!                           # brush strokes (default none): at viewer step `step` (0..=steps;
//!                           # after the viewer moved, before the re-mesh), a brush centred at
//!                           # `at` (world units, inside the box) of `radius` (world units),
//!                           # mode "add" | "subtract", held for `frames` frames of 1/60 s
//!                           # (default 1) at `strength` times the edit workload's (default 1:
//!                           # about one finest cell per frame), as the studio's brush
//! ```
//!
//! **Naming rule** (reproduces the dissertation's ids): object code, `_`, lattice letter (`b`
//! body-centred, `s` simple, `m` marching cubes), clustering letter (`u` none, `i` integrated,
//! `c` integrated-unchecked, `p` postprocessed, `q` meshopt); a simplification appends
//! `_m<target>` (`_ml<target>` with locked borders: `_mrmt`, `_m0.25`) and the vertex-cache
//! order `_vc` ([`finish_suffix`]); each sweep appends `_r<cells>`
//! (`_r64`, `_r75x40x56`) or `_t<threshold>` (`_t0.3`), and flat shading `_flat` (smooth, the
//! default, appends nothing). So `as_bi` is the asteroid on the body-centred lattice with
//! integrated clustering, and `as_bi_flat` the same mesh drawn with flat shading.
//!
//! **Shading** is a variable of a configuration like the lattice or the clustering: it does not
//! change the extraction (two configurations that differ only in shading extract the same mesh),
//! only how `render` draws it. `configurations.csv` gains a `shading` column when some
//! configuration is not smooth, so manifests that never name shading keep their files byte for
//! byte. The runner extracts such twins once (see `crate::runner`).
//!
//! **Camera elevation** is an object's, like shading not part of the extraction:
//! `configurations.csv` gains an `elevation_deg` column (empty where the object sets none) when
//! some object sets one, and `render` draws each configuration from its elevation.

mod plan;

use std::fmt;
use std::path::{Path, PathBuf};

use rmt_extract::{Clustering, Lattice, Method};
use serde::de::{self, Deserializer, SeqAccess, Visitor};
use serde::{Deserialize, Serialize};

use crate::config::{Extraction, Normals};
use crate::objects::{Bounds, ObjectKind, ObjectParams, Resolution};
use crate::simplify::{Simplify, SimplifyChoice};
pub use rmt_render::shade::Shading;

/// Why a manifest cannot be run. Every message names the file; semantic errors name the key.
#[derive(Debug, thiserror::Error)]
pub enum ManifestError {
    /// The file could not be read.
    #[error("cannot read manifest {}: {source}", path.display())]
    Read {
        /// The manifest.
        path: PathBuf,
        /// The I/O error.
        #[source]
        source: std::io::Error,
    },
    /// Malformed TOML, an unknown key, or a value of the wrong type (the message has the line and
    /// column).
    #[error("manifest {}: {message}", path.display())]
    Parse {
        /// The manifest.
        path: PathBuf,
        /// The parser's message, with line, column and the offending text.
        message: String,
    },
    /// A value that parses but cannot be run.
    #[error("manifest {}: {key}: {message}", path.display())]
    Invalid {
        /// The manifest.
        path: PathBuf,
        /// Where in the manifest (`objects[1].resolution`, `configuration as_bi`, ...).
        key: String,
        /// What is wrong.
        message: String,
    },
}

/// Cells per axis as written in a manifest: `50` or `[75, 40, 56]`, every axis >= 1.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(transparent)]
pub struct Cells(pub Resolution);

impl<'de> Deserialize<'de> for Cells {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        const EXPECTED: &str = "a positive number of cells or [nx, ny, nz]";
        fn positive<E: de::Error>(v: i64) -> Result<usize, E> {
            if v >= 1 {
                usize::try_from(v).map_err(|_| E::custom(format!("resolution {v} is too large")))
            } else {
                Err(E::custom(format!(
                    "resolution must be at least 1 cell per axis, got {v}"
                )))
            }
        }
        impl<'de> Visitor<'de> for V {
            type Value = Cells;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str(EXPECTED)
            }
            fn visit_i64<E: de::Error>(self, v: i64) -> Result<Cells, E> {
                Ok(Cells(Resolution::Cube(positive(v)?)))
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> Result<Cells, E> {
                self.visit_i64(i64::try_from(v).unwrap_or(i64::MAX))
            }
            fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Cells, A::Error> {
                let mut cells = [0usize; 3];
                for (i, c) in cells.iter_mut().enumerate() {
                    let v: i64 = seq
                        .next_element()?
                        .ok_or_else(|| de::Error::invalid_length(i, &"3 numbers [nx, ny, nz]"))?;
                    *c = positive(v)?;
                }
                if seq.next_element::<de::IgnoredAny>()?.is_some() {
                    return Err(de::Error::invalid_length(4, &"3 numbers [nx, ny, nz]"));
                }
                Ok(Cells(Resolution::Axes(cells)))
            }
        }
        d.deserialize_any(V)
    }
}

fn default_repetitions() -> usize {
    100
}
fn default_warmup() -> usize {
    1
}
fn yes() -> bool {
    true
}

/// A manifest as written (see the [module documentation](self)).
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Manifest {
    /// Run name (folder prefix).
    pub name: String,
    /// Free text.
    #[serde(default)]
    pub description: Option<String>,
    /// Timed repetitions per configuration.
    #[serde(default = "default_repetitions")]
    pub repetitions: usize,
    /// Untimed extractions before the timed ones.
    #[serde(default = "default_warmup")]
    pub warmup: usize,
    /// Worker threads (default: every core).
    #[serde(default)]
    pub threads: Option<usize>,
    /// Noise seed for objects that do not set their own.
    #[serde(default)]
    pub seed: Option<u32>,
    /// Parent folder of run folders.
    #[serde(default)]
    pub output: Option<PathBuf>,
    /// Save the last repetition's mesh of each configuration.
    #[serde(default = "yes")]
    pub save_meshes: bool,
    /// Measure every mesh's rendering cost (quad occupancy, meshoptimizer's analyzers, buffer
    /// sizes; about 0.3 s per 20,000-triangle mesh); large sweeps that only count topology turn
    /// it off.
    #[serde(default = "yes")]
    pub render_cost: bool,
    /// What to run per configuration: `extract` (default: repeated extractions) or `edit` (a
    /// chunked terrain session of random brush strokes, see [`crate::edit`]).
    #[serde(default)]
    pub workload: Option<String>,
    /// Parameters of the `edit` workload.
    #[serde(default)]
    pub edit: Option<EditEntry>,
    /// Parameters of the `lod` workload.
    #[serde(default)]
    pub lod: Option<LodEntry>,
    /// The dissertation's benchmark table to compare with.
    #[serde(default)]
    pub paper_benchmark: Option<PathBuf>,
    /// Default collapse threshold (grid spacings).
    #[serde(default)]
    pub collapse_threshold: Option<f32>,
    /// Default isovalue.
    #[serde(default)]
    pub iso: Option<f32>,
    /// Default normals.
    #[serde(default)]
    pub normals: Option<Normals>,
    /// The objects.
    #[serde(default)]
    pub objects: Vec<ObjectEntry>,
    /// Matrices of configurations: `[matrix]`, or several as `[[matrix]]`.
    #[serde(default, deserialize_with = "one_or_many")]
    pub matrix: Vec<Matrix>,
    /// Explicit configurations.
    #[serde(default)]
    pub configurations: Vec<ConfigEntry>,
    /// Parameter sweeps applied to every configuration.
    #[serde(default)]
    pub sweep: Option<Sweep>,
    /// A seed study: every configuration of a seeded (noise) object once per seed.
    #[serde(default)]
    pub seeds: Option<SeedRange>,
}

/// `seeds = { from = 1, count = 200 }`: the noise seeds `from .. from + count - 1`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SeedRange {
    /// First seed.
    pub from: u32,
    /// Number of seeds (1 to 100,000).
    pub count: u32,
}

/// Where a configuration of a seed study belongs: its configuration without the seed, and the
/// seed.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct SeedOf {
    /// The configuration's id without the `_s<seed>` suffix.
    pub base_id: String,
    /// The object's noise seed.
    pub seed: u32,
}

/// One `[[objects]]` entry.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct ObjectEntry {
    /// Name used by configurations and in the `object` column.
    pub name: String,
    /// The kind (default: `name`).
    #[serde(default)]
    pub kind: Option<ObjectKind>,
    /// Id prefix (default: the kind's code).
    #[serde(default)]
    pub code: Option<String>,
    /// Cells per axis (default 50).
    #[serde(default)]
    pub resolution: Option<Cells>,
    /// The sampled box (default `[-1, 1]^3`).
    #[serde(default)]
    pub bounds: Option<Bounds>,
    /// See [`ObjectParams::radius`].
    #[serde(default)]
    pub radius: Option<f32>,
    /// See [`ObjectParams::seed`].
    #[serde(default)]
    pub seed: Option<u32>,
    /// See [`ObjectParams::octaves`].
    #[serde(default)]
    pub octaves: Option<usize>,
    /// See [`ObjectParams::frequency`].
    #[serde(default)]
    pub frequency: Option<f64>,
    /// See [`ObjectParams::amplitude`].
    #[serde(default)]
    pub amplitude: Option<f32>,
    /// See [`ObjectParams::thickness`].
    #[serde(default)]
    pub thickness: Option<f32>,
    /// See [`ObjectParams::major`].
    #[serde(default)]
    pub major: Option<f32>,
    /// See [`ObjectParams::minor`].
    #[serde(default)]
    pub minor: Option<f32>,
    /// See [`ObjectParams::mesh`].
    #[serde(default)]
    pub mesh: Option<PathBuf>,
    /// See [`ObjectParams::margin`].
    #[serde(default)]
    pub margin: Option<f32>,
    /// See [`ObjectParams::band`].
    #[serde(default)]
    pub band: Option<f32>,
    /// See [`ObjectParams::base`].
    #[serde(default)]
    pub base: Option<f32>,
    /// See [`ObjectParams::cave_frequency`].
    #[serde(default)]
    pub cave_frequency: Option<f64>,
    /// See [`ObjectParams::cave_radius`].
    #[serde(default)]
    pub cave_radius: Option<f32>,
    /// See [`ObjectParams::cave_ceiling`].
    #[serde(default)]
    pub cave_ceiling: Option<f32>,
    /// The camera elevation `render` draws this object's configurations with, in degrees
    /// (-89..=89; default: the render settings', 20). Not part of the extraction.
    #[serde(default)]
    pub elevation_deg: Option<f32>,
}

impl ObjectEntry {
    fn params(&self) -> ObjectParams {
        ObjectParams {
            radius: self.radius,
            seed: self.seed,
            octaves: self.octaves,
            frequency: self.frequency,
            amplitude: self.amplitude,
            thickness: self.thickness,
            major: self.major,
            minor: self.minor,
            mesh: self.mesh.clone(),
            margin: self.margin,
            band: self.band,
            base: self.base,
            cave_frequency: self.cave_frequency,
            cave_radius: self.cave_radius,
            cave_ceiling: self.cave_ceiling,
        }
    }
}

fn default_lattices() -> Vec<Lattice> {
    vec![Lattice::BodyCentred, Lattice::Simple]
}
fn default_clusterings() -> Vec<Clustering> {
    vec![
        Clustering::None,
        Clustering::Integrated,
        Clustering::Postprocessed,
    ]
}
fn default_methods() -> Vec<Method> {
    vec![Method::Mt]
}

/// `[edit]`: parameters of the `edit` workload (each optional; defaults in [`EditPlan`]).
#[derive(Clone, Debug, Default, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct EditEntry {
    /// Chunk edge in cells.
    #[serde(default)]
    pub chunk: Option<usize>,
    /// Timed strokes per configuration.
    #[serde(default)]
    pub strokes: Option<usize>,
    /// Untimed strokes first.
    #[serde(default)]
    pub warmup: Option<usize>,
    /// Seed of the stroke positions and modes.
    #[serde(default)]
    pub seed: Option<u64>,
    /// Brush radius in cells.
    #[serde(default)]
    pub radius: Option<f32>,
}

/// The checked `edit` workload of a plan.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct EditPlan {
    /// Chunk edge in cells (default 32).
    pub chunk: usize,
    /// Timed strokes per configuration (default 200).
    pub strokes: usize,
    /// Untimed strokes first (default 20).
    pub warmup: usize,
    /// Seed of the strokes (default 1).
    pub seed: u64,
    /// Brush radius in cells (default 4).
    pub radius: f32,
}

/// `[lod]`: parameters of the `lod` workload (each optional; defaults in [`LodPlan`]).
#[derive(Clone, Debug, Default, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct LodEntry {
    /// The coarsest level.
    #[serde(default)]
    pub levels: Option<u8>,
    /// Chunk edge in cells.
    #[serde(default)]
    pub chunk: Option<u32>,
    /// The distance rule's ratio.
    #[serde(default)]
    pub ratio: Option<f64>,
    /// Viewer steps after the first meshing.
    #[serde(default)]
    pub steps: Option<usize>,
    /// The viewer's waypoints, world units.
    #[serde(default)]
    pub path: Option<Vec<[f32; 3]>>,
    /// Check the surface every this many steps (0: the first and last only).
    #[serde(default)]
    pub validate_every: Option<usize>,
    /// Skip a check whose region has more chunks than this.
    #[serde(default)]
    pub validate_max_chunks: Option<usize>,
    /// Count the finest level's triangles exactly up to this many finest chunks.
    #[serde(default)]
    pub finest_exact_chunks: Option<usize>,
    /// The chunk-tets cache's budget, MiB.
    #[serde(default)]
    pub tet_cache_mb: Option<usize>,
    /// The morph band (0: none).
    #[serde(default)]
    pub morph: Option<f64>,
    /// Brush strokes applied during the flight.
    #[serde(default)]
    pub edits: Option<Vec<LodEditEntry>>,
}

/// Whether a stroke of the `lod` workload adds or removes ground ([`rmt_terrain::BrushMode`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum LodEditMode {
    /// Add ground (values decrease).
    Add,
    /// Remove ground (values increase).
    Subtract,
}

/// One entry of `[lod] edits`: a brush held still for some frames at one viewer step.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct LodEditEntry {
    /// The viewer step it is applied at (0: before the first meshing).
    pub step: usize,
    /// The brush's centre, world coordinates.
    pub at: [f32; 3],
    /// The brush's radius, world units.
    pub radius: f32,
    /// `add` or `subtract`.
    pub mode: LodEditMode,
    /// Strength relative to the `edit` workload's strokes (default 1).
    #[serde(default)]
    pub strength: Option<f32>,
    /// Frames the brush is held for (default 1).
    #[serde(default)]
    pub frames: Option<u32>,
}

/// One checked stroke of the `lod` workload: at step `step` (after the viewer moved, before
/// the re-mesh), a brush at `at` of radius `radius` (world units) applied `frames` times for
/// a frame of 1/60 s each, with the `edit` workload's strength times `strength` (about
/// `strength` finest cells of ground per frame at the centre; values clamped to 8 finest
/// cells, [`rmt_terrain::StrokeParams::for_cells`]), as the studio's brush is.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct LodEdit {
    /// The viewer step (`0..=steps`).
    pub step: usize,
    /// Centre, world coordinates (inside every configuration's box).
    pub at: [f32; 3],
    /// Radius, world units (> 0).
    pub radius: f32,
    /// Add or remove ground.
    pub mode: LodEditMode,
    /// Strength relative to the `edit` workload's strokes (>= 0; default 1).
    pub strength: f32,
    /// Frames the brush is held for (1 to 10,000; default 1).
    pub frames: u32,
}

/// The checked `lod` workload of a plan.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct LodPlan {
    /// Coarsest level (default 4).
    pub levels: u8,
    /// Chunk edge in cells (default 16).
    pub chunk: u32,
    /// The distance rule's ratio (default 2).
    pub ratio: f64,
    /// Viewer steps after the first meshing (default 200).
    pub steps: usize,
    /// Waypoints, world units (default: the box's diagonal in x and z, at the top of its
    /// lowest quarter).
    pub path: Option<Vec<[f32; 3]>>,
    /// Validation cadence (default 1: every step).
    pub validate_every: usize,
    /// The largest region a check builds the tetrahedra of, in chunks (default 4096).
    pub validate_max_chunks: usize,
    /// Exact finest-level count up to this many finest chunks (default 4096).
    pub finest_exact_chunks: usize,
    /// The world's chunk-tets cache budget, MiB (default 1024; 0 keeps none). The meshes do
    /// not depend on it.
    pub tet_cache_mb: usize,
    /// The morph band (default 0, none; else in `(0, 1]`, `rmt_terrain::lod::Morph`): each
    /// level's values blend towards the coarser level's over a band of this fraction of `ratio`
    /// chunk edges, so a change of level does not pop.
    pub morph: f64,
    /// Brush strokes, in the manifest's order (default none).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub edits: Vec<LodEdit>,
}

/// `[matrix]`: objects x methods x lattices x clustering.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Matrix {
    /// Object names (default: all, in order).
    #[serde(default)]
    pub objects: Option<Vec<String>>,
    /// Methods (default `["mt"]`).
    #[serde(default = "default_methods")]
    pub methods: Vec<Method>,
    /// Lattices (default both).
    #[serde(default = "default_lattices")]
    pub lattices: Vec<Lattice>,
    /// Clustering modes (default none, integrated, postprocessed).
    #[serde(default = "default_clusterings")]
    pub clustering: Vec<Clustering>,
    /// Shadings `render` draws each configuration with (default smooth only).
    #[serde(default = "default_shadings")]
    pub shading: Vec<Shading>,
    /// Simplifications after extraction (default `["none"]`; see [`crate::simplify`]).
    #[serde(default = "default_simplify")]
    pub simplify: Vec<SimplifyChoice>,
    /// Vertex-cache order after extraction, off and/or on (default `[false]`).
    #[serde(default = "default_vertex_cache")]
    pub vertex_cache: Vec<bool>,
}

/// `[matrix]` (one table) or `[[matrix]]` (several), as a list.
fn one_or_many<'de, D: Deserializer<'de>>(d: D) -> Result<Vec<Matrix>, D::Error> {
    struct V;
    impl<'de> Visitor<'de> for V {
        type Value = Vec<Matrix>;
        fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
            f.write_str("a [matrix] table or [[matrix]] tables")
        }
        fn visit_map<A: de::MapAccess<'de>>(self, map: A) -> Result<Vec<Matrix>, A::Error> {
            Matrix::deserialize(de::value::MapAccessDeserializer::new(map)).map(|m| vec![m])
        }
        fn visit_seq<A: SeqAccess<'de>>(self, seq: A) -> Result<Vec<Matrix>, A::Error> {
            Vec::<Matrix>::deserialize(de::value::SeqAccessDeserializer::new(seq))
        }
    }
    d.deserialize_any(V)
}

fn default_simplify() -> Vec<SimplifyChoice> {
    vec![SimplifyChoice(None)]
}
fn default_vertex_cache() -> Vec<bool> {
    vec![false]
}
fn default_shadings() -> Vec<Shading> {
    vec![Shading::Smooth]
}

/// One `[[configurations]]` entry.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct ConfigEntry {
    /// Id (default: the naming rule).
    #[serde(default)]
    pub id: Option<String>,
    /// Object name.
    pub object: String,
    /// Lattice (default bcdl).
    #[serde(default)]
    pub lattice: Option<Lattice>,
    /// Clustering (default none).
    #[serde(default)]
    pub clustering: Option<Clustering>,
    /// Method (default mt).
    #[serde(default)]
    pub method: Option<Method>,
    /// Overrides the object's resolution.
    #[serde(default)]
    pub resolution: Option<Cells>,
    /// Overrides the collapse threshold.
    #[serde(default)]
    pub collapse_threshold: Option<f32>,
    /// Overrides the isovalue.
    #[serde(default)]
    pub iso: Option<f32>,
    /// How `render` draws it (default smooth).
    #[serde(default)]
    pub shading: Option<Shading>,
    /// Simplification after extraction (default none; see [`crate::simplify`]).
    #[serde(default)]
    pub simplify: Option<SimplifyChoice>,
    /// Vertex-cache order after extraction (default false).
    #[serde(default)]
    pub vertex_cache: Option<bool>,
}

/// `[sweep]`: lists of values, each configuration repeated for every combination.
#[derive(Clone, Debug, Default, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Sweep {
    /// Resolutions (suffix `_r<cells>`).
    #[serde(default)]
    pub resolution: Option<Vec<Cells>>,
    /// Collapse thresholds (suffix `_t<value>`).
    #[serde(default)]
    pub collapse_threshold: Option<Vec<f32>>,
}

/// One configuration of a plan: an id, the object's manifest name, and the extraction.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Configuration {
    /// Unique id (file-name safe).
    pub id: String,
    /// The object's name in the manifest.
    pub object: String,
    /// Everything that decides the extraction.
    pub extraction: Extraction,
    /// Set in seed studies for configurations of a seeded object.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub seed_of: Option<SeedOf>,
    /// How `render` draws the mesh (not part of the extraction).
    #[serde(skip_serializing_if = "is_smooth")]
    pub shading: Shading,
    /// The camera elevation `render` draws the mesh with, in degrees, when its object sets one
    /// (not part of the extraction).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub elevation_deg: Option<f32>,
}

fn is_smooth(s: &Shading) -> bool {
    *s == Shading::Smooth
}

/// The id suffix of a shading: `_flat` for flat, nothing for smooth (the default).
pub fn shading_suffix(s: Shading) -> &'static str {
    match s {
        Shading::Smooth => "",
        Shading::Flat => "_flat",
    }
}

/// The shading's name (`smooth`, `flat`), as manifests and `configurations.csv` write it.
pub fn shading_name(s: Shading) -> &'static str {
    match s {
        Shading::Smooth => "smooth",
        Shading::Flat => "flat",
    }
}

impl Configuration {
    /// The key of the field it extracts: the object's name, with `#s<seed>` in seed studies.
    pub fn field_key(&self) -> String {
        match &self.seed_of {
            Some(s) => format!("{}#s{}", self.object, s.seed),
            None => self.object.clone(),
        }
    }
}

/// Values that command-line flags override.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Overrides {
    /// Timed repetitions.
    pub repetitions: Option<usize>,
    /// Warm-up extractions.
    pub warmup: Option<usize>,
    /// Worker threads.
    pub threads: Option<usize>,
    /// Save meshes.
    pub save_meshes: Option<bool>,
}

/// A manifest expanded and checked: what the runner executes.
#[derive(Clone, Debug, Serialize)]
pub struct Plan {
    /// Run name.
    pub name: String,
    /// Timed repetitions per configuration (>= 1).
    pub repetitions: usize,
    /// Warm-up extractions per configuration.
    pub warmup: usize,
    /// Worker threads.
    pub threads: usize,
    /// Save the last repetition's mesh.
    pub save_meshes: bool,
    /// Measure each mesh's rendering cost.
    pub render_cost: bool,
    /// Parent folder of run folders.
    pub output: PathBuf,
    /// The resolved benchmark table to compare with, if any.
    pub paper_benchmark: Option<PathBuf>,
    /// Folders searched for relative data paths (the manifest's folder).
    pub search: Vec<PathBuf>,
    /// The sweep variables in use (`resolution`, `collapse_threshold`).
    pub sweep_variables: Vec<String>,
    /// The configurations, in execution order.
    pub configurations: Vec<Configuration>,
    /// `Some` for the `edit` workload: a terrain session per configuration instead of
    /// repeated extractions.
    pub edit: Option<EditPlan>,
    /// `Some` for the `lod` workload: a multiresolution world flown over per configuration.
    pub lod: Option<LodPlan>,
}

/// Reads and parses a manifest file (no expansion yet).
pub fn read(path: &Path) -> Result<(Manifest, String), ManifestError> {
    let text = std::fs::read_to_string(path).map_err(|source| ManifestError::Read {
        path: path.to_path_buf(),
        source,
    })?;
    let manifest = parse(&text, path)?;
    Ok((manifest, text))
}

/// Parses manifest text; `path` names it in errors.
pub fn parse(text: &str, path: &Path) -> Result<Manifest, ManifestError> {
    toml::from_str(text).map_err(|e| ManifestError::Parse {
        path: path.to_path_buf(),
        message: e.to_string().trim_end().to_string(),
    })
}

/// A manifest read, expanded and checked, with its objects built.
pub struct Loaded {
    /// The configurations and options.
    pub plan: Plan,
    /// The manifest's text (copied into the run folder).
    pub text: String,
    /// The field of every object used.
    pub fields: Fields,
}

/// Reads, expands and checks a manifest, and builds every object once, so that every error
/// shows before any work starts.
pub fn load(path: &Path, overrides: &Overrides) -> Result<Loaded, ManifestError> {
    let (manifest, text) = read(path)?;
    let base = path.parent().map(Path::to_path_buf).unwrap_or_default();
    let plan = manifest.plan(path, &base, overrides)?;
    let fields = plan.build_fields(path)?;
    Ok(Loaded { plan, text, fields })
}

/// The clustering letter of ids.
pub fn clustering_letter(c: Clustering) -> char {
    match c {
        Clustering::None => 'u',
        Clustering::Integrated => 'i',
        Clustering::IntegratedUnchecked => 'c',
        Clustering::Postprocessed => 'p',
        Clustering::Meshopt => 'q',
    }
}

/// The lattice letter of ids (`m` for marching cubes, `n` for surface nets).
pub fn lattice_letter(method: Method, l: Lattice) -> char {
    match (method, l) {
        (Method::Mc, _) => 'm',
        (Method::SurfaceNets, _) => 'n',
        (Method::Mt, Lattice::BodyCentred) => 'b',
        (Method::Mt, Lattice::Simple) => 's',
    }
}

/// The id of a configuration before sweep suffixes: `code_` + lattice letter + clustering letter.
pub fn base_id(code: &str, method: Method, lattice: Lattice, clustering: Clustering) -> String {
    format!(
        "{code}_{}{}",
        lattice_letter(method, lattice),
        clustering_letter(clustering)
    )
}

/// The id suffix of the finish steps: `_m<target>` or `_ml<target>` for a simplification, then
/// `_vc` for the vertex-cache order (empty without either).
pub fn finish_suffix(simplify: Option<&Simplify>, vertex_cache: bool) -> String {
    let mut s = simplify.map(Simplify::id_suffix).unwrap_or_default();
    if vertex_cache {
        s += "_vc";
    }
    s
}

fn safe_name(s: &str) -> bool {
    !s.is_empty()
        && !s.starts_with('.')
        && s.chars()
            .all(|c| c.is_ascii_alphanumeric() || matches!(c, '_' | '-' | '.'))
}

/// The fields of a plan's objects, built once and shared by their configurations.
pub struct Fields {
    /// `(field key, its field)`, one per distinct object (and seed) used; see
    /// [`Configuration::field_key`].
    pub fields: Vec<(String, Box<dyn rmt_fields::ScalarField>)>,
}

impl Fields {
    /// The field of key `name` ([`Configuration::field_key`]).
    pub fn get(&self, name: &str) -> Option<&dyn rmt_fields::ScalarField> {
        self.fields
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, f)| f.as_ref())
    }
}

impl Plan {
    /// Builds the field of every object the configurations use (mesh files are read here).
    /// `path` names the manifest in errors.
    pub fn build_fields(&self, path: &Path) -> Result<Fields, ManifestError> {
        let mut fields: Vec<(String, Box<dyn rmt_fields::ScalarField>)> = Vec::new();
        for c in &self.configurations {
            let key = c.field_key();
            if fields.iter().any(|(n, _)| *n == key) {
                continue;
            }
            let e = &c.extraction;
            // The coarsest grid this object is sampled on sets its narrow band (mesh objects).
            let spacing = self
                .configurations
                .iter()
                .filter(|o| o.object == c.object)
                .map(|o| {
                    let x = &o.extraction;
                    let cells = x.resolution.cells();
                    let size = x.bounds.max - x.bounds.min;
                    (0..3)
                        .map(|a| size[a] / cells[a].max(1) as f32)
                        .fold(0.0f32, f32::max)
                })
                .fold(0.0f32, f32::max);
            let field = e
                .object
                .build_for_spacing(&e.bounds, Some(spacing), &self.search)
                .map_err(|err| ManifestError::Invalid {
                    path: path.to_path_buf(),
                    key: "building objects".to_string(),
                    message: err.to_string(),
                })?;
            fields.push((key, field));
        }
        Ok(Fields { fields })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn plan(text: &str) -> Result<Plan, ManifestError> {
        let p = Path::new("test.toml");
        parse(text, p)?.plan(
            p,
            Path::new("."),
            &Overrides {
                threads: Some(1),
                ..Default::default()
            },
        )
    }

    #[test]
    fn matrix_expands_in_object_lattice_clustering_order_with_dissertation_ids() {
        let p = plan(
            r#"
            name = "t"
            [[objects]]
            name = "sphere"
            [[objects]]
            name = "asteroid"
            [matrix]
            "#,
        )
        .unwrap();
        let ids: Vec<&str> = p.configurations.iter().map(|c| c.id.as_str()).collect();
        assert_eq!(
            ids,
            [
                "ss_bu", "ss_bi", "ss_bp", "ss_su", "ss_si", "ss_sp", "as_bu", "as_bi", "as_bp",
                "as_su", "as_si", "as_sp"
            ]
        );
        assert_eq!(p.repetitions, 100);
        assert_eq!(p.configurations[4].extraction.lattice, Lattice::Simple);
        assert_eq!(
            p.configurations[4].extraction.clustering,
            Clustering::Integrated
        );
    }

    #[test]
    fn sweeps_multiply_configurations_and_append_suffixes() {
        let p = plan(
            r#"
            name = "t"
            [[objects]]
            name = "sphere"
            [matrix]
            methods = ["mt", "mc"]
            lattices = ["bcdl"]
            clustering = ["postprocessed", "meshopt"]
            [sweep]
            resolution = [8, [4, 5, 6]]
            collapse_threshold = [0.25, 0.5]
            "#,
        )
        .unwrap();
        let ids: Vec<&str> = p.configurations.iter().map(|c| c.id.as_str()).collect();
        assert_eq!(ids.len(), 3 * 2 * 2);
        assert!(ids.contains(&"ss_bp_r8_t0.25"));
        assert!(ids.contains(&"ss_bq_r4x5x6_t0.5"));
        assert!(ids.contains(&"ss_mu_r8_t0.5"));
        let c = p
            .configurations
            .iter()
            .find(|c| c.id == "ss_bq_r4x5x6_t0.5")
            .unwrap();
        assert_eq!(c.extraction.resolution.cells(), [4, 5, 6]);
        assert_eq!(c.extraction.collapse_threshold, 0.5);
        assert_eq!(p.sweep_variables, ["resolution", "collapse_threshold"]);
    }

    #[test]
    fn explicit_configurations_take_defaults_and_overrides() {
        let p = plan(
            r#"
            name = "t"
            seed = 11
            [[objects]]
            name = "rock"
            kind = "asteroid"
            code = "rk"
            resolution = 12
            [[configurations]]
            object = "rock"
            [[configurations]]
            object = "rock"
            id = "custom"
            clustering = "integrated-unchecked"
            resolution = [3, 4, 5]
            "#,
        )
        .unwrap();
        assert_eq!(p.configurations[0].id, "rk_bu");
        assert_eq!(p.configurations[0].extraction.resolution.cells(), [12; 3]);
        assert_eq!(p.configurations[0].extraction.object.params.seed, Some(11));
        assert_eq!(p.configurations[1].id, "custom");
        assert_eq!(p.configurations[1].extraction.resolution.cells(), [3, 4, 5]);
    }

    #[test]
    fn matrices_repeat_and_cross_simplifications_and_vertex_cache_orders() {
        let p = plan(
            r#"
            name = "t"
            render_cost = false
            [[objects]]
            name = "asteroid"
            resolution = 6
            [[matrix]]
            lattices = ["bcdl"]
            clustering = ["integrated"]
            vertex_cache = [false, true]
            [[matrix]]
            methods = ["mc", "surface-nets"]
            simplify = ["none", { method = "meshopt", target = "rmt" },
                        { method = "meshopt", target = 0.5, lock_border = true }]
            [[configurations]]
            object = "asteroid"
            simplify = "meshopt:100"
            vertex_cache = true
            "#,
        )
        .unwrap();
        let ids: Vec<&str> = p.configurations.iter().map(|c| c.id.as_str()).collect();
        assert_eq!(
            ids,
            [
                "as_bi",
                "as_bi_vc",
                "as_mu",
                "as_mu_mrmt",
                "as_mu_ml0.5",
                "as_nu",
                "as_nu_mrmt",
                "as_nu_ml0.5",
                "as_bu_m100_vc",
            ]
        );
        assert!(!p.render_cost);
        let e = &p.configurations[4].extraction;
        assert_eq!(
            e.simplify,
            Some(Simplify {
                target: crate::simplify::SimplifyTarget::Ratio(0.5),
                lock_border: true
            })
        );
        assert!(p.configurations[8].extraction.vertex_cache);
        // One [matrix] table still works, and errors name the matrix and the value.
        let err = plan(
            "name = \"t\"\n[[objects]]\nname = \"sphere\"\n[[matrix]]\n[[matrix]]\nsimplify = []\n",
        )
        .unwrap_err()
        .to_string();
        assert!(
            err.contains("matrix[1].simplify: the list is empty"),
            "{err}"
        );
        let err = plan(
            "name = \"t\"\n[[objects]]\nname = \"sphere\"\n[matrix]\nsimplify = [\"qem:rmt\"]\n",
        )
        .unwrap_err()
        .to_string();
        assert!(
            err.contains("unknown simplifier `qem`") && err.contains("line"),
            "{err}"
        );
        let err = plan(
            "name = \"t\"\nworkload = \"edit\"\n[[objects]]\nname = \"terrain\"\n\
             [[configurations]]\nobject = \"terrain\"\nclustering = \"integrated\"\n\
             vertex_cache = true\n",
        )
        .unwrap_err()
        .to_string();
        assert!(err.contains("cannot simplify or reorder"), "{err}");
    }

    #[test]
    fn shading_crosses_configurations_and_flat_ids_get_a_suffix() {
        let p = plan(
            r#"
            name = "t"
            [[objects]]
            name = "sphere"
            [matrix]
            methods = ["mt", "surface-nets"]
            lattices = ["bcdl"]
            clustering = ["integrated"]
            shading = ["smooth", "flat"]
            [[configurations]]
            object = "sphere"
            method = "mc"
            shading = "flat"
            "#,
        )
        .unwrap();
        let ids: Vec<(&str, Shading)> = p
            .configurations
            .iter()
            .map(|c| (c.id.as_str(), c.shading))
            .collect();
        assert_eq!(
            ids,
            [
                ("ss_bi", Shading::Smooth),
                ("ss_bi_flat", Shading::Flat),
                ("ss_nu", Shading::Smooth),
                ("ss_nu_flat", Shading::Flat),
                ("ss_mu_flat", Shading::Flat),
            ]
        );
        // Shading changes no extraction.
        assert_eq!(
            p.configurations[0].extraction,
            p.configurations[1].extraction
        );
        // The plan as run.json records it names shading only where it is not smooth.
        let json = serde_json::to_string(&p.configurations[0]).unwrap();
        assert!(!json.contains("shading"), "{json}");
        let json = serde_json::to_string(&p.configurations[1]).unwrap();
        assert!(json.contains(r#""shading":"flat""#), "{json}");
        let err = plan("name = \"t\"\n[[objects]]\nname = \"sphere\"\n[matrix]\nshading = []\n")
            .unwrap_err()
            .to_string();
        assert!(err.contains("matrix.shading"), "{err}");
        let err =
            plan("name = \"t\"\n[[objects]]\nname = \"sphere\"\n[matrix]\nshading = [\"toon\"]\n")
                .unwrap_err()
                .to_string();
        assert!(err.contains("toon"), "{err}");
    }

    #[test]
    fn parse_errors_carry_line_and_column() {
        let err = plan("name = \"t\"\nrepetitions = \"many\"\n")
            .unwrap_err()
            .to_string();
        assert!(err.contains("line 2") && err.contains("column"), "{err}");
        let err = plan("name = \"t\"\nbogus = 1\n").unwrap_err().to_string();
        assert!(err.contains("bogus") && err.contains("line 2"), "{err}");
    }

    #[test]
    fn duplicate_ids_and_unknown_objects_are_refused() {
        let dup = r#"
            name = "t"
            [[objects]]
            name = "sphere"
            [[configurations]]
            object = "sphere"
            [[configurations]]
            object = "sphere"
        "#;
        assert!(plan(dup).unwrap_err().to_string().contains("used twice"));
        let unknown = r#"
            name = "t"
            [[objects]]
            name = "sphere"
            [[configurations]]
            object = "cube"
        "#;
        let err = plan(unknown).unwrap_err().to_string();
        assert!(err.contains("no object named `cube`"), "{err}");
    }

    #[test]
    fn overrides_replace_manifest_values() {
        let p = Path::new("t.toml");
        let m = parse(
            "name = \"t\"\nrepetitions = 5\nthreads = 2\n[[objects]]\nname = \"sphere\"\n[matrix]\n",
            p,
        )
        .unwrap();
        let o = Overrides {
            repetitions: Some(3),
            warmup: Some(0),
            threads: Some(1),
            save_meshes: Some(false),
        };
        let plan = m.plan(p, Path::new("."), &o).unwrap();
        assert_eq!((plan.repetitions, plan.warmup, plan.threads), (3, 0, 1));
        assert!(!plan.save_meshes);
    }
}
