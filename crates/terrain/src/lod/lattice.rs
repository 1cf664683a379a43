//! Integer body-centred lattices of every level, and exact tetrahedron arithmetic.
//!
//! Coordinates are integers in units of `u = h / 2` (`h` the finest cell edge), so every vertex
//! the multiresolution mesh uses, at every level, is exact:
//!
//! ```text
//!   level l: cell edge s = 2^(l+1) u, half cell hs = 2^l u
//!     corners  s * Z^3            centres  s * Z^3 + hs
//!   level 0 (s = 2):  corners all even,  centres all odd
//!   level 1 (s = 4):  corners 4Z^3,      centres 4Z^3 + 2   (all level-0 corners)
//! ```
//!
//! Coarse corners and coarse centres are fine corners, so samples nest: a coarse sample is a
//! fine sample.
//!
//! A body-centred tetrahedron of level `l` spans one cube face: the two cube centres `c` and
//! `c + s e_a` beside the face and two consecutive corners `Q_m`, `Q_{m+1}` of the face
//! (the face's corners in cyclic order; `a` the axis, `m` in `0..4`):
//!
//! ```text
//!        Q1 ------ Q0          c . . . F . . . c + s e_a     F = c + hs e_a (face centre)
//!        |    F    |                 (the face, seen along a)
//!        Q2 ------ Q3          tets: (c, c + s e_a, Q_m, Q_{m+1})
//! ```

/// A lattice point in `u` units.
pub type Point = [i32; 3];

/// A tetrahedron: four lattice points, positively oriented (see [`vol6`]).
pub type Tet = [Point; 4];

/// The six edges of a tetrahedron, as vertex index pairs.
pub const EDGES: [(usize, usize); 6] = [(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)];

/// The four faces of a tetrahedron; face `i` is opposite vertex `i`.
pub const FACES: [[usize; 3]; 4] = [[1, 2, 3], [0, 2, 3], [0, 1, 3], [0, 1, 2]];

/// Cell edge of level `level` in `u`: `2^(level + 1)`.
pub fn cell_size(level: u8) -> i64 {
    2i64 << level
}

/// Six times the signed volume: `det(b - a, c - a, d - a)`, exact.
pub fn vol6(t: &Tet) -> i64 {
    let s = |p: Point, q: Point| {
        [
            i64::from(q[0]) - i64::from(p[0]),
            i64::from(q[1]) - i64::from(p[1]),
            i64::from(q[2]) - i64::from(p[2]),
        ]
    };
    let (b, c, d) = (s(t[0], t[1]), s(t[0], t[2]), s(t[0], t[3]));
    b[0] * (c[1] * d[2] - c[2] * d[1]) - b[1] * (c[0] * d[2] - c[2] * d[0])
        + b[2] * (c[0] * d[1] - c[1] * d[0])
}

/// The tetrahedron's canonical form: vertices sorted, the last two swapped when that makes the
/// volume positive. Two tetrahedra with the same vertex set have the same canonical form, so
/// whatever derives from the vertex order (marching tetrahedra's quad diagonal) is a function of
/// the tetrahedron alone.
pub fn canonical(mut t: Tet) -> Tet {
    t.sort_unstable();
    if vol6(&t) < 0 {
        t.swap(2, 3);
    }
    t
}

/// Positively oriented: swaps the first two vertices when the volume is negative.
pub fn orient(mut t: Tet) -> Tet {
    if vol6(&t) < 0 {
        t.swap(0, 1);
    }
    t
}

/// The midpoint of `p` and `q` when it is a lattice point.
pub fn mid(p: Point, q: Point) -> Option<Point> {
    let s = [p[0] + q[0], p[1] + q[1], p[2] + q[2]];
    if s.iter().all(|v| v % 2 == 0) {
        Some([s[0] / 2, s[1] / 2, s[2] / 2])
    } else {
        None
    }
}

/// Squared distance.
pub fn d2(p: Point, q: Point) -> i64 {
    (0..3)
        .map(|i| {
            let d = i64::from(p[i]) - i64::from(q[i]);
            d * d
        })
        .sum()
}

