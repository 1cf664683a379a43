//! The extraction benchmark without criterion (`experiments bench`): our MT, RMT and marching
//! cubes against two peer crates (fast-surface-nets, isomesh's marching cubes), all fed the same
//! pre-sampled values, timed with interleaved repetitions and summarised by the median.
//!
//! Per field and size the field is sampled once on each lattice (body-centred: corners and
//! centres; simple cubic: the `(n + 1)^3` corners that marching cubes and both peers read), and
//! sampling is never timed. Every repetition then runs every thread count and every method once
//! (rep loop outside, method loop inside), so slow drifts of the machine's load spread over all
//! methods alike. Our methods re-mesh with [`Extractor::extract_presampled`] and skip normals
//! ([`NormalMode::Skip`]); the isomesh adapter returns a constant gradient, so isomesh computes no
//! normals either; fast-surface-nets always estimates its (unnormalised) normals from the corner
//! values, which cannot be switched off. isomesh copies the grid into its own buffer on every call
//! (its API reads a field, not an array): that copy is timed, as it is part of using it. The peers
//! are single-threaded: with `threads = 2` they run the same single-threaded code and report
//! `threads_used = 1`.
//!
//! Timed: the whole call per method, wall clock and (Linux) CPU time of all threads; on a shared
//! machine the CPU time moves much less with other processes' load, and a two-thread call whose
//! wall time is below its CPU time really ran in parallel. For our methods the median of the
//! vertex and geometry passes (from [`Stats`]) is reported too, and the allocation share of a
//! second call on a reused extractor (`t_allocation_s / t_total_s`, pre-sampled, so sampling
//! does not dilute it).
//!
//! With a Python interpreter (`--python PY`, [`BenchConfig::python`]), VTK's Flying Edges and
//! scikit-image's `marching_cubes` are timed on the same corner grid, between the two halves of
//! our repetitions of each field and size ([`crate::bench_python`]), and every row gets its ratio
//! over Flying Edges; `--dump DIR` keeps the values, their headers and the script.

use std::path::PathBuf;
use std::time::Instant;

use fast_surface_nets::ndshape::RuntimeShape;
use fast_surface_nets::{surface_nets, SurfaceNetsBuffer};
use glam::Vec3;
use rmt_extract::{
    Clustering, ExtractError, ExtractSettings, Extractor, Grid, Lattice, Method, NormalMode,
    Samples, Stats, ThreadPlacement,
};
use rmt_fields::{Asteroid, AsteroidParams, ScalarField, Sphere};
use rmt_mesh::Mesh;
use serde::Serialize;

use crate::bench_python::{dump_values, time_peers, PythonPeerError};

/// Why a benchmark could not run.
#[derive(Debug, thiserror::Error)]
pub enum BenchError {
    /// A field name that is not benchmarked.
    #[error("unknown field {0:?}: expected sphere or asteroid")]
    UnknownField(String),
    /// A bad list or count in the configuration.
    #[error("invalid {what}: {message}")]
    InvalidConfig {
        /// The option at fault (`sizes`, `reps`, ...).
        what: &'static str,
        /// What is wrong with it.
        message: String,
    },
    /// Our extractor refused the settings or the field.
    #[error("{method} on {field} at {n}^3: {source}")]
    Extract {
        /// Method name.
        method: &'static str,
        /// Field name.
        field: &'static str,
        /// Cells per axis.
        n: usize,
        /// The extractor's error.
        source: ExtractError,
    },
    /// isomesh refused the grid.
    #[error("isomesh on {field} at {n}^3: {message}")]
    Isomesh {
        /// Field name.
        field: &'static str,
        /// Cells per axis.
        n: usize,
        /// isomesh's error.
        message: String,
    },
    /// The Python peers could not be timed.
    #[error(transparent)]
    Python(#[from] PythonPeerError),
    /// The surface comes too near the box faces for fast-surface-nets to close it.
    #[error(
        "the {field} surface at {n}^3 reaches corner ({x}, {y}, {z}): fast-surface-nets leaves \
         the min faces and the last cell layer unmeshed (its chunk convention), so the surface \
         must stay inside corners 1..=n-2 on every axis; use a larger size"
    )]
    SurfaceAtFaces {
        /// Field name.
        field: &'static str,
        /// Cells per axis.
        n: usize,
        /// Corner index x.
        x: usize,
        /// Corner index y.
        y: usize,
        /// Corner index z.
        z: usize,
    },
}

/// A benchmarked field, centred in `[-1, 1]^3`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BenchField {
    /// Sphere of radius 0.8.
    Sphere,
    /// The asteroid with default parameters.
    Asteroid,
}

impl BenchField {
    /// Every benchmarked field.
    pub const ALL: [BenchField; 2] = [BenchField::Sphere, BenchField::Asteroid];

    /// Name on the command line and in results.
    pub fn name(self) -> &'static str {
        match self {
            BenchField::Sphere => "sphere",
            BenchField::Asteroid => "asteroid",
        }
    }

    /// The field for a name (`sphere`, `asteroid`).
    pub fn parse(name: &str) -> Result<Self, BenchError> {
        Self::ALL
            .into_iter()
            .find(|f| f.name() == name.trim())
            .ok_or_else(|| BenchError::UnknownField(name.to_string()))
    }

    /// Builds the field.
    pub fn build(self) -> Box<dyn ScalarField> {
        match self {
            BenchField::Sphere => Box::new(Sphere::new(Vec3::ZERO, 0.8)),
            BenchField::Asteroid => Box::new(Asteroid::new(Vec3::ZERO, AsteroidParams::default())),
        }
    }
}

/// A compared method: ours (MT, RMT, MC) or a peer crate.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BenchMethod {
    /// Plain marching tetrahedra on the body-centred lattice.
    MtBcdlNone,
    /// RMT (integrated clustering) on the body-centred lattice.
    RmtBcdlIntegrated,
    /// Integrated clustering without the exact check (the dissertation's rules) on the
    /// body-centred lattice: the cost of the method apart from the cost of the guarantee.
    RmtBcdlUnchecked,
    /// Plain marching tetrahedra on the simple cubic lattice.
    MtSimpleNone,
    /// RMT (integrated clustering) on the simple cubic lattice.
    RmtSimpleIntegrated,
    /// Our marching cubes.
    Mc,
    /// `fast-surface-nets` (naive surface nets), the reference of the ratios.
    FastSurfaceNets,
    /// `isomesh`'s marching cubes.
    IsomeshMc,
}

