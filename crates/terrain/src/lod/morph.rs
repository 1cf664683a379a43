//! Geomorphing between levels: the value a lattice point gives marching tetrahedra blends, with
//! the viewer's distance, from the field's value to the value the next coarser level
//! interpolates there, so that where a chunk's level changes its surface is already (nearly) the
//! coarser level's, and the change of level does not pop.
//!
//! ```text
//!   level(p): the coarsest level (<= L) whose lattice holds p
//!   parents: a point p of level l < L is the midpoint of exactly one edge (a, b) of level
//!            l+1's lattice (s = 2^(l+1) u the level-l cell, S = 2 s the level-(l+1) cell):
//!     p a level-l centre (all p_i = s/2 mod s):  a = the level-(l+1) corner with
//!                        a_i = p_i -+ s/2 (whichever is a multiple of S),  b = 2 p - a
//!     p a level-l corner (all p_i = 0 mod s):    the axis `x` whose p_x mod S differs from the
//!                        other two's,  (a, b) = p -+ s e_x
//!   g(p) = f(p) + w_l(p) (I(p) - f(p)),   I(p) = (g(a) + g(b)) / 2,   g = f at level L
//!   w_l(p) = clamp((|p - viewer| - start_l) / (end_l - lead - start_l), 0, 1)
//!     end_l   = ratio * (edge of a level-(l+1) chunk): LevelMap::from_viewer splits a
//!               level-(l+1) chunk only when the viewer is nearer than this, so every point
//!               of a chunk of level > l is at least this far, and there w_l = 1
//!     start_l = end_l - band * ratio * (edge of a level-l chunk),   0 < band <= 1
//!     lead    = the longest viewer step the morph is made for (0 <= lead < end_0 - start_0):
//!               a chunk split at this step was whole at the last one, so every point of it
//!               is at least end_l - lead away now, and there w_l = 1 too
//! ```
//!
//! - **Closed, whatever the weights.** `g` is a function of the point, the field, the viewer
//!   and the settings alone, so every chunk that samples a point reads the same bits, and
//!   marching tetrahedra on a conforming mesh is closed for any values.
//! - **No pop where the level changes.** Where a chunk leaves level `l + 1` for level `l` (the
//!   viewer came nearer by at most `lead`) or comes back, `w_l = 1` at every point of its box:
//!   the values at its level-`l` points there are the linear interpolant of level `l + 1`, and
//!   red refinement nests, so the finer tets' surface there is the coarser tets' surface (to
//!   rounding; tested). The viewer moves the surface only gradually, as `w` changes: over a
//!   band `end_l - lead - start_l` deep, so by about `step / (that depth)` of the coarse and
//!   fine surfaces' distance per step.
//! - **The price.** A chunk is re-meshed whenever the weights at its points can change
//!   ([`Morph::may_differ`]): every chunk in a band, at every step of the viewer.

use foldhash::HashMap;
use glam::Vec3;
use rmt_fields::ScalarField;

use super::error::LodError;
use super::lattice::{cell_size, Point};
use super::level_map::LodGeometry;

/// The morph of a multiresolution world for one viewer position (see the module doc).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Morph {
    /// The viewer in lattice units `u`.
    pub viewer: [f64; 3],
    /// The distance rule's ratio ([`super::LevelMap::from_viewer`]).
    pub ratio: f64,
    /// The width of a level's morph band, as a fraction of `ratio` times its chunk edge.
    pub band: f64,
    /// The longest viewer step (in `u`) the weights reach 1 ahead of.
    pub lead: f64,
    /// Cells per chunk edge.
    pub chunk: u32,
    /// The coarsest level `L` (its points do not morph).
    pub levels: u8,
}

