//! The quotient test and the repair rounds of integrated clustering.
//!
//! The proposals ([`crate::cluster`]) are a partition of the crossings into groups. Picture every
//! kept group contracted at once into one vertex (at the mean of its crossings): the
//! *quotient* of plain MT. A group's star in the quotient is the plain MT triangles touching its
//! crossings (read from the triangle list and every crossing's triangles, [`Fixed`]), and the
//! labels there depend only on the groups of those triangles' crossings: 2-ring data. A group is
//! kept when
//!
//! - (a) the sub-complex it collapses (its crossings, the MT edges and triangles among them) is
//!   contractible: connected with V - E + F = 1 (it depends on the members only);
//! - (b) its link in the quotient is one simple cycle of at least three vertices: every link
//!   vertex starts one link edge and ends one, so every edge at the new vertex has exactly two
//!   triangles, oppositely oriented, and no two triangles coincide;
//! - (c) no triangle of its star flips against the gradient of the tetrahedron it comes from,
//!   and none has zero area unless its source MT triangle already had.
//!
//! Every member is an inner vertex of plain MT (the proposals leave the crossings on the box
//! faces alone): with (a) and (b) the map from plain MT to the quotient has contractible fibres
//! and keeps the surface manifold, so it keeps its topology; the property tests in
//! `tests/random_fields.rs` check that on random and adversarial fields.
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
//! parallel, and the same result for any thread count, [`settle`]). Every failing group names
//! the group to split in its closed star (itself and the groups of its link): the failing one of
//! lowest priority, smaller first, then the later owner. The named groups become singletons, and
//! only the groups whose star holds a crossing of a changed group are tested again. Groups only
//! split, and all singletons is plain MT, so the rounds end, and they end with every group
//! passing. (This follows the Python study in `shared/research/order-free-rmt`.)
//!
//! **Additions.** Once the islands settle, more is proposed in steps, each a function of the
//! state the previous step left around each crossing (so still order-free), each settled by its
//! own rounds in which a failing addition is undone before anything else splits
//! ([`Phase::Additions`]):
//!
//! 1. every split island of three or more takes back its first variant (the island without one
//!    crossing, then pairs of its crossings) that passes in the current state ([`revive`]);
//! 2. crossings left alone join the nearest kept group they share a triangle with, at most
//!    [`MAX_LONES`] per group, in a few passes; a group that fails with them gives them back,
//!    and a crossing given back tries another group in the next pass ([`give_lones`]);
//! 3. slivers (triangles of the quotient with an aspect ratio above [`SLIVER_AR`]): a crossing
//!    left alone at one joins the group across the sliver's shortest edge, or pairs with the
//!    crossing there into a new group ([`sliver_proposals`]).
//!
//! Each step only adds what then passes every test, so the result stays closed, manifold and of
//! the same topology as plain MT.

use glam::DVec3;
use rayon::prelude::*;

use crate::cluster::Candidate;
use crate::mt::Layout;

/// "No group" in the crossing-to-group table.
pub(crate) const NONE: u32 = u32::MAX;

/// At most this many lone crossings join one group.
pub(crate) const MAX_LONES: usize = 6;

/// A crossing given to the group of a neighbouring point (a lone crossing): its id.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord)]
pub(crate) struct Lone {
    pub(crate) id: u32,
}

/// What does not change while groups are tested: the lattice, the crossings and the proposals.
pub(crate) struct Fixed<'a> {
    pub(crate) l: &'a Layout<'a>,
    /// Crossing positions (plain MT vertices).
    pub(crate) cpos: &'a [[f32; 3]],
    /// The proposed groups' cores (a point's island).
    pub(crate) groups: &'a [Candidate],
    /// Plain MT's triangles (three crossing ids each), the gradient of each one's source
    /// tetrahedron (up to a positive factor), and every crossing's triangles
    /// (`inc[inc_start[x]..inc_start[x + 1]]`).
    pub(crate) tris: &'a [u32],
    pub(crate) grad: &'a [[f32; 3]],
    pub(crate) inc_start: &'a [u32],
    pub(crate) inc: &'a [u32],
    /// The tile rule's key of every crossing (chunked extraction), or `None`: a group holds
    /// crossings of one key only, never [`crate::tiles::NO_TILE`].
    pub(crate) keys: Option<&'a [u64]>,
}

/// The state of the groups, changed between rounds: which are kept, every crossing's group,
/// and each group's lone crossings, label and vertex position.
#[derive(Clone, Debug, Default)]
pub(crate) struct Groups {
    /// Per group: 1 while it is kept.
    pub(crate) active: Vec<u8>,
    /// Group of each crossing, or [`NONE`].
    pub(crate) group_of: Vec<u32>,
    /// Each group's lowest crossing id: its label in the quotient.
    pub(crate) leader: Vec<u32>,
    /// Position of each group's vertex: the mean of its crossings.
    pub(crate) centroid: Vec<[f32; 3]>,
    /// The lone crossings of group g: `lone[lone_start[g]..][..lone_len[g]]`, by id.
    pub(crate) lone: Vec<Lone>,
    pub(crate) lone_start: Vec<u32>,
    pub(crate) lone_len: Vec<u8>,
    /// How many of those the group had before the current phase: a group that fails with
    /// lones given in this phase sheds them, back to this many.
    pub(crate) base_len: Vec<u8>,
    /// Per crossing: the last group that gave it back ([`NONE`] if none); it is not given to
    /// that group again.
    pub(crate) refused: Vec<u32>,
    /// Per crossing, its vertex in the quotient of the current state: the label (the leader of
    /// its kept group, or itself) and that vertex's position ([`Groups::relabel`]).
    vlabel: Vec<u32>,
    vpos: Vec<[f32; 3]>,
}

