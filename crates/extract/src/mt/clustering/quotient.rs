//! The quotient test of integrated clustering: whether a group, contracted with all the others,
//! keeps the mesh a manifold of the same topology.
//!
//! The proposals ([`super::proposal`]) are a partition of the crossings into groups. Picture every
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
//! [`Quotient::verdict`] walks a group's star and decides all three; the repair rounds, which
//! test only kept groups, use [`Quotient::verdict_kept`], which gives the same verdict with less
//! work:
//!
//! - (a) of a group of one point's crossings is a lattice table over the 2^14 edge masks
//!   ([`crate::lattice::LatticeTables::is_contractible`]); with lone crossings, that table plus
//!   a walk around the lone crossings only ([`Quotient::lones_keep_contractible`]);
//! - membership is one label compare (a kept group's members carry its leader's label), so a
//!   star triangle's quotient corners are its corners' labels, the same from each group whose
//!   star holds it: (c) is computed once per triangle and round ([`RoundTables`]), and a round
//!   that tests many groups labels every triangle once, so the walk skips the collapsed ones.
//!
//! The repair rounds that keep only groups passing these tests are in [`super::repair`]; what is
//! proposed after the islands settle (variants of split islands, lone crossings, sliver pairs) is
//! in [`super::additions`].

use std::sync::atomic::{AtomicU8, Ordering};

use glam::DVec3;
use rayon::prelude::*;

use super::proposal::Candidate;
use crate::mt::layout::Layout;

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
    /// Plain MT's triangles (three crossing ids each), each one's source tetrahedron (see
    /// [`super::plain::PlainList::source`]), and every crossing's triangles
    /// (`inc[inc_start[x]..inc_start[x + 1]]`).
    pub(crate) tris: &'a [u32],
    pub(crate) source: &'a [(u32, u8)],
    pub(crate) inc_start: &'a [u32],
    pub(crate) inc: &'a [u32],
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
    /// Per crossing: the last group that gave it back ([`NONE`] if none); the next pass does not
    /// give it to that group. The sliver passes start with it cleared.
    pub(crate) refused: Vec<u32>,
    /// Per crossing, its vertex in the quotient of the current state: the label (the leader of
    /// its kept group, or itself) and that vertex's position ([`Groups::relabel`]).
    pub(crate) vlabel: Vec<u32>,
    pub(crate) vpos: Vec<[f32; 3]>,
    /// When recording the clustering's activity (empty otherwise): per crossing, 1 once a step
    /// after the proposals changed its state, tested its group and found it failing, or
    /// considered it as a crossing left alone that may join a group.
    pub(crate) touched: Vec<u8>,
    /// The working tables of the repair rounds ([`super::repair::settle`]), kept here so that
    /// they are sized once.
    pub(crate) round: RoundTables,
}

