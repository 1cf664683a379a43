//! Median vertex / geometry pass times on pre-sampled values (sampling excluded), per sample
//! point, for the sphere and the asteroid on both lattices, clustering none / integrated /
//! integrated-unchecked:
//!
//! ```text
//! cargo run --release -p rmt-extract --example passes -- [n] [reps] [threads] [filter]
//! ```
//!
//! For the clustering modes a second line splits the clustering part of the vertex pass into its
//! steps (see the `t_*_s` fields of `Stats`): the tests and the repair rounds run in parallel.
//!
//! `filter` keeps the configurations whose name (`field lattice clustering`, e.g.
//! `asteroid bcdl integrated`) is or contains it: `passes 64 50 1 "asteroid bcdl integrated"`
//! repeats one configuration, for a profiler; `passes 64 20 1 simple` all simple-lattice ones.
use rmt_extract::{Clustering, ExtractSettings, Extractor, Grid, Lattice, NormalMode};
use rmt_fields::{Asteroid, AsteroidParams, ScalarField, Sphere};
use rmt_mesh::Mesh;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// Argument `i` parsed, or `default` when it is absent; an error naming it when it is malformed.
fn arg<T: std::str::FromStr>(
    args: &[String],
    i: usize,
    name: &str,
    default: T,
) -> Result<T, Box<dyn std::error::Error>> {
    match args.get(i) {
        None => Ok(default),
        Some(s) => s.parse().map_err(|_| {
            format!("argument {i} ({name}): expected a whole number, got {s:?}").into()
        }),
    }
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let n: usize = arg(&args, 1, "n", 64)?;
    let reps: usize = arg(&args, 2, "reps", 20)?;
    let threads: usize = arg(&args, 3, "threads", 1)?;
    let filter = args.get(4).map_or("", String::as_str);
    if n == 0 || reps == 0 || threads == 0 {
        return Err("n, reps and threads must be at least 1".into());
    }
    let sphere = Sphere::new(glam::Vec3::ZERO, 0.8);
    let asteroid = Asteroid::new(glam::Vec3::ZERO, AsteroidParams::default());
    // A filter naming one configuration exactly keeps only that one.
    let exact = ["sphere", "asteroid"].iter().any(|f| {
        ["bcdl", "simple"].iter().any(|l| {
            ["none", "integrated", "integrated-unchecked"]
                .iter()
                .any(|c| format!("{f} {l} {c}") == filter)
        })
    });
    let mut shown = 0;
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
                let label = format!("{name} {} {}", lattice.name(), clustering.name());
                if !(label == filter || (!exact && label.contains(filter))) {
                    continue;
                }
                shown += 1;
                let mut s = ExtractSettings::new(Grid::cube(n, 1.0), lattice, clustering);
                s.threads = threads;
                s.normals = NormalMode::Skip;
                let mut ex = Extractor::new();
                let mut mesh = Mesh::default();
                let first = ex.extract(field, &s, &mut mesh)?;
                let (mut v, mut g, mut t) = (Vec::new(), Vec::new(), Vec::new());
                // The clustering steps inside the vertex pass, in order.
                let mut steps: [Vec<f64>; 4] = Default::default();
                for _ in 0..reps {
                    let st = ex.extract_presampled(&s, &mut mesh)?;
                    v.push(st.t_vertex_s);
                    g.push(st.t_geometry_s);
                    t.push(st.t_total_s);
                    for (acc, x) in steps.iter_mut().zip(st.merge_steps()) {
                        acc.push(x);
                    }
                }
                let pts = first.sample_points as f64;
                println!(
                    "{label:36} n={n} threads={threads}: vertex {:.2} ms  geometry {:.2} ms  total {:.2} ms = {:.1} ns/point ({} points, {} triangles)",
                    median(v) * 1e3,
                    median(g) * 1e3,
                    median(t.clone()) * 1e3,
                    median(t) * 1e9 / pts,
                    first.sample_points,
                    first.triangles
                );
                if clustering != Clustering::None {
                    println!(
                        "{:36}   of the vertex pass: {} ms",
                        "",
                        rmt_extract::Stats::merge_steps_text(steps.map(|s| median(s) * 1e3), 2)
                    );
                }
            }
        }
    }
    if shown == 0 {
        return Err(format!("no configuration matches {filter:?}").into());
    }
    Ok(())
}
