//! End-to-end tests of the runner on `manifests/ci.toml`: files and columns, summary against raw
//! rows, meshes, provenance, the paper comparison, and resume after an interruption.

use std::collections::HashMap;
use std::fs;
use std::io::Write;
use std::path::{Path, PathBuf};

use experiments::manifest::{self, Overrides};
use experiments::run_csv::raw_header;
use experiments::run_record::Status;
use experiments::runner::{self, RunOptions};
use rmt_runfolder::schema::{is_time_column, RAW_PREFIX};
use rmt_runfolder::Table;

fn ci_manifest() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("manifests/ci.toml")
}

fn quiet() -> RunOptions {
    RunOptions {
        quiet: true,
        stop_after: None,
    }
}

fn ci_plan() -> manifest::Plan {
    manifest::load(&ci_manifest(), &Overrides::default())
        .unwrap()
        .plan
}

/// Raw rows keyed by (id, repetition) with time columns and the run id removed.
fn rows_without_times(folder: &Path) -> Vec<Vec<String>> {
    let raw = Table::read(&folder.join("raw.csv")).unwrap();
    let keep: Vec<usize> = (0..raw.header.len())
        .filter(|&i| {
            let h = &raw.header[i];
            h != "run_id" && !is_time_column(h)
        })
        .collect();
    raw.rows
        .iter()
        .map(|r| keep.iter().map(|&i| r[i].clone()).collect())
        .collect()
}

