//! Chunked, deformable terrain: one sampled volume meshed chunk by chunk, brush edits on the
//! samples, and re-meshing of only what an edit can change.
//!
//! A [`World`] keeps the field values of its whole lattice (sampled once from a
//! [`rmt_fields::ScalarField`]) and one mesh per chunk of `C^3` cells: the triangles the chunk
//! *owns*. The chunk meshes, welded by position ([`World::mesh_welded`]), are exactly the mesh of
//! the whole volume extracted at once ([`World::extract_whole`]) with the same settings: same
//! triangles, bit for bit. How chunks meet is [`WorldSettings::seams`]:
//!
//! - [`Seams::Exact`] (marching tetrahedra with integrated clustering, checked or not, the
//!   default there; or with none): the chunks are the whole volume's own mesh, with no rule at
//!   the seams, so chunking costs no triangle. An edit re-extracts a box around it and keeps the triangles near the edit only
//!   where the box is provably the whole volume's (`world/exact.rs`, summed up below).
//! - [`Seams::Tiles`] (every other mode; integrated clustering, checked or not, refuses it,
//!   since exact seams make a tile rule dead there): each chunk is extracted on its own under
//!   the tile rule, which keeps edge collapses inside one chunk, at the price of triangles
//!   along every seam.
//!
//! # Exact seams
//!
//! - **Whole, then boxes.** The first meshing extracts the whole volume once, recording each triangle's anchor cell and where clustering did anything after
//!   its proposals (its *activity*, [`rmt_extract::Extractor::set_recording`]), and cuts the
//!   triangles into the chunks by anchor cell. An edit marks the cells where a changed value
//!   matters (below); [`World::remesh_dirty`] re-extracts a box around them.
//! - **The quiet band.** The box's triangles replace the old ones in a cut around the edit when a
//!   band of [`QUIET_BAND`] cells around it, [`PROPOSAL_REACH`] cells away from the edit and from
//!   the box faces, has no activity, neither in the box's extraction nor in the whole volume's.
//!   Every decision of the clustering there read only one side of the band, where its inputs were
//!   those of the run it came from, so the box's result inside the band is the new whole
//!   volume's. Otherwise the band moves out and the box grows, up to the whole volume. Clustering
//!   is quiet almost everywhere (on the edit terrain, 6 crossings in a million cells do anything
//!   after their proposals), so one box of about the edit plus 16 cells does. Integrated-
//!   unchecked clustering keeps its proposals and plain marching tetrahedra has none: no
//!   activity at all, the same box.
//!
//! # Tile seams
//!
//! - **Ownership** (both seams). A triangle belongs to the cell it is anchored in
//!   ([`rmt_extract::CellRange`]: the cube of a simple-lattice tetrahedron or of marching cubes,
//!   the cell above the face of a body-centred tetrahedron), and a chunk keeps the triangles of its
//!   own cells. Every chunk applies the same rule in global cells, so every triangle is kept by
//!   exactly one chunk.
//! - **Tiles = chunks.** Edge collapses (and welds) commit decisions that may depend on
//!   far-away ones (edge collapse commits one after another, each
//!   seeing the earlier ones). Both the whole extraction and the chunks therefore
//!   run under the tile rule [`rmt_extract::Tiling`] with tiles equal to the chunks: a merge is
//!   allowed only when the tetrahedra around the edges of all its crossings lie inside one
//!   chunk. Merges then touch only tetrahedra inside their chunk, never interact across chunks,
//!   and a chunk's mesh depends only on the samples of its cells and halo. The cost: crossings
//!   whose tetrahedra cross a chunk face are never clustered (a band about one to two cells wide
//!   along every seam stays plain marching tetrahedra), in the whole extraction as in the
//!   chunks. (When integrated clustering still took tiles, a 48^3 sphere with 32^3 tiles had
//!   +23% triangles, body-centred, and +11%, simple, over untiled integrated clustering;
//!   integrated-unchecked clustering under tiles of 8 x 16 x 8 cells kept 1.07-2.10x the
//!   triangles of the same cells without tiles, `mesh_hashes`.)
//! - **Halo.** One cell on each side (clipped at the world box): the tetrahedra of body-centred
//!   faces on a chunk face need the centre of the neighbouring cell, and cluster proposals of the
//!   points on a chunk face need all 14 neighbours. Body-centred ghost centres sit on the halo's
//!   outer faces, where they only shape halo triangles, which are dropped.
//! - **Exact positions** (both seams). Extraction runs in lattice units (cell edge 1, chunk boxes at integer
//!   corners), where every lattice point is an exact float, so a crossing or cluster centre is
//!   computed from the same numbers in a chunk as in the whole; world coordinates
//!   (`origin + p * h`) are applied after welding. Welding by exact position then joins exactly
//!   the vertices the chunks share (plus, in plain MT, distinct crossings that coincide because
//!   the surface passes through a sample point).
//! - **Edits.** A brush changes sample values. A chunk's mesh depends only on which side of the
//!   isovalue each point of its input (cells plus halo, ghost slots included) lies and on the
//!   values at the ends of its crossed edges, so a changed value matters only where the point
//!   changed side or has a lattice neighbour on the other side before or after the stroke; every
//!   chunk whose input holds such a point is marked dirty, and [`World::remesh_dirty`]
//!   re-extracts only those. Since a chunk depends on nothing else, the incrementally updated
//!   world equals a full re-extraction of the edited volume.
//!
//! Supported: marching tetrahedra on both lattices with clustering none, integrated,
//! integrated-unchecked and post-processed, and marching cubes (exact seams: both integrated
//! modes, and none). The meshopt mode is a global
//! simplifier and is refused ([`TerrainError::Unsupported`]).
//!
//! ```
//! use rmt_terrain::{canonical_triangles, Brush, World, WorldSettings};
//! use rmt_extract::{Clustering, Lattice};
//! use rmt_fields::Sphere;
//!
//! let settings = WorldSettings::new([16, 16, 16], glam::Vec3::splat(-1.0), 0.125,
//!     Lattice::BodyCentred, Clustering::Integrated).with_chunk(8);
//! let mut world = World::new(&Sphere::new(glam::Vec3::ZERO, 0.6), settings).unwrap();
//! world.remesh_dirty().unwrap();
//! let before = canonical_triangles(&world.mesh_welded());
//! let dirty = world.apply_brush(&Brush::add(glam::Vec3::new(0.6, 0.0, 0.0), 0.2, 5.0), 0.1).unwrap();
//! assert!(dirty >= 1 && dirty <= world.chunk_count());
//! let stats = world.remesh_dirty().unwrap();
//! assert!(stats.chunks >= 1 && stats.chunks == world.remeshed_chunks().len());
//! assert_ne!(canonical_triangles(&world.mesh_welded()), before);
//! // Exact seams: the chunks are the whole edited volume's mesh, bit for bit.
//! let (whole, _) = world.extract_whole().unwrap();
//! assert_eq!(canonical_triangles(&world.mesh_welded()), canonical_triangles(&whole));
//! ```

