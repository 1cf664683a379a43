//! The sample objects by name: what `extract --object` and a manifest's `[[objects]]` build.
//!
//! An object is a [`ObjectKind`] plus optional [`ObjectParams`]; [`ObjectSpec::build`] turns it
//! into a scalar field placed in the sampled box. Every kind accepts only its own parameters, so a
//! misspelt or misplaced parameter is an error instead of being silently ignored.
//!
//! | kind | code | parameters (default) |
//! |---|---|---|
//! | `sphere` | `ss` | `radius` (half the box's smallest side: inscribed), centred in the box |
//! | `asteroid` | `as` | `seed` (7), `octaves` (4), `frequency` (1.5), `amplitude` (0.25), `radius` (0.7) |
//! | `gyroid` | `gs` | `frequency` (1.0), `thickness` (0.3) |
//! | `torus` | `os` | `major` (0.6 half-side), `minor` (0.25 half-side), around the y axis |
//! | `bunny` | `bs` | `mesh` (`data/bunny.obj`), `margin` (0.05 of the box per side), `band` (2 grid spacings) |
//! | `terrain` | `ts` | Svoboda's height field: `seed` (11), `octaves` (5), `frequency` (1.0), `amplitude` (0.45), `base` (0) |
//! | `caves` | `cs` | 3D noise ground with tunnels: `seed` (5), `octaves` (4), `frequency` (1.2), `amplitude` (0.5), `base` (0), `cave_frequency` (1.5), `cave_radius` (0.18), `cave_ceiling` (0.2) |
//! | `random` | `rf` | a random field of the property tests' families in the largest cube inside the box (blobs, waves, thin shells, thin tubes; a quarter quantised): `seed` (7); for topology sweeps |
//!
//! The code is the first part of a configuration id (`ss_bu`, `as_bi`, `bs_sp`), reproducing the
//! dissertation's names for sphere, asteroid and bunny (`o` for the ring-shaped torus). Seeds not
//! given take the manifest's `seed`, else the defaults above. The terrains are placed in world
//! coordinates (ground height `base` at y = 0 by default), not fitted to the box, and leave the box
//! through its sides.
//! Relative mesh paths are looked up in the current folder, then in the folders above the
//! manifest, then in the workspace root (see [`resolve_data_path`]).

use std::fmt;
use std::path::{Path, PathBuf};
use std::str::FromStr;

use glam::Vec3;
use rmt_fields::{
    Asteroid, AsteroidParams, CaveParams, CaveTerrain, Gyroid, MeshSdf, RandomField, ScalarField,
    Sphere, SvobodaParams, SvobodaTerrain, Torus,
};
use serde::{Deserialize, Serialize};

/// Why an object could not be built.
#[derive(Debug, thiserror::Error)]
pub enum ObjectError {
    /// The name is not a known object kind.
    #[error("unknown object `{0}` (expected one of: {list})", list = ObjectKind::names().join(", "))]
    UnknownObject(String),
    /// A parameter that this kind does not take.
    #[error("object {kind} takes no parameter `{param}` (it takes: {accepted})")]
    UnexpectedParameter {
        /// The object kind.
        kind: ObjectKind,
        /// The parameter given.
        param: &'static str,
        /// The parameters the kind accepts.
        accepted: String,
    },
    /// A parameter out of range.
    #[error("object {kind}: parameter `{param}` {message}")]
    InvalidParameter {
        /// The object kind.
        kind: ObjectKind,
        /// The parameter.
        param: &'static str,
        /// What is wrong and what was given.
        message: String,
    },
    /// Bounds that are not a box.
    #[error(
        "invalid bounds {0:?}: need 6 finite numbers xmin,ymin,zmin,xmax,ymax,zmax with min < max"
    )]
    InvalidBounds([f32; 6]),
    /// The mesh file of a mesh object does not exist.
    #[error("mesh file {} not found (looked in: {})", path.display(), tried.iter().map(|p| p.display().to_string()).collect::<Vec<_>>().join(", "))]
    MissingMesh {
        /// The path as given.
        path: PathBuf,
        /// The places looked at.
        tried: Vec<PathBuf>,
    },
    /// The mesh file could not be read.
    #[error(transparent)]
    MeshIo(#[from] rmt_mesh::io::MeshIoError),
    /// The field could not be built (e.g. an open mesh).
    #[error(transparent)]
    Field(#[from] rmt_fields::FieldError),
}

/// The kinds of sample object.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ObjectKind {
    /// Signed distance to a sphere centred in the box.
    Sphere,
    /// A sphere displaced by fractal Perlin noise.
    Asteroid,
    /// A thickened gyroid sheet (many handles).
    Gyroid,
    /// A torus around the y axis (genus 1).
    Torus,
    /// Signed distance to a closed triangle mesh (the Stanford bunny by default), fitted into the
    /// box.
    Bunny,
    /// Svoboda's terrain: a 2D fractal-noise height field, solid below.
    Terrain,
    /// 3D fractal-noise ground with overhangs and tunnels.
    Caves,
    /// A random test field of the property tests' families (blobs, waves, thin shells, thin
    /// tubes, sometimes quantised), drawn from `seed`: the object of topology sweeps.
    Random,
}

