//! Rendering cost: what drawing a mesh costs a GPU, beyond its triangle count.
//!
//! One measure per module, each with its knobs:
//!
//! - [`occupancy`]: quad occupancy (covered pixels / 4 x 2x2 quads launched) after a depth
//!   pre-pass, unmerged and merged across triangles, and the shares of triangles below one pixel
//!   and below one quad, at several screen sizes of the bounding sphere over several views; our
//!   own rasteriser ([`crate::raster`]).
//! - [`analyzers`]: meshoptimizer's vertex-cache (ACMR, ATVR), overdraw and vertex-fetch
//!   analyzers.
//! - [`buffers`]: index, vertex and `.glb` bytes.
//!
//! [`RenderCost`] gathers them for one mesh with flat field names, one CSV column each;
//! [`RenderCostMeter`] measures it and keeps its buffers from mesh to mesh.
//!
//! ```
//! use rmt_render::cost::RenderCostMeter;
//! let mesh = rmt_render::shapes::uv_sphere(1.0, 32, 16);
//! let cost = RenderCostMeter::new().measure(&mesh).unwrap();
//! assert!(cost.quad_occupancy_135 < cost.quad_occupancy_1080);
//! assert!(cost.quad_occupancy_merged_1080 >= cost.quad_occupancy_1080);
//! assert_eq!(cost.index_bytes, 12 * mesh.triangle_count() as u64);
//! ```

pub mod analyzers;
pub mod buffers;
pub mod occupancy;

use crate::Result;
use occupancy::{OccupancyMeter, OccupancySettings, QuadCounts, SCREEN_SIZES};
use rmt_mesh::Mesh;
use serde::{Deserialize, Serialize};

/// The cache sizes of the vertex-cache analyzer, in entries.
pub const CACHE_SIZES: [u32; 2] = [16, 32];

/// The rendering cost of one mesh; every field is one CSV column.
///
/// Occupancy fields are per screen size (the bounding sphere's diameter in pixels: 1080, 540,
/// 270, 135), pooled over the default views of [`OccupancySettings`] (8 azimuths at the
/// turntable's elevation and distance); they are NaN when the mesh covers no pixel (or, for the
/// shares, shows no front face). See [`occupancy`] for what is counted.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct RenderCost {
    /// Quad occupancy at 1080 px: covered pixels / (4 x quads launched per triangle).
    pub quad_occupancy_1080: f64,
    /// Quad occupancy at 1080 px with quads merged across triangles.
    pub quad_occupancy_merged_1080: f64,
    /// Share of front-facing triangles below 1 px^2 at 1080 px.
    pub tris_below_pixel_1080: f64,
    /// Share of front-facing triangles below 4 px^2 (a quad) at 1080 px.
    pub tris_below_quad_1080: f64,
    /// Quad occupancy at 540 px.
    pub quad_occupancy_540: f64,
    /// Merged quad occupancy at 540 px.
    pub quad_occupancy_merged_540: f64,
    /// Share of front-facing triangles below one pixel at 540 px.
    pub tris_below_pixel_540: f64,
    /// Share of front-facing triangles below one quad at 540 px.
    pub tris_below_quad_540: f64,
    /// Quad occupancy at 270 px.
    pub quad_occupancy_270: f64,
    /// Merged quad occupancy at 270 px.
    pub quad_occupancy_merged_270: f64,
    /// Share of front-facing triangles below one pixel at 270 px.
    pub tris_below_pixel_270: f64,
    /// Share of front-facing triangles below one quad at 270 px.
    pub tris_below_quad_270: f64,
    /// Quad occupancy at 135 px.
    pub quad_occupancy_135: f64,
    /// Merged quad occupancy at 135 px.
    pub quad_occupancy_merged_135: f64,
    /// Share of front-facing triangles below one pixel at 135 px.
    pub tris_below_pixel_135: f64,
    /// Share of front-facing triangles below one quad at 135 px.
    pub tris_below_quad_135: f64,
    /// ACMR (vertices transformed per triangle) of the index order as given, 16-entry FIFO.
    pub acmr_16: f64,
    /// ATVR (vertices transformed per vertex used) as given, 16-entry FIFO.
    pub atvr_16: f64,
    /// ACMR as given, 32-entry FIFO.
    pub acmr_32: f64,
    /// ATVR as given, 32-entry FIFO.
    pub atvr_32: f64,
    /// ACMR after `meshopt::optimize_vertex_cache`, 16-entry FIFO.
    pub acmr_16_optimized: f64,
    /// ATVR after `meshopt::optimize_vertex_cache`, 16-entry FIFO.
    pub atvr_16_optimized: f64,
    /// ACMR after `meshopt::optimize_vertex_cache`, 32-entry FIFO.
    pub acmr_32_optimized: f64,
    /// ATVR after `meshopt::optimize_vertex_cache`, 32-entry FIFO.
    pub atvr_32_optimized: f64,
    /// meshoptimizer's overdraw (shaded / covered pixels) of the index order as given.
    pub overdraw: f64,
    /// meshoptimizer's vertex-fetch overfetch for 24-byte vertices, index order as given.
    pub overfetch: f64,
    /// Index buffer bytes (u32 indices).
    pub index_bytes: u64,
    /// Vertex buffer bytes (position and normal, f32).
    pub vertex_bytes: u64,
    /// Bytes of the mesh's `.glb`.
    pub glb_bytes: u64,
}

/// Measures [`RenderCost`]s, keeping the occupancy buffers from mesh to mesh.
#[derive(Clone, Debug)]
pub struct RenderCostMeter {
    occupancy: OccupancyMeter,
}

impl Default for RenderCostMeter {
    fn default() -> Self {
        Self::new()
    }
}

