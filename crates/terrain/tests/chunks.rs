//! Chunked extraction equals whole-volume extraction, before and after edits; seams close;
//! output does not depend on the thread count; bad input gives errors.
//!
//! Case counts scale with `RMT_CASES` (default 400 per property, a few seconds in release).

use glam::Vec3;
use proptest::prelude::*;
use proptest::test_runner::FileFailurePersistence;
use rmt_extract::{measure::on_box_boundary, Clustering, Lattice};
use rmt_fields::{FnField, Sphere};
use rmt_mesh::{validate, Mesh, ValidationReport};
use rmt_terrain::{
    canonical_triangles, run_strokes, Brush, Seams, StrokeParams, TerrainError, World,
    WorldSettings,
};

fn cases(default: u32) -> u32 {
    std::env::var("RMT_CASES")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(default)
}

/// A random field over the unit box `[-1, 1]^3` (mapped onto the world box).
#[derive(Clone, Debug)]
enum Family {
    Blobs(Vec<(Vec3, f32, f32)>),
    Waves(Vec<(Vec3, f32, f32)>, f32),
    Shell(Vec3, f32, f32),
}

#[derive(Clone, Debug)]
struct RandomField {
    family: Family,
    /// Round values to multiples of this (0 = off): surfaces through sample points.
    quantum: f32,
}

impl RandomField {
    fn eval(&self, q: Vec3) -> f32 {
        let f = match &self.family {
            Family::Blobs(b) => {
                0.5 - b
                    .iter()
                    .map(|(c, s, a)| a * (-(q - *c).length_squared() / (s * s)).exp())
                    .sum::<f32>()
            }
            Family::Waves(w, off) => {
                w.iter()
                    .map(|(k, ph, a)| a * (k.dot(q) + ph).sin())
                    .sum::<f32>()
                    + off
            }
            Family::Shell(c, r, t) => ((q - *c).length() - r).abs() - t,
        };
        if self.quantum > 0.0 {
            (f / self.quantum).round() * self.quantum
        } else {
            f
        }
    }
}

fn vec3(r: f32) -> impl Strategy<Value = Vec3> {
    (-r..r, -r..r, -r..r).prop_map(|(x, y, z)| Vec3::new(x, y, z))
}

fn field() -> impl Strategy<Value = RandomField> {
    let family = prop_oneof![
        prop::collection::vec((vec3(0.9), 0.15f32..0.6, 0.3f32..1.5), 1..6).prop_map(Family::Blobs),
        (
            prop::collection::vec((vec3(6.0), 0.0f32..6.3, 0.1f32..1.0), 1..4),
            -0.5f32..0.5
        )
            .prop_map(|(w, o)| Family::Waves(w, o)),
        (vec3(0.3), 0.2f32..0.7, 0.05f32..0.3).prop_map(|(c, r, t)| Family::Shell(c, r, t)),
    ];
    (family, prop_oneof![3 => Just(0.0f32), 1 => 0.02f32..0.2])
        .prop_map(|(family, quantum)| RandomField { family, quantum })
}

/// The supported modes: (marching cubes?, lattice, clustering).
const MODES: [(bool, Lattice, Clustering); 9] = [
    (false, Lattice::BodyCentred, Clustering::None),
    (false, Lattice::BodyCentred, Clustering::Integrated),
    (false, Lattice::BodyCentred, Clustering::IntegratedUnchecked),
    (false, Lattice::BodyCentred, Clustering::Postprocessed),
    (false, Lattice::Simple, Clustering::None),
    (false, Lattice::Simple, Clustering::Integrated),
    (false, Lattice::Simple, Clustering::IntegratedUnchecked),
    (false, Lattice::Simple, Clustering::Postprocessed),
    (true, Lattice::Simple, Clustering::None),
];

#[derive(Clone, Debug)]
struct Case {
    mode: usize,
    cells: [usize; 3],
    chunk: usize,
    origin: Vec3,
    h: f32,
    threads: usize,
    field: RandomField,
}

