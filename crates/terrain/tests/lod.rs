//! The multiresolution mesh's surfaces: closed, manifold and oriented over random fields and
//! random 2:1-balanced level maps; the plain body-centred surface where the map is uniform;
//! byte-identical whatever the chunking, the thread count or the order of viewer moves.
//!
//! Case counts scale with `RMT_CASES` (default 64 per property test here; the level-map
//! sequences run `RMT_CASES / 16`, at least 4); `RMT_CASES=10000 cargo test --release -p
//! rmt-terrain --test lod` runs the long version.

mod common;

use foldhash::HashMap;

use common::{cases, config, geometry};
use glam::Vec3;
use proptest::prelude::*;
use rmt_fields::{RandomField, ScalarField};
use rmt_terrain::lod::check::{check_surface, check_tets};
use rmt_terrain::lod::lattice::{bcc_tet, canonical, cell_size, Point};
use rmt_terrain::lod::{
    chunk_tets, march, mesh_chunks, mesh_whole, same_bits, thread_pool, weld, world_tets,
    ChunkMesh, LevelMap, LodFrame, LodGeometry, LodSettings, LodWorld, MeshTet, TetKind,
};

proptest! {
    #![proptest_config(config())]

    /// Random field, random balanced map: no open edge inside the domain, no non-manifold or
    /// misoriented edge; chunk by chunk on 1 or 2 threads and the whole world at once give the
    /// same bytes.
    #[test]
    fn surfaces_are_closed_manifold_oriented_and_chunking_free(
        field_seed in any::<u64>(),
        map_seed in any::<u64>(),
        which in 0u8..3,
        split in 0.2f64..0.8,
    ) {
        let (g, frame) = geometry(which);
        let field = RandomField::from_seed(field_seed);
        let map = LevelMap::random(g, map_seed, split);
        prop_assert!(map.is_balanced());
        let one = mesh_chunks(&map, &field, &frame, &thread_pool(1).unwrap()).unwrap();
        let two = mesh_chunks(&map, &field, &frame, &thread_pool(2).unwrap()).unwrap();
        let whole = mesh_whole(&map, &field, &frame).unwrap();
        prop_assert!(same_bits(&one, &two), "1 vs 2 threads");
        prop_assert!(same_bits(&one, &whole), "chunks vs whole");
        let tets: Vec<_> = world_tets(&map).unwrap().into_iter().map(|(_, t)| t.tet).collect();
        let (_, boundary) = check_tets(&tets);
        let (mesh, keys) = weld(&one);
        let c = check_surface(&keys, &mesh.indices, &boundary);
        prop_assert_eq!(c.open_inside, 0, "{:?}", c);
        prop_assert_eq!(c.non_manifold, 0, "{:?}", c);
        prop_assert_eq!(c.misoriented, 0, "{:?}", c);
        prop_assert!(mesh
            .normals
            .iter()
            .all(|n| (Vec3::from(*n).length() - 1.0).abs() < 1e-4));
    }
}

/// A triangle as its three positions' bits, rotated so the smallest comes first (keeps the
/// orientation).
type TriBits = [[u32; 3]; 3];

fn triangles(
    mesh: &rmt_mesh::Mesh,
    keys: &[[Point; 2]],
    keep: impl Fn(&[Point; 2]) -> bool,
) -> Vec<TriBits> {
    let mut out: Vec<TriBits> = mesh
        .indices
        .chunks_exact(3)
        .filter(|t| t.iter().all(|&v| keep(&keys[v as usize])))
        .map(|t| {
            let p: [[u32; 3]; 3] =
                std::array::from_fn(|i| mesh.positions[t[i] as usize].map(f32::to_bits));
            let r = (0..3).min_by_key(|&i| p[i]).unwrap_or(0);
            [p[r], p[(r + 1) % 3], p[(r + 2) % 3]]
        })
        .collect();
    out.sort_unstable();
    out
}

