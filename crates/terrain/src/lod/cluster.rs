//! Clustering at every level: RMT's groups on one chunk's surface, each committed only when an
//! exact local check on the current surface says the merge keeps it a closed, oriented
//! manifold of the same topology (`rmt-spec.md`, "When merging keeps the surface a manifold").
//!
//! ```text
//!   owner of a crossing (lo, hi)    the end nearer its position (lo on a tie)
//!   sheets of a lattice point C     C's crossings (owned or not), joined when they share a
//!                                   triangle (their far ends bound one tet face with C)
//!   proposal                        the owned crossings of one sheet of C, when 2 or more
//!   own crossing                    every surface edge at it has two triangles in this chunk:
//!                                   its triangles go round its lattice edge as the tets do (a
//!                                   surface edge at it for each tet face through the edge), so
//!                                   a closed fan means every tet on the edge is this chunk's,
//!                                   and no other chunk has the crossing
//!   tried                           only when the members are own: the star's triangles are
//!                                   then all this chunk's; a link edge's other triangle, when
//!                                   another chunk's, is not seen, and the merge is refused
//!   commit, proposals in order of C (z, y, x), on the surface the earlier commits left:
//!       the members become one vertex v at their mean; triangles with 2+ members vanish, the
//!       rest (the fan) take v; kept only when
//!       - v's link is one simple cycle (each ring vertex starts one link edge and ends one)
//!       - every link edge has exactly one triangle outside the star (with the simple cycle,
//!         the edge-contraction link condition along a spanning tree of the group)
//!       - the Euler characteristic does not change: (1 - |members|) - dE + dF = 0
//!       - no fan triangle's normal turns: n_new . n_old > 0
//!       - no sliver made: a fan triangle of radius ratio above SLIVER_RATIO (10) is no worse
//!         than the star's worst triangle before the merge
//!   otherwise the crossings stay plain.
//!   then each own crossing still alone, in order, joins the nearest merged group beside it
//!   (sharing a triangle) that the same check allows, at most MAX_LONES (6) per group (RMT's
//!   lone crossings given to a neighbouring island, as the extractor gives them).
//! ```
//!
//! Seams stay exact: a crossing that another chunk also has is never merged, so both sides
//! keep its plain vertex, and welding by key joins them as before. A merged vertex is named by
//! its first member's key reversed (`[hi, lo]`), which no crossing has, and it is unique, since
//! the member is this chunk's alone. The result depends on the chunk's plain surface alone
//! (thread count, chunk order and re-mesh history change no byte), and it reaches into the
//! transition tets: only groups whose star touches a crossing on a chunk face stay plain. The
//! runner measures what that costs in triangles.

use glam::DVec3;
use rmt_mesh::quality::radius_ratio;

use super::lattice::Point;
use super::mt::{ChunkMesh, LodFrame};

/// A merge may make fan triangles up to this radius ratio R / (2r) (the sliver bound the
/// extractor's edge collapse uses too); above it, none worse than the worst triangle of the star
/// it replaces. So clustering never makes a chunk's worst triangle worse than
/// `max(SLIVER_RATIO, the plain surface's worst)`.
pub use rmt_mesh::quality::SLIVER_RATIO;

/// At most this many lone crossings join one group (as in the extractor's integrated
/// clustering): groups stay near their point, and the check's stars stay small.
pub const MAX_LONES: usize = 6;

/// What [`cluster_chunk`] did to one chunk.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ClusterCount {
    /// Proposed groups.
    pub proposed: usize,
    /// Proposed groups tried (their members the chunk's own).
    pub tried: usize,
    /// Groups merged.
    pub merged: usize,
    /// Lone crossings tried beside a merged vertex (each neighbour tried counts once).
    pub lone_tried: usize,
    /// Lone crossings that joined a merged vertex.
    pub lone_merged: usize,
}

impl std::ops::AddAssign for ClusterCount {
    fn add_assign(&mut self, o: Self) {
        self.proposed += o.proposed;
        self.tried += o.tried;
        self.merged += o.merged;
        self.lone_tried += o.lone_tried;
        self.lone_merged += o.lone_merged;
    }
}

