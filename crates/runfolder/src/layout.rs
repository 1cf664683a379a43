//! Where each file of a run folder lives (names relative to the folder).
//!
//! | file | written by | holds |
//! |---|---|---|
//! | [`MANIFEST_COPY`] | runner, at start | the manifest as given |
//! | [`RUN_JSON`] | runner, at start and after each session | provenance, options, configurations, sessions, status |
//! | [`CONFIGURATIONS_CSV`] | runner, at start | [`schema::CONFIGURATIONS`](crate::schema::CONFIGURATIONS) |
//! | [`RAW_CSV`] | runner, per checkpoint | [`schema::RAW_PREFIX`](crate::schema::RAW_PREFIX), then the measurement |
//! | [`PROGRESS_JSON`] | runner, per checkpoint | finished work units and the length of [`RAW_CSV`] holding them |
//! | [`MESHES`]`/<id>.ply` | runner | the last repetition's mesh ([`mesh_file`]) |
//! | [`SUMMARY_CSV`] | runner, at the end | one row per configuration ([`schema::SUMMARY_PREFIX`](crate::schema::SUMMARY_PREFIX), statistics) |
//! | [`PAPER_CSV`] | runner, when the manifest names the dissertation's table | [`schema::PAPER_COMPARISON`](crate::schema::PAPER_COMPARISON) |
//! | [`SEEDS_CSV`] | runner, seed studies | [`schema::SEEDS_PREFIX`](crate::schema::SEEDS_PREFIX), distributions over seeds |
//! | [`TOPOLOGY_CSV`], [`FAILURES_CSV`] | runner, seed studies | topology tallies and failing fields |
//! | [`EDITS_CSV`] | runner, `edit` workload | [`schema::EDITS`](crate::schema::EDITS) |
//! | [`LOD_CSV`] | runner, `lod` workload | [`schema::LOD_STEPS`](crate::schema::LOD_STEPS) (`summary.csv`: [`schema::LOD_SUMMARY`](crate::schema::LOD_SUMMARY)) |
//! | [`LOD_LEVELS_CSV`] | runner, `lod` workload | [`schema::LOD_LEVELS`](crate::schema::LOD_LEVELS): chunks and triangles per step and level |
//! | [`LOD_MAP_CSV`] | runner, `lod` workload | [`schema::LOD_MAP`](crate::schema::LOD_MAP): the last step's level map, one row per chunk |
//!
//! The study commands (`experiments render`, `questionnaire`) add their own folders beside these
//! (see `rmt_render::run_folder`).

use std::path::{Path, PathBuf};

/// The copy of the manifest a run was started from.
pub const MANIFEST_COPY: &str = "manifest.toml";
/// Provenance, options, configurations and sessions of the run.
pub const RUN_JSON: &str = "run.json";
/// The run's configurations, one row each.
pub const CONFIGURATIONS_CSV: &str = "configurations.csv";
/// One row per timed repetition.
pub const RAW_CSV: &str = "raw.csv";
/// Finished work units and the length of [`RAW_CSV`] that holds their rows.
pub const PROGRESS_JSON: &str = "progress.json";
/// One row per configuration.
pub const SUMMARY_CSV: &str = "summary.csv";
/// The comparison with the dissertation's table.
pub const PAPER_CSV: &str = "paper_comparison.csv";
/// Folder of the meshes, `<id>.ply`.
pub const MESHES: &str = "meshes";
/// A seed study's distributions over seeds.
pub const SEEDS_CSV: &str = "seeds.csv";
/// A seed study's topology tallies.
pub const TOPOLOGY_CSV: &str = "topology.csv";
/// A seed study's failing fields, one row per (configuration, seed, check).
pub const FAILURES_CSV: &str = "topology_failures.csv";
/// The `edit` workload's strokes, one row each.
pub const EDITS_CSV: &str = "edits.csv";
/// The `lod` workload's viewer steps, one row each.
pub const LOD_CSV: &str = "lod.csv";
/// The `lod` workload's chunks and triangles per viewer step and level.
pub const LOD_LEVELS_CSV: &str = "lod_levels.csv";
/// The `lod` workload's level map at its last step, one row per chunk.
pub const LOD_MAP_CSV: &str = "lod_map.csv";

/// The mesh file of configuration `id` in run folder `folder`: `<folder>/meshes/<id>.ply`.
pub fn mesh_file(folder: &Path, id: &str) -> PathBuf {
    folder.join(MESHES).join(format!("{id}.ply"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn meshes_live_in_the_meshes_folder_under_their_id() {
        assert_eq!(
            mesh_file(Path::new("run"), "as_bi"),
            Path::new("run").join("meshes").join("as_bi.ply")
        );
    }
}
