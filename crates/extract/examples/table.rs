//! The issue-2 table: sphere (inscribed, r = 1) and asteroid at 50^3, both lattices, every
//! clustering mode; counts, reduction, quality, fidelity and median stage times of 20 runs.
//!
//! `cargo run --release -p rmt-extract --example table -- [reps] [threads]`
use rmt_extract::{measure, Clustering, ExtractSettings, Extractor, Grid, Lattice, Stats};
use rmt_fields::{Asteroid, AsteroidParams, ScalarField, Sphere};
use rmt_mesh::Mesh;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() -> Result<(), rmt_extract::ExtractError> {
    let args: Vec<String> = std::env::args().collect();
    let reps: usize = args
        .get(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(20)
        .max(1);
    let threads: usize = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(1);
    let sphere = Sphere::new(glam::Vec3::ZERO, 1.0);
    let asteroid = Asteroid::new(glam::Vec3::ZERO, AsteroidParams::default());
    println!("| object | lattice | clustering | vertices | triangles | reduction | AR mean | AR p99 | fidelity mean/max (h) | sampling ms | vertex ms | geometry ms | normals ms | total ms | committed/proposed |");
    println!("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|");
    for (name, field) in [
        ("sphere", &sphere as &dyn ScalarField),
        ("asteroid", &asteroid),
    ] {
        for lattice in [Lattice::BodyCentred, Lattice::Simple] {
            let mut base = 0;
            for clustering in [
                Clustering::None,
                Clustering::Integrated,
                Clustering::IntegratedUnchecked,
                Clustering::Postprocessed,
                Clustering::Meshopt,
            ] {
                let mut settings = ExtractSettings::new(Grid::cube(50, 1.0), lattice, clustering);
                settings.threads = threads;
                let mut ex = Extractor::new();
                let mut mesh = Mesh::default();
                let mut runs: Vec<Stats> = Vec::new();
                for _ in 0..reps {
                    runs.push(ex.extract(field, &settings, &mut mesh)?);
                }
                let m = measure(&mesh, &runs[0], Some(field), &settings);
                if clustering == Clustering::None {
                    base = m.stats.triangles;
                }
                let med = |f: fn(&Stats) -> f64| median(runs.iter().map(f).collect()) * 1e3;
                let fid = match (m.fidelity_mean_h, m.fidelity_max_h) {
                    (Some(a), Some(b)) => format!("{a:.3} / {b:.3}"),
                    _ => "n/a".into(),
                };
                println!(
                    "| {name} | {} | {} | {} | {} | {:.1}% | {:.3} | {:.3} | {fid} | {:.2} | {:.2} | {:.2} | {:.2} | {:.2} | {}/{} |{}",
                    lattice.name(),
                    clustering.name(),
                    m.stats.vertices,
                    m.stats.triangles,
                    100.0 * (1.0 - m.stats.triangles as f64 / base as f64),
                    m.quality.ar_mean,
                    m.quality.ar_p99,
                    med(|s| s.t_sampling_s),
                    med(|s| s.t_vertex_s),
                    med(|s| s.t_geometry_s),
                    med(|s| s.t_normals_s),
                    med(|s| s.t_total_s),
                    m.stats.clusters_committed,
                    m.stats.clusters_proposed,
                    if m.validation.is_watertight_manifold() { "" } else { " NOT MANIFOLD" },
                );
            }
        }
    }
    Ok(())
}
