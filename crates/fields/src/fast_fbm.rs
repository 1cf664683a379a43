//! `Fbm<Perlin>` of the `noise` crate (version 0.9) with its arithmetic in `f32` and its work
//! shared along rows of points: the same object as [`crate::fbm::BatchFbm`] to within
//! [`TOLERANCE`], several times faster on the rows of points that extraction samples.
//!
//! What stays exact, so that the noise is the same function: the octave coordinates
//! (`p * frequency * lacunarity^k`, in `f64`, in the crate's order), the Perlin cell of each
//! coordinate (the crate's corner rule), the offset `d` from the cell's corner (`f64`), the
//! permutation tables and the hash `P[P[P[x] ^ y] ^ z]`, hence the gradient picked at every
//! corner. What is `f32`: the offset once it is known (`d` in `[0, 1]`, rounded once), the
//! gradient terms, the quintic fade, the blend and the weighted octave sum.
//!
//! # Rows
//!
//! A lattice samples rows: points with the same `y` and `z` and increasing `x`. In one octave,
//! for a fixed `(y, z)` and a fixed cell `c` along `x`, every corner gradient is
//! `g = a * qx + r` with `a` in `{-1, 0, 1}` and `r` not depending on `x` (the crate's gradients
//! `+-u +- v` never use `x` twice), and the fade-weighted blend over `y` and `z` is linear. So the
//! two `x` faces of the cell reduce to `L0(qx) = A0 qx + B0` and `L1(qx) = A1 qx + B1`, with
//! `A_o = blend_yz(a)` and `B_o = blend_yz(r)` computed once per cell, and the noise is
//! `S * lerp(L0(d), L1(d - 1), fade(d))`: the crate's formula with the blend distributed over
//! `a * qx + r` (equal in real arithmetic). A row pays the hashing and the `y`-`z` blend once per
//! cell it crosses, and about fifteen `f32` operations per point, over [`LANES`] points at a time.
//!
//! **Every point is evaluated this way**, whatever its neighbours in a batch: a point's value
//! depends on the point alone (its own `y`, `z`, cell and offset), so a single sample, a batch
//! and a row give the same bits, and so do the portable build and the AVX2 build of the same code
//! (the same IEEE operations in the same order; Rust never fuses multiply-adds).
//!
//! # Why [`TOLERANCE`] holds
//!
//! Per octave, with the gradients fixed by the exact cell, the crate's value is
//! `S * blend(fade(d), g(d))` for `d` in `[0, 1]^3`; ours evaluates the same function at
//! `d' = fl32(d)` in `f32`. An error budget (unit roundoff `u = 2^-24`):
//! - `|d' - d| <= u / 2` per axis. Each gradient has partial derivatives of magnitude at most
//!   1 and value at most 2; the fade's derivative is at most `30/16`, so the blend moves by at
//!   most `1 + 1.875 * 4 = 8.5` per unit of `d` along an axis: at most `3 * 8.5 * u / 2 < 7.6e-7`.
//! - `d' - 1`: exact or off by `u / 2`; a gradient term `r` (at most 2): off by `u`.
//! - The fade of `x` in `[0, 1]`: six roundings of values at most 10, a relative error below
//!   `7u`, so each weight is off by less than `4.2e-7`; a weight multiplies a difference of at
//!   most 4, on three levels: `< 5.1e-6`.
//! - The blends (`A`, `B`: values at most 1 and 2), `A qx + B` (at most 3) and the final
//!   interpolation round about 20 times along the deepest chain on values at most 4:
//!   `< 20 * 4 * u < 4.8e-6`.
//! - Times `S = 2 / sqrt(3)` (one more rounding): `(0.76 + 0.2 + 5.1 + 4.8) * 1.155 + 0.1`, under
//!   `1.27e-5` per octave in the worst case; the clamp to `[-1, 1]` only brings values closer.
//!
//! The octaves are summed with weights `w_k = att_k * scale` (rounded to `f32`) that sum to 1, so
//! the weighted errors keep that bound, and the roundings of the sum and of the weights add
//! under `2 K u`, at most `1e-6` for 8 octaves: [`TOLERANCE`] is `2e-5`, above the budget. The
//! worst cases of the terms do not meet at one point, and the unit tests measure the largest
//! difference over about 480,000 random and grid points at 1 to 8 octaves (up to `2.4e-6`) and
//! check it against [`TOLERANCE`]; callers that bound values (the asteroid's and the caves'
//! ranges) widen by it. Octave coordinates beyond `2^30` take the exact `f64` kernel of
//! `BatchFbm`, and only its result is rounded to `f32`.

