//! The experiment runner: every configuration of a [`Plan`] extracted `warmup + repetitions`
//! times, one CSV row per timed repetition, crash-safe and resumable.
//!
//! **Timing protocol.** Each configuration gets one [`Extractor`] and one output [`Mesh`], reused
//! by its warm-up and timed repetitions (buffers kept, as a game re-meshing terrain would); each
//! repetition is one full [`Extractor::extract`] call, sampling included, and its [`Stats`] fill
//! one row. The mesh-derived metrics (validation, quality, fidelity) are computed once, on the last
//! repetition's mesh, and copied into every row of the configuration: extraction is deterministic,
//! and the runner checks it by comparing a fingerprint of every repetition's mesh with the first
//! (a mismatch stops the run).
//!
//! **Run folder.**
//!
//! | file | written |
//! |---|---|
//! | `manifest.toml` | copy of the manifest, at start |
//! | `run.json` | provenance ([`Provenance`]), options, configurations, status; at start, after each session |
//! | `configurations.csv` | `id,object,lattice,clustering,method,kind,rx,ry,rz,collapse_threshold,iso,normals` |
//! | `raw.csv` | one row per repetition: [`RAW_PREFIX`] then every key of `extract --json`'s measurement |
//! | `progress.json` | finished configurations and the length of `raw.csv` that holds their rows |
//! | `meshes/<id>.ply` | binary PLY of the last repetition (unless disabled) |
//! | `summary.csv` | per configuration: each time's mean, sd, min, median, max; other columns' values; shares |
//! | `paper_comparison.csv` | `id,metric,ours,theirs,ratio` against the dissertation (when the manifest names its table) |
//!
//! **Crash safety.** A configuration's rows are appended to `raw.csv` in one write and synced;
//! then its mesh is saved (atomically); then `progress.json` is replaced atomically with the new
//! list and the new length of `raw.csv`. Every other file is written to a temporary file and
//! renamed into place. On `--resume`, `raw.csv` is cut back to the recorded length, which drops any
//! torn row and the rows of a configuration whose progress was not recorded, so no row is lost or
//! duplicated; finished configurations are skipped.

use std::collections::HashMap;
use std::fs::{self, OpenOptions};
use std::io::Write;
use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};
use indicatif::{ProgressBar, ProgressStyle};
use rmt_extract::{Extractor, Measurement, Stats};
use rmt_fields::ScalarField;
use rmt_mesh::Mesh;
use serde::{Deserialize, Serialize};
use serde_json::Value;

use crate::cmd_extract::measurement_json;
use crate::config;
use crate::manifest::{self, Configuration, Overrides, Plan};
use crate::provenance::{self, Provenance};
use crate::shard::{self, ShardRecord, ShardSpec, WorkUnit};

/// The columns that precede the measurement in `raw.csv`.
pub const RAW_PREFIX: [&str; 15] = [
    "run_id",
    "id",
    "object",
    "kind",
    "method",
    "lattice",
    "clustering",
    "rx",
    "ry",
    "rz",
    "collapse_threshold",
    "iso",
    "normals",
    "threads",
    "repetition",
];

/// The columns of `configurations.csv`.
pub const CONFIG_COLUMNS: [&str; 12] = [
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
];

/// What the timing protocol is, recorded in `run.json`.
pub const TIMING_PROTOCOL: &str = "One Extractor and one Mesh per configuration, reused by its \
    warm-up and timed repetitions; each repetition is one full extraction including sampling. \
    Validation, quality and fidelity are computed once on the last repetition's mesh and copied \
    into every row; every repetition's mesh is checked to be identical to the first.";

/// Options of a run that are not part of the plan.
#[derive(Clone, Debug, Default)]
pub struct RunOptions {
    /// No progress bar or summary.
    pub quiet: bool,
    /// Stop (as if killed) after this many configurations of this session; for testing resume.
    pub stop_after: Option<usize>,
}

/// How a run session ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Status {
    /// Configurations remain (a session in progress, killed, failed or stopped).
    Running,
    /// Stopped on purpose (`stop_after`) with configurations remaining.
    Stopped,
    /// Every configuration is done and the summaries are written.
    Finished,
}

/// What a session did.
#[derive(Clone, Debug)]
pub struct RunReport {
    /// The run folder.
    pub folder: PathBuf,
    /// How it ended.
    pub status: Status,
    /// Configurations run in this session.
    pub configurations_run: usize,
    /// Configurations finished overall.
    pub configurations_done: usize,
    /// Configurations in the plan.
    pub configurations_total: usize,
}

/// The options a run was started with (replayed on resume).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RunSettings {
    /// Timed repetitions per configuration.
    pub repetitions: usize,
    /// Warm-up extractions per configuration.
    pub warmup: usize,
    /// Worker threads.
    pub threads: usize,
    /// Whether meshes are saved.
    pub save_meshes: bool,
}

/// One session (start or resume) of a run.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Session {
    /// Machine, build and start time.
    pub provenance: Provenance,
    /// End time, when it ended cleanly.
    pub ended: Option<String>,
    /// Configurations it ran.
    pub configurations_run: usize,
    /// How it ended.
    pub status: Status,
}

/// The manifest a run came from.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct ManifestSource {
    /// The path it was read from.
    pub path: PathBuf,
    /// The folder relative data paths were resolved from.
    pub base_dir: PathBuf,
    /// The copy in the run folder.
    pub copy: String,
}

/// `run.json`.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct RunRecord {
    /// The run's id (its folder name).
    pub run_id: String,
    /// The manifest's run name.
    pub name: String,
    /// Overall status.
    pub status: Status,
    /// The first session's provenance.
    pub provenance: Provenance,
    /// Where the manifest came from.
    pub manifest: ManifestSource,
    /// The options in effect.
    pub settings: RunSettings,
    /// How times were taken.
    pub timing_protocol: String,
    /// Sweep variables of the manifest.
    pub sweep_variables: Vec<String>,
    /// Configuration ids in execution order.
    pub configuration_ids: Vec<String>,
    /// The expanded configurations.
    pub configurations: Value,
    /// Every session.
    pub sessions: Vec<Session>,
    /// Files of the run folder.
    pub files: Vec<String>,
    /// Set when this folder is one shard of a run (`run --shard I/N`): which work units it ran.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shard: Option<ShardRecord>,
    /// Set when this folder was merged from shards (`experiments merge`): every shard's
    /// units, sessions and machines.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub merged_from: Option<Vec<MergedShard>>,
}

