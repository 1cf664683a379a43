//! Red refinement, the closure, and the three green templates.
//!
//! ```text
//!   red (1:8)       split the 6 edges: 4 corner tets + the inner octahedron cut along its
//!                   SHORTEST diagonal (the one joining the two long-edge midpoints) = exactly
//!                   the 8 body-centred tets of the next finer level
//!   closure         for every leaf t of level > 0, with V = all leaf vertices and
//!                   S = edges of t whose midpoint is in V, red-refine t when
//!                     (balance) a point (i a + j b + k c) / 4 of a face abc, i + j + k = 4,
//!                               not all of i, j, k even (a quarter point), is in V; or
//!                     (face)    S holds all 3 edges of a face and S is not exactly that face;
//!                   repeat until nothing changes (the least fixed point: refining only adds
//!                   vertices, so the result does not depend on the order); closure_bits
//!                   runs it on a worklist (leaves near new vertices) over a bit grid
//!   green           (no vertex added; green tets are never refined)
//!     S empty            keep t
//!     S = face abc       cone: split abc at its midpoints into 4, cone each to the opposite d
//!     S, no full face    recursive bisection: bisect the first edge of S in the GLOBAL edge
//!                        order (longest first, then the lexicographic order of the sorted
//!                        endpoints), hand each other edge of S to the child holding it, repeat
//! ```
//!
//! Why it conforms: a green tet's triangulation of each of its faces depends only on that face
//! and which of its edges are split (0: the face; 1: two halves; 2: the first split edge in the
//! global order is cut first, its midpoint joined to the opposite corner, then the other; 3:
//! four), and which edges are split depends only on `V`, which both tets of a face see alike.
//! The tests check every template on every body-centred tet against that face rule.

use foldhash::HashSet;

use super::error::LodError;
use super::lattice::{mid, orient, Point, Tet, EDGES, FACES};

/// The edges (indices into [`EDGES`]) of each face of [`FACES`].
pub const FACE_EDGES: [[usize; 3]; 4] = [[3, 4, 5], [1, 2, 5], [0, 2, 4], [0, 1, 3]];

/// The quarter points of a face, as weights `(i, j, k)` with `i + j + k = 4`, not all even.
const QUARTERS: [(i64, i64, i64); 9] = [
    (0, 1, 3),
    (0, 3, 1),
    (1, 0, 3),
    (3, 0, 1),
    (1, 3, 0),
    (3, 1, 0),
    (1, 1, 2),
    (1, 2, 1),
    (2, 1, 1),
];

/// How a tetrahedron of the multiresolution mesh came to be.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum TetKind {
    /// A body-centred tetrahedron of its level (a red-forest leaf with no split edge).
    Bcc,
    /// A child of the face-cone template.
    Cone,
    /// A child of recursive bisection of `n` split edges.
    Bisect(u8),
}

/// A leaf of the red forest: a body-centred tetrahedron of `level`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Leaf {
    /// The tetrahedron, positively oriented.
    pub tet: Tet,
    /// Its level.
    pub level: u8,
}

fn half(p: Point, q: Point) -> Point {
    // Callers pass edges of tets of level >= 1, whose midpoints are lattice points.
    debug_assert!(mid(p, q).is_some());
    [(p[0] + q[0]) >> 1, (p[1] + q[1]) >> 1, (p[2] + q[2]) >> 1]
}

