//! Terrains: ground below, air above, so inside (f < 0) is the solid ground.
//!
//! - [`SvobodaTerrain`]: a 2D fractal Perlin height field extended along y,
//!   `f = y - height(x, z)`; thresholding it at 0 gives a surface without overhangs (the
//!   terrain of Svoboda's dissertation).
//! - [`CaveTerrain`]: 3D fractal noise added to a base height, so the ground can fold over itself
//!   (overhangs, arches, floating rocks), with tunnels carved where two independent noises are
//!   both near zero (worm-like tubes along the curves where their zero sets meet).
//!
//! Neither is a signed distance, so neither reports a surface distance. Both surfaces leave the
//! sampled box through its sides, where the extracted mesh is open by design.

use crate::asteroid::fbm_bound;
use crate::fast_fbm::{FastFbm, TOLERANCE};
use crate::fbm::{BatchFbm, LANES};
use crate::interval::{box64, widen};
use crate::ScalarField;
use glam::Vec3;
use noise::{Fbm, MultiFractal, NoiseFn, Perlin};

/// Parameters of a [`SvobodaTerrain`].
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SvobodaParams {
    /// Seed of the Perlin noise.
    pub seed: u32,
    /// Octaves of fractal Brownian motion (1 to 8 are sensible).
    pub octaves: usize,
    /// Horizontal frequency of the first octave, in cycles per world unit.
    pub frequency: f64,
    /// Height amplitude in world units (the noise lies roughly in [-1, 1]).
    pub amplitude: f32,
    /// Height of the ground where the noise is zero.
    pub base: f32,
}

impl Default for SvobodaParams {
    fn default() -> Self {
        Self {
            seed: 11,
            octaves: 5,
            frequency: 1.0,
            amplitude: 0.45,
            base: 0.0,
        }
    }
}

/// `f = y - (base + amplitude * fbm(x, z))`: a height field, solid below.
pub struct SvobodaTerrain {
    params: SvobodaParams,
    fbm: Fbm<Perlin>,
    batch: BatchFbm,
}

impl SvobodaTerrain {
    /// A terrain with `params`.
    pub fn new(params: SvobodaParams) -> Self {
        let fbm = Fbm::<Perlin>::new(params.seed)
            .set_octaves(params.octaves.clamp(1, 32))
            .set_frequency(params.frequency);
        Self {
            params,
            fbm,
            batch: BatchFbm::new(params.seed, params.octaves.clamp(1, 32), params.frequency),
        }
    }

    /// The parameters it was built with.
    pub fn params(&self) -> &SvobodaParams {
        &self.params
    }

    /// Ground height at `(x, z)`.
    #[inline]
    pub fn height(&self, x: f32, z: f32) -> f32 {
        self.height_of(self.fbm.get([f64::from(x), f64::from(z)]))
    }

    /// The height where the noise is `n`: one formula for every way of sampling, so every way
    /// gives the same bits.
    #[inline(always)]
    fn height_of(&self, n: f64) -> f32 {
        self.params.base + self.params.amplitude * n as f32
    }
}

impl ScalarField for SvobodaTerrain {
    #[inline]
    fn sample(&self, p: Vec3) -> f32 {
        p.y - self.height(p.x, p.z)
    }

    /// The same values as `sample`, bit for bit ([`BatchFbm`]), `LANES` points at a time.
    fn sample_batch(&self, points: &[Vec3], out: &mut [f32]) {
        let mut n = [0.0f64; LANES];
        for (ps, os) in points.chunks(LANES).zip(out.chunks_mut(LANES)) {
            let lane = |f: fn(&Vec3) -> f32| -> [f64; LANES] {
                std::array::from_fn(|k| ps.get(k).map_or(0.0, |p| f64::from(f(p))))
            };
            self.batch
                .get_lanes_2d(&lane(|p| p.x), &lane(|p| p.z), &mut n);
            for ((o, p), &n) in os.iter_mut().zip(ps).zip(&n) {
                *o = p.y - self.height_of(n);
            }
        }
    }

