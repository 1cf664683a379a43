//! Edge collapses under the exact check of [`crate::post::merge`] (the link condition, no normal
//! flips), so topology and closedness are kept. Edges on the mesh boundary (the box) are never
//! collapsed: the check refuses regions whose boundary touches the merged vertices.
//!
//! - [`collapse_degenerate_tiled`]: post-processed clustering. It collapses what makes a
//!   triangle degenerate: groups of (near) coincident vertices at once, every edge shorter than
//!   the threshold, and the shortest edge of every sliver (radius ratio above
//!   [`SLIVER_RATIO`]), shortest first, in rounds until nothing more passes the check
//!   (integrated clustering handles its slivers in the quotient instead, see
//!   [`crate::mt::clustering::quotient`]);
//! - [`collapse_short_edges_tiled`]: one pass over the edges shorter than a threshold, shortest
//!   first, the merged vertex at the edge's midpoint: the weld before meshopt.
//!
//! Why post-processing needs more than the one pass (see the `collapse_slivers` example): on the
//! paper manifest's objects the pass left slivers up to a radius ratio of 864,788 (inscribed
//! sphere, simple lattice). Every short edge of those slivers had been refused by the check,
//! almost all because a triangle would flip: three crossings at one sample point (the surface
//! through it) make needles whose pairwise collapses each flip the needle the third crossing
//! makes, and a midpoint can flip a neighbour that an end point does not. And the caps (three
//! nearly collinear vertices) have no edge below the threshold, so the pass never looked at them.

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
    /// Skipped by the rule: earlier collapses moved its ends apart, to the threshold or beyond
    /// (and, for a sliver's shortest edge, left no sliver with it as its shortest edge).
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

/// Triangles whose radius ratio R / (2r) exceeds this are slivers: post-processed clustering
/// collapses their shortest edge whatever its length ([`collapse_degenerate_tiled`]).
///
/// 10 is well beyond anything a sound triangle of marching tetrahedra has (integrated
/// clustering's worst on the paper's inscribed sphere is 2.8) and far below the degenerate
/// ones (caps of 10 to 93, needles of thousands and more): it removes the degenerate triangles
/// and hardly any other (on the paper's post-processed objects, 0.1-0.7% fewer triangles than
/// without the sliver rule), which is what the dissertation's post-processing means to do.
/// Lower bounds trade triangles for quality (4: another 0.1-2.4% fewer triangles, radius-ratio
/// means up to 0.05 lower). One value with the level-of-detail world's clustering
/// (`rmt_mesh::quality::SLIVER_RATIO`).
pub use rmt_mesh::quality::SLIVER_RATIO;

/// At most this many rounds of [`collapse_degenerate_tiled`]; a round that collapses nothing
/// ends it earlier (every collapse removes a vertex, so it always ends).
const MAX_ROUNDS: usize = 32;

/// The radius ratio R / (2r) of the triangle `p` (in `f64`; infinite for zero area), as
/// [`rmt_mesh::quality`] measures it.
fn radius_ratio(p: [glam::Vec3; 3]) -> f64 {
    rmt_mesh::quality::radius_ratio(p.map(|v| v.as_dvec3()))
}

