//! `Fbm<Perlin>` of the `noise` crate (version 0.9), evaluated for many points at once.
//!
//! [`BatchFbm`] reproduces `noise::Fbm::<noise::Perlin>` in three dimensions **bit for bit**:
//! the same permutation tables (read out of `noise::permutationtable::PermutationTable`), the
//! same corner rule (`x as isize`, minus one for `x <= 0`, which is not `floor` at non-positive
//! integers), the same hash `P[P[P[x] ^ y] ^ z]`, the same twelve gradients, and every
//! floating-point operation in the same order on the same `f64` operands (Rust never fuses or
//! reorders them). A gradient `+-u +- v` is computed as `su * u + sv * v` with `su, sv = +-1.0`:
//! multiplying by `-1.0` is an exact negation and `a - b` is by definition `a + (-b)`, so even
//! the signs of zeros agree. The unit test compares it with the crate on random points and asks
//! for equal bits.
//!
//! Speed comes from evaluating [`LANES`] points together: the table look-ups stay scalar, but the
//! arithmetic (the fade curves, the 8 gradients and the 7 interpolations per octave) runs over
//! fixed-size arrays without branches, which the compiler turns into vector instructions.

use noise::permutationtable::{NoiseHasher, PermutationTable};
use noise::{Fbm, MultiFractal, Perlin};

/// Points evaluated together.
pub const LANES: usize = 8;

/// `2 / sqrt(3)`, the scale of `noise::core::perlin::perlin_3d` (the same literal).
pub(crate) const SCALE_3D: f64 = 1.154_700_538_379_251_5;

/// Per gradient index `h & 15`: whether the first term is `y` (else `x`), its sign, whether the
/// second term is `z` (else `y`), its sign (see `perlin_3d`'s match).
const GRADIENTS: [(bool, f64, bool, f64); 16] = [
    (false, 1.0, false, 1.0),   // 0: x + y
    (false, -1.0, false, 1.0),  // 1: -x + y
    (false, 1.0, false, -1.0),  // 2: x - y
    (false, -1.0, false, -1.0), // 3: -x - y
    (false, 1.0, true, 1.0),    // 4: x + z
    (false, -1.0, true, 1.0),   // 5: -x + z
    (false, 1.0, true, -1.0),   // 6: x - z
    (false, -1.0, true, -1.0),  // 7: -x - z
    (true, 1.0, true, 1.0),     // 8: y + z
    (true, -1.0, true, 1.0),    // 9: -y + z
    (true, 1.0, true, -1.0),    // 10: y - z
    (true, -1.0, true, -1.0),   // 11: -y - z
    (false, 1.0, false, 1.0),   // 12: x + y
    (false, -1.0, false, 1.0),  // 13: -x + y
    (true, -1.0, true, 1.0),    // 14: -y + z
    (true, -1.0, true, -1.0),   // 15: -y - z
];

/// [`GRADIENTS`] as bit masks over `h & 15`: first term `y`, first term negated, second term
/// `z`, second term negated (checked against the table by a unit test).
pub(crate) const U_IS_Y: u32 = 0xCF00;
pub(crate) const U_NEG: u32 = 0xEAAA;
pub(crate) const V_IS_Z: u32 = 0xCFF0;
pub(crate) const V_NEG: u32 = 0x8CCC;

/// The permutation table of `noise::Perlin::new(seed)`.
pub(crate) fn permutation(seed: u32) -> [u8; 256] {
    let table = PermutationTable::new(seed);
    // A one-element hash is the table entry itself: `values[i & 0xff]`.
    std::array::from_fn(|i| table.hash(&[i as isize]) as u8)
}

/// `noise::Fbm::<Perlin>` (3D) for batches of points; same values, bit for bit.
#[derive(Clone, Debug)]
pub struct BatchFbm {
    perms: Vec<[u8; 256]>,
    perms32: Vec<[u32; 256]>,
    frequency: f64,
    lacunarity: f64,
    persistence: f64,
    scale: f64,
    /// Each octave's attenuation, and `rest[k]`: the sum of their magnitudes from octave `k` on
    /// (`rest[octaves] = 0`), for the interval bound.
    atts: Vec<f64>,
    rest: Vec<f64>,
    /// Whether the CPU has AVX2 (then `get_lanes` runs the AVX2 build of the same code).
    avx2: bool,
}

