//! `experiments slurm`: runs a manifest on a Slurm cluster as a job array of N shards
//! (`run --shard I/N`, see [`crate::shard`]) and a merge job (`experiments merge`, see
//! [`crate::merge`]) that depends on the array with `afterok` and `--kill-on-invalid-dep=yes`
//! (a failed or cancelled shard cancels the merge instead of leaving it pending forever).
//!
//! Slurm is the scheduler; this module only writes two readable batch scripts and calls `sbatch`.
//! Next to the merged run folder `OUT` it makes a job folder `OUT.slurm/`:
//!
//! | file | content |
//! |---|---|
//! | `shards.sbatch` | the array script, one task per shard: starts its shard, or resumes it if an earlier attempt left one |
//! | `merge.sbatch` | merges `shards/shard-1` .. `shards/shard-N` into `OUT` |
//! | `job.json` | manifest, its SHA-256, N, OUT, and every submission (array and merge job ids, tasks) |
//! | `shards/shard-I/` | the shards' run folders |
//! | `logs/` | Slurm's output of every task and of the merge |
//!
//! [`resume`] resubmits only the shards that are missing or not finished, and a new merge job.

use std::fs;
use std::path::{Path, PathBuf};
use std::process::Command;

use anyhow::{bail, Context, Result};
use serde::{Deserialize, Serialize};

use crate::manifest::{self, Overrides};
use crate::run_files::{new_folder, write_json};
use crate::run_record::{RunRecord, Status};
use crate::shard;

/// What `experiments slurm` was asked for.
#[derive(Clone, Debug)]
pub struct SlurmOptions {
    /// The manifest.
    pub manifest: PathBuf,
    /// Number of shards (array tasks).
    pub shards: usize,
    /// `--partition`, if any.
    pub partition: Option<String>,
    /// `--time` limit per task (Slurm syntax, `2:00:00`), if any.
    pub time: Option<String>,
    /// CPUs per task; also the extraction threads. Default: the manifest's `threads`, else 1.
    pub cpus: Option<usize>,
    /// The merged run folder; default `<output>/<name>-<UTC timestamp>` as for `run`.
    pub out: Option<PathBuf>,
    /// The `experiments` binary the jobs run (default: this one).
    pub binary: PathBuf,
}

/// One submission of the array (or part of it) and its merge job.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Submission {
    /// Array job id (None when every shard was already finished).
    pub array_job: Option<String>,
    /// The array tasks submitted (`1-4`, `2,4`).
    pub tasks: String,
    /// The merge job id.
    pub merge_job: String,
}

/// `job.json` of a job folder.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct JobRecord {
    /// The manifest (absolute).
    pub manifest: PathBuf,
    /// SHA-256 of its text when the scripts were written.
    pub manifest_sha256: String,
    /// Number of shards.
    pub shards: usize,
    /// The merged run folder (absolute).
    pub out: PathBuf,
    /// CPUs per task (and extraction threads).
    pub cpus: usize,
    /// Submissions, oldest first.
    pub submissions: Vec<Submission>,
}

/// A written job folder.
#[derive(Clone, Debug)]
pub struct Prepared {
    /// The job folder (`OUT.slurm`).
    pub job_dir: PathBuf,
    /// The merged run folder.
    pub out: PathBuf,
    /// The array script.
    pub shards_script: PathBuf,
    /// The merge script.
    pub merge_script: PathBuf,
}

const JOB_JSON: &str = "job.json";
const SHARDS_SBATCH: &str = "shards.sbatch";
const MERGE_SBATCH: &str = "merge.sbatch";

fn absolute(p: &Path) -> Result<PathBuf> {
    if p.is_absolute() {
        return Ok(p.to_path_buf());
    }
    Ok(std::env::current_dir()
        .context("reading the current folder")?
        .join(p))
}

/// `OUT.slurm` beside `OUT`.
pub fn job_dir_of(out: &Path) -> PathBuf {
    let mut name = out.file_name().unwrap_or_default().to_os_string();
    name.push(".slurm");
    out.with_file_name(name)
}

/// Single-quotes `s` for bash.
fn quote(s: &str) -> String {
    format!("'{}'", s.replace('\'', r"'\''"))
}

