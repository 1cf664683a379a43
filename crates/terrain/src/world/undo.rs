//! Undo and redo of brush strokes: [`World::apply_brush_recorded`] keeps the values a stroke
//! changed (before and after) and the chunks it marked, and [`World::undo_stroke`] /
//! [`World::redo_stroke`] put either set back and mark the same chunks dirty.
//!
//! Why the same chunks: [`World::apply_brush`] marks a chunk when a changed point of its input
//! changed side of the isovalue or has a lattice neighbour on the other side before or after
//! the change. That test is symmetric in "before" and "after", so when every other value is as
//! it was around the stroke (a linear history: strokes are undone in reverse order and redone
//! in order), putting the old values back can alter exactly the chunks the stroke marked.

use rmt_extract::samples::sampled_lattice;
use rmt_extract::Lattice;

use super::state::{Cells, World};
use crate::{Brush, TerrainError};

/// The sample values one stroke changed and the chunks it marked dirty; see [`World::undo_stroke`].
#[derive(Clone, Debug, Default, PartialEq)]
pub struct StrokeRecord {
    /// Storage indices of the changed values, ascending.
    indices: Vec<u32>,
    /// Their values before the stroke.
    before: Vec<f32>,
    /// Their values after the stroke.
    after: Vec<f32>,
    /// The chunks dirty after the stroke (those it marked, and any that were dirty already).
    chunks: Vec<usize>,
    /// Exact seams: the cells the stroke changed in a way that matters.
    region: Option<Cells>,
}

impl StrokeRecord {
    /// Number of sample values the stroke changed.
    pub fn changed_values(&self) -> usize {
        self.indices.len()
    }

    /// The chunks an undo or redo of this stroke marks dirty.
    pub fn chunks(&self) -> &[usize] {
        &self.chunks
    }

    /// Bytes the record holds (its three value arrays and the chunk list).
    pub fn bytes(&self) -> usize {
        self.indices.len() * 12 + self.chunks.len() * std::mem::size_of::<usize>()
    }
}

impl World {
    /// [`World::apply_brush`], also returning what the stroke changed so that it can be undone
    /// ([`World::undo_stroke`]) and redone ([`World::redo_stroke`]). Only the z-slab of storage
    /// planes the brush can reach is copied to find the changes.
    pub fn apply_brush_recorded(
        &mut self,
        brush: &Brush,
        dt: f32,
    ) -> Result<(usize, StrokeRecord), TerrainError> {
        brush.check(dt)?;
        let (lo, hi) = self.slab(brush);
        let old: Vec<f32> = self.samples.values[lo..hi].to_vec();
        let marked = self.apply_brush(brush, dt)?;
        let mut record = StrokeRecord::default();
        for (k, (&before, &after)) in old.iter().zip(&self.samples.values[lo..hi]).enumerate() {
            // Bitwise: a NaN never appears (the extractor refuses it), and -0.0 vs 0.0 counts.
            if before.to_bits() != after.to_bits() {
                record.indices.push((lo + k) as u32);
                record.before.push(before);
                record.after.push(after);
            }
        }
        record.chunks = (0..self.dirty.len()).filter(|&i| self.dirty[i]).collect();
        record.region = self.last_edit;
        Ok((marked, record))
    }

    /// Puts back the values `record` changed and marks its chunks dirty; returns how many chunks
    /// it marked. Undo strokes in reverse order of [`World::apply_brush_recorded`].
    pub fn undo_stroke(&mut self, record: &StrokeRecord) -> usize {
        self.put_values(record, false)
    }

    /// Applies `record`'s changes again (after [`World::undo_stroke`]) and marks its chunks
    /// dirty; returns how many chunks it marked.
    pub fn redo_stroke(&mut self, record: &StrokeRecord) -> usize {
        self.put_values(record, true)
    }

    /// Whether chunk `i` waits for [`World::remesh_dirty`] (false past the last chunk).
    pub fn chunk_is_dirty(&self, i: usize) -> bool {
        self.dirty.get(i).copied().unwrap_or(false)
    }

    fn put_values(&mut self, record: &StrokeRecord, after: bool) -> usize {
        let values = if after { &record.after } else { &record.before };
        for (&i, &v) in record.indices.iter().zip(values) {
            if let Some(slot) = self.samples.values.get_mut(i as usize) {
                *slot = v;
            }
        }
        if let Some(region) = record.region {
            // The same cells matter again (the test is symmetric in before and after).
            self.mark_edit(region);
        }
        let mut marked = 0;
        for &c in &record.chunks {
            if let Some(d) = self.dirty.get_mut(c) {
                *d = true;
                marked += 1;
            }
        }
        marked
    }