use crate::fbm::{
    has_avx2, perlin_lanes, permutation, LANES, SCALE_3D, U_IS_Y, U_NEG, V_IS_Z, V_NEG,
};
use noise::{Fbm, MultiFractal, Perlin};

/// The largest difference from `noise::Fbm::<Perlin>`, for 1 to 8 octaves (see the
/// [module documentation](self)).
pub const TOLERANCE: f64 = 2e-5;

/// Octave coordinates of at most this magnitude take the `f32` kernel (their corners fit an
/// `i32`); the others the exact `f64` one.
const SMALL: f64 = (1u32 << 30) as f64;

/// `f32` `2 / sqrt(3)`.
const SCALE: f32 = SCALE_3D as f32;

/// `Fbm::<Perlin>` (3D) in `f32`, evaluated along rows (see the [module documentation](self)).
#[derive(Clone, Debug)]
pub struct FastFbm {
    /// Per octave: the permutation table, as bytes and as `u32` (the exact kernel takes both).
    perms8: Vec<[u8; 256]>,
    perms32: Vec<[u32; 256]>,
    frequency: f64,
    lacunarity: f64,
    /// Per octave: `persistence^(k+1) * scale`, the crate's attenuation and final scale.
    weights: Vec<f32>,
    avx2: bool,
}

impl FastFbm {
    /// The `f32` twin of
    /// `Fbm::<Perlin>::new(seed).set_octaves(octaves).set_frequency(frequency)` (`octaves`
    /// clamped to 1..=32 as the crate does; [`TOLERANCE`] is established for up to 8).
    pub fn new(seed: u32, octaves: usize, frequency: f64) -> Self {
        let reference = Fbm::<Perlin>::new(seed)
            .set_octaves(octaves)
            .set_frequency(frequency);
        let octaves = reference.octaves;
        let persistence = reference.persistence;
        // As `Fbm::calc_scale_factor`, then the attenuation of each octave.
        let denom = (1..=octaves).fold(0.0, |acc: f64, x| acc + persistence.powi(x as i32));
        let scale = 1.0 / denom;
        let mut attenuation = persistence;
        let weights = (0..octaves)
            .map(|_| {
                let w = (attenuation * scale) as f32;
                attenuation *= persistence;
                w
            })
            .collect();
        let perms8: Vec<[u8; 256]> = (0..octaves)
            .map(|k| permutation(seed.wrapping_add(k as u32)))
            .collect();
        Self {
            perms32: perms8.iter().map(|p| p.map(u32::from)).collect(),
            perms8,
            frequency: reference.frequency,
            lacunarity: reference.lacunarity,
            weights,
            avx2: has_avx2(),
        }
    }

    /// The noise at one point.
    pub fn get(&self, p: [f64; 3]) -> f32 {
        let mut out = [0.0];
        self.get_row(&[p[0]], p[1], p[2], &mut out);
        out[0]
    }

    /// The noise at the points `(xs[i], y, z)`, into `out[i]` (`out` as long as `xs`).
    #[inline]
    pub fn get_row(&self, xs: &[f64], y: f64, z: f64, out: &mut [f32]) {
        #[cfg(target_arch = "x86_64")]
        if self.avx2 {
            // SAFETY: `avx2` is set only when the CPU has AVX2 (checked at construction).
            unsafe { self.get_row_avx2(xs, y, z, out) };
            return;
        }
        self.get_row_portable(xs, y, z, out);
    }

    /// The noise at the points `(x[i], y[i], z[i])`: each run of points with equal `y` and `z`
    /// is one row (the values do not depend on how the points are grouped).
    pub fn get_points(&self, x: &[f64], y: &[f64], z: &[f64], out: &mut [f32]) {
        let n = x.len().min(y.len()).min(z.len()).min(out.len());
        let mut start = 0;
        while start < n {
            let (y0, z0) = (y[start], z[start]);
            let mut end = start + 1;
            while end < n && y[end].to_bits() == y0.to_bits() && z[end].to_bits() == z0.to_bits() {
                end += 1;
            }
            self.get_row(&x[start..end], y0, z0, &mut out[start..end]);
            start = end;
        }
    }

