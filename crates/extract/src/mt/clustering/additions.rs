//! What integrated clustering proposes once the islands settle, each step a function of the
//! state the previous one left around each crossing (so still order-free), each settled by
//! [`super::repair::settle`] in [`super::repair::Phase::Additions`]:
//!
//! 1. every split island of three or more takes back its first variant (the island without one
//!    crossing, then pairs of its crossings) that passes in the current state ([`revive`]);
//! 2. crossings left alone join the nearest kept group they share a triangle with, at most
//!    [`MAX_LONES`] per group, in a few passes; a group that fails with them gives them back,
//!    and a crossing given back tries another group in the next pass ([`give_lones`]);
//! 3. slivers (triangles of the quotient with an aspect ratio above [`SLIVER_AR`]): a crossing
//!    left alone at one joins the group across the sliver's shortest edge, or pairs with the
//!    crossing there into a new group ([`sliver_proposals`]).
//!
//! Each step only keeps what then passes every test, so the result stays closed, manifold and of
//! the same topology as plain MT.

use rayon::prelude::*;

use super::proposal::Candidate;
use super::quotient::{group_vertex, Fixed, Groups, Lone, Quotient, Star, MAX_LONES, NONE};

/// The groups that may replace a split island, in the order they are tried: its island without
/// one crossing, for each crossing in bit order, when that leaves a connected part; then (for
/// islands of four or more) every pair of its crossings joined by a mesh edge, in bit order
/// (lattice adjacency joins the crossings of one point through mesh edges, see
/// [`super::proposal`]).
pub(crate) fn variants(c: &Candidate, t: &crate::lattice::LatticeTables, out: &mut Vec<Candidate>) {
    if c.size() < 3 {
        return;
    }
    // Bit `d` of `dirs` is bit `rank(d)` of `members`: the k-th set bits correspond.
    let bits: Vec<(u16, u16)> = {
        let (mut dirs, mut members) = (c.dirs, c.members);
        let mut v = Vec::with_capacity(14);
        while dirs != 0 {
            v.push((dirs & dirs.wrapping_neg(), members & members.wrapping_neg()));
            dirs &= dirs - 1;
            members &= members - 1;
        }
        v
    };
    let mut push = |dirs: u16, members: u16| {
        out.push(Candidate {
            first: c.first,
            members,
            dirs,
            slot: c.slot,
        })
    };
    for &(d, m) in &bits {
        if t.is_connected(c.dirs & !d) {
            push(c.dirs & !d, c.members & !m);
        }
    }
    if bits.len() >= 4 {
        for (i, &(d1, m1)) in bits.iter().enumerate() {
            for &(d2, m2) in &bits[i + 1..] {
                if t.is_connected(d1 | d2) {
                    push(d1 | d2, m1 | m2);
                }
            }
        }
    }
}

/// Each split island `k` (its variants at `variant_of[k]..variant_of[k + 1]` in the candidates,
/// not kept) takes its first variant that passes every test in the current
/// state; all of them at once (each decided from the state before any is taken). Returns the
/// groups to test again: the taken variants and the groups around them.
pub(crate) fn revive(
    f: &Fixed,
    g: &mut Groups,
    variant_of: &[u32],
    pool: &rayon::ThreadPool,
) -> Vec<u32> {
    if let (Some(&first), Some(&end)) = (variant_of.first(), variant_of.last()) {
        for v in first..end {
            g.refresh(f, v as usize);
        }
    }
    let q = Quotient::new(f, g);
    let taken: Vec<u32> = pool.install(|| {
        (0..variant_of.len().saturating_sub(1))
            .into_par_iter()
            .map_init(Box::<Star>::default, |s, k| {
                (variant_of[k]..variant_of[k + 1]).find(|&v| q.passes_all(v as usize, s))
            })
            .flatten_iter()
            .collect()
    });
    for &v in &taken {
        let vi = v as usize;
        g.active[vi] = 1;
        for id in f.groups[vi].ids() {
            g.group_of[id as usize] = v;
        }
        g.refresh(f, vi);
        g.set_vertices(f, vi);
    }
    around(f, g, &taken, pool)
}

