//! Sharded runs (`run --shard I/N`) merged back (`experiments merge`): the merged folder equals
//! an unsharded run (timings and run ids aside), merging is byte-for-byte repeatable, and every
//! refusal names what is wrong. No Slurm needed.

use std::fs;
use std::io::Write;
use std::path::{Path, PathBuf};

use experiments::manifest::Overrides;
use experiments::merge;
use experiments::run_record::Status;
use experiments::runner::{self, RunOptions};
use experiments::shard::ShardSpec;
use rmt_runfolder::Table;

fn quiet() -> RunOptions {
    RunOptions {
        quiet: true,
        stop_after: None,
    }
}

fn ci_manifest() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("manifests/ci.toml")
}

/// A small manifest: 3 configurations x 3 repetitions, tiny grids.
const SMALL: &str = r#"name = "small"
repetitions = 3
warmup = 1
threads = 1

[[objects]]
name = "asteroid"
resolution = 6

[[objects]]
name = "sphere"
resolution = 6
radius = 0.8

[[configurations]]
object = "asteroid"
lattice = "bcdl"
clustering = "integrated"

[[configurations]]
object = "asteroid"
lattice = "bcdl"

[[configurations]]
object = "sphere"
method = "mc"
"#;

fn write_manifest(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    fs::write(&p, text).unwrap();
    p
}

fn run_shards(manifest: &Path, dir: &Path, n: usize) -> Vec<PathBuf> {
    (1..=n)
        .map(|i| {
            let folder = dir.join(format!("shard-{i}"));
            let report = runner::start_shard(
                manifest,
                &Overrides::default(),
                Some(&folder),
                &quiet(),
                Some(ShardSpec { index: i, count: n }),
            )
            .unwrap();
            assert_eq!(report.status, Status::Finished);
            folder
        })
        .collect()
}

/// Table with the time columns and run ids removed.
fn without_times(path: &Path) -> Vec<Vec<String>> {
    let t = Table::read(path).unwrap();
    let keep: Vec<usize> = (0..t.header.len())
        .filter(|&i| {
            let h = &t.header[i];
            h != "run_id" && !h.starts_with("t_") && !h.starts_with("share_")
        })
        .collect();
    std::iter::once(keep.iter().map(|&i| t.header[i].clone()).collect())
        .chain(
            t.rows
                .iter()
                .map(|r| keep.iter().map(|&i| r[i].clone()).collect()),
        )
        .collect()
}

fn files_of(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else {
                let rel = p.strip_prefix(dir).unwrap().to_string_lossy().into_owned();
                out.push((rel, fs::read(&p).unwrap()));
            }
        }
    }
    out.sort();
    out
}

fn assert_same_as_full(full: &Path, merged: &Path) {
    for f in ["raw.csv", "summary.csv"] {
        assert_eq!(
            without_times(&full.join(f)),
            without_times(&merged.join(f)),
            "{f}"
        );
    }
    assert_eq!(
        fs::read(full.join("configurations.csv")).unwrap(),
        fs::read(merged.join("configurations.csv")).unwrap()
    );
    assert_eq!(
        fs::read(full.join("manifest.toml")).unwrap(),
        fs::read(merged.join("manifest.toml")).unwrap()
    );
    let meshes = |d: &Path| files_of(&d.join("meshes"));
    let a = meshes(full);
    assert!(!a.is_empty());
    assert_eq!(a, meshes(merged), "meshes differ");
}

#[test]
fn ci_manifest_in_four_shards_merges_into_the_unsharded_run() {
    let dir = tempfile::tempdir().unwrap();
    let full = dir.path().join("full");
    runner::start(&ci_manifest(), &Overrides::default(), Some(&full), &quiet()).unwrap();
    let shards = run_shards(&ci_manifest(), dir.path(), 4);
    // Every shard is a normal run folder marked as a shard.
    for (i, s) in shards.iter().enumerate() {
        let rec: serde_json::Value =
            serde_json::from_slice(&fs::read(s.join("run.json")).unwrap()).unwrap();
        assert_eq!(rec["shard"]["index"], i + 1);
        assert_eq!(rec["shard"]["count"], 4);
        assert_eq!(rec["shard"]["split"], "configurations");
        assert!(rec["provenance"]["cpu_model"].is_string() || rec["provenance"]["cores"].is_u64());
        assert!(s.join("summary.csv").is_file());
    }
    let merged = dir.path().join("a/merged");
    let report = merge::merge(&merged, &shards).unwrap();
    assert_eq!(report.shards, 4);
    assert_same_as_full(&full, &merged);
    let rec: serde_json::Value =
        serde_json::from_slice(&fs::read(merged.join("run.json")).unwrap()).unwrap();
    assert_eq!(rec["status"], "finished");
    assert!(rec.get("shard").is_none());
    let from = rec["merged_from"].as_array().unwrap();
    assert_eq!(from.len(), 4);
    for (i, s) in from.iter().enumerate() {
        assert_eq!(s["shard"]["index"], i + 1);
        assert!(s["sessions"][0]["provenance"]["os"].is_string());
    }
    assert_eq!(rec["sessions"].as_array().unwrap().len(), 4);
    assert!(merged.join("paper_comparison.csv").is_file());
    assert!(merged.join("progress.json").is_file());

    // Again, arguments in another order: byte-identical, timings included.
    let mut reversed = shards.clone();
    reversed.reverse();
    let again = dir.path().join("b/merged");
    merge::merge(&again, &reversed).unwrap();
    assert_eq!(files_of(&merged), files_of(&again));
    // No temporary folder left beside it.
    let names: Vec<String> = fs::read_dir(dir.path().join("a"))
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(names, ["merged"]);
}

