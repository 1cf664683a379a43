//! Repeats one extraction on pre-sampled values, for profilers:
//! `cargo run --release -p rmt-extract --example one -- [sphere|asteroid] [n] [bcdl|simple]
//! [none|integrated|integrated-unchecked] [reps] [threads]`. Prints the median vertex, geometry
//! and total times.
use rmt_extract::{Clustering, ExtractSettings, Extractor, Grid, Lattice, NormalMode};
use rmt_fields::{Asteroid, AsteroidParams, ScalarField, Sphere};
use rmt_mesh::Mesh;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let arg = |i: usize, d: &str| args.get(i).cloned().unwrap_or_else(|| d.to_string());
    let field: Box<dyn ScalarField> = match arg(1, "asteroid").as_str() {
        "sphere" => Box::new(Sphere::new(glam::Vec3::ZERO, 0.8)),
        "asteroid" => Box::new(Asteroid::new(glam::Vec3::ZERO, AsteroidParams::default())),
        other => return Err(format!("unknown field {other}").into()),
    };
    let n: usize = arg(2, "64").parse()?;
    let lattice = match arg(3, "bcdl").as_str() {
        "bcdl" => Lattice::BodyCentred,
        "simple" => Lattice::Simple,
        other => return Err(format!("unknown lattice {other}").into()),
    };
    let clustering = match arg(4, "integrated").as_str() {
        "none" => Clustering::None,
        "integrated" => Clustering::Integrated,
        "integrated-unchecked" => Clustering::IntegratedUnchecked,
        other => return Err(format!("unknown clustering {other}").into()),
    };
    let reps: usize = arg(5, "50").parse::<usize>()?.max(1);
    let threads: usize = arg(6, "1").parse()?;
    let mut s = ExtractSettings::new(Grid::cube(n, 1.0), lattice, clustering);
    s.threads = threads;
    s.normals = NormalMode::Skip;
    let mut ex = Extractor::new();
    let mut mesh = Mesh::default();
    let first = ex.extract(field.as_ref(), &s, &mut mesh)?;
    let (mut v, mut g, mut t) = (Vec::new(), Vec::new(), Vec::new());
    for _ in 0..reps {
        let st = ex.extract_presampled(&s, &mut mesh)?;
        v.push(st.t_vertex_s);
        g.push(st.t_geometry_s);
        t.push(st.t_total_s);
    }
    let pts = first.sample_points as f64;
    println!(
        "vertex {:.2} ms  geometry {:.2} ms  total {:.2} ms = {:.1} ns/point ({} triangles)",
        median(v) * 1e3,
        median(g) * 1e3,
        median(t.clone()) * 1e3,
        median(t) * 1e9 / pts,
        first.triangles
    );
    Ok(())
}
