//! The chunked world: samples of the whole volume, one mesh per chunk, dirty flags.
//!
//! Modules, each importing only from those below it: `settings.rs` (what a world is),
//! `state.rs` (the fields of [`World`]), `weld.rs` (meshes by exact position), then the three
//! that add methods to `World`: this file (the public ones), `exact.rs` (exact seams) and
//! `undo.rs` (undo and redo).

use std::sync::{Arc, Mutex};
use std::time::Instant;

use glam::Vec3;
use rayon::prelude::*;
use rmt_extract::lattice::LatticeTables;
use rmt_extract::samples::sampled_lattice;
use rmt_extract::{
    thread_pool, CellRange, ExtractError, ExtractSettings, Extractor, Grid, Lattice, Samples,
    Stats, Tiling,
};
use rmt_fields::ScalarField;
use rmt_mesh::Mesh;

use crate::{Brush, TerrainError};

mod exact;
mod settings;
mod state;
mod undo;
mod weld;
pub use exact::{PROPOSAL_REACH, QUIET_BAND};
pub use settings::{Seams, WorldSettings};
pub use state::World;
use state::{Cells, Exact};
pub use undo::StrokeRecord;
pub use weld::{canonical_triangles, weld};

/// Cells of halo around a chunk's own cells (clipped at the world box): enough for the
/// body-centred tetrahedra on the chunk's faces and for the cluster proposals of the points on
/// them (see the crate doc).
pub const HALO: usize = 1;

/// What one [`World::remesh_dirty`] did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RemeshStats {
    /// Chunks re-meshed ([`World::remeshed_chunks`]): re-extracted under [`Seams::Tiles`],
    /// changed under [`Seams::Exact`].
    pub chunks: usize,
    /// Triangles of the re-extracted chunks (after the update).
    pub triangles: usize,
    /// Boxes extracted: one per chunk under [`Seams::Tiles`]; under [`Seams::Exact`] one per
    /// attempt (a box grows when no band around the edit is quiet; 0 when nothing was pending).
    pub boxes: usize,
    /// Cells of those boxes, in all.
    pub box_cells: usize,
    /// Wall time in seconds.
    pub seconds: f64,
}

/// One re-meshing job: chunk index, its own cells, its input box, its mesh (reused).
type Job = (usize, CellRange, ([usize; 3], [usize; 3]), Mesh);

impl World {
    /// Samples `field` over the world box (in parallel) and marks every chunk dirty; call
    /// [`World::remesh_dirty`] to mesh them.
    pub fn new(field: &dyn ScalarField, settings: WorldSettings) -> Result<Self, TerrainError> {
        settings.check()?;
        let pool = thread_pool(settings.threads, settings.placement).map_err(|e| {
            TerrainError::ThreadPool {
                threads: settings.threads,
                message: e.to_string(),
            }
        })?;
        let pool = Arc::new(pool);
        let unit = settings.unit_settings();
        let mut sampling = unit;
        sampling.grid = settings.world_grid();
        let mut samples = Samples::default();
        samples.sample(field, &sampling, &pool, &mut Stats::default())?;
        // Same layout and values, positions in lattice units.
        samples.prepare(&unit);
        let counts = settings.chunk_counts();
        let n = counts.iter().product();
        Ok(Self {
            settings,
            unit,
            samples,
            counts,
            chunks: (0..n).map(|_| Mesh::default()).collect(),
            dirty: vec![true; n],
            pool,
            extractors: Mutex::new(Vec::new()),
            stroke_old: Vec::new(),
            exact: (settings.seams == Seams::Exact).then(Exact::default),
            last_edit: None,
            remeshed: Vec::new(),
        })
    }

    /// The settings the world was built with.
    pub fn settings(&self) -> &WorldSettings {
        &self.settings
    }

    /// The world's samples (positions in lattice units).
    pub fn samples(&self) -> &Samples {
        &self.samples
    }

    /// Number of chunks.
    pub fn chunk_count(&self) -> usize {
        self.chunks.len()
    }

    /// Chunks per axis.
    pub fn chunk_counts(&self) -> [usize; 3] {
        self.counts
    }

    /// The chunks the last [`World::remesh_dirty`] rebuilt, ascending: what a viewer must upload
    /// again. Under [`Seams::Tiles`] the dirty ones; under [`Seams::Exact`] those whose mesh
    /// changed (among the chunks the box's cut meets, or all of them when the whole volume was
    /// extracted).
    pub fn remeshed_chunks(&self) -> &[usize] {
        &self.remeshed
    }

