//! The experiment runner: every configuration of a [`Plan`] extracted `warmup + repetitions`
//! times, one CSV row per timed repetition, crash-safe and resumable.
//!
//! **Timing protocol.** Each configuration gets one [`Extractor`](rmt_extract::Extractor) and one
//! output [`Mesh`](rmt_mesh::Mesh), reused by its warm-up and timed repetitions (buffers kept, as
//! a game re-meshing terrain would); each repetition is one full
//! [`Extractor::extract`](rmt_extract::Extractor::extract) call, sampling included, and its
//! [`Stats`](rmt_extract::Stats) fill one row. The mesh-derived metrics (validation, quality,
//! fidelity) are computed once, on the last repetition's mesh, and copied into every row of the
//! configuration: extraction is deterministic, and the runner checks it by comparing a
//! fingerprint of every repetition's mesh with the first (a mismatch stops the run).
//!
//! **Run folder.** Its files are listed in [`rmt_runfolder::layout`], their columns in
//! [`rmt_runfolder::schema`]; `run.json` and `progress.json` are [`crate::run_record`]'s.
//!
//! **Crash safety.** A configuration's rows are appended to `raw.csv` in one write and synced;
//! then its mesh is saved (atomically); then `progress.json` is replaced atomically with the new
//! list and the new length of `raw.csv`. Every other file is written to a temporary file and
//! renamed into place. On `--resume`, `raw.csv` is cut back to the recorded length, which drops any
//! torn row and the rows of a configuration whose progress was not recorded, so no row is lost or
//! duplicated; finished configurations are skipped.
//!
//! **Shared extractions.** Configurations that differ only in how `render` draws them (their
//! shading) extract the same mesh, so within a session the first of them is extracted and the
//! others take its result: its mesh, its measurement and its rows, timings included (the rows
//! differ only in the id). A study's `_flat` twins thus cost no second extraction. A twin whose
//! first was finished in an earlier session, or runs in another shard, is extracted itself (the
//! same mesh, by determinism).
//!
//! The roles, in the order a run meets them: this module (start, resume, the loop over work
//! units, the summaries at the end); [`session`] (options, `run.json` sessions, progress bar,
//! report); [`repetitions`] (one configuration's timed extractions); the `edit` workload in
//! `edits`, the `lod` workload in `lod`.

mod edits;
mod lod;
pub mod repetitions;
pub mod session;

use std::collections::HashMap;
use std::fs;
use std::path::{Path, PathBuf};
use std::rc::Rc;
use std::time::{Duration, Instant};

use anyhow::{bail, Context, Result};
use rmt_runfolder::layout::{
    mesh_file, CONFIGURATIONS_CSV, FAILURES_CSV, MANIFEST_COPY, MESHES, PAPER_CSV, PROGRESS_JSON,
    RAW_CSV, RUN_JSON, SEEDS_CSV, SUMMARY_CSV, TOPOLOGY_CSV,
};
use rmt_runfolder::{csv_bytes, write_atomic};

pub use repetitions::{mesh_fingerprint, run_configuration, run_repetitions, ConfigResult};
pub use session::{RunOptions, RunReport};

use crate::manifest::{self, Configuration, Fields, Overrides, Plan};
use crate::paper::paper_comparison;
use crate::provenance::Provenance;
use crate::run_csv::{configurations_csv, raw_header, raw_rows_from};
use crate::run_files::{append_synced, new_folder, truncate_synced, write_json};
use crate::run_record::{plan_of, read_record, Progress, RunRecord, Status};
use crate::shard::{self, ShardRecord, ShardSpec, WorkUnit};
use crate::summary::summarise_seeded;

/// Starts a run of the manifest at `manifest_path` in `out` (which must be new or empty) or in
/// `<output>/<name>-<UTC timestamp>`. Every check happens before the folder is created.
pub fn start(
    manifest_path: &Path,
    overrides: &Overrides,
    out: Option<&Path>,
    opts: &RunOptions,
) -> Result<RunReport> {
    start_shard(manifest_path, overrides, out, opts, None)
}

