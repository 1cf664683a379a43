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

use super::edits::{chunks_seeing, EditedField, Overlay};
use super::error::LodError;
use super::lattice::Point;
use super::level_map::{ChunkKey, LevelMap, LodGeometry};
use super::mesh::{is_fast_path, needs_remesh, world_tets, MeshTet};
use super::mt::{march, mesh_chunk_with, remesh_chunk, weld, ChunkMesh, LodFrame, Remeshed};
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
}

/// Meshes every chunk of `map` on `pool`, in map order.
pub fn mesh_chunks(
    map: &LevelMap,
    field: &dyn ScalarField,
    frame: &LodFrame,
    pool: &rayon::ThreadPool,
) -> Result<Vec<ChunkMesh>, LodError> {
    mesh_some(map, map.chunks(), field, frame, pool, None)
}

fn mesh_some(
    map: &LevelMap,
    keys: &[ChunkKey],
    field: &dyn ScalarField,
    frame: &LodFrame,
    pool: &rayon::ThreadPool,
    cache: Option<&TetCache>,
) -> Result<Vec<ChunkMesh>, LodError> {
    pool.install(|| {
        keys.par_iter()
            .map(|k| mesh_chunk_with(map, k, field, frame, cache))
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
        let pool = thread_pool(settings.threads)?;
        let pending = LevelMap::from_viewer(settings.geometry, [0.0; 3], settings.ratio);
        Ok(LodWorld {
            field,
            settings,
            pool,
            map: None,
            pending,
            meshes: HashMap::new(),
            encoded: HashMap::new(),
            edits: Overlay::new(settings.frame),
            edited: Default::default(),
            tets: TetCache::new(DEFAULT_TET_CACHE_BYTES),
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
        self.pending =
            LevelMap::from_viewer(self.settings.geometry, p.to_array(), self.settings.ratio);
    }

    /// Sets the next level map directly (it must have the world's geometry).
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
        let stale: Vec<ChunkKey> = new
            .chunks()
            .iter()
            .copied()
            .filter(|k| match (&self.map, self.meshes.contains_key(k)) {
                (Some(old), true) => {
                    if self.edited.contains(k) {
                        return true;
                    }
                    needs_remesh(old, new, k)
                }
                _ => true,
            })
            .collect();
        let field = EditedField::new(&self.field, &self.edits);
        let (old, edited, encoded) = (self.map.as_ref(), &self.edited, &self.encoded);
        let meshes = &self.meshes;
        let frame = self.settings.frame;
        let cache = &self.tets;
        let outcomes: Vec<Remeshed> = self.pool.install(|| {
            stale
                .par_iter()
                .map(|k| {
                    let before = old.filter(|o| !edited.contains(k) && o.contains(k));
                    if before.is_some_and(|o| is_fast_path(o, k) && is_fast_path(new, k)) {
                        // The fast path's tets are the lattice's over the chunk's box.
                        return Ok(Remeshed::Same);
                    }
                    let previous = before.and_then(|_| encoded.get(k));
                    let mesh = before.and_then(|_| meshes.get(k));
                    remesh_chunk(new, k, &field, &frame, cache, previous, mesh)
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
        for (k, o) in stale.iter().zip(outcomes) {
            match o {
                Remeshed::Same => unchanged.push(*k),
                Remeshed::Meshed(m, e) => {
                    self.meshes.insert(*k, m);
                    match e {
                        Some(e) => self.encoded.insert(*k, e),
                        None => self.encoded.remove(k),
                    };
                    remeshed.push(*k);
                }
            }
        }
        self.map = Some(new.clone());
        let triangles = self.meshes.values().map(ChunkMesh::triangles).sum();
        Ok(LodRemesh {
            kept: new.chunks().len() - remeshed.len(),
            remeshed,
            unchanged,
            dropped,
            triangles,
        })
    }

    /// Applies `brush` for a frame of `dt` seconds to the world's overlay of edits and marks
    /// the chunks of the current map whose tets can see a changed value
    /// ([`super::edits::chunks_seeing`]); the next [`LodWorld::remesh`] re-meshes them (with
    /// any level changes). A brush that misses the world changes nothing. Returns how many
    /// chunks it marked.
    pub fn edit(&mut self, brush: &crate::Brush, dt: f32) -> Result<usize, LodError> {
        let world = self.settings.geometry.world_size();
        let Some((lo, hi)) = self.edits.stroke_box(brush, world) else {
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

    /// The settings.
    pub fn settings(&self) -> &LodSettings {
        &self.settings
    }
}
