//! Exact seams ([`Seams::Exact`]): after every stroke the chunk meshes are the whole edited
//! volume's mesh (integrated clustering, checked or not, or plain marching tetrahedra), bit for
//! bit, though a stroke re-extracts only a box around
//! it; and the box is much smaller than the world when the clustering is quiet around it.
//!
//! Case counts scale with `RMT_CASES` (default 60 worlds).

use std::sync::atomic::{AtomicUsize, Ordering};

use glam::Vec3;
use proptest::prelude::*;
use proptest::test_runner::FileFailurePersistence;
use rmt_extract::{Clustering, Lattice};
use rmt_fields::{FnField, RandomField, ScalarField};
use rmt_terrain::{canonical_triangles, Brush, Seams, TerrainError, World, WorldSettings};

fn cases(default: u32) -> u32 {
    std::env::var("RMT_CASES")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(default)
}

/// The chunk meshes welded against the whole volume extracted at once (the global rule).
fn exact(world: &World) -> bool {
    let (whole, _) = world.extract_whole().expect("whole extraction runs");
    canonical_triangles(&world.mesh_welded()) == canonical_triangles(&whole)
}

/// Strokes that changed nothing that matters, re-meshed with a box smaller than the world,
/// with more than one box; and worlds done (the counts are printed after the last one).
static QUIET: AtomicUsize = AtomicUsize::new(0);
static SMALL: AtomicUsize = AtomicUsize::new(0);
static GREW: AtomicUsize = AtomicUsize::new(0);
static DONE: AtomicUsize = AtomicUsize::new(0);

proptest! {
    #![proptest_config(ProptestConfig {
        cases: cases(60),
        failure_persistence: Some(Box::new(FileFailurePersistence::WithSource("proptest-regressions"))),
        ..ProptestConfig::default()
    })]

    /// Random fields of the extraction's property tests (blobs, waves, thin shells and tubes,
    /// sheets, stairs; some quantised, with samples exactly on the threshold) on worlds of 36
    /// to 64 cells across, strokes of 1 to 5 cells anywhere, then all of them undone; integrated
    /// clustering in half the worlds, integrated-unchecked or none in the others.
    #[test]
    fn chunks_equal_the_whole_volume_after_every_stroke(
        seed in any::<u64>(),
        clustering in prop_oneof![
            2 => Just(Clustering::Integrated),
            1 => Just(Clustering::IntegratedUnchecked),
            1 => Just(Clustering::None),
        ],
        cells in [36usize..65, 12usize..25, 36usize..65],
        chunk in 4usize..13,
        simple in any::<bool>(),
        threads in 1usize..3,
        strokes in prop::collection::vec((0.0f32..1.0, 0.0f32..1.0, 0.0f32..1.0, 1.0f32..5.0, any::<bool>()), 1..5),
    ) {
        let lattice = if simple { Lattice::Simple } else { Lattice::BodyCentred };
        let h = 0.1;
        let origin = Vec3::ZERO;
        let size = Vec3::new(cells[0] as f32, cells[1] as f32, cells[2] as f32) * h;
        let field = RandomField::from_seed(seed).in_box(origin + 0.5 * size, 0.5 * size.max_element());
        let s = WorldSettings::new(cells, origin, h, lattice, clustering)
            .with_chunk(chunk)
            .with_threads(threads);
        if clustering == Clustering::None {
            // Plain marching tetrahedra takes either seams; the tile rule is the default there.
            prop_assert_eq!(s.seams, Seams::Tiles);
        } else {
            prop_assert_eq!(s.seams, Seams::Exact);
        }
        let s = s.with_seams(Seams::Exact);
        let mut world = World::new(&field, s).expect("world builds");
        world.remesh_dirty().expect("remesh runs");
        prop_assert!(exact(&world), "first meshing, seed {}", seed);
        let initial = canonical_triangles(&world.mesh_welded());
        let total: usize = cells.iter().product();
        let mut records = Vec::new();
        for (k, &(x, y, z, r, add)) in strokes.iter().enumerate() {
            let centre = origin + Vec3::new(x, y, z) * size;
            let brush = if add {
                Brush::add(centre, r * h, 3.0)
            } else {
                Brush::subtract(centre, r * h, 3.0)
            };
            let (_, record) = world.apply_brush_recorded(&brush, 0.1).expect("brush applies");
            records.push(record);
            let stats = world.remesh_dirty().expect("remesh runs");
            if stats.boxes == 0 {
                QUIET.fetch_add(1, Ordering::Relaxed);
            }
            if stats.boxes > 0 && stats.box_cells < total {
                SMALL.fetch_add(1, Ordering::Relaxed);
            }
            if stats.boxes > 1 {
                GREW.fetch_add(1, Ordering::Relaxed);
            }
            prop_assert!(exact(&world), "stroke {} of seed {}, {:?}, {:?}, {:?} cells, chunk {}", k, seed, clustering, lattice, cells, chunk);
        }
        // Undoing every stroke, last first, brings the first mesh back, exactly.
        for record in records.iter().rev() {
            world.undo_stroke(record);
            world.remesh_dirty().expect("remesh runs");
        }
        prop_assert!(canonical_triangles(&world.mesh_welded()) == initial, "undo, seed {}", seed);
        if DONE.fetch_add(1, Ordering::Relaxed) + 1 == cases(60) as usize {
            eprintln!(
                "exact seams over {} worlds: {} strokes changed nothing that matters, {} were \
                 re-meshed with a box smaller than the world, {} needed more than one box",
                cases(60),
                QUIET.load(Ordering::Relaxed),
                SMALL.load(Ordering::Relaxed),
                GREW.load(Ordering::Relaxed)
            );
        }
    }
}

