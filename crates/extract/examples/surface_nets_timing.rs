//! Times surface nets through the [`Extractor`] ([`Method::SurfaceNets`], pre-sampled, no
//! normals) against the `fast-surface-nets` crate called directly on the same sample values with
//! a reused buffer, at 64^3 cells, on a sphere and the asteroid: the extractor's overhead
//! (mapping positions into the box, copying into the mesh, counters). Runs alternate; medians.
//!
//! `cargo run --release -p rmt-extract --example surface_nets_timing [runs]`

use fast_surface_nets::ndshape::RuntimeShape;
use fast_surface_nets::{surface_nets, SurfaceNetsBuffer};
use rmt_extract::{
    Clustering, ExtractSettings, Extractor, Grid, Lattice, Method, NormalMode, Sampling,
};
use rmt_fields::{Asteroid, AsteroidParams, ScalarField, Sphere};
use rmt_mesh::Mesh;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() -> Result<(), String> {
    let runs: usize = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(21);
    let n = 64usize;
    let fields: [(&str, Box<dyn ScalarField>); 2] = [
        ("sphere", Box::new(Sphere::new(glam::Vec3::ZERO, 0.8))),
        (
            "asteroid",
            Box::new(Asteroid::new(glam::Vec3::ZERO, AsteroidParams::default())),
        ),
    ];
    for (name, field) in fields {
        let mut settings =
            ExtractSettings::new(Grid::cube(n, 1.0), Lattice::Simple, Clustering::None);
        settings.method = Method::SurfaceNets;
        settings.normals = NormalMode::Skip;
        let mut extractor = Extractor::new();
        extractor.set_sampling(Sampling::Dense);
        let mut mesh = Mesh::default();
        extractor
            .extract(field.as_ref(), &settings, &mut mesh)
            .map_err(|e| e.to_string())?;
        let values = extractor.samples().values.clone();
        let shape = RuntimeShape::<u32, 3>::new([n as u32 + 1; 3]);
        let mut buffer = SurfaceNetsBuffer::default();
        let (mut ours, mut passes, mut direct) = (Vec::new(), Vec::new(), Vec::new());
        for _ in 0..runs {
            let stats = extractor
                .extract_presampled(&settings, &mut mesh)
                .map_err(|e| e.to_string())?;
            ours.push(stats.t_total_s);
            passes.push(stats.t_vertex_s + stats.t_geometry_s);
            let t = std::time::Instant::now();
            surface_nets(&values, &shape, [0; 3], [n as u32; 3], &mut buffer);
            direct.push(t.elapsed().as_secs_f64());
        }
        assert_eq!(buffer.indices, mesh.indices, "the same triangles");
        let report = rmt_mesh::validate(&mesh, &|_| false);
        let (ours, passes, direct) = (median(ours), median(passes), median(direct));
        println!(
            "{name:8} {n}^3: extractor {:.3} ms (crate call + mapping {:.3} ms), direct {:.3} ms, \
             ratio {:.3}; {} triangles, {} boundary and {} non-manifold edges, median of {runs}",
            ours * 1e3,
            passes * 1e3,
            direct * 1e3,
            ours / direct,
            mesh.triangle_count(),
            report.boundary_edges_interior,
            report.non_manifold_edges
        );
    }
    Ok(())
}
