//! The compiled half of the Python package `rmt_terrain` (`rmt_terrain._native`): numpy volumes
//! in, numpy meshes out, through the extraction, mesh and fields crates. The Python half
//! (`rmt_terrain/__init__.py`) checks and converts arguments and holds the `Mesh` class; this
//! module does the work, with the GIL released during extraction.
//!
//! Modules, one role each, importing downward only: [`errors`] (library errors as Python
//! exceptions), [`volume`] (numpy volumes into the extractor's sample array), [`normals`]
//! (gradient normals of a volume), [`objects`] (the built-in objects of `sample`), [`field`]
//! (a vectorised Python callable sampled in batches), [`pool`] (extractors kept between calls),
//! [`flat`] (flat structs such as the stats as dicts, directly), [`convert`] (results as numpy
//! arrays and dicts).

mod convert;
mod errors;
mod field;
mod flat;
mod normals;
mod objects;
mod pool;
mod volume;

use glam::Vec3;
use numpy::{PyReadonlyArray2, PyReadonlyArray3, PyUntypedArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};
use rmt_extract::{
    Boundary, Clustering, ExtractSettings, Grid, Lattice, Method, NormalMode, Stats,
};
use rmt_mesh::Mesh;

use crate::errors::extract_error;

/// What the Python wrapper passes for one extraction (already checked there for types).
struct Options {
    level: f32,
    lattice: Lattice,
    method: Method,
    clustering: Clustering,
    normals: String,
    threads: usize,
}

impl Options {
    fn parse(
        level: f64,
        lattice: &str,
        method: &str,
        clustering: &str,
        normals: &str,
        threads: Option<usize>,
    ) -> PyResult<Self> {
        let level = level as f32;
        if !level.is_finite() {
            return Err(PyValueError::new_err(format!(
                "level must be a finite float32, got {level}"
            )));
        }
        let lattice = match lattice {
            "simple" => Lattice::Simple,
            "bcdl" => Lattice::BodyCentred,
            other => {
                return Err(PyValueError::new_err(format!(
                    "lattice must be 'simple' or 'bcdl', got {other:?}"
                )))
            }
        };
        let method_name = method;
        let method = match method {
            "mt" => Method::Mt,
            "mc" => Method::Mc,
            "surface-nets" => Method::SurfaceNets,
            other => {
                return Err(PyValueError::new_err(format!(
                    "method must be 'mt', 'mc' or 'surface-nets', got {other:?}"
                )))
            }
        };
        let mut clustering = match clustering {
            "none" => Clustering::None,
            "integrated" => Clustering::Integrated,
            "integrated-unchecked" => Clustering::IntegratedUnchecked,
            "postprocessed" => Clustering::Postprocessed,
            "meshopt" => Clustering::Meshopt,
            other => {
                return Err(PyValueError::new_err(format!(
                    "clustering must be 'integrated', 'none', 'integrated-unchecked', \
                     'postprocessed' or 'meshopt', got {other:?}"
                )))
            }
        };
        // Clustering belongs to marching tetrahedra: the other methods run without it, which
        // the default ('integrated') and 'none' both ask for; another mode is a mistake.
        if method != Method::Mt {
            match clustering {
                Clustering::None | Clustering::Integrated => clustering = Clustering::None,
                other => {
                    return Err(PyValueError::new_err(format!(
                        "method {method_name:?} has no clustering: pass clustering='none' \
                         (the default 'integrated' applies to method='mt' only), got {:?}",
                        other.name()
                    )))
                }
            }
        }
        if !matches!(normals, "gradient" | "area" | "none") {
            return Err(PyValueError::new_err(format!(
                "normals must be 'gradient', 'area' or 'none', got {normals:?}"
            )));
        }
        let threads = match threads {
            Some(0) => return Err(PyValueError::new_err("threads must be at least 1, got 0")),
            Some(n) => n,
            None => pool::default_threads(),
        };
        Ok(Self {
            level,
            lattice,
            method,
            clustering,
            normals: normals.to_string(),
            threads,
        })
    }

    /// The extractor's settings for `grid`; normals as the library computes them (`gradient`
    /// is computed here afterwards, from the volume or the callable).
    fn settings(&self, grid: Grid) -> ExtractSettings {
        let lattice = match self.method {
            Method::Mt => self.lattice,
            Method::Mc | Method::SurfaceNets => Lattice::Simple,
        };
        let mut s = ExtractSettings::new(grid, lattice, self.clustering);
        s.method = self.method;
        s.iso = self.level;
        s.threads = self.threads;
        s.normals = match self.normals.as_str() {
            "area" => NormalMode::AreaWeighted,
            _ => NormalMode::Skip,
        };
        s
    }
}

