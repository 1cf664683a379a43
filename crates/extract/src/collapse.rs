//! Edge collapses under the exact check of [`crate::merge`] (the link condition, no normal
//! flips), so topology and closedness are kept. Edges on the mesh boundary (the box) are never
//! collapsed: the check refuses regions whose boundary touches the merged vertices.
//!
//! - [`collapse_short_edges`]: post-processed merging, every edge shorter than a threshold,
//!   shortest first, the merged vertex at the edge's midpoint;
//! - [`collapse_slivers`]: the last step of integrated clustering, one collapse per needle or cap
//!   triangle left between clusters.

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

/// Aspect ratio R / (2 r) of the triangle `a b c` (1 for an equilateral triangle); infinite
/// when the triangle is degenerate.
pub fn aspect_ratio(a: glam::Vec3, b: glam::Vec3, c: glam::Vec3) -> f32 {
    let (la, lb, lc) = ((b - c).length(), (c - a).length(), (a - b).length());
    let double_area = (b - a).cross(c - a).length();
    if double_area <= 0.0 {
        return f32::INFINITY;
    }
    // R = la lb lc / (4 area), r = 2 area / perimeter.
    let ar = la * lb * lc * (la + lb + lc) / (4.0 * double_area * double_area);
    if ar.is_finite() {
        ar
    } else {
        f32::INFINITY
    }
}

/// Removes slivers left between clusters: every live triangle whose aspect ratio exceeds `max_ar`
/// gets one of its edges collapsed (shortest first), when the exact check accepts it. The merged
/// vertex stays where the endpoint with more members was (a cluster vertex keeps its place),
/// or at the midpoint when both have as many. Triangles are visited in index order, up to three
/// sweeps, so the result is deterministic. Returns (collapses done, triangles dropped).
///
/// Slivers come from crossings that no cluster could take: a refused cluster near a point where
/// the surface nearly touches the lattice, or a lone crossing squeezed between two clusters.
///
/// With `tile_keys = Some(keys)` (the tile rule, [`crate::Tiling`]) only edges whose endpoints
/// have the same tile key are collapsed, as in [`collapse_short_edges_tiled`].
pub fn collapse_slivers(
    merge: &mut MergeBuffers,
    positions: &mut [[f32; 3]],
    max_ar: f32,
    tile_keys: Option<&[u64]>,
) -> (usize, usize) {
    let pos = |p: &[[f32; 3]], i: u32| glam::Vec3::from(p[i as usize]);
    let (mut collapses, mut dropped) = (0, 0);
    for _sweep in 0..3 {
        let before = collapses;
        for t in 0..merge.triangle_count() {
            if !merge.is_alive(t) {
                continue;
            }
            let [a, b, c] = merge.triangle(t);
            let (pa, pb, pc) = (pos(positions, a), pos(positions, b), pos(positions, c));
            if aspect_ratio(pa, pb, pc) <= max_ar {
                continue;
            }
            let mut edges = [
                (pa.distance_squared(pb), a.min(b), a.max(b)),
                (pb.distance_squared(pc), b.min(c), b.max(c)),
                (pc.distance_squared(pa), c.min(a), c.max(a)),
            ];
            edges.sort_unstable_by(|x, y| {
                x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)).then(x.2.cmp(&y.2))
            });
            for &(_, u, v) in &edges {
                if tile_keys.is_some_and(|keys| !crate::tiles::same_tile(keys, &[u, v])) {
                    continue;
                }
                let (pu, pv) = (pos(positions, u), pos(positions, v));
                let (nu, nv) = (merge.member_count(u), merge.member_count(v));
                let target = match nu.cmp(&nv) {
                    std::cmp::Ordering::Greater => pu,
                    std::cmp::Ordering::Less => pv,
                    std::cmp::Ordering::Equal => (pu + pv) * 0.5,
                };
                if let Ok(d) = merge.merge(positions, &[u, v], target.to_array(), true) {
                    collapses += 1;
                    dropped += d;
                    break;
                }
            }
        }
        if collapses == before {
            break;
        }
    }
    (collapses, dropped)
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    #[test]
    fn aspect_ratio_is_one_for_equilateral_and_grows_for_needles() {
        let s3 = 3f32.sqrt();
        let eq = aspect_ratio(Vec3::ZERO, Vec3::X, Vec3::new(0.5, s3 / 2.0, 0.0));
        assert!((eq - 1.0).abs() < 1e-5, "{eq}");
        // Right isosceles: R = sqrt(2)/2, r = (2 - sqrt(2))/2, R/2r = 1.2071.
        let right = aspect_ratio(Vec3::ZERO, Vec3::X, Vec3::Y);
        assert!((right - 1.2071).abs() < 1e-3, "{right}");
        let needle = aspect_ratio(Vec3::ZERO, Vec3::X, Vec3::new(0.5, 1e-3, 0.0));
        assert!(needle > 100.0, "{needle}");
        assert_eq!(
            aspect_ratio(Vec3::ZERO, Vec3::X, Vec3::X * 2.0),
            f32::INFINITY
        );
    }

    #[test]
    fn without_short_edges_the_mesh_is_only_compacted_as_finish_would() {
        // An octahedron with two unused vertices (first and in the middle): nothing to collapse.
        let (positions, indices) = crate::merge::tests::octahedron();
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

    #[test]
    fn a_cap_in_a_closed_mesh_is_collapsed_and_the_mesh_stays_closed() {
        // An octahedron with one vertex pushed almost onto the opposite edge's plane: its
        // triangles there are caps. The collapse removes one vertex and keeps the surface closed.
        let (mut positions, indices) = crate::merge::tests::octahedron();
        // Make triangle 0-2-4 a needle: 4 nearly on the segment 0-2... but keep it convex-ish.
        positions[4] = [0.5, 0.5, 0.002];
        let mut merge = MergeBuffers::default();
        merge.load(positions.len(), &indices);
        let bad = (0..merge.triangle_count())
            .filter(|&t| {
                let [a, b, c] = merge.triangle(t);
                let p = |i: u32| Vec3::from(positions[i as usize]);
                aspect_ratio(p(a), p(b), p(c)) > 4.0
            })
            .count();
        assert!(bad > 0);
        let (collapses, dropped) = collapse_slivers(&mut merge, &mut positions, 4.0, None);
        assert!(collapses >= 1);
        assert_eq!(dropped, 2 * collapses);
        let mut indices_out = Vec::new();
        let mut pos_out = positions.to_vec();
        merge.finish(&mut pos_out, &mut indices_out);
        let mesh = rmt_mesh::Mesh {
            positions: pos_out,
            normals: Vec::new(),
            indices: indices_out,
        };
        let report = rmt_mesh::validate(&mesh, &|_| false);
        assert!(report.is_watertight_manifold(), "{report:?}");
        assert_eq!(report.euler, 2);
    }
}
