//! The columns of every CSV file of a run folder, each list written once. Lists that share
//! columns are built from the shared part at compile time ([`CONFIGURATION`] is the part most
//! files share), so adding a configuration column adds it everywhere it belongs.
//!
//! Columns computed from the data (one per measurement key, per time statistic, per stage) are
//! named here by their parts: [`TIME_STATISTICS`], [`SUMMARY_DERIVED`], [`SEED_STATISTICS`].

/// The columns that describe a configuration, in the order `raw.csv`, `summary.csv`,
/// `seeds.csv` and `topology.csv` give them.
pub const CONFIGURATION: [&str; 14] = [
    "id",
    "object",
    "kind",
    "method",
    "lattice",
    "clustering",
    "simplify",
    "vertex_cache",
    "rx",
    "ry",
    "rz",
    "collapse_threshold",
    "iso",
    "normals",
];

/// The columns of `configurations.csv` (the order the study commands read).
pub const CONFIGURATIONS: [&str; 14] = [
    "id",
    "object",
    "lattice",
    "clustering",
    "method",
    "kind",
    "rx",
    "ry",
    "rz",
    "collapse_threshold",
    "iso",
    "normals",
    "simplify",
    "vertex_cache",
];

/// The column `configurations.csv` appends after [`CONFIGURATIONS`] when some configuration is
/// drawn with flat shading (`smooth` or `flat`; absent, every configuration is smooth).
pub const SHADING: &str = "shading";

/// The column `configurations.csv` appends after [`CONFIGURATIONS`] (and [`SHADING`]) when some
/// object sets the camera elevation `render` draws it with (degrees; empty: the render
/// settings').
pub const ELEVATION: &str = "elevation_deg";

/// The columns that precede the measurement in `raw.csv`: `run_id`, [`CONFIGURATION`],
/// `threads`, `repetition`.
pub const RAW_PREFIX: [&str; 17] =
    concat::<15, 2, 17>(concat(["run_id"], CONFIGURATION), ["threads", "repetition"]);

/// The columns that precede the measurement statistics in `summary.csv`: [`CONFIGURATION`],
/// `threads`.
pub const SUMMARY_PREFIX: [&str; 15] = concat(CONFIGURATION, ["threads"]);

/// The summary's column after [`SUMMARY_PREFIX`]: timed repetitions of the configuration.
pub const SUMMARY_REPETITIONS: &str = "repetitions";

/// The statistics of each time column in `summary.csv` (`<time>_<statistic>`).
pub const TIME_STATISTICS: [&str; 5] = ["mean", "sd", "min", "median", "max"];

/// The derived columns that follow the measurement in `summary.csv` (then `share_<stage>` per
/// stage time).
pub const SUMMARY_DERIVED: [&str; 3] = ["triangle_reduction", "discard_share", "tetrahedra_share"];

/// The columns of `paper_comparison.csv`.
pub const PAPER_COMPARISON: [&str; 5] = ["id", "metric", "ours", "theirs", "ratio"];

/// The configuration columns of `seeds.csv` ([`CONFIGURATION`] through `collapse_threshold`).
pub const SEEDS_PREFIX: [&str; 12] = prefix(CONFIGURATION);

/// The columns of `seeds.csv` after [`SEEDS_PREFIX`]: seeds run, first and last seed.
pub const SEEDS_COUNTS: [&str; 3] = ["seeds", "seed_from", "seed_to"];

/// The statistics of each metric in `seeds.csv` (`<metric>_<statistic>`).
pub const SEED_STATISTICS: [&str; 6] = ["mean", "sd", "ci_low", "ci_high", "min", "max"];

/// The configuration columns of `topology.csv` ([`CONFIGURATION`] through `rz`).
pub const TOPOLOGY_PREFIX: [&str; 11] = prefix(CONFIGURATION);

/// The columns of `topology.csv` after [`TOPOLOGY_PREFIX`] (then one count per check, then
/// `failed_fields`).
pub const TOPOLOGY_COUNTS: [&str; 2] = ["fields", "reference"];