impl ObjectKind {
    /// Every kind, in documentation order.
    pub const ALL: [ObjectKind; 8] = [
        ObjectKind::Sphere,
        ObjectKind::Asteroid,
        ObjectKind::Gyroid,
        ObjectKind::Torus,
        ObjectKind::Bunny,
        ObjectKind::Terrain,
        ObjectKind::Caves,
        ObjectKind::Random,
    ];

    /// The name used on the command line and in manifests.
    pub fn name(self) -> &'static str {
        match self {
            ObjectKind::Sphere => "sphere",
            ObjectKind::Asteroid => "asteroid",
            ObjectKind::Gyroid => "gyroid",
            ObjectKind::Torus => "torus",
            ObjectKind::Bunny => "bunny",
            ObjectKind::Terrain => "terrain",
            ObjectKind::Caves => "caves",
            ObjectKind::Random => "random",
        }
    }

    /// Every name.
    pub fn names() -> Vec<&'static str> {
        Self::ALL.iter().map(|k| k.name()).collect()
    }

    /// The two-letter code that starts configuration ids (`ss` in `ss_bu`).
    pub fn code(self) -> &'static str {
        match self {
            ObjectKind::Sphere => "ss",
            ObjectKind::Asteroid => "as",
            ObjectKind::Gyroid => "gs",
            ObjectKind::Torus => "os",
            ObjectKind::Bunny => "bs",
            ObjectKind::Terrain => "ts",
            ObjectKind::Caves => "cs",
            ObjectKind::Random => "rf",
        }
    }

    /// The parameters this kind accepts.
    pub fn accepted(self) -> &'static [&'static str] {
        match self {
            ObjectKind::Sphere => &["radius"],
            ObjectKind::Asteroid => &["seed", "octaves", "frequency", "amplitude", "radius"],
            ObjectKind::Gyroid => &["frequency", "thickness"],
            ObjectKind::Torus => &["major", "minor"],
            ObjectKind::Bunny => &["mesh", "margin", "band"],
            ObjectKind::Terrain => &["seed", "octaves", "frequency", "amplitude", "base"],
            ObjectKind::Caves => &[
                "seed",
                "octaves",
                "frequency",
                "amplitude",
                "base",
                "cave_frequency",
                "cave_radius",
                "cave_ceiling",
            ],
            ObjectKind::Random => &["seed"],
        }
    }
}

impl fmt::Display for ObjectKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for ObjectKind {
    type Err = ObjectError;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Self::ALL
            .into_iter()
            .find(|k| k.name() == s)
            .ok_or_else(|| ObjectError::UnknownObject(s.to_string()))
    }
}

