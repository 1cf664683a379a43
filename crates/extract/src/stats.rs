//! Counters and stage timings of one extraction.

use serde::{Deserialize, Serialize};

/// What one extraction did and what it cost. Times are wall-clock seconds.
///
/// Field names are the JSON keys of `experiments extract --json` and the CSV columns of the
/// runner: keep them stable.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Stats {
    /// Output vertices.
    pub vertices: usize,
    /// Output triangles.
    pub triangles: usize,
    /// Triangles dropped because clustering or collapse made them degenerate.
    pub discarded: usize,
    /// Tetrahedra of the lattice (0 for marching cubes).
    pub tetrahedra_total: usize,
    /// Tetrahedra (or cubes, for marching cubes) with at least one crossing.
    pub tetrahedra_processed: usize,
    /// Sample points evaluated.
    pub sample_points: usize,
    /// Lattice edges (each counted once).
    pub edges: usize,
    /// Lattice edges crossed by the surface (= vertices of the unmerged mesh).
    pub crossings: usize,
    /// Seconds spent allocating and resizing buffers.
    pub t_allocation_s: f64,
    /// Seconds spent sampling the field.
    pub t_sampling_s: f64,
    /// Seconds spent in the vertex pass (crossings, clustering and its checks).
    pub t_vertex_s: f64,
    /// Seconds spent in the geometry pass (triangles; post-processing counts here too).
    pub t_geometry_s: f64,
    /// Seconds spent computing normals.
    pub t_normals_s: f64,
    /// Seconds for the whole extraction.
    pub t_total_s: f64,
    /// Part of `t_vertex_s` (integrated clustering): building the vertex-to-triangle adjacency
    /// the merges need. Serial.
    pub t_adjacency_s: f64,
    /// Part of `t_vertex_s` (integrated clustering): checking the cluster candidates against the
    /// mesh, colour by colour, in parallel.
    pub t_cluster_check_s: f64,
    /// Part of `t_vertex_s` (integrated clustering): applying the accepted cluster merges, in
    /// storage order. Serial.
    pub t_cluster_apply_s: f64,
    /// Part of `t_vertex_s` (checked integrated clustering): absorbing lone crossings into a
    /// neighbouring cluster, one after the other. Serial.
    pub t_lone_s: f64,
    /// Part of `t_vertex_s` (checked integrated clustering): collapsing needle and cap
    /// triangles. Serial.
    pub t_slivers_s: f64,
    /// Part of `t_vertex_s` (integrated clustering): writing the merged mesh out of the merge
    /// buffers, and welding coincident crossings where that applies. Serial.
    pub t_finish_s: f64,
    /// Clusters (groups of at least two crossings at one point) found by the vertex pass.
    pub clusters_proposed: usize,
    /// Clusters merged into one vertex.
    pub clusters_committed: usize,
    /// Committed clusters that the exact check accepted only without one of their crossings.
    pub clusters_reduced: usize,
    /// Lone crossings merged into a neighbouring cluster after the clusters (integrated mode).
    pub lone_absorbed: usize,
    /// Needle and cap triangles removed by one edge collapse each after the clusters
    /// (integrated mode; see [`crate::collapse::collapse_slivers`]).
    pub slivers_collapsed: usize,
    /// Clusters refused by the mask rules (more than 10 crossings, loops, pinches).
    pub clusters_rejected_prefilter: usize,
    /// Clusters refused by the exact local check on the mesh.
    pub clusters_rejected_check: usize,
    /// All refused clusters (pre-filter plus exact check).
    pub clusters_rejected: usize,
    /// Edges collapsed by post-processing.
    pub collapses: usize,
    /// Bytes of sample values (the lattice).
    pub bytes_lattice: usize,
    /// Bytes of per-point edge data (crossing flags, vertex numbering, cluster tables).
    pub bytes_edges: usize,
    /// Bytes of the output vertex buffer (positions and normals).
    pub bytes_vertices: usize,
    /// Bytes of the output index buffer.
    pub bytes_indices: usize,
}