impl Morph {
    /// The morph of a world of `geom` under the distance rule `ratio`, for a viewer at
    /// `viewer` that moves at most `lead` per step (both in `u`). `band` must lie in `(0, 1]`,
    /// and `lead` below level 0's band.
    pub fn new(
        geom: &LodGeometry,
        ratio: f64,
        band: f64,
        lead: f64,
        viewer: [f64; 3],
    ) -> Result<Self, LodError> {
        if !(band.is_finite() && band > 0.0 && band <= 1.0) {
            return Err(LodError::Invalid(format!(
                "morph band {band} not in (0, 1]"
            )));
        }
        if !(ratio.is_finite() && ratio > 0.0) {
            return Err(LodError::Invalid(format!(
                "a morph needs a ratio > 0, not {ratio}"
            )));
        }
        if !viewer.iter().all(|v| v.is_finite()) {
            return Err(LodError::Invalid(format!(
                "viewer {viewer:?} is not finite"
            )));
        }
        let m = Morph {
            viewer,
            ratio,
            band,
            lead: 0.0,
            chunk: geom.chunk,
            levels: geom.levels,
        };
        let depth = m.ramp(0).1 - m.ramp(0).0;
        if !(lead.is_finite() && lead >= 0.0 && lead < depth) {
            return Err(LodError::Invalid(format!(
                "a viewer step of {lead} u does not fit level 0's morph band of {depth} u: \
                 widen the band or take shorter steps"
            )));
        }
        Ok(Morph { lead, ..m })
    }

    /// `(start_l, end_l)` of level `level`'s ramp, in `u`.
    fn ramp(&self, level: u8) -> (f64, f64) {
        let edge = |l: u8| f64::from(self.chunk) * cell_size(l) as f64;
        let end = self.ratio * edge(level + 1);
        (end - self.band * self.ratio * edge(level), end - self.lead)
    }

    /// `w_level(p)`: 0 near the viewer, 1 from where chunks of level `level + 1` begin; 0 at
    /// the coarsest level.
    pub fn weight(&self, level: u8, p: Point) -> f64 {
        if level >= self.levels {
            return 0.0;
        }
        let d = (0..3)
            .map(|i| (f64::from(p[i]) - self.viewer[i]).powi(2))
            .sum::<f64>()
            .sqrt();
        let (s, e) = self.ramp(level);
        ((d - s) / (e - s)).clamp(0.0, 1.0)
    }

    /// The nearest and farthest distance from the viewer to the box `[lo, hi]` (`u`).
    fn distances(&self, lo: [i64; 3], hi: [i64; 3]) -> (f64, f64) {
        let (mut near, mut far) = (0.0, 0.0);
        for i in 0..3 {
            let (a, b, v) = (lo[i] as f64, hi[i] as f64, self.viewer[i]);
            let n = (a - v).max(v - b).max(0.0);
            let f = (a - v).abs().max((b - v).abs());
            near += n * n;
            far += f * f;
        }
        (near.sqrt(), far.sqrt())
    }

    /// How far (in `u`, per axis) the values at points of the box `[lo, hi]` can reach for
    /// their parents: a level-`m` point's parents are within one level-`m` cell, so the sum of
    /// the cells of every level whose weights can be non-zero there.
    pub fn reach(&self, lo: [i64; 3], hi: [i64; 3]) -> i64 {
        let g = cell_size(self.levels);
        let (_, far) = self.distances(lo.map(|v| v - g), hi.map(|v| v + g));
        (0..self.levels)
            .filter(|&m| far > self.ramp(m).0)
            .map(cell_size)
            .sum()
    }

    /// Whether a value at some point of the box `[lo, hi]` can differ between `self` and
    /// `other` (conservative: `true` when unsure). A point's value depends on its own weight
    /// and its parents', whose points are within one cell of their level.
    pub fn may_differ(&self, other: &Morph, lo: [i64; 3], hi: [i64; 3]) -> bool {
        if (self.ratio, self.band, self.lead, self.chunk, self.levels)
            != (
                other.ratio,
                other.band,
                other.lead,
                other.chunk,
                other.levels,
            )
        {
            return true;
        }
        (0..self.levels).any(|m| {
            let g = cell_size(m);
            let (lo, hi) = (lo.map(|v| v - g), hi.map(|v| v + g));
            let (a0, b0) = self.distances(lo, hi);
            let (a1, b1) = other.distances(lo, hi);
            let (near, far) = (a0.min(a1), b0.max(b1));
            let (s, e) = self.ramp(m);
            // The weight is 0 up to `s` and 1 from `e` on, for both viewers.
            !(far <= s || near >= e)
        })
    }