/// The groups `groups` and the active groups around them (those whose test may change when
/// they change), sorted, each once.
pub(crate) fn around(f: &Fixed, g: &Groups, groups: &[u32], pool: &rayon::ThreadPool) -> Vec<u32> {
    let q = Quotient::new(f, g);
    let mut out: Vec<u32> = pool.install(|| {
        groups
            .par_iter()
            .map_init(Box::<Star>::default, |s, &gi| {
                let mut out = vec![gi];
                q.neighbours(gi as usize, s, &mut out);
                out
            })
            .flatten_iter()
            .collect()
    });
    out.sort_unstable();
    out.dedup();
    out
}

/// Crossings per run of the scans over all crossings.
const RUN: usize = 1 << 12;

/// A triangle is a sliver when its aspect ratio (circumradius over twice the inradius, 1 for an
/// equilateral triangle) exceeds this.
pub(crate) const SLIVER_AR: f32 = 4.0;

/// The aspect ratio of triangle `a b c` (as [`SLIVER_AR`] measures it): infinite when flat.
fn aspect_ratio(a: glam::Vec3, b: glam::Vec3, c: glam::Vec3) -> f32 {
    let (la, lb, lc) = ((b - c).length(), (c - a).length(), (a - b).length());
    let double_area = (b - a).cross(c - a).length();
    if double_area <= 0.0 {
        return f32::INFINITY;
    }
    let ar = la * lb * lc * (la + lb + lc) / (4.0 * double_area * double_area);
    if ar.is_finite() {
        ar
    } else {
        f32::INFINITY
    }
}

/// What the slivers left after the lone passes propose: lone crossings for groups, and pairs of
/// crossings to become new groups.
#[derive(Debug, Default)]
pub(crate) struct SliverProposals {
    /// (group, crossing).
    pub(crate) lones: Vec<(u32, Lone)>,
    /// (lower crossing, higher crossing).
    pub(crate) pairs: Vec<(u32, u32)>,
}

/// Every inner crossing left alone that is a corner of a sliver of the quotient (a triangle
/// whose aspect ratio exceeds [`SLIVER_AR`]) whose shortest edge it shares, picks the other
/// end of the shortest such edge (then the lower label): a kept group takes it as a lone
/// crossing; a crossing left alone that picked it back forms a pair with it. A function of the
/// current state around each crossing, so order-free.
///
/// A crossing skips the sliver edges that lead to the group that last gave it back
/// ([`super::quotient::Groups::refused`]) and takes its next-shortest one. The sliver passes
/// start with the lone passes' refusals cleared, so a group that gave a crossing back in a lone
/// pass is asked again: its star has changed since, as the other lone passes settled. This
/// matters where a sample point lies exactly on the surface: its crossings coincide there, the
/// triangles between them are flat, and only their one group removes them, which may refuse
/// them in a lone pass (a random tube through a sample point kept 2 flat triangles that way).
pub(crate) fn sliver_proposals(
    f: &Fixed,
    g: &Groups,
    edge_of: &[(u32, u8)],
    pool: &rayon::ThreadPool,
) -> SliverProposals {
    let q = Quotient::new(f, g);
    // Only for a crossing left alone (few, once the islands settled).
    let pick = |x: u32| -> u32 {
        let (slot, dir) = edge_of[x as usize];
        if !q.inner(slot as usize, dir) {
            return NONE;
        }
        let mut best: Option<(f32, u32)> = None;
        for &t in q.tris_of(x) {
            let c = q.tri(t).map(|y| q.label(y));
            if c[0] == c[1] || c[1] == c[2] || c[0] == c[2] {
                continue;
            }
            let p = c.map(|y| glam::Vec3::from(q.position(y)));
            if aspect_ratio(p[0], p[1], p[2]) <= SLIVER_AR {
                continue;
            }
            let edges = [(0, 1), (1, 2), (2, 0)].map(|(a, b)| (p[a].distance_squared(p[b]), a, b));
            let Some(&(len, a, b)) = edges.iter().min_by(|e, o| {
                e.0.total_cmp(&o.0)
                    .then((c[e.1], c[e.2]).cmp(&(c[o.1], c[o.2])))
            }) else {
                continue;
            };
            let other = if c[a] == x {
                c[b]
            } else if c[b] == x {
                c[a]
            } else {
                continue;
            };
            let h = g.group_of[other as usize];
            if h != NONE && h == g.refused[x as usize] && g.active[h as usize] != 0 {
                continue;
            }
            if best.is_none_or(|(bl, bu)| (len, other) < (bl, bu)) {
                best = Some((len, other));
            }
        }
        best.map_or(NONE, |(_, u)| u)
    };
    // In runs of crossings, the test of the crossings in kept groups (nearly all) inline; each
    // run lists the crossings that picked one.
    let mut choice = Vec::new();
    crate::util::filled(&mut choice, edge_of.len(), NONE, pool);
    let picked: Vec<Vec<u32>> = pool.install(|| {
        choice
            .par_chunks_mut(RUN)
            .enumerate()
            .map(|(k, out)| {
                let mut picked = Vec::new();
                let group_of = &g.group_of[k * RUN..k * RUN + out.len()];
                for (i, (c, &h)) in out.iter_mut().zip(group_of).enumerate() {
                    let x = (k * RUN + i) as u32;
                    // Left alone: in no group, or in one not kept (`Quotient::alone`).
                    if h == NONE || g.active[h as usize] == 0 {
                        *c = pick(x);
                        if *c != NONE {
                            picked.push(x);
                        }
                    }
                }
                picked
            })
            .collect()
    });
    let mut out = SliverProposals::default();
    for &x in picked.iter().flatten() {
        let u = choice[x as usize];
        let h = g.group_of[u as usize];
        if h != NONE && g.active[h as usize] != 0 {
            out.lones.push((h, Lone { id: x }));
        } else if x < u && choice[u as usize] == x {
            out.pairs.push((x, u));
        }
    }
    out
}

