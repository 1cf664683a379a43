//! Random test fields: the families of the extractors' property tests
//! (`crates/extract/tests/random_fields.rs`), drawn from a seed instead of by proptest, so that a
//! sweep over thousands of fields (the `topology` manifests of `experiments`) can run anywhere,
//! sharded, and any failing field can be rebuilt from its seed alone.
//!
//! A field lives in the cube `[-1, 1]^3` (the caller maps its box onto it) and has features sized
//! for about 10 cells across: blobs, plane waves up to about one period per 2 cells, thin
//! spherical shells and thin tubes along a circle (thickness 0.3 to 1.5 cells), and in a quarter
//! of the fields values rounded to a quantum so that many samples sit exactly on the threshold.

use glam::Vec3;

use crate::ScalarField;

/// One family of random field, described by numbers only.
#[derive(Clone, Debug, PartialEq)]
pub enum RandomFamily {
    /// `0.5 - sum a exp(-|p - c|^2 / s^2)` over blobs `(c, s, a)`.
    Blobs(Vec<(Vec3, f32, f32)>),
    /// `sum a sin(k . p + phase) + offset` over waves `(k, phase, a)`.
    Waves(Vec<(Vec3, f32, f32)>, f32),
    /// A spherical shell `(centre, radius, half-thickness)`.
    Shell(Vec3, f32, f32),
    /// A tube of radius `t` along a circle of radius `r` around the y axis through `c`.
    Tube(Vec3, f32, f32),
    /// A thin planar sheet `|n . p - d| - t` (normal `n`, normalised; offset `d`; half
    /// thickness `t`). Not drawn by [`RandomField::from_seed`]; the property tests draw it.
    Sheet(Vec3, f32, f32),
    /// Integer steps of a slanted plane, `round(k . p + b)`: whole layers of sample points sit
    /// exactly on the threshold, so the surface passes through sample points everywhere (and
    /// many clustering tests fail together). Not drawn by [`RandomField::from_seed`].
    Stairs(Vec3, f32),
}

/// A random field of [`RandomFamily`] in `[-1, 1]^3`, optionally quantised. Build one with
/// [`RandomField::from_seed`]; [`RandomField::in_box`] maps it onto another box.
#[derive(Clone, Debug, PartialEq)]
pub struct RandomField {
    /// The family and its parameters.
    pub family: RandomFamily,
    /// Values are rounded to multiples of this (0 = not rounded).
    pub quantum: f32,
    /// Centre of the box mapped onto `[-1, 1]^3`.
    pub centre: Vec3,
    /// Half the side of that box (the same on every axis, so distances keep their ratios).
    pub half: f32,
}

/// SplitMix64: a tiny, well-mixed generator; the whole field is a function of the seed.
struct SplitMix(u64);

impl SplitMix {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// Uniform in `[lo, hi)` (24 random bits, exact in f32).
    fn range(&mut self, lo: f32, hi: f32) -> f32 {
        let u = (self.next() >> 40) as f32 / (1u64 << 24) as f32;
        lo + (hi - lo) * u
    }
    /// Uniform integer in `lo..hi`.
    fn int(&mut self, lo: usize, hi: usize) -> usize {
        lo + (self.next() % (hi - lo) as u64) as usize
    }
    fn vec3(&mut self, r: f32) -> Vec3 {
        Vec3::new(self.range(-r, r), self.range(-r, r), self.range(-r, r))
    }
}

impl RandomField {
    /// The field of `seed`, with the distributions of the property tests (features sized for
    /// `h = 0.2`, ten cells across the cube): each family with probability 1/4, quantised values
    /// (quantum 0.02 to 0.2) with probability 1/4.
    pub fn from_seed(seed: u64) -> Self {
        let mut g = SplitMix(seed ^ 0x5EED_0FF1_E1D5);
        let h = 0.2f32;
        let kmax = std::f32::consts::PI / h;
        let family = match g.int(0, 4) {
            0 => {
                let n = g.int(1, 6);
                RandomFamily::Blobs(
                    (0..n)
                        .map(|_| (g.vec3(0.8), g.range(0.15, 0.6), g.range(0.3, 1.5)))
                        .collect(),
                )
            }
            1 => {
                let n = g.int(1, 4);
                let waves = (0..n)
                    .map(|_| {
                        (
                            g.vec3(kmax / 3f32.sqrt()),
                            g.range(0.0, 6.3),
                            g.range(0.1, 1.0),
                        )
                    })
                    .collect();
                RandomFamily::Waves(waves, g.range(-0.5, 0.5))
            }
            2 => RandomFamily::Shell(g.vec3(0.3), g.range(0.2, 0.7), g.range(0.3 * h, 1.5 * h)),
            _ => RandomFamily::Tube(g.vec3(0.2), g.range(0.3, 0.6), g.range(0.3 * h, 1.5 * h)),
        };
        let quantum = if g.int(0, 4) == 0 {
            g.range(0.02, 0.2)
        } else {
            0.0
        };
        RandomField {
            family,
            quantum,
            centre: Vec3::ZERO,
            half: 1.0,
        }
    }