impl RenderCostMeter {
    /// A meter with the default views ([`OccupancySettings::default`]) at [`SCREEN_SIZES`].
    pub fn new() -> Self {
        let occupancy = OccupancyMeter::new(OccupancySettings::default())
            .expect("the default occupancy settings are valid");
        Self { occupancy }
    }

    /// Every measure of `mesh`. Single-threaded and deterministic: the same mesh gives the same
    /// value.
    ///
    /// Errors when the mesh has an index out of range, a partial triangle, no vertex, a
    /// non-finite position, no extent, or normals that are neither absent nor one per vertex.
    pub fn measure(&mut self, mesh: &Mesh) -> Result<RenderCost> {
        let sizes = self.occupancy.measure(mesh)?;
        let at = |size: u32| -> QuadCounts {
            sizes
                .iter()
                .find(|s| s.size == size)
                .map(|s| s.counts)
                .unwrap_or_default()
        };
        let [c1080, c540, c270, c135] = SCREEN_SIZES.map(at);
        let (before, after) = analyzers::vertex_cache_before_after(mesh, &CACHE_SIZES)?;
        let buffers = buffers::buffer_sizes(mesh)?;
        Ok(RenderCost {
            quad_occupancy_1080: c1080.occupancy(),
            quad_occupancy_merged_1080: c1080.merged_occupancy(),
            tris_below_pixel_1080: c1080.share_below_pixel(),
            tris_below_quad_1080: c1080.share_below_quad(),
            quad_occupancy_540: c540.occupancy(),
            quad_occupancy_merged_540: c540.merged_occupancy(),
            tris_below_pixel_540: c540.share_below_pixel(),
            tris_below_quad_540: c540.share_below_quad(),
            quad_occupancy_270: c270.occupancy(),
            quad_occupancy_merged_270: c270.merged_occupancy(),
            tris_below_pixel_270: c270.share_below_pixel(),
            tris_below_quad_270: c270.share_below_quad(),
            quad_occupancy_135: c135.occupancy(),
            quad_occupancy_merged_135: c135.merged_occupancy(),
            tris_below_pixel_135: c135.share_below_pixel(),
            tris_below_quad_135: c135.share_below_quad(),
            acmr_16: before[0].acmr,
            atvr_16: before[0].atvr,
            acmr_32: before[1].acmr,
            atvr_32: before[1].atvr,
            acmr_16_optimized: after[0].acmr,
            atvr_16_optimized: after[0].atvr,
            acmr_32_optimized: after[1].acmr,
            atvr_32_optimized: after[1].atvr,
            overdraw: analyzers::overdraw(mesh)?,
            overfetch: analyzers::overfetch(mesh, analyzers::VERTEX_SIZE)?,
            index_bytes: buffers.index_bytes,
            vertex_bytes: buffers.vertex_bytes,
            glb_bytes: buffers.glb_bytes,
        })
    }
}

/// The [`RenderCost`] of `mesh` (a fresh [`RenderCostMeter`]; keep one to measure many meshes).
pub fn render_cost(mesh: &Mesh) -> Result<RenderCost> {
    RenderCostMeter::new().measure(mesh)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shapes::uv_sphere;

    #[test]
    fn render_cost_is_deterministic_and_writes_one_csv_row() {
        let mesh = uv_sphere(2.0, 48, 24);
        let mut meter = RenderCostMeter::new();
        let a = meter.measure(&mesh).unwrap();
        let b = render_cost(&mesh).unwrap();
        assert_eq!(a, b);
        // Nearer means bigger triangles: occupancy rises with the screen size, small triangles
        // fall.
        let occ = [
            a.quad_occupancy_135,
            a.quad_occupancy_270,
            a.quad_occupancy_540,
            a.quad_occupancy_1080,
        ];
        assert!(occ.windows(2).all(|w| w[0] < w[1]), "{occ:?}");
        assert!(a.quad_occupancy_1080 > 0.75 && a.quad_occupancy_1080 <= 1.0);
        assert!(a.quad_occupancy_merged_135 >= a.quad_occupancy_135);
        assert!(a.tris_below_quad_135 > a.tris_below_quad_1080);
        assert!(a.tris_below_pixel_135 <= a.tris_below_quad_135);
        let occupancy = measure_counts(&mesh);
        assert_eq!(a.quad_occupancy_270, occupancy[2].counts.occupancy());
        assert_eq!(a.vertex_bytes, 24 * mesh.vertex_count() as u64);
        assert!(a.acmr_16_optimized <= a.acmr_16 + 1e-6);
        assert!(a.overdraw >= 1.0 && a.overfetch >= 1.0);

        let mut csv = csv::Writer::from_writer(Vec::new());
        csv.serialize(a).unwrap();
        let text = String::from_utf8(csv.into_inner().unwrap()).unwrap();
        let header = text.lines().next().unwrap();
        assert!(header.starts_with("quad_occupancy_1080,quad_occupancy_merged_1080,"));
        assert_eq!(header.split(',').count(), 29);
        let back: RenderCost = csv::Reader::from_reader(text.as_bytes())
            .deserialize()
            .next()
            .unwrap()
            .unwrap();
        assert_eq!(back, a);
    }

    fn measure_counts(mesh: &Mesh) -> Vec<occupancy::SizeOccupancy> {
        occupancy::measure_occupancy(mesh, &OccupancySettings::default()).unwrap()
    }

    #[test]
    fn a_mesh_with_no_triangles_is_nan_not_an_error() {
        let points = Mesh::from_triangles(vec![[0.0; 3], [1.0, 1.0, 1.0]], vec![]);
        let c = render_cost(&points).unwrap();
        assert!(c.quad_occupancy_1080.is_nan() && c.tris_below_quad_135.is_nan());
        assert_eq!((c.index_bytes, c.acmr_16), (0, 0.0));
    }
}
