//! `Extractor::extract_borrowed`: the caller's values read in place give the meshes of the
//! copied values, on every method and lattice, leave the extractor's own sample array alone,
//! and allocate no sample array (counted by a counting global allocator).

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;

use glam::Vec3;
use rmt_extract::{
    Clustering, ExtractSettings, Extractor, Grid, Lattice, Method, NormalMode, Samples, Stats,
};
use rmt_fields::ScalarField;
use rmt_mesh::Mesh;

/// Counts the bytes allocated (by every thread) while `COUNTING` is set.
struct Counting;

static COUNTING: AtomicUsize = AtomicUsize::new(0);
static ALLOCATED: AtomicUsize = AtomicUsize::new(0);

// SAFETY: forwards to the system allocator; only adds to a counter.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        if COUNTING.load(Ordering::Relaxed) != 0 {
            ALLOCATED.fetch_add(layout.size(), Ordering::Relaxed);
        }
        // SAFETY: the caller's contract, passed on.
        unsafe { System.alloc(layout) }
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: the caller's contract, passed on.
        unsafe { System.dealloc(ptr, layout) }
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        if COUNTING.load(Ordering::Relaxed) != 0 {
            ALLOCATED.fetch_add(new_size, Ordering::Relaxed);
        }
        // SAFETY: the caller's contract, passed on.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static ALLOCATOR: Counting = Counting;

/// The tests run one at a time, so that the counter sees one extraction only.
static ONE_AT_A_TIME: Mutex<()> = Mutex::new(());

/// A lumpy sphere, different at every point.
struct Lumpy;

impl ScalarField for Lumpy {
    fn sample(&self, p: Vec3) -> f32 {
        p.length() - 0.6 + 0.08 * (7.0 * p.x).sin() * (5.0 * p.y).cos() + 0.05 * (9.0 * p.z).sin()
    }
}

fn settings(n: usize, lattice: Lattice, method: Method, clustering: Clustering) -> ExtractSettings {
    let mut s = ExtractSettings::new(Grid::cube(n, 1.0), lattice, clustering);
    s.method = method;
    s.threads = 2;
    s.normals = NormalMode::AreaWeighted;
    s
}

/// The field's values laid out for `s` (dense: every value is the field's).
fn values(s: &ExtractSettings) -> Vec<f32> {
    let pool = rmt_extract::thread_pool(1, rmt_extract::ThreadPlacement::Os).expect("a pool");
    let mut samples = Samples::default();
    samples
        .sample(&Lumpy, s, &pool, &mut Stats::default())
        .expect("finite");
    samples.values.into_vec()
}

/// The mesh of `values` copied into the extractor's sample array.
fn copied(values: &[f32], s: &ExtractSettings) -> Mesh {
    let mut ex = Extractor::new();
    ex.samples_mut().prepare(s);
    ex.samples_mut().values.copy_from_slice(values);
    let mut mesh = Mesh::default();
    ex.extract_presampled(s, &mut mesh).expect("extracts");
    mesh
}

const CASES: [(Lattice, Method, Clustering); 6] = [
    (Lattice::Simple, Method::Mt, Clustering::Integrated),
    (Lattice::Simple, Method::Mt, Clustering::None),
    (Lattice::Simple, Method::Mt, Clustering::Postprocessed),
    (Lattice::BodyCentred, Method::Mt, Clustering::Integrated),
    (Lattice::Simple, Method::Mc, Clustering::None),
    (Lattice::Simple, Method::SurfaceNets, Clustering::None),
];

#[test]
fn borrowed_values_give_the_meshes_of_copied_values() {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    for (lattice, method, clustering) in CASES {
        let s = settings(24, lattice, method, clustering);
        let v = values(&s);
        let want = copied(&v, &s);
        let mut ex = Extractor::new();
        let mut mesh = Mesh::default();
        let stats = ex.extract_borrowed(&v, &s, &mut mesh).expect("extracts");
        let case = format!("{lattice:?} {method:?} {clustering:?}");
        assert!(mesh.triangle_count() > 100, "{case}");
        assert_eq!(stats.triangles, mesh.triangle_count(), "{case}");
        assert_eq!(mesh.positions, want.positions, "{case}");
        assert_eq!(mesh.indices, want.indices, "{case}");
        assert_eq!(mesh.normals, want.normals, "{case}");
        // The extractor never had a sample array of its own.
        assert_eq!(ex.samples().bytes(), 0, "{case}");
        assert!(!ex.samples().values.is_borrowed(), "{case}");
    }
}

#[test]
fn the_extractors_own_samples_are_left_alone_and_bad_lengths_refused() {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let s = settings(12, Lattice::Simple, Method::Mt, Clustering::Integrated);
    let v = values(&s);
    let mut ex = Extractor::new();
    let mut mesh = Mesh::default();
    // The extractor's own values (another lattice), before and after.
    let own = settings(8, Lattice::BodyCentred, Method::Mt, Clustering::None);
    ex.samples_mut().prepare(&own);
    let before = ex.samples().clone();
    ex.extract_borrowed(&v, &s, &mut mesh).expect("extracts");
    let bits = |s: &Samples| s.values.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
    assert_eq!(bits(ex.samples()), bits(&before));
    assert_eq!(ex.samples().dims, before.dims);
    let err = ex
        .extract_borrowed(&v[1..], &s, &mut mesh)
        .expect_err("one value short");
    assert!(err.to_string().contains("values given"), "{err}");
    // Its own values still extract as before.
    ex.extract_presampled(&own, &mut mesh)
        .expect("own layout kept");
}

#[test]
fn borrowed_extraction_allocates_no_sample_array() {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let n = 128;
    for (lattice, method, clustering) in [
        (Lattice::Simple, Method::Mc, Clustering::None),
        (Lattice::Simple, Method::Mt, Clustering::None),
        (Lattice::Simple, Method::Mt, Clustering::Integrated),
    ] {
        let s = settings(n, lattice, method, clustering);
        let v = values(&s);
        let bytes = v.len() * 4;
        let case = format!("{method:?} {clustering:?}");
        let mut ex = Extractor::new();
        let mut mesh = Mesh::default();
        // The first call sizes the working tables; the second reuses them.
        ex.extract_borrowed(&v, &s, &mut mesh).expect("extracts");
        let count = |ex: &mut Extractor, mesh: &mut Mesh, borrowed: bool| {
            ALLOCATED.store(0, Ordering::SeqCst);
            COUNTING.store(1, Ordering::SeqCst);
            if borrowed {
                ex.extract_borrowed(&v, &s, mesh).expect("extracts");
            } else {
                // What a caller without `extract_borrowed` does: copy into the samples.
                let own = ex.samples_mut();
                own.prepare(&s);
                own.values.copy_from_slice(&v);
                ex.extract_presampled(&s, mesh).expect("extracts");
            }
            COUNTING.store(0, Ordering::SeqCst);
            ALLOCATED.load(Ordering::SeqCst)
        };
        let borrowed = count(&mut ex, &mut mesh, true);
        let copying = count(&mut ex, &mut mesh, false);
        eprintln!("{case}: {bytes} bytes of values; a warm call allocated {borrowed} bytes borrowed, {copying} copying");
        // The counter sees the sample array of the copying path ...
        assert!(copying >= bytes, "{case}: {copying} < {bytes}");
        // ... and the borrowed path allocates less than one copy of the values (what it does
        // allocate grows with the surface, n^2, not with the volume).
        assert!(borrowed < bytes / 2, "{case}: {borrowed} of {bytes}");
    }
}