    /// [`FastFbm::get_row`] built for the baseline instruction set (what CPUs without AVX2 run;
    /// tested against the AVX2 build on this CPU).
    pub fn get_row_portable(&self, xs: &[f64], y: f64, z: f64, out: &mut [f32]) {
        self.row(xs, y, z, out);
    }

    /// [`FastFbm::get_row`] built for AVX2: the same code, so the same bits.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn get_row_avx2(&self, xs: &[f64], y: f64, z: f64, out: &mut [f32]) {
        self.row(xs, y, z, out);
    }

    #[inline(always)]
    fn row(&self, xs: &[f64], y: f64, z: f64, out: &mut [f32]) {
        // The per-row tables sized to the octaves (a row of a few points, as sparse sampling
        // gives, would otherwise spend most of its time clearing tables for 32 octaves).
        match self.weights.len() {
            0..=4 => self.row_tables::<4>(xs, y, z, out),
            5..=8 => self.row_tables::<8>(xs, y, z, out),
            _ => self.row_tables::<32>(xs, y, z, out),
        }
    }

    /// [`FastFbm::row`] with tables for `K` octaves (at least the number of octaves).
    #[inline(always)]
    fn row_tables<const K: usize>(&self, xs: &[f64], y: f64, z: f64, out: &mut [f32]) {
        // What the row's octaves share: y and z, scaled as the crate scales them, and their
        // cells, offsets and fades.
        let mut octaves = [RowOctave::EMPTY; K];
        let (mut py, mut pz) = (y * self.frequency, z * self.frequency);
        for o in octaves.iter_mut().take(self.weights.len()) {
            let small = py.abs() < SMALL && pz.abs() < SMALL;
            *o = RowOctave {
                py,
                pz,
                small,
                part: if small {
                    RowPart::new(py, pz)
                } else {
                    RowPart::EMPTY
                },
            };
            py *= self.lacunarity;
            pz *= self.lacunarity;
        }
        let octaves = &octaves[..self.weights.len()];
        // Per octave, the last cell met along the row and its faces: consecutive chunks of a
        // row share a cell at their boundary.
        let mut cache = [(i32::MIN, [0.0f32; 4]); K];
        for (xc, oc) in xs.chunks(LANES).zip(out.chunks_mut(LANES)) {
            // A short chunk takes fewer lanes (each lane's value depends on its own point
            // alone, whatever the number of lanes): one for a single point, half of them for
            // at most half a chunk.
            match xc.len() {
                1 => self.chunk::<1>(xc, octaves, oc, &mut cache),
                n if n <= LANES / 2 => self.chunk::<{ LANES / 2 }>(xc, octaves, oc, &mut cache),
                _ => self.chunk::<LANES>(xc, octaves, oc, &mut cache),
            }
        }
    }

    /// All octaves at the (at most `N`) points `xc` of one row, into `out`; spare lanes repeat
    /// the last point.
    #[inline(always)]
    fn chunk<const N: usize>(
        &self,
        xc: &[f64],
        octaves: &[RowOctave],
        out: &mut [f32],
        cache: &mut [(i32, [f32; 4])],
    ) {
        let last = xc[xc.len() - 1];
        let x: [f64; N] = std::array::from_fn(|i| xc.get(i).copied().unwrap_or(last));
        let mut v = [0.0f32; N];
        self.lanes(&x, octaves, &mut v, cache);
        out.copy_from_slice(&v[..out.len()]);
    }

    /// All octaves at `N` points of one row.
    #[inline(always)]
    fn lanes<const N: usize>(
        &self,
        x: &[f64; N],
        octaves: &[RowOctave],
        out: &mut [f32; N],
        cache: &mut [(i32, [f32; 4])],
    ) {
        let mut px = x.map(|v| v * self.frequency);
        let mut result = [0.0f32; N];
        let mut signal = [0.0f32; N];
        for (k, (&w, o)) in self.weights.iter().zip(octaves).enumerate() {
            let near = |v: f64| o.small && v.abs() < SMALL;
            if px.iter().all(|&v| near(v)) {
                octave_row(&self.perms8[k], &px, &o.part, &mut signal, &mut cache[k]);
            } else {
                // Some lane far out (or not finite): each point takes its own kernel, so its
                // value never depends on the other points of its chunk.
                for i in 0..N {
                    if near(px[i]) {
                        // The lanes are independent: this lane's value, alone.
                        let mut one = [0.0f32; N];
                        octave_row(
                            &self.perms8[k],
                            &[px[i]; N],
                            &o.part,
                            &mut one,
                            &mut cache[k],
                        );
                        signal[i] = one[0];
                        continue;
                    }
                    let mut exact = [0.0f64; LANES];
                    perlin_lanes(
                        &self.perms8[k],
                        &self.perms32[k],
                        &[px[i]; LANES],
                        &[o.py; LANES],
                        &[o.pz; LANES],
                        &mut exact,
                    );
                    signal[i] = exact[0] as f32;
                }
            }
            for i in 0..N {
                result[i] += signal[i] * w;
            }
            for v in px.iter_mut() {
                *v *= self.lacunarity;
            }
        }
        *out = result;
    }
}

