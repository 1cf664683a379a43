//! Edits: a sparse overlay of brush strokes over the procedural field.
//!
//! ```text
//!   Overlay = the strokes in order (brush, dt) + a hierarchical bucket index
//!   edited value at world point x:  v = f(x);  for every stroke i (in order) whose bucket
//!                                   holds x:  v = brush_i.apply(v, |x - centre_i|, dt_i)
//!   bucket grid g: cells of E_g = 4 h 2^g;  a stroke of radius r goes in the finest g with
//!                  E_g >= 2 r, in the (at most 8) cells its box meets
//!   chunks a stroke marks: those whose box, grown by one cell of the level above theirs
//!                  (the reach of the tets it owns, and the normals' probes), meets the
//!                  stroke's box in lattice units
//! ```
//!
//! **Why a stroke list and not stored samples.** An edited value is the same function of a
//! point's world position as in [`crate::World`] (the brush applied to the value there, stroke
//! after stroke, [`Brush::apply`]), evaluated when a chunk samples the point. So:
//!
//! - samples nest for free: a lattice point has one world position whatever level samples it,
//!   so the level-0 and level-3 chunks that share it read the same bits, and an edit survives
//!   any change of level (nothing is stored per level, nothing is resampled or lost);
//! - the normals' probes between lattice points see the edit too (the gradient of the edited
//!   field), which stored lattice samples could only give by interpolation;
//! - the memory is the strokes and at most 8 bucket entries each: it grows with the number of
//!   edits and not with the world, nor with a stroke's radius or the level it is seen at (a
//!   stroke on a distant, coarse chunk costs what a near one costs; a store of finest-level
//!   samples would hold `(2 r / h)^3` values for it).
//!
//! The price: sampling a point costs one bucket look-up per bucket grid in use plus one
//! [`Brush::apply`] per stroke over it, so a spot sculpted by many strokes gets slower to
//! sample. Without strokes the overlay is skipped entirely (meshes are bit-identical to the
//! unedited world's).

use std::collections::HashMap;

use glam::Vec3;
use rmt_fields::ScalarField;

use super::error::LodError;
use super::lattice::cell_size;
use super::level_map::{ChunkKey, LevelMap};
use super::mt::LodFrame;
use crate::Brush;

/// Bucket cells of grid 0 are this many finest cells wide.
const BUCKET_CELLS: f64 = 4.0;

/// One brush stroke: a brush applied for a frame of `dt` seconds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Stroke {
    /// The brush (world coordinates).
    pub brush: Brush,
    /// Its frame time in seconds.
    pub dt: f32,
}

/// The strokes applied to a world so far, in order, with an index from space to strokes.
#[derive(Clone, Debug)]
pub struct Overlay {
    frame: LodFrame,
    strokes: Vec<Stroke>,
    /// `(grid, cell)` -> indices of the strokes whose box meets that cell, ascending.
    buckets: HashMap<(u8, [i64; 3]), Vec<u32>>,
    /// Bit `g`: bucket grid `g` holds some stroke.
    grids: u64,
}

impl Overlay {
    /// An empty overlay over the lattice placed by `frame`.
    pub fn new(frame: LodFrame) -> Self {
        Overlay {
            frame,
            strokes: Vec::new(),
            buckets: HashMap::new(),
            grids: 0,
        }
    }

    /// The strokes so far, in order.
    pub fn strokes(&self) -> &[Stroke] {
        &self.strokes
    }

    /// Whether no stroke was added.
    pub fn is_empty(&self) -> bool {
        self.strokes.is_empty()
    }

    /// Edge of bucket grid `g`'s cells (world units).
    fn bucket_edge(&self, g: u8) -> f64 {
        BUCKET_CELLS * f64::from(self.frame.h) * f64::from(1u32 << g)
    }

    /// Bucket cell of grid `g` holding world coordinate `v` along `axis`.
    fn bucket_of(&self, g: u8, v: f64, axis: usize) -> i64 {
        ((v - f64::from(self.frame.origin[axis])) / self.bucket_edge(g)).floor() as i64
    }

