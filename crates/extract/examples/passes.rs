//! Median vertex / geometry pass times on pre-sampled values (sampling excluded), per sample
//! point: `cargo run --release -p rmt-extract --example passes -- [n] [reps] [threads]`.
use rmt_extract::{Clustering, ExtractSettings, Extractor, Grid, Lattice, NormalMode};
use rmt_fields::{Asteroid, AsteroidParams, ScalarField, Sphere};
use rmt_mesh::Mesh;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() -> Result<(), rmt_extract::ExtractError> {
    let args: Vec<String> = std::env::args().collect();
    let n: usize = args.get(1).and_then(|s| s.parse().ok()).unwrap_or(64);
    let reps: usize = args
        .get(2)
        .and_then(|s| s.parse().ok())
        .unwrap_or(20)
        .max(1);
    let threads: usize = args.get(3).and_then(|s| s.parse().ok()).unwrap_or(1);
    let sphere = Sphere::new(glam::Vec3::ZERO, 0.8);
    let asteroid = Asteroid::new(glam::Vec3::ZERO, AsteroidParams::default());
    for (name, field) in [
        ("sphere", &sphere as &dyn ScalarField),
        ("asteroid", &asteroid),
    ] {
        for lattice in [Lattice::BodyCentred, Lattice::Simple] {
            for clustering in [
                Clustering::None,
                Clustering::Integrated,
                Clustering::IntegratedUnchecked,
            ] {
                let mut s = ExtractSettings::new(Grid::cube(n, 1.0), lattice, clustering);
                s.threads = threads;
                s.normals = NormalMode::Skip;
                let mut ex = Extractor::new();
                let mut mesh = Mesh::default();
                let first = ex.extract(field, &s, &mut mesh)?;
                let (mut v, mut g, mut t) = (Vec::new(), Vec::new(), Vec::new());
                for _ in 0..reps {
                    let st = ex.extract_presampled(&s, &mut mesh)?;
                    v.push(st.t_vertex_s);
                    g.push(st.t_geometry_s);
                    t.push(st.t_total_s);
                }
                let pts = first.sample_points as f64;
                println!(
                    "{name:8} {:6} {:10} n={n} threads={threads}: vertex {:7.2} ms  geometry {:7.2} ms  total {:7.2} ms  = {:6.1} ns/point ({} points, {} triangles)",
                    lattice.name(),
                    clustering.name(),
                    median(v.clone()) * 1e3,
                    median(g.clone()) * 1e3,
                    median(t.clone()) * 1e3,
                    median(t) * 1e9 / pts,
                    first.sample_points,
                    first.triangles
                );
            }
        }
    }
    Ok(())
}
