//! Clustering between the vertex pass and the emission: the proposals become groups, and each
//! crossing gets its output vertex.
//!
//! The proposals are a partition of the crossings into groups ([`proposal`]: a point's
//! islands, each sheet's own crossings cut into parts joined by mesh edges; with integrated
//! clustering also the lone crossings, given to a neighbouring island). Integrated clustering
//! then lists plain MT's triangles once ([`plain::plain_triangles`]), keeps the groups
//! that pass the exact quotient test, repairing failures by splitting groups in parallel rounds,
//! and settles its additions the same way ([`quotient`], [`repair`],
//! [`additions`]); integrated-unchecked keeps every proposal and numbers its vertices
//! plane by plane, with no group tables ([`keep_all`]). Every crossing then maps to an output
//! vertex: its group's (the mean of its crossings) or its own.
//!
//! ```text
//!   proposals -> group tables -> plain triangles -> settle islands -> variants -> lone passes
//!             -> sliver passes -> output vertices (one per kept group or lone crossing)
//! ```

use rayon::prelude::*;

use super::crossings::CrossedIndex;
use super::geometry::Surface;
use super::layout::Layout;
use crate::util::{filled, for_each_bit, overwritten};
use crate::{Clustering, Stats};

pub(crate) mod additions;
pub(crate) mod plain;
pub(crate) mod proposal;
pub(crate) mod quotient;
pub(crate) mod repair;

use plain::{plain_triangles, PlainList};
use proposal::Candidate;
use quotient::{Fixed, Groups, Quotient};
use repair::{settle, Phase, Settled};

/// The clustering's tables, kept between extractions.
#[derive(Default)]
pub(crate) struct ClusterBuffers {
    /// Proposed groups, in storage order of their owners (written by the vertex pass), then
    /// the variants and sliver pairs the additions append.
    pub(crate) candidates: Vec<Candidate>,
    /// Positions of the crossings (plain MT's vertices).
    pub(crate) cpos: Vec<[f32; 3]>,
    /// The groups' state: kept or not, each crossing's group, lone crossings, labels and
    /// vertex positions.
    pub(crate) groups: Groups,
    /// Every crossing's owner slot and edge (the direction from the owner).
    pub(crate) edge_of: Vec<(u32, u8)>,
    /// Plain MT's triangles and every crossing's triangles (checked clustering): the stars of
    /// the quotient test.
    pub(crate) plain: PlainList,
    /// Output vertex of each crossing.
    pub(crate) vertex_of: Vec<u32>,
    /// Recorded: the lattice points (grid-local lattice coordinates) whose crossings the
    /// clustering touched after its proposals, sorted, each once.
    pub(crate) activity: Vec<[i32; 3]>,
}

impl ClusterBuffers {
    /// Bytes of the tables (the recorded activity aside).
    pub(crate) fn bytes(&self) -> usize {
        self.candidates.len() * std::mem::size_of::<Candidate>()
            + self.cpos.len() * 12
            + self.groups.bytes()
            + self.edge_of.len() * 8
            + self.plain.bytes()
            + self.vertex_of.len() * 4
    }
}

/// What every step of integrated clustering reads besides the tables.
struct Steps<'a> {
    layout: &'a Layout<'a>,
    /// Record the clustering's activity.
    record: bool,
    pool: &'a rayon::ThreadPool,
}

/// Passes of lone crossings after the islands settle (each: give, then test and repair).
pub(crate) const LONE_PASSES: usize = 3;

/// Passes over the slivers left after the lone passes (each: propose, then test and repair).
pub(crate) const SLIVER_PASSES: usize = 2;

/// The group tables of the proposals in `buf.candidates` (owned by the points of `crossed`),
/// every group kept: each crossing's
/// group, each group's leader (lowest crossing id) and vertex position (the mean of its
/// crossings), and empty lone tables; also what the additions read: every crossing's owner
/// slot and edge (`buf.edge_of`) and the groups that gave it back
/// ([`quotient::Groups::refused`]). Integrated clustering only: integrated-unchecked
/// numbers its vertices without group tables ([`keep_all`]).
pub(crate) fn build_groups(
    buf: &mut ClusterBuffers,
    crossed: &CrossedIndex,
    layout: &Layout,
    pool: &rayon::ThreadPool,
) {
    use quotient::NONE;
    let crossings = buf.cpos.len();
    let ClusterBuffers {
        candidates,
        cpos,
        groups: g,
        edge_of,
        ..
    } = buf;
    let count = candidates.len();
    // Ids are numbered plane by plane: a plane's first id is the `first` of its first crossed
    // point (or of the next plane's, when it has none), so each plane fills its own slice; the
    // proposals come in the order of their owners, so each plane's are one range too.
    let planes = layout.s.dims[2];
    let starts = plane_id_starts(crossed, planes, crossings);
    let cand_starts: Vec<usize> = starts
        .iter()
        .map(|&s| candidates.partition_point(|c| (c.first as usize) < s))
        .collect();
    overwritten(&mut g.group_of, crossings, NONE, pool);
    let mut parts = Vec::with_capacity(planes);
    let mut rest = &mut g.group_of[..];
    for z in 0..planes {
        let (head, tail) = rest.split_at_mut(starts[z + 1] - starts[z]);
        parts.push(head);
        rest = tail;
    }
    let candidates_ref = &*candidates;
    pool.install(|| {
        parts.into_par_iter().enumerate().for_each(|(z, out)| {
            out.fill(NONE);
            let first = cand_starts[z];
            for (k, c) in candidates_ref[first..cand_starts[z + 1]].iter().enumerate() {
                for id in c.ids() {
                    out[id as usize - starts[z]] = (first + k) as u32;
                }
            }
        })
    });
    let cpos = &*cpos;
    pool.install(|| {
        candidates
            .par_iter()
            .map(|&c| mean_position(c, cpos))
            .collect_into_vec(&mut g.centroid)
    });
    pool.install(|| {
        candidates
            .par_iter()
            .map(|c| c.leader())
            .collect_into_vec(&mut g.leader)
    });
    filled(&mut g.active, count, 1, pool);
    g.lone.clear();
    filled(&mut g.lone_start, count + 1, 0, pool);
    filled(&mut g.lone_len, count, 0, pool);
    filled(&mut g.base_len, count, 0, pool);
    g.touched.clear();
    filled(&mut g.refused, crossings, NONE, pool);
    // Every crossing's edge: plane by plane, points in slot order, edges in bit order, which
    // is the order of the ids.
    let plane = layout.s.dims[0] * layout.s.dims[1];
    overwritten(edge_of, crossings, (0, 0), pool);
    let mut parts = Vec::with_capacity(planes);
    let mut rest = &mut edge_of[..];
    for z in 0..planes {
        let (head, tail) = rest.split_at_mut(starts[z + 1] - starts[z]);
        parts.push(head);
        rest = tail;
    }
    pool.install(|| {
        parts.into_par_iter().enumerate().for_each(|(z, out)| {
            let mut r = crossed.rank_in(z, 0);
            let mut k = 0;
            for_each_bit(crossed.plane_bits(z), 0, plane, |local| {
                let entry = crossed.points[r];
                r += 1;
                let mut own = entry.owned;
                while own != 0 {
                    out[k] = ((z * plane + local) as u32, own.trailing_zeros() as u8);
                    k += 1;
                    own &= own - 1;
                }
            });
            debug_assert_eq!(k, out.len());
        })
    });
}

