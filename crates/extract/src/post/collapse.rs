//! Edge collapses under the exact check of [`crate::post::merge`] (the link condition, no normal
//! flips), so topology and closedness are kept. Edges on the mesh boundary (the box) are never
//! collapsed: the check refuses regions whose boundary touches the merged vertices.
//!
//! - [`collapse_short_edges_tiled`]: post-processed merging, every edge shorter than a threshold,
//!   shortest first, the merged vertex at the edge's midpoint (integrated clustering handles
//!   its slivers in the quotient instead, see [`crate::mt::clustering::quotient`]).

use rmt_mesh::Mesh;

use super::merge::MergeBuffers;

/// Collapses edges of `mesh` shorter than `max_len`, in order of increasing initial length (ties by
/// vertex ids, so the result is deterministic). Returns (collapses done, triangles dropped).
#[cfg(test)]
pub fn collapse_short_edges(
    merge: &mut MergeBuffers,
    mesh: &mut Mesh,
    max_len: f32,
) -> (usize, usize) {
    collapse_short_edges_tiled(merge, mesh, max_len, None)
}

/// [`collapse_short_edges`] under the tile rule ([`crate::Tiling`]): with `tile_keys = Some(keys)`
/// (one key per vertex of `mesh`) an edge is collapsed only when both its end points carry the
/// same tile key, so collapses in different tiles never interact.
pub fn collapse_short_edges_tiled(
    merge: &mut MergeBuffers,
    mesh: &mut Mesh,
    max_len: f32,
    tile_keys: Option<&[u64]>,
) -> (usize, usize) {
    let max2 = max_len * max_len;
    let pos = |p: &[[f32; 3]], i: u32| glam::Vec3::from(p[i as usize]);
    // Candidate edges, each once (a < b).
    let mut edges: Vec<(f32, u32, u32)> = Vec::new();
    for t in mesh.indices.chunks_exact(3) {
        for e in 0..3 {
            let (a, b) = (t[e], t[(e + 1) % 3]);
            if a < b {
                let d2 = pos(&mesh.positions, a).distance_squared(pos(&mesh.positions, b));
                if d2 < max2 {
                    edges.push((d2, a, b));
                }
            }
        }
    }
    if edges.is_empty() {
        // Nothing to collapse: what `finish` would leave without a merge (no adjacency built).
        merge.drop_unused_vertices(mesh);
        return (0, 0);
    }
    merge.load(mesh.positions.len(), &mesh.indices);
    edges.sort_unstable_by(|x, y| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)).then(x.2.cmp(&y.2)));
    let (mut collapses, mut dropped) = (0, 0);
    for &(_, a, b) in &edges {
        let (ra, rb) = (merge.rep(a), merge.rep(b));
        if ra == rb {
            continue;
        }
        // Vertices move as they merge: re-measure.
        let (pa, pb) = (pos(&mesh.positions, ra), pos(&mesh.positions, rb));
        if pa.distance_squared(pb) >= max2 {
            continue;
        }
        if tile_keys.is_some_and(|keys| !crate::tiles::same_tile(keys, &[ra, rb])) {
            continue;
        }
        let k = [ra.min(rb), ra.max(rb)];
        if let Ok(d) = merge.merge(&mut mesh.positions, &k, ((pa + pb) * 0.5).to_array(), true) {
            collapses += 1;
            dropped += d;
        }
    }
    merge.finish(&mut mesh.positions, &mut mesh.indices);
    (collapses, dropped)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn without_short_edges_the_mesh_is_only_compacted_as_finish_would() {
        // An octahedron with two unused vertices (first and in the middle): nothing to collapse.
        let (positions, indices) = super::super::merge::tests::octahedron();
        let mut p = vec![[9.0, 9.0, 9.0]];
        p.extend_from_slice(&positions[..3]);
        p.push([7.0, 7.0, 7.0]);
        p.extend_from_slice(&positions[3..]);
        let shifted: Vec<u32> = indices
            .iter()
            .map(|&v| if v < 3 { v + 1 } else { v + 2 })
            .collect();
        let mut mesh = Mesh {
            positions: p.clone(),
            indices: shifted.clone(),
            ..Mesh::default()
        };
        let mut merge = MergeBuffers::default();
        assert_eq!(collapse_short_edges(&mut merge, &mut mesh, 1e-3), (0, 0));
        // What loading and finishing without a merge gives.
        let (mut fp, mut fi) = (p, Vec::new());
        let mut reference = MergeBuffers::default();
        reference.load(fp.len(), &shifted);
        reference.finish(&mut fp, &mut fi);
        assert_eq!(mesh.positions, fp);
        assert_eq!(mesh.indices, fi);
        assert_eq!(mesh.positions, positions);
        assert_eq!(mesh.indices, indices);
    }
}
