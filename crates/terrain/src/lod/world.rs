//! A multiresolution world that follows a viewer: the level map, one surface per chunk, and
//! re-meshing of only the chunks whose tets can have changed.
//!
//! ```text
//!   set_viewer(pos) -> LevelMap::from_viewer (pending)
//!   remesh():  for every chunk K of the new map
//!                new, or the leaves touching dependency_box(K) differ between the maps
//!                (chunks of >= LOCAL_CHUNK cells: K's own box, so K's level or a
//!                neighbour's changed), or an edit marked it
//!                  -> stale; in parallel, on the world's threads:
//!                     not edited, and the fast path under both maps   -> same tets: keep
//!                     nothing when the field's bound puts the chunk on one side of 0
//!                     else its tets, encoded (TetCache::encoded_tets):
//!                       not edited, the encoding equal to last time  -> same tets: keep
//!                       else march (not edited: the normals of crossings the chunk's
//!                       last surface has are taken from it, not probed again)
//!                else keep K's surface
//!              chunks no longer in the map are dropped
//! ```
//!
//! A chunk's tets are a function of the map's leaves inside its dependency box
//! ([`super::mesh::dependency_box`]), and its surface a function of its tets and the field, so
//! the incrementally updated world equals a from-scratch meshing of the new map, byte for
//! byte (tested). Most chunks the rule marks keep their tets: a neighbour's change of level
//! reaches only the transition layer, one tet of the coarser level deep. The fast path's tets
//! are the lattice's over the chunk's box whatever its neighbours, and any other chunk's are
//! compared in the cache's encoding, exactly.

use std::collections::HashMap;

use glam::Vec3;
use rayon::prelude::*;
use rmt_fields::ScalarField;
use rmt_mesh::Mesh;

use super::cluster::cluster_chunk;
use super::edits::{chunks_seeing, EditedField, Overlay};
use super::error::LodError;
use super::lattice::Point;
use super::level_map::{ChunkKey, LevelMap, LodGeometry};
use super::mesh::{changed_leaves, is_fast_path, needs_remesh_given, world_tets, MeshTet};
use super::morph::Morph;
use super::mt::{march, mesh_chunk_with, remesh_chunk, weld, ChunkMesh, Last, LodFrame, Remeshed};
use super::tet_cache::{EncodedTets, TetCache, TetCacheStats, DEFAULT_TET_CACHE_BYTES};

/// What a multiresolution world is.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LodSettings {
    /// Levels, chunk size and extent.
    pub geometry: LodGeometry,
    /// Where the lattice sits in the world.
    pub frame: LodFrame,
    /// The distance rule: a chunk is split while the viewer is closer to it than `ratio` of
    /// its edge ([`LevelMap::from_viewer`]).
    pub ratio: f64,
    /// Worker threads (>= 1); the meshes do not depend on it.
    pub threads: usize,
    /// The morph between levels, if any.
    pub morph: Option<MorphSettings>,
    /// Merge RMT's groups inside every chunk, where the exact check allows it
    /// ([`cluster_chunk`]); crossings near a chunk's faces stay plain.
    pub cluster: bool,
}

/// A world's morph between levels ([`Morph`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MorphSettings {
    /// In `(0, 1]`: the depth of each level's band as a fraction of `ratio` times its chunk
    /// edge.
    pub band: f64,
    /// The longest viewer step (world units) that changes a level without a pop; it must be
    /// shorter than level 0's band.
    pub lead: f32,
}

/// What one [`LodWorld::remesh`] did.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct LodRemesh {
    /// Chunks (re-)meshed, in map order.
    pub remeshed: Vec<ChunkKey>,
    /// Chunks the re-mesh rule marked whose tets turned out the same (not edited): their
    /// surfaces were kept, in map order.
    pub unchanged: Vec<ChunkKey>,
    /// Chunks dropped (no longer leaves of the map), sorted.
    pub dropped: Vec<ChunkKey>,
    /// Chunks whose surface was kept (`unchanged` among them).
    pub kept: usize,
    /// Triangles in the world after the step.
    pub triangles: usize,
}