impl BatchFbm {
    /// The batch twin of `Fbm::<Perlin>::new(seed).set_octaves(octaves).set_frequency(frequency)`
    /// (`octaves` clamped to 1..=32 as the crate does).
    pub fn new(seed: u32, octaves: usize, frequency: f64) -> Self {
        let reference = Fbm::<Perlin>::new(seed)
            .set_octaves(octaves)
            .set_frequency(frequency);
        let octaves = reference.octaves;
        let persistence = reference.persistence;
        // As `Fbm::calc_scale_factor`.
        let denom = (1..=octaves).fold(0.0, |acc: f64, x| acc + persistence.powi(x as i32));
        let perms: Vec<[u8; 256]> = (0..octaves)
            .map(|k| permutation(seed.wrapping_add(k as u32)))
            .collect();
        let mut attenuation = persistence;
        let atts: Vec<f64> = perms
            .iter()
            .map(|_| {
                let a = attenuation;
                attenuation *= persistence;
                a
            })
            .collect();
        let mut rest = vec![0.0f64; atts.len() + 1];
        for k in (0..atts.len()).rev() {
            rest[k] = rest[k + 1] + atts[k].abs();
        }
        Self {
            perms32: perms.iter().map(|p| p.map(u32::from)).collect(),
            perms,
            atts,
            rest,
            frequency: reference.frequency,
            lacunarity: reference.lacunarity,
            persistence,
            scale: 1.0 / denom,
            avx2: has_avx2(),
        }
    }

    /// The noise at one point (as `Fbm::get`).
    pub fn get(&self, p: [f64; 3]) -> f64 {
        let mut out = [0.0; LANES];
        let lanes = [p; LANES];
        self.get_lanes(
            &lanes.map(|q| q[0]),
            &lanes.map(|q| q[1]),
            &lanes.map(|q| q[2]),
            &mut out,
        );
        out[0]
    }

    /// The noise at `LANES` points given by their coordinates.
    #[inline]
    pub fn get_lanes(
        &self,
        x: &[f64; LANES],
        y: &[f64; LANES],
        z: &[f64; LANES],
        out: &mut [f64; LANES],
    ) {
        #[cfg(target_arch = "x86_64")]
        if self.avx2 {
            // SAFETY: `avx2` is set only when the CPU has AVX2 (checked at construction).
            unsafe { self.get_lanes_avx2(x, y, z, out) };
            return;
        }
        self.get_lanes_portable(x, y, z, out);
    }

    /// [`BatchFbm::get_lanes`] compiled for AVX2 (4 `f64` per instruction; the same operations,
    /// never fused, so the same bits).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn get_lanes_avx2(
        &self,
        x: &[f64; LANES],
        y: &[f64; LANES],
        z: &[f64; LANES],
        out: &mut [f64; LANES],
    ) {
        self.fbm_lanes(x, y, z, out);
    }

    /// [`BatchFbm::get_lanes`] for the baseline instruction set (what other CPUs run; also
    /// tested on this one).
    pub fn get_lanes_portable(
        &self,
        x: &[f64; LANES],
        y: &[f64; LANES],
        z: &[f64; LANES],
        out: &mut [f64; LANES],
    ) {
        self.fbm_lanes(x, y, z, out);
    }

    #[inline(always)]
    fn fbm_lanes(
        &self,
        x: &[f64; LANES],
        y: &[f64; LANES],
        z: &[f64; LANES],
        out: &mut [f64; LANES],
    ) {
        let mut px = x.map(|v| v * self.frequency);
        let mut py = y.map(|v| v * self.frequency);
        let mut pz = z.map(|v| v * self.frequency);
        let mut result = [0.0f64; LANES];
        let mut attenuation = self.persistence;
        let mut signal = [0.0f64; LANES];
        for (perm, perm32) in self.perms.iter().zip(&self.perms32) {
            perlin_lanes(perm, perm32, &px, &py, &pz, &mut signal);
            for i in 0..LANES {
                result[i] += signal[i] * attenuation;
            }
            attenuation *= self.persistence;
            for i in 0..LANES {
                px[i] *= self.lacunarity;
                py[i] *= self.lacunarity;
                pz[i] *= self.lacunarity;
            }
        }
        for i in 0..LANES {
            out[i] = result[i] * self.scale;
        }
    }
}

