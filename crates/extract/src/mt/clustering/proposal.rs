//! Cluster proposals of the vertex pass: which of a point's nearby crossings may become one vertex.
//!
//! A crossing is *nearby* for the sample point C when it lies closer to C than to the other end of
//! its edge; C owns exactly its nearby crossings, so every crossing has one owner. The nearby
//! crossings of C are grouped by the link graph (two crossings are joined when their far ends are
//! themselves neighbours: the two edges bound one tetrahedron face). The islands are taken over all
//! of C's crossed edges, each island being one sheet of surface near C; the nearby crossings of one
//! sheet, when there are two or more, are a proposed group. Every crossing is in at most one
//! proposed group, and a proposal depends only on the samples of C and its neighbours (the
//! 1-ring): the proposals are a partition of the crossings that no processing order can change.
//! Integrated clustering then keeps the groups that pass the exact quotient test
//! ([`super::quotient`]); integrated-unchecked keeps those that pass the dissertation's mask
//! rules ([`Rules`]).
//!
//! ```text
//!        S1    S2                 C owns the crossings x nearer to it; the crossings whose far
//!         \ x  / x                ends S1, S2, S3 are neighbours of one another (one sheet of
//!          \  /                   surface through the tetrahedra around C) form one island,
//!   S3 --x- C ------- S4          proposed as one group. S4 is on C's side: no crossing.
//! ```

use crate::lattice::LatticeTables;

/// A proposed group: some of the nearby crossings of one point, to be merged into one vertex,
/// named by crossing id so that no lookup is needed to find them.
///
/// Crossings are numbered point by point in storage order, each point's owned crossings in
/// neighbour-bit order, so the point's owned crossings have the ids `first, first + 1, ...`;
/// bit `r` of `members` stands for id `first + r`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Candidate {
    /// Id of the owning point's first owned crossing.
    pub first: u32,
    /// The crossings to merge, by rank among the point's owned crossings (see above).
    pub members: u16,
    /// The same crossings by neighbour bit (the directions of their edges from the owner).
    pub dirs: u16,
    /// Storage slot of the owning point.
    pub slot: u32,
}

impl Candidate {
    /// Whether crossing `id` is one of the members.
    #[inline(always)]
    pub fn has(self, id: u32) -> bool {
        let r = id.wrapping_sub(self.first);
        r < 16 && (self.members >> r) & 1 != 0
    }

    /// The member with the lowest id: the group's name in the quotient (its label).
    #[inline(always)]
    pub fn leader(self) -> u32 {
        self.first + self.members.trailing_zeros()
    }

    /// Number of members.
    #[inline(always)]
    pub fn size(self) -> u32 {
        self.members.count_ones()
    }

    /// The candidate restricted to the crossings whose edges are in `dirs` (a subset of its
    /// own): bit `d` of `dirs` and bit `rank(d)` of `members` name the same crossing, so the
    /// k-th set bits of the two masks correspond.
    #[cfg(test)]
    pub fn restrict(self, dirs: u16) -> Candidate {
        let (mut all_dirs, mut all_members) = (self.dirs, self.members);
        let mut members = 0;
        while all_dirs != 0 {
            let (d, m) = (
                all_dirs & all_dirs.wrapping_neg(),
                all_members & all_members.wrapping_neg(),
            );
            if dirs & d != 0 {
                members |= m;
            }
            all_dirs &= all_dirs - 1;
            all_members &= all_members - 1;
        }
        Candidate {
            members,
            dirs: dirs & self.dirs,
            ..self
        }
    }

    /// The ids of the crossings to merge, in increasing order.
    pub fn ids(self) -> impl Iterator<Item = u32> {
        let mut bits = self.members;
        std::iter::from_fn(move || {
            (bits != 0).then(|| {
                let r = bits.trailing_zeros();
                bits &= bits - 1;
                self.first + r
            })
        })
    }
}

/// The bits of `bits` (a subset of `mask`) renumbered by their rank among the bits of `mask`
/// (a parallel bit extract): bit `d` of `bits` becomes bit `popcount(mask & ((1 << d) - 1))`.
pub fn compress(bits: u16, mask: u16) -> u16 {
    let mut out = 0u16;
    let mut m = mask;
    let mut r = 0;
    while m != 0 {
        let d = m.trailing_zeros();
        m &= m - 1;
        if bits & (1 << d) != 0 {
            out |= 1 << r;
        }
        r += 1;
    }
    out
}

/// Counts of the proposal step.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ProposalCounts {
    /// Islands of two or more nearby crossings.
    pub proposed: usize,
    /// Of those, refused by the mask rules.
    pub rejected: usize,
}

impl ProposalCounts {
    /// Adds another block's counts.
    pub fn add(&mut self, o: ProposalCounts) {
        self.proposed += o.proposed;
        self.rejected += o.rejected;
    }
}

