//! Criterion benchmarks of the extraction passes against two peer crates.
//!
//! `cargo bench -p rmt-extract` (add a group name to filter, e.g. `-- extract_sphere_64`).
//!
//! Groups (names are stable so that results compare run to run):
//! - `extract_<field>_<n>` for field `sphere`, `asteroid` and `n` = 32, 64, 128 cells per axis
//!   in `[-1, 1]^3`: functions `mt_bcdl_none`, `rmt_bcdl_integrated`, `mt_simple_none`,
//!   `rmt_simple_integrated`, `mc`, `fast_surface_nets`, `isomesh_mc`. Sampling is excluded from
//!   all of them: the field is sampled once per lattice before timing (for the body-centred
//!   lattice corners and centres both), our methods re-mesh those samples with
//!   [`Extractor::extract_presampled`] on one thread, and the peers get the same corner-grid values
//!   that our marching cubes reads. Normals are skipped for our methods
//!   ([`NormalMode::Skip`]); `isomesh_mc` gets a constant gradient, so it computes none either;
//!   `fast_surface_nets` always estimates its (unnormalised) normals from the corner values.
//!   `isomesh_mc` copies the grid into its own buffer through its `Sdf` trait on every call
//!   (its API has no pre-sampled entry point), which is timed.
//! - `sample_<field>_<n>`: the sampling pass alone on each lattice, 1 and 2 threads
//!   (`bcdl_threads_1`, `bcdl_threads_2`, `simple_threads_1`, `simple_threads_2`).
//! - `bunny_sdf`: the signed distance to `data/bunny.obj` on 75 x 40 x 56 cells: sampling the
//!   body-centred lattice (1 and 2 threads) and re-meshing it with MT and RMT.

use std::hint::black_box;
use std::time::Duration;

use criterion::{criterion_group, criterion_main, Criterion, SamplingMode};
use glam::Vec3;
use rmt_extract::{
    Clustering, ExtractSettings, Extractor, Grid, Lattice, Method, NormalMode, Samples, Stats,
};
use rmt_fields::{Asteroid, AsteroidParams, MeshSdf, ScalarField, Sphere};
use rmt_mesh::Mesh;

/// Cells per axis of the `extract_*` and `sample_*` groups.
const SIZES: [usize; 3] = [32, 64, 128];

/// The benchmark fields by name: a sphere of radius 0.8 and the default asteroid, both centred.
fn fields() -> Vec<(&'static str, Box<dyn ScalarField>)> {
    vec![
        ("sphere", Box::new(Sphere::new(Vec3::ZERO, 0.8))),
        (
            "asteroid",
            Box::new(Asteroid::new(Vec3::ZERO, AsteroidParams::default())),
        ),
    ]
}

/// One of our methods with its samples already taken: re-meshing it is what gets timed.
struct Prepared {
    extractor: Extractor,
    settings: ExtractSettings,
    mesh: Mesh,
}

impl Prepared {
    /// Samples `field` for the method (one full extraction, which also sizes every buffer).
    fn new(
        field: &dyn ScalarField,
        grid: Grid,
        lattice: Lattice,
        clustering: Clustering,
        method: Method,
    ) -> Self {
        let mut settings = ExtractSettings::new(grid, lattice, clustering);
        settings.method = method;
        settings.normals = NormalMode::Skip;
        settings.threads = 1;
        let mut extractor = Extractor::new();
        // Every stored value is the field's: the peers are fed these samples.
        extractor.set_sampling(rmt_extract::Sampling::Dense);
        let mut mesh = Mesh::default();
        if let Err(e) = extractor.extract(field, &settings, &mut mesh) {
            panic!("benchmark setup failed: {e}");
        }
        Self {
            extractor,
            settings,
            mesh,
        }
    }