#[test]
fn ci_manifest_runs_end_to_end_into_the_documented_files() {
    let dir = tempfile::tempdir().unwrap();
    let folder = dir.path().join("run");
    let report = runner::start(
        &ci_manifest(),
        &Overrides::default(),
        Some(&folder),
        &quiet(),
    )
    .unwrap();
    assert_eq!(report.status, Status::Finished);
    let plan = ci_plan();
    let n = plan.configurations.len();
    assert_eq!(report.configurations_run, n);

    // configurations.csv: the documented columns, one row per configuration, in plan order.
    let configs = Table::read(&folder.join("configurations.csv")).unwrap();
    assert_eq!(
        &configs.header[..5],
        ["id", "object", "lattice", "clustering", "method"]
    );
    let ids: Vec<&str> = configs.rows.iter().map(|r| r[0].as_str()).collect();
    let plan_ids: Vec<&str> = plan.configurations.iter().map(|c| c.id.as_str()).collect();
    assert_eq!(ids, plan_ids);

    // raw.csv: configurations x repetitions rows, the prefix then every measurement key.
    let raw = Table::read(&folder.join("raw.csv")).unwrap();
    assert_eq!(raw.header, raw_header());
    assert_eq!(
        &raw.header[..RAW_PREFIX.len()],
        RAW_PREFIX.map(String::from).as_slice()
    );
    assert_eq!(raw.rows.len(), n * plan.repetitions);
    for (k, c) in plan.configurations.iter().enumerate() {
        for rep in 0..plan.repetitions {
            let r = k * plan.repetitions + rep;
            assert_eq!(raw.get(r, "id"), Some(c.id.as_str()));
            assert_eq!(
                raw.get(r, "repetition"),
                Some((rep + 1).to_string().as_str())
            );
            assert_eq!(raw.get(r, "run_id"), Some("run"));
        }
    }

    // summary.csv matches raw.csv.
    let summary = Table::read(&folder.join("summary.csv")).unwrap();
    assert_eq!(summary.rows.len(), n);
    for s in 0..n {
        let id = summary.get(s, "id").unwrap();
        let members: Vec<usize> = (0..raw.rows.len())
            .filter(|&r| raw.get(r, "id") == Some(id))
            .collect();
        assert_eq!(
            summary.get(s, "repetitions").unwrap(),
            members.len().to_string()
        );
        let times: Vec<f64> = members
            .iter()
            .map(|&r| raw.get(r, "t_total_s").unwrap().parse().unwrap())
            .collect();
        let mean = times.iter().sum::<f64>() / times.len() as f64;
        let got: f64 = summary.get(s, "t_total_s_mean").unwrap().parse().unwrap();
        assert!(
            (got - mean).abs() <= 1e-12 * mean.max(1e-9),
            "{id}: {got} vs {mean}"
        );
        let min: f64 = summary.get(s, "t_total_s_min").unwrap().parse().unwrap();
        let max: f64 = summary.get(s, "t_total_s_max").unwrap().parse().unwrap();
        let median: f64 = summary.get(s, "t_total_s_median").unwrap().parse().unwrap();
        assert!(min <= median && median <= max);
        assert_eq!(min, times.iter().cloned().fold(f64::INFINITY, f64::min));
        for col in [
            "vertices",
            "triangles",
            "discarded",
            "euler",
            "ar_mean",
            "boundary_edges_interior",
        ] {
            for &r in &members {
                assert_eq!(summary.get(s, col), raw.get(r, col), "{id} {col}");
            }
        }
        // Shares of the stages are fractions of the total.
        let share: f64 = summary.get(s, "share_sampling").unwrap().parse().unwrap();
        assert!((0.0..=1.0).contains(&share), "{id}: {share}");
    }

    // Triangle reduction against the unclustered configuration of the same object and lattice.
    let row = |id: &str| (0..n).find(|&s| summary.get(s, "id") == Some(id)).unwrap();
    let tri = |id: &str| {
        summary
            .get(row(id), "triangles")
            .unwrap()
            .parse::<f64>()
            .unwrap()
    };
    let reduction: f64 = summary
        .get(row("as_bi"), "triangle_reduction")
        .unwrap()
        .parse()
        .unwrap();
    assert!((reduction - (1.0 - tri("as_bi") / tri("as_bu"))).abs() < 1e-12);
    assert!(reduction > 0.0, "integrated clustering removes triangles");

    // Meshes of the last repetition, as PLY, with the summary's counts.
    for s in 0..n {
        let id = summary.get(s, "id").unwrap();
        let mesh = rmt_mesh::io::read_ply(folder.join("meshes").join(format!("{id}.ply"))).unwrap();
        assert_eq!(
            mesh.triangle_count().to_string(),
            summary.get(s, "triangles").unwrap()
        );
        assert_eq!(
            mesh.vertex_count().to_string(),
            summary.get(s, "vertices").unwrap()
        );
    }

    // Provenance.
    let record: serde_json::Value =
        serde_json::from_slice(&fs::read(folder.join("run.json")).unwrap()).unwrap();
    assert_eq!(record["status"], "finished");
    assert_eq!(record["settings"]["repetitions"], plan.repetitions);
    assert_eq!(record["settings"]["threads"], 1);
    for key in [
        "version",
        "git_commit",
        "build_profile",
        "cpu_model",
        "cores",
        "os",
        "date",
    ] {
        assert!(
            record["provenance"].get(key).is_some(),
            "run.json lacks provenance.{key}"
        );
    }
    assert_eq!(record["configuration_ids"].as_array().unwrap().len(), n);
    assert_eq!(
        fs::read_to_string(folder.join("manifest.toml")).unwrap(),
        fs::read_to_string(ci_manifest()).unwrap()
    );

    // Paper comparison: the CI grids are far coarser than the dissertation's, so no row is
    // comparable (the join itself is tested in `paper::tests`).
    let cmp = Table::read(&folder.join("paper_comparison.csv")).unwrap();
    assert_eq!(cmp.header, ["id", "metric", "ours", "theirs", "ratio"]);
    assert!(cmp.rows.is_empty(), "{:?}", cmp.rows);

    // No temporary files left behind.
    for entry in fs::read_dir(&folder).unwrap() {
        let name = entry.unwrap().file_name().to_string_lossy().into_owned();
        assert!(!name.ends_with(".tmp"), "leftover {name}");
    }
}

