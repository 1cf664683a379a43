//! Helpers of the passes' unit tests: fields, pools, settings, and an extraction whose pass
//! tables the tests then read.

use rmt_mesh::Mesh;

use super::{extract, MtBuffers};
use crate::{Lattice, Samples, Stats};

/// A smooth field with many surface sheets in [-1, 1]^3.
pub(crate) fn wavy() -> rmt_fields::FnField<impl Fn(glam::Vec3) -> f32> {
    rmt_fields::FnField(|p: glam::Vec3| {
        (p.x * 6.3).sin() * (p.y * 4.1 + 0.3).cos() + (p.z * 5.7).sin() * 0.8 - 0.1
    })
}

/// A pool of `threads` threads for a test.
pub(crate) fn test_pool(threads: usize) -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("a thread pool")
}

/// Settings for `cells` in [-1, 1]^3.
pub(crate) fn settings_on(
    cells: [usize; 3],
    lattice: Lattice,
    clustering: crate::Clustering,
) -> crate::ExtractSettings {
    crate::ExtractSettings::new(
        crate::Grid::new(cells, glam::Vec3::splat(-1.0), glam::Vec3::splat(1.0)),
        lattice,
        clustering,
    )
}

/// `field` sampled and extracted with `settings`: the samples, the pass buffers as the
/// extraction left them, the mesh and the counters.
pub(crate) fn extracted(
    field: &impl rmt_fields::ScalarField,
    settings: &crate::ExtractSettings,
    pool: &rayon::ThreadPool,
) -> (Samples, MtBuffers, Mesh, Stats) {
    let mut stats = Stats::default();
    let mut samples = Samples::default();
    samples
        .sample(field, settings, pool, &mut stats)
        .expect("a finite field");
    let (mut buf, mut mesh) = (MtBuffers::default(), Mesh::default());
    let mut counted = Stats::default();
    extract(&samples, settings, pool, &mut buf, &mut mesh, &mut counted).expect("extraction");
    (samples, buf, mesh, counted)
}

/// Plain MT of `field` on `cells` in [-1, 1]^3: the settings, samples, the pass buffers as the
/// extraction left them, and the mesh.
pub(crate) fn plain_mt(
    field: &impl rmt_fields::ScalarField,
    lattice: Lattice,
    cells: [usize; 3],
    pool: &rayon::ThreadPool,
) -> (crate::ExtractSettings, Samples, MtBuffers, Mesh) {
    let settings = settings_on(cells, lattice, crate::Clustering::None);
    let (samples, buf, mesh, _) = extracted(field, &settings, pool);
    (settings, samples, buf, mesh)
}

/// A tiny deterministic generator for the table test (no dependency needed).
pub(crate) fn lcg(state: &mut u64) -> f32 {
    *state = state
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    ((*state >> 40) as f32 / (1u64 << 24) as f32) * 2.0 - 1.0
}
