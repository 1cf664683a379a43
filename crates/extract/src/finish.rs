//! What an engine does to an extracted mesh before it uploads it: meshoptimizer's simplifier down
//! to a triangle budget ([`simplify_to`]), and meshoptimizer's vertex-cache reordering
//! ([`optimize_vertex_cache`]). Any method's mesh can go through either, so that methods are
//! compared at an equal triangle budget and in the index order a game would draw.
//!
//! ```text
//!   extract ──► mesh ──► simplify_to(target, lock_border)? ──► optimize_vertex_cache? ──► measure
//! ```
//!
//! Rules:
//! - the simplifier stops at the target count or earlier, when no collapse is left that keeps the
//!   topology (meshoptimizer never joins parts, closes holes or flips triangles); the count
//!   reached is the mesh's, the target is recorded beside it;
//! - no error bound: the budget decides (the error limit is the mesh's whole extent), and the
//!   error meshoptimizer reports for the result is returned in world units;
//! - with `lock_border`, vertices on open borders (where the surface leaves the sampled box) do
//!   not move, as chunked terrain needs; without it they may;
//! - unused vertices are dropped, the others keep their order; normals are recomputed
//!   (area-weighted) when the mesh had them, since the old ones belong to removed vertices;
//! - vertex-cache reordering permutes triangles only: positions, normals and the set of
//!   triangles stay the same.

use meshopt::{SimplifyOptions, VertexDataAdapter};
use rmt_mesh::Mesh;

use crate::post::compact_vertices;

/// What [`simplify_to`] did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Simplified {
    /// Triangles before.
    pub triangles_before: usize,
    /// The triangle count asked for.
    pub target: usize,
    /// Triangles after (at least `target` unless the input had fewer; more when meshoptimizer
    /// ran out of collapses that keep the topology).
    pub triangles_after: usize,
    /// The error meshoptimizer reports for the result (its quadric distance estimate), in world
    /// units.
    pub error: f32,
}

/// Simplifies `mesh` in place with meshoptimizer's simplifier towards `target` triangles, with
/// open borders locked when `lock_border`. A mesh at or below the target is left as it is (error
/// 0).
pub fn simplify_to(mesh: &mut Mesh, target: usize, lock_border: bool) -> Simplified {
    let before = mesh.triangle_count();
    let mut out = Simplified {
        triangles_before: before,
        target,
        triangles_after: before,
        error: 0.0,
    };
    if before <= target || mesh.positions.is_empty() {
        return out;
    }
    let stride = std::mem::size_of::<[f32; 3]>();
    let Ok(vertices) = VertexDataAdapter::new(meshopt::typed_to_bytes(&mesh.positions), stride, 0)
    else {
        return out;
    };
    let options = if lock_border {
        SimplifyOptions::LockBorder
    } else {
        SimplifyOptions::None
    };
    let mut relative_error = 0.0f32;
    // Relative error limit 1: the whole extent, so that only the budget stops the simplifier.
    let indices = meshopt::simplify(
        &mesh.indices,
        &vertices,
        target * 3,
        1.0,
        options,
        Some(&mut relative_error),
    );
    let scale = meshopt::simplify_scale(&vertices);
    mesh.indices = indices;
    let had_normals = !mesh.normals.is_empty();
    mesh.normals.clear();
    compact_vertices(mesh);
    if had_normals {
        mesh.compute_area_weighted_normals();
    }
    out.triangles_after = mesh.triangle_count();
    out.error = relative_error * scale;
    out
}