/// Gives every inner crossing left alone (in no kept group) to the nearest kept group it shares
/// a triangle with, up to [`MAX_LONES`] lone crossings per group (lowest ids first); returns the
/// groups to test: those that took some, and (with `want_dirty`) the groups around them.
/// `edge_of` gives every crossing's owner slot and edge.
pub(crate) fn give_lones(
    f: &Fixed,
    g: &mut Groups,
    edge_of: &[(u32, u8)],
    want_dirty: bool,
    pool: &rayon::ThreadPool,
) -> Vec<u32> {
    let q = Quotient::new(f, g);
    // Only for a crossing left alone.
    let give = |x: usize| -> Option<(u32, Lone)> {
        let (slot, dir) = edge_of[x];
        if !q.inner(slot as usize, dir) {
            return None;
        }
        let refused = q.g.refused[x];
        let h = q.nearest_group(x as u32, |h| h != refused)?;
        Some((h, Lone { id: x as u32 }))
    };
    // In runs of crossings, the test of the crossings in kept groups inline; `attach` sorts.
    let runs: Vec<Vec<(u32, Lone)>> = pool.install(|| {
        (0..edge_of.len().div_ceil(RUN))
            .into_par_iter()
            .map(|k| {
                let lo = k * RUN;
                let group_of = &q.g.group_of[lo..((k + 1) * RUN).min(edge_of.len())];
                let mut found = Vec::new();
                for (i, &h) in group_of.iter().enumerate() {
                    // Left alone: in no group, or in one not kept (`Quotient::alone`).
                    if h == NONE || q.g.active[h as usize] == 0 {
                        found.extend(give(lo + i));
                    }
                }
                found
            })
            .collect()
    });
    let found = runs.concat();
    attach(f, g, found, want_dirty, pool)
}