/// Red (1:8) refinement of a body-centred tetrahedron of level >= 1: its 8 children, the
/// body-centred tetrahedra of the next finer level inside it.
pub fn red(t: &Tet) -> [Tet; 8] {
    let m: [Point; 6] = EDGES.map(|(a, b)| half(t[a], t[b]));
    // The three diagonals of the octahedron join midpoints of opposite edges.
    const DIAG: [(usize, usize); 3] = [(0, 5), (1, 4), (2, 3)];
    let len = |k: usize| super::lattice::d2(m[DIAG[k].0], m[DIAG[k].1]);
    let best = (0..3).min_by_key(|&k| (len(k), k)).unwrap_or(0);
    let (p, q) = DIAG[best];
    // The other four edges in a ring (consecutive ones share a vertex); no allocation.
    let mut ring = [0usize; 4];
    let mut used = [false; 6];
    used[p] = true;
    used[q] = true;
    ring[0] = (0..6).find(|&e| !used[e]).unwrap_or(0);
    used[ring[0]] = true;
    for r in 1..4 {
        let last = EDGES[ring[r - 1]];
        let shares = |e: usize| {
            let (a, b) = EDGES[e];
            a == last.0 || a == last.1 || b == last.0 || b == last.1
        };
        ring[r] = (0..6).find(|&e| !used[e] && shares(e)).unwrap_or(0);
        used[ring[r]] = true;
    }
    let e = |a: usize, b: usize| {
        let k = EDGES
            .iter()
            .position(|&x| x == (a.min(b), a.max(b)))
            .unwrap_or(0);
        m[k]
    };
    [
        orient([t[0], e(0, 1), e(0, 2), e(0, 3)]),
        orient([e(0, 1), t[1], e(1, 2), e(1, 3)]),
        orient([e(0, 2), e(1, 2), t[2], e(2, 3)]),
        orient([e(0, 3), e(1, 3), e(2, 3), t[3]]),
        orient([m[p], m[q], m[ring[0]], m[ring[1]]]),
        orient([m[p], m[q], m[ring[1]], m[ring[2]]]),
        orient([m[p], m[q], m[ring[2]], m[ring[3]]]),
        orient([m[p], m[q], m[ring[3]], m[ring[0]]]),
    ]
}

/// The global edge order of recursive bisection: longest first, then the sorted endpoints.
fn edge_order(p: Point, q: Point) -> (i64, Point, Point) {
    let (a, b) = if p < q { (p, q) } else { (q, p) };
    (-super::lattice::d2(a, b), a, b)
}

/// A set of lattice points the closure's rules look up.
pub trait PointSet {
    /// Whether `p` is in the set.
    fn has(&self, p: Point) -> bool;
}

impl PointSet for HashSet<Point> {
    fn has(&self, p: Point) -> bool {
        self.contains(&p)
    }
}

/// A set of lattice points as a bit grid over a box, at a power-of-two step: the points the
/// closure can add to a set of leaves are all on it (see [`closure_bits`]).
#[derive(Clone, Debug)]
pub struct PointBits {
    lo: Point,
    hi: Point,
    shift: u32,
    n: [usize; 3],
    bits: Vec<u64>,
}

impl PointBits {
    /// An empty set over the closed box `[lo, hi]`, holding points whose offsets from `lo` are
    /// multiples of `2^shift`.
    pub fn new(lo: Point, hi: Point, shift: u32) -> Self {
        let n: [usize; 3] = std::array::from_fn(|i| ((hi[i] - lo[i]) as usize >> shift) + 1);
        PointBits {
            lo,
            hi,
            shift,
            n,
            bits: vec![0; (n[0] * n[1] * n[2]).div_ceil(64)],
        }
    }

    fn index(&self, p: Point) -> Option<usize> {
        let mask = (1i32 << self.shift) - 1;
        let mut c = [0usize; 3];
        for i in 0..3 {
            let d = p[i] - self.lo[i];
            if p[i] < self.lo[i] || p[i] > self.hi[i] || d & mask != 0 {
                return None;
            }
            c[i] = (d >> self.shift) as usize;
        }
        Some((c[0] * self.n[1] + c[1]) * self.n[2] + c[2])
    }

    /// Adds `p`; returns whether it was new. A point off the grid is a bug of the caller.
    pub fn insert(&mut self, p: Point) -> bool {
        let Some(i) = self.index(p) else {
            debug_assert!(false, "point {p:?} off the grid");
            return false;
        };
        let (w, b) = (i / 64, 1u64 << (i % 64));
        let new = self.bits[w] & b == 0;
        self.bits[w] |= b;
        new
    }
}

impl PointSet for PointBits {
    fn has(&self, p: Point) -> bool {
        self.index(p)
            .is_some_and(|i| self.bits[i / 64] >> (i % 64) & 1 == 1)
    }
}

/// The split-edge mask of `t` (bit `e` for edge `EDGES[e]`): edges whose midpoint is in `v`.
pub fn split_mask(t: &Tet, v: &HashSet<Point>) -> u8 {
    split_mask_in(t, v)
}

