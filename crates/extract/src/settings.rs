//! What to extract and how: grid, lattice, method, clustering, threads.

use glam::Vec3;
use serde::{Deserialize, Serialize};

use crate::ExtractError;

/// The sampling lattice of marching tetrahedra.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Lattice {
    /// Body-centred (BCDL): cube corners and cube centres, 12 tetrahedra per cube.
    #[serde(rename = "bcdl")]
    BodyCentred,
    /// Simple cubic, each cube cut into 6 tetrahedra along its main diagonal (Kuhn).
    Simple,
}

impl Lattice {
    /// Short name used on the command line and in CSV files (`bcdl`, `simple`).
    pub fn name(self) -> &'static str {
        match self {
            Lattice::BodyCentred => "bcdl",
            Lattice::Simple => "simple",
        }
    }
}

/// How crossings are merged into fewer vertices.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Clustering {
    /// Plain marching tetrahedra: one vertex per crossed edge, shared between tetrahedra.
    None,
    /// RMT clustering in the vertex pass, each cluster committed only after an exact local check
    /// that keeps the mesh closed, manifold and of unchanged topology.
    Integrated,
    /// The dissertation's rules without the exact check (for comparison; may break the mesh).
    IntegratedUnchecked,
    /// Plain MT followed by edge collapse of short edges and of slivers' shortest edges (link
    /// condition, no normal flips).
    Postprocessed,
    /// Plain MT followed by the meshoptimizer simplifier (QEM) with an error bound tied to h.
    Meshopt,
}

impl Clustering {
    /// Short name used on the command line and in CSV files.
    pub fn name(self) -> &'static str {
        match self {
            Clustering::None => "none",
            Clustering::Integrated => "integrated",
            Clustering::IntegratedUnchecked => "integrated-unchecked",
            Clustering::Postprocessed => "postprocessed",
            Clustering::Meshopt => "meshopt",
        }
    }
}

/// The extraction algorithm.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Method {
    /// Marching tetrahedra on [`ExtractSettings::lattice`] (regularised when clustering is on).
    Mt,
    /// Marching cubes on the plain cubic grid (lattice ignored).
    Mc,
    /// Naive surface nets (the `fast-surface-nets` crate, its quads split as it splits them) on
    /// the plain cubic grid's samples, the same values marching cubes reads (lattice ignored,
    /// clustering none). Not always manifold: its defects are reported, not repaired. Named
    /// `surface-nets` in settings files.
    #[serde(rename = "surface-nets")]
    SurfaceNets,
}

/// How vertex normals are computed.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum NormalMode {
    /// Normalised area-weighted mean of the incident face normals (the dissertation's choice).
    #[default]
    AreaWeighted,
    /// Central differences of the field at each vertex (costs 6 samples per vertex).
    Gradient,
    /// No normals.
    Skip,
}

/// The sampled box: `cells[a]` cubes along axis `a` between `min` and `max`.
///
/// Cube edges may differ per axis (`spacing()`); the lattices place sample points at cube
/// corners (both lattices) and cube centres (body-centred).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Grid {
    /// Cells (cubes) per axis, each >= 1.
    pub cells: [usize; 3],
    /// Lower corner of the box in world coordinates.
    pub min: Vec3,
    /// Upper corner of the box in world coordinates.
    pub max: Vec3,
}

/// Refuse lattices with more sample points than this (about 16 GiB of f32 samples, before the
/// per-point working arrays): a clear error instead of an allocation failure.
pub const MAX_SAMPLE_POINTS: usize = 1 << 32;

impl Grid {
    /// `cells` cubes per axis in the box `[min, max]`.
    pub fn new(cells: [usize; 3], min: Vec3, max: Vec3) -> Self {
        Self { cells, min, max }
    }

    /// `n` cubes per axis in the cube `[-half, half]^3`.
    pub fn cube(n: usize, half: f32) -> Self {
        Self::new([n; 3], Vec3::splat(-half), Vec3::splat(half))
    }

    /// Cube edge length per axis.
    pub fn spacing(&self) -> Vec3 {
        (self.max - self.min)
            / Vec3::new(
                self.cells[0] as f32,
                self.cells[1] as f32,
                self.cells[2] as f32,
            )
    }