/// Object parameters, all optional (defaults in the [module table](self)); shared by the
/// command line (`--radius 0.8`) and manifests (`radius = 0.8`).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize, clap::Args)]
#[serde(deny_unknown_fields)]
pub struct ObjectParams {
    /// Sphere or asteroid radius (world units).
    #[arg(long)]
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub radius: Option<f32>,
    /// Noise seed (asteroid, terrains; the manifest's `seed` when not given there).
    #[arg(long)]
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub seed: Option<u32>,
    /// Noise octaves (asteroid, terrains), 1 to 16.
    #[arg(long)]
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub octaves: Option<usize>,
    /// Noise frequency (asteroid, terrains; cycles per unit) or gyroid periods per unit.
    #[arg(long)]
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub frequency: Option<f64>,
    /// Noise displacement amplitude (asteroid) or terrain height amplitude.
    #[arg(long)]
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub amplitude: Option<f32>,
    /// Gyroid sheet half-thickness.
    #[arg(long)]
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub thickness: Option<f32>,
    /// Torus major radius (centre of the tube).
    #[arg(long)]
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub major: Option<f32>,
    /// Torus minor radius (tube radius).
    #[arg(long)]
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub minor: Option<f32>,
    /// Closed triangle mesh (OBJ or PLY) of a mesh object (bunny).
    #[arg(long)]
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mesh: Option<PathBuf>,
    /// Free space around a fitted mesh, as a fraction of the box on each side, in [0, 0.5).
    #[arg(long)]
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub margin: Option<f32>,
    /// Narrow band of a mesh object's distance field, in grid spacings: distances are exact
    /// within it and clamped beyond it (signs stay exact). The default, 2, changes no extracted
    /// mesh and samples the bunny about 4x faster; 0 computes exact distances everywhere.
    #[arg(long)]
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub band: Option<f32>,
    /// Terrain ground height where the noise is zero.
    #[arg(long, allow_hyphen_values = true)]
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub base: Option<f32>,
    /// Cave noise frequency (caves).
    #[arg(long)]
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cave_frequency: Option<f64>,
    /// Tunnel radius in noise units, 0 for none (caves).
    #[arg(long)]
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cave_radius: Option<f32>,
    /// Height below which tunnels are carved (caves).
    #[arg(long, allow_hyphen_values = true)]
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cave_ceiling: Option<f32>,
}

impl ObjectParams {
    /// The names of the parameters that are set.
    pub fn given(&self) -> Vec<&'static str> {
        let mut out = Vec::new();
        let mut push = |set: bool, name| {
            if set {
                out.push(name)
            }
        };
        push(self.radius.is_some(), "radius");
        push(self.seed.is_some(), "seed");
        push(self.octaves.is_some(), "octaves");
        push(self.frequency.is_some(), "frequency");
        push(self.amplitude.is_some(), "amplitude");
        push(self.thickness.is_some(), "thickness");
        push(self.major.is_some(), "major");
        push(self.minor.is_some(), "minor");
        push(self.mesh.is_some(), "mesh");
        push(self.margin.is_some(), "margin");
        push(self.band.is_some(), "band");
        push(self.base.is_some(), "base");
        push(self.cave_frequency.is_some(), "cave_frequency");
        push(self.cave_radius.is_some(), "cave_radius");
        push(self.cave_ceiling.is_some(), "cave_ceiling");
        out
    }
}

/// An axis-aligned box `[xmin, ymin, zmin, xmax, ymax, zmax]`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "[f32; 6]", into = "[f32; 6]")]
pub struct Bounds {
    /// Lower corner.
    pub min: Vec3,
    /// Upper corner.
    pub max: Vec3,
}

impl Default for Bounds {
    /// The cube `[-1, 1]^3`.
    fn default() -> Self {
        Self {
            min: Vec3::splat(-1.0),
            max: Vec3::splat(1.0),
        }
    }
}

impl TryFrom<[f32; 6]> for Bounds {
    type Error = ObjectError;
    fn try_from(v: [f32; 6]) -> Result<Self, Self::Error> {
        let min = Vec3::new(v[0], v[1], v[2]);
        let max = Vec3::new(v[3], v[4], v[5]);
        if !(min.is_finite() && max.is_finite()) || min.cmpge(max).any() {
            return Err(ObjectError::InvalidBounds(v));
        }
        Ok(Self { min, max })
    }
}

impl From<Bounds> for [f32; 6] {
    fn from(b: Bounds) -> Self {
        [b.min.x, b.min.y, b.min.z, b.max.x, b.max.y, b.max.z]
    }
}

