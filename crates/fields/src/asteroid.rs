//! A noise asteroid: a sphere whose radius is displaced by fractal Perlin noise.

use crate::fast_fbm::{FastFbm, TOLERANCE};
use crate::fbm::BatchFbm;
use crate::interval::{box64, distance_to_box, widen};
use crate::{side_of, ScalarField};
use glam::Vec3;

/// Parameters of an [`Asteroid`].
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AsteroidParams {
    /// Seed of the Perlin noise.
    pub seed: u32,
    /// Octaves of fractal Brownian motion (1 to 8 are sensible).
    pub octaves: usize,
    /// Base frequency of the noise, in cycles per world unit.
    pub frequency: f64,
    /// Displacement amplitude in world units (relative to a radius of about 1).
    pub amplitude: f32,
    /// Radius of the underlying sphere.
    pub radius: f32,
}

impl Default for AsteroidParams {
    fn default() -> Self {
        Self {
            seed: 7,
            octaves: 4,
            frequency: 1.5,
            amplitude: 0.25,
            radius: 0.7,
        }
    }
}

/// `|p - centre| - radius + amplitude * fbm(p)`: a lumpy rock. Not a signed distance, so it does
/// not report a surface distance.
///
/// `fbm` is the `noise` crate's `Fbm<Perlin>` as [`FastFbm`] evaluates it: in `f32` and along
/// rows of points, within [`TOLERANCE`] (`2e-5`) of the crate's values, the same object. A
/// single sample and a batch give the same bits.
pub struct Asteroid {
    params: AsteroidParams,
    centre: Vec3,
    fast: FastFbm,
    /// The exact `f64` twin, for its interval bound ([`BatchFbm::range`]).
    batch: BatchFbm,
}

impl Asteroid {
    /// An asteroid centred at `centre`.
    pub fn new(centre: Vec3, params: AsteroidParams) -> Self {
        Self {
            params,
            centre,
            fast: FastFbm::new(params.seed, params.octaves.clamp(1, 32), params.frequency),
            batch: BatchFbm::new(params.seed, params.octaves.clamp(1, 32), params.frequency),
        }
    }

    /// The value at offset `q` from the centre, the noise there being `n`: one formula for
    /// every way of sampling, so every way gives the same bits.
    #[inline(always)]
    fn value(&self, q: Vec3, n: f32) -> f32 {
        q.length() - self.params.radius + self.params.amplitude * n
    }

    /// The parameters it was built with.
    pub fn params(&self) -> &AsteroidParams {
        &self.params
    }
}

impl ScalarField for Asteroid {
    #[inline]
    fn sample(&self, p: Vec3) -> f32 {
        let q = p - self.centre;
        let n = self.fast.get([q.x, q.y, q.z].map(f64::from));
        self.value(q, n)
    }

    /// The same values as [`ScalarField::sample`], bit for bit; runs of points with equal `y`
    /// and `z` (the rows of a lattice) share the noise's work (see [`FastFbm`]).
    fn sample_batch(&self, points: &[Vec3], out: &mut [f32]) {
        const CHUNK: usize = 256;
        let mut xyz = [[0.0f64; CHUNK]; 3];
        let mut noise = [0.0f32; CHUNK];
        for (ps, os) in points.chunks(CHUNK).zip(out.chunks_mut(CHUNK)) {
            let n = ps.len();
            for (i, &p) in ps.iter().enumerate() {
                let q = p - self.centre;
                xyz[0][i] = f64::from(q.x);
                xyz[1][i] = f64::from(q.y);
                xyz[2][i] = f64::from(q.z);
            }
            let [x, y, z] = &xyz;
            self.fast
                .get_points(&x[..n], &y[..n], &z[..n], &mut noise[..n]);
            for (i, (o, &p)) in os.iter_mut().zip(ps).enumerate() {
                *o = self.value(p - self.centre, noise[i]);
            }
        }
    }