    /// The mean cube edge length: the "h" in which thresholds and fidelity are expressed.
    pub fn h(&self) -> f32 {
        let s = self.spacing();
        (s.x + s.y + s.z) / 3.0
    }

    /// Number of cubes.
    pub fn cell_count(&self) -> usize {
        self.cells.iter().product()
    }

    /// Checks sizes and bounds: cells >= 1, finite bounds, min < max on every axis, and a sample
    /// count the machine could hold.
    pub fn check(&self) -> Result<(), ExtractError> {
        if self.cells.contains(&0) {
            return Err(ExtractError::InvalidGrid(format!(
                "every axis needs at least one cell, got {:?}",
                self.cells
            )));
        }
        if !(self.min.is_finite() && self.max.is_finite()) {
            return Err(ExtractError::InvalidGrid(format!(
                "bounds must be finite, got {} .. {}",
                self.min, self.max
            )));
        }
        if self.min.cmpge(self.max).any() {
            return Err(ExtractError::InvalidGrid(format!(
                "bounds need min < max on every axis, got {} .. {}",
                self.min, self.max
            )));
        }
        let points = self
            .cells
            .iter()
            .try_fold(1usize, |acc, &c| acc.checked_mul(c.checked_add(3)?));
        match points {
            Some(p) if p.saturating_mul(2) <= MAX_SAMPLE_POINTS => Ok(()),
            _ => Err(ExtractError::TooLarge {
                cells: self.cells,
                limit: MAX_SAMPLE_POINTS,
            }),
        }
    }
}

/// How marching tetrahedra on the body-centred lattice closes the box at its faces.
///
/// The tetrahedra of the body-centred lattice join the centres of neighbouring cubes; between
/// a box face and the centre of the cube inside it lies half an octahedron, a pyramid whose
/// base is the cube's face.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Boundary {
    /// The centres of the cubes just outside the box ("ghosts", sampled on the box face at the
    /// face centre) close each pyramid with four tetrahedra: every lattice point is sampled,
    /// ghosts included (the default, the dissertation's lattice).
    #[default]
    Ghosts,
    /// No ghost: each pyramid is split into two tetrahedra along the face diagonal through the
    /// face's lowest corner, and the crossing on that diagonal is a vertex of its own. Only the
    /// points in the box are sampled. Integrated clustering makes no proposal at a point whose
    /// tetrahedra reach a pyramid (within one and a half cells of a box face), so the
    /// crossings on the pyramids' edges stay plain and the guarantee holds.
    ///
    /// ```
    /// use rmt_extract::{Boundary, Clustering, ExtractSettings, Extractor, Grid, Lattice};
    /// // A ball through the box's upper z face: open along the box only.
    /// let ball = rmt_fields::Sphere::new(glam::Vec3::new(0.1, 0.0, 0.8), 0.5);
    /// let mut s = ExtractSettings::new(Grid::cube(16, 1.0), Lattice::BodyCentred,
    ///     Clustering::Integrated);
    /// s.boundary = Boundary::Pyramids;
    /// let mut mesh = rmt_mesh::Mesh::default();
    /// Extractor::new().extract(&ball, &s, &mut mesh).unwrap();
    /// let grid = s.grid;
    /// let r = rmt_mesh::validate(&mesh, &|p| rmt_extract::measure::on_box_boundary(&grid, p));
    /// assert_eq!((r.boundary_edges_interior, r.non_manifold_edges), (0, 0));
    /// assert_eq!(r.orientation_errors, 0);
    /// assert!(r.boundary_edges_on_box > 0);
    /// ```
    Pyramids,
}

impl Boundary {
    /// Whether this is the default ([`Boundary::Ghosts`]), which settings files leave out.
    pub fn is_ghosts(&self) -> bool {
        *self == Boundary::Ghosts
    }
}

