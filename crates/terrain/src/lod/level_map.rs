//! The chunk level map: an octree of chunks, 2:1 balanced, chosen from a viewer and a distance
//! rule (or any split rule).
//!
//! ```text
//!   level L roots (one per root chunk)  ->  split while the rule asks  ->  2:1 balance
//!   a chunk of level l: C^3 cells of edge 2^(l+1) u, box at * C 2^(l+1) + [0, C 2^(l+1)]^3
//!   2:1: two chunks whose closed boxes touch (face, edge or corner) differ by <= 1 level
//! ```
//!
//! The leaves tile the world box `[0, roots * C 2^(L+1)]` (in `u`) exactly; every point of the
//! world lies in exactly one leaf's half-open box `[lo, hi)`.

use std::collections::HashSet;

use super::error::LodError;

/// The shape of a multiresolution world: levels `0..=levels` (0 finest), chunks of `chunk^3`
/// cells at every level, `roots` chunks of the coarsest level along each axis.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LodGeometry {
    /// The coarsest level `L`; level `l` has cells of `2^(l+1)` u (`h * 2^l`).
    pub levels: u8,
    /// Cells per chunk edge, `C`.
    pub chunk: u32,
    /// Coarsest-level chunks along x, y, z.
    pub roots: [u32; 3],
}

impl LodGeometry {
    /// Checks the numbers: `levels <= 12`, `2 <= chunk <= 256`, at least one root on
    /// each axis, and a world small enough for `i32` lattice coordinates.
    pub fn new(levels: u8, chunk: u32, roots: [u32; 3]) -> Result<Self, LodError> {
        if levels > 12 {
            return Err(LodError::Invalid(format!("levels {levels} > 12")));
        }
        if !(2..=256).contains(&chunk) {
            return Err(LodError::Invalid(format!("chunk {chunk} not in 2..=256")));
        }
        if roots.contains(&0) {
            return Err(LodError::Invalid("every axis needs a root chunk".into()));
        }
        let g = LodGeometry {
            levels,
            chunk,
            roots,
        };
        let max = (0..3).map(|i| g.world_size()[i]).max().unwrap_or(0);
        if max > i64::from(i32::MAX / 8) {
            return Err(LodError::Invalid(format!(
                "world of {max} u is too large for i32 coordinates"
            )));
        }
        Ok(g)
    }

    /// Edge of a chunk of `level` in `u`.
    pub fn chunk_size(&self, level: u8) -> i64 {
        i64::from(self.chunk) << (level + 1)
    }

    /// The world box's far corner in `u` (the near one is the origin).
    pub fn world_size(&self) -> [i64; 3] {
        let s = self.chunk_size(self.levels);
        self.roots.map(|r| i64::from(r) * s)
    }
}

/// The distance rule of [`LevelMap::from_viewer`]: whether the viewer (in `u`) is closer to
/// chunk `k`'s box than `ratio` times its edge.
pub fn viewer_splits(geom: &LodGeometry, k: &ChunkKey, viewer: [f64; 3], ratio: f64) -> bool {
    let (lo, hi) = k.bounds(geom);
    let d2: f64 = (0..3)
        .map(|i| {
            let d = (lo[i] as f64 - viewer[i])
                .max(viewer[i] - hi[i] as f64)
                .max(0.0);
            d * d
        })
        .sum();
    d2.sqrt() < ratio * geom.chunk_size(k.level) as f64
}

/// One chunk: its level and its index among the chunks of that level.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct ChunkKey {
    /// Level (0 finest).
    pub level: u8,
    /// Index along x, y, z among the chunks of `level`.
    pub at: [i32; 3],
}

impl ChunkKey {
    /// The chunk's box `(lo, hi)` in `u` (closed; ownership uses it half-open).
    pub fn bounds(&self, geom: &LodGeometry) -> ([i64; 3], [i64; 3]) {
        let s = geom.chunk_size(self.level);
        let lo = self.at.map(|a| i64::from(a) * s);
        (lo, lo.map(|v| v + s))
    }

    fn children(&self) -> impl Iterator<Item = ChunkKey> + '_ {
        (0..8).map(move |k| ChunkKey {
            level: self.level - 1,
            at: [
                self.at[0] * 2 + (k & 1),
                self.at[1] * 2 + ((k >> 1) & 1),
                self.at[2] * 2 + ((k >> 2) & 1),
            ],
        })
    }
}

/// A 2:1-balanced octree of chunks over the world: the level every part of the world is meshed
/// at.
#[derive(Clone, Debug)]
pub struct LevelMap {
    geom: LodGeometry,
    /// Leaves, sorted (by level, then index): the order chunk meshes are assembled in.
    leaves: Vec<ChunkKey>,
    set: HashSet<ChunkKey>,
}

impl PartialEq for LevelMap {
    fn eq(&self, other: &Self) -> bool {
        self.geom == other.geom && self.leaves == other.leaves
    }
}

