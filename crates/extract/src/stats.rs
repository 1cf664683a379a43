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
    /// Part of `t_vertex_s` (checked integrated clustering): the group tables (each crossing's
    /// group, each group's vertex position), plain MT's triangle list and every crossing's
    /// triangles, and the additions' proposals (variants of split islands, lone crossings,
    /// sliver pairs). Integrated-unchecked builds no group tables: its numbering counts in
    /// `t_vertices_s`.
    pub t_groups_s: f64,
    /// Part of `t_vertex_s` (integrated clustering): the first round of quotient tests of every
    /// settling step (the islands, then each addition), in parallel.
    pub t_tests_s: f64,
    /// Part of `t_vertex_s` (integrated clustering): the repair rounds after those, in
    /// parallel.
    pub t_repair_s: f64,
    /// Part of `t_vertex_s` (both integrated modes): numbering the output vertices.
    pub t_vertices_s: f64,
    /// Clusters (groups of at least two crossings at one point) found by the vertex pass, plus
    /// the pairs proposed at slivers (checked integrated clustering).
    pub clusters_proposed: usize,
    /// Clusters merged into one vertex (an island kept whole or as one of its variants, or a
    /// sliver pair).
    pub clusters_committed: usize,
    /// Lone crossings (not in a kept island of their own point) in the kept groups at the end
    /// (integrated clustering).
    pub lone_absorbed: usize,
    /// Repair rounds that changed a group, over every settling step (integrated clustering; 0
    /// when every group and addition passed the quotient test at once).
    pub repair_rounds: usize,
    /// Clusters refused by the mask rules (more than 10 crossings, loops, pinches).
    pub clusters_rejected_prefilter: usize,
    /// Clusters refused by the exact quotient test: proposed and not kept in any form.
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
    pub const MERGE_STEPS: [&'static str; 4] = ["groups", "tests", "repair", "vertices"];

    /// `values`, one per merging step in [`Stats::MERGE_STEPS`] order (in whatever unit the
    /// caller prints), as one line: `groups 1.20 + tests 9.00 (parallel) + ...`.
    ///
    /// ```
    /// let line = rmt_extract::Stats::merge_steps_text([1.0, 2.0, 3.0, 4.0], 1);
    /// assert!(line.starts_with("groups 1.0 + tests 2.0 (parallel) + repair 3.0 (parallel)"));
    /// ```
    pub fn merge_steps_text(values: [f64; 4], decimals: usize) -> String {
        let parts: Vec<String> = Self::MERGE_STEPS
            .iter()
            .zip(values)
            .enumerate()
            .map(|(i, (name, v))| {
                let parallel = if i == 1 || i == 2 { " (parallel)" } else { "" };
                format!("{name} {v:.decimals$}{parallel}")
            })
            .collect();
        parts.join(" + ")
    }

    /// Seconds of each merging step inside `t_vertex_s` (see [`Stats::MERGE_STEPS`]); all zero
    /// without integrated clustering.
    ///
    /// ```
    /// let s = rmt_extract::Stats { t_repair_s: 0.25, ..Default::default() };
    /// assert_eq!(s.merge_steps()[2], 0.25);
    /// assert_eq!(rmt_extract::Stats::MERGE_STEPS[2], "repair");
    /// ```
    pub fn merge_steps(&self) -> [f64; 4] {
        [
            self.t_groups_s,
            self.t_tests_s,
            self.t_repair_s,
            self.t_vertices_s,
        ]
    }
}
