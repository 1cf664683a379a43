//! Closed-form fields: sphere, torus, gyroid, and closures.

use crate::interval::{box64, distance_to_box, widen, SLACK_ABS, SLACK_REL};
use crate::ScalarField;
use glam::Vec3;

/// Signed distance to a sphere: `|p - centre| - radius`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sphere {
    /// Centre in world coordinates.
    pub centre: Vec3,
    /// Radius (> 0).
    pub radius: f32,
}

impl Sphere {
    /// A sphere of `radius` around `centre`.
    pub fn new(centre: Vec3, radius: f32) -> Self {
        Self { centre, radius }
    }
}

impl ScalarField for Sphere {
    #[inline]
    fn sample(&self, p: Vec3) -> f32 {
        (p - self.centre).length() - self.radius
    }
    fn surface_distance(&self, p: Vec3) -> Option<f32> {
        Some(self.sample(p).abs())
    }
    /// Exact: `|p - centre|` ranges over `[near, far]`, the smallest and largest distance from
    /// the centre to the box (both attained, the box is connected), so `f` ranges over
    /// `[near - r, far - r]`. Rounding: `sample` makes about six roundings on operands of
    /// magnitude at most `far + |r|` (see `interval`'s module doc), covered by the widening.
    fn range(&self, lo: Vec3, hi: Vec3) -> Option<(f32, f32)> {
        let (lo, hi) = box64(lo, hi)?;
        let c = self.centre.to_array().map(f64::from);
        let (near, far) = distance_to_box(lo, hi, c);
        let r = f64::from(self.radius);
        widen(near - r, far - r, far + r.abs())
    }
}

/// Signed distance to a torus around the y axis through `centre`: major radius `major` (centre of
/// the tube), minor radius `minor` (tube radius). Genus 1: Euler characteristic 0.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Torus {
    /// Centre in world coordinates.
    pub centre: Vec3,
    /// Distance from the centre to the middle of the tube.
    pub major: f32,
    /// Tube radius.
    pub minor: f32,
}

impl ScalarField for Torus {
    #[inline]
    fn sample(&self, p: Vec3) -> f32 {
        let q = p - self.centre;
        let ring = (q.x * q.x + q.z * q.z).sqrt() - self.major;
        (ring * ring + q.y * q.y).sqrt() - self.minor
    }
    fn surface_distance(&self, p: Vec3) -> Option<f32> {
        Some(self.sample(p).abs())
    }
    /// Exact: with `q = p - centre`, `f = sqrt(ring^2 + q.y^2) - minor` where
    /// `ring = |(q.x, q.z)| - major` depends on `(x, z)` only and `q.y` on `y` only. The box is
    /// the product of an `xz` rectangle and a `y` interval, so the two vary independently:
    /// `|(q.x, q.z)|` ranges over `[near, far]` (distance from the axis to the rectangle),
    /// `|ring|` over `[dist(0, [near - major, far - major]), max(|near - major|, |far - major|)]`,
    /// `|q.y|` over its own `[near_y, far_y]`, and `f` is increasing in both absolute values.
    /// Rounding: about ten roundings on operands of magnitude at most
    /// `far + |major| + far_y + |minor|`, covered by the widening.
    fn range(&self, lo: Vec3, hi: Vec3) -> Option<(f32, f32)> {
        let (lo, hi) = box64(lo, hi)?;
        let c = self.centre.to_array().map(f64::from);
        let (near, far) =
            distance_to_box([lo[0], 0.0, lo[2]], [hi[0], 0.0, hi[2]], [c[0], 0.0, c[2]]);
        let (near_y, far_y) = crate::interval::axis_distance(lo[1], hi[1], c[1]);
        let (major, minor) = (f64::from(self.major), f64::from(self.minor));
        let (r0, r1) = (near - major, far - major);
        let ring_near = if r0 <= 0.0 && r1 >= 0.0 {
            0.0
        } else {
            r0.abs().min(r1.abs())
        };
        let ring_far = r0.abs().max(r1.abs());
        widen(
            ring_near.hypot(near_y) - minor,
            ring_far.hypot(far_y) - minor,
            far + major.abs() + far_y + minor.abs(),
        )
    }
}

/// A thickened gyroid, `|sin(kx)cos(ky) + sin(ky)cos(kz) + sin(kz)cos(kx)| - thickness` with
/// `k = 2 pi frequency`: a triply periodic sheet with many handles, a stress test for topology.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Gyroid {
    /// Periods per world unit.
    pub frequency: f32,
    /// Half-thickness of the sheet in gyroid-function units (0.0 to about 1.4).
    pub thickness: f32,
}

