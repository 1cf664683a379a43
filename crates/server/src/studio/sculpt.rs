//! Sculpt sessions: one chunked terrain world ([`rmt_terrain::World`]) per session, brush strokes
//! applied on the server, only the re-meshed chunks sent back, and a linear undo/redo history of
//! the strokes' changed values ([`rmt_terrain::StrokeRecord`]).

use std::collections::HashMap;
use std::sync::{Arc, Mutex};
use std::time::Instant;

use glam::Vec3;
use rmt_mesh::Mesh;
use rmt_terrain::{Brush, BrushMode, StrokeParams, StrokeRecord, World};
use serde::Deserialize;

use super::wire::Part;

/// Strokes kept for undo per session (older ones are forgotten).
pub const HISTORY: usize = 64;

/// A brush stroke as the page sends it (`POST .../brush`).
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BrushRequest {
    /// Where the cursor ray meets the surface, world coordinates.
    pub centre: [f32; 3],
    /// Brush radius in cells (0.5 to 32; default 4, the `edit` workload's).
    #[serde(default = "default_radius")]
    pub radius_cells: f32,
    /// `add` or `subtract`.
    pub mode: String,
    /// Strength relative to the `edit` workload's strokes (about one cell per stroke at 1;
    /// 0 to 20; default 1).
    #[serde(default = "default_strength")]
    pub strength: f32,
}

fn default_radius() -> f32 {
    4.0
}

fn default_strength() -> f32 {
    1.0
}

impl BrushRequest {
    /// The brush and time step for a world of cell edge `h`, scaled like the `edit` workload's
    /// strokes ([`StrokeParams::for_cells`]); an error message for bad values.
    pub fn brush(&self, h: f32) -> Result<(Brush, f32), String> {
        if !self.centre.iter().all(|c| c.is_finite()) {
            return Err(format!(
                "brush centre must be finite, got {:?}",
                self.centre
            ));
        }
        if !(self.radius_cells.is_finite() && (0.5..=32.0).contains(&self.radius_cells)) {
            return Err(format!(
                "brush radius must be 0.5 to 32 cells, got {}",
                self.radius_cells
            ));
        }
        if !(self.strength.is_finite() && (0.0..=20.0).contains(&self.strength)) {
            return Err(format!(
                "brush strength must be 0 to 20, got {}",
                self.strength
            ));
        }
        let mode = match self.mode.as_str() {
            "add" => BrushMode::Add,
            "subtract" => BrushMode::Subtract,
            other => {
                return Err(format!(
                    "unknown brush mode `{other}` (expected add or subtract)"
                ))
            }
        };
        let p = StrokeParams::for_cells(h, 1, 0);
        let brush = Brush {
            centre: Vec3::from(self.centre),
            radius: self.radius_cells * h,
            strength: p.strength * self.strength,
            mode,
            clamp: p.clamp,
        };
        Ok((brush, p.dt))
    }
}

/// One sculpting session.
pub struct Session {
    world: World,
    done: Vec<StrokeRecord>,
    undone: Vec<StrokeRecord>,
    /// What the world was built from (sent back to the page).
    pub description: serde_json::Value,
    /// Time of the last edit.
    pub last_used: Instant,
}

/// What one edit (stroke, undo, redo) did.
#[derive(Clone, Debug, Default)]
pub struct EditOutcome {
    /// The chunks re-meshed, with their new meshes (world coordinates).
    pub parts: Vec<Part>,
    /// Sample values changed.
    pub changed_values: usize,
    /// Server time of the edit and the re-meshing, milliseconds.
    pub server_ms: f64,
    /// Time of re-meshing alone, milliseconds.
    pub remesh_ms: f64,
}

impl Session {
    /// A session on `world` (meshes every chunk).
    pub fn new(mut world: World, description: serde_json::Value) -> Result<Self, String> {
        world.mark_all_dirty();
        world.remesh_dirty().map_err(|e| e.to_string())?;
        Ok(Self {
            world,
            done: Vec::new(),
            undone: Vec::new(),
            description,
            last_used: Instant::now(),
        })
    }

    /// The world.
    pub fn world(&self) -> &World {
        &self.world
    }

    /// Strokes that can be undone and redone.
    pub fn history(&self) -> (usize, usize) {
        (self.done.len(), self.undone.len())
    }

    /// Every chunk's mesh, in world coordinates (empty chunks included, so the page knows them).
    pub fn all_parts(&self) -> Vec<Part> {
        (0..self.world.chunk_count())
            .map(|i| self.part(i))
            .collect()
    }

