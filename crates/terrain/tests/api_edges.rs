//! The public API under hostile numbers: world construction, brushes (plain and recorded), undo
//! and redo, chunk queries and column queries get any `f32`, including NaN, the infinities,
//! +-3e38, values past the `i64` range once divided by a cell size, and subnormals. Every call
//! either succeeds or returns an error, never panics, and the world stays valid: after the
//! calls, re-meshing the dirty chunks gives the mesh of the whole edited volume extracted at once.
//!
//! Case counts scale with `RMT_CASES` (default 200 worlds of up to 11 calls each, about 1,500
//! calls); the test prints how many calls it made (`-- --nocapture`). 100,000 calls, no panic:
//! `RMT_CASES=14000 cargo test --release -p rmt-terrain --test api_edges -- --nocapture` (102,399
//! calls, 12 s).

use std::sync::atomic::{AtomicUsize, Ordering};

use glam::Vec3;
use proptest::prelude::*;
use proptest::test_runner::{FileFailurePersistence, TestCaseError, TestRunner};
use rmt_extract::{Clustering, Lattice};
use rmt_fields::FnField;
use rmt_terrain::{canonical_triangles, Brush, BrushMode, Seams, World, WorldSettings};

fn cases(default: u32) -> u32 {
    std::env::var("RMT_CASES")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(default)
}

/// Calls into the library made by the property, over all cases.
static CALLS: AtomicUsize = AtomicUsize::new(0);

fn count() {
    CALLS.fetch_add(1, Ordering::Relaxed);
}

/// Numbers at the edges of `f32` (and past `i64` once divided by a small cell), mixed with
/// ordinary ones so that some calls succeed and change the world.
fn edge() -> impl Strategy<Value = f32> {
    prop_oneof![
        3 => -2.0f32..2.0,
        1 => Just(f32::NAN),
        1 => Just(f32::INFINITY),
        1 => Just(f32::NEG_INFINITY),
        1 => Just(f32::MAX),
        1 => Just(f32::MIN),
        1 => Just(3e38f32),
        1 => Just(-3e38f32),
        1 => Just(3e17f32),
        1 => Just(-3e17f32),
        1 => Just(1e19f32),
        1 => Just(-1e30f32),
        1 => Just(f32::MIN_POSITIVE),
        1 => Just(1e-45f32),
        1 => Just(-1e-45f32),
        1 => Just(0.0f32),
        1 => Just(-0.0f32),
        1 => any::<f32>(),
    ]
}

/// A positive size that is usually ordinary and sometimes extreme.
fn size() -> impl Strategy<Value = f32> {
    prop_oneof![4 => 0.05f32..1.0, 1 => edge()]
}

fn point() -> impl Strategy<Value = Vec3> {
    (edge(), edge(), edge()).prop_map(|(x, y, z)| Vec3::new(x, y, z))
}

#[derive(Clone, Debug)]
enum Call {
    Brush(Brush, f32),
    Recorded(Brush, f32),
    Undo,
    Redo,
    Remesh,
    Column(f32, f32),
    Chunk(usize),
}

fn brush() -> impl Strategy<Value = Brush> {
    (
        point(),
        size(),
        prop_oneof![3 => 0.0f32..20.0, 1 => edge()],
        any::<bool>(),
        prop_oneof![2 => Just(None), 1 => size().prop_map(Some)],
    )
        .prop_map(|(centre, radius, strength, add, clamp)| Brush {
            centre,
            radius,
            strength,
            mode: if add {
                BrushMode::Add
            } else {
                BrushMode::Subtract
            },
            clamp,
        })
}

fn call() -> impl Strategy<Value = Call> {
    let dt = || prop_oneof![3 => Just(1.0f32 / 60.0), 1 => edge()];
    prop_oneof![
        4 => (brush(), dt()).prop_map(|(b, dt)| Call::Brush(b, dt)),
        3 => (brush(), dt()).prop_map(|(b, dt)| Call::Recorded(b, dt)),
        1 => Just(Call::Undo),
        1 => Just(Call::Redo),
        2 => Just(Call::Remesh),
        1 => (edge(), edge()).prop_map(|(x, z)| Call::Column(x, z)),
        1 => any::<usize>().prop_map(Call::Chunk),
    ]
}

#[derive(Clone, Debug)]
struct Setup {
    cells: [usize; 3],
    chunk: usize,
    origin: Vec3,
    h: f32,
    iso: f32,
    mode: usize,
}

