//! The quotient test and the repair rounds of integrated clustering.
//!
//! The proposals ([`crate::cluster`]) are a partition of the crossings into groups. Picture every
//! active group contracted at once into one vertex (at the mean of its crossings): the
//! *quotient* of plain MT. A group's star in the quotient comes only from the tetrahedra around
//! its owner point that hold one of its crossings' edges, and the labels there depend only on the
//! groups of the crossings of those tetrahedra: 2-ring data. A group is kept when
//!
//! - (a) the sub-complex it collapses (its crossings, the MT edges and triangles among them) is
//!   contractible: connected with V - E + F = 1 (state-independent, tested once);
//! - (b) its link in the quotient is one simple cycle of at least three vertices: every link
//!   vertex starts one link edge and ends one, so every edge at the new vertex has exactly two
//!   triangles, oppositely oriented, and no two triangles coincide;
//! - (c) no triangle of its star flips against the gradient of the tetrahedron it comes from,
//!   and none has zero area unless its source MT triangle already had.
//!
//! ```text
//!        y-----z                 the link of g: y -> z -> w -> ... -> y, one cycle;
//!       / \ g / \                each triangle (g, y, z) keeps the orientation of its MT
//!      x---[g]---w               source and faces along the field's gradient
//!       \ / \ / /
//!        v-----u
//! ```
//!
//! **Repair.** Rounds test the groups against the state the previous round left (Jacobi rounds:
//! parallel, and the same result for any thread count). Every failing group names the group to
//! split in its closed star (itself and the groups of its link): the failing one of lowest
//! priority, smaller first, then the later owner. The named groups become singletons, and only
//! the groups whose star holds a crossing of a split group are tested again. Groups only split,
//! and all singletons is plain MT, so the rounds end, and they end with every group passing.
//! (This follows the Python study in `shared/research/order-free-rmt`; the property tests in
//! `tests/random_fields.rs` check validity and topology on random fields.)

use glam::DVec3;
use rayon::prelude::*;

use crate::cluster::Candidate;
use crate::mt::{tet_triangles, CrossedIndex, Layout};

/// "No group" in the crossing-to-group table.
pub(crate) const NONE: u32 = u32::MAX;

/// At most this many lone crossings join one group.
pub(crate) const MAX_LONES: usize = 4;

/// Tetrahedra of a star: 24 around the owner, and up to 6 around each lone crossing's edge.
const MAX_TETS: usize = 24 + 6 * MAX_LONES;

/// Two triangles per tetrahedron at most.
const MAX_TRIS: usize = 2 * MAX_TETS;

/// A crossing that is in no island of its own point, given to the group of a neighbouring
/// point ([`crate::cluster`]'s proposals of lone crossings): its id, owner slot and edge.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) struct Lone {
    pub(crate) id: u32,
    pub(crate) slot: u32,
    pub(crate) dir: u8,
}

/// What the quotient test reads: the lattice, the crossings and the proposed groups.
pub(crate) struct Quotient<'a> {
    pub(crate) l: &'a Layout<'a>,
    pub(crate) iso: f32,
    pub(crate) crossed: &'a CrossedIndex,
    /// Crossing positions (plain MT vertices).
    pub(crate) cpos: &'a [[f32; 3]],
    pub(crate) groups: &'a [Candidate],
    /// The lone crossings of group g: `lones[lone_start[g]..lone_start[g + 1]]`, by id.
    pub(crate) lones: &'a [Lone],
    pub(crate) lone_start: &'a [u32],
    /// Each group's lowest crossing id: its label in the quotient.
    pub(crate) leader: &'a [u32],
    /// Group of each crossing, or [`NONE`].
    pub(crate) group_of: &'a [u32],
    /// Position of each group's vertex: the mean of its crossings.
    pub(crate) centroid: &'a [[f32; 3]],
}

/// The MT triangles of the tetrahedra around a group's owner that hold one of its crossings'
/// edges (every MT triangle touching the group comes from one of them), kept per thread.
pub(crate) struct Star {
    n: usize,
    tris: [[u32; 3]; MAX_TRIS],
    /// The source tetrahedron of each triangle, in `tets`.
    src: [u8; MAX_TRIS],
    /// Bit i: triangle i has a member of the group.
    touching: u128,
    /// The tetrahedra: the point they are taken around (slot) and their index in its
    /// [`Layout::around`] list; and (for those of lone crossings, from `lone_from` on) their
    /// corner slots, sorted (to list each once).
    ntets: usize,
    lone_from: usize,
    tets: [(u32, u8); MAX_TETS],
    keys: [[u32; 4]; MAX_TETS],
}

