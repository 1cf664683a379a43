//! Isosurface extraction: regularised marching tetrahedra (RMT) and its baselines.
//!
//! # Public API
//!
//! - [`Extractor`]: samples a [`ScalarField`] and meshes it, keeping every buffer between calls,
//!   as a game would ([`Extractor::extract`], [`Extractor::extract_presampled`],
//!   [`Extractor::extract_borrowed`] on the caller's values in place; the
//!   [`BufferPolicy`], [`Sampling`] and [`ThreadPlacement`] it runs with; with
//!   [`Extractor::set_recording`], the anchor cell of every triangle and the clustering's
//!   activity);
//! - [`ExtractSettings`]: the [`Grid`], the [`Lattice`], the [`Method`] (marching tetrahedra or
//!   cubes, or surface nets as a peer), the [`Clustering`] mode, the [`NormalMode`], the
//!   [`Boundary`] of the body-centred lattice (ghosts or pyramids), and for chunks the
//!   [`Tiling`] and the kept [`CellRange`];
//! - [`Stats`]: counters, stage timings and bytes of one extraction ([`Stats::merge_steps_text`]
//!   splits integrated clustering's time); [`ExtractError`] when it cannot run;
//! - [`measure()`]: the quality of a mesh ([`Measurement`]; [`measure::on_box_boundary`]);
//! - [`lattice`]: the lattices' derived tables ([`lattice::LatticeTables`]); [`samples`]: the
//!   sample array ([`Samples`], [`samples::sampled_lattice`]); [`threads`]: the worker pools
//!   ([`thread_pool`]);
//! - [`finish`]: what an engine does to any method's mesh before upload: meshoptimizer's
//!   simplifier down to a triangle budget ([`finish::simplify_to`]) and its vertex-cache order
//!   ([`finish::optimize_vertex_cache`]).
//!
//! # The passes
//!
//! One extraction runs these, in this order (see ARCHITECTURE.md for the picture); each pass
//! is one internal module, which takes the buffer it writes and borrows what it reads:
//! 1. **sampling**: evaluate the field at the points of the lattice ([`samples`]), in parallel,
//!    block by block; blocks whose [`ScalarField::range`] excludes the isovalue are skipped
//!    (their points only need a sign; [`Sampling`]), so the cost follows the surface;
//! 2. **vertex pass**: classify the points into inside bits, find crossed lattice edges, give
//!    each crossing to its nearer end point and number it, and propose clusters (`mt::crossings`,
//!    the proposal rules in `mt::clustering::proposal`): a partition of the crossings into
//!    groups from each point's islands of nearby crossings; order-free by construction;
//! 3. **integrated clustering** (`mt::clustering`): plain MT's triangles are listed once
//!    (`plain`), every group is tested in the mesh where all groups are contracted at once
//!    (`quotient`), failures are repaired by splitting groups in parallel rounds until every
//!    group passes (`repair`), then variants of split islands, lone crossings and sliver pairs
//!    are added the same way (`additions`); integrated-unchecked keeps every proposal;
//! 4. **emission** (`mt::emission`): one or two triangles per crossed tetrahedron from the case
//!    table, written with the clustered vertex ids; collapsed ones are left out; without ghosts,
//!    then the pyramids of the box faces (`mt::pyramids`);
//! 5. **post-processing** (`post`), for the modes that simplify after the fact: edge collapse
//!    under the exact check, or meshoptimizer's simplifier;
//! 6. **normals**.
//!
//! Marching cubes (`mc`) replaces steps 2 to 5 for [`Method::Mc`], and surface nets
//! (`surface_nets`: the `fast-surface-nets` crate on the same simple-cubic samples, its
//! non-manifold edges left in and reported by validation) for [`Method::SurfaceNets`].
//!
//! Cost, on a 2-vCPU Intel Xeon VM on one thread (pre-sampled values; README, Performance):
//! about 12.6 ns per sample point for marching tetrahedra on the body-centred lattice without
//! clustering (asteroid, 64^3); integrated clustering costs 2.3-2.7 times that (vertex and
//! geometry passes, five pinned bench runs; mostly its quotient tests, which
//! [`Stats::merge_steps`] splits out), integrated-unchecked 1.11-1.17 times.
//! Reproduce with `cargo run --release -p experiments -- bench` (side by side with
//! fast-surface-nets and isomesh) or `cargo run --release -p rmt-extract --example passes`.
//!
//! ```
//! use rmt_extract::{Extractor, ExtractSettings, Grid, Lattice, Clustering};
//! use rmt_fields::Sphere;
//! use rmt_mesh::Mesh;
//!
//! let settings = ExtractSettings::new(Grid::cube(16, 1.0), Lattice::BodyCentred, Clustering::Integrated);
//! let mut extractor = Extractor::new();
//! let mut mesh = Mesh::default();
//! let stats = extractor.extract(&Sphere::new(glam::Vec3::ZERO, 0.8), &settings, &mut mesh).unwrap();
//! assert_eq!(stats.triangles, mesh.triangle_count());
//! assert!(stats.clusters_committed > 0);
//! ```
//!
//! Orientation convention: triangles are counter-clockwise seen from the side of increasing
//! field value, so their right-hand normals point outward for a signed distance field.

