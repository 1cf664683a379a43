//! Level of detail in the runner (`rmt_terrain::lod`): the manifest workload `lod` flies a viewer
//! along a path over a multiresolution world and re-meshes it at every step.
//!
//! ```text
//!   object box + resolution (finest cells, cubic)  ->  LodSettings: roots = cells / (chunk 2^L)
//!   step 0: the viewer at the path's start, every chunk meshed (t_initial_s)
//!   step k: viewer moved -> LevelMap::from_viewer -> the step's strokes ([lod] edits,
//!           LodWorld::edit: the chunks of the new map that see them counted, per level)
//!           -> remesh (timed)
//!           pop: every chunk that left the map (its level changed) against the surface that
//!                replaced it, both ways (one-sided distances, rmt_mesh::distance), in cells of
//!                the finer of the two levels (on a step with strokes, the old map's surfaces
//!                are meshed again with the strokes, so the pop is the change of level alone)
//!           every validate_every steps and the last: the surface around the chunks meshed
//!           at that step (they and their touching leaves, up to validate_max_chunks chunks)
//!           checked: edges open inside the domain (not in a boundary face of the region's
//!           tetrahedra), non-manifold, misoriented; and the normals of every crossing that
//!           chunks of two levels share compared (the level seam); and the shape of every
//!           triangle of the world (rmt_mesh::quality: radius ratio R / 2r, 1 = equilateral)
//!   at the end: the most triangles the world had over the finest level everywhere (counted
//!           when the finest level has at most finest_exact_chunks chunks, meshed at once;
//!           else estimated as the sum over the last step's chunks of triangles x 4^level)
//! ```
//!
//! Rules: the surfaces, counts, pops and seams are functions of the field, the path and the
//! settings (not of the thread count); only the times and the process's peak memory vary
//! between runs. The distances of a pop are measured between the old and new surfaces of the
//! chunks that changed, each against the other side's surface in and around the changed chunk
//! (its touching neighbours included, in their state before or after), so a vertex near a chunk
//! face finds the surface across it.

use std::collections::{BTreeSet, HashMap};
use std::time::Instant;

use anyhow::{bail, Context, Result};
use glam::Vec3;
use rayon::prelude::*;
use rmt_extract::Clustering;
use rmt_fields::ScalarField;
use rmt_mesh::distance::{one_sided, TriangleGrid};
use rmt_terrain::lod::check::{check_surface, check_tets};
use rmt_terrain::lod::{
    chunk_tets, cluster_chunk, mesh_chunks, thread_pool, weld, ChunkKey, ChunkMesh, EditedField,
    LevelMap, LodFrame, LodGeometry, LodSettings, LodWorld, MorphSettings,
};
use rmt_terrain::{Brush, BrushMode, StrokeParams};

use crate::config::Extraction;
use crate::manifest::{LodEditMode, LodPlan};

/// The world of `e` under `plan` on `threads` threads: the box and resolution give the finest
/// cells (cubic), which the coarsest chunks (`chunk 2^levels` cells) must tile.
pub fn lod_settings(e: &Extraction, plan: &LodPlan, threads: usize) -> Result<LodSettings> {
    let cells = e.resolution.cells();
    let extent = e.bounds.max - e.bounds.min;
    let spacing = Vec3::new(
        extent.x / cells[0] as f32,
        extent.y / cells[1] as f32,
        extent.z / cells[2] as f32,
    );
    let (lo, hi) = (spacing.min_element(), spacing.max_element());
    if hi > lo * (1.0 + 1e-4) || !(hi.is_finite() && lo > 0.0) {
        bail!(
            "a multiresolution world needs cubic cells, but the box and resolution give cell \
             edges {:.6} x {:.6} x {:.6}: choose bounds proportional to the resolution",
            spacing.x,
            spacing.y,
            spacing.z
        );
    }
    let side = (plan.chunk as usize) << plan.levels;
    let mut roots = [0u32; 3];
    for i in 0..3 {
        if !cells[i].is_multiple_of(side) {
            bail!(
                "resolution {} is not a multiple of chunk x 2^levels = {side}",
                cells[i]
            );
        }
        roots[i] = u32::try_from(cells[i] / side).context("too many root chunks")?;
    }
    let geometry = LodGeometry::new(plan.levels, plan.chunk, roots)
        .context("the multiresolution world's shape")?;
    Ok(LodSettings {
        geometry,
        frame: LodFrame {
            origin: e.bounds.min,
            h: spacing.x,
        },
        ratio: plan.ratio,
        threads,
        cluster: e.clustering == Clustering::Integrated,
        // The morph is made for the path's longest step (a hair longer, for rounding).
        morph: (plan.morph > 0.0).then(|| {
            let path = viewer_path(e, plan);
            let step = path
                .windows(2)
                .map(|w| w[0].distance(w[1]))
                .fold(0.0f32, f32::max);
            MorphSettings {
                band: plan.morph,
                lead: step * (1.0 + 1e-4) + spacing.x * 1e-4,
            }
        }),
    })
}