/// The grid of a volume of `shape` (array order z, y, x: points, not cells) with `spacing` and
/// `origin` in array order. The upper corner is computed in double precision, so a spacing
/// derived from a box, `(max - min) / cells`, gives back that box's float32 corners exactly.
fn volume_grid(shape: [usize; 3], spacing: [f64; 3], origin: [f64; 3]) -> PyResult<Grid> {
    let mut cells = [0usize; 3];
    let mut min = [0f32; 3];
    let mut max = [0f32; 3];
    for axis in 0..3 {
        // Array axis 2 is x.
        let a = 2 - axis;
        if shape[a] < 2 {
            return Err(PyValueError::new_err(format!(
                "volume must have at least 2 points along every axis, got shape {shape:?}"
            )));
        }
        if !(spacing[a].is_finite() && spacing[a] > 0.0) {
            return Err(PyValueError::new_err(format!(
                "spacing must be finite and > 0 on every axis, got {spacing:?}"
            )));
        }
        if !origin[a].is_finite() {
            return Err(PyValueError::new_err(format!(
                "origin must be finite, got {origin:?}"
            )));
        }
        cells[axis] = shape[a] - 1;
        min[axis] = origin[a] as f32;
        max[axis] = (origin[a] + spacing[a] * cells[axis] as f64) as f32;
        if !(max[axis].is_finite() && max[axis] > min[axis]) {
            return Err(PyValueError::new_err(format!(
                "the box from origin {origin:?} and spacing {spacing:?} is empty or not \
                 finite in float32"
            )));
        }
    }
    Ok(Grid::new(cells, Vec3::from(min), Vec3::from(max)))
}

/// Extracts the surface of a sampled volume (the work behind `rmt_terrain.extract`).
///
/// `volume` is C-contiguous float32 of shape (nz + 1, ny + 1, nx + 1); `centres` (body-centred
/// lattice only) of shape (nz + 2, ny + 2, nx + 2), the ghost layer included (the Python
/// wrapper builds it from `centres` and `ghosts`), or (nz, ny, nx), without ghosts: then the
/// box faces are closed by pyramids (`Boundary::Pyramids`). On the simple lattice (and for marching
/// cubes and surface nets) the volume is read in place, without a copy. Returns `(vertices,
/// faces, normals, stats, box)` in array order (z, y, x), faces wound for that order.
#[pyfunction]
#[pyo3(signature = (volume, centres, level, spacing, origin, lattice, method, clustering, normals, threads))]
#[allow(clippy::too_many_arguments)]
fn extract_volume<'py>(
    py: Python<'py>,
    volume: PyReadonlyArray3<'py, f32>,
    centres: Option<PyReadonlyArray3<'py, f32>>,
    level: f64,
    spacing: [f64; 3],
    origin: [f64; 3],
    lattice: &str,
    method: &str,
    clustering: &str,
    normals: &str,
    threads: Option<usize>,
) -> PyResult<Bound<'py, PyTuple>> {
    let started = std::time::Instant::now();
    let options = Options::parse(level, lattice, method, clustering, normals, threads)?;
    let shape: [usize; 3] = volume.shape().try_into().map_err(|_| {
        PyValueError::new_err(format!(
            "volume must be 3-D, got {} dimensions",
            volume.shape().len()
        ))
    })?;
    let grid = volume_grid(shape, spacing, origin)?;
    let settings = options.settings(grid);
    let values = volume
        .as_slice()
        .map_err(|_| PyValueError::new_err("volume must be C-contiguous"))?;
    let centres_slice = match &centres {
        Some(c) => Some((
            c.as_slice()
                .map_err(|_| PyValueError::new_err("centres must be C-contiguous"))?,
            <[usize; 3]>::try_from(c.shape()).map_err(|_| {
                PyValueError::new_err(format!(
                    "centres must be 3-D, got {} dimensions",
                    c.shape().len()
                ))
            })?,
        )),
        None => None,
    };
    // Centres of shape `volume.shape - 1` (no ghost layer): the box is closed by the pyramids
    // of the box faces, split in two tetrahedra each, without ghosts.
    let mut settings = settings;
    if settings.lattice == Lattice::BodyCentred
        && centres_slice.is_some_and(|(_, c)| (0..3).all(|a| c[a] + 1 == shape[a]))
    {
        settings.boundary = Boundary::Pyramids;
    }
    let input = volume::Input {
        values,
        shape,
        centres: centres_slice,
    };
    let gradient = options.normals == "gradient";
    let (mesh, stats, t_input, t_reorder, copied) =
        py.detach(|| -> Result<(Mesh, Stats, f64, f64, bool), errors::Error> {
            let mut ex = pool::take();
            let result = (|| {
                let t = std::time::Instant::now();
                let workers = pool::workers(settings.threads)?;
                ex.set_pool(workers.clone());
                // Marching cubes and plain MT write the mesh in array order themselves
                // (`Extractor::writes_array_order`); the other modes' meshes are turned below.
                ex.set_array_order(true);
                let array_order = ex.writes_array_order(&settings);
                // In place when the storage is the volume's own (simple lattice), checked for
                // non-finite values by the extractor's first pass; the body-centred lattice
                // interleaves corner and centre planes: a copy, checked here on this thread
                // (the pool only for a large volume). The extractor hands its work to the
                // pool itself, as it does for a caller in Rust.
                let in_place = input.check_or_fill(&settings, ex.samples_mut(), &workers)?;
                let t_input = t.elapsed().as_secs_f64();
                let mut mesh = Mesh::default();
                let extracted = if in_place {
                    ex.extract_borrowed(input.values, &settings, &mut mesh)
                } else {
                    ex.extract_presampled(&settings, &mut mesh)
                };
                let mut stats = extracted.map_err(|e| input.library_error(e))?;
                if gradient {
                    let t = std::time::Instant::now();
                    normals::from_volume(&input, &settings.grid, array_order, &mut mesh);
                    stats.t_normals_s += t.elapsed().as_secs_f64();
                    stats.t_total_s += stats.t_normals_s;
                }
                // Array order before the GIL is taken back.
                let t = std::time::Instant::now();
                if !array_order {
                    convert::to_array_order(&mut mesh);
                }
                Ok((mesh, stats, t_input, t.elapsed().as_secs_f64(), !in_place))
            })();
            pool::give_back(ex);
            result
        })?;
    convert::result(
        py,
        mesh,
        &stats,
        &settings.grid,
        &[("t_input_s", t_input), ("t_reorder_s", t_reorder)],
        &[("input_copied", copied)],
        convert::Axes::Array,
        started,
    )
}