    /// Chunks waiting for [`World::remesh_dirty`].
    pub fn dirty_count(&self) -> usize {
        self.dirty.iter().filter(|&&d| d).count()
    }

    /// Marks every chunk dirty (the next [`World::remesh_dirty`] re-meshes the whole world,
    /// chunk by chunk).
    pub fn mark_all_dirty(&mut self) {
        self.dirty.iter_mut().for_each(|d| *d = true);
        if let Some(e) = self.exact.as_mut() {
            e.built = false;
        }
    }

    /// The mesh of chunk `i` in lattice units (cell edge 1, world corner at 0): its own
    /// triangles, vertices it does not use removed.
    pub fn chunk_mesh(&self, i: usize) -> Option<&Mesh> {
        self.chunks.get(i)
    }

    /// The cells `lo .. hi` of chunk `i` (an empty range for `i` past the last chunk).
    pub fn chunk_cells(&self, i: usize) -> CellRange {
        let [nx, ny, _] = self.counts;
        let c = [i % nx, (i / nx) % ny, i / (nx * ny)];
        let size = self.settings.chunk;
        // Saturating: an index past the last chunk gives an empty range at the far corner.
        let lo = [0, 1, 2].map(|a| c[a].saturating_mul(size).min(self.settings.cells[a]));
        let hi = [0, 1, 2].map(|a| lo[a].saturating_add(size).min(self.settings.cells[a]));
        CellRange { lo, hi }
    }

