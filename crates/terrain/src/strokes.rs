//! Random brush strokes with per-edit latency: the `edit` workload.

use glam::Vec3;

use crate::{Brush, BrushMode, TerrainError, World};

/// What strokes to run.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StrokeParams {
    /// Number of strokes (edits); each is applied, then the dirty chunks are re-meshed.
    pub strokes: usize,
    /// Seed of the stroke positions and modes.
    pub seed: u64,
    /// Brush radius in world units.
    pub radius: f32,
    /// Brush strength (value change per second at the centre).
    pub strength: f32,
    /// Frame time of one stroke in seconds.
    pub dt: f32,
    /// Clamp of the edited values.
    pub clamp: Option<f32>,
    /// Idle time before each stroke in seconds (not timed): a player's pace. The world's
    /// workers sleep meanwhile, and how they wake decides what a second thread gains (see
    /// `rmt_extract::threads`). 0 (or a negative or NaN value) runs the strokes back to back.
    pub pause_s: f32,
}

impl StrokeParams {
    /// Strokes scaled to cells of edge `h`: radius 4 h, and a strength that moves the ground by
    /// about one cell per stroke at dt = 1/60 s; values clamped to +-8 h.
    pub fn for_cells(h: f32, strokes: usize, seed: u64) -> Self {
        Self {
            strokes,
            seed,
            radius: 4.0 * h,
            strength: 60.0 * h,
            dt: 1.0 / 60.0,
            clamp: Some(8.0 * h),
            pause_s: 0.0,
        }
    }
}

/// Per-edit measurements of [`run_strokes`], one entry per stroke.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct StrokeReport {
    /// Wall time of brush + re-mesh, seconds.
    pub latencies_s: Vec<f64>,
    /// Chunks re-meshed.
    pub chunks: Vec<usize>,
    /// Triangles of the re-meshed chunks.
    pub triangles: Vec<usize>,
    /// Boxes extracted ([`crate::RemeshStats::boxes`]).
    pub boxes: Vec<usize>,
    /// Cells of those boxes ([`crate::RemeshStats::box_cells`]).
    pub box_cells: Vec<usize>,
}

impl StrokeReport {
    /// The `q` quantile (0..=1, nearest rank) of the latencies in seconds; 0 without strokes.
    pub fn latency_quantile(&self, q: f64) -> f64 {
        let mut v = self.latencies_s.clone();
        if v.is_empty() {
            return 0.0;
        }
        v.sort_by(f64::total_cmp);
        let rank = (q.clamp(0.0, 1.0) * v.len() as f64).ceil() as usize;
        v[rank.clamp(1, v.len()) - 1]
    }

    /// Triangles per re-meshed chunk, per edit (0 where no chunk was re-meshed).
    pub fn triangles_per_chunk(&self) -> Vec<f64> {
        self.triangles
            .iter()
            .zip(&self.chunks)
            .map(|(&t, &c)| if c == 0 { 0.0 } else { t as f64 / c as f64 })
            .collect()
    }
}

/// SplitMix64: a tiny deterministic generator (no dependency needed for stroke positions).
struct SplitMix(u64);

impl SplitMix {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1).
    fn unit(&mut self) -> f32 {
        (self.next() >> 40) as f32 / (1u64 << 24) as f32
    }
}

/// Runs `params.strokes` random strokes on `world` (meshing it first if needed, untimed): each
/// stroke picks a column uniformly over the world's x-z extent, centres the brush on the ground
/// there (the highest inside sample; mid-height if the column is empty), adds or removes ground
/// at random, and re-meshes the dirty chunks. Same world, params and seed give the same edits.
pub fn run_strokes(world: &mut World, params: &StrokeParams) -> Result<StrokeReport, TerrainError> {
    if world.dirty_count() > 0 {
        world.remesh_dirty()?;
    }
    let mut rng = SplitMix(params.seed);
    let grid = world.settings().world_grid();
    let mut report = StrokeReport::default();
    for _ in 0..params.strokes {
        let x = grid.min.x + rng.unit() * (grid.max.x - grid.min.x);
        let z = grid.min.z + rng.unit() * (grid.max.z - grid.min.z);
        let mode = if rng.next() & 1 == 0 {
            BrushMode::Add
        } else {
            BrushMode::Subtract
        };
        let y = world
            .column_surface(x, z)
            .unwrap_or(0.5 * (grid.min.y + grid.max.y));
        let brush = Brush {
            centre: Vec3::new(x, y, z),
            radius: params.radius,
            strength: params.strength,
            mode,
            clamp: params.clamp,
        };
        // Negative, NaN or unrepresentable pauses are no pause.
        if let Ok(pause) = std::time::Duration::try_from_secs_f32(params.pause_s) {
            if !pause.is_zero() {
                std::thread::sleep(pause);
            }
        }
        let start = std::time::Instant::now();
        world.apply_brush(&brush, params.dt)?;
        let stats = world.remesh_dirty()?;
        report.latencies_s.push(start.elapsed().as_secs_f64());
        report.chunks.push(stats.chunks);
        report.triangles.push(stats.triangles);
        report.boxes.push(stats.boxes);
        report.box_cells.push(stats.box_cells);
    }
    Ok(report)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quantiles_use_the_nearest_rank() {
        let r = StrokeReport {
            latencies_s: (1..=100).rev().map(f64::from).collect(),
            chunks: vec![1; 100],
            triangles: vec![10; 100],
            ..StrokeReport::default()
        };
        assert_eq!(r.latency_quantile(0.5), 50.0);
        assert_eq!(r.latency_quantile(0.99), 99.0);
        assert_eq!(r.latency_quantile(1.0), 100.0);
        assert_eq!(r.triangles_per_chunk()[0], 10.0);
        assert_eq!(StrokeReport::default().latency_quantile(0.5), 0.0);
    }

    /// A small world: a sphere in 16^3 cells, chunks of 8.
    fn small_world() -> World {
        let settings = crate::WorldSettings::new(
            [16, 16, 16],
            Vec3::splat(-1.0),
            0.125,
            rmt_extract::Lattice::BodyCentred,
            rmt_extract::Clustering::Integrated,
        )
        .with_chunk(8);
        World::new(&rmt_fields::Sphere::new(Vec3::ZERO, 0.6), settings).unwrap()
    }

    #[test]
    fn the_pause_before_a_stroke_is_not_part_of_its_latency() {
        let mut world = small_world();
        let pause = 0.02;
        let params = StrokeParams {
            pause_s: pause,
            ..StrokeParams::for_cells(0.125, 4, 3)
        };
        let start = std::time::Instant::now();
        let r = run_strokes(&mut world, &params).unwrap();
        let elapsed = start.elapsed().as_secs_f64();
        // Each sleep lasts at least the pause, so the strokes' own time fits in what is left;
        // latencies that included the pause would add up to more.
        let pauses = 4.0 * f64::from(pause);
        assert!(elapsed >= pauses, "{elapsed} s for {pauses} s of pauses");
        let timed: f64 = r.latencies_s.iter().sum();
        assert!(timed <= elapsed - pauses, "{timed} s timed of {elapsed} s");
    }

    #[test]
    fn negative_nan_and_unrepresentable_pauses_are_no_pause() {
        for pause_s in [-1.0, f32::NAN, f32::MAX, f32::INFINITY] {
            let mut world = small_world();
            let params = StrokeParams {
                pause_s,
                ..StrokeParams::for_cells(0.125, 2, 5)
            };
            let r = run_strokes(&mut world, &params).unwrap();
            assert_eq!(r.latencies_s.len(), 2, "pause {pause_s}");
        }
    }
}