/// The viewer's position at every step `0..=steps`: the path's waypoints (by default the box's
/// diagonal in x and z at the top of its lowest quarter) flown at even speed.
pub fn viewer_path(e: &Extraction, plan: &LodPlan) -> Vec<Vec3> {
    let (min, max) = (e.bounds.min, e.bounds.max);
    let y = min.y + 0.25 * (max.y - min.y);
    let points: Vec<Vec3> = match &plan.path {
        Some(p) => p.iter().map(|&c| Vec3::from(c)).collect(),
        None => vec![Vec3::new(min.x, y, min.z), Vec3::new(max.x, y, max.z)],
    };
    let lengths: Vec<f32> = points.windows(2).map(|w| w[0].distance(w[1])).collect();
    let total: f32 = lengths.iter().sum();
    (0..=plan.steps)
        .map(|k| {
            let mut s = total * k as f32 / plan.steps as f32;
            for (i, &l) in lengths.iter().enumerate() {
                if s <= l || i + 1 == lengths.len() {
                    let t = if l > 0.0 { (s / l).min(1.0) } else { 0.0 };
                    return points[i].lerp(points[i + 1], t);
                }
                s -= l;
            }
            points[0]
        })
        .collect()
}

/// The brushes of `plan`'s strokes at viewer step `step` in a world of finest cell `h`, each with
/// its frame time, in the manifest's order, one per frame held ([`crate::manifest::LodEdit`]):
/// scaled like the studio's brush and the `edit` workload's strokes
/// ([`StrokeParams::for_cells`]).
pub fn lod_brushes(plan: &LodPlan, step: usize, h: f32) -> Vec<(Brush, f32)> {
    let p = StrokeParams::for_cells(h, 1, 0);
    plan.edits
        .iter()
        .filter(|e| e.step == step)
        .flat_map(|e| {
            let brush = Brush {
                centre: Vec3::from(e.at),
                radius: e.radius,
                strength: p.strength * e.strength,
                mode: match e.mode {
                    LodEditMode::Add => BrushMode::Add,
                    LodEditMode::Subtract => BrushMode::Subtract,
                },
                clamp: p.clamp,
            };
            std::iter::repeat_n((brush, p.dt), e.frames as usize)
        })
        .collect()
}

/// How far the surface moved where chunks changed level, over one step.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Pop {
    /// Largest distance, in cells of the finer of the two levels.
    pub max_cells: f32,
    /// Sum of all measured distances, in those cells.
    pub sum_cells: f64,
    /// Points measured.
    pub points: usize,
}

impl Pop {
    /// Mean distance in cells (0 without points).
    pub fn mean_cells(&self) -> f64 {
        if self.points == 0 {
            0.0
        } else {
            self.sum_cells / self.points as f64
        }
    }

    fn add(&mut self, other: Pop) {
        self.max_cells = self.max_cells.max(other.max_cells);
        self.sum_cells += other.sum_cells;
        self.points += other.points;
    }
}

/// The checks of the welded world at one step.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct WorldCheck {
    /// Boundary edges not on the world box.
    pub open_edges: usize,
    /// Edges with more than two triangles.
    pub non_manifold_edges: usize,
    /// Edges two triangles traverse in the same direction.
    pub orientation_errors: usize,
    /// Largest angle between the normals two chunks of different levels give one shared
    /// crossing, degrees.
    pub normal_seam_max_deg: f32,
}

/// The shape of the world's triangles at one step ([`rmt_mesh::quality`], the extractor's
/// measure: radius ratio `R / (2r)`, 1 for an equilateral triangle, larger for slivers).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Shape {
    /// Triangles in the ratio statistics (all but the zero-area ones).
    pub measured: usize,
    /// Mean radius ratio.
    pub ar_mean: f64,
    /// Median radius ratio (linear interpolation, as `quality`).
    pub ar_median: f64,
    /// 99th percentile of the radius ratio (linear interpolation, as `quality`).
    pub ar_p99: f64,
    /// Largest radius ratio.
    pub ar_max: f64,
    /// Zero-area triangles (left out of the ratios).
    pub zero_area: usize,
}

/// The shape of every triangle of `world`'s chunks, measured as one mesh (chunks side by
/// side, not welded: the triangles are the same).
fn world_shape<F: ScalarField>(world: &LodWorld<F>) -> Result<Shape> {
    let chunks = world.chunk_meshes();
    let mut mesh = rmt_mesh::Mesh::default();
    for (_, m) in &chunks {
        let base = mesh.positions.len();
        u32::try_from(base + m.positions.len())
            .context("the world has too many vertices to measure as one mesh")?;
        let base = base as u32;
        mesh.positions.extend_from_slice(&m.positions);
        mesh.indices.extend(m.indices.iter().map(|&i| base + i));
    }
    let q = rmt_mesh::quality(&mesh);
    Ok(Shape {
        measured: mesh.triangle_count() - q.zero_area_triangles - q.unmeasurable_triangles,
        ar_mean: q.ar_mean,
        ar_median: q.ar_median,
        ar_p99: q.ar_p99,
        ar_max: q.ar_max,
        zero_area: q.zero_area_triangles,
    })
}

