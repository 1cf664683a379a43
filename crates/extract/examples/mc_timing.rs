//! Times marching cubes (vertex and geometry passes, no sampling, no normals) on a sphere of
//! radius 0.8 in [-1, 1]^3 at 50^3 and 128^3 cells, per grid point.
//!
//! `cargo run --release -p rmt-extract --example mc_timing [threads] [runs]`

use rmt_extract::{Clustering, ExtractSettings, Extractor, Grid, Lattice, Method, NormalMode};
use rmt_fields::Sphere;
use rmt_mesh::Mesh;

/// CPU seconds used by this process so far (all threads), from /proc (Linux); `None` elsewhere.
fn cpu_seconds() -> Option<f64> {
    let stat = std::fs::read_to_string("/proc/self/stat").ok()?;
    let fields: Vec<&str> = stat.rsplit(')').next()?.split_whitespace().collect();
    let ticks: f64 = fields.get(11)?.parse::<f64>().ok()? + fields.get(12)?.parse::<f64>().ok()?;
    Some(ticks / 100.0)
}

fn main() -> Result<(), String> {
    let args: Vec<String> = std::env::args().collect();
    let threads: usize = args.get(1).and_then(|s| s.parse().ok()).unwrap_or(1);
    let runs: usize = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(9);
    let sphere = Sphere::new(glam::Vec3::ZERO, 0.8);
    for n in [50usize, 128] {
        let mut settings =
            ExtractSettings::new(Grid::cube(n, 1.0), Lattice::Simple, Clustering::None);
        settings.method = Method::Mc;
        settings.threads = threads;
        settings.normals = NormalMode::Skip;
        let mut extractor = Extractor::new();
        let mut mesh = Mesh::default();
        extractor
            .extract(&sphere, &settings, &mut mesh)
            .map_err(|e| e.to_string())?;
        let points = (n + 1).pow(3) as f64;
        let mut passes = Vec::new();
        let cpu0 = cpu_seconds();
        for _ in 0..runs {
            let stats = extractor
                .extract_presampled(&settings, &mut mesh)
                .map_err(|e| e.to_string())?;
            passes.push(stats.t_vertex_s + stats.t_geometry_s);
        }
        let cpu = match (cpu0, cpu_seconds()) {
            (Some(a), Some(b)) => format!("{:.1} ns CPU", (b - a) / runs as f64 / points * 1e9),
            _ => "n/a".into(),
        };
        passes.sort_by(f64::total_cmp);
        let median = passes[runs / 2];
        println!(
            "{n}^3, {threads} thread(s): median {:.2} ms = {:.1} ns per grid point ({cpu}); min {:.2} ms; {} triangles",
            median * 1e3,
            median / points * 1e9,
            passes[0] * 1e3,
            mesh.triangle_count()
        );
    }
    Ok(())
}
