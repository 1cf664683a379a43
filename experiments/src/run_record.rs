//! What a run folder records about itself: `run.json` ([`RunRecord`] with its [`Session`]s) and
//! `progress.json` ([`Progress`]), and the plan a run folder was made with ([`plan_of`]).

use std::fs;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use rmt_runfolder::layout::{MANIFEST_COPY, RUN_JSON};
use serde::{Deserialize, Serialize};
use serde_json::Value;

use crate::manifest::{self, Overrides, Plan};
use crate::provenance::Provenance;
use crate::run_files::absolute;
use crate::shard::ShardRecord;

/// What the timing protocol is, recorded in `run.json`.
pub const TIMING_PROTOCOL: &str = "One Extractor and one Mesh per configuration, reused by its \
    warm-up and timed repetitions; each repetition is one full extraction including sampling. \
    Validation, quality and fidelity are computed once on the last repetition's mesh and copied \
    into every row; every repetition's mesh is checked to be identical to the first.";

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
    /// Keys of finished work units ([`crate::shard::WorkUnit::key`]: the configuration id
    /// unless sharded in repetition blocks).
    pub(crate) completed: Vec<String>,
    /// Length of `raw.csv` holding their rows.
    pub(crate) raw_bytes: u64,
}

impl RunRecord {
    /// The record of a new run folder for `plan` (status running, no session yet).
    pub fn new(
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
            provenance,
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
}

/// Reads `run.json` of `folder`; `not_a_run` says what the folder is not when it has none.
pub(crate) fn read_record(folder: &Path, not_a_run: &str) -> Result<RunRecord> {
    let path = folder.join(RUN_JSON);
    let bytes = fs::read(&path).with_context(|| {
        format!(
            "{} is not {not_a_run} (cannot read run.json)",
            folder.display()
        )
    })?;
    serde_json::from_slice(&bytes).with_context(|| format!("parsing {}", path.display()))
}

/// The plan a run folder was made with: its manifest copy, expanded with its recorded options
/// (data paths resolved from the manifest's folder when it still exists, else from the run
/// folder).
pub(crate) fn plan_of(folder: &Path, record: &RunRecord) -> Result<Plan> {
    let copy = folder.join(MANIFEST_COPY);
    let text = fs::read_to_string(&copy).with_context(|| format!("reading {}", copy.display()))?;
    let m = manifest::parse(&text, &copy)?;
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
    Ok(m.plan(&copy, &base, &overrides)?)
}
