//! A kind with its parameters, and the scalar field it builds for a box.

use std::path::PathBuf;

use rmt_fields::{
    Asteroid, AsteroidParams, CaveParams, CaveTerrain, Gyroid, MeshSdf, RandomField, ScalarField,
    Sphere, SvobodaParams, SvobodaTerrain, Torus,
};
use serde::Serialize;

use crate::bounds::Bounds;
use crate::data::resolve_data_path;
use crate::kind::{ObjectError, ObjectKind, ObjectParams};

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

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;

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
