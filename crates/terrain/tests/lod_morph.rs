//! Morphing between levels (`rmt_terrain::lod::Morph`): closed, manifold and oriented for any
//! viewer and band; byte-identical whatever the thread count, and re-meshed incrementally as
//! from scratch; and a chunk's change of level under the viewer's map moves the surface by
//! (nearly) nothing, where without the morph it pops.
//!
//! Case counts scale with `RMT_CASES` (default 64 here).

mod common;

use common::{cases, config};
use glam::Vec3;
use proptest::prelude::*;
use rmt_fields::{RandomField, ScalarField};
use rmt_terrain::lod::check::{check_surface, check_tets};
use rmt_terrain::lod::level_map::viewer_splits;
use rmt_terrain::lod::{
    mesh_chunks_morphed, same_bits, thread_pool, weld, world_tets, ChunkKey, ChunkMesh, LevelMap,
    LodFrame, LodGeometry, LodSettings, LodWorld, Morph, MorphSettings,
};

/// Worlds over `[-1, 1]` in x and z, where the random fields live.
fn geometry(which: u8) -> (LodGeometry, LodFrame) {
    let (g, h) = match which {
        0 => (LodGeometry::new(2, 2, [2, 1, 2]).unwrap(), 0.125),
        1 => (LodGeometry::new(2, 4, [1, 1, 1]).unwrap(), 0.125),
        _ => (LodGeometry::new(2, 4, [4, 1, 4]).unwrap(), 2.0 / 64.0),
    };
    (
        g,
        LodFrame {
            origin: Vec3::splat(-1.0),
            h,
        },
    )
}

/// A world position in lattice units.
fn to_u(frame: &LodFrame, p: Vec3) -> [f64; 3] {
    let u = f64::from(frame.h) * 0.5;
    ((p.as_dvec3() - frame.origin.as_dvec3()) / u).to_array()
}

proptest! {
    #![proptest_config(config())]

    /// Random field, viewer and band, the viewer's map: no open edge inside the domain, no
    /// non-manifold or misoriented edge, and the same bytes on 1 and 2 threads.
    #[test]
    fn morphed_surfaces_are_closed_manifold_oriented(
        field_seed in any::<u64>(),
        which in 0u8..3,
        x in -1.0f32..1.0,
        y in -1.0f32..0.0,
        z in -1.0f32..1.0,
        band in 0.05f64..1.0,
        ratio in 0.3f64..1.5,
    ) {
        let (g, frame) = geometry(which);
        let field = RandomField::from_seed(field_seed);
        let viewer = to_u(&frame, Vec3::new(x, y, z));
        let map = LevelMap::from_viewer(g, viewer, ratio);
        let morph = Morph::new(&g, ratio, band, 0.0, viewer).unwrap();
        let one = mesh_chunks_morphed(&map, &field, &frame, Some(&morph), &thread_pool(1).unwrap())
            .unwrap();
        let two = mesh_chunks_morphed(&map, &field, &frame, Some(&morph), &thread_pool(2).unwrap())
            .unwrap();
        prop_assert!(same_bits(&one, &two), "1 vs 2 threads");
        let tets: Vec<_> = world_tets(&map).unwrap().into_iter().map(|(_, t)| t.tet).collect();
        let (_, boundary) = check_tets(&tets);
        let (mesh, keys) = weld(&one);
        let c = check_surface(&keys, &mesh.indices, &boundary);
        prop_assert_eq!(c.open_inside, 0, "{:?}", c);
        prop_assert_eq!(c.non_manifold, 0, "{:?}", c);
        prop_assert_eq!(c.misoriented, 0, "{:?}", c);
    }
}

/// A viewer moving through a morphed world: after every step the incrementally re-meshed
/// world equals a from-scratch meshing of the same map with the same morph, byte for byte;
/// the morph changes the surface, and chunks out of every band are kept.
#[test]
fn incremental_morphed_remesh_equals_from_scratch() {
    let steps = (cases(64) / 8).max(8);
    let (g, frame) = geometry(2);
    let field = RandomField::from_seed(7);
    let settings = LodSettings {
        geometry: g,
        frame,
        ratio: 0.5,
        threads: 2,
        morph: Some(MorphSettings {
            band: 0.5,
            lead: 0.0,
        }),
        cluster: false,
    };
    let mut world = LodWorld::new(field.clone(), settings).unwrap();
    let pool = thread_pool(1).unwrap();
    let (mut kept, mut differs) = (0, 0);
    for step in 0..steps {
        let t = step as f32 / steps as f32;
        world.set_viewer(Vec3::new(-0.9 + 1.8 * t, -0.5, -0.8 + 1.2 * t));
        let r = world.remesh().unwrap();
        if step > 0 {
            kept += r.kept;
        }
        let map = world.level_map().unwrap().clone();
        let morph = *world.morph_now().expect("a morphed world has a morph");
        let fresh = mesh_chunks_morphed(&map, &field, &frame, Some(&morph), &pool).unwrap();
        let mine: Vec<ChunkMesh> = world
            .chunk_meshes()
            .into_iter()
            .map(|(_, m)| m.clone())
            .collect();
        assert!(same_bits(&mine, &fresh), "step {step}");
        let plain = mesh_chunks_morphed(&map, &field, &frame, None, &pool).unwrap();
        differs += usize::from(!same_bits(&plain, &fresh));
    }
    assert!(kept > 0, "no step kept a chunk");
    assert!(differs > 0, "the morph changed no surface");
}

