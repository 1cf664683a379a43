//! Marching cubes on the simple cubic grid, closed on ambiguous faces.
//!
//! Each cube's eight corners are classified inside (`f < iso`) or outside (`f >= iso`, so
//! `f == iso` counts outside, as in marching tetrahedra); the 8 bits index the classic case
//! tables of Lorensen and Cline as published by Bourke (`EDGE_TABLE`, `TRIANGLE_TABLE`), and
//! each crossed grid edge gets one vertex by linear interpolation, shared by the four cubes
//! around the edge.
//!
//! The classic table resolves every *ambiguous face* (two inside corners on one diagonal, two
//! outside on the other) by a fixed rule that ignores the values, so two cubes sharing such a
//! face may cut it differently and leave a crack. Here a cube with an ambiguous face instead
//! resolves it with the asymptotic decider (Nielson and Hamann 1991): the bilinear interpolant
//! on the face joins the inside corners exactly when `a * c > b * d` (`a`, `c` the values minus
//! iso at the inside corners, `b`, `d` at the outside ones), a test that both cubes evaluate on
//! the same four numbers and therefore answer alike. Its triangles come from a table generated
//! per (case, face resolution) (`CaseTables`): the face cuts are chained into closed loops
//! around the cube and each loop is triangulated without any diagonal lying in a cube face, so
//! the only edges two cubes share are the face cuts, each used once by either cube. The
//! result is closed and edge-manifold wherever the surface stays inside the box. (The decider
//! does not resolve the ambiguity inside a cube, e.g. the tunnel of case 4; that affects topology
//! inside single cubes, not closure.)
//!
//! In 116 of the 520 (case, face resolution) pairs a loop crosses one face twice, and no
//! triangulation of it avoids a diagonal in that face; such a loop is fanned around an extra
//! vertex at the centroid of its vertices (as MC33 does for its interior cases). These rare
//! centres are the only vertices not on grid edges; `Stats::crossings` counts grid-edge
//! vertices only.
//!
//! Orientation: triangles are counter-clockwise seen from the side of increasing f.
//!
//! ```text
//!         7 ----6-----6            corners (x, y, z): 0 (0,0,0)  1 (1,0,0)  2 (1,1,0)  3 (0,1,0)
//!        /|          /|                               4 (0,0,1)  5 (1,0,1)  6 (1,1,1)  7 (0,1,1)
//!       7 11        5 10           edges: 0: 0-1  1: 1-2  2: 2-3  3: 3-0   (bottom, z = 0)
//!      /  |        /  |                   4: 4-5  5: 5-6  6: 6-7  7: 7-4   (top, z = 1)
//!     4 ----4-----5   |                   8: 0-4  9: 1-5 10: 2-6 11: 3-7   (vertical)
//!     |   3 ----2-|---2
//!     8  /        9  /      z
//!     | 3         | 1       |  y
//!     |/          |/        | /
//!     0 ----0-----1         |/___ x
//! ```
//!
//! The passes follow Flying Edges (Schroeder, Maynard and Geveci 2015; VTK's
//! `vtkFlyingEdges3D`): classify, count per row, prefix-sum, write in place. The inside bits of
//! every storage row come first; then per row word (64 points) the crossed grid edges along each
//! axis, a few word operations, and their count; a prefix sum over the planes gives every word
//! the id of its first crossing, so the positions are written straight into the mesh and a
//! vertex id is that first id plus a popcount (no edge-to-vertex map). Triangles visit only the
//! cubes whose corners differ: 64 cubes of a row are tested per word operation on the four rows
//! of points around them, which trims every row to its crossings (and skips the uncrossed cubes
//! between them). Every pass is parallel over z-planes or z-slabs on the extractor's thread
//! pool; vertices are numbered in grid-edge order (edge `3 * corner + axis`) and triangles
//! emitted slab by slab, so the output is the same for any number of threads.

use std::sync::OnceLock;

use glam::Vec3;
use rayon::prelude::*;
use rmt_mesh::Mesh;

use crate::{ExtractError, ExtractSettings, Samples, Stats};

/// Marching cubes' working tables, kept between extractions by the [`crate::Extractor`] (each
/// pass overwrites what it reads, so nothing is cleared between calls).
#[derive(Default)]
pub(crate) struct McBuffers {
    /// Inside bits per storage row of points (`f < iso`), [`Rows::words`] words per row, rows
    /// in storage order (y, then z); bits past the row's last point are zero.
    inside: Vec<u64>,
    /// Per row and word: the crossed edges leaving its points along x, y and z, and the id of
    /// the word's first crossing ([`RowWord`]).
    crossed: Vec<RowWord>,
}

impl McBuffers {
    /// Bytes held.
    pub(crate) fn bytes(&self) -> usize {
        self.inside.capacity() * 8 + self.crossed.capacity() * std::mem::size_of::<RowWord>()
    }
}

/// 64 points of one storage row: which of their grid edges are crossed, per axis (bit k: the
/// edge from point `64 w + k` to its + neighbour), and the vertex id of the first of those
/// crossings in edge order (point by point, x, y, z at each point).
#[derive(Clone, Copy, Default)]
struct RowWord {
    x: u64,
    y: u64,
    z: u64,
    first: u32,
}

impl RowWord {
    /// The vertex id of the crossing on the edge leaving point `64 w + s` along `axis` (the
    /// edge must be crossed): the word's first id plus the crossings before it in edge order.
    #[inline(always)]
    fn id(&self, s: usize, axis: usize) -> u32 {
        let below = (1u64 << s) - 1;
        let through = below | (1u64 << s);
        let (mx, my) = match axis {
            0 => (below, below),
            1 => (through, below),
            _ => (through, through),
        };
        self.first
            + (self.x & mx).count_ones()
            + (self.y & my).count_ones()
            + (self.z & below).count_ones()
    }

    /// Crossings of the word.
    #[inline(always)]
    fn count(&self) -> u32 {
        self.x.count_ones() + self.y.count_ones() + self.z.count_ones()
    }
}

/// The storage rows of the simple lattice as bit rows.
#[derive(Clone, Copy)]
struct Rows {
    /// Points per row (`nx + 1`).
    points: usize,
    /// Words per row.
    words: usize,
    /// Rows per plane (`ny + 1`).
    per_plane: usize,
    /// Planes (`nz + 1`).
    planes: usize,
}

impl Rows {
    fn new(samples: &Samples) -> Self {
        let [nx, ny, nz] = samples.cells;
        Self {
            points: nx + 1,
            words: (nx + 1).div_ceil(64),
            per_plane: ny + 1,
            planes: nz + 1,
        }
    }

    /// Words of one plane.
    fn plane_words(&self) -> usize {
        self.words * self.per_plane
    }
}

/// Each cube edge (Bourke's numbering) as the row of the cube's four rows of points that holds
/// its lower end (0: (y, z), 1: (y + 1, z), 2: (y, z + 1), 3: (y + 1, z + 1)), that end's x
/// offset (0 or 1) and the edge's axis.
const EDGE_IN_ROWS: [(u8, u8, u8); 12] = {
    let mut out = [(0u8, 0u8, 0u8); 12];
    let mut e = 0;
    while e < 12 {
        let (corner, axis) = EDGE_ON_GRID[e];
        let [cx, cy, cz] = CORNERS[corner as usize];
        out[e] = (cy + 2 * cz, cx, axis);
        e += 1;
    }
    out
};