    /// Turns the field's values `values` at `points` into the morphed ones. `known` gives the
    /// field's value at a point when the caller sampled it already (any other point is sampled
    /// from `field` at `place(point)`, its world position).
    pub fn apply(
        &self,
        points: &[Point],
        values: &mut [f32],
        known: &dyn Fn(Point) -> Option<f32>,
        field: &dyn ScalarField,
        place: &dyn Fn(Point) -> Vec3,
    ) {
        // The points that morph, and every parent their values need (with its level, weight).
        let mut morphing: Vec<(usize, u8, f64)> = Vec::new();
        let mut need: HashMap<Point, (u8, f64)> = HashMap::default();
        let mut stack: Vec<Point> = Vec::new();
        for (i, &p) in points.iter().enumerate() {
            let l = point_level(p, self.levels);
            let w = self.weight(l, p);
            if w > 0.0 {
                morphing.push((i, l, w));
                stack.extend(parents(p, l));
            }
        }
        if morphing.is_empty() {
            return;
        }
        while let Some(q) = stack.pop() {
            if need.contains_key(&q) {
                continue;
            }
            let l = point_level(q, self.levels);
            let w = self.weight(l, q);
            need.insert(q, (l, w));
            if w > 0.0 {
                stack.extend(parents(q, l));
            }
        }
        // Coarse first: a point's parents are of a coarser level.
        let mut order: Vec<(u8, Point, f64)> = need.iter().map(|(&q, &(l, w))| (l, q, w)).collect();
        order.sort_unstable_by(|a, b| b.0.cmp(&a.0).then(a.1.cmp(&b.1)));
        let mut f: Vec<f32> = Vec::with_capacity(order.len());
        let mut missing: Vec<usize> = Vec::new();
        for (i, &(_, q, _)) in order.iter().enumerate() {
            let v = known(q);
            if v.is_none() {
                missing.push(i);
            }
            f.push(v.unwrap_or(f32::NAN));
        }
        if !missing.is_empty() {
            let at: Vec<Vec3> = missing.iter().map(|&i| place(order[i].1)).collect();
            let mut out = vec![0f32; at.len()];
            field.sample_batch(&at, &mut out);
            for (&i, v) in missing.iter().zip(out) {
                f[i] = v;
            }
        }
        let mut g: HashMap<Point, f32> = HashMap::default();
        g.reserve(order.len());
        for (&(l, q, w), &fq) in order.iter().zip(&f) {
            let v = if w > 0.0 {
                blend(fq, w, &parents(q, l), &g)
            } else {
                fq
            };
            g.insert(q, v);
        }
        for (i, l, w) in morphing {
            values[i] = blend(values[i], w, &parents(points[i], l), &g);
        }
    }
}

/// `f + w (I - f)` with `I` the mean of the parents' morphed values (in `f64`, rounded once).
fn blend(f: f32, w: f64, parents: &[Point; 2], g: &HashMap<Point, f32>) -> f32 {
    let at = |p: &Point| f64::from(g.get(p).copied().unwrap_or(f32::NAN));
    let i = 0.5 * (at(&parents[0]) + at(&parents[1]));
    let f = f64::from(f);
    (f + w * (i - f)) as f32
}

/// Whether `p` is a point of level `level`'s lattice (corners `s Z^3`, centres `s Z^3 + s/2`,
/// `s = 2^(level+1)`).
pub fn in_level(p: Point, level: u8) -> bool {
    let s = cell_size(level);
    let r = p.map(|c| i64::from(c).rem_euclid(s));
    r.iter().all(|&v| v == 0) || r.iter().all(|&v| v == s / 2)
}

/// The coarsest level `<= levels` whose lattice holds `p` (0 for a point of no level's lattice,
/// which the multiresolution mesh never has).
pub fn point_level(p: Point, levels: u8) -> u8 {
    (0..=levels).rev().find(|&l| in_level(p, l)).unwrap_or(0)
}