impl BatchFbm {
    /// The 2D noise (`NoiseFn<f64, 2>` of `Fbm<Perlin>`) at `LANES` points.
    #[inline]
    pub fn get_lanes_2d(&self, x: &[f64; LANES], y: &[f64; LANES], out: &mut [f64; LANES]) {
        let mut px = x.map(|v| v * self.frequency);
        let mut py = y.map(|v| v * self.frequency);
        let mut result = [0.0f64; LANES];
        let mut attenuation = self.persistence;
        let mut signal = [0.0f64; LANES];
        for perm in &self.perms {
            perlin2_lanes(perm, &px, &py, &mut signal);
            for i in 0..LANES {
                result[i] += signal[i] * attenuation;
            }
            attenuation *= self.persistence;
            for i in 0..LANES {
                px[i] *= self.lacunarity;
                py[i] *= self.lacunarity;
            }
        }
        for i in 0..LANES {
            out[i] = result[i] * self.scale;
        }
    }
}

/// `2 / sqrt(2)`, the scale of `noise::core::perlin::perlin_2d` (the same expression).
const SCALE_2D: f64 = 2.0 / std::f64::consts::SQRT_2;

/// `noise::core::perlin::perlin_2d` at `LANES` points: hash `P[P[x] ^ y] & 3` picks
/// `+-x +- y`.
#[inline(always)]
fn perlin2_lanes(perm: &[u8; 256], x: &[f64; LANES], y: &[f64; LANES], out: &mut [f64; LANES]) {
    const SIGNS: [(f64, f64); 4] = [(1.0, 1.0), (-1.0, 1.0), (1.0, -1.0), (-1.0, -1.0)];
    let mut hashes = [[0u8; LANES]; 4];
    let (mut dx, mut dy) = ([0.0; LANES], [0.0; LANES]);
    for i in 0..LANES {
        let (cx, fx) = corner(x[i]);
        let (cy, fy) = corner(y[i]);
        dx[i] = fx;
        dy[i] = fy;
        let xs = [(cx & 0xff) as usize, ((cx + 1) & 0xff) as usize];
        let ys = [(cy & 0xff) as usize, ((cy + 1) & 0xff) as usize];
        for (ox, &xi) in xs.iter().enumerate() {
            let a = perm[xi] as usize;
            for (oy, &yi) in ys.iter().enumerate() {
                hashes[ox * 2 + oy][i] = perm[a ^ yi] & 3;
            }
        }
    }
    let mut g = [[0.0f64; LANES]; 4];
    for (k, gk) in g.iter_mut().enumerate() {
        let (ox, oy) = ((k >> 1) as f64, (k & 1) as f64);
        for i in 0..LANES {
            let (sx, sy) = SIGNS[hashes[k][i] as usize];
            gk[i] = sx * (dx[i] - ox) + sy * (dy[i] - oy);
        }
    }
    for i in 0..LANES {
        let (cx, cy) = (quintic(dx[i]), quintic(dy[i]));
        let r = lerp(lerp(g[0][i], g[1][i], cy), lerp(g[2][i], g[3][i], cy), cx) * SCALE_2D;
        out[i] = r.clamp(-1.0, 1.0);
    }
}

/// Whether this CPU runs AVX2 code.
pub(crate) fn has_avx2() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        std::is_x86_feature_detected!("avx2")
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}

/// The corner of `noise`'s `floor_to_isize` and the distance from it.
#[inline(always)]
fn corner(v: f64) -> (isize, f64) {
    let c = if v <= 0.0 { v as isize - 1 } else { v as isize };
    (c, v - c as f64)
}