/// One octave of a row: its scaled `y` and `z`, whether they take the `f32` kernel, and what
/// that kernel shares along the row.
#[derive(Clone, Copy)]
struct RowOctave {
    py: f64,
    pz: f64,
    small: bool,
    part: RowPart,
}

impl RowOctave {
    const EMPTY: Self = Self {
        py: 0.0,
        pz: 0.0,
        small: false,
        part: RowPart::EMPTY,
    };
}

/// The crate's corner rule (`v as isize`, minus one for `v <= 0`) and the offset from it, for
/// `|v| < 2^30`.
#[inline(always)]
fn corner(v: f64) -> (i32, f32) {
    let t = v.trunc();
    let c = if v <= 0.0 { t - 1.0 } else { t };
    // SAFETY: callers pass `|v| < 2^30`, so `c` is an integer that fits an `i32`.
    (unsafe { c.to_int_unchecked::<i32>() }, (v - c) as f32)
}

/// One octave of Perlin noise at `N` points `(x[i], y, z)`, coordinates below `2^30`; `cache`
/// holds the last cell met in this row and octave, and its faces.
#[inline(always)]
fn octave_row<const N: usize>(
    perm: &[u8; 256],
    x: &[f64; N],
    row: &RowPart,
    out: &mut [f32; N],
    cache: &mut (i32, [f32; 4]),
) {
    // The points' x: cells and offsets.
    let mut cx = [0i32; N];
    let mut dx = [0.0f32; N];
    for i in 0..N {
        (cx[i], dx[i]) = corner(x[i]);
    }
    // Per cell met, the two x faces as `A qx + B`; copied to the lanes in that cell.
    // Rows run along x, so the cells of the lanes are usually a short range: visit it (skipping
    // cells no lane is in); otherwise visit the lanes' distinct cells one by one.
    let mut coef = [[0.0f32; N]; 4];
    let (lo, hi) = cx
        .iter()
        .fold((i32::MAX, i32::MIN), |(a, b), &c| (a.min(c), b.max(c)));
    if lo == hi {
        // Every lane in one cell (the usual case at low octaves).
        if cache.0 != lo {
            *cache = (lo, cell_faces(perm, lo, row));
        }
        coef = cache.1.map(|f| [f; N]);
    } else if hi - lo < N as i32 {
        for c in lo..=hi {
            visit(perm, row, &cx, c, &mut coef, cache);
        }
    } else {
        let mut done = [false; N];
        for i in 0..N {
            if !done[i] {
                visit(perm, row, &cx, cx[i], &mut coef, cache);
                for j in i..N {
                    done[j] |= cx[j] == cx[i];
                }
            }
        }
    }
    let [a0, b0, a1, b1] = coef;
    for i in 0..N {
        let l0 = a0[i] * dx[i] + b0[i];
        let l1 = a1[i] * (dx[i] - 1.0) + b1[i];
        let r = lerp(l0, l1, quintic(dx[i])) * SCALE;
        out[i] = r.clamp(-1.0, 1.0);
    }
}

/// What one octave of a row shares: the y and z cells (wrapped), offsets and fades.
#[derive(Clone, Copy)]
struct RowPart {
    yi: [usize; 2],
    zi: [usize; 2],
    qy: [f32; 2],
    qz: [f32; 2],
    fy: f32,
    fz: f32,
}

impl RowPart {
    const EMPTY: Self = Self {
        yi: [0; 2],
        zi: [0; 2],
        qy: [0.0; 2],
        qz: [0.0; 2],
        fy: 0.0,
        fz: 0.0,
    };