/// [`split_mask`] over any [`PointSet`].
pub fn split_mask_in<S: PointSet + ?Sized>(t: &Tet, v: &S) -> u8 {
    let mut s = 0u8;
    for (e, &(a, b)) in EDGES.iter().enumerate() {
        if mid(t[a], t[b]).is_some_and(|m| v.has(m)) {
            s |= 1 << e;
        }
    }
    s
}

/// Whether the closure's face rule refines a tet with split mask `s`: a full face with more.
pub fn face_rule(s: u8) -> bool {
    let full = FACE_EDGES
        .iter()
        .filter(|fe| fe.iter().all(|&e| s >> e & 1 == 1))
        .count();
    full > 0 && !(full == 1 && s.count_ones() == 3)
}

/// Whether the closure's 2:1 balance rule refines `t`: a quarter point of a face is in `v`.
pub fn balance_rule(t: &Tet, v: &HashSet<Point>) -> bool {
    balance_rule_in(t, v)
}

/// [`balance_rule`] over any [`PointSet`].
pub fn balance_rule_in<S: PointSet + ?Sized>(t: &Tet, v: &S) -> bool {
    FACES.iter().any(|f| {
        let (a, b, c) = (t[f[0]], t[f[1]], t[f[2]]);
        QUARTERS.iter().any(|&(i, j, k)| {
            let p: [i64; 3] = std::array::from_fn(|x| {
                i * i64::from(a[x]) + j * i64::from(b[x]) + k * i64::from(c[x])
            });
            p.iter().all(|w| w % 4 == 0)
                && v.has([(p[0] / 4) as i32, (p[1] / 4) as i32, (p[2] / 4) as i32])
        })
    })
}

/// All vertices of the leaves.
pub fn vertices(leaves: &[Leaf]) -> HashSet<Point> {
    let mut v = HashSet::with_capacity_and_hasher(leaves.len(), Default::default());
    for l in leaves {
        v.extend(l.tet);
    }
    v
}

/// Runs the closure to its fixed point; returns how many leaves it red-refined. Full passes
/// over all leaves, each against the vertices at its start: the reference for
/// [`closure_bits`].
pub fn closure(leaves: &mut Vec<Leaf>) -> usize {
    let mut reds = 0;
    loop {
        let v = vertices(leaves);
        let mut next = Vec::with_capacity(leaves.len());
        let mut changed = 0;
        for l in leaves.iter() {
            if refines(l, &v) {
                changed += 1;
                next.extend(red(&l.tet).map(|tet| Leaf {
                    tet,
                    level: l.level - 1,
                }));
            } else {
                next.push(*l);
            }
        }
        if changed == 0 {
            return reds;
        }
        *leaves = next;
        reds += changed;
    }
}

/// Whether the closure red-refines leaf `l` given the vertices `v`.
fn refines<S: PointSet + ?Sized>(l: &Leaf, v: &S) -> bool {
    l.level > 0 && (face_rule(split_mask_in(&l.tet, v)) || balance_rule_in(&l.tet, v))
}

/// [`refines`] when every point of `v` is a lattice point of level `vfine` or coarser. The
/// midpoint of an edge of a body-centred tet of level `l` is a point of level `l - 1` and not
/// of level `l`; a quarter point of one of its faces is not even of level `l - 1` (the tets of
/// level `l - 1` tile the face conformingly with its corners and midpoints only). So with
/// `vfine > l - 1` no edge is split, and with `vfine > l - 2` no quarter point is in `v`.
fn refines_from<S: PointSet + ?Sized>(l: &Leaf, v: &S, vfine: u8) -> bool {
    if l.level == 0 || l.level - 1 < vfine {
        return false;
    }
    face_rule(split_mask_in(&l.tet, v)) || (l.level >= vfine + 2 && balance_rule_in(&l.tet, v))
}