/// Checks the manifest and the shard count, and writes the job folder with both scripts and
/// `job.json` (nothing is submitted).
pub fn prepare(opts: &SlurmOptions) -> Result<Prepared> {
    let loaded = manifest::load(&opts.manifest, &Overrides::default())?;
    let plan = &loaded.plan;
    if plan.edit.is_some() || plan.lod.is_some() {
        bail!(
            "{}: the `edit` and `lod` workloads cannot be sharded; run them with `experiments run`",
            opts.manifest.display()
        );
    }
    let ids: Vec<String> = plan.configurations.iter().map(|c| c.id.clone()).collect();
    shard::split(&ids, plan.repetitions, opts.shards)
        .with_context(|| format!("sharding {}", opts.manifest.display()))?;
    let manifest_text = &loaded.text;
    let text_manifest = manifest::parse(manifest_text, &opts.manifest)?;
    let cpus = opts.cpus.or(text_manifest.threads).unwrap_or(1);
    if !(1..=1024).contains(&cpus) {
        bail!("--cpus must be 1 to 1024, got {cpus}");
    }
    let out = match &opts.out {
        Some(o) => absolute(o)?,
        None => absolute(&new_folder(&plan.output, &plan.name)?)?,
    };
    if out.exists()
        && fs::read_dir(&out)
            .with_context(|| format!("reading {}", out.display()))?
            .next()
            .is_some()
    {
        bail!(
            "{} already exists and is not empty; choose another --out",
            out.display()
        );
    }
    let job_dir = job_dir_of(&out);
    if job_dir.exists() {
        bail!(
            "{} already exists; continue it with `experiments slurm --resume {}` or choose \
             another --out",
            job_dir.display(),
            job_dir.display()
        );
    }
    let manifest_path = absolute(&opts.manifest)?;
    let binary = absolute(&opts.binary)?;
    let workdir = std::env::current_dir().context("reading the current folder")?;
    fs::create_dir_all(job_dir.join("shards"))
        .with_context(|| format!("creating {}", job_dir.display()))?;
    fs::create_dir_all(job_dir.join("logs"))
        .with_context(|| format!("creating {}", job_dir.display()))?;

    let s = |p: &Path| quote(&p.to_string_lossy());
    let mut sbatch = vec![
        format!("#SBATCH --job-name={}-shards", plan.name),
        format!("#SBATCH --array=1-{}", opts.shards),
        format!("#SBATCH --cpus-per-task={cpus}"),
        "#SBATCH --ntasks=1".to_string(),
        format!(
            "#SBATCH --output={}",
            job_dir.join("logs/shard-%a.out").display()
        ),
        format!("#SBATCH --chdir={}", workdir.display()),
    ];
    let mut merge_sbatch = vec![
        format!("#SBATCH --job-name={}-merge", plan.name),
        "#SBATCH --cpus-per-task=1".to_string(),
        "#SBATCH --ntasks=1".to_string(),
        format!(
            "#SBATCH --output={}",
            job_dir.join("logs/merge-%j.out").display()
        ),
        format!("#SBATCH --chdir={}", workdir.display()),
    ];
    if let Some(t) = &opts.time {
        sbatch.push(format!("#SBATCH --time={t}"));
        merge_sbatch.push(format!("#SBATCH --time={t}"));
    }
    if let Some(p) = &opts.partition {
        sbatch.push(format!("#SBATCH --partition={p}"));
        merge_sbatch.push(format!("#SBATCH --partition={p}"));
    }
    let shards_script = format!(
        r#"#!/bin/bash
# Shards of the manifest {manifest_name}: one array task per shard (experiments run --shard I/N).
# Written by `experiments slurm`; edit the #SBATCH lines for your site (account, partition,
# time, memory). Submit with `sbatch {shards_file}` and the merge job with
# `sbatch --dependency=afterok:<array job id> --kill-on-invalid-dep=yes {merge_file}`
# (or let `experiments slurm --submit` / `--resume` do both).
{sbatch}

set -euo pipefail
EXPERIMENTS={binary}
MANIFEST={manifest}
SHARDS={shards_dir}
N={n}
THREADS={cpus}
I=${{SLURM_ARRAY_TASK_ID:?run this script with sbatch: no array task id}}
DIR="$SHARDS/shard-$I"

if [ -f "$DIR/run.json" ]; then
  # An earlier attempt started this shard: continue it (a finished shard returns at once).
  exec "$EXPERIMENTS" run --resume "$DIR" --quiet
fi
rm -rf "$DIR"  # a folder without run.json holds nothing to resume
exec "$EXPERIMENTS" run "$MANIFEST" --shard "$I/$N" --threads "$THREADS" --out "$DIR" --quiet
"#,
        manifest_name = opts.manifest.display(),
        shards_file = job_dir.join(SHARDS_SBATCH).display(),
        merge_file = job_dir.join(MERGE_SBATCH).display(),
        sbatch = sbatch.join("\n"),
        binary = s(&binary),
        manifest = s(&manifest_path),
        shards_dir = s(&job_dir.join("shards")),
        n = opts.shards,
    );
    let merge_script = format!(
        r#"#!/bin/bash
# Merges the {n} shards of {manifest_name} into one run folder (experiments merge). Runs after
# every shard finished (afterok); it refuses torn, missing or mismatched shards.
{sbatch}

set -euo pipefail
EXPERIMENTS={binary}
SHARDS={shards_dir}
OUT={out}
N={n}

shards=()
for i in $(seq 1 "$N"); do shards+=("$SHARDS/shard-$i"); done
exec "$EXPERIMENTS" merge "$OUT" "${{shards[@]}}"
"#,
        manifest_name = opts.manifest.display(),
        sbatch = merge_sbatch.join("\n"),
        binary = s(&binary),
        shards_dir = s(&job_dir.join("shards")),
        out = s(&out),
        n = opts.shards,
    );
    let shards_path = job_dir.join(SHARDS_SBATCH);
    let merge_path = job_dir.join(MERGE_SBATCH);
    rmt_runfolder::write_atomic(&shards_path, shards_script.as_bytes())?;
    rmt_runfolder::write_atomic(&merge_path, merge_script.as_bytes())?;
    let record = JobRecord {
        manifest: manifest_path,
        manifest_sha256: shard::manifest_hash(manifest_text),
        shards: opts.shards,
        out: out.clone(),
        cpus,
        submissions: Vec::new(),
    };
    write_json(&job_dir.join(JOB_JSON), &record)?;
    Ok(Prepared {
        job_dir,
        out,
        shards_script: shards_path,
        merge_script: merge_path,
    })
}

