//! The lattice in storage terms, shared by every pass: neighbour deltas per parity, the
//! tetrahedron templates and their anchors (`TetGroup`), the border table, each template's
//! gradient coefficients, and the tetrahedron case table (`CASES`, `tet_triangles`).
//!
//! ```text
//!        v3                 a tetrahedron's corners v0..v3 (offsets from its anchor), its six
//!       /|\                 edges (`TET_EDGES`) and, for the corners inside, the cycle of
//!      / | \                crossed edges (`CASES`): a triangle, or a quad split along its
//!    v0--|--v2              shorter diagonal, oriented along the field's gradient
//!      \ | /
//!       \|/
//!        v1
//! ```

use crate::lattice::{LatticeTables, Offset, FULL};
use crate::{Lattice, Samples};

/// Edges of a tetrahedron (v0..v3), as in `rmt-spec.md`.
pub(crate) const TET_EDGES: [(usize, usize); 6] = [(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)];

/// Case table: for the corners inside (bit i: f(v_i) < T), a directed cycle of crossed edges whose
/// right-hand normal points toward increasing f for a positively oriented tetrahedron. Length 3
/// (triangle) or 4 (quad, split along its shorter diagonal); `u8::MAX` pads. Checked against
/// geometry by `case_table_orients_triangles_along_the_gradient`.
pub(crate) const CASES: [[u8; 4]; 16] = {
    const X: u8 = u8::MAX;
    [
        [X, X, X, X],
        [0, 1, 2, X],
        [0, 4, 3, X],
        [1, 2, 4, 3],
        [1, 3, 5, X],
        [0, 3, 5, 2],
        [0, 4, 5, 1],
        [2, 4, 5, X],
        [2, 5, 4, X],
        [0, 1, 5, 4],
        [0, 2, 5, 3],
        [1, 5, 3, X],
        [1, 3, 4, 2],
        [0, 3, 4, X],
        [0, 2, 1, X],
        [X, X, X, X],
    ]
};

/// The triangles of one tetrahedron (none, one, or two from a quad split along its shorter
/// diagonal) as crossing ids, oriented by the case table, read from the corner values: the
/// tests' reference for [`case_triangles_of`], the one definition that the emission and the
/// listing for the quotient test share. `val`: the corner values; `dir[i][j]`: neighbour index
/// of corner j from corner i; `id(o, d)`: the id of the crossing owned by corner `o` on its
/// edge to neighbour `d`.
#[inline(always)]
#[cfg(test)]
pub(crate) fn tet_triangles(
    val: [f32; 4],
    iso: f32,
    dir: &[[u8; 4]; 4],
    id: impl Fn(usize, u8) -> u32,
    positions: &[[f32; 3]],
    out: &mut [[u32; 3]; 2],
) -> usize {
    let case = (val[0] < iso) as usize
        | ((val[1] < iso) as usize) << 1
        | ((val[2] < iso) as usize) << 2
        | ((val[3] < iso) as usize) << 3;
    let edge = |a: usize, b: usize| {
        if owns(val[a], val[b], iso) {
            id(a, dir[a][b])
        } else {
            id(b, dir[b][a])
        }
    };
    case_triangles_of(case, edge, positions, out)
}

/// The triangles of a tetrahedron in `case` (bit i: corner i inside), as [`tet_triangles`]
/// writes them, with `edge(a, b)` the id of the crossing on the edge from corner a to corner b
/// (whichever end owns it): what the geometry pass calls when it knows the case and the owners
/// from the vertex pass's tables rather than from the values.
#[inline(always)]
pub(crate) fn case_triangles_of(
    case: usize,
    edge: impl Fn(usize, usize) -> u32,
    positions: &[[f32; 3]],
    out: &mut [[u32; 3]; 2],
) -> usize {
    if case == 0 || case == 15 {
        return 0;
    }
    let cycle = &CASES[case];
    let n = if cycle[3] == u8::MAX { 3 } else { 4 };
    let mut ids = [0u32; 4];
    for (slot, &e) in ids.iter_mut().zip(cycle.iter()).take(n) {
        let (a, b) = TET_EDGES[e as usize];
        *slot = edge(a, b);
    }
    if n == 3 {
        out[0] = [ids[0], ids[1], ids[2]];
        1
    } else {
        *out = split_quad(ids, positions);
        2
    }
}

/// The two triangles of the quad of crossings `ids` (a case table cycle), split along its
/// shorter diagonal (0-2 on a tie).
#[inline(always)]
pub(crate) fn split_quad(ids: [u32; 4], positions: &[[f32; 3]]) -> [[u32; 3]; 2] {
    // The diagonal chosen by a table index rather than a branch (the choice is data-dependent
    // and mispredicts half the time).
    const SPLITS: [[usize; 6]; 2] = [[1, 2, 3, 1, 3, 0], [0, 1, 2, 0, 2, 3]];
    let p = |i: u32| glam::Vec3::from(positions[i as usize]);
    let short02 = p(ids[0]).distance_squared(p(ids[2])) <= p(ids[1]).distance_squared(p(ids[3]));
    let s = &SPLITS[usize::from(short02)];
    [
        [ids[s[0] & 3], ids[s[1] & 3], ids[s[2] & 3]],
        [ids[s[3] & 3], ids[s[4] & 3], ids[s[5] & 3]],
    ]
}

/// Whether the end with value `f` (inside iff `f < iso`) owns the crossing shared with `g`.
#[inline(always)]
pub(crate) fn owns(f: f32, g: f32, iso: f32) -> bool {
    let (df, dg) = ((f - iso).abs(), (g - iso).abs());
    // Without short-circuits: three comparisons and no branch (the outcome is data, and the
    // vertex pass asks once per crossed edge).
    (df < dg) | ((df == dg) & (f < iso))
}

/// A tetrahedron with storage-index deltas from a reference point and edge directions.
#[derive(Clone, Copy, Debug)]
pub(crate) struct TetTemplate {
    /// Lattice offsets of the corners from the anchor.
    pub(crate) off: [Offset; 4],
    pub(crate) delta: [isize; 4],
    /// `dir[i][j]`: neighbour index of corner j seen from corner i.
    pub(crate) dir: [[u8; 4]; 4],
}

