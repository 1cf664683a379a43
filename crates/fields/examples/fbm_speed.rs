//! Nanoseconds per point of `Fbm<Perlin>` (the asteroid's noise: seed 7, 4 octaves, frequency
//! 1.5), on one thread, median of `reps` passes over `points` points: the `noise` crate one
//! point at a time, [`rmt_fields::fbm::BatchFbm`] (8 points at a time, checked bit for bit) and
//! [`rmt_fields::fast_fbm::FastFbm`] (`f32`, along rows; its largest difference from the crate
//! is printed and checked against its tolerance). Two point sets: uniform random points in
//! `[-1, 1]^3` (every point its own row), and the points of a 128^3 grid over that box in row
//! order (what extraction samples: rows of 129 points with equal `y` and `z`; the noise crate's
//! branches predict well on them, and neighbouring points share Perlin cells).
//!
//! `cargo run --release -p rmt-fields --example fbm_speed -- [points] [reps] [octaves]`
use noise::{Fbm, MultiFractal, NoiseFn, Perlin};
use rmt_fields::fast_fbm::{FastFbm, TOLERANCE};
use rmt_fields::fbm::{BatchFbm, LANES};
use std::time::Instant;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() -> Result<(), String> {
    let args: Vec<usize> = std::env::args()
        .skip(1)
        .map(|a| a.parse().map_err(|_| format!("not a whole number: {a:?}")))
        .collect::<Result<_, _>>()?;
    let n = args.first().copied().unwrap_or(1 << 20).max(LANES);
    let reps = args.get(1).copied().unwrap_or(7).max(1);
    let octaves = args.get(2).copied().unwrap_or(4);
    let reference = Fbm::<Perlin>::new(7)
        .set_octaves(octaves)
        .set_frequency(1.5);
    let batch = BatchFbm::new(7, octaves, 1.5);
    let fast = FastFbm::new(7, octaves, 1.5);
    // Points of a 2x2x2 box, as f32 coordinates like the fields pass them.
    let mut s = 0x9e37_79b9_7f4a_7c15u64;
    let mut next = || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        f64::from(((s >> 40) as f32 / (1u64 << 24) as f32) * 2.0 - 1.0)
    };
    let random: [Vec<f64>; 3] = std::array::from_fn(|_| (0..n).map(|_| next()).collect());
    let h = 2.0 / 128.0;
    let grid: [Vec<f64>; 3] = std::array::from_fn(|axis| {
        (0..n)
            .map(|i| {
                let k = [i % 129, (i / 129) % 129, (i / (129 * 129)) % 129][axis];
                f64::from((-1.0 + k as f64 * h) as f32)
            })
            .collect()
    });
    for (label, [xs, ys, zs]) in [("random points", &random), ("grid points", &grid)] {
        let (mut a, mut b, mut c) = (vec![0.0; n], vec![0.0; n], vec![0.0f32; n]);
        let (mut ta, mut tb, mut tc) = (Vec::new(), Vec::new(), Vec::new());
        for _ in 0..reps {
            let t = Instant::now();
            for i in 0..n {
                a[i] = reference.get([xs[i], ys[i], zs[i]]);
            }
            ta.push(t.elapsed().as_secs_f64() * 1e9 / n as f64);
            let t = Instant::now();
            let mut out = [0.0; LANES];
            for i in (0..n - n % LANES).step_by(LANES) {
                let lane = |v: &[f64]| -> [f64; LANES] { std::array::from_fn(|k| v[i + k]) };
                batch.get_lanes(&lane(xs), &lane(ys), &lane(zs), &mut out);
                b[i..i + LANES].copy_from_slice(&out);
            }
            tb.push(t.elapsed().as_secs_f64() * 1e9 / n as f64);
            let t = Instant::now();
            fast.get_points(xs, ys, zs, &mut c);
            tc.push(t.elapsed().as_secs_f64() * 1e9 / n as f64);
        }
        let m = n - n % LANES;
        let same = a[..m]
            .iter()
            .zip(&b[..m])
            .all(|(x, y)| x.to_bits() == y.to_bits());
        let min = |v: &[f64]| v.iter().copied().fold(f64::INFINITY, f64::min);
        println!(
            "Fbm<Perlin> {octaves} octaves, {n} {label}, 1 thread, median of {reps} (fastest): noise crate {:.1} ({:.1}) ns/point, batch {:.1} ({:.1}) ns/point, {:.2}x ({:.2}x); same bits: {same}",
            median(ta.clone()),
            min(&ta),
            median(tb.clone()),
            min(&tb),
            median(ta.clone()) / median(tb.clone()),
            min(&ta) / min(&tb)
        );
        let worst = a[..m]
            .iter()
            .zip(&c[..m])
            .map(|(x, y)| (x - f64::from(*y)).abs())
            .fold(0.0, f64::max);
        println!(
            "  f32 FastFbm {:.1} ({:.1}) ns/point: {:.2}x the noise crate, {:.2}x the batch; largest difference {worst:.2e} (tolerance {TOLERANCE:e})",
            median(tc.clone()),
            min(&tc),
            median(ta.clone()) / median(tc.clone()),
            median(tb.clone()) / median(tc.clone()),
        );
        if !same {
            return Err("the batch noise differs from the noise crate".into());
        }
        if worst >= TOLERANCE {
            return Err("the f32 noise is further from the noise crate than its tolerance".into());
        }
    }
    // The asteroid itself: one point at a time (noise crate) against `sample_batch`.
    use rmt_fields::ScalarField;
    let asteroid =
        rmt_fields::Asteroid::new(glam::Vec3::ZERO, rmt_fields::AsteroidParams::default());
    let pts: Vec<glam::Vec3> = (0..n)
        .map(|i| {
            glam::Vec3::new(
                random[0][i] as f32,
                random[1][i] as f32,
                random[2][i] as f32,
            )
        })
        .collect();
    let (mut va, mut vb) = (vec![0.0f32; n], vec![0.0f32; n]);
    let (mut sa, mut sb) = (Vec::new(), Vec::new());
    for _ in 0..reps {
        let t = Instant::now();
        for (v, p) in va.iter_mut().zip(&pts) {
            *v = asteroid.sample(*p);
        }
        sa.push(t.elapsed().as_secs_f64() * 1e9 / n as f64);
        let t = Instant::now();
        asteroid.sample_batch(&pts, &mut vb);
        sb.push(t.elapsed().as_secs_f64() * 1e9 / n as f64);
    }
    let same = va.iter().zip(&vb).all(|(a, b)| a.to_bits() == b.to_bits());
    println!(
        "Asteroid: sample {:.1} ns/point, sample_batch {:.1} ns/point, {:.2}x; same bits: {same}",
        median(sa.clone()),
        median(sb.clone()),
        median(sa) / median(sb)
    );
    Ok(())
}
