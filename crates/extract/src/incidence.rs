//! Every vertex's triangles as a CSR table (`inc[inc_start[v]..inc_start[v + 1]]`), serial
//! ([`incidence`]) or in parallel with the same result ([`incidence_parallel`]).
//!
//! Integrated clustering reads the stars of its quotient tests from the table over plain MT's
//! triangles ([`crate::mt`]); the mesh-based merge of edge collapse ([`crate::post::merge`]) builds
//! one over the mesh it simplifies.
//!
//! ```text
//!   triangles  t0=(a,b,c) t1=(b,c,d) ...      counts -> prefix sums -> inc_start
//!   inc        [ a: t0 | b: t0 t1 | c: t0 t1 | d: t1 ... ]   (each vertex's in triangle order)
//! ```

/// Every vertex's triangles as a CSR table (`inc[start[v]..start[v + 1]]`) and the working
/// memory of its parallel fill, kept between extractions.
#[derive(Default)]
pub(crate) struct Incidence {
    pub(crate) start: Vec<u32>,
    pub(crate) inc: Vec<u32>,
    /// Fill cursors.
    cursor: Vec<u32>,
    /// Per part of the triangle list, its counts and then its cursors.
    parts: Vec<Vec<u32>>,
    /// Per part, how far below its first corner's id its lowest id lay the last time (where
    /// its counting window starts).
    below: Vec<usize>,
}

impl Incidence {
    /// Bytes held.
    pub(crate) fn bytes(&self) -> usize {
        (self.start.len() + self.inc.len() + self.cursor.len()) * 4
            + self.parts.iter().map(|p| p.len() * 4).sum::<usize>()
    }
}

/// Every vertex's triangles as a CSR table: `inc[inc_start[v]..inc_start[v + 1]]` lists the
/// triangles of `indices` (three per triangle) holding vertex `v`, in triangle order.
/// `cursor` is working memory (left with `vertex_count` entries, whose values the callers do
/// not read).
///
/// The counts go two places up (`inc_start[v + 2]`), so that after their prefix sums
/// `inc_start[v + 1]` is where `v`'s triangles start: the fill's cursor, which it leaves where
/// they end, at `v + 1`'s start. No separate cursor array is copied or read, and `inc` is not
/// cleared first (every slot is written).
pub(crate) fn incidence(
    vertex_count: usize,
    indices: &[u32],
    inc_start: &mut Vec<u32>,
    inc: &mut Vec<u32>,
    cursor: &mut Vec<u32>,
) {
    let corners = &indices[..indices.len() - indices.len() % 3];
    inc_start.clear();
    inc_start.resize(vertex_count + 2, 0);
    for &v in corners {
        inc_start[v as usize + 2] += 1;
    }
    let mut sum = 0;
    for s in &mut inc_start[2..] {
        sum += *s;
        *s = sum;
    }
    inc.truncate(corners.len());
    inc.resize(corners.len(), 0);
    for (t, tri) in corners.chunks_exact(3).enumerate() {
        for &v in tri {
            let c = &mut inc_start[v as usize + 1];
            inc[*c as usize] = t as u32;
            *c += 1;
        }
    }
    inc_start.truncate(vertex_count + 1);
    cursor.clear();
    cursor.resize(vertex_count, 0);
}

