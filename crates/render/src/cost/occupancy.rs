//! Quad occupancy: how much of the pixel-shading work a GPU launches for a mesh is useful.
//!
//! GPUs shade pixels in 2x2 quads (for the derivatives of texture lookups): a triangle that
//! covers one pixel of a quad still runs four lanes, three of them helpers whose results are
//! thrown away. Small and thin triangles therefore waste shading work in proportion to how
//! little of each quad they fill.
//!
//! ```text
//!   quads are aligned to the even pixel grid        occupancy = covered pixels
//!   +---+---+---+---+                                           ---------------------------
//!   | a | a | a | b |   triangle a launches 2 quads              4 x quads launched
//!   +---+---+---+---+   triangle b launches 1
//!   | a | a | b | b |   unmerged: 7 pixels / (4 x 3) = 0.58     merged: a quad counts once
//!   +---+---+---+---+   merged:   7 pixels / (4 x 2) = 0.88     however many triangles touch it
//! ```
//!
//! The measure, in three layers:
//!
//! 1. **Screen-space core** ([`QuadRaster::measure`]): triangles in pixel coordinates with a
//!    `1/w` depth. A depth pre-pass rasterises every front-facing triangle with the crate's
//!    watertight rasteriser ([`crate::raster`]: 1/256-pixel snapping, exact edge functions,
//!    top-left rule, pixel centres at `(x + 1/2, y + 1/2)`), keeping per pixel the nearest
//!    triangle (on equal depth the first submitted, exactly as the G-buffer of
//!    [`crate::raster::rasterize`] does). Only that nearest surface is shaded, as after a depth
//!    pre-pass with an equal depth test: a triangle *owns* the pixels where it is the nearest, and
//!    *launches* every 2x2 quad (aligned to the even pixel grid; quads cut by the frame's edge
//!    have fewer pixels) in which it owns at least one pixel. Triangles that own no pixel launch
//!    nothing.
//! 2. **Per-view projection** ([`OccupancyMeter`]): the mesh's bounding sphere (the
//!    [`crate::camera::BoundingSphere`]) is framed by the turntable's camera
//!    ([`crate::camera::Camera::framing`], same elevation and distance) with a field of view
//!    that makes the sphere's image exactly `size` pixels across, in a `size` x `size` frame;
//!    every vertex lies inside the sphere, so every triangle lies inside the frame. The mesh is
//!    turned about the vertical axis to each of the views' azimuths, `360 k / views` degrees, as
//!    in the turntable ([`crate::camera::turntable_model`]).
//! 3. **Per-size aggregation** ([`SizeOccupancy`]): the counts of every view at one size are
//!    summed before dividing (a pooled ratio, not a mean of per-view ratios).
//!
//! Which triangles count in the shares of small triangles: the **front-facing** triangles of each
//! view, i.e. those the rasteriser sets up: their three vertices in front of the eye, facing the
//! camera, and with a non-zero area after snapping. Triangles hidden behind others count (a GPU
//! sets them up and rasterises them in the depth pre-pass); back faces and triangles that snap
//! to zero area do not. A triangle is *below one pixel* when its snapped screen area is below
//! 1 px^2 and *below one quad* when it is below 4 px^2 (exact integer comparisons of the snapped
//! area).
//!
//! Cost: one depth pass per view and size, reusing the same buffers (sized once for the largest
//! frame); no allocation per triangle or per view. The
//! `occupancy_cost` example measures it (`cargo run --release -p rmt-render --example
//! occupancy_cost`).

use crate::camera::{turntable_model, BoundingSphere, Camera};
use crate::raster::{check_indices, project, ScreenVertex, TriangleSetup, NO_TRIANGLE, SUBSAMPLE};
use crate::{RenderError, Result};
use glam::Vec3;
use rmt_mesh::Mesh;
use serde::Serialize;
use std::ops::AddAssign;

/// The screen sizes of the standard measure: the bounding sphere's diameter on screen in
/// pixels, near to far.
pub const SCREEN_SIZES: [u32; 4] = [1080, 540, 270, 135];

