//! The built-in objects of `rmt_terrain.sample`, built exactly as the command line builds them
//! (`experiments extract --object ...`, `ObjectSpec::build_for_spacing`): the same defaults,
//! parameter checks and box-relative placement, so the same object, box and resolution give
//! the same values.

use std::path::PathBuf;

use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use rmt_extract::Grid;
use rmt_fields::{
    Asteroid, AsteroidParams, CaveParams, CaveTerrain, Gyroid, MeshSdf, RandomField, ScalarField,
    Sphere, SvobodaParams, SvobodaTerrain, Torus,
};

use crate::errors::Error;

/// The object names, in the command line's order.
pub const NAMES: [&str; 8] = [
    "sphere", "asteroid", "gyroid", "torus", "bunny", "terrain", "caves", "random",
];

/// The parameters each object takes (the command line's `ObjectKind::accepted`).
fn accepted(name: &str) -> &'static [&'static str] {
    match name {
        "sphere" => &["radius"],
        "asteroid" => &["seed", "octaves", "frequency", "amplitude", "radius"],
        "gyroid" => &["frequency", "thickness"],
        "torus" => &["major", "minor"],
        "bunny" => &["mesh", "margin", "band"],
        "terrain" => &["seed", "octaves", "frequency", "amplitude", "base"],
        "caves" => &[
            "seed",
            "octaves",
            "frequency",
            "amplitude",
            "base",
            "cave_frequency",
            "cave_radius",
            "cave_ceiling",
        ],
        _ => &["seed"],
    }
}

/// The command line's default seed of the asteroid and the random field.
const DEFAULT_SEED: u32 = 7;

/// The bunny's mesh in the checkout this package was built from.
const DEFAULT_BUNNY: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../data/bunny.obj");

/// An object and its parameters (unset ones take the command line's defaults).
#[derive(Default)]
pub struct Spec {
    name: String,
    radius: Option<f32>,
    seed: Option<u32>,
    octaves: Option<usize>,
    frequency: Option<f64>,
    amplitude: Option<f32>,
    thickness: Option<f32>,
    major: Option<f32>,
    minor: Option<f32>,
    mesh: Option<PathBuf>,
    margin: Option<f32>,
    band: Option<f32>,
    base: Option<f32>,
    cave_frequency: Option<f64>,
    cave_radius: Option<f32>,
    cave_ceiling: Option<f32>,
}

impl Spec {
    /// `name` with the parameters of `params`; errors on unknown objects and on parameters the
    /// object does not take.
    pub fn from_dict(name: &str, params: &Bound<'_, PyDict>) -> PyResult<Self> {
        if !NAMES.contains(&name) {
            return Err(PyValueError::new_err(format!(
                "unknown object {name:?}: one of {}",
                NAMES.join(", ")
            )));
        }
        let accepted = accepted(name);
        let mut spec = Spec {
            name: name.to_string(),
            ..Default::default()
        };
        for (k, v) in params.iter() {
            let key: String = k.extract()?;
            if !accepted.contains(&key.as_str()) {
                return Err(PyValueError::new_err(format!(
                    "object {name} takes no parameter {key:?} (it takes: {})",
                    accepted.join(", ")
                )));
            }
            if v.is_none() {
                continue;
            }
            let bad = |e: PyErr| PyValueError::new_err(format!("parameter {key}: {e}"));
            match key.as_str() {
                "radius" => spec.radius = Some(v.extract().map_err(bad)?),
                "seed" => spec.seed = Some(v.extract().map_err(bad)?),
                "octaves" => spec.octaves = Some(v.extract().map_err(bad)?),
                "frequency" => spec.frequency = Some(v.extract().map_err(bad)?),
                "amplitude" => spec.amplitude = Some(v.extract().map_err(bad)?),
                "thickness" => spec.thickness = Some(v.extract().map_err(bad)?),
                "major" => spec.major = Some(v.extract().map_err(bad)?),
                "minor" => spec.minor = Some(v.extract().map_err(bad)?),
                "mesh" => spec.mesh = Some(v.extract().map_err(bad)?),
                "margin" => spec.margin = Some(v.extract().map_err(bad)?),
                "band" => spec.band = Some(v.extract().map_err(bad)?),
                "base" => spec.base = Some(v.extract().map_err(bad)?),
                "cave_frequency" => spec.cave_frequency = Some(v.extract().map_err(bad)?),
                "cave_radius" => spec.cave_radius = Some(v.extract().map_err(bad)?),
                _ => spec.cave_ceiling = Some(v.extract().map_err(bad)?),
            }
        }
        Ok(spec)
    }

