//! The object kinds by name and code, the parameters each takes, and what goes wrong building
//! one.

use std::fmt;
use std::path::PathBuf;
use std::str::FromStr;

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

/// Object parameters, all optional (defaults in the [crate table](crate)); shared by the
/// command line (`--radius 0.8`) and manifests (`radius = 0.8`).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "clap", derive(clap::Args))]
#[serde(deny_unknown_fields)]
pub struct ObjectParams {
    /// Sphere or asteroid radius (world units).
    #[cfg_attr(feature = "clap", arg(long))]
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub radius: Option<f32>,
    /// Noise seed (asteroid, terrains; the manifest's `seed` when not given there).
    #[cfg_attr(feature = "clap", arg(long))]
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub seed: Option<u32>,
    /// Noise octaves (asteroid, terrains), 1 to 16.
    #[cfg_attr(feature = "clap", arg(long))]
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub octaves: Option<usize>,
    /// Noise frequency (asteroid, terrains; cycles per unit) or gyroid periods per unit.
    #[cfg_attr(feature = "clap", arg(long))]
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub frequency: Option<f64>,
    /// Noise displacement amplitude (asteroid) or terrain height amplitude.
    #[cfg_attr(feature = "clap", arg(long))]
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub amplitude: Option<f32>,
    /// Gyroid sheet half-thickness.
    #[cfg_attr(feature = "clap", arg(long))]
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub thickness: Option<f32>,
    /// Torus major radius (centre of the tube).
    #[cfg_attr(feature = "clap", arg(long))]
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub major: Option<f32>,
    /// Torus minor radius (tube radius).
    #[cfg_attr(feature = "clap", arg(long))]
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub minor: Option<f32>,
    /// Closed triangle mesh (OBJ or PLY) of a mesh object (bunny).
    #[cfg_attr(feature = "clap", arg(long))]
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mesh: Option<PathBuf>,
    /// Free space around a fitted mesh, as a fraction of the box on each side, in [0, 0.5).
    #[cfg_attr(feature = "clap", arg(long))]
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub margin: Option<f32>,
    /// Narrow band of a mesh object's distance field, in grid spacings: distances are exact
    /// within it and clamped beyond it (signs stay exact). The default, 2, changes no extracted
    /// mesh and samples the bunny about 4x faster; 0 computes exact distances everywhere.
    #[cfg_attr(feature = "clap", arg(long))]
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub band: Option<f32>,
    /// Terrain ground height where the noise is zero.
    #[cfg_attr(feature = "clap", arg(long, allow_hyphen_values = true))]
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub base: Option<f32>,
    /// Cave noise frequency (caves).
    #[cfg_attr(feature = "clap", arg(long))]
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cave_frequency: Option<f64>,
    /// Tunnel radius in noise units, 0 for none (caves).
    #[cfg_attr(feature = "clap", arg(long))]
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cave_radius: Option<f32>,
    /// Height below which tunnels are carved (caves).
    #[cfg_attr(feature = "clap", arg(long, allow_hyphen_values = true))]
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
}