/// One shard of a merged run, as recorded in the merged `run.json`.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct MergedShard {
    /// The shard's run id (its folder name).
    pub run_id: String,
    /// The shard's index, count, split and units.
    pub shard: ShardRecord,
    /// The shard's sessions (machine, build, start and end of each).
    pub sessions: Vec<Session>,
}

/// `progress.json`: configurations whose rows are in `raw.csv`, and its length after them.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub(crate) struct Progress {
    /// Keys of finished work units ([`WorkUnit::key`]: the configuration id unless sharded in
    /// repetition blocks).
    pub(crate) completed: Vec<String>,
    /// Length of `raw.csv` holding their rows.
    pub(crate) raw_bytes: u64,
}

pub(crate) const RUN_JSON: &str = "run.json";
pub(crate) const MANIFEST_COPY: &str = "manifest.toml";
pub(crate) const CONFIGURATIONS_CSV: &str = "configurations.csv";
pub(crate) const RAW_CSV: &str = "raw.csv";
pub(crate) const PROGRESS_JSON: &str = "progress.json";
pub(crate) const SUMMARY_CSV: &str = "summary.csv";
pub(crate) const PAPER_CSV: &str = "paper_comparison.csv";
pub(crate) const MESHES: &str = "meshes";
const EDITS_CSV: &str = "edits.csv";

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
        Some(spec) => {
            if plan.edit.is_some() {
                bail!(
                    "{}: the `edit` workload cannot be sharded (its runs are short: run it whole)",
                    manifest_path.display()
                );
            }
            let ids: Vec<String> = plan.configurations.iter().map(|c| c.id.clone()).collect();
            let (split, units) = shard::units_of(&ids, plan.repetitions, spec)
                .with_context(|| format!("sharding {}", manifest_path.display()))?;
            Some(ShardRecord {
                index: spec.index,
                count: spec.count,
                manifest_sha256: shard::manifest_hash(&text),
                split,
                units,
            })
        }
    };
    let folder = match out {
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
            dir.to_path_buf()
        }
        None => match shard {
            Some(s) => new_folder(
                &plan.output,
                &format!("{}-shard-{}-of-{}", plan.name, s.index, s.count),
            )?,
            None => new_folder(&plan.output, &plan.name)?,
        },
    };
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
        let record = run_record(&plan, manifest_path, provenance.clone(), &run_id)?;
        return execute_edits(&folder, &plan, &fields, record, provenance, &edit, opts);
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
    let mut record = run_record(&plan, manifest_path, provenance.clone(), &run_id)?;
    record.shard = shard_record;
    // run.json last: its presence means the folder is initialised and resumable.
    execute(&folder, &plan, &fields, record, progress, provenance, opts)
}

/// The run record of a new run folder (status running, no session yet).
fn run_record(
    plan: &Plan,
    manifest_path: &Path,
    provenance: Provenance,
    run_id: &str,
) -> Result<RunRecord> {
    let base_dir = manifest_path
        .parent()
        .map(Path::to_path_buf)
        .unwrap_or_default();
    Ok(RunRecord {
        run_id: run_id.to_string(),
        name: plan.name.clone(),
        status: Status::Running,
        provenance: provenance.clone(),
        manifest: ManifestSource {
            path: absolute(manifest_path),
            base_dir: absolute(&base_dir),
            copy: MANIFEST_COPY.into(),
        },
        settings: RunSettings {
            repetitions: plan.repetitions,
            warmup: plan.warmup,
            threads: plan.threads,
            save_meshes: plan.save_meshes,
        },
        timing_protocol: TIMING_PROTOCOL.into(),
        sweep_variables: plan.sweep_variables.clone(),
        configuration_ids: plan.configurations.iter().map(|c| c.id.clone()).collect(),
        configurations: serde_json::to_value(&plan.configurations)?,
        sessions: Vec::new(),
        files: Vec::new(),
        shard: None,
        merged_from: None,
    })
}