/// A multiresolution world over a procedural field: a level map chosen from the viewer and
/// one surface per chunk.
pub struct LodWorld<F: ScalarField> {
    field: F,
    settings: LodSettings,
    pool: rayon::ThreadPool,
    /// The map the surfaces are of.
    map: Option<LevelMap>,
    /// The map the next remesh moves to.
    pending: LevelMap,
    /// The viewer (in `u`) of the pending map, for the morph.
    viewer: [f64; 3],
    /// The morph the surfaces were marched with.
    morphed: Option<Morph>,
    meshes: HashMap<ChunkKey, ChunkMesh>,
    /// The encoded tets each chunk's surface was marched from (every chunk marched from tets
    /// that have an encoding; none for an empty box).
    encoded: HashMap<ChunkKey, EncodedTets>,
    /// The brush strokes applied so far ([`LodWorld::edit`]).
    edits: Overlay,
    /// Chunks of the current map an edit marked for the next remesh.
    edited: std::collections::HashSet<ChunkKey>,
    /// Chunk tets by surroundings ([`TetCache`]).
    tets: TetCache,
    /// Whether [`LodWorld::remesh`] keeps the surfaces it replaces ([`LodWorld::take_replaced`]).
    keep_replaced: bool,
    /// The surfaces the last remeshes replaced, when kept.
    replaced: Vec<(ChunkKey, ChunkMesh)>,
}

/// Meshes every chunk of `map` on `pool`, in map order.
pub fn mesh_chunks(
    map: &LevelMap,
    field: &dyn ScalarField,
    frame: &LodFrame,
    pool: &rayon::ThreadPool,
) -> Result<Vec<ChunkMesh>, LodError> {
    mesh_chunks_morphed(map, field, frame, None, pool)
}

/// [`mesh_chunks`] on the values `morph` makes of the field's.
pub fn mesh_chunks_morphed(
    map: &LevelMap,
    field: &dyn ScalarField,
    frame: &LodFrame,
    morph: Option<&Morph>,
    pool: &rayon::ThreadPool,
) -> Result<Vec<ChunkMesh>, LodError> {
    pool.install(|| {
        map.chunks()
            .par_iter()
            .map(|k| mesh_chunk_with(map, k, field, frame, None, morph))
            .collect()
    })
}

/// The reference: the whole world's tets built at once ([`world_tets`]), cut by owning chunk
/// and marched chunk by chunk, in map order.
pub fn mesh_whole(
    map: &LevelMap,
    field: &dyn ScalarField,
    frame: &LodFrame,
) -> Result<Vec<ChunkMesh>, LodError> {
    let all = world_tets(map)?;
    let mut out = Vec::with_capacity(map.chunks().len());
    let mut start = 0;
    for i in 0..map.chunks().len() {
        let end = start + all[start..].iter().take_while(|(c, _)| *c == i).count();
        let tets: Vec<MeshTet> = all[start..end].iter().map(|(_, t)| *t).collect();
        out.push(march(&tets, field, frame));
        start = end;
    }
    Ok(out)
}

/// The morph of a world with `settings` (which have one) for a viewer at `viewer` (in `u`).
fn morph_at(settings: &LodSettings, viewer: [f64; 3]) -> Result<Morph, LodError> {
    let m = settings
        .morph
        .ok_or_else(|| LodError::Invalid("the world has no morph".into()))?;
    let lead = f64::from(m.lead) / (f64::from(settings.frame.h) * 0.5);
    Morph::new(&settings.geometry, settings.ratio, m.band, lead, viewer)
}

/// A rayon pool of `threads` threads.
pub fn thread_pool(threads: usize) -> Result<rayon::ThreadPool, LodError> {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads.max(1))
        .build()
        .map_err(|e| LodError::Invalid(format!("could not start {threads} threads: {e}")))
}

