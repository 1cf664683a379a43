//! Exact chunks ([`Seams::Exact`]): the chunk meshes are the whole volume's integrated
//! clustering (the global rule, no tiles; checked or not, or plain marching tetrahedra), cut by
//! anchor cell; an edit re-extracts a box around
//! it and keeps the result only where it is provably the whole volume's.
//!
//! # Why a box can be trusted
//!
//! Integrated clustering starts from its proposals, which depend on the samples within a few
//! lattice steps ([`PROPOSAL_REACH`]), then runs steps (test rounds, lone and sliver passes)
//! where every decision reads the state a few steps around it and the previous step's state
//! only. The extractor records its *activity* ([`rmt_extract::Extractor::set_recording`]): the
//! points whose crossings a step changed, found in a failing group, or considered as crossings
//! left alone. On most fields almost nothing happens after the proposals (on the edit terrain,
//! 6 crossings in a million cells). Integrated-unchecked clustering keeps its proposals and
//! plain marching tetrahedra makes none, so they have no activity at all: the argument below
//! holds with nothing after the proposals.
//!
//! An edit changes samples inside a box `E`. The world re-extracts a box `B` around it and looks
//! for a *quiet band* `Q`, a shell around `E` of [`QUIET_BAND`] cells, at least
//! [`PROPOSAL_REACH`] cells from `E` and from `B`'s faces, with no activity in `B`'s extraction
//! nor in the whole volume's (kept from the last one):
//!
//! ```text
//!   +-- B -------------------------------------------+
//!   |   +-- outer ---------------------------+        |   Q = outer minus inner: no activity
//!   |   |   +-- inner ----------------+  Q   |        |   in B nor in the whole volume
//!   |   |   |      +-- E --+          |      |        |
//!   |   |   |      | edit  |  cut ->  :      |        |   triangles anchored in the cut come
//!   |   |   |      +-------+          :      |        |   from B, the others stay
//!   |   |   +-------------------------+      |        |
//!   |   +------------------------------------+        |
//!   +--------------------------------------------------+
//! ```
//!
//! Take the history of `B` inside `Q`, the old whole volume's outside, and both's (equal:
//! nothing happened, and the proposals there see the same samples) in `Q`. Every decision
//! located in `Q` reads at most two lattice steps around it, so with a band of five cells it
//! reads one side only, where its inputs are those of the run it comes from; decisions inside
//! read inside and `Q`, decisions outside read outside and `Q`. So the glued history follows
//! the rule everywhere: it is the new whole volume's. The cut lies in the middle of `Q`, where
//! both runs agree, so the triangles it takes from `B` are the new whole volume's, bit for bit.
//! When the band holds activity, the inside grows over it and the box with it; the whole
//! volume always works.
//!
//! # The constants
//!
//! Distances are lattice steps from a crossing's owner point; a step moves at most one cell
//! along each axis, so cells bound them.
//!
//! - [`PROPOSAL_REACH`]: a point's proposals read its one-ring (1 step). A crossing left out of
//!   them joins the nearest island it shares a triangle with (owners 1 step away, their
//!   crossings' far ends 1 more), up to six per island, the lowest ids first, among the
//!   crossings that ask it (2 steps from the crossing, each choosing among islands 1 step
//!   further, whose positions reach 1 more): 4 steps. The box faces act like missing samples
//!   (the border rule, crossings on a face never group). 5 keeps a step to spare.
//! - [`QUIET_BAND`]: a group's test reads its star, the triangles of its crossings (its lone
//!   crossings are 1 step from its owner, their triangles' corners 1 more): 2 steps. A band of
//!   `2 * 2 + 1` cells has no test read both sides. What fails inside names a group to split
//!   in its closed star (3 steps), after the tests of those groups (2 more): 5 steps, which
//!   reach into the band but not past it.
//! - The cut, 2 cells into the band: a triangle's corners are crossings of its tetrahedron, 1
//!   step from its anchor, so the triangles on either side of the cut read only band state.
//! - The loops of the rule (test rounds until none fails, lone and sliver passes until none
//!   finds anything) end over the whole volume; a round or pass that finds nothing in a region
//!   changes nothing there, so one run's extra rounds leave the other's region as it is.
//!
//! `crates/terrain/tests/exact.rs` checks the result against the whole volume after every stroke
//! on random fields; with the constants cut to 1 / 1 / 0, or to 2 / 0 / 1 (no band), it fails.