    /// Adds a stroke (after checking it, [`Brush::check`]).
    pub fn add(&mut self, brush: Brush, dt: f32) -> Result<(), LodError> {
        brush
            .check(dt)
            .map_err(|e| LodError::Invalid(e.to_string()))?;
        let index = u32::try_from(self.strokes.len())
            .map_err(|_| LodError::Invalid("too many strokes".into()))?;
        // A point the brush changes is closer than `radius` (in f32): one part in a thousand
        // of margin covers the rounding.
        let r = f64::from(brush.radius) * 1.001 + f64::from(self.frame.h) * 1e-3;
        let g = (0u8..40)
            .find(|&g| self.bucket_edge(g) >= 2.0 * r)
            .unwrap_or(40);
        if g >= 40 {
            return Err(LodError::Invalid(format!(
                "brush radius {} too large",
                brush.radius
            )));
        }
        let c = brush.centre.as_dvec3();
        let lo: [i64; 3] = std::array::from_fn(|a| self.bucket_of(g, c[a] - r, a));
        let hi: [i64; 3] = std::array::from_fn(|a| self.bucket_of(g, c[a] + r, a));
        for x in lo[0]..=hi[0] {
            for y in lo[1]..=hi[1] {
                for z in lo[2]..=hi[2] {
                    self.buckets.entry((g, [x, y, z])).or_default().push(index);
                }
            }
        }
        self.grids |= 1 << g;
        self.strokes.push(Stroke { brush, dt });
        Ok(())
    }

    /// The edited value at world point `p` whose unedited value is `value`.
    pub fn apply(&self, p: Vec3, value: f32, scratch: &mut Vec<u32>) -> f32 {
        if self.strokes.is_empty() {
            return value;
        }
        scratch.clear();
        let pd = p.as_dvec3();
        let mut grids = self.grids;
        while grids != 0 {
            let g = grids.trailing_zeros() as u8;
            grids &= grids - 1;
            let cell: [i64; 3] = std::array::from_fn(|a| self.bucket_of(g, pd[a], a));
            if let Some(ids) = self.buckets.get(&(g, cell)) {
                scratch.extend_from_slice(ids);
            }
        }
        // A stroke sits in one grid, and a point in one cell per grid: no duplicates.
        scratch.sort_unstable();
        scratch.iter().fold(value, |v, &i| {
            let s = &self.strokes[i as usize];
            s.brush.apply(v, p.distance(s.brush.centre), s.dt)
        })
    }

    /// Whether some stroke's box meets the world box `[lo, hi]`.
    pub fn touches(&self, lo: Vec3, hi: Vec3) -> bool {
        self.strokes.iter().any(|s| {
            let r = Vec3::splat(s.brush.radius * 1.001);
            (s.brush.centre - r).cmple(hi).all() && (s.brush.centre + r).cmpge(lo).all()
        })
    }

    /// Bytes held: the strokes and the bucket index.
    pub fn bytes(&self) -> usize {
        let entry = std::mem::size_of::<((u8, [i64; 3]), Vec<u32>)>();
        self.strokes.capacity() * std::mem::size_of::<Stroke>()
            + self.buckets.capacity() * (entry + 1)
            + self
                .buckets
                .values()
                .map(|v| v.capacity() * 4)
                .sum::<usize>()
    }

    /// The closed box (lattice units `u`) a stroke can change values in, grown by 1 `u` for
    /// rounding; `None` when it misses the world box `[0, world]`.
    pub fn stroke_box(&self, brush: &Brush, world: [i64; 3]) -> Option<([i64; 3], [i64; 3])> {
        let u = f64::from(self.frame.h) * 0.5;
        let r = f64::from(brush.radius) / u;
        let mut lo = [0i64; 3];
        let mut hi = [0i64; 3];
        for a in 0..3 {
            let c = (f64::from(brush.centre[a]) - f64::from(self.frame.origin[a])) / u;
            let (l, h) = ((c - r).floor() - 1.0, (c + r).ceil() + 1.0);
            if !(l <= world[a] as f64 && h >= 0.0) {
                return None;
            }
            lo[a] = l.max(-1.0) as i64;
            hi[a] = h.min(world[a] as f64 + 1.0) as i64;
        }
        Some((lo, hi))
    }
}

/// The leaves of `map` whose tets (or the normals' probes around their crossings) can see a
/// value changed in the closed box `[lo, hi]` (lattice units): those whose box, grown by one
/// cell of the level above theirs, meets it. A tet a chunk owns has its centroid in the chunk
/// and comes from a red-forest leaf of the chunk's level or finer (a coarser leaf's box would
/// touch the chunk and so have been refined), so its vertices lie within one cell of the
/// chunk's level of the box; the probes reach `h / 4` beyond its edges.
pub fn chunks_seeing(map: &LevelMap, lo: [i64; 3], hi: [i64; 3]) -> Vec<ChunkKey> {
    let g = map.geometry();
    let reach = |level: u8| cell_size(level + 1);
    let m = reach(g.levels);
    map.leaves_touching(lo.map(|v| v - m), hi.map(|v| v + m))
        .into_iter()
        .filter(|k| {
            let (a, b) = k.bounds(g);
            let r = reach(k.level);
            (0..3).all(|i| a[i] - r <= hi[i] && b[i] + r >= lo[i])
        })
        .collect()
}

/// The procedural field with an overlay of strokes: what a world with edits samples.
#[derive(Clone, Copy)]
pub struct EditedField<'a> {
    field: &'a dyn ScalarField,
    overlay: &'a Overlay,
}