/// Twice one pixel's area in fixed-point units (the rasteriser's 1/256-pixel grid).
const TWICE_PIXEL_AREA: i64 = 2 * SUBSAMPLE * SUBSAMPLE;

/// What one or more depth passes counted. Sums over views with `+=`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct QuadCounts {
    /// Pixels owned by some triangle (the mesh's depth-visible coverage).
    pub covered_pixels: u64,
    /// Quads launched, each triangle launching separately every quad where it owns a pixel.
    pub quads: u64,
    /// Quads where some triangle owns a pixel, counted once however many triangles touch them.
    pub merged_quads: u64,
    /// Front-facing triangles (see the [module documentation](self)).
    pub front_triangles: u64,
    /// Triangles that own at least one pixel.
    pub visible_triangles: u64,
    /// Front-facing triangles with a screen area below 1 px^2.
    pub below_pixel: u64,
    /// Front-facing triangles with a screen area below 4 px^2 (one quad).
    pub below_quad: u64,
}

impl AddAssign for QuadCounts {
    fn add_assign(&mut self, o: Self) {
        self.covered_pixels += o.covered_pixels;
        self.quads += o.quads;
        self.merged_quads += o.merged_quads;
        self.front_triangles += o.front_triangles;
        self.visible_triangles += o.visible_triangles;
        self.below_pixel += o.below_pixel;
        self.below_quad += o.below_quad;
    }
}

/// `n / d`, or NaN when nothing was counted (no pixel, no triangle: the measure is undefined).
fn ratio(n: u64, d: u64) -> f64 {
    if d == 0 {
        f64::NAN
    } else {
        n as f64 / d as f64
    }
}

impl QuadCounts {
    /// Covered pixels / (4 x quads launched), in (0, 1]; NaN when nothing is covered.
    pub fn occupancy(&self) -> f64 {
        ratio(self.covered_pixels, 4 * self.quads)
    }

    /// Covered pixels / (4 x merged quads), the hardware's best case: at least
    /// [`Self::occupancy`]; NaN when nothing is covered.
    pub fn merged_occupancy(&self) -> f64 {
        ratio(self.covered_pixels, 4 * self.merged_quads)
    }

    /// Share of the front-facing triangles below one pixel of area; NaN without any.
    pub fn share_below_pixel(&self) -> f64 {
        ratio(self.below_pixel, self.front_triangles)
    }

    /// Share of the front-facing triangles below one quad (4 px^2) of area; NaN without any.
    pub fn share_below_quad(&self) -> f64 {
        ratio(self.below_quad, self.front_triangles)
    }
}

/// The screen-space core: a depth pass that records which triangle owns each pixel, then the
/// quad count. Keeps its buffers between calls, so measuring many views and sizes allocates only
/// when a frame or the triangle count grows.
#[derive(Clone, Debug, Default)]
pub struct QuadRaster {
    width: u32,
    height: u32,
    /// 1/w of the nearest surface per pixel, 0 where nothing was drawn.
    inv_w: Vec<f32>,
    /// The owning triangle per pixel, or [`NO_TRIANGLE`].
    owner: Vec<u32>,
    /// Per triangle, the pass in which it was last seen owning a pixel.
    seen: Vec<u32>,
    /// The current pass's stamp in `seen`.
    pass: u32,
    /// The range of `inv_w` and `owner` the last pass may have written (everything outside it
    /// is clear), as `start..end` indices.
    dirty: std::ops::Range<usize>,
}

impl QuadRaster {
    /// An empty rasteriser; buffers grow on first use.
    pub fn new() -> Self {
        Self::default()
    }