impl Groups {
    /// Bytes held.
    pub(crate) fn bytes(&self) -> usize {
        self.active.len() * 3
            + self.group_of.len() * 4
            + self.leader.len() * 4
            + self.centroid.len() * 12
            + self.lone.len() * std::mem::size_of::<Lone>()
            + self.lone_start.len() * 4
            + self.refused.len() * 4
            + self.vlabel.len() * 16
    }

    /// Computes every crossing's quotient vertex ([`Groups::vlabel`], [`Groups::vpos`]) from
    /// the groups; after that, every step that changes a group updates its members'
    /// ([`Groups::set_vertices`]).
    pub(crate) fn relabel(&mut self, f: &Fixed, pool: &rayon::ThreadPool) {
        let n = f.cpos.len();
        self.vlabel.resize(n, 0);
        self.vpos.resize(n, [0.0; 3]);
        let (group_of, active, leader, centroid) =
            (&self.group_of, &self.active, &self.leader, &self.centroid);
        pool.install(|| {
            self.vlabel
                .par_iter_mut()
                .zip(self.vpos.par_iter_mut())
                .enumerate()
                .with_min_len(1 << 12)
                .for_each(|(x, (l, p))| {
                    let h = group_of[x];
                    if h != NONE && active[h as usize] != 0 {
                        *l = leader[h as usize];
                        *p = centroid[h as usize];
                    } else {
                        *l = x as u32;
                        *p = f.cpos[x];
                    }
                })
        });
    }

    /// Sets the quotient vertex of every member of group `gi` (its island and lone crossings):
    /// the group's vertex when it is kept, else each crossing's own.
    pub(crate) fn set_vertices(&mut self, f: &Fixed, gi: usize) {
        let start = self.lone_start[gi] as usize;
        let lones = &self.lone[start..start + self.lone_len[gi] as usize];
        let kept = self.active[gi] != 0;
        for x in f.groups[gi].ids().chain(lones.iter().map(|l| l.id)) {
            let x = x as usize;
            if kept {
                self.vlabel[x] = self.leader[gi];
                self.vpos[x] = self.centroid[gi];
            } else {
                self.vlabel[x] = x as u32;
                self.vpos[x] = f.cpos[x];
            }
        }
    }

    /// Room for `count` groups: the new ones not kept, without lone crossings.
    pub(crate) fn extend_to(&mut self, count: usize) {
        let end = self.lone.len() as u32;
        self.active.resize(count, 0);
        self.leader.resize(count, 0);
        self.centroid.resize(count, [0.0; 3]);
        self.lone_start.resize(count + 1, end);
        self.lone_len.resize(count, 0);
        self.base_len.resize(count, 0);
    }

    /// Keeps the new groups from `born` on, one per pair `(x, y)`: the island `{x}` (the
    /// candidate already made) with `y` as its lone crossing.
    pub(crate) fn add_pairs(&mut self, f: &Fixed, born: usize, pairs: &[(u32, u32)]) {
        self.extend_to(f.groups.len());
        for (k, &(x, y)) in pairs.iter().enumerate() {
            let gi = born + k;
            self.active[gi] = 1;
            self.lone_start[gi] = self.lone.len() as u32;
            self.lone.push(Lone { id: y });
            self.lone_len[gi] = 1;
            self.base_len[gi] = 1;
            self.group_of[x as usize] = gi as u32;
            self.group_of[y as usize] = gi as u32;
            self.refresh(f, gi);
        }
        self.lone_start[f.groups.len()] = self.lone.len() as u32;
        for gi in born..born + pairs.len() {
            self.set_vertices(f, gi);
        }
    }

    /// Recomputes the label and the vertex position of group `gi` from its members.
    pub(crate) fn refresh(&mut self, f: &Fixed, gi: usize) {
        let c = &f.groups[gi];
        let start = self.lone_start[gi] as usize;
        let lones = &self.lone[start..start + self.lone_len[gi] as usize];
        let mut sum = glam::Vec3::ZERO;
        for id in c.ids().chain(lones.iter().map(|l| l.id)) {
            sum += glam::Vec3::from(f.cpos[id as usize]);
        }
        self.centroid[gi] = (sum / (c.size() as usize + lones.len()) as f32).to_array();
        self.leader[gi] = lones.iter().map(|l| l.id).fold(c.leader(), u32::min);
    }
}

/// The quotient test's view of one state: [`Fixed`] plus [`Groups`].
pub(crate) struct Quotient<'a> {
    pub(crate) l: &'a Layout<'a>,
    pub(crate) cpos: &'a [[f32; 3]],
    pub(crate) groups: &'a [Candidate],
    tris: &'a [u32],
    grad: &'a [[f32; 3]],
    inc_start: &'a [u32],
    inc: &'a [u32],
    keys: Option<&'a [u64]>,
    pub(crate) g: &'a Groups,
}

impl<'a> Quotient<'a> {
    /// The view of `g` over `f`.
    pub(crate) fn new(f: &Fixed<'a>, g: &'a Groups) -> Self {
        Self {
            l: f.l,
            cpos: f.cpos,
            groups: f.groups,
            tris: f.tris,
            grad: f.grad,
            inc_start: f.inc_start,
            inc: f.inc,
            keys: f.keys,
            g,
        }
    }
}