/// Which mask rules filter the proposals.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Rules {
    /// Every island of two or more nearby crossings is proposed: the exact quotient test
    /// ([`super::quotient`]) decides (integrated clustering).
    Islands,
    /// The dissertation's rules: no merge with more than 10 nearby crossings or with a loop
    /// through the point (integrated-unchecked, which has no other safeguard).
    Dissertation,
}

/// One point's edges, by neighbour bit: `valid`, the neighbours whose edges exist (all 14
/// except on the box faces); `inner`, those whose edges have every tetrahedron around them (a
/// crossing there is an inner vertex of plain MT; the others are on the mesh's boundary at the
/// box faces and are never grouped by [`Rules::Islands`]); `owned`, the point's nearby
/// crossings; `crossed`, all its crossed edges (the neighbours on the other side of the
/// threshold).
#[derive(Clone, Copy, Debug)]
pub(crate) struct PointEdges {
    pub(crate) valid: u16,
    pub(crate) inner: u16,
    pub(crate) owned: u16,
    pub(crate) crossed: u16,
}

/// Proposes the clusters of one point (storage slot `slot`), whose first owned crossing has id
/// `first`, from its `edges`.
pub fn propose(
    t: &LatticeTables,
    first: u32,
    slot: u32,
    edges: PointEdges,
    rules: Rules,
    out: &mut Vec<Candidate>,
) -> ProposalCounts {
    let PointEdges {
        valid,
        inner,
        owned,
        crossed,
    } = edges;
    let mut counts = ProposalCounts::default();
    if owned.count_ones() < 2 {
        return counts;
    }
    let dissertation = rules == Rules::Dissertation;
    // More than 10 nearby crossings: a complex, likely concave case; do not merge.
    let too_many = dissertation && owned.count_ones() > 10;
    // Loops: if the neighbours whose edges are not nearby crossings fall apart into several
    // islands, merging would collapse a tube or a loop through the point.
    let loops = dissertation && t.islands(valid & !owned).nth(1).is_some();
    // One cluster per sheet of surface passing the point: the crossed edges fall into islands
    // of the link graph (each island is one sheet), and the point's nearby crossings of one sheet
    // become one vertex. (Splitting by the nearby crossings alone would cut a sheet wherever the
    // crossing joining two of them belongs to the neighbour, leaving many lone vertices.)
    for sheet in t.islands(crossed) {
        let island = sheet & owned & if dissertation { valid } else { inner };
        if island.count_ones() < 2 {
            continue;
        }
        // The exact test contracts only groups connected through mesh edges; two crossings of
        // the point are joined by one exactly when their neighbours are adjacent (they then
        // share a tetrahedron with the point, and its triangles join the two crossings), so the
        // parts are the islands of the island itself. Parts of one crossing are lone crossings.
        // (Crossings on the mesh's boundary were left out above: a group holding one could not
        // pass, and leaving them out keeps the rest of their island.)
        let parts: &mut dyn Iterator<Item = u16> = if dissertation {
            &mut std::iter::once(island)
        } else {
            &mut t.islands(island)
        };
        for part in parts {
            if part.count_ones() < 2 {
                continue;
            }
            counts.proposed += 1;
            if too_many || loops {
                counts.rejected += 1;
                continue;
            }
            out.push(Candidate {
                first,
                members: compress(part, owned),
                dirs: part,
                slot,
            });
        }
    }
    counts
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lattice::FULL;
    use crate::Lattice;

    /// `propose` at a point with id 0 and slot 0 whose 14 neighbours exist and whose edges are
    /// all inner.
    fn propose_inner(
        t: &LatticeTables,
        owned: u16,
        crossed: u16,
        rules: Rules,
        out: &mut Vec<Candidate>,
    ) -> ProposalCounts {
        propose(t, 0, 0, edges(FULL, FULL, owned, crossed), rules, out)
    }

    /// The edges of a point, in the order of [`PointEdges`]'s fields.
    fn edges(valid: u16, inner: u16, owned: u16, crossed: u16) -> PointEdges {
        PointEdges {
            valid,
            inner,
            owned,
            crossed,
        }
    }

    #[test]
    fn islands_of_two_or_more_are_proposed_once_each() {
        let t = LatticeTables::get(Lattice::BodyCentred);
        // +x (0) with its adjacent diagonals 6 and 7; and -x (1) alone.
        let owned = (1 << 0) | (1 << 6) | (1 << 7) | (1 << 1);
        let mut out = Vec::new();
        let c = propose(
            t,
            5,
            3,
            edges(FULL, FULL, owned, owned),
            Rules::Islands,
            &mut out,
        );
        assert_eq!(c.proposed, 1);
        assert_eq!(out.len() + c.rejected, 1);
    }

    #[test]
    fn members_name_the_ids_of_the_island_crossings() {
        // Ids of a point's owned crossings: `first` plus the rank of the neighbour bit among the
        // owned bits (the numbering of the vertex pass).
        let id = |first: u32, owned: u16, d: u32| first + (owned & ((1u16 << d) - 1)).count_ones();
        let t = LatticeTables::get(Lattice::BodyCentred);
        for owned in [0x0003u16, 0x00C1, 0x3FC0 ^ 0x0100, 0x1234, 0x0F0F] {
            let mut out = Vec::new();
            let e = edges(FULL, FULL, owned, owned);
            propose(t, 100, 0, e, Rules::Islands, &mut out);
            for c in &out {
                let expected: Vec<u32> = t
                    .islands(owned)
                    .filter(|sheet| sheet.count_ones() >= 2)
                    .find(|sheet| compress(*sheet, owned) == c.members)
                    .map(|sheet| {
                        (0..14)
                            .filter(|d| sheet & (1 << d) != 0)
                            .map(|d| id(100, owned, d))
                            .collect()
                    })
                    .expect("the members are one island of the owned crossings");
                assert_eq!(c.ids().collect::<Vec<_>>(), expected);
            }
        }
        assert_eq!(compress(0b1010_0000, 0b1110_0100), 0b1010);
        assert_eq!(compress(0, 0x3FFF), 0);
        assert_eq!(compress(0x3FFF, 0x3FFF), 0x3FFF);
    }

    #[test]
    fn islands_are_cut_into_parts_joined_by_mesh_edges_and_skip_the_mesh_boundary() {
        let t = LatticeTables::get(Lattice::BodyCentred);
        // +x (0) and -x (1) are not adjacent; the diagonals 6 and 7 (adjacent to +x) join the
        // sheet, but belong to the neighbours: the point's own crossings +x and -x are joined
        // by no mesh edge.
        let crossed = (1 << 0) | (1 << 1) | (1 << 6) | (1 << 7) | (1 << 9) | (1 << 11);
        assert_eq!(t.islands(crossed).count(), 1, "one sheet");
        let owned = (1 << 0) | (1 << 1);
        let mut out = Vec::new();
        propose_inner(t, owned, crossed, Rules::Islands, &mut out);
        assert!(out.is_empty(), "two parts of one crossing each: {out:?}");
        // The dissertation's rules propose the sheet's crossings as one cluster.
        propose_inner(t, owned, crossed, Rules::Dissertation, &mut out);
        assert_eq!(out.len(), 1);
        // A connected island loses its crossings on the mesh boundary (not inner), keeping
        // the rest when two or more are left.
        let owned = (1 << 0) | (1 << 6) | (1 << 7);
        out.clear();
        let e = edges(FULL, FULL & !(1 << 7), owned, owned);
        propose(t, 0, 0, e, Rules::Islands, &mut out);
        assert_eq!(out.len(), 1);
        assert_eq!(out[0].dirs, (1 << 0) | (1 << 6));
        assert_eq!(out[0].members, compress((1 << 0) | (1 << 6), owned));
    }

    #[test]
    fn a_restricted_candidate_names_the_same_crossings() {
        let owned: u16 = 0b0011_0110_1001;
        let dirs: u16 = 0b0011_0000_1001;
        let c = Candidate {
            first: 10,
            members: compress(dirs, owned),
            dirs,
            slot: 0,
        };
        for sub in [0b0001_0000_0001u16, 0b0010_0000_1000, dirs, 0] {
            let r = c.restrict(sub);
            assert_eq!(r.dirs, sub);
            assert_eq!(r.members, compress(sub, owned), "{sub:b}");
            assert_eq!((r.first, r.slot), (10, 0));
        }
    }

    #[test]
    fn more_than_ten_nearby_crossings_are_not_merged() {
        let t = LatticeTables::get(Lattice::Simple);
        let owned = 0x07FF; // 11 crossings
        let mut out = Vec::new();
        let c = propose_inner(t, owned, owned, Rules::Dissertation, &mut out);
        assert!(out.is_empty());
        assert_eq!(c.rejected, c.proposed);
        assert!(c.proposed >= 1);
    }

    #[test]
    fn a_loop_through_the_point_is_not_merged() {
        // All 8 diagonals nearby: they form one island, but the 6 axial neighbours left over are
        // pairwise non-adjacent, so the complement splits: merging would pinch the surface.
        let t = LatticeTables::get(Lattice::BodyCentred);
        let owned = 0x3FC0;
        let mut out = Vec::new();
        let c = propose_inner(t, owned, owned, Rules::Dissertation, &mut out);
        assert_eq!(c.proposed, 1);
        assert_eq!(c.rejected, 1);
        assert!(out.is_empty());
    }
}