    /// The part of the row at octave coordinates `y`, `z` (below `2^30`).
    #[inline(always)]
    fn new(y: f64, z: f64) -> Self {
        let (cy, dy) = corner(y);
        let (cz, dz) = corner(z);
        Self {
            yi: [(cy & 0xff) as usize, ((cy + 1) & 0xff) as usize],
            zi: [(cz & 0xff) as usize, ((cz + 1) & 0xff) as usize],
            qy: [dy, dy - 1.0],
            qz: [dz, dz - 1.0],
            fy: quintic(dy),
            fz: quintic(dz),
        }
    }
}

/// Copies the faces of cell `c` (from `cache`, or computed into it) to the lanes in that cell.
#[inline(always)]
fn visit<const N: usize>(
    perm: &[u8; 256],
    row: &RowPart,
    cx: &[i32; N],
    c: i32,
    coef: &mut [[f32; N]; 4],
    cache: &mut (i32, [f32; 4]),
) {
    let mut any = false;
    for &ci in cx {
        any |= ci == c;
    }
    if !any {
        return;
    }
    if cache.0 != c {
        *cache = (c, cell_faces(perm, c, row));
    }
    let face = cache.1;
    for (k, ck) in coef.iter_mut().enumerate() {
        for i in 0..N {
            ck[i] = if cx[i] == c { face[k] } else { ck[i] };
        }
    }
}

/// `[A0, B0, A1, B1]` of cell `c` along x in the row described by `row` (see the module
/// documentation): each corner's gradient split into its x coefficient and the rest,
/// both blended over y and z with the fades `fy`, `fz`.
#[inline(always)]
fn cell_faces(perm: &[u8; 256], c: i32, row: &RowPart) -> [f32; 4] {
    let RowPart {
        yi,
        zi,
        qy,
        qz,
        fy,
        fz,
    } = *row;
    // The 8 corner hashes, corner k = 4 ox + 2 oy + oz.
    let mut h = [0u32; 8];
    for ox in 0..2 {
        let a = perm[((c + ox as i32) & 0xff) as usize] as usize;
        for oy in 0..2 {
            let b = perm[a ^ yi[oy]] as usize;
            for oz in 0..2 {
                h[4 * ox + 2 * oy + oz] = u32::from(perm[b ^ zi[oz]] & 15);
            }
        }
    }
    // The split gradients of all corners (table look-ups, no branches).
    let mut ax = [0.0f32; 8];
    let mut rest = [0.0f32; 8];
    for k in 0..8 {
        let g = &SPLIT[h[k] as usize];
        ax[k] = g[0];
        rest[k] = g[1] * qy[(k >> 1) & 1] + (g[2] * qy[(k >> 1) & 1] + g[3] * qz[k & 1]);
    }
    // Blend over z (corner pairs), then over y, for both faces.
    let lo: [f32; 8] = std::array::from_fn(|i| if i < 4 { ax[2 * i] } else { rest[2 * (i - 4)] });
    let hi: [f32; 8] = std::array::from_fn(|i| {
        if i < 4 {
            ax[2 * i + 1]
        } else {
            rest[2 * (i - 4) + 1]
        }
    });
    let mut zb = [0.0f32; 8];
    for i in 0..8 {
        zb[i] = lerp(lo[i], hi[i], fz);
    }
    // zb: [ax(ox0,oy0), ax(0,1), ax(1,0), ax(1,1), rest(0,0), rest(0,1), rest(1,0), rest(1,1)].
    [
        lerp(zb[0], zb[1], fy),
        lerp(zb[4], zb[5], fy),
        lerp(zb[2], zb[3], fy),
        lerp(zb[6], zb[7], fy),
    ]
}

/// The crate's gradient `(+-u) + (+-v)` for hash `h` as `a * qx + r`, per `h`:
/// `[a, cu, vy, vz]` with `r = cu * qy + (vy * qy + vz * qz)`: `a` is `+-1` when `u` is `x`
/// (else 0), `cu` is `+-1` when `u` is `y` (else 0), and `v` is `y` or `z` with its sign. The
/// products are exact (`+-q` or a zero) and adding a zero changes no non-zero value, so `r` is
/// the crate's `+-u +- v` when `u` is `y`, and `+-v` when `u` is `x` (up to the sign of a zero).
/// Derived from the bit masks of `fbm::GRADIENTS` (which a unit test there checks against the
/// crate's table); a test here checks it against `split_gradient`.
const SPLIT: [[f32; 4]; 16] = {
    let mut t = [[0.0f32; 4]; 16];
    let mut h = 0;
    while h < 16 {
        let (u_y, v_z) = ((U_IS_Y >> h) & 1 == 1, (V_IS_Z >> h) & 1 == 1);
        let su = if (U_NEG >> h) & 1 == 1 { -1.0f32 } else { 1.0 };
        let sv = if (V_NEG >> h) & 1 == 1 { -1.0f32 } else { 1.0 };
        t[h] = [
            if u_y { 0.0 } else { su },
            if u_y { su } else { 0.0 },
            if v_z { 0.0 } else { sv },
            if v_z { sv } else { 0.0 },
        ];
        h += 1;
    }
    t
};