/// The clustering steps between the vertex pass and the emission: with integrated-unchecked,
/// the numbering of the proposals ([`keep_all`]); with integrated (checked) clustering the
/// group tables, plain MT's triangle list ([`plain`]), the islands' quotient tests and repair
/// ([`repair`]), then the additions ([`additions`]). At the end every crossing's output vertex
/// (`buf.vertex_of`) and the vertex positions (`positions`; the crossings' own, there on entry,
/// move to `buf.cpos`). Integrated clustering, checked or not, takes no tiles: its chunks are
/// exact without them ([`crate::ExtractSettings::check`] refuses the combination). With
/// `record`, the activity too (`buf.activity`). Returns the tetrahedra that the triangle list
/// read (0 without it).
pub(crate) fn run(
    surface: &Surface,
    clustering: Clustering,
    record: bool,
    buf: &mut ClusterBuffers,
    positions: &mut Vec<[f32; 3]>,
    pool: &rayon::ThreadPool,
    stats: &mut Stats,
) -> usize {
    let layout = surface.l;
    // The crossings' positions move to `cpos`; the mesh gets the clustered vertices.
    std::mem::swap(positions, &mut buf.cpos);
    let step = std::time::Instant::now();
    if clustering == Clustering::IntegratedUnchecked {
        // Every proposal is kept: no group tables, no tests.
        keep_all(buf, surface.crossed, layout, positions, pool);
        buf.plain.clear();
        stats.lone_absorbed = 0;
        stats.clusters_committed = buf.candidates.len();
        stats.clusters_rejected_check = 0;
        stats.t_vertices_s += step.elapsed().as_secs_f64();
        return 0;
    }
    build_groups(buf, surface.crossed, layout, pool);
    let mut islands = buf.candidates.len();
    // Plain MT's triangles and every crossing's triangles: the stars of the tests.
    let plain_processed = plain_triangles(surface, &buf.cpos, record, &mut buf.plain, pool);
    // The groups' state changes while the fixed tables (in `buf`) are read.
    let mut groups = std::mem::take(&mut buf.groups);
    let s = Steps {
        layout,
        record,
        pool,
    };
    settle_islands(&s, buf, &mut groups, islands, step, stats);
    let variant_of = add_variants(&s, buf, &mut groups, islands, stats);
    revive_and_give_lones(&s, buf, &mut groups, &variant_of, stats);
    islands += sliver_passes(&s, buf, &mut groups, stats);
    if record {
        activity_points(layout, &groups.touched, &buf.edge_of, &mut buf.activity);
    }
    buf.groups = groups;
    let step = std::time::Instant::now();
    let groups = &buf.groups;
    stats.lone_absorbed = (0..buf.candidates.len())
        .filter(|&gi| groups.active[gi] != 0)
        .map(|gi| usize::from(groups.lone_len[gi]))
        .sum();
    let mut vertex_of = std::mem::take(&mut buf.vertex_of);
    let fixed = fixed(buf, layout);
    let q = Quotient::new(&fixed, groups);
    vertex_map(&q, &mut vertex_of, positions, pool);
    // An island is kept whole, or as one of its variants (at most one of them is kept).
    stats.clusters_committed = groups.active.iter().filter(|&&a| a != 0).count();
    stats.clusters_rejected_check = islands - stats.clusters_committed;
    stats.t_vertices_s += step.elapsed().as_secs_f64();
    buf.vertex_of = vertex_of;
    plain_processed
}

