//! Clustering at every level (`rmt_terrain::lod::cluster`): over random fields and random
//! 2:1-balanced level maps, the clustered multiresolution surface is closed, manifold and
//! oriented, with the Euler characteristic and component count of the plain one, and no chunk's
//! worst triangle worse than max(10, the plain chunk's) (no sliver made); crossings
//! that two chunks share keep their plain vertex; a world that clusters re-meshes
//! incrementally to the same bytes as clustering a from-scratch meshing.
//!
//! Case counts scale with `RMT_CASES` (a quarter of it; 16 by default).

mod common;

use common::{cases, config, geometry};
use glam::Vec3;
use proptest::prelude::*;
use proptest::test_runner::Config as ProptestConfig;
use rmt_fields::{RandomFamily, RandomField, ScalarField, Sphere};
use rmt_mesh::quality::radius_ratio;
use rmt_mesh::validate::validate;
use rmt_terrain::lod::check::{check_surface, check_tets};
use rmt_terrain::lod::{
    cluster::SLIVER_RATIO, cluster_chunk, mesh_chunks, same_bits, thread_pool, weld, world_tets,
    ChunkMesh, ClusterCount, LevelMap, LodFrame, LodGeometry, LodSettings, LodWorld,
};

/// Every chunk clustered, with the counts summed.
fn clustered(plain: &[ChunkMesh], frame: &LodFrame) -> (Vec<ChunkMesh>, ClusterCount) {
    let mut sum = ClusterCount::default();
    let out = plain
        .iter()
        .map(|m| {
            let (c, n) = cluster_chunk(m, frame);
            sum += n;
            c
        })
        .collect();
    (out, sum)
}

/// The largest radius ratio R / (2r) of a chunk's triangles.
fn worst_ratio(m: &ChunkMesh) -> f64 {
    m.indices
        .chunks_exact(3)
        .map(|t| radius_ratio([0, 1, 2].map(|k| Vec3::from(m.positions[t[k] as usize]).as_dvec3())))
        .fold(0.0, f64::max)
}

/// Plain and clustered surfaces of `map` compared (module doc); returns the clustering's
/// counts and the two triangle totals.
fn compare(
    map: &LevelMap,
    field: &dyn ScalarField,
    frame: &LodFrame,
) -> Result<(ClusterCount, usize, usize), TestCaseError> {
    let plain = mesh_chunks(map, field, frame, &thread_pool(1).unwrap()).unwrap();
    let (clust, count) = clustered(&plain, frame);
    let tets: Vec<_> = world_tets(map)
        .unwrap()
        .into_iter()
        .map(|(_, t)| t.tet)
        .collect();
    let (_, boundary) = check_tets(&tets);
    let (pm, pkeys) = weld(&plain);
    let (cm, ckeys) = weld(&clust);
    let c = check_surface(&ckeys, &cm.indices, &boundary);
    prop_assert_eq!(c.open_inside, 0, "{:?} {:?}", c, count);
    prop_assert_eq!(c.non_manifold, 0, "{:?} {:?}", c, count);
    prop_assert_eq!(c.misoriented, 0, "{:?} {:?}", c, count);
    // The domain's boundary: where the plain surface is open, it stays open the same way.
    let p = check_surface(&pkeys, &pm.indices, &boundary);
    prop_assert_eq!(c.open_on_boundary, p.open_on_boundary);
    let g = map.geometry();
    let size = g.world_size();
    let lo = frame.origin;
    let hi = lo + Vec3::new(size[0] as f32, size[1] as f32, size[2] as f32) * (frame.h * 0.5);
    let eps = frame.h * 1e-3;
    let on_box =
        |q: [f32; 3]| (0..3).any(|i| (q[i] - lo[i]).abs() < eps || (q[i] - hi[i]).abs() < eps);
    let (vp, vc) = (validate(&pm, &on_box), validate(&cm, &on_box));
    prop_assert_eq!(vc.euler, vp.euler, "Euler characteristic");
    prop_assert_eq!(vc.components, vp.components, "components");
    prop_assert_eq!(vc.non_manifold_vertices, vp.non_manifold_vertices);
    prop_assert_eq!(vc.duplicate_triangles, 0);
    prop_assert_eq!(vc.unreferenced_vertices, 0);
    // Crossings that two chunks share keep their plain vertex, bit for bit.
    let mut seen: std::collections::HashMap<[rmt_terrain::lod::lattice::Point; 2], usize> =
        Default::default();
    for m in &plain {
        for k in &m.keys {
            *seen.entry(*k).or_default() += 1;
        }
    }
    for (m, c) in plain.iter().zip(&clust) {
        let index: std::collections::HashMap<_, usize> =
            c.keys.iter().enumerate().map(|(i, k)| (*k, i)).collect();
        for (k, p) in m.keys.iter().zip(&m.positions) {
            if seen[k] > 1 {
                let at = index.get(k).copied();
                prop_assert!(at.is_some(), "seam crossing {:?} merged", k);
                let at = at.unwrap_or(0);
                prop_assert_eq!(c.positions[at].map(f32::to_bits), p.map(f32::to_bits));
            }
        }
        // A merged vertex's key is its first member's reversed: never a crossing's.
        prop_assert!(c.keys.iter().filter(|[a, b]| a > b).count() <= count.merged);
        // No sliver made: the chunk's worst triangle is no worse than max(SLIVER_RATIO, the
        // plain chunk's worst).
        let (wp, wc) = (worst_ratio(m), worst_ratio(c));
        prop_assert!(
            wc <= wp.max(SLIVER_RATIO),
            "worst radius ratio {} clustered against {} plain",
            wc,
            wp
        );
    }
    Ok((count, pm.indices.len() / 3, cm.indices.len() / 3))
}