    /// The field for sampling on `grid` (mesh objects keep a narrow band of `band` grid
    /// spacings, as on the command line).
    pub fn build(&self, grid: &Grid) -> Result<Box<dyn ScalarField>, Error> {
        let name = self.name.as_str();
        let invalid = |param: &str, message: String| {
            Error::Value(format!("object {name}: parameter {param} {message}"))
        };
        let positive = |param: &str, v: f32| {
            if v.is_finite() && v > 0.0 {
                Ok(v)
            } else {
                Err(invalid(param, format!("must be finite and > 0, got {v}")))
            }
        };
        let non_negative = |param: &str, v: f32| {
            if v.is_finite() && v >= 0.0 {
                Ok(v)
            } else {
                Err(invalid(param, format!("must be finite and >= 0, got {v}")))
            }
        };
        let finite = |param: &str, v: f32| {
            if v.is_finite() {
                Ok(v)
            } else {
                Err(invalid(param, format!("must be finite, got {v}")))
            }
        };
        let octaves = |n: usize| {
            if (1..=16).contains(&n) {
                Ok(n)
            } else {
                Err(invalid("octaves", format!("must be 1 to 16, got {n}")))
            }
        };
        let centre = (grid.min + grid.max) * 0.5;
        let half = (grid.max - grid.min).min_element() * 0.5;
        Ok(match name {
            "sphere" => Box::new(Sphere::new(
                centre,
                positive("radius", self.radius.unwrap_or(half))?,
            )),
            "asteroid" => {
                let d = AsteroidParams::default();
                let frequency = self.frequency.unwrap_or(d.frequency);
                positive("frequency", frequency as f32)?;
                Box::new(Asteroid::new(
                    centre,
                    AsteroidParams {
                        seed: self.seed.unwrap_or(DEFAULT_SEED),
                        octaves: octaves(self.octaves.unwrap_or(d.octaves))?,
                        frequency,
                        amplitude: non_negative(
                            "amplitude",
                            self.amplitude.unwrap_or(d.amplitude),
                        )?,
                        radius: positive("radius", self.radius.unwrap_or(d.radius))?,
                    },
                ))
            }
            "gyroid" => Box::new(Gyroid {
                frequency: positive("frequency", self.frequency.unwrap_or(1.0) as f32)?,
                thickness: positive("thickness", self.thickness.unwrap_or(0.3))?,
            }),
            "torus" => Box::new(Torus {
                centre,
                major: positive("major", self.major.unwrap_or(0.6 * half))?,
                minor: positive("minor", self.minor.unwrap_or(0.25 * half))?,
            }),
            "terrain" => {
                let d = SvobodaParams::default();
                let frequency = self.frequency.unwrap_or(d.frequency);
                positive("frequency", frequency as f32)?;
                Box::new(SvobodaTerrain::new(SvobodaParams {
                    seed: self.seed.unwrap_or(d.seed),
                    octaves: octaves(self.octaves.unwrap_or(d.octaves))?,
                    frequency,
                    amplitude: non_negative("amplitude", self.amplitude.unwrap_or(d.amplitude))?,
                    base: finite("base", self.base.unwrap_or(d.base))?,
                }))
            }
            "caves" => {
                let d = CaveParams::default();
                let frequency = self.frequency.unwrap_or(d.frequency);
                positive("frequency", frequency as f32)?;
                let cave_frequency = self.cave_frequency.unwrap_or(d.cave_frequency);
                positive("cave_frequency", cave_frequency as f32)?;
                Box::new(CaveTerrain::new(CaveParams {
                    seed: self.seed.unwrap_or(d.seed),
                    octaves: octaves(self.octaves.unwrap_or(d.octaves))?,
                    frequency,
                    amplitude: non_negative("amplitude", self.amplitude.unwrap_or(d.amplitude))?,
                    base: finite("base", self.base.unwrap_or(d.base))?,
                    cave_frequency,
                    cave_radius: non_negative(
                        "cave_radius",
                        self.cave_radius.unwrap_or(d.cave_radius),
                    )?,
                    cave_ceiling: finite(
                        "cave_ceiling",
                        self.cave_ceiling.unwrap_or(d.cave_ceiling),
                    )?,
                }))
            }
            "bunny" => {
                let path = self
                    .mesh
                    .clone()
                    .unwrap_or_else(|| PathBuf::from(DEFAULT_BUNNY));
                let mesh = rmt_mesh::io::read_mesh(&path).map_err(|e| {
                    Error::Value(format!(
                        "object bunny: reading {} (pass mesh= a closed OBJ or PLY): {e}",
                        path.display()
                    ))
                })?;
                let band = self.band.unwrap_or(2.0);
                if !(band.is_finite() && band >= 0.0) {
                    return Err(invalid(
                        "band",
                        format!("must be finite and >= 0 (grid spacings), got {band}"),
                    ));
                }
                let sdf = MeshSdf::fit(&mesh, grid.min, grid.max, self.margin.unwrap_or(0.05))
                    .map_err(|e| Error::Value(format!("object bunny ({}): {e}", path.display())))?;
                let h = grid.spacing().max_element();
                if band > 0.0 {
                    Box::new(sdf.with_band(band * h))
                } else {
                    Box::new(sdf)
                }
            }
            _ => Box::new(
                RandomField::from_seed(u64::from(self.seed.unwrap_or(DEFAULT_SEED)))
                    .in_box(centre, half),
            ),
        })
    }
}