/// The split of the crate's gradient for hash `h`, term by term (the reference for [`SPLIT`]).
#[cfg(test)]
fn split_gradient(h: u32, qx: f32, qy: f32, qz: f32) -> f32 {
    let u = if (U_IS_Y >> h) & 1 != 0 { qy } else { qx };
    let v = if (V_IS_Z >> h) & 1 != 0 { qz } else { qy };
    let u = if (U_NEG >> h) & 1 != 0 { -u } else { u };
    let v = if (V_NEG >> h) & 1 != 0 { -v } else { v };
    u + v
}

/// The quintic fade, in the crate's operation order.
#[inline(always)]
fn quintic(v: f32) -> f32 {
    let x = v.clamp(0.0, 1.0);
    x * x * x * (x * (x * 6.0 - 15.0) + 10.0)
}

/// The crate's `linear(a, b, alpha)`.
#[inline(always)]
fn lerp(a: f32, b: f32, alpha: f32) -> f32 {
    b * alpha + a * (1.0 - alpha)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fbm::tests::points;
    use noise::NoiseFn;

    /// Points of an `n^3` grid over `[lo, hi]^3` in row order, as `f32` coordinates.
    fn grid(n: usize, lo: f64, hi: f64) -> Vec<[f64; 3]> {
        let h = (hi - lo) / (n - 1) as f64;
        let c = |k: usize| f64::from((lo + k as f64 * h) as f32);
        (0..n * n * n)
            .map(|i| [c(i % n), c((i / n) % n), c(i / (n * n))])
            .collect()
    }

    /// Largest `|fast - noise crate|` over `pts` evaluated as batches (rows where `y` and `z`
    /// repeat); checks on the way that the portable build and single points give the same bits.
    fn compare(seed: u32, octaves: usize, frequency: f64, pts: &[[f64; 3]]) -> f64 {
        let reference = Fbm::<Perlin>::new(seed)
            .set_octaves(octaves)
            .set_frequency(frequency);
        let fast = FastFbm::new(seed, octaves, frequency);
        let axis = |a: usize| -> Vec<f64> { pts.iter().map(|p| p[a]).collect() };
        let (x, y, z) = (axis(0), axis(1), axis(2));
        let mut out = vec![0.0f32; pts.len()];
        fast.get_points(&x, &y, &z, &mut out);
        let mut worst = 0.0f64;
        for (i, p) in pts.iter().enumerate() {
            if i % 7 == 0 {
                assert_eq!(
                    out[i].to_bits(),
                    fast.get(*p).to_bits(),
                    "single point {p:?}"
                );
                let mut portable = [0.0f32];
                fast.get_row_portable(&[p[0]], p[1], p[2], &mut portable);
                assert_eq!(
                    out[i].to_bits(),
                    portable[0].to_bits(),
                    "portable build at {p:?}"
                );
            }
            worst = worst.max((f64::from(out[i]) - reference.get(*p)).abs());
        }
        worst
    }

    #[test]
    fn fast_fbm_is_within_the_tolerance_of_the_noise_crate() {
        for (seed, octaves, frequency) in [(7, 4, 1.5), (5, 4, 1.2), (0, 1, 1.0), (99, 8, 2.7)] {
            let mut pts = points(50_000, u64::from(seed) + 3, -3.0, 3.0);
            pts.extend(grid(41, -1.0, 1.0));
            for i in -8..8 {
                for j in -8..8 {
                    let (a, b) = (i as f64 / 2.0, j as f64 / 3.0);
                    pts.push([a, b, a]);
                    pts.push([0.0, a, -0.0]);
                    pts.push([a / frequency, b / frequency, 0.0]);
                }
            }
            let worst = compare(seed, octaves, frequency, &pts);
            println!("seed {seed}, {octaves} octaves: largest difference {worst:e}");
            assert!(
                worst < TOLERANCE,
                "seed {seed}, {octaves} octaves: off by {worst:e}"
            );
        }
    }

    #[test]
    fn one_octave_is_the_crates_perlin() {
        // The cave terrain's tunnels use one-octave noise as `Perlin` (weight 1 exactly).
        let fast = FastFbm::new(12, 1, 3.0);
        let perlin = Perlin::new(12);
        let worst = points(20_000, 5, -2.0, 2.0)
            .iter()
            .map(|p| (f64::from(fast.get(*p)) - perlin.get(p.map(|c| c * 3.0))).abs())
            .fold(0.0, f64::max);
        assert!(worst < TOLERANCE, "off by {worst:e}");
    }

    #[test]
    fn rows_of_any_length_give_each_point_its_own_value() {
        let fast = FastFbm::new(7, 4, 1.5);
        let xs: Vec<f64> = (0..37).map(|i| -1.0 + 0.057 * i as f64).collect();
        // Rows of one lane, of half the lanes and of full chunks, with every kind of tail, in
        // the AVX2 and the portable build.
        for len in [1, 2, 3, 4, 5, 8, 9, 12, 13, 37] {
            let mut out = vec![0.0f32; len];
            let mut portable = vec![0.0f32; len];
            fast.get_row(&xs[..len], 0.25, -0.4, &mut out);
            fast.get_row_portable(&xs[..len], 0.25, -0.4, &mut portable);
            for ((x, v), p) in xs.iter().zip(&out).zip(&portable) {
                let single = fast.get([*x, 0.25, -0.4]).to_bits();
                assert_eq!(v.to_bits(), single, "x {x}, {len}");
                assert_eq!(p.to_bits(), single, "x {x}, {len}, portable");
            }
        }
    }

    #[test]
    fn the_split_table_gives_the_crate_gradients() {
        let qs = [0.25f32, -0.75, 0.5, 1.0, -1.0, 0.125];
        for h in 0..16u32 {
            let g = SPLIT[h as usize];
            for &qx in &qs {
                for &qy in &qs {
                    for &qz in &qs {
                        let ours = g[0] * qx + (g[1] * qy + (g[2] * qy + g[3] * qz));
                        assert_eq!(ours, split_gradient(h, qx, qy, qz), "h {h}");
                    }
                }
            }
        }
    }

    #[test]
    fn a_far_point_does_not_change_its_neighbours_values() {
        // One chunk of lanes with near points and points whose octave coordinates pass 2^30
        // (from the third octave on here): each point's value is its own, in a row, in
        // `get_points` and alone, for the AVX2 and the portable build.
        let fast = FastFbm::new(5, 4, 1.5);
        let xs = [0.3, -0.7, 2.0e8, 0.45, 1.25, -3.0e8, 0.05, 0.9, 0.61];
        let (y, z) = (0.25, -0.4);
        let mut row = [0.0f32; 9];
        let mut portable = [0.0f32; 9];
        let mut points = [0.0f32; 9];
        fast.get_row(&xs, y, z, &mut row);
        fast.get_row_portable(&xs, y, z, &mut portable);
        fast.get_points(&xs, &[y; 9], &[z; 9], &mut points);
        for (i, &x) in xs.iter().enumerate() {
            let alone = fast.get([x, y, z]).to_bits();
            assert_eq!(row[i].to_bits(), alone, "row, x {x}");
            assert_eq!(portable[i].to_bits(), alone, "portable row, x {x}");
            assert_eq!(points[i].to_bits(), alone, "points, x {x}");
        }
    }

    #[test]
    fn far_points_take_the_exact_kernel() {
        // Octave coordinates beyond 2^30: the f64 kernel, rounded once.
        let worst = compare(3, 4, 1.0, &points(2_000, 9, 1e9, 3e9));
        assert!(worst < 1e-7, "off by {worst:e}");
    }

    #[test]
    fn a_wrong_gradient_is_caught() {
        // The comparison is sensitive: a one-octave noise with another seed is far off.
        let pts = points(1_000, 4, -2.0, 2.0);
        let reference = Fbm::<Perlin>::new(1).set_octaves(1);
        let other = FastFbm::new(2, 1, 1.0);
        let worst = pts
            .iter()
            .map(|&p| (f64::from(other.get(p)) - reference.get(p)).abs())
            .fold(0.0, f64::max);
        assert!(worst > 100.0 * TOLERANCE);
    }
}