/// The plain MT triangles touching a group (each once), and working memory of its tests; one
/// per thread, reused.
#[derive(Default)]
pub(crate) struct Star {
    /// Triangle ids.
    tris: Vec<u32>,
    /// Per triangle: bit `i` set when its corner `i` is a member.
    mask: Vec<u8>,
    /// Link edges `src[i] -> dst[i]` of the test of (b), and the cycle walk's successors.
    src: Vec<u32>,
    dst: Vec<u32>,
    next: Vec<u32>,
    /// Labels of the link vertices (see [`Quotient::passes`]).
    link: Vec<u32>,
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
    fn label(&self, x: u32) -> u32 {
        self.g.vlabel[x as usize]
    }

    /// Position of quotient vertex `label`.
    #[inline(always)]
    fn position(&self, label: u32) -> [f32; 3] {
        self.g.vpos[label as usize]
    }

    /// The lone crossings of group `gi`.
    #[inline(always)]
    fn lones_of(&self, gi: usize) -> &[Lone] {
        let start = self.g.lone_start[gi] as usize;
        &self.g.lone[start..start + self.g.lone_len[gi] as usize]
    }

    /// Whether crossing `x` is a member of group `gi` (its island, or one of its lone
    /// crossings). For a kept group this is `group_of[x] == gi`; a group not kept (a variant
    /// being tried) answers from its own members.
    #[inline(always)]
    fn is_member(&self, gi: usize, x: u32) -> bool {
        self.groups[gi].has(x) || self.lones_of(gi).iter().any(|l| l.id == x)
    }

    /// Whether group `gi` passes tests (a), (b) and (c) in the current state, as if it were
    /// kept and every other group as it is.
    pub(crate) fn passes_all(&self, gi: usize, s: &mut Star) -> bool {
        self.star(gi, s);
        self.contractible(gi, s) && self.passes(gi, s, false)
    }

    /// Number of crossings in group `gi`.
    pub(crate) fn size(&self, gi: usize) -> u32 {
        self.groups[gi].size() + self.lones_of(gi).len() as u32
    }

    /// The triangles of crossing `x` in plain MT.
    #[inline(always)]
    fn tris_of(&self, x: u32) -> &[u32] {
        &self.inc[self.inc_start[x as usize] as usize..self.inc_start[x as usize + 1] as usize]
    }

    /// Triangle `t`'s crossings.
    #[inline(always)]
    fn tri(&self, t: u32) -> [u32; 3] {
        let i = 3 * t as usize;
        [self.tris[i], self.tris[i + 1], self.tris[i + 2]]
    }

    /// Fills `s` with the star of group `gi`: the plain MT triangles with a member, each once
    /// (listed from its first corner that is a member).
    pub(crate) fn star(&self, gi: usize, s: &mut Star) {
        s.tris.clear();
        s.mask.clear();
        let g = &self.groups[gi];
        let lones = self.lones_of(gi);
        let member = |y: u32| g.has(y) || lones.iter().any(|l| l.id == y);
        for x in g.ids().chain(lones.iter().map(|l| l.id)) {
            for &t in self.tris_of(x) {
                let c = self.tri(t);
                let mask = (0..3).fold(0u8, |m, i| m | u8::from(member(c[i])) << i);
                // Listed from its first member corner.
                if c[mask.trailing_zeros() as usize] == x {
                    s.tris.push(t);
                    s.mask.push(mask);
                }
            }
        }
    }

    /// The index of member `x` of group `gi` in its test (a) bit sets: the island rank, or 16 +
    /// its place among the lone crossings.
    #[inline(always)]
    fn local(g: &Candidate, lones: &[Lone], x: u32) -> usize {
        let r = x.wrapping_sub(g.first);
        if r < 16 && (g.members >> r) & 1 != 0 {
            r as usize
        } else {
            16 + lones.iter().position(|l| l.id == x).unwrap_or(0)
        }
    }

    /// Whether the crossing on the edge from the point at `slot` to its neighbour `dir` is an
    /// inner vertex of plain MT: the tetrahedra around the edge close up (they do not on the
    /// box faces, where the surface leaves the box and the mesh has its boundary).
    fn inner(&self, slot: usize, dir: u8) -> bool {
        let p = self.l.coords_of(slot);
        self.l.inner_dirs(p) & (1 << dir) != 0
    }