/// Plain marching tetrahedra on the body-centred lattice of `level`: its tets enumerated
/// directly (every cell face with both cells in the world), not through the level map.
fn plain(
    g: &LodGeometry,
    level: u8,
    field: &dyn ScalarField,
    frame: &LodFrame,
) -> (rmt_mesh::Mesh, Vec<[Point; 2]>) {
    let s = cell_size(level);
    let n = g.world_size().map(|w| (w / s) as i32);
    let mut tets = Vec::new();
    for x in 0..n[0] {
        for y in 0..n[1] {
            for z in 0..n[2] {
                for axis in 0..3 {
                    if [x, y, z][axis] + 1 >= n[axis] {
                        continue;
                    }
                    for m in 0..4 {
                        tets.push(MeshTet {
                            tet: canonical(bcc_tet(level, [x, y, z], axis, m)),
                            level,
                            kind: TetKind::Bcc,
                        });
                    }
                }
            }
        }
    }
    tets.sort_unstable();
    let m = march(&tets, field, frame);
    weld([&m])
}

/// Whether all key points lie at least half a coarsest cell inside the world box, where both
/// the multiresolution domain (the coarsest tets with both cube centres in the world) and the
/// plain lattice's tets cover everything: a triangle's keys hold all four corners of its tet.
fn deep_inside(g: &LodGeometry) -> impl Fn(&[Point; 2]) -> bool {
    let m = cell_size(g.levels) / 2;
    let w = g.world_size();
    move |key| {
        key.iter()
            .all(|p| (0..3).all(|i| m <= i64::from(p[i]) && i64::from(p[i]) <= w[i] - m))
    }
}

fn light_config() -> ProptestConfig {
    ProptestConfig {
        cases: (cases(64) / 4).max(4),
        ..config()
    }
}

proptest! {
    #![proptest_config(light_config())]

    /// A uniform map is plain marching tetrahedra on that level's body-centred lattice: the
    /// same triangles, compared as sorted lists of position triples (bits, each rotated to
    /// start at its smallest position, so orientation counts and vertex numbering does not),
    /// away from the world's faces (the domain's boundary is the coarsest level's).
    #[test]
    fn uniform_maps_are_plain_body_centred_mt(field_seed in any::<u64>(), which in 0u8..3) {
        let (g, frame) = geometry(which);
        let field = RandomField::from_seed(field_seed);
        let pool = thread_pool(1).unwrap();
        for level in 0..=g.levels {
            let map = LevelMap::uniform(g, level);
            let (mesh, keys) = weld(&mesh_chunks(&map, &field, &frame, &pool).unwrap());
            let (pm, pk) = plain(&g, level, &field, &frame);
            let a = triangles(&mesh, &keys, deep_inside(&g));
            prop_assert_eq!(&a, &triangles(&pm, &pk, deep_inside(&g)));
        }
    }
}

/// Inside chunks of random maps whose neighbours within one chunk edge share their level, the
/// surface is plain marching tetrahedra of that level (shrunk by one cell of the level, where
/// transition tets cannot reach), compared as in `uniform_maps_are_plain_body_centred_mt`.
#[test]
fn uniform_regions_of_mixed_maps_are_plain_body_centred_mt() {
    let (g, frame) = geometry(3);
    let pool = thread_pool(2).unwrap();
    let mut compared = 0;
    for seed in 0..(cases(64) / 16).max(4) {
        let field = RandomField::from_seed(1000 + u64::from(seed));
        // Level 0 on the chunks below a plane x = const (a third to two thirds of the world),
        // balanced: uniform regions at level 0 and at the coarsest level, a seam between.
        let cut = g.world_size()[0] * i64::from(2 + seed % 3) / 6;
        let map = LevelMap::build(g, |k| k.bounds(&g).0[0] < cut);
        let (mesh, keys) = weld(&mesh_chunks(&map, &field, &frame, &pool).unwrap());
        let deep = deep_inside(&g);
        let plains: Vec<_> = (0..=g.levels)
            .map(|l| plain(&g, l, &field, &frame))
            .collect();
        for k in map.chunks() {
            let (lo, hi) = k.bounds(&g);
            let e = g.chunk_size(k.level);
            let around = map.leaves_touching(lo.map(|v| v - e), hi.map(|v| v + e));
            if around.iter().any(|n| n.level != k.level) {
                continue;
            }
            let s = cell_size(k.level);
            let inside = |key: &[Point; 2]| {
                deep(key)
                    && key.iter().all(|p| {
                        (0..3).all(|i| {
                            let v = i64::from(p[i]);
                            lo[i] + s <= v && v <= hi[i] - s
                        })
                    })
            };
            let (pm, pk) = &plains[k.level as usize];
            let a = triangles(&mesh, &keys, inside);
            assert_eq!(a, triangles(pm, pk, inside), "seed {seed}, chunk {k:?}");
            compared += a.len();
        }
    }
    assert!(compared > 0, "no uniform region compared");
}

