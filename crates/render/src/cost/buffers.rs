//! Buffer sizes: what an engine uploads for a mesh, and what its `.glb` file weighs.
//!
//! The upload is an index buffer of `u32` (4 bytes an index, 12 a triangle) and an interleaved
//! vertex buffer of position and normal (`f32` x 3 each, [`VERTEX_SIZE`] = 24 bytes a vertex),
//! whether or not the mesh already holds normals. The `.glb` size is the length of what
//! [`rmt_mesh::glb::to_glb`] writes, in memory, for the mesh with normals (computed area-weighted
//! when it holds none, as the runner writes them).

use crate::cost::analyzers::VERTEX_SIZE;
use crate::{RenderError, Result};
use rmt_mesh::Mesh;
use serde::{Deserialize, Serialize};
use std::borrow::Cow;

/// Bytes of a mesh's GPU buffers and of its binary glTF file.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct BufferSizes {
    /// Index buffer bytes: 4 per index.
    pub index_bytes: u64,
    /// Vertex buffer bytes: [`VERTEX_SIZE`] per vertex.
    pub vertex_bytes: u64,
    /// Length of the mesh's `.glb` file.
    pub glb_bytes: u64,
}

/// The buffer sizes of `mesh` (see the [module documentation](self)).
///
/// Errors when the `.glb` cannot be written (indices out of range, normals that are neither
/// absent nor one per vertex, a mesh too large for the format).
pub fn buffer_sizes(mesh: &Mesh) -> Result<BufferSizes> {
    crate::raster::check_indices(mesh)?;
    let with_normals = if mesh.normals.is_empty() && !mesh.positions.is_empty() {
        let mut m = mesh.clone();
        m.compute_area_weighted_normals();
        Cow::Owned(m)
    } else {
        Cow::Borrowed(mesh)
    };
    let glb = rmt_mesh::glb::to_glb(&with_normals)
        .map_err(|e| RenderError::InvalidMesh(format!("cannot write it as .glb: {e}")))?;
    Ok(BufferSizes {
        index_bytes: (mesh.indices.len() * std::mem::size_of::<u32>()) as u64,
        vertex_bytes: (mesh.positions.len() * VERTEX_SIZE) as u64,
        glb_bytes: glb.len() as u64,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shapes::uv_sphere;

    #[test]
    fn sizes_follow_the_counts_and_the_glb_holds_both_buffers() {
        let mut mesh = uv_sphere(1.0, 16, 8);
        mesh.normals.clear();
        let s = buffer_sizes(&mesh).unwrap();
        assert_eq!(s.index_bytes, 12 * mesh.triangle_count() as u64);
        assert_eq!(s.vertex_bytes, 24 * mesh.vertex_count() as u64);
        // The file holds positions, normals and indices, plus a header and a JSON chunk.
        let payload = s.index_bytes + s.vertex_bytes;
        assert!(
            s.glb_bytes > payload && s.glb_bytes < payload + 4096,
            "{s:?}"
        );
        // With the normals already there, the file is the same.
        mesh.compute_area_weighted_normals();
        assert_eq!(buffer_sizes(&mesh).unwrap(), s);
        let bad = Mesh::from_triangles(vec![[0.0; 3]; 3], vec![0, 1, 9]);
        assert!(buffer_sizes(&bad).is_err());
    }
}