/// One viewer step.
#[derive(Clone, Debug, PartialEq)]
pub struct LodStep {
    /// Step number (0: the first meshing).
    pub step: usize,
    /// The viewer, world units.
    pub viewer: Vec3,
    /// Wall time of the re-mesh, seconds.
    pub remesh_s: f64,
    /// Chunks in the map.
    pub chunks: usize,
    /// Chunks meshed at this step.
    pub remeshed: usize,
    /// Chunks the re-mesh rule marked whose tets stayed the same (kept, not meshed).
    pub unchanged: usize,
    /// Chunks that left the map.
    pub dropped: usize,
    /// Triangles in the world.
    pub triangles: usize,
    /// Bytes held by the world ([`LodWorld::memory_bytes`]).
    pub memory_bytes: usize,
    /// The pop, when some chunk changed level (under a morph: the old map's surfaces with the
    /// new values against the new surfaces, the change of tets alone at one viewer).
    pub pop: Option<Pop>,
    /// Under a morph, how far the surface moved over the step with the values: every chunk
    /// re-meshed in place against its surface before the step, and every chunk that left the
    /// map with the old values against itself with the new ones. Not measured on a step with
    /// strokes (they move the surface too).
    pub morph: Option<Pop>,
    /// Strokes of the manifest (`[lod] edits` entries) applied at this step.
    pub strokes: usize,
    /// Chunks of the step's map that see a value the step's strokes changed (all re-meshed).
    pub edit_chunks: usize,
    /// The checks, on validated steps.
    pub check: Option<WorldCheck>,
    /// The shape of the world's triangles, on validated steps (also where the check's region
    /// was too large).
    pub shape: Option<Shape>,
    /// Per level `0..=levels`: chunks in the map and their triangles.
    pub levels: Vec<LevelCount>,
}

/// The chunks and triangles of one level at one step.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LevelCount {
    /// Chunks of the level in the map.
    pub chunks: usize,
    /// Their triangles.
    pub triangles: usize,
    /// Those of its chunks that see a value the step's strokes changed.
    pub edit_chunks: usize,
}

/// One chunk of the level map at the last step, for the report's top view.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MapChunk {
    /// The chunk.
    pub key: ChunkKey,
    /// Its box's near corner, world coordinates.
    pub min: [f64; 3],
    /// Its box's far corner, world coordinates.
    pub max: [f64; 3],
    /// Its triangles.
    pub triangles: usize,
}

/// One configuration's flight.
#[derive(Clone, Debug, PartialEq)]
pub struct LodSession {
    /// Step 0 and every viewer step.
    pub steps: Vec<LodStep>,
    /// Triangles of the world at the finest level everywhere.
    pub finest_triangles: f64,
    /// Whether `finest_triangles` was counted (`exact`) or `estimated`.
    pub finest_source: &'static str,
    /// The process's peak resident set after the session, bytes (Linux; 0 elsewhere).
    pub rss_max_bytes: u64,
    /// The last step's world, welded, when asked for.
    pub mesh: Option<rmt_mesh::Mesh>,
    /// The last step's level map, in map order.
    pub map: Vec<MapChunk>,
}

/// Flies the viewer of `plan` over the world of `e` (see the module doc); with `keep_mesh`, the
/// session holds the last step's welded world.
pub fn run_lod_session<F: ScalarField + Copy>(
    field: F,
    e: &Extraction,
    plan: &LodPlan,
    threads: usize,
    keep_mesh: bool,
) -> Result<LodSession> {
    let settings = lod_settings(e, plan, threads)?;
    let geom = settings.geometry;
    let frame = settings.frame;
    let mut world = LodWorld::new(field, settings).context("building the multiresolution world")?;
    world.set_tet_cache_bytes(plan.tet_cache_mb.saturating_mul(1 << 20));
    let morphing = plan.morph > 0.0;
    world.set_keep_replaced(morphing);
    let path = viewer_path(e, plan);
    let mut steps = Vec::with_capacity(path.len());
    for (k, &viewer) in path.iter().enumerate() {
        let brushes = lod_brushes(plan, k, frame.h);
        let edited = !brushes.is_empty();
        // The viewer's map (`LevelMap::from_viewer`); the morph follows the viewer too.
        world.set_viewer(viewer);
        let map = world.pending_map().clone();
        // The old surfaces a pop is measured against: every chunk leaving the map and the
        // chunks touching it, before the re-mesh replaces them.
        let (leaving, old_near) = match world.level_map() {
            Some(old) => {
                let leaving: Vec<ChunkKey> = old
                    .chunks()
                    .iter()
                    .copied()
                    .filter(|c| !map.contains(c))
                    .collect();
                let mut near: HashMap<ChunkKey, ChunkMesh> = HashMap::new();
                for c in &leaving {
                    let (lo, hi) = c.bounds(&geom);
                    for n in old.leaves_touching(lo, hi) {
                        if let (false, Some(m)) = (near.contains_key(&n), world.chunk_mesh(&n)) {
                            near.insert(n, m.clone());
                        }
                    }
                }
                (leaving, Some((old.clone(), near)))
            }
            None => (Vec::new(), None),
        };
        // The step's strokes, after the viewer moved: the chunks of the new map that see them.
        let mut edit_chunks: BTreeSet<ChunkKey> = BTreeSet::new();
        for (brush, dt) in &brushes {
            world
                .edit(brush, *dt)
                .with_context(|| format!("a stroke at step {k}"))?;
            edit_chunks.extend(world.chunks_seeing_brush(&map, brush));
        }
        let t = Instant::now();
        let r = world.remesh().context("re-meshing the world")?;
        let remesh_s = t.elapsed().as_secs_f64();
        let replaced = world.take_replaced();
        // Under a morph or after strokes, the old map's surfaces again with the new values:
        // the pop is then the change of tets alone (and under a morph, the change of values
        // is the morph).
        let old_now: Option<HashMap<ChunkKey, ChunkMesh>> = match &old_near {
            Some((old, near)) if morphing || edited => {
                let keys: Vec<ChunkKey> = near.keys().copied().collect();
                let meshes: Vec<ChunkMesh> = world.pool().install(|| {
                    keys.par_iter()
                        .map(|k| world.mesh_under(old, k))
                        .collect::<Result<_, _>>()
                })?;
                Some(keys.into_iter().zip(meshes).collect())
            }
            _ => None,
        };
        let pop = match &old_near {
            Some((old, near)) if !leaving.is_empty() => {
                let before = old_now.as_ref().unwrap_or(near);
                Some(measure_pop(&world, old, before, &leaving, &geom, frame.h))
            }
            _ => None,
        };
        let morph = match (&old_near, &old_now) {
            (Some((old, near)), Some(now)) if morphing && !edited => {
                let moved = Moved {
                    old,
                    before: near,
                    now,
                    replaced: &replaced,
                };
                Some(measure_morph(&world, &moved, &leaving, &geom, frame.h))
            }
            _ => None,
        };
        drop(replaced);
        let validate = k + 1 == path.len()
            || k == 0
            || (plan.validate_every > 0 && k % plan.validate_every == 0);
        let check = if validate {
            // The region of every chunk the map change marked, kept or re-meshed.
            let marked: Vec<ChunkKey> = r.remeshed.iter().chain(&r.unchanged).copied().collect();
            check_world(&world, &marked, plan.validate_max_chunks)?
        } else {
            None
        };
        let shape = if validate {
            Some(world_shape(&world)?)
        } else {
            None
        };
        let chunks = world.level_map().map_or(0, |m| m.chunks().len());
        let mut levels = level_counts(&world, geom.levels);
        for c in &edit_chunks {
            if let Some(l) = levels.get_mut(usize::from(c.level)) {
                l.edit_chunks += 1;
            }
        }
        steps.push(LodStep {
            step: k,
            viewer,
            remesh_s,
            chunks,
            remeshed: r.remeshed.len(),
            unchanged: r.unchanged.len(),
            dropped: r.dropped.len(),
            triangles: r.triangles,
            memory_bytes: world.memory_bytes(),
            pop,
            morph,
            strokes: plan.edits.iter().filter(|e| e.step == k).count(),
            edit_chunks: edit_chunks.len(),
            check,
            shape,
            levels,
        });
    }
    let (finest_triangles, finest_source) = finest(&world, field, plan, threads)?;
    Ok(LodSession {
        steps,
        finest_triangles,
        finest_source,
        rss_max_bytes: peak_rss_bytes(),
        mesh: keep_mesh.then(|| world.mesh_welded().0),
        map: map_chunks(&world, &geom, &frame),
    })
}