    /// Measures the triangles `indices` (three per triangle, into `vertices`, in pixel
    /// coordinates with y down, as [`crate::raster::project`] makes them) on a `width` x `height`
    /// pixel frame. Front faces look counter-clockwise on screen; back faces are culled.
    ///
    /// Panics if an index is out of range of `vertices` (callers check meshes first).
    pub fn measure(
        &mut self,
        vertices: &[ScreenVertex],
        indices: &[u32],
        width: u32,
        height: u32,
    ) -> QuadCounts {
        let n = width as usize * height as usize;
        self.width = width;
        self.height = height;
        // Clear what the last pass wrote; the rest is clear already.
        let dirty = self.dirty.clone();
        self.inv_w[dirty.clone()].fill(0.0);
        self.owner[dirty].fill(NO_TRIANGLE);
        if self.inv_w.len() < n {
            self.inv_w.resize(n, 0.0);
            self.owner.resize(n, NO_TRIANGLE);
        }
        let triangles = indices.len() / 3;
        if self.seen.len() < triangles {
            self.seen.resize(triangles, 0);
        }
        if self.pass == u32::MAX {
            self.seen.fill(0);
            self.pass = 0;
        }
        self.pass += 1;

        // Depth pre-pass.
        let mut counts = QuadCounts::default();
        let (w, h) = (i64::from(width), i64::from(height));
        let (inv_w, owner) = (&mut self.inv_w[..n], &mut self.owner[..n]);
        // The box of every sample a triangle may have written: [x0, x1, y0, y1].
        let mut drawn = [i64::MAX, i64::MIN, i64::MAX, i64::MIN];
        for (t, tri) in indices.chunks_exact(3).enumerate() {
            let v = [tri[0], tri[1], tri[2]].map(|i| vertices[i as usize]);
            let Some(setup) = TriangleSetup::new(v, w, h) else {
                continue;
            };
            if let Some([x0, x1, y0, y1]) = setup.sample_box() {
                drawn = [
                    drawn[0].min(x0),
                    drawn[1].max(x1),
                    drawn[2].min(y0),
                    drawn[3].max(y1),
                ];
            }
            counts.front_triangles += 1;
            let twice_area = setup.twice_area_fixed();
            counts.below_pixel += u64::from(twice_area < TWICE_PIXEL_AREA);
            counts.below_quad += u64::from(twice_area < 4 * TWICE_PIXEL_AREA);
            setup.for_each_sample(w, |s, _, z| {
                if z > inv_w[s] {
                    inv_w[s] = z;
                    owner[s] = t as u32;
                }
            });
        }

        // Quads: the distinct owners of each 2x2 block of the even grid, inside the drawn box
        // (outside it every pixel is clear). A quad owned whole by one triangle, the common case,
        // takes one comparison chain.
        if drawn[0] > drawn[1] {
            self.dirty = 0..0;
            return counts;
        }
        let (wu, hu) = (width as usize, height as usize);
        let [x0, x1, y0, y1] = drawn.map(|v| v as usize);
        self.dirty = y0 * wu..(y1 + 1) * wu;
        let (seen, pass) = (&mut self.seen, self.pass);
        let mut visit = |t: u32, counts: &mut QuadCounts| {
            let s = &mut seen[t as usize];
            if *s != pass {
                *s = pass;
                counts.visible_triangles += 1;
            }
        };
        for qy in (y0 & !1..=y1).step_by(2) {
            let (row0, row1) = (qy * wu, (qy + 1) * wu);
            let lower = qy + 1 < hu;
            for qx in (x0 & !1..=x1).step_by(2) {
                let right = qx + 1 < wu;
                let quad = [
                    owner[row0 + qx],
                    if right {
                        owner[row0 + qx + 1]
                    } else {
                        NO_TRIANGLE
                    },
                    if lower { owner[row1 + qx] } else { NO_TRIANGLE },
                    if lower && right {
                        owner[row1 + qx + 1]
                    } else {
                        NO_TRIANGLE
                    },
                ];
                let t = quad[0];
                if quad[1] == t && quad[2] == t && quad[3] == t {
                    if t != NO_TRIANGLE {
                        counts.covered_pixels += 4;
                        counts.quads += 1;
                        counts.merged_quads += 1;
                        visit(t, &mut counts);
                    }
                    continue;
                }
                let mut ids = [NO_TRIANGLE; 4];
                let mut distinct = 0;
                for t in quad {
                    if t == NO_TRIANGLE {
                        continue;
                    }
                    counts.covered_pixels += 1;
                    if !ids[..distinct].contains(&t) {
                        ids[distinct] = t;
                        distinct += 1;
                    }
                    visit(t, &mut counts);
                }
                counts.quads += distinct as u64;
                counts.merged_quads += u64::from(distinct > 0);
            }
        }
        counts
    }