/// [`closure`] on a worklist, returning the red refinements and the final leaves' vertices
/// (the leaves' order changes: a refined leaf's first child takes its place, the others are
/// appended).
///
/// The same result as the full passes of [`closure`]: the rules are monotone in the vertex
/// set, which refinement only grows, so every refinement made here is one the least fixed
/// point makes, and the loop stops at a fixed point. A leaf's rules read only points on its
/// closed bounding box, so after the first pass only the leaves whose box meets a cell (of a
/// coarse grid) that received a new vertex are checked again. The first pass itself checks
/// only the leaves whose box meets a cell holding a vertex of a finer leaf: the points the
/// rules of a leaf of level `l` read are not of level `l`, so only leaves of levels `< l` have
/// them as vertices.
///
/// The vertex set is a bit grid: with `m` the finest leaf level, the closure adds vertices of
/// level `m - 1` at the finest (the rules need a vertex of level `< l - 1` to refine a leaf of
/// level `l`), so every vertex is on the grid of step `2^(m - 1)` (`2^0` for `m = 0`) over the
/// leaves' bounding box (refinement stays inside its tet).
pub fn closure_bits(leaves: &mut Vec<Leaf>) -> (usize, PointBits) {
    let Some(first) = leaves.first() else {
        return (0, PointBits::new([0; 3], [0; 3], 0));
    };
    let (mut lo, mut hi) = (first.tet[0], first.tet[0]);
    let mut finest = first.level;
    for l in leaves.iter() {
        finest = finest.min(l.level);
        for p in &l.tet {
            for i in 0..3 {
                lo[i] = lo[i].min(p[i]);
                hi[i] = hi[i].max(p[i]);
            }
        }
    }
    let shift = u32::from(finest.saturating_sub(1));
    let mut v = PointBits::new(lo, hi, shift);
    // Dirty cells: a coarse grid (step 2^(shift + 3)) marking where new vertices landed.
    let cshift = shift + 3;
    let cn: [usize; 3] = std::array::from_fn(|i| ((hi[i] - lo[i]) as usize >> cshift) + 1);
    let cell = |p: Point, i: usize| ((p[i] - lo[i]) >> cshift) as usize;
    // Per coarse cell, the finest level of a leaf with a vertex there. The points a leaf of
    // level l reads (split-edge midpoints: level l - 1 and not l; quarter points: not even
    // l - 1) are vertices of leaves of levels < l only, and lie on its bounding box: a leaf
    // whose box meets no cell holding a vertex of a finer leaf keeps its rules false in the
    // first pass.
    let mut finer = vec![u8::MAX; cn[0] * cn[1] * cn[2]];
    for l in leaves.iter() {
        for p in l.tet {
            v.insert(p);
            let c = &mut finer[(cell(p, 0) * cn[1] + cell(p, 1)) * cn[2] + cell(p, 2)];
            *c = (*c).min(l.level);
        }
    }
    let mut dirty = vec![false; cn[0] * cn[1] * cn[2]];
    let mut next_dirty = dirty.clone();
    let mut reds = 0;
    let mut first_pass = true;
    // The finest level of a point in `v` (a midpoint of a level-l edge is of level l - 1).
    let mut vfine = finest;
    loop {
        let mut changed = 0;
        let n = leaves.len();
        for i in 0..n {
            let l = leaves[i];
            if l.level == 0 || l.level - 1 < vfine {
                continue;
            }
            let (a, b) = super::lattice::bbox(&l.tet);
            let mut hit = false;
            'cells: for x in cell(a, 0)..=cell(b, 0) {
                for y in cell(a, 1)..=cell(b, 1) {
                    for z in cell(a, 2)..=cell(b, 2) {
                        let c = (x * cn[1] + y) * cn[2] + z;
                        if (first_pass && finer[c] < l.level) || (!first_pass && dirty[c]) {
                            hit = true;
                            break 'cells;
                        }
                    }
                }
            }
            if !hit {
                continue;
            }
            if refines_from(&l, &v, vfine) {
                changed += 1;
                vfine = vfine.min(l.level - 1);
                for &(a, b) in &EDGES {
                    let m = half(l.tet[a], l.tet[b]);
                    if v.insert(m) {
                        next_dirty[(cell(m, 0) * cn[1] + cell(m, 1)) * cn[2] + cell(m, 2)] = true;
                    }
                }
                let kids = red(&l.tet);
                leaves[i] = Leaf {
                    tet: kids[0],
                    level: l.level - 1,
                };
                leaves.extend(kids[1..].iter().map(|&tet| Leaf {
                    tet,
                    level: l.level - 1,
                }));
            }
        }
        if changed == 0 {
            return (reds, v);
        }
        reds += changed;
        first_pass = false;
        std::mem::swap(&mut dirty, &mut next_dirty);
        next_dirty.iter_mut().for_each(|d| *d = false);
    }
}

