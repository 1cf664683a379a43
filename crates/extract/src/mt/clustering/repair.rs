//! The repair rounds of integrated clustering: test the groups in the quotient
//! ([`super::quotient`]), repair the failures, test again what the repairs touched, until every
//! kept group passes.
//!
//! Rounds test the groups against the state the previous round left (Jacobi rounds: parallel,
//! and the same result for any thread count). Every failing group names the group to split in
//! its closed star (itself and the groups of its link): the failing one of lowest priority,
//! smaller first, then the later owner. The named groups become singletons, and only the groups
//! whose star holds a crossing of a changed group are tested again. Groups only split, and all
//! singletons is plain MT, so the rounds end, and they end with every group passing. (This
//! follows the Python study in `shared/research/order-free-rmt`.)
//!
//! Additions ([`super::additions`]) are settled the same way ([`Phase::Additions`]), except that
//! a failing addition is undone (a new group splits, a group gives back its new lone crossings)
//! before anything older splits.

use rayon::prelude::*;

use super::quotient::{Fixed, Groups, Quotient, Star, Verdict, NONE};

/// The outcome of the repair rounds.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct Settled {
    /// Seconds of test (a) and the first round.
    pub(crate) t_tests_s: f64,
    /// Seconds of the later rounds.
    pub(crate) t_repair_s: f64,
    /// Groups split (those refused by test (a) included).
    pub(crate) split: usize,
    /// Rounds that split at least one group (0: every group passed at once).
    pub(crate) rounds: usize,
}

/// Which proposals a run of rounds settles, and so how it repairs a failing group.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Phase {
    /// The islands (with the lone crossings given at proposal time): a failing group names the
    /// failing group of lowest priority in its closed star, which splits into singletons.
    Islands,
    /// Additions to the kept groups: lone crossings given to them, and new groups (from index
    /// `born` on). A failing group that is new splits, one that took lone crossings sheds them;
    /// else the new groups of its closed star split and those that took lone crossings shed
    /// them; else it names a group to split, as in [`Phase::Islands`].
    Additions {
        /// The first new group.
        born: u32,
    },
}

/// What a failing group asks for.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
enum Repair {
    /// The group becomes singletons.
    Split(u32),
    /// The group gives back the lone crossings of this phase.
    Shed(u32),
}