    /// Test (a): the crossings of group `gi`, with the MT edges and triangles among them, form a
    /// contractible complex (connected, Euler characteristic 1). `s` is its star.
    pub(crate) fn contractible(&self, gi: usize, s: &Star) -> bool {
        // Every member is an inner vertex: the proposals take no crossing on the mesh boundary.
        let g = &self.groups[gi];
        let lones = self.lones_of(gi);
        let mut adj = [0u32; 32];
        let mut faces = 0i32;
        for (&ti, &mask) in s.tris.iter().zip(&s.mask) {
            let t = self.tri(ti);
            let inside = [0, 1, 2].map(|i| mask >> i & 1 != 0);
            for e in 0..3 {
                let (a, b) = (e, (e + 1) % 3);
                if inside[a] && inside[b] {
                    let (ra, rb) = (Self::local(g, lones, t[a]), Self::local(g, lones, t[b]));
                    adj[ra] |= 1 << rb;
                    adj[rb] |= 1 << ra;
                }
            }
            faces += i32::from(inside == [true; 3]);
        }
        let edges: u32 = adj.iter().map(|m| m.count_ones()).sum::<u32>() / 2;
        let members = u32::from(g.members) | ((1u32 << lones.len()) - 1) << 16;
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

    /// Tests (b) and (c) of group `gi` in the current state; `s` is its star. With `link`, the
    /// labels of its link vertices (or, when it has no triangle left, of every vertex of its
    /// star) are left in `s.link`.
    pub(crate) fn passes(&self, gi: usize, s: &mut Star, link: bool) -> bool {
        let me = self.g.leader[gi];
        let mine = |x: u32| self.is_member(gi, x);
        s.src.clear();
        s.dst.clear();
        s.link.clear();
        let mut ok = true;
        for (&ti, &mask) in s.tris.iter().zip(&s.mask) {
            if mask.count_ones() >= 2 {
                // Two corners in the group: collapsed.
                continue;
            }
            let t = self.tri(ti);
            let q = [0, 1, 2].map(|i| {
                if mask >> i & 1 != 0 {
                    me
                } else {
                    self.label(t[i])
                }
            });
            if q[0] == q[1] || q[1] == q[2] || q[0] == q[2] {
                continue;
            }
            // Rotate so that the group comes first: the link edge is the opposite side.
            let k = q.iter().position(|&x| x == me).unwrap_or(0);
            let (a, b) = (q[(k + 1) % 3], q[(k + 2) % 3]);
            s.src.push(a);
            s.dst.push(b);
            if ok && !self.geometry_ok(gi, t, q, ti) {
                ok = false;
                if !link {
                    return false;
                }
            }
        }
        if link {
            s.link.extend_from_slice(&s.src);
            s.link.extend_from_slice(&s.dst);
            if s.src.is_empty() {
                // No triangle left: the neighbours in plain MT stand for the star.
                for &ti in &s.tris {
                    for x in self.tri(ti) {
                        if !mine(x) {
                            s.link.push(self.label(x));
                        }
                    }
                }
            }
        }
        ok && simple_cycle(&s.src, &s.dst, &mut s.next)
    }

    /// Test (c) for one triangle: `t` its MT crossings, `q` its quotient labels (in the same
    /// corner order), `tri` its index in plain MT.
    fn geometry_ok(&self, gi: usize, t: [u32; 3], q: [u32; 3], tri: u32) -> bool {
        let me = self.g.leader[gi];
        let new = q.map(|x| {
            if x == me {
                self.g.centroid[gi]
            } else {
                self.position(x)
            }
        });
        match shape(new) {
            Shape::Flat => shape(t.map(|x| self.cpos[x as usize])) == Shape::Flat,
            Shape::Normal(n) => n.dot(DVec3::from(self.grad[tri as usize].map(f64::from))) > 0.0,
        }
    }

    /// The group that failing group `gi` names for splitting: the failing group of lowest
    /// priority in its closed star (`failing[h] != 0`).
    fn nominate(&self, gi: usize, failing: &[u8], s: &mut Star) -> usize {
        let mut best = gi;
        let key = |h: usize| (self.size(h), std::cmp::Reverse(h));
        self.closed_star(gi, s, |h| {
            if failing[h] != 0 && key(h) < key(best) {
                best = h;
            }
        });
        best
    }

    /// Calls `visit` with every active group of the closed star of group `gi` (the groups of its
    /// link vertices, or of every vertex of its star when no triangle is left), `gi` excluded,
    /// possibly more than once.
    fn closed_star(&self, gi: usize, s: &mut Star, mut visit: impl FnMut(usize)) {
        self.star(gi, s);
        self.passes(gi, s, true);
        for &x in &s.link {
            let h = self.g.group_of[x as usize];
            if h != NONE && h as usize != gi && self.g.active[h as usize] != 0 {
                visit(h as usize);
            }
        }
    }

    /// Whether crossing `x` may be grouped at all (the tile rule).
    #[inline]
    fn joinable(&self, x: u32) -> bool {
        self.keys
            .is_none_or(|k| k[x as usize] != crate::tiles::NO_TILE)
    }

    /// Whether crossing `x` (joinable) may join group `h` (the tile rule).
    #[inline]
    fn same_tile(&self, x: u32, h: u32) -> bool {
        self.keys
            .is_none_or(|k| k[x as usize] == k[self.groups[h as usize].leader() as usize])
    }

    /// Whether crossing `x` is in no kept group.
    #[inline]
    fn alone(&self, x: u32) -> bool {
        let h = self.g.group_of[x as usize];
        h == NONE || self.g.active[h as usize] == 0
    }

    /// Whether group `gi` holds lone crossings given in the current phase.
    #[inline]
    fn has_new_lones(&self, gi: usize) -> bool {
        self.g.lone_len[gi] > self.g.base_len[gi]
    }

    /// The active groups with a crossing in a triangle of group `gi`'s star (those whose test
    /// may change when `gi` changes), appended to `out`.
    fn neighbours(&self, gi: usize, s: &mut Star, out: &mut Vec<u32>) {
        self.star(gi, s);
        for &t in &s.tris {
            for x in self.tri(t) {
                let h = self.g.group_of[x as usize];
                if h != NONE && self.g.active[h as usize] != 0 {
                    out.push(h);
                }
            }
        }
    }

    /// The active group that lone crossing `x` joins: of the groups with a crossing in a
    /// triangle of `x`, the one whose vertex is nearest (then the lowest index), among those
    /// `allowed` (not the one that gave it back; the tile rule).
    pub(crate) fn nearest_group(&self, x: u32, allowed: impl Fn(u32) -> bool) -> Option<u32> {
        let px = glam::Vec3::from(self.cpos[x as usize]);
        let mut best: Option<(f32, u32)> = None;
        for &t in self.tris_of(x) {
            for y in self.tri(t) {
                let h = self.g.group_of[y as usize];
                if h == NONE || self.g.active[h as usize] == 0 || !allowed(h) {
                    continue;
                }
                let dist = px.distance_squared(glam::Vec3::from(self.g.centroid[h as usize]));
                if best.is_none_or(|(bd, bh)| (dist, h) < (bd, bh)) {
                    best = Some((dist, h));
                }
            }
        }
        best.map(|(_, h)| h)
    }
}

/// Which proposals a run of rounds settles, and so how it repairs a failing group.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Phase {
    /// The islands (with the lone crossings given at proposal time): a failing group names the
    /// failing group of lowest priority in its closed star, which splits into singletons.
    Islands,
    /// Additions to the kept groups: lone crossings given to them, and new groups (from index
    /// `born` on). A failing group that is new splits, one that took lone crossings sheds them;
    /// else the new groups of its closed star split and those that took lone crossings shed
    /// them; else it names a group to split, as in [`Phase::Islands`].
    Additions {
        /// The first new group.
        born: u32,
    },
}