/// Chunks and triangles per level `0..=levels` of the world's current map.
fn level_counts<F: ScalarField>(world: &LodWorld<F>, levels: u8) -> Vec<LevelCount> {
    let mut out = vec![LevelCount::default(); usize::from(levels) + 1];
    for (k, m) in world.chunk_meshes() {
        if let Some(c) = out.get_mut(usize::from(k.level)) {
            c.chunks += 1;
            c.triangles += m.triangles();
        }
    }
    out
}

/// The world's current level map with every chunk's box in world coordinates.
fn map_chunks<F: ScalarField>(
    world: &LodWorld<F>,
    geom: &LodGeometry,
    frame: &LodFrame,
) -> Vec<MapChunk> {
    let u = f64::from(frame.h) * 0.5;
    let origin = frame.origin.as_dvec3().to_array();
    let at = |p: [i64; 3]| std::array::from_fn(|i| origin[i] + p[i] as f64 * u);
    world
        .chunk_meshes()
        .into_iter()
        .map(|(key, m)| {
            let (lo, hi) = key.bounds(geom);
            MapChunk {
                key,
                min: at(lo),
                max: at(hi),
                triangles: m.triangles(),
            }
        })
        .collect()
}

/// Whether the closed boxes `a` and `b` share a volume (not only a face, edge or corner).
fn overlaps(a: ([i64; 3], [i64; 3]), b: ([i64; 3], [i64; 3])) -> bool {
    (0..3).all(|i| a.0[i] < b.1[i] && b.0[i] < a.1[i])
}

/// The triangles of `meshes` on a grid of cells of about `cell`.
fn grid_of<'a>(meshes: impl Iterator<Item = &'a ChunkMesh>, cell: f32) -> TriangleGrid {
    let mut tris = Vec::new();
    for m in meshes {
        for t in m.indices.chunks_exact(3) {
            tris.push([0, 1, 2].map(|i| m.positions[t[i] as usize]));
        }
    }
    TriangleGrid::new(tris, cell)
}

/// One side of a pop: chunk `k`'s surface `mesh` against the other side's surfaces
/// (`other_mesh`) of the leaves of `other` touching it, in cells of the finer level among `k`
/// and the leaves overlapping it.
fn pop_side<'a>(
    k: &ChunkKey,
    mesh: &ChunkMesh,
    other: &LevelMap,
    other_mesh: impl Fn(&ChunkKey) -> Option<&'a ChunkMesh>,
    geom: &LodGeometry,
    h: f32,
) -> Pop {
    let b = k.bounds(geom);
    let around = other.leaves_touching(b.0, b.1);
    let finer = around
        .iter()
        .filter(|n| overlaps(n.bounds(geom), b))
        .map(|n| n.level)
        .fold(k.level, u8::min);
    let cell = h * (1u32 << finer) as f32;
    let target = grid_of(around.iter().filter_map(other_mesh), 2.0 * cell);
    let points = &mesh.positions;
    match one_sided(points, &target) {
        Some((max, mean)) => Pop {
            max_cells: max / cell,
            sum_cells: f64::from(mean) / f64::from(cell) * points.len() as f64,
            points: points.len(),
        },
        None => Pop::default(),
    }
}

