//! Scalar fields: the functions f(x, y, z) whose level set T = 0 the extractors turn into meshes.
//!
//! Convention for the whole workspace: **inside is f < 0**, the surface is f = 0, and f grows
//! outward, as for a signed distance. Extracted triangles face toward increasing f.
//!
//! Every field is a [`ScalarField`]: `Send + Sync`, sampled one point at a time or in batches
//! (override [`ScalarField::sample_batch`] where a field can do better than a loop). Fields that
//! know the distance to their own surface say so through [`ScalarField::surface_distance`], which
//! the extractors use to measure fidelity. Fields that can bound their values over a box say so
//! through [`ScalarField::range`], which lets the extractors skip sampling far from the surface.
//!
//! ```
//! use rmt_fields::{ScalarField, Sphere};
//! use glam::Vec3;
//! let s = Sphere::new(Vec3::ZERO, 1.0);
//! assert!(s.sample(Vec3::ZERO) < 0.0);
//! assert!((s.sample(Vec3::new(2.0, 0.0, 0.0)) - 1.0).abs() < 1e-6);
//! ```

mod analytic;
mod asteroid;
mod error;
pub mod fast_fbm;
pub mod fbm;
mod interval;
mod mesh_sdf;
mod random;
mod terrain;

pub use analytic::{FnField, Gyroid, Sphere, Torus};
pub use asteroid::{Asteroid, AsteroidParams};
pub use error::{FieldError, MeshProblem, MeshSource};
pub use mesh_sdf::MeshSdf;
pub use random::{RandomFamily, RandomField};
pub use terrain::{CaveParams, CaveTerrain, SvobodaParams, SvobodaTerrain};

use glam::Vec3;

/// A scalar field sampled by the extractors. Inside is `f < 0`.
pub trait ScalarField: Send + Sync {
    /// The field's value at `p` (world coordinates).
    fn sample(&self, p: Vec3) -> f32;

    /// Samples many points at once: `out[i] = sample(points[i])`, bit for bit, whatever the
    /// other points of the batch. Override when a field can vectorise or share work between
    /// points: the extractors pass lattice rows (points with equal `y` and `z`, `x` increasing)
    /// as consecutive runs.
    fn sample_batch(&self, points: &[Vec3], out: &mut [f32]) {
        for (o, &p) in out.iter_mut().zip(points) {
            *o = self.sample(p);
        }
    }

    /// Samples one row of points along `x`: `out[i] = sample(Vec3::new(xs[i], y, z))`, bit for
    /// bit. The default builds the points and calls [`ScalarField::sample_batch`]; a field that
    /// shares work along rows (the asteroid's noise) overrides it and skips building them.
    fn sample_row(&self, xs: &[f32], y: f32, z: f32, out: &mut [f32]) {
        const CHUNK: usize = 256;
        let mut points = [Vec3::ZERO; CHUNK];
        for (xc, oc) in xs.chunks(CHUNK).zip(out.chunks_mut(CHUNK)) {
            for (p, &x) in points.iter_mut().zip(xc) {
                *p = Vec3::new(x, y, z);
            }
            self.sample_batch(&points[..xc.len()], oc);
        }
    }

    /// Samples rows that share their `x` coordinates and `z`, one per `ys[r]`, row `r` at
    /// `stride * r` in `out`: `out[stride * r + i] = sample(Vec3::new(xs[i], ys[r], z))`, bit
    /// for bit (the elements between the rows are left as they are; `stride >= xs.len()`).
    /// The default calls [`ScalarField::sample_row`] per row; a field whose value along `y` is
    /// cheap once the rest is known (a height field) overrides it.
    fn sample_rows(&self, xs: &[f32], ys: &[f32], z: f32, out: &mut [f32], stride: usize) {
        for (r, &y) in ys.iter().enumerate() {
            self.sample_row(xs, y, z, &mut out[stride * r..stride * r + xs.len()]);
        }
    }

    /// Unsigned distance from `p` to the field's true surface, when the field knows it (used to
    /// measure extraction fidelity); `None` otherwise.
    fn surface_distance(&self, _p: Vec3) -> Option<f32> {
        None
    }