    /// [`ScalarField::sample_row`] without building points: the row's `y` and `z` offsets from
    /// the centre once, the noise as one row of [`FastFbm`] (what `sample_batch` finds in its
    /// points), the same operations per point, so the same bits.
    fn sample_row(&self, xs: &[f32], y: f32, z: f32, out: &mut [f32]) {
        const CHUNK: usize = 256;
        let c = self.centre;
        let (qy, qz) = (y - c.y, z - c.z);
        let mut qx = [0.0f64; CHUNK];
        let mut noise = [0.0f32; CHUNK];
        for (xc, oc) in xs.chunks(CHUNK).zip(out.chunks_mut(CHUNK)) {
            let n = xc.len();
            for (q, &x) in qx.iter_mut().zip(xc) {
                *q = f64::from(x - c.x);
            }
            self.fast
                .get_row(&qx[..n], f64::from(qy), f64::from(qz), &mut noise[..n]);
            for ((o, &x), &v) in oc.iter_mut().zip(xc).zip(&noise) {
                *o = self.value(Vec3::new(x - c.x, qy, qz), v);
            }
        }
    }

    /// Radial interval plus the noise bound. With `q = p - centre`, `|q|` ranges over
    /// `[near, far]` (distances from the centre to the box) and the noise `n` over the interval
    /// of [`BatchFbm::range`] on the box of `q` (within `[-1, 1]`, see [`fbm_bound`]), widened by
    /// [`TOLERANCE`] for the `f32` evaluation, so
    /// `f = |q| - r + A n` lies in `[near - r + min(A n), far - r + max(A n)]` (the two terms
    /// depend on the same point, so the sum of their ranges is conservative). The noise is
    /// evaluated at the `f32` point `fl(p - centre)`, within `2^-24 |q|` of the exact one per
    /// axis: the box of `q` is widened by `2^-22 max|q|` before the noise range is taken.
    /// Rounding of `f`: about eight roundings on operands of magnitude at most
    /// `far + |r| + |A|` (the rounding of `n` to `f32` included), covered by the widening (see
    /// `interval`'s module doc).
    fn range(&self, lo: Vec3, hi: Vec3) -> Option<(f32, f32)> {
        self.range_until(lo, hi, |_| false)
    }

    /// [`ScalarField::range`]'s bound built octave by octave ([`BatchFbm::range_until`]),
    /// stopping as soon as it decides the side: blocks far from the surface are decided by the
    /// radial interval alone, others after an octave or two.
    fn side(&self, lo: Vec3, hi: Vec3, iso: f32) -> Option<f32> {
        let mut side = None;
        let (a, b) = self.range_until(lo, hi, |(a, b)| {
            side = side_of(a, b, iso);
            side.is_some()
        })?;
        side.or_else(|| side_of(a, b, iso))
    }
}

impl Asteroid {
    /// The bound of [`ScalarField::range`] (see there), asking `enough` after each step of the
    /// noise's bound whether the interval so far (already a valid bound) suffices.
    fn range_until(
        &self,
        lo: Vec3,
        hi: Vec3,
        mut enough: impl FnMut((f32, f32)) -> bool,
    ) -> Option<(f32, f32)> {
        let (lo, hi) = box64(lo, hi)?;
        let c = self.centre.to_array().map(f64::from);
        let (near, far) = distance_to_box(lo, hi, c);
        let (r, a) = (
            f64::from(self.params.radius),
            f64::from(self.params.amplitude),
        );
        let qmax = (0..3)
            .map(|k| (lo[k] - c[k]).abs().max((hi[k] - c[k]).abs()))
            .fold(0.0, f64::max);
        let slack = qmax * (2.0 * f64::from(f32::EPSILON)) + 1e-30;
        let bound = f64::from(fbm_bound());
        let f_range = |(n0, n1): (f64, f64)| {
            let (n0, n1) = (n0.max(-bound) - TOLERANCE, n1.min(bound) + TOLERANCE);
            let (an0, an1) = ((a * n0).min(a * n1), (a * n0).max(a * n1));
            widen(near - r + an0, far - r + an1, far + r.abs() + a.abs())
        };
        let noise = self.batch.range_until(
            std::array::from_fn(|k| lo[k] - c[k] - slack),
            std::array::from_fn(|k| hi[k] - c[k] + slack),
            |n0, n1| f_range((n0, n1)).is_some_and(&mut enough),
        );
        f_range(noise)
    }
}