    /// Re-meshes the stored samples; returns the triangle count.
    fn run(&mut self) -> usize {
        match self
            .extractor
            .extract_presampled(&self.settings, &mut self.mesh)
        {
            Ok(stats) => stats.triangles,
            Err(e) => panic!("extraction failed: {e}"),
        }
    }
}

/// Panics unless every corner within two layers of the box faces is outside (f >= 0): then the
/// surface is clear of the box faces, where fast-surface-nets (which skips the quads of edges on
/// its `min` planes and `max - 1` planes, the chunk-seam convention) would leave holes.
fn assert_clear_of_faces(values: &[f32], n: usize) {
    let d = n + 1;
    let edge = |c: usize| c <= 1 || c + 2 >= d;
    for z in 0..d {
        for y in 0..d {
            for x in 0..d {
                if (edge(x) || edge(y) || edge(z)) && values[x + d * (y + d * z)] < 0.0 {
                    panic!("surface reaches the box faces at corner ({x}, {y}, {z}) of {n}^3");
                }
            }
        }
    }
}

/// The corner grid read by cell position, for isomesh: it asks only for grid points when its
/// crossing refinement is off (the default), with origin 0 and unit cells.
struct GridValues<'a> {
    values: &'a [f32],
    dim: usize,
}

impl isomesh::Sdf for GridValues<'_> {
    type Scalar = f32;

    #[inline]
    fn sample(&self, p: [f32; 3]) -> f32 {
        let [x, y, z] = p.map(|c| c as usize);
        self.values[x + self.dim * (y + self.dim * z)]
    }

    /// A constant: normals are not part of the timed work.
    #[inline]
    fn gradient(&self, _p: [f32; 3]) -> [f32; 3] {
        [0.0, 0.0, 1.0]
    }
}

fn extract_groups(c: &mut Criterion) {
    for (name, field) in fields() {
        for n in SIZES {
            let grid = Grid::cube(n, 1.0);
            let (bcdl, simple) = (Lattice::BodyCentred, Lattice::Simple);
            let (none, integrated) = (Clustering::None, Clustering::Integrated);
            let mut ours = vec![
                (
                    "mt_bcdl_none",
                    Prepared::new(&*field, grid, bcdl, none, Method::Mt),
                ),
                (
                    "rmt_bcdl_integrated",
                    Prepared::new(&*field, grid, bcdl, integrated, Method::Mt),
                ),
                (
                    "mt_simple_none",
                    Prepared::new(&*field, grid, simple, none, Method::Mt),
                ),
                (
                    "rmt_simple_integrated",
                    Prepared::new(&*field, grid, simple, integrated, Method::Mt),
                ),
                ("mc", Prepared::new(&*field, grid, simple, none, Method::Mc)),
            ];
            // The corner grid of marching cubes, (n + 1)^3 values with x fastest: fed to the peers.
            let corners = ours[4].1.extractor.samples().values.clone();
            assert_clear_of_faces(&corners, n);
            let dim = n + 1;
            let side = dim as u32;

            let mut group = c.benchmark_group(format!("extract_{name}_{n}"));
            group
                .sample_size(10)
                .sampling_mode(SamplingMode::Flat)
                .warm_up_time(Duration::from_millis(500))
                .measurement_time(Duration::from_secs(3));
            for (method, prepared) in &mut ours {
                group.bench_function(*method, |b| b.iter(|| black_box(prepared.run())));
            }

            let shape = fast_surface_nets::ndshape::RuntimeShape::<u32, 3>::new([side; 3]);
            let mut buffer = fast_surface_nets::SurfaceNetsBuffer::default();
            group.bench_function("fast_surface_nets", |b| {
                b.iter(|| {
                    fast_surface_nets::surface_nets(
                        black_box(&corners),
                        &shape,
                        [0; 3],
                        [side - 1; 3],
                        &mut buffer,
                    );
                    black_box(buffer.indices.len() / 3)
                })
            });

            let iso_shape = match isomesh::RuntimeShape3::new([side; 3]) {
                Ok(s) => s,
                Err(e) => panic!("isomesh shape for {n}^3: {e}"),
            };
            let grid_values = GridValues {
                values: &corners,
                dim,
            };
            let mut mc = isomesh::marching_cubes::MarchingCubes::<f32>::new();
            let mut out = isomesh::MeshBuffer::<f32>::new();
            group.bench_function("isomesh_mc", |b| {
                b.iter(|| {
                    out.reset();
                    if let Err(e) = mc.extract(&grid_values, &iso_shape, [0.0; 3], 1.0, &mut out) {
                        panic!("isomesh failed: {e}");
                    }
                    black_box(out.triangle_count())
                })
            });
            group.finish();
        }
    }
}

