//! A vectorised Python callable `f(x, y, z)` sampled on a lattice in batches: the lattice's
//! points go to `f` as three float64 arrays (the float32 positions the library itself would
//! sample, converted exactly), up to `batch` points per call, in storage order; its float32
//! answers fill the sample array. Gradient normals call it once per batch of vertices too
//! (six points per vertex, the library's central differences of step h / 4).

use glam::Vec3;
use numpy::{IntoPyArray, PyReadonlyArray1, PyUntypedArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use rmt_extract::{samples::sampled_lattice, ExtractSettings, Grid, Lattice, Samples};
use rmt_mesh::Mesh;

/// Calls `f` on `points`, checks its answer (a float32 array of one value per point, all
/// finite) and returns the values.
fn call(f: &Bound<'_, PyAny>, points: &[Vec3], out: &mut Vec<f32>) -> PyResult<()> {
    let py = f.py();
    let coord = |a: usize| -> Vec<f64> { points.iter().map(|p| f64::from(p[a])).collect() };
    let (x, y, z) = (
        coord(0).into_pyarray(py),
        coord(1).into_pyarray(py),
        coord(2).into_pyarray(py),
    );
    let answer = f.call1((x, y, z))?;
    let values: PyReadonlyArray1<'_, f32> = answer.extract().map_err(|_| {
        PyValueError::new_err("the field callable must return one float32 value per point")
    })?;
    if values.len() != points.len() {
        return Err(PyValueError::new_err(format!(
            "the field callable returned {} values for {} points",
            values.len(),
            points.len()
        )));
    }
    let values = values.as_array();
    if let Some(k) = values.iter().position(|v| !v.is_finite()) {
        let p = points[k];
        return Err(PyValueError::new_err(format!(
            "the field is not finite at ({}, {}, {}): got {}",
            p.x, p.y, p.z, values[k]
        )));
    }
    out.clear();
    out.extend(values.iter().copied());
    Ok(())
}

/// Samples `f` at every point of the lattice of `settings` into `samples`; returns the seconds
/// spent.
pub fn sample(
    f: &Bound<'_, PyAny>,
    settings: &ExtractSettings,
    samples: &mut Samples,
    batch: usize,
) -> PyResult<f64> {
    let t = std::time::Instant::now();
    samples.prepare(settings);
    samples.values.fill(f32::NAN);
    let [dx, dy, dz] = samples.dims;
    let bcdl = sampled_lattice(settings) == Lattice::BodyCentred;
    let mut slots: Vec<usize> = Vec::with_capacity(batch);
    let mut points: Vec<Vec3> = Vec::with_capacity(batch);
    let mut values = Vec::with_capacity(batch);
    let mut flush = |slots: &mut Vec<usize>, points: &mut Vec<Vec3>, samples: &mut Samples| {
        if points.is_empty() {
            return Ok(());
        }
        call(f, points, &mut values)?;
        for (&s, &v) in slots.iter().zip(&values) {
            samples.values[s] = v;
        }
        slots.clear();
        points.clear();
        Ok::<(), PyErr>(())
    };
    for z in 0..dz {
        for sy in 0..dy {
            for sx in 0..dx {
                let p = if bcdl {
                    let zz = z as i32 - 1;
                    let odd = zz & 1;
                    let q = [2 * sx as i32 - odd, 2 * sy as i32 - odd, zz];
                    if !samples.bcdl_exists(q) {
                        continue;
                    }
                    samples.bcdl_position(q)
                } else {
                    samples.simple_position(sx, sy, z)
                };
                slots.push((z * dy + sy) * dx + sx);
                points.push(p);
                if points.len() == batch {
                    flush(&mut slots, &mut points, samples)?;
                }
            }
        }
    }
    flush(&mut slots, &mut points, samples)?;
    Ok(t.elapsed().as_secs_f64())
}

/// Normals from central differences of `f` (step h / 4, the library's gradient normals),
/// pointing toward increasing values.
pub fn gradient_normals(
    f: &Bound<'_, PyAny>,
    grid: &Grid,
    mesh: &mut Mesh,
    batch: usize,
) -> PyResult<()> {
    let e = grid.h() * 0.25;
    mesh.normals.clear();
    let per_call = (batch / 6).max(1);
    let mut points = Vec::with_capacity(per_call * 6);
    let mut values = Vec::new();
    for chunk in mesh.positions.chunks(per_call) {
        points.clear();
        for &p in chunk {
            let p = Vec3::from(p);
            for axis in [Vec3::X, Vec3::Y, Vec3::Z] {
                points.push(p + axis * e);
                points.push(p - axis * e);
            }
        }
        call(f, &points, &mut values)?;
        for v in values.chunks(6) {
            let g = Vec3::new(v[0] - v[1], v[2] - v[3], v[4] - v[5]);
            mesh.normals.push(g.normalize_or_zero().to_array());
        }
    }
    Ok(())
}
