//! Marching tetrahedra on both lattices: the vertex pass, the clustering, and the geometry pass
//! (emission).
//!
//! **Vertex pass** (parallel over storage planes): for each sample point C and each of its
//! neighbours S, the edge C-S is crossed when C and S lie on opposite sides of the threshold T
//! (inside is f < T). The crossing belongs to the nearer end (|f - T| smaller; on a tie, the inside
//! end), so every crossing has exactly one owner and its vertex id does not depend on processing
//! order: ids are numbered by owner (storage order), then by neighbour index. Only points with a
//! crossed edge are stored (`CrossedIndex`: a bit per slot, a rank per 64 slots, and per crossed
//! point its 14 owned-crossing bits and the id of its first owned crossing), so
//! `id(C, d) = first(C) + popcount(owned(C) & ((1 << d) - 1))` with no table per slot beyond
//! those bits. With clustering, the pass also proposes clusters ([`crate::cluster`]).
//!
//! **Geometry pass** (parallel over z-layers): every tetrahedron whose corners disagree gives one
//! or two triangles from the case table. Each layer's triangles are counted first, from the
//! crossed edges of the face or cube anchors (`TetGroup` tables), so that every layer writes
//! into its own slice of the output in layer order: the same output for any thread count, and
//! the triangles stored once. Cubes (or body-centred faces) whose anchor has no crossed edge are
//! skipped before any tetrahedron is looked at.
//!
//! **Clustering** (between the two): the proposals are a partition of the crossings into groups
//! ([`crate::cluster`]: a point's islands, each sheet's own crossings cut into parts joined by
//! mesh edges; with integrated clustering also the lone crossings, given to a neighbouring
//! island). Integrated clustering then lists plain MT's triangles once (the same pass as the
//! emission, with each triangle's tetrahedron gradient and every crossing's triangles), keeps
//! the groups that pass the exact quotient test, repairing failures by splitting groups in
//! parallel rounds, and settles its additions the same way ([`crate::quotient`],
//! [`crate::repair`], [`crate::additions`]);
//! integrated-unchecked keeps every proposal. Every crossing then maps to an output vertex, and
//! the emission writes the triangles with those vertices directly (mapping the listed plain
//! triangles, or running the geometry pass), leaving out the ones that collapsed: no
//! intermediate mesh.
//!
//! Border rule: points on the box faces (whose lattice edges are cut by the box) cluster too, with
//! the missing neighbours counted as neither crossed nor uncrossed. A crossing whose edge lacks
//! some of its tetrahedra (it lies on the box face) is a vertex of the mesh boundary: integrated
//! clustering never groups it, so crossings on the box faces never move and the mesh stays
//! closed wherever the surface stays inside the box. (The unchecked mode has no such guarantee;
//! that is its point.)

use rayon::prelude::*;
use rmt_mesh::Mesh;

use crate::cluster::{self, Candidate, ProposalCounts, Rules, FULL};
use crate::lattice::{LatticeTables, Offset};
use crate::merge::MergeBuffers;
use crate::{CellRange, Clustering, ExtractError, ExtractSettings, Lattice, Samples, Stats};

/// Per-point working arrays kept between extractions.
#[derive(Default)]
pub struct MtBuffers {
    /// Which points have a crossed edge, and their owned crossings and ids ([`CrossedIndex`]).
    crossed: CrossedIndex,
    /// Per storage plane, its crossed points in slot order as `owned | crossed << 16` (the vertex
    /// pass's output, numbered into [`CrossedIndex::points`]).
    plane_points: Vec<Vec<u32>>,
    /// Proposed groups, in storage order of their owners.
    candidates: Vec<Candidate>,
    /// Positions of the crossings (plain MT's vertices), with clustering.
    cpos: Vec<[f32; 3]>,
    /// The groups' state: kept or not, each crossing's group, lone crossings, labels and
    /// vertex positions.
    groups: crate::quotient::Groups,
    /// Every crossing's owner slot and edge (the direction from the owner), with clustering.
    edge_of: Vec<(u32, u8)>,
    /// Plain MT's triangles (three crossing ids each) and their source tetrahedra, and every
    /// crossing's triangles (CSR), with checked clustering: the stars of the quotient test.
    plain: Vec<u32>,
    plain_grad: Vec<[f32; 3]>,
    inc_start: Vec<u32>,
    inc: Vec<u32>,
    /// Output vertex of each crossing, with clustering.
    vertex_of: Vec<u32>,
    /// Working memory of the vertex compaction (integrated-unchecked).
    scratch: Vec<u32>,
    /// One bit per storage slot, set where the value is inside (`f < iso`), plus one zero word
    /// of padding: 64 points are tested for crossings at once with a few word operations.
    inside: Vec<u64>,
    /// [`crate::BufferPolicy::Lean`]: free every table when its last reader is done.
    pub(crate) lean: bool,
}

impl MtBuffers {
    /// Bytes of the per-point tables (crossed points, per-plane lists, inside bits, candidates).
    fn table_bytes(&self) -> usize {
        self.crossed.bytes()
            + self.plane_points.iter().map(|o| o.len() * 4).sum::<usize>()
            + self.inside.len() * 8
            + self.candidates.len() * std::mem::size_of::<Candidate>()
            + self.cpos.len() * 12
            + self.groups.bytes()
            + self.edge_of.len() * 8
            + self.plain.len() * 4
            + self.plain_grad.len() * 12
            + self.inc_start.len() * 4
            + self.inc.len() * 4
            + self.vertex_of.len() * 4
    }
}

/// A point with a crossed edge: the id of its first owned crossing and its owned crossings (bit d:
/// the crossing on the edge to neighbour d). `id(C, d) = first + popcount(owned & ((1 << d) - 1))`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) struct CrossedPoint {
    first: u32,
    owned: u16,
    /// All its crossed edges (owned or not), by neighbour bit.
    crossed: u16,
}

impl CrossedPoint {
    /// Id of the crossing this point owns on its edge to neighbour `d`.
    #[inline(always)]
    pub(crate) fn id(self, d: u8) -> u32 {
        self.first + (self.owned & ((1u16 << d) - 1)).count_ones()
    }
}

/// The points with a crossed edge, found from any storage slot in a few operations and stored
/// sparsely: a bit per slot, the number of set bits before each word (a rank directory), and one
/// [`CrossedPoint`] per set bit. About 1.5 bits per slot plus 8 bytes per crossed point, where a
/// dense table of owned bits and ids took 3.25 bytes per slot.
///
/// The bits are kept per storage plane ([`plane_words`] words each, the last one padding) so that
/// planes are written in parallel; a slot's plane comes from a division by a multiplication.
#[derive(Default)]
pub(crate) struct CrossedIndex {
    /// One bit per storage slot, set where the point has a crossed edge (owned or not).
    bits: Vec<u64>,
    /// Per word of `bits`: how many bits are set in the words before it.
    rank: Vec<u32>,
    /// The crossed points in storage order (rank order).
    points: Vec<CrossedPoint>,
    /// Slots per storage plane, and words per plane.
    plane: usize,
    wpp: usize,
    /// `ceil(2^64 / plane)`: `slot / plane == (slot * div) >> 64` for every slot below 2^32
    /// (Lemire, Kaser and Kurz 2019); 0 when a plane has one slot.
    div: u64,
}

impl CrossedIndex {
    /// Bits cleared and sized for `planes` storage planes of `plane` slots; the rest is filled by
    /// [`CrossedIndex::rank_planes`] and the numbering.
    fn reset(&mut self, plane: usize, planes: usize) {
        self.plane = plane;
        self.wpp = plane_words(plane);
        self.div = if plane > 1 {
            u64::MAX / plane as u64 + 1
        } else {
            0
        };
        self.bits.clear();
        self.bits.resize(self.wpp * planes, 0);
        self.rank.resize(self.bits.len(), 0);
    }

    /// The storage plane of `slot` (below 2^32).
    #[inline(always)]
    fn plane_of(&self, slot: usize) -> usize {
        if self.div == 0 {
            return slot;
        }
        ((u128::from(self.div) * slot as u128) >> 64) as usize
    }

    /// Word of `bits` holding `slot`, and the slot's bit in it.
    #[cfg(test)]
    fn word(&self, slot: usize) -> (usize, usize) {
        let z = self.plane_of(slot);
        let local = slot - z * self.plane;
        (z * self.wpp + (local >> 6), local & 63)
    }

    /// Whether `slot` has a crossed edge.
    #[cfg(test)]
    fn is_crossed(&self, slot: usize) -> bool {
        let (w, b) = self.word(slot);
        self.bits[w] >> b & 1 != 0
    }

    /// The entry of a crossed `slot` (meaningless for others).
    #[inline(always)]
    pub(crate) fn get(&self, slot: usize) -> CrossedPoint {
        let z = self.plane_of(slot);
        self.points[self.rank_in(z, slot - z * self.plane)]
    }

    /// The rank of slot `local` of storage plane `z`: how many crossed points come before it.
    #[inline(always)]
    fn rank_in(&self, z: usize, local: usize) -> usize {
        let (w, b) = (z * self.wpp + (local >> 6), local & 63);
        (self.rank[w] + (self.bits[w] & ((1u64 << b) - 1)).count_ones()) as usize
    }

    /// Bits of plane `z`.
    fn plane_bits(&self, z: usize) -> &[u64] {
        &self.bits[z * self.wpp..(z + 1) * self.wpp]
    }

    /// Fills the rank directory, given the number of crossed points before each plane
    /// (`starts[z]`), and sizes `points`.
    fn rank_planes(&mut self, starts: &[usize], total: usize, pool: &rayon::ThreadPool) {
        let wpp = self.wpp;
        pool.install(|| {
            self.rank
                .par_chunks_mut(wpp)
                .zip(self.bits.par_chunks(wpp))
                .zip(starts.par_iter())
                .for_each(|((rank, bits), &start)| {
                    let mut r = start as u32;
                    for (out, w) in rank.iter_mut().zip(bits) {
                        *out = r;
                        r += w.count_ones();
                    }
                });
        });
        self.points.resize(total, CrossedPoint::default());
    }

