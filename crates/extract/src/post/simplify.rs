//! The QEM anchor: meshoptimizer's simplifier (Garland-Heckbert quadrics with edge collapses)
//! applied to an unmerged mesh, as the baseline that any vertex-merging scheme is compared with.
//!
//! meshoptimizer keeps the mesh's topology (it never joins separate parts or closes holes and
//! refuses collapses that would flip triangles); with `LockBorder` the vertices on open borders,
//! here where the surface leaves the sampled box, stay where they are, so the box boundary is
//! unchanged. The error bound is absolute, in world units, tied to the grid spacing.

use meshopt::{SimplifyOptions, VertexDataAdapter};
use rmt_mesh::Mesh;

/// Simplifies `mesh` in place with meshoptimizer until any further collapse would move the
/// surface by more than `error_in_h * h` (world units), keeping open borders fixed; drops the
/// vertices no triangle uses any more (the others keep their relative order) and clears the
/// normals. Returns the number of triangles removed. Does nothing for an empty mesh or a bound
/// that is not positive and finite.
pub fn meshopt_simplify(mesh: &mut Mesh, h: f32, error_in_h: f32) -> usize {
    let before = mesh.triangle_count();
    let bound = h * error_in_h;
    if before == 0 || !(bound.is_finite() && bound > 0.0) {
        return 0;
    }
    let stride = std::mem::size_of::<[f32; 3]>();
    let Ok(vertices) = VertexDataAdapter::new(meshopt::typed_to_bytes(&mesh.positions), stride, 0)
    else {
        return 0;
    };
    let options = SimplifyOptions::LockBorder | SimplifyOptions::ErrorAbsolute;
    // Target 0 triangles: stop only at the error bound.
    let indices = meshopt::simplify(&mesh.indices, &vertices, 0, bound, options, None);
    mesh.indices = indices;
    compact_vertices(mesh);
    mesh.normals.clear();
    before - mesh.triangle_count()
}

/// Removes unreferenced vertices, keeping the survivors in their original order.
pub(crate) fn compact_vertices(mesh: &mut Mesh) {
    let mut remap = vec![u32::MAX; mesh.positions.len()];
    for &i in &mesh.indices {
        remap[i as usize] = 0;
    }
    let mut next = 0u32;
    let mut kept = 0;
    for (old, slot) in remap.iter_mut().enumerate() {
        if *slot == 0 {
            *slot = next;
            mesh.positions[kept] = mesh.positions[old];
            kept += 1;
            next += 1;
        }
    }
    mesh.positions.truncate(kept);
    for i in &mut mesh.indices {
        *i = remap[*i as usize];
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::measure::on_box_boundary;
    use crate::{Clustering, ExtractSettings, Extractor, Grid, Lattice, Method};
    use glam::Vec3;
    use rmt_fields::{FnField, ScalarField, Sphere};

    /// Marching cubes of `field` on `grid` (the finish steps' tests use it too).
    pub(crate) fn marching_cubes(field: &dyn ScalarField, grid: Grid) -> Mesh {
        let mut settings = ExtractSettings::new(grid, Lattice::Simple, Clustering::None);
        settings.method = Method::Mc;
        let mut mesh = Mesh::default();
        Extractor::new()
            .extract(field, &settings, &mut mesh)
            .unwrap();
        mesh
    }

    #[test]
    fn simplified_sphere_stays_closed_genus_zero_and_within_the_bound() {
        let sphere = Sphere::new(Vec3::ZERO, 0.8);
        let grid = Grid::cube(32, 1.0);
        let mut mesh = marching_cubes(&sphere, grid);
        let before = mesh.triangle_count();
        let h = grid.h();
        let removed = meshopt_simplify(&mut mesh, h, 0.25);
        assert_eq!(removed, before - mesh.triangle_count());
        assert!(removed > before / 4, "removed only {removed} of {before}");
        let r = rmt_mesh::validate(&mesh, &|p| on_box_boundary(&grid, p));
        assert!(r.is_watertight_manifold(), "{r:?}");
        assert_eq!(
            (r.euler, r.components, r.unreferenced_vertices),
            (2, 1, 0),
            "{r:?}"
        );
        // Vertices stay near the sphere: interpolation error plus the bound.
        let limit = h * h / (8.0 * 0.8) + 0.25 * h + 1e-4;
        let worst = mesh
            .positions
            .iter()
            .map(|p| sphere.sample(Vec3::from(*p)).abs())
            .fold(0.0, f32::max);
        assert!(worst <= limit, "worst vertex {worst} > {limit}");
        assert!(mesh.normals.is_empty());
    }

    #[test]
    fn a_tighter_bound_removes_fewer_triangles_and_zero_removes_none() {
        let sphere = Sphere::new(Vec3::ZERO, 0.8);
        let grid = Grid::cube(24, 1.0);
        let original = marching_cubes(&sphere, grid);
        let removed = |e: f32| meshopt_simplify(&mut original.clone(), grid.h(), e);
        assert!(removed(0.05) < removed(0.5));
        assert_eq!(removed(0.0), 0);
        assert_eq!(removed(f32::NAN), 0);
    }

    #[test]
    fn borders_on_the_box_do_not_move() {
        // A wavy sheet that leaves the box on four sides.
        let field = FnField(|p: Vec3| p.y - 0.2 * (p.x * 3.0).sin() * (p.z * 2.0).cos());
        let grid = Grid::cube(20, 1.0);
        let mut mesh = marching_cubes(&field, grid);
        let border_before: Vec<[f32; 3]> = mesh
            .positions
            .iter()
            .copied()
            .filter(|&p| on_box_boundary(&grid, p))
            .collect();
        let removed = meshopt_simplify(&mut mesh, grid.h(), 0.5);
        assert!(removed > 0);
        let border_after: Vec<[f32; 3]> = mesh
            .positions
            .iter()
            .copied()
            .filter(|&p| on_box_boundary(&grid, p))
            .collect();
        assert_eq!(
            border_before, border_after,
            "border vertices moved or vanished"
        );
        let r = rmt_mesh::validate(&mesh, &|p| on_box_boundary(&grid, p));
        assert!(r.is_watertight_manifold(), "{r:?}");
        assert_eq!(r.boundary_edges_interior, 0);
    }

    #[test]
    fn compaction_keeps_order_and_drops_unused_vertices() {
        let mut mesh = Mesh::from_triangles(
            vec![[0.0; 3], [1.0, 0.0, 0.0], [9.0; 3], [0.0, 1.0, 0.0]],
            vec![3, 0, 1],
        );
        compact_vertices(&mut mesh);
        assert_eq!(
            mesh.positions,
            vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]
        );
        assert_eq!(mesh.indices, vec![2, 0, 1]);
    }
}
