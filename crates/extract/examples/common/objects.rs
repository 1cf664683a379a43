//! The objects of the `mesh_hashes` listing, shared by the examples that compare builds
//! (`mesh_hashes`, `quality_compare`).
use rmt_fields::{
    Asteroid, AsteroidParams, CaveParams, CaveTerrain, Gyroid, ScalarField, Sphere, SvobodaParams,
    SvobodaTerrain, Torus,
};

/// A named field of the listing.
pub type Object = (&'static str, Box<dyn ScalarField>);

/// The listing's first objects: spheres, the asteroid and the gyroid (every MT mode since the
/// first listing).
pub fn original() -> Vec<Object> {
    vec![
        ("sphere", Box::new(Sphere::new(glam::Vec3::ZERO, 0.8))),
        // Touches the box and passes through sample points: welds and border rules.
        ("inscribed", Box::new(Sphere::new(glam::Vec3::ZERO, 1.0))),
        (
            "asteroid",
            Box::new(Asteroid::new(glam::Vec3::ZERO, AsteroidParams::default())),
        ),
        (
            "gyroid",
            Box::new(Gyroid {
                frequency: 1.5,
                thickness: 0.3,
            }),
        ),
    ]
}

/// The objects added later: the torus and the two terrains.
pub fn added() -> Vec<Object> {
    vec![
        (
            "torus",
            Box::new(Torus {
                centre: glam::Vec3::new(0.05, -0.1, 0.0),
                major: 0.6,
                minor: 0.25,
            }),
        ),
        (
            "terrain",
            Box::new(SvobodaTerrain::new(SvobodaParams::default())),
        ),
        ("caves", Box::new(CaveTerrain::new(CaveParams::default()))),
    ]
}
