//! Turntables: one full turn of a mesh about the vertical axis, as frames or as a GIF.
//!
//! Every knob is in [`TurntableSettings`]; one value of it renders every configuration of a study
//! and is written next to the animations, so "identical rendering parameters" holds by
//! construction. The palette too is derived from the settings alone (a reference sphere under the
//! same camera and lights, see [`crate::palette`]), never from the mesh, so two configurations'
//! animations use the same 255 colours and can be composed without requantising.

use crate::animation::{frame_delays, IndexedAnimation};
use crate::camera::{turntable_model, BoundingSphere, Camera};
use crate::color::Rgb8;
use crate::palette::{histogram, median_cut, Palette};
use crate::raster::{check_indices, project, rasterize, GBuffer, ScreenVertex};
use crate::shade::{resolve, LightRig, Normals, Shader, Shading};
use crate::wireframe::{draw_wireframe, Wireframe};
use crate::{io_error, RenderError, Result};
use glam::{Mat3, Vec3};
use rmt_mesh::Mesh;
use serde::{Deserialize, Serialize};
use std::f32::consts::TAU;
use std::path::Path;

/// Everything that decides how a turntable looks. JSON-serialisable; missing keys take defaults.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct TurntableSettings {
    /// Frame width in pixels.
    pub width: u32,
    /// Frame height in pixels.
    pub height: u32,
    /// Frames per turn; frame `k` shows the object turned by `360 k / frames` degrees.
    pub frames: u32,
    /// Playback rate in frames per second (GIF delays are whole centiseconds: see
    /// [`frame_delays`]).
    pub fps: u32,
    /// Camera elevation above the horizontal plane through the bounding sphere's centre, degrees.
    pub elevation_degrees: f32,
    /// Camera distance from the bounding sphere's centre, in sphere radii (> 1); sets the
    /// strength of perspective.
    pub distance_radii: f32,
    /// Diameter of the bounding sphere's image as a share of the frame's shorter side (0, 1];
    /// the field of view follows from it.
    pub fill: f32,
    /// Samples per pixel along each axis (anti-aliasing by supersampling, box filter).
    pub supersampling: u32,
    /// Smooth (interpolated vertex normals) or flat (face normals) shading.
    pub shading: Shading,
    /// Background colour (sRGB).
    pub background: Rgb8,
    /// Surface colour (sRGB).
    pub material: Rgb8,
    /// The camera-fixed light rig.
    pub lights: LightRig,
    /// Optional wireframe overlay.
    pub wireframe: Option<Wireframe>,
}

impl Default for TurntableSettings {
    fn default() -> Self {
        Self {
            width: 256,
            height: 256,
            frames: 72,
            fps: 24,
            elevation_degrees: 20.0,
            distance_radii: 4.0,
            fill: 0.9,
            supersampling: 3,
            shading: Shading::Smooth,
            background: [238, 240, 243],
            material: [135, 155, 185],
            lights: LightRig::default(),
            wireframe: None,
        }
    }
}

impl TurntableSettings {
    /// Checks every value's range; the error names the field.
    pub fn validate(&self) -> Result<()> {
        let bad = |m: String| Err(RenderError::InvalidSettings(m));
        if !(8..=4096).contains(&self.width) || !(8..=4096).contains(&self.height) {
            return bad(format!(
                "width and height must be 8..=4096, got {}x{}",
                self.width, self.height
            ));
        }
        if !(1..=3600).contains(&self.frames) {
            return bad(format!("frames must be 1..=3600, got {}", self.frames));
        }
        if !(1..=100).contains(&self.fps) {
            return bad(format!("fps must be 1..=100, got {}", self.fps));
        }
        if !(-89.0..=89.0).contains(&self.elevation_degrees) {
            return bad(format!(
                "elevation_degrees must be -89..=89, got {}",
                self.elevation_degrees
            ));
        }
        if !(self.distance_radii > 1.0 && self.distance_radii <= 1000.0) {
            return bad(format!(
                "distance_radii must be in (1, 1000], got {}",
                self.distance_radii
            ));
        }
        if !(self.fill > 0.0 && self.fill <= 1.0) {
            return bad(format!("fill must be in (0, 1], got {}", self.fill));
        }
        if !(1..=8).contains(&self.supersampling) {
            return bad(format!(
                "supersampling must be 1..=8, got {}",
                self.supersampling
            ));
        }
        let l = &self.lights;
        let finite = |v: f32| v.is_finite() && v >= 0.0;
        if !(finite(l.ambient)
            && finite(l.key.intensity)
            && finite(l.fill.intensity)
            && finite(l.specular))
        {
            return bad("light intensities must be finite and >= 0".into());
        }
        for (name, light) in [("key", l.key), ("fill", l.fill)] {
            let d = Vec3::from(light.direction);
            if !d.is_finite() || d.length() < 1e-6 {
                return bad(format!("lights.{name}.direction must be a non-zero vector"));
            }
        }
        if let Some(w) = &self.wireframe {
            if !(w.width > 0.0 && w.width <= 16.0 && (0.0..=1.0).contains(&w.opacity)) {
                return bad(format!(
                    "wireframe.width must be in (0, 16] and opacity in [0, 1], got {} and {}",
                    w.width, w.opacity
                ));
            }
        }
        Ok(())
    }

