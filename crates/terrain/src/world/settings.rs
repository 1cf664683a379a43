//! What a world is and how it is meshed: [`WorldSettings`] and the chunk [`Seams`], with the
//! checks that refuse what chunks cannot reproduce.

use glam::Vec3;
use rmt_extract::{
    Clustering, ExtractSettings, Grid, Lattice, Method, NormalMode, ThreadPlacement, Tiling,
};

use crate::TerrainError;

/// How chunk meshes meet at the seams.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Seams {
    /// The tile rule with tiles equal to the chunks (see the crate doc): every chunk is meshed
    /// on its own, and no collapse crosses a chunk face. Every mode but integrated clustering
    /// of marching tetrahedra, checked or not (which has exact seams only); the chunks equal
    /// the whole volume *under the tile rule*, which costs triangles along the seams.
    Tiles,
    /// The whole volume's own mesh (marching tetrahedra with integrated clustering, checked or
    /// not, or with none; no tile rule), cut by anchor cell; an edit re-extracts a box around it and keeps what is provably the
    /// whole volume's (see `world/exact.rs`). The chunks equal the whole volume extracted at
    /// once, with no triangle added at the seams. The first meshing (and one after
    /// [`World::mark_all_dirty`](crate::World::mark_all_dirty)) extracts the whole volume at
    /// once: its working memory is about twice the world's samples, beside them.
    Exact,
}

/// What a world is and how it is meshed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WorldSettings {
    /// Cells per axis of the whole volume (each >= 1).
    pub cells: [usize; 3],
    /// World position of the corner of cell (0, 0, 0).
    pub origin: Vec3,
    /// Cell edge length in world units (> 0; the same on every axis).
    pub h: f32,
    /// Chunk edge in cells (>= 1; the last chunk along an axis may be shorter).
    pub chunk: usize,
    /// Marching tetrahedra or marching cubes.
    pub method: Method,
    /// Lattice of marching tetrahedra (ignored by marching cubes).
    pub lattice: Lattice,
    /// Vertex merging (meshopt is not supported).
    pub clustering: Clustering,
    /// Edge-collapse threshold in cells (post-processed mode).
    pub collapse_threshold: f32,
    /// The isovalue (inside is f < iso).
    pub iso: f32,
    /// Worker threads: chunks are meshed in parallel on this many threads.
    pub threads: usize,
    /// Where the workers run ([`ThreadPlacement::Os`] unless set; pinned workers keep their
    /// parallel speed after the pool has been idle between strokes, see
    /// `rmt_extract::threads`).
    pub placement: ThreadPlacement,
    /// How chunks meet: [`Seams::Exact`] for integrated clustering of marching tetrahedra,
    /// checked or not (the only seams there; plain marching tetrahedra takes them too),
    /// [`Seams::Tiles`] for every other mode (the default there).
    pub seams: Seams,
}

impl WorldSettings {
    /// Marching tetrahedra on `lattice` with `clustering`, chunks of 32 cells, one thread.
    pub fn new(
        cells: [usize; 3],
        origin: Vec3,
        h: f32,
        lattice: Lattice,
        clustering: Clustering,
    ) -> Self {
        let defaults = ExtractSettings::new(Grid::cube(1, 1.0), lattice, clustering);
        Self {
            cells,
            origin,
            h,
            chunk: 32,
            method: Method::Mt,
            lattice,
            clustering,
            collapse_threshold: defaults.collapse_threshold,
            iso: 0.0,
            threads: 1,
            placement: ThreadPlacement::Os,
            seams: if integrated(clustering) {
                Seams::Exact
            } else {
                Seams::Tiles
            },
        }
    }

    /// Marching cubes, chunks of 32 cells, one thread.
    pub fn marching_cubes(cells: [usize; 3], origin: Vec3, h: f32) -> Self {
        Self {
            method: Method::Mc,
            seams: Seams::Tiles,
            ..Self::new(cells, origin, h, Lattice::Simple, Clustering::None)
        }
    }

    /// The same settings with chunk seams `seams`.
    pub fn with_seams(mut self, seams: Seams) -> Self {
        self.seams = seams;
        self
    }