/// Continues the run in `folder`: skips finished configurations, drops rows that were not
/// recorded as finished, and runs the rest with the options the run started with.
pub fn resume(folder: &Path, opts: &RunOptions) -> Result<RunReport> {
    let record_path = folder.join(RUN_JSON);
    let bytes = fs::read(&record_path).with_context(|| {
        format!(
            "{} is not a resumable run folder (cannot read run.json)",
            folder.display()
        )
    })?;
    let record: RunRecord = serde_json::from_slice(&bytes)
        .with_context(|| format!("parsing {}", record_path.display()))?;
    let progress_path = folder.join(PROGRESS_JSON);
    if !progress_path.exists() {
        bail!(
            "{} has no progress.json: runs of the `edit` workload are not resumable (they are \
             short; start the run again)",
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
    let copy = folder.join(MANIFEST_COPY);
    let text = fs::read_to_string(&copy).with_context(|| format!("reading {}", copy.display()))?;
    let manifest = manifest::parse(&text, &copy)?;
    let base = if record.manifest.base_dir.is_dir() {
        record.manifest.base_dir.clone()
    } else {
        folder.to_path_buf()
    };
    let s = &record.settings;
    let overrides = Overrides {
        repetitions: Some(s.repetitions),
        warmup: Some(s.warmup),
        threads: Some(s.threads),
        save_meshes: Some(s.save_meshes),
    };
    let plan = manifest.plan(&copy, &base, &overrides)?;
    let ids: Vec<String> = plan.configurations.iter().map(|c| c.id.clone()).collect();
    if ids != record.configuration_ids {
        bail!(
            "{}: the manifest copy expands to other configurations than run.json records; \
             the run folder was edited or made by another version",
            folder.display()
        );
    }
    let units =
        work_units(&plan, &record).with_context(|| format!("{}: run.json", folder.display()))?;
    let keys: Vec<String> = units.iter().map(|u| u.key(plan.repetitions)).collect();
    if let Some(unknown) = progress.completed.iter().find(|k| !keys.contains(k)) {
        bail!(
            "{}: finished work unit `{unknown}` is not in the plan",
            progress_path.display()
        );
    }
    let fields = plan.build_fields(&copy)?;

    // Cut raw.csv back to the rows of finished configurations.
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
    let file = OpenOptions::new()
        .write(true)
        .open(&raw)
        .with_context(|| format!("opening {}", raw.display()))?;
    file.set_len(progress.raw_bytes)
        .with_context(|| format!("truncating {}", raw.display()))?;
    file.sync_all()
        .with_context(|| format!("syncing {}", raw.display()))?;
    let expected = csv_bytes(&[raw_header()])?;
    let head = fs::read(&raw).with_context(|| format!("reading {}", raw.display()))?;
    if !head.starts_with(&expected) {
        bail!(
            "{}: its columns differ from this version's; resume with the version that started it",
            raw.display()
        );
    }
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

/// Runs the configurations not yet in `progress`.
fn execute(
    folder: &Path,
    plan: &Plan,
    fields: &manifest::Fields,
    mut record: RunRecord,
    mut progress: Progress,
    provenance: Provenance,
    opts: &RunOptions,
) -> Result<RunReport> {
    record.sessions.push(Session {
        provenance,
        ended: None,
        configurations_run: 0,
        status: Status::Running,
    });
    record.status = Status::Running;
    write_json(&folder.join(RUN_JSON), &record)?;
    if plan.save_meshes {
        fs::create_dir_all(folder.join(MESHES))
            .with_context(|| format!("creating {}", folder.join(MESHES).display()))?;
    }

    let units = work_units(plan, &record)?;
    let todo: Vec<(&WorkUnit, &Configuration)> = units
        .iter()
        .filter(|u| !progress.completed.contains(&u.key(plan.repetitions)))
        .map(|u| {
            plan.configurations
                .iter()
                .find(|c| c.id == u.id)
                .map(|c| (u, c))
                .with_context(|| format!("work unit {} names no configuration", u.id))
        })
        .collect::<Result<_>>()?;
    let extractions: u64 = todo
        .iter()
        .map(|(u, _)| (plan.warmup + u.len()) as u64)
        .sum();
    let bar = progress_bar(
        opts.quiet,
        extractions,
        "{msg:>16} [{bar:30}] {pos}/{len} extractions, {elapsed} elapsed, ETA {eta}",
    );

    let mut ran = 0;
    let mut status = Status::Finished;
    // Checkpoints: finished units' rows are appended to raw.csv (synced) and progress.json
    // rewritten at most every CHECKPOINT, and always at the end or on an error. A crash in
    // between loses only the unrecorded units, which `--resume` runs again (it cuts raw.csv back
    // to the recorded bytes). One checkpoint per unit made sweeps of many tiny configurations
    // (topology sweeps, seed studies) cost a sync and a growing progress.json per unit.
    const CHECKPOINT: std::time::Duration = std::time::Duration::from_millis(500);
    let mut pending: Vec<u8> = Vec::new();
    let mut last_checkpoint = std::time::Instant::now();
    let checkpoint = |pending: &mut Vec<u8>, progress: &mut Progress| -> Result<()> {
        if !pending.is_empty() {
            progress.raw_bytes = append_synced(&folder.join(RAW_CSV), pending)?;
            pending.clear();
        }
        write_json(&folder.join(PROGRESS_JSON), &*progress)
    };
    for (k, &(unit, c)) in todo.iter().enumerate() {
        if opts.stop_after.is_some_and(|limit| k >= limit) {
            status = Status::Stopped;
            break;
        }
        bar.set_message(c.id.clone());
        let field = fields
            .get(&c.field_key())
            .with_context(|| format!("no field built for object {}", c.field_key()))?;
        let result = match run_repetitions(c, field, plan, unit.first, unit.last, &bar) {
            Ok(r) => r,
            Err(e) => {
                checkpoint(&mut pending, &mut progress)?;
                return Err(e.context(format!(
                    "configuration {} failed; the finished configurations are kept: fix the \
                     cause and continue with `experiments run --resume {}`",
                    c.id,
                    folder.display()
                )));
            }
        };
        let rows = raw_rows_from(
            &record.run_id,
            c,
            plan.threads,
            unit.first,
            &result.stats,
            &result.measurement,
        )?;
        pending.extend_from_slice(&csv_bytes(&rows)?);
        if plan.save_meshes {
            let path = folder.join(MESHES).join(format!("{}.ply", c.id));
            rmt_mesh::io::save_ply(&path, &result.mesh, true)
                .with_context(|| format!("saving {}", path.display()))?;
        }
        progress.completed.push(unit.key(plan.repetitions));
        ran += 1;
        if last_checkpoint.elapsed() >= CHECKPOINT {
            checkpoint(&mut pending, &mut progress)?;
            last_checkpoint = std::time::Instant::now();
        }
    }
    checkpoint(&mut pending, &mut progress)?;
    bar.finish_and_clear();

    if status == Status::Finished {
        record.files = write_summaries(folder, plan)?;
    }
    close_session(folder, &mut record, status, ran)?;
    Ok(RunReport {
        folder: folder.to_path_buf(),
        status,
        configurations_run: ran,
        configurations_done: progress.completed.len(),
        configurations_total: units.len(),
    })
}

/// Writes `summary.csv` and `paper_comparison.csv` (when the plan names the dissertation's
/// table) from the folder's `raw.csv`; returns the files of a finished run folder.
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
        write_atomic(&folder.join(crate::seeds::SEEDS_CSV), &table.to_csv()?)?;
        files.push(crate::seeds::SEEDS_CSV);
    }
    if let Some((tally, failed)) = crate::topology::topology_tables(&summary, plan)? {
        write_atomic(
            &folder.join(crate::topology::TOPOLOGY_CSV),
            &tally.to_csv()?,
        )?;
        write_atomic(
            &folder.join(crate::topology::FAILURES_CSV),
            &failed.to_csv()?,
        )?;
        files.push(crate::topology::TOPOLOGY_CSV);
        files.push(crate::topology::FAILURES_CSV);
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

/// Runs the `edit` workload: one chunked terrain session per configuration
/// ([`crate::edit::run_edit_session`]), written to `edits.csv` (one row per stroke) and
/// `summary.csv` (latency quantiles, chunks per edit, triangles per chunk, whole-volume vs
/// chunked time). Both are written once at the end, atomically; an interrupted edit run leaves no
/// CSV and is started again rather than resumed.
fn execute_edits(
    folder: &Path,
    plan: &Plan,
    fields: &manifest::Fields,
    mut record: RunRecord,
    provenance: Provenance,
    edit: &manifest::EditPlan,
    opts: &RunOptions,
) -> Result<RunReport> {
    use crate::edit::{
        edit_rows, edit_summary_row, run_edit_session, EDITS_HEADER, EDIT_SUMMARY_HEADER,
    };
    record.sessions.push(Session {
        provenance,
        ended: None,
        configurations_run: 0,
        status: Status::Running,
    });
    write_json(&folder.join(RUN_JSON), &record)?;
    let bar = progress_bar(
        opts.quiet,
        plan.configurations.len() as u64,
        "{msg:>16} [{bar:30}] {pos}/{len} edit sessions, {elapsed} elapsed",
    );
    let mut edits = vec![EDITS_HEADER.map(String::from).to_vec()];
    let mut summary = vec![EDIT_SUMMARY_HEADER.map(String::from).to_vec()];
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
            let path = folder.join(MESHES).join(format!("{}.ply", c.id));
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
    close_session(folder, &mut record, status, ran)?;
    Ok(RunReport {
        folder: folder.to_path_buf(),
        status,
        configurations_run: ran,
        configurations_done: ran,
        configurations_total: plan.configurations.len(),
    })
}

/// A progress bar of `len` steps drawn with `template` (hidden when `quiet`).
fn progress_bar(quiet: bool, len: u64, template: &str) -> ProgressBar {
    if quiet {
        return ProgressBar::hidden();
    }
    let bar = ProgressBar::new(len);
    let style = ProgressStyle::with_template(template)
        .unwrap_or_else(|_| ProgressStyle::default_bar())
        .progress_chars("=> ");
    bar.set_style(style);
    bar
}

/// Records the end of the current session (status, configurations run) in run.json.
fn close_session(folder: &Path, record: &mut RunRecord, status: Status, ran: usize) -> Result<()> {
    record.status = status;
    if let Some(s) = record.sessions.last_mut() {
        s.ended = Some(provenance::utc_now_iso());
        s.configurations_run = ran;
        s.status = status;
    }
    write_json(&folder.join(RUN_JSON), record)
}

/// What one configuration produced.
pub struct ConfigResult {
    /// Stats of every timed repetition.
    pub stats: Vec<Stats>,
    /// Measurement of the last repetition's mesh.
    pub measurement: Measurement,
    /// The last repetition's mesh.
    pub mesh: Mesh,
}

/// Runs one configuration: warm-up, then timed repetitions with one reused extractor; checks
/// that every repetition's mesh is identical.
pub fn run_configuration(
    c: &Configuration,
    field: &dyn ScalarField,
    plan: &Plan,
    bar: &ProgressBar,
) -> Result<ConfigResult> {
    run_repetitions(c, field, plan, 1, plan.repetitions, bar)
}

/// Runs timed repetitions `first..=last` of one configuration (a work unit of a shard), after
/// the plan's warm-up, with one reused extractor; checks that every repetition's mesh is
/// identical.
pub fn run_repetitions(
    c: &Configuration,
    field: &dyn ScalarField,
    plan: &Plan,
    first: usize,
    last: usize,
    bar: &ProgressBar,
) -> Result<ConfigResult> {
    let settings = c.extraction.settings(plan.threads);
    let mut extractor = Extractor::new();
    let mut mesh = Mesh::default();
    for _ in 0..plan.warmup {
        extractor.extract(field, &settings, &mut mesh)?;
        bar.inc(1);
    }
    let mut stats = Vec::with_capacity(last + 1 - first.min(last + 1));
    let mut first_print = None;
    for rep in first..=last {
        stats.push(extractor.extract(field, &settings, &mut mesh)?);
        let print = mesh_fingerprint(&mesh);
        match first_print {
            None => first_print = Some(print),
            Some(f) if f != print => bail!(
                "repetition {rep} produced a different mesh than repetition {first}: the \
                 extraction is not deterministic, so metrics measured on one mesh would not hold \
                 for all"
            ),
            Some(_) => {}
        }
        bar.inc(1);
    }
    let last = stats.last().cloned().unwrap_or_default();
    let measurement = rmt_extract::measure(&mesh, &last, Some(field), &settings);
    Ok(ConfigResult {
        stats,
        measurement,
        mesh,
    })
}

/// A 64-bit FNV-1a fingerprint of a mesh's positions, normals and indices (bit patterns).
pub fn mesh_fingerprint(mesh: &Mesh) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    let mut eat = |w: u32| {
        for b in w.to_le_bytes() {
            h ^= u64::from(b);
            h = h.wrapping_mul(0x0100_0000_01b3);
        }
    };
    eat(mesh.positions.len() as u32);
    for p in mesh.positions.iter().chain(&mesh.normals) {
        p.iter().for_each(|c| eat(c.to_bits()));
    }
    eat(mesh.indices.len() as u32);
    mesh.indices.iter().for_each(|&i| eat(i));
    h
}

/// The header of `raw.csv`: [`RAW_PREFIX`] then the measurement keys.
pub fn raw_header() -> Vec<String> {
    let keys = measurement_json(&Measurement::default())
        .map(|m| m.keys().cloned().collect::<Vec<_>>())
        .unwrap_or_default();
    RAW_PREFIX
        .iter()
        .map(|s| s.to_string())
        .chain(keys)
        .collect()
}

/// The configuration columns of a configuration (shared by raw rows and `configurations.csv`).
fn config_values(c: &Configuration) -> HashMap<&'static str, String> {
    let e = &c.extraction;
    let [rx, ry, rz] = e.resolution.cells();
    HashMap::from([
        ("id", c.id.clone()),
        ("object", c.object.clone()),
        ("kind", e.object.kind.name().to_string()),
        ("method", config::method_name(e.method).to_string()),
        (
            "lattice",
            config::lattice_name(e.method, e.lattice).to_string(),
        ),
        ("clustering", e.clustering.name().to_string()),
        ("rx", rx.to_string()),
        ("ry", ry.to_string()),
        ("rz", rz.to_string()),
        ("collapse_threshold", e.collapse_threshold.to_string()),
        ("iso", e.iso.to_string()),
        ("normals", e.normals.name().to_string()),
    ])
}

fn json_cell(v: &Value) -> String {
    match v {
        Value::Null => String::new(),
        Value::String(s) => s.clone(),
        other => other.to_string(),
    }
}

/// The raw rows of one configuration: one per repetition, each with that repetition's stats and
/// the shared mesh metrics.
pub fn raw_rows(
    run_id: &str,
    c: &Configuration,
    threads: usize,
    stats: &[Stats],
    measured: &Measurement,
) -> Result<Vec<Vec<String>>> {
    raw_rows_from(run_id, c, threads, 1, stats, measured)
}

/// Like [`raw_rows`], numbering the repetitions from `first` (a block of a sharded run).
pub fn raw_rows_from(
    run_id: &str,
    c: &Configuration,
    threads: usize,
    first: usize,
    stats: &[Stats],
    measured: &Measurement,
) -> Result<Vec<Vec<String>>> {
    let mut values = config_values(c);
    values.insert("run_id", run_id.to_string());
    values.insert("threads", threads.to_string());
    let mut rows = Vec::with_capacity(stats.len());
    for (i, s) in stats.iter().enumerate() {
        values.insert("repetition", (first + i).to_string());
        let m = Measurement {
            stats: s.clone(),
            ..measured.clone()
        };
        let mut row: Vec<String> = RAW_PREFIX
            .iter()
            .map(|k| values.get(k).cloned().unwrap_or_default())
            .collect();
        row.extend(measurement_json(&m)?.values().map(json_cell));
        rows.push(row);
    }
    Ok(rows)
}

/// `configurations.csv` of a plan.
pub fn configurations_csv(plan: &Plan) -> Result<Vec<u8>> {
    let mut rows = vec![CONFIG_COLUMNS
        .iter()
        .map(|s| s.to_string())
        .collect::<Vec<_>>()];
    for c in &plan.configurations {
        let v = config_values(c);
        rows.push(
            CONFIG_COLUMNS
                .iter()
                .map(|k| v.get(k).cloned().unwrap_or_default())
                .collect(),
        );
    }
    csv_bytes(&rows)
}

pub(crate) fn csv_bytes(rows: &[Vec<String>]) -> Result<Vec<u8>> {
    let mut w = csv::Writer::from_writer(Vec::new());
    for r in rows {
        w.write_record(r)?;
    }
    w.into_inner()
        .map_err(|e| anyhow::anyhow!("writing CSV: {e}"))
}

/// A header and rows of strings.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Table {
    /// Column names.
    pub header: Vec<String>,
    /// Rows, each as long as the header.
    pub rows: Vec<Vec<String>>,
}