impl FromStr for Bounds {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let parts: Vec<&str> = s.split(',').map(str::trim).collect();
        if parts.len() != 6 {
            return Err(format!(
                "bounds need 6 comma-separated numbers xmin,ymin,zmin,xmax,ymax,zmax, got `{s}`"
            ));
        }
        let mut v = [0.0f32; 6];
        for (slot, part) in v.iter_mut().zip(&parts) {
            *slot = part
                .parse()
                .map_err(|_| format!("bounds: `{part}` is not a number"))?;
        }
        Bounds::try_from(v).map_err(|e| e.to_string())
    }
}

impl Bounds {
    /// The centre of the box.
    pub fn centre(&self) -> Vec3 {
        (self.min + self.max) * 0.5
    }

    /// Half of the box's smallest side.
    pub fn half_min_side(&self) -> f32 {
        (self.max - self.min).min_element() * 0.5
    }
}

/// Cells per axis: one number (a cube) or three.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum Resolution {
    /// The same number of cells on every axis.
    Cube(usize),
    /// Cells along x, y, z.
    Axes([usize; 3]),
}

impl Resolution {
    /// Cells along x, y, z.
    pub fn cells(self) -> [usize; 3] {
        match self {
            Resolution::Cube(n) => [n; 3],
            Resolution::Axes(a) => a,
        }
    }

    /// `64` for a cube, `75x40x56` otherwise (used in configuration ids).
    pub fn label(self) -> String {
        let [x, y, z] = self.cells();
        if x == y && y == z {
            x.to_string()
        } else {
            format!("{x}x{y}x{z}")
        }
    }
}

impl FromStr for Resolution {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let parse = |p: &str| {
            p.trim().parse::<usize>().map_err(|_| {
                format!("resolution: `{p}` is not a whole number of cells (use N or NX,NY,NZ)")
            })
        };
        let parts: Vec<&str> = s.split(',').collect();
        let r = match parts.as_slice() {
            [n] => Resolution::Cube(parse(n)?),
            [x, y, z] => Resolution::Axes([parse(x)?, parse(y)?, parse(z)?]),
            _ => return Err(format!("resolution: expected N or NX,NY,NZ, got `{s}`")),
        };
        if r.cells().contains(&0) {
            return Err(format!(
                "resolution: every axis needs at least one cell, got `{s}`"
            ));
        }
        Ok(r)
    }
}

/// A kind with its parameters: everything needed to build the field (given the box).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ObjectSpec {
    /// What to build.
    pub kind: ObjectKind,
    /// Its parameters (unset ones take the defaults).
    pub params: ObjectParams,
}

/// Default noise seed of the asteroid.
pub const DEFAULT_SEED: u32 = 7;

/// The default mesh of the bunny, relative to the workspace root.
pub const DEFAULT_BUNNY: &str = "data/bunny.obj";

impl ObjectSpec {
    /// `kind` with `params`; errors on parameters the kind does not take.
    pub fn new(kind: ObjectKind, params: ObjectParams) -> Result<Self, ObjectError> {
        let accepted = kind.accepted();
        if let Some(param) = params.given().into_iter().find(|p| !accepted.contains(p)) {
            return Err(ObjectError::UnexpectedParameter {
                kind,
                param,
                accepted: accepted.join(", "),
            });
        }
        Ok(Self { kind, params })
    }

    /// Builds the field for the box `bounds`. `search` lists folders in which to look for a
    /// relative mesh path (after the current folder; the workspace root is always tried last).
    /// Distances of mesh objects are exact everywhere; [`ObjectSpec::build_for_spacing`] gives
    /// the faster narrow-band field for a known grid.
    pub fn build(
        &self,
        bounds: &Bounds,
        search: &[PathBuf],
    ) -> Result<Box<dyn ScalarField>, ObjectError> {
        self.build_for_spacing(bounds, None, search)
    }