/// Reorders `mesh`'s triangles for the post-transform vertex cache (meshoptimizer's
/// `optimize_vertex_cache`), as an engine does before upload.
pub fn optimize_vertex_cache(mesh: &mut Mesh) {
    if mesh.indices.is_empty() {
        return;
    }
    mesh.indices = meshopt::optimize_vertex_cache(&mesh.indices, mesh.positions.len());
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::measure::on_box_boundary;
    use crate::post::simplify::tests::marching_cubes;
    use crate::Grid;
    use glam::Vec3;
    use rmt_fields::{FnField, ScalarField, Sphere};

    fn sorted_triangles(m: &Mesh) -> Vec<[u32; 3]> {
        let mut t: Vec<[u32; 3]> = m
            .indices
            .chunks_exact(3)
            .map(|t| {
                // Rotate so the smallest index leads (keeps the orientation).
                let k = (0..3).min_by_key(|&k| t[k]).unwrap_or(0);
                [t[k], t[(k + 1) % 3], t[(k + 2) % 3]]
            })
            .collect();
        t.sort_unstable();
        t
    }

    #[test]
    fn a_sphere_reaches_the_budget_closed_and_near_the_surface() {
        let sphere = Sphere::new(Vec3::ZERO, 0.8);
        let grid = Grid::cube(32, 1.0);
        let mut mesh = marching_cubes(&sphere, grid);
        let before = mesh.triangle_count();
        let target = before / 4;
        let s = simplify_to(&mut mesh, target, false);
        assert_eq!(s.triangles_before, before);
        assert_eq!(s.triangles_after, mesh.triangle_count());
        assert!(s.triangles_after <= target, "{s:?}");
        assert!(s.triangles_after >= target * 9 / 10, "{s:?}");
        assert!(s.error > 0.0 && s.error < grid.h(), "{s:?}");
        let r = rmt_mesh::validate(&mesh, &|p| on_box_boundary(&grid, p));
        assert!(r.is_watertight_manifold(), "{r:?}");
        assert_eq!((r.euler, r.components, r.unreferenced_vertices), (2, 1, 0));
        // Normals: one per vertex again, unit length.
        assert_eq!(mesh.normals.len(), mesh.positions.len());
        assert!(mesh
            .normals
            .iter()
            .all(|n| (Vec3::from(*n).length() - 1.0).abs() < 1e-3));
        // The reported error bounds how far vertices left the sphere (plus MC's own error).
        let worst = mesh
            .positions
            .iter()
            .map(|p| sphere.sample(Vec3::from(*p)).abs())
            .fold(0.0, f32::max);
        assert!(worst <= s.error + grid.h() * 0.05, "{worst} > {}", s.error);
    }

    #[test]
    fn a_smaller_budget_costs_more_error_and_a_larger_one_changes_nothing() {
        let sphere = Sphere::new(Vec3::ZERO, 0.8);
        let grid = Grid::cube(24, 1.0);
        let original = marching_cubes(&sphere, grid);
        let n = original.triangle_count();
        let at = |t: usize| simplify_to(&mut original.clone(), t, false);
        assert!(at(n / 8).error > at(n / 2).error);
        let mut same = original.clone();
        let s = simplify_to(&mut same, n, false);
        assert_eq!((s.triangles_after, s.error), (n, 0.0));
        assert_eq!(same, original);
    }

    #[test]
    fn locked_borders_stay_and_free_borders_may_move() {
        let field = FnField(|p: Vec3| p.y - 0.2 * (p.x * 3.0).sin() * (p.z * 2.0).cos());
        let grid = Grid::cube(20, 1.0);
        let original = marching_cubes(&field, grid);
        let border = |m: &Mesh| -> Vec<[f32; 3]> {
            m.positions
                .iter()
                .copied()
                .filter(|&p| on_box_boundary(&grid, p))
                .collect()
        };
        let target = original.triangle_count() / 5;
        let mut locked = original.clone();
        simplify_to(&mut locked, target, true);
        assert_eq!(border(&locked), border(&original));
        let mut free = original.clone();
        let s = simplify_to(&mut free, target, false);
        assert!(s.triangles_after <= target, "{s:?}");
        assert!(
            border(&free).len() < border(&original).len(),
            "the free simplifier kept every border vertex"
        );
        // Locking costs budget: the locked mesh cannot go as low, or only as low.
        assert!(locked.triangle_count() >= free.triangle_count());
    }

    #[test]
    fn vertex_cache_order_keeps_the_triangles_and_lowers_acmr() {
        let sphere = Sphere::new(Vec3::ZERO, 0.8);
        let grid = Grid::cube(24, 1.0);
        let mut mesh = marching_cubes(&sphere, grid);
        // A scrambled order first, so that the reordering has something to do.
        let mut tris: Vec<[u32; 3]> = mesh
            .indices
            .chunks_exact(3)
            .map(|t| [t[0], t[1], t[2]])
            .collect();
        let n = tris.len();
        for i in 0..n {
            tris.swap(i, (i * 7919 + 13) % n);
        }
        mesh.indices = tris.concat();
        let before = mesh.clone();
        optimize_vertex_cache(&mut mesh);
        assert_eq!(mesh.positions, before.positions);
        assert_eq!(mesh.normals, before.normals);
        assert_eq!(sorted_triangles(&mesh), sorted_triangles(&before));
        let acmr =
            |m: &Mesh| meshopt::analyze_vertex_cache(&m.indices, m.positions.len(), 16, 0, 0).acmr;
        assert!(
            acmr(&mesh) < acmr(&before) * 0.8,
            "{} vs {}",
            acmr(&mesh),
            acmr(&before)
        );
        let mut empty = Mesh::default();
        optimize_vertex_cache(&mut empty);
        assert!(empty.indices.is_empty());
    }
}