    /// Reads settings from a JSON file (missing keys take their defaults, unknown keys are errors)
    /// and validates them.
    pub fn read_json(path: &Path) -> Result<Self> {
        let text = std::fs::read_to_string(path).map_err(io_error(path))?;
        let settings: Self = serde_json::from_str(&text).map_err(|source| RenderError::Json {
            path: path.to_path_buf(),
            source,
        })?;
        settings.validate().map_err(|e| RenderError::BadFile {
            path: path.to_path_buf(),
            message: e.to_string(),
        })?;
        Ok(settings)
    }

    /// Frame delays in centiseconds.
    pub fn delays(&self) -> Vec<u16> {
        frame_delays(self.frames, self.fps)
    }
}

/// One rendered image.
#[derive(Clone, Debug, PartialEq)]
pub struct Frame {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Row-major sRGB pixels.
    pub pixels: Vec<Rgb8>,
    /// Row-major share of each pixel's samples that the mesh covers, 0..=1.
    pub coverage: Vec<f32>,
}

impl Frame {
    /// The pixel at (x, y).
    pub fn pixel(&self, x: u32, y: u32) -> Rgb8 {
        self.pixels[(y * self.width + x) as usize]
    }

    /// The coverage at (x, y).
    pub fn coverage_at(&self, x: u32, y: u32) -> f32 {
        self.coverage[(y * self.width + x) as usize]
    }

    /// The image as an opaque `tiny-skia` pixmap.
    pub fn to_pixmap(&self) -> Option<tiny_skia::Pixmap> {
        let data = self
            .pixels
            .iter()
            .flat_map(|p| [p[0], p[1], p[2], 255])
            .collect();
        tiny_skia::Pixmap::from_vec(data, tiny_skia::IntSize::from_wh(self.width, self.height)?)
    }

    /// Writes the image as a PNG file.
    pub fn save_png(&self, path: &Path) -> Result<()> {
        let pixmap = self
            .to_pixmap()
            .ok_or_else(|| RenderError::InvalidSettings("empty frame".into()))?;
        let bytes = pixmap
            .encode_png()
            .map_err(|e| io_error(path)(std::io::Error::other(e.to_string())))?;
        std::fs::write(path, bytes).map_err(io_error(path))
    }
}

/// A mesh checked and converted for rendering.
struct PreparedMesh {
    positions: Vec<Vec3>,
    indices: Vec<u32>,
    vertex_normals: Vec<Vec3>,
    face_normals: Vec<Vec3>,
    sphere: BoundingSphere,
}