impl Default for Star {
    fn default() -> Self {
        Self {
            n: 0,
            tris: [[0; 3]; MAX_TRIS],
            src: [0; MAX_TRIS],
            touching: 0,
            ntets: 0,
            lone_from: 0,
            tets: [(0, 0); MAX_TETS],
            keys: [[0; 4]; MAX_TETS],
        }
    }
}

/// The outcome of the repair rounds.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct Settled {
    /// Seconds of test (a) and the first round.
    pub(crate) t_tests_s: f64,
    /// Seconds of the later rounds.
    pub(crate) t_repair_s: f64,
    /// Groups split (those refused by test (a) included).
    pub(crate) split: usize,
    /// Rounds that split at least one group (0: every group passed at once).
    pub(crate) rounds: usize,
}

impl Quotient<'_> {
    /// The label of crossing `x` in the quotient: the leader of its group when that group is
    /// active, else itself.
    #[inline(always)]
    fn label(&self, x: u32, active: &[u8]) -> u32 {
        let h = self.group_of[x as usize];
        if h != NONE && active[h as usize] != 0 {
            self.leader[h as usize]
        } else {
            x
        }
    }

    /// Position of quotient vertex `label`.
    #[inline(always)]
    fn position(&self, label: u32, active: &[u8]) -> [f32; 3] {
        let h = self.group_of[label as usize];
        if h != NONE && active[h as usize] != 0 {
            self.centroid[h as usize]
        } else {
            self.cpos[label as usize]
        }
    }

    /// The lone crossings of group `gi`.
    #[inline(always)]
    fn lones_of(&self, gi: usize) -> &[Lone] {
        &self.lones[self.lone_start[gi] as usize..self.lone_start[gi + 1] as usize]
    }

    /// Number of crossings in group `gi`.
    pub(crate) fn size(&self, gi: usize) -> u32 {
        self.groups[gi].size() + self.lones_of(gi).len() as u32
    }

    /// Fills `s` with the star of group `gi`: the tetrahedra around its owner holding one of
    /// its island's edges, and those around each of its lone crossings' edges.
    pub(crate) fn star(&self, gi: usize, s: &mut Star) {
        let g = &self.groups[gi];
        s.n = 0;
        s.ntets = 0;
        s.touching = 0;
        self.add_tets(gi, g.slot as usize, g.dirs, None, s);
        s.lone_from = s.ntets;
        for lone in self.lones_of(gi) {
            let owner = Some((g.slot as usize, g.dirs));
            self.add_tets(gi, lone.slot as usize, 1 << lone.dir, owner, s);
        }
    }

    /// Adds to `s` the tetrahedra around the point at `slot` that hold one of its edges `dirs`,
    /// with their triangles. For a lone crossing's edge, `owner` (the group's owner slot and
    /// island edges) leaves out the tetrahedra listed already: those holding an island edge, and
    /// those of an earlier lone crossing.
    fn add_tets(
        &self,
        gi: usize,
        slot: usize,
        dirs: u16,
        owner: Option<(usize, u16)>,
        s: &mut Star,
    ) {
        let p = self.l.coords_of(slot);
        let par = (p[0] & 1) as usize;
        let regular = self.l.is_regular(p);
        let v = &self.l.s.values;
        for (k, tet) in self.l.around[par].iter().enumerate() {
            if tet.from_point & dirs == 0 || !(regular || self.l.has_tet(p, tet)) {
                continue;
            }
            let idx = tet.delta.map(|d| (slot as isize + d) as usize);
            if let Some((os, od)) = owner {
                if let Some(i) = idx.iter().position(|&x| x == os) {
                    if (0..4).any(|j| j != i && od & (1 << tet.dir[i][j]) != 0) {
                        continue;
                    }
                }
                let mut key = idx.map(|i| i as u32);
                key.sort_unstable();
                if s.keys[s.lone_from..s.ntets].contains(&key) {
                    continue;
                }
                s.keys[s.ntets] = key;
            }
            if s.ntets == MAX_TETS {
                continue;
            }
            s.tets[s.ntets] = (slot as u32, k as u8);
            let val = idx.map(|i| v[i]);
            let mut tris = [[0u32; 3]; 2];
            let id = |o: usize, d: u8| self.crossed.get(idx[o]).id(d);
            let n = tet_triangles(val, self.iso, &tet.dir, id, self.cpos, &mut tris);
            for t in &tris[..n] {
                if t.iter().any(|&x| self.group_of[x as usize] == gi as u32) {
                    s.touching |= 1 << s.n;
                }
                s.tris[s.n] = *t;
                s.src[s.n] = s.ntets as u8;
                s.n += 1;
            }
            s.ntets += 1;
        }
    }

    /// The index of member `x` of group `gi` in its test (a) bit sets: the island rank, or 16 +
    /// its place among the lone crossings.
    #[inline(always)]
    fn local(&self, gi: usize, x: u32) -> usize {
        let g = &self.groups[gi];
        let r = x.wrapping_sub(g.first);
        if r < 16 && (g.members >> r) & 1 != 0 {
            r as usize
        } else {
            16 + self
                .lones_of(gi)
                .iter()
                .position(|l| l.id == x)
                .unwrap_or(0)
        }
    }

    /// Whether the crossing on the edge from the point at `slot` to its neighbour `dir` is an
    /// inner vertex of plain MT: the tetrahedra around the edge close up (they do not on the
    /// box faces, where the surface leaves the box and the mesh has its boundary).
    fn inner(&self, slot: usize, dir: u8) -> bool {
        let p = self.l.coords_of(slot);
        self.l.is_regular(p)
            || self.l.around[(p[0] & 1) as usize]
                .iter()
                .filter(|t| t.from_point & (1 << dir) != 0)
                .all(|t| self.l.has_tet(p, t))
    }

    /// Test (a): the crossings of group `gi` are inner vertices of plain MT, and with the MT
    /// edges and triangles among them they form a contractible complex (connected, Euler
    /// characteristic 1). `s` is its star.
    pub(crate) fn contractible(&self, gi: usize, s: &Star) -> bool {
        let g = &self.groups[gi];
        let mut dirs = g.dirs;
        while dirs != 0 {
            let d = dirs.trailing_zeros() as u8;
            dirs &= dirs - 1;
            if !self.inner(g.slot as usize, d) {
                return false;
            }
        }
        if !self
            .lones_of(gi)
            .iter()
            .all(|l| self.inner(l.slot as usize, l.dir))
        {
            return false;
        }
        let mut adj = [0u32; 32];
        let mut faces = 0i32;
        for i in 0..s.n {
            if s.touching >> i & 1 == 0 {
                continue;
            }
            let t = s.tris[i];
            let inside = t.map(|x| self.group_of[x as usize] == gi as u32);
            for e in 0..3 {
                let (a, b) = (e, (e + 1) % 3);
                if inside[a] && inside[b] {
                    let (ra, rb) = (self.local(gi, t[a]), self.local(gi, t[b]));
                    adj[ra] |= 1 << rb;
                    adj[rb] |= 1 << ra;
                }
            }
            faces += i32::from(inside == [true; 3]);
        }
        let edges: u32 = adj.iter().map(|m| m.count_ones()).sum::<u32>() / 2;
        let members = u32::from(g.members) | ((1u32 << self.lones_of(gi).len()) - 1) << 16;
        // Connected: grow from the lowest member along the edges.
        let mut reached = members & members.wrapping_neg();
        loop {
            let mut grown = reached;
            let mut bits = reached;
            while bits != 0 {
                grown |= adj[bits.trailing_zeros() as usize];
                bits &= bits - 1;
            }
            if grown == reached {
                break;
            }
            reached = grown;
        }
        reached == members && members.count_ones() as i32 - edges as i32 + faces == 1
    }

    /// Tests (b) and (c) of group `gi` (active) in the state `active`; `s` is its star. With
    /// `link`, the labels of its link vertices (or, when it has no triangle left, of every
    /// vertex of its star) are written there and their number returned in the `usize`.
    pub(crate) fn passes(
        &self,
        gi: usize,
        active: &[u8],
        s: &Star,
        mut link: Option<&mut [u32; 2 * MAX_TRIS]>,
    ) -> (bool, usize) {
        let me = self.leader[gi];
        let mine = |x: u32| self.group_of[x as usize] == gi as u32;
        let mut src = [0u32; MAX_TRIS];
        let mut dst = [0u32; MAX_TRIS];
        let mut m = 0;
        let mut ok = true;
        let mut listed = 0;
        for i in 0..s.n {
            if s.touching >> i & 1 == 0 {
                continue;
            }
            let t = s.tris[i];
            let q = t.map(|x| if mine(x) { me } else { self.label(x, active) });
            if q[0] == q[1] || q[1] == q[2] || q[0] == q[2] {
                continue;
            }
            // Rotate so that the group comes first: the link edge is the opposite side.
            let k = q.iter().position(|&x| x == me).unwrap_or(0);
            let (a, b) = (q[(k + 1) % 3], q[(k + 2) % 3]);
            src[m] = a;
            dst[m] = b;
            m += 1;
            if let Some(out) = link.as_deref_mut() {
                out[listed] = a;
                out[listed + 1] = b;
                listed += 2;
            }
            if ok && !self.geometry_ok(t, q, s.tets[s.src[i] as usize], active) {
                ok = false;
            }
        }
        if let Some(out) = link {
            if m == 0 {
                // No triangle left: the neighbours in plain MT stand for the star.
                for i in 0..s.n {
                    for &x in &s.tris[i] {
                        if !mine(x) && listed < out.len() {
                            out[listed] = self.label(x, active);
                            listed += 1;
                        }
                    }
                }
            }
        }
        (ok && simple_cycle(&src[..m], &dst[..m]), listed)
    }

    /// Test (c) for one triangle: `t` its MT crossings, `q` its quotient labels (in the same
    /// corner order), `tet` its source tetrahedron (the point it is taken around, and its index
    /// there).
    fn geometry_ok(&self, t: [u32; 3], q: [u32; 3], tet: (u32, u8), active: &[u8]) -> bool {
        let new = q.map(|x| self.position(x, active));
        match shape(new) {
            Shape::Flat => shape(t.map(|x| self.cpos[x as usize])) == Shape::Flat,
            Shape::Normal(n) => n.dot(self.gradient(tet.0 as usize, tet.1)) > 0.0,
        }
    }

    /// The gradient of the linear interpolant of the field on tetrahedron `tet` around the
    /// point at `slot`, up to a positive factor.
    fn gradient(&self, slot: usize, tet: u8) -> DVec3 {
        let l = self.l;
        let p = l.coords_of(slot);
        let par = (p[0] & 1) as usize;
        let tet = &l.around[par][tet as usize];
        let pos = tet.off.map(|o| {
            l.position([p[0] + o[0], p[1] + o[1], p[2] + o[2]])
                .as_dvec3()
        });
        let f = tet
            .delta
            .map(|d| f64::from(l.s.values[(slot as isize + d) as usize]));
        let (d1, d2, d3) = (pos[1] - pos[0], pos[2] - pos[0], pos[3] - pos[0]);
        // D^-1 = [d2 x d3, d3 x d1, d1 x d2] / det, det > 0 for the lattice's tetrahedra.
        d2.cross(d3) * (f[1] - f[0]) + d3.cross(d1) * (f[2] - f[0]) + d1.cross(d2) * (f[3] - f[0])
    }

    /// The group that failing group `gi` names for splitting: the failing group of lowest
    /// priority in its closed star (`failing[h] != 0`).
    fn nominate(&self, gi: usize, active: &[u8], failing: &[u8], s: &mut Star) -> usize {
        self.star(gi, s);
        let mut link = [0u32; 2 * MAX_TRIS];
        let (_, n) = self.passes(gi, active, s, Some(&mut link));
        let key = |h: usize| (self.size(h), std::cmp::Reverse(h));
        let mut best = gi;
        for &x in &link[..n] {
            let h = self.group_of[x as usize];
            if h != NONE
                && active[h as usize] != 0
                && failing[h as usize] != 0
                && key(h as usize) < key(best)
            {
                best = h as usize;
            }
        }
        best
    }

    /// Runs the test rounds until every active group passes; `active` comes in with every
    /// proposed group at 1 and leaves with the accepted ones. Test (a) does not depend on the
    /// state: it runs in the first round only, and a group failing it splits itself.
    pub(crate) fn settle(&self, active: &mut [u8], pool: &rayon::ThreadPool) -> Settled {
        let mut out = Settled::default();
        let start = std::time::Instant::now();
        let count = self.groups.len();
        // Per group: 1 while it fails (b) or (c) this round, 2 when it fails (a).
        let mut failing = vec![0u8; count];
        let mut stamp = vec![0u32; count];
        let mut dirty: Vec<u32> = (0..count as u32).collect();
        let mut round = 0u32;
        loop {
            round += 1;
            let state = &*active;
            let first = round == 1;
            let fails: Vec<(u32, u8)> = pool.install(|| {
                dirty
                    .par_iter()
                    .copied()
                    .map_init(Box::<Star>::default, |s, gi| {
                        self.star(gi as usize, s);
                        if first && !self.contractible(gi as usize, s) {
                            Some((gi, 2))
                        } else if !self.passes(gi as usize, state, s, None).0 {
                            Some((gi, 1))
                        } else {
                            None
                        }
                    })
                    .flatten()
                    .collect()
            });
            if first {
                out.t_tests_s = start.elapsed().as_secs_f64();
            }
            if fails.is_empty() {
                break;
            }
            out.rounds += 1;
            for &(g, why) in &fails {
                failing[g as usize] = why;
            }
            let state = &*active;
            let failing_ref = &failing;
            let mut split: Vec<u32> = pool.install(|| {
                fails
                    .par_iter()
                    .map_init(Box::<Star>::default, |s, &(gi, why)| {
                        if why == 2 {
                            gi
                        } else {
                            self.nominate(gi as usize, state, failing_ref, s) as u32
                        }
                    })
                    .collect()
            });
            split.sort_unstable();
            split.dedup();
            for &(g, _) in &fails {
                failing[g as usize] = 0;
            }
            for &h in &split {
                active[h as usize] = 0;
            }
            out.split += split.len();
            // Retest the groups whose star holds a crossing of a split group.
            dirty.clear();
            let mut s = Star::default();
            for &h in &split {
                self.star(h as usize, &mut s);
                for t in &s.tris[..s.n] {
                    for &x in t {
                        let g = self.group_of[x as usize];
                        if g != NONE && active[g as usize] != 0 && stamp[g as usize] != round {
                            stamp[g as usize] = round;
                            dirty.push(g);
                        }
                    }
                }
            }
            dirty.sort_unstable();
        }
        if out.rounds > 0 {
            out.t_repair_s = start.elapsed().as_secs_f64() - out.t_tests_s;
        }
        out
    }
}