/// The chunk's surface with RMT's groups merged where the exact check allows it (module doc);
/// `frame` places the lattice.
pub fn cluster_chunk(mesh: &ChunkMesh, frame: &LodFrame) -> (ChunkMesh, ClusterCount) {
    let mut count = ClusterCount::default();
    let nv = mesh.keys.len();
    let own = own_crossings(&mesh.indices, nv);
    if !own.iter().any(|&b| b) {
        return (mesh.clone(), count);
    }
    let tris = Incidence::new(&mesh.indices, nv);
    let proposals = propose(mesh, &tris, frame);
    count.proposed = proposals.len();

    let mut s = State::new(mesh);
    let mut scratch = Scratch::default();
    for (start, end) in proposals.ranges() {
        let m = &proposals.members[start..end];
        if !m.iter().all(|&v| own[v as usize]) {
            continue;
        }
        count.tried += 1;
        count.merged += usize::from(s.try_merge(m, mesh, &tris, &mut scratch));
    }
    // Lone crossings: each own crossing still alone joins the nearest merged vertex beside it
    // that the check allows, at most MAX_LONES per group.
    let mut near: Vec<(f64, u32)> = Vec::new();
    let mut lones = vec![0u8; nv];
    for x in 0..nv as u32 {
        if !own[x as usize] || s.remap[x as usize] != x || s.size[x as usize] > 1 {
            continue;
        }
        scratch.around.clear();
        s.triangles_of(x, &tris, &mut scratch.around);
        near.clear();
        let px = s.position(x);
        for &t in &scratch.around {
            for c in s.corners(mesh, t) {
                let open = usize::from(lones[c as usize]) < MAX_LONES;
                if c != x && s.size[c as usize] > 1 && open && !near.iter().any(|&(_, n)| n == c) {
                    near.push((s.position(c).distance_squared(px), c));
                }
            }
        }
        near.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        for &(_, c) in &near {
            count.lone_tried += 1;
            if s.try_merge(&[c, x], mesh, &tris, &mut scratch) {
                count.lone_merged += 1;
                // The group's leader is its lowest member, which may now be x.
                lones[s.remap[c as usize] as usize] = lones[c as usize] + 1;
                break;
            }
        }
    }
    (s.output(mesh), count)
}

/// Whether every surface edge at each vertex has two triangles (module doc: the chunk's own
/// crossings).
fn own_crossings(indices: &[u32], nv: usize) -> Vec<bool> {
    let mut edges: Vec<(u32, u32)> = indices
        .chunks_exact(3)
        .flat_map(|t| (0..3).map(move |k| (t[k].min(t[(k + 1) % 3]), t[k].max(t[(k + 1) % 3]))))
        .collect();
    edges.sort_unstable();
    let mut own = vec![true; nv];
    for run in edges.chunk_by(|a, b| a == b) {
        if run.len() != 2 {
            let (a, b) = run[0];
            own[a as usize] = false;
            own[b as usize] = false;
        }
    }
    own
}

/// Every vertex's triangles (compressed rows).
struct Incidence {
    start: Vec<u32>,
    tri: Vec<u32>,
}

impl Incidence {
    fn new(indices: &[u32], nv: usize) -> Self {
        let mut start = vec![0u32; nv + 1];
        for &v in indices {
            start[v as usize + 1] += 1;
        }
        for i in 0..nv {
            start[i + 1] += start[i];
        }
        let mut fill = start.clone();
        let mut tri = vec![0u32; indices.len()];
        for (i, &v) in indices.iter().enumerate() {
            tri[fill[v as usize] as usize] = (i / 3) as u32;
            fill[v as usize] += 1;
        }
        Incidence { start, tri }
    }

    fn of(&self, v: u32) -> &[u32] {
        &self.tri[self.start[v as usize] as usize..self.start[v as usize + 1] as usize]
    }
}

/// The proposed groups, flat: group `g` is `members[ends[g - 1]..ends[g]]`.
#[derive(Default)]
struct Proposals {
    members: Vec<u32>,
    ends: Vec<usize>,
}

impl Proposals {
    fn len(&self) -> usize {
        self.ends.len()
    }

    fn ranges(&self) -> impl Iterator<Item = (usize, usize)> + '_ {
        self.ends
            .iter()
            .scan(0, |last, &e| Some((std::mem::replace(last, e), e)))
    }
}

