//! Sparse sampling (blocks whose field range excludes the isovalue are not evaluated) gives the
//! same meshes, byte for byte, as dense sampling: random fields with a range, random boxes,
//! resolutions and isovalues, both lattices, every clustering mode, marching cubes, surface nets, 1 and 2
//! threads. The stored values agree in side everywhere and in value wherever they were
//! evaluated.

use glam::Vec3;
use proptest::prelude::*;
use rmt_extract::{
    Clustering, ExtractSettings, Extractor, Grid, Lattice, Method, NormalMode, Sampling, Stats,
};
use rmt_fields::{
    Asteroid, AsteroidParams, CaveParams, CaveTerrain, Gyroid, ScalarField, Sphere, SvobodaParams,
    SvobodaTerrain, Torus,
};
use rmt_mesh::Mesh;

/// A field with values rounded to multiples of `quantum`, so that many samples sit exactly on
/// the isovalue; its range is the inner range rounded outward (rounding is monotone).
struct Quantised<F>(F, f32);

impl<F: ScalarField> ScalarField for Quantised<F> {
    fn sample(&self, p: Vec3) -> f32 {
        (self.0.sample(p) / self.1).round() * self.1
    }
    fn range(&self, lo: Vec3, hi: Vec3) -> Option<(f32, f32)> {
        let (a, b) = self.0.range(lo, hi)?;
        Some(((a / self.1).round() * self.1, (b / self.1).round() * self.1))
    }
}

fn field(kind: usize, seed: u32, c: Vec3, r: f32) -> Box<dyn ScalarField> {
    match kind {
        0 => Box::new(Sphere::new(c, r)),
        1 => Box::new(Torus {
            centre: c,
            major: r,
            minor: r * 0.3,
        }),
        2 => Box::new(Gyroid {
            frequency: 0.5 + r,
            thickness: 0.2,
        }),
        3 => Box::new(Asteroid::new(
            c,
            AsteroidParams {
                seed,
                radius: r,
                ..Default::default()
            },
        )),
        4 => Box::new(SvobodaTerrain::new(SvobodaParams {
            seed,
            base: c.y * 0.5,
            ..Default::default()
        })),
        5 => Box::new(CaveTerrain::new(CaveParams {
            seed,
            ..Default::default()
        })),
        // Quantised sphere: many samples exactly at the isovalue 0 (welds, ties).
        _ => Box::new(Quantised(Sphere::new(c, r), 1.0 / 64.0)),
    }
}

/// Every extraction mode: (method, lattice, clustering).
fn modes() -> Vec<(Method, Lattice, Clustering)> {
    let mut m = vec![
        (Method::Mc, Lattice::Simple, Clustering::None),
        (Method::SurfaceNets, Lattice::Simple, Clustering::None),
    ];
    for lattice in [Lattice::BodyCentred, Lattice::Simple] {
        for clustering in [
            Clustering::None,
            Clustering::Integrated,
            Clustering::IntegratedUnchecked,
            Clustering::Postprocessed,
            Clustering::Meshopt,
        ] {
            m.push((Method::Mt, lattice, clustering));
        }
    }
    m
}

fn extract(
    f: &dyn ScalarField,
    s: &ExtractSettings,
    sampling: Sampling,
) -> (Mesh, Stats, Vec<f32>) {
    let mut ex = Extractor::new();
    ex.set_sampling(sampling);
    let mut mesh = Mesh::default();
    let stats = ex.extract(f, s, &mut mesh).expect("extraction runs");
    (mesh, stats, ex.samples().values.to_vec())
}

/// The counters that describe the mesh (not the sampling or the timings).
fn counters(s: &Stats) -> [usize; 12] {
    [
        s.vertices,
        s.triangles,
        s.discarded,
        s.tetrahedra_total,
        s.tetrahedra_processed,
        s.sample_points,
        s.edges,
        s.crossings,
        s.clusters_proposed,
        s.clusters_committed,
        s.lone_absorbed,
        s.collapses,
    ]
}

fn check(f: &dyn ScalarField, grid: Grid, iso: f32) -> Result<usize, TestCaseError> {
    let mut skipped = 0;
    for (method, lattice, clustering) in modes() {
        for threads in [1, 2] {
            let mut s = ExtractSettings::new(grid, lattice, clustering);
            s.method = method;
            s.iso = iso;
            s.threads = threads;
            s.normals = NormalMode::AreaWeighted;
            let (dm, ds, dv) = extract(f, &s, Sampling::Dense);
            let (sm, ss, sv) = extract(f, &s, Sampling::Sparse);
            let what = format!("{method:?} {lattice:?} {clustering:?} t={threads} iso={iso}");
            let bits = |m: &Mesh| {
                (
                    m.positions
                        .iter()
                        .flatten()
                        .map(|c| c.to_bits())
                        .collect::<Vec<_>>(),
                    m.normals
                        .iter()
                        .flatten()
                        .map(|c| c.to_bits())
                        .collect::<Vec<_>>(),
                    m.indices.clone(),
                )
            };
            prop_assert!(bits(&dm) == bits(&sm), "{what}: meshes differ");
            prop_assert_eq!(counters(&ds), counters(&ss), "{}", what);
            prop_assert_eq!(ds.points_sampled, ds.sample_points);
            prop_assert!(ss.points_sampled <= ss.sample_points);
            prop_assert!(ss.blocks_skipped <= ss.blocks && ss.blocks > 0);
            prop_assert_eq!(dv.len(), sv.len());
            let mut evaluated = 0;
            for (i, (&d, &v)) in dv.iter().zip(&sv).enumerate() {
                if d.is_nan() {
                    prop_assert!(
                        v.is_nan(),
                        "{}: slot {} unused in dense, {} in sparse",
                        what,
                        i,
                        v
                    );
                    continue;
                }
                prop_assert_eq!(
                    d < iso,
                    v < iso,
                    "{}: slot {} on another side: {} vs {}",
                    what,
                    i,
                    d,
                    v
                );
                evaluated += usize::from(d.to_bits() == v.to_bits());
            }
            prop_assert!(
                evaluated >= ss.points_sampled,
                "{}: evaluated values differ",
                what
            );
            skipped = ss.blocks_skipped;
        }
    }
    Ok(skipped)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]

    #[test]
    fn sparse_sampling_gives_the_meshes_of_dense_sampling(
        kind in 0usize..7, seed in 0u32..500,
        c in prop::array::uniform3(-0.3f32..0.3), r in 0.2f32..0.8,
        cells in prop::array::uniform3(4usize..30),
        lo in prop::array::uniform3(-1.2f32..-0.6), size in prop::array::uniform3(1.0f32..2.2),
        iso in prop::sample::select(vec![0.0f32, 0.0, 0.05, -0.1]),
    ) {
        let f = field(kind, seed, Vec3::from(c), r);
        let lo = Vec3::from(lo);
        let grid = Grid::new(cells, lo, lo + Vec3::from(size));
        check(f.as_ref(), grid, iso)?;
    }
}

/// On a grid fine enough, sparse sampling skips most of a sphere's and an asteroid's box.
#[test]
fn sparse_sampling_skips_far_blocks() {
    for f in [
        Box::new(Sphere::new(Vec3::ZERO, 0.6)) as Box<dyn ScalarField>,
        Box::new(Asteroid::new(Vec3::ZERO, AsteroidParams::default())),
    ] {
        let grid = Grid::cube(48, 1.0);
        let skipped = check(f.as_ref(), grid, 0.0).unwrap();
        assert!(skipped > 0, "no block skipped");
    }
}
