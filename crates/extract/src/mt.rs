//! Marching tetrahedra on both lattices: the vertex pass, the geometry pass, and the commit of
//! clusters.
//!
//! **Vertex pass** (parallel over storage planes): for each sample point C and each of its
//! neighbours S, the edge C-S is crossed when C and S lie on opposite sides of the threshold T
//! (inside is f < T). The crossing belongs to the nearer end (|f - T| smaller; on a tie, the inside
//! end), so every crossing has exactly one owner and its vertex id does not depend on processing
//! order: ids are numbered by owner (storage order), then by neighbour index. A point's owned
//! crossings are 14 flag bits (`owned`), and `FirstIds` gives the id of its first one in 1.25
//! bytes per slot: `id(C, d) = first(C) + popcount(owned[C] & ((1 << d) - 1))`. With clustering,
//! the pass also proposes clusters ([`crate::cluster`]).
//!
//! **Geometry pass** (parallel over z-layers): every tetrahedron whose corners disagree gives one
//! or two triangles from the case table; layers are concatenated in order, so the output is the
//! same for any thread count. Cubes (or body-centred faces) whose sample points all agree are
//! skipped before any tetrahedron is looked at.
//!
//! **Commit** (clustering): clusters are merged one lattice colour at a time, each only after the
//! exact check of [`crate::merge`] (integrated) or without it (integrated-unchecked).
//!
//! Border rule: points on the box faces (whose lattice edges are cut by the box) cluster too, with
//! the missing neighbours counted as neither crossed nor uncrossed. A crossing that lies on the box
//! face is a vertex of the mesh boundary, and the exact check refuses every cluster whose region
//! reaches the mesh boundary through a merged vertex, so crossings on the box faces never move and
//! the mesh stays closed wherever the surface stays inside the box. (The unchecked mode has no such
//! guarantee; that is its point.)

use rayon::prelude::*;
use rmt_mesh::Mesh;

use crate::cluster::{self, Candidate, ProposalCounts, FULL};
use crate::lattice::{self, LatticeTables, Offset};
use crate::merge::MergeBuffers;
use crate::{CellRange, Clustering, ExtractError, ExtractSettings, Lattice, Samples, Stats};

/// Per-point working arrays kept between extractions.
#[derive(Default)]
pub struct MtBuffers {
    /// Owned crossing flags per storage slot.
    owned: Vec<u16>,
    /// Where each point's crossings are numbered ([`FirstIds`]).
    ids: FirstIds,
    /// Cluster candidates, in storage order.
    candidates: Vec<Candidate>,
    /// Triangles of each geometry layer, as crossing ids: the geometry pass's output is their
    /// concatenation in layer order.
    layers: Vec<Vec<u32>>,
    /// One bit per storage slot, set where the value is inside (`f < iso`), plus one zero word
    /// of padding: 64 points are tested for crossings at once with a few word operations.
    inside: Vec<u64>,
    /// Working memory of the cluster commit, one per block of candidates.
    commits: Vec<CommitBlock>,
    /// One bit per storage slot, set where the point has a crossed edge (owned or not), in
    /// [`plane_words`] words per storage plane (the last one padding): the numbering and the
    /// geometry pass visit only these points.
    crossed: Vec<u64>,
}

/// Slots per block of [`FirstIds`].
const ID_BLOCK: usize = 16;

/// The id of each point's first owned crossing, in 1.25 bytes per slot instead of 4: the number
/// of crossings owned by the slots before each block of [`ID_BLOCK`] slots, and per slot the
/// number owned by the slots before it in its block (at most 15 x 14 = 210, a byte).
/// `id(C, d) = first(C) + popcount(owned[C] & ((1 << d) - 1))`.
#[derive(Default)]
struct FirstIds {
    block: Vec<u32>,
    offset: Vec<u8>,
}

impl FirstIds {
    /// Id of the first crossing owned by `slot` (meaningful where it owns one).
    #[inline(always)]
    fn first(&self, slot: usize) -> u32 {
        self.block[slot / ID_BLOCK] + u32::from(self.offset[slot])
    }