/// A chunk's surface on one side of a comparison.
type Surface<'a> = dyn Fn(&ChunkKey) -> Option<&'a ChunkMesh> + Sync + 'a;

/// [`pop_side`] of every chunk of `keys` with a surface in `mine`, against the surfaces
/// `theirs` of the leaves of `other` around it: chunk by chunk on the world's threads, summed
/// in the order of `keys` (the same bits on any thread count).
fn sides<F: ScalarField>(
    world: &LodWorld<F>,
    keys: &[ChunkKey],
    mine: &Surface<'_>,
    other: &LevelMap,
    theirs: &Surface<'_>,
    (geom, h): (&LodGeometry, f32),
) -> Pop {
    let each: Vec<Pop> = world.pool().install(|| {
        keys.par_iter()
            .filter_map(|k| Some(pop_side(k, mine(k)?, other, theirs, geom, h)))
            .collect()
    });
    let mut pop = Pop::default();
    for side in each {
        pop.add(side);
    }
    pop
}

/// The pop of one step: every chunk that left the map (its surface in `old_meshes`) against
/// the new surface around it, and every chunk that entered against the old surface around it.
fn measure_pop<F: ScalarField>(
    world: &LodWorld<F>,
    old: &LevelMap,
    old_meshes: &HashMap<ChunkKey, ChunkMesh>,
    leaving: &[ChunkKey],
    geom: &LodGeometry,
    h: f32,
) -> Pop {
    let Some(new) = world.level_map() else {
        return Pop::default();
    };
    let (old_surface, new_surface) = (
        |n: &ChunkKey| old_meshes.get(n),
        |n: &ChunkKey| world.chunk_mesh(n),
    );
    let entering: Vec<ChunkKey> = new
        .chunks()
        .iter()
        .copied()
        .filter(|c| !old.contains(c))
        .collect();
    let mut pop = sides(world, leaving, &old_surface, new, &new_surface, (geom, h));
    pop.add(sides(
        world,
        &entering,
        &new_surface,
        old,
        &old_surface,
        (geom, h),
    ));
    pop
}

/// The surfaces a morph's motion over one step is measured between.
struct Moved<'a> {
    /// The map before the step.
    old: &'a LevelMap,
    /// Chunks of `old` (the leaving ones and their neighbours) before the step.
    before: &'a HashMap<ChunkKey, ChunkMesh>,
    /// The same chunks of `old` with the values after the step.
    now: &'a HashMap<ChunkKey, ChunkMesh>,
    /// The chunks the step re-meshed in place, with their surfaces before it.
    replaced: &'a [(ChunkKey, ChunkMesh)],
}

/// How far a morph moved the surface over one step (see [`LodStep::morph`]): every chunk
/// re-meshed in place against the surface before the step around it, both ways; every chunk
/// that left the map, with the old values against the new, both ways.
fn measure_morph<F: ScalarField>(
    world: &LodWorld<F>,
    m: &Moved<'_>,
    leaving: &[ChunkKey],
    geom: &LodGeometry,
    h: f32,
) -> Pop {
    let Some(new) = world.level_map() else {
        return Pop::default();
    };
    let replaced: HashMap<ChunkKey, &ChunkMesh> = m.replaced.iter().map(|(k, c)| (*k, c)).collect();
    let keys: Vec<ChunkKey> = m.replaced.iter().map(|(k, _)| *k).collect();
    // Any chunk of the old map before the step: replaced, left, or kept as it is.
    let old_surface = |n: &ChunkKey| {
        replaced
            .get(n)
            .copied()
            .or_else(|| m.before.get(n))
            .or_else(|| world.chunk_mesh(n))
    };
    let new_surface = |n: &ChunkKey| world.chunk_mesh(n);
    let (before, now) = (|n: &ChunkKey| m.before.get(n), |n: &ChunkKey| m.now.get(n));
    let at = (geom, h);
    let mut pop = sides(
        world,
        &keys,
        &|n| replaced.get(n).copied(),
        new,
        &new_surface,
        at,
    );
    pop.add(sides(world, &keys, &new_surface, m.old, &old_surface, at));
    pop.add(sides(world, leaving, &before, m.old, &now, at));
    pop.add(sides(world, leaving, &now, m.old, &before, at));
    pop
}