/// Integrated-unchecked, every proposal kept: each crossing's output vertex (`buf.vertex_of`)
/// and the vertex positions, numbered as [`vertex_map`] numbers them (in crossing order, a
/// group where its leader comes), but plane by plane in parallel. A proposal's crossings are
/// its owner's, so they all lie in the owner's storage plane, whose crossing ids are one range:
///
/// ```text
///   plane z:   ids starts[z] .. starts[z+1]     proposals with `first` in that range
///   count:     new vertices = crossings - sum over its proposals of (size - 1)
///   prefix:    plane z's vertices start at the sum of the counts below it
///   fill:      vertex_of and positions, slice by slice: runs of crossings in no proposal are
///              copied; an owner with proposals is numbered by the ranks of its crossings
/// ```
///
/// The group tables are left empty.
pub(crate) fn keep_all(
    buf: &mut ClusterBuffers,
    crossed: &CrossedIndex,
    layout: &Layout,
    positions: &mut Vec<[f32; 3]>,
    pool: &rayon::ThreadPool,
) {
    let crossings = buf.cpos.len();
    let planes = layout.s.dims[2];
    let starts = plane_id_starts(crossed, planes, crossings);
    let candidates = &buf.candidates[..];
    // Proposals come in the order of their owners (by `first`): each plane's are one range.
    let cand_starts: Vec<usize> = starts
        .iter()
        .map(|&s| candidates.partition_point(|c| (c.first as usize) < s))
        .collect();
    let counts: Vec<usize> = pool.install(|| {
        (0..planes)
            .into_par_iter()
            .map(|z| {
                let merged: usize = candidates[cand_starts[z]..cand_starts[z + 1]]
                    .iter()
                    .map(|c| c.size() as usize - 1)
                    .sum();
                starts[z + 1] - starts[z] - merged
            })
            .collect()
    });
    // Where each plane's vertices start, and their number at the end.
    let vstarts: Vec<usize> = std::iter::once(0)
        .chain(counts.iter().scan(0, |acc, &n| {
            *acc += n;
            Some(*acc)
        }))
        .collect();
    let vertices = vstarts[planes];
    buf.groups.clear();
    buf.edge_of.clear();
    overwritten(&mut buf.vertex_of, crossings, 0, pool);
    overwritten(positions, vertices, [0.0; 3], pool);
    // Each plane's slices of the two outputs.
    let mut parts = Vec::with_capacity(planes);
    let (mut rest_v, mut rest_p) = (&mut buf.vertex_of[..], &mut positions[..]);
    for z in 0..planes {
        let (hv, tv) = rest_v.split_at_mut(starts[z + 1] - starts[z]);
        let (hp, tp) = rest_p.split_at_mut(counts[z]);
        parts.push((hv, hp));
        (rest_v, rest_p) = (tv, tp);
    }
    let cpos = &buf.cpos[..];
    pool.install(|| {
        parts
            .into_par_iter()
            .enumerate()
            .for_each(|(z, (vertex_of, out))| {
                let (base, end) = (starts[z], starts[z + 1]);
                let first_vertex = vstarts[z] as u32;
                let mut next = 0usize;
                // Crossings `from..to` (ids) that are in no proposal: a vertex each.
                let singles = |from: usize,
                               to: usize,
                               next: &mut usize,
                               vertex_of: &mut [u32],
                               out: &mut [[f32; 3]]| {
                    out[*next..*next + to - from].copy_from_slice(&cpos[from..to]);
                    for (k, v) in vertex_of[from - base..to - base].iter_mut().enumerate() {
                        *v = first_vertex + (*next + k) as u32;
                    }
                    *next += to - from;
                };
                let (mut x, mut h) = (base, cand_starts[z]);
                while h < cand_starts[z + 1] {
                    // One owner's proposals (the same `first`), its crossings by rank.
                    let f = candidates[h].first as usize;
                    singles(x, f, &mut next, vertex_of, out);
                    let mut which = [u8::MAX; 16];
                    let mut e = h;
                    let mut union = 0u16;
                    while e < cand_starts[z + 1] && candidates[e].first as usize == f {
                        let mut m = candidates[e].members;
                        union |= m;
                        while m != 0 {
                            which[m.trailing_zeros() as usize] = (e - h) as u8;
                            m &= m - 1;
                        }
                        e += 1;
                    }
                    for (r, &k) in which
                        .iter()
                        .enumerate()
                        .take(16 - union.leading_zeros() as usize)
                    {
                        let id = f + r;
                        if k == u8::MAX {
                            singles(id, id + 1, &mut next, vertex_of, out);
                            continue;
                        }
                        let c = candidates[h + k as usize];
                        let leader = c.leader() as usize;
                        if leader != id {
                            // The leader has the lowest id of the group: numbered already.
                            vertex_of[id - base] = vertex_of[leader - base];
                            continue;
                        }
                        out[next] = mean_position(c, cpos);
                        vertex_of[id - base] = first_vertex + next as u32;
                        next += 1;
                    }
                    x = f + 16 - union.leading_zeros() as usize;
                    h = e;
                }
                singles(x, end, &mut next, vertex_of, out);
                debug_assert_eq!(next, out.len());
            })
    });
}

/// The mean of the positions of proposal `c`'s crossings: its group's vertex.
fn mean_position(c: Candidate, cpos: &[[f32; 3]]) -> [f32; 3] {
    let mut sum = glam::Vec3::ZERO;
    for id in c.ids() {
        sum += glam::Vec3::from(cpos[id as usize]);
    }
    (sum / c.size() as f32).to_array()
}

/// The first crossing id of every storage plane, and the number of crossings at the end: ids
/// are numbered plane by plane, so plane `z`'s are `starts[z]..starts[z + 1]`.
fn plane_id_starts(crossed: &CrossedIndex, planes: usize, crossings: usize) -> Vec<usize> {
    (0..planes)
        .map(|z| {
            let r = crossed.rank_in(z, 0);
            crossed
                .points
                .get(r)
                .map_or(crossings, |p| p.first as usize)
        })
        .chain([crossings])
        .collect()
}

