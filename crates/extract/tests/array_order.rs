//! Array order ([`Extractor::set_array_order`]) for plain marching tetrahedra: the mesh is the
//! world-order mesh reordered, bit for bit (positions and normals reversed, every triangle's last
//! two corners swapped), on both lattices, one and two threads, every normal mode; and the modes
//! that do not honour the flag leave the mesh in world order.

use glam::Vec3;
use rmt_extract::{Clustering, ExtractSettings, Extractor, Grid, Lattice, Method, NormalMode};
use rmt_mesh::Mesh;

fn rev(v: &[[f32; 3]]) -> Vec<[f32; 3]> {
    v.iter().map(|p| [p[2], p[1], p[0]]).collect()
}

fn swap(i: &[u32]) -> Vec<u32> {
    i.chunks(3).flat_map(|t| [t[0], t[2], t[1]]).collect()
}

/// A deterministic value in [-1, 1) per index.
fn noise(seed: u64, i: usize) -> f32 {
    let mut z = seed
        .wrapping_mul(0x9E37_79B9_7F4A_7C15)
        .wrapping_add(i as u64);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^= z >> 31;
    (z >> 40) as f32 / (1u64 << 23) as f32 - 1.0
}

fn settings(cells: [usize; 3], lattice: Lattice, threads: usize) -> ExtractSettings {
    let grid = Grid::new(cells, Vec3::new(-1.0, -0.5, 0.0), Vec3::new(1.0, 0.7, 2.5));
    let mut s = ExtractSettings::new(grid, lattice, Clustering::None);
    s.threads = threads;
    s
}

#[test]
fn plain_mt_in_array_order_is_the_world_order_mesh_reordered_bit_for_bit() {
    let mut compared = 0;
    for seed in 0..16u64 {
        let cells = [
            5 + seed as usize % 4,
            4 + seed as usize % 3,
            6 + seed as usize % 5,
        ];
        let threads = 1 + seed as usize % 2;
        // White noise on the simple lattice, in place (many ambiguous quads, so both diagonals).
        let len = (cells[0] + 1) * (cells[1] + 1) * (cells[2] + 1);
        let values: Vec<f32> = (0..len).map(|i| noise(seed, i)).collect();
        for normals in [NormalMode::AreaWeighted, NormalMode::Skip] {
            let mut s = settings(cells, Lattice::Simple, threads);
            s.normals = normals;
            let (mut world, mut array) = (Mesh::default(), Mesh::default());
            let mut ex = Extractor::new();
            ex.extract_borrowed(&values, &s, &mut world).unwrap();
            ex.set_array_order(true);
            assert!(ex.writes_array_order(&s));
            ex.extract_borrowed(&values, &s, &mut array).unwrap();
            let what = format!("seed {seed} {normals:?}");
            assert!(!world.indices.is_empty(), "{what}");
            assert_eq!(rev(&array.positions), world.positions, "{what}");
            assert_eq!(swap(&array.indices), world.indices, "{what}");
            assert_eq!(rev(&array.normals), world.normals, "{what}");
            assert_eq!(
                world.normals.is_empty(),
                normals == NormalMode::Skip,
                "{what}"
            );
            compared += world.indices.len() / 3;
        }
        // A field on both lattices, with gradient and area normals.
        let ball = rmt_fields::Sphere::new(Vec3::new(0.1 * seed as f32 % 0.3, -0.2, 1.2), 0.9);
        for lattice in [Lattice::Simple, Lattice::BodyCentred] {
            for normals in [NormalMode::Gradient, NormalMode::AreaWeighted] {
                let mut s = settings(cells, lattice, threads);
                s.normals = normals;
                let (mut world, mut array) = (Mesh::default(), Mesh::default());
                let mut ex = Extractor::new();
                ex.extract(&ball, &s, &mut world).unwrap();
                ex.set_array_order(true);
                ex.extract(&ball, &s, &mut array).unwrap();
                let what = format!("seed {seed} {lattice:?} {normals:?}");
                assert!(!world.indices.is_empty(), "{what}");
                assert_eq!(rev(&array.positions), world.positions, "{what}");
                assert_eq!(swap(&array.indices), world.indices, "{what}");
                assert_eq!(rev(&array.normals), world.normals, "{what}");
                compared += world.indices.len() / 3;
            }
        }
    }
    assert!(compared > 10_000, "only {compared} triangles compared");
}

#[test]
fn modes_that_do_not_honour_the_flag_stay_in_world_order() {
    let sphere = rmt_fields::Sphere::new(Vec3::new(0.05, 0.1, 1.2), 0.8);
    for (clustering, method) in [
        (Clustering::Integrated, Method::Mt),
        (Clustering::Postprocessed, Method::Mt),
        (Clustering::None, Method::SurfaceNets),
    ] {
        let mut s = settings([9, 8, 10], Lattice::Simple, 2);
        s.clustering = clustering;
        s.method = method;
        let (mut world, mut flagged) = (Mesh::default(), Mesh::default());
        let mut ex = Extractor::new();
        ex.extract(&sphere, &s, &mut world).unwrap();
        ex.set_array_order(true);
        assert!(!ex.writes_array_order(&s), "{clustering:?} {method:?}");
        ex.extract(&sphere, &s, &mut flagged).unwrap();
        assert!(!world.indices.is_empty());
        assert_eq!(
            world.positions, flagged.positions,
            "{clustering:?} {method:?}"
        );
        assert_eq!(world.indices, flagged.indices, "{clustering:?} {method:?}");
    }
    // Marching cubes and plain MT do.
    let mut s = settings([9, 8, 10], Lattice::Simple, 1);
    let mut ex = Extractor::new();
    ex.set_array_order(true);
    assert!(ex.writes_array_order(&s));
    s.method = Method::Mc;
    assert!(ex.writes_array_order(&s));
    ex.set_array_order(false);
    assert!(!ex.writes_array_order(&s));
}