fn vec3(r: f32) -> impl Strategy<Value = Vec3> {
    (-r..r, -r..r, -r..r).prop_map(|(x, y, z)| Vec3::new(x, y, z))
}

/// The random fields of the extractor's tests (`RandomField::from_seed`), also squeezed so that
/// their features span a few finest cells, and the thin sheets and stairs (whole layers of
/// lattice points on the threshold) that `from_seed` does not draw.
fn field() -> impl Strategy<Value = RandomField> {
    let h = 2.0f32 / 64.0;
    prop_oneof![
        any::<u64>().prop_map(RandomField::from_seed),
        (any::<u64>(), 0.15f32..0.5)
            .prop_map(|(s, half)| RandomField::from_seed(s).in_box(Vec3::new(0.0, -0.5, 0.0), half)),
        (vec3(1.0), -0.5f32..0.5, (0.1 * h)..(1.0 * h)).prop_map(|(n, d, t)| RandomField {
            family: RandomFamily::Sheet(n, d, t),
            quantum: 0.0,
            centre: Vec3::ZERO,
            half: 1.0,
        }),
        (vec3(0.5 / h), -0.5f32..0.5).prop_map(|(k, b)| RandomField {
            family: RandomFamily::Stairs(k, b),
            quantum: 0.0,
            centre: Vec3::ZERO,
            half: 1.0,
        }),
    ]
}

proptest! {
    // A case meshes a few thousand chunks' worth of tets twice: a quarter of `RMT_CASES`.
    #![proptest_config(ProptestConfig { cases: (cases(64) / 4).max(4), ..config() })]

    /// Random fields and random balanced maps (module doc).
    #[test]
    fn clustered_surfaces_keep_the_plain_topology(
        field in field(),
        map_seed in any::<u64>(),
        which in 3u8..6,
        split in 0.2f64..0.8,
    ) {
        let (g, frame) = geometry(which);
        let map = LevelMap::random(g, map_seed, split);
        prop_assert!(map.is_balanced());
        compare(&map, &field, &frame)?;
    }
}

/// On a smooth surface the clustering merges most groups it tries, and the surface loses
/// triangles (inner chunks of a uniform map and of a mixed one).
#[test]
fn a_smooth_surface_loses_triangles() {
    let (g, frame) = geometry(5);
    let field = Sphere::new(Vec3::new(0.03, -0.47, 0.02), 0.41);
    for map in [
        LevelMap::uniform(g, 0),
        LevelMap::from_viewer(g, [0.0, 10.0, 0.0], 1.5),
    ] {
        let (count, plain, clust) = compare(&map, &field, &frame).unwrap();
        assert!(count.tried > 0, "{count:?}");
        assert!(2 * count.merged > count.tried, "{count:?}");
        assert!(clust < plain, "{clust} of {plain}");
        println!("{count:?}: {clust} of {plain} triangles");
    }
}

/// A world that clusters: after every viewer step its surfaces equal the clustered meshing of
/// its map from scratch, on 1 and 2 threads.
#[test]
fn a_clustering_world_remeshes_to_the_from_scratch_bytes() {
    let (g, frame): (LodGeometry, LodFrame) = geometry(5);
    let field = RandomField::from_seed(11);
    for threads in [1, 2] {
        let mut world = LodWorld::new(
            field.clone(),
            LodSettings {
                geometry: g,
                frame,
                ratio: 1.0,
                threads,
                morph: None,
                cluster: true,
            },
        )
        .unwrap();
        for step in 0..6 {
            let t = step as f32 / 5.0;
            world.set_viewer(Vec3::new(-0.9 + 1.8 * t, -0.5, -0.7 + 1.2 * t));
            world.remesh().unwrap();
            let map = world.level_map().unwrap().clone();
            let plain = mesh_chunks(&map, &field, &frame, &thread_pool(1).unwrap()).unwrap();
            let (scratch, _) = clustered(&plain, &frame);
            let now: Vec<ChunkMesh> = map
                .chunks()
                .iter()
                .map(|k| world.chunk_mesh(k).cloned().unwrap_or_default())
                .collect();
            assert!(same_bits(&now, &scratch), "step {step}, {threads} threads");
        }
    }
}