#[test]
fn a_run_stopped_and_resumed_gives_the_rows_of_an_uninterrupted_run() {
    let dir = tempfile::tempdir().unwrap();
    let whole = dir.path().join("whole");
    runner::start(
        &ci_manifest(),
        &Overrides::default(),
        Some(&whole),
        &quiet(),
    )
    .unwrap();

    let parts = dir.path().join("parts");
    let stop = |k| RunOptions {
        quiet: true,
        stop_after: Some(k),
    };
    let first = runner::start(
        &ci_manifest(),
        &Overrides::default(),
        Some(&parts),
        &stop(3),
    )
    .unwrap();
    assert_eq!(first.status, Status::Stopped);
    assert_eq!(first.configurations_done, 3);
    assert!(
        !parts.join("summary.csv").exists(),
        "no summary before the end"
    );

    // Simulate a kill in the middle of the next configuration: a few rows appended but not yet
    // recorded in progress.json, the last one torn.
    let raw_path = parts.join("raw.csv");
    let rows_before = Table::read(&raw_path).unwrap().rows.len();
    let mut f = fs::OpenOptions::new().append(true).open(&raw_path).unwrap();
    let header = raw_header();
    let fake: Vec<String> = header.iter().map(|_| "7".to_string()).collect();
    writeln!(f, "{}", fake.join(",")).unwrap();
    write!(f, "parts,ss_su,sphere,sph").unwrap();
    drop(f);

    let second = runner::resume(&parts, &stop(5)).unwrap();
    assert_eq!(second.status, Status::Stopped);
    assert_eq!(second.configurations_run, 5);
    assert_eq!(second.configurations_done, 8);
    let rows_now = Table::read(&raw_path).unwrap().rows.len();
    assert_eq!(
        rows_now,
        rows_before + 5 * ci_plan().repetitions,
        "the torn rows are gone"
    );

    let third = runner::resume(&parts, &quiet()).unwrap();
    assert_eq!(third.status, Status::Finished);
    assert_eq!(third.configurations_done, ci_plan().configurations.len());

    assert_eq!(rows_without_times(&parts), rows_without_times(&whole));
    let record: serde_json::Value =
        serde_json::from_slice(&fs::read(parts.join("run.json")).unwrap()).unwrap();
    assert_eq!(record["sessions"].as_array().unwrap().len(), 3);
    assert_eq!(record["status"], "finished");

    // Summaries agree too, apart from times.
    let strip = |p: &Path| {
        let t = Table::read(&p.join("summary.csv")).unwrap();
        let keep: Vec<usize> = (0..t.header.len())
            .filter(|&i| !t.header[i].starts_with("t_") && !t.header[i].starts_with("share_"))
            .collect();
        t.rows
            .iter()
            .map(|r| keep.iter().map(|&i| r[i].clone()).collect::<Vec<_>>())
            .collect::<Vec<_>>()
    };
    assert_eq!(strip(&parts), strip(&whole));

    // Resuming a finished run does nothing.
    let again = runner::resume(&parts, &quiet()).unwrap();
    assert_eq!(
        (again.status, again.configurations_run),
        (Status::Finished, 0)
    );
}

#[test]
fn a_non_empty_output_folder_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    fs::write(dir.path().join("something"), "x").unwrap();
    let err = runner::start(
        &ci_manifest(),
        &Overrides::default(),
        Some(dir.path()),
        &quiet(),
    )
    .unwrap_err();
    assert!(format!("{err:#}").contains("not empty"), "{err:#}");
}

#[test]
fn resuming_a_folder_that_is_not_a_run_fails_clearly() {
    let dir = tempfile::tempdir().unwrap();
    let err = runner::resume(dir.path(), &quiet()).unwrap_err();
    assert!(
        format!("{err:#}").contains("not a resumable run folder"),
        "{err:#}"
    );
}

