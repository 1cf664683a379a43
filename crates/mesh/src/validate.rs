//! Topological checks (being written: the bodies below are placeholders).
use crate::Mesh;
use serde::{Deserialize, Serialize};

/// What [`validate`] found.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct ValidationReport {
    /// Distinct undirected edges of the mesh.
    pub mesh_edges: usize,
    /// Edges with one triangle lying on the sampled domain's boundary (expected where the surface leaves the box).
    pub boundary_edges_on_box: usize,
    /// Edges with one triangle inside the domain: holes (defects).
    pub boundary_edges_interior: usize,
    /// Edges with more than two triangles.
    pub non_manifold_edges: usize,
    /// Vertices whose triangle fan is not a single disk or half-disk.
    pub non_manifold_vertices: usize,
    /// Edges whose two triangles traverse it in the same direction.
    pub orientation_errors: usize,
    /// Triangles with the same three vertices as an earlier one (any order).
    pub duplicate_triangles: usize,
    /// Triangles with (near) zero area.
    pub zero_area_triangles: usize,
    /// Vertices with a NaN or infinite coordinate.
    pub non_finite_vertices: usize,
    /// Vertices referenced by no triangle.
    pub unreferenced_vertices: usize,
    /// V - E + F over referenced vertices.
    pub euler: i64,
    /// Connected components (through shared vertices).
    pub components: usize,
}

impl ValidationReport {
    /// Closed inside the domain, manifold, consistently oriented, no duplicates, finite.
    pub fn is_watertight_manifold(&self) -> bool {
        self.boundary_edges_interior == 0
            && self.non_manifold_edges == 0
            && self.non_manifold_vertices == 0
            && self.orientation_errors == 0
            && self.duplicate_triangles == 0
            && self.non_finite_vertices == 0
    }
}

/// Checks `mesh`; `on_domain_boundary(p)` says whether a point lies on the sampled domain's outer
/// boundary (a boundary edge is "on box" when both ends and its midpoint are).
pub fn validate(_mesh: &Mesh, _on_domain_boundary: &dyn Fn([f32; 3]) -> bool) -> ValidationReport {
    ValidationReport::default()
}