/// The surface around the chunks meshed at this step checked: `region` = those chunks and the
/// leaves touching them, its tetrahedra built chunk by chunk, its chunks' surfaces welded. An
/// edge may be open only in a boundary face of the region's tetrahedra (the domain's boundary,
/// or the region's own, which no meshed chunk reaches: every meshed chunk's neighbours are in
/// the region), so a crack at any face of a meshed chunk is found. `None` when the region has
/// more than `max_chunks` chunks. The normals of every crossing that chunks of two levels in
/// the region share are compared (the level seam).
fn check_world<F: ScalarField>(
    world: &LodWorld<F>,
    meshed: &[ChunkKey],
    max_chunks: usize,
) -> Result<Option<WorldCheck>> {
    let map = world
        .level_map()
        .context("checking a world that was never meshed")?;
    let geom = map.geometry();
    let mut region: Vec<ChunkKey> = meshed.to_vec();
    for k in meshed {
        let (lo, hi) = k.bounds(geom);
        region.extend(map.leaves_touching(lo, hi));
        if region.len() > 64 * max_chunks.max(1) {
            return Ok(None);
        }
    }
    region.sort_unstable();
    region.dedup();
    if region.len() > max_chunks {
        return Ok(None);
    }
    let tets: Vec<Vec<_>> = region
        .par_iter()
        .map(|k| chunk_tets(map, k))
        .collect::<Result<_, _>>()
        .context("the region's tetrahedra")?;
    let (_, boundary) = check_tets(tets.iter().flatten().map(|t| &t.tet));
    let meshes: Vec<(ChunkKey, &ChunkMesh)> = region
        .iter()
        .filter_map(|k| world.chunk_mesh(k).map(|m| (*k, m)))
        .collect();
    let (mesh, keys) = weld(meshes.iter().map(|(_, m)| *m));
    let surface = check_surface(&keys, &mesh.indices, &boundary);
    // Every crossing some chunk meshes, with the level and normal it got there first.
    let mut seen: HashMap<_, (u8, [f32; 3])> = HashMap::new();
    let mut seam_max = 0.0f32;
    for (key, m) in meshes {
        for (v, crossing) in m.keys.iter().enumerate() {
            let normal = m.normals[v];
            match seen.get(crossing) {
                Some(&(level, first)) if level != key.level => {
                    // atan2 of the cross and dot products in f64: exact near 0, where acos of
                    // an f32 dot product reads 0.05 degrees for two equal normals.
                    let (a, b) = (Vec3::from(first).as_dvec3(), Vec3::from(normal).as_dvec3());
                    let angle = a.cross(b).length().atan2(a.dot(b)).to_degrees();
                    seam_max = seam_max.max(angle as f32);
                }
                Some(_) => {}
                None => {
                    seen.insert(*crossing, (key.level, normal));
                }
            }
        }
    }
    Ok(Some(WorldCheck {
        open_edges: surface.open_inside,
        non_manifold_edges: surface.non_manifold,
        orientation_errors: surface.misoriented,
        normal_seam_max_deg: seam_max,
    }))
}

/// Triangles of the world at the finest level everywhere (clustered when the world clusters,
/// with the world's strokes): counted when the finest level has at
/// most `plan.finest_exact_chunks` chunks (all meshed at once), else estimated from the world's
/// chunks as triangles x 4^level (a surface meshed at half the spacing has about 4 times the
/// triangles).
fn finest<F: ScalarField + Copy>(
    world: &LodWorld<F>,
    field: F,
    plan: &LodPlan,
    threads: usize,
) -> Result<(f64, &'static str)> {
    let geom = world.settings().geometry;
    let finest_chunks: u64 = geom
        .roots
        .iter()
        .map(|&r| u64::from(r) << plan.levels)
        .product();
    if finest_chunks as usize <= plan.finest_exact_chunks {
        let map = LevelMap::uniform(geom, 0);
        let pool = thread_pool(threads).context("threads for the finest level")?;
        let frame = world.settings().frame;
        let edited = EditedField::new(&field, world.edits());
        let meshes =
            mesh_chunks(&map, &edited, &frame, &pool).context("meshing the finest level")?;
        let total: usize = if world.settings().cluster {
            pool.install(|| {
                meshes
                    .par_iter()
                    .map(|m| cluster_chunk(m, &frame).0.triangles())
                    .sum()
            })
        } else {
            meshes.iter().map(ChunkMesh::triangles).sum()
        };
        return Ok((total as f64, "exact"));
    }
    let estimate: f64 = world
        .chunk_meshes()
        .iter()
        .map(|(k, m)| m.triangles() as f64 * 4f64.powi(i32::from(k.level)))
        .sum();
    Ok((estimate, "estimated"))
}

/// The process's peak resident set (VmHWM), bytes; 0 where unknown.
fn peak_rss_bytes() -> u64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            let line = s.lines().find(|l| l.starts_with("VmHWM:"))?;
            let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
            Some(kb * 1024)
        })
        .unwrap_or(0)
}

/// The rows of `lod.csv` for one session (columns of
/// [`LOD_STEPS`](rmt_runfolder::schema::LOD_STEPS)).
pub fn lod_rows(id: &str, s: &LodSession) -> Vec<Vec<String>> {
    s.steps
        .iter()
        .map(|st| {
            let opt = |v: Option<String>| v.unwrap_or_default();
            vec![
                id.to_string(),
                st.step.to_string(),
                format!("{:.6}", st.viewer.x),
                format!("{:.6}", st.viewer.y),
                format!("{:.6}", st.viewer.z),
                format!("{:.9}", st.remesh_s),
                st.chunks.to_string(),
                st.remeshed.to_string(),
                st.unchanged.to_string(),
                st.dropped.to_string(),
                st.triangles.to_string(),
                st.memory_bytes.to_string(),
                opt(st.pop.map(|p| format!("{:.4}", p.max_cells))),
                opt(st.pop.map(|p| format!("{:.4}", p.mean_cells()))),
                opt(st.pop.map(|p| p.points.to_string())),
                opt(st.morph.map(|p| format!("{:.4}", p.max_cells))),
                opt(st.morph.map(|p| format!("{:.4}", p.mean_cells()))),
                opt(st.check.map(|c| c.open_edges.to_string())),
                opt(st.check.map(|c| c.non_manifold_edges.to_string())),
                opt(st.check.map(|c| c.orientation_errors.to_string())),
                opt(st.check.map(|c| format!("{:.4}", c.normal_seam_max_deg))),
                st.edit_chunks.to_string(),
                opt(st.shape.map(|q| format!("{:.4}", q.ar_mean))),
                opt(st.shape.map(|q| format!("{:.4}", q.ar_median))),
                opt(st.shape.map(|q| format!("{:.4}", q.ar_p99))),
                opt(st.shape.map(|q| format!("{:.4}", q.ar_max))),
                opt(st.shape.map(|q| q.zero_area.to_string())),
            ]
        })
        .collect()
}

