//! Prints the statistics of one extraction: `cargo run --release -p rmt-extract --example stats -- [n] [radius]`.
use rmt_extract::{Clustering, ExtractSettings, Extractor, Grid, Lattice};
use rmt_fields::Sphere;
use rmt_mesh::Mesh;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let n = args.get(1).and_then(|s| s.parse().ok()).unwrap_or(50);
    let r = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(1.0);
    let field = Sphere::new(glam::Vec3::ZERO, r);
    for lattice in [Lattice::BodyCentred, Lattice::Simple] {
        for clustering in [
            Clustering::None,
            Clustering::Integrated,
            Clustering::IntegratedUnchecked,
            Clustering::Postprocessed,
        ] {
            let settings = ExtractSettings::new(Grid::cube(n, 1.0), lattice, clustering);
            let mut mesh = Mesh::default();
            match Extractor::new().extract(&field, &settings, &mut mesh) {
                Ok(s) => println!(
                    "{lattice:?} {clustering:?}: v {} t {} disc {} proposed {} committed {} rej_pre {} rej_check {} vertex {:.4}s geom {:.4}s",
                    s.vertices, s.triangles, s.discarded, s.clusters_proposed, s.clusters_committed, s.clusters_rejected_prefilter, s.clusters_rejected_check, s.t_vertex_s, s.t_geometry_s
                ),
                Err(e) => println!("{lattice:?} {clustering:?}: {e}"),
            }
        }
    }
}