impl Table {
    /// Reads a CSV file.
    pub fn read(path: &Path) -> Result<Table> {
        let mut r =
            csv::Reader::from_path(path).with_context(|| format!("reading {}", path.display()))?;
        let header = r
            .headers()
            .with_context(|| format!("reading {}", path.display()))?
            .iter()
            .map(String::from)
            .collect();
        let mut rows = Vec::new();
        for (i, rec) in r.records().enumerate() {
            let rec = rec.with_context(|| format!("{}: row {}", path.display(), i + 2))?;
            rows.push(rec.iter().map(String::from).collect());
        }
        Ok(Table { header, rows })
    }

    /// Index of column `name`.
    pub fn column(&self, name: &str) -> Option<usize> {
        self.header.iter().position(|h| h == name)
    }

    /// The value of column `name` in row `row`.
    pub fn get(&self, row: usize, name: &str) -> Option<&str> {
        Some(self.rows.get(row)?.get(self.column(name)?)?.as_str())
    }

    /// CSV bytes.
    pub fn to_csv(&self) -> Result<Vec<u8>> {
        let mut all = vec![self.header.clone()];
        all.extend(self.rows.iter().cloned());
        csv_bytes(&all)
    }
}

/// Whether a measurement column is a time (summarised by mean, sd, min, median, max).
pub fn is_time_column(name: &str) -> bool {
    name.starts_with("t_") && name.ends_with("_s")
}

