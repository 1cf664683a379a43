//! Edge collapses under the exact check of [`crate::post::merge`] (the link condition, no normal
//! flips), so topology and closedness are kept. Edges on the mesh boundary (the box) are never
//! collapsed: the check refuses regions whose boundary touches the merged vertices.
//!
//! - [`collapse_short_edges_tiled`]: post-processed merging, every edge shorter than a threshold,
//!   shortest first, the merged vertex at the edge's midpoint (integrated clustering handles
//!   its slivers in the quotient instead, see [`crate::mt::clustering::quotient`]).

use rmt_mesh::Mesh;

use super::merge::{MergeBuffers, Reject};

/// What edge collapse did with one candidate edge (recorded with
/// [`crate::Extractor::set_recording`], see [`crate::Extractor::collapse_log`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CollapseOutcome {
    /// Collapsed.
    Collapsed,
    /// Skipped by the rule: its ends already belonged to one vertex.
    AlreadyMerged,
    /// Skipped by the rule: earlier collapses moved its ends apart, to the threshold or beyond.
    MovedApart,
    /// Skipped by the tile rule: its ends lie in different tiles.
    OtherTile,
    /// Refused by the check: the region around the edge is not a disc (or touches the box).
    NotADisc,
    /// Refused by the check: the new fan would not be the cone over the region's boundary.
    NotACone,
    /// Refused by the check: a new triangle would flip or become flat.
    Flip,
}

impl From<Reject> for CollapseOutcome {
    fn from(r: Reject) -> Self {
        match r {
            Reject::NotADisc => Self::NotADisc,
            Reject::NotACone => Self::NotACone,
            Reject::Flip => Self::Flip,
        }
    }
}

/// One candidate edge of edge collapse and what became of it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CollapseAttempt {
    /// The output vertices its two ends ended up in (equal when they were merged; `u32::MAX`
    /// for an end whose triangles all collapsed).
    pub ends: [u32; 2],
    /// Its length when it was considered, in world units.
    pub length: f32,
    /// What happened.
    pub outcome: CollapseOutcome,
}

/// Collapses edges of `mesh` shorter than `max_len`, in order of increasing initial length (ties by
/// vertex ids, so the result is deterministic). Returns (collapses done, triangles dropped).
#[cfg(test)]
pub fn collapse_short_edges(
    merge: &mut MergeBuffers,
    mesh: &mut Mesh,
    max_len: f32,
) -> (usize, usize) {
    collapse_short_edges_tiled(merge, mesh, max_len, None, None)
}

/// [`collapse_short_edges`] under the tile rule ([`crate::Tiling`]): with `tile_keys = Some(keys)`
/// (one key per vertex of `mesh`) an edge is collapsed only when both its end points carry the
/// same tile key, so collapses in different tiles never interact. With `log`, every candidate
/// edge and its outcome is appended to it (in original vertex ids until the end, then in output
/// ids).
pub fn collapse_short_edges_tiled(
    merge: &mut MergeBuffers,
    mesh: &mut Mesh,
    max_len: f32,
    tile_keys: Option<&[u64]>,
    mut log: Option<&mut Vec<CollapseAttempt>>,
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
    let first_logged = log.as_ref().map_or(0, |l| l.len());
    for &(_, a, b) in &edges {
        let (ra, rb) = (merge.rep(a), merge.rep(b));
        let mut note = |outcome: CollapseOutcome, length: f32| {
            if let Some(l) = log.as_deref_mut() {
                l.push(CollapseAttempt {
                    ends: [a, b],
                    length,
                    outcome,
                });
            }
        };
        if ra == rb {
            note(CollapseOutcome::AlreadyMerged, 0.0);
            continue;
        }
        // Vertices move as they merge: re-measure.
        let (pa, pb) = (pos(&mesh.positions, ra), pos(&mesh.positions, rb));
        let now = pa.distance_squared(pb);
        if now >= max2 {
            note(CollapseOutcome::MovedApart, now.sqrt());
            continue;
        }
        if tile_keys.is_some_and(|keys| !crate::tiles::same_tile(keys, &[ra, rb])) {
            note(CollapseOutcome::OtherTile, now.sqrt());
            continue;
        }
        let k = [ra.min(rb), ra.max(rb)];
        match merge.merge(&mut mesh.positions, &k, ((pa + pb) * 0.5).to_array(), true) {
            Ok(d) => {
                collapses += 1;
                dropped += d;
                note(CollapseOutcome::Collapsed, now.sqrt());
            }
            Err(r) => note(r.into(), now.sqrt()),
        }
    }
    merge.finish(&mut mesh.positions, &mut mesh.indices);
    if let Some(l) = log {
        for e in &mut l[first_logged..] {
            e.ends = e.ends.map(|v| merge.output_id(v));
        }
    }
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