/// A terrain-like world of 128 x 32 x 128 cells in chunks of 16: one stroke on the ground in the
/// middle re-extracts one box much smaller than the world, re-meshes a few chunks, and the
/// result is the whole volume's; so is a stroke at the world's edge (its box is clipped) and
/// undoing both.
#[test]
fn a_stroke_re_extracts_a_box_and_stays_exact() {
    let ground = FnField(|p: Vec3| p.y - 1.6 - 0.3 * (p.x * 1.3).sin() * (p.z * 0.9).cos());
    for lattice in [Lattice::BodyCentred, Lattice::Simple] {
        let s = WorldSettings::new(
            [128, 32, 128],
            Vec3::ZERO,
            0.1,
            lattice,
            Clustering::Integrated,
        )
        .with_chunk(16)
        .with_threads(2);
        let mut world = World::new(&ground, s).expect("world builds");
        let all = world.remesh_dirty().expect("remesh runs");
        assert_eq!((all.chunks, all.boxes), (world.chunk_count(), 1));
        let before = canonical_triangles(&world.mesh_welded());
        assert!(exact(&world));
        let mut records = Vec::new();
        for centre in [Vec3::new(6.4, 1.6, 6.4), Vec3::new(0.05, 1.6, 12.75)] {
            let (marked, rec) = world
                .apply_brush_recorded(&Brush::add(centre, 0.3, 4.0), 0.1)
                .expect("brush applies");
            assert!(marked >= 1);
            let stats = world.remesh_dirty().expect("remesh runs");
            assert_eq!(
                stats.boxes, 1,
                "{lattice:?}: the band around a smooth ground is quiet"
            );
            assert!(
                stats.box_cells * 8 < 128 * 32 * 128,
                "{lattice:?}: box of {} cells",
                stats.box_cells
            );
            assert!(stats.chunks >= 1 && stats.chunks < world.chunk_count());
            assert_eq!(stats.chunks, world.remeshed_chunks().len());
            assert!(exact(&world), "{lattice:?} after the stroke at {centre}");
            records.push(rec);
        }
        assert_ne!(canonical_triangles(&world.mesh_welded()), before);
        for rec in records.iter().rev() {
            world.undo_stroke(rec);
            world.remesh_dirty().expect("remesh runs");
            assert!(exact(&world), "{lattice:?} after an undo");
        }
        assert_eq!(canonical_triangles(&world.mesh_welded()), before);
    }
}

/// Exact seams need marching tetrahedra with integrated clustering (checked or not) or none,
/// and integrated clustering takes no other; the other modes, and tiles with integrated
/// clustering, say so.
#[test]
fn exact_seams_refuse_other_modes() {
    let sphere = rmt_fields::Sphere::new(Vec3::ZERO, 0.5);
    let settings = |clustering| {
        WorldSettings::new(
            [8; 3],
            Vec3::splat(-1.0),
            0.25,
            Lattice::BodyCentred,
            clustering,
        )
    };
    for clustering in [Clustering::Postprocessed, Clustering::Meshopt] {
        let s = settings(clustering);
        assert_eq!(
            s.seams,
            Seams::Tiles,
            "{clustering:?} defaults to the tile rule"
        );
        let err = World::new(&sphere, s.with_seams(Seams::Exact))
            .err()
            .expect("refused");
        assert!(matches!(err, TerrainError::Unsupported(_)), "{err}");
        if clustering == Clustering::Postprocessed {
            assert!(err.to_string().contains("exact seams"), "{err}");
        }
    }
    let mc = WorldSettings::marching_cubes([8; 3], Vec3::splat(-1.0), 0.25);
    assert!(World::new(&sphere, mc.with_seams(Seams::Exact)).is_err());
    // And integrated clustering, checked or not, has exact seams only: it has no tile rule.
    for clustering in [Clustering::Integrated, Clustering::IntegratedUnchecked] {
        let integrated = settings(clustering);
        assert_eq!(integrated.seams, Seams::Exact);
        let err = World::new(&sphere, integrated.with_seams(Seams::Tiles))
            .err()
            .expect("refused");
        assert!(matches!(err, TerrainError::Unsupported(_)), "{err}");
        assert!(err.to_string().contains("exact seams only"), "{err}");
    }
    // Plain marching tetrahedra takes both.
    let plain = settings(Clustering::None);
    for seams in [Seams::Tiles, Seams::Exact] {
        assert!(
            World::new(&sphere, plain.with_seams(seams)).is_ok(),
            "{seams:?}"
        );
    }
    let _ = sphere.sample(Vec3::ZERO);
}