/// Mean, sample standard deviation (None below two values), min, median, max.
pub fn describe(values: &[f64]) -> (f64, Option<f64>, f64, f64, f64) {
    let n = values.len();
    if n == 0 {
        return (f64::NAN, None, f64::NAN, f64::NAN, f64::NAN);
    }
    let mean = values.iter().sum::<f64>() / n as f64;
    let sd = (n >= 2).then(|| {
        (values.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() / (n - 1) as f64).sqrt()
    });
    let mut sorted = values.to_vec();
    sorted.sort_by(f64::total_cmp);
    let median = if n % 2 == 1 {
        sorted[n / 2]
    } else {
        (sorted[n / 2 - 1] + sorted[n / 2]) / 2.0
    };
    (mean, sd, sorted[0], median, sorted[n - 1])
}

/// Summary columns that precede the measurement statistics.
const SUMMARY_PREFIX: [&str; 13] = [
    "id",
    "object",
    "kind",
    "method",
    "lattice",
    "clustering",
    "rx",
    "ry",
    "rz",
    "collapse_threshold",
    "iso",
    "normals",
    "threads",
];

/// The summary of a `raw.csv`: one row per configuration (in order of first appearance), with
/// `repetitions`, then for each time column its `_mean`, `_sd`, `_min`, `_median`, `_max`, for every
/// other measurement column its value (the mean if repetitions disagree), then the derived columns
/// `triangle_reduction` (1 - triangles / triangles of the same object, method, lattice and
/// resolution without clustering; empty when that configuration is not in the run),
/// `discard_share` (discarded / (triangles + discarded)), `tetrahedra_share` (processed / total)
/// and `share_<stage>` (mean stage time / mean total time).
pub fn summarise(raw_path: &Path) -> Result<Table> {
    summarise_seeded(raw_path, &HashMap::new())
}

