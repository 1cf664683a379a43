//! An anti-aliased wireframe drawn over the shaded image with `tiny-skia`.
//!
//! Only edges of front-facing triangles are candidates, and only the parts of them that are not
//! hidden: each edge is walked in steps of half a pixel, and a point counts as visible when, in
//! the 3 x 3 samples around it, some sample is empty or not nearer than the edge (within a depth
//! tolerance). Visible runs become line segments, stroked once with round caps.

use crate::color::Rgb8;
use crate::raster::{GBuffer, ScreenVertex};
use serde::{Deserialize, Serialize};
use tiny_skia::{LineCap, Paint, PathBuilder, Pixmap, Stroke, Transform};

/// How the wireframe looks.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Wireframe {
    /// Line colour (sRGB).
    pub color: Rgb8,
    /// Line opacity, 0..=1.
    pub opacity: f32,
    /// Line width in output pixels.
    pub width: f32,
}

impl Default for Wireframe {
    fn default() -> Self {
        Self {
            color: [30, 35, 45],
            opacity: 0.55,
            width: 0.8,
        }
    }
}

/// The unique undirected edges of the front-facing triangles, sorted.
fn front_edges(vertices: &[ScreenVertex], indices: &[u32]) -> Vec<(u32, u32)> {
    let mut edges = Vec::new();
    for t in indices.chunks_exact(3) {
        let [a, b, c] = [t[0], t[1], t[2]].map(|i| vertices[i as usize]);
        if !(a.valid && b.valid && c.valid) {
            continue;
        }
        let area = (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
        if area < 0.0 {
            for (u, v) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
                edges.push((u.min(v), u.max(v)));
            }
        }
    }
    edges.sort_unstable();
    edges.dedup();
    edges
}

/// Strokes the visible edges onto `pixmap` (the downsampled frame). `vertices` are in sample
/// units of `gbuffer`, `supersampling` samples per pixel and axis; `depth_tolerance` is relative
/// (0.01: an edge 1% farther than the surface in front of it still shows).
pub fn draw_wireframe(
    pixmap: &mut Pixmap,
    vertices: &[ScreenVertex],
    indices: &[u32],
    gbuffer: &GBuffer,
    supersampling: u32,
    wire: &Wireframe,
    depth_tolerance: f32,
) {
    let s = supersampling as f32;
    let (gw, gh) = (gbuffer.width as i64, gbuffer.height as i64);
    let visible = |x: f32, y: f32, inv_w: f32| {
        let (cx, cy) = (x.floor() as i64, y.floor() as i64);
        for sy in (cy - 1).max(0)..=(cy + 1).min(gh - 1) {
            for sx in (cx - 1).max(0)..=(cx + 1).min(gw - 1) {
                let buffered = gbuffer.inv_w[(sy * gw + sx) as usize];
                // Nearer means larger 1/w; empty samples hold 0.
                if buffered <= inv_w * (1.0 + depth_tolerance) {
                    return true;
                }
            }
        }
        false
    };
    let mut path = PathBuilder::new();
    for (a, b) in front_edges(vertices, indices) {
        let (a, b) = (vertices[a as usize], vertices[b as usize]);
        let length_px = ((b.x - a.x).hypot(b.y - a.y)) / s;
        let steps = (length_px * 2.0).ceil().max(1.0) as u32;
        let mut run: Option<(f32, f32, f32, f32)> = None;
        for k in 0..=steps {
            let t = k as f32 / steps as f32;
            let (x, y) = (a.x + (b.x - a.x) * t, a.y + (b.y - a.y) * t);
            let inv_w = a.inv_w + (b.inv_w - a.inv_w) * t;
            if visible(x, y, inv_w) {
                let (px, py) = (x / s, y / s);
                run = Some(match run {
                    Some((x0, y0, _, _)) => (x0, y0, px, py),
                    None => (px, py, px, py),
                });
            } else if let Some((x0, y0, x1, y1)) = run.take() {
                path.move_to(x0, y0);
                path.line_to(x1, y1);
            }
        }
        if let Some((x0, y0, x1, y1)) = run {
            path.move_to(x0, y0);
            path.line_to(x1, y1);
        }
    }
    let Some(path) = path.finish() else {
        return;
    };
    let mut paint = Paint::default();
    let alpha = (wire.opacity.clamp(0.0, 1.0) * 255.0).round() as u8;
    paint.set_color_rgba8(wire.color[0], wire.color[1], wire.color[2], alpha);
    paint.anti_alias = true;
    let stroke = Stroke {
        width: wire.width,
        line_cap: LineCap::Round,
        ..Stroke::default()
    };
    pixmap.stroke_path(&path, &paint, &stroke, Transform::identity(), None);
}