    /// Like [`ObjectSpec::build`], for sampling on grids whose largest cell edge is at most
    /// `spacing`: mesh objects then truncate their distance to a band of `band` (2 by default)
    /// such spacings, which changes no extracted mesh and saves most of the sampling time.
    pub fn build_for_spacing(
        &self,
        bounds: &Bounds,
        spacing: Option<f32>,
        search: &[PathBuf],
    ) -> Result<Box<dyn ScalarField>, ObjectError> {
        let p = &self.params;
        let kind = self.kind;
        let positive = |param: &'static str, v: f32| {
            if v.is_finite() && v > 0.0 {
                Ok(v)
            } else {
                Err(ObjectError::InvalidParameter {
                    kind,
                    param,
                    message: format!("must be finite and > 0, got {v}"),
                })
            }
        };
        let invalid = |param: &'static str, message: String| ObjectError::InvalidParameter {
            kind,
            param,
            message,
        };
        let non_negative = |param: &'static str, v: f32| {
            if v.is_finite() && v >= 0.0 {
                Ok(v)
            } else {
                Err(invalid(param, format!("must be finite and >= 0, got {v}")))
            }
        };
        let finite = |param: &'static str, v: f32| {
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
        let centre = bounds.centre();
        let half = bounds.half_min_side();
        Ok(match kind {
            ObjectKind::Sphere => {
                let radius = positive("radius", p.radius.unwrap_or(half))?;
                Box::new(Sphere::new(centre, radius))
            }
            ObjectKind::Asteroid => {
                let d = AsteroidParams::default();
                let frequency = p.frequency.unwrap_or(d.frequency);
                positive("frequency", frequency as f32)?;
                let params = AsteroidParams {
                    seed: p.seed.unwrap_or(DEFAULT_SEED),
                    octaves: octaves(p.octaves.unwrap_or(d.octaves))?,
                    frequency,
                    amplitude: non_negative("amplitude", p.amplitude.unwrap_or(d.amplitude))?,
                    radius: positive("radius", p.radius.unwrap_or(d.radius))?,
                };
                Box::new(Asteroid::new(centre, params))
            }
            ObjectKind::Gyroid => {
                let frequency = positive("frequency", p.frequency.unwrap_or(1.0) as f32)?;
                let thickness = positive("thickness", p.thickness.unwrap_or(0.3))?;
                Box::new(Gyroid {
                    frequency,
                    thickness,
                })
            }
            ObjectKind::Torus => {
                let major = positive("major", p.major.unwrap_or(0.6 * half))?;
                let minor = positive("minor", p.minor.unwrap_or(0.25 * half))?;
                Box::new(Torus {
                    centre,
                    major,
                    minor,
                })
            }
            ObjectKind::Terrain => {
                let d = SvobodaParams::default();
                let frequency = p.frequency.unwrap_or(d.frequency);
                positive("frequency", frequency as f32)?;
                let params = SvobodaParams {
                    seed: p.seed.unwrap_or(d.seed),
                    octaves: octaves(p.octaves.unwrap_or(d.octaves))?,
                    frequency,
                    amplitude: non_negative("amplitude", p.amplitude.unwrap_or(d.amplitude))?,
                    base: finite("base", p.base.unwrap_or(d.base))?,
                };
                Box::new(SvobodaTerrain::new(params))
            }
            ObjectKind::Caves => {
                let d = CaveParams::default();
                let frequency = p.frequency.unwrap_or(d.frequency);
                positive("frequency", frequency as f32)?;
                let cave_frequency = p.cave_frequency.unwrap_or(d.cave_frequency);
                positive("cave_frequency", cave_frequency as f32)?;
                let params = CaveParams {
                    seed: p.seed.unwrap_or(d.seed),
                    octaves: octaves(p.octaves.unwrap_or(d.octaves))?,
                    frequency,
                    amplitude: non_negative("amplitude", p.amplitude.unwrap_or(d.amplitude))?,
                    base: finite("base", p.base.unwrap_or(d.base))?,
                    cave_frequency,
                    cave_radius: non_negative(
                        "cave_radius",
                        p.cave_radius.unwrap_or(d.cave_radius),
                    )?,
                    cave_ceiling: finite("cave_ceiling", p.cave_ceiling.unwrap_or(d.cave_ceiling))?,
                };
                Box::new(CaveTerrain::new(params))
            }
            ObjectKind::Random => Box::new(
                RandomField::from_seed(u64::from(p.seed.unwrap_or(DEFAULT_SEED)))
                    .in_box(centre, half),
            ),
            ObjectKind::Bunny => {
                let margin = p.margin.unwrap_or(0.05);
                let given = p
                    .mesh
                    .clone()
                    .unwrap_or_else(|| PathBuf::from(DEFAULT_BUNNY));
                let path = resolve_data_path(&given, search)?;
                let mesh = rmt_mesh::io::read_mesh(&path)?;
                let band = p.band.unwrap_or(2.0);
                if !(band.is_finite() && band >= 0.0) {
                    return Err(ObjectError::InvalidParameter {
                        kind,
                        param: "band",
                        message: format!("must be finite and >= 0 (grid spacings), got {band}"),
                    });
                }
                let sdf = MeshSdf::fit(&mesh, bounds.min, bounds.max, margin)
                    .map_err(|e| e.with_path(&path))?;
                match spacing {
                    Some(h) if band > 0.0 => Box::new(sdf.with_band(band * h)),
                    _ => Box::new(sdf),
                }
            }
        })
    }
}