use std::collections::HashMap;

use rayon::prelude::*;

use rmt_extract::samples::sampled_lattice;
use rmt_extract::{CellRange, Extractor, Grid, Lattice};
use rmt_mesh::Mesh;

use super::state::{Cells, Exact, World};
use super::weld::key;
use crate::TerrainError;

/// Lattice steps (cells) within which the proposals and their lone crossings read samples and
/// the box faces: a point further than this from a changed sample or a box face has the same
/// proposal state in both.
pub const PROPOSAL_REACH: i64 = 5;

/// Thickness in cells of the quiet band that separates the re-extracted inside from the rest.
pub const QUIET_BAND: i64 = 5;

/// Where the cut lies inside the quiet band, in cells from its inner side.
const CUT: i64 = 2;

/// What one exact re-meshing did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct ExactStats {
    /// Chunks whose mesh changed.
    pub(crate) chunks: usize,
    /// Boxes extracted (more than one when a band was not quiet).
    pub(crate) attempts: usize,
    /// Cells of those boxes, in all.
    pub(crate) box_cells: usize,
    /// Triangles of the rebuilt chunks.
    pub(crate) triangles: usize,
}

/// A triangle (its corner positions) with its anchor cell (global linear index).
type Anchored = (u32, [[f32; 3]; 3]);

/// One box's extraction: its triangles (positions in lattice units) with their anchor cells
/// (global linear indices), and its activity (global lattice coordinates).
struct BoxOut {
    mesh: Mesh,
    cells: Vec<u32>,
    activity: Vec<[i64; 3]>,
}

impl World {
    /// The cells an edit of lattice points `lo ..= hi` re-meshes at least (the cut of the first
    /// box), for marking chunks.
    pub(crate) fn exact_cut(&self, edit: Cells) -> Cells {
        edit.grow(PROPOSAL_REACH + CUT).clip(self.settings.cells)
    }

    /// Re-meshes what the pending edits changed (or everything, the first time): see the
    /// module doc.
    pub(crate) fn remesh_exact(&mut self) -> Result<ExactStats, TerrainError> {
        let pending = self.exact.as_ref().and_then(|s| s.pending);
        let result = self.remesh_pending();
        if result.is_err() {
            // Nothing is lost: the edits stay pending (the chunk meshes are as they were, or
            // hold the box's triangles only where it was trusted), and the next call retries.
            if let Some(state) = self.exact.as_mut() {
                state.pending = match (state.pending, pending) {
                    (Some(a), Some(b)) => Some(a.union(b)),
                    (a, b) => a.or(b),
                };
            }
        }
        result
    }