/// Like [`summarise`] for a seed study: `seeds` maps configuration ids to their noise seed, and
/// `triangle_reduction` compares with the unclustered configuration of the same seed.
pub fn summarise_seeded(raw_path: &Path, seeds: &HashMap<String, u32>) -> Result<Table> {
    let raw = Table::read(raw_path)?;
    let first_measure = RAW_PREFIX.len();
    if raw.header.len() < first_measure || raw.header[..first_measure] != RAW_PREFIX {
        bail!(
            "{}: not a raw.csv of this runner (unexpected columns)",
            raw_path.display()
        );
    }
    let measures: Vec<String> = raw.header[first_measure..].to_vec();
    let id_col = 1;
    let mut order: Vec<String> = Vec::new();
    let mut groups: HashMap<String, Vec<usize>> = HashMap::new();
    for (i, row) in raw.rows.iter().enumerate() {
        let id = row[id_col].clone();
        if !groups.contains_key(&id) {
            order.push(id.clone());
        }
        groups.entry(id).or_default().push(i);
    }
    let parse = |row: usize, col: usize| -> Result<Option<f64>> {
        let cell = &raw.rows[row][col];
        if cell.is_empty() {
            return Ok(None);
        }
        cell.parse::<f64>().map(Some).with_context(|| {
            format!(
                "{}: row {}, column {}: `{cell}` is not a number",
                raw_path.display(),
                row + 2,
                raw.header[col]
            )
        })
    };

    let mut header: Vec<String> = SUMMARY_PREFIX.iter().map(|s| s.to_string()).collect();
    header.push("repetitions".into());
    for m in &measures {
        if is_time_column(m) {
            for stat in ["mean", "sd", "min", "median", "max"] {
                header.push(format!("{m}_{stat}"));
            }
        } else {
            header.push(m.clone());
        }
    }
    let stages: Vec<String> = measures
        .iter()
        .filter(|m| is_time_column(m) && *m != "t_total_s")
        .cloned()
        .collect();
    header.extend(["triangle_reduction", "discard_share", "tetrahedra_share"].map(String::from));
    header.extend(
        stages
            .iter()
            .map(|s| format!("share_{}", &s[2..s.len() - 2])),
    );

    let fmt = |v: f64| {
        if v.is_finite() {
            v.to_string()
        } else {
            String::new()
        }
    };
    let mut rows = Vec::new();
    // Numeric values per configuration, for derived columns: (mean times, values).
    let mut numbers: Vec<HashMap<String, f64>> = Vec::new();
    for id in &order {
        let members = &groups[id];
        let first = members[0];
        let mut row: Vec<String> = SUMMARY_PREFIX
            .iter()
            .map(|k| raw.get(first, k).unwrap_or_default().to_string())
            .collect();
        row.push(members.len().to_string());
        let mut nums = HashMap::new();
        for (j, m) in measures.iter().enumerate() {
            let col = first_measure + j;
            if is_time_column(m) {
                let mut values = Vec::with_capacity(members.len());
                for &r in members {
                    if let Some(v) = parse(r, col)? {
                        values.push(v);
                    }
                }
                let (mean, sd, min, median, max) = describe(&values);
                nums.insert(m.clone(), mean);
                row.extend([
                    fmt(mean),
                    sd.map(fmt).unwrap_or_default(),
                    fmt(min),
                    fmt(median),
                    fmt(max),
                ]);
            } else {
                let cells: Vec<&String> = members.iter().map(|&r| &raw.rows[r][col]).collect();
                if cells.iter().all(|c| *c == cells[0]) {
                    if let Some(v) = parse(first, col)? {
                        nums.insert(m.clone(), v);
                    }
                    row.push(cells[0].clone());
                } else {
                    let mut values = Vec::new();
                    for &r in members {
                        if let Some(v) = parse(r, col)? {
                            values.push(v);
                        }
                    }
                    let mean = describe(&values).0;
                    nums.insert(m.clone(), mean);
                    row.push(fmt(mean));
                }
            }
        }
        rows.push(row);
        numbers.push(nums);
    }

    // Derived columns.
    let key = |row: &[String], with_threshold: bool| -> Vec<String> {
        let mut cols = vec![
            "object", "method", "lattice", "rx", "ry", "rz", "iso", "normals", "threads",
        ];
        if with_threshold {
            cols.push("collapse_threshold");
        }
        let mut key: Vec<String> = cols
            .iter()
            .map(|c| {
                header
                    .iter()
                    .position(|h| h == c)
                    .map(|i| row[i].clone())
                    .unwrap_or_default()
            })
            .collect();
        if let Some(seed) = seeds.get(&row[0]) {
            key.push(seed.to_string());
        }
        key
    };
    let clustering_col = header.iter().position(|h| h == "clustering").unwrap_or(0);
    let mut baselines: HashMap<(Vec<String>, bool), usize> = HashMap::new();
    for (i, row) in rows.iter().enumerate() {
        if row[clustering_col] == "none" {
            for with in [true, false] {
                baselines.entry((key(row, with), with)).or_insert(i);
            }
        }
    }
    for i in 0..rows.len() {
        let n = &numbers[i];
        let get = |k: &str| n.get(k).copied();
        let baseline = baselines
            .get(&(key(&rows[i], true), true))
            .or_else(|| baselines.get(&(key(&rows[i], false), false)))
            .copied();
        let reduction = match (
            baseline.and_then(|b| numbers[b].get("triangles").copied()),
            get("triangles"),
        ) {
            (Some(base), Some(t)) if base > 0.0 => fmt(1.0 - t / base),
            _ => String::new(),
        };
        let ratio = |a: Option<f64>, b: Option<f64>| match (a, b) {
            (Some(a), Some(b)) if b > 0.0 => fmt(a / b),
            _ => String::new(),
        };
        let discard = ratio(
            get("discarded"),
            get("triangles").zip(get("discarded")).map(|(t, d)| t + d),
        );
        let tets = ratio(get("tetrahedra_processed"), get("tetrahedra_total"));
        let shares: Vec<String> = stages
            .iter()
            .map(|s| ratio(get(s), get("t_total_s")))
            .collect();
        let row = &mut rows[i];
        row.extend([reduction, discard, tets]);
        row.extend(shares);
    }
    Ok(Table { header, rows })
}