    /// Applies `brush` for a frame of `dt` seconds to the samples and marks the chunks whose
    /// mesh the change can alter. Returns how many chunks it marked (some may have been dirty
    /// already).
    ///
    /// A chunk's mesh depends only on the inside/outside state of the points of its input (cells
    /// plus halo, ghost slots included) and on the values at the ends of its crossed edges. So a
    /// changed value matters only where the point changed side, or where the point has a
    /// neighbour on the other side before or after the stroke (an end of a crossed edge); a
    /// chunk is marked when its input holds such a point. Changes deep inside or outside the
    /// solid re-mesh nothing. Neighbours are the lattice's 14 edge directions
    /// ([`LatticeTables::offsets`]; on the simple lattice they include the axes, the edges of
    /// marching cubes); points within two lattice steps of the box faces, where ghosts stand in
    /// for missing points, always count.
    ///
    /// Any finite brush is accepted: one entirely outside the world changes nothing and marks
    /// nothing (`Ok(0)`), and changed values are kept finite ([`Brush::apply`]). A non-finite
    /// centre, radius, strength, clamp or time step is an error ([`Brush::check`]).
    pub fn apply_brush(&mut self, brush: &Brush, dt: f32) -> Result<usize, TerrainError> {
        brush.check(dt)?;
        self.last_edit = None;
        let s = &self.settings;
        let lattice = sampled_lattice(&self.unit);
        let body = lattice == Lattice::BodyCentred;
        // Lattice coordinates: half cells on the body-centred lattice, cells on the simple one.
        let scale = if body { 2.0 } else { 1.0 };
        // In f64, where no finite f32 centre, radius or cell size overflows (|x| / h stays below
        // 3e38 / 1e-45), and clipped to the box in floating point before any cast to integers:
        // a saturating cast of a far centre followed by the +-1 below would wrap.
        let h = f64::from(s.h);
        let ru = f64::from(brush.radius) / h * scale;
        let mut lo = [0i64; 3];
        let mut hi = [0i64; 3];
        let mut bmin = [0i64; 3];
        let mut bmax = [0i64; 3];
        for a in 0..3 {
            (bmin[a], bmax[a]) = if body {
                (-1, 2 * s.cells[a] as i64 + 1)
            } else {
                (0, s.cells[a] as i64)
            };
            let cu = (f64::from(brush.centre[a]) - f64::from(s.origin[a])) / h * scale;
            // One extra point each side: ghosts sit on the box faces, off their lattice spot.
            let (l, u) = ((cu - ru).floor() - 1.0, (cu + ru).ceil() + 1.0);
            if !(l <= bmax[a] as f64 && u >= bmin[a] as f64) {
                // The brush lies entirely outside the world: nothing changes.
                return Ok(0);
            }
            lo[a] = l.max(bmin[a] as f64) as i64;
            hi[a] = u.min(bmax[a] as f64) as i64;
        }
        // Old values of the stroke's box (dense, x fastest), for the neighbour test below.
        let size = [0, 1, 2].map(|a| (hi[a] - lo[a] + 1) as usize);
        // Index into `old` of a point inside the stroke's box.
        let box_at = |q: [i64; 3]| -> Option<usize> {
            (0..3).all(|a| q[a] >= lo[a] && q[a] <= hi[a]).then(|| {
                ((q[2] - lo[2]) as usize * size[1] + (q[1] - lo[1]) as usize) * size[0]
                    + (q[0] - lo[0]) as usize
            })
        };
        let old = &mut self.stroke_old;
        old.clear();
        old.resize(size[0] * size[1] * size[2], f32::NAN);
        let samples = &mut self.samples;
        let lookup = |samples: &Samples, q: [i64; 3]| -> Option<usize> {
            if (0..3).any(|a| q[a] < bmin[a] || q[a] > bmax[a]) {
                return None;
            }
            let p = q.map(|c| c as i32);
            if body {
                samples.bcdl_exists(p).then(|| samples.bcdl_index(p))
            } else {
                let [x, y, z] = p.map(|c| c as usize);
                Some(samples.simple_index(x, y, z))
            }
        };
        let mut changed = false;
        for z in lo[2]..=hi[2] {
            for y in lo[1]..=hi[1] {
                for x in lo[0]..=hi[0] {
                    let Some(index) = lookup(samples, [x, y, z]) else {
                        continue;
                    };
                    let p = [x as i32, y as i32, z as i32];
                    let pos = if body {
                        samples.bcdl_position(p)
                    } else {
                        let [x, y, z] = p.map(|c| c as usize);
                        samples.simple_position(x, y, z)
                    };
                    let d = (s.origin + pos * s.h).distance(brush.centre);
                    let before = samples.values[index];
                    let new = brush.apply(before, d, dt);
                    if let Some(at) = box_at([x, y, z]) {
                        old[at] = before;
                    }
                    if new != before {
                        samples.values[index] = new;
                        changed = true;
                    }
                }
            }
        }
        if !changed {
            return Ok(0);
        }
        // The lattice's 14 edge directions: those of the tetrahedra, which on the simple lattice
        // include the axes, the edges of marching cubes.
        let neighbours = LatticeTables::get(lattice)
            .offsets
            .map(|d| d.map(i64::from));
        let iso = s.iso;
        let (mut clo, mut chi) = ([i64::MAX; 3], [i64::MIN; 3]);
        let samples = &self.samples;
        let old_at = |q: [i64; 3], index: usize| -> f32 {
            box_at(q).map_or(samples.values[index], |at| old[at])
        };
        for z in lo[2]..=hi[2] {
            for y in lo[1]..=hi[1] {
                for x in lo[0]..=hi[0] {
                    let q = [x, y, z];
                    let Some(index) = lookup(samples, q) else {
                        continue;
                    };
                    let (before, now) = (old_at(q, index), samples.values[index]);
                    if before == now {
                        continue;
                    }
                    let (was_in, is_in) = (before < iso, now < iso);
                    let near_box = (0..3).any(|a| q[a] - bmin[a] < 2 || bmax[a] - q[a] < 2);
                    let matters = was_in != is_in
                        || near_box
                        || neighbours.iter().any(|d| {
                            let r = [q[0] + d[0], q[1] + d[1], q[2] + d[2]];
                            lookup(samples, r).is_some_and(|j| {
                                (old_at(r, j) < iso) != was_in || (samples.values[j] < iso) != is_in
                            })
                        });
                    if matters {
                        for a in 0..3 {
                            clo[a] = clo[a].min(q[a]);
                            chi[a] = chi[a].max(q[a]);
                        }
                    }
                }
            }
        }
        if clo[0] > chi[0] {
            return Ok(0);
        }
        if self.exact.is_some() {
            let edit = Cells::of_points(lattice, clo, chi);
            self.last_edit = Some(edit);
            return Ok(self.mark_edit(edit));
        }
        let mut marked = 0;
        for i in 0..self.chunks.len() {
            let (s0, s1) = self.input_box(i);
            let (ilo, ihi) = if body {
                (s0.map(|c| 2 * c as i64 - 1), s1.map(|c| 2 * c as i64 + 1))
            } else {
                (s0.map(|c| c as i64), s1.map(|c| c as i64))
            };
            if (0..3).all(|a| clo[a] <= ihi[a] && chi[a] >= ilo[a]) {
                self.dirty[i] = true;
                marked += 1;
            }
        }
        Ok(marked)
    }