impl BenchMethod {
    /// Every method, in report order.
    pub const ALL: [BenchMethod; 8] = [
        BenchMethod::MtBcdlNone,
        BenchMethod::RmtBcdlIntegrated,
        BenchMethod::RmtBcdlUnchecked,
        BenchMethod::MtSimpleNone,
        BenchMethod::RmtSimpleIntegrated,
        BenchMethod::Mc,
        BenchMethod::FastSurfaceNets,
        BenchMethod::IsomeshMc,
    ];

    /// Name in results (the criterion function names of `rmt-extract`'s benches).
    pub fn name(self) -> &'static str {
        match self {
            BenchMethod::MtBcdlNone => "mt_bcdl_none",
            BenchMethod::RmtBcdlIntegrated => "rmt_bcdl_integrated",
            BenchMethod::RmtBcdlUnchecked => "rmt_bcdl_unchecked",
            BenchMethod::MtSimpleNone => "mt_simple_none",
            BenchMethod::RmtSimpleIntegrated => "rmt_simple_integrated",
            BenchMethod::Mc => "mc",
            BenchMethod::FastSurfaceNets => "fast_surface_nets",
            BenchMethod::IsomeshMc => "isomesh_mc",
        }
    }

    /// Our extraction settings on `n^3` cells of `[-1, 1]^3` (normals skipped), or `None` for a
    /// peer.
    pub fn settings(self, n: usize, threads: usize) -> Option<ExtractSettings> {
        let (lattice, clustering, method) = match self {
            BenchMethod::MtBcdlNone => (Lattice::BodyCentred, Clustering::None, Method::Mt),
            BenchMethod::RmtBcdlIntegrated => {
                (Lattice::BodyCentred, Clustering::Integrated, Method::Mt)
            }
            BenchMethod::RmtBcdlUnchecked => (
                Lattice::BodyCentred,
                Clustering::IntegratedUnchecked,
                Method::Mt,
            ),
            BenchMethod::MtSimpleNone => (Lattice::Simple, Clustering::None, Method::Mt),
            BenchMethod::RmtSimpleIntegrated => {
                (Lattice::Simple, Clustering::Integrated, Method::Mt)
            }
            BenchMethod::Mc => (Lattice::Simple, Clustering::None, Method::Mc),
            BenchMethod::FastSurfaceNets | BenchMethod::IsomeshMc => return None,
        };
        let mut settings = ExtractSettings::new(Grid::cube(n, 1.0), lattice, clustering);
        settings.method = method;
        settings.threads = threads;
        settings.normals = NormalMode::Skip;
        Some(settings)
    }

    /// Whether the method reads the body-centred samples (else the simple corner grid).
    pub fn body_centred(self) -> bool {
        matches!(
            self,
            BenchMethod::MtBcdlNone
                | BenchMethod::RmtBcdlIntegrated
                | BenchMethod::RmtBcdlUnchecked
        )
    }

    /// Plain MT on the same lattice, for the MT methods: the reference of
    /// [`BenchRow::vertex_geometry_over_plain`].
    pub fn plain(self) -> Option<BenchMethod> {
        match self {
            BenchMethod::MtBcdlNone
            | BenchMethod::RmtBcdlIntegrated
            | BenchMethod::RmtBcdlUnchecked => Some(BenchMethod::MtBcdlNone),
            BenchMethod::MtSimpleNone | BenchMethod::RmtSimpleIntegrated => {
                Some(BenchMethod::MtSimpleNone)
            }
            BenchMethod::Mc | BenchMethod::FastSurfaceNets | BenchMethod::IsomeshMc => None,
        }
    }
}

/// What to benchmark.
#[derive(Clone, Debug, PartialEq)]
pub struct BenchConfig {
    /// Fields, in order.
    pub fields: Vec<BenchField>,
    /// Cells per axis, in order.
    pub sizes: Vec<usize>,
    /// Timed repetitions of every (threads, method) pair.
    pub reps: usize,
    /// Thread counts of our methods.
    pub threads: Vec<usize>,
    /// Where the workers of our methods' pools run ([`ThreadPlacement::Os`] by default; see
    /// `rmt_extract::threads` for what pinning changes on an idle pool).
    pub placement: ThreadPlacement,
    /// Where to keep the sampled corner grids (`FIELD_N.f32`, `FIELD_N.json`) and the peer
    /// script; `None`: not kept (a temporary folder when `python` is set).
    pub dump: Option<PathBuf>,
    /// A Python 3 with numpy, vtk and scikit-image: times the Python peers in the same run.
    pub python: Option<String>,
}

impl Default for BenchConfig {
    fn default() -> Self {
        Self {
            fields: BenchField::ALL.to_vec(),
            sizes: vec![32, 64, 128],
            reps: 20,
            threads: vec![1, 2],
            placement: ThreadPlacement::Os,
            dump: None,
            python: None,
        }
    }
}

impl BenchConfig {
    /// Checks that every list is non-empty and every number usable.
    pub fn check(&self) -> Result<(), BenchError> {
        let bad = |what, message: String| Err(BenchError::InvalidConfig { what, message });
        if self.fields.is_empty() {
            return bad("fields", "need at least one field".into());
        }
        if self.sizes.is_empty() || self.sizes.iter().any(|&n| !(2..=1024).contains(&n)) {
            return bad(
                "sizes",
                format!("need sizes in 2..=1024, got {:?}", self.sizes),
            );
        }
        if self.reps == 0 {
            return bad("reps", "need at least one repetition".into());
        }
        if self.threads.is_empty() || self.threads.iter().any(|&t| !(1..=1024).contains(&t)) {
            return bad(
                "threads",
                format!("need thread counts in 1..=1024, got {:?}", self.threads),
            );
        }
        Ok(())
    }
}