/// RMT's proposals (module doc), in order of their point (z, y, x).
fn propose(mesh: &ChunkMesh, tris: &Incidence, frame: &LodFrame) -> Proposals {
    let origin = frame.origin.as_dvec3();
    let u = f64::from(frame.h) * 0.5;
    let lattice = |p: Point| DVec3::new(f64::from(p[0]), f64::from(p[1]), f64::from(p[2]));
    // The owner of every crossing: the end nearer its position.
    let owner: Vec<Point> = mesh
        .keys
        .iter()
        .zip(&mesh.positions)
        .map(|([a, b], p)| {
            let q = (DVec3::from(p.map(f64::from)) - origin) / u;
            if q.distance_squared(lattice(*a)) <= q.distance_squared(lattice(*b)) {
                *a
            } else {
                *b
            }
        })
        .collect();
    // Every crossing under both ends, by point.
    let mut at: Vec<(Point, u32)> = Vec::with_capacity(2 * mesh.keys.len());
    for (v, [a, b]) in mesh.keys.iter().enumerate() {
        at.push((*a, v as u32));
        at.push((*b, v as u32));
    }
    at.sort_unstable_by_key(|&(p, v)| ([p[2], p[1], p[0]], v));
    let mut out = Proposals::default();
    let mut root: Vec<usize> = Vec::new();
    let mut i = 0;
    while i < at.len() {
        let c = at[i].0;
        let mut j = i;
        while j < at.len() && at[j].0 == c {
            j += 1;
        }
        let run = &at[i..j];
        i = j;
        if run.iter().filter(|&&(_, v)| owner[v as usize] == c).count() < 2 {
            continue;
        }
        // Sheets: union-find over the run, joined through shared triangles.
        root.clear();
        root.extend(0..run.len());
        for (x, &(_, v)) in run.iter().enumerate() {
            for &t in tris.of(v) {
                for &w in &mesh.indices[3 * t as usize..3 * t as usize + 3] {
                    if w != v {
                        if let Some(y) = run.iter().position(|&(_, r)| r == w) {
                            let (rx, ry) = (find(&mut root, x), find(&mut root, y));
                            root[rx.max(ry)] = rx.min(ry);
                        }
                    }
                }
            }
        }
        for x in 0..run.len() {
            if find(&mut root, x) != x {
                continue;
            }
            let before = out.members.len();
            for (y, &(_, v)) in run.iter().enumerate() {
                if owner[v as usize] == c && find(&mut root, y) == x {
                    out.members.push(v);
                }
            }
            if out.members.len() - before >= 2 {
                out.ends.push(out.members.len());
            } else {
                out.members.truncate(before);
            }
        }
    }
    out
}

fn find(root: &mut [usize], mut x: usize) -> usize {
    while root[x] != x {
        root[x] = root[root[x]];
        x = root[x];
    }
    x
}

/// The surface as the commits so far left it. A merged vertex is its lowest member's number
/// (its leader); the members form a chain through `next`.
struct State {
    /// Every vertex's current vertex: itself, or its group's leader.
    remap: Vec<u32>,
    /// The next member of a vertex's group (`u32::MAX` at the end).
    next: Vec<u32>,
    /// A leader's members (1 for a vertex on its own).
    size: Vec<u32>,
    /// A leader's members' positions and normals, summed.
    pos_sum: Vec<DVec3>,
    nrm_sum: Vec<DVec3>,
    /// Triangles that vanished (two or more corners merged).
    dead: Vec<bool>,
}

/// Buffers reused from one proposal to the next.
#[derive(Default)]
struct Scratch {
    star: Vec<u32>,
    around: Vec<u32>,
    fan: Vec<(u32, u32, u32)>,
    gone: Vec<u32>,
    edges: Vec<(u32, u32)>,
    next: Vec<(u32, u32)>,
}

/// Stands for the merged vertex in the check's edge lists.
const NEW: u32 = u32::MAX;

impl State {
    /// The plain surface: every vertex on its own, every triangle live.
    fn new(mesh: &ChunkMesh) -> Self {
        let nv = mesh.keys.len();
        let sums = |v: &[[f32; 3]]| v.iter().map(|p| DVec3::from(p.map(f64::from))).collect();
        State {
            remap: (0..nv as u32).collect(),
            next: vec![u32::MAX; nv],
            size: vec![1; nv],
            pos_sum: sums(&mesh.positions),
            nrm_sum: sums(&mesh.normals),
            dead: vec![false; mesh.indices.len() / 3],
        }
    }