fn setup() -> impl Strategy<Value = Setup> {
    (
        (2usize..10, 2usize..10, 2usize..10),
        2usize..6,
        prop_oneof![4 => Just(Vec3::splat(-1.0)), 1 => point()],
        prop_oneof![4 => Just(0.25f32), 1 => edge()],
        prop_oneof![4 => Just(0.0f32), 1 => edge()],
        0usize..5,
    )
        .prop_map(|((x, y, z), chunk, origin, h, iso, mode)| Setup {
            cells: [x, y, z],
            chunk,
            origin,
            h,
            iso,
            mode,
        })
}

fn settings(s: &Setup) -> WorldSettings {
    let (lattice, clustering, seams) = match s.mode {
        0 => (Lattice::BodyCentred, Clustering::Integrated, Seams::Exact),
        1 => (
            Lattice::Simple,
            Clustering::IntegratedUnchecked,
            Seams::Exact,
        ),
        2 => (Lattice::BodyCentred, Clustering::None, Seams::Exact),
        3 => (Lattice::Simple, Clustering::Postprocessed, Seams::Tiles),
        _ => (Lattice::BodyCentred, Clustering::None, Seams::Tiles),
    };
    let mut ws = WorldSettings::new(s.cells, s.origin, s.h, lattice, clustering)
        .with_chunk(s.chunk)
        .with_seams(seams);
    ws.iso = s.iso;
    ws
}

/// A sphere of radius 0.6 around the world box's centre in box units, so that the surface is
/// inside whatever the box.
fn field(ws: &WorldSettings) -> FnField<impl Fn(Vec3) -> f32 + Send + Sync> {
    let grid = ws.world_grid();
    let (lo, hi) = (grid.min, grid.max);
    FnField(move |p: Vec3| {
        let q = (p - lo) / (hi - lo) * 2.0 - Vec3::ONE;
        q.length() - 0.6
    })
}

/// Runs the calls on a world built from `s`; an error names the broken promise.
fn run(s: &Setup, calls: &[Call]) -> Result<(), TestCaseError> {
    let ws = settings(s);
    count();
    let checked = ws.check();
    count();
    let Ok(mut world) = World::new(&field(&ws), ws) else {
        return Ok(());
    };
    prop_assert!(checked.is_ok(), "check refused what World::new took");
    // Slots never read (body-centred ghosts outside two faces) hold NaN; every other is finite.
    let unused: Vec<bool> = world
        .samples()
        .values
        .iter()
        .map(|v| !v.is_finite())
        .collect();
    let mut history = Vec::new();
    let mut undone = Vec::new();
    for c in calls {
        count();
        match c {
            Call::Brush(b, dt) => {
                if let Err(e) = world.apply_brush(b, *dt) {
                    prop_assert!(b.check(*dt).is_err(), "{b:?} {dt}: {e}");
                }
            }
            Call::Recorded(b, dt) => match world.apply_brush_recorded(b, *dt) {
                Ok((_, record)) => {
                    history.push(record);
                    undone.clear();
                }
                Err(e) => prop_assert!(b.check(*dt).is_err(), "{b:?} {dt}: {e}"),
            },
            Call::Undo => {
                if let Some(r) = history.pop() {
                    world.undo_stroke(&r);
                    undone.push(r);
                }
            }
            Call::Redo => {
                if let Some(r) = undone.pop() {
                    world.redo_stroke(&r);
                    history.push(r);
                }
            }
            Call::Remesh => {
                let r = world.remesh_dirty();
                prop_assert!(r.is_ok(), "remesh failed: {:?}", r.err());
            }
            Call::Column(x, z) => {
                if let Some(y) = world.column_surface(*x, *z) {
                    prop_assert!(y.is_finite());
                }
            }
            Call::Chunk(i) => {
                let n = world.chunk_count();
                // Half the time a valid index, half the time any.
                let i = if i % 2 == 0 { i % n } else { *i };
                prop_assert_eq!(world.chunk_mesh(i).is_some(), i < n);
                let cells = world.chunk_cells(i);
                prop_assert!((0..3).all(|a| cells.lo[a] <= cells.hi[a]));
                prop_assert!(i < n || !world.chunk_is_dirty(i));
                let mut ex = rmt_extract::Extractor::new();
                let mut mesh = rmt_mesh::Mesh::default();
                prop_assert_eq!(world.extract_chunk(i, &mut ex, &mut mesh).is_ok(), i < n);
            }
        }
    }
    prop_assert!(
        world
            .samples()
            .values
            .iter()
            .zip(&unused)
            .all(|(v, &unused)| unused || v.is_finite()),
        "a call left a non-finite sample"
    );
    count();
    let r = world.remesh_dirty();
    prop_assert!(r.is_ok(), "remesh failed: {:?}", r.err());
    count();
    let whole = world.extract_whole();
    prop_assert!(whole.is_ok(), "whole extraction failed: {:?}", whole.err());
    let (whole, _) = whole.unwrap_or_default();
    prop_assert_eq!(
        canonical_triangles(&world.mesh_welded()),
        canonical_triangles(&whole),
        "the chunks differ from the whole volume"
    );
    Ok(())
}