    /// Sized for `slots` storage slots (contents left as they are: numbering overwrites what is
    /// read).
    fn resize(&mut self, slots: usize) {
        self.block.resize(slots.div_ceil(ID_BLOCK), 0);
        self.offset.resize(slots, 0);
    }

    fn bytes(&self) -> usize {
        self.block.len() * 4 + self.offset.len()
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

/// Candidates of one colour are checked in blocks of this many, in parallel.
const COMMIT_BLOCK: usize = 64;

/// A cluster that passed its check, waiting to be applied.
struct Accepted {
    /// Its crossings, in [`CommitBlock::members`].
    members: std::ops::Range<u32>,
    /// What the merge changes, in [`CommitBlock::edits`].
    edits: std::ops::Range<u32>,
    centre: [f32; 3],
    /// Accepted without one of its proposed crossings.
    reduced: bool,
}

/// Checks and records of one block of cluster candidates (kept between extractions).
#[derive(Default)]
struct CommitBlock {
    scratch: crate::merge::Scratch,
    /// Members of the cluster being tried.
    k: Vec<u32>,
    accepted: Vec<Accepted>,
    members: Vec<u32>,
    edits: Vec<crate::merge::TriangleEdit>,
    rejected: usize,
}

impl CommitBlock {
    fn clear(&mut self) {
        self.accepted.clear();
        self.members.clear();
        self.edits.clear();
        self.rejected = 0;
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

/// Edges shorter than this many grid spacings are welded after clustering (coincident crossings).
const WELD: f32 = 1e-4;

/// Integrated clustering ends with one collapse per triangle whose aspect ratio R/(2r) is above
/// this (see [`crate::collapse::collapse_slivers`]); triangles of a good RMT mesh stay below 2.5.
const SLIVER_AR: f32 = 4.0;

/// Bit 15 of a point's `owned` word: some edge of the point is crossed (owned or not). A cube or
/// body-centred face whose anchor point has no crossed edge has all its points on one side.
const HAS_CROSSING: u16 = 0x8000;
/// The 14 neighbour bits of an `owned` word.
const OWNED_BITS: u16 = 0x3FFF;

/// Edges of a tetrahedron (v0..v3), as in `rmt-spec.md`.
const TET_EDGES: [(usize, usize); 6] = [(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)];

/// Case table: for the corners inside (bit i: f(v_i) < T), a directed cycle of crossed edges whose
/// right-hand normal points toward increasing f for a positively oriented tetrahedron. Length 3
/// (triangle) or 4 (quad, split along its shorter diagonal); `u8::MAX` pads. Checked against
/// geometry by `case_table_orients_triangles_along_the_gradient`.
const CASES: [[u8; 4]; 16] = {
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

/// Whether the end with value `f` (inside iff `f < iso`) owns the crossing shared with `g`.
#[inline(always)]
fn owns(f: f32, g: f32, iso: f32) -> bool {
    let (df, dg) = ((f - iso).abs(), (g - iso).abs());
    df < dg || (df == dg && f < iso)
}

/// A tetrahedron with storage-index deltas from a reference point and edge directions.
#[derive(Clone, Copy, Debug)]
struct TetTemplate {
    delta: [isize; 4],
    /// `dir[i][j]`: neighbour index of corner j seen from corner i.
    dir: [[u8; 4]; 4],
}

/// The lattice in storage terms: neighbour deltas per parity and tetrahedron templates.
struct Layout<'a> {
    s: &'a Samples,
    lattice: Lattice,
    t: &'static LatticeTables,
    /// Storage-index delta of neighbour d, for even (`[0]`) and odd (`[1]`) points.
    delta: [[isize; 14]; 2],
    tets: Vec<TetTemplate>,
    /// Existence (bit 16) and valid-neighbour mask (bits 0..14) of a point by the boundary
    /// class of each coordinate ([`boundary_class`]) and its parity; empty for grids too small
    /// for the classes to be apart (then computed point by point).
    border_table: Vec<u32>,
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
            .collect();
        let mut layout = Self {
            s,
            lattice,
            t,
            delta,
            tets,
            border_table: Vec::new(),
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
                            (1 << 16) | u32::from(self.valid_neighbours(p))
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

    /// Lattice coordinates of storage slot (sx, sy) of plane z, and whether the point exists.
    #[inline]
    fn point(&self, sx: usize, sy: usize, z: usize) -> (Offset, bool) {
        let p = self.coords(sx, sy, z);
        match self.lattice {
            Lattice::Simple => (p, true),
            Lattice::BodyCentred => (p, self.s.bcdl_exists(p)),
        }
    }

    fn position(&self, p: Offset) -> glam::Vec3 {
        match self.lattice {
            Lattice::BodyCentred => self.s.bcdl_position(p),
            Lattice::Simple => self
                .s
                .simple_position(p[0] as usize, p[1] as usize, p[2] as usize),
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
    fn is_regular(&self, p: Offset) -> bool {
        let margin = match self.lattice {
            Lattice::BodyCentred => 2 + (p[0] & 1),
            Lattice::Simple => 1,
        };
        (0..3).all(|a| p[a] >= margin && p[a] <= self.max_coord(a) - margin)
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
    let propose = matches!(
        clustering,
        Clustering::Integrated | Clustering::IntegratedUnchecked
    );
    // Tile rule (chunked extraction): lattice colours in global coordinates, and merges only
    // inside one tile (`Tiling`).
    let colour_shift: Offset = settings.tiles.map_or([0; 3], |t| {
        let scale = if lattice == Lattice::BodyCentred {
            2
        } else {
            1
        };
        t.grid_offset.map(|o| (o * scale) as i32)
    });
    let mut keys: Vec<u64> = Vec::new();

    // Allocation: per-slot tables sized to the sample array.
    let t = std::time::Instant::now();
    let slots = samples.values.len();
    buf.owned.resize(slots, 0);
    buf.ids.resize(slots);
    buf.candidates.clear();
    let words = slots.div_ceil(64);
    buf.inside.resize(words + 1, 0);
    let plane = samples.dims[0] * samples.dims[1];
    let wpp = plane_words(plane);
    buf.crossed.clear();
    buf.crossed.resize(wpp * samples.dims[2], 0);
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
                        let mut x = 0u64;
                        for (k, &f) in values[start..end].iter().enumerate() {
                            x |= u64::from(f < iso) << k;
                        }
                        *word = x;
                    }
                });
        });
        buf.inside[words] = 0;
    }

    // Vertex pass, step 1: owned crossings and proposals per plane.
    let inside = &buf.inside;
    let per_plane: Vec<(PlaneCounts, Vec<Candidate>)> = pool.install(|| {
        buf.owned
            .par_chunks_mut(plane)
            .zip(buf.crossed.par_chunks_mut(wpp))
            .enumerate()
            .map(|(z, (owned, crossed))| {
                vertex_plane(
                    &layout,
                    inside,
                    z,
                    iso,
                    propose,
                    clustering == Clustering::Integrated,
                    colour_shift,
                    owned,
                    crossed,
                )
            })
            .collect()
    });
    let mut starts = Vec::with_capacity(per_plane.len() + 1);
    let mut total = 0usize;
    let mut proposals = ProposalCounts::default();
    for (c, cands) in &per_plane {
        starts.push(total);
        total += c.crossings;
        stats.edges += c.edges;
        proposals.add(c.proposals);
        buf.candidates.extend_from_slice(cands);
    }
    stats.edges /= 2;
    stats.crossings = total;
    if total > u32::MAX as usize - 1 {
        return Err(ExtractError::TooLarge {
            cells: samples.cells,
            limit: u32::MAX as usize,
        });
    }
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
        // Plane z numbers the id blocks that start in it.
        let mut rest: &mut [u32] = &mut buf.ids.block;
        let mut blocks = Vec::with_capacity(per_plane.len());
        for z in 0..per_plane.len() {
            let n = ((z + 1) * plane).div_ceil(ID_BLOCK) - (z * plane).div_ceil(ID_BLOCK);
            let (head, tail) = rest.split_at_mut(n);
            blocks.push(head);
            rest = tail;
        }
        let (owned, crossed) = (&buf.owned, &buf.crossed);
        near_points = pool.install(|| {
            buf.ids
                .offset
                .par_chunks_mut(plane)
                .zip(chunks.into_par_iter())
                .zip(blocks.into_par_iter())
                .enumerate()
                .map(|(z, ((offset, out), blocks))| {
                    number_plane(
                        &layout,
                        z,
                        iso,
                        owned,
                        &crossed[z * wpp..(z + 1) * wpp],
                        (
                            starts[z] as u32,
                            (starts[z] + per_plane[z].0.crossings) as u32,
                        ),
                        blocks,
                        offset,
                        out,
                    )
                })
                .sum::<usize>()
        });
    }
    if let Some(tiling) = &settings.tiles {
        if propose || clustering == Clustering::Postprocessed {
            let crossed = &buf.crossed;
            let dz = samples.dims[2];
            crate::tiles::crossing_keys(
                samples,
                tiling,
                &buf.owned,
                |visit| {
                    for z in 0..dz {
                        for_each_bit(&crossed[z * wpp..(z + 1) * wpp], 0, plane, |local| {
                            visit(z * plane + local)
                        });
                    }
                },
                &mut keys,
            );
        }
    }
    let tiled = settings.tiles.is_some();
    let allowed = |k: &[u32], keys: &[u64]| !tiled || crate::tiles::same_tile(keys, k);
    stats.t_vertex_s += t.elapsed().as_secs_f64();

    // Geometry pass.
    let t = std::time::Instant::now();
    let layers = match lattice {
        Lattice::BodyCentred => samples.cells[2] + 1,
        Lattice::Simple => samples.cells[2],
    };
    if buf.layers.len() < layers {
        buf.layers.resize_with(layers, Vec::new);
    }
    let (owned, ids, crossed, positions) = (&buf.owned, &buf.ids, &buf.crossed, &mesh.positions);
    stats.tetrahedra_processed += pool.install(|| {
        buf.layers[..layers]
            .par_iter_mut()
            .enumerate()
            .map(|(k, out)| {
                out.clear();
                geometry_layer(
                    &layout,
                    k,
                    iso,
                    settings.keep_cells,
                    owned,
                    ids,
                    crossed,
                    positions,
                    out,
                )
            })
            .sum::<usize>()
    });
    let layer_tris = &buf.layers[..layers];
    let [nx, ny, nz] = samples.cells;
    stats.tetrahedra_total = match lattice {
        Lattice::BodyCentred => 4 * ((nx + 1) * ny * nz + nx * (ny + 1) * nz + nx * ny * (nz + 1)),
        Lattice::Simple => 6 * nx * ny * nz,
    };
    stats.t_geometry_s += t.elapsed().as_secs_f64();

    // Clustering: commit one colour at a time (counted in the vertex pass, where the dissertation
    // does its merging).
    stats.clusters_proposed = proposals.proposed;
    stats.clusters_rejected_prefilter = proposals.rejected;
    if propose {
        let t = std::time::Instant::now();
        let check = clustering == Clustering::Integrated;
        merge.load_parts(total, layer_tris);
        // Clusters grouped by colour, storage order inside a colour.
        buf.candidates.sort_by_key(|c| c.colour);
        let MtBuffers {
            owned,
            ids,
            candidates,
            commits,
            ..
        } = &mut *buf;
        let (owned, ids): (&[u16], &FirstIds) = (owned, ids);
        let members =
            |c: &Candidate, island: u16, positions: &[[f32; 3]], k: &mut Vec<u32>| -> [f32; 3] {
                k.clear();
                let (o, b) = (
                    owned[c.slot as usize] & OWNED_BITS,
                    ids.first(c.slot as usize),
                );
                let mut bits = island;
                let mut sum = glam::Vec3::ZERO;
                while bits != 0 {
                    let d = bits.trailing_zeros();
                    bits &= bits - 1;
                    let id = b + (o & ((1u16 << d) - 1)).count_ones();
                    k.push(id);
                    sum += glam::Vec3::from(positions[id as usize]);
                }
                (sum / k.len() as f32).to_array()
            };
        for group in candidates.chunk_by(|a, b| a.colour == b.colour) {
            // Clusters of one colour share no tetrahedron, hence no triangle: check them in
            // parallel against the mesh as the earlier colours left it, recording what each
            // accepted merge changes, then apply the records in storage order.
            let blocks = group.len().div_ceil(COMMIT_BLOCK);
            if commits.len() < blocks {
                commits.resize_with(blocks, CommitBlock::default);
            }
            let positions = &mesh.positions;
            let merge_ref = &*merge;
            let keys = &keys;
            let try_block = |b: &mut CommitBlock, cands: &[Candidate]| {
                b.clear();
                for c in cands {
                    let try_island = |island: u16, b: &mut CommitBlock| -> bool {
                        let centre = members(c, island, positions, &mut b.k);
                        if !allowed(&b.k, keys) {
                            return false;
                        }
                        let first_edit = b.edits.len();
                        if check {
                            let (scratch, edits) = (&mut b.scratch, &mut b.edits);
                            if merge_ref
                                .check_and_record(scratch, positions, &b.k, centre, edits)
                                .is_err()
                            {
                                return false;
                            }
                        } else {
                            merge_ref.record_unchecked(&mut b.scratch, &b.k, &mut b.edits);
                        }
                        let first_member = b.members.len();
                        b.members.extend_from_slice(&b.k);
                        b.accepted.push(Accepted {
                            members: first_member as u32..b.members.len() as u32,
                            edits: first_edit as u32..b.edits.len() as u32,
                            centre,
                            reduced: island != c.island,
                        });
                        true
                    };
                    // Refused: try the cluster without one of its crossings, in bit order,
                    // before giving up (keeps most of the merge where one crossing is the
                    // trouble).
                    let mut without_one = (0..14)
                        .filter(|d| c.island.count_ones() > 2 && c.island & (1 << d) != 0)
                        .map(|d| c.island & !(1 << d));
                    if !(try_island(c.island, b) || without_one.any(|sub| try_island(sub, b))) {
                        b.rejected += 1;
                    }
                }
            };
            pool.install(|| {
                commits[..blocks]
                    .par_iter_mut()
                    .zip(group.par_chunks(COMMIT_BLOCK))
                    .for_each(|(b, cands)| try_block(b, cands));
            });
            for b in &commits[..blocks] {
                for a in &b.accepted {
                    stats.discarded += merge.apply_recorded(
                        &mut mesh.positions,
                        &b.members[a.members.start as usize..a.members.end as usize],
                        a.centre,
                        &b.edits[a.edits.start as usize..a.edits.end as usize],
                    );
                    stats.clusters_committed += 1;
                    stats.clusters_reduced += usize::from(a.reduced);
                }
                stats.clusters_rejected_check += b.rejected;
            }
        }
        if check {
            // Lone crossings (the only nearby crossing of their point on that sheet) join the
            // nearest neighbouring cluster vertex when the exact check allows it: the one step
            // beyond the dissertation's rules, worth about 5% fewer triangles and rounder ones.
            let mut near = Vec::new();
            for x in 0..total as u32 {
                if merge.rep(x) != x || merge.member_count(x) != 1 {
                    continue;
                }
                merge.neighbours(x, &mut near);
                let px = glam::Vec3::from(mesh.positions[x as usize]);
                let target = near
                    .iter()
                    .map(|&u| (u, merge.member_count(u)))
                    .filter(|&(u, n)| n > 1 && allowed(&[u, x], &keys))
                    .min_by(|a, b| {
                        let da =
                            px.distance_squared(glam::Vec3::from(mesh.positions[a.0 as usize]));
                        let db =
                            px.distance_squared(glam::Vec3::from(mesh.positions[b.0 as usize]));
                        da.total_cmp(&db).then(a.0.cmp(&b.0))
                    });
                if let Some((u, n)) = target {
                    let pu = glam::Vec3::from(mesh.positions[u as usize]);
                    let centre = ((pu * n as f32 + px) / (n as f32 + 1.0)).to_array();
                    if let Ok(dropped) = merge.merge(&mut mesh.positions, &[u, x], centre, true) {
                        stats.discarded += dropped;
                        stats.lone_absorbed += 1;
                    }
                }
            }
        }
        if check {
            let (slivers, dropped) = crate::collapse::collapse_slivers(
                merge,
                &mut mesh.positions,
                SLIVER_AR,
                tiled.then_some(&keys[..]),
            );
            stats.slivers_collapsed += slivers;
            stats.discarded += dropped;
        }
        merge.finish(&mut mesh.positions, &mut mesh.indices);
        if tiled {
            crate::tiles::compact_keys(merge, &mut keys, merge.triangle_count());
        }
        if check && (near_points > 0 || tiled) {
            // Surfaces through sample points leave crossings on top of each other where a
            // cluster could not take them (near the box, or refused): weld those, under the same
            // check, so no flat triangle is left inside the box.
            weld_coincident(merge, mesh, settings, tiled.then_some(&keys[..]), stats);
        }
        stats.t_vertex_s += t.elapsed().as_secs_f64();
    } else {
        mesh.indices.clear();
        for tris in layer_tris {
            mesh.indices.extend_from_slice(tris);
        }
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
            // first, under the exact check, as integrated clustering does.
            weld_coincident(merge, mesh, settings, None, stats);
        }
        stats.discarded +=
            crate::simplify::meshopt_simplify(mesh, settings.grid.h(), settings.collapse_threshold);
        stats.t_geometry_s += t.elapsed().as_secs_f64();
    }