    /// The live triangles around current vertex `v` into `out` (appended; may repeat).
    fn triangles_of(&self, v: u32, tris: &Incidence, out: &mut Vec<u32>) {
        let mut m = v;
        while m != u32::MAX {
            out.extend(tris.of(m).iter().filter(|&&t| !self.dead[t as usize]));
            m = self.next[m as usize];
        }
    }

    /// Current vertex `v`'s position (its members' mean), as it is stored (f32).
    fn position(&self, v: u32) -> DVec3 {
        (self.pos_sum[v as usize] / f64::from(self.size[v as usize]))
            .as_vec3()
            .as_dvec3()
    }

    fn corners(&self, mesh: &ChunkMesh, t: u32) -> [u32; 3] {
        let i = 3 * t as usize;
        std::array::from_fn(|k| self.remap[mesh.indices[i + k] as usize])
    }

    /// Checks merging current vertices `members` (own, and distinct) on the current surface
    /// and commits it when it passes.
    fn try_merge(
        &mut self,
        members: &[u32],
        mesh: &ChunkMesh,
        tris: &Incidence,
        s: &mut Scratch,
    ) -> bool {
        let is_member = |v: u32| members.contains(&v);
        s.star.clear();
        for &m in members {
            self.triangles_of(m, tris, &mut s.star);
        }
        s.star.sort_unstable();
        s.star.dedup();
        // The fan (ring edge a -> b, with the triangle it came from) and the vanishing ones.
        s.fan.clear();
        s.gone.clear();
        for &t in &s.star {
            let c = self.corners(mesh, t);
            match c.iter().filter(|&&v| is_member(v)).count() {
                1 => {
                    let k = c.iter().position(|&v| is_member(v)).unwrap_or(0);
                    s.fan.push((c[(k + 1) % 3], c[(k + 2) % 3], t));
                }
                _ => s.gone.push(t),
            }
        }
        if s.fan.len() < 3 {
            return false;
        }
        // v's link: one simple cycle.
        s.next.clear();
        s.next.extend(s.fan.iter().map(|&(a, b, _)| (a, b)));
        s.next.sort_unstable();
        if s.next.windows(2).any(|w| w[0].0 == w[1].0) {
            return false;
        }
        let next_of = |a: u32, next: &[(u32, u32)]| {
            next.binary_search_by_key(&a, |e| e.0)
                .ok()
                .map(|i| next[i].1)
        };
        let first = s.next[0].0;
        let (mut a, mut steps) = (first, 0usize);
        loop {
            match next_of(a, &s.next) {
                Some(b) => a = b,
                None => return false,
            }
            steps += 1;
            if a == first || steps > s.next.len() {
                break;
            }
        }
        if a != first || steps != s.next.len() {
            return false;
        }
        // Outside the star: each link edge on exactly one triangle (one that another chunk
        // holds is not seen: the merge is then refused, never wrongly allowed).
        for &(a, b) in &s.next {
            s.around.clear();
            self.triangles_of(a, tris, &mut s.around);
            s.around.sort_unstable();
            s.around.dedup();
            let mut on_link_edge = 0;
            for &t in &s.around {
                if s.star.binary_search(&t).is_ok() {
                    continue;
                }
                if self.corners(mesh, t).contains(&b) {
                    on_link_edge += 1;
                }
            }
            if on_link_edge != 1 {
                return false;
            }
        }
        // Euler characteristic: (1 - |members|) - dE + dF = 0.
        s.edges.clear();
        for &t in &s.star {
            let c = self.corners(mesh, t);
            for k in 0..3 {
                let (x, y) = (c[k], c[(k + 1) % 3]);
                s.edges.push((x.min(y), x.max(y)));
            }
        }
        s.edges.sort_unstable();
        s.edges.dedup();
        let edges_before = s.edges.len() as i64;
        s.edges.clear();
        for &(a, b, _) in &s.fan {
            s.edges.push((a.min(b), a.max(b)));
            s.edges.push((a, NEW));
            s.edges.push((b, NEW));
        }
        s.edges.sort_unstable();
        s.edges.dedup();
        let edges_after = s.edges.len() as i64;
        let faces = s.fan.len() as i64 - s.star.len() as i64;
        if (1 - members.len() as i64) - (edges_after - edges_before) + faces != 0 {
            return false;
        }
        // The merged vertex, and no fan triangle turns.
        let (mut sum, mut normal, mut size) = (DVec3::ZERO, DVec3::ZERO, 0);
        for &m in members {
            sum += self.pos_sum[m as usize];
            normal += self.nrm_sum[m as usize];
            size += self.size[m as usize];
        }
        let p = (sum / f64::from(size)).as_vec3().as_dvec3();
        let mut worst_new: f64 = 0.0;
        for &(a, b, t) in &s.fan {
            let c = self.corners(mesh, t);
            let k = c.iter().position(|&v| is_member(v)).unwrap_or(0);
            let (pa, pb, pm) = (self.position(a), self.position(b), self.position(c[k]));
            let old = (pa - pm).cross(pb - pm);
            let new = (pa - p).cross(pb - p);
            if old.dot(new) <= 0.0 {
                return false;
            }
            worst_new = worst_new.max(radius_ratio([pa, pb, p]));
        }
        // No sliver made: a fan triangle above SLIVER_RATIO must be no worse than the worst
        // triangle of the star it replaces.
        if worst_new > SLIVER_RATIO {
            let worst_old = s
                .star
                .iter()
                .map(|&t| radius_ratio(self.corners(mesh, t).map(|v| self.position(v))))
                .fold(0.0, f64::max);
            if worst_new > worst_old {
                return false;
            }
        }
        // Commit: the lowest member leads; the others' chains join its chain.
        let leader = members.iter().copied().min().unwrap_or(members[0]);
        let mut tail = leader;
        while self.next[tail as usize] != u32::MAX {
            tail = self.next[tail as usize];
        }
        for &m in members.iter().filter(|&&m| m != leader) {
            self.next[tail as usize] = m;
            let mut x = m;
            loop {
                self.remap[x as usize] = leader;
                tail = x;
                x = self.next[x as usize];
                if x == u32::MAX {
                    break;
                }
            }
        }
        self.size[leader as usize] = size;
        self.pos_sum[leader as usize] = sum;
        self.nrm_sum[leader as usize] = normal;
        for &t in &s.gone {
            self.dead[t as usize] = true;
        }
        true
    }