mod error;
pub mod finish;
pub(crate) mod incidence;
pub mod lattice;
pub(crate) mod mc;
pub mod measure;
pub(crate) mod mt;
pub(crate) mod post;
pub mod samples;
pub(crate) mod settings;
pub(crate) mod stats;
pub(crate) mod surface_nets;
pub mod threads;
pub(crate) mod tiles;
pub(crate) mod util;

pub use error::ExtractError;
pub use measure::{measure, Measurement};
pub use post::{CollapseAttempt, CollapseOutcome};
pub use samples::{SampleValues, Samples, Sampling};
pub use settings::{
    Boundary, CellRange, Clustering, ExtractSettings, Grid, Lattice, Method, NormalMode, Tiling,
};
pub use stats::Stats;
pub use threads::{thread_pool, ThreadPlacement};

use rmt_fields::ScalarField;
use rmt_mesh::Mesh;

/// What an [`Extractor`] does with its working memory.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum BufferPolicy {
    /// Keep every table and scratch buffer between calls: re-meshing allocates nothing once the
    /// sizes have been seen (for repeated extractions, e.g. chunks). The peak is the sum of the
    /// tables of all passes.
    #[default]
    Reuse,
    /// Free each table as soon as its last reader is done (the vertex pass's tables after the
    /// geometry pass, the cluster candidates after the commit, the adjacency before the output
    /// indices are written) and everything but the samples at the end: the lowest peak, for one
    /// large extraction; every call allocates again.
    Lean,
}

/// A reusable extractor: keeps its sample array, per-point tables and scratch buffers between
/// calls so that re-meshing allocates nothing once the sizes have been seen (see
/// [`BufferPolicy`] for the low-memory alternative).
#[derive(Default)]
pub struct Extractor {
    pub(crate) samples: Samples,
    pub(crate) mt: mt::MtBuffers,
    pub(crate) merge: post::MergeBuffers,
    pub(crate) surface_nets: surface_nets::SurfaceNetsBuffers,
    pub(crate) mc: mc::McBuffers,
    /// Thread pools by worker count; `true` marks a pool given by [`Extractor::set_pool`] (the
    /// caller's: kept when the placement changes).
    pub(crate) pools: Vec<(usize, std::sync::Arc<rayon::ThreadPool>, bool)>,
    pub(crate) sampling: Sampling,
    pub(crate) placement: ThreadPlacement,
    /// Edge collapse's candidates and outcomes, when recording ([`Extractor::collapse_log`]).
    pub(crate) collapse_log: Vec<CollapseAttempt>,
    /// Marching cubes and plain MT write their meshes in array order
    /// ([`Extractor::set_array_order`]).
    pub(crate) array_order: bool,
}

impl Extractor {
    /// An extractor with empty buffers.
    pub fn new() -> Self {
        Self::default()
    }