/// The green template for split mask `s` (no full face with more, see [`face_rule`]), appended
/// to `out` with the template's kind.
pub fn green(t: &Tet, s: u8, out: &mut Vec<(Tet, TetKind)>) -> Result<(), LodError> {
    if s == 0 {
        out.push((*t, TetKind::Bcc));
        return Ok(());
    }
    if face_rule(s) {
        return Err(LodError::Closure(format!(
            "split mask {s:06b} of {t:?} has no green template"
        )));
    }
    if let Some(fi) = (0..4).find(|&fi| FACE_EDGES[fi].iter().all(|&e| s >> e & 1 == 1)) {
        let d = t[fi];
        let [a, b, c] = FACES[fi].map(|i| t[i]);
        let (mab, mbc, mca) = (half(a, b), half(b, c), half(c, a));
        for tri in [[a, mab, mca], [mab, b, mbc], [mca, mbc, c], [mab, mbc, mca]] {
            out.push((orient([tri[0], tri[1], tri[2], d]), TetKind::Cone));
        }
        return Ok(());
    }
    let mut edges: Vec<(Point, Point)> = (0..6)
        .filter(|&e| s >> e & 1 == 1)
        .map(|e| (t[EDGES[e].0], t[EDGES[e].1]))
        .collect();
    let n = edges.len() as u8;
    bisect(*t, &mut edges, n, out);
    Ok(())
}

fn bisect(t: Tet, edges: &mut Vec<(Point, Point)>, n: u8, out: &mut Vec<(Tet, TetKind)>) {
    let Some(first) = (0..edges.len()).min_by_key(|&k| edge_order(edges[k].0, edges[k].1)) else {
        out.push((t, TetKind::Bisect(n)));
        return;
    };
    let (p, q) = edges.swap_remove(first);
    let m = half(p, q);
    for (from, to) in [(q, m), (p, m)] {
        let child = orient(t.map(|x| if x == from { to } else { x }));
        let mut mine: Vec<(Point, Point)> = edges
            .iter()
            .copied()
            .filter(|(a, b)| child.contains(a) && child.contains(b))
            .collect();
        bisect(child, &mut mine, n, out);
    }
}

#[cfg(test)]
mod tests {
    use super::super::lattice::{bcc_tet, d2, is_bcc_tet, vol6};
    use super::*;
    use foldhash::HashMap;

    /// The outward faces of a positively oriented tet, in cyclic order.
    fn faces(t: &Tet) -> [[Point; 3]; 4] {
        [
            [t[1], t[2], t[3]],
            [t[0], t[3], t[2]],
            [t[0], t[1], t[3]],
            [t[0], t[2], t[1]],
        ]
    }

    fn sorted(mut f: [Point; 3]) -> [Point; 3] {
        f.sort_unstable();
        f
    }

    fn normal(f: &[Point; 3]) -> [i64; 3] {
        let u: [i64; 3] = std::array::from_fn(|i| i64::from(f[1][i] - f[0][i]));
        let v: [i64; 3] = std::array::from_fn(|i| i64::from(f[2][i] - f[0][i]));
        [
            u[1] * v[2] - u[2] * v[1],
            u[2] * v[0] - u[0] * v[2],
            u[0] * v[1] - u[1] * v[0],
        ]
    }

    fn dot(a: [i64; 3], b: [i64; 3]) -> i64 {
        a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
    }

    /// The face rule written independently of the templates: how a face `abc` with the given
    /// split edges (as endpoint pairs) is triangulated (unoriented, sorted triples).
    fn face_split(f: [Point; 3], split: &[(Point, Point)]) -> Vec<[Point; 3]> {
        let [a, b, c] = f;
        let has = |p: Point, q: Point| {
            split
                .iter()
                .any(|&(x, y)| (x, y) == (p, q) || (x, y) == (q, p))
        };
        let mut out = match split.len() {
            0 => vec![[a, b, c]],
            1 => {
                let (p, q) = split[0];
                let o = *f.iter().find(|x| **x != p && **x != q).unwrap();
                let m = half(p, q);
                vec![[p, m, o], [m, q, o]]
            }
            2 => {
                let (e1, e2) =
                    if edge_order(split[0].0, split[0].1) < edge_order(split[1].0, split[1].1) {
                        (split[0], split[1])
                    } else {
                        (split[1], split[0])
                    };
                // v shared by both edges; the first edge's far end x, the second's y.
                let v = if e1.0 == e2.0 || e1.0 == e2.1 {
                    e1.0
                } else {
                    e1.1
                };
                let x = if e1.0 == v { e1.1 } else { e1.0 };
                let y = if e2.0 == v { e2.1 } else { e2.0 };
                let (m1, m2) = (half(v, x), half(v, y));
                // First cut: m1 to y; then the part holding e2 = (v, m1, y) is cut at m2.
                vec![[m1, x, y], [v, m1, m2], [m1, m2, y]]
            }
            _ => {
                assert!(has(a, b) && has(b, c) && has(c, a));
                let (mab, mbc, mca) = (half(a, b), half(b, c), half(c, a));
                vec![[a, mab, mca], [mab, b, mbc], [mca, mbc, c], [mab, mbc, mca]]
            }
        };
        for t in &mut out {
            t.sort_unstable();
        }
        out.sort_unstable();
        out
    }