/// The topology checks, in the column order of `topology.csv`.
pub const TOPOLOGY_CHECKS: [&str; 6] = [
    "open",
    "non_manifold",
    "orientation",
    "duplicates",
    "euler",
    "components",
];

/// The last column of `topology.csv`: fields failing any check.
pub const TOPOLOGY_FAILED: &str = "failed_fields";

/// The columns of `topology_failures.csv`.
pub const TOPOLOGY_FAILURES: [&str; 5] = ["id", "base_id", "seed", "check", "detail"];

/// The columns of `edits.csv` (one row per timed stroke).
pub const EDITS: [&str; 8] = [
    "id",
    "edit",
    "latency_s",
    "chunks",
    "triangles",
    "triangles_per_chunk",
    "boxes",
    "box_cells",
];

/// The columns of an `edit` run's `summary.csv` (one row per configuration).
pub const EDIT_SUMMARY: [&str; 25] = [
    "id",
    "object",
    "method",
    "lattice",
    "clustering",
    "rx",
    "ry",
    "rz",
    "chunk",
    "threads",
    "strokes",
    "latency_p50_ms",
    "latency_p95_ms",
    "latency_p99_ms",
    "latency_max_ms",
    "chunks_per_edit_mean",
    "chunks_per_edit_max",
    "triangles_per_chunk_mean",
    "triangles",
    "whole_triangles",
    "chunks",
    "t_chunked_s",
    "t_whole_s",
    "chunked_equals_whole",
    "seams",
];

/// The columns of `lod.csv` (one row per viewer step of the `lod` workload; step 0 is the first
/// meshing of the world). `chunks_remeshed` counts the chunks whose surface was rebuilt,
/// `chunks_unchanged` those the map change marked whose tets stayed the same (their surface
/// kept). Validation and seam columns are empty on steps that were not validated, pop columns
/// on steps where no chunk changed its level, morph columns on steps with brush strokes (they
/// move the surface too). `edit_chunks` counts the chunks of the step's map that see a value
/// the step's strokes (`[lod] edits`) changed, all re-meshed at that step (0 without strokes).
/// On validated steps, `ar_mean`, `ar_median`, `ar_p99` and `ar_max` give the radius ratio `R / (2r)` of every
/// triangle of the world (`rmt_mesh::quality`, as `results.csv`'s columns of those names: 1 is
/// equilateral, larger is worse; zero-area triangles left out and counted in
/// `zero_area_triangles`). Like `remesh_s`, `memory_bytes` is a measurement of the run (it
/// follows the world's hash tables' history).
pub const LOD_STEPS: [&str; 27] = [
    "id",
    "step",
    "viewer_x",
    "viewer_y",
    "viewer_z",
    "remesh_s",
    "chunks",
    "chunks_remeshed",
    "chunks_unchanged",
    "chunks_dropped",
    "triangles",
    "memory_bytes",
    "pop_max_cells",
    "pop_mean_cells",
    "pop_points",
    "morph_max_cells",
    "morph_mean_cells",
    "open_edges",
    "non_manifold_edges",
    "orientation_errors",
    "normal_seam_max_deg",
    "edit_chunks",
    "ar_mean",
    "ar_median",
    "ar_p99",
    "ar_max",
    "zero_area_triangles",
];

/// The columns of `lod_levels.csv` (the `lod` workload: one row per viewer step and level
/// `0..=levels`, levels without chunks included): the chunks of that level in the map, their
/// triangles, and those of them that see the step's brush strokes (`lod.csv`'s `edit_chunks`
/// by level).
pub const LOD_LEVELS: [&str; 6] = ["id", "step", "level", "chunks", "triangles", "edit_chunks"];

/// The columns of `lod_map.csv` (the `lod` workload: the level map of the last step, one row per
/// chunk in map order): the chunk's level, its index among that level's chunks, its box in world
/// coordinates and its triangles.
pub const LOD_MAP: [&str; 13] = [
    "id",
    "step",
    "level",
    "ix",
    "iy",
    "iz",
    "x_min",
    "y_min",
    "z_min",
    "x_max",
    "y_max",
    "z_max",
    "triangles",
];