/// Samples a built-in object on a lattice (the work behind `rmt_terrain.sample`). Returns
/// `(volume, centres or None, spacing, origin)`, arrays in (z, y, x) order.
#[pyfunction]
#[pyo3(signature = (object, resolution, lattice, bounds, params, threads))]
fn sample<'py>(
    py: Python<'py>,
    object: &str,
    resolution: [usize; 3],
    lattice: &str,
    bounds: [f32; 6],
    params: &Bound<'py, PyDict>,
    threads: Option<usize>,
) -> PyResult<Bound<'py, PyTuple>> {
    let options = Options::parse(0.0, lattice, "mt", "none", "none", threads)?;
    let spec = objects::spec_from_dict(object, params)?;
    let grid = Grid::new(
        resolution,
        Vec3::new(bounds[0], bounds[1], bounds[2]),
        Vec3::new(bounds[3], bounds[4], bounds[5]),
    );
    let settings = options.settings(grid);
    settings.check().map_err(extract_error)?;
    pool::check_memory(&settings)?;
    let samples = py.detach(|| -> Result<rmt_extract::Samples, errors::Error> {
        let field = objects::build(&spec, &grid)?;
        let pool = pool::workers(options.threads)?;
        let mut samples = rmt_extract::Samples::default();
        let mut stats = Stats::default();
        samples
            .sample(field.as_ref(), &settings, &pool, &mut stats)
            .map_err(|e| errors::Error::Library(e.to_string()))?;
        Ok(samples)
    })?;
    convert::sampled(py, &samples, &grid)
}