impl<F: ScalarField> LodWorld<F> {
    /// A world with the viewer at the world's origin corner; nothing is meshed until
    /// [`LodWorld::remesh`].
    pub fn new(field: F, settings: LodSettings) -> Result<Self, LodError> {
        if !(settings.frame.h.is_finite() && settings.frame.h > 0.0) {
            return Err(LodError::Invalid(format!("cell size {}", settings.frame.h)));
        }
        if !(settings.ratio.is_finite() && settings.ratio >= 0.0) {
            return Err(LodError::Invalid(format!("ratio {}", settings.ratio)));
        }
        if settings.threads == 0 {
            return Err(LodError::Invalid("threads must be >= 1".into()));
        }
        if settings.morph.is_some() {
            morph_at(&settings, [0.0; 3])?;
        }
        let pool = thread_pool(settings.threads)?;
        let pending = LevelMap::from_viewer(settings.geometry, [0.0; 3], settings.ratio);
        Ok(LodWorld {
            field,
            settings,
            pool,
            map: None,
            pending,
            viewer: [0.0; 3],
            morphed: None,
            meshes: HashMap::new(),
            encoded: HashMap::new(),
            edits: Overlay::new(settings.frame),
            edited: Default::default(),
            tets: TetCache::new(DEFAULT_TET_CACHE_BYTES),
            keep_replaced: false,
            replaced: Vec::new(),
        })
    }

    /// Keeps at most `bytes` of chunk tets by surroundings ([`TetCache`]; 0 keeps none,
    /// [`DEFAULT_TET_CACHE_BYTES`] by default). The surfaces do not depend on it; it forgets
    /// what it held.
    pub fn set_tet_cache_bytes(&mut self, bytes: usize) {
        self.tets = TetCache::new(bytes);
    }

    /// What the chunk-tets cache holds and did.
    pub fn tet_cache_stats(&self) -> TetCacheStats {
        self.tets.stats()
    }

    /// Moves the viewer (world coordinates); the new level map takes effect at the next
    /// [`LodWorld::remesh`].
    pub fn set_viewer(&mut self, pos: Vec3) {
        let f = &self.settings.frame;
        let u = f64::from(f.h) * 0.5;
        let p = (pos.as_dvec3() - f.origin.as_dvec3()) / u;
        self.viewer = p.to_array();
        self.pending =
            LevelMap::from_viewer(self.settings.geometry, self.viewer, self.settings.ratio);
    }

    /// The level map the next [`LodWorld::remesh`] moves to.
    pub fn pending_map(&self) -> &LevelMap {
        &self.pending
    }

    /// Sets the next level map directly (it must have the world's geometry). A morph keeps
    /// the last viewer ([`LodWorld::set_viewer`]).
    pub fn set_level_map(&mut self, map: LevelMap) -> Result<(), LodError> {
        if *map.geometry() != self.settings.geometry {
            return Err(LodError::Invalid("level map of another geometry".into()));
        }
        self.pending = map;
        Ok(())
    }