/// The fixed tables of the quotient tests, over the candidates as they are now.
fn fixed<'a>(buf: &'a ClusterBuffers, layout: &'a Layout<'a>) -> Fixed<'a> {
    Fixed {
        l: layout,
        cpos: &buf.cpos,
        groups: &buf.candidates,
        tris: &buf.plain.tris,
        source: &buf.plain.source,
        inc_start: &buf.plain.inc.start,
        inc: &buf.plain.inc.inc,
    }
}

/// Adds the timings and rounds of one settling step to `stats`.
fn count(stats: &mut Stats, settled: Settled) {
    stats.repair_rounds += settled.rounds;
    stats.t_tests_s += settled.t_tests_s;
    stats.t_repair_s += settled.t_repair_s;
}

/// The islands: every crossing's quotient vertex, the lone crossings of the proposal (crossings
/// in no island join a neighbouring one), then the quotient tests and repair rounds of all
/// `islands`. The group tables' time, from `step` on, counts until the tests start.
fn settle_islands(
    s: &Steps,
    buf: &ClusterBuffers,
    groups: &mut Groups,
    islands: usize,
    step: std::time::Instant,
    stats: &mut Stats,
) {
    let pool = s.pool;
    let fixed = fixed(buf, s.layout);
    groups.relabel(&fixed, pool);
    additions::give_lones(&fixed, groups, &buf.edge_of, false, pool);
    if s.record {
        // The proposals are complete: from here on, what the steps do is activity.
        groups.touched.resize(buf.cpos.len(), 0);
    }
    let len = groups.base_len.len();
    filled(&mut groups.base_len, len, 0, pool);
    stats.t_groups_s += step.elapsed().as_secs_f64();
    let all = (0..islands as u32).collect();
    let settled = settle(&fixed, groups, all, Phase::Islands, pool);
    stats.repair_rounds = 0;
    count(stats, settled);
}

/// Split islands of three or more come back without one crossing: their variants are appended
/// to the candidates (not kept). Returns where each split island's variants start (and, last,
/// where they end).
fn add_variants(
    s: &Steps,
    buf: &mut ClusterBuffers,
    groups: &mut Groups,
    islands: usize,
    stats: &mut Stats,
) -> Vec<u32> {
    let step = std::time::Instant::now();
    let mut variant_of = vec![islands as u32];
    for gi in 0..islands {
        if groups.active[gi] == 0 {
            let c = buf.candidates[gi];
            additions::variants(&c, s.layout.t, &mut buf.candidates);
            variant_of.push(buf.candidates.len() as u32);
        }
    }
    groups.extend_to(buf.candidates.len());
    stats.t_groups_s += step.elapsed().as_secs_f64();
    variant_of
}

/// Each split island takes its first variant that passes; then crossings left alone (in no
/// island, or in one that split) join the nearest kept group, in [`LONE_PASSES`] passes: a group
/// that fails with them gives them back, and they try another group in the next pass.
fn revive_and_give_lones(
    s: &Steps,
    buf: &ClusterBuffers,
    groups: &mut Groups,
    variant_of: &[u32],
    stats: &mut Stats,
) {
    let pool = s.pool;
    let fixed = fixed(buf, s.layout);
    let dirty = additions::revive(&fixed, groups, variant_of, pool);
    let settled = settle(&fixed, groups, dirty, Phase::Islands, pool);
    count(stats, settled);
    let no_new = Phase::Additions {
        born: fixed.groups.len() as u32,
    };
    for _ in 0..LONE_PASSES {
        let step = std::time::Instant::now();
        mark_deciders(&fixed, groups, &buf.edge_of, pool);
        let dirty = additions::give_lones(&fixed, groups, &buf.edge_of, true, pool);
        stats.t_groups_s += step.elapsed().as_secs_f64();
        if dirty.is_empty() {
            break;
        }
        count(stats, settle(&fixed, groups, dirty, no_new, pool));
    }
}

/// Slivers left between the groups, in [`SLIVER_PASSES`] passes: a crossing left alone at one
/// joins the group across its shortest edge, or pairs with the crossing there (a new group,
/// appended to the candidates). Returns the number of pairs proposed.
fn sliver_passes(
    s: &Steps,
    buf: &mut ClusterBuffers,
    groups: &mut Groups,
    stats: &mut Stats,
) -> usize {
    let (layout, pool) = (s.layout, s.pool);
    let mut pairs = 0;
    // A group that gave a crossing back in a lone pass is asked again (see
    // `additions::sliver_proposals`).
    let crossings = groups.refused.len();
    filled(&mut groups.refused, crossings, quotient::NONE, pool);
    for _ in 0..SLIVER_PASSES {
        let step = std::time::Instant::now();
        mark_deciders(&fixed(buf, layout), groups, &buf.edge_of, pool);
        let props = additions::sliver_proposals(&fixed(buf, layout), groups, &buf.edge_of, pool);
        if props.lones.is_empty() && props.pairs.is_empty() {
            break;
        }
        let born = buf.candidates.len();
        for &(x, _) in &props.pairs {
            let (slot, dir) = buf.edge_of[x as usize];
            buf.candidates.push(Candidate {
                first: x,
                members: 1,
                dirs: 1 << dir,
                slot,
            });
        }
        pairs += props.pairs.len();
        stats.clusters_proposed += props.pairs.len();
        let fixed = fixed(buf, layout);
        groups.add_pairs(&fixed, born, &props.pairs);
        let mut dirty = additions::attach(&fixed, groups, props.lones, true, pool);
        let new: Vec<u32> = (born as u32..fixed.groups.len() as u32).collect();
        dirty.extend(additions::around(&fixed, groups, &new, pool));
        dirty.sort_unstable();
        dirty.dedup();
        stats.t_groups_s += step.elapsed().as_secs_f64();
        let phase = Phase::Additions { born: born as u32 };
        count(stats, settle(&fixed, groups, dirty, phase, pool));
    }
    pairs
}

