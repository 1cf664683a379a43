//! The world's state, defined below the modules that act on it: the fields of [`World`] and the
//! types they hold, the exact mode's state ([`Exact`]) and its boxes of [`Cells`]. `world.rs`
//! (the public methods), `exact.rs` (exact seams) and `undo.rs` (undo and redo) each add methods
//! to `World` and import it from here, downward.

use std::sync::{Arc, Mutex};

use rmt_extract::{ExtractSettings, Extractor, Lattice, Samples};
use rmt_mesh::Mesh;

use super::settings::WorldSettings;

/// A sampled volume meshed in chunks; see the crate doc.
pub struct World {
    pub(super) settings: WorldSettings,
    pub(super) unit: ExtractSettings,
    pub(super) samples: Samples,
    pub(super) counts: [usize; 3],
    /// Chunk meshes in lattice units, chunk `(cx, cy, cz)` at `cx + nx * (cy + ny * cz)`.
    pub(super) chunks: Vec<Mesh>,
    pub(super) dirty: Vec<bool>,
    pub(super) pool: Arc<rayon::ThreadPool>,
    pub(super) extractors: Mutex<Vec<Extractor>>,
    /// Old values of the last stroke's box (working memory of [`World::apply_brush`]).
    pub(super) stroke_old: Vec<f32>,
    /// [`Seams::Exact`](super::Seams::Exact): the anchor cells of the chunks' triangles, the
    /// whole volume's activity and the edits waiting.
    pub(super) exact: Option<Exact>,
    /// [`Seams::Exact`](super::Seams::Exact): the cells the last stroke changed in a way that
    /// matters (for undo).
    pub(super) last_edit: Option<Cells>,
    /// The chunks the last [`World::remesh_dirty`] rebuilt, ascending.
    pub(super) remeshed: Vec<usize>,
}

/// The exact mode's state beside the chunk meshes (see `exact.rs`).
#[derive(Default)]
pub(crate) struct Exact {
    /// Per chunk, the anchor cell (global linear index) of each triangle of its mesh, ascending.
    pub(crate) cells: Vec<Vec<u32>>,
    /// The whole volume's activity (global lattice coordinates), as of the chunk meshes.
    pub(super) activity: Vec<[i64; 3]>,
    /// Cells whose samples changed in a way that matters since the last re-meshing.
    pub(crate) pending: Option<Cells>,
    /// Whether the chunk meshes hold the whole volume (false until the first re-meshing, and
    /// after [`World::mark_all_dirty`]).
    pub(crate) built: bool,
    /// The extractor of the boxes (buffers reused between edits).
    pub(super) extractor: Option<Extractor>,
}

/// A box of cells `lo .. hi` (global cell indices, `hi` exclusive).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Cells {
    pub(crate) lo: [i64; 3],
    pub(crate) hi: [i64; 3],
}

impl Cells {
    pub(crate) fn grow(self, by: i64) -> Self {
        Self {
            lo: self.lo.map(|c| c - by),
            hi: self.hi.map(|c| c + by),
        }
    }

    pub(crate) fn clip(self, n: [usize; 3]) -> Self {
        Self {
            lo: self.lo.map(|c| c.max(0)),
            hi: [0, 1, 2].map(|a| self.hi[a].min(n[a] as i64)),
        }
    }

    pub(crate) fn union(self, o: Self) -> Self {
        Self {
            lo: [0, 1, 2].map(|a| self.lo[a].min(o.lo[a])),
            hi: [0, 1, 2].map(|a| self.hi[a].max(o.hi[a])),
        }
    }

    pub(crate) fn intersects(&self, o: &Self) -> bool {
        (0..3).all(|a| self.lo[a] < o.hi[a] && o.lo[a] < self.hi[a])
    }

    pub(crate) fn contains_box(&self, o: &Self) -> bool {
        (0..3).all(|a| self.lo[a] <= o.lo[a] && o.hi[a] <= self.hi[a])
    }

    pub(crate) fn contains(&self, c: [i64; 3]) -> bool {
        (0..3).all(|a| self.lo[a] <= c[a] && c[a] < self.hi[a])
    }

    pub(crate) fn is_world(&self, n: [usize; 3]) -> bool {
        (0..3).all(|a| self.lo[a] <= 0 && self.hi[a] >= n[a] as i64)
    }

    /// The cells touching lattice points `lo ..= hi` (lattice coordinates: half cells on the
    /// body-centred lattice, corners even; cells on the simple one).
    pub(crate) fn of_points(lattice: Lattice, lo: [i64; 3], hi: [i64; 3]) -> Self {
        match lattice {
            Lattice::BodyCentred => Self {
                lo: lo.map(|p| (p - 1).div_euclid(2)),
                hi: hi.map(|p| (p + 1).div_euclid(2) + 1),
            },
            Lattice::Simple => Self {
                lo: lo.map(|p| p - 1),
                hi: hi.map(|p| p + 1),
            },
        }
    }
}