/// One line of results: a method on a field and size with a thread count.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct BenchRow {
    /// Field name.
    pub field: &'static str,
    /// Cells per axis.
    pub n: usize,
    /// Method name.
    pub method: &'static str,
    /// Requested thread count.
    pub threads: usize,
    /// Threads the method actually used (1 for the peers).
    pub threads_used: usize,
    /// Median wall-clock seconds of one call.
    pub median_s: f64,
    /// Median CPU seconds of one call, all threads together (Linux only): robust to other
    /// processes' load, and above `median_s` when a second thread works.
    pub cpu_median_s: Option<f64>,
    /// `median_s` per sample point of the method's lattice, in nanoseconds.
    pub ns_per_point: f64,
    /// `median_s` over fast-surface-nets' `median_s` at the same field, size and threads (whole
    /// calls: the body-centred lattice has about twice the points of the grid).
    pub ratio_to_fast_surface_nets: f64,
    /// `median_s` over VTK Flying Edges' at the same field and size (Flying Edges on one
    /// thread), when the Python peers were timed: the measure of the speed targets.
    pub ratio_to_flying_edges: Option<f64>,
    /// `ns_per_point` over fast-surface-nets' `ns_per_point` (per grid point) at the same field,
    /// size and threads: the measure of the performance target ("RMT per sample point within
    /// 2x of fast-surface-nets per grid point").
    pub point_ratio_to_fast_surface_nets: f64,
    /// Sample points of the method's lattice (body-centred: corners, centres and ghost centres;
    /// otherwise the `(n + 1)^3` corners).
    pub sample_points: usize,
    /// Output triangles.
    pub triangles: usize,
    /// Median seconds of the vertex plus geometry passes (our methods only).
    pub vertex_geometry_median_s: Option<f64>,
    /// `vertex_geometry_median_s` over plain MT's on the same lattice, field, size and threads
    /// (the MT methods only): the measure of the clustering cost targets.
    pub vertex_geometry_over_plain: Option<f64>,
    /// `t_allocation_s / t_total_s` of the second pre-sampled call on a reused extractor (our
    /// methods only).
    pub second_call_allocation_share: Option<f64>,
}

/// All results of one benchmark run: `{"results": [...]}` plus the machine's load average.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct BenchReport {
    /// One row per field, size, thread count and method, in that nesting order.
    pub results: Vec<BenchRow>,
    /// Timed repetitions per row.
    pub reps: usize,
    /// Where our pools' workers ran: `os` or `pinned`.
    pub placement: &'static str,
    /// 1, 5 and 15 minute load averages before the run (Linux only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub load_average_before: Option<[f64; 3]>,
    /// The same after the run.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub load_average_after: Option<[f64; 3]>,
    /// The ratios the project's performance targets are stated in, per field and size
    /// ([`tracked_ratios`]), read off `results`.
    pub tracked: Vec<TrackedRatio>,
}

/// One of the ratios the performance targets are stated in, for one field and size: body-centred
/// RMT against plain MT, fast-surface-nets, and itself on one thread.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct TrackedRatio {
    /// Field name.
    pub field: &'static str,
    /// Cells per axis.
    pub n: usize,
    /// What is divided by what ([`TRACKED`] names them).
    pub ratio: &'static str,
    /// The value.
    pub value: f64,
}

/// The tracked ratios, in the order [`tracked_ratios`] lists them per field and size:
/// - integrated (checked) vertex + geometry passes over plain MT's, 1 thread;
/// - the same for integrated-unchecked;
/// - integrated ns per sample point over fast-surface-nets' ns per grid point, 1 thread;
/// - integrated wall time on 1 thread over on 2 threads;
/// - with the Python peers, over VTK Flying Edges (whole calls, 1 thread): integrated, plain MT
///   on the body-centred lattice, and our marching cubes.
pub const TRACKED: [&str; 7] = [
    "integrated / plain MT (vg, 1 thread)",
    "unchecked / plain MT (vg, 1 thread)",
    "integrated ns/point / fast-surface-nets (1 thread)",
    "integrated 1 thread / 2 threads (wall)",
    "integrated / Flying Edges (1 thread)",
    "plain MT body-centred / Flying Edges (1 thread)",
    "marching cubes / Flying Edges (1 thread)",
];

/// The tracked ratios ([`TRACKED`]) of `results`, per field and size in the order they first
/// appear; a ratio whose rows were not run (e.g. no 2-thread rows) is left out.
pub fn tracked_ratios(results: &[BenchRow]) -> Vec<TrackedRatio> {
    let row = |field: &str, n: usize, method: &str, threads: usize| {
        results
            .iter()
            .find(|r| (r.field, r.n, r.method, r.threads) == (field, n, method, threads))
    };
    let mut cases: Vec<(&'static str, usize)> = Vec::new();
    for r in results {
        if !cases.contains(&(r.field, r.n)) {
            cases.push((r.field, r.n));
        }
    }
    let integrated = BenchMethod::RmtBcdlIntegrated.name();
    let unchecked = BenchMethod::RmtBcdlUnchecked.name();
    let mut out = Vec::new();
    for (field, n) in cases {
        let values = [
            row(field, n, integrated, 1).and_then(|r| r.vertex_geometry_over_plain),
            row(field, n, unchecked, 1).and_then(|r| r.vertex_geometry_over_plain),
            row(field, n, integrated, 1).map(|r| r.point_ratio_to_fast_surface_nets),
            row(field, n, integrated, 1)
                .zip(row(field, n, integrated, 2))
                .map(|(one, two)| one.median_s / two.median_s),
            row(field, n, integrated, 1).and_then(|r| r.ratio_to_flying_edges),
            row(field, n, BenchMethod::MtBcdlNone.name(), 1).and_then(|r| r.ratio_to_flying_edges),
            row(field, n, BenchMethod::Mc.name(), 1).and_then(|r| r.ratio_to_flying_edges),
        ];
        for (ratio, value) in TRACKED.into_iter().zip(values) {
            if let Some(value) = value {
                out.push(TrackedRatio {
                    field,
                    n,
                    ratio,
                    value,
                });
            }
        }
    }
    out
}

/// The 1, 5 and 15 minute load averages from `/proc/loadavg`; `None` where unavailable.
pub fn load_average() -> Option<[f64; 3]> {
    let text = std::fs::read_to_string("/proc/loadavg").ok()?;
    let mut it = text.split_whitespace().map(|s| s.parse::<f64>().ok());
    Some([it.next()??, it.next()??, it.next()??])
}

/// CPU seconds used so far by this process, all threads together (Linux; `None` elsewhere):
/// unlike wall-clock time it hardly changes when other processes share the cores.
pub fn process_cpu_seconds() -> Option<f64> {
    #[cfg(target_os = "linux")]
    {
        let mut ts = libc::timespec {
            tv_sec: 0,
            tv_nsec: 0,
        };
        // SAFETY: `ts` is a valid, writable timespec owned by this frame for the whole call, and
        // the clock id is one Linux provides; a failure is reported by the return code, checked.
        let rc = unsafe { libc::clock_gettime(libc::CLOCK_PROCESS_CPUTIME_ID, &mut ts) };
        (rc == 0).then_some(ts.tv_sec as f64 + ts.tv_nsec as f64 * 1e-9)
    }
    #[cfg(not(target_os = "linux"))]
    {
        None
    }
}

/// Median of `values` (mean of the middle two for an even count); NaN when empty.
pub fn median(values: &[f64]) -> f64 {
    if values.is_empty() {
        return f64::NAN;
    }
    let mut v = values.to_vec();
    v.sort_by(f64::total_cmp);
    let m = v.len() / 2;
    if v.len() % 2 == 1 {
        v[m]
    } else {
        (v[m - 1] + v[m]) / 2.0
    }
}

/// Errors unless the surface stays inside corners `1..=n-2` on every axis of the `(n + 1)^3`
/// corner grid (x fastest): fast-surface-nets, called on the whole grid, makes no quads for
/// edges in its min planes nor for the edges of its last cell layer (the chunk-seam convention
/// that otherwise calls for a padded array), so only such a surface comes out closed.
pub fn check_clear_of_faces(
    values: &[f32],
    n: usize,
    field: &'static str,
) -> Result<(), BenchError> {
    let d = n + 1;
    let near = |c: usize| c == 0 || c + 2 >= d;
    for (i, &v) in values.iter().enumerate() {
        let (x, y, z) = (i % d, (i / d) % d, i / (d * d));
        if v < 0.0 && (near(x) || near(y) || near(z)) {
            return Err(BenchError::SurfaceAtFaces { field, n, x, y, z });
        }
    }
    Ok(())
}

/// The corner grid read by position for isomesh, which asks only for grid points (origin 0, unit
/// cells, no crossing refinement).
struct GridValues<'a> {
    values: &'a [f32],
    dim: usize,
}