#[test]
fn every_bad_manifest_gives_its_specific_error() {
    let folder = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/bad_manifests");
    let mut checked = 0;
    let mut entries: Vec<PathBuf> = fs::read_dir(&folder)
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    entries.sort();
    let mut messages = HashMap::new();
    for path in entries
        .iter()
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
    {
        let text = fs::read_to_string(path).unwrap();
        let expect = text
            .lines()
            .next()
            .and_then(|l| l.strip_prefix("# expect: "))
            .unwrap_or_else(|| panic!("{} lacks a first line `# expect: ...`", path.display()));
        let err = match manifest::load(path, &Overrides::default()) {
            Ok(_) => panic!("{} was accepted", path.display()),
            Err(e) => e.to_string(),
        };
        assert!(
            err.contains(expect),
            "{}: expected `{expect}` in:\n{err}",
            path.display()
        );
        assert!(
            err.contains(&*path.file_name().unwrap().to_string_lossy()),
            "error names the file: {err}"
        );
        messages.insert(path.clone(), err);
        checked += 1;
    }
    assert!(checked >= 20, "only {checked} bad manifests");
}

/// The paper manifest's bunny at 75 x 40 x 56 cells on the body-centred lattice: one closed,
/// manifold, consistently oriented surface of genus 0 in every clustering mode.
#[test]
fn paper_bunny_is_one_closed_manifold_sphere_on_the_bcdl_lattice() {
    use rmt_extract::{Extractor, Lattice};
    use rmt_mesh::{validate, Mesh};
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("manifests/paper.toml");
    let loaded = manifest::load(&path, &Overrides::default()).unwrap();
    let plan = loaded.plan;
    let fields = plan.build_fields(&path).unwrap();
    let bunnies: Vec<_> = plan
        .configurations
        .iter()
        .filter(|c| c.object == "bunny" && c.extraction.lattice == Lattice::BodyCentred)
        .collect();
    assert_eq!(bunnies.len(), 3, "none, integrated, postprocessed");
    let mut extractor = Extractor::new();
    let mut mesh = Mesh::default();
    for c in bunnies {
        assert_eq!(c.extraction.resolution.cells(), [75, 40, 56]);
        let settings = c.extraction.settings(2);
        let field = fields.get(&c.object).unwrap();
        let stats = extractor.extract(field, &settings, &mut mesh).unwrap();
        let grid = settings.grid;
        let r = validate(&mesh, &|p| rmt_extract::measure::on_box_boundary(&grid, p));
        let what = format!("{}: {r:?}", c.id);
        assert!(stats.triangles > 5000, "{what}");
        assert!(r.is_watertight_manifold(), "{what}");
        assert_eq!(
            r.boundary_edges_on_box + r.boundary_edges_interior,
            0,
            "{what}"
        );
        assert_eq!(r.orientation_errors, 0, "{what}");
        assert_eq!(r.components, 1, "{what}");
        assert_eq!(r.euler, 2, "{what}");
    }
}

/// The `edit` workload: one terrain session per configuration, every stroke in edits.csv, one
/// summary row each, and the chunks equal to the whole volume before and after the strokes.
#[test]
fn edit_workload_writes_one_row_per_stroke_and_a_summary() {
    let dir = tempfile::tempdir().unwrap();
    let manifest = dir.path().join("edit.toml");
    fs::write(
        &manifest,
        r#"
name = "edit-test"
workload = "edit"
threads = 2
save_meshes = false

[[objects]]
name = "terrain"
resolution = [24, 16, 24]
bounds = [-1.5, -1.0, -1.5, 1.5, 1.0, 1.5]

[[configurations]]
object = "terrain"
lattice = "bcdl"
clustering = "integrated"

[[configurations]]
object = "terrain"
method = "mc"

[edit]
chunk = 8
strokes = 5
warmup = 1
radius = 2.0
"#,
    )
    .unwrap();
    let folder = dir.path().join("run");
    let report = runner::start(&manifest, &Overrides::default(), Some(&folder), &quiet()).unwrap();
    assert_eq!(report.status, Status::Finished);
    assert_eq!(report.configurations_run, 2);
    let edits = Table::read(&folder.join("edits.csv")).unwrap();
    assert_eq!(edits.header, rmt_runfolder::schema::EDITS);
    assert_eq!(edits.rows.len(), 10);
    let summary = Table::read(&folder.join("summary.csv")).unwrap();
    assert_eq!(summary.header, rmt_runfolder::schema::EDIT_SUMMARY);
    assert_eq!(summary.rows.len(), 2);
    for r in 0..2 {
        assert_eq!(summary.get(r, "chunked_equals_whole"), Some("true"));
        assert_eq!(summary.get(r, "strokes"), Some("5"));
        let p50: f64 = summary.get(r, "latency_p50_ms").unwrap().parse().unwrap();
        let max: f64 = summary.get(r, "latency_max_ms").unwrap().parse().unwrap();
        assert!(p50 > 0.0 && p50 <= max);
        assert_eq!(summary.get(r, "chunks"), Some("18"));
    }
    assert!(!folder.join("raw.csv").exists());
}