    /// [`Seams::Exact`]: adds `edit` to the pending edits and marks the chunks its first cut
    /// meets; returns how many it marked.
    fn mark_edit(&mut self, edit: Cells) -> usize {
        let Some(state) = self.exact.as_mut() else {
            return 0;
        };
        state.pending = Some(state.pending.map_or(edit, |p| p.union(edit)));
        let cut = self.exact_cut(edit);
        let mut marked = 0;
        for i in 0..self.chunks.len() {
            let r = self.chunk_cells(i);
            let own = Cells {
                lo: r.lo.map(|c| c as i64),
                hi: r.hi.map(|c| c as i64),
            };
            if own.intersects(&cut) {
                self.dirty[i] = true;
                marked += 1;
            }
        }
        marked
    }

    /// The cells `s0 .. s1` chunk `i` is extracted from: its own plus the halo, clipped.
    fn input_box(&self, i: usize) -> ([usize; 3], [usize; 3]) {
        let r = self.chunk_cells(i);
        let s0 = r.lo.map(|c| c.saturating_sub(HALO));
        let s1 = [0, 1, 2].map(|a| (r.hi[a] + HALO).min(self.settings.cells[a]));
        (s0, s1)
    }

    /// Re-extracts the dirty chunks, in parallel on the world's threads.
    pub fn remesh_dirty(&mut self) -> Result<RemeshStats, TerrainError> {
        let start = Instant::now();
        if self.exact.is_some() {
            let stats = self.remesh_exact()?;
            self.dirty.iter_mut().for_each(|d| *d = false);
            return Ok(RemeshStats {
                chunks: stats.chunks,
                triangles: stats.triangles,
                boxes: stats.attempts,
                box_cells: stats.box_cells,
                seconds: start.elapsed().as_secs_f64(),
            });
        }
        let ids: Vec<usize> = (0..self.dirty.len()).filter(|&i| self.dirty[i]).collect();
        self.remeshed.clone_from(&ids);
        let mut jobs: Vec<Job> = ids
            .iter()
            .map(|&i| {
                (
                    i,
                    self.chunk_cells(i),
                    self.input_box(i),
                    std::mem::take(&mut self.chunks[i]),
                )
            })
            .collect();
        let (samples, unit, extractors, pool) =
            (&self.samples, &self.unit, &self.extractors, &self.pool);
        let results: Vec<Result<(), ExtractError>> = self.pool.install(|| {
            jobs.par_iter_mut()
                .map(|(_, own, input, mesh)| {
                    let mut ex = extractors
                        .lock()
                        .unwrap_or_else(|e| e.into_inner())
                        .pop()
                        .unwrap_or_else(|| {
                            let mut ex = Extractor::new();
                            ex.set_pool(pool.clone());
                            ex
                        });
                    let r = extract_chunk(samples, unit, *own, *input, &mut ex, mesh).map(|_| ());
                    extractors
                        .lock()
                        .unwrap_or_else(|e| e.into_inner())
                        .push(ex);
                    r
                })
                .collect()
        });
        let mut triangles = 0;
        let jobs_cells: Vec<usize> = jobs
            .iter()
            .map(|(_, _, (s0, s1), _)| (0..3).map(|a| s1[a] - s0[a]).product())
            .collect();
        for (i, _, _, mesh) in jobs {
            triangles += mesh.triangle_count();
            self.chunks[i] = mesh;
        }
        for r in results {
            r?;
        }
        for &i in &ids {
            self.dirty[i] = false;
        }
        let box_cells = jobs_cells.iter().sum();
        Ok(RemeshStats {
            chunks: ids.len(),
            triangles,
            boxes: ids.len(),
            box_cells,
            seconds: start.elapsed().as_secs_f64(),
        })
    }

