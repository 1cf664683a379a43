//! A numpy volume (and cube centres) into the extractor's sample array.
//!
//! The volume is indexed `volume[z, y, x]` (C order, x fastest), which is exactly the storage
//! of the simple lattice: it is copied once, with its finiteness checked in the same pass. On
//! the body-centred lattice, corner planes and centre planes alternate in storage (see
//! `rmt_extract::samples`); the centres come from `centres`, shape `(nz, ny, nx)` (the cube
//! centres) or `(nz + 2, ny + 2, nx + 2)` (with the ghost layer: index 0 and the last along an
//! axis are the centres of the cubes just outside the box, sampled on the box face).

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

/// Values per task of the parallel copy and check.
const CHUNK: usize = 1 << 15;

/// Whether `v` holds a non-finite value (a vectorisable scan).
fn has_non_finite(v: &[f32]) -> bool {
    v.iter().fold(false, |acc, x| acc | !x.is_finite())
}

/// The first non-finite value of `v`, if any (a parallel vectorisable scan first, on the
/// current rayon pool; the search only when there is one).
fn first_non_finite(v: &[f32]) -> Option<(usize, f32)> {
    if !v.par_chunks(CHUNK).any(has_non_finite) {
        return None;
    }
    v.iter().position(|x| !x.is_finite()).map(|i| (i, v[i]))
}

/// Copies `src` into `dst` (same length) in parallel; whether `src` holds a non-finite value.
fn copy_checked(dst: &mut [f32], src: &[f32]) -> bool {
    dst.par_chunks_mut(CHUNK)
        .zip(src.par_chunks(CHUNK))
        .map(|(d, s)| {
            d.copy_from_slice(s);
            has_non_finite(s)
        })
        .reduce(|| false, |a, b| a | b)
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
    /// Fills `samples` for `settings` from the volume (and centres).
    pub fn fill(&self, settings: &ExtractSettings, samples: &mut Samples) -> Result<(), Error> {
        let lattice = sampled_lattice(settings);
        if self.values.len() != self.shape.iter().product::<usize>() {
            return Err(Error::Value("volume: data and shape disagree".into()));
        }
        match lattice {
            Lattice::Simple => {
                if self.centres.is_some() {
                    return Err(Error::Value(
                        "centres are read only on the body-centred lattice (lattice='bcdl' \
                         with method='mt')"
                            .into(),
                    ));
                }
                samples.prepare(settings);
                if copy_checked(&mut samples.values, self.values) {
                    if let Some((i, v)) = first_non_finite(self.values) {
                        return Err(non_finite("volume", i, v, self.shape));
                    }
                }
                Ok(())
            }
            Lattice::BodyCentred => {
                if let Some((i, v)) = first_non_finite(self.values) {
                    return Err(non_finite("volume", i, v, self.shape));
                }
                self.fill_bcdl(settings, samples)
            }
        }
    }

    fn fill_bcdl(&self, settings: &ExtractSettings, samples: &mut Samples) -> Result<(), Error> {
        let [nz1, ny1, nx1] = self.shape;
        let (nx, ny, nz) = (nx1 - 1, ny1 - 1, nz1 - 1);
        let Some((centres, cshape)) = self.centres else {
            return Err(Error::Value(format!(
                "lattice='bcdl' needs the values at the cube centres too: pass centres= (an array \
                 of shape {:?}, the volume's shape minus 1), or use extract_field with a \
                 callable; they are not guessed by interpolation",
                [nz, ny, nx]
            )));
        };
        let interior = [nz, ny, nx];
        let ghosts = [nz + 2, ny + 2, nx + 2];
        if cshape != interior && cshape != ghosts {
            return Err(Error::Value(format!(
                "centres must have shape {interior:?} (the volume's shape minus 1: one value per \
                 cube) or {ghosts:?} (with the ghost layer), got {cshape:?}"
            )));
        }
        if centres.len() != cshape.iter().product::<usize>() {
            return Err(Error::Value("centres: data and shape disagree".into()));
        }
        samples.prepare(settings);
        samples.values.fill(f32::NAN);
        let [dx, dy, _] = samples.dims;
        let slot = |plane: usize, sy: usize, sx: usize| (plane * dy + sy) * dx + sx;
        let v = |z: usize, y: usize, x: usize| self.values[(z * ny1 + y) * nx1 + x];
        // Corners: storage plane 2 z + 1, slots (x, y).
        for z in 0..=nz {
            for y in 0..=ny {
                let src = (z * ny1 + y) * nx1;
                let at = slot(2 * z + 1, y, 0);
                samples.values[at..at + nx1].copy_from_slice(&self.values[src..src + nx1]);
            }
        }
        if cshape == ghosts {
            // Centre plane p (cube k = p - 1) is storage plane 2 p, slot (i + 1, j + 1): the
            // array's layout exactly. Only the points that exist are copied and checked.
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
            return Ok(());
        }
        if let Some((i, value)) = first_non_finite(centres) {
            return Err(non_finite("centres", i, value, cshape));
        }
        for k in 0..nz {
            for j in 0..ny {
                let src = (k * ny + j) * nx;
                let at = slot(2 * k + 2, j + 1, 1);
                samples.values[at..at + nx].copy_from_slice(&centres[src..src + nx]);
            }
        }
        // Ghosts (centres of the cubes just outside a face, sampled at the face centre): the
        // mean of the face's four corners, the value the bilinear interpolant of the face takes
        // there. Documented in the Python API; pass the (n + 2)-shaped centres to give them.
        let mean = |a: f32, b: f32, c: f32, d: f32| (a + b + c + d) * 0.25;
        for k in 0..nz {
            for j in 0..ny {
                for (x, sx) in [(0, 0), (nx, nx + 1)] {
                    let m = mean(
                        v(k, j, x),
                        v(k, j + 1, x),
                        v(k + 1, j, x),
                        v(k + 1, j + 1, x),
                    );
                    samples.values[slot(2 * k + 2, j + 1, sx)] = m;
                }
            }
            for i in 0..nx {
                for (y, sy) in [(0, 0), (ny, ny + 1)] {
                    let m = mean(
                        v(k, y, i),
                        v(k, y, i + 1),
                        v(k + 1, y, i),
                        v(k + 1, y, i + 1),
                    );
                    samples.values[slot(2 * k + 2, sy, i + 1)] = m;
                }
            }
        }
        for j in 0..ny {
            for i in 0..nx {
                for (z, plane) in [(0, 0), (nz, 2 * nz + 2)] {
                    let m = mean(
                        v(z, j, i),
                        v(z, j, i + 1),
                        v(z, j + 1, i),
                        v(z, j + 1, i + 1),
                    );
                    samples.values[slot(plane, j + 1, i + 1)] = m;
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
        let mut v = vec![0.0f32; 10_000];
        assert_eq!(first_non_finite(&v), None);
        v[7000] = f32::INFINITY;
        v[9000] = f32::NAN;
        assert_eq!(first_non_finite(&v), Some((7000, f32::INFINITY)));
    }
}