    /// Sets what happens to the working memory (default [`BufferPolicy::Reuse`]).
    ///
    /// ```
    /// use rmt_extract::{BufferPolicy, Clustering, ExtractSettings, Extractor, Grid, Lattice};
    /// let mut ex = Extractor::new();
    /// ex.set_buffer_policy(BufferPolicy::Lean);
    /// let settings = ExtractSettings::new(Grid::cube(16, 1.0), Lattice::BodyCentred,
    ///     Clustering::Integrated);
    /// let mut mesh = rmt_mesh::Mesh::default();
    /// ex.extract(&rmt_fields::Sphere::new(glam::Vec3::ZERO, 0.6), &settings, &mut mesh).unwrap();
    /// assert!(mesh.triangle_count() > 0);
    /// ```
    pub fn set_buffer_policy(&mut self, policy: BufferPolicy) {
        self.mt.lean = policy == BufferPolicy::Lean;
    }

    /// Sets how [`Extractor::extract`] samples the field (default [`Sampling::Sparse`]: the same
    /// meshes, fewer evaluations; [`Sampling::Dense`] when every stored value must be the
    /// field's, e.g. to edit or export [`Extractor::samples`]).
    ///
    /// ```
    /// use rmt_extract::{Clustering, ExtractSettings, Extractor, Grid, Lattice, Sampling};
    /// let s = ExtractSettings::new(Grid::cube(64, 1.0), Lattice::BodyCentred, Clustering::None);
    /// let sphere = rmt_fields::Sphere::new(glam::Vec3::ZERO, 0.5);
    /// let (mut a, mut b) = (rmt_mesh::Mesh::default(), rmt_mesh::Mesh::default());
    /// let sparse = Extractor::new().extract(&sphere, &s, &mut a).unwrap();
    /// let mut dense = Extractor::new();
    /// dense.set_sampling(Sampling::Dense);
    /// let all = dense.extract(&sphere, &s, &mut b).unwrap();
    /// assert_eq!((a.positions, a.indices), (b.positions, b.indices));
    /// assert!(sparse.points_sampled < all.points_sampled / 2 && sparse.blocks_skipped > 0);
    /// ```
    pub fn set_sampling(&mut self, sampling: Sampling) {
        self.sampling = sampling;
    }

    /// Sets where the workers of the extractor's own thread pools run (default
    /// [`ThreadPlacement::Os`]; see [`threads`] for why [`ThreadPlacement::Pinned`] exists). Pools
    /// built before with another placement are dropped; pools given by [`Extractor::set_pool`]
    /// are the caller's and are kept. The meshes do not depend on it.
    ///
    /// ```
    /// use rmt_extract::{Clustering, ExtractSettings, Extractor, Grid, Lattice, ThreadPlacement};
    /// let mut s = ExtractSettings::new(Grid::cube(16, 1.0), Lattice::BodyCentred,
    ///     Clustering::Integrated);
    /// s.threads = 2;
    /// let sphere = rmt_fields::Sphere::new(glam::Vec3::ZERO, 0.6);
    /// let (mut a, mut b) = (rmt_mesh::Mesh::default(), rmt_mesh::Mesh::default());
    /// Extractor::new().extract(&sphere, &s, &mut a).unwrap();
    /// let mut pinned = Extractor::new();
    /// pinned.set_thread_placement(ThreadPlacement::Pinned);
    /// pinned.extract(&sphere, &s, &mut b).unwrap();
    /// assert_eq!((a.positions, a.indices), (b.positions, b.indices));
    /// ```
    pub fn set_thread_placement(&mut self, placement: ThreadPlacement) {
        if placement != self.placement {
            self.pools.retain(|&(_, _, given)| given);
            self.placement = placement;
        }
    }

    /// Runs extractions with `pool.current_num_threads()` threads on `pool` instead of a pool of
    /// the extractor's own. Callers already running on a rayon pool (e.g. meshing chunks in
    /// parallel) pass it, so that the extractor's parallel passes run inline on the calling
    /// worker and its siblings instead of being handed to other threads and back.
    pub fn set_pool(&mut self, pool: std::sync::Arc<rayon::ThreadPool>) {
        let threads = pool.current_num_threads();
        self.pools.retain(|(n, _, _)| *n != threads);
        self.pools.push((threads, pool, true));
    }

    /// The thread pool for `threads` workers, built once and kept.
    pub(crate) fn pool(
        &mut self,
        threads: usize,
    ) -> Result<std::sync::Arc<rayon::ThreadPool>, ExtractError> {
        if let Some((_, p, _)) = self.pools.iter().find(|(n, _, _)| *n == threads) {
            return Ok(p.clone());
        }
        let pool = thread_pool(threads, self.placement).map_err(|e| ExtractError::ThreadPool {
            threads,
            message: e.to_string(),
        })?;
        let pool = std::sync::Arc::new(pool);
        self.pools.push((threads, pool.clone(), false));
        Ok(pool)
    }