/// The columns of a `lod` run's `summary.csv` (one row per configuration). `edits_applied`
/// counts the `[lod] edits` strokes applied over the flight, `edit_chunks_total` the sum of
/// `lod.csv`'s `edit_chunks` over its steps. The triangles' shape over the validated steps:
/// `ar_mean` the mean radius ratio of every triangle of every validated step's world,
/// `ar_median`, `ar_p99` and `ar_max` the largest of the steps' (`lod.csv`),
/// `zero_area_triangles` the most of a step's.
pub const LOD_SUMMARY: [&str; 42] = [
    "id",
    "object",
    "method",
    "lattice",
    "clustering",
    "rx",
    "ry",
    "rz",
    "levels",
    "chunk",
    "ratio",
    "morph",
    "threads",
    "steps",
    "t_initial_s",
    "remesh_p50_ms",
    "remesh_p99_ms",
    "remesh_max_ms",
    "chunks_remeshed_mean",
    "chunks_remeshed_max",
    "triangles_max",
    "validated_steps",
    "open_edges",
    "non_manifold_edges",
    "orientation_errors",
    "pop_max_cells",
    "pop_mean_cells",
    "morph_max_cells",
    "morph_mean_cells",
    "normal_seam_max_deg",
    "finest_triangles",
    "finest_source",
    "triangles_over_finest",
    "memory_max_bytes",
    "rss_max_bytes",
    "edits_applied",
    "edit_chunks_total",
    "ar_mean",
    "ar_median",
    "ar_p99",
    "ar_max",
    "zero_area_triangles",
];

/// Time columns that are not stages of the extraction, so get no `share_<stage>` column in
/// `summary.csv`: the extraction's total, the total with the finish steps, and the time the
/// rendering-cost measures took.
pub const NOT_STAGES: [&str; 3] = ["t_total_s", "t_pipeline_s", "t_cost_s"];

/// Whether a measurement column is a time (summarised by [`TIME_STATISTICS`]).
pub fn is_time_column(name: &str) -> bool {
    name.starts_with("t_") && name.ends_with("_s")
}

/// `a` then `b` (checked at compile time: `N` is `A + B`).
const fn concat<const A: usize, const B: usize, const N: usize>(
    a: [&'static str; A],
    b: [&'static str; B],
) -> [&'static str; N] {
    assert!(A + B == N, "concat: N must be A + B");
    let mut out = [""; N];
    let mut i = 0;
    while i < A {
        out[i] = a[i];
        i += 1;
    }
    while i < N {
        out[i] = b[i - A];
        i += 1;
    }
    out
}

/// The first `N` columns of `a` (checked at compile time: `N <= A`).
const fn prefix<const A: usize, const N: usize>(a: [&'static str; A]) -> [&'static str; N] {
    assert!(N <= A, "prefix: N must be at most A");
    let mut out = [""; N];
    let mut i = 0;
    while i < N {
        out[i] = a[i];
        i += 1;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shared_lists_are_built_from_the_configuration_columns() {
        assert_eq!(RAW_PREFIX[0], "run_id");
        assert_eq!(RAW_PREFIX[1..15], CONFIGURATION);
        assert_eq!(RAW_PREFIX[15..], ["threads", "repetition"]);
        assert_eq!(SUMMARY_PREFIX[..14], CONFIGURATION);
        assert_eq!(SUMMARY_PREFIX[14], "threads");
        assert_eq!(SEEDS_PREFIX.last(), Some(&"collapse_threshold"));
        assert_eq!(TOPOLOGY_PREFIX.last(), Some(&"rz"));
    }

    #[test]
    fn configurations_csv_has_the_configuration_columns_in_its_own_order() {
        let mut a = CONFIGURATIONS.to_vec();
        let mut b = CONFIGURATION.to_vec();
        a.sort_unstable();
        b.sort_unstable();
        assert_eq!(a, b);
        assert_ne!(CONFIGURATIONS, CONFIGURATION);
    }

    #[test]
    fn time_columns_are_t_something_s() {
        assert!(is_time_column("t_total_s"));
        assert!(!is_time_column("triangles"));
        assert!(!is_time_column("t_total"));
    }
}