impl<'a> EditedField<'a> {
    /// `field` edited by `overlay`.
    pub fn new(field: &'a dyn ScalarField, overlay: &'a Overlay) -> Self {
        EditedField { field, overlay }
    }
}

/// Where no stroke reaches, the field's own bounds hold (so chunks far from every edit keep
/// the field's shortcuts); elsewhere none is claimed.
impl ScalarField for EditedField<'_> {
    fn range(&self, lo: Vec3, hi: Vec3) -> Option<(f32, f32)> {
        if self.overlay.touches(lo, hi) {
            return None;
        }
        self.field.range(lo, hi)
    }

    fn side(&self, lo: Vec3, hi: Vec3, iso: f32) -> Option<f32> {
        if self.overlay.touches(lo, hi) {
            return None;
        }
        self.field.side(lo, hi, iso)
    }

    fn sample(&self, p: Vec3) -> f32 {
        self.overlay.apply(p, self.field.sample(p), &mut Vec::new())
    }

    fn sample_batch(&self, points: &[Vec3], out: &mut [f32]) {
        self.field.sample_batch(points, out);
        if self.overlay.is_empty() {
            return;
        }
        let mut scratch = Vec::new();
        for (o, &p) in out.iter_mut().zip(points) {
            *o = self.overlay.apply(p, *o, &mut scratch);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frame() -> LodFrame {
        LodFrame {
            origin: Vec3::splat(-1.0),
            h: 0.125,
        }
    }

    struct Zero;
    impl ScalarField for Zero {
        fn sample(&self, _: Vec3) -> f32 {
            0.5
        }
    }

    #[test]
    fn the_overlay_applies_strokes_in_order_as_the_brush_does() {
        let mut o = Overlay::new(frame());
        let a = Brush::add(Vec3::ZERO, 0.3, 2.0).with_clamp(0.6);
        let b = Brush::subtract(Vec3::new(0.1, 0.0, 0.0), 1.7, 1.0);
        o.add(a, 0.5).unwrap();
        o.add(b, 0.25).unwrap();
        let f = EditedField::new(&Zero, &o);
        for p in [
            Vec3::ZERO,
            Vec3::new(0.2, 0.1, -0.05),
            Vec3::new(1.5, 0.0, 0.0),
            Vec3::new(-0.9, 0.7, 0.3),
            Vec3::splat(3.0),
        ] {
            let want = b.apply(
                a.apply(0.5, p.distance(a.centre), 0.5),
                p.distance(b.centre),
                0.25,
            );
            assert_eq!(f.sample(p).to_bits(), want.to_bits(), "{p}");
            let mut out = [0f32];
            f.sample_batch(&[p], &mut out);
            assert_eq!(out[0].to_bits(), want.to_bits());
        }
        // Far away, nothing, and the field's bounds hold there only.
        assert_eq!(f.sample(Vec3::splat(9.0)), 0.5);
        let sphere = rmt_fields::Sphere::new(Vec3::splat(5.0), 0.5);
        let e = EditedField::new(&sphere, &o);
        let (lo, hi) = (Vec3::splat(2.5), Vec3::splat(3.0));
        assert!(e.side(lo, hi, 0.0).is_some());
        assert_eq!(e.side(lo, hi, 0.0), sphere.side(lo, hi, 0.0));
        assert!(e.side(Vec3::splat(-0.1), Vec3::splat(0.1), 0.0).is_none());
        assert!(e.range(Vec3::splat(1.6), Vec3::splat(1.7)).is_none());
    }

    #[test]
    fn memory_grows_with_the_strokes_not_their_size() {
        let mut small = Overlay::new(frame());
        let mut large = Overlay::new(frame());
        for i in 0..50 {
            let c = Vec3::new(i as f32 * 0.01, 0.0, 0.0);
            small.add(Brush::add(c, 0.2, 1.0), 0.1).unwrap();
            large.add(Brush::add(c * 40.0, 20.0, 1.0), 0.1).unwrap();
        }
        // At most 8 buckets per stroke whatever its radius.
        assert!(large.buckets.values().map(Vec::len).sum::<usize>() <= 8 * 50);
        assert!(small.buckets.values().map(Vec::len).sum::<usize>() <= 8 * 50);
        assert!(large.bytes() < 2 * small.bytes() + 4096);
        assert!(Overlay::new(frame()).bytes() == 0);
    }

    #[test]
    fn bad_strokes_are_refused() {
        let mut o = Overlay::new(frame());
        assert!(o.add(Brush::add(Vec3::ZERO, -1.0, 1.0), 0.1).is_err());
        assert!(o.add(Brush::add(Vec3::ZERO, 1.0, 1.0), f32::NAN).is_err());
        assert!(o.is_empty());
    }
}