    /// Samples `field` and extracts its surface into `mesh` (cleared first; its allocations are
    /// reused). Returns the counters and stage timings.
    pub fn extract(
        &mut self,
        field: &dyn ScalarField,
        settings: &ExtractSettings,
        mesh: &mut Mesh,
    ) -> Result<Stats, ExtractError> {
        let start = std::time::Instant::now();
        settings.check()?;
        let mut stats = Stats::default();
        let pool = self.pool(settings.threads)?;
        // The whole extraction runs on the pool: its parallel passes (a few dozen, many small)
        // then start inline on a worker instead of each being handed to the pool and back.
        pool.install(|| -> Result<(), ExtractError> {
            self.samples
                .sample_with(field, settings, &pool, &mut stats, self.sampling)?;
            self.mesh_samples(Some(field), settings, mesh, &mut stats)
        })?;
        stats.t_total_s = start.elapsed().as_secs_f64();
        Ok(stats)
    }

    /// Extracts from values already in [`Extractor::samples_mut`] (laid out for `settings`, see
    /// [`Samples::prepare`]), without sampling: for benchmarks that exclude sampling and for
    /// edited volumes. Gradient normals need a field, so they are skipped here.
    pub fn extract_presampled(
        &mut self,
        settings: &ExtractSettings,
        mesh: &mut Mesh,
    ) -> Result<Stats, ExtractError> {
        let start = std::time::Instant::now();
        settings.check()?;
        let mut stats = Stats::default();
        self.samples.check_layout(settings)?;
        stats.sample_points = self.samples.point_count();
        stats.bytes_lattice = self.samples.bytes();
        // On the pool, as in `extract`.
        let pool = self.pool(settings.threads)?;
        pool.install(|| self.mesh_samples(None, settings, mesh, &mut stats))?;
        stats.t_total_s = start.elapsed().as_secs_f64();
        Ok(stats)
    }