mod brush;
pub mod lod;
mod strokes;
mod world;

pub use brush::{Brush, BrushMode};
pub use strokes::{run_strokes, StrokeParams, StrokeReport};
pub use world::{
    canonical_triangles, weld, RemeshStats, Seams, StrokeRecord, World, WorldSettings, HALO,
    PROPOSAL_REACH, QUIET_BAND,
};

/// Why a world could not be built, edited or meshed.
#[derive(Debug, thiserror::Error)]
pub enum TerrainError {
    /// Bad world settings (chunk size, cell size, origin, ...).
    #[error("invalid world settings: {0}")]
    InvalidSettings(String),
    /// Bad brush or time step.
    #[error("invalid brush: {0}")]
    InvalidBrush(String),
    /// A mode that chunks cannot reproduce.
    #[error("unsupported for chunked worlds: {0}")]
    Unsupported(String),
    /// The extractor refused (bad grid, non-finite field value, ...).
    #[error("extraction failed: {0}")]
    Extract(#[from] rmt_extract::ExtractError),
    /// A chunk index past the last chunk.
    #[error("no chunk {index}: the world has {count} chunks")]
    NoSuchChunk {
        /// The index asked for.
        index: usize,
        /// Chunks in the world.
        count: usize,
    },
    /// The worker thread pool could not be created.
    #[error("could not start {threads} worker threads: {message}")]
    ThreadPool {
        /// Requested threads.
        threads: usize,
        /// The error from rayon.
        message: String,
    },
}
