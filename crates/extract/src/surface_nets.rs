//! Surface nets: the `fast-surface-nets` crate on our simple-cubic samples, as a peer method.
//!
//! Naive surface nets places one vertex in each grid cube whose corners are not all on one side
//! (the mean of the crossings of its crossed edges) and, for each crossed grid edge, a quad
//! joining the vertices of the four cubes around the edge, split into two triangles along its
//! shorter diagonal. All of that is the crate's: [`extract`] hands it the sample array that
//! marching cubes reads (the simple-cubic corners, same layout: `x + (nx + 1) * (y + (ny + 1) *
//! z)` is the crate's `RuntimeShape` order), so peers are measured on the same values, and keeps
//! its triangles as they are, quad split included. What this module adds:
//!
//! - **Isovalue.** The crate meshes the zero level set with `f < 0` inside. For iso 0 the
//!   samples are passed as they are; otherwise a copy holding `f - iso` is (kept in
//!   [`SurfaceNetsBuffers`]). `f - iso < 0` exactly when `f < iso` for finite floats, so the
//!   sides are ours: `f == iso` counts outside, as in marching cubes and tetrahedra.
//! - **Positions.** The crate's vertices are in grid coordinates (cube `(x, y, z)` spans
//!   `[x, x + 1]` per axis); they are mapped to `min + p * spacing` of the settings' box.
//! - **Orientation.** The crate does not document its winding. Its triangles turn out to be
//!   counter-clockwise seen from the positive side of the field (right-hand normals toward
//!   increasing values, outward for an SDF), which is our convention, so they are kept as they
//!   are; the sphere test checks it (positive enclosed volume).
//! - **The box boundary.** The crate skips the quads of grid edges that end on the box's upper
//!   faces (a chunk convention: its neighbour makes them, given a one-voxel border); we build it
//!   with its `eval-max-plane` feature, which keeps them, so the box is treated alike on all six
//!   sides. Edges lying in a box face have no quad (two of the four cubes around them are outside
//!   the box). We add no border of our own, which would cap the surface with faces at the box.
//!   So, as with marching cubes, the mesh is closed wherever the surface stays inside the box,
//!   and open along the box where it leaves it (half a cell inside the faces: the vertices lie
//!   in the cubes).
//! - **Kept cells.** A quad belongs to the cube whose lower corner is its edge's lower end (the
//!   greatest of its four cubes, per axis); with [`crate::ExtractSettings::keep_cells`] only the
//!   quads of the kept cubes remain and unreferenced vertices are dropped.
//!
//! The crate's normals (unnormalised gradients from the cube corners) are not used: the
//! extractor computes normals as for every method ([`crate::NormalMode`]).
//!
//! Defects are the method's, reported and not repaired: a cube with two separate pieces of
//! surface (e.g. two inside corners on a face diagonal) gets one vertex, which makes
//! non-manifold edges and vertices that `rmt_mesh::validate` counts.
//!
//! The crate runs on one thread: `settings.threads` does not change this method. Its output is
//! deterministic (a fixed scan order).

use fast_surface_nets::ndshape::RuntimeShape;
use fast_surface_nets::{surface_nets, SurfaceNetsBuffer};
use glam::Vec3;
use rmt_mesh::Mesh;

use crate::{ExtractError, ExtractSettings, Samples, Stats};

/// The working memory of surface nets, kept by the [`crate::Extractor`] between calls: the
/// crate's own buffer and, for a nonzero isovalue, the shifted copy of the samples.
#[derive(Default)]
pub struct SurfaceNetsBuffers {
    /// The crate's output and scratch buffers.
    pub(crate) buffer: SurfaceNetsBuffer,
    /// `f - iso` at every sample point (only for `iso != 0`).
    pub(crate) shifted: Vec<f32>,
    /// Old to new vertex number when kept cells drop vertices.
    pub(crate) remap: Vec<u32>,
}

impl SurfaceNetsBuffers {
    /// Heap bytes held.
    pub(crate) fn bytes(&self) -> usize {
        let b = &self.buffer;
        b.positions.capacity() * 12
            + b.normals.capacity() * 12
            + b.indices.capacity() * 4
            + b.surface_points.capacity() * 12
            + b.surface_strides.capacity() * 4
            + b.stride_to_index.capacity() * 4
            + self.shifted.capacity() * 4
            + self.remap.capacity() * 4
    }
}

