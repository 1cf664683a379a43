//! Spherical brushes that add or remove ground by changing the sampled values.

use glam::Vec3;

use crate::TerrainError;

/// Whether a brush adds ground (lowers values: inside is f < iso) or removes it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BrushMode {
    /// Add material: values decrease.
    Add,
    /// Remove material: values increase.
    Subtract,
}

/// A sphere with a smooth falloff, as in Svoboda's deformation: each sample at distance `d` from
/// the centre changes by `strength * dt * w(d / radius)` with `w(s) = (1 - s^2)^2` for `s < 1`
/// (1 at the centre, 0 with zero slope at the rim) and 0 outside; `dt` is the frame time. With
/// `clamp = Some(c)` the changed values are then clamped to `[-c, c]` so repeated strokes cannot
/// pile up arbitrarily large values (which would make later strokes slow to show).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Brush {
    /// Centre in world coordinates.
    pub centre: Vec3,
    /// Radius in world units (> 0).
    pub radius: f32,
    /// Change of value per unit of `dt` at the centre (>= 0, field units per second).
    pub strength: f32,
    /// Add or remove ground.
    pub mode: BrushMode,
    /// Clamp changed values to `[-c, c]` (c > 0).
    pub clamp: Option<f32>,
}

impl Brush {
    /// A brush that adds ground, without clamping.
    pub fn add(centre: Vec3, radius: f32, strength: f32) -> Self {
        Self {
            centre,
            radius,
            strength,
            mode: BrushMode::Add,
            clamp: None,
        }
    }

    /// A brush that removes ground, without clamping.
    pub fn subtract(centre: Vec3, radius: f32, strength: f32) -> Self {
        Self {
            mode: BrushMode::Subtract,
            ..Self::add(centre, radius, strength)
        }
    }

    /// The same brush with values clamped to `[-c, c]`.
    pub fn with_clamp(mut self, c: f32) -> Self {
        self.clamp = Some(c);
        self
    }

    /// Checks the brush and the time step `dt`.
    pub fn check(&self, dt: f32) -> Result<(), TerrainError> {
        let bad = |what: String| Err(TerrainError::InvalidBrush(what));
        if !self.centre.is_finite() {
            return bad(format!("centre must be finite, got {}", self.centre));
        }
        if !(self.radius.is_finite() && self.radius > 0.0) {
            return bad(format!(
                "radius must be finite and > 0, got {}",
                self.radius
            ));
        }
        if !(self.strength.is_finite() && self.strength >= 0.0) {
            return bad(format!(
                "strength must be finite and >= 0, got {}",
                self.strength
            ));
        }
        if !(dt.is_finite() && dt >= 0.0) {
            return bad(format!("time step must be finite and >= 0, got {dt}"));
        }
        if let Some(c) = self.clamp {
            if !(c.is_finite() && c > 0.0) {
                return bad(format!("clamp must be finite and > 0, got {c}"));
            }
        }
        Ok(())
    }

    /// The new value of a sample `value` at distance `d` from the centre (scaled by `dt`),
    /// finite when `value` is: a change that overflows `f32` stops at `-f32::MAX` or `f32::MAX`.
    #[inline]
    pub fn apply(&self, value: f32, d: f32, dt: f32) -> f32 {
        let s = d / self.radius;
        if s >= 1.0 {
            return value;
        }
        let w = (1.0 - s * s) * (1.0 - s * s);
        let delta = self.strength * dt * w;
        let mut v = match self.mode {
            BrushMode::Add => value - delta,
            BrushMode::Subtract => value + delta,
        };
        if !v.is_finite() && value.is_finite() {
            // The f32 arithmetic overflowed (to infinity, or inf * 0 = NaN): again in f64, where
            // a product of finite f32s cannot, stopping at the largest finite f32.
            let delta = f64::from(self.strength) * f64::from(dt) * f64::from(w);
            let v64 = match self.mode {
                BrushMode::Add => f64::from(value) - delta,
                BrushMode::Subtract => f64::from(value) + delta,
            };
            v = v64.clamp(-f64::from(f32::MAX), f64::from(f32::MAX)) as f32;
        }
        match self.clamp {
            Some(c) => v.clamp(-c, c),
            None => v,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn falloff_is_full_at_the_centre_and_zero_at_the_rim() {
        let b = Brush::add(Vec3::ZERO, 2.0, 3.0);
        assert_eq!(b.apply(1.0, 0.0, 0.5), 1.0 - 1.5);
        assert_eq!(b.apply(1.0, 2.0, 0.5), 1.0);
        let mid = b.apply(1.0, 1.0, 0.5);
        assert!(mid < 1.0 && mid > 1.0 - 1.5);
        let s = Brush::subtract(Vec3::ZERO, 2.0, 3.0).with_clamp(1.2);
        assert_eq!(s.apply(1.0, 0.0, 0.5), 1.2);
    }

    #[test]
    fn overflowing_changes_stop_at_the_largest_finite_value() {
        let b = Brush::add(Vec3::ZERO, 1.0, f32::MAX);
        assert_eq!(b.apply(-f32::MAX, 0.0, f32::MAX), -f32::MAX);
        let s = Brush::subtract(Vec3::ZERO, 1.0, 3e38);
        assert_eq!(s.apply(1.0, 0.0, 3e38), f32::MAX);
        // Near the rim: a small weight times an infinite product.
        let v = s.apply(1.0, 1.0 - f32::EPSILON / 2.0, 3e38);
        assert!(v.is_finite() && v >= 1.0, "{v}");
    }

    #[test]
    fn bad_brushes_are_refused_with_a_message() {
        let b = Brush::add(Vec3::new(f32::NAN, 0.0, 0.0), 1.0, 1.0);
        assert!(b.check(0.1).unwrap_err().to_string().contains("centre"));
        let b = Brush::add(Vec3::ZERO, 0.0, 1.0);
        assert!(b.check(0.1).unwrap_err().to_string().contains("radius"));
        let b = Brush::add(Vec3::ZERO, 1.0, f32::NAN);
        assert!(b.check(0.1).unwrap_err().to_string().contains("strength"));
        let b = Brush::add(Vec3::ZERO, 1.0, 1.0);
        assert!(b
            .check(f32::INFINITY)
            .unwrap_err()
            .to_string()
            .contains("time"));
        assert!(b.with_clamp(-1.0).check(0.1).is_err());
        assert!(b.check(0.1).is_ok());
    }
}