/// Everything that decides one extraction.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ExtractSettings {
    /// The sampled box and its resolution.
    pub grid: Grid,
    /// Marching tetrahedra, marching cubes or surface nets.
    pub method: Method,
    /// The tetrahedral lattice (ignored by marching cubes and surface nets).
    pub lattice: Lattice,
    /// Vertex merging.
    pub clustering: Clustering,
    /// Edge collapse merges edges shorter than this many grid spacings (post-processed mode,
    /// which also collapses the shortest edge of slivers whatever its length); the meshopt mode
    /// uses it as its error bound, in grid spacings.
    pub collapse_threshold: f32,
    /// The isovalue T; inside is f < T, f = T counts as outside.
    pub iso: f32,
    /// Worker threads for the parallel passes; 1 runs everything on the calling thread.
    pub threads: usize,
    /// How vertex normals are computed.
    pub normals: NormalMode,
    /// Tile rule for chunked extraction: edge collapses (and meshopt's welds) only inside one
    /// tile. `None` (the default) leaves the output unchanged. Not with integrated clustering,
    /// checked or not.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tiles: Option<Tiling>,
    /// Keep only the triangles anchored in these grid cells (chunked extraction); `None` keeps
    /// all.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub keep_cells: Option<CellRange>,
    /// How the body-centred lattice closes the box (ignored on the simple lattice and by the
    /// other methods).
    #[serde(default, skip_serializing_if = "Boundary::is_ghosts")]
    pub boundary: Boundary,
}

/// The tile rule of chunked extraction (see `crates/terrain` for the world that uses it).
///
/// The edge collapses of post-processing (and the welds before meshopt) let a decision depend on
/// decisions further and further away, so without a rule a sub-box may not reproduce the whole
/// volume's mesh and a local edit may change merges far from it. With a tiling, space is cut
/// into tiles of `size` cells (global cell coordinates: tile `t` covers cells
/// `t * size .. (t + 1) * size` per axis), and a collapse is allowed only when every crossing it
/// involves has its *footprint* (the tetrahedra around its lattice edge, where all triangles
/// touching it come from) inside one and the same tile (the crate's internal `tiles` module).
/// The tiles then never interact, and a tile's merges see only the samples of its closed box. The price: crossings whose footprint crosses a tile face are never
/// merged (about half a cell to a cell on each side of every tile face).
///
/// Integrated clustering, checked or unchecked, takes no tiles ([`ExtractSettings::check`]
/// refuses them): its groups depend on nearby samples only, so its chunks are the whole
/// volume's mesh without them (`rmt-terrain`'s exact seams), and its tile rule is gone.
///
/// For a sub-box to reproduce the whole volume's triangles bit for bit, its positions must be
/// computed exactly in both (e.g. unit cell spacing and integer box corners, as the terrain
/// world does), and it must contain each tile it keeps triangles of plus one cell of halo.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub struct Tiling {
    /// Tile edge in cells per axis (>= 1).
    pub size: [usize; 3],
    /// Global cell index of this grid's cell (0, 0, 0): a sub-box of a larger volume passes its
    /// offset so that its tiles line up with the whole volume's.
    pub grid_offset: [usize; 3],
}

impl Tiling {
    /// Tiles of `size` cells for a grid that starts at global cell `grid_offset`.
    pub fn new(size: [usize; 3], grid_offset: [usize; 3]) -> Self {
        Self { size, grid_offset }
    }
}

/// A box of grid cells `lo .. hi` per axis (grid-local indices, `hi` exclusive).
///
/// A triangle's anchor cell is the cube it comes from (simple lattice, marching cubes), or for
/// the body-centred lattice the cell on the upper side of the cube face its tetrahedron stands
/// on, clamped into the grid (the faces on the grid's upper faces belong to the last cell). Every
/// triangle has exactly one anchor, so boxes that partition a volume partition its triangles.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub struct CellRange {
    /// First cell per axis.
    pub lo: [usize; 3],
    /// One past the last cell per axis.
    pub hi: [usize; 3],
}

impl CellRange {
    /// Whether cell `c` is in the range.
    #[inline]
    pub fn contains(&self, c: [usize; 3]) -> bool {
        (0..3).all(|a| c[a] >= self.lo[a] && c[a] < self.hi[a])
    }
}

