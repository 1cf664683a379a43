//! Prints a hash of the output mesh (positions, indices, main counters) for a fixed set of
//! fields, sizes, lattices, clustering modes and thread counts, with and without the tile rule of
//! chunked worlds: run it before and after a change
//! that must not change the meshes and compare the two listings.
//! `cargo run --release -p rmt-extract --example mesh_hashes [lean]` (`lean`: extractors with
//! [`rmt_extract::BufferPolicy::Lean`], whose listing must equal the default one).
use rmt_extract::{
    BufferPolicy, CellRange, Clustering, ExtractSettings, Extractor, Grid, Lattice, NormalMode,
    Tiling,
};
use rmt_fields::{Asteroid, AsteroidParams, Gyroid, ScalarField, Sphere};
use rmt_mesh::Mesh;

/// FNV-1a over 64-bit words.
fn fnv(h: &mut u64, x: u64) {
    for b in x.to_le_bytes() {
        *h ^= u64::from(b);
        *h = h.wrapping_mul(0x100_0000_01b3);
    }
}

fn main() -> Result<(), rmt_extract::ExtractError> {
    let policy = match std::env::args().nth(1).as_deref() {
        Some("lean") => BufferPolicy::Lean,
        _ => BufferPolicy::Reuse,
    };
    let fields: Vec<(&str, Box<dyn ScalarField>)> = vec![
        ("sphere", Box::new(Sphere::new(glam::Vec3::ZERO, 0.8))),
        // Touches the box and passes through sample points: welds and border rules.
        ("inscribed", Box::new(Sphere::new(glam::Vec3::ZERO, 1.0))),
        (
            "asteroid",
            Box::new(Asteroid::new(glam::Vec3::ZERO, AsteroidParams::default())),
        ),
        (
            "gyroid",
            Box::new(Gyroid {
                frequency: 1.5,
                thickness: 0.3,
            }),
        ),
    ];
    for (name, field) in &fields {
        for n in [16, 33, 64] {
            for lattice in [Lattice::BodyCentred, Lattice::Simple] {
                for clustering in [
                    Clustering::None,
                    Clustering::Integrated,
                    Clustering::IntegratedUnchecked,
                    Clustering::Postprocessed,
                ] {
                    for (threads, tiled) in [(1, false), (2, false), (2, true)] {
                        let mut s = ExtractSettings::new(Grid::cube(n, 1.0), lattice, clustering);
                        s.threads = threads;
                        s.normals = NormalMode::Skip;
                        if tiled {
                            // The tile rule of chunked worlds, for a sub-box at global cell
                            // (5, 0, 3) of a larger volume, keeping the triangles of some cells.
                            s.tiles = Some(Tiling::new([8, 16, 8], [5, 0, 3]));
                            s.keep_cells = Some(CellRange {
                                lo: [1, 0, 2],
                                hi: [n - 1, n, n - 3],
                            });
                        }
                        let mut mesh = Mesh::default();
                        let mut ex = Extractor::new();
                        ex.set_buffer_policy(policy);
                        let st = ex.extract(field.as_ref(), &s, &mut mesh)?;
                        let mut h = 0xcbf2_9ce4_8422_2325u64;
                        for p in &mesh.positions {
                            for c in p {
                                fnv(&mut h, u64::from(c.to_bits()));
                            }
                        }
                        for &i in &mesh.indices {
                            fnv(&mut h, u64::from(i));
                        }
                        for c in [
                            st.edges,
                            st.crossings,
                            st.tetrahedra_processed,
                            st.clusters_proposed,
                            st.clusters_committed,
                            st.clusters_rejected,
                            st.lone_absorbed,
                            st.repair_rounds,
                            st.collapses,
                            st.discarded,
                        ] {
                            fnv(&mut h, c as u64);
                        }
                        println!(
                            "{name:9} n={n:2} {:6} {:20} t={threads}{}: {:6} triangles {h:016x}",
                            lattice.name(),
                            clustering.name(),
                            if tiled { " tiled" } else { "" },
                            st.triangles
                        );
                    }
                }
            }
        }
    }
    Ok(())
}