/// Like [`start`], for shard `shard` of the plan when given (see [`crate::shard`]): only its work
/// units run, and `run.json` records the shard (index, count, manifest hash, split, units). The
/// default folder is `<output>/<name>-shard-I-of-N-<UTC timestamp>`.
pub fn start_shard(
    manifest_path: &Path,
    overrides: &Overrides,
    out: Option<&Path>,
    opts: &RunOptions,
    shard: Option<ShardSpec>,
) -> Result<RunReport> {
    let manifest::Loaded { plan, text, fields } = manifest::load(manifest_path, overrides)?;
    let shard_record = match shard {
        None => None,
        Some(spec) => Some(shard_record(&plan, &text, manifest_path, spec)?),
    };
    let folder = run_folder(out, &plan, shard)?;
    fs::create_dir_all(&folder).with_context(|| format!("creating {}", folder.display()))?;
    let run_id = folder
        .canonicalize()
        .unwrap_or_else(|_| folder.clone())
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| plan.name.clone());

    write_atomic(&folder.join(MANIFEST_COPY), text.as_bytes())?;
    write_atomic(
        &folder.join(CONFIGURATIONS_CSV),
        &configurations_csv(&plan)?,
    )?;
    if let Some(edit) = plan.edit {
        let provenance = Provenance::collect();
        let record = RunRecord::new(&plan, manifest_path, provenance.clone(), &run_id)?;
        return edits::execute_edits(&folder, &plan, &fields, record, provenance, &edit, opts);
    }
    if let Some(lod) = &plan.lod {
        let provenance = Provenance::collect();
        let record = RunRecord::new(&plan, manifest_path, provenance.clone(), &run_id)?;
        return lod::execute_lod(&folder, &plan, &fields, record, provenance, lod, opts);
    }
    let header = csv_bytes(&[raw_header()])?;
    write_atomic(&folder.join(RAW_CSV), &header)?;
    let progress = Progress {
        completed: Vec::new(),
        raw_bytes: header.len() as u64,
    };
    write_atomic(
        &folder.join(PROGRESS_JSON),
        &serde_json::to_vec_pretty(&progress)?,
    )?;
    let provenance = Provenance::collect();
    let mut record = RunRecord::new(&plan, manifest_path, provenance.clone(), &run_id)?;
    record.shard = shard_record;
    // run.json last: its presence means the folder is initialised and resumable.
    execute(&folder, &plan, &fields, record, progress, provenance, opts)
}

/// What `run.json` records of shard `spec` of `plan` (manifest text `text`).
fn shard_record(
    plan: &Plan,
    text: &str,
    manifest_path: &Path,
    spec: ShardSpec,
) -> Result<ShardRecord> {
    if plan.edit.is_some() || plan.lod.is_some() {
        bail!(
            "{}: the `edit` and `lod` workloads cannot be sharded (run them whole)",
            manifest_path.display()
        );
    }
    let ids: Vec<String> = plan.configurations.iter().map(|c| c.id.clone()).collect();
    let (split, units) = shard::units_of(&ids, plan.repetitions, spec)
        .with_context(|| format!("sharding {}", manifest_path.display()))?;
    Ok(ShardRecord {
        index: spec.index,
        count: spec.count,
        manifest_sha256: shard::manifest_hash(text),
        split,
        units,
    })
}

/// The folder of a new run: `out` when given (refused unless new or empty), else a new
/// time-stamped folder under the plan's output folder.
fn run_folder(out: Option<&Path>, plan: &Plan, shard: Option<ShardSpec>) -> Result<PathBuf> {
    match out {
        Some(dir) => {
            if dir.exists() {
                let empty = fs::read_dir(dir)
                    .with_context(|| format!("reading {}", dir.display()))?
                    .next()
                    .is_none();
                if !empty {
                    bail!(
                        "run folder {} already exists and is not empty; continue it with \
                         `experiments run --resume {}` or choose another --out",
                        dir.display(),
                        dir.display()
                    );
                }
            }
            Ok(dir.to_path_buf())
        }
        None => match shard {
            Some(s) => new_folder(
                &plan.output,
                &format!("{}-shard-{}-of-{}", plan.name, s.index, s.count),
            ),
            None => new_folder(&plan.output, &plan.name),
        },
    }
}