/// `noise`'s quintic fade (`map_quintic`), same operation order.
#[inline(always)]
fn quintic(v: f64) -> f64 {
    let x = v.clamp(0.0, 1.0);
    x * x * x * (x * (x * 6.0 - 15.0) + 10.0)
}

/// `noise`'s `linear(a, b, alpha)`.
#[inline(always)]
fn lerp(a: f64, b: f64, alpha: f64) -> f64 {
    b * alpha + a * (1.0 - alpha)
}

/// `noise::core::perlin::perlin_3d` at `LANES` points: the vectorisable version when every
/// coordinate is small enough for `i32` corners (`|v| < 2^30`, where truncating to `i32` and to
/// `isize` agree), else the `isize` version.
#[inline(always)]
pub(crate) fn perlin_lanes(
    perm: &[u8; 256],
    perm32: &[u32; 256],
    x: &[f64; LANES],
    y: &[f64; LANES],
    z: &[f64; LANES],
    out: &mut [f64; LANES],
) {
    const SMALL: f64 = (1u32 << 30) as f64;
    let small = x
        .iter()
        .chain(y)
        .chain(z)
        .fold(true, |ok, v| ok & (v.abs() < SMALL));
    if small {
        perlin_lanes_small(perm32, x, y, z, out);
    } else {
        perlin_lanes_wide(perm, x, y, z, out);
    }
}

/// [`perlin_lanes`] for coordinates below `2^30` in magnitude: every step is a loop over the
/// lanes without branches (table look-ups are gathers), which vectorises.
#[inline(always)]
fn perlin_lanes_small(
    perm: &[u32; 256],
    x: &[f64; LANES],
    y: &[f64; LANES],
    z: &[f64; LANES],
    out: &mut [f64; LANES],
) {
    let mut c = [[0i32; LANES]; 3];
    let mut d = [[0.0f64; LANES]; 3];
    for (axis, v) in [x, y, z].into_iter().enumerate() {
        for i in 0..LANES {
            let t = v[i] as i32;
            let ci = if v[i] <= 0.0 { t - 1 } else { t };
            c[axis][i] = ci;
            d[axis][i] = v[i] - f64::from(ci);
        }
    }
    let wrap = |v: i32| (v & 0xff) as usize;
    let mut a = [[0u32; LANES]; 2];
    for (o, ao) in a.iter_mut().enumerate() {
        for i in 0..LANES {
            ao[i] = perm[wrap(c[0][i] + o as i32)];
        }
    }
    let mut b = [[0u32; LANES]; 4];
    for (k, bk) in b.iter_mut().enumerate() {
        for i in 0..LANES {
            bk[i] = perm[(a[k >> 1][i] as usize & 0xff) ^ wrap(c[1][i] + (k & 1) as i32)];
        }
    }
    let mut g = [[0.0f64; LANES]; 8];
    for (k, gk) in g.iter_mut().enumerate() {
        let (ox, oy, oz) = ((k >> 2) as f64, ((k >> 1) & 1) as f64, (k & 1) as f64);
        for i in 0..LANES {
            // (Table entries are below 256; the masks only tell the compiler.)
            let h = perm[(b[k >> 1][i] as usize & 0xff) ^ wrap(c[2][i] + (k & 1) as i32)] & 15;
            gk[i] = gradient(h, d[0][i] - ox, d[1][i] - oy, d[2][i] - oz);
        }
    }
    blend(&d, &g, out);
}

/// The gradient term of `perlin_3d` for hash `h` (`h & 15`) at offset `(qx, qy, qz)`:
/// `(+-u) + (+-v)`, the terms and signs picked by the bit masks of `GRADIENTS` (branch-free, so
/// lane loops vectorise); a sign is applied by flipping the sign bit, which is exactly `-u`.
#[inline(always)]
fn gradient(h: u32, qx: f64, qy: f64, qz: f64) -> f64 {
    let u = if (U_IS_Y >> h) & 1 != 0 { qy } else { qx };
    let v = if (V_IS_Z >> h) & 1 != 0 { qz } else { qy };
    let su = u64::from((U_NEG >> h) & 1) << 63;
    let sv = u64::from((V_NEG >> h) & 1) << 63;
    f64::from_bits(u.to_bits() ^ su) + f64::from_bits(v.to_bits() ^ sv)
}