/// Runs `sbatch --parsable ARGS`, returning the job id.
fn sbatch(args: &[String]) -> Result<String> {
    let out = Command::new("sbatch")
        .arg("--parsable")
        .args(args)
        .output()
        .context("running sbatch (is Slurm installed and on PATH?)")?;
    if !out.status.success() {
        bail!(
            "sbatch {} failed: {}",
            args.join(" "),
            String::from_utf8_lossy(&out.stderr).trim()
        );
    }
    // `--parsable` prints `id` or `id;cluster`.
    let text = String::from_utf8_lossy(&out.stdout);
    let id = text.trim().split(';').next().unwrap_or("").to_string();
    if id.is_empty() || !id.chars().all(|c| c.is_ascii_digit()) {
        bail!("sbatch printed no job id: `{}`", text.trim());
    }
    Ok(id)
}

fn read_job(job_dir: &Path) -> Result<JobRecord> {
    let path = job_dir.join(JOB_JSON);
    serde_json::from_slice(&fs::read(&path).with_context(|| {
        format!(
            "{} is not a job folder of `experiments slurm` (cannot read job.json)",
            job_dir.display()
        )
    })?)
    .with_context(|| format!("parsing {}", path.display()))
}

/// Submits array tasks `tasks` (a Slurm list such as `1-4` or `2,4`; None when every shard is
/// finished) and a merge job depending on them; records the submission in `job.json`.
pub fn submit(job_dir: &Path, tasks: Option<&str>) -> Result<Submission> {
    let mut record = read_job(job_dir)?;
    let array_job = match tasks {
        Some(list) => Some(sbatch(&[
            format!("--array={list}"),
            job_dir.join(SHARDS_SBATCH).to_string_lossy().into_owned(),
        ])?),
        None => None,
    };
    let mut merge_args = Vec::new();
    if let Some(id) = &array_job {
        merge_args.push(format!("--dependency=afterok:{id}"));
        merge_args.push("--kill-on-invalid-dep=yes".to_string());
    }
    merge_args.push(job_dir.join(MERGE_SBATCH).to_string_lossy().into_owned());
    let merge_job = sbatch(&merge_args)?;
    let submission = Submission {
        array_job,
        tasks: tasks.unwrap_or("").to_string(),
        merge_job,
    };
    record.submissions.push(submission.clone());
    write_json(&job_dir.join(JOB_JSON), &record)?;
    Ok(submission)
}

/// Which shards of a job folder are finished (their run folder is complete).
pub fn shard_states(job_dir: &Path, shards: usize) -> Vec<bool> {
    (1..=shards)
        .map(|i| {
            let folder = job_dir.join("shards").join(format!("shard-{i}"));
            fs::read(folder.join("run.json"))
                .ok()
                .and_then(|b| serde_json::from_slice::<RunRecord>(&b).ok())
                .is_some_and(|r| r.status == Status::Finished && r.shard.is_some())
        })
        .collect()
}

/// A Slurm task list (`1-3,5`) of 1-based indices.
pub fn task_list(tasks: &[usize]) -> String {
    let mut parts = Vec::new();
    let mut i = 0;
    while i < tasks.len() {
        let start = tasks[i];
        let mut end = start;
        while i + 1 < tasks.len() && tasks[i + 1] == end + 1 {
            i += 1;
            end = tasks[i];
        }
        parts.push(if start == end {
            start.to_string()
        } else {
            format!("{start}-{end}")
        });
        i += 1;
    }
    parts.join(",")
}