/// Continues the run in `folder`: skips finished configurations, drops rows that were not
/// recorded as finished, and runs the rest with the options the run started with.
pub fn resume(folder: &Path, opts: &RunOptions) -> Result<RunReport> {
    let record = read_record(folder, "a resumable run folder")?;
    let progress_path = folder.join(PROGRESS_JSON);
    if !progress_path.exists() {
        bail!(
            "{} has no progress.json: runs of the `edit` and `lod` workloads are not resumable \
             (start the run again)",
            folder.display()
        );
    }
    let progress: Progress = serde_json::from_slice(
        &fs::read(&progress_path)
            .with_context(|| format!("reading {}", progress_path.display()))?,
    )
    .with_context(|| format!("parsing {}", progress_path.display()))?;
    if record.status == Status::Finished {
        return Ok(RunReport {
            folder: folder.to_path_buf(),
            status: Status::Finished,
            configurations_run: 0,
            configurations_done: progress.completed.len(),
            configurations_total: record
                .shard
                .as_ref()
                .map_or(record.configuration_ids.len(), |s| s.units.len()),
        });
    }
    let plan = plan_of(folder, &record)?;
    check_resumable(folder, &plan, &record, &progress)?;
    let fields = plan.build_fields(&folder.join(MANIFEST_COPY))?;
    cut_raw_back(folder, &progress)?;
    execute(
        folder,
        &plan,
        &fields,
        record,
        progress,
        Provenance::collect(),
        opts,
    )
}

/// Checks that the run folder's plan is the one `run.json` records, and that every finished
/// work unit is one of its units.
fn check_resumable(
    folder: &Path,
    plan: &Plan,
    record: &RunRecord,
    progress: &Progress,
) -> Result<()> {
    let ids: Vec<String> = plan.configurations.iter().map(|c| c.id.clone()).collect();
    if ids != record.configuration_ids {
        bail!(
            "{}: the manifest copy expands to other configurations than run.json records; \
             the run folder was edited or made by another version",
            folder.display()
        );
    }
    let units =
        work_units(plan, record).with_context(|| format!("{}: run.json", folder.display()))?;
    let keys: Vec<String> = units.iter().map(|u| u.key(plan.repetitions)).collect();
    if let Some(unknown) = progress.completed.iter().find(|k| !keys.contains(k)) {
        bail!(
            "{}: finished work unit `{unknown}` is not in the plan",
            folder.join(PROGRESS_JSON).display()
        );
    }
    Ok(())
}

/// Cuts `raw.csv` back to the rows of finished configurations, and checks its header is this
/// version's.
fn cut_raw_back(folder: &Path, progress: &Progress) -> Result<()> {
    let raw = folder.join(RAW_CSV);
    let len = fs::metadata(&raw)
        .with_context(|| format!("reading {}", raw.display()))?
        .len();
    if len < progress.raw_bytes {
        bail!(
            "{} is shorter ({len} bytes) than the {} bytes recorded for its finished \
             configurations: rows were lost outside the runner",
            raw.display(),
            progress.raw_bytes
        );
    }
    truncate_synced(&raw, progress.raw_bytes)?;
    let expected = csv_bytes(&[raw_header()])?;
    let head = fs::read(&raw).with_context(|| format!("reading {}", raw.display()))?;
    if !head.starts_with(&expected) {
        bail!(
            "{}: its columns differ from this version's; resume with the version that started it",
            raw.display()
        );
    }
    Ok(())
}

/// Checkpoints of a session: finished units' rows are appended to `raw.csv` (synced) and
/// `progress.json` rewritten at most every [`Checkpoints::EVERY`], and always at the end or on an
/// error. A crash in between loses only the unrecorded units, which `--resume` runs again (it
/// cuts `raw.csv` back to the recorded bytes). One checkpoint per unit made sweeps of many tiny
/// configurations (topology sweeps, seed studies) cost a sync and a growing `progress.json` per
/// unit.
struct Checkpoints<'a> {
    folder: &'a Path,
    progress: Progress,
    pending: Vec<u8>,
    last: Instant,
}

impl Checkpoints<'_> {
    const EVERY: Duration = Duration::from_millis(500);

    /// Records a finished unit `key` with its rows `rows`; checkpoints when one is due.
    fn finished(&mut self, key: String, rows: &[u8]) -> Result<()> {
        self.pending.extend_from_slice(rows);
        self.progress.completed.push(key);
        if self.last.elapsed() >= Self::EVERY {
            self.now()?;
            self.last = Instant::now();
        }
        Ok(())
    }

    /// Appends the pending rows and rewrites `progress.json`.
    fn now(&mut self) -> Result<()> {
        if !self.pending.is_empty() {
            self.progress.raw_bytes = append_synced(&self.folder.join(RAW_CSV), &self.pending)?;
            self.pending.clear();
        }
        write_json(&self.folder.join(PROGRESS_JSON), &self.progress)
    }
}