    /// [`World::remesh_exact`] once the pending edits are taken.
    fn remesh_pending(&mut self) -> Result<ExactStats, TerrainError> {
        let n = self.settings.cells;
        let world = Cells {
            lo: [0; 3],
            hi: n.map(|c| c as i64),
        };
        let Some((built, pending)) = self.exact.as_mut().map(|s| (s.built, s.pending.take()))
        else {
            return Ok(ExactStats::default());
        };
        self.remeshed.clear();
        let edit = match (built, pending) {
            (false, _) => None,
            (true, None) => return Ok(ExactStats::default()),
            (true, Some(e)) => Some(e.clip(n)),
        };
        let mut stats = ExactStats::default();
        let Some(edit) = edit else {
            let out = self.extract_cells(world, world)?;
            let activity_of_whole = out.activity.clone();
            stats.attempts = 1;
            stats.box_cells = n.iter().product();
            (stats.chunks, stats.triangles) = self.splice(world, out, true);
            if let Some(state) = self.exact.as_mut() {
                state.activity = activity_of_whole;
                state.built = true;
            }
            return Ok(stats);
        };
        // A band around the edit; where it holds activity, the inside grows over that activity
        // and the band moves out past it, until a band is quiet (the whole volume always is).
        let mut inner = edit.grow(PROPOSAL_REACH);
        let lattice = sampled_lattice(&self.unit);
        loop {
            // The whole volume's activity is known before the box is extracted: the inside takes
            // in what of it lies in the band first, so that a box is not extracted in vain.
            if let Some(state) = self.exact.as_ref() {
                loop {
                    let grown = grow_over_band(inner, &state.activity, lattice);
                    if grown == inner {
                        break;
                    }
                    inner = grown;
                }
            }
            let outer = inner.grow(QUIET_BAND);
            let b = outer.grow(PROPOSAL_REACH + 1).clip(n);
            stats.attempts += 1;
            stats.box_cells += (0..3)
                .map(|a| (b.hi[a] - b.lo[a]) as usize)
                .product::<usize>();
            if b.is_world(n) {
                let out = self.extract_cells(world, world)?;
                let activity = out.activity.clone();
                (stats.chunks, stats.triangles) = self.splice(world, out, false);
                if let Some(state) = self.exact.as_mut() {
                    state.activity = activity;
                }
                return Ok(stats);
            }
            let cut = inner.grow(CUT).clip(n);
            let out = self.extract_cells(b, cut)?;
            let old = self.exact.as_ref().map_or(&[][..], |s| &s.activity[..]);
            if !out.activity.iter().any(|p| in_band(inner, p, lattice))
                && !old.iter().any(|p| in_band(inner, p, lattice))
            {
                // The new activity: the box's inside the band, the old one outside.
                let inside = |p: &[i64; 3]| inner.contains_box(&Cells::of_points(lattice, *p, *p));
                let mut activity: Vec<[i64; 3]> =
                    old.iter().filter(|p| !inside(p)).copied().collect();
                activity.extend(out.activity.iter().filter(|p| inside(p)));
                activity.sort_unstable();
                (stats.chunks, stats.triangles) = self.splice(cut, out, false);
                if let Some(state) = self.exact.as_mut() {
                    state.activity = activity;
                }
                return Ok(stats);
            }
            // The inside takes in the activity found in the band (with a cell to spare), so the
            // next band lies past it.
            inner = grow_over_band(inner, &out.activity, lattice);
        }
    }

    /// Extracts the cells `b` with the global rule, recording, keeping the triangles anchored
    /// in `keep` (inside `b`).
    fn extract_cells(&mut self, b: Cells, keep: Cells) -> Result<BoxOut, TerrainError> {
        let s0 = b.lo.map(|c| c as usize);
        let s1 = b.hi.map(|c| c as usize);
        let cells = [0, 1, 2].map(|a| s1[a] - s0[a]);
        let corner = |c: [usize; 3]| glam::Vec3::new(c[0] as f32, c[1] as f32, c[2] as f32);
        let mut st = self.unit;
        st.grid = Grid::new(cells, corner(s0), corner(s1));
        st.tiles = None;
        st.keep_cells = Some(CellRange {
            lo: [0, 1, 2].map(|a| (keep.lo[a] - b.lo[a]) as usize),
            hi: [0, 1, 2].map(|a| (keep.hi[a] - b.lo[a]) as usize),
        });
        let state = self.exact.get_or_insert_with(Exact::default);
        // The whole volume gets an extractor of its own: the boxes' keeps buffers sized for
        // boxes.
        let whole = b.is_world(self.settings.cells);
        let mut ex = (if whole { None } else { state.extractor.take() }).unwrap_or_else(|| {
            let mut ex = Extractor::new();
            ex.set_pool(self.pool.clone());
            ex.set_recording(true);
            ex
        });
        let mut mesh = Mesh::default();
        let result = ex
            .samples_mut()
            .copy_box(&self.samples, &st, s0)
            .and_then(|()| ex.extract_presampled(&st, &mut mesh));
        let out = result.map(|_| {
            let n = self.settings.cells;
            let to_global = |c: u32| -> u32 {
                let c = c as usize;
                let (x, y, z) = (
                    c % cells[0],
                    (c / cells[0]) % cells[1],
                    c / (cells[0] * cells[1]),
                );
                ((x + s0[0]) + n[0] * ((y + s0[1]) + n[1] * (z + s0[2]))) as u32
            };
            let unit = match sampled_lattice(&self.unit) {
                Lattice::BodyCentred => 2,
                Lattice::Simple => 1,
            };
            BoxOut {
                cells: ex.triangle_cells().iter().map(|&c| to_global(c)).collect(),
                activity: ex
                    .activity()
                    .iter()
                    .map(|p| [0, 1, 2].map(|a| i64::from(p[a]) + unit * s0[a] as i64))
                    .collect(),
                mesh,
            }
        });
        if let Some(state) = self.exact.as_mut() {
            if !whole {
                state.extractor = Some(ex);
            }
        }
        let out = out?;
        if out.cells.len() != out.mesh.triangle_count() {
            return Err(TerrainError::Unsupported(
                "exact chunks need the anchor cells of marching tetrahedra with integrated \
                 clustering or none"
                    .into(),
            ));
        }
        Ok(out)
    }

