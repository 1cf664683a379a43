//! Dumps the sampled corner grid of the benchmark fields for peers outside Rust, times our
//! extractors on the same values, and (with `--python PY`) runs `scripts/peer_bench.py` on the
//! dump in the same process tree, so every ratio over VTK's Flying Edges comes from one run on
//! one machine.
//!
//! `cargo run --release -p rmt-extract --example dump_values -- DIR [--sizes 64,128]
//! [--fields sphere,asteroid] [--reps 10] [--python PY]`
//!
//! The fields are those of `experiments bench`: a sphere of radius 0.8 and the default asteroid,
//! centred in `[-1, 1]^3`, sampled densely (every stored value is the field's). Per field and
//! size it writes `DIR/FIELD_N.f32` (the `(n + 1)^3` corner values that our marching cubes
//! reads, raw little-endian `f32`, x fastest) and `DIR/FIELD_N.json` (the header documented at
//! the top of `scripts/peer_bench.py`). Ours are timed like `experiments bench` times them: the
//! whole [`Extractor::extract_presampled`] call, normals skipped, one thread, repetitions of the
//! methods interleaved, median (with `--python`, half of our repetitions run before the peers
//! and half after, so a drift of the machine's load reaches both sides alike). CSV rows on stdout (`field,n,method,threads,median_ms,min_ms,
//! reps,triangles`, the peers' format), then, with `--python`, the peers' rows and every
//! method's median (and fastest run) over Flying Edges' on the same values.

use std::path::{Path, PathBuf};
use std::time::Instant;

use glam::Vec3;
use rmt_extract::{
    Clustering, ExtractSettings, Extractor, Grid, Lattice, Method, NormalMode, Sampling,
};
use rmt_fields::{Asteroid, AsteroidParams, ScalarField, Sphere};
use rmt_mesh::Mesh;

/// Our methods timed: (CSV name, lattice, clustering, method).
const METHODS: [(&str, Lattice, Clustering, Method); 6] = [
    ("mc", Lattice::Simple, Clustering::None, Method::Mc),
    (
        "mt_bcdl_none",
        Lattice::BodyCentred,
        Clustering::None,
        Method::Mt,
    ),
    (
        "mt_simple_none",
        Lattice::Simple,
        Clustering::None,
        Method::Mt,
    ),
    (
        "rmt_bcdl_unchecked",
        Lattice::BodyCentred,
        Clustering::IntegratedUnchecked,
        Method::Mt,
    ),
    (
        "rmt_bcdl_integrated",
        Lattice::BodyCentred,
        Clustering::Integrated,
        Method::Mt,
    ),
    (
        "surface_nets",
        Lattice::Simple,
        Clustering::None,
        Method::SurfaceNets,
    ),
];

struct Args {
    dir: PathBuf,
    sizes: Vec<usize>,
    fields: Vec<String>,
    reps: usize,
    python: Option<String>,
}

fn parse() -> Result<Args, String> {
    let mut it = std::env::args().skip(1);
    let mut args = Args {
        dir: PathBuf::new(),
        sizes: vec![64, 128],
        fields: vec!["sphere".into(), "asteroid".into()],
        reps: 10,
        python: None,
    };
    let mut dir = None;
    while let Some(a) = it.next() {
        let mut value = |name: &str| it.next().ok_or(format!("{name} needs a value"));
        match a.as_str() {
            "--sizes" => {
                args.sizes = value("--sizes")?
                    .split(',')
                    .map(|s| s.parse().map_err(|e| format!("--sizes {s:?}: {e}")))
                    .collect::<Result<_, _>>()?
            }
            "--fields" => args.fields = value("--fields")?.split(',').map(String::from).collect(),
            "--reps" => {
                args.reps = value("--reps")?
                    .parse()
                    .map_err(|e| format!("--reps: {e}"))?
            }
            "--python" => args.python = Some(value("--python")?),
            _ if dir.is_none() && !a.starts_with("--") => dir = Some(PathBuf::from(a)),
            _ => return Err(format!("unexpected argument {a:?}")),
        }
    }
    args.dir = dir.ok_or("usage: dump_values DIR [--sizes 64,128] [--fields sphere,asteroid] [--reps N] [--python PY]")?;
    if args.reps == 0 || args.sizes.contains(&0) {
        return Err("--reps and every size must be at least 1".into());
    }
    Ok(args)
}