fn case() -> impl Strategy<Value = Case> {
    (
        0..MODES.len(),
        [4usize..15, 4usize..15, 4usize..15],
        2usize..9,
        vec3(3.0),
        prop_oneof![Just(0.1f32), Just(0.25), Just(0.37)],
        1usize..3,
        field(),
    )
        .prop_map(|(mode, cells, chunk, origin, h, threads, field)| Case {
            mode,
            cells,
            chunk,
            origin,
            h,
            threads,
            field,
        })
}

fn settings(c: &Case) -> WorldSettings {
    let (mc, lattice, clustering) = MODES[c.mode];
    let s = if mc {
        WorldSettings::marching_cubes(c.cells, c.origin, c.h)
    } else {
        WorldSettings::new(c.cells, c.origin, c.h, lattice, clustering)
    };
    // Each mode's own seams: exact for integrated clustering, tiles for the others.
    s.with_chunk(c.chunk).with_threads(c.threads)
}

fn build(c: &Case) -> World {
    let s = settings(c);
    let grid = s.world_grid();
    let f = c.field.clone();
    let field = FnField(move |p: Vec3| {
        let q = (p - grid.min) / (grid.max - grid.min) * 2.0 - Vec3::ONE;
        f.eval(q)
    });
    World::new(&field, s).expect("world builds")
}

fn report(world: &World, mesh: &Mesh) -> ValidationReport {
    let grid = world.settings().world_grid();
    validate(mesh, &|p| on_box_boundary(&grid, p))
}

/// Chunks (welded) against the whole volume: same triangles; closed and manifold across seams.
fn assert_matches_whole(world: &World, c: &Case) -> Result<(), TestCaseError> {
    let chunked = world.mesh_welded();
    let (whole, _) = world.extract_whole().expect("whole extraction runs");
    prop_assert_eq!(chunked.triangle_count(), whole.triangle_count(), "{:?}", c);
    prop_assert!(
        canonical_triangles(&chunked) == canonical_triangles(&whole),
        "chunked and whole triangles differ: {:?}",
        c
    );
    let (r, r_whole) = (report(world, &chunked), report(world, &whole));
    prop_assert_eq!(r.boundary_edges_interior, r_whole.boundary_edges_interior);
    prop_assert_eq!(r.non_manifold_edges, r_whole.non_manifold_edges);
    let (_, _, clustering) = MODES[c.mode];
    // Without values on the threshold no two crossings coincide, so welding by position joins
    // exactly the seam vertices: the mesh must be closed and manifold (the unchecked mode may
    // break it by design).
    if c.field.quantum == 0.0 && clustering != Clustering::IntegratedUnchecked {
        prop_assert_eq!(r.boundary_edges_interior, 0, "holes: {:?} {:?}", r, c);
        prop_assert_eq!(r.non_manifold_edges, 0, "non-manifold: {:?} {:?}", r, c);
        prop_assert_eq!(r.orientation_errors, 0, "{:?} {:?}", r, c);
    }
    Ok(())
}