#[test]
fn more_shards_than_configurations_split_repetitions_in_blocks() {
    let dir = tempfile::tempdir().unwrap();
    let m = write_manifest(dir.path(), "small.toml", SMALL);
    let full = dir.path().join("full");
    runner::start(&m, &Overrides::default(), Some(&full), &quiet()).unwrap();
    let shards = run_shards(&m, dir.path(), 7);
    let rec: serde_json::Value =
        serde_json::from_slice(&fs::read(shards[1].join("run.json")).unwrap()).unwrap();
    assert_eq!(rec["shard"]["split"], "repetition-blocks");
    let raw = Table::read(&shards[1].join("raw.csv")).unwrap();
    assert_eq!(raw.rows.len(), 1);
    assert_eq!(raw.get(0, "id"), Some("as_bi"));
    assert_eq!(raw.get(0, "repetition"), Some("2"));
    let merged = dir.path().join("merged");
    merge::merge(&merged, &shards).unwrap();
    assert_same_as_full(&full, &merged);
    let summary = Table::read(&merged.join("summary.csv")).unwrap();
    assert!(
        (0..summary.rows.len()).all(|i| summary.get(i, "repetitions") == Some("3")),
        "repetitions"
    );
}

#[test]
fn a_sharded_run_resumes_after_an_interruption() {
    let dir = tempfile::tempdir().unwrap();
    let m = write_manifest(dir.path(), "small.toml", SMALL);
    let folder = dir.path().join("shard");
    let stop = RunOptions {
        quiet: true,
        stop_after: Some(1),
    };
    let spec = Some(ShardSpec { index: 1, count: 5 });
    // Shard 1 of 5 over 3 configurations: repetition blocks. Stopped before its one unit ends.
    let first = runner::start_shard(&m, &Overrides::default(), Some(&folder), &stop, spec).unwrap();
    assert_eq!(first.status, Status::Finished);
    // Shard 1 of 2: two whole configurations; stop after one, resume.
    let folder = dir.path().join("shard2");
    let spec = Some(ShardSpec { index: 1, count: 2 });
    let first = runner::start_shard(&m, &Overrides::default(), Some(&folder), &stop, spec).unwrap();
    assert_eq!(first.status, Status::Stopped);
    assert!(
        merge::merge(&dir.path().join("x"), std::slice::from_ref(&folder))
            .unwrap_err()
            .to_string()
            .contains("not marked complete")
    );
    let second = runner::resume(&folder, &quiet()).unwrap();
    assert_eq!(second.status, Status::Finished);
    assert_eq!(second.configurations_total, 2);
    let raw = Table::read(&folder.join("raw.csv")).unwrap();
    let ids: Vec<&str> = raw.rows.iter().map(|r| r[1].as_str()).collect();
    assert_eq!(ids, ["as_bi", "as_bi", "as_bi", "ss_mu", "ss_mu", "ss_mu"]);
}

fn err_of(out: &Path, shards: &[PathBuf]) -> String {
    format!("{:#}", merge::merge(out, shards).unwrap_err())
}