    fn bytes(&self) -> usize {
        self.bits.len() * 8 + self.rank.len() * 4 + self.points.len() * 8
    }
}

/// Words of the crossed-point bit set per storage plane of `plane` slots: one bit per slot plus
/// a zero word of padding, so that 64 bits can be read from any slot of the plane.
fn plane_words(plane: usize) -> usize {
    plane.div_ceil(64) + 1
}

/// Calls `visit(n)` for each set bit `n < len` of the bit set `words` counted from bit `start`.
#[inline(always)]
fn for_each_bit(words: &[u64], start: usize, len: usize, mut visit: impl FnMut(usize)) {
    let mut n = 0;
    while n < len {
        let take = (len - n).min(64);
        let mut bits = bits_at(words, start + n);
        if take < 64 {
            bits &= (1u64 << take) - 1;
        }
        while bits != 0 {
            visit(n + bits.trailing_zeros() as usize);
            bits &= bits - 1;
        }
        n += take;
    }
}

/// Bit k set where `values[k] < iso` (at most 64 values). A full word is built a byte at a time,
/// which the compiler turns into wide comparisons (about 40% faster than bit by bit).
#[inline(always)]
fn inside_word(values: &[f32], iso: f32) -> u64 {
    match <&[f32; 64]>::try_from(values) {
        Ok(v) => {
            let mut bytes = [0u8; 8];
            for (b, c) in bytes.iter_mut().zip(v.as_chunks::<8>().0) {
                *b = c
                    .iter()
                    .enumerate()
                    .fold(0u8, |b, (k, &f)| b | (u8::from(f < iso) << k));
            }
            u64::from_le_bytes(bytes)
        }
        Err(_) => values
            .iter()
            .enumerate()
            .fold(0u64, |x, (k, &f)| x | (u64::from(f < iso) << k)),
    }
}

/// The 64 bits of `words` starting at bit `pos` (bit k = slot `pos + k`); `words` has one word
/// of padding past the last slot.
#[inline(always)]
fn bits_at(words: &[u64], pos: usize) -> u64 {
    let (w, s) = (pos >> 6, pos & 63);
    let lo = words[w] >> s;
    if s == 0 {
        lo
    } else {
        lo | (words[w + 1] << (64 - s))
    }
}

/// Which of the `len` (<= 64) points from slot `i` on have a crossed edge: the inside bits of the
/// points against those of each neighbour (all 14 must exist: the fast path of a row).
#[inline(always)]
fn crossed_points(inside: &[u64], i: usize, delta: &[isize; 14], len: usize) -> u64 {
    let own = bits_at(inside, i);
    let mut any = 0u64;
    for &off in delta {
        any |= own ^ bits_at(inside, (i as isize + off) as usize);
    }
    if len < 64 {
        any &= (1u64 << len) - 1;
    }
    any
}

/// Passes of lone crossings after the islands settle (each: give, then test and repair).
const LONE_PASSES: usize = 3;

/// Passes over the slivers left after the lone passes (each: propose, then test and repair).
const SLIVER_PASSES: usize = 2;

/// Crossings nearer than this many grid spacings to their owner are counted (surfaces through
/// sample points): the meshoptimizer mode welds them first.
const WELD: f32 = 1e-4;

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
/// diagonal) as crossing ids, oriented by the case table: the one definition that the emission
/// and the quotient test share, so that the test sees exactly the triangles that are written.
/// `val`: the corner values; `dir[i][j]`: neighbour index of corner j from corner i; `id(o, d)`:
/// the id of the crossing owned by corner `o` on its edge to neighbour `d`.
#[inline(always)]
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
    if case == 0 || case == 15 {
        return 0;
    }
    let cycle = &CASES[case];
    let n = if cycle[3] == u8::MAX { 3 } else { 4 };
    let mut ids = [0u32; 4];
    for (slot, &e) in ids.iter_mut().zip(cycle.iter()).take(n) {
        let (a, b) = TET_EDGES[e as usize];
        let (o, d) = if owns(val[a], val[b], iso) {
            (a, dir[a][b])
        } else {
            (b, dir[b][a])
        };
        *slot = id(o, d);
    }
    if n == 3 {
        out[0] = [ids[0], ids[1], ids[2]];
        1
    } else {
        // Split along the shorter diagonal, chosen by a table index rather than a branch (the
        // choice is data-dependent and mispredicts half the time).
        const SPLITS: [[usize; 6]; 2] = [[1, 2, 3, 1, 3, 0], [0, 1, 2, 0, 2, 3]];
        let p = |i: u32| glam::Vec3::from(positions[i as usize]);
        let short02 =
            p(ids[0]).distance_squared(p(ids[2])) <= p(ids[1]).distance_squared(p(ids[3]));
        let s = &SPLITS[usize::from(short02)];
        out[0] = [ids[s[0] & 3], ids[s[1] & 3], ids[s[2] & 3]];
        out[1] = [ids[s[3] & 3], ids[s[4] & 3], ids[s[5] & 3]];
        2
    }
}

/// Whether the end with value `f` (inside iff `f < iso`) owns the crossing shared with `g`.
#[inline(always)]
pub(crate) fn owns(f: f32, g: f32, iso: f32) -> bool {
    let (df, dg) = ((f - iso).abs(), (g - iso).abs());
    df < dg || (df == dg && f < iso)
}

/// A tetrahedron with storage-index deltas from a reference point and edge directions.
#[derive(Clone, Copy, Debug)]
pub(crate) struct TetTemplate {
    /// Lattice offsets of the corners from the anchor.
    pub(crate) off: [Offset; 4],
    pub(crate) delta: [isize; 4],
    /// `dir[i][j]`: neighbour index of corner j seen from corner i.
    dir: [[u8; 4]; 4],
}

/// The tetrahedra visited together (a body-centred face's 4 around the centres A and B, with 6
/// distinct points; a cube's 6, with 8 corners) and the number of triangles they give for each
/// inside/outside pattern of those points, derived from the case table: the geometry pass counts
/// a layer's triangles from the anchors' crossed edges before it writes them.
#[derive(Clone, Debug, Default)]
struct TetGroup {
    /// Storage deltas of its distinct points from the anchor (point 0, in every tetrahedron of
    /// the group).
    points: [isize; 8],
    /// Neighbour index of each point seen from the anchor (`u8::MAX` for the anchor itself).
    dirs: [u8; 8],
    len: usize,
    /// Triangles of its tetrahedra when the points with bit i set in the index are inside.
    /// A tetrahedron gives as many triangles with its sides swapped, so this is also the count
    /// when bit i says "point i is on the other side from the anchor", i.e. the anchor's
    /// crossed edges: no sample value needs reading.
    triangles: Vec<u8>,
}

impl TetGroup {
    /// The group of templates `tets` (corners given by their storage deltas).
    fn new(tets: &[TetTemplate]) -> Self {
        let mut group = Self {
            len: 1,
            dirs: [u8::MAX; 8],
            ..Self::default()
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
        group.triangles = (0..1usize << group.len)
            .map(|code| {
                corners
                    .iter()
                    .map(|c| {
                        let case = (0..4).fold(0, |case, i| case | ((code >> c[i]) & 1) << i);
                        case_triangles(case)
                    })
                    .sum()
            })
            .collect();
        group
    }
}

/// Triangles a tetrahedron gives in `case` (bit i: corner i inside): none, one, or two (a quad).
fn case_triangles(case: usize) -> u8 {
    match CASES[case] {
        [u8::MAX, ..] => 0,
        [_, _, _, u8::MAX] => 1,
        _ => 2,
    }
}

/// The lattice in storage terms: neighbour deltas per parity and tetrahedron templates.
pub(crate) struct Layout<'a> {
    pub(crate) s: &'a Samples,
    lattice: Lattice,
    t: &'static LatticeTables,
    /// Storage-index delta of neighbour d, for even (`[0]`) and odd (`[1]`) points.
    delta: [[isize; 14]; 2],
    pub(crate) tets: Vec<TetTemplate>,
    /// The tetrahedra visited together: per face axis (body-centred) or the cube (simple).
    groups: Vec<TetGroup>,
    /// Existence (bit 16), valid-neighbour mask (bits 0..14) and inner-edge mask (bits 17..31,
    /// [`Layout::inner_dirs`]) of a point by the boundary class of each coordinate ([`boundary_class`]) and its parity; empty for grids too small
    /// for the classes to be apart (then computed point by point).
    border_table: Vec<u32>,
    /// The tetrahedra around a point of each parity (`[0]` even, `[1]` odd): 24 on both
    /// lattices ([`StarTet`]).
    pub(crate) around: [Vec<StarTet>; 2],
    /// Per template: `[d2 x d3, d3 x d1, d1 x d2]` for its edge vectors `d_i` from corner 0 on
    /// the lattice (the gradient of the linear interpolant is their sum weighted by the value
    /// differences, up to the positive determinant).
    grad_coef: Vec<[glam::DVec3; 3]>,
}

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
const CLASSES: usize = 11;

/// The class of lattice coordinate `c` on an axis whose largest coordinate is `max`: points of
/// one class see the same neighbours exist (offsets reach at most 2 lattice units).
#[inline(always)]
fn boundary_class(c: i32, max: i32) -> usize {
    if c <= 3 {
        (c + 1).max(0) as usize
    } else if c >= max - 3 {
        (5 + (c - (max - 3))).min(9) as usize
    } else {
        10
    }
}