/// The tetrahedra visited together (a body-centred face's 4 around the centres A and B, with 6
/// distinct points; a cube's 6, with 8 corners) and the number of triangles they give for each
/// inside/outside pattern of those points, derived from the case table: the geometry pass counts
/// a layer's triangles from the anchors' crossed edges before it writes them.
#[derive(Clone, Debug)]
pub(crate) struct TetGroup {
    /// Storage deltas of its distinct points from the anchor (point 0, in every tetrahedron of
    /// the group).
    pub(crate) points: [isize; 8],
    /// Neighbour index of each point seen from the anchor (`u8::MAX` for the anchor itself).
    pub(crate) dirs: [u8; 8],
    pub(crate) len: usize,
    /// Triangles of its tetrahedra when the points with bit i set in the index are inside.
    /// A tetrahedron gives as many triangles with its sides swapped, so this is also the count
    /// when bit i says "point i is on the other side from the anchor", i.e. the anchor's
    /// crossed edges: no sample value needs reading. [`CODES`] entries (those past the group's
    /// codes zero), so that a code, below 256, needs no bounds check.
    pub(crate) triangles: Box<[u8; CODES]>,
    /// Per index (as in `triangles`) and tetrahedron of the group (template order), the
    /// tetrahedron's case (bit i: its corner i inside) when the anchor is outside: entry
    /// `code * tets + j`. With the anchor inside every bit flips. The geometry pass reads a
    /// tetrahedron's case off the anchor's side and crossed edges with it.
    pub(crate) cases: Vec<u8>,
    /// The index into `triangles` and `cases` from the anchor's crossed edges, by their low 7
    /// and high 7 neighbour bits (or'ed): bit i set when point i's edge is crossed.
    code_parts: [[u8; 128]; 2],
    /// The group's edges as its tetrahedra name them (corner a to corner b, a < b in the
    /// tetrahedron, the order [`case_triangles_of`] asks for them), each once: the geometry
    /// pass finds the crossing on each crossed one once per group, not once per triangle corner.
    pub(crate) edges: Vec<GroupEdge>,
    /// Per edge of `edges` (entry k; the entries past the edges unused), what the geometry
    /// pass reads to find its crossing: its ends' storage deltas from the anchor and the
    /// neighbour index of each end seen from the other. [`EDGE_SLOTS`] entries, so that an edge
    /// index masked to its low 5 bits needs no bounds check.
    pub(crate) edge_reads: [EdgeRead; EDGE_SLOTS],
    /// Per index (as in `triangles`): the edges of `edges` that the group's cycles name (bit k:
    /// edge k), all crossed. [`CODES`] entries, as `triangles`.
    pub(crate) crossed_edges: Box<[u64; CODES]>,
    /// Per index and anchor side (entry `2 * code + inside`), the range of `cycles` holding its
    /// tetrahedra's cycles (`cycle_start[i]..cycle_start[i + 1]`); for every code below
    /// [`CODES`] (those past the group's codes empty), so that no bound is checked.
    pub(crate) cycle_start: Box<[u16; 2 * CODES + 1]>,
    /// The cycles of crossed edges of the group's tetrahedra, in template order, each the
    /// case table's cycle ([`CASES`]) with its tetrahedron's edges replaced by the group's.
    pub(crate) cycles: Vec<GroupCycle>,
}

/// Entries of a [`TetGroup`]'s tables by code: every value of a code (a byte).
pub(crate) const CODES: usize = 256;

/// The most edges a [`TetGroup`] has: a cube's 6 tetrahedra have 19 (its 12 edges, 6 face
/// diagonals and the main diagonal; each named in one direction only), a body-centred face's 4
/// have 13.
pub(crate) const MAX_GROUP_EDGES: usize = 19;

/// Entries of [`TetGroup::edge_reads`] and of the geometry pass's crossing ids per group: a
/// power of two above [`MAX_GROUP_EDGES`], indexed by an edge index masked with
/// `EDGE_SLOTS - 1`.
pub(crate) const EDGE_SLOTS: usize = 32;

/// An edge of a [`TetGroup`] as the geometry pass reads it: the storage deltas of its ends
/// (`from`, `to`) from the anchor, and the neighbour index of each end seen from the other.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) struct EdgeRead {
    pub(crate) deltas: [isize; 2],
    pub(crate) dir: [u8; 2],
}

/// An edge of a [`TetGroup`]: from point `from` to point `to` (indices into the group's
/// points), with the neighbour index of each end seen from the other.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct GroupEdge {
    pub(crate) from: u8,
    pub(crate) to: u8,
    /// Neighbour index of `to` seen from `from`, and of `from` seen from `to`.
    pub(crate) dir: [u8; 2],
}

/// One tetrahedron's cycle of crossed edges ([`CASES`]) in a group: indices into the group's
/// edges (the fourth `u8::MAX` for a triangle), and the tetrahedron (its index in the group).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct GroupCycle {
    pub(crate) edges: [u8; 4],
    pub(crate) tet: u8,
}

impl TetGroup {
    /// The index into `triangles` and `cases` for an anchor with crossed edges `crossed` (by
    /// neighbour bit): bit i set when point i lies on the other side from the anchor.
    #[inline(always)]
    pub(crate) fn code(&self, crossed: u16) -> usize {
        usize::from(
            self.code_parts[0][usize::from(crossed & 127)]
                | self.code_parts[1][usize::from((crossed >> 7) & 127)],
        )
    }

    /// The group of templates `tets` (corners given by their storage deltas).
    pub(crate) fn new(tets: &[TetTemplate]) -> Self {
        let mut group = Self {
            points: [0; 8],
            dirs: [u8::MAX; 8],
            len: 1,
            triangles: Box::new([0; CODES]),
            cases: Vec::new(),
            code_parts: [[0; 128]; 2],
            edges: Vec::new(),
            edge_reads: [EdgeRead::default(); EDGE_SLOTS],
            crossed_edges: Box::new([0; CODES]),
            cycle_start: Box::new([0; 2 * CODES + 1]),
            cycles: Vec::new(),
        };
        let mut corners = Vec::with_capacity(tets.len());
        for tpl in tets {
            // The anchor: the reference point of the templates.
            let a = tpl.delta.iter().position(|&d| d == 0);
            let a = a.expect("every tetrahedron of a group has the anchor as a corner");
            let mut c = [0usize; 4];
            for (i, &d) in tpl.delta.iter().enumerate() {
                c[i] = match group.points[..group.len].iter().position(|&p| p == d) {
                    Some(j) => j,
                    None => {
                        group.points[group.len] = d;
                        group.dirs[group.len] = tpl.dir[a][i];
                        group.len += 1;
                        group.len - 1
                    }
                };
            }
            corners.push(c);
        }
        for (half, part) in group.code_parts.iter_mut().enumerate() {
            for (bits, code) in part.iter_mut().enumerate() {
                let mask = bits << (7 * half);
                *code =
                    (1..group.len).fold(0u8, |c, i| c | (((mask >> group.dirs[i]) & 1) << i) as u8);
            }
        }
        group.cases = (0..1usize << group.len)
            .flat_map(|code| {
                corners.iter().map(move |c| {
                    (0..4).fold(0u8, |case, i| case | (((code >> c[i]) & 1) << i) as u8)
                })
            })
            .collect();
        // Each tetrahedron's edges as group edges (first use numbers them).
        let tet_edges: Vec<[u8; 6]> = tets
            .iter()
            .zip(&corners)
            .map(|(tpl, c)| {
                TET_EDGES.map(|(a, b)| {
                    let e = GroupEdge {
                        from: c[a] as u8,
                        to: c[b] as u8,
                        dir: [tpl.dir[a][b], tpl.dir[b][a]],
                    };
                    let k = match group.edges.iter().position(|&x| x == e) {
                        Some(k) => k,
                        None => {
                            group.edges.push(e);
                            group.edges.len() - 1
                        }
                    };
                    k as u8
                })
            })
            .collect();
        assert!(
            group.edges.len() <= MAX_GROUP_EDGES,
            "a group's edges fit the geometry pass's array"
        );
        for (read, e) in group.edge_reads.iter_mut().zip(&group.edges) {
            *read = EdgeRead {
                deltas: [e.from, e.to].map(|i| group.points[usize::from(i)]),
                dir: e.dir,
            };
        }
        for code in 0..1usize << group.len {
            let mut crossed = 0u64;
            for flip in [0, 15] {
                group.cycle_start[2 * code + usize::from(flip != 0)] = group.cycles.len() as u16;
                for (j, c) in corners.iter().enumerate() {
                    let case = (0..4).fold(0, |case, i| case | ((code >> c[i]) & 1) << i) ^ flip;
                    if case == 0 || case == 15 {
                        continue;
                    }
                    let edges = CASES[case].map(|e| {
                        if e == u8::MAX {
                            u8::MAX
                        } else {
                            crossed |= 1 << tet_edges[j][e as usize];
                            tet_edges[j][e as usize]
                        }
                    });
                    group.cycles.push(GroupCycle {
                        edges,
                        tet: j as u8,
                    });
                }
            }
            group.crossed_edges[code] = crossed;
        }
        // The codes past the group's: empty ranges at the end.
        let end = group.cycles.len() as u16;
        group.cycle_start[2 << group.len..].fill(end);
        for (code, t) in group.triangles[..1 << group.len].iter_mut().enumerate() {
            *t = corners
                .iter()
                .map(|c| {
                    let case = (0..4).fold(0, |case, i| case | ((code >> c[i]) & 1) << i);
                    case_triangles(case)
                })
                .sum();
        }
        group
    }
}

