//! `experiments bench --python PY --dump DIR`: the Python peers' options on the command line.

use std::process::Command;

fn experiments(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_experiments"))
        .args(args)
        .output()
        .expect("the experiments binary runs")
}

/// An interpreter that cannot start is refused with its path and what it needs, after the
/// values were dumped where `--dump` asked; no table is printed.
#[test]
fn a_missing_python_is_named_and_the_dump_stays() {
    let dir = tempfile::tempdir().unwrap();
    let dump = dir.path().join("values");
    let dump_arg = dump.display().to_string();
    let o = experiments(&[
        "bench",
        "--fields",
        "sphere",
        "--sizes",
        "12",
        "--reps",
        "1",
        "--threads",
        "1",
        "--python",
        "/nonexistent/python3",
        "--dump",
        &dump_arg,
    ]);
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("/nonexistent/python3") && err.contains("vtk") && !err.contains("panicked"),
        "{err}"
    );
    assert!(o.stdout.is_empty(), "a table was printed");
    for file in ["sphere_12.json", "sphere_12.f32", "peer_bench.py"] {
        assert!(dump.join(file).is_file(), "{file} missing");
    }
}

/// `--dump` alone keeps the values without any Python, and the table has no Flying Edges rows.
#[test]
fn dump_without_python_writes_the_grid_and_times_only_the_rust_methods() {
    let dir = tempfile::tempdir().unwrap();
    let dump_arg = dir.path().display().to_string();
    let o = experiments(&[
        "bench",
        "--fields",
        "sphere",
        "--sizes",
        "12",
        "--reps",
        "1",
        "--threads",
        "1",
        "--dump",
        &dump_arg,
        "--json",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let rows = v["results"].as_array().unwrap();
    assert!(rows.iter().all(|r| r["method"] != "vtk_flying_edges"));
    assert!(rows.iter().all(|r| r["ratio_to_flying_edges"].is_null()));
    let bytes = std::fs::metadata(dir.path().join("sphere_12.f32"))
        .unwrap()
        .len();
    assert_eq!(bytes, 4 * 13 * 13 * 13);
}
