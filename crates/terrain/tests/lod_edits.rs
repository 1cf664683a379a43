//! Edits on the multiresolution world (issue 40, part 5): a sparse overlay of brush strokes,
//! sampled by every level at its own lattice points; an edit re-meshes the chunks that see it,
//! survives a change of level, and works at distant, coarse levels.
//!
//! Every step compares the incrementally updated world with a from-scratch meshing of the
//! field plus the overlay, byte for byte.

use glam::Vec3;
use rmt_fields::{RandomField, ScalarField};
use rmt_terrain::lod::check::{check_surface, check_tets};
use rmt_terrain::lod::{
    mesh_chunks, same_bits, thread_pool, weld, world_tets, ChunkKey, ChunkMesh, EditedField,
    LevelMap, LodFrame, LodGeometry, LodSettings, LodWorld, Overlay,
};
use rmt_terrain::Brush;

/// Rolling ground: inside (f < 0) below `y = ground(x, z)`.
#[derive(Clone)]
struct Ground;

fn ground(x: f32, z: f32) -> f32 {
    -0.75 + 0.05 * (5.0 * x).sin() * (4.0 * z).sin()
}

impl ScalarField for Ground {
    fn sample(&self, p: Vec3) -> f32 {
        p.y - ground(p.x, p.z)
    }
}

/// Cells of `h = 1 / 32`, levels 0..=2, chunks of 4^3 cells, `roots` coarsest chunks along x
/// and z: `[-1, -1 + roots / 2]` along x and z, `[-1, -0.5]` along y.
fn settings(roots: u32, threads: usize) -> LodSettings {
    LodSettings {
        geometry: LodGeometry::new(2, 4, [roots, 1, roots]).unwrap(),
        frame: LodFrame {
            origin: Vec3::splat(-1.0),
            h: 1.0 / 32.0,
        },
        ratio: 0.5,
        threads,
        morph: None,
        cluster: false,
    }
}

/// The world's chunk meshes against a from-scratch meshing of its map over field + overlay
/// (and the surface closed, manifold and oriented inside the domain).
fn assert_from_scratch<F: ScalarField + Clone>(world: &LodWorld<F>, field: &F, what: &str) {
    let map = world.level_map().unwrap().clone();
    let edited = EditedField::new(field, world.edits());
    let fresh = mesh_chunks(
        &map,
        &edited,
        &world.settings().frame,
        &thread_pool(1).unwrap(),
    )
    .unwrap();
    let mine: Vec<ChunkMesh> = world
        .chunk_meshes()
        .into_iter()
        .map(|(_, m)| m.clone())
        .collect();
    assert!(
        same_bits(&mine, &fresh),
        "{what}: incremental != from scratch"
    );
    let tets: Vec<_> = world_tets(&map)
        .unwrap()
        .into_iter()
        .map(|(_, t)| t.tet)
        .collect();
    let (_, boundary) = check_tets(&tets);
    let (mesh, keys) = weld(&mine);
    let c = check_surface(&keys, &mesh.indices, &boundary);
    assert_eq!(
        (c.open_inside, c.non_manifold, c.misoriented),
        (0, 0, 0),
        "{what}: {c:?}"
    );
}

/// The chunks whose box holds world point `p`.
fn chunk_at(world: &LodWorld<impl ScalarField>, p: Vec3) -> ChunkKey {
    let f = world.settings().frame;
    let u = (p - f.origin) / (f.h * 0.5);
    let p4 = [u.x, u.y, u.z].map(|v| (4.0 * v).floor() as i64);
    let map = world.level_map().unwrap();
    let g = map.geometry();
    *map.chunks()
        .iter()
        .find(|k| {
            let (lo, hi) = k.bounds(g);
            (0..3).all(|i| 4 * lo[i] <= p4[i] && p4[i] < 4 * hi[i])
        })
        .unwrap()
}

/// The lowest vertex below the unedited ground within `r` (horizontally) of `c`:
/// `min (y - ground(x, z))`.
fn dip(world: &LodWorld<impl ScalarField>, c: Vec3, r: f32) -> f32 {
    let (mesh, _) = world.mesh_welded();
    mesh.positions
        .iter()
        .filter(|p| Vec3::new(p[0] - c.x, 0.0, p[2] - c.z).length() < r)
        .map(|p| p[1] - ground(p[0], p[2]))
        .fold(f32::INFINITY, f32::min)
}