    /// Triangles of the whole world.
    pub fn triangles(&self) -> usize {
        (0..self.world.chunk_count())
            .filter_map(|i| self.world.chunk_mesh(i))
            .map(Mesh::triangle_count)
            .sum()
    }

    /// The chunk meshes welded into one (world coordinates, normals): for export.
    pub fn welded(&self) -> Mesh {
        self.world.mesh_welded()
    }

    fn part(&self, i: usize) -> Part {
        let s = self.world.settings();
        let (o, h) = (s.origin, s.h);
        let mut mesh = self.world.chunk_mesh(i).cloned().unwrap_or_default();
        for p in &mut mesh.positions {
            *p = (o + Vec3::from(*p) * h).to_array();
        }
        mesh.normals.clear();
        Part {
            id: i as u32,
            mesh,
            ratios: Vec::new(),
        }
    }

    /// Applies a stroke, re-meshes the chunks it marked, and returns them.
    pub fn stroke(&mut self, request: &BrushRequest) -> Result<EditOutcome, String> {
        let start = Instant::now();
        let (brush, dt) = request.brush(self.world.settings().h)?;
        let (_, record) = self
            .world
            .apply_brush_recorded(&brush, dt)
            .map_err(|e| e.to_string())?;
        let changed_values = record.changed_values();
        if changed_values > 0 {
            self.done.push(record);
            if self.done.len() > HISTORY {
                self.done.remove(0);
            }
            self.undone.clear();
        }
        self.finish(start, changed_values)
    }

    /// Undoes the last stroke (an error when there is none).
    pub fn undo(&mut self) -> Result<EditOutcome, String> {
        let start = Instant::now();
        let record = self.done.pop().ok_or("nothing to undo")?;
        self.world.undo_stroke(&record);
        let n = record.changed_values();
        self.undone.push(record);
        self.finish(start, n)
    }

    /// Redoes the last undone stroke (an error when there is none).
    pub fn redo(&mut self) -> Result<EditOutcome, String> {
        let start = Instant::now();
        let record = self.undone.pop().ok_or("nothing to redo")?;
        self.world.redo_stroke(&record);
        let n = record.changed_values();
        self.done.push(record);
        self.finish(start, n)
    }

    fn finish(&mut self, start: Instant, changed_values: usize) -> Result<EditOutcome, String> {
        self.last_used = Instant::now();
        let stats = self.world.remesh_dirty().map_err(|e| e.to_string())?;
        // The chunks rebuilt (with exact seams more than were marked when the box had to grow).
        let rebuilt = self.world.remeshed_chunks().to_vec();
        let parts = rebuilt.iter().map(|&i| self.part(i)).collect();
        Ok(EditOutcome {
            parts,
            changed_values,
            server_ms: start.elapsed().as_secs_f64() * 1e3,
            remesh_ms: stats.seconds * 1e3,
        })
    }
}

/// A session behind its own lock: strokes on different sessions run side by side.
pub type SharedSession = Arc<Mutex<Session>>;

/// Sessions by id, at most `capacity` (the least recently used one goes first); sculpt sessions
/// by default, LOD sessions ([`super::lod::LodSession`]) too.
pub struct Sessions<S = Session> {
    map: HashMap<String, (Arc<Mutex<S>>, Instant)>,
    capacity: usize,
}

impl<S> Sessions<S> {
    /// No sessions yet.
    pub fn new(capacity: usize) -> Self {
        Self {
            map: HashMap::new(),
            capacity: capacity.max(1),
        }
    }

    /// Adds a session, evicting the least recently used one when full.
    pub fn insert(&mut self, id: String, session: S) {
        while self.map.len() >= self.capacity {
            let oldest = self
                .map
                .iter()
                .min_by_key(|(_, (_, used))| *used)
                .map(|(k, _)| k.clone());
            match oldest {
                Some(k) => {
                    self.map.remove(&k);
                }
                None => break,
            }
        }
        self.map
            .insert(id, (Arc::new(Mutex::new(session)), Instant::now()));
    }

    /// The session `id` (marked as used now).
    pub fn get(&mut self, id: &str) -> Option<Arc<Mutex<S>>> {
        let (session, used) = self.map.get_mut(id)?;
        *used = Instant::now();
        Some(session.clone())
    }

    /// Number of sessions.
    pub fn len(&self) -> usize {
        self.map.len()
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.map.is_empty()
    }
}