/// Whether the directed edges `src[i] -> dst[i]` form one simple cycle of at least 3 vertices.
fn simple_cycle(src: &[u32], dst: &[u32]) -> bool {
    let m = src.len();
    if m < 3 {
        return false;
    }
    // Each vertex starts one edge and ends one.
    let mut next = [0u8; MAX_TRIS];
    for i in 0..m {
        let mut found = None;
        for j in 0..m {
            if j != i && (src[j] == src[i] || dst[j] == dst[i]) {
                return false;
            }
            if dst[j] == src[i] {
                found = Some(j);
            }
        }
        match found {
            // Edge `j` ends where edge `i` starts: `i` follows `j`.
            Some(j) => next[j] = i as u8,
            None => return false,
        }
    }
    // One cycle through all edges.
    let mut at = 0usize;
    for step in 1..=m {
        at = next[at] as usize;
        if at == 0 {
            return step == m;
        }
    }
    false
}

/// The shape of a triangle, measured exactly as `rmt_mesh::quality` does (f64, zero area when
/// `area <= 1e-12 * longest_edge^2`).
#[derive(Clone, Copy, Debug, PartialEq)]
enum Shape {
    Flat,
    /// Not flat: its right-hand normal (twice the area).
    Normal(DVec3),
}

fn shape(p: [[f32; 3]; 3]) -> Shape {
    let p = p.map(|x| DVec3::from(x.map(f64::from)));
    let e = [p[2] - p[1], p[0] - p[2], p[1] - p[0]];
    let n = e[1].cross(e[2]);
    let l_max = e[0].length().max(e[1].length()).max(e[2].length());
    if 0.5 * n.length() <= ZERO_AREA_REL_TOL * l_max * l_max {
        Shape::Flat
    } else {
        Shape::Normal(n)
    }
}