fn field(name: &str) -> Result<Box<dyn ScalarField>, String> {
    match name {
        "sphere" => Ok(Box::new(Sphere::new(Vec3::ZERO, 0.8))),
        "asteroid" => Ok(Box::new(Asteroid::new(
            Vec3::ZERO,
            AsteroidParams::default(),
        ))),
        _ => Err(format!(
            "unknown field {name:?}: expected sphere or asteroid"
        )),
    }
}

fn settings(n: usize, lattice: Lattice, clustering: Clustering, method: Method) -> ExtractSettings {
    let mut s = ExtractSettings::new(Grid::cube(n, 1.0), lattice, clustering);
    s.method = method;
    s.threads = 1;
    s.normals = NormalMode::Skip;
    s
}

/// An extractor holding the dense samples of `f` for `s`.
fn prepared(f: &dyn ScalarField, s: &ExtractSettings) -> Result<Extractor, String> {
    let mut ex = Extractor::new();
    ex.set_sampling(Sampling::Dense);
    let mut mesh = Mesh::default();
    ex.extract(f, s, &mut mesh).map_err(|e| e.to_string())?;
    Ok(ex)
}

/// Writes `NAME.f32` and `NAME.json` (format `rmt-values-1`) into `dir`.
fn dump(dir: &Path, name: &str, field: &str, n: usize, ex: &mut Extractor) -> Result<(), String> {
    let s = ex.samples_mut();
    let dims = s.dims;
    if s.values.len() != dims[0] * dims[1] * dims[2] {
        return Err(format!("{name}: samples not laid out as a corner grid"));
    }
    let mut bytes = Vec::with_capacity(4 * s.values.len());
    for v in &s.values {
        bytes.extend_from_slice(&v.to_le_bytes());
    }
    let values = format!("{name}.f32");
    std::fs::write(dir.join(&values), bytes).map_err(|e| format!("{values}: {e}"))?;
    let header = serde_json::json!({
        "format": "rmt-values-1",
        "field": field,
        "cells": n,
        "dims": dims,
        "origin": s.min.to_array(),
        "spacing": s.spacing.to_array(),
        "level": 0.0,
        "values": values,
    });
    let text = serde_json::to_string_pretty(&header).map_err(|e| e.to_string())?;
    std::fs::write(dir.join(format!("{name}.json")), text).map_err(|e| format!("{name}.json: {e}"))
}

struct Row {
    field: String,
    n: usize,
    method: String,
    median_ms: f64,
    min_ms: f64,
    reps: usize,
    triangles: usize,
}

impl Row {
    fn csv(&self) -> String {
        format!(
            "{},{},{},1,{:.3},{:.3},{},{}",
            self.field, self.n, self.method, self.median_ms, self.min_ms, self.reps, self.triangles
        )
    }
}