    /// The surface: live triangles in their order, vertices in order of first use.
    fn output(&self, mesh: &ChunkMesh) -> ChunkMesh {
        let mut number = vec![u32::MAX; mesh.keys.len()];
        let mut out = ChunkMesh {
            samples: mesh.samples,
            ..ChunkMesh::default()
        };
        for t in 0..self.dead.len() {
            if self.dead[t] {
                continue;
            }
            for v in self.corners(mesh, t as u32) {
                let n = &mut number[v as usize];
                if *n == u32::MAX {
                    *n = out.keys.len() as u32;
                    let [a, b] = mesh.keys[v as usize];
                    let merged = self.size[v as usize] > 1;
                    out.keys.push(if merged { [b, a] } else { [a, b] });
                    if merged {
                        let n = self.nrm_sum[v as usize];
                        out.positions.push(self.position(v).as_vec3().to_array());
                        out.normals.push(if n.length_squared() > 0.0 {
                            n.normalize().as_vec3().to_array()
                        } else {
                            mesh.normals[v as usize]
                        });
                    } else {
                        out.positions.push(mesh.positions[v as usize]);
                        out.normals.push(mesh.normals[v as usize]);
                    }
                }
                out.indices.push(*n);
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A surface of the given positions and triangles (keys made up, unique).
    fn surface(positions: &[[f32; 3]], indices: &[u32]) -> ChunkMesh {
        ChunkMesh {
            keys: (0..positions.len() as i32)
                .map(|i| [[2 * i, 0, 0], [2 * i + 1, 0, 0]])
                .collect(),
            positions: positions.to_vec(),
            normals: positions.iter().map(|_| [0.0, 0.0, 1.0]).collect(),
            indices: indices.to_vec(),
            samples: 0,
        }
    }

    /// Tries merging `members` of `mesh` on a fresh state; the outcome and the surface after.
    fn merge(mesh: &ChunkMesh, members: &[u32]) -> (bool, ChunkMesh) {
        let nv = mesh.keys.len();
        let tris = Incidence::new(&mesh.indices, nv);
        let mut s = State::new(mesh);
        let r = s.try_merge(members, mesh, &tris, &mut Scratch::default());
        (r, s.output(mesh))
    }

    /// V - E + F, and whether every edge has two triangles running opposite ways.
    fn euler_closed(m: &ChunkMesh) -> (i64, bool) {
        let mut e: Vec<(u32, u32)> = m
            .indices
            .chunks_exact(3)
            .flat_map(|t| (0..3).map(move |k| (t[k], t[(k + 1) % 3])))
            .collect();
        let closed = e.iter().all(|&(a, b)| {
            e.iter().filter(|&&x| x == (b, a)).count() == 1
                && e.iter().filter(|&&x| x == (a, b)).count() == 1
        });
        e.iter_mut().for_each(|x| *x = (x.0.min(x.1), x.0.max(x.1)));
        e.sort_unstable();
        e.dedup();
        let f = m.indices.len() as i64 / 3;
        (m.keys.len() as i64 - e.len() as i64 + f, closed)
    }

    /// A solid of `rmt_mesh::solids` as a chunk surface.
    fn solid(m: rmt_mesh::Mesh) -> ChunkMesh {
        surface(&m.positions, &m.indices)
    }

    fn octahedron() -> ChunkMesh {
        solid(rmt_mesh::solids::octahedron())
    }

    #[test]
    fn the_octahedron_is_closed_with_euler_two() {
        assert_eq!(euler_closed(&octahedron()), (2, true));
    }

    #[test]
    fn two_neighbours_of_the_octahedron_merge_into_a_closed_surface() {
        let (r, after) = merge(&octahedron(), &[0, 2]);
        assert!(r);
        assert_eq!(after.keys.len(), 5);
        assert_eq!(after.indices.len() / 3, 6);
        assert_eq!(euler_closed(&after), (2, true));
        // The merged vertex sits at the mean and is named by its leader's key reversed.
        let v = after.keys.iter().position(|[a, b]| a > b).unwrap();
        assert_eq!(after.positions[v], [0.5, 0.5, 0.0]);
    }

    #[test]
    fn opposite_vertices_of_the_octahedron_do_not_merge() {
        // Every triangle keeps one of them: the new vertex's link runs round twice.
        let (r, after) = merge(&octahedron(), &[0, 1]);
        assert!(!r);
        assert_eq!(after.indices.len(), 24);
        assert_eq!(euler_closed(&after), (2, true));
    }

    #[test]
    fn a_tetrahedron_does_not_lose_an_edge() {
        let t = solid(rmt_mesh::solids::tetrahedron());
        assert_eq!(euler_closed(&t), (2, true));
        assert!(!merge(&t, &[0, 1]).0);
    }

    #[test]
    fn a_merge_that_turns_a_triangle_is_refused() {
        // A flat closed disk: centre 0 above, centre 7 below (both at the origin), rim 1..=6 in
        // angular order; rim vertex 2 sits close to the centre.
        let rim = [
            [1.0, 0.0],
            [0.05, 0.05],
            [-1.0, 0.5],
            [-1.0, -0.5],
            [0.0, -1.0],
            [0.7, -0.7],
        ];
        let mut p = vec![[0.0f32; 3]];
        p.extend(rim.iter().map(|&[x, y]| [x, y, 0.0]));
        p.push([0.0; 3]);
        let mut idx = Vec::new();
        for k in 0..6u32 {
            let (a, b) = (1 + k, 1 + (k + 1) % 6);
            idx.extend([0, a, b]);
            idx.extend([7, b, a]);
        }
        let m = surface(&p, &idx);
        assert_eq!(euler_closed(&m), (2, true));
        // 0 and 1 meet at (0.5, 0): the triangle (v, 2, 3) then faces down.
        assert!(!merge(&m, &[0, 1]).0);
        // 0 and 5 meet at (0, -0.5), from where the whole rim is seen.
        let (r, after) = merge(&m, &[0, 5]);
        assert!(r);
        assert_eq!(euler_closed(&after), (2, true));
    }

    #[test]
    fn own_crossings_are_those_with_a_closed_fan() {
        // A fan of 4 triangles round vertex 0, open at its rim.
        let p = [
            [0.0; 3],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [-1.0, 0.0, 0.0],
            [0.0, -1.0, 0.0],
        ];
        let m = surface(&p, &[0, 1, 2, 0, 2, 3, 0, 3, 4, 0, 4, 1]);
        assert_eq!(
            own_crossings(&m.indices, 5),
            vec![true, false, false, false, false]
        );
        assert!(own_crossings(&octahedron().indices, 6).iter().all(|&o| o));
    }
}