/// Runs the configurations not yet in `progress`.
fn execute(
    folder: &Path,
    plan: &Plan,
    fields: &Fields,
    mut record: RunRecord,
    progress: Progress,
    provenance: Provenance,
    opts: &RunOptions,
) -> Result<RunReport> {
    record.status = Status::Running;
    session::open(folder, &mut record, provenance)?;
    if plan.save_meshes {
        fs::create_dir_all(folder.join(MESHES))
            .with_context(|| format!("creating {}", folder.join(MESHES).display()))?;
    }
    let units = work_units(plan, &record)?;
    let todo = units_to_do(plan, &units, &progress)?;
    let extractions: u64 = todo
        .iter()
        .map(|(u, _)| (plan.warmup + u.len()) as u64)
        .sum();
    let bar = session::progress_bar(
        opts.quiet,
        extractions,
        "{msg:>16} [{bar:30}] {pos}/{len} extractions, {elapsed} elapsed, ETA {eta}",
    );
    let mut ran = 0;
    let mut status = Status::Finished;
    let mut meter = rmt_render::cost::RenderCostMeter::new();
    let mut checkpoints = Checkpoints {
        folder,
        progress,
        pending: Vec::new(),
        last: Instant::now(),
    };
    let mut shared = SharedExtractions::of(&todo)?;
    for (k, &(unit, c)) in todo.iter().enumerate() {
        if opts.stop_after.is_some_and(|limit| k >= limit) {
            status = Status::Stopped;
            break;
        }
        bar.set_message(c.id.clone());
        let key = geometry_key(unit, c)?;
        let result = match shared.take(&key) {
            Some(r) => {
                bar.inc((plan.warmup + unit.len()) as u64);
                r
            }
            None => {
                let field = fields
                    .get(&c.field_key())
                    .with_context(|| format!("no field built for object {}", c.field_key()))?;
                match run_repetitions(
                    c,
                    field,
                    plan,
                    unit.first,
                    unit.last,
                    plan.render_cost.then_some(&mut meter),
                    &bar,
                ) {
                    Ok(r) => shared.keep(key, r),
                    Err(e) => {
                        checkpoints.now()?;
                        return Err(e.context(format!(
                            "configuration {} failed; the finished configurations are kept: fix \
                             the cause and continue with `experiments run --resume {}`",
                            c.id,
                            folder.display()
                        )));
                    }
                }
            }
        };
        let rows = raw_rows_from(
            &record.run_id,
            c,
            plan.threads,
            unit.first,
            &result.stats,
            &result.finish,
            &result.measured,
        )?;
        let rows = csv_bytes(&rows)?;
        if plan.save_meshes {
            let path = mesh_file(folder, &c.id);
            rmt_mesh::io::save_ply(&path, &result.mesh, true)
                .with_context(|| format!("saving {}", path.display()))?;
        }
        checkpoints.finished(unit.key(plan.repetitions), &rows)?;
        ran += 1;
    }
    checkpoints.now()?;
    bar.finish_and_clear();

    if status == Status::Finished {
        record.files = write_summaries(folder, plan)?;
    }
    session::close(folder, &mut record, status, ran)?;
    Ok(RunReport {
        folder: folder.to_path_buf(),
        status,
        configurations_run: ran,
        configurations_done: checkpoints.progress.completed.len(),
        configurations_total: units.len(),
    })
}

/// What decides a work unit's mesh, rows and timings apart from its id: the field, the
/// extraction (object, box, resolution, method, lattice, clustering, finish steps, ...) and the
/// repetitions. Configurations that differ only in shading have the same key.
fn geometry_key(unit: &WorkUnit, c: &Configuration) -> Result<String> {
    let extraction = serde_json::to_string(&c.extraction)
        .with_context(|| format!("describing configuration {}", c.id))?;
    Ok(format!(
        "{}|{}|{}|{extraction}",
        c.field_key(),
        unit.first,
        unit.last
    ))
}

/// The results of a session's work units that later units share (same [`geometry_key`]), each
/// kept until its last user has taken it.
struct SharedExtractions {
    /// Users still to come, per key (keys of one unit only are not listed).
    waiting: HashMap<String, usize>,
    /// Results kept for them.
    kept: HashMap<String, Rc<ConfigResult>>,
}

impl SharedExtractions {
    /// The keys of `todo` that more than one unit has.
    fn of(todo: &[(&WorkUnit, &Configuration)]) -> Result<Self> {
        let mut count: HashMap<String, usize> = HashMap::new();
        for &(unit, c) in todo {
            *count.entry(geometry_key(unit, c)?).or_default() += 1;
        }
        count.retain(|_, n| *n > 1);
        Ok(Self {
            waiting: count,
            kept: HashMap::new(),
        })
    }

