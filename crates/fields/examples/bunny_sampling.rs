//! Times sampling the bunny's signed distance on the body-centred lattice of a 75 x 40 x 56-cell
//! grid in [-1, 1]^3 (corners, centres and ghost centres, one z-plane per task) on 2 threads.
//!
//! `cargo run --release -p rmt-fields --example bunny_sampling [threads] [runs] [band]`
//!
//! Prints the median wall time and the CPU time per run (the latter is the better figure on a
//! machine shared with other work). `band` truncates the field (see `MeshSdf::with_band`).

use glam::Vec3;
use rayon::prelude::*;
use rmt_fields::{MeshSdf, ScalarField};
use rmt_mesh::Mesh;

fn load_bunny() -> Result<Mesh, String> {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../data/bunny.obj");
    let options = tobj::LoadOptions {
        triangulate: true,
        single_index: true,
        ..Default::default()
    };
    let (models, _) = tobj::load_obj(path, &options).map_err(|e| format!("{path}: {e}"))?;
    let mut mesh = Mesh::default();
    for m in models {
        let base = mesh.positions.len() as u32;
        mesh.positions
            .extend(m.mesh.positions.chunks_exact(3).map(|c| [c[0], c[1], c[2]]));
        mesh.indices
            .extend(m.mesh.indices.iter().map(|&i| i + base));
    }
    Ok(mesh)
}

/// Body-centred lattice points per z-plane (half-cube units), as the extractor lays them out:
/// even planes hold corners, odd planes centres; ghosts sit on the box faces.
fn planes(cells: [usize; 3], min: Vec3, max: Vec3) -> Vec<Vec<Vec3>> {
    let h = (max - min) / Vec3::new(cells[0] as f32, cells[1] as f32, cells[2] as f32) * 0.5;
    let n2 = cells.map(|c| 2 * c as i32);
    let mut out = Vec::new();
    for z in -1..=n2[2] + 1 {
        let odd = z & 1;
        let mut plane = Vec::new();
        for y in (-odd..=n2[1] + odd).step_by(2) {
            for x in (-odd..=n2[0] + odd).step_by(2) {
                let p = [x, y, z];
                let outside = (0..3).filter(|&a| p[a] < 0 || p[a] > n2[a]).count();
                if outside > 1 || (outside == 1 && odd == 0) {
                    continue;
                }
                let c = |a: usize| p[a].clamp(0, n2[a]) as f32 * h[a];
                plane.push(min + Vec3::new(c(0), c(1), c(2)));
            }
        }
        out.push(plane);
    }
    out
}

/// CPU seconds used by this process so far (all threads), from /proc (Linux), for timing on a
/// loaded machine; `None` elsewhere.
fn cpu_seconds() -> Option<f64> {
    let stat = std::fs::read_to_string("/proc/self/stat").ok()?;
    let fields: Vec<&str> = stat.rsplit(')').next()?.split_whitespace().collect();
    let ticks: f64 = fields.get(11)?.parse::<f64>().ok()? + fields.get(12)?.parse::<f64>().ok()?;
    Some(ticks / 100.0)
}

fn main() -> Result<(), String> {
    let args: Vec<String> = std::env::args().collect();
    let threads: usize = args.get(1).and_then(|s| s.parse().ok()).unwrap_or(2);
    let runs: usize = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(9);
    let (min, max) = (Vec3::splat(-1.0), Vec3::splat(1.0));
    let t = std::time::Instant::now();
    let band: f32 = args
        .get(3)
        .and_then(|s| s.parse().ok())
        .unwrap_or(f32::INFINITY);
    let sdf = MeshSdf::fit(&load_bunny()?, min, max, 0.05)
        .map_err(|e| e.to_string())?
        .with_band(band);
    println!("build: {:.1} ms", t.elapsed().as_secs_f64() * 1e3);
    let planes = planes([75, 40, 56], min, max);
    let total: usize = planes.iter().map(Vec::len).sum();
    println!("points: {total}");
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|e| e.to_string())?;
    let mut values: Vec<Vec<f32>> = planes.iter().map(|p| vec![0.0; p.len()]).collect();
    let mut times = Vec::new();
    let cpu0 = cpu_seconds();
    for _ in 0..runs {
        let t = std::time::Instant::now();
        pool.install(|| {
            values
                .par_iter_mut()
                .zip(&planes)
                .for_each(|(v, p)| sdf.sample_batch(p, v));
        });
        times.push(t.elapsed().as_secs_f64() * 1e3);
    }
    let inside = values.iter().flatten().filter(|v| **v < 0.0).count();
    if let (Some(a), Some(b)) = (cpu0, cpu_seconds()) {
        let per_run = (b - a) / runs as f64 * 1e3;
        println!(
            "CPU time per run: {per_run:.1} ms (all threads); / {threads} threads = {:.1} ms",
            per_run / threads as f64
        );
    }
    times.sort_by(f64::total_cmp);
    println!(
        "threads {threads}: median {:.1} ms, min {:.1} ms over {runs} runs; {inside} points inside",
        times[runs / 2],
        times[0]
    );
    Ok(())
}