    /// The heights of the shared `(x, z)` columns once ([`BatchFbm`] lanes, as `sample_batch`
    /// computes them), then `y - height` for every row: the same bits as `sample`.
    fn sample_rows(&self, xs: &[f32], ys: &[f32], z: f32, out: &mut [f32], stride: usize) {
        let zs = [f64::from(z); LANES];
        let mut noise = [0.0f64; LANES];
        for (c, xc) in xs.chunks(LANES).enumerate() {
            let lanes: [f64; LANES] =
                std::array::from_fn(|k| xc.get(k).map_or(0.0, |&x| f64::from(x)));
            self.batch.get_lanes_2d(&lanes, &zs, &mut noise);
            for (k, &v) in noise.iter().take(xc.len()).enumerate() {
                let height = self.height_of(v);
                let i = c * LANES + k;
                for (r, &y) in ys.iter().enumerate() {
                    out[stride * r + i] = y - height;
                }
            }
        }
    }

    /// Bounded by the height amplitude: the noise lies in `[-1, 1]` (see `asteroid::fbm_bound`),
    /// so the height lies in `[base - |A|, base + |A|]` and `f = y - height` in
    /// `[y_lo - base - |A|, y_hi - base + |A|]`. Rounding: three roundings on operands of
    /// magnitude at most `max|y| + |base| + |A|`, covered by the widening.
    fn range(&self, lo: Vec3, hi: Vec3) -> Option<(f32, f32)> {
        let (lo, hi) = box64(lo, hi)?;
        let base = f64::from(self.params.base);
        let a = f64::from(self.params.amplitude).abs() * f64::from(fbm_bound());
        widen(
            lo[1] - base - a,
            hi[1] - base + a,
            lo[1].abs().max(hi[1].abs()) + base.abs() + a,
        )
    }
}

/// Parameters of a [`CaveTerrain`].
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CaveParams {
    /// Seed of the terrain noise; the two cave noises use `seed + 1` and `seed + 2`.
    pub seed: u32,
    /// Octaves of the terrain's fractal Brownian motion.
    pub octaves: usize,
    /// Frequency of the terrain noise's first octave, in cycles per world unit.
    pub frequency: f64,
    /// Amplitude of the terrain noise in world units. Overhangs appear where it beats the
    /// vertical slope of y, i.e. when `amplitude * frequency` is well above 1/(2 pi).
    pub amplitude: f32,
    /// Ground height where the noise is zero.
    pub base: f32,
    /// Frequency of the cave noises (higher: more, shorter tunnels).
    pub cave_frequency: f64,
    /// Tunnel radius in noise units (0 disables caves; 0.1 to 0.25 gives tunnels).
    pub cave_radius: f32,
    /// Caves are carved only below this height (world units), so the sky stays empty.
    pub cave_ceiling: f32,
}

impl Default for CaveParams {
    fn default() -> Self {
        Self {
            seed: 5,
            octaves: 4,
            frequency: 1.2,
            amplitude: 0.5,
            base: 0.0,
            cave_frequency: 1.5,
            cave_radius: 0.18,
            cave_ceiling: 0.2,
        }
    }
}

/// 3D fractal-noise ground with overhangs, carved by tunnels:
/// `f = max(y - base + amplitude * fbm(p), radius - sqrt(n1(p)^2 + n2(p)^2))` below the cave
/// ceiling (`n1`, `n2` independent Perlin noises; the second term is negative inside a tunnel,
/// so the max removes the tunnel from the ground).
///
/// The three noises are the `noise` crate's (`Fbm<Perlin>` and two `Perlin`, a one-octave
/// `Fbm<Perlin>` being exactly `Perlin`), evaluated by [`FastFbm`] in `f32` along rows, within
/// [`TOLERANCE`] of the crate's values. A single sample and a batch give the same bits.
pub struct CaveTerrain {
    params: CaveParams,
    fbm: FastFbm,
    cave_a: FastFbm,
    cave_b: FastFbm,
}

impl CaveTerrain {
    /// A terrain with `params`.
    pub fn new(params: CaveParams) -> Self {
        let k = params.cave_frequency;
        Self {
            params,
            fbm: FastFbm::new(params.seed, params.octaves.clamp(1, 32), params.frequency),
            cave_a: FastFbm::new(params.seed.wrapping_add(1), 1, k),
            cave_b: FastFbm::new(params.seed.wrapping_add(2), 1, k),
        }
    }