/// The zero-area tolerance of `rmt_mesh::quality`.
const ZERO_AREA_REL_TOL: f64 = 1e-12;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn simple_cycles_are_told_apart_from_paths_figure_eights_and_doubles() {
        assert!(simple_cycle(&[1, 2, 3], &[2, 3, 1]));
        assert!(simple_cycle(&[5, 1, 9, 2], &[9, 5, 2, 1]));
        // Too short, open, two cycles, a vertex twice.
        assert!(!simple_cycle(&[1, 2], &[2, 1]));
        assert!(!simple_cycle(&[1, 2, 3], &[2, 3, 4]));
        assert!(!simple_cycle(&[1, 2, 3, 4, 5, 6], &[2, 3, 1, 5, 6, 4]));
        assert!(!simple_cycle(&[1, 2, 3, 1], &[2, 3, 1, 4]));
    }

    #[test]
    fn flat_is_measured_like_the_quality_report() {
        assert_eq!(
            shape([[0.0; 3], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0]]),
            Shape::Flat
        );
        assert_eq!(shape([[0.0; 3], [0.0; 3], [1.0, 0.0, 0.0]]), Shape::Flat);
        match shape([[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]) {
            Shape::Normal(n) => assert!(n.z > 0.0),
            Shape::Flat => panic!("a right triangle is not flat"),
        }
    }
}