impl<'a> Layout<'a> {
    fn new(s: &'a Samples, lattice: Lattice) -> Self {
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
        let groups = match lattice {
            Lattice::BodyCentred => tets.chunks(4).map(TetGroup::new).collect(),
            Lattice::Simple => vec![TetGroup::new(&tets)],
        };
        let around = [0, 1].map(|par| star_tets(lattice, t, refs[par], &idx));
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
        let mut layout = Self {
            s,
            lattice,
            t,
            delta,
            tets,
            groups,
            border_table: Vec::new(),
            around,
            grad_coef,
        };
        layout.border_table = layout.build_border_table();
        layout
    }

    /// The table behind [`Layout::border_info`]: one representative point per class triple
    /// and parity (the coordinate itself for the border classes, 4 or 5 for the middle one).
    fn build_border_table(&self) -> Vec<u32> {
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
    fn border_info(&self, p: Offset) -> (bool, u16) {
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

    /// Lattice coordinates of storage slot (sx, sy) of plane z.
    #[inline]
    fn coords(&self, sx: usize, sy: usize, z: usize) -> Offset {
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
    fn point(&self, sx: usize, sy: usize, z: usize) -> (Offset, bool) {
        let p = self.coords(sx, sy, z);
        match self.lattice {
            Lattice::Simple => (p, true),
            Lattice::BodyCentred => (p, self.s.bcdl_exists(p)),
        }
    }

    pub(crate) fn position(&self, p: Offset) -> glam::Vec3 {
        match self.lattice {
            Lattice::BodyCentred => self.s.bcdl_position(p),
            Lattice::Simple => self
                .s
                .simple_position(p[0] as usize, p[1] as usize, p[2] as usize),
        }
    }

    /// The storage planes geometry layer `k` reads (inclusive): body-centred faces perpendicular
    /// to z are anchored in plane 2k and reach 2k + 2, those perpendicular to x and y are
    /// anchored in plane 2k + 2 and reach 2k + 1 ..= 2k + 3; cubes of layer k span planes k and
    /// k + 1.
    fn layer_planes(&self, k: usize) -> (usize, usize) {
        let last = self.s.dims[2] - 1;
        match self.lattice {
            Lattice::BodyCentred => (2 * k, (2 * k + 3).min(last)),
            Lattice::Simple => (k, (k + 1).min(last)),
        }
    }

    /// Largest lattice coordinate per axis.
    fn max_coord(&self, a: usize) -> i32 {
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
    pub(crate) fn gradient(&self, anchor: usize, ti: usize) -> [f32; 3] {
        let tet = &self.tets[ti];
        let f = tet
            .delta
            .map(|d| f64::from(self.s.values[(anchor as isize + d) as usize]));
        // Away from the ghosts (clamped onto the box faces) the corners sit on the lattice:
        // the edge vectors, and so the coefficients, are the template's.
        let p = match self.lattice {
            Lattice::Simple => None,
            Lattice::BodyCentred => Some(self.coords_of(anchor)),
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

    /// [`Layout::inner_dirs`] from the tetrahedra around `p` (what the border table stores).
    fn inner_dirs_of(&self, p: Offset) -> u16 {
        let mut missing = 0u16;
        for tet in &self.around[(p[0] & 1) as usize] {
            if !self.has_tet(p, tet) {
                missing |= tet.from_point;
            }
        }
        FULL & !missing
    }

    /// Neighbour bits of the lattice edges at `p` that belong to some tetrahedron.
    fn valid_neighbours(&self, p: Offset) -> u16 {
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

    fn is_ghost(&self, p: Offset) -> bool {
        (0..3).any(|a| p[a] < 0 || p[a] > self.max_coord(a))
    }
}

/// The tetrahedra around lattice point `r` (which must be a lattice point of its parity), from
/// the lattice's templates translated over the cells near it; `idx` gives storage indices.
fn star_tets(
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

fn add(a: Offset, b: Offset) -> Offset {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

/// Counters of one plane of the vertex pass.
#[derive(Default, Clone, Copy)]
struct PlaneCounts {
    crossings: usize,
    edges: usize,
    proposals: ProposalCounts,
}

/// Extracts the surface of `samples` with marching tetrahedra (and clustering) into `mesh`.
pub fn extract(
    samples: &Samples,
    settings: &ExtractSettings,
    pool: &rayon::ThreadPool,
    buf: &mut MtBuffers,
    merge: &mut MergeBuffers,
    mesh: &mut Mesh,
    stats: &mut Stats,
) -> Result<(), ExtractError> {
    let lattice = settings.lattice;
    let layout = Layout::new(samples, lattice);
    let iso = settings.iso;
    let clustering = settings.clustering;
    // Tetrahedra with a triangle, counted by the pass that wrote plain MT's triangles.
    let mut plain_processed = 0;
    let propose = matches!(
        clustering,
        Clustering::Integrated | Clustering::IntegratedUnchecked
    );
    let rules = if clustering == Clustering::Integrated {
        Rules::Islands
    } else {
        Rules::Dissertation
    };
    let mut keys: Vec<u64> = Vec::new();

    // Allocation: per-slot tables sized to the sample array.
    let t = std::time::Instant::now();
    let slots = samples.values.len();
    if slots > u32::MAX as usize {
        return Err(ExtractError::TooLarge {
            cells: samples.cells,
            limit: u32::MAX as usize,
        });
    }
    buf.candidates.clear();
    let words = slots.div_ceil(64);
    buf.inside.resize(words + 1, 0);
    let plane = samples.dims[0] * samples.dims[1];
    let planes = samples.dims[2];
    buf.crossed.reset(plane, planes);
    if buf.plane_points.len() < planes {
        buf.plane_points.resize_with(planes, Vec::new);
    }
    stats.t_allocation_s += t.elapsed().as_secs_f64();

    // Vertex pass, step 0: the inside bits.
    let t = std::time::Instant::now();
    {
        let values = &samples.values;
        pool.install(|| {
            buf.inside[..words]
                .par_chunks_mut(1024)
                .enumerate()
                .for_each(|(c, chunk)| {
                    for (j, word) in chunk.iter_mut().enumerate() {
                        let start = (c * 1024 + j) * 64;
                        let end = (start + 64).min(slots);
                        *word = inside_word(&values[start..end], iso);
                    }
                });
        });
        buf.inside[words] = 0;
    }

    // Vertex pass, step 1: owned crossings and proposals per plane.
    let inside = &buf.inside;
    let wpp = buf.crossed.wpp;
    let per_plane: Vec<(PlaneCounts, Vec<Candidate>)> = pool.install(|| {
        buf.plane_points[..planes]
            .par_iter_mut()
            .zip(buf.crossed.bits.par_chunks_mut(wpp))
            .enumerate()
            .map(|(z, (owned, crossed))| {
                vertex_plane(
                    &layout,
                    inside,
                    z,
                    iso,
                    propose.then_some(rules),
                    owned,
                    crossed,
                )
            })
            .collect()
    });
    let mut starts = Vec::with_capacity(per_plane.len() + 1);
    let mut point_starts = Vec::with_capacity(per_plane.len() + 1);
    let mut total = 0usize;
    let mut total_points = 0usize;
    let mut proposals = ProposalCounts::default();
    for (z, (c, cands)) in per_plane.iter().enumerate() {
        starts.push(total);
        total += c.crossings;
        point_starts.push(total_points);
        total_points += buf.plane_points[z].len();
        stats.edges += c.edges;
        proposals.add(c.proposals);
        let start = starts[z] as u32;
        buf.candidates.extend(cands.iter().map(|c| Candidate {
            first: start + c.first,
            ..*c
        }));
    }
    stats.edges /= 2;
    stats.crossings = total;
    if total > u32::MAX as usize - 1 {
        return Err(ExtractError::TooLarge {
            cells: samples.cells,
            limit: u32::MAX as usize,
        });
    }
    buf.crossed.rank_planes(&point_starts, total_points, pool);
    // Step 2: number the crossings and place them.
    let near_points;
    mesh.positions.resize(total, [0.0; 3]);
    {
        let mut rest: &mut [[f32; 3]] = &mut mesh.positions;
        let mut chunks = Vec::with_capacity(per_plane.len());
        for (c, _) in &per_plane {
            let (head, tail) = rest.split_at_mut(c.crossings);
            chunks.push(head);
            rest = tail;
        }
        // Plane z numbers its crossed points.
        let CrossedIndex { bits, points, .. } = &mut buf.crossed;
        let mut rest: &mut [CrossedPoint] = points;
        let mut entries = Vec::with_capacity(per_plane.len());
        for owned in &buf.plane_points[..planes] {
            let (head, tail) = rest.split_at_mut(owned.len());
            entries.push(head);
            rest = tail;
        }
        let (bits, plane_points) = (&*bits, &buf.plane_points);
        near_points = pool.install(|| {
            entries
                .into_par_iter()
                .zip(chunks.into_par_iter())
                .enumerate()
                .map(|(z, (entries, out))| {
                    number_plane(
                        &layout,
                        z,
                        iso,
                        &plane_points[z],
                        &bits[z * wpp..(z + 1) * wpp],
                        starts[z] as u32,
                        entries,
                        out,
                    )
                })
                .sum::<usize>()
        });
    }
    // The per-plane proposals were copied into `buf.candidates`: free them before the geometry
    // pass and the clustering allocate.
    drop(per_plane);
    if let Some(tiling) = &settings.tiles {
        if propose || clustering == Clustering::Postprocessed {
            let crossed = &buf.crossed;
            crate::tiles::crossing_keys(
                samples,
                tiling,
                |visit| {
                    let mut r = 0;
                    for z in 0..planes {
                        for_each_bit(crossed.plane_bits(z), 0, plane, |local| {
                            visit(z * plane + local, crossed.points[r].owned);
                            r += 1;
                        });
                    }
                },
                &mut keys,
            );
        }
    }
    let tiled = settings.tiles.is_some();
    stats.clusters_proposed = proposals.proposed;
    stats.clusters_rejected_prefilter = proposals.rejected;
    if propose {
        cluster(
            buf,
            &layout,
            iso,
            clustering,
            rules,
            tiled.then_some(&keys[..]),
            mesh,
            stats,
            &mut plain_processed,
            pool,
        );
    }
    stats.t_vertex_s += t.elapsed().as_secs_f64();

    // Emission: the final triangles, written straight into the mesh.
    let t = std::time::Instant::now();
    let crossed = &buf.crossed;
    let keep = settings.keep_cells;
    if propose && keep.is_none() && !buf.plain.is_empty() {
        // The plain triangles are at hand (the quotient test read them): map them through the
        // groups, in order, dropping the collapsed ones.
        let (plain, map) = (&buf.plain[..], &buf.vertex_of[..]);
        const CHUNK: usize = 3 << 14;
        let mapped = |t: &[u32]| {
            let q = [t[0], t[1], t[2]].map(|i| map[i as usize]);
            (q[0] != q[1] && q[1] != q[2] && q[0] != q[2]).then_some(q)
        };
        let counts: Vec<usize> = pool.install(|| {
            plain
                .par_chunks(CHUNK)
                .map(|c| c.chunks_exact(3).filter(|t| mapped(t).is_some()).count())
                .collect()
        });
        let kept: usize = counts.iter().sum();
        let indices = &mut mesh.indices;
        indices.clear();
        indices.resize(3 * kept, 0);
        let mut parts = Vec::with_capacity(counts.len());
        let mut rest = &mut indices[..];
        for &n in &counts {
            let (head, tail) = rest.split_at_mut(3 * n);
            parts.push(head);
            rest = tail;
        }
        pool.install(|| {
            plain
                .par_chunks(CHUNK)
                .zip(parts.into_par_iter())
                .for_each(|(c, out)| {
                    for (q, o) in c
                        .chunks_exact(3)
                        .filter_map(mapped)
                        .zip(out.chunks_exact_mut(3))
                    {
                        o.copy_from_slice(&q);
                    }
                })
        });
        stats.tetrahedra_processed += plain_processed;
        stats.discarded += plain.len() / 3 - kept;
    } else {
        emit_layers(&layout, iso, keep, crossed, propose, buf, mesh, pool, stats);
    }
    if clustering == Clustering::IntegratedUnchecked {
        // Without the test a vertex may lose all its triangles.
        mesh.drop_unused_vertices(&mut buf.scratch);
    }
    let [nx, ny, nz] = samples.cells;
    stats.tetrahedra_total = match lattice {
        Lattice::BodyCentred => 4 * ((nx + 1) * ny * nz + nx * (ny + 1) * nz + nx * ny * (nz + 1)),
        Lattice::Simple => 6 * nx * ny * nz,
    };
    stats.t_geometry_s += t.elapsed().as_secs_f64();
    // Lean: the per-point tables have no reader left.
    let mut lean_bytes = 0;
    if buf.lean {
        lean_bytes = buf.table_bytes();
        buf.crossed = CrossedIndex::default();
        buf.inside = Vec::new();
        buf.plane_points = Vec::new();
        buf.plain = Vec::new();
        buf.plain_grad = Vec::new();
        buf.inc_start = Vec::new();
        buf.inc = Vec::new();
        buf.edge_of = Vec::new();
        buf.groups = crate::quotient::Groups::default();
        pool.broadcast(|_| LAYER_WINDOW.with_borrow_mut(|w| *w = Vec::new()));
    }
    stats.clusters_rejected = stats.clusters_rejected_prefilter + stats.clusters_rejected_check;

    // Post-processing counts in the geometry pass, as in the dissertation.
    if clustering == Clustering::Postprocessed {
        let t = std::time::Instant::now();
        let h = settings.grid.h();
        let (collapses, dropped) = crate::collapse::collapse_short_edges_tiled(
            merge,
            mesh,
            settings.collapse_threshold * h,
            tiled.then_some(&keys[..]),
        );
        stats.collapses = collapses;
        stats.discarded += dropped;
        stats.t_geometry_s += t.elapsed().as_secs_f64();
    } else if clustering == Clustering::Meshopt {
        let t = std::time::Instant::now();
        if near_points > 0 {
            // meshoptimizer tells vertices apart by index: crossings on top of each other (the
            // surface through sample points) would look like seams and open holes. Weld them
            // first, under the exact check (integrated clustering groups them as one island).
            weld_coincident(merge, mesh, settings, None, stats);
        }
        stats.discarded +=
            crate::simplify::meshopt_simplify(mesh, settings.grid.h(), settings.collapse_threshold);
        stats.t_geometry_s += t.elapsed().as_secs_f64();
    }

    stats.bytes_edges = if buf.lean {
        // Measured before they were released.
        lean_bytes
    } else {
        buf.table_bytes()
            + if matches!(clustering, Clustering::Postprocessed | Clustering::Meshopt) {
                merge.bytes()
            } else {
                0
            }
    };
    if buf.lean {
        *merge = MergeBuffers::default();
        *buf = MtBuffers {
            lean: true,
            ..MtBuffers::default()
        };
        mesh.positions.shrink_to_fit();
        mesh.indices.shrink_to_fit();
    }
    Ok(())
}

/// The group tables of the proposals in `buf.candidates`, every group kept: each crossing's
/// group, each group's leader (lowest crossing id) and vertex position (the mean of its
/// crossings); and `buf.edge_of`, every crossing's owner slot and edge.
fn build_groups(buf: &mut MtBuffers, layout: &Layout, pool: &rayon::ThreadPool) {
    use crate::quotient::NONE;
    let crossings = buf.cpos.len();
    let MtBuffers {
        candidates,
        cpos,
        groups: g,
        crossed,
        edge_of,
        ..
    } = buf;
    let count = candidates.len();
    g.group_of.clear();
    g.group_of.resize(crossings, NONE);
    for (gi, c) in candidates.iter().enumerate() {
        for id in c.ids() {
            g.group_of[id as usize] = gi as u32;
        }
    }
    let cpos = &*cpos;
    pool.install(|| {
        candidates
            .par_iter()
            .map(|c| {
                let mut sum = glam::Vec3::ZERO;
                for id in c.ids() {
                    sum += glam::Vec3::from(cpos[id as usize]);
                }
                (sum / c.size() as f32).to_array()
            })
            .collect_into_vec(&mut g.centroid)
    });
    g.leader.clear();
    g.leader.extend(candidates.iter().map(|c| c.leader()));
    g.active.clear();
    g.active.resize(count, 1);
    g.lone.clear();
    g.lone_start.clear();
    g.lone_start.resize(count + 1, 0);
    g.lone_len.clear();
    g.lone_len.resize(count, 0);
    g.base_len.clear();
    g.base_len.resize(count, 0);
    g.refused.clear();
    g.refused.resize(crossings, NONE);
    // Every crossing's edge: plane by plane, points in slot order, edges in bit order, which
    // is the order of the ids.
    let plane = layout.s.dims[0] * layout.s.dims[1];
    let crossed = &*crossed;
    let per_plane: Vec<Vec<(u32, u8)>> = pool.install(|| {
        (0..layout.s.dims[2])
            .into_par_iter()
            .map(|z| {
                let mut out = Vec::new();
                let mut r = crossed.rank_in(z, 0);
                for_each_bit(crossed.plane_bits(z), 0, plane, |local| {
                    let entry = crossed.points[r];
                    r += 1;
                    let mut own = entry.owned;
                    while own != 0 {
                        out.push(((z * plane + local) as u32, own.trailing_zeros() as u8));
                        own &= own - 1;
                    }
                });
                out
            })
            .collect()
    });
    edge_of.clear();
    edge_of.reserve(crossings);
    for part in per_plane {
        edge_of.extend_from_slice(&part);
    }
    debug_assert_eq!(edge_of.len(), crossings);
}

/// The clustering steps between the vertex pass and the emission (`propose`): the proposals
/// under the tile rule, the group tables, and with integrated (checked) clustering plain MT's
/// triangle list, the islands' quotient tests and repair ([`crate::repair`]), then the
/// additions ([`crate::additions`]); at the end every crossing's output vertex
/// (`buf.vertex_of`) and the vertex positions (`mesh.positions`; the crossings' own move to
/// `buf.cpos`). `keys`: the tile rule's keys, when tiled. Counts the tetrahedra that the
/// triangle list read into `plain_processed`.
#[allow(clippy::too_many_arguments)]
fn cluster(
    buf: &mut MtBuffers,
    layout: &Layout,
    iso: f32,
    clustering: Clustering,
    rules: Rules,
    keys: Option<&[u64]>,
    mesh: &mut Mesh,
    stats: &mut Stats,
    plain_processed: &mut usize,
    pool: &rayon::ThreadPool,
) {
    let tiled = keys.is_some();
    let keys = keys.unwrap_or(&[]);
    // The crossings' positions move to `cpos`; the mesh gets the clustered vertices.
    std::mem::swap(&mut mesh.positions, &mut buf.cpos);
    if tiled {
        // Tile rule: a group only inside one tile. With integrated clustering a candidate
        // across tiles is dropped (its crossings may still join a group of their tile as
        // lone crossings); integrated-unchecked keeps it without one crossing when that
        // leaves two or more of one tile (the first such crossing in bit order), as the
        // dissertation's commit did.
        let t = layout.t;
        let mut kept = Vec::with_capacity(buf.candidates.len());
        let mut ids = Vec::with_capacity(14);
        for c in buf.candidates.drain(..) {
            ids.clear();
            ids.extend(c.ids());
            if crate::tiles::same_tile(keys, &ids) {
                kept.push(c);
                continue;
            }
            let without_one = (rules == Rules::Dissertation && ids.len() > 2)
                .then(|| {
                    let mut d = c.dirs;
                    (0..ids.len()).find_map(|i| {
                        let bit = d & d.wrapping_neg();
                        d &= d - 1;
                        let rest: Vec<u32> =
                            (0..ids.len()).filter(|&j| j != i).map(|j| ids[j]).collect();
                        crate::tiles::same_tile(keys, &rest).then(|| c.restrict(c.dirs & !bit))
                    })
                })
                .flatten();
            match without_one {
                Some(r) if t.is_connected(r.dirs) || rules == Rules::Dissertation => kept.push(r),
                _ => stats.clusters_rejected_prefilter += 1,
            }
        }
        buf.candidates = kept;
    }
    let step = std::time::Instant::now();
    build_groups(buf, layout, pool);
    let checked = clustering == Clustering::Integrated;
    if checked {
        // Plain MT's triangles and every crossing's triangles: the stars of the tests.
        *plain_processed = plain_triangles(
            layout,
            iso,
            &buf.crossed,
            &buf.cpos,
            pool,
            &mut buf.plain,
            &mut buf.plain_grad,
            &mut buf.inc_start,
            &mut buf.inc,
        );
    } else {
        buf.plain.clear();
        buf.plain_grad.clear();
        buf.inc_start.clear();
        buf.inc.clear();
    }
    let mut islands = buf.candidates.len();
    if !checked {
        stats.t_groups_s += step.elapsed().as_secs_f64();
    }
    if checked {
        let fixed = crate::quotient::Fixed {
            l: layout,
            cpos: &buf.cpos,
            groups: &buf.candidates,
            tris: &buf.plain,
            grad: &buf.plain_grad,
            inc_start: &buf.inc_start,
            inc: &buf.inc,
            keys: tiled.then_some(keys),
        };
        let groups = &mut buf.groups;
        groups.relabel(&fixed, pool);
        // Crossings in no island join a neighbouring island: part of the proposal.
        crate::additions::give_lones(&fixed, groups, &buf.edge_of, false, pool);
        groups.base_len.fill(0);
        stats.t_groups_s += step.elapsed().as_secs_f64();
        let all = (0..islands as u32).collect();
        let settled =
            crate::repair::settle(&fixed, groups, all, crate::repair::Phase::Islands, pool);
        stats.repair_rounds = settled.rounds;
        stats.t_tests_s += settled.t_tests_s;
        stats.t_repair_s += settled.t_repair_s;
    }
    // Split islands of three or more come back without one crossing: their variants are
    // appended to the candidates (not kept), and each split island takes its first variant
    // that passes.
    let mut variant_of = Vec::new();
    if checked {
        let step = std::time::Instant::now();
        let t = layout.t;
        variant_of.push(islands as u32);
        for gi in 0..islands {
            if buf.groups.active[gi] == 0 {
                let c = buf.candidates[gi];
                crate::additions::variants(&c, t, &mut buf.candidates);
                variant_of.push(buf.candidates.len() as u32);
            }
        }
        buf.groups.extend_to(buf.candidates.len());
        stats.t_groups_s += step.elapsed().as_secs_f64();
    }
    // The fixed tables of the tests, over the candidates as they are.
    macro_rules! fixed {
        () => {
            crate::quotient::Fixed {
                l: layout,
                cpos: &buf.cpos,
                groups: &buf.candidates,
                tris: &buf.plain,
                grad: &buf.plain_grad,
                inc_start: &buf.inc_start,
                inc: &buf.inc,
                keys: tiled.then_some(keys),
            }
        };
    }
    if checked {
        let fixed = fixed!();
        let groups = &mut buf.groups;
        let dirty = crate::additions::revive(&fixed, groups, &variant_of, pool);
        let settled =
            crate::repair::settle(&fixed, groups, dirty, crate::repair::Phase::Islands, pool);
        stats.repair_rounds += settled.rounds;
        stats.t_tests_s += settled.t_tests_s;
        stats.t_repair_s += settled.t_repair_s;
        // Crossings left alone (in no island, or in one that split) join the nearest kept
        // group; a group that fails with them gives them back, and they try another group
        // in the next pass.
        let no_new = crate::repair::Phase::Additions {
            born: fixed.groups.len() as u32,
        };
        for _ in 0..LONE_PASSES {
            let step = std::time::Instant::now();
            let dirty = crate::additions::give_lones(&fixed, groups, &buf.edge_of, true, pool);
            stats.t_groups_s += step.elapsed().as_secs_f64();
            if dirty.is_empty() {
                break;
            }
            let settled = crate::repair::settle(&fixed, groups, dirty, no_new, pool);
            stats.repair_rounds += settled.rounds;
            stats.t_tests_s += settled.t_tests_s;
            stats.t_repair_s += settled.t_repair_s;
        }
    }
    // Slivers left between the groups: a crossing left alone at one joins the group across
    // its shortest edge, or pairs with the crossing there (a new group).
    for _ in 0..SLIVER_PASSES {
        if !checked {
            break;
        }
        let step = std::time::Instant::now();
        let props = {
            let fixed = fixed!();
            crate::additions::sliver_proposals(&fixed, &buf.groups, &buf.edge_of, pool)
        };
        if props.lones.is_empty() && props.pairs.is_empty() {
            break;
        }
        let born = buf.candidates.len();
        for &(x, y) in &props.pairs {
            let (slot, dir) = buf.edge_of[x as usize];
            buf.candidates.push(Candidate {
                first: x,
                members: 1,
                dirs: 1 << dir,
                slot,
            });
            let _ = y;
        }
        islands += props.pairs.len();
        stats.clusters_proposed += props.pairs.len();
        let fixed = fixed!();
        let groups = &mut buf.groups;
        groups.add_pairs(&fixed, born, &props.pairs);
        let mut dirty = crate::additions::attach(&fixed, groups, props.lones, true, pool);
        let new: Vec<u32> = (born as u32..fixed.groups.len() as u32).collect();
        dirty.extend(crate::additions::around(&fixed, groups, &new, pool));
        dirty.sort_unstable();
        dirty.dedup();
        stats.t_groups_s += step.elapsed().as_secs_f64();
        let phase = crate::repair::Phase::Additions { born: born as u32 };
        let settled = crate::repair::settle(&fixed, groups, dirty, phase, pool);
        stats.repair_rounds += settled.rounds;
        stats.t_tests_s += settled.t_tests_s;
        stats.t_repair_s += settled.t_repair_s;
    }
    let fixed = fixed!();
    let groups = &buf.groups;
    stats.lone_absorbed = (0..buf.candidates.len())
        .filter(|&gi| groups.active[gi] != 0)
        .map(|gi| usize::from(groups.lone_len[gi]))
        .sum();
    let step = std::time::Instant::now();
    let q = crate::quotient::Quotient::new(&fixed, groups);
    vertex_map(&q, &mut buf.vertex_of, &mut mesh.positions);
    // An island is kept whole, or as one of its variants (at most one of them is kept).
    stats.clusters_committed = groups.active.iter().filter(|&&a| a != 0).count();
    stats.clusters_rejected_check = islands - stats.clusters_committed;
    stats.t_vertices_s += step.elapsed().as_secs_f64();
}

/// The geometry pass over the lattice, writing the final triangles into `mesh` (with `propose`,
/// through the groups' vertex map, collapsed triangles dropped), only those of the cells `keep`.
#[allow(clippy::too_many_arguments)]
fn emit_layers(
    layout: &Layout,
    iso: f32,
    keep: Option<CellRange>,
    crossed: &CrossedIndex,
    propose: bool,
    buf: &MtBuffers,
    mesh: &mut Mesh,
    pool: &rayon::ThreadPool,
    stats: &mut Stats,
) {
    // Triangles of plain MT per layer, counted from the anchors' crossed edges, so that every
    // layer writes its triangles straight into its own slice of the output (with clustering,
    // collapsed triangles leave the slice's end unused; the layers are then moved together).
    let counts = layer_counts(layout, keep, crossed, pool);
    let layers = counts.len();
    let triangles: usize = counts.iter().sum();
    let Mesh {
        positions, indices, ..
    } = mesh;
    indices.clear();
    indices.resize(3 * triangles, 0);
    let mut parts = Vec::with_capacity(layers);
    let mut rest = &mut indices[..];
    for &n in &counts {
        let (head, tail) = rest.split_at_mut(3 * n);
        parts.push(head);
        rest = tail;
    }
    let (positions, map) = if propose {
        (&buf.cpos[..], Some(&buf.vertex_of[..]))
    } else {
        (&positions[..], None)
    };
    let written: Vec<(usize, usize)> = pool.install(|| {
        parts
            .into_par_iter()
            .enumerate()
            .map(|(k, out)| {
                geometry_layer(layout, k, iso, keep, crossed, positions, map, out, None)
            })
            .collect()
    });
    stats.tetrahedra_processed += written.iter().map(|w| w.0).sum::<usize>();
    if propose {
        // Move the layers' triangles together.
        let (mut from, mut to) = (0, 0);
        for (&n, &(_, w)) in counts.iter().zip(&written) {
            indices.copy_within(3 * from..3 * (from + w), 3 * to);
            from += n;
            to += w;
        }
        indices.truncate(3 * to);
        stats.discarded += triangles - to;
    }
}

/// Plain MT's triangles over the whole box, in the order of the geometry pass (layer by
/// layer), into `tris` (three crossing ids each), with each triangle's source tetrahedron
/// gradient (of the linear interpolant on its source tetrahedron, up to a positive factor) in
/// `grad`; then every crossing's triangles as a CSR
/// table (`inc[inc_start[x]..inc_start[x + 1]]`, in triangle order). The quotient test reads
/// a group's star from these instead of from the lattice.
#[allow(clippy::too_many_arguments)]
fn plain_triangles(
    layout: &Layout,
    iso: f32,
    crossed: &CrossedIndex,
    cpos: &[[f32; 3]],
    pool: &rayon::ThreadPool,
    tris: &mut Vec<u32>,
    grad: &mut Vec<[f32; 3]>,
    inc_start: &mut Vec<u32>,
    inc: &mut Vec<u32>,
) -> usize {
    let counts = layer_counts(layout, None, crossed, pool);
    let layers = counts.len();
    let total: usize = counts.iter().sum();
    tris.clear();
    tris.resize(3 * total, 0);
    grad.clear();
    grad.resize(total, [0.0; 3]);
    let mut parts = Vec::with_capacity(layers);
    let (mut rest, mut rest_src) = (&mut tris[..], &mut grad[..]);
    for &n in &counts {
        let (head, tail) = rest.split_at_mut(3 * n);
        let (head_src, tail_src) = rest_src.split_at_mut(n);
        parts.push((head, head_src));
        rest = tail;
        rest_src = tail_src;
    }
    let processed: usize = pool.install(|| {
        parts
            .into_par_iter()
            .enumerate()
            .map(|(k, (out, src))| {
                geometry_layer(layout, k, iso, None, crossed, cpos, None, out, Some(src)).0
            })
            .sum()
    });
    // Incidence in triangle order, so the table is deterministic.
    let mut cursor = Vec::new();
    crate::merge::incidence(cpos.len(), tris, inc_start, inc, &mut cursor);
    processed
}

/// The output vertices: one per crossing outside the kept groups and one per kept group, in
/// order of their lowest crossing id; `vertex_of` maps every crossing to its vertex.
fn vertex_map(
    q: &crate::quotient::Quotient,
    vertex_of: &mut Vec<u32>,
    positions: &mut Vec<[f32; 3]>,
) {
    use crate::quotient::NONE;
    let n = q.cpos.len();
    let g = q.g;
    vertex_of.clear();
    vertex_of.resize(n, 0);
    positions.clear();
    for x in 0..n {
        let h = g.group_of[x];
        if h != NONE && g.active[h as usize] != 0 {
            let leader = g.leader[h as usize] as usize;
            if leader == x {
                vertex_of[x] = positions.len() as u32;
                positions.push(g.centroid[h as usize]);
            } else {
                // The leader has the lowest id of the group: numbered already.
                vertex_of[x] = vertex_of[leader];
            }
        } else {
            vertex_of[x] = positions.len() as u32;
            positions.push(q.cpos[x]);
        }
    }
}

/// Welds crossings closer than `WELD` grid spacings (crossings on top of each other where the
/// surface passes through sample points) under the exact check, following the tile rule when
/// `tile_keys` is given; counted as collapses.
fn weld_coincident(
    merge: &mut MergeBuffers,
    mesh: &mut Mesh,
    settings: &ExtractSettings,
    tile_keys: Option<&[u64]>,
    stats: &mut Stats,
) {
    let (welds, dropped) = crate::collapse::collapse_short_edges_tiled(
        merge,
        mesh,
        WELD * settings.grid.h(),
        tile_keys,
    );
    stats.collapses += welds;
    stats.discarded += dropped;
}

/// Vertex pass over one storage plane: counts, cluster proposals, the plane's crossed-point bits
/// (`crossed`, [`plane_words`] words, all zero on entry) and, per crossed point in slot order,
/// its owned and crossed edges as `owned | crossed << 16` (`owned`).
#[allow(clippy::too_many_arguments)]
fn vertex_plane(
    l: &Layout,
    inside_bits: &[u64],
    z: usize,
    iso: f32,
    propose: Option<Rules>,
    owned: &mut Vec<u32>,
    crossed_bits: &mut [u64],
) -> (PlaneCounts, Vec<Candidate>) {
    owned.clear();
    let v = &l.s.values;
    let [dx, dy, _] = l.s.dims;
    let slots = v.len();
    let mut counts = PlaneCounts::default();
    let mut cands = Vec::new();
    for sy in 0..dy {
        // The run of points in this row whose 14 neighbours are all regular lattice points: no
        // existence or border tests there.
        let (p0, _) = l.point(0, sy, z);
        let odd = (p0[2] & 1) as usize;
        let (lo, hi) = match l.lattice {
            Lattice::BodyCentred => (1 + odd, l.s.cells[0]),
            Lattice::Simple => (1, l.s.cells[0]),
        };
        let row_regular = lo < hi && l.is_regular(l.point(lo, sy, z).0);
        let (lo, hi) = if row_regular { (lo, hi) } else { (dx, dx) };
        let row = z * dx * dy + sy * dx;
        let delta = &l.delta[odd];
        let (dmin, dmax) = (
            delta.iter().copied().min().unwrap_or(0),
            delta.iter().copied().max().unwrap_or(0),
        );
        // One point with at least one crossed edge: owned crossings, flags, proposals.
        let point = |sx: usize,
                     valid: u16,
                     owned: &mut Vec<u32>,
                     crossed_bits: &mut [u64],
                     counts: &mut PlaneCounts,
                     cands: &mut Vec<Candidate>| {
            let local = sy * dx + sx;
            let i = row + sx;
            let f = v[i];
            let inside = f < iso;
            let (mut own, mut crossed) = (0u16, 0u16);
            let mut bits = valid;
            while bits != 0 {
                let d = bits.trailing_zeros() as usize;
                bits &= bits - 1;
                let g = v[(i as isize + delta[d]) as usize];
                if (g < iso) != inside {
                    crossed |= 1 << d;
                    if owns(f, g, iso) {
                        own |= 1 << d;
                    }
                }
            }
            if crossed != 0 {
                // Points come in slot order: `owned` stays aligned with the bits.
                owned.push(u32::from(own) | u32::from(crossed) << 16);
                crossed_bits[local >> 6] |= 1 << (local & 63);
            }
            // Ids within the plane for now; the plane's first id is added when the planes'
            // candidates are joined.
            let first = counts.crossings as u32;
            counts.crossings += own.count_ones() as usize;
            if let Some(rules) = propose.filter(|_| own.count_ones() >= 2) {
                let inner = l.inner_dirs(l.coords(sx, sy, z)) & valid;
                counts.proposals.add(cluster::propose(
                    l.t, first, i as u32, valid, inner, own, crossed, rules, cands,
                ));
            }
        };
        // Border points one by one (existence and valid neighbours from the border table).
        let border = |sx: usize,
                      owned: &mut Vec<u32>,
                      crossed_bits: &mut [u64],
                      counts: &mut PlaneCounts,
                      cands: &mut Vec<Candidate>| {
            let p = l.coords(sx, sy, z);
            let (exists, valid) = l.border_info(p);
            if !exists {
                return;
            }
            counts.edges += valid.count_ones() as usize;
            point(sx, valid, owned, crossed_bits, counts, cands);
        };
        // The points tested 64 at a time: the whole row where every neighbour slot of it is in
        // storage (the test may then let through a border point whose only difference is with a
        // slot that is not its neighbour; `point` tests the real neighbours), else the regular
        // run. The others one by one.
        let (flo, fhi) = if row as isize + dmin >= 0 && (row + dx) as isize + dmax <= slots as isize
        {
            (0, dx)
        } else {
            (lo, hi)
        };
        for sx in 0..flo {
            border(sx, owned, crossed_bits, &mut counts, &mut cands);
        }
        if flo < fhi {
            if lo < hi {
                counts.edges += 14 * (hi - lo);
            }
            for sx in (flo..lo.min(fhi)).chain(hi.max(flo)..fhi) {
                let (exists, valid) = l.border_info(l.coords(sx, sy, z));
                if exists {
                    counts.edges += valid.count_ones() as usize;
                }
            }
            let mut sx = flo;
            while sx < fhi {
                let len = (fhi - sx).min(64);
                let mut block = crossed_points(inside_bits, row + sx, delta, len);
                while block != 0 {
                    let x = sx + block.trailing_zeros() as usize;
                    block &= block - 1;
                    let valid = if x >= lo && x < hi {
                        FULL
                    } else {
                        let (exists, valid) = l.border_info(l.coords(x, sy, z));
                        if !exists {
                            continue;
                        }
                        valid
                    };
                    point(x, valid, owned, crossed_bits, &mut counts, &mut cands);
                }
                sx += len;
            }
        }
        for sx in fhi.max(flo)..dx {
            border(sx, owned, crossed_bits, &mut counts, &mut cands);
        }
    }
    (counts, cands)
}

/// Numbers the crossings of plane `z` (ids from `start` on) and writes its crossed points'
/// entries (`entries`, from the vertex pass's `owned | crossed << 16` words `owned`) and the crossings'
/// positions (`out`). Returns how many crossings lie within `WELD` of their owner (surfaces
/// through sample points).
#[allow(clippy::too_many_arguments)]
fn number_plane(
    l: &Layout,
    z: usize,
    iso: f32,
    owned: &[u32],
    crossed: &[u64],
    start: u32,
    entries: &mut [CrossedPoint],
    out: &mut [[f32; 3]],
) -> usize {
    let v = &l.s.values;
    let [dx, dy, _] = l.s.dims;
    let plane = dx * dy;
    let mut next = start;
    let (mut w, mut r) = (0, 0);
    let mut near_points = 0;
    for_each_bit(crossed, 0, plane, |local| {
        let own = owned[r] as u16;
        entries[r] = CrossedPoint {
            first: next,
            owned: own,
            crossed: (owned[r] >> 16) as u16,
        };
        r += 1;
        if own == 0 {
            return;
        }
        next += own.count_ones();
        let (sy, sx) = (local / dx, local % dx);
        let p = l.coords(sx, sy, z);
        let i = z * plane + local;
        let f = v[i];
        let pp = l.position(p);
        let mut bits = own;
        while bits != 0 {
            let d = bits.trailing_zeros() as usize;
            bits &= bits - 1;
            let q = add(p, l.t.offsets[d]);
            let g = v[(i as isize + l.delta[(p[0] & 1) as usize][d]) as usize];
            let t = (iso - f) / (g - f);
            near_points += (t < WELD) as usize;
            out[w] = pp.lerp(l.position(q), t).to_array();
            w += 1;
        }
    });
    debug_assert_eq!(
        r,
        owned.len(),
        "plane {z}: crossed bits and points disagree"
    );
    near_points
}

/// Calls `visit(anchor, rank, group)` for each body-centred face (group: its axis) or cube
/// (group 0) of geometry layer `k` that can hold surface: its anchor point (a storage slot) has a
/// crossed edge and, in a chunk, its cell is kept. The anchor's entry is `crossed.points[rank]`. The count and the geometry pass both walk the
/// layer with it, so they see the same groups.
fn for_each_group(
    l: &Layout,
    k: usize,
    keep: Option<CellRange>,
    crossed: &CrossedIndex,
    mut visit: impl FnMut(usize, usize, usize),
) {
    let [nx, ny, nz] = l.s.cells;
    let plane = l.s.dims[0] * l.s.dims[1];
    // The anchors of one row are consecutive storage slots: scan their bits, visit only the
    // crossed ones (`cell(n)`: the cell of the n-th, to test against the kept cells).
    let mut row =
        |start: usize, z: usize, len: usize, g: usize, cell: &dyn Fn(usize) -> [usize; 3]| {
            let local = start - z * plane;
            let mut rank = crossed.rank_in(z, local);
            for_each_bit(crossed.plane_bits(z), local, len, |n| {
                let r = rank;
                rank += 1;
                if keep.is_some_and(|range| !range.contains(cell(n))) {
                    return;
                }
                visit(start + n, r, g);
            });
        };
    match l.lattice {
        Lattice::Simple => {
            // Cubes by corner 0, a neighbour of the other 7: no crossed edge there, no surface
            // in the cube.
            for j in 0..ny {
                row(l.s.simple_index(0, j, k), k, nx, 0, &|i| [i, j, k]);
            }
        }
        Lattice::BodyCentred => {
            // Faces perpendicular to z at plane k, then (inside layer k) to x and to y, by their
            // anchor A, the centre below (B and the 4 face corners are neighbours of A: without
            // a crossed edge at A, no surface in the face's 4 tetrahedra). Along x a face anchor
            // moves by one storage slot.
            let ki = k as i32;
            let mut faces = |first: Offset, len: usize, axis: usize| {
                // Storage plane (see `Samples::bcdl_index`); the anchor cell is above the face
                // along `axis` (clamped into the grid).
                let z = (first[2] + 1) as usize;
                let cell = |n: usize| {
                    let a = [first[0] + 2 * n as i32, first[1], first[2]];
                    let mut c = a.map(|x| ((x - 1) / 2) as usize);
                    c[axis] = (((a[axis] + 1) / 2) as usize).min(l.s.cells[axis] - 1);
                    c
                };
                row(l.s.bcdl_index(first), z, len, axis, &cell);
            };
            for j in 0..ny as i32 {
                faces([1, 2 * j + 1, 2 * ki - 1], nx, 2);
            }
            if k < nz {
                for j in 0..ny as i32 {
                    faces([-1, 2 * j + 1, 2 * ki + 1], nx + 1, 0);
                }
                for f in 0..=ny as i32 {
                    faces([1, 2 * f - 1, 2 * ki + 1], nx, 1);
                }
            }
        }
    }
}

/// Triangles of every geometry layer (those of the cells `keep`), in layer order.
fn layer_counts(
    l: &Layout,
    keep: Option<CellRange>,
    crossed: &CrossedIndex,
    pool: &rayon::ThreadPool,
) -> Vec<usize> {
    let layers = match l.lattice {
        Lattice::BodyCentred => l.s.cells[2] + 1,
        Lattice::Simple => l.s.cells[2],
    };
    pool.install(|| {
        (0..layers)
            .into_par_iter()
            .map(|k| count_layer(l, k, keep, crossed))
            .collect()
    })
}

/// Triangles geometry layer `k` will give: per group, a table lookup by the anchor's crossed
/// edges.
fn count_layer(l: &Layout, k: usize, keep: Option<CellRange>, crossed: &CrossedIndex) -> usize {
    let mut n = 0;
    for_each_group(l, k, keep, crossed, |_, rank, g| {
        let group = &l.groups[g];
        let mask = usize::from(crossed.points[rank].crossed);
        let mut code = 0;
        for (i, &d) in group.dirs[1..group.len].iter().enumerate() {
            code |= ((mask >> d) & 1) << (i + 1);
        }
        n += usize::from(group.triangles[code]);
    });
    n
}

/// Emission over one z-layer: writes its triangles into `out`, sized by [`count_layer`] (the
/// triangles of plain MT); with `map` (crossing id to output vertex, clustering) the triangles
/// are written with the clustered vertices and those that collapsed are left out. Returns the
/// tetrahedra processed and the triangles written.
#[allow(clippy::too_many_arguments)]
fn geometry_layer(
    l: &Layout,
    k: usize,
    iso: f32,
    keep: Option<CellRange>,
    crossed: &CrossedIndex,
    positions: &[[f32; 3]],
    map: Option<&[u32]>,
    out: &mut [u32],
    grad: Option<&mut [[f32; 3]]>,
) -> (usize, usize) {
    let plane = l.s.dims[0] * l.s.dims[1];
    // The crossed points of the storage planes this layer reads, copied into a dense window (one
    // entry per slot) of this thread: a crossing's id is then one load away, where the rank
    // directory needs two dependent ones. A few planes per thread, not a table per slot.
    let (z0, z1) = l.layer_planes(k);
    LAYER_WINDOW.with_borrow_mut(|window| {
        if window.len() < (z1 + 1 - z0) * plane {
            window.resize((z1 + 1 - z0) * plane, CrossedPoint::default());
        }
        for z in z0..=z1 {
            let base = (z - z0) * plane;
            let mut r = crossed.rank_in(z, 0);
            for_each_bit(crossed.plane_bits(z), 0, plane, |local| {
                window[base + local] = crossed.points[r];
                r += 1;
            });
        }
        geometry_in_window(
            l,
            k,
            iso,
            keep,
            crossed,
            positions,
            map,
            &window[..],
            z0,
            out,
            grad,
        )
    })
}

thread_local! {
    /// The dense window of [`geometry_layer`], kept per thread between layers and extractions
    /// (entries of slots without a crossed edge are stale and never read).
    static LAYER_WINDOW: std::cell::RefCell<Vec<CrossedPoint>> =
        const { std::cell::RefCell::new(Vec::new()) };
}

/// [`geometry_layer`] once the crossed points of storage planes `z0..` are in `window`.
#[allow(clippy::too_many_arguments)]
fn geometry_in_window(
    l: &Layout,
    k: usize,
    iso: f32,
    keep: Option<CellRange>,
    crossed: &CrossedIndex,
    positions: &[[f32; 3]],
    map: Option<&[u32]>,
    window: &[CrossedPoint],
    z0: usize,
    out: &mut [u32],
    mut grad: Option<&mut [[f32; 3]]>,
) -> (usize, usize) {
    let v = &l.s.values;
    let plane = l.s.dims[0] * l.s.dims[1];
    let mut processed = 0;
    let mut w = 0;
    let mut tet = |anchor: usize, ti: usize, tpl: &TetTemplate| {
        let idx = tpl.delta.map(|d| (anchor as isize + d) as usize);
        let val = idx.map(|i| v[i]);
        let mut tris = [[0u32; 3]; 2];
        // The window starts at slot 0 of plane z0.
        let id = |o: usize, d: u8| {
            let entry = window[idx[o] - z0 * plane];
            debug_assert_eq!(entry, crossed.get(idx[o]));
            entry.id(d)
        };
        let n = tet_triangles(val, iso, &tpl.dir, id, positions, &mut tris);
        processed += usize::from(n > 0);
        match map {
            None => {
                // The gradient of the tetrahedron, for the quotient test's (c).
                let g = if n > 0 && grad.is_some() {
                    l.gradient(anchor, ti)
                } else {
                    [0.0; 3]
                };
                for t in &tris[..n] {
                    if let Some(grad) = grad.as_deref_mut() {
                        grad[w / 3] = g;
                    }
                    out[w..w + 3].copy_from_slice(t);
                    w += 3;
                }
            }
            Some(map) => {
                // Clustered: the vertices of the groups' quotient; a triangle with two corners
                // in one group collapsed and is dropped.
                for t in &tris[..n] {
                    let q = t.map(|i| map[i as usize]);
                    if q[0] != q[1] && q[1] != q[2] && q[0] != q[2] {
                        out[w..w + 3].copy_from_slice(&q);
                        w += 3;
                    }
                }
            }
        }
    };
    for_each_group(l, k, keep, crossed, |anchor, _, g| {
        let first = match l.lattice {
            Lattice::BodyCentred => 4 * g,
            Lattice::Simple => 0,
        };
        let count = match l.lattice {
            Lattice::BodyCentred => 4,
            Lattice::Simple => l.tets.len(),
        };
        for ti in first..first + count {
            tet(anchor, ti, &l.tets[ti]);
        }
    });
    debug_assert!(
        w == out.len() || (map.is_some() && w <= out.len()),
        "layer {k}: triangles counted and written differ"
    );
    (processed, w / 3)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Plain MT of `field` on `cells` in [-1, 1]^3: the settings, samples, the pass buffers as the
    /// extraction left them, and the mesh.
    fn plain_mt(
        field: &impl rmt_fields::ScalarField,
        lattice: Lattice,
        cells: [usize; 3],
        pool: &rayon::ThreadPool,
    ) -> (crate::ExtractSettings, Samples, MtBuffers, Mesh) {
        let settings = crate::ExtractSettings::new(
            crate::Grid::new(cells, glam::Vec3::splat(-1.0), glam::Vec3::splat(1.0)),
            lattice,
            crate::Clustering::None,
        );
        let mut stats = Stats::default();
        let mut samples = Samples::default();
        samples
            .sample(field, &settings, pool, &mut stats)
            .expect("a finite field");
        let (mut buf, mut merge, mut mesh) = (
            MtBuffers::default(),
            MergeBuffers::default(),
            Mesh::default(),
        );
        extract(
            &samples, &settings, pool, &mut buf, &mut merge, &mut mesh, &mut stats,
        )
        .expect("extraction");
        (settings, samples, buf, mesh)
    }

    #[test]
    fn crossed_index_finds_every_point_and_its_owned_crossings() {
        // Grids whose storage planes hold fewer slots than a word of bits, about as many, and
        // many more; the reference is each point's 14 edges tested one by one.
        let field = rmt_fields::FnField(|p: glam::Vec3| {
            (p.x * 7.1).sin() + (p.y * 5.3).cos() * (p.z * 3.7 + 0.4).sin() - 0.2
        });
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(2)
            .build()
            .expect("a pool of two threads");
        let mut checked = 0;
        for lattice in [Lattice::BodyCentred, Lattice::Simple] {
            for cells in [
                [1, 1, 6],
                [2, 1, 5],
                [1, 3, 4],
                [3, 3, 3],
                [5, 2, 7],
                [9, 8, 6],
                [40, 3, 5],
            ] {
                let (settings, samples, buf, mesh) = plain_mt(&field, lattice, cells, &pool);
                let l = Layout::new(&samples, lattice);
                let [dx, dy, dz] = samples.dims;
                let iso = settings.iso;
                let (mut before, mut rank) = (0u32, 0usize);
                for z in 0..dz {
                    for sy in 0..dy {
                        for sx in 0..dx {
                            let slot = (z * dy + sy) * dx + sx;
                            let (p, exists) = l.point(sx, sy, z);
                            let (mut crossed, mut own) = (0u16, 0u16);
                            if exists {
                                let f = samples.values[slot];
                                let valid = l.valid_neighbours(p);
                                for d in (0..14).filter(|d| valid & (1 << d) != 0) {
                                    let q =
                                        (slot as isize + l.delta[(p[0] & 1) as usize][d]) as usize;
                                    let g = samples.values[q];
                                    if (g < iso) != (f < iso) {
                                        crossed |= 1 << d;
                                        if owns(f, g, iso) {
                                            own |= 1 << d;
                                        }
                                    }
                                }
                            }
                            let what = format!("{lattice:?} {cells:?} slot {slot}");
                            assert_eq!(buf.crossed.plane_of(slot), z, "{what}");
                            assert_eq!(buf.crossed.is_crossed(slot), crossed != 0, "{what}");
                            if crossed != 0 {
                                let expected = CrossedPoint {
                                    first: before,
                                    owned: own,
                                    crossed,
                                };
                                assert_eq!(buf.crossed.get(slot), expected, "{what}");
                                assert_eq!(buf.crossed.points[rank], expected, "{what}");
                                rank += 1;
                                checked += usize::from(own != 0);
                            }
                            before += own.count_ones();
                        }
                    }
                }
                assert_eq!(rank, buf.crossed.points.len(), "{lattice:?} {cells:?}");
                assert_eq!(
                    before as usize,
                    mesh.positions.len(),
                    "{lattice:?} {cells:?}"
                );
            }
        }
        assert!(checked > 100, "only {checked} points own crossings");
    }

    #[test]
    fn the_tetrahedra_around_the_points_give_exactly_the_emitted_triangles() {
        // Every point sees 24 tetrahedra; over all points each tetrahedron of the extraction is
        // seen from its 4 corners, and their triangles (the quotient test's view) are exactly
        // the triangles the geometry pass writes, with the same orientation.
        let field = rmt_fields::FnField(|p: glam::Vec3| {
            (p.x * 5.3).sin() * (p.y * 3.9 + 0.2).cos() + (p.z * 4.7).sin() * 0.7 - 0.15
        });
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .expect("a pool of one thread");
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
                                let id = |o: usize, d: u8| buf.crossed.get(idx[o]).id(d);
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
    fn layer_triangle_counts_match_the_tetrahedra_of_every_group() {
        // The count reads only the anchor's crossed edges through the group tables; here each
        // group's tetrahedra are evaluated from the sample values instead, with and without
        // kept cells.
        let field = rmt_fields::FnField(|p: glam::Vec3| {
            (p.x * 6.3).sin() * (p.y * 4.1 + 0.3).cos() + (p.z * 5.7).sin() * 0.8 - 0.1
        });
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .expect("a pool of one thread");
        let mut triangles = 0;
        for lattice in [Lattice::BodyCentred, Lattice::Simple] {
            for cells in [[3, 2, 4], [9, 8, 6], [13, 11, 12]] {
                let (settings, samples, buf, mesh) = plain_mt(&field, lattice, cells, &pool);
                let l = Layout::new(&samples, lattice);
                let (expected_len, dirs_from) = match lattice {
                    Lattice::BodyCentred => (6, 1),
                    Lattice::Simple => (8, 0),
                };
                for g in &l.groups {
                    assert_eq!(g.len, expected_len, "{lattice:?}");
                    assert_eq!(g.points[0], 0, "the anchor comes first");
                    for i in 1..g.len {
                        let d = l.delta[dirs_from][g.dirs[i] as usize];
                        assert_eq!(d, g.points[i], "{lattice:?} point {i}");
                    }
                    for code in 0..1usize << g.len {
                        let swapped = !code & ((1 << g.len) - 1);
                        assert_eq!(g.triangles[code], g.triangles[swapped], "side swap");
                    }
                }
                let layers = match lattice {
                    Lattice::BodyCentred => cells[2] + 1,
                    Lattice::Simple => cells[2],
                };
                let keeps = [
                    None,
                    Some(CellRange {
                        lo: [1, 0, 1],
                        hi: [cells[0] - 1, cells[1], cells[2] - 1],
                    }),
                ];
                for keep in keeps {
                    let mut total = 0;
                    for k in 0..layers {
                        let mut direct = 0;
                        for_each_group(&l, k, keep, &buf.crossed, |anchor, _, g| {
                            let tets = match lattice {
                                Lattice::BodyCentred => &l.tets[4 * g..4 * g + 4],
                                Lattice::Simple => &l.tets[..],
                            };
                            for tpl in tets {
                                let case = (0..4).fold(0, |case, i| {
                                    let slot = (anchor as isize + tpl.delta[i]) as usize;
                                    case | usize::from(samples.values[slot] < settings.iso) << i
                                });
                                direct += usize::from(case_triangles(case));
                            }
                        });
                        let counted = count_layer(&l, k, keep, &buf.crossed);
                        assert_eq!(counted, direct, "{lattice:?} {cells:?} layer {k} {keep:?}");
                        total += counted;
                    }
                    if keep.is_none() {
                        assert_eq!(total * 3, mesh.indices.len(), "{lattice:?} {cells:?}");
                    }
                    triangles += total;
                }
            }
        }
        assert!(
            triangles > 1000,
            "only {triangles} triangles: the fields miss the grids"
        );
    }

    #[test]
    fn inside_words_set_exactly_the_bits_of_values_below_the_isovalue() {
        let mut state = 7u64;
        for len in [0, 1, 5, 63, 64] {
            for iso in [0.0f32, 0.25, -0.5] {
                let values: Vec<f32> = (0..len)
                    .map(|k| match k % 7 {
                        0 => iso,
                        1 => f32::NAN,
                        2 => -0.0,
                        _ => lcg(&mut state) * 2.0 - 1.0,
                    })
                    .collect();
                let word = inside_word(&values, iso);
                for (k, &f) in values.iter().enumerate() {
                    assert_eq!(
                        word >> k & 1 == 1,
                        f < iso,
                        "len {len} iso {iso} k {k} f {f}"
                    );
                }
                assert_eq!(
                    word >> len.min(63) >> u32::from(len == 64),
                    0,
                    "no bit past the end"
                );
            }
        }
    }

    #[test]
    fn plane_of_divides_exactly_for_every_slot_below_2_pow_32() {
        let mut index = CrossedIndex::default();
        let mut x = 0x9E37_79B9_7F4A_7C15u64;
        for plane in (1..600).chain([4096, 65_537, 66_049, 1 << 20, 3_000_017]) {
            index.reset(plane, 0);
            let mut slots: Vec<usize> = (0..2000).collect();
            for k in [1usize, 2, 7, 1000, 65_000, (u32::MAX as usize) / plane] {
                slots.extend([k * plane - 1, k * plane, k * plane + 1]);
            }
            slots.push(u32::MAX as usize);
            for _ in 0..2000 {
                x ^= x << 13;
                x ^= x >> 7;
                x ^= x << 17;
                slots.push((x >> 32) as usize);
            }
            for slot in slots.into_iter().filter(|&s| s <= u32::MAX as usize) {
                assert_eq!(
                    index.plane_of(slot),
                    slot / plane,
                    "slot {slot}, plane {plane}"
                );
            }
        }
    }

    #[test]
    fn for_each_bit_visits_exactly_the_set_bits_from_any_start() {
        let mut words = vec![0u64; 6];
        let set: Vec<usize> = (0..320).filter(|i| (i * 7 + i / 3) % 5 == 0).collect();
        for &i in &set {
            words[i >> 6] |= 1 << (i & 63);
        }
        for start in [0, 1, 13, 63, 64, 65, 200] {
            for len in [0, 1, 5, 63, 64, 65, 100, 320 - start] {
                if start + len > 320 {
                    continue;
                }
                let mut seen = Vec::new();
                for_each_bit(&words, start, len, |n| seen.push(start + n));
                let want: Vec<usize> = set
                    .iter()
                    .copied()
                    .filter(|&i| i >= start && i < start + len)
                    .collect();
                assert_eq!(seen, want, "start {start} len {len}");
            }
        }
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

    /// A tiny deterministic generator for the table test (no dependency needed).
    fn lcg(state: &mut u64) -> f32 {
        *state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((*state >> 40) as f32 / (1u64 << 24) as f32) * 2.0 - 1.0
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
