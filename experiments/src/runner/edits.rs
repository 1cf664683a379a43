//! The `edit` workload in a run folder: one chunked terrain session per configuration
//! ([`crate::edit::run_edit_session`]), written to `edits.csv` (one row per stroke) and
//! `summary.csv` (latency quantiles, chunks per edit, triangles per chunk, whole-volume vs
//! chunked time). Both are written once at the end, atomically; an interrupted edit run leaves no
//! CSV and is started again rather than resumed.

use std::fs;
use std::path::Path;

use anyhow::{Context, Result};
use rmt_runfolder::layout::{
    mesh_file, CONFIGURATIONS_CSV, EDITS_CSV, MANIFEST_COPY, MESHES, RUN_JSON, SUMMARY_CSV,
};
use rmt_runfolder::schema::{EDITS, EDIT_SUMMARY};
use rmt_runfolder::{csv_bytes, write_atomic};

use super::session::{self, RunOptions, RunReport};
use crate::edit::{edit_rows, edit_summary_row, run_edit_session};
use crate::manifest::{EditPlan, Fields, Plan};
use crate::provenance::Provenance;
use crate::run_record::{RunRecord, Status};

/// Runs the `edit` workload of `plan` in `folder` (see the [module documentation](self)).
pub(super) fn execute_edits(
    folder: &Path,
    plan: &Plan,
    fields: &Fields,
    mut record: RunRecord,
    provenance: Provenance,
    edit: &EditPlan,
    opts: &RunOptions,
) -> Result<RunReport> {
    session::open(folder, &mut record, provenance)?;
    let bar = session::progress_bar(
        opts.quiet,
        plan.configurations.len() as u64,
        "{msg:>16} [{bar:30}] {pos}/{len} edit sessions, {elapsed} elapsed",
    );
    let mut edits = vec![EDITS.map(String::from).to_vec()];
    let mut summary = vec![EDIT_SUMMARY.map(String::from).to_vec()];
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
        let session = run_edit_session(field, &c.extraction, edit, plan.threads)
            .with_context(|| format!("edit session of configuration {}", c.id))?;
        edits.extend(edit_rows(&c.id, &session));
        summary.push(edit_summary_row(
            &c.id,
            &c.extraction,
            edit,
            plan.threads,
            &session,
        ));
        if plan.save_meshes {
            fs::create_dir_all(folder.join(MESHES))
                .with_context(|| format!("creating {}", folder.join(MESHES).display()))?;
            let path = mesh_file(folder, &c.id);
            rmt_mesh::io::save_ply(&path, &session.initial.mesh, true)
                .with_context(|| format!("saving {}", path.display()))?;
        }
        ran += 1;
        bar.inc(1);
    }
    bar.finish_and_clear();
    if status == Status::Finished {
        write_atomic(&folder.join(EDITS_CSV), &csv_bytes(&edits)?)?;
        write_atomic(&folder.join(SUMMARY_CSV), &csv_bytes(&summary)?)?;
        let mut files = vec![
            MANIFEST_COPY,
            RUN_JSON,
            CONFIGURATIONS_CSV,
            EDITS_CSV,
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