/// [`incidence`] on `pool`'s threads into `table`: the same table, bit for bit, for any thread
/// count.
///
/// The list is cut into parts of consecutive triangles. Each part counts its corners over the
/// range of ids it touches (`parts[p]`). Then, in parallel over blocks of ids (as Flying Edges
/// sums its rows), the parts' counts add up to each id's count, in part order, and each part's
/// counts become its cursors relative to the id's start (the earlier parts' triangles there);
/// the counts' prefix sums, block by block and then across the blocks, give `inc_start`; the
/// parts add it to their cursors and fill `inc` in parallel. Every (vertex, triangle) pair has
/// its own place, so the parts never write the same slot, and each vertex's triangles come in
/// triangle order. The steps over the ids cost the sum of the parts' id ranges: meant for
/// lists whose nearby triangles have nearby ids (plain MT's, listed layer by layer, with ids
/// in storage order); when the ranges add up to more than four times the vertex count, it
/// falls back to [`incidence`].
pub(crate) fn incidence_parallel(
    vertex_count: usize,
    indices: &[u32],
    table: &mut Incidence,
    pool: &rayon::ThreadPool,
) {
    let Incidence {
        start: inc_start,
        inc,
        cursor,
        parts,
        below,
    } = table;
    use rayon::prelude::*;
    let tris = indices.len() / 3;
    let count = 4 * pool.current_num_threads();
    if count <= 4 || tris < 4096 {
        return incidence(vertex_count, indices, inc_start, inc, cursor);
    }
    let bounds: Vec<usize> = (0..=count).map(|p| tris * p / count).collect();
    parts.resize_with(count, Vec::new);
    below.resize(count, 0);
    // Each part's id range and its counts over it.
    let los: Vec<usize> = pool.install(|| {
        parts
            .par_iter_mut()
            .zip(below.par_iter_mut())
            .enumerate()
            .map(|(p, (counts, below))| {
                count_ids(&indices[3 * bounds[p]..3 * bounds[p + 1]], counts, below)
            })
            .collect()
    });
    let spans: usize = parts.iter().map(Vec::len).sum();
    if spans > 4 * vertex_count.max(1)
        || los
            .iter()
            .zip(parts.iter())
            .any(|(&lo, c)| lo + c.len() > vertex_count)
    {
        return incidence(vertex_count, indices, inc_start, inc, cursor);
    }
    // Per block of ids, in parallel: each id's count (summed over the parts, in part order)
    // and, in each part's counts, the triangles of the earlier parts at that id (the part's
    // cursor, relative to the id's start); then the counts' prefix sums, block by block.
    let blocks = vertex_count.div_ceil(BLOCK);
    let mut pieces: Vec<Vec<(usize, &mut [u32])>> = (0..blocks).map(|_| Vec::new()).collect();
    for (&lo, counts) in los.iter().zip(parts.iter_mut()) {
        let (mut v, mut rest) = (lo, &mut counts[..]);
        while !rest.is_empty() {
            let end = ((v / BLOCK + 1) * BLOCK).min(v + rest.len());
            let (head, tail) = rest.split_at_mut(end - v);
            pieces[v / BLOCK].push((v, head));
            (v, rest) = (end, tail);
        }
    }
    crate::util::overwritten(inc_start, vertex_count + 1, 0, pool);
    inc_start[0] = 0;
    let sums: Vec<u32> = pool.install(|| {
        inc_start[1..]
            .par_chunks_mut(BLOCK)
            .zip(pieces.par_iter_mut())
            .enumerate()
            .map(|(b, (ends, pieces))| {
                let first = b * BLOCK;
                ends.fill(0);
                for (v, counts) in pieces.iter_mut() {
                    let at = &mut ends[*v - first..*v - first + counts.len()];
                    for (c, total) in counts.iter_mut().zip(at) {
                        let n = *c;
                        *c = *total;
                        *total += n;
                    }
                }
                let mut sum = 0;
                for e in ends.iter_mut() {
                    sum += *e;
                    *e = sum;
                }
                sum
            })
            .collect()
    });
    drop(pieces);
    // Left with one entry per vertex, as [`incidence`] leaves it (its bytes are counted).
    crate::util::overwritten(cursor, vertex_count, 0, pool);
    // Each block's offset: the blocks before it.
    let offsets: Vec<u32> = sums
        .iter()
        .scan(0, |acc, &n| {
            let at = *acc;
            *acc += n;
            Some(at)
        })
        .collect();
    pool.install(|| {
        inc_start[1..]
            .par_chunks_mut(BLOCK)
            .zip(offsets.par_iter())
            .skip(1)
            .for_each(|(ends, &offset)| ends.iter_mut().for_each(|e| *e += offset))
    });
    // Every slot is written below: a reused table is not cleared first.
    crate::util::overwritten(inc, indices.len() - indices.len() % 3, 0, pool);
    let out = SharedSlots {
        ptr: inc.as_mut_ptr(),
        len: inc.len(),
    };
    let out = &out;
    let inc_start = &*inc_start;
    pool.install(|| {
        parts
            .par_iter_mut()
            .zip(los.par_iter())
            .enumerate()
            .for_each(|(p, (cursors, &lo))| {
                // A copy of the slots: its pointer and length held in registers in the loop.
                let out = *out;
                // The part's cursors: relative to each id's start until here.
                for (c, &at) in cursors.iter_mut().zip(&inc_start[lo..]) {
                    *c += at;
                }
                let tris = indices[3 * bounds[p]..3 * bounds[p + 1]].chunks_exact(3);
                for (t, tri) in (bounds[p] as u32..).zip(tris) {
                    for &v in tri {
                        let c = &mut cursors[v as usize - lo];
                        out.write(*c as usize, t);
                        *c += 1;
                    }
                }
            })
    });
}

