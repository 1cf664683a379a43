//! Lattice tables, derived from geometry.
//!
//! Both lattices give every sample point 14 neighbours, so the facts about a point's edges fit in
//! one 16-bit word (bit `i` = neighbour `i`). Everything here is computed from the offsets and the
//! tetrahedra, never typed in: the tests compare the results with the constants of
//! `rmt-spec.md`.
//!
//! ```text
//!  body-centred (half-cube units)          simple cubic, Kuhn split (cube units)
//!     o-------o      o corner (even)           6-------7     every cube cut along its
//!    /|  x   /|      x centre (odd)           /|      /|     main diagonal 0-7 into six
//!   o-------o |      axial neighbour: +-2    4-------5 |     tetrahedra (0,1,3,7), (0,3,2,7),
//!   | o-----|-o      diagonal: (+-1,+-1,+-1)  | 2-----|-3     (0,2,6,7), (0,6,4,7),
//!   |/      |/                               |/      |/      (0,4,5,7), (0,5,1,7)
//!   o-------o                                0-------1
//! ```

use std::sync::OnceLock;

use crate::Lattice;

/// All 14 neighbour bits.
pub(crate) const FULL: u16 = 0x3FFF;

/// An integer offset or position on a lattice (half-cube units for the body-centred lattice).
pub type Offset = [i32; 3];

/// The derived tables of one lattice.
#[derive(Clone, Debug)]
pub struct LatticeTables {
    /// The 14 neighbour offsets, in the order of `rmt-spec.md`.
    pub offsets: [Offset; 14],
    /// Bit `j` of `link_masks[i]`: neighbours `i` and `j` are adjacent (lie in one tetrahedron
    /// with the point), i.e. `offsets[i] - offsets[j]` is itself a neighbour offset.
    pub link_masks: [u16; 14],
    /// `offsets[reverse[i]] == -offsets[i]`.
    pub reverse: [u8; 14],
    /// Tetrahedron templates, each positively oriented (det > 0). Body-centred: the 4 tetrahedra
    /// around one face for each axis, relative to the centre `A` below the face
    /// (`tetrahedra[4 * axis + m]`); simple: the 6 tetrahedra of the cube at the origin.
    pub tetrahedra: Vec<[Offset; 4]>,
    /// For every 14-bit mask, its island holding the lowest set bit (0 for the empty mask):
    /// [`LatticeTables::islands`] is a few table lookups (computed once, 32 KiB).
    first_island: Vec<u16>,
    /// Bit `mask` set: the crossings on the edges `mask` from one point, with the marching
    /// tetrahedra edges and triangles among them, form a contractible complex (see
    /// [`LatticeTables::is_contractible`]; 2 KiB).
    contractible: Vec<u64>,
}