/// Triangles a tetrahedron gives in `case` (bit i: corner i inside): none, one, or two (a quad).
pub(crate) fn case_triangles(case: usize) -> u8 {
    match CASES[case] {
        [u8::MAX, ..] => 0,
        [_, _, _, u8::MAX] => 1,
        _ => 2,
    }
}

/// The lattice in storage terms: neighbour deltas per parity and tetrahedron templates.
pub(crate) struct Layout<'a> {
    pub(crate) s: &'a Samples,
    pub(crate) lattice: Lattice,
    pub(crate) t: &'static LatticeTables,
    /// Storage-index delta of neighbour d, for even (`[0]`) and odd (`[1]`) points.
    pub(crate) delta: [[isize; 14]; 2],
    /// Per parity and neighbour d (16 entries, the last two unused, so that `d & 15` needs no
    /// bounds check): its storage delta, and per axis the index of its coordinate in the
    /// point's window of the axis tables ([`Positions::around`]).
    pub(crate) far: [[(isize, [u8; 3]); 16]; 2],
    pub(crate) tets: Vec<TetTemplate>,
    /// The tetrahedra visited together: per face axis (body-centred) or the cube (simple).
    pub(crate) groups: Vec<TetGroup>,
    /// Existence (bit 16), valid-neighbour mask (bits 0..14) and inner-edge mask (bits 17..31,
    /// [`Layout::inner_dirs`]) of a point by the boundary class of each coordinate ([`boundary_class`]) and its parity; empty for grids too small
    /// for the classes to be apart (then computed point by point).
    pub(crate) border_table: Vec<u32>,
    /// The tetrahedra around a point of each parity (`[0]` even, `[1]` odd): 24 on both
    /// lattices ([`StarTet`]).
    pub(crate) around: [Vec<StarTet>; 2],
    /// Per template: `[d2 x d3, d3 x d1, d1 x d2]` for its edge vectors `d_i` from corner 0 on
    /// the lattice (the gradient of the linear interpolant is their sum weighted by the value
    /// differences, up to the positive determinant).
    pub(crate) grad_coef: Vec<[glam::DVec3; 3]>,
    /// Per axis, the largest distance (lattice units) from a template's anchor to its
    /// corners: an anchor at least this far inside the box on every axis has all its
    /// tetrahedra's corners in the box (none is a ghost).
    pub(crate) reach: Offset,
    /// Per axis, the offset from the box's lower corner of lattice coordinate `c` at index
    /// `c + COORD_PAD` (ghosts clamped onto the box face), exactly as [`Samples::bcdl_position`]
    /// and [`Samples::simple_position`] compute it: [`Layout::position`] adds the corner.
    coords: [Vec<f32>; 3],
}

/// [`Layout::position`] from borrowed tables ([`Layout::positions`]).
#[derive(Clone, Copy)]
pub(crate) struct Positions<'a> {
    coords: [&'a [f32]; 3],
    min: glam::Vec3,
}

impl Positions<'_> {
    /// The corner plus the axis offsets `(x, y, z)` read from the tables: the position of
    /// the point they belong to, bit for bit [`Layout::position`] (the same additions).
    #[inline(always)]
    pub(crate) fn min_plus(&self, x: f32, y: f32, z: f32) -> glam::Vec3 {
        self.min + glam::Vec3::new(x, y, z)
    }

    /// Per axis, the 8 table entries from coordinate `p[a] - AROUND`: entry `o + AROUND` is
    /// the offset of coordinate `p[a] + o` (`|o| <= AROUND`, a neighbour's), read without a
    /// bounds check once the index is masked to 3 bits. `p` is a lattice point or a ghost
    /// (at most one unit outside the box).
    #[inline(always)]
    pub(crate) fn around(&self, p: Offset) -> [&[f32; 8]; 3] {
        let window = |a: usize| {
            let from = (p[a] + COORD_PAD - AROUND) as usize;
            let w: &[f32; 8] = self.coords[a][from..from + 8]
                .try_into()
                .expect("eight entries");
            w
        };
        [window(0), window(1), window(2)]
    }
}

/// Lattice coordinates below 0 (and above the largest) that [`Layout::coords`] covers: enough
/// for the window of a ghost ([`Positions::around`]: from 3 below 0 to 6 above the largest).
const COORD_PAD: i32 = 8;

/// How far a neighbour's coordinate lies from the point's on one axis, at most (body-centred:
/// 2 along the axes, 1 on the diagonals; simple: 1).
pub(crate) const AROUND: i32 = 2;

/// One of the tetrahedra around a lattice point (which edges of the point have all their
/// tetrahedra: [`Layout::inner_dirs`]): corners in the positive orientation of the lattice's
/// templates (so the case table orients its triangles), relative to the point.
#[derive(Clone, Copy, Debug)]
pub(crate) struct StarTet {
    /// Lattice offsets of the corners from the point (one of them is `[0, 0, 0]`).
    pub(crate) off: [Offset; 4],
    /// Storage-index deltas of the corners from the point (the tests rebuild plain MT from
    /// these tetrahedra, which checks the table against the geometry pass).
    #[cfg_attr(not(test), allow(dead_code))]
    pub(crate) delta: [isize; 4],
    /// `dir[i][j]`: neighbour index of corner j seen from corner i (as `delta`).
    #[cfg_attr(not(test), allow(dead_code))]
    pub(crate) dir: [[u8; 4]; 4],
    /// The point's neighbour bits of the tetrahedron's other three corners (its edges from the
    /// point).
    pub(crate) from_point: u16,
}

/// Boundary classes per axis: the coordinates -1..=3, max-3..=max+1, and everything between.
pub(crate) const CLASSES: usize = 11;

/// The class of lattice coordinate `c` on an axis whose largest coordinate is `max`: points of
/// one class see the same neighbours exist (offsets reach at most 2 lattice units).
#[inline(always)]
pub(crate) fn boundary_class(c: i32, max: i32) -> usize {
    if c <= 3 {
        (c + 1).max(0) as usize
    } else if c >= max - 3 {
        (5 + (c - (max - 3))).min(9) as usize
    } else {
        10
    }
}

/// The border table of the last extraction ([`Layout::border_table`]), kept between
/// extractions: it depends only on the lattice and the cells per axis, and building it costs
/// about a fifth of a 32^3 chunk's extraction without clustering. The tetrahedron groups and
/// the tetrahedra around a point ([`Layout::groups`], [`Layout::around`]) are kept with it:
/// they depend only on the lattice and the storage layout, and building them cost about 2% of
/// a 64^3 extraction without clustering.
#[derive(Clone, Debug, Default)]
pub(crate) struct BorderCache {
    /// Lattice, cells, storage dimensions and boundary of the grid the tables were built for.
    key: Option<(Lattice, [usize; 3], [usize; 3], crate::Boundary)>,
    table: Vec<u32>,
    groups: Vec<TetGroup>,
    around: [Vec<StarTet>; 2],
    /// The lattice edges of the grid (`Stats::edges`), once an extraction counted them.
    pub(crate) edges: Option<usize>,
}