/// The closest point of triangle `abc` to `p` (Ericson, Real-Time Collision Detection 5.1.5).
fn closest_on_triangle(p: Vec3, a: Vec3, b: Vec3, c: Vec3) -> Vec3 {
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return a;
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return a + ab * (d1 / (d1 - d3));
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return a + ac * (d2 / (d2 - d6));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
    }
    let denom = 1.0 / (va + vb + vc);
    a + ab * (vb * denom) + ac * (vc * denom)
}

/// The largest distance from a vertex of `from` inside the box `[lo, hi]` to the surface
/// `to` (brute force), or `None` without such a vertex.
fn one_way(from: &rmt_mesh::Mesh, to: &rmt_mesh::Mesh, lo: Vec3, hi: Vec3) -> Option<f32> {
    let tris: Vec<[Vec3; 3]> = to
        .indices
        .chunks_exact(3)
        .map(|t| std::array::from_fn(|i| Vec3::from(to.positions[t[i] as usize])))
        .collect();
    let mut worst: Option<f32> = None;
    for p in from.positions.iter().map(|&p| Vec3::from(p)) {
        if p.cmplt(lo).any() || p.cmpgt(hi).any() {
            continue;
        }
        let d = tris
            .iter()
            .map(|t| p.distance(closest_on_triangle(p, t[0], t[1], t[2])))
            .fold(f32::INFINITY, f32::min);
        worst = Some(worst.map_or(d, |w| w.max(d)));
    }
    worst
}

/// The pop of splitting each coarse chunk of the viewer's map (with the viewer where it is):
/// the Hausdorff distance between the two surfaces around the chunk, in cells of the finer
/// level. Without the morph the surface jumps; with it, the split chunk's finer values are the
/// coarser level's interpolant, so the surface stays.
#[test]
fn a_change_of_level_does_not_pop_under_the_morph() {
    let (g, frame) = geometry(2);
    let pool = thread_pool(2).unwrap();
    let ratio = 0.5;
    let (mut plain_max, mut morph_max, mut measured) = (0f32, 0f32, 0);
    for seed in 0..(cases(64) / 16).max(3) {
        let field = RandomField::from_seed(100 + u64::from(seed));
        let v = Vec3::new(-0.6 + 0.3 * seed as f32 % 1.2, -0.5, -0.4);
        let viewer = to_u(&frame, v);
        let map = LevelMap::from_viewer(g, viewer, ratio);
        let morph = Morph::new(&g, ratio, 0.5, 0.0, viewer).unwrap();
        let coarse: Vec<ChunkKey> = map
            .chunks()
            .iter()
            .copied()
            .filter(|k| k.level >= 1)
            .collect();
        for target in coarse.iter().step_by(5).take(4) {
            let split = LevelMap::build(g, |k| viewer_splits(&g, k, viewer, ratio) || k == target);
            let (lo, hi) = target.bounds(&g);
            let u = frame.h * 0.5;
            let world =
                |p: [i64; 3]| frame.origin + Vec3::new(p[0] as f32, p[1] as f32, p[2] as f32) * u;
            let (blo, bhi) = (world(lo), world(hi));
            let finer_cell = frame.h * (1u32 << (target.level - 1)) as f32;
            for (m, worst) in [(None, &mut plain_max), (Some(&morph), &mut morph_max)] {
                let a = weld(&mesh_chunks_morphed(&map, &field, &frame, m, &pool).unwrap()).0;
                let b = weld(&mesh_chunks_morphed(&split, &field, &frame, m, &pool).unwrap()).0;
                for d in [one_way(&a, &b, blo, bhi), one_way(&b, &a, blo, bhi)]
                    .into_iter()
                    .flatten()
                {
                    *worst = worst.max(d / finer_cell);
                    measured += 1;
                }
            }
        }
    }
    eprintln!("pop without the morph {plain_max:.4}, with it {morph_max:.6} finer cells ({measured} sides)");
    assert!(measured > 8, "{measured}");
    assert!(plain_max > 0.01, "no pop to remove: {plain_max}");
    assert!(
        morph_max < 1e-3,
        "the morphed surface moved {morph_max} finer cells"
    );
}

/// The field's values feed the morph: a field that is the coarse level's interpolant already
/// (linear) gives the same surface with and without it.
#[test]
fn a_linear_field_is_its_own_interpolant() {
    struct Plane;
    impl ScalarField for Plane {
        fn sample(&self, p: Vec3) -> f32 {
            0.3 * p.x + 0.5 * p.y - 0.2 * p.z + 0.01
        }
    }
    let (g, frame) = geometry(2);
    let viewer = to_u(&frame, Vec3::new(0.1, -0.5, 0.2));
    let map = LevelMap::from_viewer(g, viewer, 0.5);
    let morph = Morph::new(&g, 0.5, 1.0, 0.0, viewer).unwrap();
    let pool = thread_pool(1).unwrap();
    let a = mesh_chunks_morphed(&map, &Plane, &frame, None, &pool).unwrap();
    let b = mesh_chunks_morphed(&map, &Plane, &frame, Some(&morph), &pool).unwrap();
    let (ma, mb) = (weld(&a).0, weld(&b).0);
    assert_eq!(ma.indices, mb.indices);
    assert!(!ma.positions.is_empty());
    for (p, q) in ma.positions.iter().zip(&mb.positions) {
        assert!(
            Vec3::from(*p).distance(Vec3::from(*q)) < 1e-5,
            "{p:?} {q:?}"
        );
    }
}