impl ScalarField for Gyroid {
    #[inline]
    fn sample(&self, p: Vec3) -> f32 {
        let q = p * (std::f32::consts::TAU * self.frequency);
        let g = q.x.sin() * q.y.cos() + q.y.sin() * q.z.cos() + q.z.sin() * q.x.cos();
        g.abs() - self.thickness
    }
    /// Lipschitz. Write `G(q) = sin qx cos qy + sin qy cos qz + sin qz cos qx` and let `k` be the
    /// `f32` factor `sample` multiplies `p` by. Then:
    /// - `|G| <= 3/2` everywhere, since `sin a cos b <= (sin^2 a + cos^2 b) / 2` and the three
    ///   terms use every `sin^2` and `cos^2` once;
    /// - `|dG/dqx| = |cos qx cos qy - sin qz sin qx| <= |(cos qx, -sin qx)| |(cos qy, sin qz)|
    ///   <= sqrt 2` (Cauchy-Schwarz), likewise for `y` and `z`; so over the box,
    ///   `|G(k p) - G(k c)| <= sqrt 2 k (sx + sy + sz)` with `c` the box centre and `s` its
    ///   half extents, and `| |G(kp)| - |G(kc)| |` obeys the same bound;
    /// - `G(k c)` is computed in `f64`.
    ///
    /// Rounding: `sample` evaluates `G` at `fl(p k)`, within `u |q|` of `k p` per axis
    /// (`u = 2^-24`), which moves `G` by at most `3 sqrt 2 u max|q|`; the library `sin`/`cos`
    /// (within an ulp, <= `u` below 1 in magnitude) and the products and sums add under `20 u`;
    /// the widening `2^-19 (max|q| + 4 + |thickness|)` covers both with room to spare.
    fn range(&self, lo: Vec3, hi: Vec3) -> Option<(f32, f32)> {
        let (lo, hi) = box64(lo, hi)?;
        let k = f64::from(std::f32::consts::TAU * self.frequency);
        if !k.is_finite() {
            return None;
        }
        let c: [f64; 3] = std::array::from_fn(|a| 0.5 * (lo[a] + hi[a]) * k);
        let g = c[0].sin() * c[1].cos() + c[1].sin() * c[2].cos() + c[2].sin() * c[0].cos();
        let spread =
            std::f64::consts::SQRT_2 * k.abs() * (0..3).map(|a| 0.5 * (hi[a] - lo[a])).sum::<f64>();
        let (g0, g1) = ((g - spread).max(-1.5), (g + spread).min(1.5));
        let near = if g0 <= 0.0 && g1 >= 0.0 {
            0.0
        } else {
            g0.abs().min(g1.abs())
        };
        let far = g0.abs().max(g1.abs());
        let qmax = (0..3)
            .map(|a| lo[a].abs().max(hi[a].abs()) * k.abs())
            .fold(0.0, f64::max);
        let t = f64::from(self.thickness);
        let slack = SLACK_REL * (qmax + 4.0 + t.abs()) + SLACK_ABS;
        widen(near - t - slack, far - t + slack, 0.0)
    }
}

/// A field defined by a closure, for tests and one-off experiments.
///
/// ```
/// use rmt_fields::{FnField, ScalarField};
/// let plane = FnField(|p: glam::Vec3| p.y - 0.25);
/// assert_eq!(plane.sample(glam::Vec3::new(3.0, 0.25, -1.0)), 0.0);
/// ```
#[derive(Clone, Copy)]
pub struct FnField<F>(pub F);

impl<F: Fn(Vec3) -> f32 + Send + Sync> ScalarField for FnField<F> {
    #[inline]
    fn sample(&self, p: Vec3) -> f32 {
        (self.0)(p)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn torus_is_negative_inside_the_tube_and_positive_in_the_hole() {
        let t = Torus {
            centre: Vec3::ZERO,
            major: 1.0,
            minor: 0.3,
        };
        assert!(t.sample(Vec3::new(1.0, 0.0, 0.0)) < 0.0);
        assert!(t.sample(Vec3::ZERO) > 0.0);
        assert!((t.sample(Vec3::new(1.3, 0.0, 0.0))).abs() < 1e-6);
    }

    #[test]
    fn gyroid_is_zero_free_at_the_origin_sheet() {
        let g = Gyroid {
            frequency: 1.0,
            thickness: 0.3,
        };
        // g(0) = 0, so the origin lies inside the thickened sheet.
        assert!(g.sample(Vec3::ZERO) < 0.0);
    }
}