    /// The owning triangle of each pixel of the last [`Self::measure`] (row-major,
    /// [`NO_TRIANGLE`] where nothing is drawn).
    pub fn owners(&self) -> &[u32] {
        &self.owner[..self.width as usize * self.height as usize]
    }
}

/// Where the views are taken from. The defaults are the turntable's
/// ([`crate::TurntableSettings::default`]): elevation 20 degrees, distance 4 sphere radii, and
/// 8 azimuths (every 45 degrees) at the [`SCREEN_SIZES`].
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct OccupancySettings {
    /// The bounding sphere's diameter on screen, in pixels, one measure per entry (1..=8192).
    pub sizes: Vec<u32>,
    /// Views per size, at azimuths `360 k / views` degrees (1..=360).
    pub views: u32,
    /// Camera elevation in degrees (-89..=89).
    pub elevation_degrees: f32,
    /// Camera distance from the sphere's centre in sphere radii (> 1).
    pub distance_radii: f32,
}

impl Default for OccupancySettings {
    fn default() -> Self {
        let turntable = crate::TurntableSettings::default();
        Self {
            sizes: SCREEN_SIZES.to_vec(),
            views: 8,
            elevation_degrees: turntable.elevation_degrees,
            distance_radii: turntable.distance_radii,
        }
    }
}

impl OccupancySettings {
    /// Checks every value's range; the error names the field.
    pub fn validate(&self) -> Result<()> {
        let bad = |m: String| Err(RenderError::InvalidSettings(m));
        if self.sizes.is_empty() || self.sizes.iter().any(|s| !(1..=8192).contains(s)) {
            return bad(format!(
                "occupancy sizes must be 1..=8192 pixels, at least one, got {:?}",
                self.sizes
            ));
        }
        if !(1..=360).contains(&self.views) {
            return bad(format!(
                "occupancy views must be 1..=360, got {}",
                self.views
            ));
        }
        if !(-89.0..=89.0).contains(&self.elevation_degrees) {
            return bad(format!(
                "occupancy elevation_degrees must be -89..=89, got {}",
                self.elevation_degrees
            ));
        }
        if !(self.distance_radii > 1.0 && self.distance_radii <= 1000.0) {
            return bad(format!(
                "occupancy distance_radii must be in (1, 1000], got {}",
                self.distance_radii
            ));
        }
        Ok(())
    }
}

/// The counts at one screen size, summed over the views.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct SizeOccupancy {
    /// The bounding sphere's diameter on screen, pixels.
    pub size: u32,
    /// The counts of every view at this size.
    pub counts: QuadCounts,
}

/// Measures quad occupancy of meshes at several sizes and views, keeping its buffers from mesh
/// to mesh.
#[derive(Clone, Debug)]
pub struct OccupancyMeter {
    settings: OccupancySettings,
    raster: QuadRaster,
    positions: Vec<Vec3>,
    screen: Vec<ScreenVertex>,
}

impl OccupancyMeter {
    /// A meter for `settings` (validated).
    pub fn new(settings: OccupancySettings) -> Result<Self> {
        settings.validate()?;
        Ok(Self {
            settings,
            raster: QuadRaster::new(),
            positions: Vec::new(),
            screen: Vec::new(),
        })
    }

    /// The settings.
    pub fn settings(&self) -> &OccupancySettings {
        &self.settings
    }

    /// The camera of one size: the sphere's image exactly `size` pixels across in a square
    /// frame of that size.
    fn camera(&self, sphere: BoundingSphere) -> Camera {
        Camera::framing(
            sphere,
            self.settings.elevation_degrees,
            self.settings.distance_radii,
            1.0,
            1.0,
        )
    }