/// Pairs of (our summary column, the dissertation's column) compared in `paper_comparison.csv`;
/// `triangle_reduction` and `discard_share` are derived on their side too.
pub const PAPER_METRICS: [(&str, &str); 16] = [
    ("vertices", "n_vertices"),
    ("triangles", "n_triangles"),
    ("discarded", "n_discarded"),
    ("tetrahedra_processed", "n_tetrahedra"),
    ("triangle_reduction", ""),
    ("discard_share", "f_discard"),
    ("ar_mean", "ar_mean"),
    ("ar_sd", "ar_sd"),
    ("t_total_s_mean", "t_total_s"),
    ("t_sampling_s_mean", "t_sampling_s"),
    ("t_vertex_s_mean", "t_vertex_s"),
    ("t_geometry_s_mean", "t_geometry_s"),
    ("bytes_lattice", "b_lattice"),
    ("bytes_edges", "b_edges"),
    ("bytes_vertices", "b_vertices"),
    ("bytes_indices", "b_indices"),
];

/// Joins a summary with the dissertation's table (`data/paper/benchmark.csv`) on configuration
/// id: `id,metric,ours,theirs,ratio` (ratio = ours / theirs, empty when theirs is 0 or missing).
/// Our `integrated-unchecked` rows (`as_bc`) join the dissertation's integrated rows (`as_bi`):
/// its clustering had no exact check.
/// Rows whose resolution (`rx`, `ry`, `rz`) differs from the dissertation's are left out.
pub fn paper_comparison(summary: &Table, benchmark: &Path) -> Result<Table> {
    let paper = Table::read(benchmark)?;
    let id_col = paper
        .column("id")
        .with_context(|| format!("{}: no `id` column", benchmark.display()))?;
    let number = |row: usize, col: &str| -> Result<Option<f64>> {
        let Some(cell) = paper.get(row, col) else {
            bail!("{}: no column `{col}`", benchmark.display());
        };
        if cell.is_empty() {
            return Ok(None);
        }
        cell.parse().map(Some).with_context(|| {
            format!(
                "{}: row {}, column {col}: `{cell}` is not a number",
                benchmark.display(),
                row + 2
            )
        })
    };
    let their_row = |id: &str| paper.rows.iter().position(|r| r[id_col] == id);
    // The dissertation's integrated clustering had no exact check: its rules are our
    // `integrated-unchecked` (letter `c`), so those rows compare with its `i` rows.
    let dissertation_id = |id: &str| -> String {
        match id.split_once('_') {
            Some((prefix, rest)) => {
                let mut letters = rest.chars();
                match (letters.next(), letters.next()) {
                    (Some(lattice), Some('c')) => {
                        format!("{prefix}_{lattice}i{}", letters.as_str())
                    }
                    _ => id.to_string(),
                }
            }
            None => id.to_string(),
        }
    };
    let ours_baseline_id = |row: usize| -> Option<String> {
        // Our baseline: the same id with the clustering letter replaced by `u`.
        let id = summary.get(row, "id")?;
        let (prefix, rest) = id.split_once('_')?;
        let mut letters = rest.chars();
        let lattice = letters.next()?;
        let tail: String = letters.skip(1).collect();
        Some(format!("{prefix}_{lattice}u{tail}"))
    };
    let mut rows = Vec::new();
    for r in 0..summary.rows.len() {
        let Some(id) = summary.get(r, "id") else {
            continue;
        };
        let Some(pr) = their_row(&dissertation_id(id)) else {
            continue;
        };
        // Same id at another resolution (e.g. the CI manifest's small grids) is not comparable.
        let same_resolution = ["rx", "ry", "rz"].iter().all(|axis| {
            match (summary.get(r, axis), paper.get(pr, axis)) {
                (Some(a), Some(b)) => a.trim() == b.trim(),
                _ => true,
            }
        });
        if !same_resolution {
            continue;
        }
        for (ours_col, theirs_col) in PAPER_METRICS {
            let ours: Option<f64> = summary.get(r, ours_col).and_then(|c| c.parse().ok());
            let theirs = match ours_col {
                "triangle_reduction" => {
                    let base = ours_baseline_id(r).and_then(|b| their_row(&b));
                    match base {
                        Some(b) => match (number(pr, "n_triangles")?, number(b, "n_triangles")?) {
                            (Some(t), Some(bt)) if bt > 0.0 => Some(1.0 - t / bt),
                            _ => None,
                        },
                        None => None,
                    }
                }
                // The dissertation gives the discarded share in percent.
                "discard_share" => number(pr, theirs_col)?.map(|p| p / 100.0),
                _ => number(pr, theirs_col)?,
            };
            let cell = |v: Option<f64>| {
                v.filter(|v| v.is_finite())
                    .map(|v| v.to_string())
                    .unwrap_or_default()
            };
            let ratio = match (ours, theirs) {
                (Some(o), Some(t)) if t != 0.0 => Some(o / t),
                _ => None,
            };
            rows.push(vec![
                id.to_string(),
                ours_col.to_string(),
                cell(ours),
                cell(theirs),
                cell(ratio),
            ]);
        }
    }
    Ok(Table {
        header: ["id", "metric", "ours", "theirs", "ratio"]
            .map(String::from)
            .to_vec(),
        rows,
    })
}

/// A new folder `<parent>/<name>-<UTC stamp>` (with `-2`, `-3`, ... if taken).
pub(crate) fn new_folder(parent: &Path, name: &str) -> Result<PathBuf> {
    let base = format!("{name}-{}", provenance::stamp(provenance::unix_now()));
    for n in 1..1000 {
        let candidate = if n == 1 {
            parent.join(&base)
        } else {
            parent.join(format!("{base}-{n}"))
        };
        if !candidate.exists() {
            return Ok(candidate);
        }
    }
    bail!("no free run folder name under {}", parent.display())
}

fn absolute(p: &Path) -> PathBuf {
    p.canonicalize().unwrap_or_else(|_| p.to_path_buf())
}

/// Writes `bytes` to `path` through a synced temporary file in the same folder, renamed into
/// place: readers see the old file or the new one, never a part.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    let folder = path
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let temp = folder.join(format!(".{name}.{}.tmp", std::process::id()));
    let result = (|| -> std::io::Result<()> {
        let mut f = fs::File::create(&temp)?;
        f.write_all(bytes)?;
        f.sync_all()?;
        fs::rename(&temp, path)?;
        // Make the rename durable too (best effort: not every platform syncs folders).
        if let Ok(dir) = fs::File::open(folder) {
            let _ = dir.sync_all();
        }
        Ok(())
    })();
    if result.is_err() {
        let _ = fs::remove_file(&temp);
    }
    result.with_context(|| format!("writing {}", path.display()))
}

