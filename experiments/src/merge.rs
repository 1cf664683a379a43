//! `experiments merge OUT SHARD_DIR...`: combines the run folders of `run --shard I/N` (see
//! [`crate::shard`]) into one run folder with everything an unsharded run has and
//! `experiments report` reads: `manifest.toml`, `configurations.csv`, `raw.csv` (rows in plan
//! order, then repetition order, each keeping its shard's `run_id`), `summary.csv` and
//! `paper_comparison.csv` recomputed from the merged rows, `meshes/`, `progress.json`, and a
//! `run.json` whose `merged_from` lists every shard with its units and sessions (machine, build,
//! times).
//!
//! **Refusals**, each naming the folder and what is wrong, before anything is written:
//! a folder that is not a shard; shards of different manifests (SHA-256 of the manifest text),
//! options (repetitions, warm-up, threads, meshes), commits or shard counts; a torn shard
//! (not finished, `raw.csv` longer than its recorded rows, a row cut short, missing rows or
//! meshes); missing or duplicated work units; meshes of one configuration that differ between the
//! shards holding its repetition blocks.
//!
//! **Deterministic.** The output depends only on the shards' contents: the order of the
//! arguments does not matter, no time or path of the merge is recorded (the merged `run_id` is
//! OUT's folder name), so merging the same shards twice gives byte-identical files. The result
//! is built in a temporary sibling folder and renamed to OUT at the end: OUT is either absent,
//! or complete.

use std::collections::BTreeMap;
use std::fs;
use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};

use rmt_runfolder::layout::{
    CONFIGURATIONS_CSV, MANIFEST_COPY, MESHES, PROGRESS_JSON, RAW_CSV, RUN_JSON,
};
use rmt_runfolder::schema::RAW_PREFIX;
use rmt_runfolder::{csv_bytes, write_atomic, Table};

use crate::manifest::Plan;
use crate::run_csv::{configurations_csv, raw_header};
use crate::run_files::write_json;
use crate::run_record::{plan_of, read_record, MergedShard, Progress, RunRecord, Status};
use crate::runner::write_summaries;
use crate::shard::{self, ShardSpec, WorkUnit};

/// The column of `raw.csv` that numbers the repetitions.
const REPETITION: usize = RAW_PREFIX.len() - 1;

/// What a merge produced.
#[derive(Clone, Debug)]
pub struct MergeReport {
    /// The merged run folder.
    pub folder: PathBuf,
    /// Shards merged.
    pub shards: usize,
    /// Configurations in the merged run.
    pub configurations: usize,
    /// Rows of the merged `raw.csv`.
    pub rows: usize,
}

/// One shard folder, read and checked on its own.
struct ShardDir {
    folder: PathBuf,
    record: RunRecord,
    raw: Table,
}