impl LevelMap {
    /// Splits every chunk of level `> 0` for which `split` says so, from the roots down, then
    /// balances 2:1 (splitting more, never merging).
    pub fn build(geom: LodGeometry, mut split: impl FnMut(&ChunkKey) -> bool) -> Self {
        let mut set = HashSet::new();
        let mut stack: Vec<ChunkKey> = Vec::new();
        for x in 0..geom.roots[0] as i32 {
            for y in 0..geom.roots[1] as i32 {
                for z in 0..geom.roots[2] as i32 {
                    stack.push(ChunkKey {
                        level: geom.levels,
                        at: [x, y, z],
                    });
                }
            }
        }
        while let Some(k) = stack.pop() {
            if k.level > 0 && split(&k) {
                stack.extend(k.children());
            } else {
                set.insert(k);
            }
        }
        let mut map = LevelMap {
            geom,
            leaves: Vec::new(),
            set,
        };
        map.balance();
        map
    }

    /// Every chunk at `level` (clamped to the coarsest).
    pub fn uniform(geom: LodGeometry, level: u8) -> Self {
        Self::build(geom, |k| k.level > level)
    }

    /// The distance rule: a chunk is split while the viewer (in `u`) is closer to its box than
    /// `ratio` times its edge, then balanced 2:1. Each level then covers a shell about `ratio`
    /// of its chunk edges thick around the finer ones (a clipmap made of chunks).
    pub fn from_viewer(geom: LodGeometry, viewer: [f64; 3], ratio: f64) -> Self {
        Self::build(geom, |k| viewer_splits(&geom, k, viewer, ratio))
    }

    /// A random map for tests and measurements: each chunk is split with probability
    /// `split` (decided by a hash of `seed` and the chunk, so the map is a function of the
    /// seed), then balanced 2:1.
    pub fn random(geom: LodGeometry, seed: u64, split: f64) -> Self {
        Self::build(geom, |k| {
            let mut z = seed
                ^ (u64::from(k.level) << 56)
                ^ ((k.at[0] as u64 & 0xFFFF) << 32)
                ^ ((k.at[1] as u64 & 0xFFFF) << 16)
                ^ (k.at[2] as u64 & 0xFFFF);
            // SplitMix64 finaliser.
            z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
            z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            z ^= z >> 31;
            ((z >> 11) as f64 / (1u64 << 53) as f64) < split
        })
    }

    /// The geometry.
    pub fn geometry(&self) -> &LodGeometry {
        &self.geom
    }

    /// The leaves (chunks), sorted by level then index.
    pub fn chunks(&self) -> &[ChunkKey] {
        &self.leaves
    }

    /// Whether `key` is a leaf.
    pub fn contains(&self, key: &ChunkKey) -> bool {
        self.set.contains(key)
    }

    /// The finest level among the leaves whose closed box meets the closed box `[lo, hi]`
    /// (`None` when the box misses the world).
    pub fn min_level_touching(&self, lo: [i64; 3], hi: [i64; 3]) -> Option<u8> {
        let mut best: Option<u8> = None;
        for root in self.roots_touching(lo, hi) {
            self.descend(root, lo, hi, &mut best);
        }
        best
    }

    /// The roots whose closed box may meet the closed box `[lo, hi]`.
    fn roots_touching(&self, lo: [i64; 3], hi: [i64; 3]) -> impl Iterator<Item = ChunkKey> {
        let g = self.geom;
        let s = g.chunk_size(g.levels);
        let r = |i: usize| {
            let a = (lo[i].div_euclid(s) - 1).max(0);
            let b = hi[i].div_euclid(s).min(i64::from(g.roots[i]) - 1);
            a as i32..=b as i32
        };
        let (rx, ry, rz) = (r(0), r(1), r(2));
        rx.flat_map(move |x| {
            let rz = rz.clone();
            ry.clone()
                .flat_map(move |y| rz.clone().map(move |z| [x, y, z]))
        })
        .map(move |at| ChunkKey {
            level: g.levels,
            at,
        })
    }

    /// The leaves whose closed box meets the closed box `[lo, hi]`, sorted.
    pub fn leaves_touching(&self, lo: [i64; 3], hi: [i64; 3]) -> Vec<ChunkKey> {
        let mut out = Vec::new();
        let g = &self.geom;
        let mut stack: Vec<ChunkKey> = self.roots_touching(lo, hi).collect();
        while let Some(k) = stack.pop() {
            let (a, b) = k.bounds(g);
            if (0..3).any(|i| a[i] > hi[i] || b[i] < lo[i]) {
                continue;
            }
            if self.set.contains(&k) {
                out.push(k);
            } else if k.level > 0 {
                stack.extend(k.children());
            }
        }
        out.sort_unstable();
        out
    }

    fn descend(&self, k: ChunkKey, lo: [i64; 3], hi: [i64; 3], best: &mut Option<u8>) {
        let (a, b) = k.bounds(&self.geom);
        if (0..3).any(|i| a[i] > hi[i] || b[i] < lo[i]) {
            return;
        }
        // Nothing is finer than level 0. (An inner node's leaves are finer than it, so a
        // best at or below its level does not make it skippable.)
        if *best == Some(0) {
            return;
        }
        if self.set.contains(&k) {
            if best.is_none_or(|m| k.level < m) {
                *best = Some(k.level);
            }
        } else if k.level > 0 {
            for c in k.children() {
                self.descend(c, lo, hi, best);
            }
        }
    }