/// The body-centred tetrahedron of `level` across face `axis` of `cell` (between `cell` and
/// `cell + e_axis`), the `m`-th of the face's four (`axis < 3`, `m < 4`), positively oriented.
pub fn bcc_tet(level: u8, cell: Point, axis: usize, m: usize) -> Tet {
    let s = 2i32 << level;
    let hs = 1i32 << level;
    let c = [s * cell[0] + hs, s * cell[1] + hs, s * cell[2] + hs];
    let mut b = c;
    b[axis] += s;
    let mut f = c;
    f[axis] += hs;
    let (p, q) = ((axis + 1) % 3, (axis + 2) % 3);
    const SIGNS: [(i32, i32); 4] = [(1, 1), (-1, 1), (-1, -1), (1, -1)];
    let corner = |k: usize| {
        let mut x = f;
        x[p] += SIGNS[k].0 * hs;
        x[q] += SIGNS[k].1 * hs;
        x
    };
    orient([c, b, corner(m), corner((m + 1) % 4)])
}

/// Whether `t` (any vertex order) is a body-centred tetrahedron of `level`.
pub fn is_bcc_tet(t: &Tet, level: u8) -> bool {
    let s = 2i32 << level;
    let hs = 1i32 << level;
    let is = |p: &Point, r: i32| p.iter().all(|v| v.rem_euclid(s) == r);
    let centres: Vec<Point> = t.iter().copied().filter(|p| is(p, hs)).collect();
    let corners: Vec<Point> = t.iter().copied().filter(|p| is(p, 0)).collect();
    if centres.len() != 2 || corners.len() != 2 {
        return false;
    }
    let Some(axis) = (0..3).find(|&a| centres[0][a] != centres[1][a]) else {
        return false;
    };
    let lo = if centres[0][axis] < centres[1][axis] {
        centres[0]
    } else {
        centres[1]
    };
    let cell = [
        (lo[0] - hs).div_euclid(s),
        (lo[1] - hs).div_euclid(s),
        (lo[2] - hs).div_euclid(s),
    ];
    let mut want = *t;
    want.sort_unstable();
    (0..4).any(|m| {
        let mut b = bcc_tet(level, cell, axis, m);
        b.sort_unstable();
        b == want
    })
}

/// The closed bounding box `(lo, hi)`.
pub fn bbox(t: &Tet) -> (Point, Point) {
    let mut lo = t[0];
    let mut hi = t[0];
    for p in &t[1..] {
        for i in 0..3 {
            lo[i] = lo[i].min(p[i]);
            hi[i] = hi[i].max(p[i]);
        }
    }
    (lo, hi)
}

/// Four times the centroid (exact): the point that decides which chunk owns a tetrahedron.
pub fn centroid4(t: &Tet) -> [i64; 3] {
    let mut c = [0i64; 3];
    for p in t {
        for i in 0..3 {
            c[i] += i64::from(p[i]);
        }
    }
    c
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bcc_tets_have_the_body_centred_volume_and_are_recognised() {
        for level in 0..4u8 {
            let s = cell_size(level);
            for axis in 0..3 {
                for m in 0..4 {
                    let t = bcc_tet(level, [1, -2, 3], axis, m);
                    // 12 tets per cube (6 faces x 4 tets, each shared by 2 cubes): V = s^3 / 12.
                    assert_eq!(vol6(&t), s * s * s / 2);
                    assert!(is_bcc_tet(&t, level));
                    assert!(!is_bcc_tet(&t, level + 1));
                    let c = canonical(t);
                    assert!(vol6(&c) > 0 && is_bcc_tet(&c, level));
                }
            }
        }
        // A level-1 tet is not a level-0 tet even though its points are level-0 points.
        assert!(!is_bcc_tet(&bcc_tet(1, [0, 0, 0], 0, 0), 0));
    }

    #[test]
    fn midpoints_are_exact_or_none() {
        assert_eq!(mid([0, 0, 0], [2, 4, -6]), Some([1, 2, -3]));
        assert_eq!(mid([0, 0, 0], [1, 1, 1]), None);
    }
}