/// Reads one shard folder and checks it is complete: finished, `raw.csv` exactly as long as its
/// recorded rows, every row whole, exactly the rows of its work units, its meshes present.
fn read_shard(folder: &Path) -> Result<ShardDir> {
    let record = read_record(folder, "a run folder")?;
    let Some(shard) = &record.shard else {
        bail!(
            "{} is not a shard (its run.json has no `shard` entry): merge takes folders made by \
             `experiments run MANIFEST --shard I/N`",
            folder.display()
        );
    };
    let name = format!(
        "shard {}/{} ({})",
        shard.index,
        shard.count,
        folder.display()
    );
    if record.status != Status::Finished {
        bail!(
            "{name} is torn: it is not marked complete (status {:?}); finish it with \
             `experiments run --resume {}`",
            record.status,
            folder.display()
        );
    }
    let progress_path = folder.join(PROGRESS_JSON);
    let progress: Progress = serde_json::from_slice(
        &fs::read(&progress_path)
            .with_context(|| format!("{name} is torn: cannot read progress.json"))?,
    )
    .with_context(|| format!("parsing {}", progress_path.display()))?;
    let raw_path = folder.join(RAW_CSV);
    let bytes = fs::read(&raw_path).with_context(|| format!("{name}: cannot read raw.csv"))?;
    if bytes.len() as u64 != progress.raw_bytes {
        bail!(
            "{name} is torn: raw.csv has {} bytes but its finished work units hold {} (an \
             unfinished or edited CSV)",
            bytes.len(),
            progress.raw_bytes
        );
    }
    if !bytes.ends_with(b"\n") {
        bail!("{name} is torn: raw.csv does not end with a whole row");
    }
    let raw = Table::read(&raw_path).with_context(|| format!("{name} is torn: raw.csv"))?;
    if raw.header != raw_header() {
        bail!(
            "{name}: raw.csv has other columns than this version writes; merge with the version \
             that ran it"
        );
    }
    let keys: Vec<String> = shard
        .units
        .iter()
        .map(|u| u.key(record.settings.repetitions))
        .collect();
    if progress.completed != keys {
        bail!(
            "{name} is torn: progress.json lists {} finished work units, run.json {}",
            progress.completed.len(),
            keys.len()
        );
    }
    // Exactly the rows of its units.
    let mut expected: Vec<(String, usize)> = shard
        .units
        .iter()
        .flat_map(|u| (u.first..=u.last).map(move |r| (u.id.clone(), r)))
        .collect();
    let mut got = Vec::with_capacity(raw.rows.len());
    for (i, row) in raw.rows.iter().enumerate() {
        let rep = row[REPETITION].parse::<usize>().with_context(|| {
            format!(
                "{name}: raw.csv row {}: repetition `{}` is not a number",
                i + 2,
                row[REPETITION]
            )
        })?;
        got.push((row[1].clone(), rep));
    }
    expected.sort();
    got.sort();
    if expected != got {
        let missing: Vec<String> = expected
            .iter()
            .filter(|e| !got.contains(e))
            .map(|(id, r)| format!("{id}#{r}"))
            .take(5)
            .collect();
        bail!(
            "{name}: raw.csv holds {} rows, its work units {} (missing e.g. [{}])",
            got.len(),
            expected.len(),
            missing.join(", ")
        );
    }
    if record.settings.save_meshes {
        for u in &shard.units {
            let mesh = folder.join(MESHES).join(format!("{}.ply", u.id));
            if !mesh.is_file() {
                bail!("{name} is torn: {} is missing", mesh.display());
            }
        }
    }
    Ok(ShardDir {
        folder: folder.to_path_buf(),
        record,
        raw,
    })
}