    /// Re-meshes the chunks the pending level map changed (all of them the first time),
    /// keeping the surface of those whose tets stay the same.
    pub fn remesh(&mut self) -> Result<LodRemesh, LodError> {
        let new = &self.pending;
        let geom = self.settings.geometry;
        let morph = self.morph()?;
        // Whether the values at a chunk's points can have changed with the viewer.
        let revalued = |k: &ChunkKey| match (&morph, &self.morphed) {
            (None, None) => false,
            (Some(a), Some(b)) => {
                let (lo, hi) = k.bounds(&geom);
                let s = super::lattice::cell_size(k.level);
                a.may_differ(b, lo.map(|v| v - s), hi.map(|v| v + s))
            }
            _ => true,
        };
        // The leaves that changed with the map: a chunk's tets can change only where one of
        // them touches its dependency box (`needs_remesh_given`, the same answer as
        // `needs_remesh`); a step that changes no leaf re-meshes nothing.
        let changed = self.map.as_ref().map(|old| changed_leaves(old, new));
        let stale: Vec<(ChunkKey, bool)> = new
            .chunks()
            .iter()
            .filter_map(|k| {
                let revalued = revalued(k);
                let stale = match (&changed, self.meshes.contains_key(k)) {
                    (Some(changed), true) => {
                        revalued || self.edited.contains(k) || needs_remesh_given(changed, new, k)
                    }
                    _ => true,
                };
                stale.then_some((*k, revalued))
            })
            .collect();
        let field = EditedField::new(&self.field, &self.edits);
        let (old, edited, encoded) = (self.map.as_ref(), &self.edited, &self.encoded);
        let meshes = &self.meshes;
        let frame = self.settings.frame;
        let cache = &self.tets;
        let morph_now = morph.as_ref();
        let cluster = self.settings.cluster;
        let outcomes: Vec<Remeshed> = self.pool.install(|| {
            stale
                .par_iter()
                .map(|(k, revalued)| {
                    let before = old.filter(|o| !edited.contains(k) && o.contains(k));
                    let same_values = before.filter(|_| !revalued);
                    if same_values.is_some_and(|o| is_fast_path(o, k) && is_fast_path(new, k)) {
                        // The fast path's tets are the lattice's over the chunk's box.
                        return Ok(Remeshed::Same);
                    }
                    let last = Last {
                        tets: same_values.and_then(|_| encoded.get(k)),
                        mesh: before.and_then(|_| meshes.get(k)),
                    };
                    let meshed = remesh_chunk(new, k, &field, &frame, cache, last, morph_now)?;
                    Ok(match meshed {
                        Remeshed::Meshed(m, e) if cluster => {
                            Remeshed::Meshed(cluster_chunk(&m, &frame).0, e)
                        }
                        other => other,
                    })
                })
                .collect::<Result<_, LodError>>()
        })?;
        self.edited.clear();
        let mut dropped: Vec<ChunkKey> = self
            .meshes
            .keys()
            .copied()
            .filter(|k| !new.contains(k))
            .collect();
        dropped.sort_unstable();
        for k in &dropped {
            self.meshes.remove(k);
            self.encoded.remove(k);
        }
        let (mut remeshed, mut unchanged) = (Vec::new(), Vec::new());
        for ((k, _), o) in stale.iter().zip(outcomes) {
            match o {
                Remeshed::Same => unchanged.push(*k),
                Remeshed::Meshed(m, e) => {
                    if let (Some(old), true) = (self.meshes.insert(*k, m), self.keep_replaced) {
                        self.replaced.push((*k, old));
                    }
                    match e {
                        Some(e) => self.encoded.insert(*k, e),
                        None => self.encoded.remove(k),
                    };
                    remeshed.push(*k);
                }
            }
        }
        self.map = Some(new.clone());
        self.morphed = morph;
        let triangles = self.meshes.values().map(ChunkMesh::triangles).sum();
        Ok(LodRemesh {
            kept: new.chunks().len() - remeshed.len(),
            remeshed,
            unchanged,
            dropped,
            triangles,
        })
    }

    /// The morph for the pending map's viewer (none when the settings have none).
    fn morph(&self) -> Result<Option<Morph>, LodError> {
        if self.settings.morph.is_none() {
            return Ok(None);
        }
        morph_at(&self.settings, self.viewer).map(Some)
    }

    /// The morph the current surfaces were marched with.
    pub fn morph_now(&self) -> Option<&Morph> {
        self.morphed.as_ref()
    }

    /// Chunk `key` of `map` (any map of the world's geometry) meshed as the world meshes now:
    /// its field, its edits and the current morph. For a chunk of the current map, its surface.
    pub fn mesh_under(&self, map: &LevelMap, key: &ChunkKey) -> Result<ChunkMesh, LodError> {
        let field = EditedField::new(&self.field, &self.edits);
        let frame = self.settings.frame;
        let mesh = mesh_chunk_with(
            map,
            key,
            &field,
            &frame,
            Some(&self.tets),
            self.morphed.as_ref(),
        )?;
        Ok(if self.settings.cluster {
            cluster_chunk(&mesh, &frame).0
        } else {
            mesh
        })
    }

    /// Whether [`LodWorld::remesh`] keeps the surfaces it replaces, for
    /// [`LodWorld::take_replaced`] (off by default; turning it off forgets them).
    pub fn set_keep_replaced(&mut self, keep: bool) {
        self.keep_replaced = keep;
        if !keep {
            self.replaced = Vec::new();
        }
    }

    /// The surfaces the remeshes since the last call replaced (chunks re-meshed in place),
    /// in the order they were replaced.
    pub fn take_replaced(&mut self) -> Vec<(ChunkKey, ChunkMesh)> {
        std::mem::take(&mut self.replaced)
    }

