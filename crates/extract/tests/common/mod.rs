//! Shared helpers of the extraction integration tests.
#![allow(dead_code)]

use rmt_extract::{
    measure::on_box_boundary, Clustering, ExtractSettings, Extractor, Grid, Lattice, Method, Stats,
};
use rmt_fields::ScalarField;
use rmt_mesh::{validate, Mesh, ValidationReport};

pub const LATTICES: [Lattice; 2] = [Lattice::BodyCentred, Lattice::Simple];

pub fn run(
    field: &dyn ScalarField,
    grid: Grid,
    lattice: Lattice,
    clustering: Clustering,
) -> (Mesh, Stats, ValidationReport) {
    let settings = ExtractSettings::new(grid, lattice, clustering);
    run_settings(field, &settings)
}

pub fn run_mc(field: &dyn ScalarField, grid: Grid) -> (Mesh, Stats, ValidationReport) {
    let mut settings = ExtractSettings::new(grid, Lattice::Simple, Clustering::None);
    settings.method = Method::Mc;
    run_settings(field, &settings)
}

pub fn run_settings(
    field: &dyn ScalarField,
    settings: &ExtractSettings,
) -> (Mesh, Stats, ValidationReport) {
    let mut mesh = Mesh::default();
    let stats = Extractor::new()
        .extract(field, settings, &mut mesh)
        .expect("extraction runs");
    let grid = settings.grid;
    let report = validate(&mesh, &|p| on_box_boundary(&grid, p));
    (mesh, stats, report)
}

/// Closed inside the box, manifold, oriented, no duplicates, no zero-area triangles.
pub fn assert_clean(what: &str, r: &ValidationReport) {
    assert_eq!(r.boundary_edges_interior, 0, "{what}: holes {r:?}");
    assert_eq!(r.non_manifold_edges, 0, "{what}: non-manifold edges {r:?}");
    assert_eq!(
        r.non_manifold_vertices, 0,
        "{what}: non-manifold vertices {r:?}"
    );
    assert_eq!(r.orientation_errors, 0, "{what}: orientation {r:?}");
    assert_eq!(r.duplicate_triangles, 0, "{what}: duplicates {r:?}");
    assert_eq!(r.non_finite_vertices, 0, "{what}: non-finite {r:?}");
    assert_eq!(
        r.unreferenced_vertices, 0,
        "{what}: unreferenced vertices {r:?}"
    );
}

/// Zero-area triangles (area <= 1e-12 l_max^2, as `rmt_mesh::quality` counts them) none of whose
/// vertices lies on the box faces: flat spots inside the box. Components of zero total area are
/// left out: they are zero-volume regions (a single sample point with f = T, outside, walled in by
/// inside points), which any mesh of the same topology must draw flat.
pub fn flat_triangles_inside(mesh: &Mesh, grid: &Grid) -> usize {
    flat_inside(mesh, grid).len()
}

/// The triangles [`flat_triangles_inside`] counts.
pub fn flat_inside(mesh: &Mesh, grid: &Grid) -> Vec<[u32; 3]> {
    let p = |i: u32| glam::Vec3::from(mesh.positions[i as usize]);
    // Components by union-find over triangle edges.
    let mut parent: Vec<usize> = (0..mesh.positions.len()).collect();
    fn find(parent: &mut [usize], mut x: usize) -> usize {
        while parent[x] != x {
            parent[x] = parent[parent[x]];
            x = parent[x];
        }
        x
    }
    for t in mesh.indices.chunks_exact(3) {
        for e in 0..3 {
            let (a, b) = (
                find(&mut parent, t[e] as usize),
                find(&mut parent, t[(e + 1) % 3] as usize),
            );
            parent[a.max(b)] = a.min(b);
        }
    }
    let h2 = grid.h() * grid.h();
    let tri_area = |t: &[u32]| 0.5 * (p(t[1]) - p(t[0])).cross(p(t[2]) - p(t[0])).length();
    let mut component_area = vec![0.0f32; mesh.positions.len()];
    for t in mesh.indices.chunks_exact(3) {
        let root = find(&mut parent, t[0] as usize);
        component_area[root] += tri_area(t);
    }
    mesh.indices
        .chunks_exact(3)
        .filter(|t| {
            let (a, b, c) = (p(t[0]), p(t[1]), p(t[2]));
            let l2 = (b - a)
                .length_squared()
                .max((c - a).length_squared())
                .max((c - b).length_squared());
            let flat = tri_area(t) <= 1e-12 * l2 || l2 == 0.0;
            let degenerate_component =
                component_area[find(&mut parent, t[0] as usize)] <= 1e-9 * h2;
            flat && !degenerate_component
                && !t
                    .iter()
                    .any(|&i| on_box_boundary(grid, mesh.positions[i as usize]))
        })
        .map(|t| [t[0], t[1], t[2]])
        .collect()
}

/// A pinch: two corners of the triangle at one position. In a mesh of a field without exact
/// ties, crossings coincide only where the surface passes exactly through a sample point (every
/// crossing of an edge from that point lies on it), so a flat pinch is the surface touching a
/// sample point, not a sliver between distinct crossings.
pub fn is_pinch(mesh: &Mesh, t: &[u32; 3]) -> bool {
    let p = |i: u32| mesh.positions[i as usize];
    p(t[0]) == p(t[1]) || p(t[1]) == p(t[2]) || p(t[2]) == p(t[0])
}