    /// Extracts chunk `i` from the current samples into `mesh` with `ex` (whose buffers are
    /// reused), without touching the world's own chunk meshes or dirty flags: the extractor's
    /// stage timings and counters for one chunk, for profiling. Under [`Seams::Tiles`] the
    /// result is the chunk's mesh; under [`Seams::Exact`] it is the chunk and its halo extracted
    /// with the global rule, which need not be (the world's chunks come from the whole volume
    /// and the edits' boxes).
    pub fn extract_chunk(
        &self,
        i: usize,
        ex: &mut Extractor,
        mesh: &mut Mesh,
    ) -> Result<Stats, TerrainError> {
        if i >= self.chunks.len() {
            return Err(TerrainError::NoSuchChunk {
                index: i,
                count: self.chunks.len(),
            });
        }
        Ok(extract_chunk(
            &self.samples,
            &self.unit,
            self.chunk_cells(i),
            self.input_box(i),
            ex,
            mesh,
        )?)
    }

    /// The chunk meshes welded into one, in world coordinates, with area-weighted normals.
    /// Chunks not meshed yet (dirty) contribute their last mesh.
    pub fn mesh_welded(&self) -> Mesh {
        let mut mesh = weld(self.chunks.iter());
        self.to_world(&mut mesh);
        mesh
    }

    /// The whole volume extracted at once from the current samples (same settings and tile rule
    /// as the chunks), in world coordinates, welded like [`World::mesh_welded`] (so the two can be
    /// compared), and the extraction's wall time in seconds (without the copy of the samples and
    /// the weld).
    pub fn extract_whole(&self) -> Result<(Mesh, f64), TerrainError> {
        let mut ex = Extractor::new();
        ex.set_pool(self.pool.clone());
        *ex.samples_mut() = self.samples.clone();
        let mut raw = Mesh::default();
        let stats = ex.extract_presampled(&self.unit, &mut raw)?;
        let mut mesh = weld(std::iter::once(&raw));
        self.to_world(&mut mesh);
        Ok((mesh, stats.t_total_s))
    }

    /// Height of the highest inside sample in the lattice column nearest to world `(x, z)`
    /// (scanning cube corners from the top), in world units: where a brush meets the ground.
    pub fn column_surface(&self, x: f32, z: f32) -> Option<f32> {
        let s = &self.settings;
        let ix = ((x - s.origin.x) / s.h).round();
        let iz = ((z - s.origin.z) / s.h).round();
        if !(ix >= 0.0 && iz >= 0.0 && ix <= s.cells[0] as f32 && iz <= s.cells[2] as f32) {
            return None;
        }
        let (ix, iz) = (ix as usize, iz as usize);
        let lattice = sampled_lattice(&self.unit);
        (0..=s.cells[1]).rev().find_map(|iy| {
            let v = match lattice {
                Lattice::BodyCentred => {
                    let p = [2 * ix as i32, 2 * iy as i32, 2 * iz as i32];
                    self.samples.values[self.samples.bcdl_index(p)]
                }
                Lattice::Simple => self.samples.values[self.samples.simple_index(ix, iy, iz)],
            };
            (v < s.iso).then_some(s.origin.y + iy as f32 * s.h)
        })
    }

    fn to_world(&self, mesh: &mut Mesh) {
        let (o, h) = (self.settings.origin, self.settings.h);
        for p in &mut mesh.positions {
            *p = (o + Vec3::from(*p) * h).to_array();
        }
        mesh.compute_area_weighted_normals();
    }
}

/// Extracts chunk `own` from the world's `samples` over its input box `s0 .. s1`.
fn extract_chunk(
    samples: &Samples,
    unit: &ExtractSettings,
    own: CellRange,
    (s0, s1): ([usize; 3], [usize; 3]),
    ex: &mut Extractor,
    mesh: &mut Mesh,
) -> Result<Stats, ExtractError> {
    let cells = [0, 1, 2].map(|a| s1[a] - s0[a]);
    let corner = |c: [usize; 3]| Vec3::new(c[0] as f32, c[1] as f32, c[2] as f32);
    let mut st = *unit;
    st.grid = Grid::new(cells, corner(s0), corner(s1));
    // Tile seams: the world's tiles, offset to the box; exact seams: no tiles.
    st.tiles = unit.tiles.map(|t| Tiling::new(t.size, s0));
    st.keep_cells = Some(CellRange {
        lo: [0, 1, 2].map(|a| own.lo[a] - s0[a]),
        hi: [0, 1, 2].map(|a| own.hi[a] - s0[a]),
    });
    // The chunk's input: its cells and halo cut from the world's samples.
    ex.samples_mut().copy_box(samples, &st, s0)?;
    let stats = ex.extract_presampled(&st, mesh)?;
    mesh.normals.clear();
    mesh.drop_unused_vertices(&mut Vec::new());
    Ok(stats)
}