    /// Checks that `kids` tile `t` conformingly: positive volumes adding up to `t`'s, every
    /// inner face shared by two kids with opposite orientation, and each face of `t` cut by
    /// the face rule for `split` (which are the split edges).
    fn check_tiles(t: &Tet, kids: &[Tet], split: &[(Point, Point)]) {
        assert!(kids.iter().all(|k| vol6(k) > 0), "{t:?} {kids:?}");
        assert_eq!(kids.iter().map(vol6).sum::<i64>(), vol6(t));
        let allowed: HashSet<Point> = t
            .iter()
            .copied()
            .chain(split.iter().map(|&(p, q)| half(p, q)))
            .collect();
        let used: HashSet<Point> = kids.iter().flatten().copied().collect();
        assert_eq!(
            used, allowed,
            "kids use exactly the corners and the split midpoints"
        );
        let mut count: HashMap<[Point; 3], Vec<[Point; 3]>> = HashMap::default();
        for k in kids {
            for f in faces(k) {
                count.entry(sorted(f)).or_default().push(f);
            }
        }
        let mut on_face: [Vec<[Point; 3]>; 4] = Default::default();
        for (key, fs) in &count {
            match fs.len() {
                1 => {
                    // On a face of t, facing the same way.
                    let n = normal(&fs[0]);
                    let which = faces(t).iter().position(|pf| {
                        let pn = normal(pf);
                        (0..3).all(|i| {
                            dot(pn, std::array::from_fn(|x| i64::from(key[i][x] - pf[0][x]))) == 0
                        }) && dot(pn, n) > 0
                    });
                    let which =
                        which.unwrap_or_else(|| panic!("inner face {key:?} of {t:?} has one tet"));
                    on_face[which].push(*key);
                }
                2 => assert!(
                    dot(normal(&fs[0]), normal(&fs[1])) < 0,
                    "face {key:?} shared with the same orientation"
                ),
                n => panic!("face {key:?} in {n} kids"),
            }
        }
        for (fi, pf) in faces(t).iter().enumerate() {
            let fsplit: Vec<(Point, Point)> = split
                .iter()
                .copied()
                .filter(|(p, q)| pf.contains(p) && pf.contains(q))
                .collect();
            let mut got = on_face[fi].clone();
            got.sort_unstable();
            assert_eq!(got, face_split(*pf, &fsplit), "face {fi} of {t:?}");
        }
    }

    fn sample_tets() -> Vec<(Tet, u8)> {
        let mut out = Vec::new();
        for level in 1..=3u8 {
            for cell in [[0, 0, 0], [-1, 2, 3], [5, -4, 1]] {
                for axis in 0..3 {
                    for m in 0..4 {
                        out.push((bcc_tet(level, cell, axis, m), level));
                    }
                }
            }
        }
        out
    }

    #[test]
    fn red_gives_the_eight_finer_body_centred_tets() {
        for (t, level) in sample_tets() {
            let kids = red(&t);
            assert!(kids.iter().all(|k| is_bcc_tet(k, level - 1)), "{t:?}");
            let all: Vec<(Point, Point)> = EDGES.iter().map(|&(a, b)| (t[a], t[b])).collect();
            check_tiles(&t, &kids, &all);
            // The octahedron's cut is the unique shortest diagonal.
            let m: Vec<Point> = EDGES.iter().map(|&(a, b)| half(t[a], t[b])).collect();
            let mut lens = [d2(m[0], m[5]), d2(m[1], m[4]), d2(m[2], m[3])];
            lens.sort_unstable();
            assert!(lens[0] < lens[1]);
        }
    }