    stats.bytes_edges =
        (buf.owned.len() * 2 + buf.ids.bytes() + buf.inside.len() * 8 + buf.crossed.len() * 8)
            + buf.candidates.len() * std::mem::size_of::<Candidate>()
            + if propose { merge.bytes() } else { 0 };
    Ok(())
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

/// Vertex pass over one storage plane: owned crossings, counts, cluster proposals, and the
/// plane's crossed-point bits (`crossed`, [`plane_words`] words, all zero on entry).
#[allow(clippy::too_many_arguments)]
fn vertex_plane(
    l: &Layout,
    inside_bits: &[u64],
    z: usize,
    iso: f32,
    propose: bool,
    pinch_rule: bool,
    colour_shift: Offset,
    owned: &mut [u16],
    crossed_bits: &mut [u64],
) -> (PlaneCounts, Vec<Candidate>) {
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
                     p: Offset,
                     valid: u16,
                     owned: &mut [u16],
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
            owned[local] = own | if crossed != 0 { HAS_CROSSING } else { 0 };
            if crossed != 0 {
                crossed_bits[local >> 6] |= 1 << (local & 63);
            }
            counts.crossings += own.count_ones() as usize;
            if propose && own.count_ones() >= 2 {
                let colour = lattice::colour(l.lattice, add(p, colour_shift)) as u8;
                counts.proposals.add(cluster::propose(
                    l.t, i as u32, colour, valid, own, crossed, pinch_rule, cands,
                ));
            }
        };
        // Border points one by one (existence and valid neighbours from the border table).
        let border = |sx: usize,
                      owned: &mut [u16],
                      crossed_bits: &mut [u64],
                      counts: &mut PlaneCounts,
                      cands: &mut Vec<Candidate>| {
            let p = l.coords(sx, sy, z);
            let (exists, valid) = l.border_info(p);
            if !exists {
                owned[sy * dx + sx] = 0;
                return;
            }
            counts.edges += valid.count_ones() as usize;
            point(sx, p, valid, owned, crossed_bits, counts, cands);
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
            owned[sy * dx + flo..sy * dx + fhi].fill(0);
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
                    let p = l.coords(x, sy, z);
                    let valid = if x >= lo && x < hi {
                        FULL
                    } else {
                        let (exists, valid) = l.border_info(p);
                        if !exists {
                            continue;
                        }
                        valid
                    };
                    point(x, p, valid, owned, crossed_bits, &mut counts, &mut cands);
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

/// Numbers the crossings of plane `z` (ids `start..end`), writes their positions, the plane's
/// per-slot id offsets (`offset`) and the id bases of the blocks that start in the plane
/// (`blocks`, from block `ceil(z * plane / ID_BLOCK)` on). Returns how many crossings lie within
/// `WELD` of their owner (surfaces through sample points).
///
/// A block's base is written where a slot of the plane owns a crossing in it, and always for a
/// block that runs on into the next plane (which may need it without owning one here); the
/// others are never read. `owned` is the whole array: a block that began in an earlier plane
/// counts that plane's part itself.
#[allow(clippy::too_many_arguments)]
fn number_plane(
    l: &Layout,
    z: usize,
    iso: f32,
    owned: &[u16],
    crossed: &[u64],
    (start, end): (u32, u32),
    blocks: &mut [u32],
    offset: &mut [u8],
    out: &mut [[f32; 3]],
) -> usize {
    let v = &l.s.values;
    let [dx, dy, _] = l.s.dims;
    let plane = dx * dy;
    let (p0, p1) = (z * plane, (z + 1) * plane);
    let first_block = p0.div_ceil(ID_BLOCK);
    let count = |from: usize, to: usize| -> u32 {
        owned[from..to]
            .iter()
            .map(|&o| (o & OWNED_BITS).count_ones())
            .sum()
    };
    // The block that starts in this plane and runs on into the next one.
    let last = (p1 - 1) / ID_BLOCK;
    if last * ID_BLOCK >= p0 && p1 % ID_BLOCK != 0 {
        blocks[last - first_block] = end - count(last * ID_BLOCK, p1);
    }
    let mut next = start;
    let mut w = 0;
    let mut near_points = 0;
    let (mut block, mut in_block) = (usize::MAX, 0u32);
    for_each_bit(crossed, 0, plane, |local| {
        let (sy, sx) = (local / dx, local % dx);
        let own = owned[p0 + local] & OWNED_BITS;
        if own == 0 {
            return;
        }
        let b = (p0 + local) / ID_BLOCK;
        if b != block {
            block = b;
            let bs = b * ID_BLOCK;
            if bs < p0 {
                // Began in an earlier plane: its slots there come first.
                in_block = count(bs, p0);
            } else {
                // First owning slot of a block of this plane: no crossing before it there.
                in_block = 0;
                blocks[b - first_block] = next;
            }
        }
        offset[local] = in_block as u8;
        in_block += own.count_ones();
        next += own.count_ones();
        let p = l.coords(sx, sy, z);
        let i = z * dx * dy + local;
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
    near_points
}

/// Geometry pass over one z-layer; returns the tetrahedra processed.
#[allow(clippy::too_many_arguments)]
fn geometry_layer(
    l: &Layout,
    k: usize,
    iso: f32,
    keep: Option<CellRange>,
    owned: &[u16],
    first_ids: &FirstIds,
    crossed: &[u64],
    positions: &[[f32; 3]],
    out: &mut Vec<u32>,
) -> usize {
    let v = &l.s.values;
    let [nx, ny, nz] = l.s.cells;
    let plane = l.s.dims[0] * l.s.dims[1];
    let wpp = plane_words(plane);
    let mut processed = 0;
    let mut tet = |anchor: usize, tpl: &TetTemplate, out: &mut Vec<u32>| {
        let idx = tpl.delta.map(|d| (anchor as isize + d) as usize);
        let val = idx.map(|i| v[i]);
        let case = (val[0] < iso) as usize
            | ((val[1] < iso) as usize) << 1
            | ((val[2] < iso) as usize) << 2
            | ((val[3] < iso) as usize) << 3;
        if case == 0 || case == 15 {
            return;
        }
        processed += 1;
        let cycle = &CASES[case];
        let n = if cycle[3] == u8::MAX { 3 } else { 4 };
        let mut ids = [0u32; 4];
        for (slot, &e) in ids.iter_mut().zip(cycle.iter()).take(n) {
            let (a, b) = TET_EDGES[e as usize];
            let (o, d) = if owns(val[a], val[b], iso) {
                (idx[a], tpl.dir[a][b])
            } else {
                (idx[b], tpl.dir[b][a])
            };
            *slot = first_ids.first(o) + (owned[o] & ((1u16 << d) - 1)).count_ones();
        }
        if n == 3 {
            out.extend_from_slice(&ids[..3]);
        } else {
            let p = |i: u32| glam::Vec3::from(positions[i as usize]);
            if p(ids[0]).distance_squared(p(ids[2])) <= p(ids[1]).distance_squared(p(ids[3])) {
                out.extend_from_slice(&[ids[0], ids[1], ids[2], ids[0], ids[2], ids[3]]);
            } else {
                out.extend_from_slice(&[ids[1], ids[2], ids[3], ids[1], ids[3], ids[0]]);
            }
        }
    };
    match l.lattice {
        Lattice::Simple => {
            let s = l.s;
            for j in 0..ny {
                for i in 0..nx {
                    if keep.is_some_and(|r| !r.contains([i, j, k])) {
                        continue;
                    }
                    let c = s.simple_index(i, j, k);
                    // Corner 0 is a neighbour of the other 7: no crossed edge there, no
                    // surface in this cube.
                    if owned[c] & HAS_CROSSING == 0 {
                        continue;
                    }
                    for tpl in &l.tets {
                        tet(c, tpl, out);
                    }
                }
            }
        }
        Lattice::BodyCentred => {
            let k = k as i32;
            // Faces perpendicular to z at plane k, then (inside layer k) to x and to y.
            // A face whose anchor A has a crossed edge (B and the 4 face corners are
            // neighbours of A: without one, no surface in the face's 4 tetrahedra).
            let mut face = |a: Offset, anchor: usize, axis: usize, out: &mut Vec<u32>| {
                if let Some(r) = keep {
                    // Anchor cell: above the face along `axis` (clamped into the grid).
                    let mut c = a.map(|x| ((x - 1) / 2) as usize);
                    c[axis] = (((a[axis] + 1) / 2) as usize).min(l.s.cells[axis] - 1);
                    if !r.contains(c) {
                        return;
                    }
                }
                for tpl in &l.tets[4 * axis..4 * axis + 4] {
                    tet(anchor, tpl, out);
                }
            };
            // The anchors of one row of faces are consecutive storage slots: scan their flags
            // and visit only the faces whose anchor has a crossed edge.
            // (Along x, a face anchor moves by one storage slot.)
            let mut row = |first: Offset, len: usize, axis: usize, out: &mut Vec<u32>| {
                let start = l.s.bcdl_index(first);
                // Storage plane and slot in the plane (see `Samples::bcdl_index`).
                let z = (first[2] + 1) as usize;
                let local = start - z * plane;
                for_each_bit(&crossed[z * wpp..(z + 1) * wpp], local, len, |n| {
                    face(
                        [first[0] + 2 * n as i32, first[1], first[2]],
                        start + n,
                        axis,
                        out,
                    );
                });
            };
            for j in 0..ny as i32 {
                row([1, 2 * j + 1, 2 * k - 1], nx, 2, out);
            }
            if (k as usize) < nz {
                for j in 0..ny as i32 {
                    row([-1, 2 * j + 1, 2 * k + 1], nx + 1, 0, out);
                }
                for f in 0..=ny as i32 {
                    row([1, 2 * f - 1, 2 * k + 1], nx, 1, out);
                }
            }
        }
    }
    processed
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn first_ids_count_the_crossings_owned_before_each_point() {
        // Grids whose storage planes hold fewer slots than an id block, about as many, and many
        // more, so that blocks start, end and span whole planes everywhere.
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
            ] {
                let settings = crate::ExtractSettings::new(
                    crate::Grid::new(cells, glam::Vec3::splat(-1.0), glam::Vec3::splat(1.0)),
                    lattice,
                    crate::Clustering::None,
                );
                let mut stats = Stats::default();
                let mut samples = Samples::default();
                samples
                    .sample(&field, &settings, &pool, &mut stats)
                    .expect("a finite field");
                let (mut buf, mut merge, mut mesh) = (
                    MtBuffers::default(),
                    MergeBuffers::default(),
                    Mesh::default(),
                );
                extract(
                    &samples, &settings, &pool, &mut buf, &mut merge, &mut mesh, &mut stats,
                )
                .expect("extraction");
                let mut before = 0u32;
                for (slot, &o) in buf.owned.iter().enumerate() {
                    let own = o & OWNED_BITS;
                    if own != 0 {
                        assert_eq!(
                            buf.ids.first(slot),
                            before,
                            "{lattice:?} {cells:?} slot {slot}"
                        );
                        checked += 1;
                    }
                    before += own.count_ones();
                }
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