impl PreparedMesh {
    fn new(mesh: &Mesh) -> Result<Self> {
        check_indices(mesh)?;
        let sphere = BoundingSphere::of_mesh(mesh)?;
        let positions: Vec<Vec3> = mesh.positions.iter().map(|&p| Vec3::from(p)).collect();
        let vertex_normals = if mesh.normals.is_empty() {
            let mut with_normals =
                Mesh::from_triangles(mesh.positions.clone(), mesh.indices.clone());
            with_normals.compute_area_weighted_normals();
            with_normals
                .normals
                .iter()
                .map(|&n| Vec3::from(n))
                .collect()
        } else if mesh.normals.len() == mesh.positions.len() {
            mesh.normals
                .iter()
                .map(|&n| Vec3::from(n).normalize_or_zero())
                .collect()
        } else {
            return Err(RenderError::InvalidMesh(format!(
                "{} normals for {} vertices",
                mesh.normals.len(),
                mesh.positions.len()
            )));
        };
        let face_normals = mesh
            .indices
            .chunks_exact(3)
            .map(|t| {
                let [a, b, c] = [t[0], t[1], t[2]].map(|i| positions[i as usize]);
                (b - a).cross(c - a).normalize_or_zero()
            })
            .collect();
        Ok(Self {
            positions,
            indices: mesh.indices.clone(),
            vertex_normals,
            face_normals,
            sphere,
        })
    }

    fn camera(&self, settings: &TurntableSettings) -> Camera {
        Camera::framing(
            self.sphere,
            settings.elevation_degrees,
            settings.distance_radii,
            settings.fill,
            settings.width as f32 / settings.height as f32,
        )
    }
}

/// Buffers reused from frame to frame.
struct Scratch {
    screen: Vec<ScreenVertex>,
    gbuffer: GBuffer,
    vertex_normals: Vec<Vec3>,
    face_normals: Vec<Vec3>,
}

impl Scratch {
    fn new(settings: &TurntableSettings) -> Self {
        let s = settings.supersampling;
        Self {
            screen: Vec::new(),
            gbuffer: GBuffer::new(settings.width * s, settings.height * s),
            vertex_normals: Vec::new(),
            face_normals: Vec::new(),
        }
    }
}

/// Renders `mesh` turned by `angle` radians about the vertical axis through its bounding sphere's
/// centre.
fn render_prepared(
    mesh: &PreparedMesh,
    settings: &TurntableSettings,
    camera: &Camera,
    shader: &Shader,
    angle: f32,
    scratch: &mut Scratch,
) -> Frame {
    let model = turntable_model(mesh.sphere.center, angle);
    let model_view = camera.view * model;
    let s = settings.supersampling;
    let g = &mut scratch.gbuffer;
    project(
        &mesh.positions,
        camera.projection * model_view,
        g.width,
        g.height,
        &mut scratch.screen,
    );
    g.clear();
    rasterize(&scratch.screen, &mesh.indices, g);

    // Rotations only: the upper 3x3 of model-view turns normals into camera space.
    let rotation = Mat3::from_mat4(model_view);
    scratch.face_normals.clear();
    scratch
        .face_normals
        .extend(mesh.face_normals.iter().map(|&n| rotation * n));
    let normals = match settings.shading {
        Shading::Flat => Normals::Flat(&scratch.face_normals),
        Shading::Smooth => {
            scratch.vertex_normals.clear();
            scratch
                .vertex_normals
                .extend(mesh.vertex_normals.iter().map(|&n| rotation * n));
            Normals::Smooth {
                vertex: &scratch.vertex_normals,
                face: &scratch.face_normals,
                indices: &mesh.indices,
            }
        }
    };
    let mut frame = Frame {
        width: settings.width,
        height: settings.height,
        pixels: Vec::new(),
        coverage: Vec::new(),
    };
    resolve(
        g,
        s,
        shader,
        normals,
        &mut frame.pixels,
        &mut frame.coverage,
    );
    if let Some(wire) = &settings.wireframe {
        if let Some(mut pixmap) = frame.to_pixmap() {
            draw_wireframe(
                &mut pixmap,
                &scratch.screen,
                &mesh.indices,
                g,
                s,
                wire,
                0.02 / settings.distance_radii,
            );
            for (p, q) in frame.pixels.iter_mut().zip(pixmap.pixels()) {
                *p = [q.red(), q.green(), q.blue()];
            }
        }
    }
    frame
}

/// Renders one frame of the turntable: `mesh` turned by `azimuth_degrees`.
pub fn render_frame(
    mesh: &Mesh,
    settings: &TurntableSettings,
    azimuth_degrees: f32,
) -> Result<Frame> {
    settings.validate()?;
    let prepared = PreparedMesh::new(mesh)?;
    let shader = Shader::new(&settings.lights, settings.material, settings.background);
    let camera = prepared.camera(settings);
    let mut scratch = Scratch::new(settings);
    Ok(render_prepared(
        &prepared,
        settings,
        &camera,
        &shader,
        azimuth_degrees.to_radians(),
        &mut scratch,
    ))
}

