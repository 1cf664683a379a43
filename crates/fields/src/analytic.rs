//! Closed-form fields: sphere, torus, gyroid, and closures.

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