    /// The parameters it was built with.
    pub fn params(&self) -> &CaveParams {
        &self.params
    }

    /// The ground without caves (negative inside).
    #[inline]
    pub fn ground(&self, p: Vec3) -> f32 {
        let n = self.fbm.get([p.x, p.y, p.z].map(f64::from));
        p.y - self.params.base + self.params.amplitude * n
    }

    /// The tunnels' field: negative inside a tunnel (ignores the ceiling).
    #[inline]
    pub fn tunnels(&self, p: Vec3) -> f32 {
        let q = [p.x, p.y, p.z].map(f64::from);
        let (a, b) = (self.cave_a.get(q), self.cave_b.get(q));
        (a * a + b * b).sqrt() - self.params.cave_radius
    }

    /// The field from the noises at a point: the formula of [`ScalarField::sample`].
    #[inline]
    fn combine(&self, p: Vec3, n: f32, a: f32, b: f32) -> f32 {
        let c = &self.params;
        let ground = p.y - c.base + c.amplitude * n;
        if c.cave_radius <= 0.0 {
            return ground;
        }
        let tunnels = (a * a + b * b).sqrt() - c.cave_radius;
        // Blend the carving out above the ceiling, continuously, so no step appears there.
        let fade = (p.y - c.cave_ceiling).max(0.0);
        ground.max(-(tunnels + fade))
    }
}

impl ScalarField for CaveTerrain {
    #[inline]
    fn sample(&self, p: Vec3) -> f32 {
        let q = [p.x, p.y, p.z].map(f64::from);
        let n = self.fbm.get(q);
        if self.params.cave_radius <= 0.0 {
            return self.combine(p, n, 0.0, 0.0);
        }
        self.combine(p, n, self.cave_a.get(q), self.cave_b.get(q))
    }

    /// The same values as `sample`, bit for bit; runs of points with equal `y` and `z` (the
    /// rows of a lattice) share the noises' work (see [`FastFbm`]).
    fn sample_batch(&self, points: &[Vec3], out: &mut [f32]) {
        const CHUNK: usize = 256;
        let caves = self.params.cave_radius > 0.0;
        let mut xyz = [[0.0f64; CHUNK]; 3];
        let (mut n, mut na, mut nb) = ([0.0f32; CHUNK], [0.0f32; CHUNK], [0.0f32; CHUNK]);
        for (ps, os) in points.chunks(CHUNK).zip(out.chunks_mut(CHUNK)) {
            let len = ps.len();
            for (i, p) in ps.iter().enumerate() {
                xyz[0][i] = f64::from(p.x);
                xyz[1][i] = f64::from(p.y);
                xyz[2][i] = f64::from(p.z);
            }
            let [x, y, z] = &xyz;
            let (x, y, z) = (&x[..len], &y[..len], &z[..len]);
            self.fbm.get_points(x, y, z, &mut n[..len]);
            if caves {
                self.cave_a.get_points(x, y, z, &mut na[..len]);
                self.cave_b.get_points(x, y, z, &mut nb[..len]);
            }
            for (i, (o, &p)) in os.iter_mut().zip(ps).enumerate() {
                *o = self.combine(p, n[i], na[i], nb[i]);
            }
        }
    }