/// Extracts the `settings.iso` level set of the simple-lattice `samples` into `mesh` (appending
/// to it; the caller clears it) with marching cubes, on `pool`'s threads, and fills the counters
/// and timings of `stats`: `tetrahedra_total = 0`, `tetrahedra_processed` = cubes with a crossing,
/// `edges` = grid edges, `crossings` = vertices on grid edges (all vertices but the rare loop
/// centres), `bytes_edges` = the bit rows and their crossing words, `t_vertex_s`,
/// `t_geometry_s`. With `array_order`, positions are written `[z, y, x]` and triangles with
/// their last two corners swapped (see `Extractor::set_array_order`; the caller computes the
/// normals). Errors with [`ExtractError::NonFiniteValue`] (the first in storage order)
/// when a value is NaN or infinite: the first pass reads every value, and checks it as it
/// classifies it.
///
/// The passes, each parallel over planes (Flying Edges' order: classify, count, prefix-sum,
/// write in place): the inside bits of every row; per row word the crossed edges along each
/// axis and their count; a prefix sum over planes then rows gives every word its first vertex
/// id, and the positions are written straight into `mesh`; the triangles of each slab of cubes
/// visit only the cubes whose corners differ (64 cubes of a row tested per word operation), and
/// read a vertex id as its word's first id plus a popcount.
pub fn extract(
    samples: &Samples,
    settings: &ExtractSettings,
    pool: &rayon::ThreadPool,
    buf: &mut McBuffers,
    array_order: bool,
    mesh: &mut Mesh,
    stats: &mut Stats,
) -> Result<(), ExtractError> {
    let tables = CaseTables::get();
    let [nx, ny, nz] = samples.cells;
    let dims = [nx + 1, ny + 1, nz + 1];
    let plane = dims[0] * dims[1];
    let iso = settings.iso;
    stats.tetrahedra_total = 0;
    stats.edges = nx * (ny + 1) * (nz + 1) + (nx + 1) * ny * (nz + 1) + (nx + 1) * (ny + 1) * nz;
    if samples.values.len() < plane * dims[2] {
        // Not laid out for these settings (the extractor checks this first); nothing to mesh.
        return Ok(());
    }
    let rows = Rows::new(samples);
    let pw = rows.plane_words();

    // Vertex pass, step 1: the inside bits of every row, and whether a value is not finite
    // (from the same read of the values).
    let t = std::time::Instant::now();
    crate::util::overwritten(&mut buf.inside, pw * rows.planes, 0, pool);
    crate::util::overwritten(&mut buf.crossed, pw * rows.planes, RowWord::default(), pool);
    let values = &samples.values;
    let non_finite = pool.install(|| {
        buf.inside
            .par_chunks_mut(pw)
            .enumerate()
            .map(|(z, bits)| {
                let mut bad = false;
                for (y, row) in bits.chunks_exact_mut(rows.words).enumerate() {
                    let start = samples.simple_index(0, y, z);
                    let row_values = &values[start..start + rows.points];
                    for (word, chunk) in row.iter_mut().zip(row_values.chunks(64)) {
                        let (w, b) = crate::util::inside_word_finite(chunk, iso);
                        *word = w;
                        bad |= b;
                    }
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

    // Step 2: crossed edges per row word, counted; ids first within the plane.
    let inside = &buf.inside;
    let plane_counts: Vec<u32> = pool.install(|| {
        buf.crossed
            .par_chunks_mut(pw)
            .enumerate()
            .map(|(z, words)| crossed_plane(inside, rows, z, words))
            .collect()
    });
    let mut plane_first = Vec::with_capacity(plane_counts.len());
    let first_vertex = mesh.positions.len();
    let mut total = first_vertex;
    for &c in &plane_counts {
        plane_first.push(total as u32);
        total += c as usize;
    }

    // Step 3: global ids, and the positions written in place, plane by plane.
    mesh.positions.resize(total, [0.0; 3]);
    {
        let mut rest = &mut mesh.positions[first_vertex..];
        let mut parts = Vec::with_capacity(plane_counts.len());
        for &c in &plane_counts {
            let (head, tail) = rest.split_at_mut(c as usize);
            parts.push(head);
            rest = tail;
        }
        pool.install(|| {
            buf.crossed
                .par_chunks_mut(pw)
                .zip(parts)
                .enumerate()
                .for_each(|(z, (words, out))| {
                    place_plane(
                        samples,
                        rows,
                        iso,
                        z,
                        plane_first[z],
                        array_order,
                        words,
                        out,
                    )
                })
        });
    }
    stats.crossings = total - first_vertex;
    stats.bytes_edges = buf.bytes();
    stats.t_vertex_s = t.elapsed().as_secs_f64();

    // Geometry pass: triangles per z-slab of cubes.
    let t = std::time::Instant::now();
    let positions = &mesh.positions;
    let crossed = &buf.crossed;
    let slabs: Vec<Slab> = pool.install(|| {
        (0..nz)
            .into_par_iter()
            .map(|z| {
                slab_triangles(
                    samples,
                    tables,
                    rows,
                    iso,
                    settings.keep_cells,
                    z,
                    inside,
                    crossed,
                    positions,
                    array_order,
                )
            })
            .collect()
    });
    let count: usize = slabs.iter().map(|s| s.indices.len()).sum();
    mesh.indices.reserve(count);
    let mut processed = 0;
    for slab in &slabs {
        // Loop centres (rare) are numbered after all edge vertices, slab by slab.
        if slab.centres.is_empty() {
            mesh.indices.extend_from_slice(&slab.indices);
        } else {
            let first_centre = mesh.positions.len() as u32;
            mesh.indices.extend(slab.indices.iter().map(|&i| {
                if i & CENTRE_FLAG != 0 {
                    first_centre + (i & !CENTRE_FLAG)
                } else {
                    i
                }
            }));
            mesh.positions.extend_from_slice(&slab.centres);
        }
        processed += slab.crossed_cubes;
    }
    stats.tetrahedra_processed = processed;
    stats.t_geometry_s = t.elapsed().as_secs_f64();
    Ok(())
}

/// Marks a slab-local loop-centre number in a slab's indices (renumbered when slabs are joined).
const CENTRE_FLAG: u32 = 1 << 31;

/// What one z-slab of cubes produced.
struct Slab {
    /// Vertex indices, three per triangle; loop centres as `CENTRE_FLAG | local number`.
    indices: Vec<u32>,
    /// Positions of the slab's loop centres.
    centres: Vec<[f32; 3]>,
    /// Cubes with at least one crossing.
    crossed_cubes: usize,
}

/// The bits below bit `k` (all 64 from `k = 64` on).
#[inline(always)]
fn low_bits(k: usize) -> u64 {
    if k >= 64 {
        u64::MAX
    } else {
        (1u64 << k) - 1
    }
}

/// Crossed edges of the rows of plane `z` (`words`, the plane's row words; `first` set to the
/// id of the word's first crossing counted from the plane's first); returns the plane's
/// crossings.
fn crossed_plane(inside: &[u64], rows: Rows, z: usize, words: &mut [RowWord]) -> u32 {
    let pw = rows.plane_words();
    let nw = rows.words;
    // Valid x-edge bits of the last word: points 0..nx start an x-edge.
    let x_edges = rows.points - 1;
    let last_x_mask = {
        let k = x_edges - 64 * (nw - 1);
        if k >= 64 {
            u64::MAX
        } else {
            (1u64 << k) - 1
        }
    };
    let mut count = 0u32;
    for y in 0..rows.per_plane {
        let at = z * pw + y * nw;
        let own = &inside[at..at + nw];
        let up = (y + 1 < rows.per_plane).then(|| &inside[at + nw..at + 2 * nw]);
        let above = (z + 1 < rows.planes).then(|| &inside[at + pw..at + pw + nw]);
        for w in 0..nw {
            let b = own[w];
            let next = if w + 1 < nw { own[w + 1] << 63 } else { 0 };
            let mut x = b ^ ((b >> 1) | next);
            if w + 1 == nw {
                x &= last_x_mask;
            }
            let word = RowWord {
                x,
                y: up.map_or(0, |u| b ^ u[w]),
                z: above.map_or(0, |a| b ^ a[w]),
                first: count,
            };
            count += word.count();
            words[y * nw + w] = word;
        }
    }
    count
}

/// Adds `first` (the plane's first vertex id) to the ids of plane `z`'s row words and writes
/// the positions of its crossings (`out`, in edge order), interpolated from the lower end of
/// each edge; `(z, y, x)` with `array_order`.
#[allow(clippy::too_many_arguments)]
fn place_plane(
    samples: &Samples,
    rows: Rows,
    iso: f32,
    z: usize,
    first: u32,
    array_order: bool,
    words: &mut [RowWord],
    out: &mut [[f32; 3]],
) {
    let values = &samples.values;
    let step = [1, samples.dims[0], samples.dims[0] * samples.dims[1]];
    let mut k = 0;
    for (y, row) in words.chunks_exact_mut(rows.words).enumerate() {
        let start = samples.simple_index(0, y, z);
        for (w, word) in row.iter_mut().enumerate() {
            word.first += first;
            let axes = [word.x, word.y, word.z];
            let mut any = word.x | word.y | word.z;
            while any != 0 {
                let s = any.trailing_zeros() as usize;
                any &= any - 1;
                let x = 64 * w + s;
                let i = start + x;
                let v0 = values[i];
                for (axis, bits) in axes.iter().enumerate() {
                    if bits >> s & 1 == 0 {
                        continue;
                    }
                    let v1 = values[i + step[axis]];
                    // From the lower corner always, so the position never depends on the cube.
                    let t = (iso - v0) / (v1 - v0);
                    let mut p = samples.simple_position(x, y, z);
                    p[axis] += t * samples.spacing[axis];
                    out[k] = if array_order {
                        [p.z, p.y, p.x]
                    } else {
                        p.to_array()
                    };
                    k += 1;
                }
            }
        }
    }
    debug_assert_eq!(
        k,
        out.len(),
        "plane {z}: crossings counted and placed differ"
    );
}

/// Triangles of the cubes in slab `z`: indices into `positions` (the edge vertices) or to the
/// slab's own loop centres. Only cubes whose eight corners are not all on one side are visited:
/// per word of the slab's four rows of points, the bits where some corner differs.
#[allow(clippy::too_many_arguments)]
fn slab_triangles(
    samples: &Samples,
    tables: &CaseTables,
    rows: Rows,
    iso: f32,
    keep: Option<crate::CellRange>,
    z: usize,
    inside: &[u64],
    crossed: &[RowWord],
    positions: &[[f32; 3]],
    array_order: bool,
) -> Slab {
    let [nx, ny, _] = samples.cells;
    let values = &samples.values;
    let (nw, pw) = (rows.words, rows.plane_words());
    let mut indices = Vec::new();
    let mut centres: Vec<[f32; 3]> = Vec::new();
    let mut crossed_cubes = 0;
    // Cubes x in [x_lo, x_hi) of each row are kept.
    let (x_lo, x_hi) = match keep {
        Some(r) => {
            if z < r.lo[2] || z >= r.hi[2] {
                return Slab {
                    indices,
                    centres,
                    crossed_cubes,
                };
            }
            (r.lo[0], r.hi[0].min(nx))
        }
        None => (0, nx),
    };
    let (y_lo, y_hi) = keep.map_or((0, ny), |r| (r.lo[1], r.hi[1].min(ny)));
    for y in y_lo..y_hi {
        // The four rows of points around the row of cubes: (y, z), (y + 1, z), (y, z + 1),
        // (y + 1, z + 1).
        let at = [
            z * pw + y * nw,
            z * pw + (y + 1) * nw,
            (z + 1) * pw + y * nw,
            (z + 1) * pw + (y + 1) * nw,
        ];
        for w in 0..nw {
            let lo = 64 * w;
            if lo >= x_hi {
                break;
            }
            let word = |r: usize| {
                let b = inside[at[r] + w];
                // Bit k: point 64 w + k + 1 (the cube's upper x corners).
                let next = if w + 1 < nw {
                    inside[at[r] + w + 1] << 63
                } else {
                    0
                };
                (b, (b >> 1) | next)
            };
            let (a0, a1) = word(0);
            let (b0, b1) = word(1);
            let (c0, c1) = word(2);
            let (d0, d1) = word(3);
            let any = a0 | a1 | b0 | b1 | c0 | c1 | d0 | d1;
            let all = a0 & a1 & b0 & b1 & c0 & c1 & d0 & d1;
            // Only cubes x_lo <= x < x_hi.
            let mut mixed = any & !all & low_bits(x_hi - lo) & !low_bits(x_lo.saturating_sub(lo));
            while mixed != 0 {
                let s = mixed.trailing_zeros() as usize;
                mixed &= mixed - 1;
                let x = lo + s;
                crossed_cubes += 1;
                let case = (a0 >> s & 1
                    | (a1 >> s & 1) << 1
                    | (b1 >> s & 1) << 2
                    | (b0 >> s & 1) << 3
                    | (c0 >> s & 1) << 4
                    | (c1 >> s & 1) << 5
                    | (d1 >> s & 1) << 6
                    | (d0 >> s & 1) << 7) as usize;
                debug_assert_ne!(EDGE_TABLE[case], 0, "cube {x} {y} {z} is not crossed");
                let ambiguous = tables.ambiguous_faces[case];
                let entry = if ambiguous == 0 {
                    &tables.classic[case]
                } else {
                    let mut w8 = [0.0f32; 8];
                    for (c, wc) in w8.iter_mut().enumerate() {
                        let [ox, oy, oz] = CORNERS[c];
                        *wc = values[samples.simple_index(
                            x + ox as usize,
                            y + oy as usize,
                            z + oz as usize,
                        )] - iso;
                    }
                    &tables.resolved[case * 64 + usize::from(face_resolution(&w8, ambiguous))]
                };
                let vertex = |e: u8| {
                    let (r, dx, axis) = EDGE_IN_ROWS[e as usize];
                    let p = x + dx as usize;
                    let word = &crossed[at[r as usize] + (p >> 6)];
                    debug_assert_eq!(
                        [word.x, word.y, word.z][axis as usize] >> (p & 63) & 1,
                        1,
                        "case {case} uses uncrossed edge {e}"
                    );
                    word.id(p & 63, axis as usize)
                };
                let first_centre = centres.len() as u32;
                for polygon in &entry.centres {
                    let sum = polygon.iter().fold(Vec3::ZERO, |acc, &e| {
                        acc + Vec3::from(positions[vertex(e) as usize])
                    });
                    centres.push((sum / polygon.len() as f32).to_array());
                }
                for t in &entry.triangles {
                    // Swapping x and z mirrors the mesh: the last two corners swap with it,
                    // so triangles stay counter-clockwise seen from increasing values.
                    let t = if array_order { [t[0], t[2], t[1]] } else { *t };
                    for e in t {
                        if e >= 12 {
                            indices.push(CENTRE_FLAG | (first_centre + u32::from(e - 12)));
                        } else {
                            indices.push(vertex(e));
                        }
                    }
                }
            }
        }
    }
    Slab {
        indices,
        centres,
        crossed_cubes,
    }
}

/// The asymptotic decider on each face in `ambiguous` (a 6-bit mask): bit `f` set when the
/// bilinear interpolant joins face `f`'s two inside corners. `w` holds value minus iso per
/// corner. With `a`, `c` the inside diagonal (negative) and `b`, `d` the outside one (>= 0), the
/// saddle value `(ac - bd) / (a + c - b - d)` is negative, i.e. inside, exactly when `ac > bd`.
/// Products of the same two floats are equal in either order, so both cubes sharing the face
/// decide alike.
#[inline]
fn face_resolution(w: &[f32; 8], ambiguous: u8) -> u8 {
    let mut bits = 0;
    for (f, face) in FACES.iter().enumerate() {
        if ambiguous & (1 << f) == 0 {
            continue;
        }
        let [p, q, r, s] = face.corners.map(|c| w[c as usize]);
        let (inside, outside) = if p < 0.0 {
            (p * r, q * s)
        } else {
            (q * s, p * r)
        };
        if inside > outside {
            bits |= 1 << f;
        }
    }
    bits
}

/// Corner offsets `(x, y, z)` in Bourke's numbering.
const CORNERS: [[u8; 3]; 8] = [
    [0, 0, 0],
    [1, 0, 0],
    [1, 1, 0],
    [0, 1, 0],
    [0, 0, 1],
    [1, 0, 1],
    [1, 1, 1],
    [0, 1, 1],
];

/// The two corners of each cube edge.
const EDGE_CORNERS: [[u8; 2]; 12] = [
    [0, 1],
    [1, 2],
    [2, 3],
    [3, 0],
    [4, 5],
    [5, 6],
    [6, 7],
    [7, 4],
    [0, 4],
    [1, 5],
    [2, 6],
    [3, 7],
];

/// Each cube edge as a grid edge: the corner it leaves in the + direction, and the axis.
const EDGE_ON_GRID: [(u8, u8); 12] = [
    (0, 0),
    (1, 1),
    (3, 0),
    (0, 1),
    (4, 0),
    (5, 1),
    (7, 0),
    (4, 1),
    (0, 2),
    (1, 2),
    (2, 2),
    (3, 2),
];

/// A face of the cube: its corners in cyclic order and its outward normal.
struct Face {
    corners: [u8; 4],
    normal: [i8; 3],
}

/// The six faces: z = 0, z = 1, y = 0, y = 1, x = 0, x = 1.
const FACES: [Face; 6] = [
    Face {
        corners: [0, 1, 2, 3],
        normal: [0, 0, -1],
    },
    Face {
        corners: [4, 5, 6, 7],
        normal: [0, 0, 1],
    },
    Face {
        corners: [0, 1, 5, 4],
        normal: [0, -1, 0],
    },
    Face {
        corners: [3, 2, 6, 7],
        normal: [0, 1, 0],
    },
    Face {
        corners: [0, 3, 7, 4],
        normal: [-1, 0, 0],
    },
    Face {
        corners: [1, 2, 6, 5],
        normal: [1, 0, 0],
    },
];

/// The cube edge joining two corners, if they are adjacent.
fn edge_between(a: u8, b: u8) -> Option<u8> {
    EDGE_CORNERS
        .iter()
        .position(|&[p, q]| (p, q) == (a, b) || (p, q) == (b, a))
        .map(|e| e as u8)
}

/// Midpoint of a cube edge in the unit cube (the embedding used to orient and choose triangles).
fn edge_midpoint(e: u8) -> Vec3 {
    let [a, b] = EDGE_CORNERS[e as usize];
    (corner_position(a) + corner_position(b)) * 0.5
}

fn corner_position(c: u8) -> Vec3 {
    let [x, y, z] = CORNERS[c as usize];
    Vec3::new(f32::from(x), f32::from(y), f32::from(z))
}

/// Bit mask of the two faces containing each cube edge.
fn edge_faces(e: u8) -> u8 {
    let [a, b] = EDGE_CORNERS[e as usize];
    FACES
        .iter()
        .enumerate()
        .filter(|(_, f)| f.corners.contains(&a) && f.corners.contains(&b))
        .fold(0, |m, (i, _)| m | 1 << i)
}

/// The triangle tables used at run time, built once.
struct CaseTables {
    /// Per case, the faces (bit per face, [`FACES`] order) with two inside corners on one diagonal
    /// and two outside on the other.
    ambiguous_faces: [u8; 256],
    /// Bourke's triangles per case, reversed to face the outside. Used for cases without
    /// ambiguous faces, where every face is cut in the only possible way.
    classic: Vec<Triangulation>,
    /// Triangles per `case * 64 + resolution` (resolution bit `f` set: face `f`'s inside corners
    /// joined), for cases with ambiguous faces; generated by [`resolved_triangles`].
    resolved: Vec<Triangulation>,
}

/// The triangles of one cube configuration.
#[derive(Clone, Debug, Default)]
struct Triangulation {
    /// Triples of cube edges (0..12), or `12 + k` for the centre of loop `k` of `centres`.
    triangles: Vec<[u8; 3]>,
    /// Loops (cube edges, in order) that could not be triangulated without a diagonal in a cube
    /// face and are fanned around an extra vertex at their centroid instead.
    centres: Vec<Vec<u8>>,
}

impl CaseTables {
    /// The tables (built on first use).
    fn get() -> &'static CaseTables {
        static TABLES: OnceLock<CaseTables> = OnceLock::new();
        TABLES.get_or_init(CaseTables::build)
    }

    fn build() -> CaseTables {
        let mut ambiguous_faces = [0u8; 256];
        let mut classic = Vec::with_capacity(256);
        let mut resolved = vec![Triangulation::default(); 256 * 64];
        for case in 0..256usize {
            let inside = |c: u8| case >> c & 1 == 1;
            for (f, face) in FACES.iter().enumerate() {
                let [p, q, r, s] = face.corners.map(inside);
                if p == r && q == s && p != q {
                    ambiguous_faces[case] |= 1 << f;
                }
            }
            classic.push(Triangulation {
                triangles: TRIANGLE_TABLE[case]
                    .chunks_exact(3)
                    .take_while(|t| t[0] >= 0)
                    .map(|t| [t[0] as u8, t[2] as u8, t[1] as u8])
                    .collect(),
                centres: Vec::new(),
            });
            let mask = ambiguous_faces[case];
            if mask == 0 {
                continue;
            }
            // Every subset of the ambiguous faces.
            let mut bits = 0u8;
            loop {
                resolved[case * 64 + usize::from(bits)] = resolved_triangles(case as u8, bits);
                if bits == mask {
                    break;
                }
                bits = (bits.wrapping_sub(mask)) & mask;
            }
        }
        CaseTables {
            ambiguous_faces,
            classic,
            resolved,
        }
    }
}

/// The directed cuts of the cube faces for `case` with ambiguous faces resolved by `joined` (bit
/// `f`: face `f`'s inside corners are joined): `next[e] = e2` when a cut runs from the vertex on
/// edge `e` to the one on edge `e2`, directed so that the inside lies to the left seen from
/// outside the cube, i.e. counter-clockwise around the inside as the triangles will be.
fn face_cuts(case: u8, joined: u8) -> [Option<u8>; 12] {
    let inside = |c: u8| case >> c & 1 == 1;
    let mut next = [None; 12];
    for (f, face) in FACES.iter().enumerate() {
        let c = face.corners;
        // Edge k of the face joins corners k and k + 1; corner k lies between edges k - 1 and k.
        let edges: [u8; 4] =
            std::array::from_fn(|k| edge_between(c[k], c[(k + 1) % 4]).unwrap_or(0));
        let crossed: Vec<usize> = (0..4)
            .filter(|&k| inside(c[k]) != inside(c[(k + 1) % 4]))
            .collect();
        // (edge, edge, the corner the cut separates from the rest of the face, if any)
        let mut cuts: Vec<(u8, u8, Option<u8>)> = Vec::new();
        match crossed.len() {
            2 => {
                let (k, l) = (crossed[0], crossed[1]);
                let cut_corner = if l == k + 1 {
                    Some(c[l])
                } else if k == 0 && l == 3 {
                    Some(c[0])
                } else {
                    None
                };
                cuts.push((edges[k], edges[l], cut_corner));
            }
            4 => {
                // Joined inside corners: cut off each outside corner; else each inside corner.
                let cut_inside = joined & (1 << f) == 0;
                for k in 0..4 {
                    if inside(c[k]) == cut_inside {
                        cuts.push((edges[(k + 3) % 4], edges[k], Some(c[k])));
                    }
                }
            }
            _ => {}
        }
        let n = Vec3::new(
            f32::from(face.normal[0]),
            f32::from(face.normal[1]),
            f32::from(face.normal[2]),
        );
        for (a, b, cut_corner) in cuts {
            let (u, v) = (edge_midpoint(a), edge_midpoint(b));
            // Reference: the cut-off corner (inside or outside), or any inside corner.
            let (reference, reference_inside) = match cut_corner {
                Some(k) => (k, inside(k)),
                None => (c.into_iter().find(|&k| inside(k)).unwrap_or(c[0]), true),
            };
            let side = (v - u).cross(corner_position(reference) - u).dot(n);
            // Inside to the left seen from outside: an inside reference gives a negative side.
            let (from, to) = if (side < 0.0) == reference_inside {
                (a, b)
            } else {
                (b, a)
            };
            next[from as usize] = Some(to);
        }
    }
    next
}

/// Triangles for `case` with ambiguous faces resolved by `joined`: the face cuts chained into
/// loops, each loop triangulated (minimum total diagonal length in the unit cube) with no
/// diagonal between two vertices on a common face, so that no edge but a face cut is ever shared
/// with a neighbouring cube. A loop that has no such triangulation (it crosses one face twice)
/// is fanned around an extra vertex at its centre.
fn resolved_triangles(case: u8, joined: u8) -> Triangulation {
    let next = face_cuts(case, joined);
    let mut visited = [false; 12];
    let mut out = Triangulation::default();
    for start in 0..12u8 {
        if visited[start as usize] || next[start as usize].is_none() {
            continue;
        }
        let mut polygon = vec![start];
        visited[start as usize] = true;
        let mut e = start;
        while let Some(n) = next[e as usize] {
            if n == start || visited[n as usize] {
                break;
            }
            visited[n as usize] = true;
            polygon.push(n);
            e = n;
        }
        if !triangulate_loop(&polygon, &mut out.triangles) {
            let centre = 12 + out.centres.len() as u8;
            let m = polygon.len();
            out.triangles
                .extend((0..m).map(|k| [polygon[k], polygon[(k + 1) % m], centre]));
            out.centres.push(polygon);
        }
    }
    out
}

/// Minimum-weight triangulation of a loop of cube edges (dynamic programming over sub-polygons),
/// never using a diagonal whose two vertices share a cube face; keeps the loop's orientation.
/// Returns false (adding nothing) when no such triangulation exists.
fn triangulate_loop(polygon: &[u8], out: &mut Vec<[u8; 3]>) -> bool {
    let m = polygon.len();
    if m < 3 {
        return true;
    }
    let allowed = |i: usize, j: usize| {
        let d = i.abs_diff(j);
        d == 1 || d == m - 1 || edge_faces(polygon[i]) & edge_faces(polygon[j]) == 0
    };
    let weight =
        |i: usize, j: usize| (edge_midpoint(polygon[i]) - edge_midpoint(polygon[j])).length();
    // cost[i][j]: best triangulation of polygon[i..=j] closed by the chord (i, j).
    let mut cost = vec![vec![f32::INFINITY; m]; m];
    let mut apex = vec![vec![usize::MAX; m]; m];
    for i in 0..m - 1 {
        cost[i][i + 1] = 0.0;
    }
    for len in 2..m {
        for i in 0..m - len {
            let j = i + len;
            if !allowed(i, j) {
                continue;
            }
            for k in i + 1..j {
                let c = cost[i][k] + cost[k][j] + weight(i, k) + weight(k, j);
                if c < cost[i][j] {
                    cost[i][j] = c;
                    apex[i][j] = k;
                }
            }
        }
    }
    if !cost[0][m - 1].is_finite() {
        return false;
    }
    let mut stack = vec![(0, m - 1)];
    while let Some((i, j)) = stack.pop() {
        if j <= i + 1 {
            continue;
        }
        let k = apex[i][j];
        out.push([polygon[i], polygon[k], polygon[j]]);
        stack.push((k, j));
        stack.push((i, k));
    }
    true
}

// The classic tables, verified against the geometry of the cube by the tests below.

/// Which of the 12 cube edges the surface crosses, per case (Bourke's `edgeTable`): bit `e` set
/// when edge `e`'s two corners lie on different sides.
#[rustfmt::skip]
const EDGE_TABLE: [u16; 256] = [
    0x000, 0x109, 0x203, 0x30a, 0x406, 0x50f, 0x605, 0x70c,
    0x80c, 0x905, 0xa0f, 0xb06, 0xc0a, 0xd03, 0xe09, 0xf00,
    0x190, 0x099, 0x393, 0x29a, 0x596, 0x49f, 0x795, 0x69c,
    0x99c, 0x895, 0xb9f, 0xa96, 0xd9a, 0xc93, 0xf99, 0xe90,
    0x230, 0x339, 0x033, 0x13a, 0x636, 0x73f, 0x435, 0x53c,
    0xa3c, 0xb35, 0x83f, 0x936, 0xe3a, 0xf33, 0xc39, 0xd30,
    0x3a0, 0x2a9, 0x1a3, 0x0aa, 0x7a6, 0x6af, 0x5a5, 0x4ac,
    0xbac, 0xaa5, 0x9af, 0x8a6, 0xfaa, 0xea3, 0xda9, 0xca0,
    0x460, 0x569, 0x663, 0x76a, 0x066, 0x16f, 0x265, 0x36c,
    0xc6c, 0xd65, 0xe6f, 0xf66, 0x86a, 0x963, 0xa69, 0xb60,
    0x5f0, 0x4f9, 0x7f3, 0x6fa, 0x1f6, 0x0ff, 0x3f5, 0x2fc,
    0xdfc, 0xcf5, 0xfff, 0xef6, 0x9fa, 0x8f3, 0xbf9, 0xaf0,
    0x650, 0x759, 0x453, 0x55a, 0x256, 0x35f, 0x055, 0x15c,
    0xe5c, 0xf55, 0xc5f, 0xd56, 0xa5a, 0xb53, 0x859, 0x950,
    0x7c0, 0x6c9, 0x5c3, 0x4ca, 0x3c6, 0x2cf, 0x1c5, 0x0cc,
    0xfcc, 0xec5, 0xdcf, 0xcc6, 0xbca, 0xac3, 0x9c9, 0x8c0,
    0x8c0, 0x9c9, 0xac3, 0xbca, 0xcc6, 0xdcf, 0xec5, 0xfcc,
    0x0cc, 0x1c5, 0x2cf, 0x3c6, 0x4ca, 0x5c3, 0x6c9, 0x7c0,
    0x950, 0x859, 0xb53, 0xa5a, 0xd56, 0xc5f, 0xf55, 0xe5c,
    0x15c, 0x055, 0x35f, 0x256, 0x55a, 0x453, 0x759, 0x650,
    0xaf0, 0xbf9, 0x8f3, 0x9fa, 0xef6, 0xfff, 0xcf5, 0xdfc,
    0x2fc, 0x3f5, 0x0ff, 0x1f6, 0x6fa, 0x7f3, 0x4f9, 0x5f0,
    0xb60, 0xa69, 0x963, 0x86a, 0xf66, 0xe6f, 0xd65, 0xc6c,
    0x36c, 0x265, 0x16f, 0x066, 0x76a, 0x663, 0x569, 0x460,
    0xca0, 0xda9, 0xea3, 0xfaa, 0x8a6, 0x9af, 0xaa5, 0xbac,
    0x4ac, 0x5a5, 0x6af, 0x7a6, 0x0aa, 0x1a3, 0x2a9, 0x3a0,
    0xd30, 0xc39, 0xf33, 0xe3a, 0x936, 0x83f, 0xb35, 0xa3c,
    0x53c, 0x435, 0x73f, 0x636, 0x13a, 0x033, 0x339, 0x230,
    0xe90, 0xf99, 0xc93, 0xd9a, 0xa96, 0xb9f, 0x895, 0x99c,
    0x69c, 0x795, 0x49f, 0x596, 0x29a, 0x393, 0x099, 0x190,
    0xf00, 0xe09, 0xd03, 0xc0a, 0xb06, 0xa0f, 0x905, 0x80c,
    0x70c, 0x605, 0x50f, 0x406, 0x30a, 0x203, 0x109, 0x000,
];

/// Triangles per case as triples of cube edges, -1 terminated (Bourke's `triTable`, after
/// Lorensen and Cline). Bourke's triangles face the inside; [`CaseTables`] reverses them.
#[rustfmt::skip]
const TRIANGLE_TABLE: [[i8; 16]; 256] = [
    [-1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1],
    [0, 8, 3, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1],
    [0, 1, 9, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1],
    [1, 8, 3, 9, 8, 1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1],
    [1, 2, 10, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1],
    [0, 8, 3, 1, 2, 10, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1],
    [9, 2, 10, 0, 2, 9, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1],
    [2, 8, 3, 2, 10, 8, 10, 9, 8, -1, -1, -1, -1, -1, -1, -1],
    [3, 11, 2, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1],
    [0, 11, 2, 8, 11, 0, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1],
    [1, 9, 0, 2, 3, 11, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1],
    [1, 11, 2, 1, 9, 11, 9, 8, 11, -1, -1, -1, -1, -1, -1, -1],
    [3, 10, 1, 11, 10, 3, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1],
    [0, 10, 1, 0, 8, 10, 8, 11, 10, -1, -1, -1, -1, -1, -1, -1],
    [3, 9, 0, 3, 11, 9, 11, 10, 9, -1, -1, -1, -1, -1, -1, -1],
    [9, 8, 10, 10, 8, 11, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1],
    [4, 7, 8, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1],
    [4, 3, 0, 7, 3, 4, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1],
    [0, 1, 9, 8, 4, 7, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1],
    [4, 1, 9, 4, 7, 1, 7, 3, 1, -1, -1, -1, -1, -1, -1, -1],
    [1, 2, 10, 8, 4, 7, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1],
    [3, 4, 7, 3, 0, 4, 1, 2, 10, -1, -1, -1, -1, -1, -1, -1],
    [9, 2, 10, 9, 0, 2, 8, 4, 7, -1, -1, -1, -1, -1, -1, -1],
    [2, 10, 9, 2, 9, 7, 2, 7, 3, 7, 9, 4, -1, -1, -1, -1],
    [8, 4, 7, 3, 11, 2, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1],
    [11, 4, 7, 11, 2, 4, 2, 0, 4, -1, -1, -1, -1, -1, -1, -1],
    [9, 0, 1, 8, 4, 7, 2, 3, 11, -1, -1, -1, -1, -1, -1, -1],
    [4, 7, 11, 9, 4, 11, 9, 11, 2, 9, 2, 1, -1, -1, -1, -1],
    [3, 10, 1, 3, 11, 10, 7, 8, 4, -1, -1, -1, -1, -1, -1, -1],
    [1, 11, 10, 1, 4, 11, 1, 0, 4, 7, 11, 4, -1, -1, -1, -1],
    [4, 7, 8, 9, 0, 11, 9, 11, 10, 11, 0, 3, -1, -1, -1, -1],
    [4, 7, 11, 4, 11, 9, 9, 11, 10, -1, -1, -1, -1, -1, -1, -1],
    [9, 5, 4, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1],
    [9, 5, 4, 0, 8, 3, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1],
    [0, 5, 4, 1, 5, 0, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1],
    [8, 5, 4, 8, 3, 5, 3, 1, 5, -1, -1, -1, -1, -1, -1, -1],
    [1, 2, 10, 9, 5, 4, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1],
    [3, 0, 8, 1, 2, 10, 4, 9, 5, -1, -1, -1, -1, -1, -1, -1],
    [5, 2, 10, 5, 4, 2, 4, 0, 2, -1, -1, -1, -1, -1, -1, -1],
    [2, 10, 5, 3, 2, 5, 3, 5, 4, 3, 4, 8, -1, -1, -1, -1],
    [9, 5, 4, 2, 3, 11, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1],
    [0, 11, 2, 0, 8, 11, 4, 9, 5, -1, -1, -1, -1, -1, -1, -1],
    [0, 5, 4, 0, 1, 5, 2, 3, 11, -1, -1, -1, -1, -1, -1, -1],
    [2, 1, 5, 2, 5, 8, 2, 8, 11, 4, 8, 5, -1, -1, -1, -1],
    [10, 3, 11, 10, 1, 3, 9, 5, 4, -1, -1, -1, -1, -1, -1, -1],
    [4, 9, 5, 0, 8, 1, 8, 10, 1, 8, 11, 10, -1, -1, -1, -1],
    [5, 4, 0, 5, 0, 11, 5, 11, 10, 11, 0, 3, -1, -1, -1, -1],
    [5, 4, 8, 5, 8, 10, 10, 8, 11, -1, -1, -1, -1, -1, -1, -1],
    [9, 7, 8, 5, 7, 9, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1],
    [9, 3, 0, 9, 5, 3, 5, 7, 3, -1, -1, -1, -1, -1, -1, -1],
    [0, 7, 8, 0, 1, 7, 1, 5, 7, -1, -1, -1, -1, -1, -1, -1],
    [1, 5, 3, 3, 5, 7, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1],
    [9, 7, 8, 9, 5, 7, 10, 1, 2, -1, -1, -1, -1, -1, -1, -1],
    [10, 1, 2, 9, 5, 0, 5, 3, 0, 5, 7, 3, -1, -1, -1, -1],
    [8, 0, 2, 8, 2, 5, 8, 5, 7, 10, 5, 2, -1, -1, -1, -1],
    [2, 10, 5, 2, 5, 3, 3, 5, 7, -1, -1, -1, -1, -1, -1, -1],
    [7, 9, 5, 7, 8, 9, 3, 11, 2, -1, -1, -1, -1, -1, -1, -1],
    [9, 5, 7, 9, 7, 2, 9, 2, 0, 2, 7, 11, -1, -1, -1, -1],
    [2, 3, 11, 0, 1, 8, 1, 7, 8, 1, 5, 7, -1, -1, -1, -1],
    [11, 2, 1, 11, 1, 7, 7, 1, 5, -1, -1, -1, -1, -1, -1, -1],
    [9, 5, 8, 8, 5, 7, 10, 1, 3, 10, 3, 11, -1, -1, -1, -1],
    [5, 7, 0, 5, 0, 9, 7, 11, 0, 1, 0, 10, 11, 10, 0, -1],
    [11, 10, 0, 11, 0, 3, 10, 5, 0, 8, 0, 7, 5, 7, 0, -1],
    [11, 10, 5, 7, 11, 5, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1],
    [10, 6, 5, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1],
    [0, 8, 3, 5, 10, 6, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1],
    [9, 0, 1, 5, 10, 6, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1],
    [1, 8, 3, 1, 9, 8, 5, 10, 6, -1, -1, -1, -1, -1, -1, -1],
    [1, 6, 5, 2, 6, 1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1],
    [1, 6, 5, 1, 2, 6, 3, 0, 8, -1, -1, -1, -1, -1, -1, -1],
    [9, 6, 5, 9, 0, 6, 0, 2, 6, -1, -1, -1, -1, -1, -1, -1],
    [5, 9, 8, 5, 8, 2, 5, 2, 6, 3, 2, 8, -1, -1, -1, -1],
    [2, 3, 11, 10, 6, 5, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1],
    [11, 0, 8, 11, 2, 0, 10, 6, 5, -1, -1, -1, -1, -1, -1, -1],
    [0, 1, 9, 2, 3, 11, 5, 10, 6, -1, -1, -1, -1, -1, -1, -1],
    [5, 10, 6, 1, 9, 2, 9, 11, 2, 9, 8, 11, -1, -1, -1, -1],
    [6, 3, 11, 6, 5, 3, 5, 1, 3, -1, -1, -1, -1, -1, -1, -1],
    [0, 8, 11, 0, 11, 5, 0, 5, 1, 5, 11, 6, -1, -1, -1, -1],
    [3, 11, 6, 0, 3, 6, 0, 6, 5, 0, 5, 9, -1, -1, -1, -1],
    [6, 5, 9, 6, 9, 11, 11, 9, 8, -1, -1, -1, -1, -1, -1, -1],
    [5, 10, 6, 4, 7, 8, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1],
    [4, 3, 0, 4, 7, 3, 6, 5, 10, -1, -1, -1, -1, -1, -1, -1],
    [1, 9, 0, 5, 10, 6, 8, 4, 7, -1, -1, -1, -1, -1, -1, -1],
    [10, 6, 5, 1, 9, 7, 1, 7, 3, 7, 9, 4, -1, -1, -1, -1],
    [6, 1, 2, 6, 5, 1, 4, 7, 8, -1, -1, -1, -1, -1, -1, -1],
    [1, 2, 5, 5, 2, 6, 3, 0, 4, 3, 4, 7, -1, -1, -1, -1],
    [8, 4, 7, 9, 0, 5, 0, 6, 5, 0, 2, 6, -1, -1, -1, -1],
    [7, 3, 9, 7, 9, 4, 3, 2, 9, 5, 9, 6, 2, 6, 9, -1],
    [3, 11, 2, 7, 8, 4, 10, 6, 5, -1, -1, -1, -1, -1, -1, -1],
    [5, 10, 6, 4, 7, 2, 4, 2, 0, 2, 7, 11, -1, -1, -1, -1],
    [0, 1, 9, 4, 7, 8, 2, 3, 11, 5, 10, 6, -1, -1, -1, -1],
    [9, 2, 1, 9, 11, 2, 9, 4, 11, 7, 11, 4, 5, 10, 6, -1],
    [8, 4, 7, 3, 11, 5, 3, 5, 1, 5, 11, 6, -1, -1, -1, -1],
    [5, 1, 11, 5, 11, 6, 1, 0, 11, 7, 11, 4, 0, 4, 11, -1],
    [0, 5, 9, 0, 6, 5, 0, 3, 6, 11, 6, 3, 8, 4, 7, -1],
    [6, 5, 9, 6, 9, 11, 4, 7, 9, 7, 11, 9, -1, -1, -1, -1],
    [10, 4, 9, 6, 4, 10, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1],
    [4, 10, 6, 4, 9, 10, 0, 8, 3, -1, -1, -1, -1, -1, -1, -1],
    [10, 0, 1, 10, 6, 0, 6, 4, 0, -1, -1, -1, -1, -1, -1, -1],
    [8, 3, 1, 8, 1, 6, 8, 6, 4, 6, 1, 10, -1, -1, -1, -1],
    [1, 4, 9, 1, 2, 4, 2, 6, 4, -1, -1, -1, -1, -1, -1, -1],
    [3, 0, 8, 1, 2, 9, 2, 4, 9, 2, 6, 4, -1, -1, -1, -1],
    [0, 2, 4, 4, 2, 6, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1],
    [8, 3, 2, 8, 2, 4, 4, 2, 6, -1, -1, -1, -1, -1, -1, -1],
    [10, 4, 9, 10, 6, 4, 11, 2, 3, -1, -1, -1, -1, -1, -1, -1],
    [0, 8, 2, 2, 8, 11, 4, 9, 10, 4, 10, 6, -1, -1, -1, -1],
    [3, 11, 2, 0, 1, 6, 0, 6, 4, 6, 1, 10, -1, -1, -1, -1],
    [6, 4, 1, 6, 1, 10, 4, 8, 1, 2, 1, 11, 8, 11, 1, -1],
    [9, 6, 4, 9, 3, 6, 9, 1, 3, 11, 6, 3, -1, -1, -1, -1],
    [8, 11, 1, 8, 1, 0, 11, 6, 1, 9, 1, 4, 6, 4, 1, -1],
    [3, 11, 6, 3, 6, 0, 0, 6, 4, -1, -1, -1, -1, -1, -1, -1],
    [6, 4, 8, 11, 6, 8, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1],
    [7, 10, 6, 7, 8, 10, 8, 9, 10, -1, -1, -1, -1, -1, -1, -1],
    [0, 7, 3, 0, 10, 7, 0, 9, 10, 6, 7, 10, -1, -1, -1, -1],
    [10, 6, 7, 1, 10, 7, 1, 7, 8, 1, 8, 0, -1, -1, -1, -1],
    [10, 6, 7, 10, 7, 1, 1, 7, 3, -1, -1, -1, -1, -1, -1, -1],
    [1, 2, 6, 1, 6, 8, 1, 8, 9, 8, 6, 7, -1, -1, -1, -1],
    [2, 6, 9, 2, 9, 1, 6, 7, 9, 0, 9, 3, 7, 3, 9, -1],
    [7, 8, 0, 7, 0, 6, 6, 0, 2, -1, -1, -1, -1, -1, -1, -1],
    [7, 3, 2, 6, 7, 2, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1],
    [2, 3, 11, 10, 6, 8, 10, 8, 9, 8, 6, 7, -1, -1, -1, -1],
    [2, 0, 7, 2, 7, 11, 0, 9, 7, 6, 7, 10, 9, 10, 7, -1],
    [1, 8, 0, 1, 7, 8, 1, 10, 7, 6, 7, 10, 2, 3, 11, -1],
    [11, 2, 1, 11, 1, 7, 10, 6, 1, 6, 7, 1, -1, -1, -1, -1],
    [8, 9, 6, 8, 6, 7, 9, 1, 6, 11, 6, 3, 1, 3, 6, -1],
    [0, 9, 1, 11, 6, 7, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1],
    [7, 8, 0, 7, 0, 6, 3, 11, 0, 11, 6, 0, -1, -1, -1, -1],
    [7, 11, 6, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1],
    [7, 6, 11, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1],
    [3, 0, 8, 11, 7, 6, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1],
    [0, 1, 9, 11, 7, 6, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1],
    [8, 1, 9, 8, 3, 1, 11, 7, 6, -1, -1, -1, -1, -1, -1, -1],
    [10, 1, 2, 6, 11, 7, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1],
    [1, 2, 10, 3, 0, 8, 6, 11, 7, -1, -1, -1, -1, -1, -1, -1],
    [2, 9, 0, 2, 10, 9, 6, 11, 7, -1, -1, -1, -1, -1, -1, -1],
    [6, 11, 7, 2, 10, 3, 10, 8, 3, 10, 9, 8, -1, -1, -1, -1],
    [7, 2, 3, 6, 2, 7, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1],
    [7, 0, 8, 7, 6, 0, 6, 2, 0, -1, -1, -1, -1, -1, -1, -1],
    [2, 7, 6, 2, 3, 7, 0, 1, 9, -1, -1, -1, -1, -1, -1, -1],
    [1, 6, 2, 1, 8, 6, 1, 9, 8, 8, 7, 6, -1, -1, -1, -1],
    [10, 7, 6, 10, 1, 7, 1, 3, 7, -1, -1, -1, -1, -1, -1, -1],
    [10, 7, 6, 1, 7, 10, 1, 8, 7, 1, 0, 8, -1, -1, -1, -1],
    [0, 3, 7, 0, 7, 10, 0, 10, 9, 6, 10, 7, -1, -1, -1, -1],
    [7, 6, 10, 7, 10, 8, 8, 10, 9, -1, -1, -1, -1, -1, -1, -1],
    [6, 8, 4, 11, 8, 6, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1],
    [3, 6, 11, 3, 0, 6, 0, 4, 6, -1, -1, -1, -1, -1, -1, -1],
    [8, 6, 11, 8, 4, 6, 9, 0, 1, -1, -1, -1, -1, -1, -1, -1],
    [9, 4, 6, 9, 6, 3, 9, 3, 1, 11, 3, 6, -1, -1, -1, -1],
    [6, 8, 4, 6, 11, 8, 2, 10, 1, -1, -1, -1, -1, -1, -1, -1],
    [1, 2, 10, 3, 0, 11, 0, 6, 11, 0, 4, 6, -1, -1, -1, -1],
    [4, 11, 8, 4, 6, 11, 0, 2, 9, 2, 10, 9, -1, -1, -1, -1],
    [10, 9, 3, 10, 3, 2, 9, 4, 3, 11, 3, 6, 4, 6, 3, -1],
    [8, 2, 3, 8, 4, 2, 4, 6, 2, -1, -1, -1, -1, -1, -1, -1],
    [0, 4, 2, 4, 6, 2, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1],
    [1, 9, 0, 2, 3, 4, 2, 4, 6, 4, 3, 8, -1, -1, -1, -1],
    [1, 9, 4, 1, 4, 2, 2, 4, 6, -1, -1, -1, -1, -1, -1, -1],
    [8, 1, 3, 8, 6, 1, 8, 4, 6, 6, 10, 1, -1, -1, -1, -1],
    [10, 1, 0, 10, 0, 6, 6, 0, 4, -1, -1, -1, -1, -1, -1, -1],
    [4, 6, 3, 4, 3, 8, 6, 10, 3, 0, 3, 9, 10, 9, 3, -1],
    [10, 9, 4, 6, 10, 4, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1],
    [4, 9, 5, 7, 6, 11, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1],
    [0, 8, 3, 4, 9, 5, 11, 7, 6, -1, -1, -1, -1, -1, -1, -1],
    [5, 0, 1, 5, 4, 0, 7, 6, 11, -1, -1, -1, -1, -1, -1, -1],
    [11, 7, 6, 8, 3, 4, 3, 5, 4, 3, 1, 5, -1, -1, -1, -1],
    [9, 5, 4, 10, 1, 2, 7, 6, 11, -1, -1, -1, -1, -1, -1, -1],
    [6, 11, 7, 1, 2, 10, 0, 8, 3, 4, 9, 5, -1, -1, -1, -1],
    [7, 6, 11, 5, 4, 10, 4, 2, 10, 4, 0, 2, -1, -1, -1, -1],
    [3, 4, 8, 3, 5, 4, 3, 2, 5, 10, 5, 2, 11, 7, 6, -1],
    [7, 2, 3, 7, 6, 2, 5, 4, 9, -1, -1, -1, -1, -1, -1, -1],
    [9, 5, 4, 0, 8, 6, 0, 6, 2, 6, 8, 7, -1, -1, -1, -1],
    [3, 6, 2, 3, 7, 6, 1, 5, 0, 5, 4, 0, -1, -1, -1, -1],
    [6, 2, 8, 6, 8, 7, 2, 1, 8, 4, 8, 5, 1, 5, 8, -1],
    [9, 5, 4, 10, 1, 6, 1, 7, 6, 1, 3, 7, -1, -1, -1, -1],
    [1, 6, 10, 1, 7, 6, 1, 0, 7, 8, 7, 0, 9, 5, 4, -1],
    [4, 0, 10, 4, 10, 5, 0, 3, 10, 6, 10, 7, 3, 7, 10, -1],
    [7, 6, 10, 7, 10, 8, 5, 4, 10, 4, 8, 10, -1, -1, -1, -1],
    [6, 9, 5, 6, 11, 9, 11, 8, 9, -1, -1, -1, -1, -1, -1, -1],
    [3, 6, 11, 0, 6, 3, 0, 5, 6, 0, 9, 5, -1, -1, -1, -1],
    [0, 11, 8, 0, 5, 11, 0, 1, 5, 5, 6, 11, -1, -1, -1, -1],
    [6, 11, 3, 6, 3, 5, 5, 3, 1, -1, -1, -1, -1, -1, -1, -1],
    [1, 2, 10, 9, 5, 11, 9, 11, 8, 11, 5, 6, -1, -1, -1, -1],
    [0, 11, 3, 0, 6, 11, 0, 9, 6, 5, 6, 9, 1, 2, 10, -1],
    [11, 8, 5, 11, 5, 6, 8, 0, 5, 10, 5, 2, 0, 2, 5, -1],
    [6, 11, 3, 6, 3, 5, 2, 10, 3, 10, 5, 3, -1, -1, -1, -1],
    [5, 8, 9, 5, 2, 8, 5, 6, 2, 3, 8, 2, -1, -1, -1, -1],
    [9, 5, 6, 9, 6, 0, 0, 6, 2, -1, -1, -1, -1, -1, -1, -1],
    [1, 5, 8, 1, 8, 0, 5, 6, 8, 3, 8, 2, 6, 2, 8, -1],
    [1, 5, 6, 2, 1, 6, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1],
    [1, 3, 6, 1, 6, 10, 3, 8, 6, 5, 6, 9, 8, 9, 6, -1],
    [10, 1, 0, 10, 0, 6, 9, 5, 0, 5, 6, 0, -1, -1, -1, -1],
    [0, 3, 8, 5, 6, 10, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1],
    [10, 5, 6, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1],
    [11, 5, 10, 7, 5, 11, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1],
    [11, 5, 10, 11, 7, 5, 8, 3, 0, -1, -1, -1, -1, -1, -1, -1],
    [5, 11, 7, 5, 10, 11, 1, 9, 0, -1, -1, -1, -1, -1, -1, -1],
    [10, 7, 5, 10, 11, 7, 9, 8, 1, 8, 3, 1, -1, -1, -1, -1],
    [11, 1, 2, 11, 7, 1, 7, 5, 1, -1, -1, -1, -1, -1, -1, -1],
    [0, 8, 3, 1, 2, 7, 1, 7, 5, 7, 2, 11, -1, -1, -1, -1],
    [9, 7, 5, 9, 2, 7, 9, 0, 2, 2, 11, 7, -1, -1, -1, -1],
    [7, 5, 2, 7, 2, 11, 5, 9, 2, 3, 2, 8, 9, 8, 2, -1],
    [2, 5, 10, 2, 3, 5, 3, 7, 5, -1, -1, -1, -1, -1, -1, -1],
    [8, 2, 0, 8, 5, 2, 8, 7, 5, 10, 2, 5, -1, -1, -1, -1],
    [9, 0, 1, 5, 10, 3, 5, 3, 7, 3, 10, 2, -1, -1, -1, -1],
    [9, 8, 2, 9, 2, 1, 8, 7, 2, 10, 2, 5, 7, 5, 2, -1],
    [1, 3, 5, 3, 7, 5, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1],
    [0, 8, 7, 0, 7, 1, 1, 7, 5, -1, -1, -1, -1, -1, -1, -1],
    [9, 0, 3, 9, 3, 5, 5, 3, 7, -1, -1, -1, -1, -1, -1, -1],
    [9, 8, 7, 5, 9, 7, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1],
    [5, 8, 4, 5, 10, 8, 10, 11, 8, -1, -1, -1, -1, -1, -1, -1],
    [5, 0, 4, 5, 11, 0, 5, 10, 11, 11, 3, 0, -1, -1, -1, -1],
    [0, 1, 9, 8, 4, 10, 8, 10, 11, 10, 4, 5, -1, -1, -1, -1],
    [10, 11, 4, 10, 4, 5, 11, 3, 4, 9, 4, 1, 3, 1, 4, -1],
    [2, 5, 1, 2, 8, 5, 2, 11, 8, 4, 5, 8, -1, -1, -1, -1],
    [0, 4, 11, 0, 11, 3, 4, 5, 11, 2, 11, 1, 5, 1, 11, -1],
    [0, 2, 5, 0, 5, 9, 2, 11, 5, 4, 5, 8, 11, 8, 5, -1],
    [9, 4, 5, 2, 11, 3, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1],
    [2, 5, 10, 3, 5, 2, 3, 4, 5, 3, 8, 4, -1, -1, -1, -1],
    [5, 10, 2, 5, 2, 4, 4, 2, 0, -1, -1, -1, -1, -1, -1, -1],
    [3, 10, 2, 3, 5, 10, 3, 8, 5, 4, 5, 8, 0, 1, 9, -1],
    [5, 10, 2, 5, 2, 4, 1, 9, 2, 9, 4, 2, -1, -1, -1, -1],
    [8, 4, 5, 8, 5, 3, 3, 5, 1, -1, -1, -1, -1, -1, -1, -1],
    [0, 4, 5, 1, 0, 5, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1],
    [8, 4, 5, 8, 5, 3, 9, 0, 5, 0, 3, 5, -1, -1, -1, -1],
    [9, 4, 5, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1],
    [4, 11, 7, 4, 9, 11, 9, 10, 11, -1, -1, -1, -1, -1, -1, -1],
    [0, 8, 3, 4, 9, 7, 9, 11, 7, 9, 10, 11, -1, -1, -1, -1],
    [1, 10, 11, 1, 11, 4, 1, 4, 0, 7, 4, 11, -1, -1, -1, -1],
    [3, 1, 4, 3, 4, 8, 1, 10, 4, 7, 4, 11, 10, 11, 4, -1],
    [4, 11, 7, 9, 11, 4, 9, 2, 11, 9, 1, 2, -1, -1, -1, -1],
    [9, 7, 4, 9, 11, 7, 9, 1, 11, 2, 11, 1, 0, 8, 3, -1],
    [11, 7, 4, 11, 4, 2, 2, 4, 0, -1, -1, -1, -1, -1, -1, -1],
    [11, 7, 4, 11, 4, 2, 8, 3, 4, 3, 2, 4, -1, -1, -1, -1],
    [2, 9, 10, 2, 7, 9, 2, 3, 7, 7, 4, 9, -1, -1, -1, -1],
    [9, 10, 7, 9, 7, 4, 10, 2, 7, 8, 7, 0, 2, 0, 7, -1],
    [3, 7, 10, 3, 10, 2, 7, 4, 10, 1, 10, 0, 4, 0, 10, -1],
    [1, 10, 2, 8, 7, 4, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1],
    [4, 9, 1, 4, 1, 7, 7, 1, 3, -1, -1, -1, -1, -1, -1, -1],
    [4, 9, 1, 4, 1, 7, 0, 8, 1, 8, 7, 1, -1, -1, -1, -1],
    [4, 0, 3, 7, 4, 3, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1],
    [4, 8, 7, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1],
    [9, 10, 8, 10, 11, 8, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1],
    [3, 0, 9, 3, 9, 11, 11, 9, 10, -1, -1, -1, -1, -1, -1, -1],
    [0, 1, 10, 0, 10, 8, 8, 10, 11, -1, -1, -1, -1, -1, -1, -1],
    [3, 1, 10, 11, 3, 10, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1],
    [1, 2, 11, 1, 11, 9, 9, 11, 8, -1, -1, -1, -1, -1, -1, -1],
    [3, 0, 9, 3, 9, 11, 1, 2, 9, 2, 11, 9, -1, -1, -1, -1],
    [0, 2, 11, 8, 0, 11, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1],
    [3, 2, 11, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1],
    [2, 3, 8, 2, 8, 10, 10, 8, 9, -1, -1, -1, -1, -1, -1, -1],
    [9, 10, 2, 0, 9, 2, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1],
    [2, 3, 8, 2, 8, 10, 0, 1, 8, 1, 10, 8, -1, -1, -1, -1],
    [1, 10, 2, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1],
    [1, 3, 8, 9, 1, 8, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1],
    [0, 9, 1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1],
    [0, 3, 8, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1],
    [-1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1],
];

#[cfg(test)]
mod tests {
    use super::*;
    use crate::measure::on_box_boundary;
    use crate::{Clustering, Extractor, Grid, Lattice, Method};
    use glam::DVec3;
    use rmt_fields::{FnField, ScalarField, Sphere, Torus};
    use std::collections::HashSet;

    fn settings(grid: Grid, threads: usize) -> ExtractSettings {
        let mut s = ExtractSettings::new(grid, Lattice::Simple, Clustering::None);
        s.method = Method::Mc;
        s.threads = threads;
        s
    }

    fn run(field: &dyn ScalarField, grid: Grid, threads: usize) -> (Mesh, Stats) {
        let mut mesh = Mesh::default();
        let stats = Extractor::new()
            .extract(field, &settings(grid, threads), &mut mesh)
            .unwrap();
        (mesh, stats)
    }

    /// Cases whose faces are all cut in the only possible way.
    fn unambiguous(case: usize) -> bool {
        CaseTables::get().ambiguous_faces[case] == 0
    }

    /// Every (case, resolution) entry of the resolved table: (case, bits, triangles).
    fn resolved_entries() -> Vec<(usize, u8, &'static Triangulation)> {
        let tables = CaseTables::get();
        let mut out = Vec::new();
        for case in 0..256 {
            let mask = tables.ambiguous_faces[case];
            if mask == 0 {
                continue;
            }
            for bits in 0..64u8 {
                if bits & !mask == 0 {
                    out.push((case, bits, &tables.resolved[case * 64 + usize::from(bits)]));
                }
            }
        }
        out
    }

    #[test]
    fn edge_table_is_what_the_triangle_table_uses_and_what_the_corner_signs_cross() {
        for case in 0..256usize {
            let used = TRIANGLE_TABLE[case]
                .iter()
                .filter(|&&e| e >= 0)
                .fold(0u16, |m, &e| m | 1 << e);
            let crossed = EDGE_CORNERS
                .iter()
                .enumerate()
                .filter(|(_, [a, b])| (case >> a & 1) != (case >> b & 1))
                .fold(0u16, |m, (e, _)| m | 1 << e);
            assert_eq!(
                used, crossed,
                "case {case}: triangles use edges {used:#x}, corners cross {crossed:#x}"
            );
            assert_eq!(EDGE_TABLE[case], crossed, "case {case}: edge table");
            // -1 terminated, whole triangles.
            let n = TRIANGLE_TABLE[case]
                .iter()
                .position(|&e| e < 0)
                .unwrap_or(16);
            assert_eq!(n % 3, 0, "case {case}");
            assert!(
                TRIANGLE_TABLE[case][n..].iter().all(|&e| e < 0),
                "case {case}"
            );
        }
        // Complementary cases cross the same edges.
        for case in 0..256 {
            assert_eq!(EDGE_TABLE[case], EDGE_TABLE[255 - case]);
        }
    }

    #[test]
    fn edge_on_grid_matches_edge_corners() {
        for (e, &(corner, axis)) in EDGE_ON_GRID.iter().enumerate() {
            let mut other = CORNERS[corner as usize];
            other[axis as usize] += 1;
            let ends: HashSet<[u8; 3]> = EDGE_CORNERS[e]
                .iter()
                .map(|&c| CORNERS[c as usize])
                .collect();
            assert_eq!(
                ends,
                HashSet::from([CORNERS[corner as usize], other]),
                "edge {e}"
            );
        }
        for face in &FACES {
            for k in 0..4 {
                assert!(edge_between(face.corners[k], face.corners[(k + 1) % 4]).is_some());
            }
            // The normal points away from the cube centre.
            let centre: Vec3 = face
                .corners
                .iter()
                .map(|&c| corner_position(c))
                .sum::<Vec3>()
                / 4.0;
            let n = Vec3::new(
                f32::from(face.normal[0]),
                f32::from(face.normal[1]),
                f32::from(face.normal[2]),
            );
            assert!((centre - Vec3::splat(0.5)).dot(n) > 0.0);
        }
    }

    /// Signed crossings of the segment `a -> b` with the triangles (vertices at edge midpoints):
    /// +1 where it leaves the inside (crosses along the normal), -1 where it enters.
    fn signed_crossings(entry: &Triangulation, a: DVec3, b: DVec3) -> (i32, usize) {
        let mut sum = 0;
        let mut count = 0;
        let d = b - a;
        let position = |e: u8| {
            if e < 12 {
                edge_midpoint(e).as_dvec3()
            } else {
                let polygon = &entry.centres[usize::from(e - 12)];
                polygon
                    .iter()
                    .map(|&v| edge_midpoint(v).as_dvec3())
                    .sum::<DVec3>()
                    / polygon.len() as f64
            }
        };
        for t in &entry.triangles {
            let [p, q, r] = t.map(position);
            let (e1, e2) = (q - p, r - p);
            let h = d.cross(e2);
            let det = e1.dot(h);
            if det.abs() < 1e-12 {
                continue;
            }
            let s = a - p;
            let u = s.dot(h) / det;
            let qv = s.cross(e1);
            let v = d.dot(qv) / det;
            let t = e2.dot(qv) / det;
            if u > 0.0 && v > 0.0 && u + v < 1.0 && t > 0.0 && t < 1.0 {
                count += 1;
                sum += if e1.cross(e2).dot(d) > 0.0 { 1 } else { -1 };
            }
        }
        (sum, count)
    }

    /// Every pair of corners, joined by a slightly perturbed segment inside the cube, crosses the
    /// triangles an odd number of times exactly when the corners lie on different sides, and the
    /// crossings' orientations add up to +1 going from inside to outside.
    fn assert_separates(case: usize, triangles: &Triangulation, what: &str) {
        let inside = |c: u8| case >> c & 1 == 1;
        let centre = DVec3::splat(0.5);
        let jitter = [
            DVec3::new(0.0123, -0.0071, 0.0093),
            DVec3::new(-0.0087, 0.0111, -0.0059),
        ];
        for a in 0..8u8 {
            for b in a + 1..8u8 {
                let pa = corner_position(a).as_dvec3();
                let pb = corner_position(b).as_dvec3();
                let from = pa + (centre - pa) * 0.02 + jitter[0];
                let to = pb + (centre - pb) * 0.02 + jitter[1];
                let (sum, count) = signed_crossings(triangles, from, to);
                let want = i32::from(inside(a)) - i32::from(inside(b));
                assert_eq!(
                    sum, want,
                    "{what}: corners {a} -> {b}: signed crossings {sum} ({count} crossings)"
                );
                assert_eq!(
                    count % 2 == 1,
                    inside(a) != inside(b),
                    "{what}: corners {a} -> {b}: {count} crossings"
                );
            }
        }
    }

    #[test]
    fn every_classic_case_separates_inside_from_outside_corners_facing_out() {
        let tables = CaseTables::get();
        for case in 0..256 {
            assert_separates(case, &tables.classic[case], &format!("classic case {case}"));
        }
    }

    #[test]
    fn every_resolved_case_separates_inside_from_outside_corners_facing_out() {
        let entries = resolved_entries();
        assert!(
            entries.len() > 100,
            "expected many ambiguous combinations, got {}",
            entries.len()
        );
        for (case, bits, triangles) in entries {
            assert_separates(
                case,
                triangles,
                &format!("resolved case {case} faces {bits:06b}"),
            );
        }
    }

    /// The directed edges of `triangles` used once with no reverse (the cube-face boundary) must
    /// be exactly the face cuts; every other edge must come once in each direction; no edge but a
    /// face cut may join two vertices on a common face (a neighbour could use it too).
    fn assert_boundary_is_the_face_cuts(case: usize, bits: u8, entry: &Triangulation, what: &str) {
        let triangles = &entry.triangles;
        let cuts: HashSet<(u8, u8)> = face_cuts(case as u8, bits)
            .iter()
            .enumerate()
            .filter_map(|(e, n)| n.map(|n| (e as u8, n)))
            .collect();
        let mut directed: Vec<(u8, u8)> = triangles
            .iter()
            .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])])
            .collect();
        directed.sort_unstable();
        let set: HashSet<(u8, u8)> = directed.iter().copied().collect();
        assert_eq!(
            set.len(),
            directed.len(),
            "{what}: a directed edge is used twice"
        );
        for &(a, b) in &directed {
            let boundary = !set.contains(&(b, a));
            assert_eq!(
                boundary,
                cuts.contains(&(a, b)),
                "{what}: edge {a}->{b} boundary={boundary}, cuts {cuts:?}"
            );
            if !boundary && a < 12 && b < 12 {
                assert_eq!(
                    edge_faces(a) & edge_faces(b),
                    0,
                    "{what}: diagonal {a}-{b} lies in a face"
                );
            }
        }
        let boundary: HashSet<(u8, u8)> = directed
            .iter()
            .copied()
            .filter(|&(a, b)| !set.contains(&(b, a)))
            .collect();
        assert_eq!(boundary, cuts, "{what}: every face cut is a triangle edge");
        // Each crossed cube edge carries exactly one vertex of the surface.
        let vertices: HashSet<u8> = triangles
            .iter()
            .flatten()
            .copied()
            .filter(|&e| e < 12)
            .collect();
        let crossed: HashSet<u8> = (0..12)
            .filter(|&e| EDGE_TABLE[case] & (1 << e) != 0)
            .collect();
        assert_eq!(vertices, crossed, "{what}");
    }

    #[test]
    fn classic_cases_without_ambiguous_faces_cut_each_face_the_only_way() {
        let tables = CaseTables::get();
        let mut checked = 0;
        for case in (0..256).filter(|&c| unambiguous(c)) {
            assert_boundary_is_the_face_cuts(
                case,
                0,
                &tables.classic[case],
                &format!("classic case {case}"),
            );
            checked += 1;
        }
        assert!(checked > 100);
    }

    #[test]
    fn resolved_cases_cut_ambiguous_faces_as_decided_and_share_no_other_edge() {
        let mut with_centres = 0;
        for (case, bits, entry) in resolved_entries() {
            assert_boundary_is_the_face_cuts(
                case,
                bits,
                entry,
                &format!("resolved case {case} faces {bits:06b}"),
            );
            with_centres += usize::from(!entry.centres.is_empty());
            // Centre fans use exactly their loop.
            for (k, polygon) in entry.centres.iter().enumerate() {
                let fan = entry
                    .triangles
                    .iter()
                    .filter(|t| t.contains(&(12 + k as u8)))
                    .count();
                assert_eq!(fan, polygon.len(), "case {case} faces {bits:06b}");
            }
        }
        // Few configurations need an extra vertex (a loop crossing one face twice).
        assert!(
            with_centres < resolved_entries().len() / 4,
            "{with_centres} entries need centres"
        );
    }

    #[test]
    fn the_decider_joins_inside_corners_when_their_product_wins() {
        // Face 0 (z = 0): corners 0 and 2 inside, 1 and 3 outside.
        let mut w = [1.0f32; 8];
        w[0] = -1.0;
        w[2] = -1.0;
        w[1] = 0.5;
        w[3] = 0.5;
        assert_eq!(face_resolution(&w, 1), 1, "(-1)(-1) > (0.5)(0.5): joined");
        w[1] = 2.0;
        assert_eq!(face_resolution(&w, 1), 0, "(-1)(-1) < (2)(0.5): separated");
        // A tie (saddle exactly at iso) counts outside: separated.
        w[1] = 2.0;
        w[3] = 0.5;
        w[0] = -0.5;
        w[2] = -2.0;
        assert_eq!(face_resolution(&w, 1), 0);
        // The same face seen from a mirrored cube (corners permuted) decides alike.
        let mut m = [1.0f32; 8];
        m[4] = w[3];
        m[5] = w[2];
        m[6] = w[1];
        m[7] = w[0];
        assert_eq!(face_resolution(&m, 2), 0);
    }

    fn signed_volume(mesh: &Mesh) -> f64 {
        mesh.triangles()
            .map(|t| {
                let [a, b, c] = t.map(|i| DVec3::from(mesh.positions[i as usize].map(f64::from)));
                a.dot(b.cross(c)) / 6.0
            })
            .sum()
    }

    #[test]
    fn sphere_is_closed_manifold_outward_genus_zero_and_accurate() {
        let sphere = Sphere::new(Vec3::ZERO, 0.8);
        for n in [16, 23, 32, 48] {
            let grid = Grid::cube(n, 1.0);
            let (mesh, stats) = run(&sphere, grid, 2);
            let r = rmt_mesh::validate(&mesh, &|p| on_box_boundary(&grid, p));
            assert!(r.is_watertight_manifold(), "n={n}: {r:?}");
            assert_eq!(r.boundary_edges_on_box, 0, "n={n}");
            assert_eq!(r.orientation_errors, 0, "n={n}");
            assert_eq!(r.euler, 2, "n={n}: {r:?}");
            assert_eq!(r.components, 1, "n={n}");
            assert_eq!(r.unreferenced_vertices, 0, "n={n}");
            let volume = signed_volume(&mesh);
            let want_volume = 4.0 / 3.0 * std::f64::consts::PI * 0.512;
            assert!(
                volume > 0.0 && (volume - want_volume).abs() / want_volume < 0.05,
                "n={n}: volume {volume}: normals must face out"
            );
            assert_eq!(stats.crossings, mesh.vertex_count());
            assert_eq!(stats.tetrahedra_total, 0);
            assert_eq!(stats.edges, 3 * n * (n + 1) * (n + 1));
            assert!(stats.tetrahedra_processed > 0 && stats.tetrahedra_processed < n * n * n);
            if n == 48 {
                let want = 4.0 * std::f64::consts::PI * 0.64;
                let area = mesh.area();
                assert!((area - want).abs() / want < 0.02, "area {area} vs {want}");
            }
            // Linear interpolation of a distance along a cube edge errs by at most h^2 / (8 r).
            let bound = grid.h() * grid.h() / (8.0 * 0.8) + 1e-5;
            for p in &mesh.positions {
                let d = sphere.sample(Vec3::from(*p)).abs();
                assert!(d <= bound, "n={n}: vertex {p:?} is {d} off the sphere");
            }
        }
    }

    #[test]
    fn one_vertex_per_crossed_grid_edge() {
        let grid = Grid::new(
            [9, 7, 11],
            Vec3::new(-1.0, -0.9, -1.1),
            Vec3::new(1.0, 0.8, 1.2),
        );
        let field = FnField(|p: Vec3| (p * 3.0).x.sin() + (p * 2.0).y.cos() * 0.7 + p.z * 0.4);
        let (mesh, stats) = run(&field, grid, 1);
        // Count sign changes along grid edges independently.
        let s = grid.spacing();
        let at = |x: usize, y: usize, z: usize| {
            field.sample(grid.min + Vec3::new(x as f32, y as f32, z as f32) * s)
        };
        let [nx, ny, nz] = grid.cells;
        let mut crossed = 0;
        for z in 0..=nz {
            for y in 0..=ny {
                for x in 0..=nx {
                    let v = at(x, y, z) < 0.0;
                    crossed += usize::from(x < nx && v != (at(x + 1, y, z) < 0.0));
                    crossed += usize::from(y < ny && v != (at(x, y + 1, z) < 0.0));
                    crossed += usize::from(z < nz && v != (at(x, y, z + 1) < 0.0));
                }
            }
        }
        assert_eq!(mesh.vertex_count(), crossed);
        assert_eq!(stats.crossings, crossed);
        let distinct: HashSet<[u32; 3]> =
            mesh.positions.iter().map(|p| p.map(f32::to_bits)).collect();
        assert_eq!(
            distinct.len(),
            mesh.vertex_count(),
            "duplicate vertex positions"
        );
        let r = rmt_mesh::validate(&mesh, &|p| on_box_boundary(&grid, p));
        assert!(r.is_watertight_manifold(), "{r:?}");
        assert!(r.boundary_edges_on_box > 0, "this surface leaves the box");
    }

    #[test]
    fn torus_has_euler_characteristic_zero() {
        let torus = Torus {
            centre: Vec3::ZERO,
            major: 0.6,
            minor: 0.25,
        };
        for n in [20, 32, 41] {
            let grid = Grid::cube(n, 1.0);
            let (mesh, _) = run(&torus, grid, 2);
            let r = rmt_mesh::validate(&mesh, &|p| on_box_boundary(&grid, p));
            assert!(r.is_watertight_manifold(), "n={n}: {r:?}");
            assert_eq!(r.euler, 0, "n={n}: {r:?}");
            assert_eq!(r.components, 1, "n={n}");
            assert!(signed_volume(&mesh) > 0.0);
        }
    }

    #[test]
    fn output_is_identical_for_any_thread_count() {
        let field = FnField(|p: Vec3| {
            (p.x * 5.0).sin() * (p.y * 4.0).cos() + (p.z * 6.0).sin() * 0.5 - 0.1
        });
        let grid = Grid::new([23, 17, 31], Vec3::splat(-1.0), Vec3::splat(1.0));
        let (reference, _) = run(&field, grid, 1);
        assert!(reference.triangle_count() > 1000);
        for threads in [2, 3, 4, 7] {
            let (mesh, _) = run(&field, grid, threads);
            assert_eq!(mesh.positions, reference.positions, "{threads} threads");
            assert_eq!(mesh.indices, reference.indices, "{threads} threads");
        }
    }

    /// A small deterministic generator (SplitMix64).
    struct SplitMix(u64);
    impl SplitMix {
        fn next(&mut self) -> u64 {
            self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
            let mut z = self.0;
            z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            z ^ (z >> 31)
        }
        fn unit(&mut self) -> f32 {
            (self.next() >> 40) as f32 / (1u64 << 24) as f32
        }
    }

    /// Extracts pre-sampled values (so exact zeros and white noise can be planted).
    fn run_values(grid: Grid, fill: impl Fn(Vec3, usize) -> f32) -> Mesh {
        let s = settings(grid, 2);
        let mut extractor = Extractor::new();
        extractor.samples_mut().prepare(&s);
        let samples = extractor.samples_mut();
        let [nx, ny, nz] = grid.cells;
        for z in 0..=nz {
            for y in 0..=ny {
                for x in 0..=nx {
                    let i = samples.simple_index(x, y, z);
                    let p = samples.simple_position(x, y, z);
                    samples.values[i] = fill(p, i);
                }
            }
        }
        let mut mesh = Mesh::default();
        extractor.extract_presampled(&s, &mut mesh).unwrap();
        mesh
    }

    fn assert_closed(grid: &Grid, mesh: &Mesh, what: &str) {
        let r = rmt_mesh::validate(mesh, &|p| on_box_boundary(grid, p));
        assert!(r.is_watertight_manifold(), "{what}: {r:?}");
        assert_eq!(r.boundary_edges_interior, 0, "{what}");
    }

    #[test]
    fn array_order_is_the_world_order_mesh_reordered_bit_for_bit() {
        // White noise (many ambiguous faces, so loop centres too) on anisotropic grids, area
        // normals; and a field with gradient normals. Positions and normals reversed, the last
        // two corners of every triangle swapped, nothing else different.
        let rev = |v: &[[f32; 3]]| v.iter().map(|p| [p[2], p[1], p[0]]).collect::<Vec<_>>();
        let swap = |i: &[u32]| {
            i.chunks(3)
                .flat_map(|t| [t[0], t[2], t[1]])
                .collect::<Vec<_>>()
        };
        let mut centres = 0;
        for seed in 0..12u64 {
            let mut rng = SplitMix(seed);
            let cells = [5 + seed as usize % 4, 4 + seed as usize % 3, 6];
            let len = (cells[0] + 1) * (cells[1] + 1) * (cells[2] + 1);
            let values: Vec<f32> = (0..len).map(|_| rng.unit() * 2.0 - 1.0).collect();
            let grid = Grid::new(cells, Vec3::new(-1.0, -0.5, 0.0), Vec3::new(1.0, 0.7, 2.5));
            let mut s = settings(grid, 1 + seed as usize % 2);
            s.normals = crate::NormalMode::AreaWeighted;
            let (mut world, mut array) = (Mesh::default(), Mesh::default());
            let mut ex = Extractor::new();
            let stats = ex.extract_borrowed(&values, &s, &mut world).unwrap();
            ex.set_array_order(true);
            ex.extract_borrowed(&values, &s, &mut array).unwrap();
            centres += world.positions.len() - stats.crossings;
            assert_eq!(rev(&array.positions), world.positions, "seed {seed}");
            assert_eq!(swap(&array.indices), world.indices, "seed {seed}");
            assert_eq!(rev(&array.normals), world.normals, "seed {seed}");
            assert!(!world.normals.is_empty());
        }
        assert!(centres > 0, "no loop centre was made");
        let sphere = Sphere::new(Vec3::new(0.1, -0.2, 0.05), 0.7);
        let mut s = settings(
            Grid::new([13, 17, 11], Vec3::splat(-1.0), Vec3::splat(1.0)),
            2,
        );
        s.normals = crate::NormalMode::Gradient;
        let (mut world, mut array) = (Mesh::default(), Mesh::default());
        let mut ex = Extractor::new();
        ex.extract(&sphere, &s, &mut world).unwrap();
        ex.set_array_order(true);
        ex.extract(&sphere, &s, &mut array).unwrap();
        assert_eq!(rev(&array.positions), world.positions);
        assert_eq!(swap(&array.indices), world.indices);
        assert_eq!(rev(&array.normals), world.normals);
        assert!(!world.normals.is_empty());
    }

    #[test]
    fn white_noise_with_many_ambiguous_faces_stays_closed() {
        for seed in 0..40u64 {
            let mut rng = SplitMix(seed);
            let n = 4 + (seed % 5) as usize;
            let values: Vec<f32> = (0..(n + 1).pow(3))
                .map(|_| rng.unit() * 2.0 - 1.0)
                .collect();
            let grid = Grid::cube(n, 1.0);
            let mesh = run_values(grid, |_, i| values[i]);
            assert_closed(&grid, &mesh, &format!("seed {seed}"));
        }
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(64))]
        #[test]
        fn random_smooth_fields_with_exact_zeros_give_closed_manifold_meshes(seed in 0u64..u64::MAX, n in 5usize..14, zeros in 0usize..40) {
            let mut rng = SplitMix(seed);
            let bumps: Vec<(Vec3, f32, f32)> = (0..5)
                .map(|_| {
                    let c = Vec3::new(rng.unit(), rng.unit(), rng.unit()) * 1.6 - 0.8;
                    (c, 0.2 + rng.unit() * 0.5, rng.unit() * 2.0 - 0.5)
                })
                .collect();
            let freq = Vec3::new(rng.unit(), rng.unit(), rng.unit()) * 8.0;
            let amp = rng.unit() * 0.4;
            let field = move |p: Vec3| {
                let g: f32 = bumps.iter().map(|(c, s, a)| a * (-(p - *c).length_squared() / (s * s)).exp()).sum();
                0.3 - g + amp * (p.x * freq.x).sin() * (p.y * freq.y).cos() * (p.z * freq.z + 0.3).sin()
            };
            let total = (n + 1).pow(3);
            let zero_at: HashSet<usize> = (0..zeros).map(|_| (rng.next() % total as u64) as usize).collect();
            let grid = Grid::cube(n, 1.0);
            let mesh = run_values(grid, |p, i| if zero_at.contains(&i) { 0.0 } else { field(p) });
            assert_closed(&grid, &mesh, &format!("seed {seed} n {n} zeros {zeros}"));
        }
    }
}
