//! The built-in objects of `rmt_terrain.sample`: a Python dict of parameters turned into the
//! command line's [`ObjectSpec`] (crate `rmt-objects`, shared with `experiments extract
//! --object ...`), built with `ObjectSpec::build_for_spacing` for the sampled grid, so the same
//! object, box and resolution give the same values.

use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use rmt_extract::Grid;
use rmt_fields::ScalarField;
use rmt_objects::{Bounds, ObjectKind, ObjectParams, ObjectSpec};

use crate::errors::Error;

/// The object names, in the command line's order.
pub fn names() -> Vec<&'static str> {
    ObjectKind::names()
}

/// `name` with the parameters of `params` (`None` values count as unset); errors on unknown
/// objects and on parameters the object does not take.
pub fn spec_from_dict(name: &str, params: &Bound<'_, PyDict>) -> PyResult<ObjectSpec> {
    let kind: ObjectKind = name
        .parse()
        .map_err(|e: rmt_objects::ObjectError| PyValueError::new_err(e.to_string()))?;
    let accepted = kind.accepted();
    let mut p = ObjectParams::default();
    for (k, v) in params.iter() {
        let key: String = k.extract()?;
        if !accepted.contains(&key.as_str()) {
            return Err(PyValueError::new_err(format!(
                "object {kind} takes no parameter {key:?} (it takes: {})",
                accepted.join(", ")
            )));
        }
        if v.is_none() {
            continue;
        }
        let bad = |e: PyErr| PyValueError::new_err(format!("parameter {key}: {e}"));
        match key.as_str() {
            "radius" => p.radius = Some(v.extract().map_err(bad)?),
            "seed" => p.seed = Some(v.extract().map_err(bad)?),
            "octaves" => p.octaves = Some(v.extract().map_err(bad)?),
            "frequency" => p.frequency = Some(v.extract().map_err(bad)?),
            "amplitude" => p.amplitude = Some(v.extract().map_err(bad)?),
            "thickness" => p.thickness = Some(v.extract().map_err(bad)?),
            "major" => p.major = Some(v.extract().map_err(bad)?),
            "minor" => p.minor = Some(v.extract().map_err(bad)?),
            "mesh" => p.mesh = Some(v.extract().map_err(bad)?),
            "margin" => p.margin = Some(v.extract().map_err(bad)?),
            "band" => p.band = Some(v.extract().map_err(bad)?),
            "base" => p.base = Some(v.extract().map_err(bad)?),
            "cave_frequency" => p.cave_frequency = Some(v.extract().map_err(bad)?),
            "cave_radius" => p.cave_radius = Some(v.extract().map_err(bad)?),
            _ => p.cave_ceiling = Some(v.extract().map_err(bad)?),
        }
    }
    ObjectSpec::new(kind, p).map_err(|e| PyValueError::new_err(e.to_string()))
}

/// The field of `spec` for sampling on `grid` (mesh objects keep a narrow band of `band` grid
/// spacings, as on the command line).
pub fn build(spec: &ObjectSpec, grid: &Grid) -> Result<Box<dyn ScalarField>, Error> {
    let bounds = Bounds {
        min: grid.min,
        max: grid.max,
    };
    spec.build_for_spacing(&bounds, Some(grid.spacing().max_element()), &[])
        .map_err(|e| Error::Value(e.to_string()))
}