/// The ends of the level-`(level + 1)` edge whose midpoint is `p`, a point of level `level`
/// but not of level `level + 1` (see the module doc).
pub fn parents(p: Point, level: u8) -> [Point; 2] {
    let s = cell_size(level) as i32;
    let big = 2 * i64::from(s);
    if i64::from(p[0]).rem_euclid(i64::from(s)) != 0 {
        // A centre: step half a cell towards the coarse corner on each axis.
        let a: Point = std::array::from_fn(|i| {
            if (i64::from(p[i]) - i64::from(s / 2)).rem_euclid(big) == 0 {
                p[i] - s / 2
            } else {
                p[i] + s / 2
            }
        });
        let b: Point = std::array::from_fn(|i| 2 * p[i] - a[i]);
        return [a, b];
    }
    let odd = p.map(|c| i64::from(c).rem_euclid(big) != 0);
    let x = (0..3)
        .find(|&i| odd[i] != odd[(i + 1) % 3] && odd[i] != odd[(i + 2) % 3])
        .unwrap_or(0);
    let mut a = p;
    let mut b = p;
    a[x] -= s;
    b[x] += s;
    [a, b]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every point of level `l` (not of `l + 1`) in a block is the midpoint of exactly one edge
    /// of level `l + 1`'s body-centred lattice, and [`parents`] names it: the edges are derived
    /// here from the lattice's geometry (the 14 neighbours of a point: 6 along the axes at one
    /// cell, 8 along the diagonals at half a cell per axis).
    #[test]
    fn every_finer_point_is_the_midpoint_of_one_coarser_edge() {
        for l in 0u8..3 {
            let s = cell_size(l + 1) as i32;
            let coarse = |p: Point| in_level(p, l + 1);
            let mut offsets: Vec<Point> = Vec::new();
            for a in 0..3 {
                for sign in [-1, 1] {
                    let mut o = [0; 3];
                    o[a] = sign * s;
                    offsets.push(o);
                }
            }
            for x in [-1, 1] {
                for y in [-1, 1] {
                    for z in [-1, 1] {
                        offsets.push([x * s / 2, y * s / 2, z * s / 2]);
                    }
                }
            }
            let span = 3 * s;
            let mut checked = 0;
            for x in -span..=span {
                for y in -span..=span {
                    for z in -span..=span {
                        let p = [x, y, z];
                        if !in_level(p, l) || coarse(p) {
                            continue;
                        }
                        // Edges (a, a + o) of the coarse lattice with midpoint p.
                        let mut found: Vec<[Point; 2]> = Vec::new();
                        for o in &offsets {
                            let a: Point = std::array::from_fn(|i| p[i] - o[i] / 2);
                            let b: Point = std::array::from_fn(|i| p[i] + o[i] / 2);
                            if o.iter().all(|v| v % 2 == 0) && coarse(a) && coarse(b) {
                                let mut e = [a, b];
                                e.sort_unstable();
                                if !found.contains(&e) {
                                    found.push(e);
                                }
                            }
                        }
                        assert_eq!(found.len(), 1, "level {l} point {p:?}: edges {found:?}");
                        let mut mine = parents(p, l);
                        mine.sort_unstable();
                        assert_eq!(mine, found[0], "level {l} point {p:?}");
                        assert_eq!(point_level(p, 6), l);
                        checked += 1;
                    }
                }
            }
            assert!(checked > 100, "level {l}: {checked} points");
        }
    }

    fn morph(band: f64) -> Morph {
        let g = LodGeometry::new(3, 4, [2, 1, 2]).unwrap();
        Morph::new(&g, 1.5, band, 2.0, [10.0, 3.0, 7.0]).unwrap()
    }

    #[test]
    fn weights_ramp_from_start_to_end_and_vanish_at_the_coarsest_level() {
        let m = morph(0.5);
        for l in 0..3u8 {
            let (s, e) = m.ramp(l);
            assert!(s < e && s > 0.0);
            // Points along x from the viewer.
            let at = |d: f64| [(10.0 + d).round() as i32, 3, 7];
            assert_eq!(m.weight(l, at(s - 2.0)), 0.0);
            assert_eq!(m.weight(l, at(e + 2.0)), 1.0);
            let mid = m.weight(l, at(0.5 * (s + e)));
            assert!(mid > 0.3 && mid < 0.7, "level {l}: {mid}");
        }
        assert_eq!(m.weight(3, [1000, 0, 0]), 0.0);
    }

    /// A point of a chunk of level `l + 1` is at least `end_l` from the viewer, where
    /// `LevelMap::from_viewer` leaves a level-(l+1) chunk whole: its weight is 1.
    #[test]
    fn points_of_coarser_chunks_are_fully_morphed() {
        let g = LodGeometry::new(3, 4, [2, 1, 2]).unwrap();
        for viewer in [[10.0, 3.0, 7.0], [200.0, 40.0, 90.0], [0.0, 0.0, 0.0]] {
            let m = Morph::new(&g, 1.5, 0.7, 0.0, viewer).unwrap();
            let map = super::super::LevelMap::from_viewer(g, viewer, 1.5);
            let mut seen = 0;
            for k in map.chunks() {
                let (lo, hi) = k.bounds(&g);
                for l in 0..k.level {
                    for p in [lo, hi, [lo[0], hi[1], lo[2]], [hi[0], lo[1], hi[2]]] {
                        let p = p.map(|v| v as i32);
                        assert_eq!(m.weight(l, p), 1.0, "{k:?} level {l} {p:?}");
                        seen += 1;
                    }
                }
            }
            assert!(seen > 0);
        }
    }

    /// A chunk that the viewer's step (at most `lead`) made split has weight 1 at every point
    /// of its box under the new viewer: it was whole under the old one.
    #[test]
    fn points_of_chunks_split_by_a_step_are_fully_morphed() {
        let g = LodGeometry::new(3, 4, [2, 1, 2]).unwrap();
        let lead = 3.0;
        let mut seen = 0;
        for i in 0..200 {
            let t = f64::from(i) * 0.37;
            let old = [40.0 + 5.0 * t.sin(), 20.0, 60.0 + 3.0 * t];
            let dir = [t.cos(), 0.3 * t.sin(), (1.7 * t).sin()];
            let len = dir.iter().map(|v| v * v).sum::<f64>().sqrt();
            let new: [f64; 3] = std::array::from_fn(|a| old[a] + lead * dir[a] / len);
            let before = super::super::LevelMap::from_viewer(g, old, 1.5);
            let after = super::super::LevelMap::from_viewer(g, new, 1.5);
            let m = Morph::new(&g, 1.5, 0.9, lead, new).unwrap();
            for k in after.chunks() {
                // Chunks of `after` finer than the leaf of `before` holding them.
                let (lo, hi) = k.bounds(&g);
                let Some(was) = before.leaves_touching(lo, hi).into_iter().find(|b| {
                    let (blo, bhi) = b.bounds(&g);
                    (0..3).all(|a| blo[a] <= lo[a] && hi[a] <= bhi[a])
                }) else {
                    continue;
                };
                for l in k.level..was.level {
                    for x in [lo[0], hi[0]] {
                        for y in [lo[1], hi[1]] {
                            for z in [lo[2], hi[2]] {
                                let p = [x as i32, y as i32, z as i32];
                                assert_eq!(m.weight(l, p), 1.0, "{k:?} was {was:?}, level {l}");
                                seen += 1;
                            }
                        }
                    }
                }
            }
        }
        assert!(seen > 0, "no step split a chunk");
    }

    /// `may_differ` is conservative: where it says no, every point's weights are equal.
    #[test]
    fn may_differ_is_conservative() {
        let a = morph(0.5);
        let mut b = a;
        b.viewer[0] += 3.0;
        let mut differ = 0;
        for x in (0..256).step_by(8) {
            for z in (0..256).step_by(8) {
                let (lo, hi) = ([x, 0, z], [x + 8, 8, z + 8]);
                if a.may_differ(&b, lo, hi) {
                    differ += 1;
                    continue;
                }
                for px in (lo[0] - 2)..=(hi[0] + 2) {
                    for pz in [lo[2] - 2, lo[2], hi[2], hi[2] + 2] {
                        let p = [px as i32, 4, pz as i32];
                        for l in 0..3 {
                            assert_eq!(a.weight(l, p), b.weight(l, p), "{p:?} level {l}");
                        }
                    }
                }
            }
        }
        assert!(differ > 0 && differ < 32 * 32, "{differ}");
    }

    #[test]
    fn bad_morphs_are_refused() {
        let g = LodGeometry::new(3, 4, [2, 1, 2]).unwrap();
        assert!(Morph::new(&g, 1.5, 0.0, 0.0, [0.0; 3]).is_err());
        assert!(Morph::new(&g, 1.5, 1.5, 0.0, [0.0; 3]).is_err());
        assert!(Morph::new(&g, 1.5, f64::NAN, 0.0, [0.0; 3]).is_err());
        assert!(Morph::new(&g, 0.0, 0.5, 0.0, [0.0; 3]).is_err());
        assert!(Morph::new(&g, 1.5, 0.5, 0.0, [f64::INFINITY, 0.0, 0.0]).is_err());
        // Level 0's band: 0.5 * 1.5 * 8 u = 6 u.
        assert!(Morph::new(&g, 1.5, 0.5, 5.9, [0.0; 3]).is_ok());
        assert!(Morph::new(&g, 1.5, 0.5, 6.0, [0.0; 3]).is_err());
        assert!(Morph::new(&g, 1.5, 0.5, -1.0, [0.0; 3]).is_err());
    }
}