/// The fade-weighted trilinear blend of the 8 corner gradients `g` at distances `d`, scaled and
/// clamped as `perlin_3d` does.
#[inline(always)]
fn blend(d: &[[f64; LANES]; 3], g: &[[f64; LANES]; 8], out: &mut [f64; LANES]) {
    for i in 0..LANES {
        let (cx, cy, cz) = (quintic(d[0][i]), quintic(d[1][i]), quintic(d[2][i]));
        let r = lerp(
            lerp(lerp(g[0][i], g[1][i], cz), lerp(g[2][i], g[3][i], cz), cy),
            lerp(lerp(g[4][i], g[5][i], cz), lerp(g[6][i], g[7][i], cz), cy),
            cx,
        ) * SCALE_3D;
        out[i] = r.clamp(-1.0, 1.0);
    }
}

/// [`perlin_lanes`] with `isize` corners, for any coordinates.
#[inline(always)]
fn perlin_lanes_wide(
    perm: &[u8; 256],
    x: &[f64; LANES],
    y: &[f64; LANES],
    z: &[f64; LANES],
    out: &mut [f64; LANES],
) {
    // Hashes of the 8 corners (scalar look-ups), lane by lane.
    let mut hashes = [[0u8; LANES]; 8];
    let (mut dx, mut dy, mut dz) = ([0.0; LANES], [0.0; LANES], [0.0; LANES]);
    for i in 0..LANES {
        let (cx, fx) = corner(x[i]);
        let (cy, fy) = corner(y[i]);
        let (cz, fz) = corner(z[i]);
        dx[i] = fx;
        dy[i] = fy;
        dz[i] = fz;
        let xs = [(cx & 0xff) as usize, ((cx + 1) & 0xff) as usize];
        let ys = [(cy & 0xff) as usize, ((cy + 1) & 0xff) as usize];
        let zs = [(cz & 0xff) as usize, ((cz + 1) & 0xff) as usize];
        for (ox, &xi) in xs.iter().enumerate() {
            let a = perm[xi] as usize;
            for (oy, &yi) in ys.iter().enumerate() {
                let b = perm[a ^ yi] as usize;
                for (oz, &zi) in zs.iter().enumerate() {
                    hashes[ox * 4 + oy * 2 + oz][i] = perm[b ^ zi] & 15;
                }
            }
        }
    }
    // Gradients at the 8 corners (see `gradient`).
    let mut g = [[0.0f64; LANES]; 8];
    for (k, gk) in g.iter_mut().enumerate() {
        let (ox, oy, oz) = ((k >> 2) as f64, ((k >> 1) & 1) as f64, (k & 1) as f64);
        for i in 0..LANES {
            gk[i] = gradient(u32::from(hashes[k][i]), dx[i] - ox, dy[i] - oy, dz[i] - oz);
        }
    }
    for i in 0..LANES {
        let (cx, cy, cz) = (quintic(dx[i]), quintic(dy[i]), quintic(dz[i]));
        let r = lerp(
            lerp(lerp(g[0][i], g[1][i], cz), lerp(g[2][i], g[3][i], cz), cy),
            lerp(lerp(g[4][i], g[5][i], cz), lerp(g[6][i], g[7][i], cz), cy),
            cx,
        ) * SCALE_3D;
        out[i] = r.clamp(-1.0, 1.0);
    }
}