/// Checks that the shard folders are complete pieces of one run and together hold every work
/// unit exactly once. Returns them sorted by shard index, with the plan.
fn check_shards(dirs: &[PathBuf]) -> Result<(Vec<ShardDir>, Plan)> {
    if dirs.is_empty() {
        bail!("give the shard folders to merge");
    }
    let mut shards = Vec::with_capacity(dirs.len());
    for d in dirs {
        shards.push(read_shard(d)?);
    }
    let shard_of = |s: &ShardDir| s.record.shard.clone().expect("checked in read_shard");
    let first = &shards[0];
    let f = shard_of(first);
    let differ = |what: &str, a: &ShardDir, av: String, b: &ShardDir, bv: String| {
        anyhow::anyhow!(
            "shards of different {what}: {} has {av}, {} has {bv}; merge only shards of one run",
            a.folder.display(),
            b.folder.display()
        )
    };
    for s in &shards[1..] {
        let r = shard_of(s);
        if r.manifest_sha256 != f.manifest_sha256 {
            return Err(differ(
                "manifests (content hash)",
                first,
                format!("manifest sha256 {}", f.manifest_sha256),
                s,
                format!("manifest sha256 {}", r.manifest_sha256),
            ));
        }
        if s.record.provenance.git_commit != first.record.provenance.git_commit {
            return Err(differ(
                "commits",
                first,
                format!("{:?}", first.record.provenance.git_commit),
                s,
                format!("{:?}", s.record.provenance.git_commit),
            ));
        }
        if s.record.settings != first.record.settings {
            return Err(differ(
                "options",
                first,
                format!("{:?}", first.record.settings),
                s,
                format!("{:?}", s.record.settings),
            ));
        }
        if r.count != f.count {
            return Err(differ(
                "shard counts",
                first,
                format!("{} shards", f.count),
                s,
                format!("{} shards", r.count),
            ));
        }
    }
    // Every session of a shard must come from the commit its run started with.
    for s in &shards {
        for session in &s.record.sessions {
            if session.provenance.git_commit != s.record.provenance.git_commit {
                bail!(
                    "{}: resumed with another commit ({:?}, started with {:?}); its rows mix \
                     builds",
                    s.folder.display(),
                    session.provenance.git_commit,
                    s.record.provenance.git_commit
                );
            }
        }
    }

    let plan = plan_of(&first.folder, &first.record)
        .with_context(|| format!("expanding the manifest of {}", first.folder.display()))?;
    let ids: Vec<String> = plan.configurations.iter().map(|c| c.id.clone()).collect();
    let (split, expected) = shard::split(&ids, plan.repetitions, f.count)?;
    // Duplicates first (the same unit in two folders), then each folder's units against the
    // split, then what is missing.
    let mut owner: BTreeMap<&WorkUnit, &Path> = BTreeMap::new();
    for s in &shards {
        for u in &s.record.shard.as_ref().expect("checked").units {
            if let Some(other) = owner.insert(u, &s.folder) {
                bail!(
                    "work unit {} (repetitions {}-{}) is duplicated: it is in {} and {}",
                    u.id,
                    u.first,
                    u.last,
                    other.display(),
                    s.folder.display()
                );
            }
        }
    }
    for s in &shards {
        let r = shard_of(s);
        let spec = ShardSpec {
            index: r.index,
            count: r.count,
        };
        if r.split != split || expected.get(r.index.wrapping_sub(1)) != Some(&r.units) {
            bail!(
                "{}: shard {spec} records other work units than the manifest's split gives; the \
                 folder was edited or made by another version",
                s.folder.display()
            );
        }
    }
    let mut missing = Vec::new();
    for (k, units) in expected.iter().enumerate() {
        if !shards.iter().any(|s| shard_of(s).index == k + 1) {
            let names: Vec<String> = units
                .iter()
                .map(|u| u.key(plan.repetitions))
                .take(4)
                .collect();
            let more = if units.len() > 4 { ", ..." } else { "" };
            missing.push(format!(
                "shard {}/{} ({}{more})",
                k + 1,
                f.count,
                names.join(", ")
            ));
        }
    }
    if !missing.is_empty() {
        bail!(
            "missing work units: {} of {} shards not given: {}",
            missing.len(),
            f.count,
            missing.join("; ")
        );
    }
    shards.sort_by_key(|s| shard_of(s).index);
    Ok((shards, plan))
}