fn main() -> Result<(), String> {
    let args = parse()?;
    std::fs::create_dir_all(&args.dir).map_err(|e| format!("{}: {e}", args.dir.display()))?;
    // Clear earlier dumps' headers, so the peers read exactly this run's volumes.
    for entry in std::fs::read_dir(&args.dir).map_err(|e| e.to_string())? {
        let path = entry.map_err(|e| e.to_string())?.path();
        if matches!(
            path.extension().and_then(|e| e.to_str()),
            Some("json" | "f32")
        ) {
            std::fs::remove_file(&path).map_err(|e| format!("{}: {e}", path.display()))?;
        }
    }
    // With the peers, our repetitions are split in two rounds around their run, so a drift
    // of the machine's load reaches both sides alike.
    let rounds = if args.python.is_some() && args.reps >= 2 {
        [args.reps / 2, args.reps - args.reps / 2]
    } else {
        [args.reps, 0]
    };
    // Per (field, size, method): times and triangles.
    let mut timed: Vec<(String, usize, &str, Vec<f64>, usize)> = Vec::new();
    let round = |reps: usize,
                 dump_now: bool,
                 timed: &mut Vec<(String, usize, &'static str, Vec<f64>, usize)>|
     -> Result<(), String> {
        for name in &args.fields {
            let f = field(name)?;
            for &n in &args.sizes {
                let mut runners = Vec::new();
                for &(method, lattice, clustering, m) in &METHODS {
                    let s = settings(n, lattice, clustering, m);
                    let ex = prepared(f.as_ref(), &s)?;
                    runners.push((method, s, ex, Mesh::default()));
                }
                if dump_now {
                    // The corner grid of marching cubes is what the peers read.
                    dump(
                        &args.dir,
                        &format!("{name}_{n}"),
                        name,
                        n,
                        &mut runners[0].2,
                    )?;
                }
                for (_, s, ex, mesh) in runners.iter_mut() {
                    ex.extract_presampled(s, mesh).map_err(|e| e.to_string())?;
                }
                let mut times = vec![Vec::new(); runners.len()];
                let mut triangles = vec![0; runners.len()];
                for _ in 0..reps {
                    for (k, (_, s, ex, mesh)) in runners.iter_mut().enumerate() {
                        let t = Instant::now();
                        let stats = ex.extract_presampled(s, mesh).map_err(|e| e.to_string())?;
                        times[k].push(t.elapsed().as_secs_f64() * 1e3);
                        triangles[k] = stats.triangles;
                    }
                }
                for (k, (method, ..)) in runners.iter().enumerate() {
                    match timed
                        .iter_mut()
                        .find(|t| t.0 == *name && t.1 == n && t.2 == *method)
                    {
                        Some(t) => t.3.extend_from_slice(&times[k]),
                        None => {
                            timed.push((name.clone(), n, method, times[k].clone(), triangles[k]))
                        }
                    }
                }
                eprintln!("dump_values: {name} {n}^3 timed");
            }
        }
        Ok(())
    };
    round(rounds[0], true, &mut timed)?;
    let peers = match &args.python {
        Some(python) => Some(run_peers(python, &args)?),
        None => None,
    };
    if rounds[1] > 0 {
        round(rounds[1], false, &mut timed)?;
    }
    println!("field,n,method,threads,median_ms,min_ms,reps,triangles");
    let mut rows = Vec::new();
    for (field, n, method, mut times, triangles) in timed {
        times.sort_by(f64::total_cmp);
        let row = Row {
            field,
            n,
            method: method.into(),
            median_ms: times[times.len() / 2],
            min_ms: times[0],
            reps: times.len(),
            triangles,
        };
        println!("{}", row.csv());
        rows.push(row);
    }
    let Some(text) = peers else {
        return Ok(());
    };
    for line in text.lines().skip(1) {
        let c: Vec<&str> = line.split(',').collect();
        if c.len() < 8 {
            return Err(format!("peer_bench.py row {line:?}"));
        }
        let num = |s: &str| s.parse::<f64>().map_err(|e| format!("{line:?}: {e}"));
        let row = Row {
            field: c[0].into(),
            n: num(c[1])? as usize,
            method: c[2].into(),
            median_ms: num(c[4])?,
            min_ms: num(c[5])?,
            reps: num(c[6])? as usize,
            triangles: num(c[7])? as usize,
        };
        println!("{}", row.csv());
        rows.push(row);
    }
    println!();
    println!("field,n,method,median_over_flying_edges,min_over_flying_edges");
    for row in &rows {
        let fe = rows
            .iter()
            .find(|r| r.field == row.field && r.n == row.n && r.method == "vtk_flying_edges");
        if let Some(fe) = fe {
            println!(
                "{},{},{},{:.2},{:.2}",
                row.field,
                row.n,
                row.method,
                row.median_ms / fe.median_ms,
                row.min_ms / fe.min_ms
            );
        }
    }
    Ok(())
}

/// Runs `scripts/peer_bench.py` on the dump with `python`; its CSV output.
fn run_peers(python: &str, args: &Args) -> Result<String, String> {
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scripts/peer_bench.py");
    let out = std::process::Command::new(python)
        .arg(&script)
        .arg(&args.dir)
        .args(["--reps", &args.reps.to_string()])
        .stderr(std::process::Stdio::inherit())
        .output()
        .map_err(|e| format!("{python} {}: {e}", script.display()))?;
    if !out.status.success() {
        return Err(format!("peer_bench.py failed: {}", out.status));
    }
    String::from_utf8(out.stdout).map_err(|e| e.to_string())
}
