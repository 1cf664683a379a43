//! A noise asteroid: a sphere whose radius is displaced by fractal Perlin noise.

use crate::ScalarField;
use glam::Vec3;
use noise::{Fbm, MultiFractal, NoiseFn, Perlin};

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
pub struct Asteroid {
    params: AsteroidParams,
    centre: Vec3,
    fbm: Fbm<Perlin>,
}

impl Asteroid {
    /// An asteroid centred at `centre`.
    pub fn new(centre: Vec3, params: AsteroidParams) -> Self {
        let fbm = Fbm::<Perlin>::new(params.seed)
            .set_octaves(params.octaves.clamp(1, 32))
            .set_frequency(params.frequency);
        Self {
            params,
            centre,
            fbm,
        }
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
        let n = self.fbm.get([q.x as f64, q.y as f64, q.z as f64]) as f32;
        q.length() - self.params.radius + self.params.amplitude * n
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