proptest! {
    // A failing case's seed is kept beside this file (`*.proptest-regressions`) and replayed
    // first on every later run: a rare failure found by a long run is not lost with the run.
    #![proptest_config(ProptestConfig {
        cases: cases(400),
        failure_persistence: Some(Box::new(FileFailurePersistence::WithSource("proptest-regressions"))),
        ..ProptestConfig::default()
    })]

    #[test]
    fn chunked_extraction_equals_the_whole_volume(c in case()) {
        let mut world = build(&c);
        let stats = world.remesh_dirty().expect("remesh runs");
        prop_assert_eq!(stats.chunks, world.chunk_count());
        prop_assert_eq!(world.dirty_count(), 0);
        assert_matches_whole(&world, &c)?;
    }

    #[test]
    fn incremental_updates_equal_a_full_re_extraction(
        c in case(),
        brushes in prop::collection::vec((vec3(1.1), 0.05f32..0.5, 0.0f32..3.0, any::<bool>(), prop::option::of(0.2f32..2.0)), 1..4),
    ) {
        let mut world = build(&c);
        world.remesh_dirty().expect("remesh runs");
        let grid = world.settings().world_grid();
        let size = grid.max - grid.min;
        for (centre, radius, strength, add, clamp) in brushes {
            // Brush in unit-box coordinates, mapped to the world box (may stick out of it).
            let centre = grid.min + (centre + Vec3::ONE) * 0.5 * size;
            let radius = radius * size.max_element();
            let mut brush = if add {
                Brush::add(centre, radius, strength)
            } else {
                Brush::subtract(centre, radius, strength)
            };
            brush.clamp = clamp;
            let marked = world.apply_brush(&brush, 0.1).expect("brush applies");
            prop_assert!(marked <= world.chunk_count());
            let stats = world.remesh_dirty().expect("remesh runs");
            if world.settings().seams == Seams::Tiles {
                prop_assert_eq!(stats.chunks, marked);
            } else {
                // Exact seams report the chunks whose mesh changed.
                prop_assert_eq!(stats.chunks, world.remeshed_chunks().len());
            }
        }
        // Against the whole edited volume, and against re-meshing every chunk.
        assert_matches_whole(&world, &c)?;
        let incremental = world.mesh_welded();
        world.mark_all_dirty();
        world.remesh_dirty().expect("remesh runs");
        let full = world.mesh_welded();
        prop_assert!(canonical_triangles(&incremental) == canonical_triangles(&full), "{:?}", c);
    }
}

/// Two chunks sharing a face: each alone is open along the seam, welded they are closed.
#[test]
fn two_chunks_sharing_a_face_weld_into_a_closed_mesh() {
    let sphere = Sphere::new(Vec3::new(1.0, 0.5, 0.5), 0.37);
    for (mc, lattice, clustering) in MODES {
        if clustering == Clustering::IntegratedUnchecked {
            continue;
        }
        let s = if mc {
            WorldSettings::marching_cubes([16, 8, 8], Vec3::ZERO, 0.125)
        } else {
            WorldSettings::new([16, 8, 8], Vec3::ZERO, 0.125, lattice, clustering)
        };
        let mut world = World::new(&sphere, s.with_chunk(8)).expect("world builds");
        world.remesh_dirty().expect("remesh runs");
        assert_eq!(world.chunk_count(), 2);
        let what = format!("mc={mc} {lattice:?} {clustering:?}");
        for i in 0..2 {
            let mut alone = world.chunk_mesh(i).expect("chunk exists").clone();
            for p in &mut alone.positions {
                *p = (Vec3::from(*p) * 0.125).to_array();
            }
            let r = report(&world, &alone);
            assert!(
                r.boundary_edges_interior > 0,
                "{what}: chunk {i} should be open"
            );
        }
        let welded = world.mesh_welded();
        let r = report(&world, &welded);
        assert_eq!(r.boundary_edges_interior, 0, "{what}: {r:?}");
        assert_eq!(r.boundary_edges_on_box, 0, "{what}: {r:?}");
        assert_eq!(r.non_manifold_edges, 0, "{what}: {r:?}");
        assert_eq!(r.non_manifold_vertices, 0, "{what}: {r:?}");
        assert_eq!(r.orientation_errors, 0, "{what}: {r:?}");
        assert_eq!(r.euler, 2, "{what}: a sphere");
    }
}

/// The tile rule still lets clustering work inside chunks.
#[test]
fn integrated_clustering_still_merges_inside_chunks() {
    let sphere = Sphere::new(Vec3::splat(1.0), 0.7);
    let mesh = |clustering| {
        let s = WorldSettings::new([16; 3], Vec3::ZERO, 0.125, Lattice::BodyCentred, clustering);
        let mut world = World::new(&sphere, s.with_chunk(8)).expect("world builds");
        world.remesh_dirty().expect("remesh runs");
        world.mesh_welded().triangle_count()
    };
    let (plain, merged) = (mesh(Clustering::None), mesh(Clustering::Integrated));
    assert!(
        (merged as f64) < 0.6 * plain as f64,
        "{merged} of {plain} triangles left"
    );
}

