//! The vertex pass (parallel over storage planes): which points are inside, which lattice edges
//! the surface crosses, who owns each crossing, and every crossing's id and position.
//!
//! For each sample point C and each of its neighbours S, the edge C-S is crossed when C and S lie
//! on opposite sides of the threshold T (inside is f < T). The crossing belongs to the nearer end
//! (|f - T| smaller; on a tie, the inside end), so every crossing has exactly one owner and its
//! vertex id does not depend on processing order: ids are numbered by owner (storage order),
//! then by neighbour index. Only points with a crossed edge are stored ([`CrossedIndex`]: a bit
//! per slot, a rank per 64 slots, and per crossed point its 14 owned-crossing bits and the id of
//! its first owned crossing), so `id(C, d) = first(C) + popcount(owned(C) & ((1 << d) - 1))`
//! with no table per slot beyond those bits. The crossed edges of 64 points at a time come from
//! the inside bits (one word operation per neighbour, with a checked read where a neighbour
//! slot lies outside storage); only the far ends of crossed edges are read, to decide the
//! owner. With clustering, the pass also proposes clusters
//! ([`crate::mt::clustering::proposal`]).
//!
//! ```text
//!   S1 (out)        C owns the crossings on C-S1 and C-S2 (it is nearer T than S1 and S2);
//!     \             the crossing on C-S3 belongs to S3: ids = first(C) + 0, first(C) + 1
//!      C (in) ---- S2 (out)
//!      |
//!      S3 (out, nearer T than C)
//! ```
//!
//! The steps, as Flying Edges orders its passes (classify, count, prefix-sum, write in place),
//! each parallel over storage planes:
//!
//! ```text
//!   0   inside bits, 64 values per word (SIMD compares)
//!   1a  the sides of every storage row: some slot inside, some outside
//!   1b  per plane, one walk over its rows:
//!         a row whose slots and whose points' neighbour slots (the rows they fall in) all
//!         lie on one side is trimmed away: no crossed edge starts in it;
//!         otherwise its crossed points 64 at a time, and per crossed point in one visit:
//!         owned crossings, entry (ids from the plane's first crossing), the positions of
//!         its crossings, the triangles of the groups it anchors -> the plane's own buffers
//!   2   the planes' counts prefix-summed (crossings, crossed points): the rank directory,
//!       and each plane's entries (its first id added) and positions copied into place
//! ```

use rayon::prelude::*;

use super::clustering::proposal::{self, Candidate, PointEdges, ProposalCounts, Rules};
use super::layout::{owns, Layout, AROUND};
use crate::lattice::FULL;
use crate::util::{bits_at_signed, inside_word, inside_word_finite64, overwritten};
use crate::{ExtractError, Lattice, Stats};

/// Crossings nearer than this many grid spacings to their owner are counted (surfaces through
/// sample points): the meshoptimizer mode welds them first ([`crate::post`]).
pub(crate) const WELD: f32 = 1e-4;

/// The vertex pass's tables, kept between extractions: what the later passes read of the
/// lattice's crossings.
#[derive(Default)]
pub(crate) struct VertexTables {
    /// One bit per storage slot, set where the value is inside (`f < iso`), plus one zero word
    /// of padding: 64 points are tested for crossings at once with a few word operations.
    pub(crate) inside: Vec<u64>,
    /// Which points have a crossed edge, and their owned crossings and ids ([`CrossedIndex`]).
    pub(crate) crossed: CrossedIndex,
    /// Per storage plane, its crossed points in slot order, their ids counted from the plane's
    /// first crossing (copied into [`CrossedIndex::points`] with the plane's first id added).
    pub(crate) plane_points: Vec<Vec<CrossedPoint>>,
    /// Per storage plane, the positions of its crossings (copied into the mesh's positions
    /// once the planes' first ids are known).
    pub(crate) plane_positions: Vec<Vec<[f32; 3]>>,
    /// Per storage row (`z * dy + sy`, entry `SIDES_PAD(dy)` rows later), which sides its
    /// slots lie on ([`row_sides`]: bit 0 some inside, bit 1 some outside), with rows of padding
    /// on both ends (outside, as slots past storage read): a row whose slots and whose points'
    /// neighbour slots all lie on one side has no crossed edge, and the vertex pass skips it
    /// (Flying Edges' trimming). Bits 2 and 3 are the same for the slots a row's last block of
    /// 64 points and their neighbours read in that row ([`tail_start`]; rows of one block
    /// leave them clear): a last block whose rows all lie on one side there is skipped too.
    pub(crate) sides: Vec<u8>,
}

impl VertexTables {
    /// Sized for `samples` (the inside bits and the crossed-point bits; the rest is sized by the
    /// pass).
    pub(crate) fn allocate(&mut self, samples: &crate::Samples) {
        let slots = samples.values.len();
        let words = slots.div_ceil(64);
        self.inside.resize(words + 1, 0);
        let plane = samples.dims[0] * samples.dims[1];
        let planes = samples.dims[2];
        self.crossed.reset(plane, planes);
        let pad = sides_pad(samples.dims[1]);
        self.sides.clear();
        self.sides
            .resize(samples.dims[1] * planes + 2 * pad, PAD_SIDES);
        if self.plane_points.len() < planes {
            self.plane_points.resize_with(planes, Vec::new);
            self.plane_positions.resize_with(planes, Vec::new);
        }
    }

    /// Bytes of the tables.
    pub(crate) fn bytes(&self) -> usize {
        self.crossed.bytes()
            + self.plane_points.iter().map(|o| o.len() * 8).sum::<usize>()
            + self
                .plane_positions
                .iter()
                .map(|o| o.len() * 12)
                .sum::<usize>()
            + self.inside.len() * 8
            + self.sides.len()
    }
}

/// What the vertex pass writes besides its tables.
pub(crate) struct VertexOut<'a> {
    /// The cluster proposals, appended in storage order of their owners.
    pub(crate) proposals: &'a mut Vec<Candidate>,
    /// One position per crossing (plain MT's vertices).
    pub(crate) positions: &'a mut Vec<[f32; 3]>,
}