impl<'a> Layout<'a> {
    /// The layout of `s` on `lattice`, its border table built anew.
    #[cfg(test)]
    pub(crate) fn new(s: &'a Samples, lattice: Lattice) -> Self {
        let mut layout = Self::without_border_table(s, lattice, None);
        layout.border_table = layout.build_border_table();
        layout
    }

    /// [`Layout::new`], the border table, the groups and the tetrahedra around a point taken
    /// from `cache` when they were built for the same lattice and storage (else built and kept
    /// there).
    pub(crate) fn cached(s: &'a Samples, lattice: Lattice, cache: &mut BorderCache) -> Self {
        let key = Some((lattice, s.cells, s.dims, s.boundary));
        let fresh = cache.key != key;
        let kept = (!fresh).then_some((&cache.groups[..], &cache.around));
        let mut layout = Self::without_border_table(s, lattice, kept);
        if fresh {
            cache.table = layout.build_border_table();
            cache.groups.clone_from(&layout.groups);
            cache.around.clone_from(&layout.around);
            cache.key = key;
            cache.edges = None;
        }
        layout.border_table.clone_from(&cache.table);
        layout
    }

    /// Everything of the layout but its border table (left empty); the groups and the
    /// tetrahedra around a point copied from `kept` when given (built for the same lattice and
    /// storage).
    fn without_border_table(
        s: &'a Samples,
        lattice: Lattice,
        kept: Option<(&[TetGroup], &[Vec<StarTet>; 2])>,
    ) -> Self {
        let t = LatticeTables::get(lattice);
        let idx = |p: Offset| -> isize {
            match lattice {
                Lattice::BodyCentred => s.bcdl_index(p) as isize,
                Lattice::Simple => {
                    s.simple_index(p[0] as usize, p[1] as usize, p[2] as usize) as isize
                }
            }
        };
        // Reference points far enough from the border for every offset to stay in storage.
        let refs: [Offset; 2] = match lattice {
            Lattice::BodyCentred => [[2, 2, 2], [3, 3, 3]],
            Lattice::Simple => [[1, 1, 1], [1, 1, 1]],
        };
        let mut delta = [[0isize; 14]; 2];
        for (par, r) in refs.iter().enumerate() {
            for (d, o) in t.offsets.iter().enumerate() {
                delta[par][d] = idx(add(*r, *o)) - idx(*r);
            }
        }
        // Templates: body-centred relative to the centre A below a face (odd point); simple
        // relative to the cube's corner 0.
        let r = refs[1];
        let tets = t
            .tetrahedra
            .iter()
            .map(|tet| {
                let mut tpl = TetTemplate {
                    off: *tet,
                    delta: [0; 4],
                    dir: [[0; 4]; 4],
                };
                for i in 0..4 {
                    tpl.delta[i] = idx(add(r, tet[i])) - idx(r);
                    for j in 0..4 {
                        if i != j {
                            let o = [
                                tet[j][0] - tet[i][0],
                                tet[j][1] - tet[i][1],
                                tet[j][2] - tet[i][2],
                            ];
                            tpl.dir[i][j] = t.direction(o).map_or(u8::MAX, |d| d as u8);
                        }
                    }
                }
                tpl
            })
            .collect::<Vec<_>>();
        // Groups: a body-centred face's 4 tetrahedra (the table lists them by face axis), a
        // cube's 6.
        let (groups, around) = match kept {
            Some((groups, around)) => (groups.to_vec(), around.clone()),
            None => (
                match lattice {
                    Lattice::BodyCentred => tets.chunks(4).map(TetGroup::new).collect(),
                    Lattice::Simple => vec![TetGroup::new(&tets)],
                },
                [0, 1].map(|par| star_tets(lattice, t, refs[par], &idx)),
            ),
        };
        // Lattice units per world unit along each axis: half cubes on the body-centred lattice.
        let unit = match lattice {
            Lattice::BodyCentred => s.spacing.as_dvec3() * 0.5,
            Lattice::Simple => s.spacing.as_dvec3(),
        };
        let grad_coef = tets
            .iter()
            .map(|tpl| {
                let d = [1, 2, 3].map(|i| {
                    let o = [0, 1, 2].map(|a| f64::from(tpl.off[i][a] - tpl.off[0][a]));
                    glam::DVec3::from(o) * unit
                });
                [d[1].cross(d[2]), d[2].cross(d[0]), d[0].cross(d[1])]
            })
            .collect();
        let reach = [0, 1, 2].map(|a| {
            tets.iter()
                .flat_map(|tpl| tpl.off.iter().map(move |o| o[a].abs()))
                .max()
                .unwrap_or(0)
        });
        // Per axis, as the samples compute positions (the same f32 operations, so the same
        // bits): body-centred in half cubes, ghosts clamped; simple in cubes.
        let coords = [0, 1, 2].map(|a| {
            let max = match lattice {
                Lattice::BodyCentred => 2 * s.cells[a] as i32,
                Lattice::Simple => s.cells[a] as i32,
            };
            (-COORD_PAD..=max + COORD_PAD)
                .map(|c| match lattice {
                    Lattice::BodyCentred => {
                        let h = s.spacing * 0.5;
                        c.clamp(0, max) as f32 * h[a]
                    }
                    Lattice::Simple => c as f32 * s.spacing[a],
                })
                .collect()
        });
        let far = [0, 1].map(|par| {
            let mut far = [(0, [AROUND as u8; 3]); 16];
            for (d, slot) in far.iter_mut().take(14).enumerate() {
                let o = t.offsets[d];
                debug_assert!(o.iter().all(|c| c.abs() <= AROUND), "offset {o:?}");
                *slot = (delta[par][d], o.map(|c| (c + AROUND) as u8));
            }
            far
        });
        Self {
            s,
            lattice,
            t,
            delta,
            far,
            reach,
            tets,
            groups,
            border_table: Vec::new(),
            around,
            grad_coef,
            coords,
        }
    }

    /// The table behind [`Layout::border_info`]: one representative point per class triple
    /// and parity (the coordinate itself for the border classes, 4 or 5 for the middle one).
    pub(crate) fn build_border_table(&self) -> Vec<u32> {
        // The middle class needs coordinates of either parity clear of both border classes.
        if (0..3).any(|a| self.max_coord(a) < 10) {
            return Vec::new();
        }
        let mut table = vec![0u32; CLASSES * CLASSES * CLASSES * 2];
        let rep = |class: usize, odd: i32, max: i32| -> Option<i32> {
            let c = match class {
                0..=4 => class as i32 - 1,
                5..=9 => max - 3 + (class as i32 - 5),
                _ => 4 + odd,
            };
            ((c & 1) == odd || self.lattice == Lattice::Simple).then_some(c)
        };
        for cx in 0..CLASSES {
            for cy in 0..CLASSES {
                for cz in 0..CLASSES {
                    for odd in 0..2 {
                        let (Some(x), Some(y), Some(z)) = (
                            rep(cx, odd, self.max_coord(0)),
                            rep(cy, odd, self.max_coord(1)),
                            rep(cz, odd, self.max_coord(2)),
                        ) else {
                            continue;
                        };
                        let p = [x, y, z];
                        let exists = match self.lattice {
                            Lattice::BodyCentred => self.s.bcdl_exists(p),
                            Lattice::Simple => true,
                        };
                        let entry = if exists {
                            (1 << 16)
                                | u32::from(self.valid_neighbours(p))
                                | u32::from(self.inner_dirs_of(p)) << 17
                        } else {
                            0
                        };
                        table[((cx * CLASSES + cy) * CLASSES + cz) * 2 + odd as usize] = entry;
                    }
                }
            }
        }
        table
    }

