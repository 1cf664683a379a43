//! One extraction of the sphere (radius 0.8 in [-1, 1]^3), to measure peak memory from outside:
//!
//! `/usr/bin/time -v target/release/examples/peak_memory [n] [clustering] [threads] [lean]`
//!
//! Defaults: 256 cells per axis, body-centred lattice, integrated clustering (`none` for plain
//! MT), 1 thread, normals skipped, buffers kept for reuse (`lean`:
//! [`rmt_extract::BufferPolicy::Lean`]). Prints the f32 sample array size and the other buffer sizes of
//! [`rmt_extract::Stats`], and this process's peak resident set (VmHWM, Linux) for comparison
//! with what `time -v` reports, in total and beyond the output mesh, as ratios to the samples.

use rmt_extract::{
    BufferPolicy, Clustering, ExtractSettings, Extractor, Grid, Lattice, NormalMode,
};
use rmt_fields::Sphere;
use rmt_mesh::Mesh;

/// Peak resident set size of this process in bytes, from /proc (Linux); `None` elsewhere.
fn peak_rss_bytes() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

fn mib(bytes: usize) -> f64 {
    bytes as f64 / (1024.0 * 1024.0)
}

fn main() -> Result<(), String> {
    let args: Vec<String> = std::env::args().collect();
    let n: usize = match args.get(1) {
        Some(s) => s.parse().map_err(|e| format!("cells {s:?}: {e}"))?,
        None => 256,
    };
    let clustering = match args.get(2).map(String::as_str) {
        None | Some("integrated") => Clustering::Integrated,
        Some("none") => Clustering::None,
        Some(other) => return Err(format!("clustering {other:?}: expected integrated or none")),
    };
    let threads: usize = match args.get(3) {
        Some(s) => s.parse().map_err(|e| format!("threads {s:?}: {e}"))?,
        None => 1,
    };
    let mut settings = ExtractSettings::new(Grid::cube(n, 1.0), Lattice::BodyCentred, clustering);
    settings.threads = threads;
    settings.normals = NormalMode::Skip;
    let mut extractor = Extractor::new();
    let lean = args.get(4).map(String::as_str) == Some("lean");
    if lean {
        extractor.set_buffer_policy(BufferPolicy::Lean);
    }
    let mut mesh = Mesh::default();
    let stats = extractor
        .extract(&Sphere::new(glam::Vec3::ZERO, 0.8), &settings, &mut mesh)
        .map_err(|e| e.to_string())?;
    println!(
        "{n}^3 bcdl {}, {threads} thread(s), buffers {}: {} sample points, {} triangles, {:.3} s",
        clustering.name(),
        if lean { "lean" } else { "reused" },
        stats.sample_points,
        stats.triangles,
        stats.t_total_s
    );
    println!(
        "f32 samples {:.1} MiB (storage incl. unused slots), dense f32 of the points {:.1} MiB",
        mib(stats.bytes_lattice),
        mib(stats.sample_points * 4)
    );
    println!(
        "edge tables {:.1} MiB, vertices {:.1} MiB, indices {:.1} MiB",
        mib(stats.bytes_edges),
        mib(stats.bytes_vertices),
        mib(stats.bytes_indices)
    );
    match peak_rss_bytes() {
        Some(b) => {
            println!(
                "peak RSS {:.1} MiB = {:.2} x the f32 sample array",
                mib(b as usize),
                b as f64 / stats.bytes_lattice as f64
            );
            // The measure: peak memory beyond the output mesh, against the samples.
            let output = stats.bytes_vertices + stats.bytes_indices;
            println!(
                "beyond the output mesh: {:.1} MiB = {:.2} x the f32 sample array",
                mib((b as usize).saturating_sub(output)),
                (b as usize).saturating_sub(output) as f64 / stats.bytes_lattice as f64
            );
        }
        None => println!("peak RSS: n/a"),
    }
    Ok(())
}