/// Gives the lone crossings `found` (group, crossing) to their groups, up to [`MAX_LONES`] per
/// group (lowest ids first): the kept groups' lone tables are rebuilt, their lones so far
/// first (the count [`Groups::base_len`] a failing group sheds back to). Returns the groups
/// that took some, and (with `want_dirty`) the groups around them.
pub(crate) fn attach(
    f: &Fixed,
    g: &mut Groups,
    mut found: Vec<(u32, Lone)>,
    want_dirty: bool,
    pool: &rayon::ThreadPool,
) -> Vec<u32> {
    if found.is_empty() {
        // Nothing joins: the table only forgets the lone crossings of the groups not kept, and
        // every group keeps the rest as its base (the same slices as the rebuilt table).
        let Groups {
            active,
            lone_len,
            base_len,
            ..
        } = &mut *g;
        let count = f.groups.len();
        pool.install(|| {
            base_len[..count]
                .par_chunks_mut(RUN)
                .zip(lone_len[..count].par_chunks_mut(RUN))
                .zip(active[..count].par_chunks(RUN))
                .for_each(|((bases, lens), active)| {
                    for ((base, len), &a) in bases.iter_mut().zip(lens).zip(active) {
                        if a == 0 {
                            *len = 0;
                        }
                        *base = *len;
                    }
                })
        });
        return Vec::new();
    }
    pool.install(|| found.par_sort_unstable_by_key(|&(h, l)| (h, l.id)));
    // The new lone table, built in parallel over runs of `RUN` groups: each run sets its
    // groups' base lengths (the lones they keep) and counts its lones (pass 1), prefix sums
    // give where each run's lones start, then each run writes its groups' entries (pass 2).
    // The same table as one pass over the groups in order.
    const RUN: usize = 1 << 12;
    let count = f.groups.len();
    let runs = count.div_ceil(RUN);
    // Each run's part of `found` (sorted by group).
    let part: Vec<usize> = (0..=runs)
        .map(|r| found.partition_point(|&(h, _)| (h as usize) < (r * RUN).min(count)))
        .collect();
    let Groups {
        active,
        group_of,
        lone: old_lone,
        lone_start: old_start,
        lone_len,
        base_len,
        centroid,
        leader,
        ..
    } = &mut *g;
    let (active, old_lone, old_start) = (&*active, &*old_lone, &*old_start);
    let totals: Vec<usize> = pool.install(|| {
        base_len[..count]
            .par_chunks_mut(RUN)
            .enumerate()
            .map(|(r, bases)| {
                let mut total = 0;
                let mut next = found[part[r]..part[r + 1]].iter().peekable();
                let run = r * RUN..r * RUN + bases.len();
                let (active, lens) = (&active[run.clone()], &lone_len[run]);
                for (j, ((base, &a), &len)) in bases.iter_mut().zip(active).zip(lens).enumerate() {
                    let gi = r * RUN + j;
                    // A kept group keeps its lones so far; the others start over.
                    let k = if a != 0 { len } else { 0 };
                    *base = k;
                    let mut new = 0;
                    while next.next_if(|&&(h, _)| h as usize == gi).is_some() {
                        new += 1;
                    }
                    let k = usize::from(k);
                    total += k + new.min(MAX_LONES.saturating_sub(k));
                }
                total
            })
            .collect()
    });
    let mut lone = vec![Lone { id: 0 }; totals.iter().sum()];
    let mut lone_start = vec![0u32; count + 1];
    let mut parts = Vec::with_capacity(runs);
    let (mut rest, mut first) = (&mut lone[..], 0usize);
    for &t in &totals {
        let (head, tail) = rest.split_at_mut(t);
        parts.push((first, head));
        first += t;
        rest = tail;
    }
    lone_start[count] = first as u32;
    // Per run: the groups that took lones, and the lones taken (crossing, group). The groups
    // that took some get their label and vertex position from their new members here
    // ([`Groups::refresh`]).
    type Taken = (Vec<u32>, Vec<(u32, u32)>);
    let cpos = f.cpos;
    let taken: Vec<Taken> = pool.install(|| {
        parts
            .into_par_iter()
            .zip(lone_start[..count].par_chunks_mut(RUN))
            .zip(lone_len[..count].par_chunks_mut(RUN))
            .zip(base_len[..count].par_chunks(RUN))
            .zip(centroid[..count].par_chunks_mut(RUN))
            .zip(leader[..count].par_chunks_mut(RUN))
            .enumerate()
            .map(
                |(r, ((((((first, out), starts), lens), bases), centroids), leaders))| {
                    let (mut changed, mut joined) = (Vec::new(), Vec::new());
                    let mut w = 0;
                    let mut next = found[part[r]..part[r + 1]].iter().peekable();
                    for (j, ((start, len), base)) in
                        starts.iter_mut().zip(lens).zip(bases).enumerate()
                    {
                        let gi = r * RUN + j;
                        let from_w = w;
                        *start = (first + w) as u32;
                        let k = usize::from(*base);
                        if k > 0 {
                            let from = old_start[gi] as usize;
                            out[w..w + k].copy_from_slice(&old_lone[from..from + k]);
                            w += k;
                        }
                        let mut n = k;
                        while let Some(&(h, l)) = next.next_if(|&&(h, _)| h as usize == gi) {
                            if n < MAX_LONES {
                                out[w] = l;
                                w += 1;
                                joined.push((l.id, h));
                                n += 1;
                            }
                        }
                        *len = n as u8;
                        if n > k {
                            changed.push(gi as u32);
                            (centroids[j], leaders[j]) =
                                group_vertex(f.groups[gi], &out[from_w..w], cpos);
                        }
                    }
                    debug_assert_eq!(w, out.len());
                    (changed, joined)
                },
            )
            .collect()
    });
    for (_, joined) in &taken {
        for &(x, h) in joined {
            group_of[x as usize] = h;
        }
    }
    g.lone = lone;
    g.lone_start = lone_start;
    let changed: Vec<u32> = taken.into_iter().flat_map(|(c, _)| c).collect();
    set_vertices_of(f, g, &changed, pool);
    if !want_dirty {
        return changed;
    }
    around(f, g, &changed, pool)
}