impl isomesh::Sdf for GridValues<'_> {
    type Scalar = f32;

    #[inline]
    fn sample(&self, p: [f32; 3]) -> f32 {
        let [x, y, z] = p.map(|c| c as usize);
        self.values[x + self.dim * (y + self.dim * z)]
    }

    /// A constant: normals are not part of the compared work.
    #[inline]
    fn gradient(&self, _p: [f32; 3]) -> [f32; 3] {
        [0.0, 0.0, 1.0]
    }
}

/// One timed call.
#[derive(Clone, Copy, Debug)]
struct Timing {
    seconds: f64,
    cpu_seconds: Option<f64>,
    triangles: usize,
    stats: Option<(f64, f64)>, // (vertex + geometry seconds, allocation share)
}

/// A method ready to re-mesh its samples.
enum Runner {
    Ours {
        extractor: Box<Extractor>,
        settings: ExtractSettings,
        mesh: Mesh,
    },
    SurfaceNets {
        shape: RuntimeShape<u32, 3>,
        buffer: SurfaceNetsBuffer,
    },
    Isomesh {
        shape: isomesh::RuntimeShape3,
        mc: Box<isomesh::marching_cubes::MarchingCubes<f32>>,
        out: isomesh::MeshBuffer<f32>,
    },
}

/// The inputs of one field and size: the samples of both lattices.
struct Case {
    field: &'static str,
    n: usize,
    bcdl: Samples,
    simple: Samples,
}

impl Case {
    /// Samples `field` on both lattices (with the largest thread count: sampling is not timed).
    fn new(field: BenchField, n: usize, threads: usize) -> Result<Self, BenchError> {
        let f = field.build();
        let take = |method: BenchMethod| -> Result<Samples, BenchError> {
            let settings = method
                .settings(n, threads)
                .ok_or(BenchError::InvalidConfig {
                    what: "method",
                    message: format!("{} has no settings", method.name()),
                })?;
            let mut extractor = Extractor::new();
            // Every stored value is the field's: the peers are fed these samples.
            extractor.set_sampling(rmt_extract::Sampling::Dense);
            let mut mesh = Mesh::default();
            extractor
                .extract(&*f, &settings, &mut mesh)
                .map_err(|source| BenchError::Extract {
                    method: method.name(),
                    field: field.name(),
                    n,
                    source,
                })?;
            Ok(std::mem::take(extractor.samples_mut()))
        };
        let bcdl = take(BenchMethod::MtBcdlNone)?;
        let simple = take(BenchMethod::Mc)?;
        check_clear_of_faces(&simple.values, n, field.name())?;
        Ok(Self {
            field: field.name(),
            n,
            bcdl,
            simple,
        })
    }

    fn points(&self, method: BenchMethod) -> usize {
        if method.body_centred() {
            self.bcdl.point_count()
        } else {
            self.simple.point_count()
        }
    }

    fn runner(
        &self,
        method: BenchMethod,
        placement: ThreadPlacement,
    ) -> Result<Runner, BenchError> {
        let side = (self.n + 1) as u32;
        Ok(match method.settings(self.n, 1) {
            Some(settings) => {
                let mut extractor = Box::new(Extractor::new());
                extractor.set_thread_placement(placement);
                *extractor.samples_mut() = if method.body_centred() {
                    self.bcdl.clone()
                } else {
                    self.simple.clone()
                };
                Runner::Ours {
                    extractor,
                    settings,
                    mesh: Mesh::default(),
                }
            }
            None if method == BenchMethod::FastSurfaceNets => Runner::SurfaceNets {
                shape: RuntimeShape::<u32, 3>::new([side; 3]),
                buffer: SurfaceNetsBuffer::default(),
            },
            None => Runner::Isomesh {
                shape: isomesh::RuntimeShape3::new([side; 3]).map_err(|e| BenchError::Isomesh {
                    field: self.field,
                    n: self.n,
                    message: e.to_string(),
                })?,
                mc: Box::new(isomesh::marching_cubes::MarchingCubes::new()),
                out: isomesh::MeshBuffer::new(),
            },
        })
    }

