//! Tile keys of the tile rule ([`crate::Tiling`]): which tile, if any, may merge a crossing.
//!
//! The *footprint* of a crossing is the union of the tetrahedra around its lattice edge: every
//! triangle that can touch the crossing's vertex comes from one of them. A crossing whose
//! footprint lies in one tile (closed box) gets that tile's key; the others get [`NO_TILE`] and
//! are never merged. A merge is allowed when all its vertices carry the same key; merged vertices
//! keep the key of their representative, so by induction every merge touches only tetrahedra of
//! one tile, and tiles never interact. Keys are computed from global lattice coordinates (the
//! grid's offset in the tiling), so a sub-box gives the same keys as the whole volume.

use std::sync::OnceLock;

use crate::lattice::{LatticeTables, Offset};
use crate::{Lattice, Samples, Tiling};

/// Key of crossings that no tile may merge.
pub const NO_TILE: u64 = u64::MAX;

/// Footprint boxes `(lo, hi)` of the edge from a point of parity `par` (`[par][d]`) to its
/// neighbour `d`, relative to the point, in lattice units.
type Footprints = [[(Offset, Offset); 14]; 2];

/// The footprints of `lattice`, derived from its tetrahedron templates: every tetrahedron around
/// an edge is a translate of a template, so the union over the templates' edges of the same
/// direction and parity covers all of them.
fn footprints(lattice: Lattice) -> &'static Footprints {
    static BCDL: OnceLock<Footprints> = OnceLock::new();
    static SIMPLE: OnceLock<Footprints> = OnceLock::new();
    let cell = match lattice {
        Lattice::BodyCentred => &BCDL,
        Lattice::Simple => &SIMPLE,
    };
    cell.get_or_init(|| {
        let t = LatticeTables::get(lattice);
        let mut fp = [[([i32::MAX; 3], [i32::MIN; 3]); 14]; 2];
        for tet in &t.tetrahedra {
            let lo: Offset = [0, 1, 2].map(|a| tet.iter().map(|v| v[a]).min().unwrap_or(0));
            let hi: Offset = [0, 1, 2].map(|a| tet.iter().map(|v| v[a]).max().unwrap_or(0));
            for (i, vi) in tet.iter().enumerate() {
                // Body-centred templates are relative to a centre (odd point).
                let par = match lattice {
                    Lattice::BodyCentred => ((vi[0] & 1) ^ 1) as usize,
                    Lattice::Simple => 0,
                };
                for (j, vj) in tet.iter().enumerate() {
                    if i == j {
                        continue;
                    }
                    let Some(d) = t.direction([0, 1, 2].map(|a| vj[a] - vi[a])) else {
                        continue;
                    };
                    let (flo, fhi) = &mut fp[par][d];
                    for a in 0..3 {
                        flo[a] = flo[a].min(lo[a] - vi[a]);
                        fhi[a] = fhi[a].max(hi[a] - vi[a]);
                    }
                }
            }
        }
        if lattice == Lattice::Simple {
            fp[1] = fp[0];
        }
        fp
    })
}

/// The key of the tile holding box `lo ..= hi` (global lattice units, `unit` lattice units per
/// cell), or [`NO_TILE`].
fn key_of(tiling: &Tiling, unit: i64, lo: [i64; 3], hi: [i64; 3]) -> u64 {
    let mut key = 0u64;
    for a in 0..3 {
        let size = i64::try_from(tiling.size[a])
            .unwrap_or(i64::MAX)
            .saturating_mul(unit)
            .max(1);
        let t = lo[a].div_euclid(size);
        if t < 0 || hi[a] > (t + 1).saturating_mul(size) || t >= 1 << 21 {
            return NO_TILE;
        }
        key |= (t as u64) << (21 * a);
    }
    key
}