    /// A conservative range of the field over the axis-aligned box `[lo, hi]`: `Some((a, b))`
    /// promises `a <= self.sample(p) <= b` (and the same for [`ScalarField::sample_batch`]) for
    /// every `p` with `lo <= p <= hi` componentwise, *as the `f32` values the field returns*, so
    /// rounding must be accounted for. `None` means unknown (the default, and the answer for an
    /// empty or non-finite box). The extractors skip sampling boxes whose range excludes the
    /// isovalue, so a wrong range changes meshes: implement it only with a proof.
    ///
    /// ```
    /// use rmt_fields::{ScalarField, Sphere};
    /// use glam::Vec3;
    /// let s = Sphere::new(Vec3::ZERO, 1.0);
    /// let (a, b) = s.range(Vec3::splat(2.0), Vec3::splat(3.0)).unwrap();
    /// assert!(a <= s.sample(Vec3::splat(2.0)) && s.sample(Vec3::splat(3.0)) <= b);
    /// assert!(a > 0.0, "the box is outside the sphere");
    /// ```
    fn range(&self, _lo: Vec3, _hi: Vec3) -> Option<(f32, f32)> {
        None
    }

    /// Whether the field stays on one side of `iso` over the box `[lo, hi]`, as far as a proven
    /// bound tells: `Some(v)` with `v < iso` when every value the field returns there is below
    /// `iso`, `v >= iso` when every one is at least `iso` (`v` is a placeholder for the box's
    /// values, an end of such a bound); `None` when no bound tells. The default decides from
    /// [`ScalarField::range`] with [`side_of`]; a field whose range is costly may stop as soon
    /// as a cheaper bound decides (the asteroid adds its noise octave by octave).
    fn side(&self, lo: Vec3, hi: Vec3, iso: f32) -> Option<f32> {
        self.range(lo, hi).and_then(|(a, b)| side_of(a, b, iso))
    }
}

/// The side of `iso` that a range `[a, b]` of values lies on, as [`ScalarField::side`] reports
/// it: `Some(b)` when `b < iso` (all inside), `Some(a)` when `a >= iso` (all outside), else `None`.
/// Infinite ends become the extreme finite values, so the placeholder is finite.
///
/// ```
/// use rmt_fields::side_of;
/// assert_eq!(side_of(-3.0, -1.0, 0.0), Some(-1.0));
/// assert_eq!(side_of(0.5, f32::INFINITY, 0.0), Some(0.5));
/// assert_eq!(side_of(-1.0, 1.0, 0.0), None);
/// assert_eq!(side_of(f32::NEG_INFINITY, f32::NEG_INFINITY, 0.0), Some(f32::MIN));
/// assert_eq!(side_of(-1.0, f32::INFINITY, 0.0), None);
/// assert_eq!(side_of(f32::NAN, f32::NAN, 0.0), None);
/// ```
pub fn side_of(a: f32, b: f32, iso: f32) -> Option<f32> {
    // (Comparisons with NaN are false: a NaN end decides nothing.)
    if b < iso {
        Some(if b.is_finite() { b } else { f32::MIN })
    } else if a >= iso {
        Some(if a.is_finite() { a } else { f32::MAX })
    } else {
        None
    }
}

impl<F: ScalarField + ?Sized> ScalarField for &F {
    fn sample(&self, p: Vec3) -> f32 {
        (**self).sample(p)
    }
    fn sample_batch(&self, points: &[Vec3], out: &mut [f32]) {
        (**self).sample_batch(points, out)
    }
    fn surface_distance(&self, p: Vec3) -> Option<f32> {
        (**self).surface_distance(p)
    }
    fn range(&self, lo: Vec3, hi: Vec3) -> Option<(f32, f32)> {
        (**self).range(lo, hi)
    }
    fn side(&self, lo: Vec3, hi: Vec3, iso: f32) -> Option<f32> {
        (**self).side(lo, hi, iso)
    }
}

impl<F: ScalarField + ?Sized> ScalarField for Box<F> {
    fn sample(&self, p: Vec3) -> f32 {
        (**self).sample(p)
    }
    fn sample_batch(&self, points: &[Vec3], out: &mut [f32]) {
        (**self).sample_batch(points, out)
    }
    fn surface_distance(&self, p: Vec3) -> Option<f32> {
        (**self).surface_distance(p)
    }
    fn range(&self, lo: Vec3, hi: Vec3) -> Option<(f32, f32)> {
        (**self).range(lo, hi)
    }
    fn side(&self, lo: Vec3, hi: Vec3, iso: f32) -> Option<f32> {
        (**self).side(lo, hi, iso)
    }
}