    /// Runs `method` once with `threads`; times it in wall-clock and CPU seconds.
    fn run(
        &self,
        method: BenchMethod,
        runner: &mut Runner,
        threads: usize,
    ) -> Result<Timing, BenchError> {
        let cpu0 = process_cpu_seconds();
        let mut timing = self.run_once(method, runner, threads)?;
        timing.cpu_seconds = match (cpu0, process_cpu_seconds()) {
            (Some(a), Some(b)) => Some(b - a),
            _ => None,
        };
        Ok(timing)
    }

    /// Runs `method` once with `threads` and times it (wall clock).
    fn run_once(
        &self,
        method: BenchMethod,
        runner: &mut Runner,
        threads: usize,
    ) -> Result<Timing, BenchError> {
        let corners = &self.simple.values;
        match runner {
            Runner::Ours {
                extractor,
                settings,
                mesh,
            } => {
                settings.threads = threads;
                let t = Instant::now();
                let stats: Stats =
                    extractor
                        .extract_presampled(settings, mesh)
                        .map_err(|source| BenchError::Extract {
                            method: method.name(),
                            field: self.field,
                            n: self.n,
                            source,
                        })?;
                let seconds = t.elapsed().as_secs_f64();
                let share = if stats.t_total_s > 0.0 {
                    stats.t_allocation_s / stats.t_total_s
                } else {
                    0.0
                };
                Ok(Timing {
                    seconds,
                    cpu_seconds: None,
                    triangles: stats.triangles,
                    stats: Some((stats.t_vertex_s + stats.t_geometry_s, share)),
                })
            }
            Runner::SurfaceNets { shape, buffer } => {
                let max = self.n as u32;
                let t = Instant::now();
                surface_nets(corners, shape, [0; 3], [max; 3], buffer);
                let seconds = t.elapsed().as_secs_f64();
                Ok(Timing {
                    seconds,
                    cpu_seconds: None,
                    triangles: buffer.indices.len() / 3,
                    stats: None,
                })
            }
            Runner::Isomesh { shape, mc, out } => {
                let grid = GridValues {
                    values: corners,
                    dim: self.n + 1,
                };
                let t = Instant::now();
                out.reset();
                mc.extract(&grid, shape, [0.0; 3], 1.0, out)
                    .map_err(|e| BenchError::Isomesh {
                        field: self.field,
                        n: self.n,
                        message: e.to_string(),
                    })?;
                let seconds = t.elapsed().as_secs_f64();
                Ok(Timing {
                    seconds,
                    cpu_seconds: None,
                    triangles: out.triangle_count(),
                    stats: None,
                })
            }
        }
    }
}

/// Runs the benchmark; `progress` receives one line per field and size as it starts.
pub fn run_bench(
    config: &BenchConfig,
    mut progress: impl FnMut(&str),
) -> Result<BenchReport, BenchError> {
    config.check()?;
    let load_average_before = load_average();
    let sample_threads = config.threads.iter().copied().max().unwrap_or(1);
    // The Python peers read the dumped values; without --dump they go to a temporary folder.
    let dump_dir = match (&config.dump, &config.python) {
        (Some(dir), _) => Some(dir.clone()),
        (None, Some(_)) => {
            Some(std::env::temp_dir().join(format!("rmt-bench-values-{}", std::process::id())))
        }
        (None, None) => None,
    };
    let result = run_cases(config, dump_dir.as_deref(), sample_threads, &mut progress);
    if let (None, Some(dir)) = (&config.dump, &dump_dir) {
        // Best effort: a leftover temporary folder is not worth failing a finished run.
        let _ = std::fs::remove_dir_all(dir);
    }
    let results = result?;
    Ok(BenchReport {
        tracked: tracked_ratios(&results),
        results,
        reps: config.reps,
        placement: config.placement.name(),
        load_average_before,
        load_average_after: load_average(),
    })
}