    /// Replaces the triangles anchored in `cut` of every chunk it meets with `out`'s; returns
    /// the chunks whose mesh changed (with `all`, every chunk the cut meets) and their
    /// triangles ([`World::remeshed_chunks`] lists them).
    fn splice(&mut self, cut: Cells, out: BoxOut, all: bool) -> (usize, usize) {
        let n = self.settings.cells;
        let size = self.settings.chunk;
        let counts = self.counts;
        let coords = |c: u32| -> [i64; 3] {
            let c = c as usize;
            [c % n[0], (c / n[0]) % n[1], c / (n[0] * n[1])].map(|v| v as i64)
        };
        let chunk_of = |c: [i64; 3]| -> usize {
            let k = c.map(|v| v as usize / size);
            k[0] + counts[0] * (k[1] + counts[1] * k[2])
        };
        // The box's triangles by chunk, in order.
        let mut by_chunk: HashMap<usize, Vec<Anchored>> = HashMap::new();
        for (t, &cell) in out.mesh.indices.chunks_exact(3).zip(&out.cells) {
            let p = [0, 1, 2].map(|i| out.mesh.positions[t[i] as usize]);
            by_chunk
                .entry(chunk_of(coords(cell)))
                .or_default()
                .push((cell, p));
        }
        if let Some(state) = self.exact.as_mut() {
            if state.cells.len() != self.chunks.len() {
                state.cells = vec![Vec::new(); self.chunks.len()];
            }
        }
        // The chunks the cut meets, with their new triangles.
        let jobs: Vec<(usize, Vec<Anchored>)> = (0..self.chunks.len())
            .filter(|&i| {
                let r = self.chunk_cells(i);
                let own = Cells {
                    lo: r.lo.map(|c| c as i64),
                    hi: r.hi.map(|c| c as i64),
                };
                own.intersects(&cut)
            })
            .map(|i| (i, by_chunk.remove(&i).unwrap_or_default()))
            .collect();
        let Some(state) = self.exact.as_mut() else {
            return (0, 0);
        };
        let (chunks, cells) = (&self.chunks, &state.cells);
        // Chunks in parallel on the world's threads.
        let rebuilt: Vec<Option<(usize, Mesh, Vec<u32>)>> = self.pool.install(|| {
            jobs.into_par_iter()
                .map(|(i, mut new)| {
                    new.sort_by_key(|&(c, _)| c);
                    let mesh = &chunks[i];
                    let triangles = || {
                        mesh.indices
                            .chunks_exact(3)
                            .zip(&cells[i])
                            .map(|(t, &c)| (c, [0, 1, 2].map(|k| mesh.positions[t[k] as usize])))
                    };
                    // A chunk whose triangles in the cut come out the same (bit for bit, in the
                    // same order) is left as it was: nothing to rebuild or upload.
                    let bits = |t: &[[f32; 3]; 3]| t.map(|p| p.map(f32::to_bits));
                    let same = !all
                        && triangles()
                            .filter(|&(c, _)| cut.contains(coords(c)))
                            .map(|(c, t)| (c, bits(&t)))
                            .eq(new.iter().map(|(c, t)| (*c, bits(t))));
                    if same {
                        return None;
                    }
                    let old = triangles().filter(|&(c, _)| !cut.contains(coords(c)));
                    let (m, c) = merge_into_mesh(old, new);
                    Some((i, m, c))
                })
                .collect()
        });
        let (mut count, mut triangles) = (0, 0);
        self.remeshed.clear();
        for (i, m, c) in rebuilt.into_iter().flatten() {
            self.remeshed.push(i);
            count += 1;
            triangles += m.triangle_count();
            self.chunks[i] = m;
            state.cells[i] = c;
        }
        (count, triangles)
    }
}

