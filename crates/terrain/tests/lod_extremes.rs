//! The multiresolution world's public functions fed extreme and non-finite input: viewers at
//! NaN, infinity and far away, strokes with non-finite or huge centres, radii, strengths and
//! time steps, and fields that answer NaN or infinity, in plain, morphed and clustered worlds.
//! Each call returns (a value or an error); none panics, and a world that refused an input still
//! re-meshes.

use glam::Vec3;
use rmt_fields::ScalarField;
use rmt_terrain::lod::{LodFrame, LodGeometry, LodSettings, LodWorld, MorphSettings};
use rmt_terrain::Brush;

/// A plane through the world, except where the field answers `bad` (a slab of NaN or infinity).
#[derive(Clone)]
struct Spoiled {
    bad: f32,
}

impl ScalarField for Spoiled {
    fn sample(&self, p: Vec3) -> f32 {
        if (p.x - 0.1).abs() < 0.07 {
            self.bad
        } else {
            p.y + 0.75
        }
    }
}

/// Plain, morphed (`morph`) or clustered (`cluster`) worlds.
fn settings(morph: bool, cluster: bool) -> LodSettings {
    LodSettings {
        geometry: LodGeometry::new(2, 4, [2, 1, 2]).unwrap(),
        frame: LodFrame {
            origin: Vec3::splat(-1.0),
            h: 1.0 / 32.0,
        },
        ratio: 0.5,
        threads: 2,
        morph: morph.then_some(MorphSettings {
            band: 0.5,
            lead: 0.01,
        }),
        cluster,
    }
}

const EXTREMES: [f32; 7] = [
    f32::NAN,
    f32::INFINITY,
    f32::NEG_INFINITY,
    f32::MAX,
    -f32::MAX,
    1e-30,
    0.0,
];

#[test]
fn extreme_viewers_strokes_and_fields_give_answers_not_panics() {
    let kinds = [(false, false), (true, false), (false, true)];
    for (bad, (morph, cluster)) in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY, 1e30]
        .into_iter()
        .flat_map(|b| kinds.map(|k| (b, k)))
    {
        let mut world = LodWorld::new(Spoiled { bad }, settings(morph, cluster)).unwrap();
        world.set_viewer(Vec3::new(0.0, -0.75, 0.0));
        assert!(world.remesh().is_ok(), "field answering {bad}");
        let mut answered = 0;
        for &e in &EXTREMES {
            for viewer in [Vec3::splat(e), Vec3::new(0.0, e, 0.0)] {
                world.set_viewer(viewer);
                let _ = world.remesh();
                answered += 1;
            }
            for brush in [
                Brush::add(Vec3::splat(e), 0.1, 1.0),
                Brush::add(Vec3::new(0.0, -0.75, 0.0), e, 1.0),
                Brush::add(Vec3::new(0.0, -0.75, 0.0), 0.1, e),
            ] {
                for dt in [0.1, e] {
                    let _ = world.edit(&brush, dt);
                    let _ = world.remesh();
                    answered += 1;
                }
            }
        }
        assert_eq!(answered, EXTREMES.len() * 8);
        // After all of it, a sane viewer still gives a world.
        world.set_viewer(Vec3::new(0.0, -0.75, 0.0));
        let step = world.remesh();
        assert!(step.is_ok(), "field answering {bad}: {step:?}");
        assert!(world.level_map().is_some());
    }
}