    /// The result kept for `key`, if an earlier unit of this session made it.
    fn take(&mut self, key: &str) -> Option<Rc<ConfigResult>> {
        let result = self.kept.get(key).cloned()?;
        self.used(key);
        Some(result)
    }

    /// Records `result`, made for `key`, and keeps it when later units share it.
    fn keep(&mut self, key: String, result: ConfigResult) -> Rc<ConfigResult> {
        let result = Rc::new(result);
        if self.waiting.contains_key(&key) {
            self.kept.insert(key.clone(), Rc::clone(&result));
            self.used(&key);
        }
        result
    }

    /// One user of `key` is served: the last one drops the kept result.
    fn used(&mut self, key: &str) {
        if let Some(n) = self.waiting.get_mut(key) {
            *n -= 1;
            if *n == 0 {
                self.waiting.remove(key);
                self.kept.remove(key);
            }
        }
    }
}

/// The units of `units` not finished in `progress`, each with its configuration.
fn units_to_do<'a>(
    plan: &'a Plan,
    units: &'a [WorkUnit],
    progress: &Progress,
) -> Result<Vec<(&'a WorkUnit, &'a Configuration)>> {
    units
        .iter()
        .filter(|u| !progress.completed.contains(&u.key(plan.repetitions)))
        .map(|u| {
            plan.configurations
                .iter()
                .find(|c| c.id == u.id)
                .map(|c| (u, c))
                .with_context(|| format!("work unit {} names no configuration", u.id))
        })
        .collect()
}

/// Writes `summary.csv` and `paper_comparison.csv` (when the plan names the dissertation's
/// table), and a seed study's `seeds.csv` and topology tables, from the folder's `raw.csv`;
/// returns the files of a finished run folder.
pub(crate) fn write_summaries(folder: &Path, plan: &Plan) -> Result<Vec<String>> {
    let seeds = crate::seeds::seed_map(plan);
    let summary = summarise_seeded(&folder.join(RAW_CSV), &seeds)?;
    write_atomic(&folder.join(SUMMARY_CSV), &summary.to_csv()?)?;
    let mut files = vec![
        MANIFEST_COPY,
        RUN_JSON,
        CONFIGURATIONS_CSV,
        RAW_CSV,
        SUMMARY_CSV,
    ];
    if let Some(bench) = &plan.paper_benchmark {
        let single = crate::seeds::single_seed_view(&summary, plan);
        let comparison = paper_comparison(&single, bench)?;
        write_atomic(&folder.join(PAPER_CSV), &comparison.to_csv()?)?;
        files.push(PAPER_CSV);
    }
    if let Some(table) = crate::seeds::seed_summary(&summary, plan)? {
        write_atomic(&folder.join(SEEDS_CSV), &table.to_csv()?)?;
        files.push(SEEDS_CSV);
    }
    if let Some((tally, failed)) = crate::topology::topology_tables(&summary, plan)? {
        write_atomic(&folder.join(TOPOLOGY_CSV), &tally.to_csv()?)?;
        write_atomic(&folder.join(FAILURES_CSV), &failed.to_csv()?)?;
        files.push(TOPOLOGY_CSV);
        files.push(FAILURES_CSV);
    }
    if plan.save_meshes {
        files.push(MESHES);
    }
    Ok(files.into_iter().map(String::from).collect())
}

/// The work units a run folder runs: its shard's (checked against the plan's split), or every
/// configuration whole.
pub(crate) fn work_units(plan: &Plan, record: &RunRecord) -> Result<Vec<WorkUnit>> {
    match &record.shard {
        None => Ok(plan
            .configurations
            .iter()
            .map(|c| WorkUnit::whole(&c.id, plan.repetitions))
            .collect()),
        Some(s) => {
            let ids: Vec<String> = plan.configurations.iter().map(|c| c.id.clone()).collect();
            let spec = ShardSpec {
                index: s.index,
                count: s.count,
            };
            let (split, units) = shard::units_of(&ids, plan.repetitions, spec)?;
            if split != s.split || units != s.units {
                bail!(
                    "shard {spec}: the recorded work units differ from the plan's split; the \
                     run folder was edited or made by another version"
                );
            }
            Ok(units)
        }
    }
}