    /// The same settings with chunks of `chunk` cells.
    pub fn with_chunk(mut self, chunk: usize) -> Self {
        self.chunk = chunk;
        self
    }

    /// The same settings with the workers placed as `placement` says.
    pub fn with_placement(mut self, placement: ThreadPlacement) -> Self {
        self.placement = placement;
        self
    }

    /// The same settings with `threads` worker threads.
    pub fn with_threads(mut self, threads: usize) -> Self {
        self.threads = threads;
        self
    }

    /// The whole volume's box in world coordinates.
    pub fn world_grid(&self) -> Grid {
        let n = Vec3::new(
            self.cells[0] as f32,
            self.cells[1] as f32,
            self.cells[2] as f32,
        );
        Grid::new(self.cells, self.origin, self.origin + n * self.h)
    }

    /// Chunks per axis.
    pub fn chunk_counts(&self) -> [usize; 3] {
        self.cells.map(|n| n.div_ceil(self.chunk.max(1)))
    }

    /// Checks the settings: chunk size, cell size, origin, mode, and the extractor's own checks.
    pub fn check(&self) -> Result<(), TerrainError> {
        let bad = |m: String| Err(TerrainError::InvalidSettings(m));
        if self.chunk == 0 {
            return bad("chunk size must be at least 1 cell, got 0".into());
        }
        if !(self.h.is_finite() && self.h > 0.0) {
            return bad(format!(
                "cell size h must be finite and > 0, got {}",
                self.h
            ));
        }
        if !self.origin.is_finite() {
            return bad(format!("origin must be finite, got {}", self.origin));
        }
        // Lattice coordinates are exact floats only up to 2^23 half cells.
        if self.cells.iter().any(|&n| n > 1 << 22) {
            return bad(format!(
                "at most {} cells per axis, got {:?}",
                1 << 22,
                self.cells
            ));
        }
        if self.method == Method::Mt && self.clustering == Clustering::Meshopt {
            return Err(TerrainError::Unsupported(
                "the meshopt mode simplifies the whole mesh at once, so chunks cannot reproduce \
                 it; use integrated or post-processed clustering"
                    .into(),
            ));
        }
        if self.seams == Seams::Exact
            && !(self.method == Method::Mt
                && (integrated(self.clustering) || self.clustering == Clustering::None))
        {
            return Err(TerrainError::Unsupported(format!(
                "exact seams need marching tetrahedra with integrated clustering (checked or \
                 not) or none (got {:?} with {:?} clustering); use Seams::Tiles",
                self.method, self.clustering
            )));
        }
        if self.seams == Seams::Tiles && self.method == Method::Mt && integrated(self.clustering) {
            return Err(TerrainError::Unsupported(format!(
                "{} clustering has exact seams only: its chunks are the whole volume's mesh, \
                 with no tile rule; use Seams::Exact (the default)",
                self.clustering.name()
            )));
        }
        self.world_grid().check()?;
        self.unit_settings().check()?;
        Ok(())
    }

    /// Extraction settings of the whole volume in lattice units (cell edge 1, box from 0 to
    /// `cells`), under the tile rule with tiles equal to the chunks ([`Seams::Tiles`]) or with
    /// no tiles ([`Seams::Exact`]).
    pub fn unit_settings(&self) -> ExtractSettings {
        let n = Vec3::new(
            self.cells[0] as f32,
            self.cells[1] as f32,
            self.cells[2] as f32,
        );
        let mut s = ExtractSettings::new(
            Grid::new(self.cells, Vec3::ZERO, n),
            self.lattice,
            self.clustering,
        );
        s.method = self.method;
        s.collapse_threshold = self.collapse_threshold;
        s.iso = self.iso;
        s.threads = self.threads;
        s.normals = NormalMode::Skip;
        s.tiles = (self.seams == Seams::Tiles).then(|| Tiling::new([self.chunk; 3], [0; 3]));
        s
    }
}

/// Integrated clustering, checked or not: the modes with exact seams only.
fn integrated(clustering: Clustering) -> bool {
    matches!(
        clustering,
        Clustering::Integrated | Clustering::IntegratedUnchecked
    )
}