/// The rows of `lod_levels.csv` for one session (columns of
/// [`LOD_LEVELS`](rmt_runfolder::schema::LOD_LEVELS)): every step, every level.
pub fn lod_level_rows(id: &str, s: &LodSession) -> Vec<Vec<String>> {
    s.steps
        .iter()
        .flat_map(|st| {
            st.levels.iter().enumerate().map(move |(level, c)| {
                vec![
                    id.to_string(),
                    st.step.to_string(),
                    level.to_string(),
                    c.chunks.to_string(),
                    c.triangles.to_string(),
                    c.edit_chunks.to_string(),
                ]
            })
        })
        .collect()
}

/// The rows of `lod_map.csv` for one session (columns of
/// [`LOD_MAP`](rmt_runfolder::schema::LOD_MAP)): the last step's chunks in map order.
pub fn lod_map_rows(id: &str, s: &LodSession) -> Vec<Vec<String>> {
    let step = s.steps.last().map_or(0, |st| st.step).to_string();
    s.map
        .iter()
        .map(|c| {
            let mut row = vec![id.to_string(), step.clone(), c.key.level.to_string()];
            row.extend(c.key.at.iter().map(i32::to_string));
            row.extend(c.min.iter().chain(&c.max).map(|v| format!("{v:.6}")));
            row.push(c.triangles.to_string());
            row
        })
        .collect()
}

/// Quantile `q` of `values` (nearest rank); 0 when empty.
fn quantile(values: &[f64], q: f64) -> f64 {
    if values.is_empty() {
        return 0.0;
    }
    let mut v = values.to_vec();
    v.sort_by(f64::total_cmp);
    let rank = ((q * v.len() as f64).ceil() as usize).clamp(1, v.len());
    v[rank - 1]
}

