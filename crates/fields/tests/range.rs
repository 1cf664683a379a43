//! `ScalarField::range` is conservative: on random boxes, every value the field returns at
//! points of the box (a dense grid including the corners and faces, plus random points, through
//! both `sample` and `sample_batch`) lies within the range. `ScalarField::side` is right
//! whenever it answers, and answers whenever the range decides.

use glam::Vec3;
use proptest::prelude::*;
use rmt_fields::{
    side_of, Asteroid, AsteroidParams, CaveParams, CaveTerrain, Gyroid, MeshSdf, ScalarField,
    Sphere, SvobodaParams, SvobodaTerrain, Torus,
};
use rmt_mesh::Mesh;

/// Points of the box: a `k^3` grid (corners and faces included) and `extra` pseudo-random ones.
fn points_in(lo: Vec3, hi: Vec3, k: usize, extra: usize, seed: u64) -> Vec<Vec3> {
    let mut pts = Vec::with_capacity(k * k * k + extra);
    let t = |i: usize| i as f32 / (k - 1) as f32;
    for i in 0..k {
        for j in 0..k {
            for l in 0..k {
                let p = lo + (hi - lo) * Vec3::new(t(i), t(j), t(l));
                pts.push(p.clamp(lo, hi));
            }
        }
    }
    let mut s = seed | 1;
    let mut next = || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        (s >> 40) as f32 / (1u64 << 24) as f32
    };
    for _ in 0..extra {
        let p = lo + (hi - lo) * Vec3::new(next(), next(), next());
        pts.push(p.clamp(lo, hi));
    }
    pts
}

/// Checks the range of `field` on the box `[lo, hi]`; returns whether it was known.
fn check(field: &dyn ScalarField, lo: Vec3, hi: Vec3, seed: u64) -> Result<bool, TestCaseError> {
    let Some((a, b)) = field.range(lo, hi) else {
        return Ok(false);
    };
    prop_assert!(a <= b, "empty range {a} > {b} on {lo} .. {hi}");
    let pts = points_in(lo, hi, 7, 64, seed);
    let mut batch = vec![0.0; pts.len()];
    field.sample_batch(&pts, &mut batch);
    for (&p, &vb) in pts.iter().zip(&batch) {
        let v = field.sample(p);
        prop_assert!(
            a <= v && v <= b,
            "sample({p}) = {v} outside [{a}, {b}] of the box {lo} .. {hi}"
        );
        prop_assert!(
            a <= vb && vb <= b,
            "sample_batch at {p} = {vb} outside [{a}, {b}] of the box {lo} .. {hi}"
        );
    }
    // `side`, at isovalues below, inside and above the range, and at sampled values.
    let isos = [
        a - 0.1,
        a,
        0.5 * (a + b),
        b,
        b + 0.1,
        batch[0],
        batch[batch.len() / 2],
        0.0,
    ];
    for iso in isos.into_iter().filter(|v| v.is_finite()) {
        let side = field.side(lo, hi, iso);
        if let Some(v) = side {
            let inside = v < iso;
            for (&p, &vb) in pts.iter().zip(&batch) {
                prop_assert!(
                    (vb < iso) == inside,
                    "side({lo} .. {hi}, {iso}) = {v}, but the value at {p} is {vb}"
                );
            }
        }
        prop_assert!(
            side.is_some() || side_of(a, b, iso).is_none(),
            "the range [{a}, {b}] decides iso {iso} on {lo} .. {hi} but side does not"
        );
    }
    Ok(true)
}

