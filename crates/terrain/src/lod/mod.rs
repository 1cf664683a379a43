//! Level of detail without cracks: one conforming multiresolution tetrahedral mesh over nested
//! body-centred lattices, and marching tetrahedra on it.
//!
//! ```text
//!   LevelMap (level_map.rs)   2:1-balanced octree of chunks, from a viewer + distance rule
//!        |
//!   forest (mesh.rs)          coarsest body-centred tets, red-refined where the map is finer
//!        |
//!   closure + green (refine.rs)   2:1 balance rule, face rule; cone / one-edge / ordered bisection
//!        |
//!   chunk tets (mesh.rs)      no finer neighbour: the lattice's tets it owns (fast path);
//!                             else a window's forest + closure, keeping the tets it owns
//!        |
//!   tet cache (tet_cache.rs)  the same tets for the same surroundings, moved: built once
//!        |
//!   morph (morph.rs)          optional: a point's value blended towards the coarser level's
//!                             interpolant with the viewer's distance (no pop at a level change)
//!        |
//!   march (mt.rs)             marching tetrahedra, crossings keyed by their edge's lattice points
//!        |
//!   cluster (cluster.rs)      optional: RMT's groups merged inside each chunk, each by an exact
//!                             local check; crossings near the chunk's faces stay plain
//!        |
//!   LodWorld (world.rs)       viewer moves -> new map -> re-mesh the chunks whose level or
//!                             neighbours' levels changed
//! ```
//!
//! Lattice coordinates are integers in `u = h / 2` ([`lattice`]); level `l` has cells of
//! `h 2^l`. On any conforming tetrahedral mesh marching tetrahedra's surface is closed, so the
//! seams between levels need no transition tables: the mesh itself is conforming across them.
//! A crossing is named by its edge's two lattice points and computed from them alone, so every
//! chunk that meets it computes the same bits, and welding by key joins the chunks exactly.
//!
//! Edits are an overlay of brush strokes over the procedural field ([`edits`]), sampled by
//! every level at its own lattice points.
//!
//! Clustering ([`cluster`]) merges groups only where no other chunk sees them, so the seams
//! and the transition layer stay plain and exact.

pub mod check;
pub mod cluster;
pub mod edits;
pub mod error;
pub mod lattice;
pub mod level_map;
pub mod mesh;
pub mod morph;
pub mod mt;
pub mod refine;
pub mod tet_cache;
pub mod world;

pub use cluster::{cluster_chunk, ClusterCount};
pub use edits::{EditedField, Overlay, Stroke};
pub use error::LodError;
pub use level_map::{ChunkKey, LevelMap, LodGeometry};
pub use mesh::{chunk_tets, world_tets, MeshTet};
pub use morph::Morph;
pub use mt::{march, same_bits, weld, ChunkMesh, LodFrame};
pub use refine::TetKind;
pub use tet_cache::{TetCache, TetCacheStats, DEFAULT_TET_CACHE_BYTES};
pub use world::{
    mesh_chunks, mesh_chunks_morphed, mesh_whole, thread_pool, LodRemesh, LodSettings, LodWorld,
    MorphSettings,
};