/// The rows of every field and size (see [`run_bench`]); the values are dumped into `dump_dir`
/// when it is set.
fn run_cases(
    config: &BenchConfig,
    dump_dir: Option<&std::path::Path>,
    sample_threads: usize,
    progress: &mut impl FnMut(&str),
) -> Result<Vec<BenchRow>, BenchError> {
    let methods = BenchMethod::ALL;
    let mut results = Vec::new();
    for &field in &config.fields {
        for &n in &config.sizes {
            progress(&format!("{} at {n}^3: sampling", field.name()));
            let case = Case::new(field, n, sample_threads)?;
            if let Some(dir) = dump_dir {
                dump_values(dir, field.name(), n, &case.simple)?;
            }
            let mut runners = methods
                .iter()
                .map(|&m| case.runner(m, config.placement))
                .collect::<Result<Vec<_>, _>>()?;
            // Warm-up: two untimed calls per thread count; the second gives the allocation share.
            let mut share = vec![vec![None; methods.len()]; config.threads.len()];
            for (ti, &threads) in config.threads.iter().enumerate() {
                for (mi, (&m, runner)) in methods.iter().zip(&mut runners).enumerate() {
                    case.run(m, runner, threads)?;
                    share[ti][mi] = case.run(m, runner, threads)?.stats.map(|s| s.1);
                }
            }
            progress(&format!(
                "{} at {n}^3: {} repetitions",
                field.name(),
                config.reps
            ));
            let mut times = vec![vec![Vec::new(); methods.len()]; config.threads.len()];
            let mut cpu = vec![vec![Vec::new(); methods.len()]; config.threads.len()];
            let mut passes = vec![vec![Vec::new(); methods.len()]; config.threads.len()];
            let mut triangles = vec![vec![0; methods.len()]; config.threads.len()];
            let mut peers = Vec::new();
            for rep in 0..config.reps {
                // The Python peers run once, between the two halves of our repetitions.
                if let (Some(python), Some(dir), true) =
                    (&config.python, dump_dir, rep == config.reps / 2)
                {
                    progress(&format!(
                        "{} at {n}^3: Flying Edges and scikit-image ({python})",
                        field.name()
                    ));
                    peers = time_peers(python, dir, field.name(), n, config.reps)?;
                }
                for (ti, &threads) in config.threads.iter().enumerate() {
                    for (mi, (&m, runner)) in methods.iter().zip(&mut runners).enumerate() {
                        let timing = case.run(m, runner, threads)?;
                        times[ti][mi].push(timing.seconds);
                        cpu[ti][mi].extend(timing.cpu_seconds);
                        triangles[ti][mi] = timing.triangles;
                        if let Some((vg, _)) = timing.stats {
                            passes[ti][mi].push(vg);
                        }
                    }
                }
            }
            let reference = methods
                .iter()
                .position(|&m| m == BenchMethod::FastSurfaceNets)
                .unwrap_or(0);
            for (ti, &threads) in config.threads.iter().enumerate() {
                let fsn = median(&times[ti][reference]);
                let fsn_per_point = fsn / case.points(methods[reference]) as f64;
                for (mi, &m) in methods.iter().enumerate() {
                    let median_s = median(&times[ti][mi]);
                    let points = case.points(m);
                    let ours = m.settings(n, threads).is_some();
                    results.push(BenchRow {
                        field: field.name(),
                        n,
                        method: m.name(),
                        threads,
                        threads_used: if ours { threads } else { 1 },
                        median_s,
                        cpu_median_s: (!cpu[ti][mi].is_empty()).then(|| median(&cpu[ti][mi])),
                        ns_per_point: median_s * 1e9 / points as f64,
                        ratio_to_fast_surface_nets: median_s / fsn,
                        point_ratio_to_fast_surface_nets: median_s / points as f64 / fsn_per_point,
                        sample_points: points,
                        triangles: triangles[ti][mi],
                        vertex_geometry_median_s: ours.then(|| median(&passes[ti][mi])),
                        vertex_geometry_over_plain: m.plain().and_then(|p| {
                            let pi = methods.iter().position(|&x| x == p)?;
                            Some(median(&passes[ti][mi]) / median(&passes[ti][pi]))
                        }),
                        second_call_allocation_share: share[ti][mi],
                        ratio_to_flying_edges: None,
                    });
                }
                let points = case.simple.point_count();
                for peer in &peers {
                    results.push(BenchRow {
                        field: field.name(),
                        n,
                        method: peer.method,
                        threads,
                        threads_used: 1,
                        median_s: peer.median_s,
                        cpu_median_s: None,
                        ns_per_point: peer.median_s * 1e9 / points as f64,
                        ratio_to_fast_surface_nets: peer.median_s / fsn,
                        point_ratio_to_fast_surface_nets: peer.median_s
                            / points as f64
                            / fsn_per_point,
                        sample_points: points,
                        triangles: peer.triangles,
                        vertex_geometry_median_s: None,
                        vertex_geometry_over_plain: None,
                        second_call_allocation_share: None,
                        ratio_to_flying_edges: None,
                    });
                }
            }
            if let Some(fe) = peers.iter().find(|p| p.method == "vtk_flying_edges") {
                for row in results
                    .iter_mut()
                    .filter(|r| r.field == field.name() && r.n == n)
                {
                    row.ratio_to_flying_edges = Some(row.median_s / fe.median_s);
                }
            }
        }
    }
    Ok(results)
}