    /// Interval arithmetic on the formula. The crate's noises lie in `[-1, 1]` (Perlin clamps
    /// its result; `asteroid::fbm_bound` for the fractal), and [`FastFbm`]'s within
    /// [`TOLERANCE`] of them, so in `[-m, m]` with `m = 1 + TOLERANCE`:
    /// - `ground = y - base + A fbm` lies in `[y_lo - base - m|A|, y_hi - base + m|A|]`;
    /// - `tunnels = sqrt(a^2 + b^2) - radius` in `[-radius, m sqrt 2 - radius]`;
    /// - `fade = max(y - ceiling, 0)` in `[max(y_lo - ceiling, 0), max(y_hi - ceiling, 0)]`;
    /// - `max(ground, -(tunnels + fade))` in `[max(lo_g, lo_c), max(hi_g, hi_c)]` (max is
    ///   increasing in both arguments), or `ground` alone without caves.
    ///
    /// Rounding: about ten roundings on operands of magnitude at most
    /// `max|y| + |base| + |A| + 2 + |radius| + |ceiling|`, covered by the widening.
    fn range(&self, lo: Vec3, hi: Vec3) -> Option<(f32, f32)> {
        let (lo, hi) = box64(lo, hi)?;
        let p = &self.params;
        let (base, radius, ceiling) = (
            f64::from(p.base),
            f64::from(p.cave_radius),
            f64::from(p.cave_ceiling),
        );
        let m = f64::from(fbm_bound()) + TOLERANCE;
        let a = f64::from(p.amplitude).abs() * m;
        let (g0, g1) = (lo[1] - base - a, hi[1] - base + a);
        let magnitude =
            lo[1].abs().max(hi[1].abs()) + base.abs() + a + 2.0 + radius.abs() + ceiling.abs();
        if p.cave_radius <= 0.0 {
            return widen(g0, g1, magnitude);
        }
        let (fade0, fade1) = ((lo[1] - ceiling).max(0.0), (hi[1] - ceiling).max(0.0));
        let (c0, c1) = (
            -(m * std::f64::consts::SQRT_2 - radius + fade1),
            radius - fade0,
        );
        widen(g0.max(c0), g1.max(c1), magnitude)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(200))]

        /// Rows sharing their x coordinates give the bits of single samples, for the terrain's
        /// own `sample_rows` (heights once per column) and for the trait's default (through
        /// `sample_row`, here on the cave terrain), with any number of rows and row lengths
        /// around the lane width.
        #[test]
        fn shared_rows_give_the_same_bits_as_single_samples(
            x0 in -3.0f32..3.0,
            step in 0.001f32..0.1,
            len in 1usize..40,
            ys in proptest::collection::vec(-1.0f32..1.0, 0..6),
            z in -3.0f32..3.0,
            seed in 0u32..1000,
            gap in 0usize..5,
        ) {
            let t = SvobodaTerrain::new(SvobodaParams { seed, ..SvobodaParams::default() });
            let caves = CaveTerrain::new(CaveParams::default());
            let xs: Vec<f32> = (0..len).map(|i| x0 + step * i as f32).collect();
            // Rows `stride` apart, with a gap that must stay untouched.
            let stride = len + gap;
            for field in [&t as &dyn ScalarField, &caves] {
                let mut out = vec![f32::NAN; stride * ys.len()];
                field.sample_rows(&xs, &ys, z, &mut out, stride);
                for (r, &y) in ys.iter().enumerate() {
                    for (i, &x) in xs.iter().enumerate() {
                        let p = Vec3::new(x, y, z);
                        proptest::prop_assert_eq!(
                            out[stride * r + i].to_bits(),
                            field.sample(p).to_bits(),
                            "at {}",
                            p
                        );
                    }
                    proptest::prop_assert!(out[stride * r + len..stride * (r + 1)]
                        .iter()
                        .all(|v| v.is_nan()));
                }
            }
        }
    }

    fn lattice(n: usize) -> impl Iterator<Item = Vec3> {
        (0..n * n * n).map(move |k| {
            let (x, y, z) = (k % n, (k / n) % n, k / (n * n));
            Vec3::new(x as f32, y as f32, z as f32) * (2.0 / (n - 1) as f32) - 1.0
        })
    }

    #[test]
    fn batches_give_the_same_bits_as_single_samples() {
        let pts: Vec<Vec3> = lattice(23)
            .map(|p| p * 1.3 + Vec3::new(0.01, 0.02, -0.03))
            .chain(lattice(5))
            .collect();
        let svoboda = SvobodaTerrain::new(SvobodaParams::default());
        let caves = CaveTerrain::new(CaveParams::default());
        let plain = CaveTerrain::new(CaveParams {
            cave_radius: 0.0,
            ..Default::default()
        });
        for f in [&svoboda as &dyn ScalarField, &caves, &plain] {
            let mut out = vec![0.0; pts.len()];
            f.sample_batch(&pts, &mut out);
            for (p, v) in pts.iter().zip(&out) {
                assert_eq!(v.to_bits(), f.sample(*p).to_bits(), "at {p}");
            }
        }
    }

    #[test]
    fn svoboda_terrain_is_a_height_field_solid_below() {
        let t = SvobodaTerrain::new(SvobodaParams::default());
        for p in lattice(9) {
            let h = t.height(p.x, p.z);
            assert!((t.sample(p) - (p.y - h)).abs() < 1e-6);
            // Monotone along y: exactly one crossing per vertical line.
            assert!(t.sample(p + Vec3::Y * 0.1) > t.sample(p));
        }
        let heights: Vec<f32> = lattice(9).map(|p| t.height(p.x, p.z)).collect();
        let spread = heights.iter().cloned().fold(f32::NEG_INFINITY, f32::max)
            - heights.iter().cloned().fold(f32::INFINITY, f32::min);
        assert!(
            spread > 0.1,
            "the terrain should not be flat: spread {spread}"
        );
        assert!(
            heights.iter().all(|h| h.abs() <= 0.45 * 2.0),
            "heights within the amplitude"
        );
    }

    #[test]
    fn seeds_decide_the_terrain() {
        let p = Vec3::new(0.33, 0.1, -0.41);
        let a = SvobodaTerrain::new(SvobodaParams::default());
        let b = SvobodaTerrain::new(SvobodaParams {
            seed: 12,
            ..Default::default()
        });
        assert_eq!(
            a.sample(p),
            SvobodaTerrain::new(SvobodaParams::default()).sample(p)
        );
        assert_ne!(a.sample(p), b.sample(p));
        let c = CaveTerrain::new(CaveParams::default());
        let d = CaveTerrain::new(CaveParams {
            seed: 6,
            ..Default::default()
        });
        assert_eq!(
            c.sample(p),
            CaveTerrain::new(CaveParams::default()).sample(p)
        );
        assert_ne!(c.sample(p), d.sample(p));
    }

    #[test]
    fn cave_terrain_has_overhangs_and_tunnels() {
        let t = CaveTerrain::new(CaveParams::default());
        let n = 40;
        // Overhangs: a vertical line that enters the ground more than once.
        let mut overhangs = 0;
        let mut carved = 0;
        for i in 0..n {
            for k in 0..n {
                let (x, z) = (
                    i as f32 / n as f32 * 2.0 - 1.0,
                    k as f32 / n as f32 * 2.0 - 1.0,
                );
                let mut entries = 0;
                let mut was_solid = false;
                for j in (0..4 * n).rev() {
                    let p = Vec3::new(x, j as f32 / (4 * n) as f32 * 2.0 - 1.0, z);
                    let solid = t.sample(p) < 0.0;
                    entries += usize::from(solid && !was_solid);
                    was_solid = solid;
                    carved += usize::from(t.ground(p) < 0.0 && !solid);
                }
                overhangs += usize::from(entries > 1);
            }
        }
        assert!(overhangs > 0, "no vertical line meets the ground twice");
        assert!(carved > 0, "no tunnel carved");
        // Deep below is solid, high above is air, away from tunnels.
        assert!(t.ground(Vec3::new(0.0, -5.0, 0.0)) < 0.0);
        assert!(t.sample(Vec3::new(0.0, 5.0, 0.0)) > 0.0);
        // Without caves, nothing is carved.
        let plain = CaveTerrain::new(CaveParams {
            cave_radius: 0.0,
            ..Default::default()
        });
        assert!(lattice(8).all(|p| plain.sample(p) == plain.ground(p)));
    }

    #[test]
    fn params_reject_unknown_keys_and_round_trip() {
        let err = serde_json::from_str::<SvobodaParams>(
            r#"{"seed": 1, "octaves": 2, "frequency": 1.0, "amplitude": 0.1, "base": 0.0, "bogus": 1}"#,
        )
        .unwrap_err();
        assert!(err.to_string().contains("bogus"), "{err}");
        let err = serde_json::from_str::<CaveParams>(r#"{"seed": 1, "caves": 2}"#).unwrap_err();
        assert!(err.to_string().contains("caves"), "{err}");
        let text = serde_json::to_string(&CaveParams::default()).unwrap();
        assert_eq!(
            serde_json::from_str::<CaveParams>(&text).unwrap(),
            CaveParams::default()
        );
    }
}
