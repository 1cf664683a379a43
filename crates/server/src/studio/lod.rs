//! LOD sessions: one multiresolution world ([`rmt_terrain::lod::LodWorld`]) per session, fine
//! near the viewer and coarse far away. The page flies a camera over it and sends the viewer's
//! position as it moves; the world re-meshes only the chunks whose level (or whose neighbours'
//! levels) changed, and only those come back, with the ids of the chunks that left the map.
//! Brush strokes at any distance change the world's sparse overlay of edits and re-mesh every
//! chunk, at whatever level, that sees a changed value.
//!
//! Each chunk of a session keeps one part id (`u32`) for as long as it is in the map; the reply's
//! JSON header says, for every part sent, its chunk's level and index (`chunks`), and which ids
//! were dropped (`dropped`).

use std::time::Instant;

use glam::Vec3;
use rmt_fields::ScalarField;
use rmt_mesh::Mesh;
use rmt_terrain::lod::{ChunkKey, LodRemesh, LodWorld};
use serde::Deserialize;
use serde_json::{json, Value};

use super::sculpt::BrushRequest;
use super::wire::Part;

/// The field a LOD world samples (the backend's object, boxed).
pub type LodField = Box<dyn ScalarField>;

/// A viewer move as the page sends it (`POST .../viewer`).
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ViewerRequest {
    /// The camera's position, world coordinates.
    pub viewer: [f32; 3],
}

impl ViewerRequest {
    /// The position, or why it is refused (not finite).
    pub fn position(&self) -> Result<Vec3, String> {
        if self.viewer.iter().all(|c| c.is_finite()) {
            Ok(Vec3::from(self.viewer))
        } else {
            Err(format!("viewer must be finite, got {:?}", self.viewer))
        }
    }
}

/// One LOD session.
pub struct LodSession {
    world: LodWorld<LodField>,
    /// Part id of every chunk in the map.
    ids: std::collections::HashMap<ChunkKey, u32>,
    next_id: u32,
    /// Brush strokes applied.
    strokes: usize,
    /// The viewer the map is of.
    viewer: Vec3,
    /// What the world was built from (sent back to the page).
    pub description: Value,
}

/// What one request (start, viewer move, stroke) did.
#[derive(Clone, Debug, Default)]
pub struct LodOutcome {
    /// The chunks meshed, as parts.
    pub parts: Vec<Part>,
    /// For each part: `{"id", "level", "at"}`.
    pub chunks: Vec<Value>,
    /// Part ids of the chunks that left the map.
    pub dropped: Vec<u32>,
    /// Chunks the stroke marked (0 for a viewer move).
    pub marked: usize,
    /// Re-meshing time, milliseconds.
    pub remesh_ms: f64,
}

impl LodSession {
    /// A session on `world` with the viewer at `viewer`: meshes every chunk.
    pub fn new(
        world: LodWorld<LodField>,
        description: Value,
        viewer: Vec3,
    ) -> Result<(Self, LodOutcome), String> {
        let mut s = LodSession {
            world,
            ids: Default::default(),
            next_id: 0,
            strokes: 0,
            viewer,
            description,
        };
        s.world.set_viewer(viewer);
        let out = s.remesh(0)?;
        Ok((s, out))
    }

    /// Moves the viewer and re-meshes what the new level map changed.
    pub fn move_viewer(&mut self, request: &ViewerRequest) -> Result<LodOutcome, String> {
        let p = request.position()?;
        self.world.set_viewer(p);
        self.viewer = p;
        self.remesh(0)
    }

    /// Applies a brush stroke (at any distance) and re-meshes the chunks that see it.
    pub fn stroke(&mut self, request: &BrushRequest) -> Result<LodOutcome, String> {
        let (brush, dt) = request.brush(self.world.settings().frame.h)?;
        let marked = self.world.edit(&brush, dt).map_err(|e| e.to_string())?;
        self.strokes += 1;
        self.remesh(marked)
    }

    fn remesh(&mut self, marked: usize) -> Result<LodOutcome, String> {
        let start = Instant::now();
        let LodRemesh {
            remeshed, dropped, ..
        } = self.world.remesh().map_err(|e| e.to_string())?;
        let remesh_ms = start.elapsed().as_secs_f64() * 1e3;
        let dropped: Vec<u32> = dropped.iter().filter_map(|k| self.ids.remove(k)).collect();
        let mut parts = Vec::with_capacity(remeshed.len());
        let mut chunks = Vec::with_capacity(remeshed.len());
        for key in &remeshed {
            let id = match self.ids.get(key) {
                Some(&id) => id,
                None => {
                    let id = self.next_id;
                    self.next_id = self.next_id.wrapping_add(1);
                    self.ids.insert(*key, id);
                    id
                }
            };
            let mesh = self
                .world
                .chunk_mesh(key)
                .map(|m| Mesh {
                    positions: m.positions.clone(),
                    normals: m.normals.clone(),
                    indices: m.indices.clone(),
                })
                .unwrap_or_default();
            parts.push(Part {
                id,
                mesh,
                ratios: Vec::new(),
            });
            chunks.push(json!({ "id": id, "level": key.level, "at": key.at }));
        }
        Ok(LodOutcome {
            parts,
            chunks,
            dropped,
            marked,
            remesh_ms,
        })
    }

    /// The reply header: the session, the world, the map's chunks per level, triangles, and
    /// what `outcome` did.
    pub fn header(&self, id: &str, outcome: &LodOutcome, server_ms: f64) -> Value {
        let levels = usize::from(self.world.settings().geometry.levels) + 1;
        let mut per_level = vec![0usize; levels];
        let mut triangles_per_level = vec![0usize; levels];
        for (k, m) in self.world.chunk_meshes() {
            if let Some(c) = per_level.get_mut(usize::from(k.level)) {
                *c += 1;
                triangles_per_level[usize::from(k.level)] += m.triangles();
            }
        }
        json!({
            "session": id,
            "world": self.description,
            "viewer": self.viewer.to_array(),
            "chunk_count": per_level.iter().sum::<usize>(),
            "chunks_per_level": per_level,
            "triangles_per_level": triangles_per_level,
            "triangles": triangles_per_level.iter().sum::<usize>(),
            "chunks": outcome.chunks,
            "chunks_remeshed": outcome.parts.len(),
            "dropped": outcome.dropped,
            "marked": outcome.marked,
            "strokes": self.strokes,
            "remesh_ms": outcome.remesh_ms,
            "server_ms": server_ms,
        })
    }

    /// The world welded into one mesh (world coordinates, normals): for export.
    pub fn welded(&self) -> Mesh {
        self.world.mesh_welded().0
    }
}