/// Recording the activity: marks every crossing that the next lone or sliver pass considers
/// (an inner crossing in no kept group), whatever it finds.
fn mark_deciders(f: &Fixed, g: &mut Groups, edge_of: &[(u32, u8)], pool: &rayon::ThreadPool) {
    if g.touched.is_empty() {
        return;
    }
    let mut touched = std::mem::take(&mut g.touched);
    let q = Quotient::new(f, g);
    pool.install(|| {
        touched.par_iter_mut().enumerate().for_each(|(x, t)| {
            let (slot, dir) = edge_of[x];
            if q.alone(x as u32) && q.inner(slot as usize, dir) {
                *t = 1;
            }
        })
    });
    g.touched = touched;
}

/// The lattice points (grid-local lattice coordinates) of the crossings `touched` marks,
/// sorted, each once.
fn activity_points(
    layout: &Layout,
    touched: &[u8],
    edge_of: &[(u32, u8)],
    out: &mut Vec<[i32; 3]>,
) {
    out.clear();
    let mut last = u32::MAX;
    for (x, &t) in touched.iter().enumerate() {
        let slot = edge_of[x].0;
        // Crossings are numbered point by point: one entry per point.
        if t != 0 && slot != last {
            out.push(layout.coords_of(slot as usize));
            last = slot;
        }
    }
    out.sort_unstable();
    out.dedup();
}