/// Where [`vertex_plane`] writes one plane's crossed points and crossings.
pub(crate) struct PlaneOut<'a> {
    /// The plane's crossed points in slot order (ids from the plane's first crossing).
    pub(crate) points: &'a mut Vec<CrossedPoint>,
    /// The positions of the plane's crossings.
    pub(crate) positions: &'a mut Vec<[f32; 3]>,
    /// The plane's crossed-point bits ([`plane_words`] words, all zero on entry).
    pub(crate) bits: &'a mut [u64],
}

/// Set bits of every byte.
const POP8: [u8; 256] = {
    let mut t = [0u8; 256];
    let mut i = 0;
    while i < 256 {
        t[i] = (i as u8).count_ones() as u8;
        i += 1;
    }
    t
};

/// A point with a crossed edge: the id of its first owned crossing and its owned crossings (bit d:
/// the crossing on the edge to neighbour d). `id(C, d) = first + popcount(owned & ((1 << d) - 1))`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) struct CrossedPoint {
    pub(crate) first: u32,
    pub(crate) owned: u16,
    /// All its crossed edges (owned or not), by neighbour bit.
    pub(crate) crossed: u16,
}

impl CrossedPoint {
    /// Id of the crossing this point owns on its edge to neighbour `d`.
    #[inline(always)]
    pub(crate) fn id(self, d: u8) -> u32 {
        let below = self.owned & ((1u16 << d) - 1);
        // Two byte lookups: without a popcount instruction in the baseline target, faster than
        // `count_ones` on the geometry pass's path (one id per triangle corner).
        self.first
            + u32::from(POP8[usize::from(below as u8)])
            + u32::from(POP8[usize::from(below >> 8)])
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
    pub(crate) bits: Vec<u64>,
    /// Per word of `bits`: how many bits are set in the words before it.
    pub(crate) rank: Vec<u32>,
    /// The crossed points in storage order (rank order).
    pub(crate) points: Vec<CrossedPoint>,
    /// Slots per storage plane, and words per plane.
    pub(crate) plane: usize,
    pub(crate) wpp: usize,
    /// `ceil(2^64 / plane)`: `slot / plane == (slot * div) >> 64` for every slot below 2^32
    /// (Lemire, Kaser and Kurz 2019); 0 when a plane has one slot.
    pub(crate) div: u64,
    /// Per storage plane and group (face axis, or the cube), the triangles of the groups its
    /// crossed points anchor, counted by the numbering ([`number_plane`]): the geometry
    /// layers' counts without a walk ([`crate::mt::geometry::layer_counts`]).
    pub(crate) plane_triangles: Vec<[u32; 3]>,
}

impl CrossedIndex {
    /// Bits cleared and sized for `planes` storage planes of `plane` slots; the rest is filled by
    /// [`CrossedIndex::rank_planes`] and the numbering.
    pub(crate) fn reset(&mut self, plane: usize, planes: usize) {
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
    pub(crate) fn plane_of(&self, slot: usize) -> usize {
        if self.div == 0 {
            return slot;
        }
        ((u128::from(self.div) * slot as u128) >> 64) as usize
    }

    /// Word of `bits` holding `slot`, and the slot's bit in it.
    #[cfg(test)]
    pub(crate) fn word(&self, slot: usize) -> (usize, usize) {
        let z = self.plane_of(slot);
        let local = slot - z * self.plane;
        (z * self.wpp + (local >> 6), local & 63)
    }

    /// Whether `slot` has a crossed edge.
    #[cfg(test)]
    pub(crate) fn is_crossed(&self, slot: usize) -> bool {
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
    pub(crate) fn rank_in(&self, z: usize, local: usize) -> usize {
        let (w, b) = (z * self.wpp + (local >> 6), local & 63);
        (self.rank[w] + (self.bits[w] & ((1u64 << b) - 1)).count_ones()) as usize
    }

    /// Bits of plane `z`.
    pub(crate) fn plane_bits(&self, z: usize) -> &[u64] {
        &self.bits[z * self.wpp..(z + 1) * self.wpp]
    }

    /// Fills the rank directory, given the number of crossed points before each plane
    /// (`starts[z]`), and sizes `points`.
    pub(crate) fn rank_planes(&mut self, starts: &[usize], total: usize, pool: &rayon::ThreadPool) {
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
        // Every entry is written by the vertex pass's step 2.
        overwritten(&mut self.points, total, CrossedPoint::default(), pool);
    }

    pub(crate) fn bytes(&self) -> usize {
        self.bits.len() * 8 + self.rank.len() * 4 + self.points.len() * 8
    }
}

/// The 64 bits of `words` from bit `pos` (as [`crate::util::bits_at`], without its branch on
/// an aligned `pos`): `words` holds a word past the one of `pos`.
#[inline(always)]
fn bits_from(words: &[u64], pos: usize) -> u64 {
    let (w, s) = (pos >> 6, pos & 63);
    // The higher word first: its bounds check covers the lower one's.
    let hi = words[w + 1];
    (words[w] >> s) | ((hi << 1) << (63 - s))
}

/// The inside bits of 64 values (bit k set when `values[k] < iso`), as
/// [`crate::util::inside_word`] gives them: on x86-64 four values per comparison (an ordered
/// less-than: NaN is outside, as with `<`), the masks of 16 values packed to bytes (all ones
/// or zero, which the signed saturating packs keep) and read with one byte mask.
#[inline]
fn inside_word64(values: &[f32; 64], iso: f32) -> u64 {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{
            _mm_castps_si128, _mm_cmplt_ps, _mm_loadu_ps, _mm_movemask_epi8, _mm_packs_epi16,
            _mm_packs_epi32, _mm_set1_ps,
        };
        let mut word = 0u64;
        // SAFETY: SSE2 is in the x86-64 baseline; each load reads 4 values of its chunk of 16
        // (unaligned).
        unsafe {
            let t = _mm_set1_ps(iso);
            for (i, sixteen) in values.as_chunks::<16>().0.iter().enumerate() {
                let p = sixteen.as_ptr();
                let m = |k: usize| _mm_castps_si128(_mm_cmplt_ps(_mm_loadu_ps(p.add(4 * k)), t));
                let bytes =
                    _mm_packs_epi16(_mm_packs_epi32(m(0), m(1)), _mm_packs_epi32(m(2), m(3)));
                word |= u64::from(_mm_movemask_epi8(bytes) as u16) << (16 * i);
            }
        }
        word
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        inside_word(values, iso)
    }
}

/// [`VertexTables::sides`]: some slot of a row inside.
const SOME_INSIDE: u8 = 1;
/// [`VertexTables::sides`]: some slot of a row outside (unused slots and slots past storage
/// read as outside, as their inside bits are clear).
const SOME_OUTSIDE: u8 = 2;
/// [`VertexTables::sides`]: slots on both sides.
const BOTH_SIDES: u8 = SOME_INSIDE | SOME_OUTSIDE;
/// [`VertexTables::sides`] of a padding row: outside, for the whole row and its last block.
const PAD_SIDES: u8 = SOME_OUTSIDE | SOME_OUTSIDE << TAIL;
/// The shift of the sides of a row's last block in [`VertexTables::sides`].
const TAIL: u32 = 2;

/// The first slot of the last block of 64 points of a row of `dx` slots, when the row has more
/// than one block (else 0: the row check covers it).
fn tail_start(dx: usize) -> usize {
    if dx > 64 {
        64 * ((dx - 1) / 64)
    } else {
        0
    }
}

/// [`VertexTables::sides`] of the row of `dx` slots from slot `start`, of `slots` in storage:
/// the row's sides, and with more than one block ([`tail_start`]) the sides of the slots that
/// its last block's points and their neighbours read in the row (one slot more on both ends:
/// a neighbour lies at most one slot along the row from the point; the slot past the last is
/// the next row's first, or past storage, outside).
fn row_and_tail_sides(words: &[u64], start: usize, dx: usize, slots: usize) -> u8 {
    let sides =
        |any: bool, all: bool| (u8::from(any) * SOME_INSIDE) | (u8::from(!all) * SOME_OUTSIDE);
    if dx > 64 && dx <= 125 {
        // Two blocks, the last one short (as on a 64^3 body-centred grid): the row's first 64
        // slots in one read, and slots 63 to `dx` (the last block's reach, the row's other
        // slots among them: bits 1 to `dx - 64`) in another.
        let first = bits_from(words, start);
        let from = start + 63;
        let len = (dx - 62).min(slots + 1 - from);
        let reach = (1u64 << len) - 1;
        let last = bits_from(words, from) & reach;
        let rest = ((1u64 << (dx - 63)) - 1) & !1;
        let row = sides(
            (first | (last & rest)) != 0,
            first == !0 && last & rest == rest,
        );
        return row | sides(last != 0, last == reach) << TAIL;
    }
    let row = row_sides(words, start, dx);
    let tail = tail_start(dx);
    if tail == 0 {
        return row;
    }
    let from = start + tail - 1;
    let len = (dx + 2 - tail).min(slots + 1 - from);
    let sides = if len < 64 {
        // One read (the common case: a short last block).
        let mask = (1u64 << len) - 1;
        let w = bits_from(words, from) & mask;
        (u8::from(w != 0) * SOME_INSIDE) | (u8::from(w != mask) * SOME_OUTSIDE)
    } else {
        row_sides(words, from, len)
    };
    row | sides << TAIL
}

/// Rows of padding before and after the rows of [`VertexTables::sides`], for rows of `dy` slots
/// per plane column: more than any neighbour's reach (two planes and a row).
fn sides_pad(dy: usize) -> usize {
    2 * dy + 2
}

/// The sides of the `len` slots from slot `start` ([`SOME_INSIDE`], [`SOME_OUTSIDE`]), from
/// the inside bits (`words` holds a word past the last slot).
fn row_sides(words: &[u64], start: usize, len: usize) -> u8 {
    let (mut any, mut all) = (0u64, !0u64);
    let mut n = 0;
    while n < len {
        let take = (len - n).min(64);
        let mask = if take < 64 { (1u64 << take) - 1 } else { !0 };
        let w = bits_from(words, start + n) & mask;
        any |= w;
        all &= w | !mask;
        n += take;
    }
    (u8::from(any != 0) * SOME_INSIDE) | (u8::from(all != !0) * SOME_OUTSIDE)
}

/// Set bits of a 16-bit word, by two byte lookups (no popcount instruction in the baseline
/// target).
#[inline(always)]
fn pop16(x: u16) -> u32 {
    u32::from(POP8[usize::from(x as u8)]) + u32::from(POP8[usize::from(x >> 8)])
}

/// Appends the positions of the crossings that the point at lattice coordinates `p` (storage
/// slot `i`) owns (`own`, by neighbour bit) to `positions`, in id order; returns how many lie
/// within [`WELD`] of it. The far end's coordinates are read from the point's window of each
/// axis table ([`super::layout::Positions::around`], by [`Layout::far`]) and the positions
/// written into capacity reserved once: no bounds or capacity check per crossing. Inlined into
/// the vertex pass's point visit (fewer instructions than a call since it has no such checks).
#[inline(always)]
fn place(
    l: &Layout,
    p: crate::lattice::Offset,
    i: usize,
    own: u16,
    iso: f32,
    positions: &mut Vec<[f32; 3]>,
) -> usize {
    let v = &l.s.values[..];
    let f = v[i];
    let far = &l.far[(p[0] & 1) as usize];
    let at = l.positions();
    let [cx, cy, cz] = at.around(p);
    let c = AROUND as usize;
    let pp = at.min_plus(cx[c], cy[c], cz[c]);
    let n = pop16(own) as usize;
    positions.reserve(n);
    let mut near = 0;
    let mut bits = own;
    for slot in &mut positions.spare_capacity_mut()[..n] {
        let (delta, o) = far[bits.trailing_zeros() as usize & 15];
        bits &= bits.wrapping_sub(1);
        let q = at.min_plus(
            cx[usize::from(o[0]) & 7],
            cy[usize::from(o[1]) & 7],
            cz[usize::from(o[2]) & 7],
        );
        let g = v[(i as isize + delta) as usize];
        let t = (iso - f) / (g - f);
        near += usize::from(t < WELD);
        slot.write(pp.lerp(q, t).to_array());
    }
    // SAFETY: the `n` slots past the length were reserved and written just above.
    unsafe { positions.set_len(positions.len() + n) };
    near
}

/// Words of the crossed-point bit set per storage plane of `plane` slots: one bit per slot plus
/// a zero word of padding, so that 64 bits can be read from any slot of the plane.
pub(crate) fn plane_words(plane: usize) -> usize {
    plane.div_ceil(64) + 1
}

/// What the vertex pass computes besides the crossings.
#[derive(Clone, Copy)]
pub(crate) struct VertexWork {
    /// Propose clusters by these rules ([`crate::mt::clustering::proposal`]).
    pub(crate) propose: Option<Rules>,
    /// The lattice edges of this grid, when an earlier extraction counted them (else they are
    /// counted into `Stats::edges`).
    pub(crate) known_edges: Option<usize>,
}

/// Counters of one plane of the vertex pass.
#[derive(Default, Clone, Copy)]
pub(crate) struct PlaneCounts {
    pub(crate) crossings: usize,
    pub(crate) edges: usize,
    pub(crate) proposals: ProposalCounts,
    /// Crossings within [`WELD`] of their owner (surfaces through sample points).
    pub(crate) near_points: usize,
    /// Per group (face axis, or the cube), the triangles of the groups whose anchors are the
    /// plane's crossed points ([`CrossedIndex::plane_triangles`]).
    pub(crate) triangles: [u32; 3],
}

/// Vertex pass over one storage plane: counts, cluster proposals, the plane's crossed-point bits
/// (`out.bits`), its crossed points in slot order (`out.points`: owned and crossed edges, the
/// id of the first owned crossing counted from the plane's first) and the positions of its
/// crossings (`out.positions`, in id order), and per group the triangles its points anchor.
/// The lattice edges of the plane are counted only without `work.known_edges` (they depend on
/// the grid alone: the extractor keeps the count of the last grid).
///
/// Per row (Flying Edges' trimming, by row): its slots and the slots its points' 14 neighbours
/// read lie in the row itself and in the rows `row + delta[d]` and the next one fall in; when
/// the sides of all of them ([`VertexTables::sides`]) are one side, no point of the row has a
/// crossed edge and the row is skipped. Otherwise 64 points at a time:
///
/// ```text
///   differ[d] = inside(64 points) ^ inside(their neighbours d)       14 word operations
///   block     = differ[0] | ... | differ[13]                          the crossed points
///   known[b] |= 1 << d   for each set bit b of differ[d] & block      per crossed edge
///   per crossed point b: owners of its crossed edges (far ends read), ids counted, the
///                        anchored groups' triangles counted, owned crossings placed
/// ```
// Not inlined into the pass: fewer instructions than inlined.
#[inline(never)]
pub(crate) fn vertex_plane(
    l: &Layout,
    inside_bits: &[u64],
    sides: &[u8],
    z: usize,
    iso: f32,
    work: VertexWork,
    mut out: PlaneOut<'_>,
) -> (PlaneCounts, Vec<Candidate>) {
    let VertexWork {
        propose,
        known_edges,
    } = work;
    let count_edges = known_edges.is_none();
    out.points.clear();
    out.positions.clear();
    let v = &l.s.values;
    let [dx, dy, _] = l.s.dims;
    let [nx, ny, nz] = l.s.cells;
    // The groups this plane's points anchor, as `geometry::for_each_group` walks them: per
    // group, its rows (`sy`) and the slots of each row (`sx`), empty when the plane has none.
    let none = (1, 0, 1, 0);
    let anchors: [(usize, usize, usize, usize); 3] = match l.lattice {
        Lattice::Simple if z < nz => [(0, ny - 1, 0, nx - 1), none, none],
        Lattice::Simple => [none; 3],
        Lattice::BodyCentred => {
            let faces = z.is_multiple_of(2) && z >= 2 && z <= 2 * nz;
            // Without ghosts, not the faces on the box's upper faces (as the walk).
            let upper = usize::from(l.s.boundary == crate::Boundary::Pyramids);
            [
                // Faces perpendicular to x (layer z / 2 - 1), to y, then to z (layer z / 2).
                if faces { (1, ny, 0, nx - upper) } else { none },
                if faces { (0, ny - upper, 1, nx) } else { none },
                if z.is_multiple_of(2) && z + 2 * upper <= 2 * nz {
                    (1, ny, 1, nx)
                } else {
                    none
                },
            ]
        }
    };
    let groups = [0, 1, 2].map(|g| &l.groups[g.min(l.groups.len() - 1)]);
    let slots = v.len();
    let mut counts = PlaneCounts::default();
    let mut cands = Vec::new();
    // Per parity: the storage rows (relative to a point's own row, each once) that a row's
    // points and their neighbour slots fall in: for neighbour d, from the row of `delta[d]`
    // to that of `delta[d] + dx - 1`.
    let mut near_rows = [([0isize; 32], 0usize); 2];
    for (par, (offs, n)) in near_rows.iter_mut().enumerate() {
        let mut add_row = |r: isize| {
            if !offs[..*n].contains(&r) {
                offs[*n] = r;
                *n += 1;
            }
        };
        add_row(0);
        for &a in &l.delta[par] {
            for r in a.div_euclid(dx as isize)..=(a + dx as isize - 1).div_euclid(dx as isize) {
                add_row(r);
            }
        }
    }
    let pad = sides_pad(dy);
    // The parity of the plane's points (every row's), their neighbour deltas and the rows
    // those fall in.
    let odd = (l.coords(0, 0, z)[2] & 1) as usize;
    let delta = &l.delta[odd];
    // The deltas again, 16 entries: `d & 15` is read without a bounds check.
    let far = &l.far[odd];
    let (dmin, dmax) = (
        delta.iter().copied().min().unwrap_or(0),
        delta.iter().copied().max().unwrap_or(0),
    );
    let (offs, n) = &near_rows[odd];
    let near = &offs[..*n];
    // The first row of the plane in `sides`: every near row lies inside its padding.
    let first_side = pad + z * dy;
    let tail = tail_start(dx);
    debug_assert!(
        delta.iter().all(|&a| (a + 1).rem_euclid(dx as isize) <= 2),
        "a neighbour lies at most one slot along the row from its point"
    );
    // Per row of the plane, the sides of the rows its points and their neighbour slots read
    // (the near rows' entries of `sides` OR-ed, a row offset at a time over the whole plane).
    // Near rows past the padding (never, for the lattices' reach) count as both sides: the
    // row is then walked.
    let mut around = vec![0u8; dy];
    for &o in near {
        let from = first_side.wrapping_add_signed(o);
        match sides.get(from..from + dy) {
            Some(near_sides) => {
                for (a, &s) in around.iter_mut().zip(near_sides) {
                    *a |= s;
                }
            }
            None => around.fill(BOTH_SIDES | BOTH_SIDES << TAIL),
        }
    }
    for (sy, &around) in around.iter().enumerate() {
        // The run of points in this row whose 14 neighbours are all regular lattice points: no
        // existence or border tests there.
        let run = || {
            let (lo, hi) = match l.lattice {
                Lattice::BodyCentred => (1 + odd, l.s.cells[0]),
                Lattice::Simple => (1, l.s.cells[0]),
            };
            let row_regular = lo < hi && l.is_regular(l.point(lo, sy, z).0);
            if row_regular {
                (lo, hi)
            } else {
                (dx, dx)
            }
        };
        if count_edges {
            let (lo, hi) = run();
            if lo < hi {
                counts.edges += 14 * (hi - lo);
            }
            for sx in (0..lo.min(dx)).chain(hi.max(lo)..dx) {
                let (exists, valid) = l.border_info(l.coords(sx, sy, z));
                if exists {
                    counts.edges += valid.count_ones() as usize;
                }
            }
        }
        // The row trimmed away when it and every row its neighbour slots fall in lie on one
        // side (before anything else is computed for it).
        if around & BOTH_SIDES != BOTH_SIDES {
            continue;
        }
        // The row's last block (of several) skipped likewise: where its rows all lie on one
        // side, no neighbour of its points differs from them.
        let end = if tail > 0 && around >> TAIL != BOTH_SIDES {
            tail
        } else {
            dx
        };
        let (lo, hi) = run();
        let row = z * dx * dy + sy * dx;
        // The slots of this row that anchor each group (empty: none).
        let anchor_x = anchors.map(|(y0, y1, x0, x1)| {
            if sy >= y0 && sy <= y1 {
                (x0, x1)
            } else {
                (1, 0)
            }
        });
        // Whether some group is anchored in this row at all (none in half the body-centred
        // planes).
        let anchoring = anchor_x.iter().any(|&(x0, x1)| x0 <= x1);
        // One point with at least one crossed edge: owned crossings, flags, proposals.
        // `known`: the point's crossed edges to all 14 neighbour slots, from the inside bits;
        // `border`: the neighbours whose edges exist, for a point off the regular run (`None`:
        // all 14, and every edge inner).
        let point = |sx: usize,
                     border: Option<u16>,
                     known: u16,
                     out: &mut PlaneOut<'_>,
                     counts: &mut PlaneCounts,
                     cands: &mut Vec<Candidate>| {
            let local = sy * dx + sx;
            let i = row + sx;
            let f = v[i];
            let valid = border.unwrap_or(FULL);
            // Only the crossed edges' far ends are read, for the owner.
            let crossed = known & valid;
            if crossed == 0 {
                return;
            }
            let mut own = 0u16;
            let mut bits = crossed;
            while bits != 0 {
                let d = bits.trailing_zeros() as usize;
                bits &= bits - 1;
                let g = v[(i as isize + far[d & 15].0) as usize];
                own |= u16::from(owns(f, g, iso)) << d;
            }
            // Ids within the plane for now; the plane's first id is added when the planes are
            // joined (points and proposals).
            let first = counts.crossings as u32;
            // Points come in slot order: `points` stays aligned with the bits.
            out.points.push(CrossedPoint {
                first,
                owned: own,
                crossed,
            });
            out.bits[local >> 6] |= 1 << (local & 63);
            if anchoring {
                for (g, &(x0, x1)) in anchor_x.iter().enumerate() {
                    if sx >= x0 && sx <= x1 {
                        let group = groups[g];
                        counts.triangles[g] += u32::from(group.triangles[group.code(crossed)]);
                    }
                }
            }
            if own != 0 {
                counts.crossings += pop16(own) as usize;
                let p = l.coords(sx, sy, z);
                counts.near_points += place(l, p, i, own, iso, out.positions);
            }
            // Without ghosts, no proposal near the pyramids of the box faces
            // (`Layout::near_pyramid`).
            if let Some(rules) =
                propose.filter(|_| own.count_ones() >= 2 && !l.near_pyramid(l.coords(sx, sy, z)))
            {
                // Only the islands rule reads which edges are inner (all of them in the regular
                // run).
                let inner = match (rules, border) {
                    (Rules::Islands, Some(valid)) => l.inner_dirs(l.coords(sx, sy, z)) & valid,
                    _ => valid,
                };
                let edges = PointEdges {
                    valid,
                    inner,
                    owned: own,
                    crossed,
                };
                counts
                    .proposals
                    .add(proposal::propose(l.t, first, i as u32, edges, rules, cands));
            }
        };
        // The points tested 64 at a time, the whole row (the test may let through a border
        // point whose only difference is with a slot that is not its neighbour; `point` keeps
        // the real neighbours). Where some neighbour slot of the row lies outside storage (the
        // first and last planes), the bits are read with that check (slots outside read as
        // outside points: never a real neighbour).
        let safe = row as isize + dmin >= 0 && (row + dx) as isize + dmax <= slots as isize;
        let mut sx = 0;
        while sx < end {
            let len = (end - sx).min(64);
            // Per neighbour, which of the 64 points differ from it.
            let own_bits = bits_from(inside_bits, row + sx);
            let at = (row + sx) as isize;
            let differ: [u64; 14] = if safe {
                std::array::from_fn(|d| own_bits ^ bits_from(inside_bits, (at + delta[d]) as usize))
            } else {
                std::array::from_fn(|d| own_bits ^ bits_at_signed(inside_bits, at + delta[d]))
            };
            let mut block = differ.iter().fold(0, |a, &w| a | w);
            if len < 64 {
                block &= (1u64 << len) - 1;
            }
            if block == 0 {
                sx += len;
                continue;
            }
            // Each point's differing neighbours, edge by edge: a crossed point has a few of its
            // 14 (about 4 on a smooth surface), cheaper than gathering 14 bits per point.
            let mut known = [0u16; 64];
            for (d, &w) in differ.iter().enumerate() {
                let mut w = w & block;
                while w != 0 {
                    known[w.trailing_zeros() as usize & 63] |= 1 << d;
                    w &= w - 1;
                }
            }
            while block != 0 {
                let b = block.trailing_zeros() as usize;
                let x = sx + b;
                block &= block - 1;
                let known = known[b & 63];
                let border = if x >= lo && x < hi {
                    None
                } else {
                    let (exists, valid) = l.border_info(l.coords(x, sy, z));
                    if !exists {
                        continue;
                    }
                    Some(valid)
                };
                point(x, border, known, &mut out, &mut counts, &mut cands);
            }
            sx += len;
        }
    }
    (counts, cands)
}

/// The vertex pass, after [`VertexTables::allocate`]: step 0, the inside bit of every sample point;
/// step 1 (parallel over storage planes), the sides of every row, then each plane's crossed
/// points, their owned crossings, the crossings' positions and (with `work.propose`) the
/// cluster proposals ([`crate::mt::clustering::proposal`]); step 2 (parallel over planes),
/// the planes' crossed points with their ids, their proposals (`out.proposals`, replacing what
/// it held) and the positions (`out.positions`, one vertex per crossing) copied into place. Returns how many crossings lie on a sample
/// point (within the weld distance). On the simple lattice, step 0 also checks every value and
/// errors with [`ExtractError::NonFiniteValue`] (the first in storage order) on NaN or
/// infinity.
///
/// ```text
///   inside bits  ->  crossed points (bits + rank)  ->  ids: first(C) + popcount(owned & below d)
///   1 0 0 1 ...      C: owned = {d : |f(C)-T| < |f(S_d)-T|, C-S_d crossed}
/// ```
pub(crate) fn vertex_pass(
    layout: &Layout,
    iso: f32,
    work: VertexWork,
    pool: &rayon::ThreadPool,
    buf: &mut VertexTables,
    out: VertexOut<'_>,
    stats: &mut Stats,
) -> Result<usize, ExtractError> {
    let samples = layout.s;
    let known_edges = work.known_edges;
    let slots = samples.values.len();
    let words = slots.div_ceil(64);
    let planes = samples.dims[2];
    // Vertex pass, step 0: the inside bits. On the simple lattice every slot is a lattice
    // point, and its values are checked for NaN and infinities in the same read (the unused
    // slots of the body-centred lattice hold NaN; its values come from a field, checked as
    // sampled, or are the caller's to check).
    {
        let values = &samples.values;
        let check = layout.lattice == Lattice::Simple;
        let non_finite = pool.install(|| {
            buf.inside[..words]
                .par_chunks_mut(1024)
                .enumerate()
                .map(|(c, chunk)| {
                    let mut bad = false;
                    for (j, word) in chunk.iter_mut().enumerate() {
                        let start = (c * 1024 + j) * 64;
                        let end = (start + 64).min(slots);
                        let block = &values[start..end];
                        *word = match (<&[f32; 64]>::try_from(block), check) {
                            (Ok(block), false) => inside_word64(block, iso),
                            (Ok(block), true) => {
                                let (w, b) = inside_word_finite64(block, iso);
                                bad |= b;
                                w
                            }
                            (Err(_), _) => {
                                bad |= check && block.iter().any(|v| !v.is_finite());
                                inside_word(block, iso)
                            }
                        };
                    }
                    bad
                })
                .reduce(|| false, |a, b| a | b)
        });
        if non_finite {
            if let Some(e) = samples.non_finite_error() {
                return Err(e);
            }
        }
        buf.inside[words] = 0;
    }

    // Vertex pass, step 1a: the sides of every storage row (the trimming of step 1b).
    {
        let [dx, dy, _] = samples.dims;
        let inside = &buf.inside;
        let pad = sides_pad(dy);
        pool.install(|| {
            buf.sides[pad..pad + dy * planes]
                .par_chunks_mut(dy)
                .enumerate()
                .for_each(|(z, sides)| {
                    for (sy, side) in sides.iter_mut().enumerate() {
                        *side = row_and_tail_sides(inside, (z * dy + sy) * dx, dx, slots);
                    }
                })
        });
    }

    // Vertex pass, step 1b: owned crossings and proposals per plane.
    let inside = &buf.inside;
    let sides = &buf.sides;
    let wpp = buf.crossed.wpp;
    let per_plane: Vec<(PlaneCounts, Vec<Candidate>)> = pool.install(|| {
        buf.plane_points[..planes]
            .par_iter_mut()
            .zip(buf.plane_positions[..planes].par_iter_mut())
            .zip(buf.crossed.bits.par_chunks_mut(wpp))
            .enumerate()
            .map(|(z, ((points, positions), bits))| {
                let out = PlaneOut {
                    points,
                    positions,
                    bits,
                };
                vertex_plane(layout, inside, sides, z, iso, work, out)
            })
            .collect()
    });
    let mut starts = Vec::with_capacity(per_plane.len() + 1);
    let mut point_starts = Vec::with_capacity(per_plane.len() + 1);
    let mut total = 0usize;
    let mut total_points = 0usize;
    let mut proposals = ProposalCounts::default();
    let (mut cand_starts, mut total_cands) = (Vec::with_capacity(per_plane.len()), 0usize);
    for (z, (c, cands)) in per_plane.iter().enumerate() {
        starts.push(total);
        total += c.crossings;
        point_starts.push(total_points);
        total_points += buf.plane_points[z].len();
        if known_edges.is_none() {
            stats.edges += c.edges;
        }
        proposals.add(c.proposals);
        cand_starts.push(total_cands);
        total_cands += cands.len();
    }
    stats.edges = match known_edges {
        Some(edges) => edges,
        None => stats.edges / 2,
    };
    stats.crossings = total;
    if total > u32::MAX as usize - 1 {
        return Err(ExtractError::TooLarge {
            cells: samples.cells,
            limit: u32::MAX as usize,
        });
    }
    buf.crossed.rank_planes(&point_starts, total_points, pool);
    // Step 2: the planes joined: their crossed points and their proposals, with the plane's
    // first id added, and their crossings' positions copied into place.
    // Zeroed in parallel: the mesh's positions start empty, often in fresh memory, and one
    // thread taking every first touch cost more than the fill (plain MT, 64^3 sphere, 2
    // threads: this step 156 -> 27 us, the extraction 0.92 of its time; 1 thread unchanged).
    overwritten(out.positions, total, [0.0; 3], pool);
    let no_candidate = Candidate {
        first: 0,
        members: 0,
        dirs: 0,
        slot: 0,
    };
    overwritten(out.proposals, total_cands, no_candidate, pool);
    {
        let mut rest: &mut [Candidate] = out.proposals;
        let mut cand_parts = Vec::with_capacity(per_plane.len());
        for (_, cands) in &per_plane {
            let (head, tail) = rest.split_at_mut(cands.len());
            cand_parts.push(head);
            rest = tail;
        }
        let mut rest: &mut [[f32; 3]] = out.positions;
        let mut chunks = Vec::with_capacity(per_plane.len());
        for (c, _) in &per_plane {
            let (head, tail) = rest.split_at_mut(c.crossings);
            chunks.push(head);
            rest = tail;
        }
        let mut rest: &mut [CrossedPoint] = &mut buf.crossed.points;
        let mut entries = Vec::with_capacity(per_plane.len());
        for points in &buf.plane_points[..planes] {
            let (head, tail) = rest.split_at_mut(points.len());
            entries.push(head);
            rest = tail;
        }
        let (plane_points, plane_positions) = (&buf.plane_points, &buf.plane_positions);
        let per_plane = &per_plane;
        pool.install(|| {
            entries
                .into_par_iter()
                .zip(chunks.into_par_iter())
                .zip(cand_parts.into_par_iter())
                .enumerate()
                .for_each(|(z, ((entries, positions), cands))| {
                    let start = starts[z] as u32;
                    for (e, p) in entries.iter_mut().zip(&plane_points[z]) {
                        *e = CrossedPoint {
                            first: start + p.first,
                            ..*p
                        };
                    }
                    positions.copy_from_slice(&plane_positions[z]);
                    for (out, c) in cands.iter_mut().zip(&per_plane[z].1) {
                        *out = Candidate {
                            first: start + c.first,
                            ..*c
                        };
                    }
                })
        });
    }
    let near_points = per_plane.iter().map(|(c, _)| c.near_points).sum();
    buf.crossed.plane_triangles.clear();
    buf.crossed
        .plane_triangles
        .extend(per_plane.iter().map(|(c, _)| c.triangles));
    // The per-plane proposals were copied into `out.proposals`: free them before the geometry
    // pass and the clustering allocate.
    drop(per_plane);
    stats.clusters_proposed = proposals.proposed;
    stats.clusters_rejected_prefilter = proposals.rejected;
    Ok(near_points)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mt::layout::Layout;
    use crate::mt::testing::{lcg, plain_mt, settings_on, test_pool, wavy};

    #[test]
    fn a_reused_extractor_counts_the_edges_and_crossings_of_each_grid_as_a_fresh_one() {
        // The second extraction of a grid takes the edge count from the first; a new grid
        // (or lattice) counts anew. A fresh extractor is the reference every time.
        let field = wavy();
        let mut compared = 0;
        for lattice in [Lattice::BodyCentred, Lattice::Simple] {
            let mut reused = crate::Extractor::new();
            for cells in [[6, 5, 7], [6, 5, 7], [5, 6, 7], [2, 2, 4], [6, 5, 7]] {
                for clustering in [crate::Clustering::None, crate::Clustering::Integrated] {
                    let settings = settings_on(cells, lattice, clustering);
                    let (mut a, mut b) = (rmt_mesh::Mesh::default(), rmt_mesh::Mesh::default());
                    let sa = reused.extract(&field, &settings, &mut a).unwrap();
                    let sb = crate::Extractor::new()
                        .extract(&field, &settings, &mut b)
                        .unwrap();
                    let what = format!("{lattice:?} {cells:?} {clustering:?}");
                    assert!(sa.edges > 0, "{what}");
                    assert_eq!(sa.edges, sb.edges, "{what}");
                    assert_eq!(sa.crossings, sb.crossings, "{what}");
                    assert_eq!(a.indices, b.indices, "{what}");
                    assert_eq!(a.positions, b.positions, "{what}");
                    compared += a.triangle_count();
                }
            }
        }
        assert!(compared > 500, "only {compared} triangles compared");
    }

    #[test]
    fn crossed_index_finds_every_point_and_its_owned_crossings() {
        // Grids whose storage planes hold fewer slots than a word of bits, about as many, and
        // many more; the reference is each point's 14 edges tested one by one.
        let field = rmt_fields::FnField(|p: glam::Vec3| {
            (p.x * 7.1).sin() + (p.y * 5.3).cos() * (p.z * 3.7 + 0.4).sin() - 0.2
        });
        let pool = test_pool(2);
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
                // Rows of two blocks of 64 points (the last one checked on its own).
                [70, 3, 4],
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
                            assert_eq!(buf.vertices.crossed.plane_of(slot), z, "{what}");
                            assert_eq!(
                                buf.vertices.crossed.is_crossed(slot),
                                crossed != 0,
                                "{what}"
                            );
                            if crossed != 0 {
                                let expected = CrossedPoint {
                                    first: before,
                                    owned: own,
                                    crossed,
                                };
                                assert_eq!(buf.vertices.crossed.get(slot), expected, "{what}");
                                assert_eq!(buf.vertices.crossed.points[rank], expected, "{what}");
                                rank += 1;
                                checked += usize::from(own != 0);
                            }
                            before += own.count_ones();
                        }
                    }
                }
                assert_eq!(
                    rank,
                    buf.vertices.crossed.points.len(),
                    "{lattice:?} {cells:?}"
                );
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
    fn the_vertex_pass_reads_inside_bits_as_the_shared_helpers_do() {
        // 64 values at a time (SIMD on x86-64) against `inside_word`, NaN, signed zeros and
        // values equal to the isovalue included; `bits_from` against `bits_at` at every offset.
        let mut state = 11u64;
        for iso in [0.0f32, 0.25, -0.5] {
            for _ in 0..200 {
                let values: [f32; 64] =
                    std::array::from_fn(|k| match (k * 7 + state as usize) % 9 {
                        0 => iso,
                        1 => f32::NAN,
                        2 => -0.0,
                        3 => 0.0,
                        _ => lcg(&mut state) * 2.0 - 1.0,
                    });
                assert_eq!(
                    inside_word64(&values, iso),
                    inside_word(&values, iso),
                    "iso {iso}"
                );
            }
        }
        let words: Vec<u64> = (0..5)
            .map(|_| (lcg(&mut state) * 1e18) as u64 ^ 0xA5A5_5A5A_0F0F_F0F0)
            .collect();
        for pos in 0..64 * 4 {
            assert_eq!(
                bits_from(&words, pos),
                crate::util::bits_at(&words, pos),
                "pos {pos}"
            );
        }
    }

