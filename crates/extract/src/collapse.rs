//! Post-processed merging: collapse every edge shorter than a threshold, shortest first, each
//! collapse accepted only under the exact check of [`crate::merge`] (the link condition, no
//! normal flips), so topology and closedness are kept. The merged vertex sits at the edge's
//! midpoint. Edges on the mesh boundary (the box) are never collapsed: the check refuses regions
//! whose boundary touches the merged vertices.

use rmt_mesh::Mesh;

use crate::merge::MergeBuffers;

/// Collapses edges of `mesh` shorter than `max_len`, in order of increasing initial length (ties by
/// vertex ids, so the result is deterministic). Returns (collapses done, triangles dropped).
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
    merge.load(mesh.positions.len(), &mesh.indices);
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
