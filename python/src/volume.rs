//! A numpy volume (and cube centres) for the extractor.
//!
//! The volume is indexed `volume[z, y, x]` (C order, x fastest), which is exactly the storage
//! of the simple lattice: it is read in place (`Extractor::extract_borrowed`), no copy, and
//! checked for finiteness by the extractor's first pass over it (which reads every value
//! anyway), not by a scan here. On the body-centred lattice, corner planes and
//! centre planes alternate in storage (see `rmt_extract::samples`), so the values are copied
//! into the extractor's sample array, the centres from `centres` of shape
//! `(nz + 2, ny + 2, nx + 2)`: the ghost layer included (index 0 and the last along an axis are
//! the centres of the cubes just outside the box, sampled on the box face; the Python wrapper
//! builds that array from `(nz, ny, nx)` centres and the user's `ghosts`), or of shape
//! `(nz, ny, nx)` without ghosts, for `rmt_extract::Boundary::Pyramids`. No ghost value is
//! ever made up here.

use rayon::prelude::*;
use rmt_extract::{samples::sampled_lattice, ExtractSettings, Lattice, Samples};

use crate::errors::Error;

/// A checked-for-shape volume, borrowed from numpy.
pub struct Input<'a> {
    /// `volume[z, y, x]`, C order.
    pub values: &'a [f32],
    /// The volume's shape, array order `(z, y, x)`.
    pub shape: [usize; 3],
    /// The centres and their shape, array order.
    pub centres: Option<(&'a [f32], [usize; 3])>,
}

/// The C-order index (`[i, j, k]`) of flat position `at` in an array of `shape`.
fn index_of(at: usize, shape: [usize; 3]) -> [usize; 3] {
    [
        at / (shape[1] * shape[2]),
        (at / shape[2]) % shape[1],
        at % shape[2],
    ]
}

/// Values per task of the parallel check.
const CHUNK: usize = 1 << 16;

/// Volumes with fewer values than this (about 160^3) are checked on the calling thread: the
/// scan runs at memory speed (a 64^3 volume, 275k values, in 20-40 us), and handing it to the
/// worker pool and back costs a wake-up of each, which on a busy machine is more than the
/// second core saves on all but large volumes.
const PARALLEL_MIN: usize = 1 << 22;

/// Whether `v` holds a non-finite value. Branch-free and vectorisable: `x - x` is 0 for a
/// finite `x` and NaN for infinities and NaN, and a sum that meets a NaN stays NaN; 32
/// independent sums let the compiler keep them in vector registers (float additions are not
/// reordered for it).
#[inline(always)]
fn has_non_finite_lanes(v: &[f32]) -> bool {
    const LANES: usize = 32;
    let mut acc = [0f32; LANES];
    let chunks = v.chunks_exact(LANES);
    let rest = chunks.remainder();
    for c in chunks {
        for (a, x) in acc.iter_mut().zip(c) {
            // Not 0: NaN for a non-finite x (the point of the scan).
            #[allow(clippy::eq_op)]
            {
                *a += x - x;
            }
        }
    }
    acc.iter().fold(false, |bad, a| bad | (*a != 0.0))
        | rest.iter().fold(false, |bad, x| bad | !x.is_finite())
}

/// [`has_non_finite_lanes`] compiled for AVX2 (twice the width of the baseline's SSE2).
///
/// # Safety
/// The CPU must have AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn has_non_finite_avx2(v: &[f32]) -> bool {
    has_non_finite_lanes(v)
}

/// Whether `v` holds a non-finite value (AVX2 where the CPU has it).
fn has_non_finite(v: &[f32]) -> bool {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU has AVX2 (checked just above).
        return unsafe { has_non_finite_avx2(v) };
    }
    has_non_finite_lanes(v)
}

/// The first non-finite value of `v`, if any: a vectorised scan first (on the calling thread,
/// or on `pool` for a large volume), and the search for the index only when it found one.
fn first_non_finite(v: &[f32], pool: &rayon::ThreadPool) -> Option<(usize, f32)> {
    let bad = if v.len() < PARALLEL_MIN {
        has_non_finite(v)
    } else {
        pool.install(|| v.par_chunks(CHUNK).any(has_non_finite))
    };
    if !bad {
        return None;
    }
    v.iter().position(|x| !x.is_finite()).map(|i| (i, v[i]))
}