/// Same inputs give byte-identical welded meshes for 1 and 2 threads, before and after strokes.
#[test]
fn output_does_not_depend_on_the_thread_count() {
    let field = FnField(|p: Vec3| p.y - 1.0 - 0.3 * (3.0 * p.x).sin() * (2.0 * p.z).cos());
    // 64 x 16 x 64 cells: exact seams' boxes are smaller than the world there. Exact seams with
    // the modes that take them, tile seams with plain MT and edge collapse.
    let run = |threads: usize, (clustering, seams): (Clustering, Seams)| {
        let s = WorldSettings::new(
            [64, 16, 64],
            Vec3::ZERO,
            0.125,
            Lattice::BodyCentred,
            clustering,
        )
        .with_chunk(8)
        .with_threads(threads)
        .with_seams(seams);
        let mut world = World::new(&field, s).expect("world builds");
        let report =
            run_strokes(&mut world, &StrokeParams::for_cells(0.125, 10, 7)).expect("strokes run");
        (world.mesh_welded(), report.chunks, report.box_cells)
    };
    let bits = |m: &Mesh| -> Vec<u32> {
        m.positions
            .iter()
            .chain(&m.normals)
            .flatten()
            .map(|c| c.to_bits())
            .collect()
    };
    for mode in [
        (Clustering::Integrated, Seams::Exact),
        (Clustering::IntegratedUnchecked, Seams::Exact),
        (Clustering::None, Seams::Exact),
        (Clustering::None, Seams::Tiles),
        (Clustering::Postprocessed, Seams::Tiles),
    ] {
        let (a, ca, boxes) = run(1, mode);
        assert!(a.triangle_count() > 0);
        assert!(
            ca.iter().any(|&c| c > 0),
            "{mode:?}: strokes re-meshed nothing"
        );
        if mode.1 == Seams::Exact {
            assert!(
                boxes.iter().any(|&c| c > 0 && c < 64 * 16 * 64),
                "{mode:?}: no stroke re-meshed with a box smaller than the world"
            );
        }
        for threads in [2, 8] {
            let (b, cb, _) = run(threads, mode);
            assert_eq!(ca, cb, "{mode:?}, {threads} threads");
            assert_eq!(a.indices, b.indices, "{mode:?}, {threads} threads");
            assert!(bits(&a) == bits(&b), "{mode:?}, {threads} threads");
        }
    }
}

/// A stroke re-meshes a few chunks, not the world, and none where it cannot change the surface.
#[test]
fn a_small_brush_marks_only_nearby_chunks() {
    // The ground y = 1 lies on the seam between the two chunk layers (cells 0..8 and 8..16).
    let field = FnField(|p: Vec3| p.y - 1.0);
    let s = WorldSettings::new(
        [32, 16, 32],
        Vec3::ZERO,
        0.125,
        Lattice::Simple,
        Clustering::Postprocessed,
    )
    .with_chunk(8)
    .with_seams(Seams::Tiles);
    let mut world = World::new(&field, s).expect("world builds");
    world.remesh_dirty().expect("remesh runs");
    let before = canonical_triangles(&world.mesh_welded());
    // In the air above chunk (1, 1, 1) (world 1.0 .. 2.0): values change (by at most 0.1, all
    // stay > 0) but no point next to the surface does, so no mesh can change.
    let marked = world
        .apply_brush(&Brush::add(Vec3::new(1.5, 1.5, 1.5), 0.3, 1.0), 0.1)
        .expect("brush applies");
    assert_eq!(marked, 0);
    world.mark_all_dirty();
    world.remesh_dirty().expect("remesh runs");
    assert!(canonical_triangles(&world.mesh_welded()) == before);
    // On the ground in the middle of a column of chunks: the chunk above and the one below.
    let marked = world
        .apply_brush(&Brush::add(Vec3::new(1.5, 1.0, 1.5), 0.3, 1.0), 0.1)
        .expect("brush applies");
    assert_eq!(marked, 2);
    // On the ground at a chunk corner: the 8 chunks around it.
    let marked = world
        .apply_brush(&Brush::add(Vec3::new(1.0, 1.0, 1.0), 0.3, 1.0), 0.1)
        .expect("brush applies");
    assert_eq!(marked, 8);
    // Outside the world: nothing.
    let marked = world
        .apply_brush(&Brush::add(Vec3::new(-5.0, 1.0, 1.0), 0.3, 1.0), 0.1)
        .expect("brush applies");
    assert_eq!(marked, 0);
    // The two strokes on the ground overlap in chunks (1, 0, 1) and (1, 1, 1).
    assert_eq!(world.remesh_dirty().expect("remesh runs").chunks, 8);
}