    /// Storage index range of the z-planes a brush can change (two planes of margin each side).
    fn slab(&self, brush: &Brush) -> (usize, usize) {
        let s = &self.settings;
        let dims = self.samples.dims;
        let plane = dims[0] * dims[1];
        // Storage plane of lattice z coordinate u (cells): simple planes are cells, body-centred
        // planes half cells shifted by one (the ghost plane below the box).
        let (scale, shift) = match sampled_lattice(&self.unit) {
            Lattice::BodyCentred => (2.0, 1.0),
            Lattice::Simple => (1.0, 0.0),
        };
        let u = (brush.centre.z - s.origin.z) / s.h;
        let r = brush.radius / s.h;
        let last = dims[2].saturating_sub(1) as f32;
        let z0 = ((u - r) * scale + shift).floor() - 2.0;
        let z1 = ((u + r) * scale + shift).ceil() + 2.0;
        let z0 = z0.clamp(0.0, last) as usize;
        let z1 = z1.clamp(0.0, last) as usize;
        (
            z0 * plane,
            ((z1 + 1) * plane).min(self.samples.values.len()),
        )
    }
}

#[cfg(test)]
mod tests {
    use crate::{canonical_triangles, Brush, World, WorldSettings};
    use glam::Vec3;
    use rmt_extract::{Clustering, Lattice};
    use rmt_fields::Sphere;

    fn world(lattice: Lattice) -> World {
        let settings = WorldSettings::new(
            [16, 16, 16],
            Vec3::splat(-1.0),
            0.125,
            lattice,
            Clustering::Integrated,
        )
        .with_chunk(8)
        .with_threads(1);
        let mut w = World::new(&Sphere::new(Vec3::ZERO, 0.6), settings).unwrap();
        w.remesh_dirty().unwrap();
        w
    }

    #[test]
    fn undo_restores_values_and_mesh_and_redo_repeats_the_stroke() {
        for lattice in [Lattice::BodyCentred, Lattice::Simple] {
            let mut w = world(lattice);
            let bits = |w: &World| -> Vec<u32> {
                w.samples().values.iter().map(|v| v.to_bits()).collect()
            };
            let values0 = bits(&w);
            let mesh0 = canonical_triangles(&w.mesh_welded());
            let mut records = Vec::new();
            for (i, c) in [Vec3::new(0.6, 0.0, 0.0), Vec3::new(0.0, 0.55, 0.2)]
                .into_iter()
                .enumerate()
            {
                let b = if i == 0 {
                    Brush::add(c, 0.25, 5.0)
                } else {
                    Brush::subtract(c, 0.3, 5.0)
                };
                let (marked, rec) = w.apply_brush_recorded(&b, 0.1).unwrap();
                assert!(marked >= 1 && rec.changed_values() > 0);
                assert_eq!(rec.chunks().len(), marked);
                w.remesh_dirty().unwrap();
                records.push(rec);
            }
            let values2 = bits(&w);
            let mesh2 = canonical_triangles(&w.mesh_welded());
            assert_ne!(mesh2, mesh0);
            for rec in records.iter().rev() {
                assert_eq!(w.undo_stroke(rec), rec.chunks().len());
                w.remesh_dirty().unwrap();
            }
            assert!(bits(&w) == values0, "undo left changed values");
            assert_eq!(canonical_triangles(&w.mesh_welded()), mesh0);
            // The incrementally re-meshed world equals the whole volume extracted at once.
            let (whole, _) = w.extract_whole().unwrap();
            assert_eq!(canonical_triangles(&whole), mesh0);
            for rec in &records {
                w.redo_stroke(rec);
                w.remesh_dirty().unwrap();
            }
            assert!(bits(&w) == values2, "redo did not repeat the strokes");
            assert_eq!(canonical_triangles(&w.mesh_welded()), mesh2);
        }
    }

    #[test]
    fn a_stroke_far_from_the_surface_records_values_but_no_chunks() {
        let mut w = world(Lattice::BodyCentred);
        // Deep in the air: values rise but no point changes side or neighbours the surface.
        let (marked, rec) = w
            .apply_brush_recorded(&Brush::subtract(Vec3::splat(-0.55), 0.1, 1.0), 0.1)
            .unwrap();
        assert_eq!(marked, 0);
        assert!(rec.chunks().is_empty());
        assert!(rec.changed_values() > 0);
    }
}