fn small_world() -> World {
    let ws = WorldSettings::new(
        [8, 8, 8],
        Vec3::splat(-1.0),
        0.25,
        Lattice::BodyCentred,
        Clustering::Integrated,
    )
    .with_chunk(4);
    let mut world = World::new(&field(&ws), ws).expect("world");
    world.remesh_dirty().expect("mesh");
    world
}

/// The defect: a centre at 3e17 or more on one or three axes made the stroke's box size wrap
/// (saturating cast, then +-1) and `apply_brush` panicked with "capacity overflow".
#[test]
fn brushes_far_outside_the_world_change_nothing() {
    let mut world = small_world();
    let before = world.samples().values.clone();
    let finite = |values: &[f32]| values.iter().filter(|v| v.is_finite()).count();
    for c in [3e17f32, -3e17, 1e19, -1e30, 3e38, f32::MAX, f32::MIN] {
        for centre in [
            Vec3::new(c, 0.0, 0.0),
            Vec3::splat(c),
            Vec3::new(0.0, 0.0, c),
        ] {
            for brush in [
                Brush::add(centre, 0.5, 5.0),
                Brush::subtract(centre, 3e38, 5.0),
            ] {
                let marked = world.apply_brush(&brush, 0.1);
                let far = brush.radius < 1.0;
                // A huge radius reaches the world from anywhere finite; a small one does not.
                if far {
                    assert_eq!(marked.expect("a finite brush is accepted"), 0, "{brush:?}");
                } else {
                    assert!(marked.is_ok(), "{brush:?}: {marked:?}");
                }
                let (_, record) = world.apply_brush_recorded(&brush, 0.1).expect("recorded");
                if far {
                    assert_eq!(record.changed_values(), 0);
                }
            }
        }
    }
    // Only the huge brushes changed values, and every value is still finite.
    assert_ne!(world.samples().values, before);
    assert_eq!(finite(&world.samples().values), finite(&before));
    world.remesh_dirty().expect("remesh");
    let (whole, _) = world.extract_whole().expect("whole");
    assert_eq!(
        canonical_triangles(&world.mesh_welded()),
        canonical_triangles(&whole)
    );
}

/// A cell so small that centre / h leaves the f32 range: the brush still reaches the world when
/// it covers it.
#[test]
fn subnormal_cells_and_huge_radii_still_apply() {
    let ws = WorldSettings::new(
        [4, 4, 4],
        Vec3::ZERO,
        1e-40,
        Lattice::Simple,
        Clustering::None,
    )
    .with_seams(Seams::Exact);
    let mut world = World::new(&FnField(|p: Vec3| p.x - 2e-40), ws).expect("world");
    world.remesh_dirty().expect("mesh");
    let before = world.samples().values.clone();
    // Centre one unit away (1e40 cells: past f32), radius two units: every sample changes.
    let marked = world
        .apply_brush(&Brush::add(Vec3::new(1.0, 0.0, 0.0), 2.0, 1.0), 1.0)
        .expect("stroke");
    assert!(marked > 0);
    assert!(world
        .samples()
        .values
        .iter()
        .zip(&before)
        .all(|(a, b)| a != b));
}

#[test]
fn no_call_panics_and_the_world_stays_valid() {
    let config = ProptestConfig {
        cases: cases(200),
        failure_persistence: Some(Box::new(FileFailurePersistence::Off)),
        ..ProptestConfig::default()
    };
    let mut runner = TestRunner::new(config);
    let result = runner.run(
        &(setup(), prop::collection::vec(call(), 1..12)),
        |(s, calls)| run(&s, &calls),
    );
    eprintln!(
        "api_edges: {} calls into rmt-terrain",
        CALLS.load(Ordering::Relaxed)
    );
    if let Err(e) = result {
        panic!("{e}");
    }
}