/// The output vertices: one per crossing outside the kept groups and one per kept group, in
/// order of their lowest crossing id; `vertex_of` maps every crossing to its vertex. Read from
/// the quotient's labels ([`quotient::Groups::vlabel`] and `vpos`, kept up to date by
/// every step): a crossing labelled with itself is a vertex, at its quotient position; the
/// others take their label's, numbered before them (a label is its group's lowest id).
///
/// In parallel over runs of crossings, as Flying Edges numbers its points: each run counts its
/// vertices, prefix sums give where each run's start, then each run numbers its own and places
/// their positions, and maps the crossings whose label it has mapped. The rest (a label in an
/// earlier run, or one left for later) take their label's number after, in order: the same
/// map as one pass over the crossings in order.
pub(crate) fn vertex_map(
    q: &Quotient,
    vertex_of: &mut Vec<u32>,
    positions: &mut Vec<[f32; 3]>,
    pool: &rayon::ThreadPool,
) {
    const RUN: usize = 1 << 14;
    // Not a vertex number (there are fewer vertices than crossings, fewer than `u32::MAX`).
    const LATER: u32 = u32::MAX;
    let n = q.cpos.len();
    let g = q.g;
    let (vlabel, vpos) = (&g.vlabel[..n], &g.vpos[..n]);
    // Each run's vertices, and where they start.
    let counts: Vec<usize> = pool.install(|| {
        vlabel
            .par_chunks(RUN)
            .enumerate()
            .map(|(k, labels)| {
                let first = (k * RUN) as u32;
                let mut count = 0u32;
                for (x, &l) in (first..).zip(labels) {
                    count += u32::from(l == x);
                }
                count as usize
            })
            .collect()
    });
    // Every entry of both is written below.
    overwritten(vertex_of, n, 0, pool);
    overwritten(positions, counts.iter().sum(), [0.0; 3], pool);
    let (mut firsts, mut parts) = (Vec::with_capacity(counts.len()), Vec::new());
    let (mut rest, mut first) = (&mut positions[..], 0);
    for &c in &counts {
        let (head, tail) = rest.split_at_mut(c);
        parts.push(head);
        firsts.push(first as u32);
        first += c;
        rest = tail;
    }
    let later: Vec<Vec<u32>> = pool.install(|| {
        vertex_of[..n]
            .par_chunks_mut(RUN)
            .zip(parts.into_par_iter())
            .enumerate()
            .map(|(k, (out, placed))| {
                let lo = k * RUN;
                let (labels, at) = (&vlabel[lo..lo + out.len()], &vpos[lo..lo + out.len()]);
                let mut vertex = firsts[k];
                let mut placed = placed.iter_mut();
                let mut later = Vec::new();
                for i in 0..out.len() {
                    let l = labels[i] as usize;
                    if l == lo + i {
                        out[i] = vertex;
                        vertex += 1;
                        if let Some(p) = placed.next() {
                            *p = at[i];
                        }
                    } else if l >= lo && out[l - lo] != LATER {
                        debug_assert!(l < lo + i, "crossing {} labelled {l}", lo + i);
                        out[i] = out[l - lo];
                    } else {
                        out[i] = LATER;
                        later.push((lo + i) as u32);
                    }
                }
                later
            })
            .collect()
    });
    // The labels in earlier runs (or not vertices themselves), in order.
    for &x in later.iter().flatten() {
        let x = x as usize;
        let l = vlabel[x] as usize;
        debug_assert!(
            l < x,
            "crossing {x} labelled {l}: labels are their groups' lowest ids"
        );
        vertex_of[x] = vertex_of[l];
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mt::testing::{extracted, settings_on, test_pool, wavy};
    use crate::Lattice;

    /// Of the vertex pass's proposals on `field` (body-centred, integrated clustering, `n`
    /// cells in [-1, 1]^3): how many there are, and how many have 0, 1, ..., 7 or more other
    /// proposals with a crossing in their star (the plain MT triangles touching their
    /// crossings). With none, tests (a) and (b) of a group depend on its own neighbourhood's
    /// signs alone (issue 41, part 1: what a table could decide).
    fn isolated_proposals(field: &impl rmt_fields::ScalarField, n: usize) -> (usize, [usize; 8]) {
        let pool = test_pool(1);
        let settings = settings_on([n; 3], Lattice::BodyCentred, crate::Clustering::Integrated);
        let (samples, buf, _, _) = extracted(field, &settings, &pool);
        // The proposals again, from the vertex pass alone (the extraction appended additions).
        let layout = Layout::new(&samples, Lattice::BodyCentred);
        let mut tables = crate::mt::crossings::VertexTables::default();
        tables.allocate(&samples);
        let (mut proposals, mut positions) = (Vec::new(), Vec::new());
        let work = crate::mt::crossings::VertexWork {
            propose: Some(proposal::Rules::Islands),
            known_edges: None,
        };
        let out = crate::mt::crossings::VertexOut {
            proposals: &mut proposals,
            positions: &mut positions,
        };
        let mut stats = Stats::default();
        crate::mt::crossings::vertex_pass(
            &layout,
            settings.iso,
            work,
            &pool,
            &mut tables,
            out,
            &mut stats,
        )
        .expect("vertex pass");
        assert_eq!(
            positions, buf.clustering.cpos,
            "the same crossings as the extraction"
        );
        let mut owner = vec![u32::MAX; positions.len()];
        for (gi, c) in proposals.iter().enumerate() {
            for r in 0..16 {
                if c.members >> r & 1 != 0 {
                    assert_eq!(owner[(c.first + r) as usize], u32::MAX, "proposals overlap");
                    owner[(c.first + r) as usize] = gi as u32;
                }
            }
        }
        let (plain, inc) = (&buf.clustering.plain.tris, &buf.clustering.plain.inc);
        // Per proposal, the other proposals with a crossing in its star: a histogram of 0, 1,
        // 2, ..., 7 and more.
        let mut others = [0usize; 8];
        let mut seen = Vec::new();
        for (gi, c) in proposals.iter().enumerate() {
            seen.clear();
            for r in (0..16u32).filter(|r| c.members >> r & 1 != 0) {
                let x = (c.first + r) as usize;
                for &t in &inc.inc[inc.start[x] as usize..inc.start[x + 1] as usize] {
                    for k in 0..3 {
                        let o = owner[plain[3 * t as usize + k] as usize];
                        if o != u32::MAX && o != gi as u32 && !seen.contains(&o) {
                            seen.push(o);
                        }
                    }
                }
            }
            others[seen.len().min(7)] += 1;
        }
        (proposals.len(), others)
    }

    /// What the first round of the islands' tests meets on `field` (integrated clustering,
    /// `n` cells in [-1, 1]^3): the islands tested, those with no lone crossing (test (a) by
    /// the lattice's table), those the table refuses (decided without walking the star), and
    /// the lookups and evaluations of test (c)'s memo. Every island's verdict from the labels,
    /// table and memo ([`Quotient::verdict_kept`]) is compared with the walk
    /// ([`Quotient::verdict`]), and the table with the walk's test (a) alone.
    fn first_round(field: &impl rmt_fields::ScalarField, n: usize, lattice: Lattice) -> [usize; 6] {
        use std::sync::atomic::Ordering;
        let pool = test_pool(1);
        let settings = settings_on([n; 3], lattice, crate::Clustering::Integrated);
        let (samples, _, _, _) = extracted(field, &settings, &pool);
        let layout = Layout::new(&samples, lattice);
        let mut tables = crate::mt::crossings::VertexTables::default();
        tables.allocate(&samples);
        let mut buf = ClusterBuffers::default();
        let work = crate::mt::crossings::VertexWork {
            propose: Some(proposal::Rules::Islands),
            known_edges: None,
        };
        let out = crate::mt::crossings::VertexOut {
            proposals: &mut buf.candidates,
            positions: &mut buf.cpos,
        };
        let mut stats = Stats::default();
        crate::mt::crossings::vertex_pass(
            &layout,
            settings.iso,
            work,
            &pool,
            &mut tables,
            out,
            &mut stats,
        )
        .expect("vertex pass");
        // The steps of `run` up to the islands' first round.
        build_groups(&mut buf, &tables.crossed, &layout, &pool);
        let surface = Surface {
            l: &layout,
            iso: settings.iso,
            keep: None,
            crossed: &tables.crossed,
        };
        plain_triangles(&surface, &buf.cpos, false, &mut buf.plain, &pool);
        let mut groups = std::mem::take(&mut buf.groups);
        let f = fixed(&buf, &layout);
        groups.relabel(&f, &pool);
        additions::give_lones(&f, &mut groups, &buf.edge_of, false, &pool);
        let q = Quotient::new(&f, &groups);
        let islands = f.groups.len();
        let mut tables = quotient::RoundTables::default();
        tables.prepare(&q, false, &pool);
        let flips = &tables.flips;
        // The round's tables with every triangle labelled (a round testing many groups).
        let mut labelled = quotient::RoundTables::default();
        labelled.prepare(&q, true, &pool);
        let mut s = quotient::Star::default();
        let (mut by_table, mut refused, mut with_lones) = (0, 0, 0);
        for gi in 0..islands {
            let walk = q.verdict(gi, &mut s, true);
            assert_eq!(
                q.verdict_kept(gi, &mut s, true, &tables),
                walk,
                "island {gi}: labels, table and memo against the walk"
            );
            assert_eq!(
                q.verdict_kept(gi, &mut s, true, &labelled),
                walk,
                "island {gi}: the round's labelled triangles against the walk"
            );
            assert_eq!(
                q.verdict_kept(gi, &mut s, false, &labelled),
                q.verdict(gi, &mut s, false),
                "island {gi}: (b) and (c) from the labelled triangles against the walk"
            );
            let table = layout.t.is_contractible(f.groups[gi].dirs);
            let lones = q.lones_of(gi);
            if lones.is_empty() {
                by_table += 1;
                assert_eq!(
                    table,
                    walk != quotient::Verdict::FailsContractible,
                    "island {gi}: test (a) by table against the walk"
                );
                refused += usize::from(!table);
            } else if table {
                // The point's part by table, the lone crossings walked around them only.
                by_table += 1;
                let contractible = q.lones_keep_contractible(lones, groups.leader[gi]);
                assert_eq!(
                    contractible,
                    walk != quotient::Verdict::FailsContractible,
                    "island {gi} with {} lone crossings: test (a) against the walk",
                    lones.len()
                );
                with_lones += 1;
            }
        }
        // Test (c)'s memo: a triangle of three different labels is read once from each of its
        // corners in a kept group, and evaluated once.
        let (mut lookups, mut evaluated) = (0, 0);
        for t in f.tris.chunks_exact(3) {
            let l = [0, 1, 2].map(|k| groups.vlabel[t[k] as usize]);
            if l[0] == l[1] || l[1] == l[2] || l[0] == l[2] {
                continue;
            }
            let kept = t.iter().filter(|&&x| !q.alone(x)).count();
            lookups += kept;
            evaluated += usize::from(kept > 0);
        }
        let memo: usize = flips
            .iter()
            .map(|m| usize::from(m.load(Ordering::Relaxed) != 0))
            .sum();
        assert!(memo <= evaluated, "the memo holds only star triangles");
        [islands, by_table, refused, lookups, evaluated, with_lones]
    }

    #[test]
    fn islands_decided_by_the_lattice_table_and_the_memo_agree_with_the_walk() {
        // Also a measurement (printed with --nocapture): the share of the first round's
        // islands whose test (a) the table decides, of those it decides without the walk, and
        // the share of test (c)'s reads the memo answers.
        use rmt_fields::{Asteroid, AsteroidParams, CaveParams, CaveTerrain, RandomField, Sphere};
        for lattice in [Lattice::BodyCentred, Lattice::Simple] {
            let n = 40;
            let mut rows = vec![
                (
                    "sphere",
                    first_round(&Sphere::new(glam::Vec3::ZERO, 0.8), n, lattice),
                ),
                (
                    "asteroid",
                    first_round(
                        &Asteroid::new(glam::Vec3::ZERO, AsteroidParams::default()),
                        n,
                        lattice,
                    ),
                ),
                (
                    "caves",
                    first_round(&CaveTerrain::new(CaveParams::default()), n, lattice),
                ),
                ("wavy", first_round(&wavy(), n, lattice)),
            ];
            let mut random = [0usize; 6];
            for seed in 0..6 {
                let r = first_round(&RandomField::from_seed(seed), 20, lattice);
                for (a, b) in random.iter_mut().zip(r) {
                    *a += b;
                }
            }
            rows.push(("random x6", random));
            for (name, [islands, by_table, refused, lookups, evaluated, with_lones]) in &rows {
                let pct = |a: usize, b: usize| 100.0 * a as f64 / (b.max(1)) as f64;
                println!(
                    "{lattice:?} {name:10}: {islands:6} islands; test (a) by table {:.1}% \
                     ({:.1}% with lone crossings walked), decided without the walk {:.2}%; \
                     test (c) memo answers {:.1}% of {lookups} reads",
                    pct(*by_table, *islands),
                    pct(*with_lones, *islands),
                    pct(*refused, *islands),
                    100.0 - pct(*evaluated, *lookups),
                );
                assert!(
                    by_table <= islands && *refused + *with_lones <= *by_table,
                    "{name}"
                );
            }
            for (name, [islands, by_table, _, lookups, evaluated, with_lones]) in &rows[..2] {
                assert!(*islands > 1000, "{name}: only {islands} islands");
                assert!(
                    *by_table > 0 && *with_lones > 0 && evaluated < lookups,
                    "{name}"
                );
            }
        }
    }

    #[test]
    fn share_of_proposals_with_no_other_proposal_in_their_star() {
        // A measurement (printed with --nocapture) for the table of issue 41; it asserts that
        // the histogram covers every proposal, and that the sphere and asteroid have proposals.
        use rmt_fields::{Asteroid, AsteroidParams, CaveParams, CaveTerrain, RandomField, Sphere};
        let mut rows = Vec::new();
        let n = 48;
        rows.push((
            "sphere",
            isolated_proposals(&Sphere::new(glam::Vec3::ZERO, 0.8), n),
        ));
        rows.push((
            "asteroid",
            isolated_proposals(
                &Asteroid::new(glam::Vec3::ZERO, AsteroidParams::default()),
                n,
            ),
        ));
        rows.push((
            "caves",
            isolated_proposals(&CaveTerrain::new(CaveParams::default()), n),
        ));
        rows.push(("wavy", isolated_proposals(&wavy(), n)));
        let mut random = (0, [0usize; 8]);
        for seed in 0..8 {
            let (t, h) = isolated_proposals(&RandomField::from_seed(seed), 24);
            random.0 += t;
            for (a, b) in random.1.iter_mut().zip(h) {
                *a += b;
            }
        }
        rows.push(("random x8", random));
        for (name, (total, others)) in &rows {
            assert_eq!(others.iter().sum::<usize>(), *total, "{name}");
            let share: Vec<String> = others
                .iter()
                .map(|&k| format!("{:.1}%", 100.0 * k as f64 / (*total).max(1) as f64))
                .collect();
            println!(
                "{name:10}: {total:6} proposals; with 0, 1, ..., 7+ other proposals in the star: {}",
                share.join(" ")
            );
        }
        for (name, (total, _)) in &rows[..2] {
            assert!(*total > 1000, "{name}: only {total} proposals");
        }
        let empty = isolated_proposals(&Sphere::new(glam::Vec3::splat(5.0), 0.1), 8);
        assert_eq!(empty, (0, [0; 8]), "no surface, no proposal");
    }

    #[test]
    fn unchecked_numbering_by_planes_is_the_group_tables_numbering() {
        // `keep_all` (integrated-unchecked: every proposal kept, numbered plane by plane in
        // parallel) against the group tables and the serial `vertex_map` of integrated
        // clustering with every group kept: the same vertex of every crossing and the same
        // positions, bit for bit.
        let field = wavy();
        let mut compared = 0;
        for threads in [1, 2] {
            let pool = test_pool(threads);
            for lattice in [Lattice::BodyCentred, Lattice::Simple] {
                for cells in [[12, 10, 14], [16, 16, 16], [5, 23, 9]] {
                    let settings =
                        settings_on(cells, lattice, crate::Clustering::IntegratedUnchecked);
                    let (samples, mut buf, _, _) = extracted(&field, &settings, &pool);
                    let what = format!("{lattice:?} {cells:?} threads={threads}");
                    assert!(
                        buf.clustering.candidates.len() > 20,
                        "{what}: few proposals"
                    );
                    let l = Layout::new(&samples, lattice);
                    let mut by_planes = Vec::new();
                    keep_all(
                        &mut buf.clustering,
                        &buf.vertices.crossed,
                        &l,
                        &mut by_planes,
                        &pool,
                    );
                    let planes_map = buf.clustering.vertex_of.clone();
                    build_groups(&mut buf.clustering, &buf.vertices.crossed, &l, &pool);
                    let (mut tables_map, mut by_tables) = (Vec::new(), Vec::new());
                    let fixed = Fixed {
                        l: &l,
                        cpos: &buf.clustering.cpos,
                        groups: &buf.clustering.candidates,
                        tris: &[],
                        source: &[],
                        inc_start: &[],
                        inc: &[],
                    };
                    // Every crossing's quotient vertex, which the numbering reads.
                    buf.clustering.groups.relabel(&fixed, &pool);
                    let q = Quotient::new(&fixed, &buf.clustering.groups);
                    vertex_map(&q, &mut tables_map, &mut by_tables, &pool);
                    assert_eq!(planes_map, tables_map, "{what}");
                    let bits = |p: &[[f32; 3]]| -> Vec<[u32; 3]> {
                        p.iter().map(|v| v.map(f32::to_bits)).collect()
                    };
                    assert_eq!(bits(&by_planes), bits(&by_tables), "{what}");
                    // Merged groups: fewer vertices than crossings.
                    assert!(by_planes.len() < buf.clustering.cpos.len(), "{what}");
                    compared += buf.clustering.cpos.len();
                }
            }
        }
        assert!(compared > 5000, "only {compared} crossings compared");
    }

    #[test]
    fn parallel_vertex_map_equals_one_pass_in_order() {
        // Labels near and far (in the same run of the parallel map, in an earlier one) and
        // chains (a label that is not a vertex itself): the map and the positions of one pass
        // over the crossings in order, for any thread count.
        use crate::{ExtractSettings, Grid, Samples};
        let settings = ExtractSettings::new(
            Grid::cube(2, 1.0),
            Lattice::BodyCentred,
            crate::Clustering::Integrated,
        );
        let mut samples = Samples::default();
        samples.prepare(&settings);
        let l = Layout::new(&samples, Lattice::BodyCentred);
        let mut seed = 0x2545_f491_4f6c_dd1du64;
        let mut next = move || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            seed
        };
        for n in [0usize, 1, 1000, 70_000] {
            let cpos: Vec<[f32; 3]> = (0..n).map(|x| [x as f32, 1.0, 2.0]).collect();
            let mut g = Groups::default();
            for x in 0..n {
                let label = match next() % 8 {
                    _ if x == 0 => 0,
                    0..=2 => x,
                    3 => x - 1 - (next() as usize % x.min(40_000)),
                    _ => x - 1 - (next() as usize % x.min(20)),
                };
                g.vlabel.push(label as u32);
                g.vpos.push([label as f32, 0.5, -(x as f32)]);
            }
            // The reference: one pass in order.
            let (mut want_map, mut want_pos) = (vec![0u32; n], Vec::new());
            for x in 0..n {
                let label = g.vlabel[x] as usize;
                if label == x {
                    want_map[x] = want_pos.len() as u32;
                    want_pos.push(g.vpos[x]);
                } else {
                    want_map[x] = want_map[label];
                }
            }
            let fixed = Fixed {
                l: &l,
                cpos: &cpos,
                groups: &[],
                tris: &[],
                source: &[],
                inc_start: &[],
                inc: &[],
            };
            let q = Quotient::new(&fixed, &g);
            for threads in [1, 2, 3] {
                let pool = test_pool(threads);
                let (mut map, mut pos) = (vec![7; 3], vec![[9.0; 3]; n + 5]);
                vertex_map(&q, &mut map, &mut pos, &pool);
                assert_eq!(map, want_map, "{n} crossings, {threads} threads");
                assert_eq!(pos, want_pos, "{n} crossings, {threads} threads");
            }
        }
    }
}