/// The summary row of one session (columns of
/// [`LOD_SUMMARY`](rmt_runfolder::schema::LOD_SUMMARY)); the re-mesh times are the viewer
/// steps' (step 0, the first meshing, is `t_initial_s`).
pub fn lod_summary_row(
    id: &str,
    e: &Extraction,
    plan: &LodPlan,
    threads: usize,
    s: &LodSession,
) -> Vec<String> {
    let moves: Vec<&LodStep> = s.steps.iter().filter(|st| st.step > 0).collect();
    let times: Vec<f64> = moves.iter().map(|st| st.remesh_s * 1e3).collect();
    let remeshed: Vec<usize> = moves.iter().map(|st| st.remeshed).collect();
    let mut pop = Pop::default();
    for p in s.steps.iter().filter_map(|st| st.pop) {
        pop.add(p);
    }
    let mut morph = Pop::default();
    for p in s.steps.iter().filter_map(|st| st.morph) {
        morph.add(p);
    }
    let morphed = |v: String| if plan.morph > 0.0 { v } else { String::new() };
    let checks: Vec<WorldCheck> = s.steps.iter().filter_map(|st| st.check).collect();
    let max_of = |f: fn(&WorldCheck) -> usize| checks.iter().map(f).max().unwrap_or(0);
    let seam = checks
        .iter()
        .map(|c| c.normal_seam_max_deg)
        .fold(0.0f32, f32::max);
    let most_triangles = s.steps.iter().map(|st| st.triangles).max().unwrap_or(0);
    let shapes: Vec<Shape> = s.steps.iter().filter_map(|st| st.shape).collect();
    let measured: usize = shapes.iter().map(|q| q.measured).sum();
    let ar_mean = shapes
        .iter()
        .map(|q| q.ar_mean * q.measured as f64)
        .sum::<f64>()
        / measured.max(1) as f64;
    let worst = |f: fn(&Shape) -> f64| shapes.iter().map(f).fold(0.0f64, f64::max);
    let [rx, ry, rz] = e.resolution.cells();
    vec![
        id.to_string(),
        e.object.kind.name().to_string(),
        crate::config::method_name(e.method).to_string(),
        crate::config::lattice_name(e.method, e.lattice).to_string(),
        e.clustering.name().to_string(),
        rx.to_string(),
        ry.to_string(),
        rz.to_string(),
        plan.levels.to_string(),
        plan.chunk.to_string(),
        plan.ratio.to_string(),
        plan.morph.to_string(),
        threads.to_string(),
        moves.len().to_string(),
        format!("{:.6}", s.steps.first().map_or(0.0, |st| st.remesh_s)),
        format!("{:.4}", quantile(&times, 0.5)),
        format!("{:.4}", quantile(&times, 0.99)),
        format!("{:.4}", quantile(&times, 1.0)),
        format!(
            "{:.3}",
            remeshed.iter().sum::<usize>() as f64 / remeshed.len().max(1) as f64
        ),
        remeshed.iter().max().copied().unwrap_or(0).to_string(),
        most_triangles.to_string(),
        checks.len().to_string(),
        max_of(|c| c.open_edges).to_string(),
        max_of(|c| c.non_manifold_edges).to_string(),
        max_of(|c| c.orientation_errors).to_string(),
        format!("{:.4}", pop.max_cells),
        format!("{:.4}", pop.mean_cells()),
        morphed(format!("{:.4}", morph.max_cells)),
        morphed(format!("{:.4}", morph.mean_cells())),
        format!("{seam:.4}"),
        format!("{:.0}", s.finest_triangles),
        s.finest_source.to_string(),
        format!(
            "{:.5}",
            if s.finest_triangles > 0.0 {
                most_triangles as f64 / s.finest_triangles
            } else {
                0.0
            }
        ),
        s.steps
            .iter()
            .map(|st| st.memory_bytes)
            .max()
            .unwrap_or(0)
            .to_string(),
        s.rss_max_bytes.to_string(),
        s.steps
            .iter()
            .map(|st| st.strokes)
            .sum::<usize>()
            .to_string(),
        s.steps
            .iter()
            .map(|st| st.edit_chunks)
            .sum::<usize>()
            .to_string(),
        format!("{ar_mean:.4}"),
        format!("{:.4}", worst(|q| q.ar_median)),
        format!("{:.4}", worst(|q| q.ar_p99)),
        format!("{:.4}", worst(|q| q.ar_max)),
        shapes
            .iter()
            .map(|q| q.zero_area)
            .max()
            .unwrap_or(0)
            .to_string(),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::Normals;
    use crate::objects::{Bounds, ObjectKind, ObjectParams, ObjectSpec, Resolution};
    use rmt_extract::{Clustering, Lattice, Method};

    fn extraction(cells: [usize; 3], bounds: [f32; 6]) -> Extraction {
        Extraction {
            object: ObjectSpec::new(ObjectKind::Caves, ObjectParams::default()).unwrap(),
            bounds: Bounds::try_from(bounds).unwrap(),
            resolution: Resolution::Axes(cells),
            method: Method::Mt,
            lattice: Lattice::BodyCentred,
            clustering: Clustering::None,
            collapse_threshold: 0.5,
            iso: 0.0,
            normals: Normals::Area,
            simplify: None,
            vertex_cache: false,
        }
    }

    fn plan(path: Option<Vec<[f32; 3]>>, steps: usize) -> LodPlan {
        LodPlan {
            levels: 2,
            chunk: 4,
            ratio: 1.0,
            steps,
            path,
            validate_every: 1,
            validate_max_chunks: 4096,
            finest_exact_chunks: 4096,
            tet_cache_mb: 1024,
            morph: 0.0,
            edits: Vec::new(),
        }
    }

    #[test]
    fn the_path_is_flown_at_even_speed_through_every_waypoint() {
        let e = extraction([32, 16, 32], [-1.0, -0.5, -1.0, 1.0, 0.5, 1.0]);
        // Two legs of length 1 and 3: 4 steps of length 1.
        let p = plan(Some(vec![[0.0; 3], [1.0, 0.0, 0.0], [1.0, 3.0, 0.0]]), 4);
        let v = viewer_path(&e, &p);
        assert_eq!(v.len(), 5);
        let expect = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [1.0, 2.0, 0.0],
            [1.0, 3.0, 0.0],
        ];
        for (a, b) in v.iter().zip(expect) {
            assert!(a.distance(Vec3::from(b)) < 1e-5, "{a} vs {b:?}");
        }
        // Default: the box's x-z diagonal at the top of its lowest quarter.
        let d = viewer_path(&e, &plan(None, 2));
        assert!(d[0].distance(Vec3::new(-1.0, -0.25, -1.0)) < 1e-6);
        assert!(d[2].distance(Vec3::new(1.0, -0.25, 1.0)) < 1e-6);
    }

    #[test]
    fn the_world_shape_comes_from_the_resolution() {
        let e = extraction([32, 16, 32], [-1.0, -0.5, -1.0, 1.0, 0.5, 1.0]);
        let s = lod_settings(&e, &plan(None, 1), 2).unwrap();
        assert_eq!(s.geometry.roots, [2, 1, 2]);
        assert_eq!(s.frame.origin, Vec3::new(-1.0, -0.5, -1.0));
        assert!((s.frame.h - 1.0 / 16.0).abs() < 1e-7);
        let flat = extraction([32, 16, 32], [-1.0, -1.0, -1.0, 1.0, 1.0, 1.0]);
        let err = lod_settings(&flat, &plan(None, 1), 2)
            .unwrap_err()
            .to_string();
        assert!(err.contains("cubic cells"), "{err}");
        let uneven = extraction([40, 16, 32], [-1.25, -0.5, -1.0, 1.25, 0.5, 1.0]);
        let err = lod_settings(&uneven, &plan(None, 1), 2)
            .unwrap_err()
            .to_string();
        assert!(err.contains("40") && err.contains("16"), "{err}");
    }

    #[test]
    fn quantiles_are_nearest_rank() {
        let v = [5.0, 1.0, 4.0, 2.0, 3.0];
        assert_eq!(quantile(&v, 0.5), 3.0);
        assert_eq!(quantile(&v, 0.99), 5.0);
        assert_eq!(quantile(&v, 0.0), 1.0);
        assert_eq!(quantile(&[], 0.5), 0.0);
        let p = Pop {
            max_cells: 1.0,
            sum_cells: 3.0,
            points: 4,
        };
        assert_eq!(p.mean_cells(), 0.75);
        assert_eq!(Pop::default().mean_cells(), 0.0);
    }
}