impl Groups {
    /// Empties every table (their memory is kept for the next extraction).
    pub(crate) fn clear(&mut self) {
        self.active.clear();
        self.group_of.clear();
        self.leader.clear();
        self.centroid.clear();
        self.lone.clear();
        self.lone_start.clear();
        self.lone_len.clear();
        self.base_len.clear();
        self.refused.clear();
        self.vlabel.clear();
        self.vpos.clear();
        self.touched.clear();
        self.round.flips.clear();
        self.round.labels.clear();
    }

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
            + self.round.bytes()
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
        const RUN: usize = 1 << 12;
        pool.install(|| {
            self.vlabel
                .par_chunks_mut(RUN)
                .zip(self.vpos.par_chunks_mut(RUN))
                .enumerate()
                .for_each(|(k, (labels, positions))| {
                    let lo = k * RUN;
                    let run = lo..lo + labels.len();
                    let (groups, own) = (&group_of[run.clone()], &f.cpos[run]);
                    for (i, ((l, p), (&h, &at))) in labels
                        .iter_mut()
                        .zip(positions)
                        .zip(groups.iter().zip(own))
                        .enumerate()
                    {
                        if h != NONE && active[h as usize] != 0 {
                            *l = leader[h as usize];
                            *p = centroid[h as usize];
                        } else {
                            *l = (lo + i) as u32;
                            *p = at;
                        }
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
        let track = !self.touched.is_empty();
        for x in f.groups[gi].ids().chain(lones.iter().map(|l| l.id)) {
            let x = x as usize;
            if track {
                self.touched[x] = 1;
            }
            if kept {
                self.vlabel[x] = self.leader[gi];
                self.vpos[x] = self.centroid[gi];
            } else {
                self.vlabel[x] = x as u32;
                self.vpos[x] = f.cpos[x];
            }
        }
    }

    /// Marks the members of group `gi` (its island and lone crossings) as touched, when
    /// recording.
    pub(crate) fn touch_group(&mut self, f: &Fixed, gi: usize) {
        if self.touched.is_empty() {
            return;
        }
        let start = self.lone_start[gi] as usize;
        let lones = &self.lone[start..start + self.lone_len[gi] as usize];
        for x in f.groups[gi].ids().chain(lones.iter().map(|l| l.id)) {
            self.touched[x as usize] = 1;
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
        let start = self.lone_start[gi] as usize;
        let lones = &self.lone[start..start + self.lone_len[gi] as usize];
        (self.centroid[gi], self.leader[gi]) = group_vertex(f.groups[gi], lones, f.cpos);
    }
}

/// The vertex position (the mean of its crossings) and the label (the lowest id) of the group
/// with island `c` and lone crossings `lones` ([`Groups::refresh`]).
#[inline]
pub(crate) fn group_vertex(c: Candidate, lones: &[Lone], cpos: &[[f32; 3]]) -> ([f32; 3], u32) {
    let mut sum = glam::Vec3::ZERO;
    for id in c.ids().chain(lones.iter().map(|l| l.id)) {
        sum += glam::Vec3::from(cpos[id as usize]);
    }
    let centroid = (sum / (c.size() as usize + lones.len()) as f32).to_array();
    (
        centroid,
        lones.iter().map(|l| l.id).fold(c.leader(), u32::min),
    )
}

/// The quotient test's view of one state: [`Fixed`] plus [`Groups`].
pub(crate) struct Quotient<'a> {
    pub(crate) l: &'a Layout<'a>,
    pub(crate) cpos: &'a [[f32; 3]],
    pub(crate) groups: &'a [Candidate],
    tris: &'a [u32],
    source: &'a [(u32, u8)],
    inc_start: &'a [u32],
    inc: &'a [u32],
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
            source: f.source,
            inc_start: f.inc_start,
            inc: f.inc,
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
    /// Link edges `src[i] -> dst[i]` of the test of (b).
    src: Vec<u32>,
    dst: Vec<u32>,
    /// Labels of the link vertices (see [`Quotient::passes`]).
    link: Vec<u32>,
}

/// Test (c)'s memo value of a plain MT triangle that collapsed in the state of the round (two
/// of its corners' labels coincide), set by [`RoundTables::prepare`].
pub(crate) const COLLAPSED: u8 = 3;

/// Per plain MT triangle, what the tests of one round (one state) share: test (c)'s memo (0
/// not known yet, 1 passes, 2 fails, filled by whichever test reads the triangle first), and,
/// when the round tests many groups, every triangle's quotient labels with the collapsed ones
/// marked [`COLLAPSED`] in the memo, computed once for the round. Kept between rounds and
/// extractions ([`Groups::round`]).
#[derive(Debug, Default)]
pub(crate) struct RoundTables {
    pub(crate) flips: Vec<AtomicU8>,
    /// Per triangle, its corners' labels (when `labelled`).
    pub(crate) labels: Vec<[u32; 3]>,
    pub(crate) labelled: bool,
}

impl Clone for RoundTables {
    fn clone(&self) -> Self {
        Self {
            flips: self
                .flips
                .iter()
                .map(|m| AtomicU8::new(m.load(Ordering::Relaxed)))
                .collect(),
            labels: self.labels.clone(),
            labelled: self.labelled,
        }
    }
}

impl RoundTables {
    /// Bytes held.
    pub(crate) fn bytes(&self) -> usize {
        self.flips.len() + self.labels.len() * 12
    }

    /// Sets the tables up for the state of `q`: the memo cleared, and with `label` every
    /// triangle's labels and collapsed mark (in parallel over runs of triangles).
    pub(crate) fn prepare(&mut self, q: &Quotient, label: bool, pool: &rayon::ThreadPool) {
        let n = q.tris.len() / 3;
        self.labelled = label;
        self.flips.resize_with(n, || AtomicU8::new(0));
        if !label {
            pool.install(|| {
                self.flips
                    .par_chunks_mut(1 << 14)
                    .for_each(|c| c.iter_mut().for_each(|m| *m.get_mut() = 0))
            });
            return;
        }
        self.labels.resize(n, [0; 3]);
        const RUN: usize = 1 << 12;
        let vlabel = &q.g.vlabel[..];
        pool.install(|| {
            self.flips
                .par_chunks_mut(RUN)
                .zip(self.labels.par_chunks_mut(RUN))
                .enumerate()
                .for_each(|(k, (flips, labels))| {
                    let tris = &q.tris[3 * k * RUN..3 * (k * RUN + labels.len())];
                    for ((m, l), t) in flips.iter_mut().zip(labels).zip(tris.chunks_exact(3)) {
                        let c = [
                            vlabel[t[0] as usize],
                            vlabel[t[1] as usize],
                            vlabel[t[2] as usize],
                        ];
                        *l = c;
                        // Without branches: whether two labels coincide is data.
                        let collapsed = (c[0] == c[1]) | (c[1] == c[2]) | (c[0] == c[2]);
                        *m.get_mut() = COLLAPSED * u8::from(collapsed);
                    }
                })
        });
    }
}

impl Quotient<'_> {
    /// The label of crossing `x` in the quotient: the leader of its group when that group is
    /// active, else itself.
    #[inline(always)]
    pub(crate) fn label(&self, x: u32) -> u32 {
        self.g.vlabel[x as usize]
    }

    /// Position of quotient vertex `label`.
    #[inline(always)]
    pub(crate) fn position(&self, label: u32) -> [f32; 3] {
        self.g.vpos[label as usize]
    }

    /// The lone crossings of group `gi`.
    #[inline(always)]
    pub(crate) fn lones_of(&self, gi: usize) -> &[Lone] {
        let start = self.g.lone_start[gi] as usize;
        &self.g.lone[start..start + self.g.lone_len[gi] as usize]
    }

    /// Whether crossing `x` is a member of group `gi` (its island, or one of its lone
    /// crossings). For a kept group this is `group_of[x] == gi`; a group not kept (a variant
    /// being tried) answers from its own members.
    #[inline(always)]
    pub(crate) fn is_member(&self, gi: usize, x: u32) -> bool {
        self.groups[gi].has(x) || self.lones_of(gi).iter().any(|l| l.id == x)
    }

    /// Whether group `gi` passes tests (a), (b) and (c) in the current state, as if it were
    /// kept and every other group as it is.
    pub(crate) fn passes_all(&self, gi: usize, s: &mut Star) -> bool {
        self.verdict(gi, s, true) == Verdict::Passes
    }

    /// The tests of group `gi` in one walk over its star: (a) when `test_a` (its crossings,
    /// with the MT edges and triangles among them, form a contractible complex: connected,
    /// Euler characteristic 1), then (b) and (c), without
    /// listing the star first: each triangle is read once, from its first member corner.
    pub(crate) fn verdict(&self, gi: usize, s: &mut Star, test_a: bool) -> Verdict {
        let g = &self.groups[gi];
        let lones = self.lones_of(gi);
        let member = |y: u32| g.has(y) || lones.iter().any(|l| l.id == y);
        let me = self.g.leader[gi];
        s.src.clear();
        s.dst.clear();
        // Test (a)'s complex: member adjacency (bit sets by `local` index) and its faces.
        let mut adj = [0u32; 32];
        let mut faces = 0i32;
        let mut geometry = true;
        for x in g.ids().chain(lones.iter().map(|l| l.id)) {
            for &ti in self.tris_of(x) {
                let t = self.tri(ti);
                let mask = (0..3).fold(0u8, |m, i| m | u8::from(member(t[i])) << i);
                if mask.count_ones() >= 2 {
                    // Collapsed: only test (a) reads it, once, from its first member corner.
                    if test_a && t[mask.trailing_zeros() as usize] == x {
                        for e in 0..3 {
                            let (a, b) = (e, (e + 1) % 3);
                            if mask >> a & 1 != 0 && mask >> b & 1 != 0 {
                                let ra = Self::local(g, lones, t[a]);
                                let rb = Self::local(g, lones, t[b]);
                                adj[ra] |= 1 << rb;
                                adj[rb] |= 1 << ra;
                            }
                        }
                        faces += i32::from(mask == 0b111);
                    }
                    continue;
                }
                // One member corner, `x`: the triangle is listed once, from it.
                let Some(q) = self.quotient_triangle(t, mask, me) else {
                    continue;
                };
                let k = mask.trailing_zeros() as usize;
                s.src.push(q[(k + 1) % 3]);
                s.dst.push(q[(k + 2) % 3]);
                if geometry && !self.geometry_ok(gi, t, q, ti) {
                    if !test_a {
                        return Verdict::FailsLink;
                    }
                    geometry = false;
                }
            }
        }
        if test_a {
            let edges: u32 = adj.iter().map(|m| m.count_ones()).sum::<u32>() / 2;
            let members = u32::from(g.members) | ((1u32 << lones.len()) - 1) << 16;
            if !connected(&adj, members) || members.count_ones() as i32 - edges as i32 + faces != 1
            {
                return Verdict::FailsContractible;
            }
        }
        if geometry && simple_cycle(&s.src, &s.dst) {
            Verdict::Passes
        } else {
            Verdict::FailsLink
        }
    }

    /// [`Quotient::verdict`] of a kept group `gi` (the repair rounds test only kept groups),
    /// read from the quotient labels: a crossing is a member exactly when its label is the
    /// group's (the labels of a kept group's members are its leader, and no other crossing's
    /// is), and the group's vertex is its leader's quotient position. So a star triangle's
    /// quotient corners are its corners' labels, the same from each of the up to three groups
    /// whose star holds it, and so is test (c) on it: `flips` memoises (c) per plain MT
    /// triangle for one state (0 not known yet, 1 passes, 2 fails), filled by whichever test
    /// reaches the triangle first. The same verdict as [`Quotient::verdict`]; the tests of
    /// `repair` compare the two on every group they test.
    pub(crate) fn verdict_kept(
        &self,
        gi: usize,
        s: &mut Star,
        test_a: bool,
        r: &RoundTables,
    ) -> Verdict {
        debug_assert_ne!(self.g.active[gi], 0, "group {gi} is not kept");
        let flips = &r.flips[..];
        let g = &self.groups[gi];
        let lones = self.lones_of(gi);
        let me = self.g.leader[gi];
        debug_assert_eq!(self.g.vpos[me as usize], self.g.centroid[gi]);
        let vlabel = &self.g.vlabel[..];
        // Test (a) of a group of one point's crossings (no lone crossing) by the lattice's
        // table ([`crate::lattice::LatticeTables::is_contractible`]); with lone crossings, when
        // the point's part is contractible, from what the lone crossings add to it, walked
        // around them only ([`Quotient::lones_keep_contractible`]). The walk then tests (b) and
        // (c) only.
        let decided = if !test_a {
            None
        } else if lones.is_empty() {
            Some(self.l.t.is_contractible(g.dirs))
        } else if self.l.t.is_contractible(g.dirs) {
            Some(self.lones_keep_contractible(lones, me))
        } else {
            None
        };
        if decided == Some(false) {
            return Verdict::FailsContractible;
        }
        let test_a = test_a && decided.is_none();
        if !test_a && r.labelled {
            return self.verdict_labelled(gi, s, r);
        }
        s.src.clear();
        s.dst.clear();
        let mut adj = [0u32; 32];
        let (mut faces, mut edges) = (0i32, 0u32);
        let mut geometry = true;
        for x in g.ids().chain(lones.iter().map(|l| l.id)) {
            for &ti in self.tris_of(x) {
                let t = self.tri(ti);
                let q = t.map(|y| vlabel[y as usize]);
                let mask =
                    u8::from(q[0] == me) | u8::from(q[1] == me) << 1 | u8::from(q[2] == me) << 2;
                debug_assert_ne!(
                    mask, 0,
                    "crossing {x} of group {gi} is labelled {}",
                    vlabel[x as usize]
                );
                // Two or more member corners (no popcount: it is a library call on the
                // baseline target).
                if mask & (mask - 1) != 0 {
                    // Collapsed: only test (a) reads it, once, from its first member corner.
                    if test_a && t[mask.trailing_zeros() as usize] == x {
                        for e in 0..3 {
                            let (a, b) = (e, (e + 1) % 3);
                            if mask >> a & 1 != 0 && mask >> b & 1 != 0 {
                                let ra = Self::local(g, lones, t[a]);
                                let rb = Self::local(g, lones, t[b]);
                                // Each edge counted once, when it is first seen.
                                edges += adj[ra] >> rb & 1 ^ 1;
                                adj[ra] |= 1 << rb;
                                adj[rb] |= 1 << ra;
                            }
                        }
                        faces += i32::from(mask == 0b111);
                    }
                    continue;
                }
                // One member corner, `x`: the triangle is read once, from it.
                if q[0] == q[1] || q[1] == q[2] || q[0] == q[2] {
                    continue;
                }
                let k = mask.trailing_zeros() as usize;
                s.src.push(q[(k + 1) % 3]);
                s.dst.push(q[(k + 2) % 3]);
                if geometry && !self.flip_ok(q, ti, flips) {
                    if !test_a {
                        return Verdict::FailsLink;
                    }
                    geometry = false;
                }
            }
        }
        if test_a {
            let members = u32::from(g.members) | ((1u32 << lones.len()) - 1) << 16;
            if !connected(&adj, members) || members.count_ones() as i32 - edges as i32 + faces != 1
            {
                return Verdict::FailsContractible;
            }
        }
        if geometry && simple_cycle(&s.src, &s.dst) {
            Verdict::Passes
        } else {
            Verdict::FailsLink
        }
    }

    /// Test (a) of a kept group (labelled `me`) whose own point's crossings form a contractible
    /// complex, with its lone crossings `lones`: the group's complex is that one plus the lone
    /// crossings, the member edges at them and the member triangles through them, so it is
    /// contractible exactly when every lone crossing reaches the point's part along member
    /// edges and the lone crossings add as many edges as vertices and triangles (V - E + F
    /// stays 1). Every member is an inner vertex, so each edge at a lone crossing lies in two
    /// of its triangles: an edge to the point's part is seen twice, one between two lone
    /// crossings four times (weights 2 and 1 make both 4); a triangle is counted from its first
    /// lone corner.
    pub(crate) fn lones_keep_contractible(&self, lones: &[Lone], me: u32) -> bool {
        let vlabel = &self.g.vlabel[..];
        let lone_index = |y: u32| lones.iter().position(|l| l.id == y);
        // Bit i: lone crossing i has an edge to the point's part; `near[i]` bit j: to lone j.
        let mut near_part = 0u8;
        let mut near = [0u8; MAX_LONES];
        let (mut quarter_edges, mut faces) = (0usize, 0usize);
        for (i, l) in lones.iter().enumerate() {
            for &ti in self.tris_of(l.id) {
                let t = self.tri(ti);
                let k = t.iter().position(|&y| y == l.id).unwrap_or(0);
                let mut all = true;
                for y in [t[(k + 1) % 3], t[(k + 2) % 3]] {
                    if vlabel[y as usize] != me {
                        all = false;
                        continue;
                    }
                    match lone_index(y) {
                        Some(j) => {
                            quarter_edges += 1;
                            near[i] |= 1 << j;
                        }
                        None => {
                            quarter_edges += 2;
                            near_part |= 1 << i;
                        }
                    }
                }
                if all && t[..k].iter().all(|&y| lone_index(y).is_none()) {
                    faces += 1;
                }
            }
        }
        debug_assert_eq!(
            quarter_edges % 4,
            0,
            "an edge at a lone crossing in one triangle"
        );
        let mut reached = near_part;
        loop {
            let mut grown = reached;
            let mut bits = reached;
            while bits != 0 {
                grown |= near[bits.trailing_zeros() as usize];
                bits &= bits - 1;
            }
            if grown == reached {
                break;
            }
            reached = grown;
        }
        let every = (1u16 << lones.len()) - 1;
        u16::from(reached) == every && quarter_edges / 4 == lones.len() + faces
    }

    /// [`Quotient::verdict_kept`] without test (a) (not asked, or decided by the table), from
    /// the round's tables (`r.labelled`): a triangle that collapsed in this state is skipped
    /// on one byte, and the others' quotient labels are read in one place.
    fn verdict_labelled(&self, gi: usize, s: &mut Star, r: &RoundTables) -> Verdict {
        let g = self.groups[gi];
        let lones = self.lones_of(gi);
        let me = self.g.leader[gi];
        let (flips, labels) = (&r.flips[..], &r.labels[..]);
        s.src.clear();
        s.dst.clear();
        // Each triangle's memo is read once: collapsed, or test (c)'s outcome when known.
        let mut walk = |x: u32| -> bool {
            for &ti in self.tris_of(x) {
                let memo = &flips[ti as usize];
                let known = memo.load(Ordering::Relaxed);
                if known == COLLAPSED {
                    continue;
                }
                // Three different labels, one of them the group's (`x`'s): its corner found
                // without branches.
                let q = labels[ti as usize];
                let k = usize::from(q[1] == me) | usize::from(q[2] == me) << 1;
                debug_assert_eq!(q[k], me, "triangle {ti} at member {x} of group {gi}");
                s.src.push(q[(k + 1) % 3]);
                s.dst.push(q[(k + 2) % 3]);
                let ok = match known {
                    1 => true,
                    2 => false,
                    _ => self.flip_eval(q, ti, memo),
                };
                if !ok {
                    return false;
                }
            }
            true
        };
        for x in g.ids().chain(lones.iter().map(|l| l.id)) {
            if !walk(x) {
                return Verdict::FailsLink;
            }
        }
        if simple_cycle(&s.src, &s.dst) {
            Verdict::Passes
        } else {
            Verdict::FailsLink
        }
    }

    /// Test (c) on plain MT triangle `tri` (quotient labels `q`, all distinct) in
    /// the current state, memoised in `flips` (see [`Quotient::verdict_kept`]).
    #[inline]
    fn flip_ok(&self, q: [u32; 3], tri: u32, flips: &[AtomicU8]) -> bool {
        let memo = &flips[tri as usize];
        match memo.load(Ordering::Relaxed) {
            1 => true,
            2 => false,
            _ => self.flip_eval(q, tri, memo),
        }
    }

    /// Test (c) on plain MT triangle `tri` evaluated (its memo `memo` not known yet), and the
    /// outcome stored in the memo.
    #[inline(never)]
    fn flip_eval(&self, q: [u32; 3], tri: u32, memo: &AtomicU8) -> bool {
        let ok = match shape(q.map(|x| self.position(x))) {
            Shape::Flat => shape(self.tri(tri).map(|x| self.cpos[x as usize])) == Shape::Flat,
            Shape::Normal(n) => n.dot(DVec3::from(self.gradient(tri).map(f64::from))) > 0.0,
        };
        memo.store(if ok { 1 } else { 2 }, Ordering::Relaxed);
        ok
    }

    /// The gradient of plain MT triangle `tri`'s source tetrahedron (of the linear interpolant
    /// on it, up to a positive factor): computed when test (c) reads the triangle, the same
    /// bits as the listing would have stored.
    #[inline]
    fn gradient(&self, tri: u32) -> [f32; 3] {
        let (anchor, tet) = self.source[tri as usize];
        self.l
            .gradient(anchor as usize, usize::from(tet & 0x7f), tet & 0x80 != 0)
    }

    /// Number of crossings in group `gi`.
    pub(crate) fn size(&self, gi: usize) -> u32 {
        self.groups[gi].size() + self.lones_of(gi).len() as u32
    }

    /// The triangles of crossing `x` in plain MT.
    #[inline(always)]
    pub(crate) fn tris_of(&self, x: u32) -> &[u32] {
        &self.inc[self.inc_start[x as usize] as usize..self.inc_start[x as usize + 1] as usize]
    }

    /// Triangle `t`'s crossings.
    #[inline(always)]
    pub(crate) fn tri(&self, t: u32) -> [u32; 3] {
        let i = 3 * t as usize;
        let c = &self.tris[i..i + 3];
        [c[0], c[1], c[2]]
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
    pub(crate) fn local(g: &Candidate, lones: &[Lone], x: u32) -> usize {
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
    pub(crate) fn inner(&self, slot: usize, dir: u8) -> bool {
        let p = self.l.coords_of(slot);
        self.l.inner_dirs(p) & (1 << dir) != 0
    }

    /// Leaves in `s.link` the labels of the link vertices of group `gi` in the current state
    /// (both ends of every link edge of test (b)), or, when it has no triangle left, of every
    /// vertex of its star; `s` is its star.
    pub(crate) fn link(&self, gi: usize, s: &mut Star) {
        let me = self.g.leader[gi];
        s.link.clear();
        for (&ti, &mask) in s.tris.iter().zip(&s.mask) {
            if mask.count_ones() >= 2 {
                // Two corners in the group: collapsed.
                continue;
            }
            if let Some(q) = self.quotient_triangle(self.tri(ti), mask, me) {
                s.link.extend(q.into_iter().filter(|&x| x != me));
            }
        }
        if s.link.is_empty() {
            // No triangle left: the neighbours in plain MT stand for the star.
            for &ti in &s.tris {
                for x in self.tri(ti) {
                    if !self.is_member(gi, x) {
                        s.link.push(self.label(x));
                    }
                }
            }
        }
    }

    /// The quotient labels of plain MT triangle `t` (corners `mask` in the group labelled `me`),
    /// or `None` when two of them coincide (the triangle collapsed).
    #[inline(always)]
    fn quotient_triangle(&self, t: [u32; 3], mask: u8, me: u32) -> Option<[u32; 3]> {
        let q = [0, 1, 2].map(|i| {
            if mask >> i & 1 != 0 {
                me
            } else {
                self.label(t[i])
            }
        });
        (q[0] != q[1] && q[1] != q[2] && q[0] != q[2]).then_some(q)
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
            Shape::Normal(n) => n.dot(DVec3::from(self.gradient(tri).map(f64::from))) > 0.0,
        }
    }

    /// The group that failing group `gi` names for splitting: the failing group of lowest
    /// priority in its closed star (`failing[h] != 0`).
    pub(crate) fn nominate(&self, gi: usize, failing: &[u8], s: &mut Star) -> usize {
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
    pub(crate) fn closed_star(&self, gi: usize, s: &mut Star, mut visit: impl FnMut(usize)) {
        self.star(gi, s);
        self.link(gi, s);
        for &x in &s.link {
            let h = self.g.group_of[x as usize];
            if h != NONE && h as usize != gi && self.g.active[h as usize] != 0 {
                visit(h as usize);
            }
        }
    }

    /// Whether crossing `x` is in no kept group.
    #[inline]
    pub(crate) fn alone(&self, x: u32) -> bool {
        let h = self.g.group_of[x as usize];
        h == NONE || self.g.active[h as usize] == 0
    }

    /// Whether group `gi` holds lone crossings given in the current phase.
    #[inline]
    pub(crate) fn has_new_lones(&self, gi: usize) -> bool {
        self.g.lone_len[gi] > self.g.base_len[gi]
    }

    /// The active groups with a crossing in a triangle of group `gi`'s star (those whose test
    /// may change when `gi` changes), appended to `out`.
    pub(crate) fn neighbours(&self, gi: usize, s: &mut Star, out: &mut Vec<u32>) {
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
    /// `allowed` (not the one that gave it back).
    pub(crate) fn nearest_group(&self, x: u32, allowed: impl Fn(u32) -> bool) -> Option<u32> {
        let px = glam::Vec3::from(self.cpos[x as usize]);
        let mut best: Option<(f32, u32)> = None;
        // The group just weighed: a corner of the same group again weighs the same.
        let mut last = NONE;
        for &t in self.tris_of(x) {
            for y in self.tri(t) {
                let h = self.g.group_of[y as usize];
                if h == last || h == NONE || self.g.active[h as usize] == 0 || !allowed(h) {
                    continue;
                }
                last = h;
                let dist = px.distance_squared(glam::Vec3::from(self.g.centroid[h as usize]));
                if best.is_none_or(|(bd, bh)| (dist, h) < (bd, bh)) {
                    best = Some((dist, h));
                }
            }
        }
        best.map(|(_, h)| h)
    }
}

/// The outcome of a group's tests ([`Quotient::verdict`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Verdict {
    /// (a), (b) and (c) hold.
    Passes,
    /// (b) or (c) fails (and (a) holds, or was not asked).
    FailsLink,
    /// (a) fails.
    FailsContractible,
}

/// Whether the members (bit set) are connected along `adj` (member adjacency bit sets): grown
/// from the lowest member.
fn connected(adj: &[u32; 32], members: u32) -> bool {
    let mut reached = members & members.wrapping_neg();
    loop {
        let mut grown = reached;
        let mut bits = reached;
        while bits != 0 {
            grown |= adj[bits.trailing_zeros() as usize];
            bits &= bits - 1;
        }
        if grown == reached {
            return reached == members;
        }
        reached = grown;
    }
}

/// Whether the directed edges `src[i] -> dst[i]` form one simple cycle of at least 3 vertices:
/// every vertex starts one edge and ends one, and the edges make one cycle.
///
/// The walk from edge 0 always takes the *first* edge that starts where the current one ends.
/// It comes back to edge 0 after exactly `m` steps, and not before, if and only if the edges
/// form one simple cycle: such a walk visits all `m` edges, each of them the first edge with
/// its start, so no two edges start at one vertex; and it is a bijection on the edges, so no
/// two end at one. Conversely, on one simple cycle the first edge is the only one. (A test
/// beside this function compares it with the definition on every small edge set.)
fn simple_cycle(src: &[u32], dst: &[u32]) -> bool {
    let m = src.len();
    if m < 3 {
        return false;
    }
    let mut at = 0usize;
    for step in 1..=m {
        match src.iter().position(|&v| v == dst[at]) {
            Some(j) => at = j,
            None => return false,
        }
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
    // The same comparison squared, without the square roots, where it is clear by far more
    // than the rounding of either form (a relative 1e-6 against a few 1e-16); the exact form
    // below decides the rest.
    let l2_max = e[0]
        .length_squared()
        .max(e[1].length_squared())
        .max(e[2].length_squared());
    let (lhs, rhs) = (
        n.length_squared(),
        4.0 * ZERO_AREA_REL_TOL * ZERO_AREA_REL_TOL * l2_max * l2_max,
    );
    if lhs > rhs * (1.0 + 1e-6) {
        return Shape::Normal(n);
    }
    if lhs < rhs * (1.0 - 1e-6) {
        return Shape::Flat;
    }
    shape_exact(p)
}

/// [`shape`] with no shortcut: the square roots of `rmt_mesh::quality`.
fn shape_exact(p: [DVec3; 3]) -> Shape {
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

    /// The definition, directly: at least 3 edges, every vertex starts one edge and ends one,
    /// and following the edges from edge 0 passes through all of them before it returns.
    fn simple_cycle_by_definition(src: &[u32], dst: &[u32]) -> bool {
        let m = src.len();
        if m < 3 {
            return false;
        }
        for i in 0..m {
            for j in 0..m {
                if i != j && (src[i] == src[j] || dst[i] == dst[j]) {
                    return false;
                }
            }
        }
        let mut at = 0;
        for step in 1..=m {
            match (0..m).find(|&j| src[j] == dst[at]) {
                Some(j) => at = j,
                None => return false,
            }
            if at == 0 {
                return step == m;
            }
        }
        false
    }

    #[test]
    fn the_walk_agrees_with_the_definition_on_every_small_edge_set() {
        // Every list of up to 5 edges over 4 vertices (ordered, repeats allowed).
        let mut checked = 0;
        for m in 0..=5u32 {
            for code in 0..16u32.pow(m) {
                let (mut src, mut dst) = (Vec::new(), Vec::new());
                let mut c = code;
                for _ in 0..m {
                    src.push(c % 4);
                    dst.push(c / 4 % 4);
                    c /= 16;
                }
                assert_eq!(
                    simple_cycle(&src, &dst),
                    simple_cycle_by_definition(&src, &dst),
                    "edges {src:?} -> {dst:?}"
                );
                checked += 1;
            }
        }
        assert_eq!(checked, (0..=5).map(|m| 16u32.pow(m)).sum::<u32>());
    }

    /// [`shape_exact`] of f32 corners, as [`shape`] takes them.
    fn exact(p: [[f32; 3]; 3]) -> Shape {
        shape_exact(p.map(|x| DVec3::from(x.map(f64::from))))
    }

    #[test]
    fn the_squared_shortcut_agrees_with_the_exact_shape() {
        let (mut flat, mut tested) = (0, 0);
        // Heights around the threshold (area 1e-12 of the longest edge squared: a height of
        // 2e-12 on these unit bases), on both sides in steps of 1e-5, and random triangles.
        let mut h = 0.5e-12f32;
        while h < 8e-12 {
            for p in [
                [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.5, h, 0.0]],
                [[0.25, 0.0, 1.0], [1.25, 0.0, 1.0], [0.75, 0.0, 1.0 + h]],
            ] {
                assert_eq!(shape(p), exact(p), "{p:?}");
                flat += usize::from(shape(p) == Shape::Flat);
                tested += 1;
            }
            h = f32::from_bits(h.to_bits() + 1).max(h * (1.0 + 1e-5));
        }
        assert!(flat > 0 && flat < tested, "{flat} of {tested} flat");
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 40) as f32 / (1u64 << 24) as f32 - 0.5
        };
        for _ in 0..20_000 {
            let p = [
                [next(), next(), next()],
                [next(), next(), next()],
                [next(), next(), next()],
            ];
            assert_eq!(shape(p), exact(p), "{p:?}");
        }
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