pub(crate) fn write_json<T: Serialize>(path: &Path, value: &T) -> Result<()> {
    let mut bytes = serde_json::to_vec_pretty(value)?;
    bytes.push(b'\n');
    write_atomic(path, &bytes)
}

/// Appends `bytes` to `path` in one write and syncs it; returns the new length.
fn append_synced(path: &Path, bytes: &[u8]) -> Result<u64> {
    let mut f = OpenOptions::new()
        .append(true)
        .open(path)
        .with_context(|| format!("opening {}", path.display()))?;
    f.write_all(bytes)
        .with_context(|| format!("appending to {}", path.display()))?;
    f.sync_data()
        .with_context(|| format!("syncing {}", path.display()))?;
    Ok(f.metadata()
        .with_context(|| format!("reading {}", path.display()))?
        .len())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A dissertation table in `dir` with an unclustered (100 triangles) and an integrated (25
    /// triangles) row of object code `object` at 50^3.
    fn dissertation_table(dir: &Path, object: &str) -> PathBuf {
        let bench = dir.join("benchmark.csv");
        std::fs::write(
            &bench,
            format!(
                "id,rx,ry,rz,n_tetrahedra,n_vertices,n_triangles,n_discarded,f_discard,ar_mean,\
                 ar_sd,t_total_s,t_sampling_s,t_vertex_s,t_geometry_s,b_lattice,b_edges,b_vertices,\
                 b_indices\n\
                 {object}_bu,50,50,50,9,52,100,0,0,2,1,1,1,1,1,1,1,1,1\n\
                 {object}_bi,50,50,50,9,14,25,75,75,2,1,1,1,1,1,1,1,1,1\n"
            ),
        )
        .unwrap();
        bench
    }

    #[test]
    fn paper_comparison_skips_rows_at_another_resolution() {
        let dir = tempfile::tempdir().unwrap();
        let bench = dissertation_table(dir.path(), "ss");
        let summary = |res: &str| Table {
            header: ["id", "rx", "ry", "rz", "triangles", "vertices"]
                .map(String::from)
                .to_vec(),
            rows: vec![
                ["ss_bu", res, res, res, "90", "50"]
                    .map(String::from)
                    .to_vec(),
                ["ss_bi", res, res, res, "20", "12"]
                    .map(String::from)
                    .to_vec(),
            ],
        };
        let same = paper_comparison(&summary("50"), &bench).unwrap();
        let tri = same
            .rows
            .iter()
            .find(|r| r[0] == "ss_bi" && r[1] == "triangles")
            .unwrap();
        assert_eq!((tri[2].as_str(), tri[3].as_str()), ("20", "25"));
        let reduction = same
            .rows
            .iter()
            .find(|r| r[0] == "ss_bi" && r[1] == "triangle_reduction")
            .unwrap();
        assert_eq!(reduction[3], "0.75");
        let other = paper_comparison(&summary("8"), &bench).unwrap();
        assert!(other.rows.is_empty(), "{:?}", other.rows);
    }

    #[test]
    fn unchecked_rows_compare_with_the_dissertations_integrated_rows() {
        let dir = tempfile::tempdir().unwrap();
        let bench = dissertation_table(dir.path(), "as");
        let summary = Table {
            header: ["id", "rx", "ry", "rz", "triangles"]
                .map(String::from)
                .to_vec(),
            rows: vec![
                ["as_bu", "50", "50", "50", "90"].map(String::from).to_vec(),
                ["as_bc", "50", "50", "50", "30"].map(String::from).to_vec(),
                ["as_bc_t0.3", "50", "50", "50", "31"]
                    .map(String::from)
                    .to_vec(),
            ],
        };
        let table = paper_comparison(&summary, &bench).unwrap();
        let find = |id: &str, metric: &str| {
            table
                .rows
                .iter()
                .find(|r| r[0] == id && r[1] == metric)
                .cloned()
        };
        let tri = find("as_bc", "triangles").unwrap();
        assert_eq!((tri[2].as_str(), tri[3].as_str()), ("30", "25"));
        // Reduction: ours against our `as_bu`, theirs against their `as_bu`.
        assert_eq!(find("as_bc", "triangle_reduction").unwrap()[3], "0.75");
        // A sweep id keeps its suffix and so has no counterpart.
        assert!(find("as_bc_t0.3", "triangles").is_none());
    }

    #[test]
    fn describe_gives_mean_sd_min_median_max() {
        let (mean, sd, min, median, max) = describe(&[4.0, 1.0, 3.0, 2.0]);
        assert_eq!((mean, min, median, max), (2.5, 1.0, 2.5, 4.0));
        assert!((sd.unwrap() - (5.0f64 / 3.0).sqrt()).abs() < 1e-12);
        assert_eq!(describe(&[7.0]).1, None);
        assert_eq!(describe(&[3.0, 1.0, 2.0]).3, 2.0);
    }

    #[test]
    fn fingerprint_sees_any_change() {
        let mut m = Mesh::from_triangles(
            vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
            vec![0, 1, 2],
        );
        let a = mesh_fingerprint(&m);
        assert_eq!(a, mesh_fingerprint(&m.clone()));
        m.indices = vec![0, 2, 1];
        assert_ne!(a, mesh_fingerprint(&m));
        m.indices = vec![0, 1, 2];
        m.positions[2][1] = 1.0000001;
        assert_ne!(a, mesh_fingerprint(&m));
    }

    #[test]
    fn raw_header_starts_with_the_prefix_and_has_every_measurement_key() {
        let h = raw_header();
        assert_eq!(
            &h[..RAW_PREFIX.len()],
            RAW_PREFIX.map(String::from).as_slice()
        );
        for k in [
            "vertices",
            "triangles",
            "t_total_s",
            "ar_mean",
            "euler",
            "fidelity_max_h",
        ] {
            assert!(h.iter().any(|c| c == k), "missing {k}");
        }
    }

    #[test]
    fn atomic_writes_replace_the_whole_file_and_leave_no_temporary() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("a.txt");
        write_atomic(&p, b"first, longer content").unwrap();
        write_atomic(&p, b"second").unwrap();
        assert_eq!(fs::read(&p).unwrap(), b"second");
        assert_eq!(fs::read_dir(dir.path()).unwrap().count(), 1);
        assert_eq!(append_synced(&p, b"+more").unwrap(), 11);
    }
}