/// Times [`Samples::sample`] alone for `settings` on a pool of `threads`.
fn sample_bench(
    group: &mut criterion::BenchmarkGroup<'_, criterion::measurement::WallTime>,
    id: &str,
    field: &dyn ScalarField,
    settings: &ExtractSettings,
    threads: usize,
) {
    let pool = match rayon::ThreadPoolBuilder::new().num_threads(threads).build() {
        Ok(p) => p,
        Err(e) => panic!("thread pool of {threads}: {e}"),
    };
    let mut samples = Samples::default();
    group.bench_function(id, |b| {
        b.iter(|| {
            let mut stats = Stats::default();
            if let Err(e) = samples.sample(field, settings, &pool, &mut stats) {
                panic!("sampling failed: {e}");
            }
            black_box(stats.sample_points)
        })
    });
}

fn sample_groups(c: &mut Criterion) {
    for (name, field) in fields() {
        for n in SIZES {
            let mut group = c.benchmark_group(format!("sample_{name}_{n}"));
            group
                .sample_size(10)
                .sampling_mode(SamplingMode::Flat)
                .warm_up_time(Duration::from_millis(500))
                .measurement_time(Duration::from_secs(3));
            for lattice in [Lattice::BodyCentred, Lattice::Simple] {
                let settings = ExtractSettings::new(Grid::cube(n, 1.0), lattice, Clustering::None);
                for threads in [1, 2] {
                    let id = format!("{}_threads_{threads}", lattice.name());
                    sample_bench(&mut group, &id, &*field, &settings, threads);
                }
            }
            group.finish();
        }
    }
}

fn bunny_group(c: &mut Criterion) {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../data/bunny.obj");
    let mesh = match rmt_mesh::io::read_obj(path) {
        Ok(m) => m,
        Err(e) => panic!("bunny_sdf needs {path}: {e}"),
    };
    let (min, max) = (Vec3::new(-1.5, -0.8, -1.12), Vec3::new(1.5, 0.8, 1.12));
    let sdf = match MeshSdf::fit(&mesh, min, max, 0.05) {
        Ok(s) => s,
        Err(e) => panic!("bunny SDF from {path}: {e}"),
    };
    let grid = Grid::new([75, 40, 56], min, max);
    let mut group = c.benchmark_group("bunny_sdf");
    group
        .sample_size(10)
        .sampling_mode(SamplingMode::Flat)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(3));
    let settings = ExtractSettings::new(grid, Lattice::BodyCentred, Clustering::None);
    for threads in [1, 2] {
        let id = format!("sample_bcdl_threads_{threads}");
        sample_bench(&mut group, &id, &sdf, &settings, threads);
    }
    for (id, clustering) in [
        ("mt_bcdl_none", Clustering::None),
        ("rmt_bcdl_integrated", Clustering::Integrated),
    ] {
        let mut prepared = Prepared::new(&sdf, grid, Lattice::BodyCentred, clustering, Method::Mt);
        group.bench_function(id, |b| b.iter(|| black_box(prepared.run())));
    }
    group.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default();
    targets = extract_groups, sample_groups, bunny_group
}
criterion_main!(benches);
