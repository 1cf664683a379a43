//! Meshes joined and compared by exact position: a position's bit pattern ([`key`]), the weld of
//! chunk meshes into one ([`weld`]) and the vertex-numbering-free triangle list
//! ([`canonical_triangles`]).

use std::collections::HashMap;

use rmt_mesh::Mesh;

/// Bit pattern of a position, with -0.0 taken as 0.0.
pub(super) fn key(p: [f32; 3]) -> [u32; 3] {
    p.map(|c| (c + 0.0).to_bits())
}

/// Concatenates `meshes` and joins vertices at exactly the same position (first occurrence
/// first, so the result depends only on the order of the meshes). No normals.
pub fn weld<'a>(meshes: impl Iterator<Item = &'a Mesh>) -> Mesh {
    let mut ids: HashMap<[u32; 3], u32> = HashMap::new();
    let mut out = Mesh::default();
    let mut map = Vec::new();
    for m in meshes {
        map.clear();
        for &p in &m.positions {
            let next = out.positions.len() as u32;
            let id = *ids.entry(key(p)).or_insert_with(|| {
                out.positions.push(p);
                next
            });
            map.push(id);
        }
        out.indices
            .extend(m.indices.iter().map(|&v| map[v as usize]));
    }
    out
}

/// The triangles of `mesh` as position bit patterns, each rotated to start at its smallest
/// corner (orientation kept), sorted: equal for two meshes exactly when they have the same
/// triangles, whatever their vertex numbering.
pub fn canonical_triangles(mesh: &Mesh) -> Vec<[[u32; 3]; 3]> {
    let mut out: Vec<[[u32; 3]; 3]> = mesh
        .triangles()
        .map(|t| {
            let k = t.map(|v| key(mesh.positions[v as usize]));
            let r = (0..3).min_by_key(|&i| k[i]).unwrap_or(0);
            [k[r], k[(r + 1) % 3], k[(r + 2) % 3]]
        })
        .collect();
    out.sort_unstable();
    out
}