impl LatticeTables {
    /// The tables of `lattice` (computed once).
    pub fn get(lattice: Lattice) -> &'static LatticeTables {
        static BCDL: OnceLock<LatticeTables> = OnceLock::new();
        static SIMPLE: OnceLock<LatticeTables> = OnceLock::new();
        match lattice {
            Lattice::BodyCentred => {
                BCDL.get_or_init(|| Self::derive(bcdl_offsets(), bcdl_tetrahedra()))
            }
            Lattice::Simple => {
                SIMPLE.get_or_init(|| Self::derive(simple_offsets(), simple_tetrahedra()))
            }
        }
    }

    fn derive(offsets: [Offset; 14], tetrahedra: Vec<[Offset; 4]>) -> Self {
        let index_of = |o: Offset| offsets.iter().position(|&x| x == o);
        let mut link_masks = [0u16; 14];
        let mut reverse = [0u8; 14];
        for i in 0..14 {
            for j in 0..14 {
                if i != j && index_of(sub(offsets[i], offsets[j])).is_some() {
                    link_masks[i] |= 1 << j;
                }
            }
            reverse[i] = index_of(neg(offsets[i])).map_or(u8::MAX, |r| r as u8);
        }
        let first_island: Vec<u16> = (0..=cluster_mask())
            .map(|mask| grow_island(&link_masks, mask))
            .collect();
        let contractible = contractible_masks(&link_masks, &first_island);
        Self {
            offsets,
            link_masks,
            reverse,
            tetrahedra,
            first_island,
            contractible,
        }
    }

    /// The neighbour index of offset `o`, if it is one.
    pub fn direction(&self, o: Offset) -> Option<usize> {
        self.offsets.iter().position(|&x| x == o)
    }

    /// Splits `mask` into its connected parts in the link graph, lowest bit first.
    ///
    /// ```
    /// use rmt_extract::{lattice::LatticeTables, Lattice};
    /// let t = LatticeTables::get(Lattice::BodyCentred);
    /// // +x and -x axial neighbours are not adjacent: two islands.
    /// assert_eq!(t.islands(0b11).count(), 2);
    /// ```
    pub fn islands(&self, mask: u16) -> impl Iterator<Item = u16> + '_ {
        let mut rest = mask & cluster_mask();
        std::iter::from_fn(move || {
            if rest == 0 {
                return None;
            }
            let island = self.first_island[rest as usize];
            rest &= !island;
            Some(island)
        })
    }

    /// Whether `mask` is non-empty and connected in the link graph.
    pub fn is_connected(&self, mask: u16) -> bool {
        mask != 0 && self.islands(mask).nth(1).is_none()
    }

    /// Whether the crossings on the edges `mask` from one point `C` (every edge crossed, `C`
    /// an inner point), with the marching tetrahedra edges and triangles among them, form a
    /// contractible complex: connected, with Euler characteristic 1. Those edges and
    /// triangles are fixed by `mask` alone: the crossings on edges `CA` and `CB` are joined by
    /// an MT edge exactly when `A` and `B` are adjacent in the link (the surface cuts the
    /// face `CAB`, where `C` is alone on its side, along that edge; a quad's diagonal never
    /// joins two of `C`'s edges, which are neighbours on the quad), and three of them bound an
    /// MT triangle exactly when `A`, `B`, `D` span a triangle of the link (the tetrahedron
    /// `CABD` with `C` alone on its side). So V - E + F is counted on the link graph: test (a)
    /// of the quotient test for a group of one point's crossings, by table.
    pub fn is_contractible(&self, mask: u16) -> bool {
        let m = usize::from(mask & cluster_mask());
        self.contractible[m / 64] >> (m % 64) & 1 != 0
    }
}

/// The table of [`LatticeTables::is_contractible`]: one bit per 14-bit mask.
fn contractible_masks(link_masks: &[u16; 14], first_island: &[u16]) -> Vec<u64> {
    // The triangles of the link (3-cliques: the tetrahedra around the point), as masks.
    let mut triangles = Vec::new();
    for i in 0..14 {
        for j in i + 1..14 {
            for k in j + 1..14 {
                let adjacent = |a: usize, b: usize| link_masks[a] >> b & 1 != 0;
                if adjacent(i, j) && adjacent(j, k) && adjacent(i, k) {
                    triangles.push((1u16 << i) | (1 << j) | (1 << k));
                }
            }
        }
    }
    let mut table = vec![0u64; (1usize << 14) / 64];
    for mask in 1..=cluster_mask() {
        if first_island[usize::from(mask)] != mask {
            continue;
        }
        let v = mask.count_ones() as i32;
        let e = (0..14)
            .filter(|&i| mask >> i & 1 != 0)
            .map(|i| (link_masks[i] & mask).count_ones() as i32)
            .sum::<i32>()
            / 2;
        let f = triangles.iter().filter(|&&t| t & mask == t).count() as i32;
        if v - e + f == 1 {
            table[usize::from(mask) / 64] |= 1 << (mask % 64);
        }
    }
    table
}

/// The 14 neighbour bits.
const fn cluster_mask() -> u16 {
    (1 << 14) - 1
}

/// The island of `mask` (in the link graph `link_masks`) holding its lowest set bit.
fn grow_island(link_masks: &[u16; 14], mask: u16) -> u16 {
    if mask == 0 {
        return 0;
    }
    let mut island = mask & mask.wrapping_neg();
    loop {
        let mut grown = island;
        let mut bits = island;
        while bits != 0 {
            let i = bits.trailing_zeros() as usize;
            bits &= bits - 1;
            grown |= link_masks[i] & mask;
        }
        if grown == island {
            return island;
        }
        island = grown;
    }
}