    /// The same field mapped onto the cube of side `2 half` around `centre`.
    pub fn in_box(mut self, centre: Vec3, half: f32) -> Self {
        self.centre = centre;
        self.half = half;
        self
    }

    /// A short description of the family (for reports): `blobs`, `waves`, `shell`, `tube`,
    /// `sheet` or `stairs`,
    /// with `+quantised` when values are rounded.
    pub fn describe(&self) -> String {
        let f = match self.family {
            RandomFamily::Blobs(_) => "blobs",
            RandomFamily::Waves(..) => "waves",
            RandomFamily::Shell(..) => "shell",
            RandomFamily::Tube(..) => "tube",
            RandomFamily::Sheet(..) => "sheet",
            RandomFamily::Stairs(..) => "stairs",
        };
        if self.quantum > 0.0 {
            format!("{f}+quantised")
        } else {
            f.to_string()
        }
    }
}

impl ScalarField for RandomField {
    fn sample(&self, p: Vec3) -> f32 {
        let p = (p - self.centre) / self.half;
        let f = match &self.family {
            RandomFamily::Blobs(b) => {
                0.5 - b
                    .iter()
                    .map(|(c, s, a)| a * (-(p - *c).length_squared() / (s * s)).exp())
                    .sum::<f32>()
            }
            RandomFamily::Waves(w, off) => {
                w.iter()
                    .map(|(k, ph, a)| a * (k.dot(p) + ph).sin())
                    .sum::<f32>()
                    + off
            }
            RandomFamily::Shell(c, r, t) => ((p - *c).length() - r).abs() - t,
            RandomFamily::Tube(c, r, t) => {
                let q = p - *c;
                let ring = (q.x * q.x + q.z * q.z).sqrt() - r;
                (ring * ring + q.y * q.y).sqrt() - t
            }
            RandomFamily::Sheet(n, d, t) => (n.normalize_or_zero().dot(p) - d).abs() - t,
            RandomFamily::Stairs(k, b) => (k.dot(p) + b).round(),
        };
        if self.quantum > 0.0 {
            (f / self.quantum).round() * self.quantum
        } else {
            f
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_seed_gives_one_field_and_seeds_cover_every_family() {
        assert_eq!(RandomField::from_seed(7), RandomField::from_seed(7));
        assert_ne!(RandomField::from_seed(7), RandomField::from_seed(8));
        let mut seen = std::collections::BTreeMap::new();
        for seed in 0..400 {
            *seen
                .entry(RandomField::from_seed(seed).describe())
                .or_insert(0) += 1;
        }
        for f in ["blobs", "waves", "shell", "tube"] {
            let plain = seen.get(f).copied().unwrap_or(0);
            let quantised = seen.get(&format!("{f}+quantised")).copied().unwrap_or(0);
            // Each family about 100 times in 400, a quarter of them quantised.
            assert!((60..=140).contains(&(plain + quantised)), "{f}: {seen:?}");
            assert!(quantised > 5 && plain > quantised, "{f}: {seen:?}");
        }
    }

    #[test]
    fn fields_cross_zero_inside_the_cube_and_map_onto_a_box() {
        // A shell of radius 0.2..0.7 around a centre within 0.3: negative on the shell, positive
        // at the far corner.
        let f = RandomField {
            family: RandomFamily::Shell(Vec3::ZERO, 0.5, 0.1),
            quantum: 0.0,
            centre: Vec3::ZERO,
            half: 1.0,
        };
        assert!(f.sample(Vec3::new(0.5, 0.0, 0.0)) < 0.0);
        assert!(f.sample(Vec3::splat(1.0)) > 0.0);
        let moved = f.clone().in_box(Vec3::splat(10.0), 2.0);
        assert_eq!(
            moved.sample(Vec3::new(11.0, 10.0, 10.0)),
            f.sample(Vec3::new(0.5, 0.0, 0.0))
        );
        let q = RandomField { quantum: 0.25, ..f };
        let v = q.sample(Vec3::new(0.3, 0.1, 0.0));
        assert_eq!((v / 0.25).round() * 0.25, v);
    }
}
