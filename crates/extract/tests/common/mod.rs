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