    #[test]
    fn row_sides_say_whether_some_slot_is_inside_and_some_outside() {
        // Runs of every length up to three words from every offset of a random bit set with
        // long runs of one side, against the bits one by one.
        let mut state = 5u64;
        let mut bits = vec![0u64; 6];
        let mut inside = false;
        for i in 0..5 * 64 {
            if lcg(&mut state) < 0.05 {
                inside = !inside;
            }
            bits[i >> 6] |= u64::from(inside) << (i & 63);
        }
        let mut seen = [0usize; 4];
        for start in 0..2 * 64 {
            for len in 1..=3 * 64 {
                let slots = start..start + len;
                let any_in = slots.clone().any(|i| bits[i >> 6] >> (i & 63) & 1 == 1);
                let any_out = slots.clone().any(|i| bits[i >> 6] >> (i & 63) & 1 == 0);
                let want = (u8::from(any_in) * SOME_INSIDE) | (u8::from(any_out) * SOME_OUTSIDE);
                assert_eq!(
                    row_sides(&bits, start, len),
                    want,
                    "start {start} len {len}"
                );
                seen[usize::from(want)] += 1;
            }
        }
        assert!(
            seen[1] > 0 && seen[2] > 0 && seen[3] > 0,
            "every outcome met: {seen:?}"
        );
    }