/// Jobs of the job folder that Slurm still holds (pending or running), from `squeue`.
fn queued_jobs(record: &JobRecord) -> Result<Vec<String>> {
    let ids: Vec<&str> = record
        .submissions
        .iter()
        .flat_map(|s| {
            s.array_job
                .iter()
                .map(String::as_str)
                .chain([s.merge_job.as_str()])
        })
        .collect();
    if ids.is_empty() {
        return Ok(Vec::new());
    }
    let out = Command::new("squeue")
        .args(["-h", "-o", "%i %T", "-j", &ids.join(",")])
        .output()
        .context("running squeue (is Slurm installed and on PATH?)")?;
    // squeue fails for job ids it no longer knows; that means none of them is queued.
    if !out.status.success() {
        return Ok(Vec::new());
    }
    Ok(String::from_utf8_lossy(&out.stdout)
        .lines()
        .map(|l| l.trim().to_string())
        .filter(|l| !l.is_empty())
        .collect())
}

/// What [`resume`] did.
#[derive(Clone, Debug)]
pub struct Resumed {
    /// The job folder.
    pub job_dir: PathBuf,
    /// The merged run folder.
    pub out: PathBuf,
    /// Shards resubmitted (1-based).
    pub resubmitted: Vec<usize>,
    /// The new submission (None when the run was already merged).
    pub submission: Option<Submission>,
}

/// The job folder for `dir`: `dir` itself when it holds `job.json`, else `dir.slurm` (the run
/// folder was given).
pub fn find_job_dir(dir: &Path) -> Result<PathBuf> {
    if dir.join(JOB_JSON).is_file() {
        return Ok(dir.to_path_buf());
    }
    let beside = job_dir_of(dir);
    if beside.join(JOB_JSON).is_file() {
        return Ok(beside);
    }
    bail!(
        "{} is not a job folder of `experiments slurm` and has no {} beside it",
        dir.display(),
        beside.display()
    )
}

/// Resubmits the shards of a job folder (or of the run folder it merges into) that are missing
/// or not finished, and a merge job depending on them. Refuses while jobs of the folder are still
/// queued (resubmitting would run shards twice).
pub fn resume(dir: &Path) -> Result<Resumed> {
    let job_dir = find_job_dir(dir)?;
    let record = read_job(&job_dir)?;
    let merged = fs::read(record.out.join("run.json"))
        .ok()
        .and_then(|b| serde_json::from_slice::<RunRecord>(&b).ok())
        .is_some_and(|r| r.status == Status::Finished && r.merged_from.is_some());
    if merged {
        return Ok(Resumed {
            job_dir,
            out: record.out,
            resubmitted: Vec::new(),
            submission: None,
        });
    }
    let queued = queued_jobs(&record)?;
    if !queued.is_empty() {
        bail!(
            "jobs of {} are still queued or running ({}); wait for them to end or cancel them \
             with scancel, then resume",
            job_dir.display(),
            queued.join(", ")
        );
    }
    let text = fs::read_to_string(&record.manifest)
        .with_context(|| format!("reading {}", record.manifest.display()))?;
    if shard::manifest_hash(&text) != record.manifest_sha256 {
        bail!(
            "{} changed since the shards were submitted (its SHA-256 differs from job.json); \
             shards of two manifests cannot be merged: start a new run",
            record.manifest.display()
        );
    }
    let todo: Vec<usize> = shard_states(&job_dir, record.shards)
        .iter()
        .enumerate()
        .filter(|(_, done)| !**done)
        .map(|(i, _)| i + 1)
        .collect();
    let list = (!todo.is_empty()).then(|| task_list(&todo));
    let submission = submit(&job_dir, list.as_deref())?;
    Ok(Resumed {
        job_dir,
        out: record.out,
        resubmitted: todo,
        submission: Some(submission),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn task_lists_compress_runs() {
        assert_eq!(task_list(&[1, 2, 3, 5, 7, 8]), "1-3,5,7-8");
        assert_eq!(task_list(&[4]), "4");
        assert_eq!(task_list(&[]), "");
    }

    #[test]
    fn quoting_survives_quotes() {
        assert_eq!(quote("a'b c"), r"'a'\''b c'");
    }

    #[test]
    fn job_folder_sits_beside_the_run() {
        assert_eq!(
            job_dir_of(Path::new("/r/ci-1")),
            PathBuf::from("/r/ci-1.slurm")
        );
    }
}
