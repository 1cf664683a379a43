//! Prints a hash of the output mesh (positions, indices, main counters) for a fixed set of
//! fields, sizes, lattices, clustering modes and thread counts, with and without the tile rule of
//! chunked worlds (integrated clustering, checked or not, takes no tiles: its chunk lines,
//! "kept", keep the same cells without them): run it before and after a change
//! that must not change the meshes and compare the two listings.
//! `cargo run --release -p rmt-extract --example mesh_hashes [lean] [dense]` (`lean`: extractors
//! with [`rmt_extract::BufferPolicy::Lean`]; `dense`: [`rmt_extract::Sampling::Dense`] instead of
//! the default sparse sampling; every listing must equal the default one). Marching cubes, the
//! meshopt mode and the terrains come after the original listing, so an older listing is a
//! prefix-free subset: compare with `comm`. Surface nets comes last (its chunk line keeps cells
//! only: "kept"). `mesh_hashes.txt` beside this file is the listing of the last changes that
//! meant to change meshes: post-processed clustering (edge collapse) collapses what makes a
//! triangle degenerate (coincident crossings at once, slivers' shortest edges, in rounds), so its
//! 126 lines changed (0-4% fewer triangles); surface nets' 63 lines were appended after every
//! earlier line; every other line is as before.
use rmt_extract::{
    BufferPolicy, CellRange, Clustering, ExtractSettings, Extractor, Grid, Lattice, Method,
    NormalMode, Sampling, Tiling,
};
#[path = "common/objects.rs"]
mod objects;
use rmt_mesh::Mesh;

/// FNV-1a over 64-bit words.
fn fnv(h: &mut u64, x: u64) {
    for b in x.to_le_bytes() {
        *h ^= u64::from(b);
        *h = h.wrapping_mul(0x100_0000_01b3);
    }
}

fn main() -> Result<(), rmt_extract::ExtractError> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let policy = if args.iter().any(|a| a == "lean") {
        BufferPolicy::Lean
    } else {
        BufferPolicy::Reuse
    };
    let sampling = if args.iter().any(|a| a == "dense") {
        Sampling::Dense
    } else {
        Sampling::Sparse
    };
    let fields = objects::original();
    let more = objects::added();
    // The original listing, then marching cubes and meshopt for its fields, then the terrains
    // and the torus in every mode.
    let original = [
        (Method::Mt, Clustering::None),
        (Method::Mt, Clustering::Integrated),
        (Method::Mt, Clustering::IntegratedUnchecked),
        (Method::Mt, Clustering::Postprocessed),
    ];
    let added = [
        (Method::Mt, Clustering::Meshopt),
        (Method::Mc, Clustering::None),
    ];
    let all: Vec<(Method, Clustering)> = original.iter().chain(&added).copied().collect();
    // Surface nets (a peer) last, for every field, so every earlier line stays where it was.
    let peers = [(Method::SurfaceNets, Clustering::None)];
    let runs = [
        (&fields, &original[..]),
        (&fields, &added[..]),
        (&more, &all[..]),
        (&fields, &peers[..]),
        (&more, &peers[..]),
    ];
    for (fields, modes) in runs {
        for (name, field) in fields {
            for n in [16, 33, 64] {
                for lattice in [Lattice::BodyCentred, Lattice::Simple] {
                    for &(method, clustering) in modes {
                        if method != Method::Mt && lattice != Lattice::Simple {
                            continue;
                        }
                        for (threads, tiled) in [(1, false), (2, false), (2, true)] {
                            if method == Method::Mc && tiled {
                                continue;
                            }
                            let mut s =
                                ExtractSettings::new(Grid::cube(n, 1.0), lattice, clustering);
                            s.method = method;
                            s.threads = threads;
                            s.normals = NormalMode::Skip;
                            // Integrated clustering, checked or not, takes no tiles (its
                            // chunks are exact without them): its chunk keeps the cells only
                            // ("kept").
                            let tiles = tiled
                                && method == Method::Mt
                                && !matches!(
                                    clustering,
                                    Clustering::Integrated | Clustering::IntegratedUnchecked
                                );
                            if tiled {
                                // The tile rule of chunked worlds, for a sub-box at global cell
                                // (5, 0, 3) of a larger volume, keeping the triangles of some cells.
                                if tiles {
                                    s.tiles = Some(Tiling::new([8, 16, 8], [5, 0, 3]));
                                }
                                s.keep_cells = Some(CellRange {
                                    lo: [1, 0, 2],
                                    hi: [n - 1, n, n - 3],
                                });
                            }
                            let mut mesh = Mesh::default();
                            let mut ex = Extractor::new();
                            ex.set_buffer_policy(policy);
                            ex.set_sampling(sampling);
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
                                st.repair_rounds,
                                st.collapses,
                                st.discarded,
                            ] {
                                fnv(&mut h, c as u64);
                            }
                            let mode = match method {
                                Method::Mc => "marching-cubes",
                                Method::SurfaceNets => "surface-nets",
                                Method::Mt => clustering.name(),
                            };
                            println!(
                            "{name:9} n={n:2} {:6} {:20} t={threads}{}: {:6} triangles {h:016x}",
                            lattice.name(),
                            mode,
                            match (tiled, tiles) {
                                (true, true) => " tiled",
                                (true, false) => " kept",
                                _ => "",
                            },
                            st.triangles
                        );
                        }
                    }
                }
            }
        }
    }
    Ok(())
}