    /// Calls `each(size, view, counts, owners)` for every size and view of the settings.
    fn for_each_view(
        &mut self,
        mesh: &Mesh,
        mut each: impl FnMut(u32, u32, QuadCounts, &[u32], &[ScreenVertex]),
    ) -> Result<()> {
        check_indices(mesh)?;
        let sphere = BoundingSphere::of_mesh(mesh)?;
        let camera = self.camera(sphere);
        self.positions.clear();
        self.positions
            .extend(mesh.positions.iter().map(|&p| Vec3::from(p)));
        let views = self.settings.views;
        for view in 0..views {
            let angle = (360.0 * view as f32 / views as f32).to_radians();
            let mvp = camera.projection * camera.view * turntable_model(sphere.center, angle);
            for &size in &self.settings.sizes {
                project(&self.positions, mvp, size, size, &mut self.screen);
                let counts = self.raster.measure(&self.screen, &mesh.indices, size, size);
                each(size, view, counts, self.raster.owners(), &self.screen);
            }
        }
        Ok(())
    }

    /// The counts at each of the settings' sizes (in their order), summed over the views.
    ///
    /// Errors when the mesh has an index out of range, a partial triangle, no vertex, a
    /// non-finite position, or no extent.
    pub fn measure(&mut self, mesh: &Mesh) -> Result<Vec<SizeOccupancy>> {
        let mut out: Vec<SizeOccupancy> = self
            .settings
            .sizes
            .iter()
            .map(|&size| SizeOccupancy {
                size,
                counts: QuadCounts::default(),
            })
            .collect();
        self.for_each_view(mesh, |size, _, counts, _, _| {
            if let Some(o) = out.iter_mut().find(|o| o.size == size) {
                o.counts += counts;
            }
        })?;
        Ok(out)
    }
}