/// A viewer moving through the world (and jumps between random maps): after every step the
/// incrementally re-meshed world equals a from-scratch meshing of the same map, byte for
/// byte, and some steps keep chunks.
#[test]
fn incremental_remesh_equals_from_scratch() {
    let steps = (cases(64) / 8).max(8);
    let (g, frame) = geometry(4);
    let field = RandomField::from_seed(7);
    let settings = LodSettings {
        geometry: g,
        frame,
        ratio: 0.5,
        threads: 2,
        morph: None,
        cluster: false,
    };
    let mut world = LodWorld::new(field.clone(), settings).unwrap();
    let pool = thread_pool(1).unwrap();
    let mut kept = 0;
    let mut remeshed = 0;
    let mut unchanged = 0;
    let mut old: Option<LevelMap> = None;
    for step in 0..steps {
        if step % 3 == 2 {
            world
                .set_level_map(LevelMap::random(g, u64::from(step), 0.5))
                .unwrap();
        } else {
            let t = step as f32 / steps as f32;
            world.set_viewer(Vec3::new(-0.9 + 1.8 * t, -0.5, -0.8 + 1.2 * t));
        }
        let r = world.remesh().unwrap();
        kept += r.kept;
        remeshed += r.remeshed.len();
        unchanged += r.unchanged.len();
        let map = world.level_map().unwrap().clone();
        // A chunk kept as unchanged has the same tets under both maps, built from scratch.
        for k in &r.unchanged {
            let before = old
                .as_ref()
                .expect("nothing is unchanged at the first remesh");
            assert_eq!(chunk_tets(before, k).unwrap(), chunk_tets(&map, k).unwrap());
            assert!(!r.remeshed.contains(k));
        }
        old = Some(map.clone());
        let fresh = mesh_chunks(&map, &field, &frame, &pool).unwrap();
        let mine: Vec<ChunkMesh> = world
            .chunk_meshes()
            .into_iter()
            .map(|(_, m)| m.clone())
            .collect();
        assert!(same_bits(&mine, &fresh), "step {step}");
        assert_eq!(
            r.triangles,
            fresh.iter().map(ChunkMesh::triangles).sum::<usize>()
        );
        assert!(world.memory_bytes() > 0);
    }
    assert!(kept > 0, "no step kept a chunk");
    assert!(remeshed > 0);
    assert!(unchanged > 0, "no marked chunk kept its tets");
    // The world took some chunks' tets from its cache (the fresh meshing builds them all).
    let c = world.tet_cache_stats();
    assert!(c.hits > 0 && c.entries > 0, "{c:?}");
}

/// The surfaces of a level change meet: every crossing on the seam is one vertex with one
/// normal (the two sides share it), so shading has no seam.
#[test]
fn seam_vertices_are_shared() {
    let (g, frame) = geometry(0);
    let field = RandomField::from_seed(11);
    let map = LevelMap::build(g, |k| k.bounds(&g).0[0] < g.world_size()[0] / 2);
    let meshes = mesh_chunks(&map, &field, &frame, &thread_pool(1).unwrap()).unwrap();
    let mut seen: HashMap<[Point; 2], ([u32; 3], usize)> = HashMap::default();
    let mut shared = 0;
    for (c, m) in meshes.iter().enumerate() {
        for (v, k) in m.keys.iter().enumerate() {
            let bits = m.normals[v].map(f32::to_bits);
            if let Some((n, owner)) = seen.get(k) {
                if *owner != c {
                    assert_eq!(*n, bits);
                    shared += 1;
                }
            } else {
                seen.insert(*k, (bits, c));
            }
        }
    }
    assert!(shared > 0);
}