#[test]
fn one_chunk_extracted_alone_is_the_chunk_of_the_world() {
    let field = FnField(|p: Vec3| p.length() - 0.9);
    let s = WorldSettings::new(
        [12, 12, 12],
        Vec3::splat(-1.5),
        0.25,
        Lattice::BodyCentred,
        Clustering::Postprocessed,
    )
    .with_chunk(6)
    .with_seams(Seams::Tiles);
    let mut world = World::new(&field, s).expect("world builds");
    world.remesh_dirty().expect("remesh runs");
    let mut ex = rmt_extract::Extractor::new();
    let mut mesh = Mesh::default();
    for i in 0..world.chunk_count() {
        let stats = world
            .extract_chunk(i, &mut ex, &mut mesh)
            .expect("chunk extracts");
        let own = world.chunk_mesh(i).expect("chunk exists");
        assert_eq!(mesh.indices, own.indices, "chunk {i}");
        assert_eq!(mesh.positions, own.positions, "chunk {i}");
        assert!(stats.sample_points > 0);
    }
    let err = world
        .extract_chunk(world.chunk_count(), &mut ex, &mut mesh)
        .expect_err("no such chunk");
    assert!(err.to_string().contains("no chunk 8"), "{err}");
}

#[test]
fn bad_settings_and_brushes_give_clear_errors() {
    let sphere = Sphere::new(Vec3::ZERO, 0.5);
    let base = WorldSettings::new(
        [8; 3],
        Vec3::splat(-1.0),
        0.25,
        Lattice::BodyCentred,
        Clustering::Integrated,
    );
    let err = World::new(&sphere, base.with_chunk(0))
        .err()
        .expect("refused");
    assert!(matches!(err, TerrainError::InvalidSettings(_)));
    assert!(err.to_string().contains("chunk size"), "{err}");
    let mut s = base;
    s.h = f32::NAN;
    assert!(World::new(&sphere, s).is_err());
    let mut s = base;
    s.clustering = Clustering::Meshopt;
    let err = World::new(&sphere, s).err().expect("refused");
    assert!(matches!(err, TerrainError::Unsupported(_)), "{err}");
    let s = base.with_threads(0);
    assert!(World::new(&sphere, s).is_err());
    let nan = FnField(|p: Vec3| if p.x > 0.5 { f32::NAN } else { p.x });
    let err = World::new(&nan, base).err().expect("refused");
    assert!(err.to_string().contains("not finite"), "{err}");

    let mut world = World::new(&sphere, base).expect("world builds");
    let err = world
        .apply_brush(&Brush::add(Vec3::new(0.0, f32::NAN, 0.0), 0.3, 1.0), 0.1)
        .unwrap_err();
    assert!(err.to_string().contains("centre"), "{err}");
    assert!(world
        .apply_brush(&Brush::add(Vec3::ZERO, 0.3, 1.0), f32::NAN)
        .is_err());
    assert_eq!(world.dirty_count(), world.chunk_count());
}
