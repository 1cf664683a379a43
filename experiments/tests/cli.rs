//! The `experiments` binary: `extract` output and errors, `run` exit codes, resume through the
//! command line, and determinism of repeated extractions (which the runner relies on to measure
//! each configuration's mesh once).

use std::path::Path;
use std::process::{Command, Output};

use experiments::config::Normals;
use experiments::objects::{Bounds, ObjectKind, ObjectParams, ObjectSpec, Resolution};
use rmt_extract::{Clustering, Extractor, Lattice, Method};
use rmt_mesh::Mesh;

fn experiments(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_experiments"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .unwrap()
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

#[test]
fn extract_json_has_the_config_keys_then_the_measurement() {
    let dir = tempfile::tempdir().unwrap();
    let ply = dir.path().join("s.ply");
    let o = experiments(&[
        "extract",
        "--object",
        "sphere",
        "--radius",
        "0.7",
        "--resolution",
        "10",
        "--lattice",
        "simple",
        "--clustering",
        "integrated",
        "--threads",
        "1",
        "--json",
        "--out",
        ply.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let keys: Vec<&String> = v.as_object().unwrap().keys().collect();
    assert_eq!(
        &keys[..5],
        ["object", "lattice", "clustering", "method", "resolution"]
    );
    assert_eq!(v["object"], "sphere");
    assert_eq!(v["lattice"], "simple");
    assert_eq!(v["resolution"], serde_json::json!([10, 10, 10]));
    for key in [
        "vertices",
        "triangles",
        "t_total_s",
        "ar_mean",
        "euler",
        "fidelity_mean_h",
    ] {
        assert!(v.get(key).is_some(), "missing {key}");
    }
    let mesh = rmt_mesh::io::read_ply(&ply).unwrap();
    assert_eq!(serde_json::json!(mesh.triangle_count()), v["triangles"]);
}

#[test]
fn extract_writes_the_format_its_out_extension_names() {
    let dir = tempfile::tempdir().unwrap();
    let mut meshes = Vec::new();
    for name in ["t.ply", "t.obj", "t.glb", "T.GLB"] {
        let path = dir.path().join(name);
        let o = experiments(&[
            "extract",
            "--object",
            "torus",
            "--resolution",
            "12",
            "--threads",
            "1",
            "--out",
            path.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{name}: {}", stderr(&o));
        let bytes = std::fs::read(&path).unwrap();
        match name {
            "t.ply" => assert!(bytes.starts_with(b"ply\n")),
            "t.obj" => assert!(bytes.starts_with(b"# written by rmt-mesh\nv ")),
            _ => assert!(bytes.starts_with(b"glTF")),
        }
        meshes.push(rmt_mesh::io::read_mesh(&path).unwrap());
    }
    // Every format holds the same oriented triangles, f32 for f32 (OBJ may renumber vertices in
    // order of first use, so triangles are compared by their corners' positions).
    let triangles = |m: &Mesh| {
        let mut t: Vec<[[u32; 3]; 3]> = m
            .triangles()
            .map(|t| {
                let c = t.map(|i| m.positions[i as usize].map(f32::to_bits));
                let first = (0..3).min_by_key(|&k| c[k]).unwrap();
                [c[first], c[(first + 1) % 3], c[(first + 2) % 3]]
            })
            .collect();
        t.sort_unstable();
        t
    };
    assert!(meshes[0].triangle_count() > 0);
    assert!(meshes.iter().all(|m| triangles(m) == triangles(&meshes[0])));
    let bad = dir.path().join("t.stl");
    let o = experiments(&["extract", "--out", bad.to_str().unwrap()]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("unknown mesh format"), "{}", stderr(&o));
    assert!(!bad.exists());
}

#[test]
fn extract_with_marching_cubes_alone_takes_no_clustering() {
    let o = experiments(&["extract", "--method", "mc", "--resolution", "10", "--json"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["method"], "mc");
    assert_eq!(v["clustering"], "none");
    assert!(v["triangles"].as_u64().unwrap() > 0);
}

#[test]
fn extract_with_surface_nets_counts_its_defects_and_takes_no_clustering() {
    // The asteroid at 64^3: surface nets leaves non-manifold edges there, which are reported in
    // the measurement, not hidden and not an error.
    let o = experiments(&[
        "extract",
        "--object",
        "asteroid",
        "--method",
        "surface-nets",
        "--resolution",
        "64",
        "--json",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["method"], "surface-nets");
    assert_eq!(v["lattice"], "simple");
    assert_eq!(v["clustering"], "none");
    assert!(v["triangles"].as_u64().unwrap() > 0);
    assert!(v["non_manifold_edges"].as_u64().unwrap() > 0, "{v}");
    let o = experiments(&[
        "extract",
        "--method",
        "surface-nets",
        "--clustering",
        "integrated",
    ]);
    assert!(!o.status.success());
    assert!(
        stderr(&o).contains("surface nets takes clustering none"),
        "{}",
        stderr(&o)
    );
}

#[test]
fn extract_simplifies_any_method_to_rmts_count_and_measures_the_rendering_cost() {
    let json = |args: &[&str]| -> serde_json::Value {
        let mut line = vec![
            "extract",
            "--object",
            "asteroid",
            "--resolution",
            "20",
            "--threads",
            "1",
            "--json",
        ];
        line.extend_from_slice(args);
        let o = experiments(&line);
        assert!(o.status.success(), "{}", stderr(&o));
        serde_json::from_slice(&o.stdout).unwrap()
    };
    let rmt = json(&[]);
    let rmt_triangles = rmt["triangles"].as_u64().unwrap();
    for method in ["mc", "surface-nets"] {
        let plain = json(&["--method", method]);
        let v = json(&[
            "--method",
            method,
            "--simplify",
            "meshopt:rmt",
            "--vertex-cache",
        ]);
        assert_eq!(v["simplify"], "meshopt:rmt");
        assert_eq!(v["vertex_cache"], true);
        assert_eq!(
            v["simplify_target"].as_u64(),
            Some(rmt_triangles),
            "{method}"
        );
        assert_eq!(
            v["simplify_triangles_before"], plain["triangles"],
            "{method}"
        );
        let t = v["triangles"].as_u64().unwrap();
        // meshoptimizer stops at the target or just below it.
        assert!(
            t <= rmt_triangles && t * 100 >= rmt_triangles * 95,
            "{method}: {t}"
        );
        assert!(v["simplify_error_h"].as_f64().unwrap() > 0.0);
        let pipeline = v["t_pipeline_s"].as_f64().unwrap();
        assert!(
            pipeline
                >= v["t_total_s"].as_f64().unwrap() + v["t_simplify_s"].as_f64().unwrap() * 0.999
        );
        // Reordered for the vertex cache: the analyzer sees little left to gain.
        let (acmr, best) = (
            v["acmr_16"].as_f64().unwrap(),
            v["acmr_16_optimized"].as_f64().unwrap(),
        );
        assert!(acmr <= best * 1.05, "{method}: {acmr} vs {best}");
    }
    // Every mesh gets its rendering cost; a plain one too.
    for key in [
        "quad_occupancy_1080",
        "quad_occupancy_135",
        "overdraw",
        "glb_bytes",
    ] {
        assert!(rmt[key].is_number(), "{key}: {}", rmt[key]);
    }
    assert_eq!(rmt["simplify"], "none");
    assert!(rmt["simplify_target"].is_null());
    // Bad values name themselves.
    let o = experiments(&["extract", "--simplify", "meshopt:2.5"]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("between 0 and 1"), "{}", stderr(&o));
    let o = experiments(&["extract", "--chunks", "8", "--simplify", "meshopt:rmt"]);
    assert!(!o.status.success());
    assert!(
        stderr(&o).contains("--chunks cannot be combined"),
        "{}",
        stderr(&o)
    );
}

#[test]
fn extract_prints_a_readable_summary_without_json() {
    let o = experiments(&[
        "extract",
        "--object",
        "torus",
        "--resolution",
        "8",
        "--threads",
        "1",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(
        text.starts_with("torus (mt, bcdl, integrated) at 8x8x8 cells"),
        "{text}"
    );
    assert!(
        text.contains("triangles") && text.contains("ms total"),
        "{text}"
    );
}

#[test]
fn extract_refuses_bad_input_with_a_message_and_no_panic() {
    for (args, expect) in [
        (&["--resolution", "0"][..], "at least one cell"),
        (&["--bounds", "NaN,0,0,1,1,1"][..], "invalid bounds"),
        (&["--bounds", "0,0,0,1,1"][..], "6 comma-separated"),
        (&["--object", "teapot"][..], "unknown object `teapot`"),
        (
            &["--object", "bunny", "--mesh", "nowhere.obj"][..],
            "not found",
        ),
        (
            &["--object", "sphere", "--thickness", "1"][..],
            "takes no parameter `thickness`",
        ),
        (
            &["--method", "mc", "--clustering", "integrated"][..],
            "marching cubes takes clustering none",
        ),
        (&["--resolution", "100000"][..], "too large"),
        (&["--lattice", "hex"][..], "unknown lattice"),
    ] {
        let mut all = vec!["extract"];
        all.extend_from_slice(args);
        let o = experiments(&all);
        let err = stderr(&o);
        assert!(!o.status.success(), "{args:?} succeeded");
        assert!(
            err.contains(expect),
            "{args:?}: expected `{expect}` in {err}"
        );
        assert!(!err.contains("panicked"), "{args:?} panicked: {err}");
    }
}

#[test]
fn run_exits_non_zero_on_a_bad_manifest_before_creating_anything() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    let bad = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/bad_manifests/missing_mesh.toml");
    let o = experiments(&["run", bad.to_str().unwrap(), "--out", out.to_str().unwrap()]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("no_such_bunny.obj"), "{}", stderr(&o));
    assert!(!out.exists(), "nothing is created for a bad manifest");
}

#[test]
fn run_stops_and_resumes_through_the_command_line() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    let out_s = out.to_str().unwrap();
    let o = experiments(&[
        "run",
        "manifests/ci.toml",
        "--out",
        out_s,
        "--reps",
        "1",
        "--warmup",
        "0",
        "--quiet",
        "--no-meshes",
        "--stop-after",
        "2",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(String::from_utf8_lossy(&o.stdout).contains("--resume"));
    assert!(!out.join("summary.csv").exists());
    let o = experiments(&["run", "--resume", out_s, "--quiet"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let raw = std::fs::read_to_string(out.join("raw.csv")).unwrap();
    let configs = std::fs::read_to_string(out.join("configurations.csv")).unwrap();
    // One repetition (the override survives the resume): one raw row per configuration.
    assert_eq!(raw.lines().count(), configs.lines().count());
    assert!(out.join("summary.csv").exists());
    assert!(
        !out.join("meshes").exists(),
        "--no-meshes survives the resume"
    );
    // Flags that change the plan cannot be combined with --resume.
    let o = experiments(&["run", "--resume", out_s, "--reps", "3"]);
    assert!(!o.status.success());
}

#[test]
fn run_dry_run_lists_the_paper_configurations() {
    let o = experiments(&["run", "manifests/paper.toml", "--dry-run", "--threads", "1"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = String::from_utf8_lossy(&o.stdout);
    let listed: Vec<&str> = text
        .lines()
        .skip(2)
        .map(|l| l.split(',').next().unwrap_or(""))
        .collect();
    let expected = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../data/questionnaire/configurations.csv"),
    )
    .unwrap();
    let expected: Vec<&str> = expected
        .lines()
        .skip(1)
        .map(|l| l.split(',').next().unwrap_or(""))
        .collect();
    assert_eq!(listed, expected);
}

/// The runner measures a configuration's mesh once and copies the metrics to every repetition's
/// row; that is only right if repeated extractions give the same mesh, with a reused extractor as
/// with a fresh one.
#[test]
fn repeated_extractions_give_identical_meshes() {
    for (kind, lattice, clustering) in [
        (
            ObjectKind::Sphere,
            Lattice::BodyCentred,
            Clustering::Integrated,
        ),
        (
            ObjectKind::Asteroid,
            Lattice::Simple,
            Clustering::Integrated,
        ),
        (
            ObjectKind::Asteroid,
            Lattice::BodyCentred,
            Clustering::Postprocessed,
        ),
        (ObjectKind::Bunny, Lattice::BodyCentred, Clustering::None),
        (ObjectKind::Gyroid, Lattice::Simple, Clustering::Integrated),
    ] {
        let spec = ObjectSpec::new(kind, ObjectParams::default()).unwrap();
        let e = experiments::config::Extraction {
            object: spec,
            bounds: Bounds::default(),
            resolution: Resolution::Cube(9),
            method: Method::Mt,
            lattice,
            clustering,
            collapse_threshold: 0.5,
            iso: 0.0,
            normals: Normals::Area,
            simplify: None,
            vertex_cache: false,
        };
        let field = e.object.build(&e.bounds, &[]).unwrap();
        for threads in [1, 2] {
            let settings = e.settings(threads);
            let mut reused = Extractor::new();
            let mut meshes = Vec::new();
            for _ in 0..3 {
                let mut mesh = Mesh::default();
                reused
                    .extract(field.as_ref(), &settings, &mut mesh)
                    .unwrap();
                meshes.push(mesh);
            }
            let mut fresh = Mesh::default();
            Extractor::new()
                .extract(field.as_ref(), &settings, &mut fresh)
                .unwrap();
            assert!(fresh.triangle_count() > 0, "{kind} produced no surface");
            for m in &meshes {
                assert_eq!(
                    m, &fresh,
                    "{kind} {lattice:?} {clustering:?} threads {threads}"
                );
            }
            assert_eq!(
                experiments::runner::repetitions::mesh_fingerprint(&meshes[0]),
                experiments::runner::repetitions::mesh_fingerprint(&fresh)
            );
        }
    }
}

#[test]
fn extract_in_chunks_equals_the_whole_volume_and_refuses_non_cubic_cells() {
    let o = experiments(&[
        "extract",
        "--object",
        "asteroid",
        "--resolution",
        "24",
        "--chunks",
        "8",
        "--threads",
        "2",
        "--json",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["chunks"], 27);
    assert_eq!(v["chunk_size"], 8);
    assert_eq!(v["chunked_equals_whole"], true);
    assert_eq!(v["triangles"], v["whole_triangles"]);
    assert_eq!(v["boundary_edges_interior"], 0);
    assert_eq!(v["non_manifold_edges"], 0);

    let o = experiments(&["extract", "--resolution", "24,12,24", "--chunks", "8"]);
    assert!(!o.status.success());
    let err = stderr(&o);
    assert!(
        err.contains("cubic cells") && !err.contains("panicked"),
        "{err}"
    );
}

#[test]
fn bench_with_pinned_workers_says_so_and_measures_every_method() {
    let run = |pin: bool| {
        let mut args = vec![
            "bench",
            "--fields",
            "sphere",
            "--sizes",
            "16",
            "--reps",
            "1",
            "--threads",
            "1,2",
            "--json",
        ];
        if pin {
            args.push("--pin");
        }
        let o = experiments(&args);
        assert!(o.status.success(), "bench failed: {}", stderr(&o));
        let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        let rows = v["results"].as_array().unwrap().clone();
        (v["placement"].as_str().unwrap().to_string(), rows)
    };
    let (os, os_rows) = run(false);
    let (pinned, pinned_rows) = run(true);
    assert_eq!((os.as_str(), pinned.as_str()), ("os", "pinned"));
    assert_eq!(os_rows.len(), pinned_rows.len());
    // Where the workers run changes no mesh: the same triangle counts, row by row.
    for (a, b) in os_rows.iter().zip(&pinned_rows) {
        assert_eq!(a["method"], b["method"]);
        assert_eq!(a["triangles"], b["triangles"]);
        assert!(b["triangles"].as_u64().unwrap() > 0);
    }
}
