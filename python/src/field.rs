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

/// Calls `f` on the points `(x, y, z)` (moved into numpy, no copy), checks its answer (a
/// float32 array of one finite value per point) and hands the values to `put` in order.
fn call(f: &Bound<'_, PyAny>, xyz: [Vec<f64>; 3], mut put: impl FnMut(usize, f32)) -> PyResult<()> {
    let py = f.py();
    let n = xyz[0].len();
    let [x, y, z] = xyz;
    let answer = f.call1((x.into_pyarray(py), y.into_pyarray(py), z.into_pyarray(py)))?;
    let values: PyReadonlyArray1<'_, f32> = answer.extract().map_err(|_| {
        PyValueError::new_err("the field callable must return one float32 value per point")
    })?;
    if values.len() != n {
        return Err(PyValueError::new_err(format!(
            "the field callable returned {} values for {n} points",
            values.len()
        )));
    }
    for (k, &v) in values.as_array().iter().enumerate() {
        put(k, v);
    }
    Ok(())
}

/// Three coordinate buffers of `capacity`.
fn buffers(capacity: usize) -> [Vec<f64>; 3] {
    std::array::from_fn(|_| Vec::with_capacity(capacity))
}

/// The lattice point in storage slot `(sx, sy)` of plane `z`, if one exists there.
fn point(samples: &Samples, bcdl: bool, sx: usize, sy: usize, z: usize) -> Option<Vec3> {
    if !bcdl {
        return Some(samples.simple_position(sx, sy, z));
    }
    let zz = z as i32 - 1;
    let odd = zz & 1;
    let q = [2 * sx as i32 - odd, 2 * sy as i32 - odd, zz];
    samples.bcdl_exists(q).then(|| samples.bcdl_position(q))
}

/// Evaluates the batch `slots` / `xyz` (emptied) into `values`; errors on the first
/// non-finite answer, naming its point.
fn evaluate(
    f: &Bound<'_, PyAny>,
    layout: &Samples,
    bcdl: bool,
    slots: &mut Vec<usize>,
    xyz: &mut [Vec<f64>; 3],
    values: &mut [f32],
) -> PyResult<()> {
    if slots.is_empty() {
        return Ok(());
    }
    let points = std::mem::replace(xyz, buffers(slots.capacity()));
    let mut bad: Option<(usize, f32)> = None;
    call(f, points, |k, v| {
        if v.is_finite() {
            values[slots[k]] = v;
        } else if bad.is_none() {
            bad = Some((slots[k], v));
        }
    })?;
    slots.clear();
    match bad {
        None => Ok(()),
        Some((slot, v)) => {
            let [dx, dy, _] = layout.dims;
            let (z, sy, sx) = (slot / (dx * dy), slot / dx % dy, slot % dx);
            let p = point(layout, bcdl, sx, sy, z).unwrap_or(Vec3::NAN);
            Err(PyValueError::new_err(format!(
                "the field is not finite at ({}, {}, {}): got {v}",
                p.x, p.y, p.z
            )))
        }
    }
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
    let mut values = std::mem::take(&mut samples.values);
    values.fill(f32::NAN);
    let layout = &*samples;
    let [dx, dy, dz] = layout.dims;
    let bcdl = sampled_lattice(settings) == Lattice::BodyCentred;
    let mut slots: Vec<usize> = Vec::with_capacity(batch);
    let mut xyz = buffers(batch);
    let mut run = || -> PyResult<()> {
        for z in 0..dz {
            for sy in 0..dy {
                for sx in 0..dx {
                    let Some(p) = point(layout, bcdl, sx, sy, z) else {
                        continue;
                    };
                    slots.push((z * dy + sy) * dx + sx);
                    for (a, c) in xyz.iter_mut().enumerate() {
                        c.push(f64::from(p[a]));
                    }
                    if slots.len() == batch {
                        evaluate(f, layout, bcdl, &mut slots, &mut xyz, &mut values)?;
                    }
                }
            }
        }
        evaluate(f, layout, bcdl, &mut slots, &mut xyz, &mut values)
    };
    let result = run();
    samples.values = values;
    result.map(|()| t.elapsed().as_secs_f64())
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
    let mut values = Vec::with_capacity(per_call * 6);
    for chunk in mesh.positions.chunks(per_call) {
        let mut xyz = buffers(chunk.len() * 6);
        for &p in chunk {
            let p = Vec3::from(p);
            for axis in [Vec3::X, Vec3::Y, Vec3::Z] {
                for q in [p + axis * e, p - axis * e] {
                    for (a, c) in xyz.iter_mut().enumerate() {
                        c.push(f64::from(q[a]));
                    }
                }
            }
        }
        values.clear();
        let mut bad = None;
        call(f, xyz, |k, v| {
            if !v.is_finite() && bad.is_none() {
                bad = Some((k / 6, v));
            }
            values.push(v);
        })?;
        if let Some((k, v)) = bad {
            let p = chunk[k];
            return Err(PyValueError::new_err(format!(
                "the field is not finite near vertex ({}, {}, {}) (gradient normals): got {v}",
                p[0], p[1], p[2]
            )));
        }
        for v in values.chunks(6) {
            let g = Vec3::new(v[0] - v[1], v[2] - v[3], v[4] - v[5]);
            mesh.normals.push(g.normalize_or_zero().to_array());
        }
    }
    Ok(())
}