    /// Applies `brush` for a frame of `dt` seconds to the world's overlay of edits and marks
    /// the chunks of the current map whose tets can see a changed value
    /// ([`super::edits::chunks_seeing`]); the next [`LodWorld::remesh`] re-meshes them (with
    /// any level changes). A brush that misses the world changes nothing. Returns how many
    /// chunks it marked.
    pub fn edit(&mut self, brush: &crate::Brush, dt: f32) -> Result<usize, LodError> {
        let Some((lo, hi)) = self.stroke_reach(brush) else {
            brush
                .check(dt)
                .map_err(|e| LodError::Invalid(e.to_string()))?;
            return Ok(0);
        };
        self.edits.add(*brush, dt)?;
        let marked = self
            .map
            .as_ref()
            .map_or(Vec::new(), |m| chunks_seeing(m, lo, hi));
        let n = marked.len();
        self.edited.extend(marked);
        Ok(n)
    }

    /// The box (lattice units) of values `brush` can change ([`Overlay::stroke_box`]), grown by
    /// what a morphed value reads (one coarsest cell); `None` when it misses the world.
    fn stroke_reach(&self, brush: &crate::Brush) -> Option<([i64; 3], [i64; 3])> {
        let world = self.settings.geometry.world_size();
        let (lo, hi) = self.edits.stroke_box(brush, world)?;
        // A morphed value reads its parents' values, within one coarsest cell.
        let r = match self.settings.morph {
            None => 0,
            Some(_) => super::lattice::cell_size(self.settings.geometry.levels),
        };
        Some((lo.map(|v| v - r), hi.map(|v| v + r)))
    }

    /// The chunks of `map` (a map of the world's geometry, e.g. [`LodWorld::pending_map`])
    /// whose surface can see a value `brush` changes: those [`LodWorld::edit`] marks when `map`
    /// is the current map, sorted. Empty for a brush that misses the world.
    pub fn chunks_seeing_brush(&self, map: &LevelMap, brush: &crate::Brush) -> Vec<ChunkKey> {
        self.stroke_reach(brush)
            .map_or(Vec::new(), |(lo, hi)| chunks_seeing(map, lo, hi))
    }

    /// The strokes applied so far: the world samples `EditedField::new(field, edits)`.
    pub fn edits(&self) -> &Overlay {
        &self.edits
    }

    /// The level map of the current surfaces (`None` before the first remesh).
    pub fn level_map(&self) -> Option<&LevelMap> {
        self.map.as_ref()
    }

    /// One chunk's surface.
    pub fn chunk_mesh(&self, key: &ChunkKey) -> Option<&ChunkMesh> {
        self.meshes.get(key)
    }

    /// Every chunk's surface, in map order.
    pub fn chunk_meshes(&self) -> Vec<(ChunkKey, &ChunkMesh)> {
        self.map
            .iter()
            .flat_map(|m| m.chunks())
            .filter_map(|k| self.meshes.get(k).map(|m| (*k, m)))
            .collect()
    }

    /// The whole surface, welded by crossing key in map order, with each vertex's key.
    pub fn mesh_welded(&self) -> (Mesh, Vec<[Point; 2]>) {
        weld(self.chunk_meshes().into_iter().map(|(_, m)| m))
    }

    /// Bytes held by the chunk surfaces, the encoded tets they were marched from, the level
    /// map and the edits (the field is procedural; no samples are kept; the tet cache is
    /// apart, [`LodWorld::tet_cache_stats`]).
    pub fn memory_bytes(&self) -> usize {
        let meshes: usize = self.meshes.values().map(ChunkMesh::bytes).sum();
        // Counted here even where the tet cache shares them.
        let encoded: usize = self.encoded.values().map(EncodedTets::bytes).sum::<usize>()
            + self.encoded.capacity() * (16 + std::mem::size_of::<EncodedTets>());
        let map = self.map.as_ref().map_or(0, |m| m.chunks().len()) * 2 * 16;
        meshes
            + map
            + self.meshes.capacity() * (16 + std::mem::size_of::<ChunkMesh>())
            + self.edits.bytes()
            + encoded
    }

    /// The world's worker threads (the settings' `threads`), for work beside the world's
    /// that should share them.
    pub fn pool(&self) -> &rayon::ThreadPool {
        &self.pool
    }

    /// The settings.
    pub fn settings(&self) -> &LodSettings {
        &self.settings
    }
}