/// A bound on `|fbm.get(p) as f32|` for the `noise` crate's `Fbm<Perlin>` with the default
/// persistence 1/2 and any octave count from 1 to 32, as the fields build it: `1.0`.
///
/// Proof (from the crate's source, noise 0.9): `perlin_2d`/`perlin_3d` clamp their result to
/// `[-1, 1]`. `Fbm` adds `signal_k * att_k` with `att_k = (1/2)^(k+1)`, a power of two, so each
/// product is exact and at most `att_k` in magnitude; rounding is monotone, so the running sum
/// is at most the rounded sum of the bounds, `1 - 2^-K`, which is exact. It multiplies by
/// `fl(1 / (1 - 2^-K))`, where the denominator (a sum of exact powers of two) is exact too, so
/// the result is at most `1 + 2^-52` in magnitude, which rounds to `1.0` in `f32`. The property
/// test in this module checks the bound on many points.
pub(crate) const fn fbm_bound() -> f32 {
    1.0
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn batches_give_the_same_bits_as_single_samples() {
        for params in [
            AsteroidParams::default(),
            AsteroidParams {
                seed: 123,
                octaves: 6,
                frequency: 2.3,
                amplitude: 0.4,
                radius: 0.5,
            },
        ] {
            let a = Asteroid::new(Vec3::new(0.1, -0.05, 0.02), params);
            let pts: Vec<Vec3> = (0..4099)
                .map(|i| {
                    let t = i as f32;
                    Vec3::new((t * 0.37).sin(), (t * 0.11).cos(), (t * 0.013).sin() * 1.2)
                })
                .chain([Vec3::ZERO, Vec3::splat(-1.0), Vec3::new(0.1, -0.05, 0.02)])
                .collect();
            let mut out = vec![0.0; pts.len()];
            a.sample_batch(&pts, &mut out);
            for (p, v) in pts.iter().zip(&out) {
                assert_eq!(v.to_bits(), a.sample(*p).to_bits(), "at {p}");
            }
        }
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(200))]

        /// A row gives the bits of single samples, for the asteroid's own `sample_row` and for
        /// the trait's default (through `sample_batch`, here on a sphere), on rows of any length
        /// (longer than the 256-point chunks included), spacing and place.
        #[test]
        fn rows_give_the_same_bits_as_single_samples(
            x0 in -1.5f32..1.5,
            step in 0.001f32..0.05,
            len in 0usize..700,
            y in -1.2f32..1.2,
            z in -1.2f32..1.2,
            seed in 0u32..1000,
            octaves in 1usize..9,
        ) {
            let params = AsteroidParams { seed, octaves, ..AsteroidParams::default() };
            let a = Asteroid::new(Vec3::new(0.1, -0.05, 0.02), params);
            let sphere = crate::Sphere::new(Vec3::new(0.2, 0.0, -0.1), 0.7);
            let xs: Vec<f32> = (0..len).map(|i| x0 + step * i as f32).collect();
            let mut out = vec![f32::NAN; len];
            a.sample_row(&xs, y, z, &mut out);
            for (&x, v) in xs.iter().zip(&out) {
                let p = Vec3::new(x, y, z);
                proptest::prop_assert_eq!(v.to_bits(), a.sample(p).to_bits(), "at {}", p);
            }
            sphere.sample_row(&xs, y, z, &mut out);
            for (&x, v) in xs.iter().zip(&out) {
                let p = Vec3::new(x, y, z);
                proptest::prop_assert_eq!(v.to_bits(), sphere.sample(p).to_bits(), "at {}", p);
            }
        }
    }

    #[test]
    fn asteroid_is_deterministic_for_a_seed_and_differs_across_seeds() {
        let a = Asteroid::new(Vec3::ZERO, AsteroidParams::default());
        let b = Asteroid::new(Vec3::ZERO, AsteroidParams::default());
        let c = Asteroid::new(
            Vec3::ZERO,
            AsteroidParams {
                seed: 8,
                ..Default::default()
            },
        );
        let p = Vec3::new(0.31, -0.2, 0.55);
        assert_eq!(a.sample(p), b.sample(p));
        assert_ne!(a.sample(p), c.sample(p));
        assert!(a.sample(Vec3::ZERO) < 0.0, "centre inside");
        assert!(a.sample(Vec3::splat(2.0)) > 0.0, "far point outside");
    }
}