/// The error for a non-finite value at `at` of array `name` of `shape`.
fn non_finite(name: &str, at: usize, value: f32, shape: [usize; 3]) -> Error {
    let [i, j, k] = index_of(at, shape);
    Error::Value(format!(
        "{name} is not finite at index [{i}, {j}, {k}] (z, y, x): got {value}; the first such \
         value in C order"
    ))
}

impl Input<'_> {
    /// Readies the volume (and centres) for `settings`: on the simple lattice (and for marching
    /// cubes and surface nets) the storage is the volume's own C order, so the values are read
    /// in place and checked by the extractor (returns `true`; see [`Input::library_error`]);
    /// on the body-centred lattice they are checked and copied into `samples` with the centres
    /// (returns `false`).
    pub fn check_or_fill(
        &self,
        settings: &ExtractSettings,
        samples: &mut Samples,
        pool: &rayon::ThreadPool,
    ) -> Result<bool, Error> {
        let lattice = sampled_lattice(settings);
        if self.values.len() != self.shape.iter().product::<usize>() {
            return Err(Error::Value("volume: data and shape disagree".into()));
        }
        match lattice {
            // Checked by the extractor's first pass, which reads every value anyway
            // (`ExtractError::NonFiniteValue`, turned into the same message by
            // [`Input::library_error`]): no scan of its own.
            Lattice::Simple => {
                if self.centres.is_some() {
                    return Err(Error::Value(
                        "centres are read only on the body-centred lattice (lattice='bcdl' \
                         with method='mt')"
                            .into(),
                    ));
                }
                Ok(true)
            }
            Lattice::BodyCentred => {
                if let Some((i, v)) = first_non_finite(self.values, pool) {
                    return Err(non_finite("volume", i, v, self.shape));
                }
                self.fill_bcdl(settings, samples).map(|()| false)
            }
        }
    }

    /// The extractor's error for this volume: a non-finite value (found by the extractor's
    /// first pass on the simple lattice, where slots are the volume's C order) named by its
    /// index as [`first_non_finite`]'s is; any other with the library's message.
    pub fn library_error(&self, e: rmt_extract::ExtractError) -> Error {
        match e {
            rmt_extract::ExtractError::NonFiniteValue { slot, value, .. }
                if slot < self.values.len() =>
            {
                non_finite("volume", slot, value, self.shape)
            }
            other => Error::Library(other.to_string()),
        }
    }

    /// The corners into the body-centred sample array: storage plane 2 z + 1, slots (x, y).
    fn fill_corners(&self, samples: &mut Samples, slot: impl Fn(usize, usize, usize) -> usize) {
        let [nz1, ny1, nx1] = self.shape;
        for z in 0..nz1 {
            for y in 0..ny1 {
                let src = (z * ny1 + y) * nx1;
                let at = slot(2 * z + 1, y, 0);
                samples.values[at..at + nx1].copy_from_slice(&self.values[src..src + nx1]);
            }
        }
    }

    fn fill_bcdl(&self, settings: &ExtractSettings, samples: &mut Samples) -> Result<(), Error> {
        let [nz1, ny1, nx1] = self.shape;
        let (nx, ny, nz) = (nx1 - 1, ny1 - 1, nz1 - 1);
        let Some((centres, cshape)) = self.centres else {
            return Err(Error::Value(format!(
                "lattice='bcdl' needs the values at the cube centres too: pass centres= (an array \
                 of shape {:?}, the volume's shape minus 1; or {:?}, with the ghost layer; or a \
                 callable), or use extract_field with a callable; they are not guessed by \
                 interpolation",
                [nz, ny, nx],
                [nz + 2, ny + 2, nx + 2]
            )));
        };
        let ghosts = [nz + 2, ny + 2, nx + 2];
        let inner = [nz, ny, nx];
        if cshape != ghosts && cshape != inner {
            return Err(Error::Value(format!(
                "centres must have shape {ghosts:?} (the cube centres with the ghost layer) or \
                 {inner:?} (without it: the box faces are closed by pyramids), got {cshape:?}"
            )));
        }
        if centres.len() != cshape.iter().product::<usize>() {
            return Err(Error::Value("centres: data and shape disagree".into()));
        }
        samples.prepare(settings);
        samples.values.fill(f32::NAN);
        let [dx, dy, _] = samples.dims;
        let slot = |plane: usize, sy: usize, sx: usize| (plane * dy + sy) * dx + sx;
        if cshape == inner {
            // No ghost: centre [k, j, i] is storage plane 2 k + 2, slot (i + 1, j + 1); the
            // ghosts' slots stay NaN and are never read (`Boundary::Pyramids`).
            self.fill_corners(samples, slot);
            for k in 0..nz {
                for j in 0..ny {
                    let src = (k * ny + j) * nx;
                    let row = &centres[src..src + nx];
                    if let Some(i) = row.iter().position(|v| !v.is_finite()) {
                        return Err(non_finite("centres", src + i, row[i], cshape));
                    }
                    let at = slot(2 * k + 2, j + 1, 1);
                    samples.values[at..at + nx].copy_from_slice(row);
                }
            }
            return Ok(());
        }
        self.fill_corners(samples, slot);
        // Centre plane p (cube k = p - 1) is storage plane 2 p, slot (i + 1, j + 1): the
        // array's layout exactly. Only the points that exist are copied and checked (the
        // centres of cubes outside two or three faces are never read).
        for p in 0..nz + 2 {
            for sy in 0..ny + 2 {
                for sx in 0..nx + 2 {
                    let outside = usize::from(p == 0 || p == nz + 1)
                        + usize::from(sy == 0 || sy == ny + 1)
                        + usize::from(sx == 0 || sx == nx + 1);
                    if outside > 1 {
                        continue;
                    }
                    let at = (p * (ny + 2) + sy) * (nx + 2) + sx;
                    let value = centres[at];
                    if !value.is_finite() {
                        return Err(non_finite("centres", at, value, cshape));
                    }
                    samples.values[slot(2 * p, sy, sx)] = value;
                }
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn index_of_is_c_order() {
        let shape = [3, 4, 5];
        assert_eq!(index_of(0, shape), [0, 0, 0]);
        assert_eq!(index_of(5 * 4 * 2 + 5 * 3 + 4, shape), [2, 3, 4]);
    }

    #[test]
    fn first_non_finite_finds_the_first() {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(2)
            .build()
            .unwrap();
        // On this thread, and on the pool (the bad values in different chunks).
        for n in [10_000, PARALLEL_MIN + 1000] {
            let mut v = vec![0.0f32; n];
            assert_eq!(first_non_finite(&v, &pool), None);
            v[n / 2] = f32::INFINITY;
            v[n - 1000] = f32::NAN;
            assert_eq!(first_non_finite(&v, &pool), Some((n / 2, f32::INFINITY)));
        }
    }

    #[test]
    fn every_position_and_kind_is_seen() {
        // Every position of a length that leaves a remainder after the 32 lanes, in both the
        // dispatched and the baseline kernel; large finite values (whose x - x is 0) are not
        // flagged.
        let bad = [f32::NAN, f32::INFINITY, f32::NEG_INFINITY, -f32::NAN];
        let mut v: Vec<f32> = (0..103).map(|i| (i as f32 - 50.0) * 1e36).collect();
        v[7] = f32::MAX;
        v[8] = f32::MIN;
        v[9] = f32::MIN_POSITIVE / 4.0;
        assert!(!has_non_finite(&v) && !has_non_finite_lanes(&v));
        for at in 0..v.len() {
            for b in bad {
                let keep = v[at];
                v[at] = b;
                assert!(has_non_finite(&v), "{b} at {at}");
                assert!(has_non_finite_lanes(&v), "{b} at {at}");
                v[at] = keep;
            }
        }
        assert!(!has_non_finite(&[]));
    }
}