    /// Extracts from `values`, read in place for this call (no copy): the sample array as
    /// [`Samples::prepare`] lays it out for `settings`. On the simple lattice, and for marching
    /// cubes and surface nets, that is corner `(x, y, z)` at `x + (nx + 1) * (y + (ny + 1) *
    /// z)`, i.e. a C-ordered `(z, y, x)` volume of `(nz + 1, ny + 1, nx + 1)` values. The mesh
    /// is the one [`Extractor::extract_presampled`] gives for the same values copied into
    /// [`Extractor::samples_mut`]; the extractor's own sample array is left as it was. Errors
    /// when `values` has another length; the values are not checked (see
    /// [`Samples::sample`] for fields: they must be finite).
    ///
    /// ```
    /// use rmt_extract::{Clustering, ExtractSettings, Extractor, Grid, Lattice, Method};
    /// let n = 16;
    /// let mut s = ExtractSettings::new(Grid::cube(n, 1.0), Lattice::Simple, Clustering::None);
    /// s.method = Method::Mc;
    /// let h = 2.0 / n as f32;
    /// let mut volume = Vec::new();
    /// for z in 0..=n {
    ///     for y in 0..=n {
    ///         for x in 0..=n {
    ///             let p = glam::Vec3::new(x as f32, y as f32, z as f32) * h - 1.0;
    ///             volume.push(p.length() - 0.6);
    ///         }
    ///     }
    /// }
    /// let mut mesh = rmt_mesh::Mesh::default();
    /// let stats = Extractor::new().extract_borrowed(&volume, &s, &mut mesh).unwrap();
    /// assert_eq!(stats.triangles, mesh.triangle_count());
    /// assert!(mesh.triangle_count() > 0);
    /// ```
    pub fn extract_borrowed(
        &mut self,
        values: &[f32],
        settings: &ExtractSettings,
        mesh: &mut Mesh,
    ) -> Result<Stats, ExtractError> {
        // SAFETY: the borrowed sample array is taken out of `self` below, before this call
        // returns or its panic unwinds out of it, so it is not used after `values`' borrow.
        let borrowed = unsafe { Samples::borrowing(values, settings)? };
        let own = std::mem::replace(&mut self.samples, borrowed);
        let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            self.extract_presampled(settings, mesh)
        }));
        self.samples = own;
        match result {
            Ok(r) => r,
            Err(panic) => std::panic::resume_unwind(panic),
        }
    }

    /// Sets whether extractions record, for marching tetrahedra with integrated clustering
    /// (checked or not) or none, the anchor cell of every output triangle
    /// ([`Extractor::triangle_cells`]) and where the clustering did anything after its
    /// proposals ([`Extractor::activity`]: always empty unless checked); other modes record
    /// nothing. Off by default: it costs a pass over the crossings per lone and sliver pass,
    /// and four bytes per triangle. With post-processed clustering it records edge collapse's
    /// candidate edges and their outcomes instead ([`Extractor::collapse_log`]). The meshes do
    /// not depend on it.
    ///
    /// Activity is what makes a sub-box's result checkable against the whole volume's: where
    /// neither did anything after the proposals, both kept their proposals, which depend on
    /// nearby samples only (see `rmt_terrain`'s exact chunks).
    ///
    /// ```
    /// use rmt_extract::{Clustering, ExtractSettings, Extractor, Grid, Lattice};
    /// let s = ExtractSettings::new(Grid::cube(16, 1.0), Lattice::BodyCentred,
    ///     Clustering::Integrated);
    /// let mut ex = Extractor::new();
    /// ex.set_recording(true);
    /// let mut mesh = rmt_mesh::Mesh::default();
    /// ex.extract(&rmt_fields::Sphere::new(glam::Vec3::ZERO, 0.6), &s, &mut mesh).unwrap();
    /// assert_eq!(ex.triangle_cells().len(), mesh.triangle_count());
    /// // Every proposal of a sphere passes at once: nothing happens after the proposals.
    /// assert!(ex.activity().is_empty());
    /// ```
    pub fn set_recording(&mut self, record: bool) {
        self.mt.record = record;
    }

    /// Sets whether marching cubes ([`Method::Mc`]) and plain marching tetrahedra write their
    /// meshes in the array order of a C-ordered `(z, y, x)` volume (see
    /// [`Extractor::extract_borrowed`]), as scikit-image's `marching_cubes` returns it: every
    /// position and normal as `[z, y, x]` and every triangle's last two corners swapped
    /// (swapping two axes mirrors the mesh; the swap keeps triangles counter-clockwise seen from
    /// increasing values). Off by default. Normals are computed as in world order, so the mesh
    /// is exactly the world-order one reordered.
    ///
    /// - Marching cubes writes positions and triangles that way in the passes that write them:
    ///   no pass of its own.
    /// - Plain MT ([`Method::Mt`] with [`Clustering::None`], no tiles, the ghost boundary)
    ///   writes its triangles swapped in the geometry pass and turns its positions in one
    ///   parallel pass after it (the positions are read in world order while the triangles are
    ///   made).
    ///
    /// Other methods and modes ignore it ([`Extractor::writes_array_order`] says which):
    /// their meshes are in world order `(x, y, z)`.
    ///
    /// ```
    /// use rmt_extract::{Clustering, ExtractSettings, Extractor, Grid, Lattice, Method};
    /// let mut s = ExtractSettings::new(Grid::cube(12, 1.0), Lattice::Simple, Clustering::None);
    /// s.method = Method::Mc;
    /// let sphere = rmt_fields::Sphere::new(glam::Vec3::new(0.1, 0.0, -0.2), 0.6);
    /// let (mut world, mut array) = (rmt_mesh::Mesh::default(), rmt_mesh::Mesh::default());
    /// Extractor::new().extract(&sphere, &s, &mut world).unwrap();
    /// let mut ex = Extractor::new();
    /// ex.set_array_order(true);
    /// ex.extract(&sphere, &s, &mut array).unwrap();
    /// let rev = |v: &[[f32; 3]]| v.iter().map(|p| [p[2], p[1], p[0]]).collect::<Vec<_>>();
    /// assert_eq!(rev(&array.positions), world.positions);
    /// assert_eq!(rev(&array.normals), world.normals);
    /// let swap = |i: &[u32]| i.chunks(3).flat_map(|t| [t[0], t[2], t[1]]).collect::<Vec<_>>();
    /// assert_eq!(swap(&array.indices), world.indices);
    /// ```
    pub fn set_array_order(&mut self, array_order: bool) {
        self.array_order = array_order;
    }

    /// Whether an extraction with `settings` writes its mesh in array order: the flag of
    /// [`Extractor::set_array_order`] is on and the method honours it (marching cubes, or plain
    /// MT without tiles on the ghost boundary).
    pub fn writes_array_order(&self, settings: &ExtractSettings) -> bool {
        self.array_order
            && match settings.method {
                settings::Method::Mc => true,
                settings::Method::Mt => Self::plain_mt_in_array_order(settings),
                settings::Method::SurfaceNets => false,
            }
    }

    /// Plain MT that can write array order: no clustering or post-process, no tiles, and the
    /// ghost boundary (the pyramids' pass writes in world order).
    fn plain_mt_in_array_order(settings: &ExtractSettings) -> bool {
        settings.method == settings::Method::Mt
            && settings.clustering == Clustering::None
            && settings.tiles.is_none()
            && (settings.lattice == Lattice::Simple || settings.boundary == Boundary::Ghosts)
    }

    /// Recorded by the last extraction ([`Extractor::set_recording`]): the anchor cell of each
    /// output triangle ([`CellRange`]'s anchors), as a linear index `x + nx * (y + ny * z)` over
    /// the grid's cells; empty when nothing was recorded.
    pub fn triangle_cells(&self) -> &[u32] {
        &self.mt.emission.tri_cells
    }

    /// Recorded by the last extraction ([`Extractor::set_recording`]): the lattice points, in
    /// grid-local lattice coordinates (cells on the simple lattice; half cells on the
    /// body-centred one, corners even, centres odd), with a crossing that a step of integrated
    /// clustering after the proposals changed, found in a failing group, or considered as a
    /// crossing left alone; sorted, each once.
    pub fn activity(&self) -> &[[i32; 3]] {
        &self.mt.clustering.activity
    }

    /// Recorded by the last extraction ([`Extractor::set_recording`]) with post-processed
    /// clustering: every candidate edge of edge collapse, in the order considered, with its
    /// outcome and the output vertices its ends ended up in; empty otherwise.
    pub fn collapse_log(&self) -> &[CollapseAttempt] {
        &self.collapse_log
    }

    /// The sample array (to fill it yourself before [`Extractor::extract_presampled`]).
    pub fn samples_mut(&mut self) -> &mut Samples {
        &mut self.samples
    }

    /// The sample array of the last extraction (with [`Sampling::Sparse`], skipped blocks hold
    /// placeholders: right side of the isovalue, not the field's values).
    pub fn samples(&self) -> &Samples {
        &self.samples
    }

    fn mesh_samples(
        &mut self,
        field: Option<&dyn ScalarField>,
        settings: &ExtractSettings,
        mesh: &mut Mesh,
        stats: &mut Stats,
    ) -> Result<(), ExtractError> {
        let pool = self.pool(settings.threads)?;
        mesh.clear();
        self.collapse_log.clear();
        match settings.method {
            settings::Method::Mc => {
                if settings.clustering != Clustering::None {
                    return Err(ExtractError::Unsupported(format!(
                        "marching cubes takes clustering none, got {}",
                        settings.clustering.name()
                    )));
                }
                mc::extract(
                    &self.samples,
                    settings,
                    &pool,
                    &mut self.mc,
                    self.array_order,
                    mesh,
                    stats,
                )?;
                if self.mt.lean {
                    self.mc = mc::McBuffers::default();
                }
            }
            settings::Method::SurfaceNets => {
                if settings.clustering != Clustering::None {
                    return Err(ExtractError::Unsupported(format!(
                        "surface nets takes clustering none, got {}",
                        settings.clustering.name()
                    )));
                }
                surface_nets::extract(
                    &self.samples,
                    settings,
                    &mut self.surface_nets,
                    mesh,
                    stats,
                )?;
                stats.bytes_edges = self.surface_nets.bytes();
                if self.mt.lean {
                    self.surface_nets = surface_nets::SurfaceNetsBuffers::default();
                }
            }
            settings::Method::Mt => {
                // Marching tetrahedra (with its clustering), then the post-processing modes on
                // its mesh.
                self.mt.flip = self.array_order && Self::plain_mt_in_array_order(settings);
                let emitted =
                    mt::extract(&self.samples, settings, &pool, &mut self.mt, mesh, stats)?;
                let keys = settings.tiles.is_some().then_some(&emitted.tile_keys[..]);
                let log = self.mt.record.then_some(&mut self.collapse_log);
                post::process(
                    settings,
                    keys,
                    emitted.near_points,
                    &mut self.merge,
                    mesh,
                    stats,
                    log,
                );
                if self.mt.flip {
                    // Array order: the triangles were written swapped; the positions, read in
                    // world order while they were made, are turned now.
                    use rayon::prelude::*;
                    pool.install(|| {
                        mesh.positions
                            .par_chunks_mut(1 << 14)
                            .for_each(|c| c.iter_mut().for_each(|p| *p = reversed(*p)))
                    });
                }
                let lean = self.mt.lean;
                stats.bytes_edges = emitted.table_bytes
                    + if !lean
                        && matches!(
                            settings.clustering,
                            Clustering::Postprocessed | Clustering::Meshopt
                        )
                    {
                        self.merge.bytes()
                    } else {
                        0
                    };
                if lean {
                    self.merge = post::MergeBuffers::default();
                    mesh.positions.shrink_to_fit();
                    mesh.indices.shrink_to_fit();
                }
            }
        }
        let t = std::time::Instant::now();
        let array_order = self.writes_array_order(settings);
        match (settings.normals, field) {
            (NormalMode::Skip, _) => mesh.normals.clear(),
            (NormalMode::Gradient, Some(f)) => gradient_normals(f, settings, array_order, mesh),
            _ if array_order => area_normals_array_order(mesh),
            _ => mesh.compute_area_weighted_normals(),
        }
        stats.t_normals_s = t.elapsed().as_secs_f64();
        stats.vertices = mesh.vertex_count();
        stats.triangles = mesh.triangle_count();
        let (bv, bi) = mesh.buffer_bytes();
        stats.bytes_vertices = bv;
        stats.bytes_indices = bi;
        Ok(())
    }
}