/// Runs test rounds over the groups `dirty` (and those their repairs touch) until every active
/// group passes. Test (a) depends on a group's members only: it runs in the first round, for
/// every group in [`Phase::Islands`] and for the new groups and those holding new lones in
/// [`Phase::Additions`].
/// Each round reads only the state the previous round left (Jacobi rounds), so the result is
/// the same for any thread count.
pub(crate) fn settle(
    f: &Fixed,
    g: &mut Groups,
    mut dirty: Vec<u32>,
    phase: Phase,
    pool: &rayon::ThreadPool,
) -> Settled {
    let mut out = Settled::default();
    let start = std::time::Instant::now();
    // Per group: 1 while it fails (b) or (c) this round, 2 when it fails (a).
    let mut failing = vec![0u8; f.groups.len()];
    // Test (c) per plain MT triangle in the state of the round, and the triangles' labels when
    // the round tests many groups (see `Quotient::verdict_kept`).
    let mut tables = std::mem::take(&mut g.round);
    let mut round = 0u32;
    loop {
        round += 1;
        let first = round == 1;
        let q = Quotient::new(f, g);
        // Labelling every triangle costs about as much as skipping the collapsed ones saves
        // in the stars of one group in twenty triangles.
        tables.prepare(&q, 20 * dirty.len() >= f.tris.len() / 3, pool);
        let tables = &tables;
        let fails: Vec<(u32, u8)> = pool.install(|| {
            // Runs of at least 256 groups: each run sets up one star's working memory (a run
            // per test cost about 2% of the tests on one thread, 5% on two).
            dirty
                .par_iter()
                .with_min_len(256)
                .copied()
                .map_init(Box::<Star>::default, |s, gi| {
                    let i = gi as usize;
                    let test_a = first
                        && match phase {
                            Phase::Islands => true,
                            Phase::Additions { born } => gi >= born || q.has_new_lones(i),
                        };
                    let verdict = q.verdict_kept(i, s, test_a, tables);
                    #[cfg(test)]
                    assert_ne!(q.g.active[i], 0, "group {gi} tested but not kept");
                    #[cfg(test)]
                    assert_eq!(
                        verdict,
                        q.verdict(i, s, test_a),
                        "group {gi}: the verdict from the labels and memo against the walk"
                    );
                    match verdict {
                        Verdict::Passes => None,
                        Verdict::FailsLink => Some((gi, 1)),
                        Verdict::FailsContractible => Some((gi, 2)),
                    }
                })
                .flatten_iter()
                .collect()
        });
        if first {
            out.t_tests_s = start.elapsed().as_secs_f64();
        }
        if fails.is_empty() {
            break;
        }
        out.rounds += 1;
        for &(gi, why) in &fails {
            failing[gi as usize] = why;
        }
        let failing_ref = &failing;
        // The repairs, and the groups each one touches (to test again).
        let repairs: Vec<(Vec<Repair>, Vec<u32>)> = pool.install(|| {
            fails
                .par_iter()
                .map_init(Box::<Star>::default, |s, &(gi, why)| {
                    let i = gi as usize;
                    let mut asks = Vec::new();
                    match phase {
                        Phase::Islands if why == 2 => asks.push(Repair::Split(gi)),
                        Phase::Islands => {}
                        Phase::Additions { born } => {
                            let undo = |h: u32| {
                                if h >= born {
                                    Repair::Split(h)
                                } else {
                                    Repair::Shed(h)
                                }
                            };
                            let new = |h: usize| h >= born as usize || q.has_new_lones(h);
                            if why == 2 || new(i) {
                                asks.push(undo(gi));
                            } else {
                                q.closed_star(i, s, |h| {
                                    if new(h) {
                                        asks.push(undo(h as u32));
                                    }
                                });
                            }
                        }
                    }
                    if asks.is_empty() {
                        asks.push(Repair::Split(q.nominate(i, failing_ref, s) as u32));
                    }
                    let mut touched = Vec::new();
                    for r in &asks {
                        let (Repair::Split(h) | Repair::Shed(h)) = *r;
                        touched.push(h);
                        q.neighbours(h as usize, s, &mut touched);
                    }
                    (asks, touched)
                })
                .collect()
        });
        for &(gi, _) in &fails {
            failing[gi as usize] = 0;
            // Recording: a failing group is activity, whatever its repair.
            g.touch_group(f, gi as usize);
        }
        let mut asks: Vec<Repair> = repairs.iter().flat_map(|r| r.0.iter().copied()).collect();
        asks.sort_unstable();
        asks.dedup();
        for r in &asks {
            match *r {
                Repair::Split(h) => {
                    if g.active[h as usize] != 0 {
                        g.active[h as usize] = 0;
                        g.set_vertices(f, h as usize);
                        out.split += 1;
                    }
                }
                Repair::Shed(h) => shed(f, g, h as usize),
            }
        }
        dirty.clear();
        dirty.extend(
            repairs
                .iter()
                .flat_map(|r| r.1.iter().copied())
                .filter(|&h| g.active[h as usize] != 0),
        );
        dirty.sort_unstable();
        dirty.dedup();
    }
    g.round = tables;
    if out.rounds > 0 {
        out.t_repair_s = start.elapsed().as_secs_f64() - out.t_tests_s;
    }
    out
}

/// Group `gi` gives back the lone crossings of the current phase (they become singletons).
fn shed(f: &Fixed, g: &mut Groups, gi: usize) {
    let start = g.lone_start[gi] as usize;
    let (base, len) = (g.base_len[gi] as usize, g.lone_len[gi] as usize);
    for l in &g.lone[start + base..start + len] {
        let x = l.id as usize;
        if !g.touched.is_empty() {
            g.touched[x] = 1;
        }
        g.group_of[x] = NONE;
        g.refused[x] = gi as u32;
        g.vlabel[x] = l.id;
        g.vpos[x] = f.cpos[x];
    }
    g.lone_len[gi] = base as u8;
    g.refresh(f, gi);
    if g.active[gi] != 0 {
        g.set_vertices(f, gi);
    }
}
