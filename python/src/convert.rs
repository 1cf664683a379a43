//! Results as Python objects: meshes as numpy arrays that own the library's buffers (no copy),
//! reports and stats as dicts, sample arrays as volumes; and numpy meshes back into
//! [`rmt_mesh::Mesh`] for validation, quality and writing.

use numpy::ndarray::{Array2, Array3};
use numpy::{IntoPyArray, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList, PyTuple};
use rmt_extract::{Grid, Lattice, Samples, Stats};
use rmt_mesh::Mesh;
use serde_json::Value;

/// The coordinate order of a returned mesh.
#[derive(Clone, Copy, PartialEq, Eq)]
pub enum Axes {
    /// World `(x, y, z)`, the library's and the mesh files' order.
    World,
    /// A volume's array order `(z, y, x)`, as scikit-image returns its vertices.
    Array,
}

/// Reverses every triple of `v`.
fn reverse_triples(v: &mut [[f32; 3]]) {
    for p in v {
        *p = [p[2], p[1], p[0]];
    }
}

/// Turns a mesh in world order `(x, y, z)` into array order `(z, y, x)`: the first and last
/// coordinates of every position and normal swapped, and every triangle's last two corners,
/// since swapping two axes mirrors the mesh: so its triangles stay counter-clockwise seen from
/// increasing values in the new frame. Exact (no arithmetic); doing it twice gives the mesh
/// back. One pass at memory speed (about 90 us for the 28k vertices and 57k triangles of a 64^3
/// sphere by plain marching tetrahedra, under load): not worth waking the worker pool for.
/// Marching cubes needs none: it writes its mesh in array order itself
/// (`Extractor::set_array_order`).
pub fn to_array_order(mesh: &mut Mesh) {
    reverse_triples(&mut mesh.positions);
    reverse_triples(&mut mesh.normals);
    for t in mesh.indices.chunks_exact_mut(3) {
        t.swap(1, 2);
    }
}

/// `(vertices (N, 3) float32, faces (M, 3) uint32, normals (N, 3) float32 or None, stats dict,
/// (box min, box max, cells))`, in the order `axes`: the mesh is in that order already (see
/// [`to_array_order`]), the box is turned here. The arrays take over the mesh's buffers. The stats get the `extra` numbers and `flags`, and `t_call_s`, the time since
/// `started` (the native call's entry).
#[allow(clippy::too_many_arguments)]
pub fn result<'py>(
    py: Python<'py>,
    mesh: Mesh,
    stats: &Stats,
    grid: &Grid,
    extra: &[(&str, f64)],
    flags: &[(&str, bool)],
    axes: Axes,
    started: std::time::Instant,
) -> PyResult<Bound<'py, PyTuple>> {
    let (mut lo, mut hi, mut cells) = (grid.min.to_array(), grid.max.to_array(), grid.cells);
    if axes == Axes::Array {
        lo.reverse();
        hi.reverse();
        cells.reverse();
    }
    let Mesh {
        positions,
        normals,
        indices,
    } = mesh;
    let vertices = Array2::from(positions).into_pyarray(py);
    let m = indices.len() / 3;
    let faces = Array2::from_shape_vec((m, 3), indices)
        .map_err(|e| PyValueError::new_err(e.to_string()))?
        .into_pyarray(py);
    let normals = (!normals.is_empty()).then(|| Array2::from(normals).into_pyarray(py));
    let stats = crate::flat::to_dict(py, stats)?;
    for (k, v) in extra {
        stats.set_item(*k, *v)?;
    }
    for (k, v) in flags {
        stats.set_item(*k, *v)?;
    }
    stats.set_item(
        "axes",
        match axes {
            Axes::World => "xyz",
            Axes::Array => "zyx",
        },
    )?;
    let grid_box = (lo, hi, cells);
    stats.set_item("t_call_s", started.elapsed().as_secs_f64())?;
    (vertices, faces, normals, stats, grid_box).into_pyobject(py)
}

/// A serialisable report as a dict (via JSON values: numbers, strings, booleans, lists, maps).
pub fn to_dict<'py, T: serde::Serialize>(
    py: Python<'py>,
    value: &T,
) -> PyResult<Bound<'py, PyDict>> {
    let json = serde_json::to_value(value).map_err(|e| PyValueError::new_err(e.to_string()))?;
    let Value::Object(map) = json else {
        return Err(PyValueError::new_err("report is not a map"));
    };
    let dict = PyDict::new(py);
    for (k, v) in map {
        dict.set_item(k, json_to_py(py, v)?)?;
    }
    Ok(dict)
}