/// Keys of all crossings in id order: crossings are numbered by owner (storage order), then by
/// neighbour index, so walking the owned bits in that order meets them in id order. `points`
/// visits the slots that may own crossings with their owned bits (bit d: the edge to neighbour
/// d), in storage order (the others own none).
pub(crate) fn crossing_keys(
    samples: &Samples,
    tiling: &Tiling,
    points: impl FnOnce(&mut dyn FnMut(usize, u16)),
    out: &mut Vec<u64>,
) {
    out.clear();
    let Some(lattice) = samples.lattice else {
        return;
    };
    let t = LatticeTables::get(lattice);
    let fp = footprints(lattice);
    let (unit, shift) = match lattice {
        Lattice::BodyCentred => (2i64, tiling.grid_offset.map(|o| 2 * o as i64)),
        Lattice::Simple => (1i64, tiling.grid_offset.map(|o| o as i64)),
    };
    let [dx, dy, _] = samples.dims;
    points(&mut |slot, owned| {
        let mut bits = owned;
        if bits == 0 {
            return;
        }
        let (sx, sy, z) = (slot % dx, (slot / dx) % dy, slot / (dx * dy));
        let p: [i64; 3] = match lattice {
            Lattice::BodyCentred => {
                let zz = z as i64 - 1;
                let odd = zz & 1;
                [2 * sx as i64 - odd, 2 * sy as i64 - odd, zz]
            }
            Lattice::Simple => [sx as i64, sy as i64, z as i64],
        };
        let par = (p[0] & 1) as usize;
        while bits != 0 {
            let d = bits.trailing_zeros() as usize;
            bits &= bits - 1;
            debug_assert!(t.offsets[d] != [0; 3]);
            let (lo, hi) = fp[par][d];
            let g = [0, 1, 2].map(|a| p[a] + shift[a]);
            out.push(key_of(
                tiling,
                unit,
                [0, 1, 2].map(|a| g[a] + i64::from(lo[a])),
                [0, 1, 2].map(|a| g[a] + i64::from(hi[a])),
            ));
        }
    });
}

/// Whether the vertices `k` may merge: all carry the same tile key.
#[inline]
pub(crate) fn same_tile(keys: &[u64], k: &[u32]) -> bool {
    let first = keys[k[0] as usize];
    first != NO_TILE && k.iter().all(|&v| keys[v as usize] == first)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn footprints_span_the_cells_around_each_edge() {
        // Body-centred centre-to-centre edge along +x: the 4 tetrahedra of the face between them.
        let fp = footprints(Lattice::BodyCentred);
        assert_eq!(fp[1][0], ([0, -1, -1], [2, 1, 1]));
        // Corner-to-corner along +x: the tetrahedra of the 4 faces around it.
        assert_eq!(fp[0][0], ([0, -1, -1], [2, 1, 1]));
        // Corner to the centre at (+1, +1, +1): the tetrahedra of the centre's 3 faces at the
        // corner reach the 3 centres beyond them.
        let d = LatticeTables::get(Lattice::BodyCentred)
            .direction([1, 1, 1])
            .expect("a neighbour");
        assert_eq!(fp[0][d], ([-1, -1, -1], [2, 2, 2]));
        // Simple lattice: the main diagonal lies in one cube only.
        let t = LatticeTables::get(Lattice::Simple);
        let d = t.direction([1, 1, 1]).expect("a neighbour");
        assert_eq!(footprints(Lattice::Simple)[0][d], ([0, 0, 0], [1, 1, 1]));
        // Every footprint contains its edge.
        for (lattice, pars) in [(Lattice::BodyCentred, 2), (Lattice::Simple, 1)] {
            let t = LatticeTables::get(lattice);
            for par in 0..pars {
                for d in 0..14 {
                    let (lo, hi) = footprints(lattice)[par][d];
                    for a in 0..3 {
                        assert!(lo[a] <= 0.min(t.offsets[d][a]), "{lattice:?} {par} {d}");
                        assert!(hi[a] >= 0.max(t.offsets[d][a]), "{lattice:?} {par} {d}");
                    }
                }
            }
        }
    }

    #[test]
    fn keys_name_the_tile_holding_the_whole_box() {
        let t = Tiling::new([4, 4, 4], [0; 3]);
        assert_eq!(key_of(&t, 1, [0; 3], [4; 3]), 0);
        assert_eq!(key_of(&t, 1, [4, 0, 0], [8, 1, 1]), 1);
        assert_eq!(key_of(&t, 1, [0, 4, 0], [1, 5, 1]), 1 << 21);
        assert_eq!(key_of(&t, 1, [3, 0, 0], [5, 1, 1]), NO_TILE);
        assert_eq!(key_of(&t, 2, [-1, 0, 0], [1, 1, 1]), NO_TILE);
        assert!(same_tile(&[5, 5, 7], &[0, 1]));
        assert!(!same_tile(&[5, 5, 7], &[0, 2]));
        assert!(!same_tile(&[NO_TILE, NO_TILE], &[0, 1]));
    }
}