/// Merges the shard folders `dirs` into the new run folder `out` (absent or empty); see the
/// [module documentation](self).
pub fn merge(out: &Path, dirs: &[PathBuf]) -> Result<MergeReport> {
    if out.exists() {
        let empty = fs::read_dir(out)
            .with_context(|| format!("reading {}", out.display()))?
            .next()
            .is_none();
        if !empty {
            bail!(
                "{} already exists and is not empty; merge into a new folder",
                out.display()
            );
        }
    }
    let (shards, plan) = check_shards(dirs)?;

    // Rows in plan order, then repetition order.
    let order: BTreeMap<&str, usize> = plan
        .configurations
        .iter()
        .enumerate()
        .map(|(i, c)| (c.id.as_str(), i))
        .collect();
    let mut rows: Vec<(usize, usize, &Vec<String>)> = Vec::new();
    for s in &shards {
        for row in &s.raw.rows {
            let rep: usize = row[REPETITION].parse().unwrap_or(0);
            rows.push((order[row[1].as_str()], rep, row));
        }
    }
    rows.sort_by_key(|&(c, r, _)| (c, r));

    // Meshes: one per configuration; blocks of one configuration on several shards must agree.
    let mut meshes: BTreeMap<String, (PathBuf, Vec<u8>)> = BTreeMap::new();
    if plan.save_meshes {
        for s in &shards {
            for u in &s.record.shard.as_ref().expect("checked").units {
                let path = s.folder.join(MESHES).join(format!("{}.ply", u.id));
                let bytes =
                    fs::read(&path).with_context(|| format!("reading {}", path.display()))?;
                match meshes.get(&u.id) {
                    Some((other, b)) if *b != bytes => bail!(
                        "configuration {}: the meshes of its repetition blocks differ ({} and \
                         {}); extraction was not deterministic across the shards' machines",
                        u.id,
                        other.display(),
                        path.display()
                    ),
                    Some(_) => {}
                    None => {
                        meshes.insert(u.id.clone(), (path, bytes));
                    }
                }
            }
        }
    }

    // Build next to OUT, then rename.
    let name = out
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .with_context(|| format!("{}: not a folder name", out.display()))?;
    let parent = out
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    fs::create_dir_all(parent).with_context(|| format!("creating {}", parent.display()))?;
    let temp = parent.join(format!(".{name}.merging"));
    if temp.exists() {
        fs::remove_dir_all(&temp).with_context(|| format!("removing {}", temp.display()))?;
    }
    fs::create_dir_all(&temp).with_context(|| format!("creating {}", temp.display()))?;
    let result = (|| -> Result<MergeReport> {
        let first = &shards[0];
        fs::copy(first.folder.join(MANIFEST_COPY), temp.join(MANIFEST_COPY))
            .with_context(|| format!("copying {}", first.folder.join(MANIFEST_COPY).display()))?;
        write_atomic(&temp.join(CONFIGURATIONS_CSV), &configurations_csv(&plan)?)?;
        let mut all = vec![raw_header()];
        all.extend(rows.iter().map(|(_, _, r)| (*r).clone()));
        let raw_bytes = csv_bytes(&all)?;
        write_atomic(&temp.join(RAW_CSV), &raw_bytes)?;
        if plan.save_meshes {
            fs::create_dir_all(temp.join(MESHES))?;
            for (id, (_, bytes)) in &meshes {
                write_atomic(&temp.join(MESHES).join(format!("{id}.ply")), bytes)?;
            }
        }
        let files = write_summaries(&temp, &plan)?;
        let progress = Progress {
            completed: plan.configurations.iter().map(|c| c.id.clone()).collect(),
            raw_bytes: raw_bytes.len() as u64,
        };
        write_json(&temp.join(PROGRESS_JSON), &progress)?;
        let mut record = first.record.clone();
        record.run_id = name.clone();
        record.status = Status::Finished;
        record.shard = None;
        record.sessions = shards
            .iter()
            .flat_map(|s| s.record.sessions.iter().cloned())
            .collect();
        record.merged_from = Some(
            shards
                .iter()
                .map(|s| MergedShard {
                    run_id: s.record.run_id.clone(),
                    shard: s.record.shard.clone().expect("checked"),
                    sessions: s.record.sessions.clone(),
                })
                .collect(),
        );
        record.files = files;
        write_json(&temp.join(RUN_JSON), &record)?;
        Ok(MergeReport {
            folder: out.to_path_buf(),
            shards: shards.len(),
            configurations: plan.configurations.len(),
            rows: rows.len(),
        })
    })();
    match result {
        Ok(report) => {
            if out.exists() {
                fs::remove_dir(out).with_context(|| format!("replacing {}", out.display()))?;
            }
            fs::rename(&temp, out)
                .with_context(|| format!("renaming {} to {}", temp.display(), out.display()))?;
            Ok(report)
        }
        Err(e) => {
            let _ = fs::remove_dir_all(&temp);
            Err(e)
        }
    }
}