/// Conservative interval arithmetic on the same formula, for [`crate::ScalarField::range`].
impl BatchFbm {
    /// An interval containing every value `get` returns for points in the box `[lo, hi]` (given
    /// in the coordinates passed to `get`, before the frequency).
    ///
    /// Proof, per octave (the octave's box is the input box scaled by its frequency, widened by
    /// `1e-12` relative and absolute for the rounding of `x * frequency * lacunarity^k`):
    /// - split the box along the integer planes into closed unit cells `[c, c + 1]`; in a cell
    ///   the noise is the formula of `perlin_3d` with the cell's 8 corner hashes (the corner rule
    ///   of `noise` picks one of the closed cells containing the point, so the union over cells
    ///   covers it), and the distance `d = p - c` ranges over a sub-box of `[0, 1]^3`;
    /// - each corner's gradient term `+-u +- v` uses two different axes of `d - offset`, so its
    ///   range is exact: the sum of the two axis ranges;
    /// - the fade curve is increasing on `[0, 1]`, so its range is `[q(d0), q(d1)]`;
    /// - `lerp(a, b, t) = b t + a (1 - t)` with `t` in `[0, 1]` is increasing in `a` and `b`
    ///   and linear in `t`, so over independent intervals its least value is the smaller of
    ///   `b0 t + a0 (1 - t)` at `t0` and `t1`, its greatest likewise with `a1, b1`: true bounds
    ///   (the inputs are in fact dependent, which only makes the true range smaller);
    /// - the scale by `2 / sqrt 3` and the clamp to `[-1, 1]` are monotone.
    ///
    /// The octaves are then summed with their weights and scaled, as `get` does. The `f64`
    /// evaluation of `get` itself differs from the exact formula by a few units of `2^-53`; the
    /// result is widened by `1e-9`, and intersected with the global bound `[-1, 1]` (see
    /// `asteroid::fbm_bound`; widened by `2^-52`). Boxes that cover more than 8 cells in an
    /// octave take that octave's whole range `[-1, 1]`.
    pub fn range(&self, lo: [f64; 3], hi: [f64; 3]) -> (f64, f64) {
        self.range_until(lo, hi, |_, _| false)
    }

    /// [`BatchFbm::range`] built octave by octave, lowest frequency first, asking `enough`
    /// after each step whether the interval so far suffices (then it is returned at once).
    /// Before the first octave and after each one, the octaves not yet bounded are each within
    /// `[-1, 1]` (`perlin_3d` clamps), so the running sum widened by their attenuations (summed
    /// with a relative slack of `1e-12`) and scaled, widened and clipped as in `range`, is an
    /// interval of the same kind: every interval passed to `enough` contains every value `get`
    /// returns in the box, and so does the one returned.
    pub fn range_until(
        &self,
        lo: [f64; 3],
        hi: [f64; 3],
        mut enough: impl FnMut(f64, f64) -> bool,
    ) -> (f64, f64) {
        let full = (-1.0 - 1e-15, 1.0 + 1e-15);
        if !(lo.iter().chain(&hi).all(|v| v.is_finite())) {
            return full;
        }
        let (atts, rest) = (&self.atts, &self.rest);
        let bound = |total_lo: f64, total_hi: f64, k: usize| {
            let r = rest[k] * (1.0 + 1e-12);
            let (a, b) = (
                (total_lo - r) * self.scale - 1e-9,
                (total_hi + r) * self.scale + 1e-9,
            );
            (a.max(full.0), b.min(full.1))
        };
        let (mut total_lo, mut total_hi) = (0.0, 0.0);
        let (a, b) = bound(0.0, 0.0, 0);
        if enough(a, b) {
            return (a, b);
        }
        let mut scale = self.frequency;
        for (k, (perm, &attenuation)) in self.perms.iter().zip(atts).enumerate() {
            let widen = |v: f64, s: f64| v * scale + s * (1e-12 * (v * scale).abs() + 1e-12);
            let b0: [f64; 3] = std::array::from_fn(|a| {
                widen(lo[a].min(hi[a]), -1.0).min(widen(lo[a].max(hi[a]), -1.0))
            });
            let b1: [f64; 3] = std::array::from_fn(|a| {
                widen(lo[a].min(hi[a]), 1.0).max(widen(lo[a].max(hi[a]), 1.0))
            });
            let (olo, ohi) = octave_range(perm, b0, b1);
            total_lo += olo * attenuation;
            total_hi += ohi * attenuation;
            scale *= self.lacunarity;
            let (a, b) = bound(total_lo, total_hi, k + 1);
            if k + 1 == atts.len() || enough(a, b) {
                return (a, b);
            }
        }
        full
    }
}