    /// Whether point `p` exists, and its valid-neighbour mask (0 if it does not exist).
    #[inline]
    pub(crate) fn border_info(&self, p: Offset) -> (bool, u16) {
        if self.border_table.is_empty() {
            let exists = match self.lattice {
                Lattice::BodyCentred => self.s.bcdl_exists(p),
                Lattice::Simple => true,
            };
            return (exists, if exists { self.valid_neighbours(p) } else { 0 });
        }
        let class = |a: usize| boundary_class(p[a], self.max_coord(a));
        let odd = match self.lattice {
            Lattice::BodyCentred => (p[0] & 1) as usize,
            Lattice::Simple => 0,
        };
        let e = self.border_table[((class(0) * CLASSES + class(1)) * CLASSES + class(2)) * 2 + odd];
        (e >> 16 != 0, e as u16)
    }

    /// The cell of the geometry walk's anchor at lattice point `a` (its group `g`: on the
    /// body-centred lattice the face axis, the cell above the face along it, clamped into the
    /// grid; on the simple lattice the cube's corner 0 is `a` itself). Anchors outside the grid
    /// give coordinates no cell range holds.
    #[inline]
    pub(crate) fn anchor_cell(&self, a: Offset, g: usize) -> [usize; 3] {
        match self.lattice {
            Lattice::Simple => a.map(|x| x as usize),
            Lattice::BodyCentred => {
                let mut c = a.map(|x| ((x - 1) / 2) as usize);
                c[g] = (((a[g] + 1) / 2) as usize).min(self.s.cells[g] - 1);
                c
            }
        }
    }

    /// Whether every corner of the tetrahedra of the anchor at lattice point `p` lies in the
    /// box (at least [`Layout::reach`] inside on every axis): none is a ghost clamped onto a
    /// face.
    #[inline]
    pub(crate) fn inner_anchor(&self, p: Offset) -> bool {
        (0..3).all(|a| p[a] >= self.reach[a] && p[a] + self.reach[a] <= self.max_coord(a))
    }

    /// Lattice coordinates of storage slot (sx, sy) of plane z.
    #[inline]
    pub(crate) fn coords(&self, sx: usize, sy: usize, z: usize) -> Offset {
        match self.lattice {
            Lattice::Simple => [sx as i32, sy as i32, z as i32],
            Lattice::BodyCentred => {
                let zz = z as i32 - 1;
                let odd = zz & 1;
                [2 * sx as i32 - odd, 2 * sy as i32 - odd, zz]
            }
        }
    }

    /// Lattice coordinates of storage slot `slot`.
    #[inline]
    pub(crate) fn coords_of(&self, slot: usize) -> Offset {
        let [dx, dy, _] = self.s.dims;
        let (z, local) = (slot / (dx * dy), slot % (dx * dy));
        self.coords(local % dx, local / dx, z)
    }

    /// Whether lattice point `p` exists (the simple lattice: inside the box).
    #[inline]
    pub(crate) fn exists(&self, p: Offset) -> bool {
        match self.lattice {
            Lattice::BodyCentred => self.s.bcdl_exists(p),
            Lattice::Simple => (0..3).all(|a| p[a] >= 0 && p[a] <= self.max_coord(a)),
        }
    }

    /// Whether the tetrahedron `tet` around point `p` is one of the extraction's: all its
    /// corners exist and at most one is a ghost (two ghosts are never joined by an edge), as for
    /// the faces the geometry pass visits (body-centred), or inside the box (simple).
    #[inline]
    pub(crate) fn has_tet(&self, p: Offset, tet: &StarTet) -> bool {
        let mut ghosts = 0;
        for o in &tet.off {
            let q = add(p, *o);
            if !self.exists(q) {
                return false;
            }
            ghosts += usize::from(self.lattice == Lattice::BodyCentred && self.is_ghost(q));
        }
        ghosts <= 1
    }

    /// Lattice coordinates of storage slot (sx, sy) of plane z, and whether the point exists.
    #[inline]
    pub(crate) fn point(&self, sx: usize, sy: usize, z: usize) -> (Offset, bool) {
        let p = self.coords(sx, sy, z);
        match self.lattice {
            Lattice::Simple => (p, true),
            Lattice::BodyCentred => (p, self.s.bcdl_exists(p)),
        }
    }

    /// World position of lattice point `p` (body-centred ghosts on the box face), bit for bit
    /// [`Samples::bcdl_position`] or [`Samples::simple_position`], from the per-axis tables.
    #[inline]
    pub(crate) fn position(&self, p: Offset) -> glam::Vec3 {
        let c = |a: usize| {
            let i = (p[a] + COORD_PAD) as usize;
            debug_assert!(i < self.coords[a].len(), "coordinate {} on axis {a}", p[a]);
            self.coords[a][i]
        };
        self.s.min + glam::Vec3::new(c(0), c(1), c(2))
    }