/// Samples a vectorised Python callable on a lattice and extracts its surface (the work behind
/// `rmt_terrain.extract_field`). `f(x, y, z)` takes three float64 arrays of one batch and
/// returns float32 values of the same length. Returns as [`extract_volume`].
#[pyfunction]
#[pyo3(signature = (f, bounds, resolution, level, lattice, method, clustering, normals, threads, batch))]
#[allow(clippy::too_many_arguments)]
fn extract_field<'py>(
    py: Python<'py>,
    f: &Bound<'py, PyAny>,
    bounds: [f32; 6],
    resolution: [usize; 3],
    level: f64,
    lattice: &str,
    method: &str,
    clustering: &str,
    normals: &str,
    threads: Option<usize>,
    batch: usize,
) -> PyResult<Bound<'py, PyTuple>> {
    let started = std::time::Instant::now();
    let options = Options::parse(level, lattice, method, clustering, normals, threads)?;
    let grid = Grid::new(
        resolution,
        Vec3::new(bounds[0], bounds[1], bounds[2]),
        Vec3::new(bounds[3], bounds[4], bounds[5]),
    );
    let settings = options.settings(grid);
    settings.check().map_err(extract_error)?;
    pool::check_memory(&settings)?;
    let workers = pool::workers(options.threads)?;
    let mut ex = pool::take();
    ex.set_pool(workers);
    ex.set_array_order(false);
    let t_sampling = match field::sample(f, &settings, ex.samples_mut(), batch.max(1)) {
        Ok(t) => t,
        Err(e) => {
            pool::give_back(ex);
            return Err(e);
        }
    };
    let result = py.detach(|| {
        let mut mesh = Mesh::default();
        ex.extract_presampled(&settings, &mut mesh)
            .map(|stats| (mesh, stats))
    });
    pool::give_back(ex);
    let (mut mesh, mut stats) = result.map_err(extract_error)?;
    stats.t_sampling_s += t_sampling;
    stats.t_total_s += t_sampling;
    if options.normals == "gradient" {
        let t = std::time::Instant::now();
        field::gradient_normals(f, &settings.grid, &mut mesh, batch.max(1))?;
        stats.t_normals_s += t.elapsed().as_secs_f64();
        stats.t_total_s += stats.t_normals_s;
    }
    convert::result(
        py,
        mesh,
        &stats,
        &settings.grid,
        &[],
        &[],
        convert::Axes::World,
        started,
    )
}

/// Validates a mesh: closed, manifold, oriented, Euler characteristic, components. Edges on
/// the box `[lo, hi]` do not count as holes.
#[pyfunction]
fn validate<'py>(
    py: Python<'py>,
    vertices: PyReadonlyArray2<'py, f32>,
    faces: PyReadonlyArray2<'py, u32>,
    lo: [f32; 3],
    hi: [f32; 3],
    cells: [usize; 3],
) -> PyResult<Bound<'py, PyDict>> {
    let mesh = convert::mesh_from_arrays(&vertices, &faces, None)?;
    let grid = Grid::new(cells, Vec3::from(lo), Vec3::from(hi));
    let report = py
        .detach(|| rmt_mesh::validate(&mesh, &|p| rmt_extract::measure::on_box_boundary(&grid, p)));
    let dict = convert::to_dict(py, &report)?;
    dict.set_item("closed", report.boundary_edges_interior == 0)?;
    dict.set_item(
        "manifold",
        report.non_manifold_edges == 0 && report.non_manifold_vertices == 0,
    )?;
    dict.set_item("oriented", report.orientation_errors == 0)?;
    dict.set_item("watertight_manifold", report.is_watertight_manifold())?;
    Ok(dict)
}

/// Triangle quality: radius ratio (the dissertation's aspect ratio) and angle statistics.
#[pyfunction]
fn quality<'py>(
    py: Python<'py>,
    vertices: PyReadonlyArray2<'py, f32>,
    faces: PyReadonlyArray2<'py, u32>,
) -> PyResult<Bound<'py, PyDict>> {
    let mesh = convert::mesh_from_arrays(&vertices, &faces, None)?;
    let report = py.detach(|| rmt_mesh::quality(&mesh));
    convert::to_dict(py, &report)
}

/// Writes a mesh as binary PLY, OBJ or binary glTF (`.glb`), by the extension of `path`: the
/// writers of the command line, so the same mesh gives the same bytes.
#[pyfunction]
#[pyo3(signature = (path, vertices, faces, normals))]
fn write<'py>(
    py: Python<'py>,
    path: std::path::PathBuf,
    vertices: PyReadonlyArray2<'py, f32>,
    faces: PyReadonlyArray2<'py, u32>,
    normals: Option<PyReadonlyArray2<'py, f32>>,
) -> PyResult<()> {
    let mesh = convert::mesh_from_arrays(&vertices, &faces, normals.as_ref())?;
    py.detach(|| rmt_mesh::io::save_mesh(&path, &mesh, false))
        .map_err(|e| PyValueError::new_err(format!("writing {}: {e}", path.display())))
}

/// The compiled module `rmt_terrain._native`.
#[pymodule]
#[pyo3(name = "_native")]
fn native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(extract_volume, m)?)?;
    m.add_function(wrap_pyfunction!(extract_field, m)?)?;
    m.add_function(wrap_pyfunction!(sample, m)?)?;
    m.add_function(wrap_pyfunction!(validate, m)?)?;
    m.add_function(wrap_pyfunction!(quality, m)?)?;
    m.add_function(wrap_pyfunction!(write, m)?)?;
    m.add("OBJECTS", objects::names())?;
    Ok(())
}
