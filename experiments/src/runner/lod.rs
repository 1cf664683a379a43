//! The `lod` workload in a run folder: one viewer flight over a multiresolution world per
//! configuration ([`crate::lod::run_lod_session`]), written to `lod.csv` (one row per step),
//! `lod_levels.csv` (chunks and triangles per step and level), `lod_map.csv` (the last step's
//! level map, for the report's top view) and `summary.csv` (re-mesh time quantiles, pops, seams,
//! validation, triangles over the finest level, memory). Both are written once at the end, atomically; an interrupted run leaves no
//! CSV and is started again rather than resumed.

use std::fs;
use std::path::Path;

use anyhow::{Context, Result};
use rmt_runfolder::layout::{
    mesh_file, CONFIGURATIONS_CSV, LOD_CSV, LOD_LEVELS_CSV, LOD_MAP_CSV, MANIFEST_COPY, MESHES,
    RUN_JSON, SUMMARY_CSV,
};
use rmt_runfolder::schema::{LOD_LEVELS, LOD_MAP, LOD_STEPS, LOD_SUMMARY};
use rmt_runfolder::{csv_bytes, write_atomic};

use super::session::{self, RunOptions, RunReport};
use crate::lod::{lod_level_rows, lod_map_rows, lod_rows, lod_summary_row, run_lod_session};
use crate::manifest::{Fields, LodPlan, Plan};
use crate::provenance::Provenance;
use crate::run_record::{RunRecord, Status};

/// Runs the `lod` workload of `plan` in `folder` (see the [module documentation](self)).
pub(super) fn execute_lod(
    folder: &Path,
    plan: &Plan,
    fields: &Fields,
    mut record: RunRecord,
    provenance: Provenance,
    lod: &LodPlan,
    opts: &RunOptions,
) -> Result<RunReport> {
    session::open(folder, &mut record, provenance)?;
    let bar = session::progress_bar(
        opts.quiet,
        plan.configurations.len() as u64,
        "{msg:>16} [{bar:30}] {pos}/{len} flights, {elapsed} elapsed",
    );
    let mut steps = vec![LOD_STEPS.map(String::from).to_vec()];
    let mut levels = vec![LOD_LEVELS.map(String::from).to_vec()];
    let mut map = vec![LOD_MAP.map(String::from).to_vec()];
    let mut summary = vec![LOD_SUMMARY.map(String::from).to_vec()];
    let mut status = Status::Finished;
    let mut ran = 0;
    for (k, c) in plan.configurations.iter().enumerate() {
        if opts.stop_after.is_some_and(|limit| k >= limit) {
            status = Status::Stopped;
            break;
        }
        bar.set_message(c.id.clone());
        let field = fields
            .get(&c.field_key())
            .with_context(|| format!("no field built for object {}", c.field_key()))?;
        let session = run_lod_session(field, &c.extraction, lod, plan.threads, plan.save_meshes)
            .with_context(|| format!("lod flight of configuration {}", c.id))?;
        steps.extend(lod_rows(&c.id, &session));
        levels.extend(lod_level_rows(&c.id, &session));
        map.extend(lod_map_rows(&c.id, &session));
        summary.push(lod_summary_row(
            &c.id,
            &c.extraction,
            lod,
            plan.threads,
            &session,
        ));
        if let Some(mesh) = &session.mesh {
            fs::create_dir_all(folder.join(MESHES))
                .with_context(|| format!("creating {}", folder.join(MESHES).display()))?;
            let path = mesh_file(folder, &c.id);
            rmt_mesh::io::save_ply(&path, mesh, true)
                .with_context(|| format!("saving {}", path.display()))?;
        }
        ran += 1;
        bar.inc(1);
    }
    bar.finish_and_clear();
    if status == Status::Finished {
        write_atomic(&folder.join(LOD_CSV), &csv_bytes(&steps)?)?;
        write_atomic(&folder.join(LOD_LEVELS_CSV), &csv_bytes(&levels)?)?;
        write_atomic(&folder.join(LOD_MAP_CSV), &csv_bytes(&map)?)?;
        write_atomic(&folder.join(SUMMARY_CSV), &csv_bytes(&summary)?)?;
        let mut files = vec![
            MANIFEST_COPY,
            RUN_JSON,
            CONFIGURATIONS_CSV,
            LOD_CSV,
            LOD_LEVELS_CSV,
            LOD_MAP_CSV,
            SUMMARY_CSV,
        ];
        if plan.save_meshes {
            files.push(MESHES);
        }
        record.files = files.into_iter().map(String::from).collect();
    }
    session::close(folder, &mut record, status, ran)?;
    Ok(RunReport {
        folder: folder.to_path_buf(),
        status,
        configurations_run: ran,
        configurations_done: ran,
        configurations_total: plan.configurations.len(),
    })
}