    /// [`Layout::position`]'s tables, to be held in locals by a loop that also writes memory
    /// (which would otherwise reload them from the layout after every store).
    #[inline]
    pub(crate) fn positions(&self) -> Positions<'_> {
        Positions {
            coords: [
                &self.coords[0][..],
                &self.coords[1][..],
                &self.coords[2][..],
            ],
            min: self.s.min,
        }
    }

    /// The storage planes geometry layer `k` reads (inclusive): body-centred faces perpendicular
    /// to z are anchored in plane 2k and reach 2k + 2, those perpendicular to x and y are
    /// anchored in plane 2k + 2 and reach 2k + 1 ..= 2k + 3; cubes of layer k span planes k and
    /// k + 1.
    pub(crate) fn layer_planes(&self, k: usize) -> (usize, usize) {
        let last = self.s.dims[2] - 1;
        match self.lattice {
            Lattice::BodyCentred => (2 * k, (2 * k + 3).min(last)),
            Lattice::Simple => (k, (k + 1).min(last)),
        }
    }

    /// Largest lattice coordinate per axis.
    pub(crate) fn max_coord(&self, a: usize) -> i32 {
        match self.lattice {
            Lattice::BodyCentred => 2 * self.s.cells[a] as i32,
            Lattice::Simple => self.s.cells[a] as i32,
        }
    }

    /// Whether all 14 neighbours of `p` are regular lattice points (no border, no ghosts).
    #[inline]
    pub(crate) fn is_regular(&self, p: Offset) -> bool {
        let margin = match self.lattice {
            Lattice::BodyCentred => 2 + (p[0] & 1),
            Lattice::Simple => 1,
        };
        (0..3).all(|a| p[a] >= margin && p[a] <= self.max_coord(a) - margin)
    }

    /// The gradient of the linear interpolant of the field on template tetrahedron `tet` at
    /// `anchor` (up to a positive factor, rounded to `f32`), from the sample positions (ghosts
    /// on the box face included).
    ///
    /// `inner`: every corner is known to lie in the box ([`Layout::inner_anchor`]), so no ghost
    /// is among them and the anchor's coordinates are not needed.
    pub(crate) fn gradient(&self, anchor: usize, ti: usize, inner: bool) -> [f32; 3] {
        let tet = &self.tets[ti];
        let f = tet
            .delta
            .map(|d| f64::from(self.s.values[(anchor as isize + d) as usize]));
        // Away from the ghosts (clamped onto the box faces) the corners sit on the lattice:
        // the edge vectors, and so the coefficients, are the template's.
        let p = match self.lattice {
            Lattice::BodyCentred if !inner => Some(self.coords_of(anchor)),
            _ => None,
        };
        let clamped = p.is_some_and(|p| {
            tet.off
                .iter()
                .any(|o| (0..3).any(|a| p[a] + o[a] < 0 || p[a] + o[a] > self.max_coord(a)))
        });
        if !clamped {
            let c = &self.grad_coef[ti];
            let g = c[0] * (f[1] - f[0]) + c[1] * (f[2] - f[0]) + c[2] * (f[3] - f[0]);
            return g.as_vec3().to_array();
        }
        let p = self.coords_of(anchor);
        let pos = tet.off.map(|o| {
            self.position([p[0] + o[0], p[1] + o[1], p[2] + o[2]])
                .as_dvec3()
        });
        let (d1, d2, d3) = (pos[1] - pos[0], pos[2] - pos[0], pos[3] - pos[0]);
        // D^-1 = [d2 x d3, d3 x d1, d1 x d2] / det, det > 0 for the lattice's tetrahedra.
        let g = d2.cross(d3) * (f[1] - f[0])
            + d3.cross(d1) * (f[2] - f[0])
            + d1.cross(d2) * (f[3] - f[0]);
        g.as_vec3().to_array()
    }

    /// Neighbour bits of the lattice edges at `p` that have every tetrahedron around them (a
    /// crossing there is an inner vertex of plain MT; at the box faces some are missing).
    pub(crate) fn inner_dirs(&self, p: Offset) -> u16 {
        if self.near_pyramid(p) {
            return 0;
        }
        if self.is_regular(p) {
            return FULL;
        }
        if self.border_table.is_empty() {
            return self.inner_dirs_of(p);
        }
        // Like `border_info`: the boundary class of each coordinate decides.
        let class = |a: usize| boundary_class(p[a], self.max_coord(a));
        let odd = match self.lattice {
            Lattice::BodyCentred => (p[0] & 1) as usize,
            Lattice::Simple => 0,
        };
        let e = self.border_table[((class(0) * CLASSES + class(1)) * CLASSES + class(2)) * 2 + odd];
        (e >> 17) as u16 & FULL
    }

    /// Whether, without ghosts ([`crate::Boundary::Pyramids`]), a tetrahedron around an edge of
    /// `p` may reach a pyramid of the box faces (`super::pyramids`): `p` lies within 3 lattice
    /// units (one and a half cells) of a box face. A tetrahedron spans at most 2 units per
    /// axis, so around the edges of a point 3 or more units inside, every corner is at least 1
    /// unit inside, and every pyramid edge has a corner on the face. Integrated clustering
    /// makes no proposal at such a point and treats its crossings as not inner (the additions
    /// skip them): no group's star touches a pyramid, whose triangles the quotient test does
    /// not see, and the pyramids' crossings stay plain.
    #[inline]
    pub(crate) fn near_pyramid(&self, p: Offset) -> bool {
        self.lattice == Lattice::BodyCentred
            && self.s.boundary == crate::Boundary::Pyramids
            && (0..3).any(|a| p[a] < 3 || p[a] > self.max_coord(a) - 3)
    }

    /// [`Layout::inner_dirs`] from the tetrahedra around `p` (what the border table stores).
    pub(crate) fn inner_dirs_of(&self, p: Offset) -> u16 {
        let mut missing = 0u16;
        for tet in &self.around[(p[0] & 1) as usize] {
            if !self.has_tet(p, tet) {
                missing |= tet.from_point;
            }
        }
        FULL & !missing
    }

    /// Neighbour bits of the lattice edges at `p` that belong to some tetrahedron.
    pub(crate) fn valid_neighbours(&self, p: Offset) -> u16 {
        if self.is_regular(p) {
            return FULL;
        }
        let mut mask = 0;
        for (d, o) in self.t.offsets.iter().enumerate() {
            let q = add(p, *o);
            let ok = match self.lattice {
                Lattice::Simple => (0..3).all(|a| q[a] >= 0 && q[a] <= self.max_coord(a)),
                // Ghost centres connect to real points only.
                Lattice::BodyCentred => {
                    self.s.bcdl_exists(q) && !(self.is_ghost(p) && self.is_ghost(q))
                }
            };
            if ok {
                mask |= 1 << d;
            }
        }
        mask
    }

    pub(crate) fn is_ghost(&self, p: Offset) -> bool {
        (0..3).any(|a| p[a] < 0 || p[a] > self.max_coord(a))
    }
}

/// The tetrahedra around lattice point `r` (which must be a lattice point of its parity), from
/// the lattice's templates translated over the cells near it; `idx` gives storage indices.
pub(crate) fn star_tets(
    lattice: Lattice,
    t: &LatticeTables,
    r: Offset,
    idx: &dyn Fn(Offset) -> isize,
) -> Vec<StarTet> {
    let mut out = Vec::with_capacity(24);
    for x in -2..=2 {
        for y in -2..=2 {
            for z in -2..=2 {
                let base = match lattice {
                    // Templates are relative to a cell centre (odd point).
                    Lattice::BodyCentred => {
                        let c = |v: i32, k: i32| 2 * ((v - 1).div_euclid(2) + k) + 1;
                        [c(r[0], x), c(r[1], y), c(r[2], z)]
                    }
                    Lattice::Simple => [r[0] + x, r[1] + y, r[2] + z],
                };
                for tet in &t.tetrahedra {
                    let abs = tet.map(|o| add(base, o));
                    if !abs.contains(&r) {
                        continue;
                    }
                    let off = abs.map(|v| [v[0] - r[0], v[1] - r[1], v[2] - r[2]]);
                    if out.iter().any(|s: &StarTet| s.off == off) {
                        continue;
                    }
                    let mut dir = [[u8::MAX; 4]; 4];
                    let mut from_point = 0u16;
                    for i in 0..4 {
                        for j in 0..4 {
                            if i != j {
                                let o = [
                                    off[j][0] - off[i][0],
                                    off[j][1] - off[i][1],
                                    off[j][2] - off[i][2],
                                ];
                                dir[i][j] = t.direction(o).map_or(u8::MAX, |d| d as u8);
                                if off[i] == [0; 3] {
                                    from_point |= 1 << dir[i][j];
                                }
                            }
                        }
                    }
                    out.push(StarTet {
                        off,
                        delta: abs.map(|v| idx(v) - idx(r)),
                        dir,
                        from_point,
                    });
                }
            }
        }
    }
    out
}

