//! meshoptimizer's analyzers (the `meshopt` crate): the vertex-transform cache, overdraw and
//! vertex fetch, as a game engine's tooling reports them.
//!
//! - [`vertex_cache`]: ACMR (vertices transformed per triangle; best 0.5, worst 3) and ATVR
//!   (vertices transformed per vertex used; best 1) of meshoptimizer's FIFO cache model with
//!   `cache_size` entries, no warp and no primitive-group limit (`warp_size = 0`,
//!   `primgroup_size = 0`, as meshoptimizer's own demo reports them), for the index order as
//!   given or after [`meshopt::optimize_vertex_cache`] (what an engine applies before upload).
//! - [`overdraw`]: shaded / covered pixels of meshoptimizer's own rasteriser: three
//!   axis-aligned orthographic views of the mesh's bounding box at 256 x 256 pixels, front and
//!   back faces in separate buffers, a depth test in submission order and no pre-pass, so a
//!   pixel is shaded again whenever a later triangle is nearer (best 1; it depends on the
//!   triangle order).
//! - [`overfetch`]: bytes fetched / bytes used of a direct-mapped 128 KiB cache of 64-byte lines
//!   over a vertex buffer of `vertex_size` bytes per vertex: best 1.
//!
//! meshoptimizer trusts its inputs (an index out of range is undefined behaviour in C++), so
//! every function here checks the mesh first.

use crate::raster::check_indices;
use crate::{RenderError, Result};
use rmt_mesh::Mesh;

/// Bytes per vertex as an engine uploads our meshes: position and normal, 3 x f32 each.
pub const VERTEX_SIZE: usize = 24;

/// Results of meshoptimizer's vertex-transform cache model.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VertexCacheStats {
    /// Average cache miss ratio: vertices transformed per triangle (0.5..=3).
    pub acmr: f64,
    /// Average transformed vertex ratio: vertices transformed per vertex used (>= 1).
    pub atvr: f64,
}

/// Checks the indices and that every position is finite.
fn check_mesh(mesh: &Mesh) -> Result<()> {
    check_indices(mesh)?;
    if let Some(i) = mesh
        .positions
        .iter()
        .position(|p| !p.iter().all(|c| c.is_finite()))
    {
        return Err(RenderError::InvalidMesh(format!(
            "vertex {i} has a non-finite position {:?}",
            mesh.positions[i]
        )));
    }
    Ok(())
}

/// ACMR and ATVR of `mesh`'s index order with a FIFO cache of `cache_size` (>= 3) entries; with
/// `optimize`, of the order [`meshopt::optimize_vertex_cache`] makes. Both 0 without triangles.
pub fn vertex_cache(mesh: &Mesh, cache_size: u32, optimize: bool) -> Result<VertexCacheStats> {
    check_mesh(mesh)?;
    if cache_size < 3 {
        return Err(RenderError::InvalidSettings(format!(
            "the vertex cache needs at least 3 entries, got {cache_size}"
        )));
    }
    let n = mesh.positions.len();
    let optimized;
    let indices = if optimize {
        optimized = meshopt::optimize_vertex_cache(&mesh.indices, n);
        &optimized
    } else {
        &mesh.indices
    };
    Ok(cache_stats(indices, n, cache_size))
}

/// The analyzer on indices already checked.
fn cache_stats(indices: &[u32], vertex_count: usize, cache_size: u32) -> VertexCacheStats {
    let s = meshopt::analyze_vertex_cache(indices, vertex_count, cache_size, 0, 0);
    VertexCacheStats {
        acmr: f64::from(s.acmr),
        atvr: f64::from(s.atvr),
    }
}

/// ACMR and ATVR at each of `cache_sizes`, for the index order as given and after
/// [`meshopt::optimize_vertex_cache`] (optimising once): `(as_given, optimized)`.
pub fn vertex_cache_before_after(
    mesh: &Mesh,
    cache_sizes: &[u32],
) -> Result<(Vec<VertexCacheStats>, Vec<VertexCacheStats>)> {
    check_mesh(mesh)?;
    if let Some(s) = cache_sizes.iter().find(|&&s| s < 3) {
        return Err(RenderError::InvalidSettings(format!(
            "the vertex cache needs at least 3 entries, got {s}"
        )));
    }
    let n = mesh.positions.len();
    let optimized = meshopt::optimize_vertex_cache(&mesh.indices, n);
    let stats = |indices: &[u32]| -> Vec<VertexCacheStats> {
        cache_sizes
            .iter()
            .map(|&s| cache_stats(indices, n, s))
            .collect()
    };
    Ok((stats(&mesh.indices), stats(&optimized)))
}