/// [`Groups::set_vertices`] of the groups `changed`, in their order: in parallel over runs of
/// crossings. Runs of groups list their members' new quotient vertices by run of crossings, then
/// each run of crossings takes its entries, group run after group run: the same writes in the
/// same order as the serial loop. (Recording the activity, the serial loop.)
fn set_vertices_of(f: &Fixed, g: &mut Groups, changed: &[u32], pool: &rayon::ThreadPool) {
    const GROUPS: usize = 1 << 10;
    const CROSSINGS: usize = 1 << 14;
    if !g.touched.is_empty() || changed.len() < GROUPS {
        for &gi in changed {
            g.set_vertices(f, gi as usize);
        }
        return;
    }
    let n = g.vlabel.len();
    let runs = n.div_ceil(CROSSINGS);
    type Writes = Vec<Vec<(u32, u32, [f32; 3])>>;
    let q = &*g;
    let writes: Vec<Writes> = pool.install(|| {
        changed
            .par_chunks(GROUPS)
            .map(|groups| {
                let mut by_run: Writes = vec![Vec::new(); runs];
                for &gi in groups {
                    let gi = gi as usize;
                    let start = q.lone_start[gi] as usize;
                    let lones = &q.lone[start..start + q.lone_len[gi] as usize];
                    let kept = q.active[gi] != 0;
                    for x in f.groups[gi].ids().chain(lones.iter().map(|l| l.id)) {
                        let (label, at) = if kept {
                            (q.leader[gi], q.centroid[gi])
                        } else {
                            (x, f.cpos[x as usize])
                        };
                        by_run[x as usize / CROSSINGS].push((x, label, at));
                    }
                }
                by_run
            })
            .collect()
    });
    let writes = &writes;
    pool.install(|| {
        g.vlabel
            .par_chunks_mut(CROSSINGS)
            .zip(g.vpos.par_chunks_mut(CROSSINGS))
            .enumerate()
            .for_each(|(r, (labels, positions))| {
                let lo = r * CROSSINGS;
                for by_run in writes {
                    for &(x, label, at) in &by_run[r] {
                        labels[x as usize - lo] = label;
                        positions[x as usize - lo] = at;
                    }
                }
            })
    });
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The lone table as the serial pass built it before the parallel runs: each group in
    /// order, its kept lones, then its new ones up to [`MAX_LONES`]; then, group by group, the
    /// label, vertex position and quotient vertices of those that took some. Returns them.
    fn attach_serial(
        f: &Fixed,
        count: usize,
        g: &mut Groups,
        mut found: Vec<(u32, Lone)>,
    ) -> Vec<u32> {
        found.sort_unstable_by_key(|&(h, l)| (h, l.id));
        let mut lone = Vec::new();
        let mut lone_start = Vec::new();
        let mut changed = Vec::new();
        let mut next = found.iter().peekable();
        for gi in 0..count {
            lone_start.push(lone.len() as u32);
            let start = g.lone_start[gi] as usize;
            let kept = if g.active[gi] != 0 {
                usize::from(g.lone_len[gi])
            } else {
                0
            };
            lone.extend_from_slice(&g.lone[start..start + kept]);
            g.base_len[gi] = kept as u8;
            let mut len = kept;
            while let Some(&(h, l)) = next.next_if(|&&(h, _)| h as usize == gi) {
                if len < MAX_LONES {
                    lone.push(l);
                    g.group_of[l.id as usize] = h;
                    len += 1;
                }
            }
            g.lone_len[gi] = len as u8;
            if len > kept {
                changed.push(gi as u32);
            }
        }
        lone_start.push(lone.len() as u32);
        g.lone = lone;
        g.lone_start = lone_start;
        for &gi in &changed {
            g.refresh(f, gi as usize);
            g.set_vertices(f, gi as usize);
        }
        changed
    }

    #[test]
    fn parallel_lone_table_equals_the_serial_one_for_any_thread_count() {
        use crate::{Clustering, ExtractSettings, Grid, Lattice, Samples};
        let settings = ExtractSettings::new(
            Grid::cube(2, 1.0),
            Lattice::BodyCentred,
            Clustering::Integrated,
        );
        let mut samples = Samples::default();
        samples.prepare(&settings);
        let layout = crate::mt::Layout::new(&samples, Lattice::BodyCentred);
        let mut seed = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = move || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            seed
        };
        // Enough groups for several runs of the parallel table, and at most `MAX_LONES` lones
        // kept or offered per group, sometimes more offered than fit.
        for (count, offered) in [
            (20_000usize, 30_000usize),
            (9_000, 2_000),
            (5, 40),
            (0, 0),
            (9_000, 0),
        ] {
            // Crossings 0..count are the groups' cores (singletons), the rest lone candidates.
            let crossings = count + 6 * count + offered + 1;
            let cores: Vec<Candidate> = (0..count as u32)
                .map(|gi| Candidate {
                    first: gi,
                    members: 1,
                    dirs: 1,
                    slot: 0,
                })
                .collect();
            let cpos: Vec<[f32; 3]> = (0..crossings).map(|x| [x as f32, 0.0, 1.0]).collect();
            let f = Fixed {
                l: &layout,
                cpos: &cpos,
                groups: &cores,
                tris: &[],
                source: &[],
                inc_start: &[],
                inc: &[],
            };
            // The state before: some groups kept, each with a few lones already.
            let mut g = Groups {
                group_of: vec![NONE; crossings],
                vlabel: vec![0; crossings],
                vpos: vec![[0.0; 3]; crossings],
                ..Groups::default()
            };
            let mut free = count as u32;
            for gi in 0..count {
                g.group_of[gi] = gi as u32;
                g.active.push(u8::from(next() % 4 != 0));
                g.leader.push(gi as u32);
                g.centroid.push([0.0; 3]);
                g.lone_start.push(g.lone.len() as u32);
                let len = (next() % (MAX_LONES as u64 + 1)) as u8;
                for _ in 0..len {
                    g.group_of[free as usize] = gi as u32;
                    g.lone.push(Lone { id: free });
                    free += 1;
                }
                g.lone_len.push(len);
                g.base_len.push(0);
            }
            g.lone_start.push(g.lone.len() as u32);
            // The offers: crossings in no group yet, each to a random group, in any order.
            let found: Vec<(u32, Lone)> = if count == 0 {
                Vec::new()
            } else {
                (0..offered as u32)
                    .map(|k| ((next() % count as u64) as u32, Lone { id: free + k }))
                    .collect()
            };
            let mut expected = g.clone();
            let expected_changed = attach_serial(&f, count, &mut expected, found.clone());
            for threads in [1, 2, 3] {
                let pool = rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .expect("a thread pool");
                let mut got = g.clone();
                let changed = attach(&f, &mut got, found.clone(), false, &pool);
                assert_eq!(
                    changed, expected_changed,
                    "{count} groups, {threads} threads"
                );
                if found.is_empty() {
                    // Nothing joins: the table is not rebuilt, every group's lone crossings
                    // are the same slices.
                    let slice = |g: &Groups, gi: usize| {
                        let start = g.lone_start[gi] as usize;
                        g.lone[start..start + usize::from(g.lone_len[gi])].to_vec()
                    };
                    for gi in 0..count {
                        assert_eq!(slice(&got, gi), slice(&expected, gi), "group {gi}");
                    }
                } else {
                    assert_eq!(got.lone, expected.lone, "{count} groups, {threads} threads");
                    assert_eq!(got.lone_start, expected.lone_start);
                }
                assert_eq!(got.lone_len, expected.lone_len);
                assert_eq!(got.base_len, expected.base_len);
                assert_eq!(got.group_of, expected.group_of);
                // The groups that took lones: their label and vertex, and their members'
                // quotient vertices (in parallel from a thousand groups on).
                assert_eq!(got.leader, expected.leader);
                assert_eq!(got.centroid, expected.centroid);
                assert_eq!(got.vlabel, expected.vlabel);
                assert_eq!(got.vpos, expected.vpos);
            }
            if count > 0 && offered > 0 {
                assert!(
                    !expected_changed.is_empty(),
                    "the test offers lones that fit"
                );
            }
        }
    }

    #[test]
    fn variants_drop_one_crossing_then_keep_pairs_all_connected() {
        use super::super::proposal::compress;
        use crate::lattice::LatticeTables;
        use crate::Lattice;
        let t = LatticeTables::get(Lattice::BodyCentred);
        // +x (0) with its adjacent diagonals 6 and 7, and 8 (adjacent to 0 too), owned along
        // with -x (1), which is not in the island.
        let owned: u16 = (1 << 0) | (1 << 1) | (1 << 6) | (1 << 7) | (1 << 8);
        let island: u16 = (1 << 0) | (1 << 6) | (1 << 7) | (1 << 8);
        assert!(t.is_connected(island));
        let c = Candidate {
            first: 40,
            members: compress(island, owned),
            dirs: island,
            slot: 9,
        };
        let mut out = Vec::new();
        variants(&c, t, &mut out);
        let without_one: Vec<u16> = [0, 6, 7, 8]
            .iter()
            .map(|&d| island & !(1 << d))
            .filter(|&m| t.is_connected(m))
            .collect();
        let pairs = (out.len() - without_one.len()) as u32;
        assert_eq!(
            out.iter()
                .take(without_one.len())
                .map(|v| v.dirs)
                .collect::<Vec<_>>(),
            without_one,
            "the islands without one crossing come first, in bit order"
        );
        for v in &out {
            assert!(t.is_connected(v.dirs), "{:b}", v.dirs);
            assert_eq!(
                v.members,
                compress(v.dirs, owned),
                "members follow the edges"
            );
            assert_eq!((v.first, v.slot), (40, 9));
            assert_eq!(v.dirs & !island, 0);
        }
        // Every connected pair of the island, each once.
        let expected = [0, 6, 7, 8]
            .iter()
            .enumerate()
            .flat_map(|(i, &a)| {
                [0, 6, 7, 8][i + 1..]
                    .iter()
                    .map(move |&b| (1u16 << a) | (1 << b))
            })
            .filter(|&m| t.is_connected(m))
            .count() as u32;
        assert_eq!(pairs, expected);
        // Islands of two have no variant; of three, no pairs.
        let mut none = Vec::new();
        let two = (1 << 0) | (1 << 6);
        variants(
            &Candidate {
                first: 0,
                members: compress(two, owned),
                dirs: two,
                slot: 0,
            },
            t,
            &mut none,
        );
        assert!(none.is_empty());
    }

    #[test]
    fn aspect_ratio_is_one_for_equilateral_and_grows_for_needles() {
        use glam::Vec3;
        let s3 = 3f32.sqrt();
        let eq = aspect_ratio(Vec3::ZERO, Vec3::X, Vec3::new(0.5, s3 / 2.0, 0.0));
        assert!((eq - 1.0).abs() < 1e-5, "{eq}");
        let needle = aspect_ratio(Vec3::ZERO, Vec3::X, Vec3::new(0.5, 0.01, 0.0));
        assert!(needle > SLIVER_AR, "{needle}");
        assert_eq!(
            aspect_ratio(Vec3::ZERO, Vec3::X, 2.0 * Vec3::X),
            f32::INFINITY
        );
    }
}