/// Post-processed clustering: collapses what makes a triangle degenerate, under the exact check
/// of [`crate::post::merge`] (and the tile rule with `tile_keys`), in rounds until a round
/// collapses nothing. Each round:
///
/// 1. welds, all at once, each group of vertices joined by edges shorter than `weld_len`
///    (crossings on top of each other where the surface passes through a sample point: merged
///    two at a time, each pair's collapse would flip the needles the third one makes);
/// 2. collapses, shortest first (ties by vertex ids), every edge shorter than `max_len` and the
///    shortest edge of every triangle whose radius ratio exceeds `sliver_ratio` (caps have no
///    short edge), as long as it is still that short, or still the shortest edge of such a
///    triangle, when its turn comes.
///
/// A merged vertex goes to the edge's (or group's) midpoint; when the check refuses that because
/// a triangle would flip, to either end point instead (lower vertex id first). Everything runs
/// in one deterministic order on the calling thread. Returns (collapses done, one per vertex
/// removed; triangles dropped); with `log`, every candidate and its outcome (see
/// [`crate::Extractor::collapse_log`]: in original vertex ids while it runs, then in output
/// ids).
pub fn collapse_degenerate_tiled(
    merge: &mut MergeBuffers,
    mesh: &mut Mesh,
    max_len: f32,
    weld_len: f32,
    sliver_ratio: f64,
    tile_keys: Option<&[u64]>,
    mut log: Option<&mut Vec<CollapseAttempt>>,
) -> (usize, usize) {
    if mesh.indices.is_empty() {
        merge.drop_unused_vertices(mesh);
        return (0, 0);
    }
    let (max2, weld2) = (max_len * max_len, weld_len * weld_len);
    let pos = |p: &[[f32; 3]], i: u32| glam::Vec3::from(p[i as usize]);
    merge.load(mesh.positions.len(), &mesh.indices);
    let first_logged = log.as_ref().map_or(0, |l| l.len());
    let (mut collapses, mut dropped) = (0, 0);
    // (squared length, a, b, whether it is a sliver's shortest edge and not short).
    let mut candidates: Vec<(f32, u32, u32, bool)> = Vec::new();
    let mut parent: Vec<u32> = Vec::new();
    let mut groups: Vec<(u32, u32)> = Vec::new();
    let mut k: Vec<u32> = Vec::new();
    let (mut ids, mut around) = (Vec::new(), Vec::new());
    let note = |log: &mut Option<&mut Vec<CollapseAttempt>>, ends, length, outcome| {
        if let Some(l) = log.as_deref_mut() {
            l.push(CollapseAttempt {
                ends,
                length,
                outcome,
            });
        }
    };
    for _ in 0..MAX_ROUNDS {
        let before = collapses;
        // 1. Groups of (near) coincident vertices, by union-find over the short edges.
        parent.clear();
        parent.extend(0..mesh.positions.len() as u32);
        let find = |parent: &mut Vec<u32>, mut v: u32| {
            while parent[v as usize] != v {
                let up = parent[parent[v as usize] as usize];
                parent[v as usize] = up;
                v = up;
            }
            v
        };
        let mut any = false;
        for t in merge.live_triangles() {
            for e in 0..3 {
                let (a, b) = (t[e], t[(e + 1) % 3]);
                if pos(&mesh.positions, a).distance_squared(pos(&mesh.positions, b)) < weld2 {
                    let (ra, rb) = (find(&mut parent, a), find(&mut parent, b));
                    if ra != rb {
                        // The smaller id is the root: groups are keyed by their first vertex.
                        parent[ra.max(rb) as usize] = ra.min(rb);
                        any = true;
                    }
                }
            }
        }
        if any {
            groups.clear();
            for v in 0..mesh.positions.len() as u32 {
                let r = find(&mut parent, v);
                if r != v {
                    groups.push((r, v));
                }
            }
            groups.sort_unstable();
            for group in groups.chunk_by(|x, y| x.0 == y.0) {
                k.clear();
                k.push(group[0].0);
                k.extend(group.iter().map(|g| g.1));
                if tile_keys.is_some_and(|keys| !crate::tiles::same_tile(keys, &k)) {
                    continue;
                }
                let centre = k
                    .iter()
                    .fold(glam::Vec3::ZERO, |s, &v| s + pos(&mesh.positions, v))
                    / k.len() as f32;
                let places = [centre, pos(&mesh.positions, k[0])];
                let mut result = Err(Reject::Flip);
                for p in places {
                    result = merge.merge(&mut mesh.positions, &k, p.to_array(), true);
                    if result != Err(Reject::Flip) {
                        break;
                    }
                }
                let outcome = match result {
                    Ok(d) => {
                        // One collapse per vertex removed, as for edges.
                        collapses += k.len() - 1;
                        dropped += d;
                        CollapseOutcome::Collapsed
                    }
                    Err(r) => r.into(),
                };
                for &v in &k[1..] {
                    note(&mut log, [k[0], v], 0.0, outcome);
                }
            }
        }
        // 2. Short edges, and the shortest edge of each sliver.
        candidates.clear();
        for t in merge.live_triangles() {
            let p = t.map(|v| pos(&mesh.positions, v));
            let d2 = [0, 1, 2].map(|e| p[e].distance_squared(p[(e + 1) % 3]));
            for e in 0..3 {
                if d2[e] < max2 {
                    let (a, b) = (t[e], t[(e + 1) % 3]);
                    candidates.push((d2[e], a.min(b), a.max(b), false));
                }
            }
            let e = (0..3).min_by(|&x, &y| d2[x].total_cmp(&d2[y])).unwrap_or(0);
            if d2[e] >= max2 && radius_ratio(p) > sliver_ratio {
                let (a, b) = (t[e], t[(e + 1) % 3]);
                candidates.push((d2[e], a.min(b), a.max(b), true));
            }
        }
        candidates.sort_unstable_by(|x, y| {
            x.0.total_cmp(&y.0)
                .then(x.1.cmp(&y.1))
                .then(x.2.cmp(&y.2))
                .then(x.3.cmp(&y.3))
        });
        candidates.dedup_by(|x, y| (x.1, x.2) == (y.1, y.2));
        for &(_, a, b, sliver) in &candidates {
            let (ra, rb) = (merge.rep(a), merge.rep(b));
            if ra == rb {
                note(&mut log, [a, b], 0.0, CollapseOutcome::AlreadyMerged);
                continue;
            }
            // Vertices move as they merge: re-measure.
            let (pa, pb) = (pos(&mesh.positions, ra), pos(&mesh.positions, rb));
            let now = pa.distance_squared(pb);
            let wanted = now < max2
                || (sliver && {
                    merge.triangles_around(ra, &mut ids, &mut around);
                    around.iter().any(|t| {
                        t.contains(&rb) && {
                            let p = t.map(|v| pos(&mesh.positions, v));
                            let d2 = [0, 1, 2].map(|e| p[e].distance_squared(p[(e + 1) % 3]));
                            d2.iter().all(|&d| d >= now) && radius_ratio(p) > sliver_ratio
                        }
                    })
                });
            if !wanted {
                note(&mut log, [a, b], now.sqrt(), CollapseOutcome::MovedApart);
                continue;
            }
            if tile_keys.is_some_and(|keys| !crate::tiles::same_tile(keys, &[ra, rb])) {
                note(&mut log, [a, b], now.sqrt(), CollapseOutcome::OtherTile);
                continue;
            }
            let k = [ra.min(rb), ra.max(rb)];
            let places = [
                (pa + pb) * 0.5,
                pos(&mesh.positions, k[0]),
                pos(&mesh.positions, k[1]),
            ];
            let mut result = Err(Reject::Flip);
            for p in places {
                result = merge.merge(&mut mesh.positions, &k, p.to_array(), true);
                if result != Err(Reject::Flip) {
                    break;
                }
            }
            match result {
                Ok(d) => {
                    collapses += 1;
                    dropped += d;
                    note(&mut log, [a, b], now.sqrt(), CollapseOutcome::Collapsed);
                }
                Err(r) => note(&mut log, [a, b], now.sqrt(), r.into()),
            }
        }
        if collapses == before {
            break;
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

    /// The worst radius ratio of `mesh`, and how many of its slivers (ratio above
    /// [`SLIVER_RATIO`]) have an edge shorter than `short` (the others are caps).
    fn slivers(mesh: &Mesh, short: f32) -> (f64, usize, usize) {
        let (mut worst, mut needles, mut caps) = (0.0f64, 0, 0);
        for t in mesh.triangles() {
            let p = t.map(|v| glam::Vec3::from(mesh.positions[v as usize]));
            let r = radius_ratio(p);
            worst = worst.max(r);
            if r > SLIVER_RATIO {
                if (0..3).any(|e| p[e].distance(p[(e + 1) % 3]) < short) {
                    needles += 1;
                } else {
                    caps += 1;
                }
            }
        }
        (worst, needles, caps)
    }

    #[test]
    fn post_processing_leaves_no_sliver_on_the_papers_inscribed_sphere() {
        // The paper's ss_sp: radius 1 in [-1, 1]^3, 50 cells, simple lattice. The surface
        // passes through sample points, where three crossings coincide.
        use crate::{Clustering, ExtractSettings, Extractor, Grid, Lattice};
        let grid = Grid::cube(50, 1.0);
        let sphere = rmt_fields::Sphere::new(glam::Vec3::ZERO, 1.0);
        let s = ExtractSettings::new(grid, Lattice::Simple, Clustering::None);
        let mut plain = Mesh::default();
        Extractor::new().extract(&sphere, &s, &mut plain).unwrap();
        let h = grid.h();
        let on_box = |p: [f32; 3]| crate::measure::on_box_boundary(&grid, p);
        let r0 = rmt_mesh::validate(&plain, &on_box);
        let mut merge = MergeBuffers::default();
        // The one pass over short edges keeps needles (a zero-length edge whose collapse
        // flips) and caps (no short edge).
        let mut one_pass = plain.clone();
        collapse_short_edges(&mut merge, &mut one_pass, 0.5 * h);
        let (worst, needles, caps) = slivers(&one_pass, 0.5 * h);
        assert!(
            worst > 1e5 && needles > 0 && caps > 0,
            "{worst} {needles} {caps}"
        );
        let mut mesh = plain.clone();
        let (collapses, dropped) = collapse_degenerate_tiled(
            &mut merge,
            &mut mesh,
            0.5 * h,
            crate::mt::WELD * h,
            SLIVER_RATIO,
            None,
            None,
        );
        let (worst, needles, caps) = slivers(&mesh, 0.5 * h);
        assert!(worst <= SLIVER_RATIO, "{worst}");
        assert_eq!((needles, caps), (0, 0));
        assert!(mesh.triangle_count() < one_pass.triangle_count());
        assert_eq!(plain.triangle_count() - mesh.triangle_count(), dropped);
        assert_eq!(plain.vertex_count() - mesh.vertex_count(), collapses);
        let r = rmt_mesh::validate(&mesh, &on_box);
        assert!(r.is_watertight_manifold(), "{r:?}");
        assert_eq!((r.euler, r.components), (r0.euler, r0.components));
        assert_eq!((r.zero_area_triangles, r.unreferenced_vertices), (0, 0));
    }

    #[test]
    fn post_processing_follows_the_tile_rule() {
        // With every vertex in its own tile nothing merges; with one tile for all, as without.
        use crate::{Clustering, ExtractSettings, Extractor, Grid, Lattice};
        let grid = Grid::cube(16, 1.0);
        let sphere = rmt_fields::Sphere::new(glam::Vec3::ZERO, 0.7);
        let s = ExtractSettings::new(grid, Lattice::BodyCentred, Clustering::None);
        let mut plain = Mesh::default();
        Extractor::new().extract(&sphere, &s, &mut plain).unwrap();
        let run = |keys: Option<&[u64]>| {
            let mut mesh = plain.clone();
            let out = collapse_degenerate_tiled(
                &mut MergeBuffers::default(),
                &mut mesh,
                0.5 * grid.h(),
                1e-4 * grid.h(),
                SLIVER_RATIO,
                keys,
                None,
            );
            (mesh, out)
        };
        let own: Vec<u64> = (0..plain.vertex_count() as u64).collect();
        assert_eq!(run(Some(&own)).1, (0, 0));
        let (free, counts) = run(None);
        assert!(counts.0 > 0);
        let one = vec![3u64; plain.vertex_count()];
        let (tiled, tiled_counts) = run(Some(&one));
        assert_eq!(tiled_counts, counts);
        assert_eq!(
            (tiled.positions, tiled.indices),
            (free.positions, free.indices)
        );
    }
}
