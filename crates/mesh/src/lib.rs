//! Indexed triangle meshes and what we measure on them.
//!
//! This crate owns the output type of every extractor in the workspace, [`Mesh`], and the checks
//! that decide whether a mesh is fit for a game: [`validate()`] (closed, manifold, consistently
//! oriented, no duplicate or zero-area triangles, Euler characteristic, components) and
//! [`quality()`] (radius ratio, minimum angle, area statistics), and how far one surface is from
//! another ([`distance`]: point-to-triangles distances on a grid). It also reads and writes meshes
//! ([`io`]: binary and ASCII PLY, OBJ, binary glTF; OBJ input through `tobj`, glTF through
//! `gltf`).
//!
//! It knows nothing about scalar fields or lattices: the extractor tells [`validate()`] which
//! points lie on the sampled domain's boundary through a closure.
//!
//! ```
//! use rmt_mesh::Mesh;
//! // A tetrahedron with outward-facing triangles.
//! let mesh = Mesh::from_triangles(
//!     vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
//!     vec![0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3],
//! );
//! assert_eq!(mesh.triangle_count(), 4);
//! ```

pub mod distance;
pub mod glb;
pub mod io;
pub mod quality;
pub mod solids;
pub mod validate;

pub use io::MeshIoError;
pub use quality::{quality, QualityReport};
pub use validate::{validate, ValidationReport};

use serde::{Deserialize, Serialize};

/// An indexed triangle mesh.
///
/// Triangles are counter-clockwise when seen from the side their normal points to (right-hand
/// rule); for extracted surfaces that is the side of increasing field value (outward for a signed
/// distance field).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Mesh {
    /// Vertex positions in world coordinates.
    pub positions: Vec<[f32; 3]>,
    /// Per-vertex unit normals; empty when not computed, else one per position.
    pub normals: Vec<[f32; 3]>,
    /// Three indices into `positions` per triangle.
    pub indices: Vec<u32>,
}

/// Marks a vertex that no triangle uses, in the table of [`compact_marked_vertices`].
pub const UNUSED_VERTEX: u32 = u32::MAX;

/// Moves the vertices whose entry in `id` is not [`UNUSED_VERTEX`] to the front, in increasing
/// old order, truncates the rest, and writes each kept vertex's new index into its entry of
/// `id` (one entry per vertex). `normals`, when given (one per vertex), follow their vertices.
/// Returns the number of vertices kept. The step shared by [`Mesh::drop_unused_vertices`] and
/// other compactions that mark the used vertices their own way.
///
/// ```
/// let mut id = vec![0, rmt_mesh::UNUSED_VERTEX, 0];
/// let mut p = vec![[0.0; 3], [1.0; 3], [2.0; 3]];
/// assert_eq!(rmt_mesh::compact_marked_vertices(&mut id, &mut p, None), 2);
/// assert_eq!((id[0], id[2], p), (0, 1, vec![[0.0; 3], [2.0; 3]]));
/// ```
pub fn compact_marked_vertices(
    id: &mut [u32],
    positions: &mut Vec<[f32; 3]>,
    mut normals: Option<&mut Vec<[f32; 3]>>,
) -> usize {
    let mut next = 0;
    for (v, slot) in id.iter_mut().enumerate() {
        if *slot != UNUSED_VERTEX {
            *slot = next as u32;
            positions[next] = positions[v];
            if let Some(n) = normals.as_deref_mut() {
                n[next] = n[v];
            }
            next += 1;
        }
    }
    positions.truncate(next);
    if let Some(n) = normals {
        n.truncate(next);
    }
    next
}

impl Mesh {
    /// A mesh from positions and a flat index list (no normals).
    pub fn from_triangles(positions: Vec<[f32; 3]>, indices: Vec<u32>) -> Self {
        Self {
            positions,
            normals: Vec::new(),
            indices,
        }
    }

    /// Number of vertices.
    pub fn vertex_count(&self) -> usize {
        self.positions.len()
    }

    /// Number of triangles.
    pub fn triangle_count(&self) -> usize {
        self.indices.len() / 3
    }

