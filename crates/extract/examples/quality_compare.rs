//! Counts and quality of every clustering mode on the objects of the listing and the paper's
//! bunny: one line per configuration (for comparing two builds with `diff`).
//!
//! `cargo run --release -p rmt-extract --example quality_compare -- [sizes...]` (default 33 50);
//! `QC_ONLY=gyroid` keeps one object, `QC_DEBUG=1` also prints the clustering counters (groups
//! proposed and kept, repair rounds, lone crossings) to stderr.
use rmt_extract::{measure, Clustering, ExtractSettings, Extractor, Grid, Lattice, NormalMode};
use rmt_fields::{MeshSdf, ScalarField};

#[path = "common/objects.rs"]
mod objects;
use rmt_mesh::Mesh;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let sizes: Vec<usize> = std::env::args()
        .skip(1)
        .filter_map(|s| s.parse().ok())
        .collect();
    let sizes = if sizes.is_empty() {
        vec![33, 50]
    } else {
        sizes
    };
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let bunny_mesh = rmt_mesh::io::read_obj(root.join("data/bunny.obj"))?;
    let bmin = glam::Vec3::new(-4.96, -0.01, -3.73);
    let bmax = glam::Vec3::new(4.95, 9.66, 3.81);
    let bunny_grid = Grid::new([75, 40, 56], bmin, bmax);
    let bunny = MeshSdf::fit(&bunny_mesh, bmin, bmax, 0.09)?.with_band(2.0 * bunny_grid.h());
    let mut fields = objects::original();
    fields.extend(objects::added());
    let mut jobs: Vec<(&str, &dyn ScalarField, Grid)> = Vec::new();
    for (name, f) in &fields {
        for &n in &sizes {
            jobs.push((name, f.as_ref(), Grid::cube(n, 1.0)));
        }
    }
    jobs.push(("bunny", &bunny, bunny_grid));
    println!("object n lattice clustering triangles reduction ar_mean ar_p99 fid_mean_h euler nonmanifold");
    let only = std::env::var("QC_ONLY").ok();
    for (name, field, grid) in jobs {
        if only.as_deref().is_some_and(|o| o != name) {
            continue;
        }
        for lattice in [Lattice::BodyCentred, Lattice::Simple] {
            let mut base = 0usize;
            for clustering in [
                Clustering::None,
                Clustering::Integrated,
                Clustering::IntegratedUnchecked,
            ] {
                let mut s = ExtractSettings::new(grid, lattice, clustering);
                s.normals = NormalMode::Skip;
                let mut mesh = Mesh::default();
                let st = Extractor::new().extract(field, &s, &mut mesh)?;
                let m = measure::measure(&mesh, &st, Some(field), &s);
                if clustering == Clustering::None {
                    base = st.triangles;
                }
                let v = &m.validation;
                if std::env::var("QC_DEBUG").is_ok() {
                    eprintln!(
                        "  proposed {} committed {} rej_pre {} rej_check {} rounds {} lone {}",
                        st.clusters_proposed,
                        st.clusters_committed,
                        st.clusters_rejected_prefilter,
                        st.clusters_rejected_check,
                        st.repair_rounds,
                        st.lone_absorbed
                    );
                }
                println!(
                    "{name} {} {lattice:?} {clustering:?} {} {:.4} {:.4} {:.2} {:.4} {} {}",
                    grid.cells[0],
                    st.triangles,
                    1.0 - st.triangles as f64 / base.max(1) as f64,
                    m.quality.ar_mean,
                    m.quality.ar_p99,
                    m.fidelity_mean_h.unwrap_or(f64::NAN),
                    v.euler,
                    v.non_manifold_edges + v.non_manifold_vertices + v.orientation_errors,
                );
            }
        }
    }
    Ok(())
}