/// What a failing group asks for.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
enum Repair {
    /// The group becomes singletons.
    Split(u32),
    /// The group gives back the lone crossings of this phase.
    Shed(u32),
}

/// Runs test rounds over the groups `dirty` (and those their repairs touch) until every active
/// group passes. Test (a) depends on a group's members only: it runs in the first round, for
/// every group in [`Phase::Islands`] and for the new groups and those holding new lones in
/// [`Phase::Additions`].
/// Each round reads only the state the previous round left (Jacobi rounds), so the result is
/// the same for any thread count.
pub(crate) fn settle(
    f: &Fixed,
    g: &mut Groups,
    mut dirty: Vec<u32>,
    phase: Phase,
    pool: &rayon::ThreadPool,
) -> Settled {
    let mut out = Settled::default();
    let start = std::time::Instant::now();
    // Per group: 1 while it fails (b) or (c) this round, 2 when it fails (a).
    let mut failing = vec![0u8; f.groups.len()];
    let mut round = 0u32;
    loop {
        round += 1;
        let first = round == 1;
        let q = Quotient::new(f, g);
        let fails: Vec<(u32, u8)> = pool.install(|| {
            dirty
                .par_iter()
                .copied()
                .map_init(Box::<Star>::default, |s, gi| {
                    let i = gi as usize;
                    q.star(i, s);
                    let test_a = first
                        && match phase {
                            Phase::Islands => true,
                            Phase::Additions { born } => gi >= born || q.has_new_lones(i),
                        };
                    if test_a && !q.contractible(i, s) {
                        Some((gi, 2))
                    } else if !q.passes(i, s, false) {
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
        for &(gi, why) in &fails {
            failing[gi as usize] = why;
        }
        let failing_ref = &failing;
        // The repairs, and the groups each one touches (to test again).
        let repairs: Vec<(Vec<Repair>, Vec<u32>)> = pool.install(|| {
            fails
                .par_iter()
                .map_init(Box::<Star>::default, |s, &(gi, why)| {
                    let i = gi as usize;
                    let mut asks = Vec::new();
                    match phase {
                        Phase::Islands if why == 2 => asks.push(Repair::Split(gi)),
                        Phase::Islands => {}
                        Phase::Additions { born } => {
                            let undo = |h: u32| {
                                if h >= born {
                                    Repair::Split(h)
                                } else {
                                    Repair::Shed(h)
                                }
                            };
                            let new = |h: usize| h >= born as usize || q.has_new_lones(h);
                            if why == 2 || new(i) {
                                asks.push(undo(gi));
                            } else {
                                q.closed_star(i, s, |h| {
                                    if new(h) {
                                        asks.push(undo(h as u32));
                                    }
                                });
                            }
                        }
                    }
                    if asks.is_empty() {
                        asks.push(Repair::Split(q.nominate(i, failing_ref, s) as u32));
                    }
                    let mut touched = Vec::new();
                    for r in &asks {
                        let (Repair::Split(h) | Repair::Shed(h)) = *r;
                        touched.push(h);
                        q.neighbours(h as usize, s, &mut touched);
                    }
                    (asks, touched)
                })
                .collect()
        });
        for &(gi, _) in &fails {
            failing[gi as usize] = 0;
        }
        let mut asks: Vec<Repair> = repairs.iter().flat_map(|r| r.0.iter().copied()).collect();
        asks.sort_unstable();
        asks.dedup();
        for r in &asks {
            match *r {
                Repair::Split(h) => {
                    if g.active[h as usize] != 0 {
                        g.active[h as usize] = 0;
                        g.set_vertices(f, h as usize);
                        out.split += 1;
                    }
                }
                Repair::Shed(h) => shed(f, g, h as usize),
            }
        }
        dirty.clear();
        dirty.extend(
            repairs
                .iter()
                .flat_map(|r| r.1.iter().copied())
                .filter(|&h| g.active[h as usize] != 0),
        );
        dirty.sort_unstable();
        dirty.dedup();
    }
    if out.rounds > 0 {
        out.t_repair_s = start.elapsed().as_secs_f64() - out.t_tests_s;
    }
    out
}

/// Group `gi` gives back the lone crossings of the current phase (they become singletons).
fn shed(f: &Fixed, g: &mut Groups, gi: usize) {
    let start = g.lone_start[gi] as usize;
    let (base, len) = (g.base_len[gi] as usize, g.lone_len[gi] as usize);
    for l in &g.lone[start + base..start + len] {
        let x = l.id as usize;
        g.group_of[x] = NONE;
        g.refused[x] = gi as u32;
        g.vlabel[x] = l.id;
        g.vpos[x] = f.cpos[x];
    }
    g.lone_len[gi] = base as u8;
    g.refresh(f, gi);
    if g.active[gi] != 0 {
        g.set_vertices(f, gi);
    }
}

/// The groups that may replace a split island, in the order they are tried: its island without
/// one crossing, for each crossing in bit order, when that leaves a connected part; then (for
/// islands of four or more) every pair of its crossings joined by a mesh edge, in bit order
/// (lattice adjacency joins the crossings of one point through mesh edges, see
/// [`crate::cluster`]).
pub(crate) fn variants(c: &Candidate, t: &crate::lattice::LatticeTables, out: &mut Vec<Candidate>) {
    if c.size() < 3 {
        return;
    }
    // Bit `d` of `dirs` is bit `rank(d)` of `members`: the k-th set bits correspond.
    let bits: Vec<(u16, u16)> = {
        let (mut dirs, mut members) = (c.dirs, c.members);
        let mut v = Vec::with_capacity(14);
        while dirs != 0 {
            v.push((dirs & dirs.wrapping_neg(), members & members.wrapping_neg()));
            dirs &= dirs - 1;
            members &= members - 1;
        }
        v
    };
    let mut push = |dirs: u16, members: u16| {
        out.push(Candidate {
            first: c.first,
            members,
            dirs,
            slot: c.slot,
        })
    };
    for &(d, m) in &bits {
        if t.is_connected(c.dirs & !d) {
            push(c.dirs & !d, c.members & !m);
        }
    }
    if bits.len() >= 4 {
        for (i, &(d1, m1)) in bits.iter().enumerate() {
            for &(d2, m2) in &bits[i + 1..] {
                if t.is_connected(d1 | d2) {
                    push(d1 | d2, m1 | m2);
                }
            }
        }
    }
}

/// Each split island `k` (its variants at `variant_of[k]..variant_of[k + 1]` in the candidates,
/// not kept) takes its first variant that passes every test in the current
/// state; all of them at once (each decided from the state before any is taken). Returns the
/// groups to test again: the taken variants and the groups around them.
pub(crate) fn revive(
    f: &Fixed,
    g: &mut Groups,
    variant_of: &[u32],
    pool: &rayon::ThreadPool,
) -> Vec<u32> {
    if let (Some(&first), Some(&end)) = (variant_of.first(), variant_of.last()) {
        for v in first..end {
            g.refresh(f, v as usize);
        }
    }
    let q = Quotient::new(f, g);
    let taken: Vec<u32> = pool.install(|| {
        (0..variant_of.len().saturating_sub(1))
            .into_par_iter()
            .map_init(Box::<Star>::default, |s, k| {
                (variant_of[k]..variant_of[k + 1]).find(|&v| q.passes_all(v as usize, s))
            })
            .flatten()
            .collect()
    });
    for &v in &taken {
        let vi = v as usize;
        g.active[vi] = 1;
        for id in f.groups[vi].ids() {
            g.group_of[id as usize] = v;
        }
        g.refresh(f, vi);
        g.set_vertices(f, vi);
    }
    let q = Quotient::new(f, g);
    let mut dirty: Vec<u32> = pool.install(|| {
        taken
            .par_iter()
            .map_init(Box::<Star>::default, |s, &v| {
                let mut out = vec![v];
                q.neighbours(v as usize, s, &mut out);
                out
            })
            .flatten()
            .collect()
    });
    dirty.sort_unstable();
    dirty.dedup();
    dirty
}

/// The groups `range` and the active groups around them (to test).
pub(crate) fn around(
    f: &Fixed,
    g: &Groups,
    range: std::ops::Range<usize>,
    pool: &rayon::ThreadPool,
) -> Vec<u32> {
    let q = Quotient::new(f, g);
    pool.install(|| {
        range
            .into_par_iter()
            .map_init(Box::<Star>::default, |s, gi| {
                let mut out = vec![gi as u32];
                q.neighbours(gi, s, &mut out);
                out
            })
            .flatten()
            .collect()
    })
}

/// A triangle is a sliver when its aspect ratio (circumradius over twice the inradius, 1 for an
/// equilateral triangle) exceeds this.
pub(crate) const SLIVER_AR: f32 = 4.0;

/// The aspect ratio of triangle `a b c` (as [`SLIVER_AR`] measures it): infinite when flat.
fn aspect_ratio(a: glam::Vec3, b: glam::Vec3, c: glam::Vec3) -> f32 {
    let (la, lb, lc) = ((b - c).length(), (c - a).length(), (a - b).length());
    let double_area = (b - a).cross(c - a).length();
    if double_area <= 0.0 {
        return f32::INFINITY;
    }
    let ar = la * lb * lc * (la + lb + lc) / (4.0 * double_area * double_area);
    if ar.is_finite() {
        ar
    } else {
        f32::INFINITY
    }
}

/// What the slivers left after the lone passes propose: lone crossings for groups, and pairs of
/// crossings to become new groups.
#[derive(Debug, Default)]
pub(crate) struct SliverProposals {
    /// (group, crossing).
    pub(crate) lones: Vec<(u32, Lone)>,
    /// (lower crossing, higher crossing).
    pub(crate) pairs: Vec<(u32, u32)>,
}

/// Every inner crossing left alone that is a corner of a sliver of the quotient (a triangle
/// whose aspect ratio exceeds [`SLIVER_AR`]) whose shortest edge it shares, picks the other
/// end of the shortest such edge (then the lower label): a kept group takes it as a lone
/// crossing; a crossing left alone that picked it back forms a pair with it. A function of the
/// current state around each crossing, so order-free. The tile rule keeps groups and pairs
/// inside one tile.
pub(crate) fn sliver_proposals(
    f: &Fixed,
    g: &Groups,
    edge_of: &[(u32, u8)],
    pool: &rayon::ThreadPool,
) -> SliverProposals {
    let q = Quotient::new(f, g);
    let pick = |x: u32| -> u32 {
        let (slot, dir) = edge_of[x as usize];
        if !q.alone(x) || !q.joinable(x) || !q.inner(slot as usize, dir) {
            return NONE;
        }
        let mut best: Option<(f32, u32)> = None;
        for &t in q.tris_of(x) {
            let c = q.tri(t).map(|y| q.label(y));
            if c[0] == c[1] || c[1] == c[2] || c[0] == c[2] {
                continue;
            }
            let p = c.map(|y| glam::Vec3::from(q.position(y)));
            if aspect_ratio(p[0], p[1], p[2]) <= SLIVER_AR {
                continue;
            }
            let edges = [(0, 1), (1, 2), (2, 0)].map(|(a, b)| (p[a].distance_squared(p[b]), a, b));
            let Some(&(len, a, b)) = edges.iter().min_by(|e, o| {
                e.0.total_cmp(&o.0)
                    .then((c[e.1], c[e.2]).cmp(&(c[o.1], c[o.2])))
            }) else {
                continue;
            };
            let other = if c[a] == x {
                c[b]
            } else if c[b] == x {
                c[a]
            } else {
                continue;
            };
            if best.is_none_or(|(bl, bu)| (len, other) < (bl, bu)) {
                best = Some((len, other));
            }
        }
        best.map_or(NONE, |(_, u)| u)
    };
    let choice: Vec<u32> = pool.install(|| {
        (0..edge_of.len() as u32)
            .into_par_iter()
            .map(pick)
            .collect()
    });
    let mut out = SliverProposals::default();
    for (x, &u) in choice.iter().enumerate() {
        let x = x as u32;
        if u == NONE {
            continue;
        }
        let h = g.group_of[u as usize];
        if h != NONE && g.active[h as usize] != 0 {
            if g.refused[x as usize] != h && q.same_tile(x, h) {
                out.lones.push((h, Lone { id: x }));
            }
        } else if x < u
            && choice[u as usize] == x
            && f.keys.is_none_or(|k| k[x as usize] == k[u as usize])
        {
            out.pairs.push((x, u));
        }
    }
    out
}

/// Gives every inner crossing left alone (in no kept group) to the nearest kept group it shares
/// a triangle with, up to [`MAX_LONES`] lone crossings per group (lowest ids first); returns the
/// groups to test: those that took some, and (with `want_dirty`) the groups around them. `edge_of` gives every
/// crossing's owner slot and edge; the tile rule keeps groups inside one tile.
pub(crate) fn give_lones(
    f: &Fixed,
    g: &mut Groups,
    edge_of: &[(u32, u8)],
    want_dirty: bool,
    pool: &rayon::ThreadPool,
) -> Vec<u32> {
    let q = Quotient::new(f, g);
    let found: Vec<(u32, Lone)> = pool.install(|| {
        (0..edge_of.len())
            .into_par_iter()
            .filter(|&x| q.alone(x as u32) && q.joinable(x as u32))
            .filter_map(|x| {
                let (slot, dir) = edge_of[x];
                if !q.inner(slot as usize, dir) {
                    return None;
                }
                let refused = q.g.refused[x];
                let h = q.nearest_group(x as u32, |h| h != refused && q.same_tile(x as u32, h))?;
                Some((h, Lone { id: x as u32 }))
            })
            .collect()
    });
    attach(f, g, found, want_dirty, pool)
}

/// Gives the lone crossings `found` (group, crossing) to their groups, up to [`MAX_LONES`] per
/// group (lowest ids first): the kept groups' lone tables are rebuilt, their lones so far
/// first (the count [`Groups::base_len`] a failing group sheds back to). Returns the groups
/// that took some, and (with `want_dirty`) the groups around them.
pub(crate) fn attach(
    f: &Fixed,
    g: &mut Groups,
    mut found: Vec<(u32, Lone)>,
    want_dirty: bool,
    pool: &rayon::ThreadPool,
) -> Vec<u32> {
    found.sort_unstable_by_key(|&(h, l)| (h, l.id));
    // The new lone table: each kept group's lones so far, then its new ones.
    let count = f.groups.len();
    let mut lone = Vec::with_capacity(g.lone.len() + found.len());
    let mut lone_start = Vec::with_capacity(count + 1);
    let mut changed = Vec::new();
    let mut next = found.iter().peekable();
    for gi in 0..count {
        lone_start.push(lone.len() as u32);
        let start = g.lone_start[gi] as usize;
        let kept = if g.active[gi] != 0 {
            g.lone_len[gi] as usize
        } else {
            0
        };
        lone.extend_from_slice(&g.lone[start..start + kept]);
        g.base_len[gi] = kept as u8;
        let mut len = kept;
        while let Some(&&(h, l)) = next.peek() {
            if h as usize != gi {
                break;
            }
            next.next();
            if len < MAX_LONES {
                lone.push(l);
                g.group_of[l.id as usize] = h;
                len += 1;
            }
        }
        g.lone_len[gi] = len as u8;
        if len > kept {
            changed.push(gi as u32);
        }
    }
    lone_start.push(lone.len() as u32);
    g.lone = lone;
    g.lone_start = lone_start;
    for &gi in &changed {
        g.refresh(f, gi as usize);
        g.set_vertices(f, gi as usize);
    }
    if !want_dirty {
        return changed;
    }
    let q = Quotient::new(f, g);
    let mut dirty: Vec<u32> = pool.install(|| {
        changed
            .par_iter()
            .map_init(Box::<Star>::default, |s, &gi| {
                let mut out = vec![gi];
                q.neighbours(gi as usize, s, &mut out);
                out
            })
            .flatten()
            .collect()
    });
    dirty.sort_unstable();
    dirty.dedup();
    dirty
}

/// Whether the directed edges `src[i] -> dst[i]` form one simple cycle of at least 3 vertices
/// (`next` is working memory).
fn simple_cycle(src: &[u32], dst: &[u32], next: &mut Vec<u32>) -> bool {
    let m = src.len();
    if m < 3 {
        return false;
    }
    // Each vertex starts one edge and ends one.
    next.clear();
    next.resize(m, 0);
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
            Some(j) => next[j] = i as u32,
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
        let n = &mut Vec::new();
        assert!(simple_cycle(&[1, 2, 3], &[2, 3, 1], n));
        assert!(simple_cycle(&[5, 1, 9, 2], &[9, 5, 2, 1], n));
        // Too short, open, two cycles, a vertex twice.
        assert!(!simple_cycle(&[1, 2], &[2, 1], n));
        assert!(!simple_cycle(&[1, 2, 3], &[2, 3, 4], n));
        assert!(!simple_cycle(&[1, 2, 3, 4, 5, 6], &[2, 3, 1, 5, 6, 4], n));
        assert!(!simple_cycle(&[1, 2, 3, 1], &[2, 3, 1, 4], n));
    }

    #[test]
    fn variants_drop_one_crossing_then_keep_pairs_all_connected() {
        use crate::cluster::compress;
        use crate::lattice::LatticeTables;
        use crate::Lattice;
        let t = LatticeTables::get(Lattice::BodyCentred);
        // +x (0) with its adjacent diagonals 6 and 7, and 8 (adjacent to 0 too), owned along
        // with -x (1), which is not in the island.
        let owned: u16 = (1 << 0) | (1 << 1) | (1 << 6) | (1 << 7) | (1 << 8);
        let island: u16 = (1 << 0) | (1 << 6) | (1 << 7) | (1 << 8);
        assert!(t.is_connected(island));
        let c = Candidate {
            first: 40,
            members: compress(island, owned),
            dirs: island,
            slot: 9,
        };
        let mut out = Vec::new();
        variants(&c, t, &mut out);
        let without_one: Vec<u16> = [0, 6, 7, 8]
            .iter()
            .map(|&d| island & !(1 << d))
            .filter(|&m| t.is_connected(m))
            .collect();
        let pairs = (out.len() - without_one.len()) as u32;
        assert_eq!(
            out.iter()
                .take(without_one.len())
                .map(|v| v.dirs)
                .collect::<Vec<_>>(),
            without_one,
            "the islands without one crossing come first, in bit order"
        );
        for v in &out {
            assert!(t.is_connected(v.dirs), "{:b}", v.dirs);
            assert_eq!(
                v.members,
                compress(v.dirs, owned),
                "members follow the edges"
            );
            assert_eq!((v.first, v.slot), (40, 9));
            assert_eq!(v.dirs & !island, 0);
        }
        // Every connected pair of the island, each once.
        let expected = [0, 6, 7, 8]
            .iter()
            .enumerate()
            .flat_map(|(i, &a)| {
                [0, 6, 7, 8][i + 1..]
                    .iter()
                    .map(move |&b| (1u16 << a) | (1 << b))
            })
            .filter(|&m| t.is_connected(m))
            .count() as u32;
        assert_eq!(pairs, expected);
        // Islands of two have no variant; of three, no pairs.
        let mut none = Vec::new();
        let two = (1 << 0) | (1 << 6);
        variants(
            &Candidate {
                first: 0,
                members: compress(two, owned),
                dirs: two,
                slot: 0,
            },
            t,
            &mut none,
        );
        assert!(none.is_empty());
    }

    #[test]
    fn aspect_ratio_is_one_for_equilateral_and_grows_for_needles() {
        use glam::Vec3;
        let s3 = 3f32.sqrt();
        let eq = aspect_ratio(Vec3::ZERO, Vec3::X, Vec3::new(0.5, s3 / 2.0, 0.0));
        assert!((eq - 1.0).abs() < 1e-5, "{eq}");
        let needle = aspect_ratio(Vec3::ZERO, Vec3::X, Vec3::new(0.5, 0.01, 0.0));
        assert!(needle > SLIVER_AR, "{needle}");
        assert_eq!(
            aspect_ratio(Vec3::ZERO, Vec3::X, 2.0 * Vec3::X),
            f32::INFINITY
        );
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