/// The workspace root as seen at build time (the folder above this package).
pub fn workspace_root() -> PathBuf {
    let here = Path::new(env!("CARGO_MANIFEST_DIR"));
    here.parent()
        .map(Path::to_path_buf)
        .unwrap_or_else(|| here.to_path_buf())
}

/// Finds a data file: `path` itself when absolute; else the first existing of the current folder,
/// each folder of `search` and their ancestors, and the workspace root.
pub fn resolve_data_path(path: &Path, search: &[PathBuf]) -> Result<PathBuf, ObjectError> {
    if path.is_absolute() {
        return if path.is_file() {
            Ok(path.to_path_buf())
        } else {
            Err(ObjectError::MissingMesh {
                path: path.to_path_buf(),
                tried: vec![path.into()],
            })
        };
    }
    let mut tried = vec![path.to_path_buf()];
    for folder in search {
        for ancestor in folder.ancestors() {
            if !ancestor.as_os_str().is_empty() {
                tried.push(ancestor.join(path));
            }
        }
    }
    tried.push(workspace_root().join(path));
    let mut seen = Vec::new();
    tried.retain(|p| {
        let new = !seen.contains(p);
        seen.push(p.clone());
        new
    });
    match tried.iter().find(|p| p.is_file()) {
        Some(p) => Ok(p.clone()),
        None => Err(ObjectError::MissingMesh {
            path: path.to_path_buf(),
            tried,
        }),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_kind_round_trips_through_its_name_and_has_a_unique_code() {
        let mut codes = Vec::new();
        for k in ObjectKind::ALL {
            assert_eq!(k.name().parse::<ObjectKind>().ok(), Some(k));
            assert!(!codes.contains(&k.code()), "duplicate code {}", k.code());
            codes.push(k.code());
        }
        let err = "teapot"
            .parse::<ObjectKind>()
            .map(|_| ())
            .unwrap_err()
            .to_string();
        assert!(err.contains("teapot") && err.contains("sphere"), "{err}");
    }

    #[test]
    fn parameters_of_another_kind_are_refused() {
        let params = ObjectParams {
            thickness: Some(0.2),
            ..Default::default()
        };
        let err = ObjectSpec::new(ObjectKind::Sphere, params)
            .unwrap_err()
            .to_string();
        assert!(err.contains("thickness") && err.contains("radius"), "{err}");
    }

    #[test]
    fn default_sphere_is_inscribed_in_the_box() {
        let spec = ObjectSpec::new(ObjectKind::Sphere, ObjectParams::default()).unwrap();
        let b = Bounds {
            min: Vec3::new(0.0, 0.0, 0.0),
            max: Vec3::new(2.0, 4.0, 2.0),
        };
        let f = spec.build(&b, &[]).unwrap();
        assert!(f.sample(Vec3::new(1.0, 2.0, 1.0)) < 0.0);
        assert!(
            f.sample(Vec3::new(2.0, 2.0, 1.0)).abs() < 1e-6,
            "touches the x faces"
        );
    }

    #[test]
    fn bad_parameters_are_reported_by_name() {
        let spec = ObjectSpec::new(
            ObjectKind::Torus,
            ObjectParams {
                minor: Some(-1.0),
                ..Default::default()
            },
        )
        .unwrap();
        let err = spec
            .build(&Bounds::default(), &[])
            .err()
            .unwrap()
            .to_string();
        assert!(err.contains("minor") && err.contains("-1"), "{err}");
    }

    #[test]
    fn resolution_and_bounds_parse_and_reject_bad_text() {
        assert_eq!("50".parse::<Resolution>().unwrap().cells(), [50; 3]);
        assert_eq!(
            "75,40,56".parse::<Resolution>().unwrap().label(),
            "75x40x56"
        );
        assert!("0".parse::<Resolution>().is_err());
        assert!("4,4".parse::<Resolution>().is_err());
        assert!("x".parse::<Resolution>().is_err());
        let b: Bounds = "-1,-2,-3,1,2,3".parse().unwrap();
        assert_eq!(b.max, Vec3::new(1.0, 2.0, 3.0));
        assert!("1,1,1,0,0,0".parse::<Bounds>().is_err());
        assert!("NaN,0,0,1,1,1".parse::<Bounds>().is_err());
        assert!("0,0,0,1,1".parse::<Bounds>().is_err());
    }

    #[test]
    fn bunny_is_found_from_the_workspace_root_and_fitted_inside_the_box() {
        let spec = ObjectSpec::new(ObjectKind::Bunny, ObjectParams::default()).unwrap();
        let b = Bounds::default();
        let f = spec.build(&b, &[]).unwrap();
        // Some points of a coarse grid are inside; the box corners are outside.
        let steps = 12;
        let inside = (0..steps * steps * steps)
            .filter(|i| {
                let g = Vec3::new(
                    (i % steps) as f32,
                    ((i / steps) % steps) as f32,
                    (i / (steps * steps)) as f32,
                );
                f.sample(b.min + (g + 0.5) / steps as f32 * (b.max - b.min)) < 0.0
            })
            .count();
        assert!(inside > 0 && inside < steps * steps * steps, "{inside}");
        assert!(f.sample(b.min) > 0.0 && f.sample(b.max) > 0.0);
    }

    #[test]
    fn terrains_are_solid_below_and_air_above_and_take_the_seed() {
        for kind in [ObjectKind::Terrain, ObjectKind::Caves] {
            let f = ObjectSpec::new(kind, ObjectParams::default())
                .unwrap()
                .build(&Bounds::default(), &[])
                .unwrap();
            // Tunnels may cross the bottom layer, so ask for mostly solid there; the top is air.
            let layer = |y: f32| {
                (0..100).map(move |i| {
                    Vec3::new((i % 10) as f32 / 5.0 - 0.9, y, (i / 10) as f32 / 5.0 - 0.9)
                })
            };
            let solid = layer(-0.95).filter(|&p| f.sample(p) < 0.0).count();
            assert!(solid > 80, "{kind}: ground below ({solid} of 100 solid)");
            assert!(layer(0.95).all(|p| f.sample(p) > 0.0), "{kind}: air above");
            let seeded = ObjectSpec::new(
                kind,
                ObjectParams {
                    seed: Some(99),
                    ..Default::default()
                },
            )
            .unwrap()
            .build(&Bounds::default(), &[])
            .unwrap();
            let p = Vec3::new(0.31, 0.0, -0.27);
            assert_ne!(
                f.sample(p),
                seeded.sample(p),
                "{kind}: the seed changes the surface"
            );
        }
    }

    #[test]
    fn a_missing_mesh_file_names_the_places_looked_at() {
        let params = ObjectParams {
            mesh: Some("no/such/bunny.obj".into()),
            ..Default::default()
        };
        let spec = ObjectSpec::new(ObjectKind::Bunny, params).unwrap();
        let err = spec
            .build(&Bounds::default(), &[])
            .err()
            .unwrap()
            .to_string();
        assert!(
            err.contains("no/such/bunny.obj") && err.contains("not found"),
            "{err}"
        );
    }
}