#[test]
fn edits_remesh_the_chunks_that_see_them_and_equal_from_scratch() {
    for (which, field) in [
        (0, None),
        (1, Some(RandomField::from_seed(5))),
        (2, Some(RandomField::from_seed(23))),
    ] {
        let s = settings(4, 2);
        match field {
            None => run_edits(LodWorld::new(Ground, s).unwrap(), &Ground, which),
            Some(f) => run_edits(LodWorld::new(f.clone(), s).unwrap(), &f, which),
        }
    }
}

fn run_edits<F: ScalarField + Clone>(mut world: LodWorld<F>, field: &F, which: u64) {
    world.set_viewer(Vec3::new(-0.6, -0.75, -0.6));
    world.remesh().unwrap();
    let total = world.level_map().unwrap().chunks().len();
    let mut changed = 0;
    let mut levels = std::collections::BTreeSet::new();
    // Strokes near the viewer (level 0) and far from it (coarser levels), adding and removing.
    let centres = [
        Vec3::new(-0.6, -0.75, -0.55),
        Vec3::new(0.7, -0.72, 0.6),
        Vec3::new(-0.1, -0.8, 0.3),
        Vec3::new(0.5, -0.7, -0.6),
        Vec3::new(0.9, -0.75, 0.9),
    ];
    for (i, &c) in centres.iter().enumerate() {
        let before: Vec<ChunkMesh> = world
            .chunk_meshes()
            .into_iter()
            .map(|(_, m)| m.clone())
            .collect();
        // Random fields reach +-1: a stronger brush.
        let strength = if which == 0 { 2.0 } else { 10.0 };
        let brush = if (i as u64 + which).is_multiple_of(2) {
            Brush::subtract(c, 0.15, strength)
        } else {
            Brush::add(c, 0.12, strength).with_clamp(0.5)
        };
        let marked = world.edit(&brush, 0.1).unwrap();
        assert!(
            marked >= 1 && marked < total,
            "stroke {i}: {marked} of {total}"
        );
        levels.insert(chunk_at(&world, c).level);
        let r = world.remesh().unwrap();
        // No level change: exactly the marked chunks are re-meshed.
        assert_eq!(r.remeshed.len(), marked, "stroke {i}");
        assert_eq!(r.kept, total - marked);
        assert!(r.dropped.is_empty());
        let after: Vec<ChunkMesh> = world
            .chunk_meshes()
            .into_iter()
            .map(|(_, m)| m.clone())
            .collect();
        if !same_bits(&before, &after) {
            changed += 1;
        }
        assert_from_scratch(&world, field, &format!("field {which}, stroke {i}"));
    }
    // Every stroke on the ground changes it; random fields may have no surface under some.
    let want = if which == 0 { centres.len() } else { 1 };
    assert!(
        changed >= want,
        "field {which}: only {changed} strokes changed the surface"
    );
    assert!(
        levels.iter().any(|&l| l >= 1) && levels.contains(&0),
        "strokes at levels {levels:?}"
    );
    // A stroke outside the world marks nothing and stores nothing.
    let n = world.edits().strokes().len();
    assert_eq!(
        world
            .edit(&Brush::add(Vec3::splat(50.0), 0.1, 1.0), 0.1)
            .unwrap(),
        0
    );
    assert_eq!(world.edits().strokes().len(), n);
    assert!(world
        .edit(&Brush::add(Vec3::ZERO, f32::NAN, 1.0), 0.1)
        .is_err());
}

