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
    /// Sample points of the lattice (evaluated or not; see `points_sampled`).
    pub sample_points: usize,
    /// Sample points at which the field was evaluated: all of them with dense sampling, those
    /// of the blocks not skipped with sparse sampling, 0 for pre-sampled extraction.
    #[serde(default)]
    pub points_sampled: usize,
    /// Blocks of sparse sampling, of `samples::BLOCK / 2` = 4 cells per axis (0 with dense
    /// sampling; see `rmt_extract::samples`).
    #[serde(default)]
    pub blocks: usize,
    /// Blocks whose field range (or that of the 8^3-cell block holding them) excluded the
    /// isovalue, so that none of their points was evaluated.
    #[serde(default)]
    pub blocks_skipped: usize,
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

impl Stats {
    /// Names of the merging steps of integrated clustering, in the order of
    /// [`Stats::merge_steps`] (and of the work).
    pub const MERGE_STEPS: [&'static str; 6] = [
        "adjacency",
        "cluster checks",
        "apply",
        "lone crossings",
        "slivers",
        "mesh out",
    ];

    /// Seconds of each merging step inside `t_vertex_s` (see [`Stats::MERGE_STEPS`]); all zero
    /// without integrated clustering. Only the cluster checks run in parallel.
    ///
    /// ```
    /// let s = rmt_extract::Stats { t_lone_s: 0.25, ..Default::default() };
    /// assert_eq!(s.merge_steps()[3], 0.25);
    /// assert_eq!(rmt_extract::Stats::MERGE_STEPS[3], "lone crossings");
    /// ```
    /// `values`, one per merging step in [`Stats::MERGE_STEPS`] order (in whatever unit the
    /// caller prints), as one line: `adjacency 1.20 + cluster checks 9.00 (parallel) + ...`.
    ///
    /// ```
    /// let line = rmt_extract::Stats::merge_steps_text([1.0, 2.0, 3.0, 4.0, 5.0, 6.0], 1);
    /// assert!(line.starts_with("adjacency 1.0 + cluster checks 2.0 (parallel) + apply 3.0"));
    /// ```
    pub fn merge_steps_text(values: [f64; 6], decimals: usize) -> String {
        let parts: Vec<String> = Self::MERGE_STEPS
            .iter()
            .zip(values)
            .enumerate()
            .map(|(i, (name, v))| {
                let parallel = if i == 1 { " (parallel)" } else { "" };
                format!("{name} {v:.decimals$}{parallel}")
            })
            .collect();
        parts.join(" + ")
    }

    pub fn merge_steps(&self) -> [f64; 6] {
        [
            self.t_adjacency_s,
            self.t_cluster_check_s,
            self.t_cluster_apply_s,
            self.t_lone_s,
            self.t_slivers_s,
            self.t_finish_s,
        ]
    }
}