/// Range of `perlin_3d` over the box `[lo, hi]` (noise coordinates), by cells.
fn octave_range(perm: &[u8; 256], lo: [f64; 3], hi: [f64; 3]) -> (f64, f64) {
    let cells: [(i64, i64); 3] =
        std::array::from_fn(|a| (lo[a].floor() as i64, hi[a].floor() as i64));
    let count: i64 = cells.iter().map(|(c0, c1)| c1 - c0 + 1).product();
    if count > 8 || count <= 0 {
        return (-1.0, 1.0);
    }
    let (mut rlo, mut rhi) = (f64::INFINITY, f64::NEG_INFINITY);
    for cx in cells[0].0..=cells[0].1 {
        for cy in cells[1].0..=cells[1].1 {
            for cz in cells[2].0..=cells[2].1 {
                let c = [cx, cy, cz];
                // The box's part in this cell, as distances from its corner.
                let d0: [f64; 3] = std::array::from_fn(|a| (lo[a] - c[a] as f64).clamp(0.0, 1.0));
                let d1: [f64; 3] = std::array::from_fn(|a| (hi[a] - c[a] as f64).clamp(0.0, 1.0));
                let (a, b) = cell_range(perm, c, d0, d1);
                rlo = rlo.min(a);
                rhi = rhi.max(b);
            }
        }
    }
    (rlo, rhi)
}