    /// Empties the mesh but keeps its allocations (for reuse across extractions).
    pub fn clear(&mut self) {
        self.positions.clear();
        self.normals.clear();
        self.indices.clear();
    }

    /// Drops the vertices no triangle uses, renumbering the others in increasing old order (the
    /// triangles keep their order; normals, when there is one per vertex, follow their
    /// vertices). `scratch` is working memory (one entry per vertex), so a caller that keeps it
    /// allocates nothing.
    ///
    /// ```
    /// let mut m = rmt_mesh::Mesh::from_triangles(vec![[9.0; 3], [0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]], vec![1, 2, 3]);
    /// m.drop_unused_vertices(&mut Vec::new());
    /// assert_eq!((m.vertex_count(), m.indices.clone()), (3, vec![0, 1, 2]));
    /// ```
    pub fn drop_unused_vertices(&mut self, scratch: &mut Vec<u32>) {
        let id = scratch;
        id.clear();
        id.resize(self.positions.len(), UNUSED_VERTEX);
        for &v in &self.indices {
            id[v as usize] = 0;
        }
        if id.iter().all(|&i| i == 0) {
            return;
        }
        let normals = (self.normals.len() == self.positions.len()).then_some(&mut self.normals);
        compact_marked_vertices(id, &mut self.positions, normals);
        for v in &mut self.indices {
            *v = id[*v as usize];
        }
    }

    /// Iterator over triangles as index triples.
    pub fn triangles(&self) -> impl Iterator<Item = [u32; 3]> + '_ {
        self.indices.chunks_exact(3).map(|t| [t[0], t[1], t[2]])
    }

    /// Total surface area.
    pub fn area(&self) -> f64 {
        self.triangles()
            .map(|t| {
                let [a, b, c] =
                    t.map(|i| glam::DVec3::from(self.positions[i as usize].map(f64::from)));
                (b - a).cross(c - a).length() * 0.5
            })
            .sum()
    }

    /// Bytes held by the vertex buffer (positions and normals) and the index buffer.
    pub fn buffer_bytes(&self) -> (usize, usize) {
        (
            (self.positions.len() + self.normals.len()) * std::mem::size_of::<[f32; 3]>(),
            self.indices.len() * std::mem::size_of::<u32>(),
        )
    }

    /// Per-vertex normals as the normalised area-weighted sum of the incident face normals
    /// (the dissertation's choice). Vertices with no triangle get a zero normal.
    pub fn compute_area_weighted_normals(&mut self) {
        let mut acc = vec![glam::Vec3::ZERO; self.positions.len()];
        for t in self.indices.chunks_exact(3) {
            let [a, b, c] =
                [t[0], t[1], t[2]].map(|i| glam::Vec3::from(self.positions[i as usize]));
            // The cross product's length is twice the area: weighting by area for free.
            let n = (b - a).cross(c - a);
            for &i in t {
                acc[i as usize] += n;
            }
        }
        self.normals.clear();
        self.normals
            .extend(acc.into_iter().map(|n| n.normalize_or_zero().to_array()));
    }
}

/// Checks that `mesh` can be written (one normal per vertex or none, whole triangles, indices in
/// range); returns whether it has normals to write. Shared by the writers of [`io`] and [`glb`].
pub(crate) fn check_writable(mesh: &Mesh) -> std::io::Result<bool> {
    let invalid = |msg: String| Err(std::io::Error::new(std::io::ErrorKind::InvalidInput, msg));
    if !mesh.normals.is_empty() && mesh.normals.len() != mesh.positions.len() {
        return invalid(format!(
            "mesh has {} normals for {} vertices",
            mesh.normals.len(),
            mesh.positions.len()
        ));
    }
    if mesh.triangle_count() * 3 != mesh.indices.len() {
        return invalid(format!(
            "index count {} is not a multiple of 3",
            mesh.indices.len()
        ));
    }
    if let Some(&i) = mesh
        .indices
        .iter()
        .find(|&&i| i as usize >= mesh.positions.len())
    {
        return invalid(format!(
            "index {i} out of range for {} vertices",
            mesh.positions.len()
        ));
    }
    Ok(!mesh.normals.is_empty())
}