/// Whether activity point `p` (lattice coordinates) lies in the band of `inner`: the cells it
/// touches meet the band's outer box and are not all inside `inner`.
fn in_band(inner: Cells, p: &[i64; 3], lattice: Lattice) -> bool {
    let c = Cells::of_points(lattice, *p, *p);
    c.intersects(&inner.grow(QUIET_BAND)) && !inner.contains_box(&c)
}

/// `inner` grown over the activity `points` that lie in its band, with a cell to spare, so that
/// they are inside it; `inner` itself when none does.
fn grow_over_band(inner: Cells, points: &[[i64; 3]], lattice: Lattice) -> Cells {
    points
        .iter()
        .filter(|p| in_band(inner, p, lattice))
        .fold(inner, |i, p| {
            i.union(Cells::of_points(lattice, *p, *p).grow(1))
        })
}

/// The triangles of `old` and `new` (each ascending by anchor cell) merged by cell, as a mesh
/// whose vertices are the distinct positions in order of first use, and their cells.
fn merge_into_mesh(old: impl Iterator<Item = Anchored>, new: Vec<Anchored>) -> (Mesh, Vec<u32>) {
    let mut mesh = Mesh::default();
    let mut cells = Vec::new();
    let mut ids: HashMap<[u32; 3], u32, foldhash::fast::FixedState> =
        HashMap::with_hasher(foldhash::fast::FixedState::default());
    let mut push = |mesh: &mut Mesh, cell: u32, tri: [[f32; 3]; 3]| {
        for p in tri {
            let next = mesh.positions.len() as u32;
            let id = *ids.entry(key(p)).or_insert_with(|| {
                mesh.positions.push(p);
                next
            });
            mesh.indices.push(id);
        }
        cells.push(cell);
    };
    let mut new = new.into_iter().peekable();
    for (c, t) in old {
        while let Some((nc, nt)) = new.next_if(|&(nc, _)| nc < c) {
            push(&mut mesh, nc, nt);
        }
        push(&mut mesh, c, t);
    }
    for (nc, nt) in new {
        push(&mut mesh, nc, nt);
    }
    (mesh, cells)
}

#[cfg(test)]
mod tests {
    use super::*;

    const INNER: Cells = Cells {
        lo: [10, 10, 10],
        hi: [20, 20, 20],
    };

    #[test]
    fn points_of_the_band_are_told_from_inside_and_outside() {
        for lattice in [Lattice::BodyCentred, Lattice::Simple] {
            let unit = if lattice == Lattice::BodyCentred {
                2
            } else {
                1
            };
            let at = |c: [i64; 3]| c.map(|v| v * unit + unit / 2);
            // A point in the middle of the inside, one a cell past the inside (in the band),
            // one deep outside.
            assert!(!in_band(INNER, &at([15, 15, 15]), lattice));
            assert!(in_band(INNER, &at([20, 15, 15]), lattice));
            assert!(in_band(INNER, &at([15, 15, 9]), lattice));
            assert!(!in_band(INNER, &at([15, 15, 40]), lattice));
            // On the inside's last cell the point touches cells past it: in the band.
            let rim = [20 * unit, 15 * unit, 15 * unit];
            assert!(in_band(INNER, &rim, lattice), "{lattice:?}");
        }
    }

    #[test]
    fn the_inside_grows_over_the_band_s_activity_and_not_over_the_rest() {
        let lattice = Lattice::BodyCentred;
        let inside = [30, 30, 30];
        let far = [100, 30, 30];
        assert_eq!(grow_over_band(INNER, &[inside, far], lattice), INNER);
        let near = [2 * 22 + 1, 31, 31];
        let grown = grow_over_band(INNER, &[inside, near, far], lattice);
        assert_ne!(grown, INNER);
        assert!(grown.contains_box(&INNER));
        // The point is inside now, with a cell to spare, and the far one still is not.
        assert!(!in_band(grown, &near, lattice));
        assert!(grown.contains_box(&Cells::of_points(lattice, near, near).grow(1)));
        assert!(!grown.contains_box(&Cells::of_points(lattice, far, far)));
    }
}