/// An edit seen at level 0, then the viewer flies away so the edited chunks are meshed at a
/// coarser level, then back: the pit stays (at every level the surface near the edit sits
/// well below the unedited ground), and each step equals from scratch.
#[test]
fn an_edit_survives_changes_of_level() {
    let mut world = LodWorld::new(Ground, settings(4, 2)).unwrap();
    let c = Vec3::new(-0.55, -0.75, -0.55);
    world.set_viewer(c);
    world.remesh().unwrap();
    let unedited = dip(&world, c, 0.1);
    assert!(unedited.abs() < 0.02, "{unedited}");
    let at0 = chunk_at(&world, c);
    assert_eq!(at0.level, 0);
    world.edit(&Brush::subtract(c, 0.3, 2.0), 0.1).unwrap();
    world.remesh().unwrap();
    assert_from_scratch(&world, &Ground, "edited at level 0");
    // The stroke raises values by 0.2 at its centre: the ground sinks by about 0.2.
    let d0 = dip(&world, c, 0.1);
    assert!(d0 < -0.12, "level 0: {d0}");
    let mut seen = vec![0u8];
    for (step, viewer) in [
        Vec3::new(0.2, -0.75, 0.2),
        Vec3::new(0.95, -0.75, 0.95),
        Vec3::new(-0.5, -0.75, -0.6),
    ]
    .into_iter()
    .enumerate()
    {
        world.set_viewer(viewer);
        let r = world.remesh().unwrap();
        assert!(!r.remeshed.is_empty());
        assert_from_scratch(&world, &Ground, &format!("step {step}"));
        let k = chunk_at(&world, c);
        seen.push(k.level);
        let d = dip(&world, c, 0.15);
        assert!(d < -0.1, "step {step}, level {}: {d}", k.level);
        // The same map without the edit has no pit: the edit is what the surface shows.
        let plain = mesh_chunks(
            world.level_map().unwrap(),
            &Ground,
            &world.settings().frame,
            &thread_pool(1).unwrap(),
        )
        .unwrap();
        let (pm, _) = weld(&plain);
        let pd = pm
            .positions
            .iter()
            .filter(|p| Vec3::new(p[0] - c.x, 0.0, p[2] - c.z).length() < 0.15)
            .map(|p| p[1] - ground(p[0], p[2]))
            .fold(f32::INFINITY, f32::min);
        assert!(pd > -0.03, "step {step}: unedited dip {pd}");
    }
    assert!(
        seen.contains(&2),
        "the edited chunk never reached level 2: {seen:?}"
    );
    assert_eq!(*seen.last().unwrap(), 0);
}

/// A small stroke on a distant chunk of the coarsest level: marked, re-meshed, and the same as
/// from scratch; a finer map sees the same edit.
#[test]
fn edits_at_distant_coarse_levels_work() {
    let mut world = LodWorld::new(Ground, settings(4, 1)).unwrap();
    world.set_viewer(Vec3::new(-0.9, -0.75, -0.9));
    world.remesh().unwrap();
    let c = Vec3::new(0.8, -0.75, 0.8);
    assert_eq!(chunk_at(&world, c).level, 2);
    let before = dip(&world, c, 0.2);
    let marked = world.edit(&Brush::subtract(c, 0.25, 2.0), 0.1).unwrap();
    assert!(marked >= 1);
    let r = world.remesh().unwrap();
    assert_eq!(r.remeshed.len(), marked);
    assert!(r.remeshed.iter().all(|k| k.level >= 1), "{:?}", r.remeshed);
    assert_from_scratch(&world, &Ground, "coarse edit");
    let after = dip(&world, c, 0.2);
    assert!(after < before - 0.08, "{before} -> {after}");
    // Samples nest: a lattice point shared by levels 0 and 2 has one edited value.
    let f = world.settings().frame;
    let edited = EditedField::new(&Ground, world.edits());
    let p = f.world([112, 16, 112]);
    assert_ne!(edited.sample(p), Ground.sample(p));
    let uniform = LevelMap::uniform(*world.level_map().unwrap().geometry(), 0);
    let fine = mesh_chunks(&uniform, &edited, &f, &thread_pool(2).unwrap()).unwrap();
    let (fm, _) = weld(&fine);
    let fd = fm
        .positions
        .iter()
        .filter(|p| Vec3::new(p[0] - c.x, 0.0, p[2] - c.z).length() < 0.2)
        .map(|p| p[1] - ground(p[0], p[2]))
        .fold(f32::INFINITY, f32::min);
    // The stroke raises values by 0.2 at its centre; the surface there sinks by t with
    // t = 0.2 (1 - (t / 0.25)^2)^2, t = 0.118.
    assert!(fd < -0.11, "level 0 sees {fd}");
}