/// A random box inside `[-1.3, 1.3]^3`: small (a few cells), medium or large.
fn boxes() -> impl Strategy<Value = (Vec3, Vec3)> {
    (
        prop::array::uniform3(-1.3f32..1.3),
        prop::sample::select(vec![0.004f32, 0.03, 0.15, 0.6, 2.0]),
        prop::array::uniform3(0.1f32..1.0),
    )
        .prop_map(|(c, size, f)| {
            let lo = Vec3::from(c);
            (lo, lo + Vec3::from(f) * size)
        })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    #[test]
    fn analytic_ranges_hold((lo, hi) in boxes(), c in prop::array::uniform3(-0.5f32..0.5),
                            r in 0.05f32..1.2, minor in 0.02f32..0.5, freq in 0.2f32..4.0,
                            thick in 0.0f32..1.0, seed in any::<u64>()) {
        let sphere = Sphere::new(Vec3::from(c), r);
        prop_assert!(check(&sphere, lo, hi, seed)?, "sphere range must be known");
        let torus = Torus { centre: Vec3::from(c), major: r, minor };
        prop_assert!(check(&torus, lo, hi, seed)?, "torus range must be known");
        let gyroid = Gyroid { frequency: freq, thickness: thick };
        prop_assert!(check(&gyroid, lo, hi, seed)?, "gyroid range must be known");
    }

    #[test]
    fn noise_ranges_hold((lo, hi) in boxes(), seed in 0u32..1000, octaves in 1usize..7,
                         frequency in 0.5f64..3.0, amplitude in 0.0f32..0.6, radius in 0.2f32..0.9,
                         base in -0.3f32..0.3, cave_radius in prop::sample::select(vec![0.0f32, 0.1, 0.25])) {
        let asteroid = Asteroid::new(Vec3::ZERO, AsteroidParams { seed, octaves, frequency, amplitude, radius });
        prop_assert!(check(&asteroid, lo, hi, u64::from(seed))?);
        let terrain = SvobodaTerrain::new(SvobodaParams { seed, octaves, frequency, amplitude, base });
        prop_assert!(check(&terrain, lo, hi, u64::from(seed))?);
        let caves = CaveTerrain::new(CaveParams { seed, octaves, frequency, amplitude, base, cave_radius, ..Default::default() });
        prop_assert!(check(&caves, lo, hi, u64::from(seed))?);
    }
}

fn bunny() -> Mesh {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../data/bunny.obj");
    let (models, _) = tobj::load_obj(
        path,
        &tobj::LoadOptions {
            triangulate: true,
            single_index: true,
            ..Default::default()
        },
    )
    .unwrap_or_else(|e| panic!("cannot read {path}: {e}"));
    let mut mesh = Mesh::default();
    for m in models {
        let base = mesh.positions.len() as u32;
        mesh.positions
            .extend(m.mesh.positions.chunks_exact(3).map(|c| [c[0], c[1], c[2]]));
        mesh.indices
            .extend(m.mesh.indices.iter().map(|&i| i + base));
    }
    mesh
}

#[test]
fn mesh_sdf_ranges_hold_with_and_without_a_band() {
    let mesh = bunny();
    let plain = MeshSdf::fit(&mesh, Vec3::splat(-1.0), Vec3::splat(1.0), 0.05).unwrap();
    let banded = MeshSdf::fit(&mesh, Vec3::splat(-1.0), Vec3::splat(1.0), 0.05)
        .unwrap()
        .with_band(0.05);
    let mut runner = proptest::test_runner::TestRunner::new(ProptestConfig::with_cases(60));
    runner
        .run(&(boxes(), any::<u64>()), |((lo, hi), seed)| {
            prop_assert!(check(&plain, lo, hi, seed)?);
            prop_assert!(check(&banded, lo, hi, seed)?);
            Ok(())
        })
        .unwrap();
}

/// The ranges are useful, not just conservative: far boxes are decided.
#[test]
fn far_boxes_exclude_the_surface() {
    let a = Asteroid::new(Vec3::ZERO, AsteroidParams::default());
    let (lo, _) = a.range(Vec3::splat(0.9), Vec3::splat(1.0)).unwrap();
    assert!(lo > 0.0, "corner box of the asteroid's box is outside");
    let (_, hi) = a.range(Vec3::splat(-0.1), Vec3::splat(0.1)).unwrap();
    assert!(hi < 0.0, "its core is inside");
    let t = SvobodaTerrain::new(SvobodaParams::default());
    assert!(
        t.range(Vec3::new(0.0, 0.6, 0.0), Vec3::splat(0.8))
            .unwrap()
            .0
            > 0.0
    );
    assert!(
        t.range(Vec3::new(0.0, -0.9, 0.0), Vec3::new(0.2, -0.6, 0.2))
            .unwrap()
            .1
            < 0.0
    );
    let s = Sphere::new(Vec3::ZERO, 0.5);
    let (lo, hi) = s
        .range(Vec3::new(1.0, -0.1, -0.1), Vec3::new(1.2, 0.1, 0.1))
        .unwrap();
    assert!(lo > 0.49 && lo <= 0.5 && hi >= (1.2f32 * 1.2 + 0.02).sqrt() - 0.5);
    assert!(
        s.range(Vec3::ONE, Vec3::ZERO).is_none(),
        "an empty box has no range"
    );
    assert!(s.range(Vec3::splat(f32::NAN), Vec3::ONE).is_none());
}