/// The corners of each id from the lowest to the highest in `corners` (not empty) into
/// `counts`; returns the lowest. One pass while the ids fall in a window as wide as `counts`
/// held before, from `below` (and a little more) below the first corner's id: where the lowest
/// id lay the last time (a part's ids lie near each other, and a reused table allocates
/// nothing). At the first id outside it, the counts start over on the ids' exact range (two
/// more passes, in the table's memory when it is large enough, which then keeps a margin for
/// the next window). The counts are trimmed to the ids present at the end, and `below` set for
/// the next time.
fn count_ids(corners: &[u32], counts: &mut Vec<u32>, below: &mut usize) -> usize {
    let width = counts.capacity().max(64);
    let first_id = corners[0] as usize;
    let lo = first_id.saturating_sub(*below + width / 64);
    counts.clear();
    counts.resize(width, 0);
    let mut fits = true;
    for &v in corners {
        let i = (v as usize).wrapping_sub(lo);
        if i >= counts.len() {
            fits = false;
            break;
        }
        counts[i] += 1;
    }
    let lo = if fits {
        lo
    } else {
        let (min, max) = corners
            .iter()
            .fold((u32::MAX, 0), |(lo, hi), &v| (lo.min(v), hi.max(v)));
        let (min, max) = (min as usize, max as usize);
        counts.clear();
        // Room for the window of the next time: the range and a margin either side.
        counts.reserve(max + 1 - min + (max + 1 - min) / 16);
        counts.resize(max + 1 - min, 0);
        for &v in corners {
            counts[v as usize - min] += 1;
        }
        min
    };
    let first = counts.iter().position(|&c| c != 0).unwrap_or(0);
    let last = counts.iter().rposition(|&c| c != 0).unwrap_or(0);
    counts.truncate(last + 1);
    counts.drain(..first);
    *below = first_id - (lo + first);
    lo + first
}

/// Ids per block of the parallel steps of [`incidence_parallel`] that run over the ids.
const BLOCK: usize = 1 << 12;

/// Slots of a `u32` slice that threads write in parallel, each slot by one writer only
/// ([`incidence_parallel`]: every (vertex, triangle) pair has its own slot).
#[derive(Clone, Copy)]
struct SharedSlots {
    ptr: *mut u32,
    len: usize,
}

// SAFETY: the slots are written through `write` only, each by one thread (see `SharedSlots`),
// while the slice they point into is borrowed mutably by the function that made them.
unsafe impl Sync for SharedSlots {}

impl SharedSlots {
    /// Writes `value` to slot `i` (ignored past the end, which the cursors never reach).
    #[inline(always)]
    fn write(&self, i: usize, value: u32) {
        if i < self.len {
            // SAFETY: `i` is in bounds, and no other thread writes or reads slot `i` while the
            // slots are shared (each slot belongs to one (vertex, triangle) pair).
            unsafe { *self.ptr.add(i) = value };
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A triangle list of `tris` triangles over `n` vertices: local (each triangle's ids within
    /// `spread` of a point that moves along the list) or not.
    fn triangle_list(tris: usize, n: usize, spread: usize, seed: u64) -> Vec<u32> {
        let mut state = seed;
        let mut next = move || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 33) as usize
        };
        (0..tris)
            .flat_map(|t| {
                let centre = t * n / tris;
                let mut corner = || {
                    let lo = centre.saturating_sub(spread);
                    (lo + next() % (2 * spread + 1)).min(n - 1) as u32
                };
                [corner(), corner(), corner()]
            })
            .collect()
    }

    #[test]
    fn ids_are_counted_from_the_lowest_to_the_highest() {
        // Ids below and above the first one's window, far and near, repeated.
        for corners in [
            vec![5u32],
            vec![9, 9, 9],
            vec![100, 3, 250, 100, 7_000, 0, 4_000_000, 99],
            vec![50_000, 49_999, 50_001, 1, 50_000],
            (0..3000u32).map(|i| (i * 7919) % 4001 + 20).collect(),
        ] {
            let (mut counts, mut below) = (vec![1, 2, 3], 2);
            let lo = count_ids(&corners, &mut counts, &mut below);
            assert_eq!(below, corners[0] as usize - lo, "{corners:?}");
            let (min, max) = (corners.iter().min(), corners.iter().max());
            let (min, max) = (*min.unwrap_or(&0) as usize, *max.unwrap_or(&0) as usize);
            assert_eq!(lo, min, "{corners:?}");
            assert_eq!(counts.len(), max - min + 1, "{corners:?}");
            for (k, &c) in counts.iter().enumerate() {
                let n = corners.iter().filter(|&&v| v as usize == lo + k).count();
                assert_eq!(c as usize, n, "id {}", lo + k);
            }
        }
    }

    #[test]
    fn parallel_incidence_equals_the_serial_table_for_any_thread_count() {
        for (tris, n, spread) in [(20_000, 9_000, 40), (20_000, 9_000, 9_000), (5_000, 3, 1)] {
            let indices = triangle_list(tris, n, spread, tris as u64 + spread as u64);
            let (mut start, mut inc, mut cursor) = (Vec::new(), Vec::new(), Vec::new());
            incidence(n, &indices, &mut start, &mut inc, &mut cursor);
            for threads in [1, 2, 3, 5] {
                let pool = rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .expect("a thread pool");
                let mut table = Incidence {
                    start: vec![7],
                    inc: vec![7],
                    ..Incidence::default()
                };
                incidence_parallel(n, &indices, &mut table, &pool);
                let (s2, i2) = (table.start, table.inc);
                assert_eq!(
                    s2, start,
                    "starts: {tris} triangles, spread {spread}, {threads} threads"
                );
                assert_eq!(
                    i2, inc,
                    "table: {tris} triangles, spread {spread}, {threads} threads"
                );
            }
        }
    }
}