/// Body-centred neighbours: 6 axial (one cube edge, same kind of point), then 8 diagonal (half a
/// cube diagonal, the other kind), signs enumerated x slowest.
fn bcdl_offsets() -> [Offset; 14] {
    let mut o = [[0; 3]; 14];
    for a in 0..3 {
        o[2 * a][a] = 2;
        o[2 * a + 1][a] = -2;
    }
    for i in 0..8 {
        let s = |bit: usize| if i & (1 << bit) == 0 { 1 } else { -1 };
        o[6 + i] = [s(2), s(1), s(0)];
    }
    o
}

/// Simple-cubic neighbours, in pairs `(v, -v)`; the tests check that this is exactly the set of
/// edges of the Kuhn tetrahedra at a point.
fn simple_offsets() -> [Offset; 14] {
    const HALF: [Offset; 7] = [
        [1, 0, 0],
        [0, 1, 0],
        [0, 0, 1],
        [1, 1, 0],
        [1, 0, 1],
        [0, 1, 1],
        [1, 1, 1],
    ];
    let mut o = [[0; 3]; 14];
    for (i, v) in HALF.iter().enumerate() {
        o[2 * i] = *v;
        o[2 * i + 1] = neg(*v);
    }
    o
}

/// The 12 body-centred tetrahedra of one cell, as 3 axes x 4: for axis triple (a, b, d), A = the
/// centre, B = A + 2 e_a (next centre), Q_m = A + e_a + s e_b + t e_d with (s, t) = (+,+), (-,+),
/// (-,-), (+,-); tetrahedron (A, B, Q_m, Q_(m+1)). Relative to A.
fn bcdl_tetrahedra() -> Vec<[Offset; 4]> {
    let mut tets = Vec::with_capacity(12);
    for a in 0..3 {
        let (b, d) = ((a + 1) % 3, (a + 2) % 3);
        let q = |s: i32, t: i32| {
            let mut p = [0; 3];
            p[a] = 1;
            p[b] = s;
            p[d] = t;
            p
        };
        let qs = [q(1, 1), q(-1, 1), q(-1, -1), q(1, -1)];
        let mut bb = [0; 3];
        bb[a] = 2;
        for m in 0..4 {
            tets.push([[0; 3], bb, qs[m], qs[(m + 1) % 4]]);
        }
    }
    tets
}

/// Kuhn's 6 tetrahedra of the unit cube, corner `n = x + 2y + 4z`, all around the diagonal 0-7.
fn simple_tetrahedra() -> Vec<[Offset; 4]> {
    const CORNERS: [[usize; 4]; 6] = [
        [0, 1, 3, 7],
        [0, 3, 2, 7],
        [0, 2, 6, 7],
        [0, 6, 4, 7],
        [0, 4, 5, 7],
        [0, 5, 1, 7],
    ];
    let corner = |n: usize| [(n & 1) as i32, ((n >> 1) & 1) as i32, ((n >> 2) & 1) as i32];
    CORNERS.iter().map(|c| c.map(corner)).collect()
}