/// Renders turntables with one settings value; builds the palette once.
#[derive(Clone, Debug)]
pub struct Renderer {
    settings: TurntableSettings,
    shader: Shader,
    palette: Palette,
}

/// Segments and rings of the reference sphere the palette is trained on.
const REFERENCE_SPHERE: (u32, u32) = (96, 48);
/// Turns of the reference sphere sampled for the palette (only a wireframe or flat facets change
/// under rotation).
const REFERENCE_ANGLES: [f32; 3] = [0.0, 0.21, 0.43];

impl Renderer {
    /// Validates the settings and derives the palette from them.
    pub fn new(settings: TurntableSettings) -> Result<Self> {
        settings.validate()?;
        let shader = Shader::new(&settings.lights, settings.material, settings.background);
        let sphere = crate::shapes::uv_sphere(1.0, REFERENCE_SPHERE.0, REFERENCE_SPHERE.1);
        let prepared = PreparedMesh::new(&sphere)?;
        let camera = prepared.camera(&settings);
        let mut scratch = Scratch::new(&settings);
        let mut samples = Vec::new();
        for angle in REFERENCE_ANGLES {
            let frame =
                render_prepared(&prepared, &settings, &camera, &shader, angle, &mut scratch);
            samples.extend(
                frame
                    .pixels
                    .iter()
                    .zip(&frame.coverage)
                    .filter(|&(&p, &c)| c > 0.0 && p != settings.background)
                    .map(|(&p, _)| p),
            );
        }
        // The background is exact and first; the surface shades share 254 entries; the 256th
        // index stays free for the GIF's transparent pixels.
        let mut colors = vec![settings.background];
        colors.extend(median_cut(&histogram(samples), 254));
        let palette = Palette::new(colors)
            .ok_or_else(|| RenderError::InvalidSettings("no palette colours".into()))?;
        Ok(Self {
            settings,
            shader,
            palette,
        })
    }

    /// The settings.
    pub fn settings(&self) -> &TurntableSettings {
        &self.settings
    }

    /// The palette every animation of this renderer uses.
    pub fn palette(&self) -> &Palette {
        &self.palette
    }

    /// One full turn of `mesh`. Frames are spread over the available cores; each frame is
    /// computed independently, so the result does not depend on the thread count.
    pub fn render(&self, mesh: &Mesh) -> Result<IndexedAnimation> {
        let prepared = PreparedMesh::new(mesh)?;
        let settings = &self.settings;
        let camera = prepared.camera(settings);
        let frames = settings.frames as usize;
        let threads = std::thread::available_parallelism()
            .map_or(1, |n| n.get())
            .clamp(1, frames);
        let mut indexed: Vec<Vec<u8>> = vec![Vec::new(); frames];
        std::thread::scope(|scope| {
            let workers: Vec<_> = (0..threads)
                .map(|t| {
                    let (prepared, camera) = (&prepared, &camera);
                    scope.spawn(move || {
                        let mut scratch = Scratch::new(settings);
                        let mut mapper = self.palette.mapper();
                        (t..frames)
                            .step_by(threads)
                            .map(|k| {
                                let angle = TAU * k as f32 / frames as f32;
                                let frame = render_prepared(
                                    prepared,
                                    settings,
                                    camera,
                                    &self.shader,
                                    angle,
                                    &mut scratch,
                                );
                                (k, frame.pixels.iter().map(|&p| mapper.index(p)).collect())
                            })
                            .collect::<Vec<(usize, Vec<u8>)>>()
                    })
                })
                .collect();
            for worker in workers {
                let done = worker
                    .join()
                    .unwrap_or_else(|panic| std::panic::resume_unwind(panic));
                for (k, f) in done {
                    indexed[k] = f;
                }
            }
        });
        let (width, height) = (settings.width as u16, settings.height as u16);
        Ok(IndexedAnimation {
            width,
            height,
            palette: self.palette.colors().to_vec(),
            frames: indexed,
            delays: settings.delays(),
        })
    }
}