fn json_to_py(py: Python<'_>, v: Value) -> PyResult<Bound<'_, PyAny>> {
    Ok(match v {
        Value::Null => py.None().into_bound(py),
        Value::Bool(b) => b.into_pyobject(py)?.to_owned().into_any(),
        Value::Number(n) => match (n.as_u64(), n.as_i64(), n.as_f64()) {
            (Some(u), _, _) => u.into_pyobject(py)?.into_any(),
            (_, Some(i), _) => i.into_pyobject(py)?.into_any(),
            (_, _, Some(f)) => f.into_pyobject(py)?.into_any(),
            _ => py.None().into_bound(py),
        },
        Value::String(s) => s.into_pyobject(py)?.into_any(),
        Value::Array(items) => {
            let list = PyList::empty(py);
            for item in items {
                list.append(json_to_py(py, item)?)?;
            }
            list.into_any()
        }
        Value::Object(map) => {
            let dict = PyDict::new(py);
            for (k, v) in map {
                dict.set_item(k, json_to_py(py, v)?)?;
            }
            dict.into_any()
        }
    })
}

/// The mesh of numpy arrays (copied): vertices (N, 3) float32, faces (M, 3) uint32 with
/// indices below N, normals (N, 3) float32 or none.
pub fn mesh_from_arrays(
    vertices: &PyReadonlyArray2<'_, f32>,
    faces: &PyReadonlyArray2<'_, u32>,
    normals: Option<&PyReadonlyArray2<'_, f32>>,
) -> PyResult<Mesh> {
    let rows = |a: &[usize], name: &str| -> PyResult<usize> {
        match a {
            [n, 3] => Ok(*n),
            _ => Err(PyValueError::new_err(format!(
                "{name} must have shape (n, 3), got {a:?}"
            ))),
        }
    };
    let n = rows(vertices.shape(), "vertices")?;
    rows(faces.shape(), "faces")?;
    let positions: Vec<[f32; 3]> = vertices
        .as_array()
        .rows()
        .into_iter()
        .map(|r| [r[0], r[1], r[2]])
        .collect();
    let indices: Vec<u32> = faces.as_array().iter().copied().collect();
    if let Some(bad) = indices.iter().find(|&&i| i as usize >= n) {
        return Err(PyValueError::new_err(format!(
            "faces refer to vertex {bad}, but there are {n} vertices"
        )));
    }
    let mut mesh = Mesh::from_triangles(positions, indices);
    if let Some(normals) = normals {
        if rows(normals.shape(), "normals")? != n {
            return Err(PyValueError::new_err(format!(
                "normals must have one row per vertex ({n}), got {:?}",
                normals.shape()
            )));
        }
        mesh.normals = normals
            .as_array()
            .rows()
            .into_iter()
            .map(|r| [r[0], r[1], r[2]])
            .collect();
    }
    Ok(mesh)
}

/// `(volume, centres or None, spacing, origin)` of a sample array: the volume `(nz + 1, ny + 1,
/// nx + 1)`, the centres with their ghost layer `(nz + 2, ny + 2, nx + 2)` (NaN where no point
/// exists), spacing and origin in array order (z, y, x), the spacing in double precision from
/// the box, so that `extract` rebuilds the same float32 box.
pub fn sampled<'py>(
    py: Python<'py>,
    samples: &Samples,
    grid: &Grid,
) -> PyResult<Bound<'py, PyTuple>> {
    let [nx, ny, nz] = samples.cells;
    let shape = (nz + 1, ny + 1, nx + 1);
    let (volume, centres) = match samples.lattice {
        Some(Lattice::BodyCentred) => {
            let [dx, dy, _] = samples.dims;
            let plane = dx * dy;
            let mut corners = Vec::with_capacity((nx + 1) * (ny + 1) * (nz + 1));
            for z in 0..=nz {
                for y in 0..=ny {
                    let at = (2 * z + 1) * plane + y * dx;
                    corners.extend_from_slice(&samples.values[at..at + nx + 1]);
                }
            }
            let mut centres = Vec::with_capacity((nz + 2) * plane);
            for p in 0..nz + 2 {
                centres.extend_from_slice(&samples.values[2 * p * plane..(2 * p + 1) * plane]);
            }
            let centres = Array3::from_shape_vec((nz + 2, ny + 2, nx + 2), centres)
                .map_err(|e| PyValueError::new_err(e.to_string()))?;
            (corners, Some(centres.into_pyarray(py)))
        }
        _ => (samples.values.to_vec(), None),
    };
    let volume = Array3::from_shape_vec(shape, volume)
        .map_err(|e| PyValueError::new_err(e.to_string()))?
        .into_pyarray(py);
    let spacing =
        |a: usize| (f64::from(grid.max[a]) - f64::from(grid.min[a])) / grid.cells[a] as f64;
    let spacing = (spacing(2), spacing(1), spacing(0));
    let origin = (
        f64::from(grid.min.z),
        f64::from(grid.min.y),
        f64::from(grid.min.x),
    );
    (volume, centres, spacing, origin).into_pyobject(py)
}