impl ExtractSettings {
    /// Marching tetrahedra on `lattice` with `clustering`, one thread, iso 0, area-weighted
    /// normals, collapse threshold 0.5 h.
    pub fn new(grid: Grid, lattice: Lattice, clustering: Clustering) -> Self {
        Self {
            grid,
            method: Method::Mt,
            lattice,
            clustering,
            collapse_threshold: 0.5,
            iso: 0.0,
            threads: 1,
            normals: NormalMode::AreaWeighted,
            tiles: None,
            keep_cells: None,
            boundary: Boundary::Ghosts,
        }
    }

    /// Checks the settings before any work: grid, threads, threshold, iso.
    pub fn check(&self) -> Result<(), ExtractError> {
        self.grid.check()?;
        if self.boundary == Boundary::Pyramids
            && self.method == Method::Mt
            && self.lattice == Lattice::BodyCentred
            && (self.tiles.is_some() || self.keep_cells.is_some())
        {
            return Err(ExtractError::Unsupported(
                "the pyramid boundary (no ghosts) is for a whole box: not with tiles or kept \
                 cells"
                    .into(),
            ));
        }
        if self.threads == 0 || self.threads > 1024 {
            return Err(ExtractError::InvalidSettings(format!(
                "threads must be 1..=1024, got {}",
                self.threads
            )));
        }
        if !self.iso.is_finite() {
            return Err(ExtractError::InvalidSettings(format!(
                "iso must be finite, got {}",
                self.iso
            )));
        }
        if !(self.collapse_threshold.is_finite() && self.collapse_threshold >= 0.0) {
            return Err(ExtractError::InvalidSettings(format!(
                "collapse threshold must be finite and >= 0, got {}",
                self.collapse_threshold
            )));
        }
        if let Some(t) = self.tiles {
            if t.size.contains(&0) {
                return Err(ExtractError::InvalidSettings(format!(
                    "tile size must be at least 1 cell per axis, got {:?}",
                    t.size
                )));
            }
        }
        if self.tiles.is_some()
            && self.method == Method::Mt
            && matches!(
                self.clustering,
                Clustering::Integrated | Clustering::IntegratedUnchecked
            )
        {
            return Err(ExtractError::InvalidSettings(format!(
                "{} clustering takes no tiles: a chunk extracted with a halo (keep_cells) is the \
                 whole volume's mesh without them (rmt-terrain's exact seams); tiles are for \
                 post-processed and meshopt clustering",
                self.clustering.name()
            )));
        }
        if let Some(k) = self.keep_cells {
            if (0..3).any(|a| k.lo[a] >= k.hi[a] || k.hi[a] > self.grid.cells[a]) {
                return Err(ExtractError::InvalidSettings(format!(
                    "kept cells {:?}..{:?} must be a non-empty box inside the grid's {:?} cells",
                    k.lo, k.hi, self.grid.cells
                )));
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bad_tiles_and_kept_cells_are_refused() {
        let mut s = ExtractSettings::new(Grid::cube(8, 1.0), Lattice::Simple, Clustering::None);
        s.tiles = Some(Tiling::new([0, 4, 4], [0; 3]));
        assert!(s.check().unwrap_err().to_string().contains("tile size"));
        s.tiles = None;
        // Integrated clustering (checked or not) refuses tiles; the post-processes take them.
        for (clustering, refused) in [
            (Clustering::Integrated, true),
            (Clustering::IntegratedUnchecked, true),
            (Clustering::Postprocessed, false),
            (Clustering::Meshopt, false),
        ] {
            let mut t = ExtractSettings::new(Grid::cube(8, 1.0), Lattice::BodyCentred, clustering);
            t.tiles = Some(Tiling::new([4; 3], [0; 3]));
            match t.check() {
                Err(e) => assert!(refused && e.to_string().contains("no tiles"), "{e}"),
                Ok(()) => assert!(!refused, "{clustering:?}"),
            }
        }
        s.keep_cells = Some(CellRange {
            lo: [0; 3],
            hi: [9, 8, 8],
        });
        assert!(s.check().unwrap_err().to_string().contains("kept cells"));
        s.keep_cells = Some(CellRange {
            lo: [2; 3],
            hi: [2, 8, 8],
        });
        assert!(s.check().is_err());
        s.keep_cells = Some(CellRange {
            lo: [2; 3],
            hi: [8; 3],
        });
        assert!(s.check().is_ok());
    }
}