/// Range of `perlin_3d` in cell `c` for distances in `[d0, d1]`.
fn cell_range(perm: &[u8; 256], c: [i64; 3], d0: [f64; 3], d1: [f64; 3]) -> (f64, f64) {
    let wrap = |v: i64| (v & 0xff) as usize;
    let mut g = [(0.0f64, 0.0f64); 8];
    for (k, gk) in g.iter_mut().enumerate() {
        let o = [(k >> 2) as i64, ((k >> 1) & 1) as i64, (k & 1) as i64];
        let h = perm[perm[perm[wrap(c[0] + o[0])] as usize ^ wrap(c[1] + o[1])] as usize
            ^ wrap(c[2] + o[2])]
            & 15;
        let (u_is_y, su, v_is_z, sv) = GRADIENTS[h as usize];
        // Ranges of the offset point's components.
        let q = |a: usize| (d0[a] - o[a] as f64, d1[a] - o[a] as f64);
        let (u, v) = (q(usize::from(u_is_y)), q(if v_is_z { 2 } else { 1 }));
        let signed = |(a, b): (f64, f64), s: f64| if s > 0.0 { (a, b) } else { (-b, -a) };
        let (u, v) = (signed(u, su), signed(v, sv));
        *gk = (u.0 + v.0, u.1 + v.1);
    }
    let t: [(f64, f64); 3] = std::array::from_fn(|a| (quintic(d0[a]), quintic(d1[a])));
    let lerp_range = |a: (f64, f64), b: (f64, f64), t: (f64, f64)| {
        let low = |t: f64| b.0 * t + a.0 * (1.0 - t);
        let high = |t: f64| b.1 * t + a.1 * (1.0 - t);
        (low(t.0).min(low(t.1)), high(t.0).max(high(t.1)))
    };
    let r = lerp_range(
        lerp_range(
            lerp_range(g[0], g[1], t[2]),
            lerp_range(g[2], g[3], t[2]),
            t[1],
        ),
        lerp_range(
            lerp_range(g[4], g[5], t[2]),
            lerp_range(g[6], g[7], t[2]),
            t[1],
        ),
        t[0],
    );
    (
        (r.0 * SCALE_3D).clamp(-1.0, 1.0),
        (r.1 * SCALE_3D).clamp(-1.0, 1.0),
    )
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use noise::NoiseFn;

    /// `n` pseudo-random points (xorshift) in `[lo, hi)^3` (also used by `fast_fbm`'s tests).
    pub(crate) fn points(n: usize, seed: u64, lo: f64, hi: f64) -> Vec<[f64; 3]> {
        let mut s = seed | 1;
        let mut next = || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            lo + (hi - lo) * ((s >> 11) as f64 / (1u64 << 53) as f64)
        };
        (0..n).map(|_| [next(), next(), next()]).collect()
    }

    #[test]
    fn gradient_masks_match_the_table() {
        for (h, &(u_is_y, su, v_is_z, sv)) in GRADIENTS.iter().enumerate() {
            assert_eq!((U_IS_Y >> h) & 1 == 1, u_is_y, "{h}");
            assert_eq!((U_NEG >> h) & 1 == 1, su < 0.0, "{h}");
            assert_eq!((V_IS_Z >> h) & 1 == 1, v_is_z, "{h}");
            assert_eq!((V_NEG >> h) & 1 == 1, sv < 0.0, "{h}");
        }
    }

    #[test]
    fn batch_fbm_equals_the_noise_crate_bit_for_bit() {
        // 32 octaves reach coordinates beyond 2^30: the `isize` corner path.
        for (seed, octaves, frequency) in [
            (7, 4, 1.5),
            (5, 4, 1.2),
            (0, 1, 1.0),
            (99, 6, 2.7),
            (3, 32, 1.0),
        ] {
            let reference = Fbm::<Perlin>::new(seed)
                .set_octaves(octaves)
                .set_frequency(frequency);
            let ours = BatchFbm::new(seed, octaves, frequency);
            let mut pts = points(20_000, u64::from(seed) + 3, -3.0, 3.0);
            // Integers and half-integers, where the corner rule and zero signs matter.
            for i in -8..8 {
                for j in -8..8 {
                    let (a, b) = (i as f64 / 2.0, j as f64 / 3.0);
                    pts.push([a, b, a]);
                    pts.push([0.0, a, -0.0]);
                    pts.push([a / frequency, b / frequency, 0.0]);
                }
            }
            // f32 points, as the fields pass them.
            pts.extend(
                points(2000, 11, -1.0, 1.0)
                    .iter()
                    .map(|p| p.map(|c| f64::from(c as f32))),
            );
            // Runs of 8 neighbouring points, as extraction passes them (one batch each, the
            // batches aligned): every lane in one cell for the low octaves, runs across cell
            // boundaries for the others.
            assert_eq!(pts.len() % LANES, 0);
            for (k, base) in points(1000, 17, -2.0, 2.0).iter().enumerate() {
                let step = [1e-4, 1e-3, 0.02, 0.2][k % 4];
                pts.extend((0..LANES).map(|i| [base[0] + i as f64 * step, base[1], base[2]]));
            }
            for chunk in pts.chunks(LANES) {
                let mut lanes = [[0.0; 3]; LANES];
                lanes[..chunk.len()].copy_from_slice(chunk);
                let mut out = [0.0; LANES];
                ours.get_lanes(
                    &lanes.map(|p| p[0]),
                    &lanes.map(|p| p[1]),
                    &lanes.map(|p| p[2]),
                    &mut out,
                );
                let mut portable = [0.0; LANES];
                ours.get_lanes_portable(
                    &lanes.map(|p| p[0]),
                    &lanes.map(|p| p[1]),
                    &lanes.map(|p| p[2]),
                    &mut portable,
                );
                for ((p, o), q) in chunk.iter().zip(out).zip(portable) {
                    let r = reference.get(*p);
                    assert_eq!(o.to_bits(), r.to_bits(), "seed {seed} at {p:?}: {o} vs {r}");
                    assert_eq!(q.to_bits(), r.to_bits(), "portable, seed {seed} at {p:?}");
                }
            }
            assert_eq!(
                ours.get([0.3, -0.2, 0.9]).to_bits(),
                reference.get([0.3, -0.2, 0.9]).to_bits()
            );
            // 2D, as the height field uses it.
            for chunk in pts.chunks_exact(LANES) {
                let lane = |a: usize| -> [f64; LANES] { std::array::from_fn(|k| chunk[k][a]) };
                let mut out = [0.0; LANES];
                ours.get_lanes_2d(&lane(0), &lane(2), &mut out);
                for (p, o) in chunk.iter().zip(out) {
                    let r = NoiseFn::<f64, 2>::get(&reference, [p[0], p[2]]);
                    assert_eq!(
                        o.to_bits(),
                        r.to_bits(),
                        "2D seed {seed} at {p:?}: {o} vs {r}"
                    );
                }
            }
        }
    }
}