/// The overlay's memory is its strokes: the same strokes cost the same bytes in a world 4
/// times wider (16 times the ground), bytes grow about linearly with the strokes, and a world
/// without edits holds none.
#[test]
fn overlay_memory_follows_the_edits_not_the_world() {
    let strokes = |n: usize| -> Vec<Brush> {
        (0..n)
            .map(|i| {
                let t = i as f32 / n as f32;
                Brush::subtract(
                    Vec3::new(-0.8 + 1.6 * t, -0.75, 0.3 * (7.0 * t).sin()),
                    0.1,
                    1.0,
                )
            })
            .collect()
    };
    let bytes = |roots: u32, n: usize| {
        let mut w = LodWorld::new(Ground, settings(roots, 1)).unwrap();
        let empty = w.memory_bytes();
        for b in strokes(n) {
            w.edit(&b, 0.1).unwrap();
        }
        assert_eq!(w.memory_bytes() - empty, w.edits().bytes());
        w.edits().bytes()
    };
    assert_eq!(Overlay::new(settings(1, 1).frame).bytes(), 0);
    let (a, b) = (bytes(4, 64), bytes(16, 64));
    assert_eq!(a, b, "the same strokes in a 16 times larger world");
    let double = bytes(4, 128);
    assert!(double > a + a / 4 && double < 3 * a, "{a} -> {double}");
    assert!(a < 64 * 8 * 80, "{a} bytes for 64 strokes");
}

fn cases(default: u32) -> u32 {
    std::env::var("RMT_CASES")
        .ok()
        .and_then(|s| s.parse().ok())
        .map_or(default, |n: u32| (n / 16).max(default))
}

proptest::proptest! {
    #![proptest_config(proptest::test_runner::Config {
        cases: cases(8),
        failure_persistence: None,
        ..proptest::test_runner::Config::default()
    })]

    /// Random fields, random balanced maps and random strokes (adding or removing, clamped or
    /// not, any size), interleaved: after every step the incremental world equals a
    /// from-scratch meshing of field + overlay, byte for byte, closed, manifold and oriented.
    #[test]
    fn random_strokes_and_maps_equal_from_scratch(
        field_seed in proptest::prelude::any::<u64>(),
        map_seeds in proptest::collection::vec(proptest::prelude::any::<u64>(), 3),
        strokes in proptest::collection::vec(
            ((-1.2f32..1.2, -1.2f32..1.2, -1.2f32..1.2), 0.05f32..0.6, 0.5f32..10.0, 0u8..4),
            4,
        ),
    ) {
        let field = RandomField::from_seed(field_seed);
        let s = LodSettings {
            geometry: LodGeometry::new(2, 2, [2, 1, 2]).unwrap(),
            frame: LodFrame { origin: Vec3::splat(-1.0), h: 0.125 },
            ratio: 0.5,
            threads: 2,
            morph: None,
            cluster: false,
        };
        let g = s.geometry;
        let mut world = LodWorld::new(field.clone(), s).unwrap();
        world.set_level_map(LevelMap::random(g, map_seeds[0], 0.5)).unwrap();
        world.remesh().unwrap();
        for (i, ((x, y, z), radius, strength, kind)) in strokes.into_iter().enumerate() {
            let c = Vec3::new(x, y, z);
            let brush = match kind {
                0 => Brush::add(c, radius, strength),
                1 => Brush::subtract(c, radius, strength),
                2 => Brush::add(c, radius, strength).with_clamp(0.3),
                _ => Brush::subtract(c, radius, strength).with_clamp(0.3),
            };
            world.edit(&brush, 0.05).unwrap();
            if i % 2 == 1 {
                world
                    .set_level_map(LevelMap::random(g, map_seeds[1 + i / 2], 0.5))
                    .unwrap();
            }
            world.remesh().unwrap();
            assert_from_scratch(&world, &field, &format!("stroke {i}"));
        }
    }
}