/// `[z, y, x]` for `[x, y, z]` and back.
fn reversed(p: [f32; 3]) -> [f32; 3] {
    [p[2], p[1], p[0]]
}

/// Normals from central differences of the field (step h / 4), pointing toward increasing f;
/// positions and normals in array order with `array_order`.
fn gradient_normals(
    field: &dyn ScalarField,
    settings: &ExtractSettings,
    array_order: bool,
    mesh: &mut Mesh,
) {
    let e = settings.grid.h() * 0.25;
    mesh.normals.clear();
    for p in &mesh.positions {
        let p = glam::Vec3::from(if array_order { reversed(*p) } else { *p });
        let g = glam::Vec3::new(
            field.sample(p + glam::Vec3::X * e) - field.sample(p - glam::Vec3::X * e),
            field.sample(p + glam::Vec3::Y * e) - field.sample(p - glam::Vec3::Y * e),
            field.sample(p + glam::Vec3::Z * e) - field.sample(p - glam::Vec3::Z * e),
        );
        let n = g.normalize_or_zero().to_array();
        mesh.normals.push(if array_order { reversed(n) } else { n });
    }
}

/// [`Mesh::compute_area_weighted_normals`] of a mesh in array order (positions `[z, y, x]`,
/// triangles' last two corners swapped): computed on the world-order mesh, the same operations
/// in the same order, so the normals are exactly the world-order ones, reversed.
fn area_normals_array_order(mesh: &mut Mesh) {
    let mut acc = vec![glam::Vec3::ZERO; mesh.positions.len()];
    for t in mesh.indices.chunks_exact(3) {
        let world = [t[0], t[2], t[1]];
        let [a, b, c] = world.map(|i| glam::Vec3::from(reversed(mesh.positions[i as usize])));
        let n = (b - a).cross(c - a);
        for i in world {
            acc[i as usize] += n;
        }
    }
    mesh.normals.clear();
    mesh.normals.extend(
        acc.into_iter()
            .map(|n| reversed(n.normalize_or_zero().to_array())),
    );
}