/// The report as an aligned text table, one row per result, plus the load averages.
pub fn format_table(report: &BenchReport) -> String {
    use std::fmt::Write;
    let mut s = String::new();
    let _ = writeln!(
        s,
        "{:<9} {:>4} {:>3} {:<22} {:>10} {:>10} {:>8} {:>7} {:>8} {:>6} {:>10} {:>6} {:>7} {:>9}",
        "field",
        "n",
        "thr",
        "method",
        "median_ms",
        "cpu_ms",
        "ns/point",
        "x_fsn",
        "x_fsn/pt",
        "x_fe",
        "vg_ms",
        "vg_xmt",
        "alloc2",
        "triangles"
    );
    for r in &report.results {
        let vg = r
            .vertex_geometry_median_s
            .map_or("-".to_string(), |v| format!("{:.3}", v * 1e3));
        let over_plain = r
            .vertex_geometry_over_plain
            .map_or("-".to_string(), |v| format!("{v:.2}"));
        let cpu = r
            .cpu_median_s
            .map_or("-".to_string(), |v| format!("{:.3}", v * 1e3));
        let over_fe = r
            .ratio_to_flying_edges
            .map_or("-".to_string(), |v| format!("{v:.2}"));
        let alloc = r
            .second_call_allocation_share
            .map_or("-".to_string(), |v| format!("{:.2}%", v * 100.0));
        let thr = if r.threads_used == r.threads {
            r.threads.to_string()
        } else {
            format!("{}*", r.threads_used)
        };
        let _ = writeln!(
            s,
            "{:<9} {:>4} {:>3} {:<22} {:>10.3} {:>10} {:>8.2} {:>7.2} {:>8.2} {:>6} {:>10} {:>6} {:>7} {:>9}",
            r.field,
            r.n,
            thr,
            r.method,
            r.median_s * 1e3,
            cpu,
            r.ns_per_point,
            r.ratio_to_fast_surface_nets,
            r.point_ratio_to_fast_surface_nets,
            over_fe,
            vg,
            over_plain,
            alloc,
            r.triangles
        );
    }
    if !report.tracked.is_empty() {
        let _ = writeln!(s, "tracked ratios (body-centred RMT; medians of this run):");
        for t in &report.tracked {
            let _ = writeln!(
                s,
                "  {:<9} {:>4}  {:<52} {:>6.2}",
                t.field, t.n, t.ratio, t.value
            );
        }
    }
    let load = |l: Option<[f64; 3]>| {
        l.map_or("n/a".to_string(), |[a, b, c]| {
            format!("{a:.2} {b:.2} {c:.2}")
        })
    };
    let _ = writeln!(
        s,
        "{} repetitions, medians; cpu = CPU time of all threads; * = single-threaded peer; \
         x_fsn = time over fast-surface-nets'; x_fsn/pt = ns/point over fast-surface-nets' ns per \
         grid point (the target's measure); x_fe = time over VTK Flying Edges' (--python); vg = vertex + geometry passes (wall); vg_xmt = vg over \
         plain MT's on the same lattice; alloc2 = \
         allocation share of a second call; workers placed by: {}; load average before {}, after {}",
        report.reps,
        report.placement,
        load(report.load_average_before),
        load(report.load_average_after)
    );
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip_and_unknown_fields_are_refused() {
        for f in BenchField::ALL {
            assert_eq!(BenchField::parse(f.name()).unwrap(), f);
        }
        let err = BenchField::parse("torus").unwrap_err().to_string();
        assert!(err.contains("torus") && err.contains("sphere"), "{err}");
    }

    #[test]
    fn median_of_odd_and_even_counts() {
        assert_eq!(median(&[3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(&[4.0, 1.0, 3.0, 2.0]), 2.5);
        assert!(median(&[]).is_nan());
    }

    #[test]
    fn bad_configs_name_the_option() {
        let base = BenchConfig::default();
        let cases = [
            (
                BenchConfig {
                    sizes: vec![],
                    ..base.clone()
                },
                "sizes",
            ),
            (
                BenchConfig {
                    sizes: vec![1],
                    ..base.clone()
                },
                "sizes",
            ),
            (
                BenchConfig {
                    reps: 0,
                    ..base.clone()
                },
                "reps",
            ),
            (
                BenchConfig {
                    threads: vec![0],
                    ..base.clone()
                },
                "threads",
            ),
            (
                BenchConfig {
                    fields: vec![],
                    ..base.clone()
                },
                "fields",
            ),
        ];
        for (config, what) in cases {
            let err = config.check().unwrap_err().to_string();
            assert!(err.contains(what), "{err}");
        }
        assert!(base.check().is_ok());
    }

    #[test]
    fn surfaces_near_the_faces_are_refused() {
        let n = 8;
        let d = n + 1;
        let mut values = vec![1.0f32; d * d * d];
        values[4 + d * (4 + d * 4)] = -1.0;
        assert!(check_clear_of_faces(&values, n, "t").is_ok());
        values[(n - 1) + d * (4 + d * 4)] = -1.0;
        let err = check_clear_of_faces(&values, n, "t")
            .unwrap_err()
            .to_string();
        assert!(err.contains("(7, 4, 4)"), "{err}");
    }

    #[test]
    fn the_sphere_is_too_near_the_faces_at_eight_cells() {
        assert!(matches!(
            Case::new(BenchField::Sphere, 8, 1),
            Err(BenchError::SurfaceAtFaces { .. })
        ));
    }

    /// The peers, fed our corner grid, mesh the same closed surface as our marching cubes.
    #[test]
    fn peers_mesh_a_closed_surface_from_the_shared_samples() {
        let case = Case::new(BenchField::Sphere, 16, 1).unwrap();
        let mut mc = case.runner(BenchMethod::Mc, ThreadPlacement::Os).unwrap();
        let ours = case.run(BenchMethod::Mc, &mut mc, 1).unwrap();
        let mut iso = case
            .runner(BenchMethod::IsomeshMc, ThreadPlacement::Os)
            .unwrap();
        let theirs = case.run(BenchMethod::IsomeshMc, &mut iso, 1).unwrap();
        // Marching cubes is marching cubes: same case table size, same triangle count.
        assert_eq!(ours.triangles, theirs.triangles);
        let mut fsn = case
            .runner(BenchMethod::FastSurfaceNets, ThreadPlacement::Os)
            .unwrap();
        let nets = case.run(BenchMethod::FastSurfaceNets, &mut fsn, 1).unwrap();
        assert!(nets.triangles > 0);
        for runner in [&iso, &fsn] {
            let mesh = match runner {
                Runner::SurfaceNets { buffer, .. } => {
                    Mesh::from_triangles(buffer.positions.clone(), buffer.indices.clone())
                }
                Runner::Isomesh { out, .. } => {
                    Mesh::from_triangles(out.positions.clone(), out.indices.clone())
                }
                Runner::Ours { .. } => unreachable!(),
            };
            let report = rmt_mesh::validate(&mesh, &|_| false);
            assert_eq!(report.boundary_edges_interior, 0, "{report:?}");
            assert_eq!(report.components, 1);
        }
    }

    #[test]
    fn a_small_run_has_one_row_per_field_size_threads_and_method() {
        let config = BenchConfig {
            fields: vec![BenchField::Sphere],
            sizes: vec![12, 16],
            reps: 3,
            threads: vec![1, 2],
            placement: ThreadPlacement::Os,
            dump: None,
            python: None,
        };
        let mut lines = 0;
        let report = run_bench(&config, |_| lines += 1).unwrap();
        assert_eq!(lines, 4);
        assert_eq!(report.results.len(), 2 * 2 * BenchMethod::ALL.len());
        for r in &report.results {
            assert!(r.median_s.is_finite() && r.median_s > 0.0, "{r:?}");
            assert!(r.triangles > 0, "{r:?}");
            let points = if r.method.contains("bcdl") {
                (r.n + 1).pow(3) + r.n.pow(3) + 6 * r.n * r.n
            } else {
                (r.n + 1).pow(3)
            };
            assert_eq!(r.sample_points, points, "{r:?}");
            assert!((r.ns_per_point - r.median_s * 1e9 / points as f64).abs() < 1e-9);
            let ours = !matches!(r.method, "fast_surface_nets" | "isomesh_mc");
            assert_eq!(r.vertex_geometry_median_s.is_some(), ours);
            // Vertex + geometry over plain MT's on the same lattice (MT methods only).
            let plain = match r.method {
                "mt_bcdl_none" | "rmt_bcdl_integrated" | "rmt_bcdl_unchecked" => {
                    Some("mt_bcdl_none")
                }
                "mt_simple_none" | "rmt_simple_integrated" => Some("mt_simple_none"),
                _ => None,
            };
            assert_eq!(
                r.vertex_geometry_over_plain.is_some(),
                plain.is_some(),
                "{r:?}"
            );
            if let (Some(plain), Some(ratio)) = (plain, r.vertex_geometry_over_plain) {
                let p = report
                    .results
                    .iter()
                    .find(|f| {
                        f.method == plain && (f.field, f.n, f.threads) == (r.field, r.n, r.threads)
                    })
                    .expect("a plain MT row per field, size and thread count");
                let expected =
                    r.vertex_geometry_median_s.unwrap() / p.vertex_geometry_median_s.unwrap();
                assert!((ratio - expected).abs() < 1e-9 * expected, "{r:?}");
            }
            assert_eq!(r.second_call_allocation_share.is_some(), ours);
            assert_eq!(r.threads_used, if ours { r.threads } else { 1 });
            if cfg!(target_os = "linux") {
                assert!(r.cpu_median_s.is_some_and(|c| c >= 0.0), "{r:?}");
            }
            if let Some(share) = r.second_call_allocation_share {
                assert!((0.0..=1.0).contains(&share), "{r:?}");
            }
            if r.method == "fast_surface_nets" {
                assert_eq!(r.ratio_to_fast_surface_nets, 1.0);
                assert!((r.point_ratio_to_fast_surface_nets - 1.0).abs() < 1e-12);
            }
            // Per point: the time ratio scaled by the grid's points over the method's.
            let fsn = report
                .results
                .iter()
                .find(|f| {
                    f.method == "fast_surface_nets"
                        && (f.field, f.n, f.threads) == (r.field, r.n, r.threads)
                })
                .expect("a fast-surface-nets row per field, size and thread count");
            let expected = r.ns_per_point / fsn.ns_per_point;
            assert!(
                (r.point_ratio_to_fast_surface_nets - expected).abs() < 1e-9 * expected,
                "{r:?}"
            );
        }
        let json = serde_json::to_value(&report).unwrap();
        let first = &json["results"][0];
        for key in [
            "field",
            "n",
            "method",
            "threads",
            "median_s",
            "ns_per_point",
            "ratio_to_fast_surface_nets",
            "point_ratio_to_fast_surface_nets",
        ] {
            assert!(!first[key].is_null(), "{key} missing in {first}");
        }
        let table = format_table(&report);
        assert!(table.contains("rmt_bcdl_integrated") && table.contains("rmt_bcdl_unchecked"));
        assert!(table.contains("vg_xmt"));
        // The tracked ratios: the first four per field and size (both thread counts ran; the
        // three over Flying Edges need the Python peers), each the quotient of the rows it names.
        assert_eq!(report.tracked.len(), 2 * 4, "{:?}", report.tracked);
        let get = |n: usize, method: &str, threads: usize| {
            report
                .results
                .iter()
                .find(|r| (r.n, r.method, r.threads) == (n, method, threads))
                .expect("a row")
        };
        for t in &report.tracked {
            let int1 = get(t.n, "rmt_bcdl_integrated", 1);
            let expected = match TRACKED.iter().position(|&r| r == t.ratio) {
                Some(0) => int1.vertex_geometry_over_plain.unwrap(),
                Some(1) => get(t.n, "rmt_bcdl_unchecked", 1)
                    .vertex_geometry_over_plain
                    .unwrap(),
                Some(2) => int1.point_ratio_to_fast_surface_nets,
                Some(3) => int1.median_s / get(t.n, "rmt_bcdl_integrated", 2).median_s,
                _ => panic!("unknown ratio {t:?}"),
            };
            assert_eq!(t.value, expected, "{t:?}");
            assert!(table.contains(t.ratio), "{t:?} not in the table");
        }
        assert_eq!(json["tracked"].as_array().map(Vec::len), Some(8));
        // One thread only: no scaling ratio.
        let one: Vec<BenchRow> = report
            .results
            .iter()
            .filter(|r| r.threads == 1)
            .cloned()
            .collect();
        let tracked = tracked_ratios(&one);
        assert_eq!(tracked.len(), 2 * 3);
        assert!(tracked.iter().all(|t| t.ratio != TRACKED[3]));
    }

    /// The Python peers' wiring, with a stand-in interpreter (a shell script) that checks what
    /// it is asked and answers as `peer_bench.py` would: the values are dumped before it runs,
    /// its rows join the results, and every row gets its ratio over its Flying Edges.
    #[cfg(unix)]
    #[test]
    fn python_peer_rows_join_the_results_with_ratios_over_flying_edges() {
        use std::os::unix::fs::PermissionsExt;
        let dir = tempfile::tempdir().unwrap();
        let fake = dir.path().join("fake-python");
        std::fs::write(
            &fake,
            "#!/bin/sh\n\
             # args: SCRIPT DIR --only NAME --reps R\n\
             [ \"$3\" = --only ] && [ -f \"$2/$4.json\" ] && [ -f \"$2/$4.f32\" ] || exit 3\n\
             n=${4#sphere_}\n\
             echo field,n,method,threads,median_ms,min_ms,reps,triangles\n\
             echo sphere,$n,vtk_flying_edges,1,0.010,0.009,$6,77\n\
             echo sphere,$n,skimage_mc,1,0.040,0.030,$6,78\n",
        )
        .unwrap();
        std::fs::set_permissions(&fake, std::fs::Permissions::from_mode(0o755)).unwrap();
        let dump = dir.path().join("values");
        let config = BenchConfig {
            fields: vec![BenchField::Sphere],
            sizes: vec![12, 16],
            reps: 2,
            threads: vec![1],
            placement: ThreadPlacement::Os,
            dump: Some(dump.clone()),
            python: Some(fake.display().to_string()),
        };
        let report = run_bench(&config, |_| {}).unwrap();
        assert_eq!(report.results.len(), 2 * (BenchMethod::ALL.len() + 2));
        for n in [12, 16] {
            assert!(dump.join(format!("sphere_{n}.json")).is_file());
            let row = |m: &str| {
                report
                    .results
                    .iter()
                    .find(|r| r.n == n && r.method == m)
                    .unwrap()
            };
            let fe = row("vtk_flying_edges");
            assert_eq!((fe.triangles, fe.threads_used), (77, 1));
            assert!((fe.median_s - 1e-5).abs() < 1e-12);
            assert_eq!(row("skimage_mc").ratio_to_flying_edges, Some(4.0));
            let mc = row("mc");
            let over = mc.ratio_to_flying_edges.unwrap();
            assert!((over - mc.median_s / 1e-5).abs() < 1e-9 * over, "{over}");
        }
        let tracked: Vec<&str> = report.tracked.iter().map(|t| t.ratio).collect();
        assert!(tracked.contains(&"marching cubes / Flying Edges (1 thread)"));
        assert!(tracked.contains(&"integrated / Flying Edges (1 thread)"));
        // A peer that fails stops the run with its message.
        let config = BenchConfig {
            python: Some("/bin/false".into()),
            sizes: vec![12],
            ..config
        };
        let err = run_bench(&config, |_| {}).unwrap_err().to_string();
        assert!(
            err.contains("/bin/false") && err.contains("sphere_12"),
            "{err}"
        );
    }
}