    #[test]
    fn red_refinement_reproduces_the_finer_lattice() {
        // All level-1 tets across the faces of a 3^3 block of cells, refined: exactly the
        // level-0 tets of the same faces' region, each once.
        let mut kids: Vec<Tet> = Vec::new();
        let mut parents = 0;
        for x in 0..3 {
            for y in 0..3 {
                for z in 0..3 {
                    for axis in 0..3 {
                        for m in 0..4 {
                            parents += 1;
                            kids.extend(red(&bcc_tet(1, [x, y, z], axis, m)).map(|k| {
                                let mut s = k;
                                s.sort_unstable();
                                s
                            }));
                        }
                    }
                }
            }
        }
        let distinct: HashSet<Tet> = kids.iter().copied().collect();
        assert_eq!(distinct.len(), 8 * parents);
        // Every level-0 tet whose centroid lies in the refined region is among them: count
        // the level-0 tets inside each parent by containment of the centroid.
        let mut fine = 0;
        for x in -1..8 {
            for y in -1..8 {
                for z in -1..8 {
                    for axis in 0..3 {
                        for m in 0..4 {
                            let mut f = bcc_tet(0, [x, y, z], axis, m);
                            f.sort_unstable();
                            if distinct.contains(&f) {
                                fine += 1;
                            }
                        }
                    }
                }
            }
        }
        assert_eq!(fine, 8 * parents);
    }

    #[test]
    fn every_green_template_tiles_its_tet_and_follows_the_face_rule() {
        let mut cases = [0usize; 3];
        for (t, _) in sample_tets() {
            for s in 0u8..64 {
                let mut out = Vec::new();
                let r = green(&t, s, &mut out);
                if face_rule(s) {
                    assert!(r.is_err());
                    continue;
                }
                assert!(r.is_ok());
                let split: Vec<(Point, Point)> = (0..6)
                    .filter(|&e| s >> e & 1 == 1)
                    .map(|e| (t[EDGES[e].0], t[EDGES[e].1]))
                    .collect();
                let kids: Vec<Tet> = out.iter().map(|k| k.0).collect();
                check_tiles(&t, &kids, &split);
                match out[0].1 {
                    TetKind::Bcc => cases[0] += 1,
                    TetKind::Cone => cases[1] += 1,
                    TetKind::Bisect(n) => {
                        assert_eq!(u32::from(n), s.count_ones());
                        cases[2] += 1
                    }
                }
            }
        }
        // Per tet: the empty mask, the 4 single faces, and every mask without a full face.
        let no_full = (1u8..64)
            .filter(|&s| {
                !FACE_EDGES
                    .iter()
                    .any(|fe| fe.iter().all(|&e| s >> e & 1 == 1))
            })
            .count();
        let n = sample_tets().len();
        assert_eq!(cases, [n, 4 * n, no_full * n]);
    }

    #[test]
    fn closure_rules() {
        let t = bcc_tet(1, [0, 0, 0], 0, 0);
        // A face with more: refine; exactly one face: cone.
        assert!(face_rule(0b111111));
        assert!(!face_rule(
            1 << FACE_EDGES[0][0] | 1 << FACE_EDGES[0][1] | 1 << FACE_EDGES[0][2]
        ));
        assert!(face_rule(
            1 << FACE_EDGES[0][0] | 1 << FACE_EDGES[0][1] | 1 << FACE_EDGES[0][2] | 1 << 0
        ));
        // A quarter point of a face in V forces balance refinement; a midpoint does not.
        let [a, b, c] = FACES[0].map(|i| t[i]);
        let q: Point = std::array::from_fn(|x| (a[x] * 2 + b[x] + c[x]) / 4);
        assert!((0..3).all(|x| (a[x] * 2 + b[x] + c[x]) % 4 == 0));
        assert!(balance_rule(&t, &[q].into_iter().collect()));
        assert!(!balance_rule(&t, &[half(a, b)].into_iter().collect()));
        let v: HashSet<Point> = [half(a, b)].into_iter().collect();
        assert_eq!(split_mask(&t, &v).count_ones(), 1);
    }
}