/// Extracts the `settings.iso` level set of the simple-lattice `samples` into `mesh` (appending
/// to it; the caller clears it) with `fast_surface_nets::surface_nets`, and fills the counters
/// and timings of `stats`: `tetrahedra_total = 0`, `tetrahedra_processed` = cubes with a vertex,
/// `edges` = grid edges, `crossings` = crossed grid edges that got a quad (those not lying in a
/// box face), `t_vertex_s` = the crate's call (its vertex and quad passes run in one call),
/// `t_geometry_s` = mapping positions and copying into `mesh`. `bytes_edges` is left
/// to the caller (the buffers' size). Errors with [`ExtractError::NonFiniteValue`] (the first
/// in storage order) when a value is NaN or infinite: the crate reads the values itself, so
/// they are checked first, in one vectorised scan.
pub fn extract(
    samples: &Samples,
    settings: &ExtractSettings,
    buffers: &mut SurfaceNetsBuffers,
    mesh: &mut Mesh,
    stats: &mut Stats,
) -> Result<(), ExtractError> {
    let [nx, ny, nz] = samples.cells;
    let dims = [nx + 1, ny + 1, nz + 1];
    let len = dims[0] * dims[1] * dims[2];
    stats.tetrahedra_total = 0;
    stats.edges = nx * (ny + 1) * (nz + 1) + (nx + 1) * ny * (nz + 1) + (nx + 1) * (ny + 1) * nz;
    if samples.values.len() < len {
        // Not laid out for these settings (the extractor checks this first); nothing to mesh.
        return Ok(());
    }

    let t = std::time::Instant::now();
    if crate::util::any_non_finite(&samples.values[..len]) {
        if let Some(e) = samples.non_finite_error() {
            return Err(e);
        }
    }
    let iso = settings.iso;
    let values: &[f32] = if iso == 0.0 {
        &samples.values[..len]
    } else {
        buffers.shifted.clear();
        buffers
            .shifted
            .extend(samples.values[..len].iter().map(|&v| v - iso));
        &buffers.shifted
    };
    // `Grid::check` allows at most 2^31 sample points, so strides fit the crate's u32.
    let shape = RuntimeShape::<u32, 3>::new([dims[0] as u32, dims[1] as u32, dims[2] as u32]);
    let max = [nx as u32, ny as u32, nz as u32];
    surface_nets(values, &shape, [0; 3], max, &mut buffers.buffer);
    stats.t_vertex_s = t.elapsed().as_secs_f64();

    let t = std::time::Instant::now();
    let b = &buffers.buffer;
    stats.tetrahedra_processed = b.positions.len();
    stats.crossings = b.indices.len() / 6;
    let first = mesh.positions.len() as u32;
    let to_world = |p: &[f32; 3]| (samples.min + Vec3::from(*p) * samples.spacing).to_array();
    match settings.keep_cells {
        None => {
            mesh.positions.extend(b.positions.iter().map(to_world));
            mesh.indices.extend(b.indices.iter().map(|&i| first + i));
        }
        Some(keep) => {
            let remap = &mut buffers.remap;
            remap.clear();
            remap.resize(b.positions.len(), u32::MAX);
            for quad in b.indices.chunks_exact(6) {
                // The quad's edge starts at the lower corner of the greatest of its four cubes.
                let mut anchor = [0u32; 3];
                for &v in quad {
                    let c = b.surface_points[v as usize];
                    for a in 0..3 {
                        anchor[a] = anchor[a].max(c[a]);
                    }
                }
                if !keep.contains(anchor.map(|c| c as usize)) {
                    continue;
                }
                for &v in quad {
                    let r = &mut remap[v as usize];
                    if *r == u32::MAX {
                        *r = mesh.positions.len() as u32;
                        mesh.positions.push(to_world(&b.positions[v as usize]));
                    }
                    mesh.indices.push(*r);
                }
            }
        }
    }
    stats.t_geometry_s = t.elapsed().as_secs_f64();
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::measure::on_box_boundary;
    use crate::{CellRange, Clustering, ExtractError, Extractor, Grid, Lattice, Method, Sampling};
    use rmt_fields::{FnField, ScalarField, Sphere};
    use rmt_mesh::{validate, ValidationReport};

    fn settings(grid: Grid) -> ExtractSettings {
        let mut s = ExtractSettings::new(grid, Lattice::Simple, Clustering::None);
        s.method = Method::SurfaceNets;
        s
    }

    fn run(field: &dyn ScalarField, s: &ExtractSettings) -> (Mesh, Stats, ValidationReport) {
        let mut mesh = Mesh::default();
        let stats = Extractor::new().extract(field, s, &mut mesh).unwrap();
        let grid = s.grid;
        let report = validate(&mesh, &|p| on_box_boundary(&grid, p));
        (mesh, stats, report)
    }

    /// Six times the signed volume enclosed: positive when right-hand normals point outward.
    fn signed_volume6(mesh: &Mesh) -> f64 {
        mesh.triangles()
            .map(|[a, b, c]| {
                let [a, b, c] =
                    [a, b, c].map(|i| Vec3::from(mesh.positions[i as usize]).as_dvec3());
                a.dot(b.cross(c))
            })
            .sum()
    }

    #[test]
    fn sphere_is_closed_oriented_outward_with_euler_two() {
        let sphere = Sphere::new(Vec3::new(0.05, -0.03, 0.02), 0.7);
        let s = settings(Grid::cube(24, 1.0));
        let (mesh, stats, r) = run(&sphere, &s);
        assert!(r.is_watertight_manifold(), "{r:?}");
        assert_eq!((r.euler, r.components), (2, 1), "{r:?}");
        assert_eq!(r.boundary_edges_on_box, 0);
        // Outward: the enclosed volume is positive and close to the sphere's.
        let volume = signed_volume6(&mesh) / 6.0;
        let exact = 4.0 / 3.0 * std::f64::consts::PI * 0.7f64.powi(3);
        assert!((volume - exact).abs() < 0.05 * exact, "{volume} vs {exact}");
        // Every vertex lies near the sphere (within a cube diagonal).
        let h = s.grid.h();
        for p in &mesh.positions {
            let d = sphere.sample(Vec3::from(*p)).abs();
            assert!(d < 0.87 * h, "{p:?} at {d}");
        }
        assert_eq!(stats.triangles, mesh.triangle_count());
        assert_eq!(stats.vertices, mesh.vertex_count());
        assert_eq!(stats.tetrahedra_processed, mesh.vertex_count());
        assert_eq!(stats.crossings * 2, mesh.triangle_count());
        assert_eq!(stats.tetrahedra_total, 0);
        assert_eq!(stats.edges, 3 * 24 * 25 * 25);
    }

    /// Two inside points on a face diagonal of a cube: the cubes holding both get one vertex
    /// each for two separate pieces of surface, and the edge between two of them is shared by
    /// the quads of four crossed edges: non-manifold, and counted by validation.
    #[test]
    fn diagonal_spheres_make_non_manifold_edges_that_validation_counts() {
        let grid = Grid::cube(8, 4.0); // unit spacing, corners at integers
        let (a, b) = (Vec3::new(0.0, 0.0, 0.0), Vec3::new(1.0, 1.0, 0.0));
        let two = FnField(move |p: Vec3| (p.distance(a) - 0.3).min(p.distance(b) - 0.3));
        let (_, _, r) = run(&two, &settings(grid));
        assert!(r.non_manifold_edges > 0, "{r:?}");
        assert!(!r.is_watertight_manifold());
        // Each sphere alone is a clean closed surface.
        let one = FnField(move |p: Vec3| p.distance(a) - 0.3);
        let (_, _, r) = run(&one, &settings(grid));
        assert!(r.is_watertight_manifold(), "{r:?}");
        assert_eq!(r.euler, 2);
    }

    /// The mesh is the crate's, on our samples: the same triangles, and its positions mapped
    /// into the box.
    #[test]
    fn output_is_the_crates_mapped_into_the_box() {
        let sphere = Sphere::new(Vec3::new(0.3, 0.1, -0.2), 1.1);
        let mut s = settings(Grid::new(
            [10, 12, 14],
            Vec3::new(-1.0, -2.0, -1.5),
            Vec3::new(2.0, 1.0, 1.5),
        ));
        s.normals = crate::NormalMode::Skip;
        let mut ex = Extractor::new();
        ex.set_sampling(Sampling::Dense);
        let mut mesh = Mesh::default();
        ex.extract(&sphere, &s, &mut mesh).unwrap();
        let samples = ex.samples();
        let shape = RuntimeShape::<u32, 3>::new([11, 13, 15]);
        let mut direct = SurfaceNetsBuffer::default();
        surface_nets(&samples.values, &shape, [0; 3], [10, 12, 14], &mut direct);
        assert!(!direct.indices.is_empty());
        assert_eq!(mesh.indices, direct.indices);
        let spacing = s.grid.spacing();
        for (p, q) in mesh.positions.iter().zip(&direct.positions) {
            let want = s.grid.min + Vec3::from(*q) * spacing;
            assert_eq!(*p, want.to_array());
        }
    }

    #[test]
    fn isovalue_shift_sparse_sampling_reuse_and_kept_cells() {
        let sphere = Sphere::new(Vec3::new(0.1, -0.05, 0.02), 0.5);
        let mut s = settings(Grid::cube(16, 1.0));
        // Level 0.2 of the sphere of radius 0.5 is the zero level of the sphere of radius 0.7.
        s.iso = 0.2;
        let (shifted, _, r) = run(&sphere, &s);
        assert!(r.is_watertight_manifold());
        let bigger = FnField(|p: Vec3| (p - Vec3::new(0.1, -0.05, 0.02)).length() - 0.5 - 0.2);
        s.iso = 0.0;
        let mut dense = Extractor::new();
        dense.set_sampling(Sampling::Dense);
        let mut m = Mesh::default();
        dense.extract(&bigger, &s, &mut m).unwrap();
        assert_eq!(m.triangle_count(), shifted.triangle_count());

        // Sparse sampling (the default) gives the dense mesh, and a reused extractor repeats it.
        let mut ex = Extractor::new();
        let mut a = Mesh::default();
        ex.extract(&bigger, &s, &mut a).unwrap();
        assert_eq!((&a.positions, &a.indices), (&m.positions, &m.indices));
        ex.extract(&sphere, &s, &mut a).unwrap();
        ex.extract(&bigger, &s, &mut a).unwrap();
        assert_eq!((&a.positions, &a.indices), (&m.positions, &m.indices));

        // Kept cells partition the triangles.
        let mut total = 0;
        for (lo, hi) in [(0, 7), (7, 16)] {
            s.keep_cells = Some(CellRange {
                lo: [0, lo, 0],
                hi: [16, hi, 16],
            });
            let (part, _, r) = run(&bigger, &s);
            assert!(part.triangle_count() > 0);
            assert_eq!(r.unreferenced_vertices, 0);
            total += part.triangle_count();
        }
        assert_eq!(total, m.triangle_count());
    }

    /// The box's upper faces are treated as its lower ones (the crate's `eval-max-plane`): half
    /// spheres cut by opposite faces, mirror images on the grid, get as many triangles, and
    /// their open rims lie half a cell inside the box, not on it.
    #[test]
    fn upper_and_lower_box_faces_are_treated_alike() {
        let s = settings(Grid::cube(16, 1.0));
        let mut counts = Vec::new();
        for x in [-1.0, 1.0] {
            let (mesh, _, r) = run(&Sphere::new(Vec3::new(x, 0.0, 0.0), 0.55), &s);
            assert!(
                r.boundary_edges_interior > 0 && r.non_manifold_edges == 0,
                "{r:?}"
            );
            counts.push(mesh.triangle_count());
        }
        assert!(counts[0] > 0);
        assert_eq!(counts[0], counts[1]);
    }

    #[test]
    fn clustering_is_refused() {
        let mut s = settings(Grid::cube(8, 1.0));
        s.clustering = Clustering::Meshopt;
        let err = Extractor::new()
            .extract(&Sphere::new(Vec3::ZERO, 0.5), &s, &mut Mesh::default())
            .unwrap_err();
        assert!(matches!(err, ExtractError::Unsupported(_)), "{err}");
        assert!(err.to_string().contains("surface nets"), "{err}");
    }

    #[test]
    fn name_in_settings_files_is_surface_nets() {
        let s = settings(Grid::cube(4, 1.0));
        assert_eq!(
            serde_json::to_string(&s.method).unwrap(),
            "\"surface-nets\""
        );
        let back: Method = serde_json::from_str("\"surface-nets\"").unwrap();
        assert_eq!(back, Method::SurfaceNets);
    }
}