pub(crate) fn add(a: Offset, b: Offset) -> Offset {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mt::testing::{lcg, plain_mt, test_pool};

    #[test]
    fn group_cycles_are_the_case_tables_cycles_of_each_tetrahedron_in_template_order() {
        // For every group, code and anchor side, the group's cycles name, tetrahedron by
        // tetrahedron, the case table's crossed edges (corner a to corner b, a < b, and their
        // directions), and the crossed-edge mask holds exactly the edges they name.
        let pool = test_pool(1);
        let field = crate::mt::testing::wavy();
        let mut cycles = 0;
        for lattice in [Lattice::BodyCentred, Lattice::Simple] {
            let (_, samples, _, _) = plain_mt(&field, lattice, [4, 4, 4], &pool);
            let l = Layout::new(&samples, lattice);
            for (g, group) in l.groups.iter().enumerate() {
                let tets = match lattice {
                    Lattice::BodyCentred => &l.tets[4 * g..4 * g + 4],
                    Lattice::Simple => &l.tets[..],
                };
                assert!(group.edges.len() <= MAX_GROUP_EDGES, "{lattice:?}");
                // The geometry pass reads each edge's ends by these deltas.
                for (k, e) in group.edges.iter().enumerate() {
                    let ends = [e.from, e.to].map(|i| group.points[usize::from(i)]);
                    let read = EdgeRead {
                        deltas: ends,
                        dir: e.dir,
                    };
                    assert_eq!(group.edge_reads[k], read, "{lattice:?} group {g} edge {k}");
                    assert_ne!(ends[0], ends[1], "{lattice:?} group {g} edge {k}");
                }
                let point = |d: isize| group.points[..group.len].iter().position(|&p| p == d);
                for code in 0..1usize << group.len {
                    let mut named = 0u64;
                    for side in 0..2 {
                        let mut expected = Vec::new();
                        for (j, tpl) in tets.iter().enumerate() {
                            let corner = tpl.delta.map(|d| point(d).expect("a group point"));
                            let case = (0..4).fold(0, |c, i| c | ((code >> corner[i]) & 1) << i)
                                ^ (15 * side);
                            for &e in CASES[case].iter().filter(|&&e| e != u8::MAX) {
                                let (a, b) = TET_EDGES[e as usize];
                                let edge = GroupEdge {
                                    from: corner[a] as u8,
                                    to: corner[b] as u8,
                                    dir: [tpl.dir[a][b], tpl.dir[b][a]],
                                };
                                expected.push((j, CASES[case][3] == u8::MAX, edge));
                            }
                        }
                        let range = usize::from(group.cycle_start[2 * code + side])
                            ..usize::from(group.cycle_start[2 * code + side + 1]);
                        let mut got = Vec::new();
                        for cycle in &group.cycles[range] {
                            cycles += 1;
                            for &e in cycle.edges.iter().filter(|&&e| e != u8::MAX) {
                                named |= 1 << e;
                                got.push((
                                    usize::from(cycle.tet),
                                    cycle.edges[3] == u8::MAX,
                                    group.edges[usize::from(e)],
                                ));
                            }
                        }
                        assert_eq!(
                            got, expected,
                            "{lattice:?} group {g} code {code} side {side}"
                        );
                    }
                    assert_eq!(group.crossed_edges[code], named, "{lattice:?} group {g}");
                }
            }
        }
        assert!(cycles > 1000, "only {cycles} cycles");
    }

    #[test]
    fn positions_from_the_axis_tables_are_the_samples_positions_bit_for_bit() {
        let pool = test_pool(1);
        let field = crate::mt::testing::wavy();
        let mut checked = 0;
        for lattice in [Lattice::BodyCentred, Lattice::Simple] {
            for cells in [[3, 7, 5], [10, 9, 11]] {
                let (_, mut samples, _, _) = plain_mt(&field, lattice, cells, &pool);
                // An odd box and spacing, so that rounding would show.
                samples.min = glam::Vec3::new(-0.73, 0.311, 1.9);
                samples.spacing = glam::Vec3::new(0.0371, 0.113, 0.0667);
                let l = Layout::new(&samples, lattice);
                let max = |a: usize| l.max_coord(a);
                let lo = if lattice == Lattice::BodyCentred {
                    -1
                } else {
                    0
                };
                for x in lo..=max(0) + (-lo) {
                    for y in lo..=max(1) + (-lo) {
                        for z in lo..=max(2) + (-lo) {
                            let p = [x, y, z];
                            let want = match lattice {
                                Lattice::BodyCentred => samples.bcdl_position(p),
                                Lattice::Simple => {
                                    samples.simple_position(x as usize, y as usize, z as usize)
                                }
                            };
                            let got = l.position(p);
                            assert_eq!(
                                got.to_array().map(f32::to_bits),
                                want.to_array().map(f32::to_bits),
                                "{lattice:?} {cells:?} {p:?}"
                            );
                            checked += 1;
                        }
                    }
                }
            }
        }
        assert!(checked > 5000, "only {checked} points");
    }

    #[test]
    fn group_codes_and_cases_follow_the_crossed_edges_of_the_anchor() {
        // Every neighbour mask of the anchor: the code has bit i exactly when point i's edge
        // is crossed, and each tetrahedron's case (anchor outside) has bit j exactly when its
        // corner j is on the other side from the anchor.
        let samples = Samples {
            lattice: None,
            cells: [4, 4, 4],
            min: glam::Vec3::ZERO,
            spacing: glam::Vec3::ONE,
            dims: [6, 6, 11],
            values: vec![0.0; 6 * 6 * 11].into(),
            boundary: crate::Boundary::Ghosts,
        };
        for lattice in [Lattice::BodyCentred, Lattice::Simple] {
            let mut s = samples.clone();
            if lattice == Lattice::Simple {
                s.dims = [5, 5, 5];
                s.values = vec![0.0; 125].into();
            }
            let l = Layout::new(&s, lattice);
            for (g, group) in l.groups.iter().enumerate() {
                let tets = group.cases.len() >> group.len;
                assert!(tets == 4 || tets == 6, "{lattice:?} group {g}: {tets}");
                for mask in 0..1u16 << 14 {
                    let code = group.code(mask);
                    for i in 1..group.len {
                        let crossed = mask >> group.dirs[i] & 1 == 1;
                        assert_eq!(code >> i & 1 == 1, crossed, "{lattice:?} {g} {mask:#x} {i}");
                    }
                    assert_eq!(code & 1, 0, "the anchor is never on the other side");
                }
                let first = if lattice == Lattice::BodyCentred {
                    4 * g
                } else {
                    0
                };
                for code in 0..1usize << group.len {
                    for j in 0..tets {
                        let tpl = &l.tets[first + j];
                        let want = (0..4).fold(0u8, |case, i| {
                            let k = group.points[..group.len]
                                .iter()
                                .position(|&p| p == tpl.delta[i])
                                .expect("every corner is a point of the group");
                            case | (((code >> k) & 1) as u8) << i
                        });
                        assert_eq!(group.cases[code * tets + j], want, "{lattice:?} {g} {code}");
                    }
                }
            }
        }
    }
    use crate::{Clustering, ExtractSettings};

    #[test]
    fn the_tetrahedra_around_the_points_give_exactly_the_emitted_triangles() {
        // Every point sees 24 tetrahedra; over all points each tetrahedron of the extraction is
        // seen from its 4 corners, and their triangles (the quotient test's view) are exactly
        // the triangles the geometry pass writes, with the same orientation.
        let field = rmt_fields::FnField(|p: glam::Vec3| {
            (p.x * 5.3).sin() * (p.y * 3.9 + 0.2).cos() + (p.z * 4.7).sin() * 0.7 - 0.15
        });
        let pool = test_pool(1);
        for lattice in [Lattice::BodyCentred, Lattice::Simple] {
            for cells in [[3, 4, 5], [9, 8, 7]] {
                let (settings, samples, buf, mesh) = plain_mt(&field, lattice, cells, &pool);
                let l = Layout::new(&samples, lattice);
                assert_eq!(l.around[0].len(), 24, "{lattice:?}");
                assert_eq!(l.around[1].len(), 24, "{lattice:?}");
                for tet in l.around.iter().flatten() {
                    assert_eq!(crate::lattice::det(&tet.off).signum(), 1, "{lattice:?}");
                    assert_eq!(tet.from_point.count_ones(), 3);
                }
                let canonical = |t: [u32; 3]| {
                    let k = (0..3).min_by_key(|&i| t[i]).unwrap_or(0);
                    [t[k], t[(k + 1) % 3], t[(k + 2) % 3]]
                };
                let mut seen = std::collections::HashMap::new();
                let mut tets = 0;
                let [dx, dy, dz] = samples.dims;
                for z in 0..dz {
                    for sy in 0..dy {
                        for sx in 0..dx {
                            let (p, exists) = l.point(sx, sy, z);
                            if !exists {
                                continue;
                            }
                            let slot = (z * dy + sy) * dx + sx;
                            for tet in &l.around[(p[0] & 1) as usize] {
                                if !l.has_tet(p, tet) {
                                    continue;
                                }
                                tets += 1;
                                let idx = tet.delta.map(|d| (slot as isize + d) as usize);
                                let val = idx.map(|i| samples.values[i]);
                                let id = |o: usize, d: u8| buf.vertices.crossed.get(idx[o]).id(d);
                                let mut tris = [[0; 3]; 2];
                                let n = tet_triangles(
                                    val,
                                    settings.iso,
                                    &tet.dir,
                                    id,
                                    &mesh.positions,
                                    &mut tris,
                                );
                                for t in &tris[..n] {
                                    *seen.entry(canonical(*t)).or_insert(0) += 1;
                                }
                            }
                        }
                    }
                }
                let stats_tets = match lattice {
                    Lattice::BodyCentred => {
                        let [nx, ny, nz] = cells;
                        4 * ((nx + 1) * ny * nz + nx * (ny + 1) * nz + nx * ny * (nz + 1))
                    }
                    Lattice::Simple => 6 * cells.iter().product::<usize>(),
                };
                assert_eq!(tets, 4 * stats_tets, "{lattice:?} {cells:?}");
                let emitted: std::collections::HashSet<[u32; 3]> = mesh
                    .indices
                    .chunks_exact(3)
                    .map(|t| canonical([t[0], t[1], t[2]]))
                    .collect();
                assert_eq!(emitted.len() * 3, mesh.indices.len());
                assert!(seen.values().all(|&c| c == 4), "{lattice:?} {cells:?}");
                let seen: std::collections::HashSet<[u32; 3]> = seen.into_keys().collect();
                assert_eq!(seen, emitted, "{lattice:?} {cells:?}");
            }
        }
    }

    #[test]
    fn a_cached_border_table_is_the_one_built_for_the_same_lattice_and_cells() {
        let mut cache = BorderCache::default();
        let mut built = 0;
        for (lattice, cells) in [
            (Lattice::BodyCentred, [12, 14, 16]),
            (Lattice::BodyCentred, [12, 14, 16]),
            (Lattice::BodyCentred, [16, 14, 12]),
            (Lattice::Simple, [16, 14, 12]),
            (Lattice::BodyCentred, [16, 14, 12]),
            (Lattice::BodyCentred, [3, 4, 5]),
            (Lattice::Simple, [20, 12, 11]),
        ] {
            let settings = ExtractSettings::new(
                crate::Grid::new(cells, glam::Vec3::ZERO, glam::Vec3::ONE),
                lattice,
                Clustering::None,
            );
            let mut samples = Samples::default();
            samples.prepare(&settings);
            let fresh = Layout::new(&samples, lattice).border_table;
            let cached = Layout::cached(&samples, lattice, &mut cache).border_table;
            assert_eq!(cached, fresh, "{lattice:?} {cells:?}");
            built += usize::from(!fresh.is_empty());
        }
        // Six of the seven grids are large enough for the classes to have a table.
        assert_eq!(built, 6);
    }

    #[test]
    fn border_table_agrees_with_the_point_by_point_rules() {
        for lattice in [Lattice::BodyCentred, Lattice::Simple] {
            for cells in [[4, 5, 6], [5, 5, 5], [6, 11, 7], [12, 10, 13], [17, 16, 5]] {
                let settings = crate::ExtractSettings::new(
                    crate::Grid::new(cells, glam::Vec3::ZERO, glam::Vec3::ONE),
                    lattice,
                    crate::Clustering::None,
                );
                let mut samples = Samples::default();
                samples.prepare(&settings);
                let l = Layout::new(&samples, lattice);
                let big = (0..3).all(|a| l.max_coord(a) >= 10);
                assert_eq!(l.border_table.is_empty(), !big, "{cells:?}");
                let [dx, dy, dz] = samples.dims;
                for z in 0..dz {
                    for sy in 0..dy {
                        for sx in 0..dx {
                            let (p, exists) = l.point(sx, sy, z);
                            let valid = if exists { l.valid_neighbours(p) } else { 0 };
                            assert_eq!(
                                l.border_info(p),
                                (exists, valid),
                                "{lattice:?} {cells:?} at {p:?}"
                            );
                            if exists {
                                assert_eq!(
                                    l.inner_dirs(p),
                                    l.inner_dirs_of(p),
                                    "inner edges, {lattice:?} {cells:?} at {p:?}"
                                );
                            }
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn case_table_orients_triangles_along_the_gradient() {
        let mut s = 12345u64;
        let mut checked = 0;
        for _ in 0..2000 {
            let mut p: [glam::Vec3; 4] =
                [0; 4].map(|_| glam::Vec3::new(lcg(&mut s), lcg(&mut s), lcg(&mut s)));
            let vol = (p[1] - p[0]).dot((p[2] - p[0]).cross(p[3] - p[0]));
            if vol.abs() < 1e-3 {
                continue;
            }
            if vol < 0.0 {
                p.swap(2, 3);
            }
            let grad = glam::Vec3::new(lcg(&mut s), lcg(&mut s), lcg(&mut s));
            let off = lcg(&mut s) * 0.5;
            let f: Vec<f32> = p.iter().map(|q| q.dot(grad) + off).collect();
            let case = (0..4).filter(|&i| f[i] < 0.0).fold(0, |c, i| c | 1 << i);
            if case == 0 || case == 15 {
                continue;
            }
            let cycle = &CASES[case];
            let n = if cycle[3] == u8::MAX { 3 } else { 4 };
            let pts: Vec<glam::Vec3> = cycle[..n]
                .iter()
                .map(|&e| {
                    let (a, b) = TET_EDGES[e as usize];
                    // Each edge of the cycle must really be crossed.
                    assert_ne!(f[a] < 0.0, f[b] < 0.0, "case {case} edge {e} not crossed");
                    p[a].lerp(p[b], f[a] / (f[a] - f[b]))
                })
                .collect();
            for tri in [[0, 1, 2], [0, 2, 3]].iter().take(n - 2) {
                let nrm = (pts[tri[1]] - pts[tri[0]]).cross(pts[tri[2]] - pts[tri[0]]);
                if nrm.length() > 1e-6 {
                    assert!(
                        nrm.dot(grad) > 0.0,
                        "case {case} faces against the gradient"
                    );
                    checked += 1;
                }
            }
            // Every crossed edge of the tetrahedron appears in the cycle.
            let crossed = TET_EDGES
                .iter()
                .filter(|(a, b)| (f[*a] < 0.0) != (f[*b] < 0.0))
                .count();
            assert_eq!(crossed, n, "case {case}");
        }
        assert!(checked > 1000);
    }
}