/// meshoptimizer's overdraw: pixels shaded / pixels covered (>= 1; 0 without triangles).
pub fn overdraw(mesh: &Mesh) -> Result<f64> {
    check_mesh(mesh)?;
    let bytes = meshopt::typed_to_bytes(&mesh.positions);
    let adapter = meshopt::VertexDataAdapter::new(bytes, std::mem::size_of::<[f32; 3]>(), 0)
        .map_err(|e| RenderError::InvalidMesh(format!("meshopt vertex data: {e}")))?;
    Ok(f64::from(
        meshopt::analyze_overdraw(&mesh.indices, &adapter).overdraw,
    ))
}

/// meshoptimizer's vertex-fetch overfetch for a buffer of `vertex_size` (1..=256) bytes per
/// vertex: bytes fetched / bytes of the vertices used (>= 1; 0 without triangles).
pub fn overfetch(mesh: &Mesh, vertex_size: usize) -> Result<f64> {
    check_mesh(mesh)?;
    if !(1..=256).contains(&vertex_size) {
        return Err(RenderError::InvalidSettings(format!(
            "the vertex size must be 1..=256 bytes, got {vertex_size}"
        )));
    }
    let s = meshopt::analyze_vertex_fetch(&mesh.indices, mesh.positions.len(), vertex_size);
    Ok(f64::from(s.overfetch))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shapes::uv_sphere;

    /// The sphere's triangles in a scrambled order (a fixed stride through them), which a
    /// vertex cache handles badly.
    fn scrambled_sphere() -> Mesh {
        let mut mesh = uv_sphere(1.0, 48, 24);
        let tris: Vec<[u32; 3]> = mesh.triangles().collect();
        let n = tris.len();
        let stride = (0..n).map(|k| 997 + k).find(|s| gcd(*s, n) == 1).unwrap();
        mesh.indices = (0..n).flat_map(|k| tris[k * stride % n]).collect();
        mesh
    }

    fn gcd(a: usize, b: usize) -> usize {
        if b == 0 {
            a
        } else {
            gcd(b, a % b)
        }
    }

    #[test]
    fn optimizing_the_cache_lowers_acmr_of_a_scrambled_mesh() {
        let mesh = scrambled_sphere();
        let (before, after) = vertex_cache_before_after(&mesh, &[16, 32]).unwrap();
        for (b, a) in before.iter().zip(&after) {
            assert!(b.acmr > 2.0 && b.acmr <= 3.0, "{b:?}");
            assert!(a.acmr < 1.0 && a.acmr >= 0.5, "{a:?}");
            assert!(a.atvr >= 1.0 && a.atvr < b.atvr, "{a:?} {b:?}");
        }
        // A larger cache never misses more on the optimised order.
        assert!(after[1].acmr <= after[0].acmr);
        assert_eq!(vertex_cache(&mesh, 16, true).unwrap(), after[0]);
        assert_eq!(vertex_cache(&mesh, 32, false).unwrap(), before[1]);
    }

    #[test]
    fn one_triangle_transforms_each_vertex_once() {
        let mesh = Mesh::from_triangles(
            vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
            vec![0, 1, 2],
        );
        let s = vertex_cache(&mesh, 16, false).unwrap();
        assert_eq!((s.acmr, s.atvr), (3.0, 1.0));
        // 3 vertices of 24 bytes fit in two 64-byte lines: 128 bytes fetched for 72 used.
        assert_eq!(
            overfetch(&mesh, VERTEX_SIZE).unwrap(),
            f64::from(128.0f32 / 72.0)
        );
    }

    #[test]
    fn a_convex_closed_mesh_shades_each_pixel_about_once() {
        // Front and back faces go to separate buffers, and a convex mesh has one layer of each
        // in every direction: one shade per covered pixel, but for ties on shared edges.
        let o = overdraw(&uv_sphere(1.0, 48, 24)).unwrap();
        assert!((1.0..1.1).contains(&o), "{o}");
    }

    #[test]
    fn bad_input_is_an_error_not_undefined_behaviour() {
        let bad = Mesh::from_triangles(
            vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
            vec![0, 1, 3],
        );
        assert!(vertex_cache(&bad, 16, false).is_err());
        assert!(overdraw(&bad).is_err());
        assert!(overfetch(&bad, 24).is_err());
        let nan = Mesh::from_triangles(
            vec![[0.0; 3], [f32::NAN, 0.0, 0.0], [0.0, 1.0, 0.0]],
            vec![0, 1, 2],
        );
        assert!(overdraw(&nan).unwrap_err().to_string().contains("vertex 1"));
        let ok = uv_sphere(1.0, 8, 4);
        assert!(vertex_cache(&ok, 2, false).is_err());
        assert!(overfetch(&ok, 0).is_err());
    }
}