    #[test]
    fn the_sides_of_a_rows_last_block_cover_the_slots_its_points_and_neighbours_read() {
        // Rows of one block and of several, every row of a random bit set with long runs
        // (storage ending mid-word and at a word's end), against the bits one by one: the
        // row's slots, then its last block's slots with one more on both ends (past storage:
        // outside).
        let mut state = 3u64;
        let mut seen = [0usize; 4];
        for slots in [9 * 64 - 5, 9 * 64usize] {
            let mut bits = vec![0u64; slots.div_ceil(64) + 1];
            let mut inside = false;
            for i in 0..slots {
                if lcg(&mut state) < 0.03 {
                    inside = !inside;
                }
                bits[i >> 6] |= u64::from(inside) << (i & 63);
            }
            let bit = |i: usize| i < slots && bits[i >> 6] >> (i & 63) & 1 == 1;
            let sides_of = |r: std::ops::Range<usize>| {
                let any_in = r.clone().any(bit);
                let any_out = r.clone().any(|i| !bit(i));
                (u8::from(any_in) * SOME_INSIDE) | (u8::from(any_out) * SOME_OUTSIDE)
            };
            for dx in [5, 64, 65, 66, 100, 128, 129, 190] {
                for start in (0..slots).step_by(dx) {
                    let dx = dx.min(slots - start);
                    let got = row_and_tail_sides(&bits, start, dx, slots);
                    assert_eq!(got & 3, sides_of(start..start + dx), "{slots} {dx} {start}");
                    let tail = tail_start(dx);
                    let want = if tail == 0 {
                        0
                    } else {
                        sides_of(start + tail - 1..start + dx + 1)
                    };
                    assert_eq!(got >> TAIL, want, "{slots} {dx} {start}");
                    seen[usize::from(want)] += 1;
                }
            }
        }
        assert!(
            seen[1] > 0 && seen[2] > 0 && seen[3] > 0,
            "every outcome met: {seen:?}"
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
}