#[test]
fn edit_workload_refuses_meshopt_and_an_edit_table_without_the_workload() {
    let dir = tempfile::tempdir().unwrap();
    let write = |name: &str, text: &str| {
        let p = dir.path().join(name);
        fs::write(&p, text).unwrap();
        p
    };
    let base = "name = \"e\"\n[[objects]]\nname = \"sphere\"\nresolution = 8\n";
    let meshopt = write(
        "meshopt.toml",
        &format!("workload = \"edit\"\n{base}[[configurations]]\nobject = \"sphere\"\nclustering = \"meshopt\"\n"),
    );
    let err = manifest::load(&meshopt, &Overrides::default())
        .err()
        .unwrap()
        .to_string();
    assert!(
        err.contains("meshopt") && err.contains("meshopt.toml"),
        "{err}"
    );
    let stray = write(
        "stray.toml",
        &format!("{base}[[configurations]]\nobject = \"sphere\"\n[edit]\nchunk = 8\n"),
    );
    let err = manifest::load(&stray, &Overrides::default())
        .err()
        .unwrap()
        .to_string();
    assert!(err.contains("workload"), "{err}");
}

/// The topology sweep: a seed study of the `random` object (the property tests' field
/// families) tallies the checks per configuration in `topology.csv`, and a sharded run merges
/// into the same tally.
#[test]
fn topology_sweep_tallies_every_field_and_merges_from_shards() {
    let dir = tempfile::tempdir().unwrap();
    let manifest = dir.path().join("topology.toml");
    fs::write(
        &manifest,
        r#"name = "topology-test"
repetitions = 1
warmup = 0
threads = 1
save_meshes = false
seeds = { from = 1, count = 12 }

[[objects]]
name = "random"
resolution = 9

[matrix]
objects = ["random"]
methods = ["mt"]
lattices = ["bcdl", "simple"]
clustering = ["none", "integrated", "postprocessed"]
"#,
    )
    .unwrap();
    let whole = dir.path().join("whole");
    let report = runner::start(&manifest, &Overrides::default(), Some(&whole), &quiet()).unwrap();
    assert_eq!(report.configurations_run, 6 * 12);
    let tally = Table::read(&whole.join("topology.csv")).unwrap();
    assert_eq!(tally.rows.len(), 6);
    for r in 0..tally.rows.len() {
        assert_eq!(tally.get(r, "fields"), Some("12"));
        // The property tests hold on these fields: no check fails.
        assert_eq!(
            tally.get(r, "failed_fields"),
            Some("0"),
            "{:?}",
            tally.rows[r]
        );
        let clustered = tally.get(r, "clustering") != Some("none");
        assert_eq!(
            tally.get(r, "reference").is_some_and(|s| !s.is_empty()),
            clustered
        );
    }
    let failures = Table::read(&whole.join("topology_failures.csv")).unwrap();
    assert!(failures.rows.is_empty());
    // Every field is a different mesh: the seeds are not all one field.
    let summary = Table::read(&whole.join("summary.csv")).unwrap();
    let triangles: std::collections::BTreeSet<&str> = (0..summary.rows.len())
        .filter(|&r| summary.get(r, "clustering") == Some("none"))
        .filter_map(|r| summary.get(r, "triangles"))
        .collect();
    assert!(triangles.len() >= 8, "{triangles:?}");

    let mut shards = Vec::new();
    for i in 1..=3 {
        let out = dir.path().join(format!("s{i}"));
        let shard = experiments::shard::ShardSpec { index: i, count: 3 };
        runner::start_shard(
            &manifest,
            &Overrides::default(),
            Some(&out),
            &quiet(),
            Some(shard),
        )
        .unwrap();
        shards.push(out);
    }
    let merged = dir.path().join("merged");
    experiments::merge::merge(&merged, &shards).unwrap();
    assert_eq!(
        fs::read(merged.join("topology.csv")).unwrap(),
        fs::read(whole.join("topology.csv")).unwrap()
    );
}