#[test]
fn merge_refuses_with_a_message_naming_what_is_wrong() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let m = write_manifest(d, "small.toml", SMALL);
    let shards = run_shards(&m, &d.join("ok"), 3);
    let out = d.join("out");

    // Missing work units: shard 2 of 3 not given.
    let e = err_of(&out, &[shards[0].clone(), shards[2].clone()]);
    assert!(
        e.contains("missing work units") && e.contains("shard 2/3"),
        "{e}"
    );

    // Duplicated work units: shard 2 given twice (a copy).
    let copy = d.join("copy-of-2");
    copy_dir(&shards[1], &copy);
    let e = err_of(
        &out,
        &[
            shards[0].clone(),
            shards[1].clone(),
            copy.clone(),
            shards[2].clone(),
        ],
    );
    assert!(e.contains("duplicated") && e.contains("as_bu"), "{e}");

    // Different manifests (a comment changes the content hash).
    let other = write_manifest(d, "other.toml", &format!("# changed\n{SMALL}"));
    let other_shards = run_shards(&other, &d.join("other"), 3);
    let e = err_of(
        &out,
        &[
            shards[0].clone(),
            other_shards[1].clone(),
            shards[2].clone(),
        ],
    );
    assert!(e.contains("different manifests (content hash)"), "{e}");

    // Different commits.
    let moved = d.join("moved-2");
    copy_dir(&shards[1], &moved);
    edit_json(&moved.join("run.json"), |v| {
        v["provenance"]["git_commit"] = "0123456789abcdef".into();
    });
    let e = err_of(&out, &[shards[0].clone(), moved, shards[2].clone()]);
    assert!(
        e.contains("different commits") && e.contains("0123456789abcdef"),
        "{e}"
    );

    // Torn shard: an unfinished row after the recorded ones.
    let torn = d.join("torn-3");
    copy_dir(&shards[2], &torn);
    fs::OpenOptions::new()
        .append(true)
        .open(torn.join("raw.csv"))
        .unwrap()
        .write_all(b"shard-3,ss_mu,sphere,sph")
        .unwrap();
    let e = err_of(&out, &[shards[0].clone(), shards[1].clone(), torn.clone()]);
    assert!(e.contains("torn") && e.contains("unfinished"), "{e}");

    // Torn shard: not marked complete.
    let running = d.join("running-3");
    copy_dir(&shards[2], &running);
    edit_json(&running.join("run.json"), |v| {
        v["status"] = "running".into()
    });
    let e = err_of(&out, &[shards[0].clone(), shards[1].clone(), running]);
    assert!(
        e.contains("torn") && e.contains("not marked complete"),
        "{e}"
    );

    // A row deleted (and progress rewritten to match): missing rows.
    let short = d.join("short-3");
    copy_dir(&shards[2], &short);
    let text = fs::read_to_string(short.join("raw.csv")).unwrap();
    let cut: String = text.lines().take(3).map(|l| format!("{l}\n")).collect();
    fs::write(short.join("raw.csv"), &cut).unwrap();
    edit_json(&short.join("progress.json"), |v| {
        v["raw_bytes"] = cut.len().into();
    });
    let e = err_of(&out, &[shards[0].clone(), shards[1].clone(), short]);
    assert!(e.contains("raw.csv holds 2 rows, its work units 3"), "{e}");

    // Not a shard.
    let plain = d.join("plain");
    runner::start(&m, &Overrides::default(), Some(&plain), &quiet()).unwrap();
    let e = err_of(&out, std::slice::from_ref(&plain));
    assert!(e.contains("is not a shard"), "{e}");

    // Shards of another count.
    let two = run_shards(&m, &d.join("two"), 2);
    let e = err_of(
        &out,
        &[shards[0].clone(), two[1].clone(), shards[2].clone()],
    );
    assert!(e.contains("different shard counts"), "{e}");

    // OUT not empty.
    fs::create_dir_all(&out).unwrap();
    fs::write(out.join("x"), "x").unwrap();
    let e = err_of(&out, &shards);
    assert!(e.contains("not empty"), "{e}");

    // Nothing half-written by the refusals; the good shards still merge.
    let good = d.join("good");
    merge::merge(&good, &shards).unwrap();
    assert_eq!(
        Table::read(&good.join("raw.csv")).unwrap().rows.len(),
        9,
        "3 configurations x 3 repetitions"
    );
}

fn copy_dir(from: &Path, to: &Path) {
    fs::create_dir_all(to).unwrap();
    for e in fs::read_dir(from).unwrap() {
        let e = e.unwrap();
        let p = e.path();
        if p.is_dir() {
            copy_dir(&p, &to.join(e.file_name()));
        } else {
            fs::copy(&p, to.join(e.file_name())).unwrap();
        }
    }
}

fn edit_json(path: &Path, f: impl FnOnce(&mut serde_json::Value)) {
    let mut v: serde_json::Value = serde_json::from_slice(&fs::read(path).unwrap()).unwrap();
    f(&mut v);
    fs::write(path, serde_json::to_vec_pretty(&v).unwrap()).unwrap();
}