    /// The leaf whose half-open box `[lo, hi)` holds `4 p` given as `p4 = 4 p` (exact for
    /// centroids), if `p` is in the world.
    pub fn chunk_of4(&self, p4: [i64; 3]) -> Option<ChunkKey> {
        let g = &self.geom;
        let ws = g.world_size();
        if (0..3).any(|i| p4[i] < 0 || p4[i] >= 4 * ws[i]) {
            return None;
        }
        let mut level = g.levels;
        loop {
            let s4 = 4 * g.chunk_size(level);
            let k = ChunkKey {
                level,
                at: p4.map(|v| (v / s4) as i32),
            };
            if self.set.contains(&k) || level == 0 {
                return self.set.contains(&k).then_some(k);
            }
            level -= 1;
        }
    }

    /// Whether every two leaves whose closed boxes touch differ by at most one level.
    pub fn is_balanced(&self) -> bool {
        self.leaves.iter().all(|k| {
            let (lo, hi) = k.bounds(&self.geom);
            self.min_level_touching(lo, hi)
                .is_some_and(|m| m + 1 >= k.level)
        })
    }

    fn balance(&mut self) {
        loop {
            let mut split: Vec<ChunkKey> = self
                .set
                .iter()
                .copied()
                .filter(|k| {
                    let (lo, hi) = k.bounds(&self.geom);
                    k.level >= 2
                        && self
                            .min_level_touching(lo, hi)
                            .is_some_and(|m| m + 1 < k.level)
                })
                .collect();
            if split.is_empty() {
                break;
            }
            split.sort_unstable();
            for k in split {
                self.set.remove(&k);
                self.set.extend(k.children());
            }
        }
        self.leaves = self.set.iter().copied().collect();
        self.leaves.sort_unstable();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn geom() -> LodGeometry {
        LodGeometry::new(3, 4, [4, 1, 4]).unwrap()
    }

    #[test]
    fn leaves_tile_the_world() {
        let g = geom();
        let map = LevelMap::from_viewer(g, [3.0, 5.0, 7.0], 1.0);
        assert!(map.is_balanced());
        let vol: i64 = map
            .chunks()
            .iter()
            .map(|k| g.chunk_size(k.level).pow(3))
            .sum();
        let w = g.world_size();
        assert_eq!(vol, w[0] * w[1] * w[2]);
        assert!(map.chunks().iter().any(|k| k.level == 0));
        assert!(map.chunks().iter().any(|k| k.level == 3));
        // Every point is in exactly one half-open leaf.
        for p in [
            [0, 0, 0],
            [4, 8, 12],
            [255, 63, 255],
            [128, 32, 1],
            [200, 0, 250],
        ] {
            let p4 = p.map(|v: i64| 4 * v);
            let k = map.chunk_of4(p4).unwrap();
            let (lo, hi) = k.bounds(&g);
            assert!((0..3).all(|i| lo[i] <= p[i] && p[i] < hi[i]));
        }
        assert_eq!(map.chunk_of4([4 * 256, 0, 0]), None);
    }

    #[test]
    fn balancing_splits_what_a_rule_leaves_unbalanced() {
        let g = geom();
        // Level 0 at the far corner of the level-2 chunk at the origin touches level 2.
        let map = LevelMap::build(g, |k| match k.level {
            1 => k.at == [1, 1, 1],
            _ => k.at == [0, 0, 0],
        });
        assert!(map.is_balanced());
        // Unbalanced, the rule alone gives 15 roots + 7 + 7 + 8 leaves: the level-0 chunks
        // touch level-2 ones, which balancing splits.
        assert!(
            map.chunks().len() > 15 + 7 + 7 + 8,
            "{}",
            map.chunks().len()
        );
    }

    #[test]
    fn the_finest_touching_leaf_is_found_behind_a_coarser_one() {
        // Root 0 is a leaf (level 1); root 1 is split. A box touching both must see level 0,
        // whichever root is visited first (a search that skipped an inner node once it had a
        // leaf of the node's level missed it).
        let g = LodGeometry::new(1, 4, [2, 1, 1]).unwrap();
        let map = LevelMap::build(g, |k| k.at[0] == 1);
        let s = g.chunk_size(1);
        assert_eq!(map.min_level_touching([0; 3], [s, s, s]), Some(0));
        assert_eq!(map.min_level_touching([0; 3], [s - 1, s, s]), Some(1));
        for k in map.chunks() {
            let (lo, hi) = k.bounds(&g);
            let want = map.leaves_touching(lo, hi).iter().map(|n| n.level).min();
            assert_eq!(map.min_level_touching(lo, hi), want, "{k:?}");
        }
    }

    #[test]
    fn bad_geometry_is_refused() {
        assert!(LodGeometry::new(13, 4, [1, 1, 1]).is_err());
        assert!(LodGeometry::new(2, 1, [1, 1, 1]).is_err());
        assert!(LodGeometry::new(2, 4, [1, 0, 1]).is_err());
        assert!(LodGeometry::new(12, 256, [1 << 20, 1, 1]).is_err());
    }
}