/// The counts of `mesh` at each size of `settings`, summed over the views (see
/// [`OccupancyMeter::measure`]; a meter reuses its buffers across meshes).
pub fn measure_occupancy(mesh: &Mesh, settings: &OccupancySettings) -> Result<Vec<SizeOccupancy>> {
    OccupancyMeter::new(settings.clone())?.measure(mesh)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::raster::{rasterize, GBuffer};
    use crate::shapes::uv_sphere;
    use proptest::prelude::*;

    fn v(x: f32, y: f32) -> ScreenVertex {
        ScreenVertex {
            x,
            y,
            inv_w: 1.0,
            valid: true,
        }
    }

    fn vz(x: f32, y: f32, inv_w: f32) -> ScreenVertex {
        ScreenVertex {
            x,
            y,
            inv_w,
            valid: true,
        }
    }

    /// The axis-aligned square [x0, x1] x [y0, y1] as two front-facing triangles split along the
    /// diagonal (x0, y0)-(x1, y1), at depth `inv_w`; vertices appended to `vertices`.
    fn square(
        vertices: &mut Vec<ScreenVertex>,
        indices: &mut Vec<u32>,
        [x0, y0, x1, y1]: [f32; 4],
        inv_w: f32,
    ) {
        let b = vertices.len() as u32;
        vertices.extend([
            vz(x0, y0, inv_w),
            vz(x1, y0, inv_w),
            vz(x1, y1, inv_w),
            vz(x0, y1, inv_w),
        ]);
        // On screen (y down), (top-left, bottom-left, bottom-right) turns counter-clockwise.
        indices.extend([b, b + 3, b + 2, b, b + 2, b + 1]);
    }

    fn measure(vertices: &[ScreenVertex], indices: &[u32], w: u32, h: u32) -> QuadCounts {
        QuadRaster::new().measure(vertices, indices, w, h)
    }

    #[test]
    fn aligned_8x8_square_of_two_triangles_is_0_80() {
        let (mut vs, mut is) = (Vec::new(), Vec::new());
        square(&mut vs, &mut is, [0.0, 0.0, 8.0, 8.0], 1.0);
        let c = measure(&vs, &is, 16, 16);
        assert_eq!(c.front_triangles, 2);
        assert_eq!(c.covered_pixels, 64);
        // 16 quads, the 4 on the diagonal launched by both triangles.
        assert_eq!((c.quads, c.merged_quads), (20, 16));
        assert_eq!(c.occupancy(), 0.80);
        assert_eq!(c.merged_occupancy(), 1.0);
        assert_eq!(
            (c.visible_triangles, c.below_pixel, c.below_quad),
            (2, 0, 0)
        );
        // The other diagonal splits 4 quads too.
        let anti = [0, 3, 1, 1, 3, 2];
        let c = measure(&vs, &anti, 16, 16);
        assert_eq!((c.covered_pixels, c.quads, c.merged_quads), (64, 20, 16));
    }

    #[test]
    fn square_off_the_quad_grid_launches_more_quads() {
        // The same square moved by one pixel straddles 5 x 5 quads; on the diagonal, only the
        // 3 middle quads hold pixels of both triangles (the corner quads hold one pixel each).
        let (mut vs, mut is) = (Vec::new(), Vec::new());
        square(&mut vs, &mut is, [1.0, 1.0, 9.0, 9.0], 1.0);
        let c = measure(&vs, &is, 16, 16);
        assert_eq!((c.covered_pixels, c.quads, c.merged_quads), (64, 28, 25));
        assert_eq!(c.occupancy(), 64.0 / 112.0);
        assert_eq!(c.merged_occupancy(), 0.64);
    }

    #[test]
    fn triangle_inside_one_pixel_over_its_centre_is_0_25() {
        // Inside pixel (5, 5), around its centre (5.5, 5.5); counter-clockwise on screen.
        let vs = [v(5.1, 5.1), v(5.3, 5.9), v(5.9, 5.2)];
        let c = measure(&vs, &[0, 1, 2], 16, 16);
        assert_eq!((c.covered_pixels, c.quads, c.merged_quads), (1, 1, 1));
        assert_eq!(c.occupancy(), 0.25);
        assert_eq!(c.merged_occupancy(), 0.25);
        assert_eq!((c.front_triangles, c.below_pixel, c.below_quad), (1, 1, 1));
    }

    #[test]
    fn one_pixel_wide_strip_100_pixels_long_is_0_5() {
        for rect in [[0.0, 0.0, 100.0, 1.0], [0.0, 2.0, 100.0, 3.0]] {
            let (mut vs, mut is) = (Vec::new(), Vec::new());
            square(&mut vs, &mut is, rect, 1.0);
            let c = measure(&vs, &is, 128, 4);
            assert_eq!(c.covered_pixels, 100, "{rect:?}");
            // The diagonal crosses the strip's middle row at x = 50, a quad boundary.
            assert_eq!((c.quads, c.merged_quads), (50, 50), "{rect:?}");
            assert_eq!(c.occupancy(), 0.5);
            assert_eq!(c.merged_occupancy(), 0.5);
        }
        // Standing up: the same.
        let (mut vs, mut is) = (Vec::new(), Vec::new());
        square(&mut vs, &mut is, [4.0, 0.0, 5.0, 100.0], 1.0);
        let c = measure(&vs, &is, 8, 128);
        assert_eq!((c.covered_pixels, c.quads), (100, 50));
        assert_eq!(c.occupancy(), 0.5);
    }

    #[test]
    fn only_the_nearest_surface_launches_quads() {
        // A near square hides a far one exactly: the far triangles are set up but own nothing.
        for near_first in [true, false] {
            let (mut vs, mut is) = (Vec::new(), Vec::new());
            let depths = if near_first { [0.5, 0.2] } else { [0.2, 0.5] };
            for d in depths {
                square(&mut vs, &mut is, [0.0, 0.0, 8.0, 8.0], d);
            }
            let c = measure(&vs, &is, 16, 16);
            assert_eq!(c.front_triangles, 4);
            assert_eq!(c.visible_triangles, 2, "near_first {near_first}");
            assert_eq!((c.covered_pixels, c.quads, c.merged_quads), (64, 20, 16));
        }
        // Half hidden: the far square [0, 8]^2 behind a near one over [4, 8] x [0, 8]. The far
        // square owns columns 0..4 (its diagonal quads (0, 0) and (1, 1) split), the near one
        // columns 4..8 (its diagonal runs from (4, 0) to (8, 8): it splits quads (2, 0), (2, 1),
        // (3, 2) and (3, 3)).
        let (mut vs, mut is) = (Vec::new(), Vec::new());
        square(&mut vs, &mut is, [0.0, 0.0, 8.0, 8.0], 0.2);
        square(&mut vs, &mut is, [4.0, 0.0, 8.0, 8.0], 0.5);
        let c = measure(&vs, &is, 16, 16);
        assert_eq!((c.covered_pixels, c.merged_quads), (64, 16));
        assert_eq!(c.quads, 16 + 2 + 4);
        assert_eq!(c.visible_triangles, 4);
    }

    #[test]
    fn small_triangle_shares_use_the_exact_area() {
        // Areas 1/2, 1 and 4 px^2 (the last two exactly on the thresholds, so not below them),
        // and a back face, which does not count.
        let vs = [
            v(0.0, 0.0),
            v(0.0, 1.0),
            v(1.0, 0.0),
            v(0.0, 2.0),
            v(2.0, 0.0),
            v(0.0, 4.0),
            v(4.0, 0.0),
        ];
        let c = measure(&vs, &[0, 1, 2, 0, 3, 2, 0, 5, 4, 0, 2, 1], 8, 8);
        assert_eq!(c.front_triangles, 3);
        assert_eq!((c.below_pixel, c.below_quad), (1, 2));
        assert_eq!(c.share_below_quad(), 2.0 / 3.0);
    }

    #[test]
    fn frame_edges_cut_quads_of_odd_frames() {
        // A 3 x 3 frame fully covered: quads of 4, 2, 2 and 1 pixels.
        let (mut vs, mut is) = (Vec::new(), Vec::new());
        square(&mut vs, &mut is, [0.0, 0.0, 3.0, 3.0], 1.0);
        let c = measure(&vs, &is, 3, 3);
        assert_eq!((c.covered_pixels, c.merged_quads), (9, 4));
        assert_eq!(c.merged_occupancy(), 9.0 / 16.0);
    }

    #[test]
    fn nothing_drawn_is_undefined_not_zero() {
        let c = measure(&[], &[], 4, 4);
        assert_eq!(c, QuadCounts::default());
        assert!(c.occupancy().is_nan() && c.share_below_pixel().is_nan());
    }

    #[test]
    fn sphere_covers_its_projected_disc_and_views_match_the_gbuffer() {
        let mesh = uv_sphere(2.0, 64, 32);
        let settings = OccupancySettings {
            sizes: vec![270, 135],
            views: 3,
            ..Default::default()
        };
        let mut meter = OccupancyMeter::new(settings).unwrap();
        let mut checked = 0;
        meter
            .for_each_view(&mesh, |size, view, counts, owners, screen| {
                // The sphere's disc, size pixels across (inscribed polygons lose a little).
                let disc = std::f64::consts::PI * (f64::from(size) / 2.0).powi(2);
                let covered = counts.covered_pixels as f64;
                assert!(
                    (covered / disc - 1.0).abs() < 0.02,
                    "size {size} view {view}: {covered} vs {disc}"
                );
                let mut g = GBuffer::new(size, size);
                let front = rasterize(screen, &mesh.indices, &mut g);
                assert_eq!(owners, &g.triangle[..], "size {size} view {view}");
                assert_eq!(counts.front_triangles, front as u64);
                checked += 1;
            })
            .unwrap();
        assert_eq!(checked, 6);
        let sizes = meter.measure(&mesh).unwrap();
        assert_eq!(sizes.iter().map(|s| s.size).collect::<Vec<_>>(), [270, 135]);
        // Farther away, the same triangles are smaller: occupancy falls, small triangles grow.
        let (near, far) = (sizes[0].counts, sizes[1].counts);
        assert!(far.occupancy() < near.occupancy(), "{near:?} {far:?}");
        assert!(far.share_below_quad() >= near.share_below_quad());
        assert!(near.occupancy() > 0.0 && near.occupancy() <= 1.0);
        // From d = 4 radii an eye sees the cap of the sphere within acos(1/4) of it: a share
        // (1 - 1/4) / 2 = 3/8 of the surface faces it (of the triangles, about as much).
        let share = near.front_triangles as f64 / (3 * mesh.triangle_count()) as f64;
        assert!((share - 0.375).abs() < 0.02, "front-facing share {share}");
    }

    #[test]
    fn bad_meshes_and_settings_give_errors() {
        let meter = || OccupancyMeter::new(OccupancySettings::default()).unwrap();
        let bad = Mesh::from_triangles(
            vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
            vec![0, 1, 7],
        );
        let err = meter().measure(&bad).unwrap_err().to_string();
        assert!(err.contains("vertex 7"), "{err}");
        let partial = Mesh::from_triangles(vec![[0.0; 3], [1.0, 0.0, 0.0]], vec![0, 1]);
        assert!(meter().measure(&partial).is_err());
        assert!(meter().measure(&Mesh::default()).is_err());
        for s in [
            OccupancySettings {
                sizes: vec![],
                ..Default::default()
            },
            OccupancySettings {
                views: 0,
                ..Default::default()
            },
            OccupancySettings {
                distance_radii: 1.0,
                ..Default::default()
            },
        ] {
            assert!(OccupancyMeter::new(s).is_err());
        }
    }

    /// Vertices on the 1/256-pixel grid, so moving them by whole pixels is exact.
    fn grid_vertex() -> impl Strategy<Value = ScreenVertex> {
        (0i32..24 * 256, 0i32..24 * 256, 1u32..1000)
            .prop_map(|(x, y, d)| vz(x as f32 / 256.0, y as f32 / 256.0, d as f32 / 1000.0))
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(200))]

        #[test]
        fn soup_counts_are_consistent_and_match_the_gbuffer(
            vertices in prop::collection::vec(grid_vertex(), 3..30),
            picks in prop::collection::vec(0usize..1000, 3..60),
        ) {
            let n = vertices.len();
            let indices: Vec<u32> = picks[..picks.len() / 3 * 3]
                .iter()
                .map(|&p| (p % n) as u32)
                .collect();
            let c = measure(&vertices, &indices, 24, 24);
            let mut g = GBuffer::new(24, 24);
            let front = rasterize(&vertices, &indices, &mut g);
            let drawn = g.triangle.iter().filter(|&&t| t != NO_TRIANGLE).count();
            prop_assert_eq!(c.front_triangles, front as u64);
            prop_assert_eq!(c.covered_pixels, drawn as u64);
            prop_assert!(c.merged_quads <= c.quads);
            prop_assert!(c.covered_pixels <= 4 * c.merged_quads);
            prop_assert!(c.merged_quads <= c.covered_pixels);
            prop_assert!(c.visible_triangles <= c.front_triangles);
            prop_assert!(c.below_pixel <= c.below_quad && c.below_quad <= c.front_triangles);
            if c.covered_pixels > 0 {
                prop_assert!(c.occupancy() > 0.0 && c.occupancy() <= 1.0);
                prop_assert!(c.merged_occupancy() >= c.occupancy());
                prop_assert!(c.merged_occupancy() <= 1.0);
            }
        }

        #[test]
        fn moving_by_whole_quads_changes_nothing(
            vertices in prop::collection::vec(grid_vertex(), 3..12),
            picks in prop::collection::vec(0usize..1000, 3..24),
            dx in 0u32..4,
            dy in 0u32..4,
        ) {
            let n = vertices.len();
            let indices: Vec<u32> = picks[..picks.len() / 3 * 3]
                .iter()
                .map(|&p| (p % n) as u32)
                .collect();
            let moved: Vec<ScreenVertex> = vertices
                .iter()
                .map(|p| vz(p.x + 2.0 * dx as f32, p.y + 2.0 * dy as f32, p.inv_w))
                .collect();
            // Frames large enough to hold both placements whole.
            prop_assert_eq!(measure(&vertices, &indices, 40, 40), measure(&moved, &indices, 40, 40));
        }
    }
}