#[test]
fn configurations_that_differ_only_in_shading_share_one_extraction() {
    let dir = tempfile::tempdir().unwrap();
    let manifest = dir.path().join("shaded.toml");
    fs::write(
        &manifest,
        "name = \"shaded\"\nrepetitions = 3\nwarmup = 1\nthreads = 1\n\
         [[objects]]\nname = \"sphere\"\nresolution = 10\n\
         [[objects]]\nname = \"asteroid\"\nresolution = 10\n\
         [matrix]\nlattices = [\"bcdl\", \"simple\"]\nclustering = [\"integrated\"]\n\
         shading = [\"smooth\", \"flat\"]\n",
    )
    .unwrap();
    let whole = dir.path().join("whole");
    runner::start(&manifest, &Overrides::default(), Some(&whole), &quiet()).unwrap();

    // Every id column aside, a flat twin's rows are its smooth configuration's, times included:
    // one extraction served both (two extractions would not time alike to the nanosecond).
    let raw = Table::read(&whole.join("raw.csv")).unwrap();
    let id = raw.header.iter().position(|h| h == "id").unwrap();
    let time = raw.header.iter().position(|h| h == "t_total_s").unwrap();
    let rows_of = |wanted: &str| -> Vec<Vec<String>> {
        raw.rows
            .iter()
            .filter(|r| r[id] == wanted)
            .map(|r| {
                let mut r = r.clone();
                r[id].clear();
                r
            })
            .collect()
    };
    let mut twins = 0;
    for smooth in ["ss_bi", "ss_si", "as_bi", "as_si"] {
        let flat = format!("{smooth}_flat");
        let (a, b) = (rows_of(smooth), rows_of(&flat));
        assert_eq!(a.len(), 3, "{smooth}");
        assert_eq!(a, b, "{flat} has its own rows");
        assert!(a.iter().all(|r| r[time].parse::<f64>().unwrap() > 0.0));
        let mesh = |i: &str| fs::read(whole.join("meshes").join(format!("{i}.ply"))).unwrap();
        assert_eq!(mesh(smooth), mesh(&flat), "{flat}: another mesh");
        twins += 1;
    }
    assert_eq!(twins, 4);
    // Different configurations are extracted on their own.
    assert_ne!(rows_of("ss_bi"), rows_of("ss_si"));

    // Stopped between a configuration and its twin, the resumed session extracts the twin
    // itself: the same rows apart from times, the same mesh.
    let parts = dir.path().join("parts");
    let stop = RunOptions {
        quiet: true,
        stop_after: Some(1),
    };
    runner::start(&manifest, &Overrides::default(), Some(&parts), &stop).unwrap();
    runner::resume(&parts, &quiet()).unwrap();
    assert_eq!(rows_without_times(&parts), rows_without_times(&whole));
    for i in ["ss_bi_flat", "as_si_flat"] {
        let mesh = |f: &Path| fs::read(f.join("meshes").join(format!("{i}.ply"))).unwrap();
        assert_eq!(mesh(&parts), mesh(&whole), "{i}");
    }
}