/// One full turn of `mesh` as an indexed animation.
pub fn render_turntable(mesh: &Mesh, settings: &TurntableSettings) -> Result<IndexedAnimation> {
    Renderer::new(settings.clone())?.render(mesh)
}

/// One full turn of `mesh`, written to `path` as a looping GIF.
pub fn render_turntable_gif(mesh: &Mesh, settings: &TurntableSettings, path: &Path) -> Result<()> {
    render_turntable(mesh, settings)?.write_gif(path)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::animation::decode_gif;
    use crate::shapes::uv_sphere;
    use gif::Repeat;

    fn small() -> TurntableSettings {
        TurntableSettings {
            width: 48,
            height: 40,
            frames: 8,
            ..TurntableSettings::default()
        }
    }

    #[test]
    fn sphere_renders_as_a_centred_disc_of_the_projected_radius() {
        let settings = TurntableSettings {
            width: 200,
            height: 200,
            supersampling: 4,
            ..Default::default()
        };
        let mesh = uv_sphere(3.0, 128, 64);
        let frame = render_frame(&mesh, &settings, 30.0).unwrap();
        let prepared = PreparedMesh::new(&mesh).unwrap();
        let camera = prepared.camera(&settings);
        let radius = camera.projected_radius_pixels(3.0, settings.height);
        assert!(
            (radius - 90.0).abs() < 0.5,
            "fill 0.9 of 200 px: radius {radius}"
        );
        let area: f64 = frame.coverage.iter().map(|&c| f64::from(c)).sum();
        let expected = std::f64::consts::PI * f64::from(radius).powi(2);
        assert!(
            (area / expected - 1.0).abs() < 0.02,
            "area {area} vs {expected}"
        );
        // Centroid of coverage at the frame centre (100, 100), within half a pixel.
        let (mut cx, mut cy) = (0.0, 0.0);
        for y in 0..200 {
            for x in 0..200 {
                let c = f64::from(frame.coverage_at(x, y));
                cx += c * (f64::from(x) + 0.5);
                cy += c * (f64::from(y) + 0.5);
            }
        }
        assert!((cx / area - 100.0).abs() < 0.5 && (cy / area - 100.0).abs() < 0.5);
        // Inside the disc everything is covered, outside nothing.
        for (x, y) in [(100, 100), (100, 100 - 85), (100 + 85, 100), (40, 160)] {
            assert_eq!(frame.coverage_at(x, y), 1.0, "({x}, {y})");
        }
        for (x, y) in [(100, 100 - 95), (100 + 95, 100), (10, 10), (190, 185)] {
            assert_eq!(frame.coverage_at(x, y), 0.0, "({x}, {y})");
            assert_eq!(frame.pixel(x, y), settings.background);
        }
    }

    #[test]
    fn key_light_brightens_the_upper_left() {
        let settings = TurntableSettings {
            width: 100,
            height: 100,
            ..Default::default()
        };
        let frame = render_frame(&uv_sphere(1.0, 64, 32), &settings, 0.0).unwrap();
        let luma = |p: Rgb8| p.iter().map(|&c| u32::from(c)).sum::<u32>();
        assert!(luma(frame.pixel(35, 35)) > luma(frame.pixel(65, 65)) + 60);
    }

    #[test]
    fn turntable_gif_has_the_frames_size_and_loop() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("t.gif");
        let settings = small();
        render_turntable_gif(&uv_sphere(1.0, 10, 6), &settings, &path).unwrap();
        let gif = decode_gif(&path).unwrap();
        assert_eq!((gif.width, gif.height), (48, 40));
        assert_eq!(gif.frames.len(), 8);
        assert_eq!(gif.repeat, Repeat::Infinite);
        assert_eq!(gif.delays, settings.delays());
        // A coarse sphere (10 segments) turned by 45 degrees is not the same picture.
        assert!(gif.frames[0] != gif.frames[1]);
    }

    #[test]
    fn rendering_is_deterministic_to_the_byte() {
        let mut settings = small();
        settings.wireframe = Some(Wireframe::default());
        settings.shading = Shading::Flat;
        let mesh = uv_sphere(2.0, 12, 7);
        let a = render_turntable(&mesh, &settings)
            .unwrap()
            .encode_gif()
            .unwrap();
        let b = render_turntable(&mesh, &settings)
            .unwrap()
            .encode_gif()
            .unwrap();
        assert_eq!(a, b);
    }

    #[test]
    fn palette_depends_on_settings_only() {
        let renderer = Renderer::new(small()).unwrap();
        let a = renderer.render(&uv_sphere(1.0, 10, 5)).unwrap();
        let b = renderer.render(&uv_sphere(5.0, 40, 20)).unwrap();
        assert_eq!(a.palette, b.palette);
        assert_eq!(a.palette[0], small().background);
        assert_eq!(
            a.palette.len(),
            255,
            "shaded sphere fills the palette, one index stays free"
        );
    }

    #[test]
    fn quantisation_error_is_small_on_a_shaded_sphere() {
        let settings = TurntableSettings {
            width: 96,
            height: 96,
            frames: 1,
            ..Default::default()
        };
        let mesh = uv_sphere(1.0, 40, 20);
        let exact = render_frame(&mesh, &settings, 0.0).unwrap();
        let anim = render_turntable(&mesh, &settings).unwrap();
        let quantised = anim.frame_rgb(0);
        // Worst channel error inside the disc (shades the palette was trained on) and on its
        // anti-aliased rim (blends with the background, sparser in the training set).
        let (mut inside, mut rim) = (0u8, 0u8);
        for ((a, b), &c) in exact.pixels.iter().zip(&quantised).zip(&exact.coverage) {
            let e = (0..3).map(|k| a[k].abs_diff(b[k])).max().unwrap_or(0);
            let worst = if c == 1.0 { &mut inside } else { &mut rim };
            *worst = (*worst).max(e);
        }
        assert!(inside <= 3, "worst channel error inside {inside}");
        assert!(rim <= 10, "worst channel error on the rim {rim}");
    }

    #[test]
    fn flat_shading_shows_facets_and_smooth_does_not() {
        // Count distinct colours in the middle of a coarse sphere: flat shading gives one per
        // facet, smooth shading a gradient of many.
        let mesh = uv_sphere(1.0, 10, 6);
        let base = TurntableSettings {
            width: 80,
            height: 80,
            ..Default::default()
        };
        let flat = render_frame(
            &mesh,
            &TurntableSettings {
                shading: Shading::Flat,
                ..base.clone()
            },
            0.0,
        )
        .unwrap();
        let smooth = render_frame(&mesh, &base, 0.0).unwrap();
        let distinct = |f: &Frame| {
            let mut v: Vec<Rgb8> = (30..50)
                .flat_map(|y| (30..50).map(move |x| (x, y)))
                .map(|(x, y)| f.pixel(x, y))
                .collect();
            v.sort_unstable();
            v.dedup();
            v.len()
        };
        assert!(
            distinct(&smooth) > 3 * distinct(&flat),
            "{} vs {}",
            distinct(&smooth),
            distinct(&flat)
        );
    }

    #[test]
    fn bad_settings_and_meshes_give_errors_naming_the_problem() {
        let s = TurntableSettings {
            distance_radii: 0.5,
            ..Default::default()
        };
        assert!(s
            .validate()
            .unwrap_err()
            .to_string()
            .contains("distance_radii"));
        let s = TurntableSettings {
            frames: 0,
            ..Default::default()
        };
        assert!(s.validate().unwrap_err().to_string().contains("frames"));
        let bad = Mesh::from_triangles(
            vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
            vec![0, 1, 5],
        );
        let err = render_frame(&bad, &small(), 0.0).unwrap_err().to_string();
        assert!(
            err.contains("triangle 0") && err.contains("vertex 5"),
            "{err}"
        );
    }

    #[test]
    fn settings_round_trip_through_json_and_defaults_fill_gaps() {
        let s = TurntableSettings {
            frames: 60,
            wireframe: Some(Wireframe::default()),
            ..Default::default()
        };
        let json = serde_json::to_string(&s).unwrap();
        assert_eq!(serde_json::from_str::<TurntableSettings>(&json).unwrap(), s);
        let partial: TurntableSettings = serde_json::from_str(r#"{"width": 128}"#).unwrap();
        assert_eq!(
            partial,
            TurntableSettings {
                width: 128,
                ..Default::default()
            }
        );
        assert!(serde_json::from_str::<TurntableSettings>(r#"{"widht": 1}"#).is_err());
    }
}