fn sub(a: Offset, b: Offset) -> Offset {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn neg(a: Offset) -> Offset {
    [-a[0], -a[1], -a[2]]
}

/// Determinant of `[b - a, c - a, d - a]`: six times the signed volume.
pub fn det(t: &[Offset; 4]) -> i64 {
    let [a, b, c, d] = *t;
    let u = sub(b, a).map(i64::from);
    let v = sub(c, a).map(i64::from);
    let w = sub(d, a).map(i64::from);
    u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0])
        + u[2] * (v[0] * w[1] - v[1] * w[0])
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::HashMap;

    const BCDL_MASKS: [u16; 14] = [
        0x03C0, 0x3C00, 0x0CC0, 0x3300, 0x1540, 0x2A80, 0x0595, 0x0A65, 0x1259, 0x21A9, 0x1856,
        0x24A6, 0x251A, 0x1A2A,
    ];
    const SIMPLE_MASKS: [u16; 14] = [
        0x1968, 0x2694, 0x1662, 0x2991, 0x158A, 0x2A45, 0x1025, 0x201A, 0x1019, 0x2026, 0x1016,
        0x2029, 0x0555, 0x0AAA,
    ];

    fn both() -> [(Lattice, &'static LatticeTables); 2] {
        [Lattice::BodyCentred, Lattice::Simple].map(|l| (l, LatticeTables::get(l)))
    }

    #[test]
    fn island_table_partitions_every_mask_into_connected_parts() {
        for lattice in [Lattice::BodyCentred, Lattice::Simple] {
            let t = LatticeTables::get(lattice);
            for mask in 0..=cluster_mask() {
                let parts: Vec<u16> = t.islands(mask).collect();
                // Disjoint, covering the mask, each connected, none adjacent to another.
                assert_eq!(parts.iter().fold(0, |a, &p| a | p), mask);
                assert_eq!(
                    parts.iter().map(|p| p.count_ones()).sum::<u32>(),
                    mask.count_ones()
                );
                for (i, &p) in parts.iter().enumerate() {
                    assert_eq!(
                        grow_island(&t.link_masks, p),
                        p,
                        "{mask:#x}: {p:#x} not connected"
                    );
                    let touching = (0..14)
                        .filter(|&b| p & (1 << b) != 0)
                        .fold(0u16, |a, b| a | t.link_masks[b]);
                    for &q in &parts[i + 1..] {
                        assert_eq!(
                            touching & q,
                            0,
                            "{mask:#x}: islands {p:#x} and {q:#x} touch"
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn link_masks_match_the_spec() {
        assert_eq!(
            LatticeTables::get(Lattice::BodyCentred).link_masks,
            BCDL_MASKS
        );
        assert_eq!(LatticeTables::get(Lattice::Simple).link_masks, SIMPLE_MASKS);
    }

    #[test]
    fn bcdl_offsets_match_the_spec() {
        let t = LatticeTables::get(Lattice::BodyCentred);
        assert_eq!(t.offsets[0], [2, 0, 0]);
        assert_eq!(t.offsets[5], [0, 0, -2]);
        assert_eq!(t.offsets[6], [1, 1, 1]);
        assert_eq!(t.offsets[7], [1, 1, -1]);
        assert_eq!(t.offsets[9], [1, -1, -1]);
        assert_eq!(t.offsets[10], [-1, 1, 1]);
        assert_eq!(t.offsets[13], [-1, -1, -1]);
    }

    #[test]
    fn reverse_edges_follow_the_spec_rule() {
        for (lattice, t) in both() {
            for i in 0..14 {
                let expected = match lattice {
                    Lattice::BodyCentred if i >= 6 => 19 - i,
                    _ => i ^ 1,
                };
                assert_eq!(t.reverse[i] as usize, expected, "{lattice:?} {i}");
            }
        }
    }

    #[test]
    fn link_has_14_vertices_36_edges_24_triangles() {
        for (lattice, t) in both() {
            let edges: u32 = t.link_masks.iter().map(|m| m.count_ones()).sum::<u32>() / 2;
            assert_eq!(edges, 36, "{lattice:?}");
            let mut triangles = 0;
            for i in 0..14 {
                for j in i + 1..14 {
                    for k in j + 1..14 {
                        let m = &t.link_masks;
                        if m[i] & (1 << j) != 0 && m[j] & (1 << k) != 0 && m[i] & (1 << k) != 0 {
                            triangles += 1;
                        }
                    }
                }
            }
            assert_eq!(triangles, 24, "{lattice:?}");
        }
        let t = LatticeTables::get(Lattice::BodyCentred);
        for i in 0..14 {
            assert_eq!(t.link_masks[i].count_ones(), if i < 6 { 4 } else { 6 });
        }
    }

    #[test]
    fn exactly_7500_masks_merge_without_changing_topology() {
        for (lattice, t) in both() {
            let count = (0u32..1 << 14)
                .filter(|&x| {
                    let x = x as u16;
                    let y = !x & 0x3FFF;
                    t.is_connected(x) && t.is_connected(y)
                })
                .count();
            assert_eq!(count, 7500, "{lattice:?}");
        }
    }

    /// Every tetrahedron of a block of cells, in absolute coordinates.
    fn block(lattice: Lattice, n: i32) -> Vec<[Offset; 4]> {
        let t = LatticeTables::get(lattice);
        let mut out = Vec::new();
        for x in 0..n {
            for y in 0..n {
                for z in 0..n {
                    let base = match lattice {
                        Lattice::BodyCentred => [2 * x + 1, 2 * y + 1, 2 * z + 1],
                        Lattice::Simple => [x, y, z],
                    };
                    for tet in &t.tetrahedra {
                        out.push(tet.map(|o| [o[0] + base[0], o[1] + base[1], o[2] + base[2]]));
                    }
                }
            }
        }
        out
    }

    #[test]
    fn tetrahedra_are_positive_with_the_spec_determinants() {
        for (lattice, t) in both() {
            let want = match lattice {
                Lattice::BodyCentred => 4,
                Lattice::Simple => 1,
            };
            assert_eq!(
                t.tetrahedra.len(),
                if lattice == Lattice::BodyCentred {
                    12
                } else {
                    6
                }
            );
            for tet in &t.tetrahedra {
                assert_eq!(det(tet), want, "{lattice:?} {tet:?}");
            }
        }
    }

    #[test]
    fn interior_faces_pair_up_with_opposite_orientation_and_edges_are_neighbours() {
        for (lattice, t) in both() {
            let tets = block(lattice, 4);
            // Oriented faces (outward orientation of a positive tetrahedron).
            let mut faces: HashMap<[Offset; 3], i32> = HashMap::new();
            let mut seen = std::collections::HashSet::new();
            for tet in &tets {
                let mut sorted = *tet;
                sorted.sort();
                assert!(seen.insert(sorted), "tetrahedron emitted twice: {tet:?}");
                let [a, b, c, d] = *tet;
                for f in [[b, c, d], [a, d, c], [a, b, d], [a, c, b]] {
                    let mut key = f;
                    key.sort();
                    // Parity of the permutation from f to sorted order gives the orientation sign.
                    let perm = f.map(|v| key.iter().position(|&k| k == v).unwrap_or(0));
                    let inversions = (perm[0] > perm[1]) as i32
                        + (perm[0] > perm[2]) as i32
                        + (perm[1] > perm[2]) as i32;
                    *faces.entry(key).or_default() += if inversions % 2 == 0 { 1 } else { -1 };
                }
                for i in 0..4 {
                    for j in 0..4 {
                        if i != j {
                            assert!(
                                t.direction(sub(tet[j], tet[i])).is_some(),
                                "{lattice:?}: tetrahedron edge is not a neighbour offset"
                            );
                        }
                    }
                }
            }
            // A face seen twice with opposite orientations sums to 0; boundary faces sum to +-1.
            let lim = match lattice {
                Lattice::BodyCentred => (2, 8),
                Lattice::Simple => (0, 4),
            };
            let interior = |v: &Offset| v.iter().all(|&c| c > lim.0 && c < lim.1);
            let mut interior_faces = 0;
            for (key, sum) in &faces {
                if key.iter().all(interior) {
                    interior_faces += 1;
                    assert_eq!(
                        *sum, 0,
                        "{lattice:?}: interior face {key:?} not paired oppositely"
                    );
                } else {
                    assert!(sum.abs() <= 1);
                }
            }
            assert!(interior_faces > 0);
        }
    }

    #[test]
    fn simple_offsets_are_the_edges_of_the_kuhn_tetrahedra_at_a_point() {
        let tets = block(Lattice::Simple, 3);
        let centre = [1, 1, 1];
        let mut edges = std::collections::BTreeSet::new();
        for tet in &tets {
            if let Some(i) = tet.iter().position(|&v| v == centre) {
                for (j, v) in tet.iter().enumerate() {
                    if j != i {
                        edges.insert(sub(*v, centre));
                    }
                }
            }
        }
        let offsets: std::collections::BTreeSet<_> = LatticeTables::get(Lattice::Simple)
            .offsets
            .into_iter()
            .collect();
        assert_eq!(edges, offsets);
    }

    #[test]
    fn bcdl_offsets_are_the_edges_of_the_tetrahedra_at_a_point() {
        let tets = block(Lattice::BodyCentred, 3);
        for centre in [[3, 3, 3], [2, 2, 2]] {
            let mut edges = std::collections::BTreeSet::new();
            let mut count = 0;
            for tet in &tets {
                if let Some(i) = tet.iter().position(|&v| v == centre) {
                    count += 1;
                    for (j, v) in tet.iter().enumerate() {
                        if j != i {
                            edges.insert(sub(*v, centre));
                        }
                    }
                }
            }
            let offsets: std::collections::BTreeSet<_> = LatticeTables::get(Lattice::BodyCentred)
                .offsets
                .into_iter()
                .collect();
            assert_eq!(edges, offsets);
            assert_eq!(count, 24, "each point lies in 24 tetrahedra");
        }
    }
}
